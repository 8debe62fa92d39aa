//! The safing function: the second, independent agreement every Fire needs.
//!
//! Production airbag ECUs never let one sensor fire a restraint: besides the main algorithm on
//! the crash accelerometer, a **safing** function on an independent second acceleration
//! channel (its own sensor, its own port, its own plausibility monitor) must also see a crash.
//! Its threshold is lower than the main algorithm's — it must never delay a real crash — so
//! what it adds is independence, not discrimination: one crash accelerometer that spikes,
//! sticks, drifts, goes noisy or dies cannot fire anything on its own, and neither can a
//! safing sensor that does any of these.
//!
//! **Rule.** The safing channel *closes* when, within one event of its own signal (onset at
//! `safing_wake_g`, over after `confirm_reset_gap_ms` below it — the same [`Onset`] as the
//! main detectors, on the other sensor), the velocity change since the onset reaches
//! `safing_dv_mps`. It stays closed while that event lasts and `safing_hold_ms` after it ends,
//! then opens again. A crash-phase fire (airbag, pyrotechnic pretensioner) goes out only in a
//! cycle in which the channel is closed; a fire that is due and finds it open waits at most
//! `safing_wait_ms` and is then dropped (counted: `fires_vetoed_by_safing`).
//!
//! **A faulty safing channel** (stale, stuck, saturated, out of range, bad time stamps, port
//! errors: the same [`crate::accel::AccelMonitor`] checks as the crash accelerometer) is on the
//! bus (`EcuStatus.FaultSafingSensor`) and two other witnesses stand in for it: the crush-zone
//! satellites' crushed front end ([`crate::satellites::Satellites::front_end_crushed`]: a
//! frontal crash, seen within a millisecond or two of the contact, so the crash fires when it
//! would with a healthy safing sensor), or the vehicle-dynamics deceleration of the gateway's
//! `EgoVehicleState` (fresh within `vehicle_timeout_ms`): a frame received within the hold
//! window showing at least `safing_substitute_g` closes the channel — for a crash the
//! satellites do not see fold, later by up to one 10 ms vehicle frame. A spike or stuck crash
//! accelerometer still cannot fire alone: neither witness is moved by it. The pre-crash
//! (reversible, motor-driven) pretensioner needs no safing agreement: it fires on the
//! prediction before any deceleration exists and is released when the crash does not come.

use crate::accel::PlausibleBatch;
use crate::confirm::{ConfirmParams, Onset, OnsetStep};

/// Safing settings in the function's units (from the file's `safing_*` keys:
/// [`crate::CycleConfig::safing_params`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SafingParams {
    /// Onset of the safing channel's events (wake threshold, quiet gap).
    pub onset: ConfirmParams,
    /// Δv since the safing onset that closes the channel, m/s.
    pub dv_mps: f64,
    /// The channel stays closed this long after its event ended, ns.
    pub hold_ns: u64,
    /// A vehicle-dynamics deceleration at least this closes the channel while the safing
    /// sensor is faulty, m/s².
    pub substitute_mps2: f64,
}

/// State of the safing function on the safing sensor's plausible samples.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Safing {
    params: SafingParams,
    onset: Onset,
    /// The channel closed in the current event.
    closed: bool,
    /// Consecutive samples at or above the wake threshold.
    run: u32,
    /// Closed until this time (set when the closing event ended), ns.
    closed_until_ns: Option<u64>,
    /// The newest sample of the event in progress, ns.
    latest_ns: u64,
}

impl Safing {
    /// Open, with validated settings.
    pub fn new(params: SafingParams) -> Self {
        Self {
            params,
            onset: Onset::default(),
            closed: false,
            run: 0,
            closed_until_ns: None,
            latest_ns: 0,
        }
    }

    /// The plausible samples of one safing batch, in time order. A quiet batch (every sample
    /// below the wake threshold, no event in progress) only keeps its last reading for the
    /// next trapezoid — every cycle of a drive, what the sample loop would do.
    pub fn on_batch(&mut self, batch: &PlausibleBatch) {
        if !self.onset.awake() && batch.all_below(self.params.onset.wake_mps2) {
            if let Some(last) = batch.last_decel_mps2() {
                self.onset.note_quiet(last);
            }
            return;
        }
        for s in batch.iter() {
            match self.onset.push(&self.params.onset, &s) {
                OnsetStep::Quiet => {}
                OnsetStep::Reset => {
                    self.run = 0;
                    if core::mem::take(&mut self.closed) {
                        self.closed_until_ns = Some(s.t_ns.saturating_add(self.params.hold_ns));
                    }
                }
                OnsetStep::Woke | OnsetStep::Awake => {
                    self.latest_ns = s.t_ns;
                    self.run = if s.decel_mps2 >= self.params.onset.wake_mps2 {
                        self.run.saturating_add(1)
                    } else {
                        0
                    };
                    if self.run >= self.params.onset.samples
                        && self.onset.delta_v_mps() >= self.params.dv_mps
                    {
                        self.closed = true;
                    }
                }
            }
        }
    }

    /// Whether the safing sensor agrees at `now` (closed in the current event, or within the
    /// hold time after the event that closed it).
    pub fn closed(&self, now: u64) -> bool {
        self.closed || self.closed_until_ns.is_some_and(|t| now <= t)
    }

    /// Whether the safing function agrees at `now`: the safing sensor when it is healthy,
    /// else the crush-zone satellites' crushed front end (`front_end_crushed`) or the vehicle
    /// deceleration `vehicle` (m/s², receive time) received within the hold time (module docs).
    pub fn agrees(
        &self,
        now: u64,
        sensor_faulty: bool,
        vehicle: Option<(f64, u64)>,
        front_end_crushed: bool,
    ) -> bool {
        if !sensor_faulty {
            return self.closed(now);
        }
        front_end_crushed
            || vehicle.is_some_and(|(decel, rx_ns)| {
                decel >= self.params.substitute_mps2
                    && now.saturating_sub(rx_ns) <= self.params.hold_ns
            })
    }

    /// Onset of the safing channel's event in progress, ns (`None` when quiet).
    pub fn onset_ns(&self) -> Option<u64> {
        self.onset.onset_ns()
    }

    /// The safing channel's event in progress: its onset and its newest sample, ns.
    pub fn event_span_ns(&self) -> Option<(u64, u64)> {
        self.onset.onset_ns().map(|o| (o, self.latest_ns.max(o)))
    }

    /// Δv since the onset of the safing channel's event in progress, m/s (0 when quiet).
    pub fn delta_v_mps(&self) -> f64 {
        self.onset.delta_v_mps()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::{AccelLimits, AccelMonitor};
    use crate::settings::G_MPS2;

    const MS: u64 = 1_000_000;

    fn params() -> SafingParams {
        SafingParams {
            onset: ConfirmParams {
                wake_mps2: 1.5 * G_MPS2,
                decel_mps2: 4.0 * G_MPS2,
                samples: 3,
                delta_v_mps: 0.5,
                reset_gap_ns: 10 * MS,
            },
            dv_mps: 0.2,
            hold_ns: 20 * MS,
            substitute_mps2: 2.0 * G_MPS2,
        }
    }

    /// Feeds `g(t_ms)` at 1 kHz for `ms` samples from `t0_ms`, through a real monitor.
    fn feed(s: &mut Safing, t0_ms: u64, ms: u64, g: impl Fn(u64) -> f64) {
        let mut mon = AccelMonitor::new(AccelLimits {
            timeout_ns: 50 * MS,
            stuck_ns: 20 * MS,
            full_scale_mps2: 200.0 * G_MPS2,
        });
        let mut b = PlausibleBatch::new();
        for k in t0_ms..t0_ms + ms {
            let a = -(g(k) * G_MPS2) as f32 + if k % 2 == 0 { 0.01 } else { -0.01 };
            mon.feed(k * MS, k * MS, 1_000_000, &[a], &mut b);
            s.on_batch(&b);
        }
    }

    #[test]
    fn closes_at_its_delta_v_and_opens_after_the_event_and_the_hold() {
        // 5 g from t = 100 ms for 20 ms: Δv (trapezoidal, from 0) = (n − ½)·0.049 m/s ≥ 0.2 at
        // n = 5 samples (t = 104 ms).
        let mut s = Safing::new(params());
        feed(&mut s, 0, 104, |t| if t >= 100 { 5.0 } else { 0.0 });
        assert!(!s.closed(103 * MS), "Δv {}", s.delta_v_mps());
        feed(&mut s, 104, 1, |_| 5.0);
        assert!(s.closed(104 * MS));
        // The event ends at 120 ms (last wake sample 119), resets 11 ms later (130 ms);
        // closed until 130 + 20 ms.
        feed(&mut s, 105, 60, |t| if t < 120 { 5.0 } else { 0.0 });
        assert!(s.closed(150 * MS));
        assert!(!s.closed(151 * MS));
    }

    #[test]
    fn a_spike_or_a_short_slam_never_closes_it() {
        let mut s = Safing::new(params());
        // One sample of 60 g integrates (trapezoids up and down) to 60 g·1 ms = 0.59 m/s, more
        // than the threshold, but is one sample: the persistence keeps the channel open.
        feed(&mut s, 0, 30, |t| if t == 10 { 60.0 } else { 0.0 });
        assert!(!s.closed(12 * MS));
        // A 3 g, 3 ms bump integrates to 0.074 m/s: stays open.
        let mut s = Safing::new(params());
        feed(
            &mut s,
            0,
            30,
            |t| if (10..13).contains(&t) { 3.0 } else { 0.0 },
        );
        assert!(!s.closed(13 * MS));
    }

    #[test]
    fn a_faulty_safing_sensor_is_replaced_by_a_fresh_vehicle_deceleration() {
        let s = Safing::new(params());
        let now = 500 * MS;
        assert!(!s.agrees(now, true, None, false));
        assert!(!s.agrees(now, true, Some((1.0 * G_MPS2, now)), false));
        assert!(s.agrees(now, true, Some((3.0 * G_MPS2, now - 5 * MS)), false));
        // Older than the hold: no longer.
        assert!(!s.agrees(now, true, Some((3.0 * G_MPS2, now - 21 * MS)), false));
        // A healthy but open sensor is not overruled by the vehicle signal, nor by the
        // satellites.
        assert!(!s.agrees(now, false, Some((3.0 * G_MPS2, now)), true));
        // A crushed front end stands in as the vehicle frame does.
        assert!(s.agrees(now, true, None, true));
    }
}
