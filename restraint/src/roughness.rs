//! Road roughness from the crash accelerometer: how far the road has recently pushed the car
//! *forward* — an excursion no crash makes — added to every crash-phase fire's severity floor.
//!
//! **Why.** A rough road is zero-mean: the tunnel's velocity swings back
//! as far as it swings forward. Its swings against the car's motion look, for their first tens
//! of ms, like a slow crash's onset, and on a long rough stretch at the matrix's 3–4.5 g rms
//! one of them now and then carries the 1.25 m/s floor (σ of the velocity ≈ 0.33 m/s at 3 g,
//! 0.5 m/s at 4.5 g over the 5–40 Hz band). A crash only ever slows the car: its velocity goes
//! one way. So the forward swings measure the road without being raised by the crash itself,
//! and a fire needs its floor *plus* that measure — a rough road's backward swing must then be
//! larger than its recent forward ones by the whole floor.
//!
//! **Measure.** The crash sensor's velocity high-passed at [`HIGH_PASS_S`] (a steady 0.3 g of
//! throttle leaves 0.15 m/s; braking and crashes only drive it negative); its positive part's
//! peak, held and decaying with `hold_s` (`roughness_hold_ms`, 0.5 s): a rough road's lobes
//! keep refreshing it, a single pothole's forward rebound lifts the floors for about that long
//! — a crash right after a pothole fires a few ms later, the safe direction. A faulty
//! crash sensor that reads forward (a negative spike or offset) also only raises the floors.
//! Allocation-free, a few operations per batch.

/// Time constant of the velocity high-pass, s: passes the rough road's band (≥ 5 Hz:
/// 1/(2π·5 Hz) = 32 ms), removes steady driving accelerations.
pub const HIGH_PASS_S: f64 = 0.050;

/// Forward excursion that lifts nothing, m/s: the sensor's noise and ordinary driving leave a
/// few mm/s (the library's crashes: ≤ 0.003 m/s, which moved a 31 + 31 km/h crash's airbag,
/// right at its floor, by 2 ms); a rough road's swings are tenths of m/s and more.
pub const DEAD_BAND_MPS: f64 = 0.05;

/// Velocities below this are zero (see [`Roughness::push`]), m/s.
const FLUSH_BELOW_MPS: f64 = 1e-100;

/// State of the roughness measure.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Roughness {
    /// How much of the measure a floor adds (0 = off).
    k: f64,
    /// Decay time of the held peak, s.
    hold_s: f64,
    /// High-passed velocity, m/s (positive = forward).
    v_hp_mps: f64,
    /// Held peak of the forward excursion, m/s.
    peak_mps: f64,
}

impl Roughness {
    /// A smooth road so far; `k` × the measure is added to the floors, the peak decays over
    /// `hold_s`.
    pub fn new(k: f64, hold_s: f64) -> Self {
        Self {
            k,
            hold_s,
            v_hp_mps: 0.0,
            peak_mps: 0.0,
        }
    }

    /// One batch of plausible samples: they slowed the car by `decel_integral_mps`
    /// (Σ decel · dt) over `span_s` (`PlausibleBatch::decel_integral_mps`). Once per batch, not
    /// per sample: the measure runs every cycle of a drive, and within a 1 ms batch the
    /// velocity moves by ≤ 0.015 m/s while the road is quiet (< 1.5 g).
    #[inline]
    pub fn push(&mut self, decel_integral_mps: f64, span_s: f64) {
        // Forward Euler of v' = −decel − v/τ (span ≤ 1 ms ≪ τ); then the decaying peak.
        self.v_hp_mps += -decel_integral_mps - self.v_hp_mps * (span_s / HIGH_PASS_S);
        if !self.v_hp_mps.is_finite() {
            self.v_hp_mps = 0.0; // plausible samples are finite; never stay stuck on NaN
        }
        self.peak_mps *= 1.0 - (span_s / self.hold_s).min(1.0);
        if self.v_hp_mps > self.peak_mps {
            self.peak_mps = self.v_hp_mps;
        }
        // Both decay geometrically on a quiet road and would sink into subnormal numbers
        // (the peak after ≈ 6 min at a 0.5 s hold), on which Intel CPUs take ≈ 100 cycles an
        // operation: a cycle's cost would then depend on the CPU. Far below any excursion
        // that matters, they are zero.
        if self.v_hp_mps.abs() < FLUSH_BELOW_MPS {
            self.v_hp_mps = 0.0;
        }
        if self.peak_mps < FLUSH_BELOW_MPS {
            self.peak_mps = 0.0;
        }
    }

    /// What it adds to a fire's severity floor now: `k` × the held forward excursion beyond
    /// [`DEAD_BAND_MPS`], m/s (≥ 0).
    pub fn floor_lift_mps(&self) -> f64 {
        let lift = self.k * (self.peak_mps - DEAD_BAND_MPS);
        if lift >= 0.0 {
            lift
        } else {
            0.0
        }
    }

    /// The held forward excursion, m/s (diagnostics).
    pub fn peak_mps(&self) -> f64 {
        self.peak_mps
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::settings::G_MPS2;

    /// 1 ms batches of four 4 kHz samples of `g(t)` (deceleration, g).
    fn run(r: &mut Roughness, ms: u64, g: impl Fn(f64) -> f64) {
        for m in 0..ms {
            let sum: f64 = (0..4)
                .map(|k| g((m * 4 + k) as f64 * 0.25e-3) * G_MPS2 * 0.25e-3)
                .sum();
            r.push(sum, 1e-3);
        }
    }

    #[test]
    fn a_crash_and_braking_never_lift_the_floor() {
        let mut r = Roughness::new(1.0, 2.0);
        run(&mut r, 500, |_| 0.9); // braking
        run(&mut r, 100, |t| (t * 2_000.0).min(30.0)); // a crash ramp to 30 g
        assert_eq!(r.floor_lift_mps(), 0.0);
    }

    #[test]
    fn a_zero_mean_swing_lifts_it_by_its_forward_excursion() {
        // 5 g at 10 Hz for 0.5 s: forward lobes of 2·a/(2πf)... the high-passed velocity's
        // amplitude is a/(ω·√(1 + 1/(ωτ)²)) = 49.03/62.83/1.025 ≈ 0.76 m/s.
        let mut r = Roughness::new(1.0, 2.0);
        run(&mut r, 500, |t| {
            5.0 * (core::f64::consts::TAU * 10.0 * t).sin()
        });
        let peak = r.peak_mps();
        assert!((0.65..0.85).contains(&peak), "{peak}");
        assert!((r.floor_lift_mps() - (peak - DEAD_BAND_MPS)).abs() < 1e-12);
        // ... and it decays once the road is smooth again (hold 2 s: e⁻¹ after 2 s).
        run(&mut r, 2_000, |_| 0.0);
        assert!((r.peak_mps() / peak - (-1.0f64).exp()).abs() < 0.05);
    }

    /// Minutes of a quiet road after a swing: the decaying measure reaches zero instead of
    /// lingering as subnormal numbers.
    #[test]
    fn a_quiet_road_decays_the_measure_to_zero_not_to_subnormal_numbers() {
        let mut r = Roughness::new(1.0, 0.5);
        run(&mut r, 500, |t| {
            5.0 * (core::f64::consts::TAU * 10.0 * t).sin()
        });
        assert!(r.peak_mps() > 0.5);
        for _ in 0..600_000 {
            r.push(0.0, 1e-3);
            for v in [r.v_hp_mps, r.peak_mps] {
                assert!(v == 0.0 || v.is_normal(), "{v:e}");
            }
        }
        assert_eq!(r.peak_mps(), 0.0);
    }

    #[test]
    fn off_adds_nothing_and_nan_adds_nothing() {
        let mut r = Roughness::new(0.0, 2.0);
        run(&mut r, 200, |t| {
            5.0 * (core::f64::consts::TAU * 10.0 * t).sin()
        });
        assert_eq!(r.floor_lift_mps(), 0.0);
        let mut r = Roughness::new(1.0, 2.0);
        r.push(f64::NAN, 1e-3);
        assert_eq!(r.floor_lift_mps(), 0.0);
    }
}
