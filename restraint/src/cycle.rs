//! The restraint cycle: inputs + now → commands. Composes the four jobs, each in its own
//! module with its own state — [`InputMonitor`], [`Estimator`], [`Decision`], [`Outputs`] —
//! and implements the [`Activity`] contract the shell runs.
//!
//! All state is built in [`RestraintCycle::new`]; `step` does not allocate, lock, block or
//! panic (property-tested and counted in `tests/cycle_*.rs`).

use bus::secoc::SecOcTx;
use bus::{EnumCount, RejectReason, VariantArray};
use physics::CollisionSummary;

use crate::agreement::SeverityAgreement;
use crate::config::CycleConfig;
use crate::contract::{Activity, CycleInfo, CycleIo, StartupError};
use crate::counters::CycleCounters;
use crate::crash::{plan_for, CrashMonitor, FreezeContext};
use crate::decision::{Decision, DecisionInputs, Phase, Pretensioner};
use crate::estimate::{check_lut, Estimator, Lut, LutMismatch, Situation};
use crate::inputs::InputMonitor;
use crate::outputs::{publish_diagnostics, Outputs};
use crate::pair_monitor::{CycleMean, PairMonitor};
use crate::plan::{ReferenceSettings, RestraintPlan};
use crate::safing::Safing;
use crate::satellites::{Relief, Satellites, TUNNEL_FROZEN_NS};
use crate::settings::ConfigError;
use crate::settings::G_MPS2;
use crate::signals::{Degraded, SatelliteSide};

/// What [`RestraintCycle::new`] found (for start-up messages).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StartupNotes {
    /// The LUT given was optimised for another car, or verified for a smaller planning margin
    /// than the configured one needs: rejected, the ECU runs DEGRADED.
    pub lut_rejected: Option<LutMismatch>,
}

/// The restraint decision activity. `'lut` is the life of the characteristic diagram it
/// borrows (the shell keeps the loaded table alive as long as the cycle).
/// `Clone` so a bench can replay one prepared cycle many times (the state is plain data).
#[derive(Clone)]
pub struct RestraintCycle<'lut> {
    cfg: CycleConfig,
    inputs: InputMonitor,
    estimate: Estimator<'lut>,
    decision: Decision,
    crash: CrashMonitor,
    safing: Safing,
    /// The two accelerometers' Δv over the same window.
    agreement: SeverityAgreement,
    /// The two accelerometers against each other and the vehicle frame (offset, noise).
    pair: PairMonitor,
    /// The crush-zone satellites: the frontal severity that lowers the tunnel's thresholds.
    satellites: Satellites,
    /// Their relief as the newest judged accelerometer batch had it (none while the batches
    /// are quiet: no event, nothing to relieve).
    relief: Relief,
    /// The deceleration the car's braking explains, m/s², held while an accelerometer event
    /// is in progress (`braking_compensation_max_g`).
    braking_decel_mps2: f64,
    /// The crash sensor was known faulty at the end of the previous cycle: the safing sensor
    /// is the tunnel for the satellites' crush and the road's roughness.
    crash_sensor_faulty: bool,
    outputs: Outputs,
    reasons: Degraded,
    counters: CycleCounters,
}

/// Report-counter names of the E2E rejections, in [`RejectReason::VARIANTS`] order.
const E2E_COUNTER_NAMES: [&str; RejectReason::COUNT] = [
    "can_rejected_unknown_id",
    "can_rejected_wrong_dlc",
    "can_rejected_crc_mismatch",
    "can_rejected_counter_repeated",
    "can_rejected_counter_skipped",
    "can_rejected_out_of_range",
];

impl<'lut> RestraintCycle<'lut> {
    /// Builds the activity: validates `cfg`, precomputes the collision model and checks that
    /// `lut` belongs to the configured ego vehicle and margins. `lut = None` (or a mismatching table) →
    /// permanent `LUT_INVALID`: the ECU runs DEGRADED on the `reference` restraint.
    pub fn new(
        cfg: CycleConfig,
        lut: Option<Lut<'lut>>,
        reference: &ReferenceSettings,
    ) -> Result<(Self, StartupNotes), ConfigError> {
        cfg.validate()?;
        let (lut, lut_rejected) = check_lut(&cfg, lut);
        let thresholds = Estimator::thresholds(lut.as_ref());
        let reference = RestraintPlan::from_reference_settings(reference, &thresholds);
        let lut_id = lut.map_or(0, |l| l.id);
        let estimate = Estimator::new(&cfg, lut, reference)?;
        let s = Self {
            inputs: InputMonitor::new(&cfg),
            estimate,
            decision: Decision::new(&cfg, reference),
            crash: CrashMonitor::new(&cfg),
            safing: Safing::new(cfg.safing_params()),
            agreement: cfg.severity_agreement(),
            pair: PairMonitor::new(),
            satellites: Satellites::new(cfg.satellite_params()),
            relief: Relief::NONE,
            braking_decel_mps2: 0.0,
            crash_sensor_faulty: false,
            outputs: Outputs::new(lut_id),
            reasons: Degraded::empty(),
            counters: CycleCounters::default(),
            cfg,
        };
        Ok((s, StartupNotes { lut_rejected }))
    }

    /// Sets the SecOC sender (call once before the first `step`). `Some`: every
    /// `BeltLimiterCmd` / `AirbagStageCmd` frame is followed by its authenticator frame.
    /// `None`: the key file was unusable — commands go out without authenticators (the
    /// actuators ignore them) and `EcuStatus.FaultConfig` is set, so the failure is visible on
    /// the bus instead of the ECU refusing to start. A cycle never given a sender (tests,
    /// benches) sends no authenticators and reports no fault.
    pub fn set_secoc(&mut self, tx: Option<SecOcTx>) {
        self.outputs.set_secoc(tx);
    }

    /// Whether authenticator frames are sent.
    pub fn secoc_enabled(&self) -> bool {
        self.outputs.secoc_enabled()
    }
    /// Current phase.
    pub fn phase(&self) -> Phase {
        self.decision.phase()
    }
    /// Current degraded reasons.
    pub fn degraded_reasons(&self) -> Degraded {
        self.reasons
    }
    /// The preset plan (adaptive or reference).
    pub fn plan(&self) -> RestraintPlan {
        self.decision.plan()
    }
    /// The plan latched at crash confirmation.
    pub fn crash_plan(&self) -> RestraintPlan {
        self.decision.crash_plan()
    }
    /// The reference restraint plan.
    pub fn reference_plan(&self) -> RestraintPlan {
        self.decision.reference_plan()
    }
    /// Pretensioner state.
    pub fn pretensioner(&self) -> Pretensioner {
        self.decision.pretensioner()
    }
    /// The crash detectors' evidence (confirmation, matcher, accelerometer-only algorithm).
    pub fn crash(&self) -> &CrashMonitor {
        &self.crash
    }
    /// How the crash was confirmed (`None` before a crash).
    pub fn crash_kind(&self) -> Option<crate::crash::ConfirmKind> {
        self.decision.crash_kind()
    }
    /// A crash event is under way: the accelerometer shows one in progress, or the crash is
    /// confirmed (CRASH, POST-CRASH). Its cycles run the crash detectors on every sample.
    pub fn crash_event(&self) -> bool {
        self.crash.awake() || matches!(self.phase(), Phase::Crash | Phase::PostCrash)
    }
    /// Crash-phase fires the safing function vetoed (`fires_vetoed_by_safing`).
    pub fn vetoed_fires(&self) -> u64 {
        self.decision.vetoed_fires()
    }
    /// The crush-zone satellites' fusion.
    pub fn satellites(&self) -> &Satellites {
        &self.satellites
    }
    /// The safing function's state.
    pub fn safing(&self) -> &Safing {
        &self.safing
    }
    /// The two accelerometers' severity agreement.
    pub fn agreement(&self) -> &SeverityAgreement {
        &self.agreement
    }
    /// Whether the airbag fire command has been sent.
    pub fn airbag_fired(&self) -> bool {
        self.decision.airbag_fired()
    }
    /// Newest situation estimate.
    pub fn situation(&self) -> Option<Situation> {
        self.estimate.situation
    }
    /// Newest collision prediction.
    pub fn prediction(&self) -> Option<CollisionSummary> {
        self.estimate.summary
    }
    /// Counters.
    pub fn counters(&self) -> CycleCounters {
        self.counters
    }
    /// E2E receive statistics (rejections by [`RejectReason`]).
    pub fn e2e_stats(&self) -> bus::RxStats {
        *self.inputs.e2e_stats()
    }
    /// LUT id sent in the heartbeat (0 = no LUT).
    pub fn lut_id(&self) -> u16 {
        self.outputs.lut_id()
    }
    /// The configuration in use.
    pub fn config(&self) -> &CycleConfig {
        &self.cfg
    }
}

impl Activity for RestraintCycle<'_> {
    fn name(&self) -> &'static str {
        "restraint-cycle"
    }

    fn startup(&mut self, _now_ns: u64, _io: &mut dyn CycleIo) -> Result<(), StartupError> {
        Ok(())
    }

    fn step(&mut self, info: &CycleInfo, io: &mut dyn CycleIo) {
        let now = info.now_ns;
        let c = &mut self.counters;
        let inputs = &mut self.inputs;
        inputs.begin_cycle();
        io.drain_can(&mut |f| inputs.on_can(f, now, c));
        io.drain_objects(&mut |o| inputs.on_object(o, now, c));
        // Plausible samples go to the crash detectors; a wake-up in PRE-CRASH freezes the
        // prediction of the previous cycle's situation.
        let freeze = FreezeContext {
            situation: self.estimate.situation,
            armed: self.decision.phase() == Phase::PreCrash,
            estimator: &self.estimate,
        };
        // The braking the vehicle frame explains, as it was before the event began (a crash
        // shows on the vehicle frame too, one frame later: it must not explain itself). Not in
        // PRE-CRASH: there the crash is predicted, its own (AEB) braking belongs to it and
        // the plan's fire times were made with it (config docs).
        if !self.crash.event_in_progress() {
            self.braking_decel_mps2 = if self.decision.phase() == Phase::PreCrash {
                0.0
            } else {
                inputs.braking_decel(now, self.cfg.braking_compensation_max_g * G_MPS2)
            };
        }
        let braking = self.braking_decel_mps2;
        let belted = inputs.occupant_belted(now);
        let no_fire_ebs_kph = self.cfg.no_fire_line_kph(belted);
        // The satellites first: their crush Δv up to now relieves this cycle's samples.
        let satellites = &mut self.satellites;
        satellites.begin_cycle(now);
        io.drain_satellites(&mut |side, b| satellites.on_frames(side, b, now));
        // A folding front end lowers the boundary only for a tracked crash that is a must-fire
        // one even against the lightest opponent the object list's report allows; asked only
        // while the crash detector judges an event (a fold needs milliseconds of crush anyway).
        let fold_ok = self.crash.awake()
            && self.estimate.situation.as_ref().is_some_and(|s| {
                must_fire_if_lightest(
                    s.closing_speed_mps,
                    s.opponent_mass_estimate_kg - self.cfg.mass_misreport_kg,
                    self.cfg.ego_mass_kg,
                    no_fire_ebs_kph,
                )
            });
        satellites.allow_fold(fold_ok);
        // The satellites' crush and the road's roughness are measured on the tunnel: the crash
        // sensor, or the safing sensor while the crash sensor is known faulty (as of the
        // previous cycle).
        let tunnel_is_safing = self.crash_sensor_faulty;
        let crash = &mut self.crash;
        let agreement = &mut self.agreement;
        // The relief of the cycle's latest judged batch (none when every batch was quiet).
        let relief = &mut self.relief;
        *relief = Relief::NONE;
        let mut plausible = crate::accel::PlausibleBatch::new();
        let (mut crash_mean, mut safing_mean) = (CycleMean::default(), CycleMean::default());
        io.drain_accel(&mut |a| {
            inputs.on_accel(a, now, c, &mut plausible);
            crash_mean.add(&plausible);
            // The agreement, the road's roughness and the satellites' crush Δv take the
            // readings as they are.
            let beside = agreement.safing.recording();
            agreement.crash.on_batch(&plausible, beside);
            let (dv_mps, span_s) = plausible.decel_integral_mps();
            crash.on_raw_batch(dv_mps, span_s);
            if !tunnel_is_safing {
                satellites.on_tunnel_dv(dv_mps);
            }
            plausible.remove_decel(braking);
            let accel = &inputs.accel;
            crash.on_batch(&plausible, &freeze, belted, || {
                // A frozen crash sensor is no reference for the satellites' crush
                // (`satellites::TUNNEL_FROZEN_MS`); asked of a judged batch only.
                let frozen = !tunnel_is_safing
                    && plausible
                        .last_sample()
                        .is_some_and(|(t, _)| accel.unchanged_for_ns(t) >= TUNNEL_FROZEN_NS);
                satellites.set_tunnel_frozen(frozen);
                *relief = satellites.relief(now, belted);
                *relief
            });
        });
        // The front end began to fold in this cycle: a judged segment that a road's lobe or a
        // kerb strike began earlier restarts at the fold (after the cycle's batches, the
        // latest of which `plausible` holds).
        if let Some(o) = self.satellites.crush_onset_at(now) {
            self.crash.restart_at_crush(o, braking, &plausible);
        }
        // A crash phase that has fired nothing follows the next accelerometer event when its
        // own has ended (`CrashMonitor::follow_later_event`). The phase is asked first, inline:
        // outside a crash the cycle pays one compare, not the out-of-line call.
        if self.decision.phase() == Phase::Crash && self.decision.nothing_fired_in_crash() {
            self.crash.follow_later_event(now);
        }
        // The independent safing channel: its own monitor, its own function.
        let safing = &mut self.safing;
        let crash = &mut self.crash;
        let satellites = &mut self.satellites;
        let mut safing_batch = crate::accel::PlausibleBatch::new();
        io.drain_safing(&mut |a| {
            inputs.on_safing(a, now, &mut safing_batch);
            safing_mean.add(&safing_batch);
            if tunnel_is_safing {
                let (dv_mps, span_s) = safing_batch.decel_integral_mps();
                crash.on_raw_safing_batch(dv_mps, span_s);
                satellites.on_tunnel_dv(dv_mps);
            } else {
                crash.end_safing_roughness(now);
            }
            safing.on_batch(&safing_batch);
            let beside = agreement.crash.recording();
            agreement.safing.on_batch(&safing_batch, beside);
        });
        inputs.on_receive_errors(io.receive_errors(), now);
        // The fresh vehicle frame's deceleration: the pair check's reference and, for a faulty
        // safing sensor, the safing function's stand-in (no CAN frame is read after this).
        let vehicle = inputs.vehicle_decel(now);
        let pair = self
            .pair
            .on_cycle(now, &crash_mean, &safing_mean, vehicle.map(|(d, _)| d));
        if pair.crash_faulty {
            inputs.accel.flag_implausible(now);
        }
        if pair.safing_faulty {
            inputs.safing.flag_implausible(now);
        }
        let lut_present = self.estimate.lut().is_some();
        self.reasons = self.inputs.reasons(now, io.can_enabled(), lut_present);
        // A satellite out of the fusion is reported, never degrading (`EcuStatus`'s
        // FaultSatelliteLeft / FaultSatelliteRight).
        let sat = &self.satellites;
        self.reasons.set(
            Degraded::SATELLITE_LEFT,
            sat.faulty(SatelliteSide::Left, now),
        );
        self.reasons.set(
            Degraded::SATELLITE_RIGHT,
            sat.faulty(SatelliteSide::Right, now),
        );
        let c = &mut self.counters;
        if self.reasons.contains(Degraded::OBJECT_STALE) {
            c.object_stale_cycles = c.object_stale_cycles.saturating_add(1);
            if self.inputs.objects_seen() {
                c.object_lost_cycles = c.object_lost_cycles.saturating_add(1);
            }
        }
        if self.reasons.contains(Degraded::ACCEL_STALE) {
            self.inputs.accel.note_stale_cycle();
        }
        let degraded = self.reasons.intersects(Degraded::DEGRADING);
        if degraded {
            c.degraded_cycles = c.degraded_cycles.saturating_add(1);
        }
        // Recompute the situation only when its inputs changed materially, and only before
        // the crash: from confirmation on the plan is latched and the estimate frozen (the
        // tracker sees the opponent at the bumper; its cycles belong to the crash phase), and
        // not once the accelerometer shows a crash in progress (the object list then predicts
        // nothing new; the crash matcher keeps its own frozen prediction).
        let crashed = matches!(self.decision.phase(), Phase::Crash | Phase::PostCrash);
        let estimated = !crashed
            && !self.crash.awake()
            && (self.inputs.new_object
                || (self.inputs.occupant_changed && self.estimate.situation.is_some()));
        if estimated {
            if let Some(plan) = self.estimate.update(now, &self.inputs, no_fire_ebs_kph, c) {
                self.decision.plan = plan;
            }
        }
        if self.reasons.contains(Degraded::OBJECT_STALE) {
            self.estimate.situation = None; // a stale track predicts nothing
        }
        let accel_faulty = self
            .reasons
            .intersects(Degraded::ACCEL_STALE | Degraded::ACCEL_INVALID)
            || self.inputs.accel_port_error(now);
        let safing_faulty = self
            .reasons
            .intersects(Degraded::SAFING_STALE | Degraded::SAFING_INVALID);
        self.crash_sensor_faulty = accel_faulty;
        // Asked only for a faulty safing sensor, which it stands in for.
        let front_end_crushed = safing_faulty && self.satellites.front_end_crushed(now);
        let mut safing = self
            .safing
            .agrees(now, safing_faulty, vehicle, front_end_crushed);
        // With a healthy safing sensor, safing must also agree in severity on the confirmed
        // event (module `agreement`) — also once the crash sensor is found faulty (a stuck
        // sensor's first 20 ms were plausible); the backup path (confirmed by the vehicle
        // deceleration) has no crash-sensor event to compare.
        let (mut pair_disagrees, mut crash_reads_more) = (false, false);
        if let Some(c) = self.crash.confirmation() {
            if !safing_faulty && c.kind != crate::crash::ConfirmKind::Backup {
                safing &= self.agreement.agrees(c.onset_ns);
                pair_disagrees = self.agreement.pair_disagrees(c.onset_ns);
                crash_reads_more = self.agreement.crash_reads_more(c.onset_ns);
            }
        }
        // Two accelerometers that disagree on the confirmed event cannot say which of them is
        // wrong (a crash sensor reading high, or a safing sensor reading low): the event is
        // then decided by the backup path's two other sources, a predicted crash and the
        // vehicle deceleration on CAN (`Decision`, "backup for a disagreeing pair"). So is an
        // event the crash sensor confirmed while the pair check holds it faulty.
        let crash_flagged = self.pair.crash_flagged(now)
            && self
                .crash
                .confirmation()
                .is_some_and(|c| c.kind != crate::crash::ConfirmKind::Backup);
        let safing_onset_ns = (!safing_faulty).then(|| self.safing.onset_ns()).flatten();
        // The safing sensor measures the crash for the backup while the crash sensor is known
        // faulty, or reads more than the safing sensor allows (whichever of the two is wrong,
        // the safing sensor's is then the smaller reading) — never for a safing sensor that
        // reads more —, with the satellites' relief against it as the tunnel.
        let safing_measures = accel_faulty || crash_flagged || crash_reads_more;
        let mut measured = if safing_measures && !safing_faulty && self.safing.onset_ns().is_some()
        {
            let relief = self.satellites.relief(now, belted);
            Some(self.crash.backup_boundaries(&self.safing, relief))
        } else {
            None
        };
        let backup_for_disagreement = if pair_disagrees || crash_flagged {
            let evidence = self.estimate.situation.as_ref().and_then(|s| {
                self.crash
                    .backup_evidence(now, s, &self.inputs, safing_onset_ns, measured)
            });
            // The safing sensor read more than the crash sensor allows (and the crash sensor
            // never more): the crash sensor's is then the smaller reading whichever of the two
            // is wrong, so its own accelerometer-only decisions time the backup's fires, as the
            // safing sensor's measurement does the other way round. The decision stays the
            // evidence's; this only brings its scheduled fires forward (and a healthy crash
            // sensor's measurement confirms no backup: `CrashMonitor::end_cycle`).
            if let (None, Some(e)) = (measured, evidence) {
                if !crash_reads_more && !crash_flagged && !accel_faulty {
                    measured = Some(self.crash.own_severity(e.contact_ns));
                }
            }
            evidence
        } else {
            None
        };
        self.crash.end_cycle(
            now,
            accel_faulty,
            self.estimate.situation.as_ref(),
            &self.inputs,
            safing_onset_ns,
            measured,
        );
        let (cfg, est, inputs) = (&self.cfg, &self.estimate, &self.inputs);
        let situation = est.situation;
        let c = &mut self.counters;
        // A table lookup, asked only when a crash phase is entered with a belt-only plan.
        let crash = &self.crash;
        let event_loading = || crash.event_loading();
        let heaviest_fires_airbag =
            || situation.is_some_and(|s| est.heaviest_opponent_fires_airbag(&s, inputs));
        let mut replan = |closing_mps: f64| {
            let sit = situation?;
            plan_for(cfg, est, &sit, closing_mps, inputs, no_fire_ebs_kph, c)
        };
        let mut x = DecisionInputs {
            half_period_ns: info.period_ns / 2,
            degraded,
            situation,
            no_fire_ebs_kph,
            new_object: self.inputs.new_object,
            object_present: self.inputs.object_present,
            confirmation: self.crash.confirmation(),
            fallback: self.crash.fallback(),
            pretensioner_fallback: self.crash.pretensioner(),
            segment_onset_ns: self.crash.segment_onset_ns(),
            safing,
            backup_for_disagreement,
            backup_severity: measured,
            event_in_progress: self.crash.event_in_progress(),
            event_dv_mps: self.crash.event_dv_mps(),
            event_loading: &event_loading,
            floor_lift_mps: self.crash.floor_lift_mps(),
            relief: self.relief,
            matched_course_broken: self.crash.matcher().course_broken_ns().is_some(),
            heaviest_fires_airbag: &heaviest_fires_airbag,
            replan: &mut replan,
        };
        self.decision.step(now, &mut x);
        if self.decision.take_abandoned() {
            self.crash.rearm();
        }
        // Prediction and diagnostics pulse in the cycles that have time (estimate docs): not
        // in a crash, nor while the accelerometer shows one in progress.
        if !estimated
            && !matches!(self.phase(), Phase::Crash | Phase::PostCrash)
            && !self.crash.awake()
        {
            self.estimate.background(&mut self.counters);
        }
        let c = &mut self.counters;
        self.outputs
            .write(info, io, &self.decision, &self.inputs, self.reasons, c);
        publish_diagnostics(
            info,
            io,
            &self.decision,
            &self.estimate,
            &self.inputs,
            self.reasons,
            c,
        );
    }

    fn shutdown(&mut self, _now_ns: u64, _io: &mut dyn CycleIo) {}

    fn report_counters(&self, out: &mut dyn FnMut(&'static str, u64)) {
        let c = &self.counters;
        let a = self.inputs.accel.faults;
        let e2e = self.inputs.e2e_stats();
        for (name, v) in [
            ("objects_rx", c.objects_rx),
            ("objects_invalid", c.objects_invalid),
            ("object_stale_cycles", c.object_stale_cycles),
            ("object_lost_cycles", c.object_lost_cycles),
            ("accel_batches_rx", c.accel_batches_rx),
            ("accel_samples_rx", c.accel_samples_rx),
            ("accel_bad_time_batches", a.bad_time_batches),
            ("accel_out_of_range_samples", a.out_of_range_samples),
            ("accel_saturated_samples", a.saturated_samples),
            ("accel_stuck_events", a.stuck_events),
            ("accel_stale_cycles", a.stale_cycles),
            (
                "safing_bad_time_batches",
                self.inputs.safing.faults.bad_time_batches,
            ),
            (
                "safing_out_of_range_samples",
                self.inputs.safing.faults.out_of_range_samples,
            ),
            (
                "safing_saturated_samples",
                self.inputs.safing.faults.saturated_samples,
            ),
            (
                "safing_stuck_events",
                self.inputs.safing.faults.stuck_events,
            ),
            (
                "satellite_corrupt_frames",
                self.satellites.faults.corrupt_frames,
            ),
            (
                "satellite_status_frames",
                self.satellites.faults.status_frames,
            ),
            ("satellite_bad_batches", self.satellites.faults.bad_batches),
            ("satellite_implausible", self.satellites.faults.implausible),
            (
                "satellite_relieved_batches",
                self.satellites.relieved_batches,
            ),
            ("fires_vetoed_by_safing", self.decision.vetoed_fires()),
            ("fires_below_floor", self.decision.fires_below_floor()),
            ("severity_disagreements", self.agreement.disagreements()),
            ("can_frames_rx", c.can_frames_rx),
            ("can_accepted", e2e.accepted),
            ("can_lost_frames", e2e.lost_frames),
            ("track_starts", c.track_starts),
            ("track_outliers", c.track_outliers),
            ("track_refused", c.track_refused),
            ("predictions", c.predictions),
            ("prediction_errors", c.prediction_errors),
            ("lut_lookups", c.lut_lookups),
            ("v2x_lookups", c.v2x_lookups),
            ("lut_out_of_range", c.lut_out_of_range),
            ("lut_bottoming_out", c.lut_bottoming_out),
            ("degraded_cycles", c.degraded_cycles),
            ("can_tx", c.can_tx),
            ("can_tx_errors", c.can_tx_errors),
            ("secoc_commands_tx", c.secoc_commands_tx),
            ("encode_errors", c.encode_errors),
            ("diagnostics_publish_failures", c.diagnostics_failures),
        ] {
            out(name, v);
        }
        for (name, reason) in E2E_COUNTER_NAMES.iter().zip(RejectReason::VARIANTS) {
            out(name, e2e.rejected_for(*reason));
        }
    }
}

/// Whether a tracked crash at `closing_mps` is a must-fire one (ego EBS at the no-fire line or
/// above) against an opponent of `lightest_kg` — its reported mass less the planning margin:
/// then one object fault cannot make a no-fire crash pass (`satellites`, "The front end folds").
fn must_fire_if_lightest(
    closing_mps: f64,
    lightest_kg: f64,
    ego_kg: f64,
    no_fire_ebs_kph: f64,
) -> bool {
    // EBS = v · m / (ego + m) · 3.6 ≥ line, without the division (both masses ≥ 0).
    let m = lightest_kg.max(0.0);
    closing_mps * m * 3.6 >= no_fire_ebs_kph * (ego_kg + m)
}

#[cfg(test)]
mod tests {
    use super::must_fire_if_lightest;

    /// The division-free form is the EBS against the line: a 64 km/h fixed barrier reported
    /// at 3 000 kg is a must-fire crash even at 1 800 kg (EBS 32.1 km/h), equal cars at
    /// 35 + 35 km/h are not at 585 kg (17.3 km/h), and a mass under the margin is none.
    #[test]
    fn the_lightest_opponent_decides_against_the_line() {
        let ego = 1785.0;
        assert!(must_fire_if_lightest(
            64.0 / 3.6,
            3000.0 - 1200.0,
            ego,
            20.0
        ));
        assert!(!must_fire_if_lightest(
            70.0 / 3.6,
            1785.0 - 1200.0,
            ego,
            20.0
        ));
        assert!(!must_fire_if_lightest(100.0, 800.0 - 1200.0, ego, 20.0));
        assert!(!must_fire_if_lightest(f64::NAN, 3000.0, ego, 20.0));
        for (v, m) in [(10.0, 900.0), (12.3, 2400.0), (30.0, 300.0), (8.0, 9000.0)] {
            let ebs = physics::equivalent_barrier_speed_kph(v, ego, m);
            for line in [ebs - 0.01, ebs + 0.01] {
                assert_eq!(
                    must_fire_if_lightest(v, m, ego, line),
                    ebs >= line,
                    "{v} {m} {line}"
                );
            }
        }
    }
}
