//! Calibration of the ECU's accelerometer-only airbag algorithm (`restraint::fallback`) on a
//! sweep of crashes through the model, and the check of the result (`lut study fallback`).
//!
//! **Cases.** Rigid barriers and car-to-car crashes of the default ego (1785 kg, class 4)
//! against opponents of 800–3000 kg over closing speeds, each simulated like the bench's true
//! world (two-mass model, 0.1 ms) and sampled like its crash accelerometer (4 kHz, linear
//! between the 0.1 ms points, Gaussian noise 0.5 m/s², 20 ms of quiet before the contact, the
//! contact between two samples), then fed through the ECU's own detectors: the onset and Δv
//! of [`restraint::confirm::Onset`], the generic confirmation and the
//! [`restraint::fallback::FallbackAlgorithm`]. Severity is the ego's equivalent barrier speed
//! EBS = Δv / (1 + e) (the judge's definition: v for a barrier, v/2 for equal cars).
//!
//! **Requirements** (the occupant model: 75 kg, 300 mm, belted, reference restraint):
//! * **no-fire line** — EBS below `no_fire_ebs_kph` (20 km/h, SPEC: adaptive restraints make
//!   no sense below it; the judge's reference does not fire there): the airbag must not fire
//!   — for every crash whose onset is below the line too ([`CaseSpec::no_fire`]).
//! * **must-fire line** — the lowest barrier EBS at which the belt alone (reference limiter,
//!   no airbag) lets the occupant bottom out: above it the airbag must fire.
//! * **in time** — the latest airbag time at which the reference airbag still gives no
//!   bottoming-out and a_max + a_mean within 5 % (`NO_WORSE_TOLERANCE` of the judge) of the
//!   reference's own 10 ms; the ECU fires at max(decision, onset + 10 ms).
//!
//! **Calibration** ([`derive_boundary`]): the boundary is the upper envelope of the Δv(τ)
//! curves of every no-fire case of the sweep (three noise seeds, with and without 1 g of
//! braking continuing through the crash), raised by a margin, made non-decreasing, and
//! raised where the piecewise-linear knots would dip under the envelope between them.
//! Must-fire timing is then checked against the occupant model (independent of the
//! calibration), and the no-fire side on cases between and beyond the sweep's grid and at the
//! accelerometer's lowest rate (1 kHz).

use anyhow::{Context, Result};
use physics::defaults::STANDARD_GRAVITY_MPS2 as G_MPS2;
use physics::{OccupantInput, RestraintHardware, RestraintSettings};
use rand_xoshiro::{rand_core::SeedableRng, Xoshiro256PlusPlus};
use restraint::accel::AccelSample;
use restraint::confirm::{CrashDetector, Onset, OnsetStep};
use restraint::fallback::{FallbackAlgorithm, FallbackDecision, KNOTS, KNOT_SPACING_MS, WINDOW_MS};
use restraint::CycleConfig;

use crate::scenario::{Ego, Opponent, Pulse};

/// Sensor noise of the bench's crash accelerometer (scenario default), m/s² (1σ).
pub const NOISE_MPS2: f64 = 0.5;
/// Quiet before the contact, s.
const LEAD_S: f64 = 0.020;
/// Relative tolerance of "in time" (the judge's `NO_WORSE_TOLERANCE`).
const IN_TIME_TOLERANCE: f64 = 0.05;
/// Latest airbag time searched for the in-time requirement, ms.
const LATEST_SEARCHED_MS: f64 = 60.0;

/// What the ego hits.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Family {
    /// Rigid barrier.
    Barrier,
    /// Another car of this mass (stiffness class by mass).
    Car {
        /// Opponent mass, kg.
        opponent_kg: f64,
    },
}

impl Family {
    /// Short label for tables and plots.
    pub fn label(&self) -> String {
        match self {
            Family::Barrier => "barrier".into(),
            Family::Car { opponent_kg } => format!("car {opponent_kg:.0} kg"),
        }
    }
}

/// One crash of the sweep.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CaseSpec {
    /// Opponent.
    pub family: Family,
    /// Closing speed at contact, km/h.
    pub closing_kph: f64,
}

/// How the accelerometer is simulated.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SensorSpec {
    /// Sample rate, Hz.
    pub rate_hz: f64,
    /// Noise seed.
    pub seed: u64,
    /// Deceleration added during the crash (braking that goes on), m/s².
    pub braking_mps2: f64,
}

impl SensorSpec {
    /// The bench's default sensor (4 kHz) with `seed`, no braking.
    pub fn bench(seed: u64) -> Self {
        Self {
            rate_hz: 4000.0,
            seed,
            braking_mps2: 0.0,
        }
    }
}

/// The physical requirement of one crash (occupant model).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Requirement {
    /// Ego equivalent barrier speed Δv / (1 + e), km/h.
    pub ebs_kph: f64,
    /// The belt alone (reference limiter, no airbag) lets the occupant bottom out.
    pub belt_only_bottoms_out: bool,
    /// Latest airbag time that is still in time, ms after contact (None: not even at 10 ms).
    pub latest_ms: Option<f64>,
}

/// What the ECU's detectors made of one crash.
#[derive(Debug, Clone, PartialEq)]
pub struct Measured {
    /// Onset (wake-up sample), ms after the true contact.
    pub onset_ms: Option<f64>,
    /// Generic confirmation, ms after contact.
    pub confirm_ms: Option<f64>,
    /// The algorithm's must-fire decision, ms after contact.
    pub decision_ms: Option<f64>,
    /// (τ ms after the onset, Δv m/s) of every sample of the first event up to the window.
    pub dv_curve: Vec<(f64, f64)>,
}

impl Measured {
    /// When the ECU fires the reference airbag: max(decision, confirmation, onset + t_ab,ref),
    /// ms after contact (None: not fired).
    pub fn airbag_ms(&self, reference_time_ms: f64) -> Option<f64> {
        let (d, c, o) = (self.decision_ms?, self.confirm_ms?, self.onset_ms?);
        Some(d.max(c).max(o + reference_time_ms))
    }
}

/// A simulated crash pulse (ego acceleration at 0.1 ms, from the contact) and its severity.
pub struct Crash {
    /// The case.
    pub spec: CaseSpec,
    pulse: Pulse,
}

impl Crash {
    /// Simulates `spec` (default ego).
    pub fn new(spec: CaseSpec) -> Result<Self> {
        let opponent = match spec.family {
            Family::Barrier => Opponent::Barrier,
            Family::Car { opponent_kg } => Opponent::Car {
                mass_kg: opponent_kg,
            },
        };
        let pulse = Pulse::predict(&Ego::default(), opponent, spec.closing_kph)
            .with_context(|| format!("{spec:?}"))?;
        Ok(Self { spec, pulse })
    }

    /// The predicted collision (the ego's pulse and crush).
    pub fn pulse(&self) -> &Pulse {
        &self.pulse
    }

    /// Ego equivalent barrier speed Δv / (1 + e), km/h.
    pub fn ebs_kph(&self) -> f64 {
        self.pulse.summary.vehicle.delta_v_mps * 3.6 / (1.0 + physics::defaults::RESTITUTION)
    }

    /// The crash accelerometer's samples: `LEAD_S` of quiet, then the pulse (+ braking while
    /// the car decelerates), linear between the 0.1 ms points, with noise; the contact lies
    /// 0.37 of a period after a sample (no alignment with the grid).
    pub fn samples(&self, sensor: &SensorSpec) -> (Vec<AccelSample>, u64) {
        let p = self.pulse.ego();
        let (step, accel) = (p.step_s, p.accel_mps2);
        let dt = 1.0 / sensor.rate_hz;
        let n = ((LEAD_S + accel.len() as f64 * step) / dt) as usize;
        let contact_s = LEAD_S + 0.37 * dt;
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(sensor.seed);
        let mut out = Vec::with_capacity(n);
        for k in 0..n {
            let t = k as f64 * dt;
            let tau = t - contact_s;
            let crash = if tau < 0.0 {
                0.0
            } else {
                let x = tau / step;
                let i = x as usize;
                match (accel.get(i), accel.get(i + 1)) {
                    (Some(a), Some(b)) => -(a + (b - a) * (x - i as f64)),
                    (Some(a), None) => -a,
                    _ => 0.0,
                }
            };
            let braking = if crash > 0.0 {
                sensor.braking_mps2
            } else {
                0.0
            };
            out.push(AccelSample {
                t_ns: (t * 1e9).round() as u64,
                dt_s: dt,
                decel_mps2: crash + braking + NOISE_MPS2 * crate::robustness::normal(&mut rng),
            });
        }
        (out, (contact_s * 1e9).round() as u64)
    }

    /// The requirement of this crash for the reference occupant.
    pub fn requirement(&self, reference: &RestraintSettings) -> Result<Requirement> {
        let occ = OccupantInput {
            mass_kg: 75.0,
            chest_to_wheel_m: 0.300,
            belted: true,
        };
        let hw = RestraintHardware::default();
        let pulse = self.pulse.ego();
        let run = |s: &RestraintSettings| {
            physics::simulate_occupant(&pulse, &occ, s, &hw)
                .map_err(|e| anyhow::anyhow!("occupant: {e:?}"))
        };
        let belt_only = run(&RestraintSettings {
            airbag_force_n: 0.0,
            airbag_time_s: 1.0,
            ..*reference
        })?;
        let at_ref = run(reference)?;
        let cost = |o: &physics::OccupantOutcome| o.max_decel_mps2 + o.mean_decel_mps2;
        let limit = cost(&at_ref) * (1.0 + IN_TIME_TOLERANCE);
        let mut latest_ms = None;
        if !at_ref.bottomed_out {
            let mut t_ms = reference.airbag_time_s * 1e3;
            while t_ms <= LATEST_SEARCHED_MS {
                let o = run(&RestraintSettings {
                    airbag_time_s: t_ms * 1e-3,
                    ..*reference
                })?;
                if o.bottomed_out || cost(&o) > limit {
                    break;
                }
                latest_ms = Some(t_ms);
                t_ms += 0.5;
            }
        }
        Ok(Requirement {
            ebs_kph: self.ebs_kph(),
            belt_only_bottoms_out: belt_only.bottomed_out,
            latest_ms,
        })
    }
}

/// Runs the ECU's detectors over `samples` (contact at `contact_ns`), for a belted occupant or
/// (`belted` false) one the ECU does not know to be belted: the airbag boundary is then
/// `unbelted_dv_mps`.
pub fn measure(
    cfg: &CycleConfig,
    samples: &[AccelSample],
    contact_ns: u64,
    belted: bool,
) -> Measured {
    let p = cfg.confirm_params();
    let mut onset = Onset::default();
    let mut generic = CrashDetector::default();
    let mut algo = FallbackAlgorithm::new(cfg.fallback_dv_mps, cfg.fallback_floor())
        .with_unbelted(cfg.unbelted_dv_mps);
    algo.set_belted(belted);
    let mut roughness = cfg.roughness();
    let mut curve = Vec::new();
    let mut first_event = true;
    let rel = |t: u64| (t as f64 - contact_ns as f64) * 1e-6;
    for s in samples {
        generic.push(&p, s);
        roughness.push(s.decel_mps2 * s.dt_s, s.dt_s);
        // Central-only: the study calibrates the boundary a car without satellites needs.
        let now = algo.thresholds_now(
            roughness.floor_lift_mps(),
            restraint::satellites::Relief::NONE,
        );
        algo.push(&p, s, &now);
        match onset.push(&p, s) {
            OnsetStep::Reset => first_event = false,
            OnsetStep::Woke | OnsetStep::Awake if first_event => {
                if let Some(o) = onset.onset_ns() {
                    let tau = (s.t_ns - o) as f64 * 1e-6;
                    if tau <= WINDOW_MS {
                        curve.push((tau, onset.delta_v_mps()));
                    }
                }
            }
            _ => {}
        }
    }
    Measured {
        onset_ms: generic.onset_ns().map(rel),
        confirm_ms: generic.confirmed_at_ns().map(rel),
        decision_ms: match algo.decision() {
            FallbackDecision::Fire { at_ns, .. } => Some(rel(at_ns)),
            _ => None,
        },
        dv_curve: curve,
    }
}

/// The boundary (knots at 0, 4, … 40 ms) over the Δv(τ) curves of the no-fire cases: their
/// upper envelope × (1 + `margin`) (+ `floor_mps` at τ = 0), non-decreasing, raised until the
/// linear interpolation between knots never dips under the envelope (checked every 0.1 ms).
pub fn derive_boundary(curves: &[Vec<(f64, f64)>], margin: f64, floor_mps: f64) -> [f64; KNOTS] {
    const FINE_PER_KNOT: usize = 40;
    let fine = (KNOTS - 1) * FINE_PER_KNOT + 1;
    let step = KNOT_SPACING_MS / FINE_PER_KNOT as f64;
    // Envelope on the fine grid: the largest Δv any curve reached at or before each instant.
    let mut env = vec![0.0f64; fine];
    for c in curves {
        for &(tau, dv) in c {
            let i = ((tau / step).ceil() as usize).min(fine - 1);
            env[i] = env[i].max(dv * (1.0 + margin));
        }
    }
    for i in 1..fine {
        env[i] = env[i].max(env[i - 1]);
    }
    let mut t: [f64; KNOTS] = core::array::from_fn(|k| env[k * FINE_PER_KNOT]);
    t[0] = t[0].max(floor_mps);
    for k in 1..KNOTS {
        t[k] = t[k].max(t[k - 1]);
    }
    // Where a segment dips under the envelope, lift both its knots by the deficit (lifting
    // only ever keeps the other segments above the envelope).
    for k in 0..KNOTS - 1 {
        let deficit = (0..=FINE_PER_KNOT)
            .map(|j| {
                let f = j as f64 / FINE_PER_KNOT as f64;
                env[k * FINE_PER_KNOT + j] - (t[k] + (t[k + 1] - t[k]) * f)
            })
            .fold(0.0f64, f64::max);
        t[k] += deficit;
        t[k + 1] += deficit;
    }
    for k in 1..KNOTS {
        t[k] = t[k].max(t[k - 1]);
    }
    // Round up to 5 cm/s: a calibration table a human reads (k/20 is the f64 of the literal).
    t.map(|v| (v * 20.0).ceil() / 20.0)
}

/// The sweep's opponents: a rigid barrier and cars of 800–3000 kg.
pub fn families() -> Vec<Family> {
    let mut f = vec![Family::Barrier];
    f.extend(
        [
            800.0, 1000.0, 1300.0, 1600.0, 1785.0, 2200.0, 2600.0, 3000.0,
        ]
        .map(|m| Family::Car { opponent_kg: m }),
    );
    f
}

impl CaseSpec {
    /// The severity the first tens of ms show: the EBS of an equal-mass crash at this closing
    /// speed (half the closing speed; a barrier's own speed), km/h. The opponent's mass does
    /// not show that early (`restraint::crash_match`): a light car at 60 km/h closing speed
    /// starts like a 30 km/h barrier, though its EBS is lower.
    pub fn onset_ebs_kph(&self) -> f64 {
        match self.family {
            Family::Barrier => self.closing_kph,
            Family::Car { .. } => 0.5 * self.closing_kph,
        }
    }

    /// A no-fire case: below the no-fire line both in EBS and in onset severity. (Light
    /// opponents above the line in onset severity but below it in EBS are a grey zone: no
    /// accelerometer-only algorithm can tell them from a barrier at half their closing speed
    /// before the airbag is due.)
    pub fn no_fire(&self, ebs_kph: f64, line_kph: f64) -> bool {
        ebs_kph < line_kph && self.onset_ebs_kph() < line_kph
    }
}

/// Closing speed of `family` at which the EBS is `ebs_kph` (inverse of v·m/(m_ego + m)).
pub fn closing_for_ebs(family: Family, ebs_kph: f64) -> f64 {
    match family {
        Family::Barrier => ebs_kph,
        Family::Car { opponent_kg } => {
            ebs_kph * (crate::scenario::DEFAULT_EGO_MASS_KG + opponent_kg) / opponent_kg
        }
    }
}

/// Gravity, for tables in g.
pub fn to_g(mps2: f64) -> f64 {
    mps2 / G_MPS2
}

/// The grid of a sweep: severities, opponents and sensor variants.
#[derive(Debug, Clone)]
pub struct Sweep {
    /// Lowest EBS, km/h.
    pub ebs_from_kph: f64,
    /// Highest EBS, km/h.
    pub ebs_to_kph: f64,
    /// EBS step, km/h.
    pub step_kph: f64,
    /// Opponents.
    pub families: Vec<Family>,
    /// Sensor variants every case is run with.
    pub sensors: Vec<SensorSpec>,
    /// The occupant is belted (the airbag boundary `fallback_dv_mps`); `false`: not known to
    /// be (`unbelted_dv_mps`).
    pub belted: bool,
}

/// Braking that goes on through the crash in the robustness variant, m/s² (1 g).
pub const BRAKING_MPS2: f64 = G_MPS2;

impl Sweep {
    /// The calibration sweep: EBS 6–64 km/h in 1 km/h steps, [`families`], and five sensor
    /// variants: 4 kHz with noise seeds 1, 2, 3; 4 kHz with 1 g of braking going on through the
    /// crash; 1 kHz (the slowest rate a scenario may have).
    pub fn calibration() -> Self {
        let mut sensors: Vec<SensorSpec> = [1, 2, 3].map(SensorSpec::bench).to_vec();
        sensors.push(SensorSpec {
            braking_mps2: BRAKING_MPS2,
            ..SensorSpec::bench(4)
        });
        sensors.push(SensorSpec {
            rate_hz: 1000.0,
            ..SensorSpec::bench(5)
        });
        Self {
            ebs_from_kph: 6.0,
            ebs_to_kph: 64.0,
            step_kph: 1.0,
            families: families(),
            sensors,
            belted: true,
        }
    }

    /// The cases of the grid (closing speeds above 200 km/h left out).
    pub fn cases(&self) -> Vec<CaseSpec> {
        let mut specs = Vec::new();
        for &family in &self.families {
            let mut ebs = self.ebs_from_kph;
            while ebs <= self.ebs_to_kph + 1e-9 {
                let closing_kph = closing_for_ebs(family, ebs);
                if closing_kph <= 200.0 {
                    specs.push(CaseSpec {
                        family,
                        closing_kph,
                    });
                }
                ebs += self.step_kph;
            }
        }
        specs
    }
}

/// One case of a sweep through the detectors, every sensor variant.
#[derive(Debug, Clone)]
pub struct Row {
    /// The case.
    pub spec: CaseSpec,
    /// Its requirement.
    pub req: Requirement,
    /// Per sensor variant: what the detectors measured.
    pub measured: Vec<Measured>,
}

impl Row {
    /// Airbag time of variant `i`, ms after contact (None: not fired).
    pub fn airbag_ms(&self, i: usize, t_ref_ms: f64) -> Option<f64> {
        self.measured.get(i).and_then(|m| m.airbag_ms(t_ref_ms))
    }

    /// The deadline of variant `i`: the occupant's, or the reference restraint's own time after
    /// the measured onset where that is later (the algorithm cannot fire the reference airbag
    /// earlier than its definition), ms after contact. `None`: the reference restraint bottoms
    /// out even at its own time (no deadline to meet).
    pub fn deadline_ms(&self, i: usize, t_ref_ms: f64) -> Option<f64> {
        let own = self
            .measured
            .get(i)
            .and_then(|m| m.onset_ms)
            .map(|o| o + t_ref_ms);
        match (self.req.latest_ms, own) {
            (Some(l), Some(o)) => Some(l.max(o)),
            (l, _) => l,
        }
    }

    /// Fired in any variant.
    pub fn fires(&self, t_ref_ms: f64) -> bool {
        (0..self.measured.len()).any(|i| self.airbag_ms(i, t_ref_ms).is_some())
    }
}

/// Runs every case of `sweep` through the detectors of `cfg` (in parallel).
///
/// # Errors
/// A case the model refuses, or an occupant simulation error.
pub fn run_sweep(cfg: &CycleConfig, sweep: &Sweep) -> Result<Vec<Row>> {
    use rayon::prelude::*;
    let reference = physics::reference::ReferenceRestraint::builtin()
        .map_err(anyhow::Error::msg)?
        .settings();
    sweep
        .cases()
        .par_iter()
        .map(|&spec| {
            let crash = Crash::new(spec)?;
            let req = crash.requirement(&reference)?;
            let measured = sweep
                .sensors
                .iter()
                .map(|sensor| {
                    let (samples, contact_ns) = crash.samples(sensor);
                    measure(cfg, &samples, contact_ns, sweep.belted)
                })
                .collect();
            Ok(Row {
                spec,
                req,
                measured,
            })
        })
        .collect()
}

/// The lowest barrier EBS of `rows` at which the belt alone lets the occupant bottom out.
pub fn must_fire_line(rows: &[Row]) -> Option<f64> {
    rows.iter()
        .filter(|r| r.spec.family == Family::Barrier && r.req.belt_only_bottoms_out)
        .map(|r| r.req.ebs_kph)
        .reduce(f64::min)
}

/// The boundary calibrated on `rows`: [`derive_boundary`] over every sensor variant's Δv
/// curve of every no-fire case, floor 0.1 m/s.
pub fn calibrate(rows: &[Row], no_fire_line_kph: f64, margin: f64) -> [f64; KNOTS] {
    let curves: Vec<Vec<(f64, f64)>> = rows
        .iter()
        .filter(|r| r.spec.no_fire(r.req.ebs_kph, no_fire_line_kph))
        .flat_map(|r| r.measured.iter().map(|m| m.dv_curve.clone()))
        .collect();
    derive_boundary(&curves, margin, 0.1)
}

/// How late the accelerometer-only path may fire a must-fire crash after its deadline, ms
/// (the safety order): no misuse event or single fault may fire a
/// restraint, then every must-fire crash fires, then fire time. The path that runs without a
/// usable prediction (a degraded mode) may be late where the first rule requires it — its
/// severity floors sit above the largest misuse Δv (1.2 m/s, a pothole under both front
/// wheels at 1.5 × its envelope) — never the other way round, and by at most this much.
/// Production ECUs win that time back with crush-zone (upfront) sensors.
pub const ACCEL_ONLY_LATENESS_BOUND_MS: f64 = 6.0;

/// Every requirement a sweep's results break: a fire in a no-fire case; a must-fire case
/// (EBS ≥ `must_kph`) not fired, or fired more than `late_allowance_ms` after its deadline.
pub fn violations(
    rows: &[Row],
    no_fire_line_kph: f64,
    must_kph: f64,
    t_ref_ms: f64,
    late_allowance_ms: f64,
) -> Vec<String> {
    let mut bad = Vec::new();
    for r in rows {
        let e = r.req.ebs_kph;
        let label = r.spec.family.label();
        if r.spec.no_fire(e, no_fire_line_kph) && r.fires(t_ref_ms) {
            bad.push(format!(
                "{label}, EBS {e:.1} km/h: fired below the no-fire line"
            ));
        }
        if e >= must_kph {
            for i in 0..r.measured.len() {
                let late = match (r.airbag_ms(i, t_ref_ms), r.deadline_ms(i, t_ref_ms)) {
                    (None, _) => true,
                    (Some(t), Some(l)) => t > l + late_allowance_ms,
                    (Some(_), None) => false,
                };
                if late {
                    bad.push(format!(
                        "{label}, EBS {e:.1} km/h, sensor variant {i}: airbag {} (deadline {})",
                        r.airbag_ms(i, t_ref_ms)
                            .map_or("not fired".into(), |t| format!("at {t:.1} ms")),
                        r.deadline_ms(i, t_ref_ms)
                            .map_or("none".into(), |l| format!("{l:.1} ms"))
                    ));
                }
            }
        }
    }
    bad
}
