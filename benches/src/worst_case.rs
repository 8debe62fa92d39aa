//! The worst case of one ECU cycle, searched for rather than assumed.
//!
//! A [`CycleCase`] is a point in the space of what one cycle of `RestraintCycle::step` can
//! meet: the *state* it starts from — reached by running the real cycle through a prefix of
//! a scenario: an object approach (closing speed, closing acceleration, opponent mass and
//! reported σ, object period, latency, noise, how long it has been tracked), the occupant and
//! ego frames, a crash pulse (level, accelerometer rate), the time of the measured cycle
//! relative to contact (before it: PRE-CRASH or MONITORING; after it: confirmation, CRASH),
//! with or without LUT, SecOC, CAN — and the *inputs of the measured cycle itself*: up to 2
//! object samples (on track, outlier, out of order, non-finite, new object, "no object", low
//! confidence), up to 4 CAN frames (ego; occupant unchanged or changed; V2X; a corrupt or
//! foreign frame), up to 2 accelerometer batches, and its timing (late start, overruns). A V2X
//! station that is the tracked object can report throughout the prefix (`v2x`): the lookups
//! then take the second-source branch.
//!
//! **Bounds of the space.** The measured cycle's own inputs are bounded by what the senders'
//! contracts deliver in one 1 ms cycle plus one of catching up: object list ≥ 5 ms period (2
//! samples), one accelerometer batch per ms (2 batches), and per CAN message at most one
//! frame per cycle (EgoVehicleState 10 ms, OccupantClassification and V2xOpponentMass 100 ms in the DBC) plus one
//! frame that the E2E check rejects or the ECU does not consume. A babbling node or a burst of
//! queued frames after a stall is outside the budget's contract (each received frame costs
//! 400–1 200 instructions in the bus crate's E2E check and decode); the shell bounds it at 64
//! frames per cycle.
//!
//! [`prepare`] runs the prefix (not measured); [`measured_step`] is the one cycle whose
//! instructions count — a non-inlined function, so callgrind can collect exactly it
//! (`--toggle-collect`), and [`crate::icount::collected_totals`] reads one count per case.
//! The search (`worst-cycle search`, its operators in [`crate::search`]) is a seeded (μ + λ)
//! evolution over cases with that count as its objective; the gate measures the committed seed
//! `benches/worst-case/seed.json`.

use anyhow::Context;
use bus::codec::{
    EgoVehicleStateBrakeState, OccupantClassificationBeltBuckle,
    OccupantClassificationOccupantClass,
};
use bus::{E2eProtector, RawFrame};
use diagram::Diagram;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use restraint::{
    Activity, CrashAccelSample, CycleConfig, CycleInfo, ObjectState, Phase, ReferenceSettings,
    RestraintCycle, SimIo, SimLoop, VALID,
};
use serde::{Deserialize, Serialize};
use std::path::Path;

const MS: u64 = 1_000_000;
/// Standard gravity, m/s².
const G: f64 = 9.806_65;
/// The measured function's path as callgrind names it (`--toggle-collect`).
pub const MEASURED_FN: &str = "cycle_benches::worst_case::measured_step";

/// Time of the measured cycle (a fixed epoch keeps cases reproducible), ns.
const T_MEASURED: u64 = 100_000 * MS;

/// Reference restraint of the cases (as in `ecu_cycle`).
const REFERENCE: ReferenceSettings = ReferenceSettings {
    belt_limiter_kn: 8.5,
    airbag_level_kn: 12.0,
    pretensioner_time_ms: 10.0,
    airbag_time_ms: 10.0,
};

/// What one measured-cycle object sample is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ObjectKind {
    /// The next sample of the track.
    OnTrack,
    /// 5 m closer and 8 m/s faster than the track (beyond the filter's gate).
    Outlier,
    /// Measured before the track's newest sample.
    OutOfOrder,
    /// NaN distance (the input monitor rejects it).
    NonFinite,
    /// Another tracker object id (a new track).
    NewObject,
    /// A "no object" record (valid = 0).
    NoObject,
    /// Confidence below the ECU's minimum.
    LowConfidence,
}

impl ObjectKind {
    /// Every kind, in declaration order.
    pub const ALL: [Self; 7] = [
        Self::OnTrack,
        Self::Outlier,
        Self::OutOfOrder,
        Self::NonFinite,
        Self::NewObject,
        Self::NoObject,
        Self::LowConfidence,
    ];
}

/// What one measured-cycle CAN frame is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum CanKind {
    /// The next EgoVehicleState.
    Ego,
    /// The next OccupantClassification, same occupant.
    Occupant,
    /// The next OccupantClassification, occupant 10 kg heavier (the LUT is queried again).
    OccupantChanged,
    /// An OccupantClassification with a broken CRC (E2E rejection).
    Corrupt,
    /// A standard id the ECU does not consume.
    Foreign,
    /// The next V2xOpponentMass of a station that is the tracked object.
    V2x,
}

impl CanKind {
    /// Every kind, in declaration order.
    pub const ALL: [Self; 6] = [
        Self::Ego,
        Self::Occupant,
        Self::OccupantChanged,
        Self::Corrupt,
        Self::Foreign,
        Self::V2x,
    ];
}

/// One point of the search space (see the module docs). Every field is clamped to its
/// range by [`CycleCase::clamped`], so any value read from a file is a valid case.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CycleCase {
    /// Closing speed at contact, m/s (5..=45).
    pub closing_speed_mps: f64,
    /// Closing acceleration of the approach, m/s² (−12..=2).
    pub closing_accel_mps2: f64,
    /// Opponent mass, kg (500..=4000).
    pub opponent_mass_kg: f64,
    /// Reported mass σ, kg (0..=1000).
    pub mass_sigma_kg: f64,
    /// True contact relative to the measured cycle, ms (−40..=700: negative = contact was
    /// that long before the measured cycle).
    pub contact_in_ms: f64,
    /// How long the object has been tracked before the measured cycle, ms (10..=1000).
    pub tracked_ms: f64,
    /// Object list period, ms (5..=40).
    pub object_period_ms: u32,
    /// Object measurement latency, ms (0..=60).
    pub latency_ms: u32,
    /// Sample noise scale (0..=1): 0.3 m distance, 0.5 m/s speed, 2 m/s² acceleration at 1.
    pub noise: f64,
    /// Seed of the noise.
    pub noise_seed: u64,
    /// Track confidence of the samples (0..=1).
    pub confidence: f64,
    /// Ego speed on CAN, m/s (0..=60).
    pub ego_speed_mps: f64,
    /// Occupant mass, kg (30..=150).
    pub occupant_mass_kg: f64,
    /// Chest to wheel, mm (150..=500).
    pub chest_mm: f64,
    /// Belt buckled.
    pub buckled: bool,
    /// An adult occupant (else a child seat).
    pub adult: bool,
    /// Crash pulse after contact, g (0..=60; 0 = none).
    pub crash_decel_g: f64,
    /// Accelerometer rate, Hz (1000..=8000).
    pub accel_rate_hz: f64,
    /// SecOC sender set (the shipped example keys).
    pub secoc: bool,
    /// The default table loaded (else: DEGRADED on the reference restraint).
    pub lut: bool,
    /// A V2X station that is the tracked object reports every 100 ms of the prefix (absent in
    /// a case file: none, as before the second mass source).
    #[serde(default)]
    pub v2x: bool,
    /// Object samples of the measured cycle (at most 2).
    pub objects: Vec<ObjectKind>,
    /// CAN frames of the measured cycle: at most one EgoVehicleState, one
    /// OccupantClassification, one V2xOpponentMass and one rejected or foreign frame.
    pub can: Vec<CanKind>,
    /// Accelerometer batches of the measured cycle (0..=2).
    pub accel_batches: u32,
    /// Late start of the measured cycle, µs (0..=900).
    pub late_us: u32,
    /// Overruns reported so far (0..=3).
    pub overruns: u32,
}

impl CycleCase {
    /// The hand-picked worst case of `ecu_cycle::WorstCasePreCrash`, as a case: steady
    /// PRE-CRASH 250 ms before contact, a new object sample in the measured cycle.
    pub fn hand_picked() -> Self {
        Self {
            closing_speed_mps: 24.5,
            closing_accel_mps2: -2.0,
            opponent_mass_kg: 1500.0,
            mass_sigma_kg: 150.0,
            contact_in_ms: 250.0,
            tracked_ms: 50.0,
            object_period_ms: 5,
            latency_ms: 0,
            noise: 0.0,
            noise_seed: 0,
            confidence: 0.9,
            ego_speed_mps: 15.0,
            occupant_mass_kg: 80.0,
            chest_mm: 310.0,
            buckled: true,
            adult: true,
            crash_decel_g: 0.0,
            accel_rate_hz: 8000.0,
            secoc: false,
            lut: true,
            v2x: false,
            objects: vec![ObjectKind::OnTrack],
            can: vec![],
            accel_batches: 0,
            late_us: 0,
            overruns: 0,
        }
    }

    /// The case with every field in its range (NaN → the range's lower end), numbers on a
    /// 0.001 grid (a case file reads back bit for bit, and stays readable).
    pub fn clamped(mut self) -> Self {
        let c = |v: f64, lo: f64, hi: f64| {
            let v = if v.is_nan() { lo } else { v.clamp(lo, hi) };
            (v * 1000.0).round() / 1000.0
        };
        self.closing_speed_mps = c(self.closing_speed_mps, 5.0, 45.0);
        self.closing_accel_mps2 = c(self.closing_accel_mps2, -12.0, 2.0);
        self.opponent_mass_kg = c(self.opponent_mass_kg, 500.0, 4000.0);
        self.mass_sigma_kg = c(self.mass_sigma_kg, 0.0, 1000.0);
        self.contact_in_ms = c(self.contact_in_ms, -40.0, 700.0);
        self.tracked_ms = c(self.tracked_ms, 10.0, 1000.0);
        self.object_period_ms = self.object_period_ms.clamp(5, 40);
        self.latency_ms = self.latency_ms.min(60);
        self.noise = c(self.noise, 0.0, 1.0);
        self.confidence = c(self.confidence, 0.0, 1.0);
        self.ego_speed_mps = c(self.ego_speed_mps, 0.0, 60.0);
        self.occupant_mass_kg = c(self.occupant_mass_kg, 30.0, 150.0);
        self.chest_mm = c(self.chest_mm, 150.0, 500.0);
        self.crash_decel_g = c(self.crash_decel_g, 0.0, 60.0);
        self.accel_rate_hz = c(self.accel_rate_hz, 1000.0, 8000.0);
        self.objects.truncate(2);
        // One frame per message and cycle (their DBC periods are 10 and 100 ms), plus one
        // frame the ECU rejects or ignores.
        let class = |k: &CanKind| match k {
            CanKind::Ego => 0,
            CanKind::Occupant | CanKind::OccupantChanged => 1,
            CanKind::Corrupt | CanKind::Foreign => 2,
            CanKind::V2x => 3,
        };
        let mut seen = [false; 4];
        self.can
            .retain(|k| !std::mem::replace(&mut seen[class(k)], true));
        self.accel_batches = self.accel_batches.min(2);
        self.late_us = self.late_us.min(900);
        self.overruns = self.overruns.min(3);
        self
    }

    /// Closing speed at `t_ns` (constant closing acceleration towards the contact).
    fn speed_at(&self, t_ns: u64, contact_ns: u64) -> f64 {
        let to_contact_s = (contact_ns as f64 - t_ns as f64) * 1e-9;
        (self.closing_speed_mps - self.closing_accel_mps2 * to_contact_s).max(0.5)
    }

    /// Distance at `t_ns` (the integral of the closing speed up to contact; ≤ 0 after it).
    fn distance_at(&self, t_ns: u64, contact_ns: u64) -> f64 {
        let s = (contact_ns as f64 - t_ns as f64) * 1e-9;
        self.closing_speed_mps * s - 0.5 * self.closing_accel_mps2 * s * s
    }
}

/// Reads a case file: one JSON case or a list of them, each clamped.
///
/// # Errors
/// I/O or syntax errors, naming the file.
pub fn load_cases(path: &Path) -> anyhow::Result<Vec<CycleCase>> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
    let v: serde_json::Value =
        serde_json::from_str(&text).with_context(|| format!("{}: not JSON", path.display()))?;
    let list = match v {
        serde_json::Value::Array(a) => a,
        one => vec![one],
    };
    list.into_iter()
        .map(|c| {
            let c: CycleCase = serde_json::from_value(c)
                .with_context(|| format!("{}: not a cycle case", path.display()))?;
            Ok(c.clamped())
        })
        .collect()
}

/// The committed seed of the gate's worst-case row (SecOC off), `benches/worst-case/seed.json`.
pub fn seed_path() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("worst-case/seed.json")
}

/// The shipped table, loaded once per process.
fn default_table() -> anyhow::Result<&'static Diagram> {
    static TABLE: std::sync::OnceLock<Diagram> = std::sync::OnceLock::new();
    if let Some(t) = TABLE.get() {
        return Ok(t);
    }
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../data/default.lut");
    let d = Diagram::load(path).map_err(|e| anyhow::anyhow!("{path}: {e}"))?;
    Ok(TABLE.get_or_init(|| d))
}

/// The shipped example SecOC keys.
fn secoc_tx() -> anyhow::Result<bus::secoc::SecOcTx> {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../data/secoc-keys.example.toml"
    );
    Ok(bus::secoc::SecOcKeys::load(Path::new(path))
        .map_err(|e| anyhow::anyhow!("{path}: {e}"))?
        .tx())
}

/// A cycle about to run the measured step of a case (`Clone`: a bench replays it).
#[derive(Clone)]
pub struct Prepared {
    /// The cycle.
    pub ecu: RestraintCycle<'static>,
    /// Its I/O with the measured cycle's inputs queued.
    pub io: SimIo,
    /// The measured cycle's timing.
    pub info: CycleInfo,
}

/// What the measured cycle did (for reports and for checking that a seed still takes the
/// path it was found on).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct PathSummary {
    /// Phase before and after the measured cycle.
    pub phase_before: &'static str,
    /// Phase after it.
    pub phase_after: &'static str,
    /// Collision predictions it made.
    pub predictions: u64,
    /// LUT lookups it made.
    pub lookups: u64,
    /// Track filter events (starts, outliers, refusals).
    pub track_events: u64,
    /// CAN frames it sent.
    pub frames_sent: u64,
    /// A crash event was under way before or after it (accelerometer event in progress,
    /// CRASH, POST-CRASH): a crash cycle, with its own budget.
    pub crash_event: bool,
}

fn phase_name(p: Phase) -> &'static str {
    match p {
        Phase::Monitoring => "monitoring",
        Phase::PreCrash => "pre-crash",
        Phase::Degraded => "degraded",
        Phase::Crash => "crash",
        Phase::PostCrash => "post-crash",
    }
}

/// The scenario's input generator (prefix and measured cycle share it).
struct Feed<'c> {
    case: &'c CycleCase,
    contact_ns: u64,
    rng: ChaCha8Rng,
    tx: E2eProtector,
    next_object_ns: u64,
    last_meas_ns: u64,
    sequence: u64,
    accel_next_ns: u64,
    accel_sequence: u64,
}

impl Feed<'_> {
    fn object(&mut self, t_meas: u64) -> ObjectState {
        let c = self.case;
        let n = c.noise;
        let mut g = || {
            let u1: f64 = self.rng.gen_range(f64::MIN_POSITIVE..1.0);
            let u2: f64 = self.rng.gen();
            (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
        };
        let (gd, gv, ga) = (g(), g(), g());
        self.sequence += 1;
        self.last_meas_ns = t_meas;
        ObjectState {
            timestamp_ns: t_meas,
            sequence: self.sequence,
            distance_m: (self.case.distance_at(t_meas, self.contact_ns) + 0.3 * n * gd) as f32,
            closing_speed_mps: (c.speed_at(t_meas, self.contact_ns) + 0.5 * n * gv) as f32,
            relative_accel_mps2: (c.closing_accel_mps2 + 2.0 * n * ga) as f32,
            opponent_mass_kg: c.opponent_mass_kg as f32,
            opponent_mass_sigma_kg: c.mass_sigma_kg as f32,
            confidence: c.confidence as f32,
            object_id: 7,
            valid: VALID,
            _reserved: [0; 3],
        }
    }

    fn ego_frame(&mut self) -> anyhow::Result<RawFrame> {
        let m = bus::EgoVehicleState::encode(
            EgoVehicleStateBrakeState::Released,
            self.case.ego_speed_mps as f32,
            0.0,
        )
        .map_err(|e| anyhow::anyhow!("ego frame: {e:?}"))?;
        Ok(self.tx.seal(m))
    }

    fn occupant_frame(&mut self, extra_kg: f64) -> anyhow::Result<RawFrame> {
        let c = self.case;
        let m = bus::OccupantClassification::encode(
            if c.buckled {
                OccupantClassificationBeltBuckle::Buckled
            } else {
                OccupantClassificationBeltBuckle::Unbuckled
            },
            if c.adult {
                OccupantClassificationOccupantClass::MidAdult
            } else {
                OccupantClassificationOccupantClass::ChildSeat
            },
            90,
            (c.occupant_mass_kg + extra_kg) as f32,
            c.chest_mm.round() as u16,
            150,
        )
        .map_err(|e| anyhow::anyhow!("occupant frame: {e:?}"))?;
        Ok(self.tx.seal(m))
    }

    /// The V2X station's frame at `now`: the tracked object's range and closing speed, its
    /// mass (σ 100 kg).
    fn v2x_frame(&mut self, now: u64) -> anyhow::Result<RawFrame> {
        let c = self.case;
        let m = bus::V2xOpponentMass::encode(
            bus::codec::V2xOpponentMassStationStatus::Valid,
            c.opponent_mass_kg as f32,
            100.0,
            c.distance_at(now, self.contact_ns).clamp(0.0, 400.0) as f32,
            c.speed_at(now, self.contact_ns).clamp(-100.0, 100.0) as f32,
        )
        .map_err(|e| anyhow::anyhow!("V2X frame: {e:?}"))?;
        Ok(self.tx.seal(m))
    }

    /// The accelerometer batch of the millisecond starting at `t_ns`: the crash pulse after
    /// contact, before it a live sensor's quiet reading (±0.05 m/s² alternating: the ECU flags
    /// bit-identical readings as a stuck sensor).
    fn accel(&mut self, t_ns: u64) -> CrashAccelSample {
        let c = self.case;
        let per_ms = ((c.accel_rate_hz / 1000.0).round() as u32).clamp(1, 8);
        let period = (1_000_000 / per_ms).max(1);
        let first = self.accel_next_ns.max(t_ns.saturating_sub(MS));
        self.accel_next_ns = first + u64::from(per_ms) * u64::from(period);
        self.accel_sequence += 1;
        let mut a = CrashAccelSample::EMPTY;
        a.first_timestamp_ns = first;
        a.sequence = self.accel_sequence;
        a.sample_period_ns = period;
        a.count = per_ms;
        for (k, s) in a.accel_mps2.iter_mut().take(per_ms as usize).enumerate() {
            let t = first + k as u64 * u64::from(period);
            *s = if t >= self.contact_ns {
                (-c.crash_decel_g * G) as f32
            } else if (self.accel_sequence * u64::from(per_ms) + k as u64).is_multiple_of(2) {
                0.05
            } else {
                -0.05
            };
        }
        a
    }

    /// Everything that arrives in the prefix cycle at `now`.
    fn prefix_inputs(&mut self, now: u64, start: u64, io: &mut SimIo) -> anyhow::Result<()> {
        let c = self.case;
        let ms = (now - start) / MS;
        if ms.is_multiple_of(10) {
            io.push_can(self.ego_frame()?);
        }
        if ms.is_multiple_of(100) {
            io.push_can(self.occupant_frame(0.0)?);
            if c.v2x {
                io.push_can(self.v2x_frame(now)?);
            }
        }
        let track_from = T_MEASURED.saturating_sub((c.tracked_ms * 1e6) as u64);
        let latency = u64::from(c.latency_ms) * MS;
        if now >= track_from.saturating_add(latency) && now >= self.next_object_ns {
            self.next_object_ns = now + u64::from(c.object_period_ms) * MS;
            let t_meas = now - latency;
            let o = if t_meas < self.contact_ns {
                self.object(t_meas)
            } else {
                // After contact the tracker loses the object at the bumper.
                let mut o = ObjectState::INVALID;
                o.timestamp_ns = t_meas;
                o
            };
            io.push_object(o);
        }
        // A live accelerometer every ms (a silent one is a fault the ECU degrades on).
        io.push_both_accel(self.accel(now));
        Ok(())
    }

    /// The measured cycle's own inputs.
    fn measured_inputs(&mut self, now: u64, io: &mut SimIo) -> anyhow::Result<()> {
        let c = self.case;
        let t_meas = now - u64::from(c.latency_ms) * MS;
        for kind in &c.objects {
            let mut o = self.object(t_meas.max(self.last_meas_ns + 1));
            match kind {
                ObjectKind::OnTrack => {}
                ObjectKind::Outlier => {
                    o.distance_m -= 5.0;
                    o.closing_speed_mps += 8.0;
                }
                ObjectKind::OutOfOrder => {
                    o = self.object(self.last_meas_ns.saturating_sub(5 * MS));
                }
                ObjectKind::NonFinite => o.distance_m = f32::NAN,
                ObjectKind::NewObject => o.object_id = 9,
                ObjectKind::NoObject => {
                    o = ObjectState::INVALID;
                    o.timestamp_ns = t_meas;
                }
                ObjectKind::LowConfidence => o.confidence = 0.1,
            }
            io.push_object(o);
        }
        for kind in &c.can {
            let f = match kind {
                CanKind::Ego => self.ego_frame()?,
                CanKind::Occupant => self.occupant_frame(0.0)?,
                CanKind::OccupantChanged => self.occupant_frame(10.0)?,
                CanKind::Corrupt => {
                    let mut f = self.occupant_frame(0.0)?;
                    f.data[0] ^= 0x5a;
                    f
                }
                CanKind::Foreign => RawFrame::new(0x123, &[1, 2, 3, 4, 5, 6, 7, 8]),
                CanKind::V2x => self.v2x_frame(now)?,
            };
            io.push_can(f);
        }
        for _ in 0..c.accel_batches {
            io.push_both_accel(self.accel(now));
        }
        Ok(())
    }
}

/// Synchronized time at simulated time 0 (`host::SimClock::SYNC_EPOCH_US`): SecOC freshness
/// values of a plausible date.
const SYNC_EPOCH_US: u64 = 1_750_000_000_000_000;

/// Runs the case's prefix through a fresh cycle and queues the measured cycle's inputs.
///
/// # Errors
/// Set-up failures (table, keys, frame encoding): a bench bug, not a case property.
pub fn prepare(case: &CycleCase) -> anyhow::Result<Prepared> {
    let case = case.clone().clamped();
    let lut = if case.lut {
        let d = default_table()?;
        Some(restraint::Lut {
            view: d.view(),
            id: d.lut_id(),
            ego_mass_kg: d.header().ego.mass_kg,
            ego_class: d.header().ego.class,
            // An unreadable span: NaN, which the core rejects.
            lighter_opponent_kg: d
                .header()
                .lighter_opponent_span_kg()
                .map_or(Some(f32::NAN), |s| s.map(|kg| kg as f32)),
        })
    } else {
        None
    };
    let (mut ecu, _) = RestraintCycle::new(CycleConfig::default(), lut, &REFERENCE)
        .map_err(|e| anyhow::anyhow!("RestraintCycle::new: {e}"))?;
    if case.secoc {
        ecu.set_secoc(Some(secoc_tx()?));
    }
    let contact_ns = T_MEASURED.saturating_add_signed((case.contact_in_ms * 1e6) as i64);
    let mut feed = Feed {
        case: &case,
        contact_ns,
        rng: ChaCha8Rng::seed_from_u64(case.noise_seed),
        tx: E2eProtector::new(),
        next_object_ns: 0,
        last_meas_ns: 0,
        sequence: 0,
        accel_next_ns: 0,
        accel_sequence: 0,
    };
    let start = T_MEASURED - (case.tracked_ms.ceil() as u64 + 200) * MS;
    let mut io = SimIo::new();
    let mut clock = SimLoop::new(start, MS).with_sync_epoch_us(SYNC_EPOCH_US);
    while clock.now_ns() < T_MEASURED {
        feed.prefix_inputs(clock.now_ns(), start, &mut io)?;
        clock.step(&mut ecu, &mut io);
        io.can_tx.clear();
    }
    let now = clock.now_ns();
    feed.measured_inputs(now, &mut io)?;
    let late = u64::from(case.late_us) * 1_000;
    let info = CycleInfo {
        deadline_ns: now - late,
        wake_latency_ns: late,
        overruns: u64::from(case.overruns),
        ..clock.next_info()
    };
    Ok(Prepared { ecu, io, info })
}

/// The measured cycle: exactly one `RestraintCycle::step`. Never inlined, so that callgrind
/// can count it alone (`--toggle-collect=*measured_step*`).
#[inline(never)]
pub fn measured_step(p: &mut Prepared) {
    p.ecu.step(std::hint::black_box(&p.info), &mut p.io);
}

/// Prepares `case`, runs the measured cycle and reports its path.
///
/// # Errors
/// See [`prepare`].
pub fn run(case: &CycleCase) -> anyhow::Result<PathSummary> {
    let mut p = prepare(case)?;
    let before = (p.ecu.phase(), p.ecu.counters(), p.io.can_tx_total);
    let event_before = p.ecu.crash_event();
    measured_step(&mut p);
    let c = p.ecu.counters();
    let track = |c: &restraint::CycleCounters| c.track_starts + c.track_outliers + c.track_refused;
    Ok(PathSummary {
        phase_before: phase_name(before.0),
        phase_after: phase_name(p.ecu.phase()),
        predictions: c.predictions - before.1.predictions,
        lookups: c.lut_lookups - before.1.lut_lookups,
        track_events: track(&c) - track(&before.1),
        frames_sent: p.io.can_tx_total - before.2,
        crash_event: event_before || p.ecu.crash_event(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hand_picked_case_looks_up_in_precrash_and_predicts_in_the_next_cycle() {
        let s = run(&CycleCase::hand_picked()).unwrap();
        assert_eq!((s.phase_before, s.phase_after), ("pre-crash", "pre-crash"));
        assert_eq!((s.predictions, s.lookups), (0, 1));
        // The last prefix cycle had a sample (51 ms tracked, every 5 ms): the measured cycle
        // without one solves its prediction.
        let c = CycleCase {
            objects: vec![],
            tracked_ms: 51.0,
            ..CycleCase::hand_picked()
        };
        assert_eq!(run(&c).unwrap().predictions, 1);
    }

    #[test]
    fn a_crash_case_confirms_in_the_measured_cycle() {
        // Contact 6 ms before the measured cycle at 40 g and 8 kHz: confirmation needs
        // 0.5 m/s — reached within the measured cycle's batch or before it.
        let c = CycleCase {
            contact_in_ms: -3.0,
            crash_decel_g: 20.0,
            accel_batches: 1,
            ..CycleCase::hand_picked()
        };
        let s = run(&c).unwrap();
        assert_eq!(s.phase_before, "pre-crash");
        assert!(matches!(s.phase_after, "crash" | "post-crash"), "{s:?}");
    }
}
