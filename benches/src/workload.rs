//! The measured work, shared by criterion benches and the callgrind binaries.
//!
//! Also the collision-prediction inputs ([`PredictionWorkload`]).
//!
//! Everything that runs per iteration here is allocation-free and panic-free (the same rules as
//! the ECU cycle), so that what is timed is the stage and not the harness. Set-up (tables,
//! pre-sealed frames, pulse buffers) happens once, outside the timed part.

use bus::codec::{
    AirbagStageCmdArm, AirbagStageCmdCmdSource, AirbagStageCmdFire, AirbagStageCmdStage,
    BeltLimiterCmdCmdSource, BeltLimiterCmdPretensionerCmd, CanError, EcuStatusEcuMode,
    EgoVehicleStateBrakeState, OccupantClassificationBeltBuckle,
    OccupantClassificationOccupantClass,
};
use bus::{
    AirbagStageCmd, BeltLimiterCmd, E2eChecker, E2eProtector, EcuStatus, EgoVehicleState, Messages,
    OccupantClassification, RawFrame,
};
use diagram::{AirbagThresholds, Axes, BuildInfo, Cell, Diagram, EgoVehicle, Header, Query};
use physics::{CollisionInput, CombinedSpring};

/// Alive counters are 4 bits: 16 pre-sealed frames per message replay as a valid stream forever.
const COUNTER_PERIOD: usize = 16;

/// Physical values the ECU takes from one cycle's CAN input (what a decode must deliver).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct DecodedInputs {
    /// Ego speed, m/s.
    pub ego_speed_mps: f32,
    /// Ego longitudinal acceleration, m/s².
    pub ego_long_accel_mps2: f32,
    /// Occupant mass, kg.
    pub occupant_mass_kg: f32,
    /// Chest-to-wheel distance, mm.
    pub chest_to_wheel_mm: u16,
    /// Seat track position, mm.
    pub seat_track_mm: u16,
    /// Belt buckled.
    pub buckled: bool,
    /// Frames rejected by the E2E check this cycle (0 in the bench: the stream is valid).
    pub rejected: u8,
}

/// The worst-case CAN input of one 1 ms cycle: the 10 ms `EgoVehicleState` and the 100 ms
/// `OccupantClassification` both arrive in the same cycle, and each goes through the full
/// receive check (id, DLC, CRC-8 over data id + payload, alive counter, DBC ranges) and the
/// raw → physical conversion of every signal the ECU uses.
#[derive(Debug, Clone)]
pub struct CycleInputFrames {
    ego: [RawFrame; COUNTER_PERIOD],
    occupant: [RawFrame; COUNTER_PERIOD],
    next: usize,
    checker: E2eChecker,
}

impl CycleInputFrames {
    /// Pre-seals 16 frames of each input message (alive counters 0..=15) with realistic values.
    ///
    /// # Errors
    /// A value outside its DBC range (would be a bug in this bench).
    pub fn new() -> Result<Self, CanError> {
        let mut protector = E2eProtector::new();
        let mut ego = [RawFrame::new(0, &[]); COUNTER_PERIOD];
        let mut occupant = ego;
        for (i, (e, o)) in ego.iter_mut().zip(occupant.iter_mut()).enumerate() {
            let k = i as f32;
            *e = protector.seal(EgoVehicleState::new(
                0,
                0,
                EgoVehicleStateBrakeState::AutonomousEmergencyBraking,
                27.5 - 0.01 * k,
                -9.5 + 0.01 * k,
            )?);
            *o = protector.seal(OccupantClassification::new(
                0,
                0,
                OccupantClassificationBeltBuckle::Buckled,
                OccupantClassificationOccupantClass::MidAdult,
                95,
                78.5 + 0.1 * k,
                310,
                180,
            )?);
        }
        Ok(Self {
            ego,
            occupant,
            next: 0,
            checker: E2eChecker::new(),
        })
    }

    /// Receive-checks and decodes the next cycle's two frames.
    pub fn decode_next(&mut self) -> DecodedInputs {
        let i = self.next % COUNTER_PERIOD;
        self.next = (i + 1) % COUNTER_PERIOD;
        let mut out = DecodedInputs::default();
        let frames = [self.ego.get(i), self.occupant.get(i)];
        for frame in frames.into_iter().flatten() {
            match self.checker.check_frame(frame) {
                Ok(Messages::EgoVehicleState(m)) => {
                    out.ego_speed_mps = m.ego_speed();
                    out.ego_long_accel_mps2 = m.ego_long_accel();
                }
                Ok(Messages::OccupantClassification(m)) => {
                    out.occupant_mass_kg = m.occupant_mass();
                    out.chest_to_wheel_mm = m.chest_to_wheel();
                    out.seat_track_mm = m.seat_track_position();
                    out.buckled =
                        matches!(m.belt_buckle(), OccupantClassificationBeltBuckle::Buckled);
                }
                Ok(_) | Err(_) => out.rejected = out.rejected.saturating_add(1),
            }
        }
        out
    }
}

/// The command content of one cycle (physical units, as the decision logic produces them).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Commands {
    /// Airbag force level, kN (DBC 0..=12).
    pub airbag_force_kn: f32,
    /// Airbag fire time relative to contact, ms.
    pub airbag_fire_time_ms: f32,
    /// Belt load-limiter level, kN.
    pub load_limiter_kn: f32,
    /// Pretensioner fire time relative to contact, ms (negative: before contact).
    pub pretensioner_fire_time_ms: f32,
    /// ECU overrun count for the status frame.
    pub overruns: u16,
}

impl Commands {
    /// A deploying cycle (every frame carries non-trivial values).
    pub const FIRE: Commands = Commands {
        airbag_force_kn: 8.45,
        airbag_fire_time_ms: 12.3,
        load_limiter_kn: 5.6,
        pretensioner_fire_time_ms: -35.0,
        overruns: 3,
    };
}

/// Encodes and E2E-seals the three cyclic output frames of a cycle: `AirbagStageCmd`,
/// `BeltLimiterCmd`, `EcuStatus` (the SecOC authenticator frames are not in the bus crate yet).
#[derive(Debug, Clone, Default)]
pub struct CommandEncoder {
    protector: E2eProtector,
}

impl CommandEncoder {
    /// Fresh alive counters.
    pub fn new() -> Self {
        Self::default()
    }

    /// Encodes one cycle's commands into `out` (airbag, belt, status).
    ///
    /// # Errors
    /// A value outside its DBC range or not finite.
    pub fn encode(&mut self, c: &Commands, out: &mut [RawFrame; 3]) -> Result<(), CanError> {
        // The generated setters range-check with `<`, which NaN passes (and `as` then encodes
        // it as 0): reject non-finite values here, before any frame is touched.
        if !(c.airbag_force_kn.is_finite() && c.airbag_fire_time_ms.is_finite()) {
            return Err(CanError::ParameterOutOfRange {
                message_id: AirbagStageCmd::MESSAGE_ID,
            });
        }
        if !(c.load_limiter_kn.is_finite() && c.pretensioner_fire_time_ms.is_finite()) {
            return Err(CanError::ParameterOutOfRange {
                message_id: BeltLimiterCmd::MESSAGE_ID,
            });
        }
        let [airbag, belt, status] = out;
        *airbag = self.protector.seal(AirbagStageCmd::new(
            0,
            0,
            AirbagStageCmdArm::Armed,
            AirbagStageCmdFire::Fire,
            AirbagStageCmdCmdSource::Adaptive,
            AirbagStageCmdStage::Stage2,
            c.airbag_force_kn,
            c.airbag_fire_time_ms,
        )?);
        *belt = self.protector.seal(BeltLimiterCmd::new(
            0,
            0,
            BeltLimiterCmdPretensionerCmd::Fire,
            BeltLimiterCmdCmdSource::Adaptive,
            c.load_limiter_kn,
            c.pretensioner_fire_time_ms,
        )?);
        *status = self.protector.seal(EcuStatus::new(
            0,
            0,
            EcuStatusEcuMode::Deployed,
            false,
            false,
            false,
            false,
            false,
            false,
            c.overruns > 0,
            false,
            false,
            false,
            false,
            c.overruns,
            7,
        )?);
        Ok(())
    }
}

/// The characteristic diagram the LUT benches use: the size a default table is expected to have
/// (9 closing speeds × 12 opponent masses × 7 occupant masses × 6 seat distances = 4536 cells,
/// ~160 KB, larger than L1), non-uniform closing-speed axis so the axis search is real.
///
/// # Panics
/// Never for these constant axes (validated by `Diagram::from_fn`; a failure is a bench bug).
#[allow(clippy::missing_panics_doc)]
pub fn bench_table() -> Diagram {
    let header = Header {
        ego: EgoVehicle {
            mass_kg: 1785.0,
            class: 4,
            description: "bench".into(),
        },
        build: BuildInfo::default(),
        airbag_thresholds: AirbagThresholds::DEFAULT,
    };
    let axes = Axes::new(
        vec![40.0, 48.0, 56.0, 64.0, 72.0, 80.0, 90.0, 100.0, 108.0],
        (0..12).map(|i| 800.0 + 200.0 * i as f32).collect(),
        vec![30.0, 45.0, 60.0, 75.0, 90.0, 105.0, 125.0],
        vec![200.0, 250.0, 300.0, 350.0, 400.0, 450.0],
    );
    Diagram::from_fn(header, axes, |p| {
        let s = p.query.closing_speed_kph / 108.0;
        Cell {
            belt_limiter_kn: 2.0 + 8.0 * s,
            airbag_level_kn: if s < 0.4 { 0.0 } else { 12.0 * s },
            pretensioner_time_ms: -50.0 * s,
            airbag_time_ms: 5.0 + 10.0 * (1.0 - s),
            a_max_g: 40.0 * s,
            a_mean_g: 20.0 * s,
            excursion_mm: p.query.seat_distance_mm * 0.6,
            bottoming_out: if s > 0.95 && p.query.opponent_mass_kg > 2500.0 {
                1.0
            } else {
                0.0
            },
            a_ideal_g: 15.0 * s,
        }
    })
    .expect("bench table is valid")
}

/// Deterministic spread of `n` queries over (and slightly beyond) the bench table's axes.
pub fn bench_queries(n: usize) -> Vec<Query> {
    let mut state = 0x2545_F491_4F6C_DD1Du64;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 40) as f32 / (1u64 << 24) as f32
    };
    (0..n)
        .map(|_| Query {
            closing_speed_kph: 35.0 + 80.0 * next(),
            opponent_mass_kg: 700.0 + 2400.0 * next(),
            occupant_mass_kg: 25.0 + 105.0 * next(),
            seat_distance_mm: 190.0 + 270.0 * next(),
        })
        .collect()
}

/// The fixed step the ECU integrated its per-cycle prediction at before it switched to the
/// closed form (no `prediction_step_ms` any more), s. Only the comparison rows use it.
pub const FORMER_ECU_STEP_S: f64 = 5.0e-4;

/// Collision predictions as the ECU makes them: the default ego (1785 kg, class 4) against
/// opponents over the default table's opponent-mass and closing-speed axes (opponent class by
/// mass), cycled so that consecutive calls see different inputs (no single-case favouritism).
/// Shared by the `collision_*_varied` criterion benches and `icount-prediction`.
pub struct PredictionWorkload {
    springs: Vec<CombinedSpring>,
    /// (spring index, opponent kg, closing m/s).
    cases: Vec<(usize, f64, f64)>,
}

impl PredictionWorkload {
    /// Default ego mass [kg] (the paper's Ford Taurus, class 4).
    pub const EGO_KG: f64 = 1785.0;

    /// 12 opponent masses (800–3000 kg) × 9 closing speeds (40–108 km/h) = 108 cases.
    ///
    /// # Panics
    /// Never for the shipped class curves (a failure is a bench bug).
    #[allow(clippy::missing_panics_doc)]
    pub fn new() -> Self {
        let ego = physics::MassClass::new(4).expect("class 4").curve();
        let springs = (1..=6)
            .map(|c| {
                let opp = physics::MassClass::new(c).expect("class 1..=6").curve();
                CombinedSpring::series(ego, Some(opp)).expect("shipped curves combine")
            })
            .collect();
        let mut cases = Vec::new();
        for m in (0..12).map(|i| 800.0 + 200.0 * f64::from(i)) {
            let class = physics::class_for_mass_kg(m)
                .expect("positive mass")
                .number();
            for kph in (0..9).map(|i| 40.0 + 8.5 * f64::from(i)) {
                cases.push((usize::from(class - 1), m, physics::kph_to_mps(kph)));
            }
        }
        PredictionWorkload { springs, cases }
    }

    /// Number of distinct cases.
    pub fn len(&self) -> usize {
        self.cases.len()
    }

    /// Never empty.
    pub fn is_empty(&self) -> bool {
        self.cases.is_empty()
    }

    /// Input of case `i` (modulo the number of cases) with the integrator step `step_s`.
    pub fn input(&self, i: usize, step_s: f64) -> CollisionInput<'_> {
        let (c, m, v) = self.cases[i % self.cases.len()];
        CollisionInput {
            step_s,
            ..CollisionInput::with_defaults(&self.springs[c], Self::EGO_KG, m, v)
        }
    }
}

impl Default for PredictionWorkload {
    fn default() -> Self {
        Self::new()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn prediction_workload_spans_the_default_axes_with_valid_inputs() {
        let w = PredictionWorkload::new();
        assert_eq!(w.len(), 108);
        let mut seen = std::collections::BTreeSet::new();
        for i in 0..w.len() {
            let input = w.input(i, 5e-4);
            assert_eq!(input.ego_mass_kg, PredictionWorkload::EGO_KG);
            assert!((800.0..=3000.0).contains(&input.opp_mass_kg));
            let kph = input.closing_speed_mps * 3.6;
            assert!((40.0 - 1e-9..=108.0 + 1e-9).contains(&kph), "{kph}");
            let s = physics::predict_summary(&input).expect("valid prediction input");
            assert!(s.vehicle.a_mean_mps2 > 0.0);
            seen.insert((input.opp_mass_kg as u32, (kph * 10.0).round() as u32));
        }
        assert_eq!(seen.len(), 108, "cases are distinct");
        // Cycled: case 108 is case 0 again.
        assert_eq!(
            w.input(108, 5e-4).closing_speed_mps,
            w.input(0, 5e-4).closing_speed_mps
        );
    }

    #[test]
    fn input_frames_decode_to_what_was_sealed_for_many_cycles() {
        let mut f = CycleInputFrames::new().unwrap();
        // 40 cycles wrap the 4-bit alive counter twice: the replayed stream must stay valid.
        for i in 0..40 {
            let d = f.decode_next();
            assert_eq!(d.rejected, 0, "cycle {i}");
            let k = (i % 16) as f32;
            // The generated setters truncate to the raw step: error < one step.
            assert!((d.ego_speed_mps - (27.5 - 0.01 * k)).abs() <= 0.01 + 1e-4);
            assert!((d.occupant_mass_kg - (78.5 + 0.1 * k)).abs() <= 0.1 + 1e-3);
            assert_eq!((d.chest_to_wheel_mm, d.seat_track_mm), (310, 180));
            assert!(d.buckled);
        }
    }

    #[test]
    fn command_frames_pass_the_receivers_check() {
        let mut enc = CommandEncoder::new();
        let mut rx = E2eChecker::new();
        let mut out = [RawFrame::new(0, &[]); 3];
        for _ in 0..20 {
            enc.encode(&Commands::FIRE, &mut out).unwrap();
            for f in &out {
                rx.check_frame(f).unwrap();
            }
        }
        let m = bus::decode(out[0].id, out[0].payload()).unwrap();
        let Messages::AirbagStageCmd(a) = m else {
            panic!("not an airbag frame")
        };
        // DBC factor 0.05 kN: 8.45 kN within one raw step (the setter truncates).
        assert!((a.force_level() - 8.45).abs() <= 0.05 + 1e-4);
    }

    #[test]
    fn out_of_range_command_is_an_error_not_a_panic() {
        let mut enc = CommandEncoder::new();
        let mut out = [RawFrame::new(0, &[]); 3];
        let bad = Commands {
            airbag_force_kn: f32::NAN,
            ..Commands::FIRE
        };
        assert!(enc.encode(&bad, &mut out).is_err());
        let too_high = Commands {
            load_limiter_kn: 12.5,
            ..Commands::FIRE
        };
        assert!(enc.encode(&too_high, &mut out).is_err());
    }
}
