//! Outputs: the E2E-protected (and SecOC-authenticated) CAN commands, the `EcuStatus`
//! heartbeat and the diagnostics record.
//!
//! Commands and status go out on change and cyclically at the DBC's `GenMsgCycleTime`. The
//! cyclic repetitions follow the clock: each one is due one period after the previous one was
//! *due*, anchored to the cycle's deadline, so wake-up jitter and skipped slots do not stretch
//! the period (a repetition that comes late is followed by one on the original grid; after a
//! gap longer than a period the grid restarts at the current cycle, so no burst follows).

use bus::codec::{
    AirbagStageCmdArm, AirbagStageCmdCmdSource, AirbagStageCmdFire, AirbagStageCmdStage,
    BeltLimiterCmdCmdSource, BeltLimiterCmdPretensionerCmd, EcuStatusEcuMode,
};
use bus::secoc::SecOcTx;
use bus::{AirbagStageCmd, BeltLimiterCmd, E2eProtector, EcuStatus, RawFrame};
use diagram::AirbagStage;

use crate::contract::{CycleInfo, CycleIo};
use crate::counters::CycleCounters;
use crate::decision::{Decision, Pretensioner};
use crate::estimate::{pulse::PULSE_DT_S, Estimator};
use crate::inputs::InputMonitor;
use crate::plan::PlanSource;
use crate::signals::{Degraded, EcuDiagnostics, EcuMode};

/// The mode `EcuStatus` puts on the bus for a diagnostics mode — the one mapping between the
/// two vocabularies. The bus has no pre-crash (a preset is `Normal`, its settings are on
/// `BeltLimiterCmd`), calls the degraded phase `ReferenceFallback` (what the actuators then
/// receive) and splits the crash phase at the airbag's fire.
pub fn bus_mode(mode: EcuMode, airbag_fired: bool) -> EcuStatusEcuMode {
    use EcuStatusEcuMode as Bus;
    match mode {
        EcuMode::Startup => Bus::Init,
        EcuMode::Monitoring | EcuMode::PreCrash => Bus::Normal,
        EcuMode::Degraded => Bus::ReferenceFallback,
        EcuMode::Crash if !airbag_fired => Bus::CrashDetected,
        EcuMode::Crash | EcuMode::PostCrash => Bus::Deployed,
    }
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

/// The fault flags of `EcuStatus`, one field per DBC signal (the generated encoder places
/// them; no bit position is typed here).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct StatusFaults {
    /// `FaultVehicleInput`.
    pub vehicle_input: bool,
    /// `FaultOccupantInput`.
    pub occupant_input: bool,
    /// `FaultObjectInput`.
    pub object_input: bool,
    /// `FaultAccelSensor`.
    pub accel_sensor: bool,
    /// `FaultE2e`.
    pub e2e: bool,
    /// `FaultLut`.
    pub lut: bool,
    /// `FaultOverrun`.
    pub overrun: bool,
    /// `FaultConfig` (the SecOC keys were unusable).
    pub config: bool,
    /// `FaultSafingSensor`.
    pub safing_sensor: bool,
    /// `FaultSatelliteLeft`.
    pub satellite_left: bool,
    /// `FaultSatelliteRight`.
    pub satellite_right: bool,
}

/// One cyclic frame's schedule: last content sent and when the next repetition is due.
#[derive(Debug, Clone, Copy)]
struct Cyclic<T> {
    last: Option<T>,
    next_due_ns: u64,
    period_ns: u64,
}

impl<T: PartialEq + Copy> Cyclic<T> {
    fn new(period_ms: u32) -> Self {
        Self {
            last: None,
            next_due_ns: 0,
            period_ns: u64::from(period_ms) * 1_000_000,
        }
    }

    /// The frame is due: its content changed, or its repetition time has come.
    fn due(&self, content: T, now: u64) -> bool {
        self.last.is_none_or(|l| l != content) || now >= self.next_due_ns
    }

    /// Records a send of `content` in the cycle of `info`.
    fn sent(&mut self, content: T, info: &CycleInfo) {
        let now = info.now_ns;
        // The cycle's grid time: its deadline, unless the shell handed none that fits.
        let anchor = if info.deadline_ns <= now && now - info.deadline_ns < self.period_ns {
            info.deadline_ns
        } else {
            now
        };
        let on_grid = self.next_due_ns.saturating_add(self.period_ns);
        self.next_due_ns = if self.last == Some(content) && on_grid > now {
            on_grid // a repetition: the next one one period after this one was due
        } else {
            anchor.saturating_add(self.period_ns) // a change, the first, or after a gap
        };
        self.last = Some(content);
    }
}

/// State of the outputs.
#[derive(Clone)]
pub struct Outputs {
    protector: E2eProtector,
    secoc: Option<SecOcTx>,
    secoc_unavailable: bool,
    lut_id: u16,
    belt: Cyclic<BeltContent>,
    airbag: Cyclic<AirbagContent>,
    status: Cyclic<(EcuStatusEcuMode, StatusFaults)>,
}

fn clamp_finite(v: f32, lo: f32, hi: f32) -> f32 {
    if v.is_finite() {
        v.clamp(lo, hi)
    } else {
        lo
    }
}

fn count(c: &mut u64) {
    *c = c.saturating_add(1);
}

impl Outputs {
    /// Outputs with the DBC's cycle times, no SecOC sender yet.
    pub fn new(lut_id: u16) -> Self {
        Self {
            protector: E2eProtector::new(),
            secoc: None,
            secoc_unavailable: false,
            lut_id,
            belt: Cyclic::new(BeltLimiterCmd::MESSAGE_CYCLE_TIME_MS),
            airbag: Cyclic::new(AirbagStageCmd::MESSAGE_CYCLE_TIME_MS),
            status: Cyclic::new(EcuStatus::MESSAGE_CYCLE_TIME_MS),
        }
    }

    /// See [`crate::RestraintCycle::set_secoc`].
    pub(crate) fn set_secoc(&mut self, tx: Option<SecOcTx>) {
        self.secoc_unavailable = tx.is_none();
        self.secoc = tx;
    }

    /// Whether authenticator frames are sent.
    pub fn secoc_enabled(&self) -> bool {
        self.secoc.is_some()
    }

    /// LUT id sent in the heartbeat (0 = no LUT).
    pub fn lut_id(&self) -> u16 {
        self.lut_id
    }

    fn belt_content(d: &Decision) -> BeltContent {
        let p = d.active_plan();
        BeltContent {
            cmd: match d.pretensioner() {
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

    fn airbag_content(d: &Decision) -> AirbagContent {
        let p = d.active_plan();
        AirbagContent {
            arm: if d.armed() {
                AirbagStageCmdArm::Armed
            } else {
                AirbagStageCmdArm::Disarmed
            },
            fire: if d.airbag_fired() {
                AirbagStageCmdFire::Fire
            } else {
                AirbagStageCmdFire::NoFire
            },
            source: match p.airbag_source {
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

    /// Sends one frame; true if the I/O took it.
    fn send(io: &mut dyn CycleIo, raw: &RawFrame, counters: &mut CycleCounters) -> bool {
        match io.send_can(raw) {
            Ok(()) => {
                count(&mut counters.can_tx);
                true
            }
            Err(_) => {
                count(&mut counters.can_tx_errors);
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
    fn send_authenticated(
        &mut self,
        io: &mut dyn CycleIo,
        raw: &RawFrame,
        sync_time_us: u64,
        counters: &mut CycleCounters,
    ) {
        let cmd_sent = Self::send(io, raw, counters);
        if let Some(tx) = self.secoc.as_mut() {
            match tx.authenticate(raw, sync_time_us) {
                Ok(auth) => {
                    if Self::send(io, &auth, counters) && cmd_sent {
                        count(&mut counters.secoc_commands_tx);
                    }
                }
                Err(_) => count(&mut counters.encode_errors),
            }
        }
    }

    /// Commands and status of this cycle (nothing while CAN is off).
    pub(crate) fn write(
        &mut self,
        info: &CycleInfo,
        io: &mut dyn CycleIo,
        d: &Decision,
        inputs: &InputMonitor,
        reasons: Degraded,
        counters: &mut CycleCounters,
    ) {
        let now = info.now_ns;
        if !io.can_enabled() {
            return;
        }
        let belt = Self::belt_content(d);
        if self.belt.due(belt, now) {
            match BeltLimiterCmd::encode(belt.cmd, belt.source, belt.level_kn, belt.time_ms) {
                Ok(m) => {
                    let raw = self.protector.seal(m);
                    self.send_authenticated(io, &raw, info.sync_time_us, counters);
                    self.belt.sent(belt, info);
                }
                Err(_) => count(&mut counters.encode_errors),
            }
        }
        let bag = Self::airbag_content(d);
        if self.airbag.due(bag, now) {
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
                    self.send_authenticated(io, &raw, info.sync_time_us, counters);
                    self.airbag.sent(bag, info);
                }
                Err(_) => count(&mut counters.encode_errors),
            }
        }
        let mode = bus_mode(d.phase().mode(), d.airbag_fired());
        let faults = StatusFaults {
            vehicle_input: inputs.vehicle_stale(now),
            occupant_input: inputs.occupant_stale(now),
            object_input: reasons.intersects(Degraded::OBJECT_STALE | Degraded::OBJECT_INVALID)
                || inputs.object_port_error(now),
            accel_sensor: reasons.intersects(Degraded::ACCEL_INVALID | Degraded::ACCEL_STALE)
                || inputs.accel_port_error(now),
            e2e: reasons.contains(Degraded::E2E_FAILURE),
            lut: reasons.contains(Degraded::LUT_INVALID),
            overrun: info.overruns > 0,
            config: self.secoc_unavailable,
            safing_sensor: reasons.intersects(Degraded::SAFING_STALE | Degraded::SAFING_INVALID),
            satellite_left: reasons.contains(Degraded::SATELLITE_LEFT),
            satellite_right: reasons.contains(Degraded::SATELLITE_RIGHT),
        };
        let overruns = u16::try_from(info.overruns).unwrap_or(u16::MAX);
        // On change of mode or fault flags (not of the overrun count: a noisy host would
        // turn the heartbeat into bus load), else cyclically.
        let status = (mode, faults);
        if self.status.due(status, now) {
            let f = faults;
            match EcuStatus::encode(
                mode,
                f.vehicle_input,
                f.occupant_input,
                f.object_input,
                f.accel_sensor,
                f.e2e,
                f.lut,
                f.overrun,
                f.config,
                f.safing_sensor,
                f.satellite_left,
                f.satellite_right,
                overruns,
                self.lut_id,
            ) {
                Ok(m) => {
                    let raw = self.protector.seal(m);
                    Self::send(io, &raw, counters);
                    self.status.sent(status, info);
                }
                Err(_) => count(&mut counters.encode_errors),
            }
        }
    }
}

/// Writes this cycle's diagnostics record.
pub(crate) fn publish_diagnostics(
    info: &CycleInfo,
    io: &mut dyn CycleIo,
    d: &Decision,
    est: &Estimator<'_>,
    inputs: &InputMonitor,
    reasons: Degraded,
    counters: &mut CycleCounters,
) {
    let plan = d.active_plan();
    let mode = d.phase().mode() as u8;
    let sit = est.situation;
    let ttc_s = sit.map_or(f32::NAN, |s| {
        ((s.contact_estimate_ns as f64 - info.now_ns as f64) * 1.0e-9) as f32
    });
    let summary = est.summary;
    let (pulse, pulse_points) = est.pulse();
    let (objects_rx, accel_rx) = (counters.objects_rx, counters.accel_batches_rx);
    let last_obj = inputs.object.sequence;
    let last_acc = inputs.last_accel_sequence;
    let pret = u8::from(d.pretensioner() == Pretensioner::Fired);
    let bag = u8::from(d.airbag_fired());
    let r = io.publish_diagnostics(&mut |rec: &mut EcuDiagnostics| {
        rec.timestamp_ns = info.now_ns;
        rec.cycle_count = info.cycle.saturating_add(1);
        rec.overrun_count = info.overruns;
        rec.last_exec_ns = info.last_exec_ns;
        rec.wake_latency_ns = info.wake_latency_ns;
        rec.last_object_sequence = last_obj;
        rec.last_accel_sequence = last_acc;
        rec.object_samples_rx = objects_rx;
        rec.accel_batches_rx = accel_rx;
        // Every field is written (the I/O need not clear the record first).
        match summary {
            Some(s) => {
                rec.predicted_delta_v_mps = s.vehicle.delta_v_mps as f32;
                rec.predicted_a_max_mps2 = s.vehicle.a_max_mps2 as f32;
                rec.predicted_a_mean_mps2 = s.vehicle.a_mean_mps2 as f32;
                rec.predicted_contact_time_s = s.contact_duration_s as f32;
                // Filled a chunk per cycle after the prediction (estimate::pulse).
                rec.pulse_accel_mps2 = *pulse;
                rec.pulse_points = pulse_points as u32;
                rec.pulse_dt_s = PULSE_DT_S as f32;
            }
            None => {
                let z = &EcuDiagnostics::ZERO;
                rec.predicted_delta_v_mps = z.predicted_delta_v_mps;
                rec.predicted_a_max_mps2 = z.predicted_a_max_mps2;
                rec.predicted_a_mean_mps2 = z.predicted_a_mean_mps2;
                rec.predicted_contact_time_s = z.predicted_contact_time_s;
                rec.pulse_accel_mps2 = z.pulse_accel_mps2;
                rec.pulse_points = z.pulse_points;
                rec.pulse_dt_s = z.pulse_dt_s;
            }
        }
        rec.time_to_contact_s = ttc_s;
        let nan = f32::NAN;
        rec.time_to_contact_sigma_s = sit.map_or(nan, |s| s.contact_sigma_s as f32);
        rec.closing_speed_mps = sit.map_or(nan, |s| s.closing_speed_mps as f32);
        rec.closing_speed_sigma_mps = sit.map_or(nan, |s| s.closing_speed_sigma_mps as f32);
        rec.opponent_mass_kg = sit.map_or(nan, |s| s.opponent_mass_estimate_kg as f32);
        rec.opponent_mass_sigma_kg = sit.map_or(nan, |s| s.opponent_mass_sigma_kg as f32);
        rec.belt_force_limit_n = plan.belt_limiter_kn * 1000.0;
        rec.pretensioner_time_s = plan.pretensioner_time_ms * 1.0e-3;
        rec.airbag_time_s = plan.airbag_time_ms * 1.0e-3;
        rec.airbag_stage = match plan.airbag_stage {
            AirbagStage::NoFire => 0,
            AirbagStage::Stage1 => 1,
            AirbagStage::Stage2 => 2,
        };
        rec.mode = mode;
        rec.pretensioner_fired = pret;
        rec.airbag_fired = bag;
        rec.degraded_reasons = reasons.bits();
    });
    if r.is_err() {
        count(&mut counters.diagnostics_failures);
    }
}
