//! The pure restraint cycle: inputs + now → commands (implements [`Activity`]).
//!
//! Per cycle: drain inputs (CAN through [`bus::E2eChecker`], object states, accelerometer
//! batches) → estimate (time to contact, closing speed at contact, conservative opponent mass,
//! occupant) → collision prediction ([`physics::simulate_collision`], only when a new object
//! sample arrived) → LUT interpolation ([`diagram::DiagramView::lookup`]) → decision state
//! machine → E2E-protected CAN commands (on change and cyclically) → diagnostics record.
//!
//! State machine (see the crate README for the full table):
//!
//! ```text
//! Monitoring ──valid object, TTC < horizon, EBS ≥ no-fire──▶ PreCrash (preset, armed,
//!     ▲   ▲                                                  pretensioner at contact + t_pt)
//!     │   └──────── avoided (lost / receding / contact + margin passed): release, disarm
//!     │
//!  Degraded (stale/invalid inputs, E2E burst, no LUT): reference restraint
//!
//! any of the three ──accelerometer confirms──▶ Crash: airbag at max(confirm, contact + t_ab)
//!                                                        ──all fired──▶ PostCrash (latched)
//! ```
//!
//! All state is allocated in [`RestraintCycle::new`]; `step` does not allocate, lock, block or
//! panic (property-tested and counted in `tests/cycle_*.rs`).

// `!(x >= y)` is deliberate: it is true for NaN, which is how NaN inputs fail safe.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

mod config;
mod estimate;
mod plan;

pub use config::{CycleConfig, MAX_E2E_BURST};
pub use estimate::{
    equivalent_barrier_speed_kph, time_to_contact, ConfirmParams, Contact, CrashDetector, G_MPS2,
};
pub use plan::{PlanSource, RestraintPlan};

use bus::codec::{
    AirbagStageCmdArm, AirbagStageCmdCmdSource, AirbagStageCmdFire, AirbagStageCmdStage,
    BeltLimiterCmdCmdSource, BeltLimiterCmdPretensionerCmd, EcuStatusEcuMode,
    OccupantClassificationBeltBuckle, OccupantClassificationOccupantClass,
};
use bus::secoc::SecOcTx;
use bus::{
    AirbagStageCmd, BeltLimiterCmd, E2eChecker, E2eProtector, EcuStatus, Messages, RawFrame,
    RejectReason,
};
use diagram::{AirbagStage, AirbagThresholds, Diagram, Query};
use ipc::{degraded, CrashAccelSample, EcuDiagnostics, EcuMode, ObjectState, PULSE_POINTS};
use physics::{
    simulate_collision, CollisionInput, CollisionSummary, CombinedSpring, DefaultPulseBuffer,
    MassClass,
};

use crate::runtime::{Activity, CanFrame, CycleInfo, CycleIo};
use config::ms_to_ns;

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

/// Degraded reasons that switch the decision to the reference restraint. `CAN_DISABLED` is
/// among them: without CAN there is no occupant information for the LUT.
pub const DEGRADING: u32 = degraded::OBJECT_STALE
    | degraded::OBJECT_INVALID
    | degraded::ACCEL_INVALID
    | degraded::CAN_STALE
    | degraded::E2E_FAILURE
    | degraded::LUT_INVALID
    | degraded::CAN_DISABLED;

/// How long an invalid accelerometer sample keeps `ACCEL_INVALID` set, ms.
const ACCEL_INVALID_HOLD_MS: f64 = 500.0;
/// Closing speed above ego speed + this is implausible (opponent > 250 km/h), m/s.
const MAX_OPPONENT_SPEED_MPS: f32 = 70.0;
/// CAN ids the ECU consumes (kernel filter of the SocketCAN port), from the generated codec.
pub fn input_can_ids() -> [u32; 2] {
    [
        raw_id(bus::EgoVehicleState::MESSAGE_ID),
        raw_id(bus::OccupantClassification::MESSAGE_ID),
    ]
}

/// Linux `can_id` of a codec id.
pub fn raw_id(id: embedded_can::Id) -> u32 {
    match id {
        embedded_can::Id::Standard(s) => s.as_raw() as u32,
        embedded_can::Id::Extended(e) => e.as_raw() | bus::CAN_EFF_FLAG,
    }
}

/// Occupant as last reported on CAN.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Occupant {
    /// Mass, kg.
    pub mass_kg: f32,
    /// Chest to wheel / airbag module, mm.
    pub chest_to_wheel_mm: f32,
    /// Belt buckled (the LUT is optimised for belted occupants; unbelted → reference).
    pub buckled: bool,
    /// An adult occupant the LUT covers (not empty, not a child seat).
    pub adult: bool,
}

/// The estimated situation from the newest object sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Situation {
    /// Predicted first contact, CLOCK_MONOTONIC ns.
    pub contact_ns: u64,
    /// Closing speed at contact, m/s.
    pub closing_speed_mps: f64,
    /// Conservative opponent mass m + k·σ, kg.
    pub opponent_mass_kg: f64,
    /// Ego equivalent barrier speed, km/h.
    pub ebs_kph: f64,
    /// Below the no-fire threshold.
    pub low_speed: bool,
}

/// Contents of a belt-limiter command (for change detection).
#[derive(Debug, Clone, Copy, PartialEq)]
struct BeltContent {
    cmd: BeltLimiterCmdPretensionerCmd,
    source: BeltLimiterCmdCmdSource,
    level_kn: f32,
    time_ms: f32,
}

/// Contents of an airbag-stage command (for change detection).
#[derive(Debug, Clone, Copy, PartialEq)]
struct AirbagContent {
    arm: AirbagStageCmdArm,
    fire: AirbagStageCmdFire,
    source: AirbagStageCmdCmdSource,
    stage: AirbagStageCmdStage,
    level_kn: f32,
    time_ms: f32,
}

/// Counters for the timing report.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct CycleCounters {
    /// Object states received.
    pub objects_rx: u64,
    /// Object states rejected as invalid (NaN, out of range, implausible).
    pub objects_invalid: u64,
    /// Cycles with stale object data.
    pub object_stale_cycles: u64,
    /// Accelerometer batches received.
    pub accel_batches_rx: u64,
    /// Accelerometer samples received.
    pub accel_samples_rx: u64,
    /// CAN frames received.
    pub can_frames_rx: u64,
    /// Collision predictions computed.
    pub predictions: u64,
    /// Predictions that failed (input outside the physics model).
    pub prediction_errors: u64,
    /// LUT lookups.
    pub lut_lookups: u64,
    /// Lookups outside the table (reference used).
    pub lut_out_of_range: u64,
    /// Lookups whose optimum still bottoms out (reported, not hidden).
    pub lut_bottoming_out: u64,
    /// Cycles spent degraded.
    pub degraded_cycles: u64,
    /// CAN frames sent.
    pub can_tx: u64,
    /// CAN send failures.
    pub can_tx_errors: u64,
    /// Commands sent together with their SecOC authenticator (both frames taken by the socket).
    pub secoc_commands_tx: u64,
    /// Command encode failures (value outside the DBC after clamping: should stay 0).
    pub encode_errors: u64,
    /// Diagnostics publish failures.
    pub diagnostics_failures: u64,
}

/// The restraint decision activity.
pub struct RestraintCycle {
    cfg: CycleConfig,
    confirm: ConfirmParams,
    horizon_ns: u64,
    exit_horizon_ns: u64,
    avoided_margin_ns: u64,
    object_timeout_ns: u64,
    vehicle_timeout_ns: u64,
    occupant_timeout_ns: u64,
    e2e_window_ns: u64,
    e2e_hold_ns: u64,
    accel_hold_ns: u64,
    cmd_cycle_ns: u64,
    status_cycle_ns: u64,

    springs: Box<[Option<CombinedSpring>; 6]>,
    pulse: Box<DefaultPulseBuffer>,
    lut: Option<Diagram>,
    lut_id: u16,
    reference: RestraintPlan,

    checker: E2eChecker,
    protector: E2eProtector,
    secoc: Option<SecOcTx>,
    secoc_unavailable: bool,
    e2e_ring: [u64; MAX_E2E_BURST],
    e2e_ring_next: usize,
    e2e_ring_len: usize,
    e2e_active_until_ns: Option<u64>,

    object: ObjectState,
    object_present: bool,
    object_invalid: bool,
    object_rx_ns: Option<u64>,
    new_object: bool,
    ego_speed_mps: f32,
    vehicle_rx_ns: Option<u64>,
    occupant: Occupant,
    occupant_rx_ns: Option<u64>,
    occupant_changed: bool,
    accel_invalid_until_ns: Option<u64>,
    last_accel_sequence: u64,

    detector: CrashDetector,
    situation: Option<Situation>,
    summary: Option<CollisionSummary>,
    pulse_class: u8,
    plan: RestraintPlan,
    crash_plan: RestraintPlan,

    phase: Phase,
    reasons: u32,
    pretensioner: Pretensioner,
    pretensioner_at_ns: Option<u64>,
    airbag_fire_at_ns: Option<u64>,
    airbag_fired: bool,
    armed: bool,
    contact_ns: Option<u64>,
    confirmed_ns: Option<u64>,

    last_belt: Option<BeltContent>,
    last_belt_tx_ns: u64,
    last_airbag: Option<AirbagContent>,
    last_airbag_tx_ns: u64,
    last_status: Option<(EcuStatusEcuMode, u8)>,
    last_status_tx_ns: u64,
    counters: CycleCounters,
}

/// What `RestraintCycle::new` found (for start-up messages).
#[derive(Debug, Clone, Default)]
pub struct StartupNotes {
    /// Human-readable warnings (LUT rejected, reference from built-in copy, …).
    pub warnings: Vec<String>,
}

impl RestraintCycle {
    /// Builds the activity: validates `cfg`, precomputes the six combined springs
    /// (ego class × opponent class), preallocates the pulse buffer, and checks that `lut`
    /// belongs to the configured ego vehicle. `lut = None` (or a mismatching table) →
    /// permanent `LUT_INVALID`: the ECU runs DEGRADED on the `reference` restraint.
    pub fn new(
        cfg: CycleConfig,
        lut: Option<Diagram>,
        reference: &physics::reference::ReferenceSettings,
    ) -> Result<(Self, StartupNotes), String> {
        cfg.validate()?;
        let mut notes = StartupNotes::default();
        let ego_class = MassClass::new(cfg.ego_class).map_err(|e| e.to_string())?;
        let mut springs: Box<[Option<CombinedSpring>; 6]> = Box::new([None; 6]);
        for (i, s) in springs.iter_mut().enumerate() {
            let opp = MassClass::new(i as u8 + 1).map_err(|e| e.to_string())?;
            *s = CombinedSpring::series(ego_class.curve(), Some(opp.curve())).ok();
        }
        let lut = match lut {
            Some(d) => {
                let ego = &d.header().ego;
                let rel = (f64::from(ego.mass_kg) - cfg.ego_mass_kg).abs() / cfg.ego_mass_kg;
                if ego.class != cfg.ego_class || rel > 0.01 {
                    notes.warnings.push(format!(
                        "LUT is for ego {} kg class {}, ECU configured for {} kg class {}: \
                         LUT rejected, DEGRADED (reference restraint)",
                        ego.mass_kg, ego.class, cfg.ego_mass_kg, cfg.ego_class
                    ));
                    None
                } else {
                    Some(d)
                }
            }
            None => None,
        };
        let thresholds = lut
            .as_ref()
            .map_or(AirbagThresholds::DEFAULT, |d| d.header().airbag_thresholds);
        let lut_id = lut.as_ref().map_or(0, Diagram::lut_id);
        let reference = RestraintPlan::from_reference_file(reference, &thresholds);
        // Cyclic send periods straight from the DBC (`GenMsgCycleTime`).
        let cmd_cycle_ms =
            BeltLimiterCmd::MESSAGE_CYCLE_TIME_MS.min(AirbagStageCmd::MESSAGE_CYCLE_TIME_MS);
        let status_cycle_ms = EcuStatus::MESSAGE_CYCLE_TIME_MS;
        let horizon_ns = ms_to_ns(cfg.preset_horizon_ms);
        let s = Self {
            confirm: ConfirmParams {
                wake_mps2: cfg.confirm_wake_g * G_MPS2,
                decel_mps2: cfg.confirm_decel_g * G_MPS2,
                samples: cfg.confirm_samples,
                delta_v_mps: cfg.confirm_delta_v_mps,
                reset_gap_ns: ms_to_ns(cfg.confirm_reset_gap_ms),
            },
            horizon_ns,
            exit_horizon_ns: horizon_ns.saturating_add(ms_to_ns(cfg.preset_exit_hysteresis_ms)),
            avoided_margin_ns: ms_to_ns(cfg.avoided_margin_ms),
            object_timeout_ns: ms_to_ns(cfg.object_timeout_ms),
            vehicle_timeout_ns: ms_to_ns(cfg.vehicle_timeout_ms),
            occupant_timeout_ns: ms_to_ns(cfg.occupant_timeout_ms),
            e2e_window_ns: ms_to_ns(cfg.e2e_burst_window_ms),
            e2e_hold_ns: ms_to_ns(cfg.e2e_hold_ms),
            accel_hold_ns: ms_to_ns(ACCEL_INVALID_HOLD_MS),
            cmd_cycle_ns: u64::from(cmd_cycle_ms) * 1_000_000,
            status_cycle_ns: u64::from(status_cycle_ms) * 1_000_000,
            springs,
            pulse: Box::new(DefaultPulseBuffer::new()),
            lut,
            lut_id,
            reference,
            checker: E2eChecker::with_max_lost(cfg.e2e_max_lost),
            protector: E2eProtector::new(),
            secoc: None,
            secoc_unavailable: false,
            e2e_ring: [0; MAX_E2E_BURST],
            e2e_ring_next: 0,
            e2e_ring_len: 0,
            e2e_active_until_ns: None,
            object: ObjectState::INVALID,
            object_present: false,
            object_invalid: false,
            object_rx_ns: None,
            new_object: false,
            ego_speed_mps: 0.0,
            vehicle_rx_ns: None,
            occupant: Occupant {
                mass_kg: f32::NAN,
                chest_to_wheel_mm: f32::NAN,
                buckled: false,
                adult: false,
            },
            occupant_rx_ns: None,
            occupant_changed: false,
            accel_invalid_until_ns: None,
            last_accel_sequence: 0,
            detector: CrashDetector::default(),
            situation: None,
            summary: None,
            pulse_class: 0,
            plan: reference,
            crash_plan: reference,
            phase: Phase::Monitoring,
            reasons: 0,
            pretensioner: Pretensioner::Idle,
            pretensioner_at_ns: None,
            airbag_fire_at_ns: None,
            airbag_fired: false,
            armed: false,
            contact_ns: None,
            confirmed_ns: None,
            last_belt: None,
            last_belt_tx_ns: 0,
            last_airbag: None,
            last_airbag_tx_ns: 0,
            last_status: None,
            last_status_tx_ns: 0,
            counters: CycleCounters::default(),
            cfg,
        };
        Ok((s, notes))
    }

    /// Sets the SecOC sender (call once before the first `step`). `Some`: every
    /// `BeltLimiterCmd` / `AirbagStageCmd` frame is followed by its authenticator frame.
    /// `None`: the key file was unusable — commands go out without authenticators (the
    /// actuators ignore them) and `EcuStatus.FaultConfig` is set, so the failure is visible on
    /// the bus instead of the ECU refusing to start. A cycle never given a sender (tests,
    /// benches) sends no authenticators and reports no fault.
    pub fn set_secoc(&mut self, tx: Option<SecOcTx>) {
        self.secoc_unavailable = tx.is_none();
        self.secoc = tx;
    }

    /// Whether authenticator frames are sent.
    pub fn secoc_enabled(&self) -> bool {
        self.secoc.is_some()
    }

    /// Current phase.
    pub fn phase(&self) -> Phase {
        self.phase
    }
    /// Current degraded-reason bits ([`ipc::degraded`]).
    pub fn degraded_reasons(&self) -> u32 {
        self.reasons
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
    /// Whether the airbag fire command has been sent.
    pub fn airbag_fired(&self) -> bool {
        self.airbag_fired
    }
    /// Newest situation estimate.
    pub fn situation(&self) -> Option<Situation> {
        self.situation
    }
    /// Newest collision prediction.
    pub fn prediction(&self) -> Option<CollisionSummary> {
        self.summary
    }
    /// Counters.
    pub fn counters(&self) -> CycleCounters {
        self.counters
    }
    /// E2E receive statistics (rejections by [`RejectReason`]).
    pub fn e2e_stats(&self) -> bus::RxStats {
        *self.checker.stats()
    }
    /// LUT id sent in the heartbeat (0 = no LUT).
    pub fn lut_id(&self) -> u16 {
        self.lut_id
    }
    /// The configuration in use.
    pub fn config(&self) -> &CycleConfig {
        &self.cfg
    }

    // ----------------------------------------------------------------------- inputs

    fn on_can(&mut self, f: &CanFrame, now: u64) {
        self.counters.can_frames_rx = self.counters.can_frames_rx.saturating_add(1);
        if f.extended {
            return; // never ours; the kernel filter drops them on a real bus
        }
        // A stream that timed out starts a new counter sequence (e.g. its sender restarted):
        // resynchronise on its first frame instead of rejecting it.
        let stale = |rx: Option<u64>, limit: u64| rx.is_none_or(|t| now.saturating_sub(t) > limit);
        let resync = match f.id {
            id if id == raw_id(bus::EgoVehicleState::MESSAGE_ID) => {
                stale(self.vehicle_rx_ns, self.vehicle_timeout_ns)
            }
            id if id == raw_id(bus::OccupantClassification::MESSAGE_ID) => {
                stale(self.occupant_rx_ns, self.occupant_timeout_ns)
            }
            _ => false,
        };
        let checked = if resync {
            self.checker.check_resync(f.id, f.payload())
        } else {
            self.checker.check(f.id, f.payload())
        };
        match checked {
            Ok(Messages::EgoVehicleState(m)) => {
                self.ego_speed_mps = m.ego_speed();
                self.vehicle_rx_ns = Some(now);
            }
            Ok(Messages::OccupantClassification(m)) => {
                let occ = Occupant {
                    mass_kg: m.occupant_mass(),
                    chest_to_wheel_mm: f32::from(m.chest_to_wheel()),
                    buckled: m.belt_buckle() == OccupantClassificationBeltBuckle::Buckled,
                    adult: matches!(
                        m.occupant_class(),
                        OccupantClassificationOccupantClass::SmallAdult
                            | OccupantClassificationOccupantClass::MidAdult
                            | OccupantClassificationOccupantClass::LargeAdult
                    ),
                };
                self.occupant_changed |= occ != self.occupant;
                self.occupant = occ;
                self.occupant_rx_ns = Some(now);
            }
            Ok(_) => {}
            Err(e) if e.reason() == RejectReason::UnknownId => {}
            Err(_) => self.note_e2e_rejection(now),
        }
    }

    fn note_e2e_rejection(&mut self, now: u64) {
        if let Some(slot) = self.e2e_ring.get_mut(self.e2e_ring_next) {
            *slot = now;
        }
        self.e2e_ring_next = (self.e2e_ring_next + 1) % MAX_E2E_BURST;
        self.e2e_ring_len = (self.e2e_ring_len + 1).min(MAX_E2E_BURST);
        let n = (self.cfg.e2e_burst_count as usize).clamp(1, MAX_E2E_BURST);
        if self.e2e_ring_len >= n {
            // The n-th newest rejection: index next − n (mod ring).
            let idx = (self.e2e_ring_next + MAX_E2E_BURST - n) % MAX_E2E_BURST;
            let oldest = self.e2e_ring.get(idx).copied().unwrap_or(0);
            if now.saturating_sub(oldest) <= self.e2e_window_ns {
                self.e2e_active_until_ns = Some(now.saturating_add(self.e2e_hold_ns));
            }
        }
        if let Some(until) = self.e2e_active_until_ns {
            // A rejection while the burst is held extends the hold.
            if now <= until {
                self.e2e_active_until_ns = Some(now.saturating_add(self.e2e_hold_ns));
            }
        }
    }

    fn object_plausible(&self, o: &ObjectState, now: u64) -> bool {
        let f = [
            o.distance_m,
            o.closing_speed_mps,
            o.relative_accel_mps2,
            o.opponent_mass_kg,
            o.opponent_mass_sigma_kg,
            o.confidence,
        ];
        if !f.iter().all(|v| v.is_finite()) {
            return false;
        }
        let ranges_ok = (-5.0..=300.0).contains(&o.distance_m)
            && (-100.0..=100.0).contains(&o.closing_speed_mps)
            && (-300.0..=300.0).contains(&o.relative_accel_mps2)
            && (100.0..=60_000.0).contains(&o.opponent_mass_kg)
            && (0.0..=10_000.0).contains(&o.opponent_mass_sigma_kg)
            && (0.0..=1.0).contains(&o.confidence);
        // The measurement must be recent on our clock (same CLOCK_MONOTONIC on the bench).
        let age_ok = now.abs_diff(o.timestamp_ns) <= self.object_timeout_ns;
        let vehicle_fresh = self
            .vehicle_rx_ns
            .is_some_and(|t| now.saturating_sub(t) <= self.vehicle_timeout_ns);
        let speed_ok =
            !vehicle_fresh || o.closing_speed_mps <= self.ego_speed_mps + MAX_OPPONENT_SPEED_MPS;
        ranges_ok && age_ok && speed_ok
    }

    fn on_object(&mut self, o: &ObjectState, now: u64) {
        self.counters.objects_rx = self.counters.objects_rx.saturating_add(1);
        if !o.is_valid() {
            // A "no track" record is information too, and can be as old as any other: a
            // stuck sensor repeating its last "nothing ahead" must go stale like any sample.
            if now.abs_diff(o.timestamp_ns) > self.object_timeout_ns {
                self.counters.objects_invalid = self.counters.objects_invalid.saturating_add(1);
                self.object_invalid = true;
                return;
            }
            // A fresh "no track" sample: the sensor is alive, nothing ahead.
            self.object_present = false;
            self.object_invalid = false;
            self.object_rx_ns = Some(now);
            self.object = *o;
            self.new_object = true;
            return;
        }
        if self.object_plausible(o, now) {
            self.object = *o;
            self.object_present = f64::from(o.confidence) >= self.cfg.min_confidence;
            self.object_invalid = false;
            self.object_rx_ns = Some(now);
            self.new_object = true;
        } else {
            self.counters.objects_invalid = self.counters.objects_invalid.saturating_add(1);
            self.object_invalid = true;
        }
    }

    fn on_accel(&mut self, a: &CrashAccelSample, now: u64) {
        self.counters.accel_batches_rx = self.counters.accel_batches_rx.saturating_add(1);
        let s = a.samples();
        self.counters.accel_samples_rx = self
            .counters
            .accel_samples_rx
            .saturating_add(s.len() as u64);
        self.last_accel_sequence = a.sequence;
        if self
            .detector
            .feed(&self.confirm, a.first_timestamp_ns, a.sample_period_ns, s)
        {
            self.accel_invalid_until_ns = Some(now.saturating_add(self.accel_hold_ns));
        }
    }

    fn compute_reasons(&self, now: u64, can_on: bool) -> u32 {
        let stale = |rx: Option<u64>, limit: u64| rx.is_none_or(|t| now.saturating_sub(t) > limit);
        let mut r = 0;
        if stale(self.object_rx_ns, self.object_timeout_ns) {
            r |= degraded::OBJECT_STALE;
        }
        if self.object_invalid {
            r |= degraded::OBJECT_INVALID;
        }
        if self.accel_invalid_until_ns.is_some_and(|t| now <= t) {
            r |= degraded::ACCEL_INVALID;
        }
        if can_on {
            if stale(self.vehicle_rx_ns, self.vehicle_timeout_ns)
                || stale(self.occupant_rx_ns, self.occupant_timeout_ns)
            {
                r |= degraded::CAN_STALE;
            }
        } else {
            r |= degraded::CAN_DISABLED;
        }
        if self.e2e_active_until_ns.is_some_and(|t| now <= t) {
            r |= degraded::E2E_FAILURE;
        }
        if self.lut.is_none() {
            r |= degraded::LUT_INVALID;
        }
        r
    }

    // ----------------------------------------------------------------------- estimate

    /// Situation from the newest object sample; runs the prediction and the LUT lookup.
    /// Called only when a new sample (or a changed occupant) arrived.
    fn estimate(&mut self, now: u64) {
        self.situation = None;
        if !self.object_present || self.object_invalid {
            return;
        }
        let o = self.object;
        let Some(c) = time_to_contact(
            f64::from(o.distance_m),
            f64::from(o.closing_speed_mps),
            f64::from(o.relative_accel_mps2),
        ) else {
            return;
        };
        let meas_ns = o.timestamp_ns.min(now);
        let contact_ns = meas_ns.saturating_add((c.ttc_s * 1.0e9) as u64);
        let m = f64::from(o.opponent_mass_kg);
        let sigma = f64::from(o.opponent_mass_sigma_kg);
        let opp_kg = m + self.cfg.conservative_mass_k * sigma;
        let ebs_kph =
            equivalent_barrier_speed_kph(c.closing_speed_mps, self.cfg.ego_mass_kg, opp_kg);
        let sit = Situation {
            contact_ns,
            closing_speed_mps: c.closing_speed_mps,
            opponent_mass_kg: opp_kg,
            ebs_kph,
            low_speed: !(ebs_kph >= self.cfg.no_fire_ebs_kph),
        };
        self.situation = Some(sit);
        // Predict only what can become relevant before the next sample: contact within the
        // exit horizon (bounds the work to objects that matter).
        if contact_ns.saturating_sub(now) > self.exit_horizon_ns || sit.low_speed {
            return;
        }
        self.predict(&sit);
        self.plan = self.lookup(&sit);
    }

    fn predict(&mut self, sit: &Situation) {
        self.counters.predictions = self.counters.predictions.saturating_add(1);
        let class = physics::class_for_mass_kg(sit.opponent_mass_kg)
            .map(MassClass::number)
            .unwrap_or(6);
        let spring = self
            .springs
            .get(usize::from(class.saturating_sub(1)))
            .and_then(Option::as_ref);
        let Some(spring) = spring else {
            self.summary = None;
            self.counters.prediction_errors = self.counters.prediction_errors.saturating_add(1);
            return;
        };
        let input = CollisionInput {
            step_s: self.cfg.prediction_step_ms * 1e-3,
            ..CollisionInput::with_defaults(
                spring,
                self.cfg.ego_mass_kg,
                sit.opponent_mass_kg,
                sit.closing_speed_mps,
            )
        };
        match simulate_collision(&input, &mut self.pulse) {
            Ok(s) => {
                self.summary = Some(s);
                self.pulse_class = class;
            }
            Err(_) => {
                self.summary = None;
                self.counters.prediction_errors = self.counters.prediction_errors.saturating_add(1);
            }
        }
    }

    /// LUT plan for the situation; the reference plan when the LUT is missing, the occupant
    /// is outside what the table covers (unbelted, not an adult, no data), or any query
    /// axis is out of the table's range or NaN (the diagram's rule: a flagged lookup is
    /// degraded input).
    fn lookup(&mut self, sit: &Situation) -> RestraintPlan {
        let Some(lut) = self.lut.as_ref() else {
            return self.reference;
        };
        let occ = self.occupant;
        if !(occ.buckled && occ.adult) {
            return self.reference;
        }
        let q = Query {
            closing_speed_kph: (sit.closing_speed_mps * 3.6) as f32,
            opponent_mass_kg: sit.opponent_mass_kg as f32,
            occupant_mass_kg: occ.mass_kg,
            seat_distance_mm: occ.chest_to_wheel_mm,
        };
        let l = lut.view().lookup(&q);
        self.counters.lut_lookups = self.counters.lut_lookups.saturating_add(1);
        if l.bottoming_out {
            self.counters.lut_bottoming_out = self.counters.lut_bottoming_out.saturating_add(1);
        }
        if l.out_of_range.any() {
            self.counters.lut_out_of_range = self.counters.lut_out_of_range.saturating_add(1);
            return self.reference;
        }
        RestraintPlan::from_lookup(&l)
    }

    // ----------------------------------------------------------------------- decision

    fn time_ms_to_ns(t_ms: f32) -> i64 {
        (f64::from(t_ms) * 1.0e6) as i64
    }

    fn at(base_ns: u64, offset_ms: f32) -> u64 {
        base_ns.saturating_add_signed(Self::time_ms_to_ns(offset_ms))
    }

    fn release_pretensioner(&mut self) {
        if self.pretensioner == Pretensioner::Fired {
            self.pretensioner = Pretensioner::Released;
        }
        self.pretensioner_at_ns = None;
    }

    fn enter_crash(&mut self, confirm_ns: u64, degraded_now: bool) {
        // Measured contact (accelerometer wake-up) is a better contact estimate than the
        // pre-crash TTC; fall back to the prediction, then to the confirmation instant.
        let contact = self
            .detector
            .onset_ns()
            .or(self.contact_ns)
            .unwrap_or(confirm_ns);
        let fresh_low_speed = self.situation.is_some_and(|s| {
            s.low_speed && s.contact_ns.abs_diff(contact) <= self.avoided_margin_ns
        });
        let plan = if self.phase == Phase::PreCrash && !degraded_now {
            self.plan
        } else if fresh_low_speed && !degraded_now {
            // Low-speed no-fire: belt per reference, no airbag.
            self.reference.without_airbag()
        } else {
            self.reference
        };
        self.crash_plan = plan;
        self.contact_ns = Some(contact);
        self.confirmed_ns = Some(confirm_ns);
        self.armed = true;
        if self.pretensioner != Pretensioner::Fired {
            self.pretensioner_at_ns =
                Some(Self::at(contact, plan.pretensioner_time_ms).max(confirm_ns));
        }
        self.airbag_fire_at_ns = plan
            .airbag_fires()
            .then(|| Self::at(contact, plan.airbag_time_ms).max(confirm_ns));
        self.phase = Phase::Crash;
    }

    fn decide(&mut self, now: u64) {
        let degraded_now = self.reasons & DEGRADING != 0;
        if let (Some(confirm), Phase::Monitoring | Phase::PreCrash | Phase::Degraded) =
            (self.detector.confirmed_at_ns(), self.phase)
        {
            self.enter_crash(confirm, degraded_now);
        }
        match self.phase {
            Phase::Monitoring => {
                if degraded_now {
                    self.phase = Phase::Degraded;
                    self.armed = true;
                    self.plan = self.reference;
                } else if let Some(s) = self.situation.filter(|s| {
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
                if degraded_now {
                    // Keep a fired pretensioner until the predicted contact has passed.
                    self.phase = Phase::Degraded;
                    self.plan = self.reference;
                    return;
                }
                let avoided = match self.situation {
                    None => self.new_object || !self.object_present,
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
                } else if let Some(s) = self.situation {
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
                if !degraded_now {
                    self.phase = Phase::Monitoring;
                    self.armed = false;
                    if self.pretensioner == Pretensioner::Fired {
                        self.release_pretensioner();
                    }
                }
            }
            Phase::Crash | Phase::PostCrash => {}
        }
        // Scheduled fires (pre-crash pretensioner, crash fires).
        if let Some(t) = self.pretensioner_at_ns {
            if now >= t {
                self.pretensioner = Pretensioner::Fired;
                self.pretensioner_at_ns = None;
            }
        }
        if let Some(t) = self.airbag_fire_at_ns {
            if now >= t {
                self.airbag_fired = true;
                self.airbag_fire_at_ns = None;
            }
        }
        if self.phase == Phase::Crash
            && self.pretensioner_at_ns.is_none()
            && self.airbag_fire_at_ns.is_none()
        {
            self.phase = Phase::PostCrash;
        }
    }

    /// In PRE-CRASH only a pre-crash (negative) pretensioner time fires before confirmation.
    fn schedule_precrash_pretensioner(&mut self) {
        if self.pretensioner == Pretensioner::Fired {
            return;
        }
        match self.contact_ns {
            Some(c) if self.plan.pretensioner_time_ms < 0.0 => {
                self.pretensioner_at_ns = Some(Self::at(c, self.plan.pretensioner_time_ms));
            }
            _ => self.pretensioner_at_ns = None,
        }
    }

    // ----------------------------------------------------------------------- outputs

    fn active_plan(&self) -> RestraintPlan {
        match self.phase {
            Phase::Crash | Phase::PostCrash => self.crash_plan,
            Phase::PreCrash => self.plan,
            Phase::Monitoring | Phase::Degraded => self.reference,
        }
    }

    fn belt_content(&self) -> BeltContent {
        let p = self.active_plan();
        BeltContent {
            cmd: match self.pretensioner {
                Pretensioner::Idle => BeltLimiterCmdPretensionerCmd::Idle,
                Pretensioner::Fired => BeltLimiterCmdPretensionerCmd::Fire,
                Pretensioner::Released => BeltLimiterCmdPretensionerCmd::Release,
            },
            source: match p.source {
                PlanSource::Adaptive => BeltLimiterCmdCmdSource::Adaptive,
                PlanSource::Reference => BeltLimiterCmdCmdSource::Reference,
            },
            level_kn: clamp_finite(p.belt_limiter_kn, 0.0, 12.0),
            time_ms: clamp_finite(p.pretensioner_time_ms, -200.0, 200.0),
        }
    }

    fn airbag_content(&self) -> AirbagContent {
        let p = self.active_plan();
        AirbagContent {
            arm: if self.armed {
                AirbagStageCmdArm::Armed
            } else {
                AirbagStageCmdArm::Disarmed
            },
            fire: if self.airbag_fired {
                AirbagStageCmdFire::Fire
            } else {
                AirbagStageCmdFire::NoFire
            },
            source: match p.source {
                PlanSource::Adaptive => AirbagStageCmdCmdSource::Adaptive,
                PlanSource::Reference => AirbagStageCmdCmdSource::Reference,
            },
            stage: match p.airbag_stage {
                AirbagStage::NoFire => AirbagStageCmdStage::NoStage,
                AirbagStage::Stage1 => AirbagStageCmdStage::Stage1,
                AirbagStage::Stage2 => AirbagStageCmdStage::BothStages,
            },
            level_kn: clamp_finite(p.airbag_level_kn, 0.0, 12.0),
            time_ms: clamp_finite(p.airbag_time_ms, -200.0, 200.0),
        }
    }

    /// Sends one frame; true if the socket took it.
    fn send(&mut self, io: &mut dyn CycleIo, raw: RawFrame) -> bool {
        let frame = CanFrame {
            id: raw.id,
            extended: false,
            len: raw.len,
            data: raw.data,
        };
        match io.send_can(&frame) {
            Ok(()) => {
                self.counters.can_tx = self.counters.can_tx.saturating_add(1);
                true
            }
            Err(_) => {
                self.counters.can_tx_errors = self.counters.can_tx_errors.saturating_add(1);
                false
            }
        }
    }

    /// Sends a command frame and, with SecOC on, its authenticator right after it (the
    /// receiver pairs them within one command cycle). `authenticate` is allocation-free.
    /// Complete pairs are counted: an actuator that acts on fewer authenticated commands
    /// than this lost some (the fault campaign's "commands lost").
    /// The authenticator's freshness is the cycle's synchronized time `sync_time_us`
    /// ([`CycleInfo::sync_time_us`]), made strictly increasing by the sender.
    fn send_authenticated(&mut self, io: &mut dyn CycleIo, raw: RawFrame, sync_time_us: u64) {
        let cmd_sent = self.send(io, raw);
        if let Some(tx) = self.secoc.as_mut() {
            match tx.authenticate(&raw, sync_time_us) {
                Ok(auth) => {
                    if self.send(io, auth) && cmd_sent {
                        self.counters.secoc_commands_tx =
                            self.counters.secoc_commands_tx.saturating_add(1);
                    }
                }
                Err(_) => {
                    self.counters.encode_errors = self.counters.encode_errors.saturating_add(1)
                }
            }
        }
    }

    fn due<T: PartialEq>(
        last: Option<T>,
        now_content: T,
        last_tx: u64,
        now: u64,
        cycle: u64,
    ) -> bool {
        last.is_none_or(|l| l != now_content) || now.saturating_sub(last_tx) >= cycle
    }

    fn write_outputs(&mut self, info: &CycleInfo, io: &mut dyn CycleIo) {
        let now = info.now_ns;
        if !io.can_enabled() {
            return;
        }
        let belt = self.belt_content();
        if Self::due(
            self.last_belt,
            belt,
            self.last_belt_tx_ns,
            now,
            self.cmd_cycle_ns,
        ) {
            match BeltLimiterCmd::encode(belt.cmd, belt.source, belt.level_kn, belt.time_ms) {
                Ok(m) => {
                    let raw = self.protector.seal(m);
                    self.send_authenticated(io, raw, info.sync_time_us);
                    self.last_belt = Some(belt);
                    self.last_belt_tx_ns = now;
                }
                Err(_) => {
                    self.counters.encode_errors = self.counters.encode_errors.saturating_add(1)
                }
            }
        }
        let bag = self.airbag_content();
        if Self::due(
            self.last_airbag,
            bag,
            self.last_airbag_tx_ns,
            now,
            self.cmd_cycle_ns,
        ) {
            match AirbagStageCmd::encode(
                bag.arm,
                bag.fire,
                bag.source,
                bag.stage,
                bag.level_kn,
                bag.time_ms,
            ) {
                Ok(m) => {
                    let raw = self.protector.seal(m);
                    self.send_authenticated(io, raw, info.sync_time_us);
                    self.last_airbag = Some(bag);
                    self.last_airbag_tx_ns = now;
                }
                Err(_) => {
                    self.counters.encode_errors = self.counters.encode_errors.saturating_add(1)
                }
            }
        }
        let mode = match self.phase {
            Phase::Monitoring | Phase::PreCrash => EcuStatusEcuMode::Normal,
            Phase::Degraded => EcuStatusEcuMode::ReferenceFallback,
            Phase::Crash if !self.airbag_fired => EcuStatusEcuMode::CrashDetected,
            Phase::Crash | Phase::PostCrash => EcuStatusEcuMode::Deployed,
        };
        let r = self.reasons;
        let vehicle_stale = self
            .vehicle_rx_ns
            .is_none_or(|t| now.saturating_sub(t) > self.vehicle_timeout_ns);
        let occupant_stale = self
            .occupant_rx_ns
            .is_none_or(|t| now.saturating_sub(t) > self.occupant_timeout_ns);
        let faults = u8::from(vehicle_stale)
            | u8::from(occupant_stale) << 1
            | u8::from(r & (degraded::OBJECT_STALE | degraded::OBJECT_INVALID) != 0) << 2
            | u8::from(r & (degraded::ACCEL_INVALID | degraded::ACCEL_STALE) != 0) << 3
            | u8::from(r & degraded::E2E_FAILURE != 0) << 4
            | u8::from(r & degraded::LUT_INVALID != 0) << 5
            | u8::from(info.overruns > 0) << 6;
        let overruns = u16::try_from(info.overruns).unwrap_or(u16::MAX);
        // On change of mode or fault bits (not of the overrun count: a noisy host would
        // turn the heartbeat into bus load), else cyclically.
        let status = (mode, faults);
        if Self::due(
            self.last_status,
            status,
            self.last_status_tx_ns,
            now,
            self.status_cycle_ns,
        ) {
            let bit = |n: u8| faults & (1 << n) != 0;
            match EcuStatus::encode(
                mode,
                bit(0),
                bit(1),
                bit(2),
                bit(3),
                bit(4),
                bit(5),
                bit(6),
                self.secoc_unavailable,
                overruns,
                self.lut_id,
            ) {
                Ok(m) => {
                    let raw = self.protector.seal(m);
                    self.send(io, raw);
                    self.last_status = Some(status);
                    self.last_status_tx_ns = now;
                }
                Err(_) => {
                    self.counters.encode_errors = self.counters.encode_errors.saturating_add(1)
                }
            }
        }
    }

    fn publish(&mut self, info: &CycleInfo, io: &mut dyn CycleIo) {
        let plan = self.active_plan();
        let reasons = self.reasons;
        let mode = self.phase.mode() as u8;
        let ttc_s = self.situation.map_or(f32::NAN, |s| {
            ((s.contact_ns as f64 - info.now_ns as f64) * 1.0e-9) as f32
        });
        let summary = self.summary;
        let pulse = self.pulse.ego_accel_mps2();
        let step_s = self.pulse.step_s();
        let stride = pulse.len().div_ceil(PULSE_POINTS).max(1);
        let c = &self.counters;
        let (objects_rx, accel_rx) = (c.objects_rx, c.accel_batches_rx);
        let last_obj = self.object.sequence;
        let last_acc = self.last_accel_sequence;
        let pret = u8::from(self.pretensioner == Pretensioner::Fired);
        let bag = u8::from(self.airbag_fired);
        let r = io.publish_diagnostics(&mut |d: &mut EcuDiagnostics| {
            d.timestamp_ns = info.now_ns;
            d.cycle_count = info.cycle.saturating_add(1);
            d.overrun_count = info.overruns;
            d.last_exec_ns = info.last_exec_ns;
            d.wake_latency_ns = info.wake_latency_ns;
            d.last_object_sequence = last_obj;
            d.last_accel_sequence = last_acc;
            d.object_samples_rx = objects_rx;
            d.accel_batches_rx = accel_rx;
            if let Some(s) = summary {
                d.predicted_delta_v_mps = s.vehicle.delta_v_mps as f32;
                d.predicted_a_max_mps2 = s.vehicle.a_max_mps2 as f32;
                d.predicted_a_mean_mps2 = s.vehicle.a_mean_mps2 as f32;
                d.predicted_contact_time_s = s.contact_duration_s as f32;
                let mut n = 0u32;
                for (dst, src) in d
                    .pulse_accel_mps2
                    .iter_mut()
                    .zip(pulse.iter().step_by(stride))
                {
                    *dst = *src as f32;
                    n += 1;
                }
                d.pulse_points = n;
                d.pulse_dt_s = (step_s * stride as f64) as f32;
            }
            d.time_to_contact_s = ttc_s;
            d.belt_force_limit_n = plan.belt_limiter_kn * 1000.0;
            d.pretensioner_time_s = plan.pretensioner_time_ms * 1.0e-3;
            d.airbag_time_s = plan.airbag_time_ms * 1.0e-3;
            d.airbag_stage = match plan.airbag_stage {
                AirbagStage::NoFire => 0,
                AirbagStage::Stage1 => 1,
                AirbagStage::Stage2 => 2,
            };
            d.mode = mode;
            d.pretensioner_fired = pret;
            d.airbag_fired = bag;
            d.degraded_reasons = reasons;
        });
        if r.is_err() {
            self.counters.diagnostics_failures =
                self.counters.diagnostics_failures.saturating_add(1);
        }
    }
}

fn clamp_finite(v: f32, lo: f32, hi: f32) -> f32 {
    if v.is_finite() {
        v.clamp(lo, hi)
    } else {
        lo
    }
}

/// Report-counter names of the E2E rejections, in [`RejectReason::ALL`] order.
const E2E_COUNTER_NAMES: [&str; RejectReason::COUNT] = [
    "can_rejected_unknown_id",
    "can_rejected_wrong_dlc",
    "can_rejected_crc_mismatch",
    "can_rejected_counter_repeated",
    "can_rejected_counter_skipped",
    "can_rejected_out_of_range",
];

impl Activity for RestraintCycle {
    fn name(&self) -> &'static str {
        "restraint-cycle"
    }

    fn startup(&mut self, _now_ns: u64, _io: &mut dyn CycleIo) -> anyhow::Result<()> {
        Ok(())
    }

    fn step(&mut self, info: &CycleInfo, io: &mut dyn CycleIo) {
        let now = info.now_ns;
        self.new_object = false;
        self.occupant_changed = false;
        io.drain_can(&mut |f| self.on_can(f, now));
        io.drain_objects(&mut |o| self.on_object(o, now));
        io.drain_accel(&mut |a| self.on_accel(a, now));
        self.reasons = self.compute_reasons(now, io.can_enabled());
        if self.reasons & degraded::OBJECT_STALE != 0 {
            self.counters.object_stale_cycles = self.counters.object_stale_cycles.saturating_add(1);
        }
        if self.reasons & DEGRADING != 0 {
            self.counters.degraded_cycles = self.counters.degraded_cycles.saturating_add(1);
        }
        // Recompute the prediction only when its inputs changed materially.
        if self.new_object || (self.occupant_changed && self.situation.is_some()) {
            self.estimate(now);
        }
        if self.reasons & degraded::OBJECT_STALE != 0 {
            self.situation = None; // a stale track predicts nothing
        }
        self.decide(now);
        self.write_outputs(info, io);
        self.publish(info, io);
    }

    fn shutdown(&mut self, _now_ns: u64, _io: &mut dyn CycleIo) {}

    fn report_counters(&self, out: &mut Vec<(&'static str, u64)>) {
        let c = &self.counters;
        out.extend([
            ("objects_rx", c.objects_rx),
            ("objects_invalid", c.objects_invalid),
            ("object_stale_cycles", c.object_stale_cycles),
            ("accel_batches_rx", c.accel_batches_rx),
            ("accel_samples_rx", c.accel_samples_rx),
            ("accel_invalid_samples", self.detector.invalid_samples),
            ("accel_invalid_batches", self.detector.invalid_batches),
            ("can_frames_rx", c.can_frames_rx),
            ("can_accepted", self.checker.stats().accepted),
            ("can_lost_frames", self.checker.stats().lost_frames),
            ("predictions", c.predictions),
            ("prediction_errors", c.prediction_errors),
            ("lut_lookups", c.lut_lookups),
            ("lut_out_of_range", c.lut_out_of_range),
            ("lut_bottoming_out", c.lut_bottoming_out),
            ("degraded_cycles", c.degraded_cycles),
            ("can_tx", c.can_tx),
            ("can_tx_errors", c.can_tx_errors),
            ("secoc_commands_tx", c.secoc_commands_tx),
            ("encode_errors", c.encode_errors),
            ("diagnostics_publish_failures", c.diagnostics_failures),
        ]);
        for (name, reason) in E2E_COUNTER_NAMES.iter().zip(RejectReason::ALL) {
            out.push((name, self.checker.stats().rejected_for(reason)));
        }
    }
}
