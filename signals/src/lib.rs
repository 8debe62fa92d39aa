//! The records that cross shared memory between the bench's processes and the ECU core —
//! the one interface both sides compile against, so that the transport (`ipc`), the sensor
//! feeds and the actuator stubs need not link the restraint core, and the core never links
//! the transport. `no_std`, no allocation, no dependency beyond `bitflags` and `strum`.
//!
//! What the cycle reads and writes besides CAN: the opponent object, the crash accelerometer,
//! the crush-zone satellites' PSI5 frames ([`psi5`]) and the diagnostics record, plus the mode and degraded-reason vocabulary they use.

#![no_std]
#![warn(missing_docs)]
// Every method here is a few instructions on the ECU cycle's path, called from another crate:
// `#[inline]` lets the core inline them as it did while they were its own module (the budget
// gate's instruction counts are the check).
//!
//! Plain `#[repr(C)]`, `Copy`, pointer-free records: the shell carries them over iceoryx2
//! shared memory (the `ipc` crate wraps each in its transport type), a microcontroller port
//! would fill them from its drivers. Flags are `u8`, not `bool`: a producer in another process
//! could write any byte, and a `bool` other than 0/1 is undefined behaviour in Rust.

pub mod psi5;
pub use psi5::{SatelliteFrames, SatelliteSide, SATELLITE_BATCH_CAPACITY};

/// `valid` flag value meaning "the producer vouches for this object".
pub const VALID: u8 = 1;

/// Opponent object / pre-crash state from the environment sensors (one tracked object).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct ObjectState {
    /// CLOCK_MONOTONIC time of the measurement (not of publication), ns.
    pub timestamp_ns: u64,
    /// Publisher sequence counter; gaps reveal dropped samples.
    pub sequence: u64,
    /// Longitudinal distance to the object, m (positive ahead).
    pub distance_m: f32,
    /// Closing speed, m/s (positive = approaching).
    pub closing_speed_mps: f32,
    /// Relative acceleration (rate of change of closing speed), m/s².
    pub relative_accel_mps2: f32,
    /// Estimated opponent mass, kg.
    pub opponent_mass_kg: f32,
    /// One-sigma uncertainty of the opponent mass, kg.
    pub opponent_mass_sigma_kg: f32,
    /// Track confidence 0..1.
    pub confidence: f32,
    /// Tracker object id.
    pub object_id: u32,
    /// [`VALID`] (1) if the track is valid; anything else is invalid.
    pub valid: u8,
    /// Explicit padding so the layout has no implicit holes.
    pub _reserved: [u8; 3],
}

impl ObjectState {
    /// An invalid, all-zero state (used as the "nothing received" value).
    pub const INVALID: Self = Self {
        timestamp_ns: 0,
        sequence: 0,
        distance_m: 0.0,
        closing_speed_mps: 0.0,
        relative_accel_mps2: 0.0,
        opponent_mass_kg: 0.0,
        opponent_mass_sigma_kg: 0.0,
        confidence: 0.0,
        object_id: 0,
        valid: 0,
        _reserved: [0; 3],
    };

    /// True if the producer flagged the track valid (does not check the values).
    #[inline]
    pub fn is_valid(&self) -> bool {
        self.valid == VALID
    }
}

impl Default for ObjectState {
    fn default() -> Self {
        Self::INVALID
    }
}

/// Maximum samples in one [`CrashAccelSample`] batch.
pub const ACCEL_BATCH_CAPACITY: usize = 8;

/// A small batch of compartment accelerometer samples (longitudinal, vehicle frame).
///
/// Batching keeps the sample rate (e.g. 4–8 kHz) decoupled from the message rate.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct CrashAccelSample {
    /// CLOCK_MONOTONIC time of `accel_mps2[0]`, ns.
    pub first_timestamp_ns: u64,
    /// Publisher sequence counter.
    pub sequence: u64,
    /// Time between consecutive samples, ns.
    pub sample_period_ns: u32,
    /// Number of valid entries in `accel_mps2` (values above capacity are clamped by readers).
    pub count: u32,
    /// Longitudinal acceleration, m/s² (negative = deceleration).
    pub accel_mps2: [f32; ACCEL_BATCH_CAPACITY],
}

impl CrashAccelSample {
    /// An empty batch.
    pub const EMPTY: Self = Self {
        first_timestamp_ns: 0,
        sequence: 0,
        sample_period_ns: 0,
        count: 0,
        accel_mps2: [0.0; ACCEL_BATCH_CAPACITY],
    };

    /// The valid samples; a corrupt `count` is clamped, so this never panics.
    #[inline]
    pub fn samples(&self) -> &[f32] {
        let n = (self.count as usize).min(ACCEL_BATCH_CAPACITY);
        self.accel_mps2.get(..n).unwrap_or(&[])
    }
}

impl Default for CrashAccelSample {
    fn default() -> Self {
        Self::EMPTY
    }
}

/// Points of the predicted pulse carried in [`EcuDiagnostics`].
pub const PULSE_POINTS: usize = 64;

/// ECU operating mode as carried in diagnostics (`EcuDiagnostics::mode`). Byte values and
/// display names (kebab case) are derived (strum).
#[repr(u8)]
#[derive(Debug, Clone, Copy, PartialEq, Eq, strum::FromRepr, strum::IntoStaticStr)]
#[strum(serialize_all = "kebab-case")]
pub enum EcuMode {
    /// Runtime up, cycle logic not yet running.
    Startup = 0,
    /// Normal monitoring.
    Monitoring = 1,
    /// Collision predicted, settings preset.
    PreCrash = 2,
    /// Crash confirmed by the accelerometer.
    Crash = 3,
    /// After the crash.
    PostCrash = 4,
    /// Inputs degraded: conventional reference restraint.
    Degraded = 5,
}

impl EcuMode {
    /// Decodes a raw mode byte; unknown values map to `None`.
    #[inline]
    pub fn from_u8(v: u8) -> Option<Self> {
        Self::from_repr(v)
    }

    /// Short display name (`pre-crash`, …): the decision's phase, finer than the bus's mode
    /// (`restraint::bus_mode` maps one to the other).
    #[inline]
    pub fn name(self) -> &'static str {
        self.into()
    }
}

bitflags::bitflags! {
    /// Why the inputs are not trusted (`EcuDiagnostics::degraded_reasons` carries the bits).
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
    pub struct Degraded: u32 {
        /// Object state missing or older than the staleness limit.
        const OBJECT_STALE = 1 << 0;
        /// Object state present but invalid / out of range / NaN.
        const OBJECT_INVALID = 1 << 1;
        /// Accelerometer samples missing or stale.
        const ACCEL_STALE = 1 << 2;
        /// Accelerometer samples invalid.
        const ACCEL_INVALID = 1 << 3;
        /// CAN inputs stale (vehicle speed, occupant).
        const CAN_STALE = 1 << 4;
        /// E2E check failed on a CAN input.
        const E2E_FAILURE = 1 << 5;
        /// Characteristic diagram (LUT) missing or invalid.
        const LUT_INVALID = 1 << 6;
        /// CAN side switched off (`--no-can`) or unavailable.
        const CAN_DISABLED = 1 << 7;
        /// IPC receive errors (held 500 ms after the last).
        const IPC_ERROR = 1 << 8;
        /// Safing accelerometer samples missing or stale (not degrading: the vehicle
        /// deceleration stands in for it, module `safing`).
        const SAFING_STALE = 1 << 9;
        /// Safing accelerometer samples invalid, or receive errors on its port (not
        /// degrading, as `SAFING_STALE`).
        const SAFING_INVALID = 1 << 10;
        /// The left crush-zone satellite is out of the fusion: missing, stale, corrupt,
        /// defective or implausible (not degrading: the satellites never fire, they only lower
        /// the tunnel's thresholds, and without them the central-only logic decides).
        const SATELLITE_LEFT = 1 << 11;
        /// The right crush-zone satellite, as `SATELLITE_LEFT`.
        const SATELLITE_RIGHT = 1 << 12;
    }
}

impl Degraded {
    /// Reasons that switch the decision to the reference restraint. `CAN_DISABLED` is among
    /// them: without CAN there is no occupant information for the LUT; so are the crash
    /// accelerometer's faults (without it no adaptive plan can be confirmed in time: a
    /// predicted crash is then confirmed by the backup and gets the reference restraint).
    pub const DEGRADING: Self = Self::OBJECT_STALE
        .union(Self::OBJECT_INVALID)
        .union(Self::ACCEL_STALE)
        .union(Self::ACCEL_INVALID)
        .union(Self::IPC_ERROR)
        .union(Self::CAN_STALE)
        .union(Self::E2E_FAILURE)
        .union(Self::LUT_INVALID)
        .union(Self::CAN_DISABLED);
}

/// One record the sensor feeds published, as they log it (`sensor-feeds --log`) for the run's
/// recording: what was published, and when (CLOCK_MONOTONIC, ns). The log is postcard records
/// back to back.
#[cfg(feature = "serde")]
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FeedLogRecord {
    /// CLOCK_MONOTONIC time of the publish call, ns.
    pub published_ns: u64,
    /// What was published.
    pub item: FeedItem,
}

/// A published record of [`FeedLogRecord`], by service.
#[cfg(feature = "serde")]
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum FeedItem {
    /// On the object-list service.
    Object(ObjectState),
    /// On the crash accelerometer's service.
    CrashAccel(CrashAccelSample),
    /// On the safing accelerometer's service.
    SafingAccel(CrashAccelSample),
    /// On the left crush-zone satellite's service.
    SatelliteLeft(SatelliteFrames),
    /// On the right crush-zone satellite's service.
    SatelliteRight(SatelliteFrames),
}

/// ECU diagnostics, published every cycle (predicted pulse, chosen settings, mode, timing).
/// With the `serde` feature it (de)serializes field by field: how the actuator stubs log the
/// records they see and the `record` crate reads them back into a run's recording.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct EcuDiagnostics {
    /// CLOCK_MONOTONIC time of the cycle that produced this record, ns.
    pub timestamp_ns: u64,
    /// Cycles run since start.
    pub cycle_count: u64,
    /// Cycles that ended after the next deadline (skipped slots are not re-run).
    pub overrun_count: u64,
    /// Execution time of the previous cycle, ns.
    pub last_exec_ns: u64,
    /// Wake-up latency of this cycle (actual wake − deadline), ns.
    pub wake_latency_ns: u64,
    /// Sequence of the newest object state seen (0 = none).
    pub last_object_sequence: u64,
    /// Sequence of the newest accelerometer batch seen (0 = none).
    pub last_accel_sequence: u64,
    /// Object states received since start.
    pub object_samples_rx: u64,
    /// Accelerometer batches received since start.
    pub accel_batches_rx: u64,
    /// Predicted velocity change of the ego vehicle, m/s.
    pub predicted_delta_v_mps: f32,
    /// Predicted peak deceleration magnitude, m/s².
    pub predicted_a_max_mps2: f32,
    /// Predicted mean deceleration magnitude, m/s².
    pub predicted_a_mean_mps2: f32,
    /// Predicted contact duration, s.
    pub predicted_contact_time_s: f32,
    /// Predicted time to contact, s (negative/NaN when none).
    pub time_to_contact_s: f32,
    /// σ of the time to contact (the track filter's), s (NaN when none).
    pub time_to_contact_sigma_s: f32,
    /// Estimated closing speed at contact, m/s (NaN when none).
    pub closing_speed_mps: f32,
    /// σ of the closing speed at contact, m/s (NaN when none).
    pub closing_speed_sigma_mps: f32,
    /// Fused opponent mass estimate, kg (NaN when none; the prediction and the LUT use the
    /// conservative m + k·σ).
    pub opponent_mass_kg: f32,
    /// σ of the fused opponent mass, kg (NaN when none).
    pub opponent_mass_sigma_kg: f32,
    /// Time between consecutive `pulse_accel_mps2` points, s.
    pub pulse_dt_s: f32,
    /// Predicted pulse, ego acceleration m/s², from contact on.
    #[cfg_attr(feature = "serde", serde(with = "serde_big_array::BigArray"))]
    pub pulse_accel_mps2: [f32; PULSE_POINTS],
    /// Number of valid pulse points.
    pub pulse_points: u32,
    /// Chosen belt load-limiter level, N.
    pub belt_force_limit_n: f32,
    /// Chosen pretensioner fire time relative to predicted contact, s.
    pub pretensioner_time_s: f32,
    /// Chosen airbag fire time relative to contact, s.
    pub airbag_time_s: f32,
    /// Chosen airbag stage/level (0 = no fire).
    pub airbag_stage: u8,
    /// [`EcuMode`] as a byte.
    pub mode: u8,
    /// 1 if the pretensioner is commanded/fired.
    pub pretensioner_fired: u8,
    /// 1 if the airbag is commanded/fired.
    pub airbag_fired: u8,
    /// Bits of [`Degraded`].
    pub degraded_reasons: u32,
}

impl EcuDiagnostics {
    /// All-zero record in [`EcuMode::Startup`].
    pub const ZERO: Self = Self {
        timestamp_ns: 0,
        cycle_count: 0,
        overrun_count: 0,
        last_exec_ns: 0,
        wake_latency_ns: 0,
        last_object_sequence: 0,
        last_accel_sequence: 0,
        object_samples_rx: 0,
        accel_batches_rx: 0,
        predicted_delta_v_mps: 0.0,
        predicted_a_max_mps2: 0.0,
        predicted_a_mean_mps2: 0.0,
        predicted_contact_time_s: 0.0,
        time_to_contact_s: f32::NAN,
        time_to_contact_sigma_s: f32::NAN,
        closing_speed_mps: f32::NAN,
        closing_speed_sigma_mps: f32::NAN,
        opponent_mass_kg: f32::NAN,
        opponent_mass_sigma_kg: f32::NAN,
        pulse_dt_s: 0.0,
        pulse_accel_mps2: [0.0; PULSE_POINTS],
        pulse_points: 0,
        belt_force_limit_n: 0.0,
        pretensioner_time_s: 0.0,
        airbag_time_s: 0.0,
        airbag_stage: 0,
        mode: EcuMode::Startup as u8,
        pretensioner_fired: 0,
        airbag_fired: 0,
        degraded_reasons: 0,
    };

    /// The degraded reasons as a set (unknown bits dropped).
    #[inline]
    pub fn degraded(&self) -> Degraded {
        Degraded::from_bits_truncate(self.degraded_reasons)
    }
}

impl Default for EcuDiagnostics {
    fn default() -> Self {
        Self::ZERO
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn payloads_are_fixed_size_and_padding_free_where_it_matters() {
        // Sizes computed by hand from the field lists (repr(C), natural alignment).
        assert_eq!(
            core::mem::size_of::<ObjectState>(),
            8 + 8 + 6 * 4 + 4 + 1 + 3
        );
        assert_eq!(
            core::mem::size_of::<CrashAccelSample>(),
            8 + 8 + 4 + 4 + 8 * 4
        );
    }

    #[test]
    fn corrupt_accel_count_is_clamped() {
        let mut s = CrashAccelSample::EMPTY;
        s.count = u32::MAX;
        assert_eq!(s.samples().len(), ACCEL_BATCH_CAPACITY);
        s.count = 3;
        assert_eq!(s.samples().len(), 3);
    }

    #[test]
    fn mode_roundtrip() {
        for m in 0..=5u8 {
            assert_eq!(EcuMode::from_u8(m).map(|x| x as u8), Some(m));
        }
        assert_eq!(EcuMode::from_u8(6), None);
        // The names monitors and reports print.
        let names = [0, 2, 4, 5].map(|m| EcuMode::from_u8(m).map(EcuMode::name));
        assert_eq!(
            names,
            [
                Some("startup"),
                Some("pre-crash"),
                Some("post-crash"),
                Some("degraded")
            ]
        );
    }

    #[test]
    fn degraded_bits_are_the_published_ones() {
        // The diagnostics record's bit positions are an interface (monitors, stubs, tests).
        assert_eq!(Degraded::OBJECT_STALE.bits(), 1);
        assert_eq!(Degraded::CAN_DISABLED.bits(), 0x80);
        assert_eq!(Degraded::IPC_ERROR.bits(), 0x100);
        assert_eq!(Degraded::DEGRADING.bits(), 0b1_1111_1111);
        assert_eq!(Degraded::SAFING_STALE.bits(), 0x200);
        assert_eq!(Degraded::SAFING_INVALID.bits(), 0x400);
        assert_eq!(Degraded::SATELLITE_LEFT.bits(), 0x800);
        assert_eq!(Degraded::SATELLITE_RIGHT.bits(), 0x1000);
        assert!(
            !Degraded::DEGRADING.intersects(Degraded::SATELLITE_LEFT | Degraded::SATELLITE_RIGHT)
        );
    }
}
