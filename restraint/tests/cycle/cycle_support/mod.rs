//! Shared helpers of the cycle tests: a small LUT with LINEAR cells (multilinear
//! interpolation reproduces a linear function exactly, so the expected settings are closed
//! form), a test reference restraint, E2E-sealed input frames and a 1 kHz simulated bench.
#![allow(dead_code)]

use bus::codec::{
    EgoVehicleStateBrakeState, OccupantClassificationBeltBuckle,
    OccupantClassificationOccupantClass,
};
use bus::RawFrame;
use bus::{E2eProtector, EgoVehicleState, OccupantClassification};
use diagram::{AirbagThresholds, Axes, BuildInfo, Cell, Diagram, EgoVehicle, Header};
use restraint::{
    Activity, CrashAccelSample, CycleConfig, CycleInfo, EcuDiagnostics, EcuMode, Lut, ObjectState,
    ReferenceSettings, RestraintCycle, SimIo, VALID,
};

pub const MS: u64 = 1_000_000;

/// Linear cell functions of (closing speed km/h, opponent kg): the oracle.
pub fn belt_kn(v_kph: f64, m_kg: f64) -> f64 {
    0.001 * m_kg + 0.05 * v_kph
}
pub fn airbag_kn(_v_kph: f64, m_kg: f64) -> f64 {
    0.002 * m_kg
}
pub fn pret_ms(v_kph: f64, _m_kg: f64) -> f64 {
    -0.5 * v_kph
}
pub fn airbag_ms(v_kph: f64, _m_kg: f64) -> f64 {
    5.0 + 0.1 * v_kph
}

pub fn test_lut() -> Diagram {
    let header = Header {
        ego: EgoVehicle {
            mass_kg: 1785.0,
            class: 4,
            description: "test".into(),
        },
        build: BuildInfo::default(),
        airbag_thresholds: AirbagThresholds::DEFAULT,
    };
    let axes = Axes::new(
        vec![40.0, 70.0, 108.0],
        vec![800.0, 1500.0, 3000.0],
        vec![30.0, 75.0, 125.0],
        vec![200.0, 300.0, 450.0],
    );
    Diagram::from_fn(header, axes, |p| {
        let v = f64::from(p.query.closing_speed_kph);
        let m = f64::from(p.query.opponent_mass_kg);
        Cell {
            belt_limiter_kn: belt_kn(v, m) as f32,
            airbag_level_kn: airbag_kn(v, m) as f32,
            pretensioner_time_ms: pret_ms(v, m) as f32,
            airbag_time_ms: airbag_ms(v, m) as f32,
            a_max_g: 30.0,
            a_mean_g: 20.0,
            excursion_mm: 150.0,
            bottoming_out: 0.0,
            a_ideal_g: 15.0,
        }
    })
    .expect("test LUT is valid")
}

/// The reference restraint of the tests (conventional: both fire 10 ms after contact).
pub const REFERENCE: ReferenceSettings = ReferenceSettings {
    belt_limiter_kn: 8.5,
    airbag_level_kn: 12.0,
    pretensioner_time_ms: 10.0,
    airbag_time_ms: 10.0,
};

/// The core's view of an owned test table (the shell's `ecu::lut_input` does the same).
pub fn lut_of(d: &Diagram) -> Lut<'_> {
    Lut {
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

/// Simulated bench at 1 kHz with scripted CAN inputs and a live crash accelerometer: every
/// step delivers one 1 kHz sample stamped on the 1 ms grid, 0 m/s² (or what [`Bench::push_accel`]
/// scheduled for that step) with a ±0.05 m/s² alternating dither — a real sensor's reading is
/// never bit-identical for long, and the ECU flags one that is as stuck.
pub struct Bench {
    pub ecu: RestraintCycle<'static>,
    pub io: SimIo,
    pub now: u64,
    pub cycle: u64,
    pub tx: E2eProtector,
    pub send_vehicle: bool,
    pub send_occupant: bool,
    pub occupant_mass_kg: f32,
    pub chest_mm: u16,
    pub buckle: OccupantClassificationBeltBuckle,
    /// (cycle index, now) of every step, aligned with `diagnostics`.
    pub step_times: Vec<u64>,
    /// The diagnostics record of every step.
    pub diagnostics: Vec<EcuDiagnostics>,
    /// (send time, frame) of every frame sent.
    pub sent: Vec<(u64, RawFrame)>,
    /// Deadline of the next step (`None`: the step's `now`, an on-time cycle).
    pub deadline: Option<u64>,
    /// The accelerometer delivers a sample every step (false: silent, a dead sensor).
    pub accel_live: bool,
    /// The ±0.05 m/s² dither of a live sensor (false: the bit-identical readings of a stuck one).
    pub accel_dither: bool,
    /// `EgoLongAccel` of the vehicle frames, m/s² (the vehicle-dynamics sensor).
    pub ego_long_accel_mps2: f32,
    /// The vehicle frames' brake state says ABS braking (else released).
    pub abs_braking: bool,
    /// The reading of the next step's sample, m/s² (taken by the step; then 0 again).
    pending_accel_mps2: Option<f32>,
    /// The safing accelerometer delivers a sample every step (false: a dead safing sensor).
    pub safing_live: bool,
    /// The ego speed the vehicle frame reports, m/s.
    pub ego_speed_mps: f32,
    /// A fault of one sensor for the next step: the crash (`.0`) or the safing (`.1`)
    /// accelerometer reads this instead of the mechanical acceleration, m/s².
    pending_fault_mps2: (Option<f32>, Option<f32>),
}

pub const T0: u64 = 10_000 * MS;

/// Synchronized time at simulated time 0, µs (the shell's `host::SimClock::SYNC_EPOCH_US`:
/// 2025-06-15 15:06:40 UTC, a plausible wall-clock value).
pub const SYNC_EPOCH_US: u64 = 1_750_000_000_000_000;

/// The synchronized time (µs) the bench hands the cycle at monotonic `now_ns`, as the
/// simulated clock defines it.
pub fn sync_time_us(now_ns: u64) -> u64 {
    SYNC_EPOCH_US + now_ns / 1_000
}

/// The default configuration with the track filter's two σ-dependent knobs neutral, for
/// closed-form decision oracles: the contact instant is planned at the estimate itself
/// (`contact_time_k = 0`) and the fused mass σ of equal reported σs is that σ
/// (`mass_sigma_correlation = 1`), so the conservative mass is m + σ. The filter of
/// noise-free samples on the motion model's own trajectory (constant closing acceleration)
/// reproduces them exactly — every innovation is zero — so the estimate is the closed form.
/// The knobs themselves are tested in `cycle/estimate.rs` and the filter's unit tests.
/// The benches' accelerometer samples are ideal (no anti-alias filter), so their onset is
/// the contact: `accel_delay_ms = 0` (`ideal_sensor_config`).
pub fn oracle_config() -> CycleConfig {
    let mut cfg = ideal_sensor_config();
    cfg.track.contact_time_k = 0.0;
    cfg.track.mass_sigma_correlation = 1.0;
    cfg
}

/// The default configuration for a sensor without anti-alias filter: the samples these
/// benches push are the pulse itself at their instants, so no filter delay is to be taken
/// off the measured onset (`accel_delay_ms = 0`).
pub fn ideal_sensor_config() -> CycleConfig {
    CycleConfig {
        accel_delay_ms: 0.0,
        ..CycleConfig::default()
    }
}

impl Bench {
    pub fn new(lut: Option<Diagram>) -> Self {
        Self::with_config(ideal_sensor_config(), lut)
    }

    /// A bench with [`oracle_config`].
    pub fn oracle(lut: Option<Diagram>) -> Self {
        Self::with_config(oracle_config(), lut)
    }

    /// `lut` is leaked to `'static`: a bench lives for one test, and the cycle borrows its
    /// table as the shell's does.
    pub fn with_config(cfg: CycleConfig, lut: Option<Diagram>) -> Self {
        let lut: Option<&'static Diagram> = lut.map(|d| &*Box::leak(Box::new(d)));
        let (ecu, _) = RestraintCycle::new(cfg, lut.map(lut_of), &REFERENCE).expect("valid config");
        Self {
            ecu,
            io: SimIo::new(),
            now: T0,
            cycle: 0,
            tx: E2eProtector::new(),
            send_vehicle: true,
            send_occupant: true,
            occupant_mass_kg: 75.0,
            chest_mm: 300,
            buckle: OccupantClassificationBeltBuckle::Buckled,
            step_times: Vec::new(),
            diagnostics: Vec::new(),
            sent: Vec::new(),
            deadline: None,
            accel_live: true,
            accel_dither: true,
            ego_long_accel_mps2: 0.0,
            abs_braking: false,
            pending_accel_mps2: None,
            safing_live: true,
            ego_speed_mps: 15.0,
            pending_fault_mps2: (None, None),
        }
    }

    pub fn vehicle_frame(&mut self, speed_mps: f32) -> RawFrame {
        let brake = if self.abs_braking {
            EgoVehicleStateBrakeState::AbsActive
        } else {
            EgoVehicleStateBrakeState::Released
        };
        let m = EgoVehicleState::encode(brake, speed_mps, self.ego_long_accel_mps2).unwrap();
        self.tx.seal(m)
    }

    pub fn occupant_frame(&mut self) -> RawFrame {
        let m = OccupantClassification::encode(
            self.buckle,
            OccupantClassificationOccupantClass::MidAdult,
            90,
            self.occupant_mass_kg,
            self.chest_mm,
            150,
        )
        .unwrap();
        self.tx.seal(m)
    }

    /// One 1 ms cycle; CAN inputs at their DBC rates (10 ms / 100 ms).
    pub fn step(&mut self) {
        let ms = (self.now - T0) / MS;
        if self.send_vehicle && ms.is_multiple_of(10) {
            let f = self.vehicle_frame(self.ego_speed_mps);
            self.io.push_can(f);
        }
        if self.send_occupant && ms.is_multiple_of(100) {
            let f = self.occupant_frame();
            self.io.push_can(f);
        }
        let reading = self.pending_accel_mps2.take().unwrap_or(0.0);
        let (crash_fault, safing_fault) = core::mem::take(&mut self.pending_fault_mps2);
        if self.accel_live {
            let dither = match (self.accel_dither, ms.is_multiple_of(2)) {
                (false, _) => 0.0,
                (true, true) => 0.05,
                (true, false) => -0.05,
            };
            self.io.push_accel(accel_batch(
                T0 + ms * MS,
                crash_fault.unwrap_or(reading + dither),
            ));
        }
        if self.safing_live {
            // The second sensor sees the same car with its own (opposite-phase) dither.
            let dither = if ms.is_multiple_of(2) { -0.07 } else { 0.07 };
            self.io.push_safing(accel_batch(
                T0 + ms * MS,
                safing_fault.unwrap_or(reading + dither),
            ));
        }
        let info = CycleInfo {
            deadline_ns: self.deadline.take().unwrap_or(self.now),
            ..CycleInfo::on_time(self.cycle, MS, self.now).with_sync_time_us(sync_time_us(self.now))
        };
        let before = self.io.can_tx_total;
        self.ecu.step(&info, &mut self.io);
        for f in self.io.sent_since(before) {
            self.sent.push((self.now, *f));
        }
        self.diagnostics.push(self.io.diagnostics);
        self.step_times.push(self.now);
        self.now += MS;
        self.cycle += 1;
    }

    pub fn run_ms(&mut self, n: u64) {
        for _ in 0..n {
            self.step();
        }
    }

    /// Runs until `t` (exclusive).
    pub fn run_until(&mut self, t: u64) {
        while self.now < t {
            self.step();
        }
    }

    /// Pushes an object measured now on a straight constant-speed approach that reaches us
    /// at `contact_ns`.
    pub fn push_approach(&mut self, contact_ns: u64, closing_mps: f32, opp_kg: f32, sigma_kg: f32) {
        let ttc_s = (contact_ns as f64 - self.now as f64) * 1e-9;
        let mut o = object(self.now, closing_mps, opp_kg, sigma_kg);
        o.distance_m = (ttc_s * f64::from(closing_mps)) as f32;
        self.io.push_object(o);
    }

    /// The car undergoes `accel_mps2` (negative = deceleration) in the next step: both the
    /// crash and the safing accelerometer read it.
    pub fn push_accel(&mut self, accel_mps2: f32) {
        self.pending_accel_mps2 = Some(accel_mps2);
    }

    /// A fault of the crash accelerometer alone: it reads `accel_mps2` in the next step.
    pub fn push_crash_sensor_fault(&mut self, accel_mps2: f32) {
        self.pending_fault_mps2.0 = Some(accel_mps2);
    }

    /// A fault of the safing accelerometer alone: it reads `accel_mps2` in the next step.
    pub fn push_safing_sensor_fault(&mut self, accel_mps2: f32) {
        self.pending_fault_mps2.1 = Some(accel_mps2);
    }

    pub fn decoded(&self) -> Vec<(u64, bus::Messages)> {
        self.sent
            .iter()
            .map(|(t, f)| {
                (
                    *t,
                    bus::decode(f.id, f.payload()).expect("ECU frames decode"),
                )
            })
            .collect()
    }

    pub fn belt_frames(&self) -> Vec<(u64, bus::BeltLimiterCmd)> {
        self.decoded()
            .into_iter()
            .filter_map(|(t, m)| match m {
                bus::Messages::BeltLimiterCmd(b) => Some((t, b)),
                _ => None,
            })
            .collect()
    }

    pub fn airbag_frames(&self) -> Vec<(u64, bus::AirbagStageCmd)> {
        self.decoded()
            .into_iter()
            .filter_map(|(t, m)| match m {
                bus::Messages::AirbagStageCmd(b) => Some((t, b)),
                _ => None,
            })
            .collect()
    }

    /// The reports' counter `name` (`Activity::report_counters`).
    pub fn counter(&self, name: &str) -> u64 {
        use restraint::Activity;
        let mut v = None;
        self.ecu.report_counters(&mut |n, x| {
            if n == name {
                v = Some(x);
            }
        });
        v.unwrap_or_else(|| panic!("no counter {name}"))
    }

    /// The first AirbagStageCmd that fires, with its time.
    pub fn first_airbag_fire(&self) -> Option<(u64, bus::AirbagStageCmd)> {
        self.airbag_frames()
            .into_iter()
            .find(|(_, f)| f.fire() == bus::codec::AirbagStageCmdFire::Fire)
    }

    /// The first BeltLimiterCmd that fires the pretensioner, with its time.
    pub fn first_pretensioner_fire(&self) -> Option<(u64, bus::BeltLimiterCmd)> {
        self.belt_frames()
            .into_iter()
            .find(|(_, f)| f.pretensioner_cmd() == bus::codec::BeltLimiterCmdPretensionerCmd::Fire)
    }

    pub fn status_frames(&self) -> Vec<(u64, bus::EcuStatus)> {
        self.decoded()
            .into_iter()
            .filter_map(|(t, m)| match m {
                bus::Messages::EcuStatus(b) => Some((t, b)),
                _ => None,
            })
            .collect()
    }

    /// Mode byte of the diagnostics record published at time `t`.
    pub fn mode_at(&self, t: u64) -> u8 {
        let i = self
            .step_times
            .iter()
            .position(|&x| x == t)
            .expect("step at t");
        self.diagnostics[i].mode
    }

    /// First step time at which the diagnostics mode equals `mode`.
    pub fn first_mode(&self, mode: EcuMode) -> Option<u64> {
        self.diagnostics
            .iter()
            .zip(&self.step_times)
            .find(|(d, _)| d.mode == mode as u8)
            .map(|(_, t)| *t)
    }
}

/// Quiet running until `end`: "no track" objects every 10 ms, a live accelerometer, no crash.
pub fn idle_until(b: &mut Bench, end: u64) {
    run_scenario(b, end, u64::MAX, 0, 0.0, u64::MAX, None, &|_| 0.0);
}

/// Runs until `end`: every 10 ms an object sample (approach towards `contact` from
/// `approach_from`, a "no track" sample before), stops objects at `objects_until`, and from
/// `crash_at` on the accelerometer reads `pulse_g(ms since crash_at)` g of deceleration.
#[allow(clippy::too_many_arguments)]
pub fn run_scenario(
    b: &mut Bench,
    end: u64,
    approach_from: u64,
    contact: u64,
    closing_mps: f32,
    objects_until: u64,
    crash_at: Option<u64>,
    pulse_g: &dyn Fn(u64) -> f32,
) {
    while b.now < end {
        if (b.now - T0).is_multiple_of(10 * MS) && b.now < objects_until {
            if b.now >= approach_from && b.now < contact {
                b.push_approach(contact, closing_mps, 1500.0, 100.0);
            } else {
                let mut o = ObjectState::INVALID;
                o.timestamp_ns = b.now;
                b.io.push_object(o);
            }
        }
        if let Some(c) = crash_at {
            if b.now >= c {
                b.push_accel(-pulse_g((b.now - c) / MS) * G);
            }
        }
        b.step();
    }
}

/// [`run_scenario`] for a crash no object predicts: no object track, a constant `decel_g`
/// from `crash` on, 100 ms of it.
pub fn run_unpredicted_crash(b: &mut Bench, crash: u64, decel_g: f32) {
    run_scenario(
        b,
        crash + 100 * MS,
        u64::MAX,
        0,
        0.0,
        u64::MAX,
        Some(crash),
        &|_| decel_g,
    );
}

/// When a constant `decel_g` from `crash` on has carried the airbag's severity floor
/// (`fallback_min_dv_mps`), as the ECU integrates 1 kHz samples that each count their whole
/// 1 ms: the first sample k with (k + 1) · a · 1 ms ≥ floor. The reference restraint fires in
/// that cycle when its boundary is already crossed and the safing function agrees.
pub fn floor_reached_at(crash: u64, decel_g: f64) -> u64 {
    let floor_mps = restraint::CycleConfig::default().fallback_min_dv_mps;
    let per_sample_mps = decel_g * f64::from(G) * 1e-3;
    let k = (floor_mps / per_sample_mps).ceil() as u64 - 1;
    crash + k * MS
}

/// Standard gravity as the tests type it, m/s².
pub const G: f32 = 9.806_65;

/// Series stiffness of the first loading segments of a class-4 ego (175.6 kN at 40 mm) and a
/// class-3 opponent (170.1 kN at 40 mm, the test approaches' conservative 1600 kg), N/m.
pub const K_SERIES_4_3: f64 = 1.0 / (0.040 / 175.6e3 + 0.040 / 170.1e3);

/// The onset ramp of a crash at `closing_mps` against the class-3 test opponent: deceleration
/// k·v·t / m_ego, in g, `ms` after contact (capped at 15 g, after the first knee).
pub fn ramp_g(closing_mps: f64, ms: u64) -> f32 {
    let slope_g_per_ms = K_SERIES_4_3 * closing_mps / 1785.0 * 1e-3 / f64::from(G);
    (slope_g_per_ms * ms as f64).min(15.0) as f32
}

/// A 1-sample, 1 kHz accelerometer batch measured at `t_ns`.
pub fn accel_batch(t_ns: u64, accel_mps2: f32) -> CrashAccelSample {
    let mut a = CrashAccelSample::EMPTY;
    a.first_timestamp_ns = t_ns;
    a.sample_period_ns = 1_000_000;
    a.count = 1;
    a.accel_mps2[0] = accel_mps2;
    a.sequence = t_ns / MS;
    a
}

pub fn object(now: u64, closing_mps: f32, opp_kg: f32, sigma_kg: f32) -> ObjectState {
    ObjectState {
        timestamp_ns: now,
        sequence: now / MS,
        distance_m: 50.0,
        closing_speed_mps: closing_mps,
        relative_accel_mps2: 0.0,
        opponent_mass_kg: opp_kg,
        opponent_mass_sigma_kg: sigma_kg,
        confidence: 0.95,
        object_id: 7,
        valid: VALID,
        _reserved: [0; 3],
    }
}

/// Rounds to the DBC step (0.05 kN / 0.1 ms) like the encoder does.
pub fn q(v: f64, step: f64) -> f32 {
    ((v / step).round() * step) as f32
}
