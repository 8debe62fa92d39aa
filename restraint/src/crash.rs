//! The crash phase's evidence: which detector confirmed the crash, when, where the contact
//! was, how severe it is, and — for the conventional path — whether the airbag must fire.
//!
//! Every plausible accelerometer sample goes to three detectors at once:
//!
//! * [`PulseMatch`] (`crash_match`): in PRE-CRASH, the onset ramp against the frozen prediction
//!   → an early confirmation with the re-estimated severity, or a mismatch;
//! * [`CrashDetector`] (`confirm`): the generic thresholds (4 g × 3 samples and 0.5 m/s);
//! * [`FallbackAlgorithm`] (`fallback`): the accelerometer-only must-fire / no-fire decision.
//!
//! With a faulty crash accelerometer none of them has data; then a crash the object list
//! predicts is confirmed by the vehicle-dynamics deceleration on CAN (`backup_confirm_g`,
//! within ± `match_window_ms` of the predicted contact) — two independent sensors agreeing, so
//! that neither a faulty object list nor a faulty vehicle signal alone can fire.
//!
//! The first confirmation latches ([`Confirmation`]); [`plan_for`] re-plans an adaptive crash
//! from the table at the measured severity (and, as every lookup, the robust planning mass).

use crate::accel::{AccelSample, PlausibleBatch};
use crate::config::CycleConfig;
use crate::confirm::{ConfirmParams, CrashDetector};
use crate::counters::CycleCounters;
use crate::crash_match::{MatchState, PulseMatch, SeverityEstimate};
use crate::estimate::{Estimator, Situation};
use crate::fallback::{FallbackAlgorithm, FallbackDecision, Thresholds};
use crate::inputs::InputMonitor;
use crate::plan::RestraintPlan;
use crate::roughness::Roughness;
use crate::satellites::{CrushOnset, Relief};
use crate::settings::{ms_to_ns, G_MPS2};
use physics::equivalent_barrier_speed_kph;

/// Which path confirmed the crash.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ConfirmKind {
    /// The onset matched the prediction (or departed from it within the re-estimation range).
    Matched(SeverityEstimate),
    /// The generic thresholds (the accelerometer-only algorithm decides the airbag);
    /// `prediction_refuted`: the matcher found the pulse does not belong to the predicted
    /// crash (diagnostics only).
    Generic {
        /// The matcher rejected this pulse (timing, severity or shape).
        prediction_refuted: bool,
    },
    /// The vehicle-dynamics deceleration on CAN, with the crash accelerometer faulty.
    Backup,
}

/// The latched crash confirmation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Confirmation {
    /// When it was confirmed (sample or frame time), ns.
    pub at_ns: u64,
    /// The contact instant it implies, ns: the measured onset less the accelerometer's
    /// filter delay (`accel_delay_ms`); for the backup the predicted contact.
    pub contact_ns: u64,
    /// The accelerometer event it belongs to (its wake-up sample, ns; the backup's: the
    /// predicted contact): the conventional path's decisions are matched to it.
    pub onset_ns: u64,
    /// The path.
    pub kind: ConfirmKind,
}

/// What the samples' handler needs to freeze a prediction at a wake-up.
pub(crate) struct FreezeContext<'a, 'lut> {
    /// The newest situation (from the previous cycle's estimate).
    pub situation: Option<Situation>,
    /// A crash is predicted (PRE-CRASH, inputs not degraded).
    pub armed: bool,
    /// The estimate (springs, ego mass).
    pub estimator: &'a Estimator<'lut>,
}

/// State of the crash-phase detectors.
#[derive(Debug, Clone)]
pub struct CrashMonitor {
    onset_params: ConfirmParams,
    generic: CrashDetector,
    matcher: PulseMatch,
    /// The accelerometer-only algorithm: the airbag's and the pyrotechnic pretensioner's
    /// boundaries on the conventional path.
    fallback: FallbackAlgorithm,
    window_ns: u64,
    backup_decel_mps2: f64,
    /// The accelerometers' anti-alias group delay, ns: a measured onset is this late.
    accel_delay_ns: u64,
    confirmation: Option<Confirmation>,
    /// The road's roughness: lifts every fire's severity floor.
    roughness: Roughness,
}

impl CrashMonitor {
    /// The detectors with the thresholds of a validated `cfg`.
    pub fn new(cfg: &CycleConfig) -> Self {
        let onset_params = cfg.confirm_params();
        Self {
            onset_params,
            generic: CrashDetector::default(),
            matcher: PulseMatch::new(cfg.match_params()),
            fallback: FallbackAlgorithm::new(cfg.fallback_dv_mps, cfg.fallback_floor())
                .with_unbelted(cfg.unbelted_dv_mps)
                .with_pretensioner(cfg.pretensioner_dv_mps, cfg.pretensioner_min_dv_mps),
            window_ns: ms_to_ns(cfg.match_window_ms),
            backup_decel_mps2: cfg.backup_confirm_g * G_MPS2,
            accel_delay_ns: ms_to_ns(cfg.accel_delay_ms),
            confirmation: None,
            roughness: cfg.roughness(),
        }
    }

    /// The plausible samples of one accelerometer batch, in time order, for all three
    /// detectors. A quiet batch (every sample below the wake threshold, no event in progress)
    /// only updates their integrators' previous value with its last sample: the common case,
    /// every cycle of a drive, and what each detector would do sample by sample. `relief`:
    /// what the crush-zone satellites take off the thresholds now ([`crate::satellites`]),
    /// asked only for a batch that is judged (a quiet one needs none); `belted`: the occupant
    /// is known to be belted (else the airbag's boundary is `CycleConfig::unbelted_dv_mps`).
    pub(crate) fn on_batch(
        &mut self,
        batch: &PlausibleBatch,
        ctx: &FreezeContext<'_, '_>,
        belted: bool,
        relief: impl FnOnce() -> Relief,
    ) {
        let wake = self.onset_params.wake_mps2;
        if !(self.matcher.awake() || self.generic.awake() || self.fallback.awake())
            && batch.all_below(wake)
        {
            if let Some(last) = batch.last_decel_mps2() {
                self.matcher.note_quiet(last);
                self.generic.note_quiet(last);
                self.fallback.note_quiet(last);
            }
            return;
        }
        let relief = relief();
        let lift = self.roughness.floor_lift_mps();
        // The satellites' low-crush lift is the airbag's: a crash below its no-fire line may
        // still need the belt.
        self.fallback.lift_boundary(relief.boundary_lift_mps);
        self.fallback.set_belted(belted);
        let thresholds = self.fallback.thresholds_now(lift, relief);
        // A rough road's lobes are no crash evidence for the generic confirmation either (nor
        // for the CrashDetected it puts on the bus, which body ECUs act on): its Δv threshold
        // carries the roughness lift too. On a smooth road the lift is 0; on a rough one every
        // fire needs floor + lift, more than this, so no fire waits for it.
        let generic = ConfirmParams {
            delta_v_mps: relief.floor_mps(self.onset_params.delta_v_mps, lift),
            ..self.onset_params
        };
        for s in batch.iter() {
            self.on_sample(&s, ctx, &generic, thresholds);
        }
    }

    /// The front end began to fold ([`CrushOnset`]) after the accelerometer-only algorithm's
    /// judged segment began — a road's lobe or a kerb strike running into the contact: the
    /// segment restarts at the fold (`fallback`, "Crush onset"), with the tunnel's Δv since
    /// less the `braking_mps2` the samples had removed; after `batch`, the latest batch.
    pub(crate) fn restart_at_crush(
        &mut self,
        o: CrushOnset,
        braking_mps2: f64,
        batch: &PlausibleBatch,
    ) {
        if let Some(last) = batch.iter().last() {
            let braking_dv_mps = braking_mps2 * last.t_ns.saturating_sub(o.at_ns) as f64 * 1e-9;
            self.fallback.restart_at_crush(
                o.at_ns,
                o.tunnel_dv_mps - braking_dv_mps,
                last.decel_mps2,
            );
        }
    }

    /// The road-roughness measure's batch (its `decel_integral_mps`): the readings as the sensor
    /// gave them, before the braking compensation (braking only slows the car, so it never lifts
    /// the measure; a compensation that runs ahead of the sensor's own braking ramp would read
    /// as forward).
    pub(crate) fn on_raw_batch(&mut self, dv_mps: f64, span_s: f64) {
        self.roughness.push(dv_mps, span_s);
    }

    /// One plausible accelerometer sample for all three detectors.
    fn on_sample(
        &mut self,
        s: &AccelSample,
        ctx: &FreezeContext<'_, '_>,
        generic: &ConfirmParams,
        thresholds: Thresholds,
    ) {
        self.matcher.push(s, &mut |slot| {
            let Some(sit) = ctx.situation.filter(|_| ctx.armed) else {
                return false;
            };
            let Some(spring) = ctx.estimator.spring_for(sit.opponent_mass_kg) else {
                return false;
            };
            slot.solve_in_place(
                spring,
                ctx.estimator.ego_mass_kg(),
                sit.opponent_mass_kg,
                sit.closing_speed_mps,
                sit.contact_ns,
            )
        });
        self.generic.push(generic, s);
        self.fallback.push(&self.onset_params, s, thresholds);
        if self.confirmation.is_some() {
            return;
        }
        if let MatchState::Confirmed(e) = self.matcher.state() {
            self.confirmation = Some(Confirmation {
                at_ns: e.confirm_ns,
                contact_ns: e.onset_ns.saturating_sub(self.accel_delay_ns),
                // The conventional path's decisions belong to its own event (the same onset
                // rule; a gated matched fire waits for them).
                onset_ns: self.fallback.onset_ns().unwrap_or(e.onset_ns),
                kind: ConfirmKind::Matched(e),
            });
        } else if let (Some(at_ns), Some(onset)) =
            (self.generic.confirmed_at_ns(), self.generic.onset_ns())
        {
            self.confirmation = Some(Confirmation {
                at_ns,
                contact_ns: onset.saturating_sub(self.accel_delay_ns),
                onset_ns: onset,
                kind: ConfirmKind::Generic {
                    prediction_refuted: matches!(self.matcher.state(), MatchState::Mismatch(_)),
                },
            });
        }
    }

    /// Once per cycle after the inputs: the backup confirmation. With the crash accelerometer
    /// faulty (`accel_faulty`) and a crash predicted at `situation.contact_ns` (above the
    /// no-fire line), a fresh vehicle frame received within ± the match window of the
    /// predicted contact whose deceleration reaches `backup_confirm_g` confirms it, at the
    /// contact [`Self::backup_evidence`] gives.
    pub(crate) fn end_cycle(
        &mut self,
        now: u64,
        accel_faulty: bool,
        situation: Option<&Situation>,
        inputs: &InputMonitor,
        safing_onset_ns: Option<u64>,
    ) {
        if self.confirmation.is_some() || !accel_faulty {
            return;
        }
        let Some(sit) = situation else {
            return;
        };
        if let Some(b) = self.backup_evidence(now, sit, inputs, safing_onset_ns) {
            self.confirmation = Some(Confirmation {
                at_ns: b.rx_ns,
                contact_ns: b.contact_ns,
                onset_ns: b.contact_ns,
                kind: ConfirmKind::Backup,
            });
        }
    }

    /// The backup path's evidence at `now`: a crash predicted above the no-fire line
    /// (`sit`) and a fresh vehicle frame received within ± the match window of its contact
    /// whose deceleration reaches `backup_confirm_g`. Two sources independent of the crash
    /// accelerometer: the object list and the vehicle dynamics. The contact is the healthy
    /// safing sensor's onset (`safing_onset_ns`, less the structure's delay) when that lies
    /// within the match window of the predicted one — measured, where the object list's
    /// prediction is off by its latency and range error (8 ms in a 109 km/h closing car
    /// crash) — else the predicted contact.
    pub(crate) fn backup_evidence(
        &self,
        now: u64,
        sit: &Situation,
        inputs: &InputMonitor,
        safing_onset_ns: Option<u64>,
    ) -> Option<BackupEvidence> {
        let (decel, rx_ns) = inputs.vehicle_decel(now)?;
        let in_window = rx_ns.abs_diff(sit.contact_ns) <= self.window_ns;
        if sit.low_speed || !in_window || !(decel >= self.backup_decel_mps2) {
            return None;
        }
        let contact_ns = safing_onset_ns
            .map(|t| t.saturating_sub(self.accel_delay_ns))
            .filter(|t| t.abs_diff(sit.contact_ns) <= self.window_ns)
            .unwrap_or(sit.contact_ns);
        Some(BackupEvidence { rx_ns, contact_ns })
    }

    /// The latched confirmation.
    pub fn confirmation(&self) -> Option<Confirmation> {
        self.confirmation
    }

    /// The velocity change of the current accelerometer event since its onset, m/s.
    pub fn event_dv_mps(&self) -> f64 {
        self.fallback.event_dv_mps()
    }

    /// Onset of the accelerometer event in progress (the accelerometer-only boundaries' τ = 0),
    /// ns.
    pub fn event_onset_ns(&self) -> Option<u64> {
        self.fallback.onset_ns()
    }

    /// Start of the segment of the current event the accelerometer-only algorithm judges, ns
    /// (`fallback`, "Re-onset").
    pub fn segment_onset_ns(&self) -> Option<u64> {
        self.fallback.segment_onset_ns()
    }

    /// The airbag's accelerometer-only boundary for the occupant of the latest judged batch
    /// (m/s at the knots, before the satellites' relief and lift).
    pub fn airbag_boundary(&self) -> &[f64; crate::fallback::KNOTS] {
        self.fallback.airbag_boundary()
    }

    /// What the road's roughness adds to every fire's severity floor now, m/s.
    pub fn floor_lift_mps(&self) -> f64 {
        self.roughness.floor_lift_mps()
    }

    /// The accelerometer-only algorithm's decision on the current event.
    pub fn fallback(&self) -> FallbackDecision {
        self.fallback.decision()
    }

    /// The pretensioner's accelerometer-only decision on the current event.
    pub fn pretensioner(&self) -> FallbackDecision {
        self.fallback.pretensioner_decision()
    }

    /// The accelerometer event in progress is still loading (`FallbackAlgorithm::loading`).
    pub fn event_loading(&self) -> bool {
        self.fallback.loading()
    }

    /// An accelerometer event is in progress on any detector (the conventional algorithms
    /// track every event, also after a confirmation).
    pub fn event_in_progress(&self) -> bool {
        self.fallback.awake() || self.matcher.awake()
    }

    /// Moves the latched confirmation to the accelerometer event in progress when that began
    /// after the confirmed one (the confirmed event ended and the next began inside the crash
    /// phase). Call only while the crash phase has fired nothing:
    /// then the next event is confirmed and decided on its own onset, exactly as if the crash
    /// phase had ended with the first one — a rough road's lobe at the predicted contact can
    /// confirm the crash phase, end, and leave the real crash a millisecond later to an event
    /// whose decisions belong to no confirmation. The backup's confirmation (no crash-sensor
    /// event) never moves.
    pub fn follow_later_event(&mut self, now: u64) {
        let (Some(c), Some(onset_ns)) = (self.confirmation, self.fallback.onset_ns()) else {
            return;
        };
        if c.kind == ConfirmKind::Backup || onset_ns <= c.onset_ns {
            return;
        }
        self.confirmation = Some(Confirmation {
            at_ns: now,
            contact_ns: onset_ns.saturating_sub(self.accel_delay_ns),
            onset_ns,
            kind: ConfirmKind::Generic {
                prediction_refuted: false,
            },
        });
    }

    /// Forgets a confirmation whose event ended without any fire (a bump the generic
    /// thresholds confirmed, a crash the safing channel never agreed with): the detectors
    /// start afresh, so the next event is judged on its own (a decision belongs to its event:
    /// a spike's leftover must-fire must not complete on a later bump). Call only when no
    /// event is in progress.
    pub fn rearm(&mut self) {
        self.generic = CrashDetector::default();
        self.matcher = PulseMatch::new(*self.matcher.params());
        self.confirmation = None;
    }

    /// The prediction-matched confirmation's state.
    pub fn matcher(&self) -> &PulseMatch {
        &self.matcher
    }

    /// An accelerometer event is in progress: the object list no longer predicts anything.
    pub fn awake(&self) -> bool {
        self.matcher.awake()
    }

    /// Δv since the onset of the event the generic detector tracks, m/s.
    pub fn delta_v_mps(&self) -> f64 {
        self.generic.delta_v_mps()
    }
}

/// What confirms a crash on the backup path (`CrashMonitor::backup_evidence`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BackupEvidence {
    /// The vehicle frame's receive time, ns.
    pub rx_ns: u64,
    /// The contact the backup path's fires are timed from, ns.
    pub contact_ns: u64,
}

/// The table's plan for an adaptive crash re-estimated at closing speed `closing_mps` (the
/// lookup raises the mass to the robust planning mass, `Estimator::lookup`). `None` when the
/// re-estimated severity is below the occupant's no-fire line `no_fire_ebs_kph`: the crash
/// then goes the conventional way.
pub(crate) fn plan_for(
    cfg: &CycleConfig,
    estimator: &Estimator<'_>,
    sit: &Situation,
    closing_mps: f64,
    inputs: &InputMonitor,
    no_fire_ebs_kph: f64,
    counters: &mut CycleCounters,
) -> Option<RestraintPlan> {
    let ebs = equivalent_barrier_speed_kph(closing_mps, cfg.ego_mass_kg, sit.opponent_mass_kg);
    if !(ebs >= no_fire_ebs_kph) {
        return None;
    }
    let planned = Situation {
        closing_speed_mps: closing_mps,
        ..*sit
    };
    Some(estimator.lookup(&planned, inputs, counters))
}
