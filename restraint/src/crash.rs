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
use crate::safing::Safing;
use crate::satellites::{CrushOnset, Relief};
use crate::settings::{ms_to_ns, G_MPS2};
use physics::equivalent_barrier_speed_kph;

/// How often the crash sensor's roughness measure is kept for a fault to come, ms
/// ([`CrashMonitor::end_safing_roughness`]).
pub const SNAPSHOT_MS: u64 = 32;
const SNAPSHOT_NS: u64 = SNAPSHOT_MS * 1_000_000;

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
    /// The same measure on the safing sensor while the crash sensor is known faulty (`None`
    /// while it is healthy): the lift of the backup's floor while the safing sensor stands in
    /// for it ([`Self::backup_boundaries`]). It starts from the crash sensor's measure as it
    /// was before the fault could reach it (`roughness_before`) and follows the safing sensor
    /// from then on; the healthy cycles pay nothing for it but the snapshot.
    safing_roughness: Option<Roughness>,
    /// The crash sensor's measure [`SNAPSHOT_MS`] and 2 × [`SNAPSHOT_MS`] ago at most
    /// (refreshed every [`SNAPSHOT_MS`] while the crash sensor is healthy): the checks find a
    /// fault within 13 (pair check) to 20 ms (stuck) of its start, so the older one is the road
    /// as the fault had not touched it — a fault that reads forward would hold the lift up.
    roughness_before: [Roughness; 2],
    /// When the next snapshot is due, ns.
    next_snapshot_ns: u64,
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
            safing_roughness: None,
            roughness_before: [cfg.roughness(); 2],
            next_snapshot_ns: 0,
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
            self.on_sample(&s, ctx, &generic, &thresholds);
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

    /// The safing sensor's batch for its own roughness measure while the crash sensor is known
    /// faulty (as [`Self::on_raw_batch`]).
    pub(crate) fn on_raw_safing_batch(&mut self, dv_mps: f64, span_s: f64) {
        let [before, _] = self.roughness_before;
        self.safing_roughness
            .get_or_insert(before)
            .push(dv_mps, span_s);
    }

    /// The crash sensor is healthy at `now`: the safing sensor's roughness measure ends, and
    /// the crash sensor's is kept for the next fault (`roughness_before`).
    #[inline]
    pub(crate) fn end_safing_roughness(&mut self, now: u64) {
        if self.safing_roughness.is_some() {
            self.safing_roughness = None;
        }
        if now >= self.next_snapshot_ns {
            self.roughness_before = [self.roughness_before[1], self.roughness];
            self.next_snapshot_ns = now.saturating_add(SNAPSHOT_NS);
        }
    }

    /// One plausible accelerometer sample for all three detectors.
    fn on_sample(
        &mut self,
        s: &AccelSample,
        ctx: &FreezeContext<'_, '_>,
        generic: &ConfirmParams,
        thresholds: &Thresholds,
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
        measured: Option<BackupSeverity>,
    ) {
        if self.confirmation.is_some() || !accel_faulty {
            return;
        }
        let Some(sit) = situation else {
            return;
        };
        if let Some(b) = self.backup_evidence(now, sit, inputs, safing_onset_ns, measured) {
            self.confirmation = Some(Confirmation {
                at_ns: b.rx_ns,
                contact_ns: b.contact_ns,
                onset_ns: b.contact_ns,
                kind: ConfirmKind::Backup,
            });
        }
    }

    /// The backup path's evidence at `now`: a crash predicted above the no-fire line
    /// (`sit`), measured by a source independent of the crash accelerometer — a fresh
    /// vehicle frame received within ± the match window of its contact whose deceleration
    /// reaches `backup_confirm_g`, or, while the crash accelerometer is known faulty, the
    /// healthy safing sensor's event (`measured`, [`Self::backup_boundaries`]) beginning within
    /// that window and reaching the airbag's accelerometer-only boundary and floor. The object list
    /// and one of the vehicle dynamics or the safing sensor: two sources that no single fault
    /// makes agree on a crash. The vehicle frame comes every 10 ms; the safing sensor measures
    /// the crash as the crash sensor would, so the backup fires when the crash sensor's
    /// boundary would have. The contact is the safing sensor's onset (`safing_onset_ns`, less
    /// the structure's delay) when that lies within the match window of the predicted one —
    /// measured, where the object list's prediction is off by its latency and range error (8 ms
    /// in a 109 km/h closing car crash) — else the predicted contact.
    #[inline(never)]
    pub(crate) fn backup_evidence(
        &self,
        now: u64,
        sit: &Situation,
        inputs: &InputMonitor,
        safing_onset_ns: Option<u64>,
        measured: Option<BackupSeverity>,
    ) -> Option<BackupEvidence> {
        if sit.low_speed {
            return None;
        }
        let in_window = |t: u64| t.abs_diff(sit.contact_ns) <= self.window_ns;
        if let Some((decel, rx_ns)) = inputs.vehicle_decel(now) {
            if in_window(rx_ns) && decel >= self.backup_decel_mps2 {
                let contact_ns = safing_onset_ns
                    .map(|t| t.saturating_sub(self.accel_delay_ns))
                    .filter(|&t| in_window(t))
                    .unwrap_or(sit.contact_ns);
                return Some(BackupEvidence { rx_ns, contact_ns });
            }
        }
        let m = measured.filter(|m| m.airbag)?;
        let contact_ns = m.contact_ns.filter(|&t| in_window(t))?;
        Some(BackupEvidence {
            rx_ns: now,
            contact_ns,
        })
    }

    /// The crash measured by the healthy safing sensor, for the backup path: whether the
    /// safing event's Δv since its onset, at its newest sample, has reached the
    /// accelerometer-only airbag's and pyrotechnic pretensioner's boundaries and severity
    /// floors — with the satellites' `relief` and the road's lift as the crash sensor's samples
    /// are judged, the lift measured on the safing sensor while the crash sensor is known
    /// faulty — and the contact that onset dates (as
    /// [`Self::backup_evidence`] dates it). Persistence and loading are not asked: the backup's
    /// crash is decided by its own evidence, this times it and, for a crash sensor known
    /// faulty, stands in for its measurement.
    #[inline(never)]
    pub(crate) fn backup_boundaries(&self, safing: &Safing, relief: Relief) -> BackupSeverity {
        let Some((onset_ns, latest_ns)) = safing.event_span_ns() else {
            return BackupSeverity::default();
        };
        let tau_ms = latest_ns.saturating_sub(onset_ns) as f64 * 1e-6;
        let t = self.fallback.thresholds_now(
            self.safing_roughness
                .unwrap_or(self.roughness)
                .floor_lift_mps(),
            relief,
        );
        let (airbag, pretensioner) = self.fallback.boundaries_reached(
            tau_ms,
            safing.delta_v_mps(),
            t,
            relief.boundary_lift_mps,
        );
        BackupSeverity {
            contact_ns: Some(onset_ns.saturating_sub(self.accel_delay_ns)),
            airbag,
            pretensioner,
        }
    }

    /// The crash sensor's own accelerometer-only decisions on its event, for the backup path
    /// whose evidence dated the contact at `contact_ns`: whether the airbag's and the
    /// pyrotechnic pretensioner's decisions are must-fire (used while the safing sensor reads
    /// more than the crash sensor allows: the crash sensor's is then the smaller reading).
    #[inline(never)]
    pub(crate) fn own_severity(&self, contact_ns: u64) -> BackupSeverity {
        let fires = |d: FallbackDecision| matches!(d, FallbackDecision::Fire { .. });
        BackupSeverity {
            contact_ns: Some(contact_ns),
            airbag: fires(self.fallback()),
            pretensioner: fires(self.pretensioner()),
        }
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

/// What the healthy safing sensor measures of the backup path's crash
/// (`CrashMonitor::backup_boundaries`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct BackupSeverity {
    /// The contact its event's onset dates, ns (`None`: no safing event in progress).
    pub contact_ns: Option<u64>,
    /// Its Δv has reached the airbag's accelerometer-only boundary and floor.
    pub airbag: bool,
    /// Its Δv has reached the pyrotechnic pretensioner's accelerometer-only boundary and floor.
    pub pretensioner: bool,
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
