//! Thresholds and timeouts of the restraint decision (`[cycle]` in `ecu.toml`).
//!
//! Every number the decision logic uses lives here, with its default and the reason for it.
//! Times are in ms in the file (engineers think in ms); the cycle converts them to ns once.
//! Files (LUT, reference restraint, SecOC keys) are the shell's business: the core gets their
//! contents, never a path.

use serde::{Deserialize, Serialize};

use crate::estimate::track::TrackConfig;

/// Decision-logic configuration. Every key is optional (defaults below).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CycleConfig {
    /// Ego vehicle mass, kg (*default* 1785 kg: the paper's Ford Taurus). The LUT header must
    /// agree (±1 %), otherwise the LUT is rejected: its cells were optimised for another car.
    pub ego_mass_kg: f64,
    /// Ego stiffness class 1..=6 (*default* 4 for 1785 kg).
    pub ego_class: u8,

    /// k of the conservative opponent mass m + k·σ used for prediction and LUT lookup
    /// (*default* 1.0). Why: an opponent heavier than estimated raises the ego Δv and pulse,
    /// and with it the risk of bottoming out through a too-soft restraint; a lighter one only
    /// costs some comfort (paper: ±300 kg moves a_mean by ~2 g). k = 1 covers ~84 % of a
    /// Gaussian estimate one-sided.
    pub conservative_mass_k: f64,

    /// Enter PRE-CRASH when the predicted time to contact is below this, ms (*default* 300).
    /// Must exceed the earliest pretensioner time of the LUT (−100 ms) plus one object period
    /// (20 ms) and the prediction latency, so the preset is ready before it is needed.
    pub preset_horizon_ms: f64,
    /// Leave PRE-CRASH (collision avoided) when the time to contact grows above
    /// `preset_horizon_ms` + this, ms (*default* 200; hysteresis against TTC noise).
    pub preset_exit_hysteresis_ms: f64,
    /// Leave PRE-CRASH (collision avoided) when the predicted contact time plus this has
    /// passed without crash confirmation, ms (*default* 60: contact-time estimate error of a
    /// 10–20 ms object list plus the ~10 ms the accelerometer needs to confirm).
    pub avoided_margin_ms: f64,
    /// Objects below this track confidence are ignored (*default* 0.5).
    pub min_confidence: f64,

    /// Airbag no-fire below this ego equivalent barrier speed, km/h (*default* 20). The paper
    /// gives "below about 20 km/h per vehicle adaptive restraints make no sense (no-fire)". The
    /// per-vehicle speed of a car-to-car crash is the ego's change of speed to the common
    /// velocity, v_close · m_opp / (m_ego + m_opp): v/2 for equal cars, v for a rigid barrier.
    /// The conservative opponent mass is used (fails towards firing).
    pub no_fire_ebs_kph: f64,

    /// Crash confirmation: the accelerometer is "awake" from this deceleration, g
    /// (*default* 1.5); the first awake sample is the measured contact instant.
    pub confirm_wake_g: f64,
    /// Crash confirmation: deceleration threshold, g (*default* 4.0: above road and braking
    /// loads (≤ 1.2 g) and potholes' short spikes are filtered by the persistence below).
    pub confirm_decel_g: f64,
    /// Crash confirmation: consecutive samples over `confirm_decel_g` (*default* 3 = 3 ms at
    /// 1 kHz, 0.75 ms at 4 kHz: rejects single-sample spikes).
    pub confirm_samples: u32,
    /// Crash confirmation: Δv integrated since wake-up, m/s (*default* 0.5 m/s ≈ 1.8 km/h:
    /// reached 4–8 ms after contact from 20 to 54 km/h per vehicle, so confirmation comes
    /// before the reference fire time of 10 ms; a bump or pothole does not integrate to it).
    pub confirm_delta_v_mps: f64,
    /// Crash confirmation: the integrator is reset after this long below the wake threshold,
    /// ms (*default* 10).
    pub confirm_reset_gap_ms: f64,

    /// Object data older than this (by receipt) is stale → DEGRADED, ms (*default* 100 = five
    /// missed samples of a 20 ms object list).
    pub object_timeout_ms: f64,
    /// Ego vehicle state (10 ms cycle) older than this → DEGRADED, ms (*default* 100).
    pub vehicle_timeout_ms: f64,
    /// Occupant classification (100 ms cycle) older than this → DEGRADED, ms (*default* 500).
    pub occupant_timeout_ms: f64,
    /// E2E failure burst: this many rejected input frames ... (*default* 3, max 16)
    pub e2e_burst_count: u32,
    /// ... within this window, ms (*default* 100) → DEGRADED ...
    pub e2e_burst_window_ms: f64,
    /// ... held until this long after the last rejection, ms (*default* 500).
    pub e2e_hold_ms: f64,
    /// Alive-counter gap tolerated without rejection (AUTOSAR MaxDeltaCounter − 1;
    /// *default* 1: one lost frame on a loaded bus is not a fault).
    pub e2e_max_lost: u8,

    /// The track filter of the object samples (`[cycle.track]`; see
    /// [`crate::estimate::track`]). The collision prediction has no setting: it is solved in
    /// closed form (no step size).
    pub track: TrackConfig,
}

impl Default for CycleConfig {
    fn default() -> Self {
        Self {
            ego_mass_kg: 1785.0,
            ego_class: 4,
            conservative_mass_k: 1.0,
            preset_horizon_ms: 300.0,
            preset_exit_hysteresis_ms: 200.0,
            avoided_margin_ms: 60.0,
            min_confidence: 0.5,
            no_fire_ebs_kph: 20.0,
            confirm_wake_g: 1.5,
            confirm_decel_g: 4.0,
            confirm_samples: 3,
            confirm_delta_v_mps: 0.5,
            confirm_reset_gap_ms: 10.0,
            object_timeout_ms: 100.0,
            vehicle_timeout_ms: 100.0,
            occupant_timeout_ms: 500.0,
            e2e_burst_count: 3,
            e2e_burst_window_ms: 100.0,
            e2e_hold_ms: 500.0,
            e2e_max_lost: 1,
            track: TrackConfig::default(),
        }
    }
}

/// Most E2E rejections remembered for burst detection (size of a preallocated ring).
pub const MAX_E2E_BURST: usize = 16;

impl CycleConfig {
    /// Range checks; the error names the key.
    pub fn validate(&self) -> Result<(), ConfigError> {
        fn range(key: &'static str, value: f64, lo: f64, hi: f64) -> Result<(), ConfigError> {
            if value.is_finite() && (lo..=hi).contains(&value) {
                Ok(())
            } else {
                Err(ConfigError { key, value, lo, hi })
            }
        }
        range("ego_mass_kg", self.ego_mass_kg, 500.0, 5000.0)?;
        range("ego_class", f64::from(self.ego_class), 1.0, 6.0)?;
        range("conservative_mass_k", self.conservative_mass_k, 0.0, 5.0)?;
        range("preset_horizon_ms", self.preset_horizon_ms, 50.0, 5000.0)?;
        range(
            "preset_exit_hysteresis_ms",
            self.preset_exit_hysteresis_ms,
            0.0,
            5000.0,
        )?;
        range("avoided_margin_ms", self.avoided_margin_ms, 0.0, 1000.0)?;
        range("min_confidence", self.min_confidence, 0.0, 1.0)?;
        range("no_fire_ebs_kph", self.no_fire_ebs_kph, 0.0, 100.0)?;
        range("confirm_wake_g", self.confirm_wake_g, 0.1, 50.0)?;
        range(
            "confirm_decel_g",
            self.confirm_decel_g,
            self.confirm_wake_g,
            100.0,
        )?;
        range(
            "confirm_samples",
            f64::from(self.confirm_samples),
            1.0,
            100.0,
        )?;
        range("confirm_delta_v_mps", self.confirm_delta_v_mps, 0.0, 20.0)?;
        range(
            "confirm_reset_gap_ms",
            self.confirm_reset_gap_ms,
            0.1,
            1000.0,
        )?;
        range("object_timeout_ms", self.object_timeout_ms, 1.0, 10_000.0)?;
        range("vehicle_timeout_ms", self.vehicle_timeout_ms, 1.0, 10_000.0)?;
        range(
            "occupant_timeout_ms",
            self.occupant_timeout_ms,
            1.0,
            10_000.0,
        )?;
        range(
            "e2e_burst_count",
            f64::from(self.e2e_burst_count),
            1.0,
            MAX_E2E_BURST as f64,
        )?;
        range(
            "e2e_burst_window_ms",
            self.e2e_burst_window_ms,
            1.0,
            10_000.0,
        )?;
        range("e2e_hold_ms", self.e2e_hold_ms, 0.0, 60_000.0)?;
        range("e2e_max_lost", f64::from(self.e2e_max_lost), 0.0, 14.0)?;
        self.track.validate()
    }
}

/// A decision setting outside its range (the shell adds where it came from).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ConfigError {
    /// Key inside `[cycle]`.
    pub key: &'static str,
    /// The value given.
    pub value: f64,
    /// Smallest allowed value.
    pub lo: f64,
    /// Largest allowed value.
    pub hi: f64,
}

impl core::fmt::Display for ConfigError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        let Self { key, value, lo, hi } = self;
        write!(f, "cycle.{key} = {value} is outside {lo}..={hi}")
    }
}

/// ms (config) → ns (cycle), saturating, NaN → 0.
pub(crate) fn ms_to_ns(ms: f64) -> u64 {
    // `as` from float saturates and maps NaN to 0: never panics.
    (ms * 1.0e6) as u64
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_valid_and_bad_values_name_the_key() {
        CycleConfig::default().validate().unwrap();
        let c = CycleConfig {
            conservative_mass_k: f64::NAN,
            ..CycleConfig::default()
        };
        assert_eq!(c.validate().unwrap_err().key, "conservative_mass_k");
        let c = CycleConfig {
            e2e_burst_count: 17,
            ..CycleConfig::default()
        };
        let e = c.validate().unwrap_err();
        assert_eq!((e.key, e.value, e.hi), ("e2e_burst_count", 17.0, 16.0));
    }
}
