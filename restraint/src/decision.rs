//! The decision state machine: when to preset, arm, fire, release and fall back.
//!
//! ```text
//! Monitoring ──valid object, TTC < horizon, EBS ≥ no-fire──▶ PreCrash (preset, armed,
//!     ▲   ▲                                                  pretensioner at contact + t_pt)
//!     │   └──────── avoided (lost / receding / contact + margin passed): release, disarm
//!     │
//!  Degraded (stale/invalid inputs, E2E burst, no LUT, faulty accelerometer): reference
//!
//! any of the three ──crash confirmed (crash::Confirmation)──▶ Crash ──all done──▶ PostCrash
//! ```
//!
//! **The crash plan** — every path to Fire (README "Decision table"):
//!
//! | confirmed by | when | plan | airbag |
//! |---|---|---|---|
//! | the pulse following the prediction (onset slope within ± `match_tolerance`) | PRE-CRASH, not degraded | the preset plan (table at the predicted speed and the robust mass; the reference restraint where the table does not cover the situation) | at max(confirm, onset + t_ab) if the plan fires; the reference at the confirmation (held below its floor) |
//! | the pulse departing from the prediction within the re-estimation range | PRE-CRASH, not degraded, re-estimated at or above the no-fire line | the table at the re-estimated closing speed and the robust mass (`crash::plan_for`) | as above |
//! | the vehicle-dynamics deceleration on CAN (backup) | crash accelerometer faulty, a crash predicted above the no-fire line | reference restraint | at max(confirm, predicted contact + t_ab,ref) |
//! | the generic thresholds (any other case: no prediction, degraded, pulse refuted or re-estimated below the no-fire line) | — | reference belt | only when the accelerometer-only algorithm decides must-fire: at the decision (an adaptive plan kept: at max(decision, onset + t_ab)) |
//!
//! Only the matched path uses the table: it confirms 1.5–3.5 ms after contact, so a plan is
//! executed within a cycle of its time, which is what the table's fire-delay tolerance assumes.
//!
//! Inputs are the estimate ([`Situation`], the looked-up plan), the input monitor's object
//! facts, the crash detectors' evidence and whether the inputs are degraded; outputs are the
//! phase, the active plan and the pretensioner/airbag commands ([`Decision`]'s accessors).

use crate::config::CycleConfig;
use crate::crash::{BackupEvidence, BackupSeverity, ConfirmKind, Confirmation};
use crate::estimate::Situation;
use crate::fallback::{FallbackDecision, LATE_WINDOW_MS};
use crate::plan::{PlanSource, RestraintPlan};
use crate::satellites::Relief;
use crate::settings::ms_to_ns;
use crate::signals::EcuMode;

/// Decision phase (what the state machine is doing).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Phase {
    /// Inputs fine, no imminent collision.
    Monitoring,
    /// Collision predicted: settings preset, airbag armed, pretensioner at its planned time.
    PreCrash,
    /// Inputs degraded: the reference restraint is armed.
    Degraded,
    /// Crash confirmed by the accelerometer; fires pending.
    Crash,
    /// Everything commanded has fired (latched until restart).
    PostCrash,
}

impl Phase {
    /// The diagnostics mode of this phase.
    pub fn mode(self) -> EcuMode {
        match self {
            Self::Monitoring => EcuMode::Monitoring,
            Self::PreCrash => EcuMode::PreCrash,
            Self::Degraded => EcuMode::Degraded,
            Self::Crash => EcuMode::Crash,
            Self::PostCrash => EcuMode::PostCrash,
        }
    }
}

/// State of the reversible pretensioner as commanded.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Pretensioner {
    /// Not commanded.
    Idle,
    /// Fired (slack removed).
    Fired,
    /// Released after an avoided collision.
    Released,
}

/// What the state machine reads from the estimate and the input monitor in one cycle.
pub(crate) struct DecisionInputs<'d> {
    /// Half the cycle period, ns: a scheduled fire goes out in the cycle nearest its time.
    pub half_period_ns: u64,
    /// Any degrading reason is set.
    pub degraded: bool,
    /// Newest situation estimate (`None`: no object, no contact, or stale).
    pub situation: Option<Situation>,
    /// The airbag's no-fire line for the occupant, km/h (`CycleConfig::no_fire_line_kph`).
    pub no_fire_ebs_kph: f64,
    /// A new object sample arrived this cycle.
    pub new_object: bool,
    /// The newest object sample tracks an object.
    pub object_present: bool,
    /// The crash confirmation (latched), if any.
    pub confirmation: Option<Confirmation>,
    /// The accelerometer-only algorithm's decision on the current event.
    pub fallback: FallbackDecision,
    /// The pretensioner's accelerometer-only decision on the current event.
    pub pretensioner_fallback: FallbackDecision,
    /// Start of the segment of the current event the accelerometer-only algorithm judges (its
    /// onset or latest re-onset, `FallbackAlgorithm::segment_onset_ns`), ns.
    pub segment_onset_ns: Option<u64>,
    /// The safing function agrees in this cycle (`safing`).
    pub safing: bool,
    /// The two accelerometers disagree on the confirmed event and the backup path's evidence
    /// holds (`CrashMonitor::backup_evidence`).
    pub backup_for_disagreement: Option<BackupEvidence>,
    /// What the healthy safing sensor measures of the crash while the crash sensor is known
    /// faulty or reads more than the safing sensor allows (`CrashMonitor::backup_boundaries`);
    /// while the safing sensor reads more, the crash sensor's own accelerometer-only decisions.
    pub backup_severity: Option<BackupSeverity>,
    /// An accelerometer event is still in progress.
    pub event_in_progress: bool,
    /// The velocity change of the current accelerometer event since its onset, m/s.
    pub event_dv_mps: f64,
    /// Whether the current accelerometer event is still loading (`CrashMonitor::event_loading`;
    /// asked only where a matched fire held below its floor has the Δv).
    pub event_loading: &'d dyn Fn() -> bool,
    /// What the road's roughness adds to every severity floor, m/s (`roughness`).
    pub floor_lift_mps: f64,
    /// What the crush-zone satellites take off the severity floors and the lift now
    /// (`satellites`).
    pub relief: Relief,
    /// A matched confirmation's pulse has left its ramp (`PulseMatch::course_broken_ns`).
    pub matched_course_broken: bool,
    /// Whether the table fires the airbag for this situation with the heaviest opponent it
    /// covers (`Estimator::heaviest_opponent_fires_airbag`: a lookup, asked only when a crash
    /// phase is entered with a belt-only plan).
    pub heaviest_fires_airbag: &'d dyn Fn() -> bool,
    /// The table's plan for an adaptive crash at a closing speed (m/s): `None` when that
    /// severity is below the no-fire line (`crash::plan_for`).
    pub replan: &'d mut dyn FnMut(f64) -> Option<RestraintPlan>,
}

/// How a restraint of the crash plan (airbag, pyrotechnic pretensioner) is decided.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum AirbagGate {
    /// Decided at the confirmation (scheduled or not fired).
    Decided,
    /// Waiting for the accelerometer-only algorithm of the confirmed event (conventional
    /// path): its must-fire schedules the restraint, its no-fire or the window's end drops it.
    Fallback,
}

/// State of the decision.
#[derive(Debug, Clone)]
pub struct Decision {
    horizon_ns: u64,
    exit_horizon_ns: u64,
    avoided_margin_ns: u64,
    reference: RestraintPlan,
    /// The preset plan (adaptive or reference).
    pub(crate) plan: RestraintPlan,
    crash_plan: RestraintPlan,
    phase: Phase,
    pretensioner: Pretensioner,
    pretensioner_at_ns: Option<u64>,
    airbag_fire_at_ns: Option<u64>,
    airbag_fired: bool,
    armed: bool,
    contact_ns: Option<u64>,
    /// The accelerometer event of the crash phase (`Confirmation::onset_ns`).
    event_onset_ns: u64,
    /// A tracked low-speed crash: the airbag needs the event's Δv above this, m/s.
    low_speed_dv_limit_mps: Option<f64>,
    /// The closing speed from which one object fault (any opponent mass down to
    /// `lightest_opponent_kg`, the closing speed `speed_misreport_mps` high) cannot have lifted
    /// a crash over the no-fire line, m/s: a matched crash slower than this waits for the
    /// measured pulse ([`CycleConfig::unguarded_closing_mps`]).
    unguarded_closing_mps: f64,
    /// `CycleConfig::low_speed_misuse_dv_mps`, `low_speed_dv_factor`.
    low_speed_misuse_dv_mps: f64,
    low_speed_dv_factor: f64,
    /// For the low-speed limit: the ego mass, the opponent-mass misreport one fault may carry
    /// (`mass_misreport_kg`; the no-fire line is the situation's, for its occupant).
    ego_mass_kg: f64,
    mass_misreport_kg: f64,
    gate: AirbagGate,
    /// The pyrotechnic pretensioner's gate in the crash phase.
    pt_gate: AirbagGate,
    /// A due crash-phase fire waits this long for the safing agreement, ns.
    safing_wait_ns: u64,
    /// Something fired in the crash phase (it then ends in POST-CRASH).
    crash_fired: bool,
    /// The crash phase's pretensioner decision latched a belt the pre-crash plan had already
    /// tensioned (it then ends in POST-CRASH too, but nothing new went out: the backup may
    /// still take a disagreeing pair's event over).
    belt_latched: bool,
    /// The phase the crash phase was entered from (returned to when the event ends with
    /// nothing fired).
    before_crash: Phase,
    /// The crash phase ended without a fire: the cycle re-arms the detectors.
    abandoned: bool,
    /// Crash-phase fires dropped because the safing function did not agree in time.
    vetoed: u64,
    /// How the crash was confirmed (latched with the crash plan).
    crash_kind: Option<ConfirmKind>,
    /// The severity floors a matched crash's fires wait for, m/s (airbag, pyrotechnic
    /// pretensioner): the conventional path's `fallback_min_dv_mps` and
    /// `pretensioner_min_dv_mps` ([`Decision::hold_below_floor`]).
    airbag_floor_mps: f64,
    pretensioner_floor_mps: f64,
    /// Matched fires dropped because their event ended below the floor.
    held_below_floor: u64,
    /// The crash phase was handed to the backup path because the accelerometers disagree:
    /// its fires stand on the vehicle deceleration instead of the safing agreement.
    backup_stands_in: bool,
}

fn time_ms_to_ns(t_ms: f32) -> i64 {
    (f64::from(t_ms) * 1.0e6) as i64
}

fn at(base_ns: u64, offset_ms: f32) -> u64 {
    base_ns.saturating_add_signed(time_ms_to_ns(offset_ms))
}

impl Decision {
    /// Monitoring, reference restraint preset.
    pub fn new(cfg: &CycleConfig, reference: RestraintPlan) -> Self {
        let horizon_ns = ms_to_ns(cfg.preset_horizon_ms);
        Self {
            horizon_ns,
            exit_horizon_ns: horizon_ns.saturating_add(ms_to_ns(cfg.preset_exit_hysteresis_ms)),
            avoided_margin_ns: ms_to_ns(cfg.avoided_margin_ms),
            reference,
            plan: reference,
            crash_plan: reference,
            phase: Phase::Monitoring,
            pretensioner: Pretensioner::Idle,
            pretensioner_at_ns: None,
            airbag_fire_at_ns: None,
            airbag_fired: false,
            armed: false,
            contact_ns: None,
            event_onset_ns: 0,
            low_speed_dv_limit_mps: None,
            unguarded_closing_mps: cfg.unguarded_closing_mps(),
            low_speed_misuse_dv_mps: cfg.low_speed_misuse_dv_mps,
            low_speed_dv_factor: cfg.low_speed_dv_factor,
            ego_mass_kg: cfg.ego_mass_kg,
            mass_misreport_kg: cfg.mass_misreport_kg,
            gate: AirbagGate::Decided,
            pt_gate: AirbagGate::Decided,
            safing_wait_ns: ms_to_ns(cfg.safing_wait_ms),
            crash_fired: false,
            belt_latched: false,
            before_crash: Phase::Monitoring,
            abandoned: false,
            vetoed: 0,
            crash_kind: None,
            airbag_floor_mps: cfg.fallback_min_dv_mps,
            // A matched pretensioner waits for the lower of the two floors: the matched hold is
            // against misuse at a predicted contact (≤ 1.2 m/s), which the airbag's floor
            // already exceeds; the pretensioner's own, higher floor is for the conventional
            // path, where a rough road's first lobe has no prediction to be refuted by.
            pretensioner_floor_mps: cfg.pretensioner_min_dv_mps.min(cfg.fallback_min_dv_mps),
            held_below_floor: 0,
            backup_stands_in: false,
        }
    }

    /// Matched crash-phase fires dropped because their event ended before it carried the
    /// restraint's severity floor.
    pub fn fires_below_floor(&self) -> u64 {
        self.held_below_floor
    }

    /// Crash-phase fires the safing function vetoed (not agreeing within `safing_wait_ms`).
    pub fn vetoed_fires(&self) -> u64 {
        self.vetoed
    }

    /// True once after a crash phase ended with nothing fired (the event is over): the
    /// caller re-arms the crash detectors ([`crate::crash::CrashMonitor::rearm`]).
    pub fn take_abandoned(&mut self) -> bool {
        core::mem::take(&mut self.abandoned)
    }

    /// How the crash was confirmed (`None` before a crash).
    pub fn crash_kind(&self) -> Option<ConfirmKind> {
        self.crash_kind
    }

    /// Current phase.
    pub fn phase(&self) -> Phase {
        self.phase
    }
    /// The preset plan (adaptive or reference).
    pub fn plan(&self) -> RestraintPlan {
        self.plan
    }
    /// The plan latched at crash confirmation.
    pub fn crash_plan(&self) -> RestraintPlan {
        self.crash_plan
    }
    /// The reference restraint plan.
    pub fn reference_plan(&self) -> RestraintPlan {
        self.reference
    }
    /// Pretensioner state.
    pub fn pretensioner(&self) -> Pretensioner {
        self.pretensioner
    }
    /// Whether the airbag fire command has been given.
    pub fn airbag_fired(&self) -> bool {
        self.airbag_fired
    }
    /// Whether the airbag is armed.
    pub fn armed(&self) -> bool {
        self.armed
    }

    /// The plan the commands carry in the current phase.
    pub fn active_plan(&self) -> RestraintPlan {
        match self.phase {
            Phase::Crash | Phase::PostCrash => self.crash_plan,
            Phase::PreCrash => self.plan,
            Phase::Monitoring | Phase::Degraded => self.reference,
        }
    }

    fn release_pretensioner(&mut self) {
        if self.pretensioner == Pretensioner::Fired {
            self.pretensioner = Pretensioner::Released;
        }
        self.pretensioner_at_ns = None;
    }

    /// The crash plan and its airbag gate for confirmation `c` (table in the module docs).
    fn crash_plan_for(
        &mut self,
        c: &Confirmation,
        x: &mut DecisionInputs<'_>,
    ) -> (RestraintPlan, AirbagGate) {
        let predicted = self.phase == Phase::PreCrash && !x.degraded;
        if let (ConfirmKind::Matched(e), true) = (c.kind, predicted) {
            // A fire only the prediction justifies waits for the measured pulse unless one
            // object fault could not have lifted the crash over the no-fire line.
            let closing = x
                .situation
                .map_or(0.0, |s| s.closing_speed_mps)
                .min(e.closing_mps);
            let gate = if closing >= self.unguarded_closing_mps {
                AirbagGate::Decided
            } else {
                AirbagGate::Fallback
            };
            // Follows the prediction: the preset plan (the radar's speed is the better
            // estimate; the onset slope mixes speed with the structures' stiffness, which
            // differs by up to ±10 % between the classes). Departs: the re-estimated severity.
            if e.follows {
                return (self.plan, gate);
            }
            if let Some(plan) = (x.replan)(e.closing_mps) {
                return (plan, gate);
            }
        }
        // A tracked low-speed object whose predicted contact is the measured one: its own
        // Δv (and a misuse event's on top) never fires the airbag. Low-speed here even with
        // the opponent `mass_misreport_kg` heavier than reported (one misreport cannot make a
        // severe crash look low-speed), and a standing object's mass is not credited at all:
        // the object sensor cannot weigh a wall, a pole or a parked truck (it reports a
        // default), so its EBS is the closing speed. The bound takes the closing speed, not
        // the EBS: the opponent's mass only lowers the ego's Δv (EBS ≤ closing speed).
        let no_fire_ebs_kph = x.no_fire_ebs_kph;
        if let Some(s) = x.situation.filter(|s| {
            let robust_opponent_kg = if s.opponent_standing {
                f64::INFINITY
            } else {
                s.opponent_mass_estimate_kg + self.mass_misreport_kg
            };
            let robust_ebs_kph = physics::equivalent_barrier_speed_kph(
                s.closing_speed_mps,
                self.ego_mass_kg,
                robust_opponent_kg,
            );
            s.low_speed
                && robust_ebs_kph < no_fire_ebs_kph
                && s.contact_estimate_ns.abs_diff(c.contact_ns) <= self.avoided_margin_ns
        }) {
            self.low_speed_dv_limit_mps =
                Some(s.closing_speed_mps * self.low_speed_dv_factor + self.low_speed_misuse_dv_mps);
        }
        if c.kind == ConfirmKind::Backup {
            return (self.reference, AirbagGate::Decided);
        }
        (self.reference, AirbagGate::Fallback)
    }

    fn enter_crash(&mut self, c: Confirmation, x: &mut DecisionInputs<'_>) {
        self.low_speed_dv_limit_mps = None;
        self.backup_stands_in = false;
        let (plan, gate) = self.crash_plan_for(&c, x);
        let (confirm_ns, contact) = (c.at_ns, c.contact_ns);
        self.before_crash = self.phase;
        self.crash_plan = plan;
        self.crash_kind = Some(c.kind);
        self.gate = gate;
        self.crash_fired = false;
        self.belt_latched = false;
        self.contact_ns = Some(contact);
        self.event_onset_ns = c.onset_ns;
        self.armed = true;
        // The conventional path's pretensioner has its own boundary (like the airbag); the
        // adaptive and backup paths fire it as planned. Either way only with safing.
        self.pt_gate = AirbagGate::Decided;
        if gate == AirbagGate::Fallback {
            self.pt_gate = AirbagGate::Fallback;
            self.pretensioner_at_ns = None;
            self.airbag_fire_at_ns = None;
        } else {
            self.schedule(&plan, contact, confirm_ns, c.kind != ConfirmKind::Backup);
        }
        // A belt-only plan made so by the opponent's mass — the table fires the airbag for
        // the same crash against the heaviest opponent one object fault can hide
        // (`Estimator::heaviest_opponent_fires_airbag`) — rests on the object list's mass,
        // which one object fault (a truck reported as a car, a mass misreported within its
        // bound) gets wrong. The measured event still decides the airbag: its
        // accelerometer-only must-fire adds the reference airbag, as it would without any
        // prediction. A plan belt-only for the occupant (a light one) stays belt-only.
        if !plan.airbag_fires()
            && c.kind != ConfirmKind::Backup
            && self.reference.airbag_fires()
            && (x.heaviest_fires_airbag)()
        {
            self.crash_plan = plan.with_airbag_of(&self.reference);
            self.gate = AirbagGate::Fallback;
        }
        self.phase = Phase::Crash;
    }

    /// A matched crash whose pulse left the matched ramp before its fires went out: the
    /// prediction no longer explains the event, so the fires still pending are decided by the
    /// accelerometer-only boundaries of the event, as for a crash without a prediction (a
    /// pothole at the predicted contact of an avoided collision can ramp like the crash for a
    /// few ms, then falls away).
    fn hand_over_to_the_conventional_path(&mut self) {
        if self.gate == AirbagGate::Decided && self.airbag_fire_at_ns.take().is_some() {
            self.gate = AirbagGate::Fallback;
        }
        // A pending pretensioner fire is one not yet fired (scheduled only while not fired).
        if self.pt_gate == AirbagGate::Decided && self.pretensioner_at_ns.take().is_some() {
            self.pt_gate = AirbagGate::Fallback;
        }
    }

    /// Backup for a disagreeing pair: the crash sensor and the safing sensor disagree on the
    /// confirmed event, so neither the crash sensor's decisions nor the safing agreement can
    /// be trusted — one of them is wrong, and two sensors cannot say which. Until the airbag
    /// has fired, the backup path's own evidence (a crash predicted above the no-fire line,
    /// the vehicle deceleration on CAN ≥ `backup_confirm_g` within the match window of its
    /// contact: two sources independent of both accelerometers) decides the event as it does
    /// for a faulty crash sensor: the reference restraint, the vehicle deceleration standing
    /// in for the safing agreement. A pyrotechnic pretensioner the crash phase has already
    /// fired stays fired and is not fired again; the airbag is the backup's to add (a crash
    /// sensor reading 6 g low under a standing offset lifts its own event's floors out of
    /// reach, and its crash phase would end with the belt alone). Without a predicted crash
    /// nothing fires, as with a dead crash sensor.
    fn hand_over_to_the_backup(&mut self, now: u64, evidence: BackupEvidence) {
        if self.backup_stands_in || self.airbag_fired {
            return;
        }
        self.backup_stands_in = true;
        let contact = evidence.contact_ns;
        self.contact_ns = Some(contact);
        self.crash_plan = self.reference;
        self.crash_kind = Some(ConfirmKind::Backup);
        self.gate = AirbagGate::Decided;
        self.pt_gate = AirbagGate::Decided;
        let reference = self.reference;
        let belt_fired = self.crash_fired;
        self.schedule(&reference, contact, now, false);
        if belt_fired {
            self.pretensioner_at_ns = None;
        }
    }

    /// The backup path fires the reference restraint at its times after the contact. A crash
    /// that the healthy safing sensor measures as severe sooner — the Δv of the event whose
    /// onset dated the contact reaches a restraint's accelerometer-only boundary and floor —
    /// fires that restraint then, as the crash sensor's would have in the same crash. Only a
    /// fire the backup has already scheduled moves, and only to an earlier time: the decision
    /// stays the backup evidence's (`CrashMonitor::backup_evidence`).
    #[inline(never)]
    fn bring_backup_forward(&mut self, now: u64, s: BackupSeverity) {
        if s.contact_ns.is_none() || s.contact_ns != self.contact_ns {
            return;
        }
        if s.airbag {
            if let Some(t) = self.airbag_fire_at_ns.as_mut() {
                *t = (*t).min(now);
            }
        }
        if s.pretensioner {
            if let Some(t) = self.pretensioner_at_ns.as_mut() {
                *t = (*t).min(now);
            }
        }
    }

    /// Schedules a decided plan's crash-phase fires: the pyrotechnic pretensioner and the
    /// airbag (if the plan fires it), each at its time after `contact`, never before
    /// `not_before` (the confirmation or hand-over: the past). A belt the pre-crash plan
    /// already tensioned is fired again: the crash's own decision latches it (the crash phase
    /// then ends in post-crash, never with the reversible belt released as after a near miss).
    /// With `at_decision`, the reference restraint's fires are due at `not_before`, the
    /// decision (see [`Self::conventional_fire_at`]); the backup path keeps the reference's
    /// time after the contact, because its decision can come at the contact itself (a
    /// predicted crash and the first vehicle frame that shows it), where an airbag fired for
    /// the reference's 10 ms would have vented before the occupant reaches it.
    fn schedule(&mut self, plan: &RestraintPlan, contact: u64, not_before: u64, at_decision: bool) {
        let due = |time_ms: f32, source: PlanSource| {
            if at_decision && source == PlanSource::Reference {
                not_before
            } else {
                at(contact, time_ms).max(not_before)
            }
        };
        self.pretensioner_at_ns = Some(due(plan.pretensioner_time_ms, plan.source));
        self.airbag_fire_at_ns = plan
            .airbag_fires()
            .then(|| due(plan.airbag_time_ms, plan.airbag_source));
    }

    /// When the conventional path fires the crash plan's airbag (`airbag`) or pyrotechnic
    /// pretensioner that its accelerometer-only algorithm decided at `decided_ns`: an adaptive
    /// plan at its time after `contact`, never before the decision (the table optimised that
    /// time); the reference restraint **at the decision**, as a conventional airbag ECU fires
    /// when its algorithm decides — its 10 ms (the paper's) is that decision's time in the
    /// calibration barrier test, not a wait, and a 56 km/h rigid barrier needs its airbag by
    /// "127 mm − 30 ms", ≈ 9–13 ms. The bus's FireTime keeps the reference's nominal time:
    /// it is counted from the ECU's own contact estimate, which an earlier event (a kerb strike
    /// before a wall) can date tens of ms early, while the reference is a fixed restraint.
    fn conventional_fire_at(&self, contact: u64, decided_ns: u64, airbag: bool) -> u64 {
        let plan = &self.crash_plan;
        let (time_ms, source) = if airbag {
            (plan.airbag_time_ms, plan.airbag_source)
        } else {
            (plan.pretensioner_time_ms, plan.source)
        };
        if source == PlanSource::Reference {
            decided_ns
        } else {
            at(contact, time_ms).max(decided_ns)
        }
    }

    /// The accelerometer-only decision window of the crash phase's event has passed: one ms
    /// after [`LATE_WINDOW_MS`] from the contact, or from the segment being judged when the
    /// event re-onset later (`fallback`, "Re-onset").
    fn window_over(&self, now: u64, segment_onset_ns: Option<u64>) -> bool {
        let contact = self.contact_ns.unwrap_or(now);
        let from = segment_onset_ns.map_or(contact, |s| s.max(contact));
        now > at(from, (LATE_WINDOW_MS + 1.0) as f32)
    }

    /// The conventional path: the reference airbag when the accelerometer-only algorithm says
    /// must-fire for the confirmed event (and only for it); no airbag when it says no-fire,
    /// or its window has passed.
    fn gate_airbag(
        &mut self,
        now: u64,
        fallback: FallbackDecision,
        event_dv_mps: f64,
        segment_onset_ns: Option<u64>,
    ) {
        if self.gate != AirbagGate::Fallback {
            return;
        }
        let contact = self.contact_ns.unwrap_or(now);
        let window_over = self.window_over(now, segment_onset_ns);
        let below_low_speed = self
            .low_speed_dv_limit_mps
            .is_some_and(|limit| !(event_dv_mps > limit));
        match (fallback.fire_of(self.event_onset_ns), fallback) {
            (Some(_), _) if below_low_speed && !window_over => {}
            (Some(t), _) if self.crash_plan.airbag_fires() && !below_low_speed => {
                let t = if self.low_speed_dv_limit_mps.is_some() {
                    t.max(now)
                } else {
                    t
                };
                self.airbag_fire_at_ns = Some(self.conventional_fire_at(contact, t, true));
                self.gate = AirbagGate::Decided;
            }
            (None, FallbackDecision::Pending) if !window_over => {}
            _ => {
                self.crash_plan = self.crash_plan.without_airbag();
                self.gate = AirbagGate::Decided;
            }
        }
    }

    /// The conventional path's pyrotechnic pretensioner: at the decision (an adaptive plan's at
    /// max(decision, contact + t_pt), [`Self::conventional_fire_at`])
    /// when its own boundary — or the airbag's — says must-fire for the confirmed event; none
    /// otherwise. Why the airbag's too: its floor is lower than the pretensioner's
    /// (`pretensioner_min_dv_mps`), and a crash that needs the airbag needs the belt at the
    /// same instant, never after it.
    fn gate_pretensioner(
        &mut self,
        now: u64,
        own: FallbackDecision,
        airbag: FallbackDecision,
        segment_onset_ns: Option<u64>,
    ) {
        if self.pt_gate != AirbagGate::Fallback {
            return;
        }
        let contact = self.contact_ns.unwrap_or(now);
        let window_over = self.window_over(now, segment_onset_ns);
        let onset = self.event_onset_ns;
        let pending = own == FallbackDecision::Pending || airbag == FallbackDecision::Pending;
        match own.fire_of(onset).or_else(|| airbag.fire_of(onset)) {
            Some(t) => {
                self.pretensioner_at_ns = Some(self.conventional_fire_at(contact, t, false));
                self.pt_gate = AirbagGate::Decided;
            }
            None if pending && !window_over => {}
            None => self.pt_gate = AirbagGate::Decided,
        }
    }

    /// A matched crash's fire that is due waits until its event has carried `floor_mps` since
    /// the onset while it is still loading (near misses): a pothole or kerb strike at the
    /// predicted contact of a collision that does not happen can follow the predicted ramp for
    /// the few ms before a planned fire, but carries at most the misuse envelope's net Δv (1.2
    /// m/s at 1.5 × the pothole's), which the floors exceed — only its ringing's overshoot can
    /// pass a floor for a moment, on its falling flank, where the loading rule (the smoothed
    /// deceleration at ≥ 85 % of its peak, as for the accelerometer-only decision) says no; a
    /// crash of the table's range carries the floor 4–9 ms after contact, still loading.
    /// Postponed to the next cycle while not; dropped (`true`) when the event ended without it.
    fn hold_below_floor(
        slot: &mut Option<u64>,
        floor_mps: f64,
        now: u64,
        x: &DecisionInputs<'_>,
    ) -> bool {
        let Some(t) = *slot else { return false };
        if now.saturating_add(x.half_period_ns) < t
            || (x.event_dv_mps >= x.relief.floor_mps(floor_mps, x.floor_lift_mps)
                && (x.event_loading)())
        {
            return false;
        }
        if !x.event_in_progress {
            *slot = None;
            return true;
        }
        *slot = Some(now.saturating_add(x.half_period_ns).saturating_add(1));
        false
    }

    /// A scheduled fire at `t`: whether it goes out now (`Some(true)`), is dropped
    /// (`Some(false)`: the safing function did not agree within the wait), or waits (`None`).
    /// Pre-crash (reversible pretensioner) fires need no safing.
    fn release(&mut self, t: u64, now: u64, due_slack_ns: u64, safing: bool) -> Option<bool> {
        if now.saturating_add(due_slack_ns) < t {
            return None;
        }
        if !matches!(self.phase, Phase::Crash | Phase::PostCrash) || safing {
            return Some(true);
        }
        if now > t.saturating_add(self.safing_wait_ns) {
            self.vetoed = self.vetoed.saturating_add(1);
            return Some(false);
        }
        None
    }

    /// In the crash phase with nothing fired in it (no airbag, no pyrotechnic pretensioner,
    /// no latched belt) and no backup standing in: its decisions may still move to a later
    /// event ([`crate::crash::CrashMonitor::follow_later_event`]).
    #[inline(never)]
    pub(crate) fn nothing_fired_in_crash(&self) -> bool {
        self.phase == Phase::Crash
            && !(self.airbag_fired || self.crash_fired || self.belt_latched)
            && !self.backup_stands_in
            && self.crash_kind != Some(ConfirmKind::Backup)
    }

    /// One step of the state machine at `now`, then the scheduled fires that are due.
    pub(crate) fn step(&mut self, now: u64, x: &mut DecisionInputs<'_>) {
        // The confirmation moved to a later event (nothing fired for the earlier one): the
        // crash phase is entered anew for it, from the phase before the crash.
        if x.confirmation
            .is_some_and(|c| c.onset_ns != self.event_onset_ns && self.nothing_fired_in_crash())
        {
            self.phase = self.before_crash;
        }
        if let (Some(c), Phase::Monitoring | Phase::PreCrash | Phase::Degraded) =
            (x.confirmation, self.phase)
        {
            self.enter_crash(c, x);
        }
        if self.phase == Phase::Crash
            && x.matched_course_broken
            && matches!(self.crash_kind, Some(ConfirmKind::Matched(_)))
        {
            self.hand_over_to_the_conventional_path();
        }
        if let (Phase::Crash, Some(b)) = (self.phase, x.backup_for_disagreement) {
            self.hand_over_to_the_backup(now, b);
        }
        if let (Phase::Crash, Some(ConfirmKind::Backup), Some(s)) =
            (self.phase, self.crash_kind, x.backup_severity)
        {
            self.bring_backup_forward(now, s);
        }
        if self.phase == Phase::Crash {
            self.gate_airbag(now, x.fallback, x.event_dv_mps, x.segment_onset_ns);
            self.gate_pretensioner(now, x.pretensioner_fallback, x.fallback, x.segment_onset_ns);
        }
        match self.phase {
            Phase::Monitoring => {
                if x.degraded {
                    self.phase = Phase::Degraded;
                    self.armed = true;
                    self.plan = self.reference;
                } else if let Some(s) = x.situation.filter(|s| {
                    !s.low_speed
                        && s.contact_ns.saturating_sub(now) < self.horizon_ns
                        && s.contact_ns.saturating_add(self.avoided_margin_ns) > now
                }) {
                    self.phase = Phase::PreCrash;
                    self.armed = true;
                    self.contact_ns = Some(s.contact_ns);
                    self.schedule_precrash_pretensioner();
                }
            }
            Phase::PreCrash => {
                if x.degraded {
                    // Keep a fired pretensioner until the predicted contact has passed.
                    self.phase = Phase::Degraded;
                    self.plan = self.reference;
                    return;
                }
                let avoided = match x.situation {
                    None => x.new_object || !x.object_present,
                    Some(s) => {
                        s.low_speed
                            || s.contact_ns.saturating_sub(now) > self.exit_horizon_ns
                            || now > s.contact_ns.saturating_add(self.avoided_margin_ns)
                    }
                };
                if avoided {
                    self.phase = Phase::Monitoring;
                    self.armed = false;
                    self.release_pretensioner();
                    self.plan = self.reference;
                    self.contact_ns = None;
                } else if let Some(s) = x.situation {
                    self.contact_ns = Some(s.contact_ns);
                    self.schedule_precrash_pretensioner();
                }
            }
            Phase::Degraded => {
                // A pretensioner fired during PRE-CRASH is released once the predicted
                // contact plus margin has passed without a crash.
                if self.pretensioner == Pretensioner::Fired
                    && self
                        .contact_ns
                        .is_none_or(|c| now > c.saturating_add(self.avoided_margin_ns))
                {
                    self.release_pretensioner();
                    self.contact_ns = None;
                }
                if !x.degraded {
                    self.phase = Phase::Monitoring;
                    self.armed = false;
                    if self.pretensioner == Pretensioner::Fired {
                        self.release_pretensioner();
                    }
                }
            }
            Phase::Crash | Phase::PostCrash => {}
        }
        // Scheduled fires (pre-crash pretensioner, crash fires), each in the cycle nearest its
        // time (a crash fire is never scheduled before its confirmation, which is past).
        // A crash-phase fire also needs the safing function (module `safing`).
        let in_crash = self.phase == Phase::Crash;
        // Handed to the backup: the vehicle deceleration that confirmed it stands in for the
        // safing agreement (`hand_over_to_the_backup`).
        let safing = x.safing || (in_crash && self.backup_stands_in);
        if in_crash && matches!(self.crash_kind, Some(ConfirmKind::Matched(_))) {
            let airbag =
                Self::hold_below_floor(&mut self.airbag_fire_at_ns, self.airbag_floor_mps, now, x);
            let pretensioner = Self::hold_below_floor(
                &mut self.pretensioner_at_ns,
                self.pretensioner_floor_mps,
                now,
                x,
            );
            self.held_below_floor += u64::from(airbag) + u64::from(pretensioner);
        }
        if let Some(t) = self.pretensioner_at_ns {
            if let Some(go) = self.release(t, now, x.half_period_ns, safing) {
                if go {
                    if self.pretensioner == Pretensioner::Fired {
                        self.belt_latched |= in_crash;
                    } else {
                        self.crash_fired |= in_crash;
                    }
                    self.pretensioner = Pretensioner::Fired;
                }
                self.pretensioner_at_ns = None;
            }
        }
        if let Some(t) = self.airbag_fire_at_ns {
            if let Some(go) = self.release(t, now, x.half_period_ns, safing) {
                if go {
                    self.airbag_fired = true;
                    self.crash_fired |= in_crash;
                }
                self.airbag_fire_at_ns = None;
            }
        }
        if self.phase == Phase::Crash
            && self.pretensioner_at_ns.is_none()
            && self.airbag_fire_at_ns.is_none()
            && self.gate == AirbagGate::Decided
            && self.pt_gate == AirbagGate::Decided
        {
            if self.crash_fired || self.airbag_fired || self.belt_latched {
                self.phase = Phase::PostCrash;
            } else if !x.event_in_progress {
                // The event ended and nothing fired: it was not a crash that needed a
                // restraint (or the safing channel never agreed). Its decisions end with it.
                self.phase = self.before_crash;
                self.crash_plan = self.reference;
                self.gate = AirbagGate::Decided;
                self.crash_kind = None;
                self.abandoned = true;
                if self.phase == Phase::Monitoring {
                    self.armed = false;
                }
            }
        }
    }

    /// In PRE-CRASH only a pre-crash (negative) pretensioner time fires before confirmation.
    fn schedule_precrash_pretensioner(&mut self) {
        if self.pretensioner == Pretensioner::Fired {
            return;
        }
        match self.contact_ns {
            Some(c) if self.plan.pretensioner_time_ms < 0.0 => {
                self.pretensioner_at_ns = Some(at(c, self.plan.pretensioner_time_ms));
            }
            _ => self.pretensioner_at_ns = None,
        }
    }
}
