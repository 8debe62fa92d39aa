//! Crash-accelerometer monitoring: is the sensor alive, and is what it says a measurement?
//!
//! Every batch is checked before any of its samples reaches a crash detector:
//!
//! | check | rule | reaction |
//! |---|---|---|
//! | **stale** | no batch received for `accel_timeout_ms` (50 ms; by receipt time; none yet = stale) | `ACCEL_STALE` while it lasts |
//! | **time** | sample period 0 or > 10 ms; a batch that starts before the previous one ended (half a period of slack: non-monotonic time); a first sample older than the timeout or more than one cycle in the future | batch dropped, `ACCEL_INVALID` held |
//! | **out of range** | a non-finite sample, or one beyond the sensor's measuring range (`accel_full_scale_g`) | sample dropped, `ACCEL_INVALID` held |
//! | **saturated** | a sample at full scale (within 0.1 %: a sensor pinned at its rail) | sample dropped, `ACCEL_INVALID` held |
//! | **stuck** | bit-identical readings for `accel_stuck_ms` (20 ms) | `ACCEL_INVALID` held |
//!
//! `ACCEL_INVALID` is held for [`INVALID_HOLD_MS`] after the last implausible sample, so a
//! flickering sensor cannot toggle the decision every cycle. Why a stuck sensor is caught by
//! bit-identity: a live MEMS accelerometer's noise (≥ 1 LSB) changes its reading from sample
//! to sample; the bench's sensor model has 0.5 m/s² of noise, so identical readings for 20 ms
//! (80 samples at 4 kHz) do not happen by chance. A sensor with a coarse LSB and little noise
//! needs a longer `accel_stuck_ms`.
//!
//! Plausible samples come out in time order, as [`AccelSample`]s in a fixed-capacity batch
//! ([`PlausibleBatch`]: no allocation, and the detectors are called without dynamic dispatch).

use crate::settings::ms_to_ns;
use crate::signals::ACCEL_BATCH_CAPACITY;

/// The plausible samples of one batch: the batch's timing once, each sample as its index in
/// the batch and its reading (8 bytes instead of a 24-byte [`AccelSample`]: this runs for every
/// sample of a drive, and the quiet ones need only their reading).
#[derive(Debug, Clone, Default)]
pub struct PlausibleBatch {
    first_ns: u64,
    period_ns: u64,
    dt_s: f64,
    /// (index in the batch, acceleration m/s², negative = deceleration).
    readings: heapless::Vec<(u8, f32), ACCEL_BATCH_CAPACITY>,
    /// The lowest reading (the highest deceleration), m/s² (+∞ when empty): every detector
    /// asks whether a batch is quiet, so it is answered once while the batch is built.
    min_accel_mps2: f32,
    /// The readings' sum, m/s² (for the batch's velocity change, [`Self::decel_integral_mps`]).
    sum_accel_mps2: f32,
}

impl PlausibleBatch {
    /// An empty batch.
    pub const fn new() -> Self {
        Self {
            first_ns: 0,
            period_ns: 0,
            dt_s: 0.0,
            readings: heapless::Vec::new(),
            min_accel_mps2: f32::INFINITY,
            sum_accel_mps2: 0.0,
        }
    }

    fn clear(&mut self) {
        self.readings.clear();
        self.min_accel_mps2 = f32::INFINITY;
        self.sum_accel_mps2 = 0.0;
    }

    #[inline]
    fn push(&mut self, i: u8, a: f32) {
        // Cannot fail: at most ACCEL_BATCH_CAPACITY samples are read.
        let _ = self.readings.push((i, a));
        self.min_accel_mps2 = self.min_accel_mps2.min(a);
        self.sum_accel_mps2 += a;
    }

    /// Takes off a deceleration the car's braking explains (`decel_mps2`, m/s²; nothing when it
    /// is not positive): every reading as if the car were not braking (sustained braking is not
    /// crash evidence; `CycleConfig::braking_compensation_max_g`).
    pub fn remove_decel(&mut self, decel_mps2: f64) {
        if !(decel_mps2 > 0.0) {
            return;
        }
        let b = decel_mps2 as f32;
        for r in self.readings.iter_mut() {
            r.1 += b;
        }
        self.min_accel_mps2 += b;
        self.sum_accel_mps2 += b * self.readings.len() as f32;
    }

    /// The readings' sum, m/s² (negative = deceleration), and their number.
    pub fn sum_and_len(&self) -> (f64, u32) {
        (f64::from(self.sum_accel_mps2), self.readings.len() as u32)
    }

    /// Number of plausible samples.
    pub fn len(&self) -> usize {
        self.readings.len()
    }

    /// No plausible sample.
    pub fn is_empty(&self) -> bool {
        self.readings.is_empty()
    }

    /// Every sample's deceleration is below `decel_mps2` (true when empty).
    pub fn all_below(&self, decel_mps2: f64) -> bool {
        // decel = −a < d  ⇔  a > −d (the readings are finite: the monitor checked them).
        f64::from(self.min_accel_mps2) > -decel_mps2
    }

    /// The batch's deceleration integrated with the rectangle rule, m/s (Σ decel · dt: how much
    /// the samples slowed the car), and the time they cover, s — for measures that need the
    /// batch's velocity, not each sample's (`roughness`).
    pub fn decel_integral_mps(&self) -> (f64, f64) {
        let span_s = self.dt_s * self.readings.len() as f64;
        (-f64::from(self.sum_accel_mps2) * self.dt_s, span_s)
    }

    /// The deceleration of the newest sample, m/s².
    pub fn last_decel_mps2(&self) -> Option<f64> {
        self.readings.last().map(|&(_, a)| -f64::from(a))
    }

    /// The newest sample: its time (ns) and deceleration (m/s²).
    pub fn last_sample(&self) -> Option<(u64, f64)> {
        self.readings.last().map(|&(i, a)| {
            let t = u64::from(i).saturating_mul(self.period_ns);
            (self.first_ns.saturating_add(t), -f64::from(a))
        })
    }

    /// The samples, in time order.
    pub fn iter(&self) -> impl Iterator<Item = AccelSample> + '_ {
        self.readings.iter().map(|&(i, a)| AccelSample {
            t_ns: self
                .first_ns
                .saturating_add(u64::from(i).saturating_mul(self.period_ns)),
            dt_s: self.dt_s,
            decel_mps2: -f64::from(a),
        })
    }
}

/// How long an implausible accelerometer sample keeps `ACCEL_INVALID` set, ms.
pub const INVALID_HOLD_MS: f64 = 500.0;
/// Longest sample period accepted, ns (10 ms: slower than any crash sensor).
pub const MAX_SAMPLE_PERIOD_NS: u32 = 10_000_000;
/// A batch's first sample may lie this far in the future of the cycle's clock (one cycle of
/// jitter between the sensor's and the ECU's time stamps), ns.
const FUTURE_SLACK_NS: u64 = 1_000_000;
/// Relative band around full scale that counts as saturated.
const SATURATION_BAND: f64 = 1.0e-3;

/// One plausible accelerometer sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AccelSample {
    /// Measurement time, ns (the sensor's clock = the cycle's CLOCK_MONOTONIC).
    pub t_ns: u64,
    /// Sample period, s (the integration step of this sample).
    pub dt_s: f64,
    /// Longitudinal deceleration, m/s² (positive = the car is slowed down).
    pub decel_mps2: f64,
}

/// Counts of what the monitor rejected (timing report).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct AccelFaultCounts {
    /// Batches dropped: unusable period, non-monotonic or out-of-window time stamps.
    pub bad_time_batches: u64,
    /// Samples dropped as non-finite or beyond the measuring range.
    pub out_of_range_samples: u64,
    /// Samples dropped as saturated (at full scale).
    pub saturated_samples: u64,
    /// Times the sensor was found stuck.
    pub stuck_events: u64,
    /// Cycles in which the sensor was stale.
    pub stale_cycles: u64,
}

/// State of the accelerometer monitoring.
#[derive(Debug, Clone)]
pub struct AccelMonitor {
    timeout_ns: u64,
    stuck_ns: u64,
    full_scale_mps2: f64,
    hold_ns: u64,
    /// Receipt time of the newest accepted batch.
    rx_ns: Option<u64>,
    /// Time of the newest accepted sample + half a period (where the next batch may start).
    next_from_ns: Option<u64>,
    /// Bits of the last reading and since when it has not changed.
    last_bits: Option<u32>,
    same_since_ns: u64,
    stuck: bool,
    invalid_until_ns: Option<u64>,
    /// What was rejected so far.
    pub faults: AccelFaultCounts,
}

/// The monitor's limits in its units (from the file's `accel_*` keys:
/// [`crate::CycleConfig::accel_limits`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AccelLimits {
    /// No batch for this long: the sensor is stale, ns.
    pub timeout_ns: u64,
    /// The same reading for this long: the sensor is stuck, ns.
    pub stuck_ns: u64,
    /// A reading at or beyond this magnitude is saturated, m/s².
    pub full_scale_mps2: f64,
}

impl AccelMonitor {
    /// Monitoring with the limits of a validated configuration.
    pub fn new(limits: AccelLimits) -> Self {
        let AccelLimits {
            timeout_ns,
            stuck_ns,
            full_scale_mps2,
        } = limits;
        Self {
            timeout_ns,
            stuck_ns,
            full_scale_mps2,
            hold_ns: ms_to_ns(INVALID_HOLD_MS),
            rx_ns: None,
            next_from_ns: None,
            last_bits: None,
            same_since_ns: 0,
            stuck: false,
            invalid_until_ns: None,
            faults: AccelFaultCounts::default(),
        }
    }

    fn implausible(&mut self, now: u64) {
        self.invalid_until_ns = Some(now.saturating_add(self.hold_ns));
    }

    /// Another check found the sensor's readings implausible at `now` (`pair_monitor`): held
    /// as the monitor's own findings are.
    pub(crate) fn flag_implausible(&mut self, now: u64) {
        self.implausible(now);
    }

    /// Checks one batch received at `now` (`first_ns`, `period_ns`, samples in m/s²,
    /// negative = deceleration; at most [`ACCEL_BATCH_CAPACITY`] are read) and puts its
    /// plausible samples into `out` (cleared first), in time order.
    pub fn feed(
        &mut self,
        now: u64,
        first_ns: u64,
        period_ns: u32,
        samples: &[f32],
        out: &mut PlausibleBatch,
    ) {
        out.clear();
        let too_old = now.saturating_sub(first_ns) > self.timeout_ns;
        let in_future = first_ns > now.saturating_add(FUTURE_SLACK_NS);
        let backwards = self.next_from_ns.is_some_and(|t| first_ns < t);
        if period_ns == 0 || period_ns > MAX_SAMPLE_PERIOD_NS || too_old || in_future || backwards {
            self.faults.bad_time_batches = self.faults.bad_time_batches.saturating_add(1);
            self.implausible(now);
            return;
        }
        self.rx_ns = Some(now);
        let dt_s = f64::from(period_ns) * 1.0e-9;
        let period = u64::from(period_ns);
        (out.first_ns, out.period_ns, out.dt_s) = (first_ns, period, dt_s);
        let out_of_range_mps2 = self.full_scale_mps2 * (1.0 + SATURATION_BAND);
        let saturated_mps2 = self.full_scale_mps2 * (1.0 - SATURATION_BAND);
        let samples = &samples[..samples.len().min(ACCEL_BATCH_CAPACITY)];
        let time_of = |i: u8| first_ns.saturating_add(u64::from(i) * period);
        if let Some(&last) = samples.last() {
            // Where the next batch may start: the newest sample + half a period.
            let last_ns = time_of(samples.len() as u8 - 1);
            self.next_from_ns = Some(last_ns.saturating_add(period / 2));
            // The common batch, checked in bulk: every reading within range and each differing
            // from the one before (a live sensor's noise) — all plausible, nothing stuck.
            // One pass; the first reading that breaks the rule sends the batch to the
            // sample-by-sample path below.
            let mut prev = self.last_bits;
            let mut bulk = true;
            for (i, &a) in (0u8..).zip(samples) {
                let bits = Some(a.to_bits());
                if !(f64::from(a).abs() < saturated_mps2) || bits == prev {
                    bulk = false;
                    break;
                }
                prev = bits;
                out.push(i, a);
            }
            if bulk {
                self.last_bits = Some(last.to_bits());
                self.same_since_ns = last_ns;
                self.stuck = false;
                return;
            }
        }
        // Sample by sample: a reading out of range, saturated, or repeated (the state in
        // locals, written back once).
        out.clear();
        let (mut last_bits, mut stuck) = (self.last_bits, self.stuck);
        // The index of the newest change of reading in this batch (its time is computed once,
        // after the loop, or where a repeated reading needs it).
        let mut changed_at: Option<u8> = None;
        let mut implausible = false;
        for (i, &a) in (0u8..).zip(samples) {
            let v = f64::from(a);
            let magnitude = v.abs();
            // One comparison for a plausible reading; NaN fails it too.
            if !(magnitude < saturated_mps2) {
                if magnitude <= out_of_range_mps2 {
                    self.faults.saturated_samples = self.faults.saturated_samples.saturating_add(1);
                } else {
                    self.faults.out_of_range_samples =
                        self.faults.out_of_range_samples.saturating_add(1);
                }
                implausible = true;
                continue;
            }
            let bits = a.to_bits();
            if last_bits == Some(bits) {
                let same_since_ns = changed_at.map_or(self.same_since_ns, time_of);
                if !stuck && time_of(i).saturating_sub(same_since_ns) >= self.stuck_ns {
                    stuck = true;
                    self.faults.stuck_events = self.faults.stuck_events.saturating_add(1);
                }
                if stuck {
                    implausible = true;
                    continue;
                }
            } else {
                last_bits = Some(bits);
                changed_at = Some(i);
                stuck = false;
            }
            out.push(i, a);
        }
        (self.last_bits, self.stuck) = (last_bits, stuck);
        if let Some(i) = changed_at {
            self.same_since_ns = time_of(i);
        }
        if implausible {
            self.implausible(now);
        }
    }

    /// How long the reading at sample time `t_ns` has been bit-identical, ns (0 before any
    /// reading, and at a sample that changed it): what a stuck sensor shows long before it is
    /// flagged (`accel_stuck_ms`).
    pub fn unchanged_for_ns(&self, t_ns: u64) -> u64 {
        if self.last_bits.is_none() {
            0
        } else {
            t_ns.saturating_sub(self.same_since_ns)
        }
    }

    /// No batch received within the timeout (none at all = stale).
    pub fn stale(&self, now: u64) -> bool {
        self.rx_ns
            .is_none_or(|t| now.saturating_sub(t) > self.timeout_ns)
    }

    /// An implausible batch or sample within the hold time (or the sensor is stuck now).
    pub fn invalid(&self, now: u64) -> bool {
        self.stuck || self.invalid_until_ns.is_some_and(|t| now <= t)
    }

    /// Counts one stale cycle (the cycle calls it once per cycle while stale).
    pub(crate) fn note_stale_cycle(&mut self) {
        self.faults.stale_cycles = self.faults.stale_cycles.saturating_add(1);
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use crate::settings::G_MPS2;
    use std::vec::Vec;

    const MS: u64 = 1_000_000;

    fn monitor() -> AccelMonitor {
        AccelMonitor::new(crate::CycleConfig::default().accel_limits())
    }

    /// Feeds one 4-sample 4 kHz batch ending at `now`; returns the samples passed on.
    fn feed(m: &mut AccelMonitor, now: u64, v: [f32; 4]) -> Vec<AccelSample> {
        let mut out = PlausibleBatch::new();
        m.feed(now, now - 750_000, 250_000, &v, &mut out);
        out.iter().collect()
    }

    #[test]
    fn a_reading_unchanged_since_its_last_change_is_timed_from_that_change() {
        let mut m = monitor();
        assert_eq!(m.unchanged_for_ns(5 * MS), 0, "no reading yet");
        // Samples at 9.25, 9.5, 9.75, 10 ms; the reading last changes at 9.5 ms.
        feed(&mut m, 10 * MS, [-1.0, -2.0, -2.0, -2.0]);
        assert_eq!(m.unchanged_for_ns(10 * MS), 500_000);
        feed(&mut m, 11 * MS, [-2.0, -2.0, -2.0, -2.0]);
        assert_eq!(m.unchanged_for_ns(11 * MS), 1_500_000);
        // A live batch: every reading differs, the newest changed it.
        feed(&mut m, 12 * MS, [-1.0, -2.0, -3.0, -4.0]);
        assert_eq!(m.unchanged_for_ns(12 * MS), 0);
    }

    #[test]
    fn a_live_sensor_is_passed_through_in_time_order_and_goes_stale_after_the_timeout() {
        let mut m = monitor();
        assert!(m.stale(0), "nothing received yet");
        let s = feed(&mut m, 10 * MS, [-1.0, -2.0, -3.0, -4.0]);
        assert_eq!(s.len(), 4);
        assert_eq!(s[0].t_ns, 10 * MS - 750_000);
        assert_eq!(s[3].decel_mps2, 4.0);
        assert_eq!(s[1].dt_s, 250e-6);
        assert!(!m.stale(10 * MS) && !m.invalid(10 * MS));
        // Default timeout 50 ms: stale strictly after it.
        assert!(!m.stale(60 * MS));
        assert!(m.stale(60 * MS + 1));
    }

    #[test]
    fn out_of_range_saturated_and_non_finite_samples_never_reach_a_detector() {
        let mut m = monitor();
        let fs = (200.0 * G_MPS2) as f32;
        let s = feed(&mut m, 10 * MS, [-fs, f32::NAN, -3.0 * fs, -100.0]);
        assert_eq!(s.len(), 1);
        assert_eq!(s[0].decel_mps2, 100.0);
        assert_eq!(m.faults.saturated_samples, 1);
        assert_eq!(m.faults.out_of_range_samples, 2);
        assert!(m.invalid(10 * MS));
        // Held 500 ms after the last implausible sample, then plausible again.
        assert!(m.invalid(510 * MS));
        assert!(!m.invalid(510 * MS + 1));
    }

    #[test]
    fn batches_going_back_in_time_or_from_the_past_or_future_are_dropped() {
        let mut m = monitor();
        assert_eq!(feed(&mut m, 10 * MS, [1.0, 2.0, 3.0, 4.0]).len(), 4);
        // The same batch again (a replayed or duplicated batch): starts before the last ended.
        let mut out = PlausibleBatch::new();
        m.feed(11 * MS, 10 * MS - 750_000, 250_000, &[5.0; 4], &mut out);
        assert!(out.is_empty());
        assert_eq!(m.faults.bad_time_batches, 1);
        // Older than the timeout, and 2 ms in the future.
        let mut n = 0;
        for (first, period) in [(15 * MS, 250_000), (72 * MS, 250_000), (69 * MS, 0)] {
            m.feed(70 * MS, first, period, &[5.0; 4], &mut out);
            n += out.len();
        }
        assert_eq!((n, m.faults.bad_time_batches), (0, 4));
        assert!(m.invalid(70 * MS));
        // A dropped batch is not a sign of life.
        assert!(m.stale(70 * MS));
        // The next genuine batch continues.
        assert_eq!(feed(&mut m, 71 * MS, [1.5, 2.0, 3.0, 4.0]).len(), 4);
    }

    #[test]
    fn identical_readings_for_the_stuck_time_are_a_stuck_sensor() {
        let mut m = monitor();
        // 20 ms of one value at 4 kHz: the 81st identical sample is 20 ms after the first.
        let mut passed = 0;
        let mut now = 10 * MS;
        for _ in 0..20 {
            passed += feed(&mut m, now, [-7.25; 4]).len();
            now += MS;
        }
        assert_eq!(passed, 80);
        assert!(!m.invalid(now));
        passed += feed(&mut m, now, [-7.25; 4]).len();
        assert_eq!(
            passed, 80,
            "from 20 ms on the repeated reading is not a measurement"
        );
        assert!(m.invalid(now));
        assert_eq!(m.faults.stuck_events, 1);
        // It moves again: plausible, but held invalid for the hold time.
        assert_eq!(feed(&mut m, now + MS, [-7.0, -7.5, -7.25, -7.0]).len(), 4);
        assert!(m.invalid(now + MS));
        assert!(!m.invalid(now + MS + 501 * MS));
    }
}
