//! The whole ECU decision cycle (`restraint::RestraintCycle` as an `Activity`) driven through
//! `SimIo` with arbitrary inputs, cycle after cycle — on BOTH decision paths:
//!
//! * the adaptive LUT path (input flag bit 0 = 1): the real table `data/default.lut` (9×12×7×6
//!   cells), so prediction → LUT lookup → state machine → commands runs as on the bench;
//! * the degraded path (bit 0 = 0): no LUT, built-in reference restraint only.
//!
//! Arbitrary raw values alone almost never make a coherent approach (an object track that
//! stays plausible for 100 ms, genuine E2E-sealed occupant frames, a crash pulse that lasts), so
//! besides raw records the input can switch on *generators* that produce plausible inputs from
//! a few fuzzed parameters; the fuzzer mixes both freely.
//!
//! Input: flag byte (bit 0: with LUT; other bits reserved), then records `[kind][fields…]`,
//! kind % 8:
//! * 0 — raw object state (age, sequence, 6 × f32 LE, valid flag): any values, NaN/inf included;
//! * 1 — raw accelerometer batch (age, sequence, period u32, count, count × f32);
//! * 2 — raw CAN frame (id LE u16 → 11 bit, bit 15 = extended; len; 8 bytes);
//! * 3 — run one cycle after `b × 0.25 ms` (b = 0: time stands still);
//! * 4 — object track generator: contact in `u16 LE` ms from now (0 = track off: no more
//!   samples, the track goes stale), closing speed `10 + b·20/255` m/s, opponent mass
//!   `800 + 9·b` kg, σ `b` kg, flags (bit 0: confidence 0.3 instead of 1; bits 1–7: braking
//!   `0.25·n` m/s²). While on, every 10 ms of cycle time a valid sample at distance
//!   `v · (contact − now)` is published — a coherent approach from tens of metres;
//! * 5 — vehicle / occupant CAN generator: ego speed `0.4·b` m/s, occupant mass `30 + 0.4·b` kg,
//!   chest to wheel `150 + 1.5·b` mm, flags (bits 0–1 buckle, bits 2–4 class % 5, bit 5 off,
//!   bit 6: `EgoLongAccel` −8 g, a crash on the vehicle-dynamics sensor; bit 7: a V2X station,
//!   then one more byte `b`: its reported mass `160·b` kg, 0–40 t). While on, genuine
//!   E2E-sealed `EgoVehicleState` every 10 ms and `OccupantClassification` every 100 ms (own
//!   `E2eProtector`, so alive counters are consistent), and with the station a
//!   `V2xOpponentMass` every 100 ms at the track generator's range and speed (`NoStation`
//!   without a track) — the second mass source the lookup plans with;
//! * 6 — accelerometer, `[b, n, p]`: for `n < 128` one crash-pulse batch, `n % 8 + 1` samples of
//!   `−0.5·b·g` at `(1 + p % 20) × 125 µs`, continuing the accelerometer time line (what a real
//!   crash sensor delivers); for `n ≥ 128` the live sensor: bit 6 of `n` switches it off (a dead
//!   sensor), otherwise on: from then on, before every cycle, the samples since the last batch
//!   at 4 kHz with a ±0.05 m/s² dither (a live MEMS sensor is never bit-constant), plus a crash
//!   ramp of `0.1·b` g/ms from this record on, capped at 40 g (`b = 0`: quiet) — the onset the
//!   prediction-matched confirmation looks for;
//! * 7 — run `b + 1` cycles of 1 ms (long stretches of time from two bytes).
//!
//! At most 2 000 cycles per input. Generators emit just before a cycle is run.
//!
//! Oracles (every cycle, on the frames it sent): no panic, no hang;
//! 1. every frame decodes with `bus::decode` (valid DBC frame, correct CRC, signals in range);
//! 2. an `AirbagStageCmd` with `Fire` is only sent (a) in phase CRASH / POST-CRASH with
//!    `airbag_fired()` set — the state machine fires only through a crash confirmation — and
//!    (b) only if the input fed so far made the path that confirmed POSSIBLE, checked
//!    independently of the detectors (README "Decision table"): prediction-matched — at least
//!    three finite samples with deceleration ≥ `confirm_wake_g`; generic thresholds — at
//!    least `confirm_samples` finite samples ≥ `confirm_decel_g` and an upper bound of the
//!    integrated Δv ≥ `confirm_delta_v_mps` (each positive sample counts at most half its own
//!    period plus half the longest usable period, the most a trapezoid can give it); backup —
//!    a frame decoding as `EgoVehicleState` with `EgoLongAccel` ≤ −`backup_confirm_g`, or
//!    (the safing sensor measuring the crash for a faulty crash sensor; the harness feeds both
//!    sensors the same samples) that Δv bound ≥ the lowest airbag floor the satellites' relief
//!    allows, min(`fallback_min_dv_mps`, `satellite_floor_mps`);
//! 3. a command with source `Adaptive` is only sent with a LUT and after at least one LUT
//!    lookup (the adaptive settings come from nowhere else).
#![no_main]

use std::sync::OnceLock;

use bus::codec::{
    AirbagStageCmdCmdSource, AirbagStageCmdFire, BeltLimiterCmdCmdSource,
    EgoVehicleStateBrakeState, OccupantClassificationBeltBuckle,
    OccupantClassificationOccupantClass, V2xOpponentMassStationStatus,
};
use bus::{
    E2eProtector, EgoVehicleState, Messages, OccupantClassification, RawFrame, V2xOpponentMass,
};
use diagram::Diagram;
use restraint::crash::ConfirmKind;
use restraint::{Activity, CycleConfig, CycleInfo, Phase, RestraintCycle, SimIo, G_MPS2};
use libfuzzer_sys::fuzz_target;
use physics::reference::ReferenceSettings;

const MS: u64 = 1_000_000;
/// Object list period of the track generator (a 10–20 ms sensor), ns.
const OBJECT_PERIOD_NS: u64 = 10 * MS;
/// DBC cycle times of the generated vehicle / occupant frames, ns.
const VEHICLE_PERIOD_NS: u64 = 10 * MS;
const OCCUPANT_PERIOD_NS: u64 = 100 * MS;
/// Longest sample period the crash detector integrates (its `MAX_SAMPLE_PERIOD_NS`), ns.
const MAX_SAMPLE_PERIOD_NS: u32 = 10_000_000;
/// Cycles per input (bounds the time per input).
const MAX_CYCLES: u32 = 2_000;

/// The real table and the reference restraint, loaded once per process: building them per
/// input (163 kB file decode + validation + CRC, a TOML parse) would dominate the run time.
/// Each input gets a clone of the table (a memcpy of its cells; `RestraintCycle` owns it).
struct Fixture {
    lut: Diagram,
    reference: ReferenceSettings,
}

fn fixture() -> &'static Fixture {
    static F: OnceLock<Fixture> = OnceLock::new();
    F.get_or_init(|| {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../data/default.lut");
        // A harness set-up failure, not a finding: without the table the LUT path is not
        // fuzzed at all, so stop loudly.
        let lut = Diagram::load(path).unwrap_or_else(|e| panic!("fuzz set-up: {path}: {e}"));
        let reference = physics::reference::ReferenceRestraint::builtin()
            .unwrap_or_else(|e| panic!("fuzz set-up: built-in reference restraint: {e}"))
            .restraint;
        Fixture { lut, reference }
    })
}

struct Reader<'a>(&'a [u8]);

impl Reader<'_> {
    fn u8(&mut self) -> Option<u8> {
        let (b, rest) = self.0.split_first()?;
        self.0 = rest;
        Some(*b)
    }
    fn u16(&mut self) -> Option<u16> {
        let b = self.0.get(..2)?;
        let v = u16::from_le_bytes([b[0], b[1]]);
        self.0 = &self.0[2..];
        Some(v)
    }
    fn u32(&mut self) -> Option<u32> {
        let b = self.0.get(..4)?;
        let v = u32::from_le_bytes([b[0], b[1], b[2], b[3]]);
        self.0 = &self.0[4..];
        Some(v)
    }
    fn f32(&mut self) -> Option<f32> {
        self.u32().map(f32::from_bits)
    }
}

/// Plausible object track: a constant-speed (or braking) approach to a contact instant.
struct Track {
    contact_ns: u64,
    closing_mps: f32,
    opp_kg: f32,
    sigma_kg: f32,
    confidence: f32,
    rel_accel_mps2: f32,
    next_ns: u64,
    sequence: u64,
}

/// Genuine vehicle / occupant CAN sender.
struct CanGen {
    ego_speed_mps: f32,
    ego_long_accel_mps2: f32,
    occ_kg: f32,
    chest_mm: u16,
    buckle: OccupantClassificationBeltBuckle,
    class: OccupantClassificationOccupantClass,
    next_vehicle_ns: u64,
    next_occupant_ns: u64,
    /// The V2X station's reported mass, kg (`None`: no station).
    v2x_kg: Option<f32>,
    next_v2x_ns: u64,
}

/// What the input made possible so far (the independent fire oracle).
#[derive(Default)]
struct AccelFed {
    /// Finite samples at or above the confirmation deceleration.
    over_threshold: u64,
    /// Finite samples at or above the wake threshold.
    over_wake: u64,
    /// Σ max(decel, 0)·own period over finite samples of batches with a usable period, m/s.
    delta_v_own_mps: f64,
    /// Σ max(decel, 0) over the same samples, m/s².
    decel_sum_mps2: f64,
    /// Longest usable sample period fed, s.
    max_period_s: f64,
    /// A vehicle frame with a crash deceleration (≤ −`backup_confirm_g`) was fed.
    can_crash_decel: bool,
}

impl AccelFed {
    fn note(&mut self, cfg: &CycleConfig, a: &restraint::CrashAccelSample) {
        if a.sample_period_ns == 0 || a.sample_period_ns > MAX_SAMPLE_PERIOD_NS {
            return; // the monitor drops the whole batch
        }
        let dt_s = f64::from(a.sample_period_ns) * 1.0e-9;
        self.max_period_s = self.max_period_s.max(dt_s);
        let decel_mps2 = cfg.confirm_decel_g * G_MPS2;
        let wake_mps2 = cfg.confirm_wake_g * G_MPS2;
        for &s in a.samples() {
            if !s.is_finite() {
                continue;
            }
            let decel = -f64::from(s);
            if decel >= decel_mps2 {
                self.over_threshold += 1;
            }
            if decel >= wake_mps2 {
                self.over_wake += 1;
            }
            if decel > 0.0 {
                self.delta_v_own_mps += decel * dt_s;
                self.decel_sum_mps2 += decel;
            }
        }
    }

    fn note_can(&mut self, cfg: &CycleConfig, f: &RawFrame) {
        if let Ok(Messages::EgoVehicleState(m)) = bus::decode(f.id, f.payload()) {
            if f64::from(m.ego_long_accel()) <= -cfg.backup_confirm_g * G_MPS2 {
                self.can_crash_decel = true;
            }
        }
    }

    /// The most Δv a trapezoidal integration over any subset of the samples can reach, m/s.
    fn delta_v_bound_mps(&self) -> f64 {
        0.5 * self.delta_v_own_mps + 0.5 * self.max_period_s * self.decel_sum_mps2
    }

    /// The input made the confirmation path `kind` possible (module docs, oracle 2b).
    fn confirmation_possible(&self, cfg: &CycleConfig, kind: Option<ConfirmKind>) -> bool {
        // The tolerance only absorbs summation-order rounding (≈ 1e-16 relative).
        let generic = self.over_threshold >= u64::from(cfg.confirm_samples)
            && self.delta_v_bound_mps() >= cfg.confirm_delta_v_mps * (1.0 - 1.0e-9);
        match kind {
            Some(ConfirmKind::Matched(_)) => self.over_wake >= 3,
            Some(ConfirmKind::Generic { .. }) => generic,
            Some(ConfirmKind::Backup) => {
                let floor_mps = cfg.fallback_min_dv_mps.min(cfg.satellite_floor_mps);
                self.can_crash_decel || self.delta_v_bound_mps() >= floor_mps * (1.0 - 1.0e-9)
            }
            None => false,
        }
    }
}

/// The live accelerometer generator (kind 6, `n ≥ 128`).
struct LiveAccel {
    /// Start of the crash ramp, ns.
    ramp_from_ns: u64,
    /// Ramp slope, m/s² per ms (0: quiet).
    slope_mps2_per_ms: f64,
}

struct Harness {
    cycle: RestraintCycle<'static>,
    io: SimIo,
    info: CycleInfo,
    now_ns: u64,
    cycles: u32,
    with_lut: bool,
    track: Option<Track>,
    can_gen: Option<CanGen>,
    tx: E2eProtector,
    accel_next_ns: u64,
    accel_sequence: u64,
    live_accel: Option<LiveAccel>,
    fed: AccelFed,
}

impl Harness {
    /// The live sensor's samples since the last batch, at 4 kHz (≤ 8 per batch).
    fn emit_live_accel(&mut self) {
        let now = self.now_ns;
        let Some(live) = &self.live_accel else {
            return;
        };
        const PERIOD_NS: u64 = 250_000;
        // Continue the time line; after a long silence start 2 ms back (a fresh batch).
        let mut t = self.accel_next_ns.max(now.saturating_sub(2_000_000));
        let mut a = restraint::CrashAccelSample::EMPTY;
        a.first_timestamp_ns = t;
        a.sample_period_ns = PERIOD_NS as u32;
        while t <= now && (a.count as usize) < a.accel_mps2.len() {
            let dither = if (t / PERIOD_NS) % 2 == 0 { 0.05 } else { -0.05 };
            let ms = t.saturating_sub(live.ramp_from_ns) as f64 * 1e-6;
            let crash = (live.slope_mps2_per_ms * ms).min(40.0 * G_MPS2);
            a.accel_mps2[a.count as usize] = (dither - crash) as f32;
            a.count += 1;
            t += PERIOD_NS;
        }
        if a.count > 0 {
            self.accel_next_ns = t;
            self.accel_sequence += 1;
            a.sequence = self.accel_sequence;
            self.push_accel(a);
        }
    }

    fn emit_generated(&mut self) {
        self.emit_live_accel();
        let now = self.now_ns;
        if let Some(t) = self.track.as_mut() {
            if now >= t.next_ns {
                t.next_ns = now.saturating_add(OBJECT_PERIOD_NS);
                t.sequence += 1;
                let to_contact_s = (t.contact_ns as f64 - now as f64) * 1.0e-9;
                let o = restraint::ObjectState {
                    timestamp_ns: now,
                    sequence: t.sequence,
                    object_id: 7,
                    // After contact the object sits at the bumper (small negative = overlap).
                    distance_m: (f64::from(t.closing_mps) * to_contact_s).max(-1.0) as f32,
                    closing_speed_mps: t.closing_mps,
                    relative_accel_mps2: t.rel_accel_mps2,
                    opponent_mass_kg: t.opp_kg,
                    opponent_mass_sigma_kg: t.sigma_kg,
                    confidence: t.confidence,
                    valid: restraint::VALID,
                    ..Default::default()
                };
                self.io.push_object(o);
            }
        }
        if let Some(g) = self.can_gen.as_mut() {
            if now >= g.next_vehicle_ns {
                g.next_vehicle_ns = now.saturating_add(VEHICLE_PERIOD_NS);
                if let Ok(m) = EgoVehicleState::encode(
                    EgoVehicleStateBrakeState::Released,
                    g.ego_speed_mps,
                    g.ego_long_accel_mps2,
                ) {
                    let f = self.tx.seal(m);
                    self.fed.note_can(self.cycle.config(), &f);
                    self.io.push_can(f);
                }
            }
            if now >= g.next_occupant_ns {
                g.next_occupant_ns = now.saturating_add(OCCUPANT_PERIOD_NS);
                if let Ok(m) =
                    OccupantClassification::encode(g.buckle, g.class, 90, g.occ_kg, g.chest_mm, 150)
                {
                    self.io.push_can(self.tx.seal(m));
                }
            }
            if let Some(kg) = g.v2x_kg.filter(|_| now >= g.next_v2x_ns) {
                g.next_v2x_ns = now.saturating_add(OCCUPANT_PERIOD_NS);
                let (status, range_m, closing_mps) = match &self.track {
                    Some(t) => {
                        let to_contact_s = (t.contact_ns as f64 - now as f64) * 1.0e-9;
                        (
                            V2xOpponentMassStationStatus::Valid,
                            (f64::from(t.closing_mps) * to_contact_s).clamp(0.0, 400.0) as f32,
                            t.closing_mps,
                        )
                    }
                    None => (V2xOpponentMassStationStatus::NoStation, 0.0, 0.0),
                };
                if let Ok(m) = V2xOpponentMass::encode(status, kg, 100.0, range_m, closing_mps) {
                    self.io.push_can(self.tx.seal(m));
                }
            }
        }
    }

    /// Runs one cycle at `now_ns` and checks every frame it sent.
    fn run_cycle(&mut self) {
        self.emit_generated();
        self.info.deadline_ns = self.now_ns;
        self.info.now_ns = self.now_ns;
        self.cycle.step(&self.info, &mut self.io);
        self.info.cycle += 1;
        self.info.slot += 1;
        self.cycles += 1;
        self.check_sent();
    }

    fn check_sent(&mut self) {
        for f in self.io.can_tx.oldest_ordered() {
            let msg = match bus::decode(f.id, f.payload()) {
                Ok(m) => m,
                // No SecOC sender is set, so every frame carries E2E and must decode.
                Err(e) => panic!(
                    "ECU sent an invalid frame {:#x} {:?}: {e}",
                    f.id,
                    f.payload()
                ),
            };
            let adaptive = match &msg {
                Messages::AirbagStageCmd(m) => {
                    if m.fire() == AirbagStageCmdFire::Fire {
                        let phase = self.cycle.phase();
                        assert!(
                            matches!(phase, Phase::Crash | Phase::PostCrash)
                                && self.cycle.airbag_fired(),
                            "airbag fire sent in phase {phase:?} (airbag_fired {})",
                            self.cycle.airbag_fired()
                        );
                        let cfg = self.cycle.config();
                        let kind = self.cycle.crash_kind();
                        assert!(
                            self.fed.confirmation_possible(cfg, kind),
                            "airbag fire sent although no input could confirm the crash the way \
                             it was confirmed ({kind:?}): {} samples ≥ {} g, {} ≥ {} g (generic \
                             needs {}), Δv bound {:.4} m/s (generic needs {}), CAN crash decel {}",
                            self.fed.over_wake,
                            cfg.confirm_wake_g,
                            self.fed.over_threshold,
                            cfg.confirm_decel_g,
                            cfg.confirm_samples,
                            self.fed.delta_v_bound_mps(),
                            cfg.confirm_delta_v_mps,
                            self.fed.can_crash_decel
                        );
                    }
                    m.cmd_source() == AirbagStageCmdCmdSource::Adaptive
                }
                Messages::BeltLimiterCmd(m) => m.cmd_source() == BeltLimiterCmdCmdSource::Adaptive,
                _ => false,
            };
            if adaptive {
                assert!(
                    self.with_lut && self.cycle.counters().lut_lookups > 0,
                    "adaptive command without a LUT lookup (LUT {}, lookups {})",
                    self.with_lut,
                    self.cycle.counters().lut_lookups
                );
            }
        }
        self.io.can_tx.clear();
    }

    fn push_accel(&mut self, a: restraint::CrashAccelSample) {
        self.fed.note(self.cycle.config(), &a);
        self.io.push_both_accel(a);
    }
}

fn buckle_of(b: u8) -> OccupantClassificationBeltBuckle {
    match b & 3 {
        0 => OccupantClassificationBeltBuckle::Unbuckled,
        1 => OccupantClassificationBeltBuckle::Buckled,
        2 => OccupantClassificationBeltBuckle::SwitchFault,
        _ => OccupantClassificationBeltBuckle::NotAvailable,
    }
}

fn class_of(b: u8) -> OccupantClassificationOccupantClass {
    match b % 5 {
        0 => OccupantClassificationOccupantClass::Empty,
        1 => OccupantClassificationOccupantClass::ChildSeat,
        2 => OccupantClassificationOccupantClass::SmallAdult,
        3 => OccupantClassificationOccupantClass::MidAdult,
        _ => OccupantClassificationOccupantClass::LargeAdult,
    }
}

fuzz_target!(|data: &[u8]| {
    let Some((&flags, body)) = data.split_first() else {
        return;
    };
    let fx = fixture();
    let with_lut = flags & 1 != 0;
    let lut = with_lut.then(|| ecu::lut_input(&fx.lut));
    let reference = fx.reference;
    let Ok((mut cycle, notes)) = RestraintCycle::new(CycleConfig::default(), lut, &reference)
    else {
        panic!("default cycle config must build");
    };
    assert!(
        !with_lut || notes.lut_rejected.is_none(),
        "data/default.lut rejected by the default cycle config: {:?}",
        notes.lut_rejected
    );
    let now_ns: u64 = 1_000_000_000;
    if cycle.startup(now_ns, &mut SimIo::new()).is_err() {
        return;
    }
    let mut h = Harness {
        cycle,
        io: SimIo::new(),
        info: CycleInfo {
            period_ns: MS,
            ..CycleInfo::default()
        },
        now_ns,
        cycles: 0,
        with_lut,
        track: None,
        can_gen: None,
        tx: E2eProtector::new(),
        accel_next_ns: now_ns,
        accel_sequence: 0,
        live_accel: None,
        fed: AccelFed::default(),
    };
    let mut r = Reader(body);
    while let Some(kind) = r.u8() {
        if h.cycles > MAX_CYCLES {
            break;
        }
        let now_ns = h.now_ns;
        match kind % 8 {
            0 => {
                // Fields are read in declaration order (the documented layout).
                let o = restraint::ObjectState {
                    timestamp_ns: now_ns.saturating_sub(u64::from(r.u8().unwrap_or(0)) * 100_000),
                    sequence: u64::from(r.u8().unwrap_or(0)),
                    distance_m: r.f32().unwrap_or(10.0),
                    closing_speed_mps: r.f32().unwrap_or(10.0),
                    relative_accel_mps2: r.f32().unwrap_or(0.0),
                    opponent_mass_kg: r.f32().unwrap_or(1500.0),
                    opponent_mass_sigma_kg: r.f32().unwrap_or(100.0),
                    confidence: r.f32().unwrap_or(1.0),
                    valid: r.u8().unwrap_or(1) & 1,
                    ..Default::default()
                };
                h.io.push_object(o);
            }
            1 => {
                let mut a = restraint::CrashAccelSample::EMPTY;
                a.first_timestamp_ns =
                    now_ns.saturating_sub(u64::from(r.u8().unwrap_or(0)) * 100_000);
                a.sequence = u64::from(r.u8().unwrap_or(0));
                a.sample_period_ns = r.u32().unwrap_or(100_000);
                a.count = u32::from(r.u8().unwrap_or(0));
                let n = (a.count as usize).min(a.accel_mps2.len());
                for s in a.accel_mps2.iter_mut().take(n) {
                    *s = r.f32().unwrap_or(-300.0);
                }
                h.push_accel(a);
            }
            2 => {
                let id_lo = r.u8().unwrap_or(0xA0);
                let id_hi = r.u8().unwrap_or(0);
                let len = r.u8().unwrap_or(8);
                let mut data = [0u8; 8];
                for d in &mut data {
                    *d = r.u8().unwrap_or(0);
                }
                let id = u32::from(u16::from_le_bytes([id_lo, id_hi]) & 0x7FF);
                let extended = id_hi & 0x80 != 0;
                let f = RawFrame {
                    id: if extended { id | bus::CAN_EFF_FLAG } else { id },
                    len,
                    data,
                };
                h.fed.note_can(h.cycle.config(), &f);
                h.io.push_can(f);
            }
            3 => {
                let step = u64::from(r.u8().unwrap_or(1));
                h.now_ns = now_ns.saturating_add(step * 250_000);
                h.run_cycle();
            }
            4 => {
                let contact_ms = r.u16().unwrap_or(0);
                let v = r.u8().unwrap_or(128);
                let m = r.u8().unwrap_or(80);
                let sigma = r.u8().unwrap_or(100);
                let f = r.u8().unwrap_or(0);
                h.track = (contact_ms != 0).then(|| Track {
                    contact_ns: now_ns.saturating_add(u64::from(contact_ms) * MS),
                    closing_mps: 10.0 + f32::from(v) * (20.0 / 255.0),
                    opp_kg: 800.0 + 9.0 * f32::from(m),
                    sigma_kg: f32::from(sigma),
                    confidence: if f & 1 != 0 { 0.3 } else { 1.0 },
                    rel_accel_mps2: -0.25 * f32::from(f >> 1),
                    next_ns: now_ns,
                    sequence: h.track.as_ref().map_or(0, |t| t.sequence),
                });
            }
            5 => {
                let speed = r.u8().unwrap_or(38);
                let occ = r.u8().unwrap_or(112);
                let chest = r.u8().unwrap_or(100);
                let f = r.u8().unwrap_or(0b1101);
                let v2x_kg = (f & 0x80 != 0).then(|| (160.0 * f32::from(r.u8().unwrap_or(11))).min(40_000.0));
                h.can_gen = (f & 0x20 == 0).then(|| CanGen {
                    v2x_kg,
                    next_v2x_ns: now_ns,
                    ego_speed_mps: (0.4 * f32::from(speed)).min(100.0),
                    ego_long_accel_mps2: if f & 0x40 != 0 {
                        (-8.0 * G_MPS2) as f32
                    } else {
                        0.0
                    },
                    occ_kg: 30.0 + 0.4 * f32::from(occ),
                    chest_mm: 150 + u16::from(chest) * 3 / 2,
                    buckle: buckle_of(f),
                    class: class_of(f >> 2),
                    next_vehicle_ns: now_ns,
                    next_occupant_ns: now_ns,
                });
            }
            6 => {
                let level = r.u8().unwrap_or(40);
                let n_byte = r.u8().unwrap_or(7);
                let p_byte = r.u8().unwrap_or(7);
                if n_byte >= 128 {
                    h.live_accel = (n_byte & 0x40 == 0).then(|| LiveAccel {
                        ramp_from_ns: now_ns,
                        slope_mps2_per_ms: 0.1 * f64::from(level) * G_MPS2,
                    });
                    continue;
                }
                let n = usize::from(n_byte % 8) + 1;
                let period_ns = (1 + u32::from(p_byte % 20)) * 125_000;
                let span_ns = n as u64 * u64::from(period_ns);
                // Continue the sensor's time line; never start in the future.
                let first = h
                    .accel_next_ns
                    .max(now_ns.saturating_sub(span_ns))
                    .min(now_ns);
                h.accel_next_ns = first.saturating_add(span_ns);
                h.accel_sequence += 1;
                let mut a = restraint::CrashAccelSample::EMPTY;
                a.first_timestamp_ns = first;
                a.sequence = h.accel_sequence;
                a.sample_period_ns = period_ns;
                a.count = n as u32;
                let accel = (-0.5 * f64::from(level) * G_MPS2) as f32;
                a.accel_mps2.iter_mut().take(n).for_each(|s| *s = accel);
                h.push_accel(a);
            }
            _ => {
                let n = u32::from(r.u8().unwrap_or(0)) + 1;
                for _ in 0..n {
                    if h.cycles > MAX_CYCLES {
                        break;
                    }
                    h.now_ns = h.now_ns.saturating_add(MS);
                    h.run_cycle();
                }
            }
        }
    }
    h.run_cycle();
});
