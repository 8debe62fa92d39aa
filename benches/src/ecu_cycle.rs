//! The real ECU cycle (`restraint::RestraintCycle::step`) on its measured paths, shared by
//! the `cycle` criterion bench and the `icount-cycle` callgrind binary so both time the same
//! code on the same inputs:
//!
//! * [`WorstCasePreCrash`] — the hand-picked worst case: steady PRE-CRASH with a
//!   NEW object sample every cycle: track filter + LUT interpolation + state machine +
//!   command encode and E2E seal + diagnostics record (the closed-form
//!   collision prediction runs in the next cycle without a sample, so a sample every cycle
//!   never pays it; the searched worst case, `worst_case`, covers every path).
//! * [`DecisionOnly`] — PRE-CRASH with no new input: state machine, scheduled fires, cyclic
//!   command/heartbeat encode, diagnostics (the common cycle). Inputs are refreshed in untimed
//!   extra cycles.
//! * [`crash_confirmation_setup`] — the state one cycle before the accelerometer batch that
//!   confirms the crash.
//!
//! Everything run per cycle is allocation-free (the com layer is the core's fixed-capacity
//! [`SimIo`], the same test double the cycle tests use); set-up may allocate.

use crate::workload::bench_table;
use anyhow::Context;
use bus::codec::{
    EgoVehicleStateBrakeState, OccupantClassificationBeltBuckle,
    OccupantClassificationOccupantClass,
};
use bus::RawFrame;
use restraint::{
    CrashAccelSample, CycleConfig, ObjectState, Phase, ReferenceSettings, RestraintCycle, SimIo,
    SimLoop, VALID,
};

/// One cycle period, ns.
pub const MS: u64 = 1_000_000;

/// Reference restraint (used only when the LUT cannot serve; never on the measured paths).
const REFERENCE: ReferenceSettings = ReferenceSettings {
    belt_limiter_kn: 8.5,
    airbag_level_kn: 12.0,
    pretensioner_time_ms: 10.0,
    airbag_time_ms: 10.0,
};

/// Cycles between CAN input refreshes (the 10 ms ego frame would arrive every 10th cycle;
/// refreshing every 8th keeps the inputs from going stale without making every cycle decode).
const CAN_EVERY: u64 = 8;

/// Object 6.25 m ahead closing at 25 m/s in even and 25.5 m/s in odd cycles (~250 ms to
/// contact): steady PRE-CRASH, inside the prediction horizon, so every new sample runs the
/// track filter + LUT; the alternating speed moves the filtered estimate and with it the
/// LUT plan, so the airbag and belt commands are re-encoded and sealed in most cycles (they
/// are sent on change, else only every command period).
pub fn object(now_ns: u64) -> ObjectState {
    let odd = (now_ns / MS) % 2 == 1;
    ObjectState {
        timestamp_ns: now_ns,
        sequence: now_ns / MS,
        distance_m: 6.25,
        closing_speed_mps: if odd { 25.5 } else { 25.0 },
        relative_accel_mps2: -2.0,
        opponent_mass_kg: 1500.0,
        opponent_mass_sigma_kg: 150.0,
        confidence: 0.9,
        object_id: 1,
        valid: VALID,
        _reserved: [0; 3],
    }
}

/// 8 samples of −200 m/s² (Δv 0.2 m/s per batch) from `now_ns` on.
pub fn accel(now_ns: u64) -> CrashAccelSample {
    CrashAccelSample {
        first_timestamp_ns: now_ns,
        sequence: now_ns / MS,
        sample_period_ns: 125_000,
        count: 8,
        accel_mps2: [-200.0; 8],
    }
}

/// A live crash accelerometer's quiet batch: 8 samples at 8 kHz ending at `now_ns`, ±0.05 m/s²
/// (the core flags a bit-constant sensor as stuck and a silent one as stale: every measured
/// cycle drains one batch, as on the bench).
pub fn quiet_accel(now_ns: u64) -> CrashAccelSample {
    let first = now_ns.saturating_sub(7 * 125_000);
    CrashAccelSample {
        first_timestamp_ns: first,
        sequence: now_ns / MS,
        sample_period_ns: 125_000,
        count: 8,
        accel_mps2: core::array::from_fn(|i| if i % 2 == 0 { 0.05 } else { -0.05 }),
    }
}

/// When the benches' simulated loops start (1 s: the sensors' time stamps are past zero).
pub const START_NS: u64 = 1_000 * MS;

/// E2E-sealed input frames: (`EgoVehicleState`, `OccupantClassification`) of a buckled
/// mid-adult at 15 m/s ego speed.
///
/// # Errors
/// A value outside its DBC range (a bench bug).
pub fn can_inputs(tx: &mut bus::E2eProtector) -> anyhow::Result<[RawFrame; 2]> {
    let ego = bus::EgoVehicleState::encode(EgoVehicleStateBrakeState::Released, 15.0, 0.0)
        .map_err(|e| anyhow::anyhow!("ego frame: {e:?}"))?;
    let occ = bus::OccupantClassification::encode(
        OccupantClassificationBeltBuckle::Buckled,
        OccupantClassificationOccupantClass::MidAdult,
        90,
        80.0,
        310,
        150,
    )
    .map_err(|e| anyhow::anyhow!("occupant frame: {e:?}"))?;
    Ok([tx.seal(ego), tx.seal(occ)])
}

/// The bench table, leaked to `'static` (set-up only: the cycle borrows its table as the
/// shell's does, and a bench process builds a handful).
fn bench_lut() -> restraint::Lut<'static> {
    let d: &'static diagram::Diagram = Box::leak(Box::new(bench_table()));
    restraint::Lut {
        view: d.view(),
        id: d.lut_id(),
        ego_mass_kg: d.header().ego.mass_kg,
        ego_class: d.header().ego.class,
        // An unreadable span: NaN, which the core rejects.
        lighter_opponent_kg: d
            .header()
            .lighter_opponent_span_kg()
            .map_or(Some(f32::NAN), |s| s.map(|kg| kg as f32)),
    }
}

/// A cycle (default config, bench table) driven 50 cycles into steady PRE-CRASH.
///
/// # Errors
/// Cycle construction failed or it is not in PRE-CRASH afterwards.
pub fn precrash(
    clock: &mut SimLoop,
    io: &mut SimIo,
    tx: &mut bus::E2eProtector,
) -> anyhow::Result<RestraintCycle<'static>> {
    let (mut ecu, _) = RestraintCycle::new(CycleConfig::default(), Some(bench_lut()), &REFERENCE)
        .map_err(|e| anyhow::anyhow!("RestraintCycle::new: {e}"))?;
    for k in 0..50u64 {
        let [e, o] = can_inputs(tx)?;
        io.push_can(if k.is_multiple_of(2) { e } else { o });
        io.push_object(object(clock.now_ns()));
        io.push_both_accel(quiet_accel(clock.now_ns()));
        clock.step(&mut ecu, io);
    }
    anyhow::ensure!(
        ecu.phase() == Phase::PreCrash,
        "set-up did not reach PRE-CRASH: {:?}",
        ecu.phase()
    );
    Ok(ecu)
}

/// Pre-sealed CAN inputs replayed with valid alive counters (4 bits: 16 frames per message),
/// so the measured cycles do no encoding of their own inputs.
struct CanReplay {
    frames: [[RawFrame; 2]; 16],
    next: usize,
}

impl CanReplay {
    /// 16 consecutive seals of both messages, continuing `tx`'s alive counters.
    fn new(tx: &mut bus::E2eProtector) -> anyhow::Result<Self> {
        let mut frames = [can_inputs(tx)?; 16];
        for f in frames.iter_mut().skip(1) {
            *f = can_inputs(tx)?;
        }
        Ok(Self { frames, next: 0 })
    }

    /// Alternates ego and occupant frames, each with its next alive counter.
    fn next(&mut self) -> Option<RawFrame> {
        let [e, o] = self.frames.get(self.next / 2)?;
        let ego = self.next.is_multiple_of(2);
        self.next = (self.next + 1) % 32;
        Some(if ego { *e } else { *o })
    }
}

/// The worst-case pre-crash cycle: a new object sample every cycle (see the module docs).
pub struct WorstCasePreCrash {
    ecu: RestraintCycle<'static>,
    io: SimIo,
    can: CanReplay,
    clock: SimLoop,
    k: u64,
    predictions_before: u64,
    lookups_before: u64,
    sent_before: u64,
    rejected_before: u64,
}

/// Input frames rejected so far (all reasons).
fn rejected(ecu: &RestraintCycle<'_>) -> u64 {
    ecu.e2e_stats().rejected.iter().sum()
}

impl WorstCasePreCrash {
    /// Builds the cycle in steady PRE-CRASH.
    ///
    /// # Errors
    /// See [`precrash`].
    pub fn new() -> anyhow::Result<Self> {
        let mut clock = SimLoop::new(START_NS, MS);
        let mut io = SimIo::new();
        let mut tx = bus::E2eProtector::new();
        let ecu = precrash(&mut clock, &mut io, &mut tx)?;
        let can = CanReplay::new(&mut tx)?;
        let c = ecu.counters();
        Ok(Self {
            predictions_before: c.predictions,
            lookups_before: c.lut_lookups,
            rejected_before: rejected(&ecu),
            sent_before: io.can_tx_total,
            ecu,
            io,
            can,
            clock,
            k: 0,
        })
    }

    /// One measured cycle: new object sample (+ a CAN input every 8th cycle), then `step`.
    pub fn step(&mut self) {
        self.k += 1;
        self.io.push_object(object(self.clock.now_ns()));
        self.io.push_both_accel(quiet_accel(self.clock.now_ns()));
        if self.k.is_multiple_of(CAN_EVERY) {
            if let Some(f) = self.can.next() {
                self.io.push_can(f);
            }
        }
        self.clock.step(&mut self.ecu, &mut self.io);
    }

    /// Checks that every measured cycle stayed in PRE-CRASH and ran the track filter and the
    /// LUT lookup, that most re-sent the airbag and belt commands, and that no CAN input was
    /// rejected.
    ///
    /// # Errors
    /// The measurement did not measure the hand-picked path.
    pub fn verify(&self) -> anyhow::Result<()> {
        anyhow::ensure!(self.ecu.phase() == Phase::PreCrash, "left PRE-CRASH");
        let c = self.ecu.counters();
        anyhow::ensure!(
            c.predictions == self.predictions_before,
            "a prediction ran in a sample cycle"
        );
        let looked_up = c.lut_lookups - self.lookups_before;
        anyhow::ensure!(
            looked_up >= self.k,
            "{looked_up} LUT lookups in {} cycles",
            self.k
        );
        let sent = self.io.can_tx_total - self.sent_before;
        anyhow::ensure!(
            sent >= self.k * 3 / 2,
            "{sent} command frames in {} cycles (airbag + belt expected in most cycles)",
            self.k
        );
        let rej = rejected(&self.ecu) - self.rejected_before;
        anyhow::ensure!(rej == 0, "{rej} CAN input frames rejected");
        Ok(())
    }

    /// Commands sent so far (keeps the output observable).
    pub fn frames_sent(&self) -> u64 {
        self.io.can_tx_total
    }
}

/// The common pre-crash cycle without new inputs (see the module docs).
pub struct DecisionOnly {
    ecu: RestraintCycle<'static>,
    io: SimIo,
    can: CanReplay,
    clock: SimLoop,
    k: u64,
}

impl DecisionOnly {
    /// Builds the cycle in steady PRE-CRASH.
    ///
    /// # Errors
    /// See [`precrash`].
    pub fn new() -> anyhow::Result<Self> {
        let mut clock = SimLoop::new(START_NS, MS);
        let mut io = SimIo::new();
        let mut tx = bus::E2eProtector::new();
        let ecu = precrash(&mut clock, &mut io, &mut tx)?;
        let can = CanReplay::new(&mut tx)?;
        Ok(Self {
            ecu,
            io,
            can,
            clock,
            k: 0,
        })
    }

    /// Every 8th call, an extra cycle with a new object sample and CAN input (to be run
    /// outside the timing).
    pub fn refresh_if_due(&mut self) {
        self.k += 1;
        if self.k.is_multiple_of(CAN_EVERY) {
            self.io.push_object(object(self.clock.now_ns()));
            self.io.push_both_accel(quiet_accel(self.clock.now_ns()));
            if let Some(f) = self.can.next() {
                self.io.push_can(f);
            }
            self.clock.step(&mut self.ecu, &mut self.io);
        }
    }

    /// One measured cycle without new object or CAN inputs (the accelerometer's batch, as
    /// every cycle).
    pub fn step(&mut self) {
        self.io.push_both_accel(quiet_accel(self.clock.now_ns()));
        self.clock.step(&mut self.ecu, &mut self.io);
    }

    /// The measured cycles stayed in PRE-CRASH.
    ///
    /// # Errors
    /// It left PRE-CRASH.
    pub fn verify(&self) -> anyhow::Result<()> {
        anyhow::ensure!(self.ecu.phase() == Phase::PreCrash, "left PRE-CRASH");
        Ok(())
    }
}

/// A PRE-CRASH cycle after two sub-threshold accelerometer batches, with the third (which
/// confirms: 3 × 0.2 m/s ≥ 0.5 m/s) queued: the next `clock.step(&mut ecu, &mut io)` is the
/// crash confirmation cycle. Returns `(cycle, io, clock)`.
///
/// # Errors
/// See [`precrash`].
pub fn crash_confirmation_setup() -> anyhow::Result<(RestraintCycle<'static>, SimIo, SimLoop)> {
    let mut clock = SimLoop::new(START_NS, MS);
    let mut io = SimIo::new();
    let mut tx = bus::E2eProtector::new();
    let mut ecu = precrash(&mut clock, &mut io, &mut tx).context("crash confirmation")?;
    for _ in 0..2 {
        io.push_both_accel(accel(clock.now_ns()));
        clock.step(&mut ecu, &mut io);
    }
    io.push_both_accel(accel(clock.now_ns()));
    Ok((ecu, io, clock))
}

/// The crash phase of a predicted crash, cycle by cycle (`icount-crash`): a cycle driven into
/// PRE-CRASH by an approach that predicts contact at `contact_ns` (25 m/s, 1500 ± 150 kg →
/// conservative 1650 kg, class 3), then from the contact on the accelerometer delivers the
/// predicted pulse itself (the closed-form collision of that situation) in 8-sample 8 kHz
/// batches: the first cycles wake the detectors and freeze the prediction (one closed-form
/// solve), fit the onset ramp, confirm (prediction-matched), re-plan from the table and fire.
pub struct CrashPhase {
    ecu: RestraintCycle<'static>,
    io: SimIo,
    can: CanReplay,
    crash: physics::ExactCollision,
    contact_ns: u64,
    clock: SimLoop,
}

impl CrashPhase {
    /// Closing speed of the approach, m/s.
    const CLOSING_MPS: f32 = 25.0;

    /// Builds the cycle 5 ms before the contact.
    ///
    /// # Errors
    /// Cycle construction failed, or it is not in PRE-CRASH 5 ms before the contact.
    pub fn new() -> anyhow::Result<Self> {
        let mut clock = SimLoop::new(START_NS, MS);
        let contact_ns = START_NS + 400 * MS;
        let mut io = SimIo::new();
        let mut tx = bus::E2eProtector::new();
        let (mut ecu, _) =
            RestraintCycle::new(CycleConfig::default(), Some(bench_lut()), &REFERENCE)
                .map_err(|e| anyhow::anyhow!("RestraintCycle::new: {e}"))?;
        let mut can = CanReplay::new(&mut tx)?;
        while clock.now_ns() < contact_ns - 5 * MS {
            let now_ns = clock.now_ns();
            if (now_ns / MS).is_multiple_of(10) {
                let mut o = object(now_ns);
                o.closing_speed_mps = Self::CLOSING_MPS;
                o.relative_accel_mps2 = 0.0;
                o.distance_m = Self::CLOSING_MPS * (contact_ns - now_ns) as f32 * 1e-9;
                io.push_object(o);
            }
            if (now_ns / MS).is_multiple_of(CAN_EVERY) {
                if let Some(f) = can.next() {
                    io.push_can(f);
                }
            }
            io.push_both_accel(quiet_accel(now_ns));
            clock.step(&mut ecu, &mut io);
        }
        anyhow::ensure!(
            ecu.phase() == Phase::PreCrash,
            "set-up did not reach PRE-CRASH: {:?}",
            ecu.phase()
        );
        let ego = physics::MassClass::new(4).map_err(|e| anyhow::anyhow!("{e:?}"))?;
        let opp = physics::class_for_mass_kg(1650.0).map_err(|e| anyhow::anyhow!("{e:?}"))?;
        let spring = physics::CombinedSpring::series(ego.curve(), Some(opp.curve()))
            .map_err(|e| anyhow::anyhow!("{e:?}"))?;
        let crash = physics::ExactCollision::solve(&physics::CollisionInput::with_defaults(
            &spring,
            1785.0,
            1650.0,
            f64::from(Self::CLOSING_MPS),
        ))
        .map_err(|e| anyhow::anyhow!("{e:?}"))?;
        Ok(Self {
            ecu,
            io,
            can,
            crash,
            contact_ns,
            clock,
        })
    }

    /// One cycle with the accelerometer batch of the last ms (the pulse from the contact on).
    pub fn step(&mut self) {
        let mut a = quiet_accel(self.clock.now_ns());
        for (i, s) in a.accel_mps2.iter_mut().enumerate() {
            let t = a.first_timestamp_ns + i as u64 * 125_000;
            if t >= self.contact_ns {
                let tau_s = (t - self.contact_ns) as f64 * 1e-9;
                *s += self.crash.state_at(tau_s).ego_accel_mps2 as f32;
            }
        }
        self.io.push_both_accel(a);
        if (self.clock.now_ns() / MS).is_multiple_of(CAN_EVERY) {
            if let Some(f) = self.can.next() {
                self.io.push_can(f);
            }
        }
        self.clock.step(&mut self.ecu, &mut self.io);
    }

    /// The cycle (its phase, how the crash was confirmed, whether the airbag fired).
    pub fn ecu(&self) -> &RestraintCycle<'static> {
        &self.ecu
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn worst_case_predicts_every_cycle_and_stays_in_precrash() {
        let mut w = WorstCasePreCrash::new().unwrap();
        for _ in 0..40 {
            w.step();
        }
        w.verify().unwrap();
        // Airbag + belt every cycle (verify checks it), plus the cyclic status frame.
        assert!(w.frames_sent() >= 2 * 40, "{}", w.frames_sent());
        // 40 cycles replay 5 CAN frames; more than 16 cycles of replay wrap the counters.
        for _ in 0..300 {
            w.step();
        }
        w.verify().unwrap();
    }

    #[test]
    fn the_crash_phase_workload_is_confirmed_by_the_prediction_and_fires() {
        let mut c = CrashPhase::new().unwrap();
        for _ in 0..20 {
            c.step();
        }
        assert!(
            matches!(
                c.ecu().crash_kind(),
                Some(restraint::crash::ConfirmKind::Matched(_))
            ),
            "{:?}",
            c.ecu().crash_kind()
        );
        assert!(c.ecu().airbag_fired());
    }

    #[test]
    fn crash_confirmation_setup_confirms_on_the_next_cycle() {
        let (mut ecu, mut io, mut clock) = crash_confirmation_setup().unwrap();
        assert_eq!(ecu.phase(), Phase::PreCrash);
        clock.step(&mut ecu, &mut io);
        assert!(matches!(ecu.phase(), Phase::Crash | Phase::PostCrash));
    }
}
