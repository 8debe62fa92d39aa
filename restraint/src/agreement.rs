//! Severity agreement: the safing sensor must have measured the crash sensor's velocity change
//! over the same window, not merely seen an event.
//!
//! **Why.** The safing channel closes on any event of its own that reaches 0.2 m/s; a real
//! misuse event (a door slam's ringing, a pothole) does that. If the crash sensor fails during
//! that event — stuck at a ringing crest, a 199 g sample, an 8 g offset — the crash path sees a
//! crash, safing is closed, and one fault fires a restraint. Two healthy sensors on the tunnel
//! measure the *same* Δv over the same window (the same filtered pulse, a few 0.01 m/s of
//! noise and sampling apart); a crash sensor that measures much more than the safing sensor
//! is the faulty one of the pair — or the pair cannot tell, which is reason enough not to fire.
//!
//! **Rule.** Both sensors' plausible samples are integrated to a velocity trace while either
//! is in an event (a sample ≥ the wake threshold, then `reset_gap` of quiet) — each trace
//! records every sample while the other's event runs, so a plateau at the wake threshold that
//! one sensor reads just above it and the other just below counts on both —: a quiet sensor's
//! velocity does not change. For the confirmed event (onset `t₀`) and the newest instant both
//! sensors have measured (`t₁`): with Δv_c and Δv_s the crash and safing sensors' velocity
//! change over [t₀, t₁], the pair **disagrees** when
//! `Δv_c − Δv_s > tolerance_dv + tolerance_fraction · Δv_c`. A disagreement makes the crash
//! sensor implausible for that event *at once*: no crash-phase fire of the event goes out
//! (counted: `severity_disagreements`). Only this direction counts: a safing sensor that reads
//! more than the crash sensor cannot make the crash path fire.
//!
//! **Range.** The safing sensor's range (50 g) is narrower than the crash sensor's (200 g); a
//! safing reading at its rail is dropped by its monitor and flags the channel faulty — then the
//! vehicle deceleration stands in for safing (module `safing`) and there is nothing to compare.
//! (Clipping the crash sensor to the safing range instead would hide most of a 150–199 g wild
//! sample: 50 g × 0.25 ms is 0.12 m/s.)

use crate::accel::PlausibleBatch;

/// Points of a trace (a power of two: the ring's index is masked, never out of bounds): with
/// [`POINT_SPACING_NS`], ≥ 115 ms of event (every decision's window).
const TRACE_POINTS: usize = 256;
const MASK: usize = TRACE_POINTS - 1;
/// Least time between stored points of a trace, ns (the 2 kHz safing sensor stores every
/// sample, the 4 kHz crash sensor every other; Δv between points is interpolated linearly).
const POINT_SPACING_NS: u64 = 450_000;

/// How far one sensor's trace is carried past its newest sample to the other's, ns: a little
/// more than the 2 kHz safing sensor's period (its batch may end that much earlier). A real
/// crash's deceleration changes by a few g per ms, so the carried velocity is off by
/// ≈ 0.01 m/s at most; a wild sample of the other sensor is not in it.
const MAX_EXTRAPOLATION_NS: u64 = 600_000;
/// How far past the newest instant the pair is compared, ns: one period of the 4 kHz crash
/// sensor, so that its newest sample counts with its whole weight (the trapezoid has added
/// half of it so far).
const LOOKAHEAD_NS: u64 = 250_000;

/// A sensor's velocity integrated over its events (trapezoidal), as time-stamped points in a
/// ring (plain arrays: this runs for every sample of an event, on both sensors).
#[derive(Debug, Clone)]
pub struct VelocityTrace {
    wake_mps2: f64,
    gap_ns: u64,
    /// Velocity change integrated so far, m/s.
    v_mps: f64,
    /// The newest sample: time ns, deceleration m/s² (`seen`: there is one).
    last_ns: u64,
    last_decel_mps2: f64,
    seen: bool,
    /// Samples are being integrated (an event, or its quiet gap, in progress).
    recording: bool,
    /// The event's gap ends here, ns.
    active_until_ns: u64,
    /// The ring: point k at `t_ns[k]`, `v_mps[k]`; `next` is where the next one goes.
    point_ns: [u64; TRACE_POINTS],
    point_v_mps: [f64; TRACE_POINTS],
    next: usize,
    len: usize,
    /// The trace knows the velocity from here on, ns (the oldest point once points dropped).
    covered_from_ns: u64,
}

impl VelocityTrace {
    /// An empty trace: events begin at `wake_mps2` and end `gap_ns` after the last sample
    /// above it.
    pub fn new(wake_mps2: f64, gap_ns: u64) -> Self {
        Self {
            wake_mps2,
            gap_ns,
            v_mps: 0.0,
            last_ns: 0,
            last_decel_mps2: 0.0,
            seen: false,
            recording: false,
            active_until_ns: 0,
            point_ns: [0; TRACE_POINTS],
            point_v_mps: [0.0; TRACE_POINTS],
            next: 0,
            len: 0,
            covered_from_ns: 0,
        }
    }

    /// One batch of plausible samples; `beside`: the other sensor's trace is recording, so
    /// this one records every sample too (module docs, "Rule"). A quiet batch outside an event
    /// only keeps its newest sample (every cycle of a drive: what the integration needs for its
    /// next trapezoid).
    pub fn on_batch(&mut self, batch: &PlausibleBatch, beside: bool) {
        if !(self.recording || beside) && batch.all_below(self.wake_mps2) {
            if let Some((t, d)) = batch.last_sample() {
                (self.last_ns, self.last_decel_mps2, self.seen) = (t, d, true);
            }
            return;
        }
        for s in batch.iter() {
            self.push(s.t_ns, s.decel_mps2, beside);
        }
    }

    /// Samples are being integrated: an event of this sensor, or of the other one, in progress.
    pub fn recording(&self) -> bool {
        self.recording
    }

    /// One sample (a trapezoid from the previous one, across any dropped sample); `beside`:
    /// the other sensor's event keeps this one's going.
    #[inline]
    fn push(&mut self, t_ns: u64, d: f64, beside: bool) {
        if beside || d >= self.wake_mps2 {
            self.active_until_ns = t_ns.saturating_add(self.gap_ns);
        }
        if self.seen {
            if t_ns <= self.last_ns {
                return; // not newer: the monitor's order was broken, ignore
            }
            if !self.recording {
                // The velocity was constant up to the quiet sample before the event.
                self.recording = true;
                self.record(self.last_ns, true);
            }
            let width_s = (t_ns - self.last_ns) as f64 * 1e-9;
            self.v_mps += 0.5 * (self.last_decel_mps2 + d) * width_s;
        }
        (self.last_ns, self.last_decel_mps2, self.seen) = (t_ns, d, true);
        let ending = t_ns > self.active_until_ns;
        if self.recording {
            self.record(t_ns, ending);
        }
        if ending {
            self.recording = false;
        }
    }

    #[inline]
    fn record(&mut self, t_ns: u64, force: bool) {
        if self.len > 0 {
            let tb = self.point_ns[self.next.wrapping_sub(1) & MASK];
            if t_ns <= tb || (!force && t_ns - tb < POINT_SPACING_NS) {
                return;
            }
        }
        if self.len == TRACE_POINTS {
            // The oldest point is overwritten: the one after it is the oldest now.
            self.covered_from_ns = self.point_ns[(self.next + 1) & MASK];
        } else {
            self.len += 1;
        }
        let k = self.next & MASK;
        self.point_ns[k] = t_ns;
        self.point_v_mps[k] = self.v_mps;
        self.next = (k + 1) & MASK;
    }

    /// The newest sample's time, ns (`None` before the first sample).
    pub fn latest_ns(&self) -> Option<u64> {
        self.seen.then_some(self.last_ns)
    }

    /// The trace knows the velocity from here on, ns.
    pub fn covered_from_ns(&self) -> u64 {
        self.covered_from_ns
    }

    /// [`Self::v_at`]`(t_ns)` will not change any more (a stored point lies at or after it).
    fn settled_at(&self, t_ns: u64) -> bool {
        self.len > 0 && self.point_ns[self.next.wrapping_sub(1) & MASK] >= t_ns
    }

    /// [`Self::v_at`], and after the newest sample its velocity carried on with its newest
    /// deceleration (the caller bounds how far: [`MAX_EXTRAPOLATION_NS`]), m/s.
    pub fn v_ahead(&self, t_ns: u64) -> f64 {
        if self.seen && t_ns > self.last_ns {
            return self.v_mps + self.last_decel_mps2 * (t_ns - self.last_ns) as f64 * 1e-9;
        }
        self.v_at(t_ns)
    }

    /// The integrated velocity at `t_ns` (linear between points; the newest value after the
    /// newest sample; the oldest point's before it — check [`Self::covered_from_ns`]), m/s.
    pub fn v_at(&self, t_ns: u64) -> f64 {
        let (mut t1, mut v1) = (self.last_ns, self.v_mps);
        if !self.seen || t_ns >= t1 {
            return v1;
        }
        for back in 1..=self.len {
            let k = self.next.wrapping_sub(back) & MASK;
            let (t0, v0) = (self.point_ns[k], self.point_v_mps[k]);
            if t_ns >= t0 {
                let span = t1.saturating_sub(t0) as f64;
                return if span > 0.0 {
                    v0 + (v1 - v0) * ((t_ns - t0) as f64 / span)
                } else {
                    v1
                };
            }
            (t1, v1) = (t0, v0);
        }
        v1
    }
}

/// Tolerance of the agreement (from `[cycle]`: `severity_tolerance_dv_mps`,
/// `severity_tolerance_fraction`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AgreementParams {
    /// Absolute part, m/s.
    pub tolerance_dv_mps: f64,
    /// Part proportional to the crash sensor's Δv.
    pub tolerance_fraction: f64,
}

/// The two accelerometers' traces and the verdict on the confirmed event.
#[derive(Debug, Clone)]
pub struct SeverityAgreement {
    params: AgreementParams,
    /// The crash accelerometer's trace.
    pub crash: VelocityTrace,
    /// The safing accelerometer's trace.
    pub safing: VelocityTrace,
    /// The event judged last (onset, ns) and whether the pair disagreed in it.
    event: Option<(u64, bool)>,
    /// Both traces' velocity at the window's start once settled (t₀ ns, crash, safing m/s):
    /// each cycle then interpolates only near the newest samples.
    start: Option<(u64, f64, f64)>,
    disagreements: u64,
    /// The event (onset, ns) in which the safing sensor measured more than the crash sensor
    /// allows, by the same tolerance: it vetoes nothing (a safing sensor reading more cannot
    /// make the crash path fire), but the pair disagrees ([`SeverityAgreement::pair_disagrees`]).
    safing_reads_more: Option<u64>,
    /// Largest `Δv_c − Δv_s` seen in a judged event, m/s (diagnostics: the tolerance's
    /// margin on the runs at hand).
    worst_excess_mps: f64,
}

impl SeverityAgreement {
    /// Two empty traces (events as the safing function's: `wake_mps2`, `gap_ns`).
    pub fn new(params: AgreementParams, wake_mps2: f64, gap_ns: u64) -> Self {
        Self {
            params,
            crash: VelocityTrace::new(wake_mps2, gap_ns),
            safing: VelocityTrace::new(wake_mps2, gap_ns),
            event: None,
            start: None,
            disagreements: 0,
            safing_reads_more: None,
            worst_excess_mps: f64::NEG_INFINITY,
        }
    }

    /// Whether the two sensors disagree on the event that began at `onset_ns` in either
    /// direction, as far as [`SeverityAgreement::agrees`] has judged it this cycle: the crash
    /// sensor measured more than the safing sensor allows, or the safing sensor more than the
    /// crash sensor allows. Two sensors cannot say which of them is wrong.
    pub fn pair_disagrees(&self, onset_ns: u64) -> bool {
        self.event == Some((onset_ns, true)) || self.safing_reads_more == Some(onset_ns)
    }

    /// Whether the crash sensor measured more than the safing sensor allows on the event that
    /// began at `onset_ns`, and the safing sensor never more than the crash sensor allows: the
    /// safing sensor's reading is then the smaller of the two, whichever of them is wrong.
    pub fn crash_reads_more(&self, onset_ns: u64) -> bool {
        self.event == Some((onset_ns, true)) && self.safing_reads_more != Some(onset_ns)
    }

    /// Whether the pair agrees on the event that began at `onset_ns` so far (module docs).
    /// A disagreement holds for the rest of that event.
    pub fn agrees(&mut self, onset_ns: u64) -> bool {
        match self.event {
            Some((t, disagreed)) if t == onset_ns => {
                if disagreed {
                    return false;
                }
            }
            _ => self.event = Some((onset_ns, false)),
        }
        let (Some(tc), Some(ts)) = (self.crash.latest_ns(), self.safing.latest_ns()) else {
            return true;
        };
        // Compared a little ahead of the newest samples, each trace carried on with its newest
        // deceleration ([`LOOKAHEAD_NS`]): the trapezoid has put only half of a newest sample
        // into the velocity yet, and a wild crash sample decides its fire in the very cycle it
        // arrives (a 177 g sample in a pothole fired with half its 0.43 m/s counted,
        // an excess of 0.20 m/s, inside the tolerance; the other half came a cycle too late).
        // The newest instant either sensor measured counts, the other one carried to it too
        // (the 4 kHz crash sensor's batch may end after the 2 kHz safing sensor's).
        let t1 = tc
            .max(ts)
            .min(tc.min(ts).saturating_add(MAX_EXTRAPOLATION_NS))
            .saturating_add(LOOKAHEAD_NS);
        let t0 = onset_ns
            .max(self.crash.covered_from_ns())
            .max(self.safing.covered_from_ns());
        if t1 <= t0 {
            return true;
        }
        let (vc0, vs0) = match self.start {
            Some((t, vc, vs)) if t == t0 => (vc, vs),
            _ => {
                let v0 = (self.crash.v_at(t0), self.safing.v_at(t0));
                if self.crash.settled_at(t0) && self.safing.settled_at(t0) {
                    self.start = Some((t0, v0.0, v0.1));
                }
                v0
            }
        };
        let dv_crash = self.crash.v_ahead(t1) - vc0;
        let dv_safing = self.safing.v_ahead(t1) - vs0;
        let excess = dv_crash - dv_safing;
        self.worst_excess_mps = self.worst_excess_mps.max(excess);
        let p = self.params;
        if -excess > p.tolerance_dv_mps + p.tolerance_fraction * dv_safing.max(0.0) {
            self.safing_reads_more = Some(onset_ns);
        }
        // NaN (cannot come from plausible samples) counts as a disagreement.
        if excess <= p.tolerance_dv_mps + p.tolerance_fraction * dv_crash.max(0.0) {
            return true;
        }
        self.event = Some((onset_ns, true));
        self.disagreements = self.disagreements.saturating_add(1);
        false
    }

    /// Events in which the crash sensor measured more than the safing sensor allows.
    pub fn disagreements(&self) -> u64 {
        self.disagreements
    }

    /// Largest crash-minus-safing Δv of a judged event, m/s (`None`: none judged yet).
    pub fn worst_excess_mps(&self) -> Option<f64> {
        self.worst_excess_mps
            .is_finite()
            .then_some(self.worst_excess_mps)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::{AccelLimits, AccelMonitor};
    use crate::settings::G_MPS2;

    const MS: u64 = 1_000_000;
    const US: u64 = 1_000;

    fn params() -> AgreementParams {
        AgreementParams {
            tolerance_dv_mps: 0.15,
            tolerance_fraction: 0.2,
        }
    }

    fn agreement() -> SeverityAgreement {
        SeverityAgreement::new(params(), 1.5 * G_MPS2, 10 * MS)
    }

    /// A monitor with the crash sensor's limits.
    fn monitor() -> AccelMonitor {
        AccelMonitor::new(AccelLimits {
            timeout_ns: 50 * MS,
            stuck_ns: 20 * MS,
            full_scale_mps2: 200.0 * G_MPS2,
        })
    }

    /// The 1 ms batch from `t_us` of `g(t_us)` (deceleration, g) sampled every `period_us`,
    /// through `mon`.
    fn batch(
        mon: &mut AccelMonitor,
        t: u64,
        period_us: u64,
        g: &impl Fn(u64) -> f64,
    ) -> PlausibleBatch {
        let samples: heapless::Vec<f32, 16> = (0..1_000 / period_us)
            .map(|k| {
                // A tiny alternating noise keeps the stuck check quiet.
                -(g(t + k * period_us) * G_MPS2) as f32 + if k % 2 == 0 { 0.01 } else { -0.01 }
            })
            .collect();
        let mut b = PlausibleBatch::new();
        mon.feed(
            t * US + MS,
            t * US,
            (period_us * US) as u32,
            &samples,
            &mut b,
        );
        b
    }

    /// Feeds `g(t_us)` (deceleration, g) sampled every `period_us` over `[0, t1)` µs, in 1 ms
    /// batches through a real monitor.
    fn feed(trace: &mut VelocityTrace, period_us: u64, t1_us: u64, g: impl Fn(u64) -> f64) {
        let mut mon = monitor();
        for t in (0..t1_us).step_by(1_000) {
            trace.on_batch(&batch(&mut mon, t, period_us, &g), false);
        }
    }

    /// A half-sine of `peak_g` over `dur_us` from `start_us`.
    fn half_sine(peak_g: f64, start_us: u64, dur_us: u64) -> impl Fn(u64) -> f64 {
        move |t| {
            if t < start_us || t >= start_us + dur_us {
                return 0.0;
            }
            let x = (t - start_us) as f64 / dur_us as f64;
            peak_g * (core::f64::consts::PI * x).sin()
        }
    }

    #[test]
    fn a_trace_integrates_an_event_to_its_closed_form_dv() {
        // 20 g half-sine over 10 ms: Δv = 2·a·T/π = 2·196.13·0.01/π = 1.2487 m/s.
        let mut tr = VelocityTrace::new(1.5 * G_MPS2, 10 * MS);
        feed(&mut tr, 250, 60_000, half_sine(20.0, 20_000, 10_000));
        let dv = tr.v_at(59 * MS) - tr.v_at(19 * MS);
        let exact = 2.0 * 20.0 * G_MPS2 * 0.010 / core::f64::consts::PI;
        assert!((dv - exact).abs() < 0.01, "{dv} vs {exact}");
        // Half-way (the half-sine's integral to T/2 is exactly half).
        let half = tr.v_at(25 * MS) - tr.v_at(19 * MS);
        assert!((half - exact / 2.0).abs() < 0.02, "{half}");
    }

    #[test]
    fn two_healthy_sensors_agree_on_the_same_pulse() {
        for (peak, dur) in [(8.0, 40_000), (30.0, 20_000), (45.0, 60_000), (4.0, 80_000)] {
            let mut a = agreement();
            feed(&mut a.crash, 250, 150_000, half_sine(peak, 10_000, dur));
            feed(&mut a.safing, 500, 150_000, half_sine(peak, 10_000, dur));
            assert!(a.agrees(10 * MS), "{peak} g × {dur} µs");
            let worst = a.worst_excess_mps().unwrap();
            assert!(worst.abs() < 0.03, "{peak} g: {worst}");
        }
    }

    /// Two healthy sensors on a plateau at the wake threshold (a truck bed's hood: the crash
    /// sensor reads 1.55 g, the safing sensor 1.45 g) for 50 ms, then 6 g for 20 ms, fed as the
    /// cycle feeds them (each 1 ms: the crash sensor's batch, then the safing sensor's). The
    /// safing sensor's samples count while the crash sensor's event runs: the pair agrees.
    /// Each trace on its own events, the crash sensor's 0.76 m/s of plateau had no counterpart
    /// and the pair disagreed (an underride with the object list dead was missed).
    #[test]
    fn a_plateau_at_the_wake_threshold_counts_on_both_sensors() {
        let (mut crash, mut safing) = (monitor(), monitor());
        let level = |plateau_g: f64| {
            move |t_us: u64| match t_us {
                10_000..=59_999 => plateau_g,
                60_000..=79_999 => 6.0,
                _ => 0.0,
            }
        };
        let (crash_g, safing_g) = (level(1.55), level(1.45));
        let mut a = agreement();
        for t in (0..100_000).step_by(1_000) {
            let beside = a.safing.recording();
            a.crash
                .on_batch(&batch(&mut crash, t, 250, &crash_g), beside);
            let beside = a.crash.recording();
            a.safing
                .on_batch(&batch(&mut safing, t, 500, &safing_g), beside);
        }
        assert!(a.agrees(10 * MS), "excess {:?}", a.worst_excess_mps());
        let excess = a.worst_excess_mps().unwrap();
        assert!((excess - 0.1 * G_MPS2 * 0.050).abs() < 0.02, "{excess}");
    }

    #[test]
    fn a_crash_sensor_reading_more_than_the_safing_sensor_disagrees_at_once() {
        // A pothole both see (10 g × 8 ms ≈ 0.5 m/s); the crash sensor alone also carries an
        // 8 g offset from its onset: after 5 ms it leads by 0.39 m/s > 0.15 + 0.2·Δv_c.
        let pothole = half_sine(10.0, 10_000, 8_000);
        let mut a = agreement();
        feed(&mut a.crash, 250, 16_000, |t| {
            pothole(t) + if t >= 10_000 { 8.0 } else { 0.0 }
        });
        feed(&mut a.safing, 500, 16_000, &pothole);
        assert!(!a.agrees(10 * MS));
        assert_eq!(a.disagreements(), 1);
        // Held for the event, however the rest of it looks; a new event is judged afresh.
        assert!(!a.agrees(10 * MS));
        assert_eq!(a.disagreements(), 1);
        assert!(a.agrees(500 * MS));
    }

    /// A 10 g pothole both sensors see, and the crash sensor alone reading 150 g more at
    /// `wild_us` (one 4 kHz sample: 0.37 m/s); both fed up to `until_us`.
    fn wild_sample_in_a_pothole(wild_us: u64, until_us: u64) -> SeverityAgreement {
        let pothole = half_sine(10.0, 10_000, 10_000);
        let mut a = agreement();
        feed(&mut a.crash, 250, until_us, |t| {
            pothole(t) + if t == wild_us { 150.0 } else { 0.0 }
        });
        feed(&mut a.safing, 500, until_us, &pothole);
        a
    }

    #[test]
    fn one_wild_sample_in_a_shared_event_disagrees() {
        assert!(!wild_sample_in_a_pothole(13_000, 30_000).agrees(10 * MS));
    }

    #[test]
    fn a_wild_sample_that_ends_its_batch_disagrees_in_that_cycle() {
        // The wild sample is the newest of its batch, so the trapezoid holds half of
        // it (0.19 m/s of 0.37, inside the tolerance) and its fire is decided in this very
        // cycle: the pair is compared one crash-sensor period ahead, each trace carried on
        // with its newest deceleration, so the whole sample counts now.
        // Batches of t..t+750 µs: the sample at 13 750 µs ends the batch fed up to 14 000.
        let mut a = wild_sample_in_a_pothole(13_750, 14_000);
        assert!(!a.agrees(10 * MS), "{:?}", a.worst_excess_mps());
    }

    #[test]
    fn the_safing_sensor_reading_more_is_no_disagreement() {
        let mut a = agreement();
        feed(&mut a.crash, 250, 50_000, half_sine(10.0, 10_000, 10_000));
        feed(&mut a.safing, 500, 50_000, half_sine(30.0, 10_000, 10_000));
        assert!(a.agrees(10 * MS));
    }
}
