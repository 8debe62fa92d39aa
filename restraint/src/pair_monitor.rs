//! Pair plausibility: the crash and safing accelerometers sit in one housing and read the same
//! rigid-body acceleration; a sensor that departs from its partner by more than their
//! specified offset and noise is faulty, and the one that departs from the vehicle's own
//! acceleration on CAN is the faulty one.
//!
//! **Why.** The per-sensor checks (`accel`: stale, stuck, saturated, out of range) catch a
//! sensor that stops measuring. A sensor that keeps measuring with a standing offset or with
//! noise far beyond its specification passes them, and inside a real crash it costs the
//! deployment: an offset that reads the car *forward* raises the roughness lift (module
//! `roughness`) until no crash reaches its floor; noise holds the event's onset and segment
//! apart. Such a sensor is no measurement: it is flagged as the per-sensor checks flag a
//! dead one (`ACCEL_INVALID` / `SAFING_INVALID`, held [`crate::accel::INVALID_HOLD_MS`]) and the
//! paths that cover a dead sensor take over — the backup path (a predicted crash and the
//! vehicle deceleration on CAN) for the crash sensor, the vehicle deceleration standing in
//! for safing for the safing sensor. Flagging never adds a path to Fire: a flagged crash
//! sensor can only be replaced by two other sources, a flagged safing sensor by a third.
//!
//! **Rule** (once per cycle in which both sensors delivered samples; `d` = the difference of
//! the two sensors' mean decelerations over the cycle):
//! - the pair's disagreement `p` = mean square of `d`, exponentially averaged over
//!   [`AVERAGE_MS`]; the pair **disagrees** while `√p` > [`PAIR_LIMIT_G`] (1 g: a standing
//!   offset of ≥ 1 g or band-limited noise of ≥ 1 g rms on one of them; two healthy sensors
//!   differ by their noise, ≈ 0.05 g over a 1 ms cycle, and by the 0.125 ms between their
//!   batches' mean sample times, ≤ 0.6 g on the steepest crash ramp);
//! - each sensor's departure `e` = mean square of (its mean deceleration − the vehicle frame's),
//!   averaged over [`DEPARTURE_AVERAGE_MS`]; the vehicle frame carries the rigid-body motion both sensors must read, so
//!   a fault adds its own power to its sensor's `e` only (`e_faulty − e_healthy ≈ p`);
//! - a disagreeing pair flags the sensor whose `e` exceeds the other's by half of `p`;
//!   without a fresh vehicle frame, both (the pair cannot be trusted, nothing says which);
//! - the departures are only compared while the vehicle frame and at least one of the two
//!   sensors read under [`ATTRIBUTE_BELOW_G`]: in a crash the 10 ms frame lags the sensors
//!   by up to a period, and a fault that appears with the crash would be blamed on its healthy
//!   partner. There the pair's disagreement is left to the crash phase (`agreement`: a
//!   disagreeing pair hands the event to the backup path).
//!
//! A crash phase the flagged crash sensor confirmed on its own (noise through the wake
//! threshold) is handed to the backup path as a disagreeing pair's is (`Decision`).
//!
//! Allocation-free, O(1) per cycle: the batches' sums are computed while they are checked.

use crate::accel::{PlausibleBatch, INVALID_HOLD_MS};
use crate::settings::{ms_to_ns, G_MPS2};

/// Averaging time of the pair's disagreement, ms: a 2 g offset passes the limit within 2 ms.
pub const AVERAGE_MS: f64 = 5.0;
/// Averaging time of the sensors' departures from the vehicle frame, ms: long enough that a
/// fault's own power, not its momentary product with the road's motion, decides which sensor
/// it is on. A step fault of any size is attributed 13 ms after it appears (the first cycle
/// with e_faulty − e_healthy > p/2), short against the 0–200 ms a fault may precede contact.
pub const DEPARTURE_AVERAGE_MS: f64 = 20.0;
/// Largest rms difference of two healthy sensors' cycle means, g (see the module docs).
pub const PAIR_LIMIT_G: f64 = 1.0;
/// The departures are compared only while the vehicle frame's deceleration magnitude is under
/// this, g (ordinary driving and braking; a crash lags on the 10 ms frame).
pub const ATTRIBUTE_BELOW_G: f64 = 2.0;

/// [`PAIR_LIMIT_G`] squared, (m/s²)² (the averaged square difference is compared with it).
const PAIR_LIMIT_SQ_MPS2: f64 = (PAIR_LIMIT_G * G_MPS2) * (PAIR_LIMIT_G * G_MPS2);
/// [`ATTRIBUTE_BELOW_G`] in m/s².
const ATTRIBUTE_BELOW_MPS2: f64 = ATTRIBUTE_BELOW_G * G_MPS2;

/// One sensor's readings over a cycle: their sum and count (m/s², negative = deceleration).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct CycleMean {
    sum_mps2: f64,
    n: u32,
}

impl CycleMean {
    /// Adds a batch's plausible samples.
    #[inline]
    pub fn add(&mut self, b: &PlausibleBatch) {
        let (sum, n) = b.sum_and_len();
        self.sum_mps2 += sum;
        self.n += n;
    }

    /// The mean deceleration, m/s² (positive = slowing), if any sample came.
    fn decel_mps2(&self) -> Option<f64> {
        (self.n > 0).then(|| -self.sum_mps2 / f64::from(self.n))
    }
}

/// Which sensors this cycle found faulty.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct PairVerdict {
    /// The crash accelerometer departs from its partner and the vehicle.
    pub crash_faulty: bool,
    /// The safing accelerometer departs from its partner and the vehicle.
    pub safing_faulty: bool,
}

/// State of the pair plausibility check.
#[derive(Debug, Clone, PartialEq)]
pub struct PairMonitor {
    /// Averaged square of the pair's difference, (m/s²)².
    p: f64,
    /// Averaged square departure of the crash and the safing sensor from the vehicle frame.
    e_crash: f64,
    e_safing: f64,
    last_ns: Option<u64>,
    /// The crash sensor was last flagged at this time + the hold, ns.
    crash_until_ns: Option<u64>,
}

impl Default for PairMonitor {
    fn default() -> Self {
        Self::new()
    }
}

impl PairMonitor {
    /// Two agreeing sensors so far.
    pub const fn new() -> Self {
        Self {
            p: 0.0,
            e_crash: 0.0,
            e_safing: 0.0,
            last_ns: None,
            crash_until_ns: None,
        }
    }

    /// This check flagged the crash sensor within the hold time before `now`.
    pub fn crash_flagged(&self, now: u64) -> bool {
        self.crash_until_ns.is_some_and(|t| now <= t)
    }

    /// One cycle at `now`: the two sensors' readings over it, and the fresh vehicle frame's
    /// deceleration (m/s², positive = slowing; `None` when stale). Nothing is judged in a cycle
    /// in which either sensor delivered nothing (a missing sensor is the per-sensor checks').
    pub fn on_cycle(
        &mut self,
        now: u64,
        crash: &CycleMean,
        safing: &CycleMean,
        vehicle_decel_mps2: Option<f64>,
    ) -> PairVerdict {
        let (Some(c), Some(s)) = (crash.decel_mps2(), safing.decel_mps2()) else {
            return PairVerdict::default();
        };
        // The averages' weights for the time since the last judged cycle (1 ms: 1/5, 1/20).
        let dt_ms = self
            .last_ns
            .map_or(1.0, |t| now.saturating_sub(t) as f64 * 1e-6);
        self.last_ns = Some(now);
        let a = (dt_ms * (1.0 / AVERAGE_MS)).min(1.0);
        let ae = (dt_ms * (1.0 / DEPARTURE_AVERAGE_MS)).min(1.0);
        let d = c - s;
        self.p += a * (d * d - self.p);
        let quiet = |x: f64| x.abs() < ATTRIBUTE_BELOW_MPS2;
        let attribute = vehicle_decel_mps2.filter(|&v| quiet(v) && (quiet(c) || quiet(s)));
        if let Some(v) = attribute {
            self.e_crash += ae * ((c - v) * (c - v) - self.e_crash);
            self.e_safing += ae * ((s - v) * (s - v) - self.e_safing);
        }
        // The common answer first: the pair agrees.
        if self.p <= PAIR_LIMIT_SQ_MPS2 {
            return PairVerdict::default();
        }
        // Plausible samples are finite and within full scale, and so are the averages; a NaN
        // (a frame's value the codec let through) resets them rather than silencing the check.
        if !(self.p.is_finite() && self.e_crash.is_finite() && self.e_safing.is_finite()) {
            (self.p, self.e_crash, self.e_safing) = (0.0, 0.0, 0.0);
            return PairVerdict::default();
        }
        let vehicle = vehicle_decel_mps2.filter(|v| v.is_finite());
        let verdict = match (vehicle, attribute) {
            (None, _) => PairVerdict {
                crash_faulty: true,
                safing_faulty: true,
            },
            (Some(_), None) => PairVerdict::default(),
            (Some(_), Some(_)) => PairVerdict {
                crash_faulty: self.e_crash - self.e_safing > 0.5 * self.p,
                safing_faulty: self.e_safing - self.e_crash > 0.5 * self.p,
            },
        };
        if verdict.crash_faulty {
            self.crash_until_ns = Some(now.saturating_add(ms_to_ns(INVALID_HOLD_MS)));
        }
        verdict
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const MS: u64 = 1_000_000;

    /// One cycle's mean of `g` (deceleration, g) as the cycle's readings.
    fn mean(g: f64) -> CycleMean {
        CycleMean {
            sum_mps2: -g * G_MPS2 * 4.0,
            n: 4,
        }
    }

    /// Runs `ms` cycles of crash/safing/vehicle decelerations (g) from `t(ms)`; returns the
    /// first cycle (ms) with each verdict flag.
    fn run(
        m: &mut PairMonitor,
        ms: u64,
        f: impl Fn(f64) -> (f64, f64, Option<f64>),
    ) -> (Option<u64>, Option<u64>) {
        let (mut crash, mut safing) = (None, None);
        for k in 1..=ms {
            let (c, s, v) = f(k as f64);
            let r = m.on_cycle(k * MS, &mean(c), &mean(s), v.map(|g| g * G_MPS2));
            if r.crash_faulty && crash.is_none() {
                crash = Some(k);
            }
            if r.safing_faulty && safing.is_none() {
                safing = Some(k);
            }
        }
        (crash, safing)
    }

    #[test]
    fn two_healthy_sensors_in_a_crash_and_on_a_braking_drive_are_never_flagged() {
        let mut m = PairMonitor::new();
        // Braking at 0.9 g, then a 30 g crash ramp of 5 g/ms whose safing batches lag the
        // crash sensor's by 0.125 ms (0.6 g), the vehicle frame a 10 ms step behind.
        let ramp = |t: f64| ((t - 100.0) * 5.0).clamp(0.0, 30.0);
        let r = run(&mut m, 200, |t| {
            let v = ramp(((t / 10.0).floor() - 1.0) * 10.0).max(0.9);
            (ramp(t).max(0.9), (ramp(t) - 0.6).max(0.9), Some(v))
        });
        assert_eq!(r, (None, None));
        assert!(m.p.sqrt() < 0.7 * G_MPS2);
    }

    #[test]
    fn a_standing_offset_is_flagged_on_the_sensor_the_vehicle_frame_contradicts() {
        // Oracle: a step of size x from cycle 1 on: p(t) = x²·(1 − 0.8^t) (1 ms of 5 ms),
        // e_faulty(t) = x²·(1 − 0.95^t) (1 ms of 20 ms), e_healthy = 0. Flagged at the first t
        // with √p > 1 g (x = 2 g: t ≥ 2) and 1 − 0.95^t > (1 − 0.8^t)/2: t = 13 (at 12,
        // 0.4596 < 0.4656; at 13, 0.4867 > 0.4725), for any x.
        let mut m = PairMonitor::new();
        let r = run(&mut m, 40, |_| (-2.0, 0.0, Some(0.0)));
        assert_eq!(r, (Some(13), None));
        // The safing sensor reading 6 g high while cruising.
        let mut m = PairMonitor::new();
        let r = run(&mut m, 40, |_| (0.0, 6.0, Some(0.0)));
        assert_eq!(r, (None, Some(13)));
        // Half a gram of offset is within the pair's specification.
        let mut m = PairMonitor::new();
        assert_eq!(run(&mut m, 200, |_| (0.5, 0.0, Some(0.0))), (None, None));
    }

    #[test]
    fn without_a_vehicle_frame_a_disagreeing_pair_flags_both() {
        let mut m = PairMonitor::new();
        assert_eq!(run(&mut m, 10, |_| (3.0, 0.0, None)), (Some(1), Some(1)));
    }

    #[test]
    fn noise_on_one_sensor_is_blamed_on_it_and_a_shared_rough_road_flags_nothing() {
        // 1.5 g rms of 31 Hz noise on the safing sensor only, the car cruising.
        let mut m = PairMonitor::new();
        let noise =
            |t: f64| 1.5 * 2f64.sqrt() * (core::f64::consts::TAU * 31.0 * t * 1e-3 + 1.0).sin();
        let (crash, safing) = run(&mut m, 300, |t| (0.0, noise(t), Some(0.0)));
        assert!(safing.is_some_and(|k| k < 30), "{safing:?}");
        assert_eq!(crash, None);
        // A 20 Hz road of 3 g rms both read (the vehicle frame does not carry it) flags nothing.
        let road = |t: f64| 3.0 * 2f64.sqrt() * (core::f64::consts::TAU * 20.0 * t * 1e-3).sin();
        let mut m = PairMonitor::new();
        assert_eq!(
            run(&mut m, 300, |t| (road(t), road(t), Some(0.0))),
            (None, None)
        );
    }

    #[test]
    fn in_a_crash_on_the_vehicle_frame_nothing_is_attributed_and_nan_resets() {
        let mut m = PairMonitor::new();
        // The crash sensor 6 g low from the moment the vehicle frame shows 15 g.
        assert_eq!(run(&mut m, 20, |_| (9.0, 15.0, Some(15.0))), (None, None));
        let mut m = PairMonitor::new();
        let nan = CycleMean {
            sum_mps2: f64::NAN,
            n: 1,
        };
        assert_eq!(
            m.on_cycle(MS, &nan, &mean(0.0), Some(0.0)),
            PairVerdict::default()
        );
        assert_eq!(m.p, 0.0);
        // A cycle without one sensor's samples judges nothing.
        assert_eq!(
            m.on_cycle(2 * MS, &CycleMean::default(), &mean(9.0), Some(0.0)),
            PairVerdict::default()
        );
    }
}
