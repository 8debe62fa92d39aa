//! `lut study estimation`: what the ECU's track filter buys over the newest sample alone.
//!
//! For every scenario of the library with a contact, under several sensor variations and
//! noise seeds, the object list is generated with the bench's sensor model
//! (`world::SensorModelSim` over the scenario's `Truth`) and fed, under a simulated
//! 1 kHz clock, to
//!
//! * **filtered**: the restraint core itself (`restraint::RestraintCycle` with `SimIo`): its
//!   track filter's situation — contact instant (and the early one it plans with), closing
//!   speed at contact, fused and conservative opponent mass, with their σ;
//! * **raw**: the estimate without a track filter — the closed form of the newest
//!   sample alone (`restraint::time_to_contact` from its distance, speed and acceleration at
//!   its measurement time; the reported mass and σ).
//!
//! Both are read at the last cycle before the true contact (the estimate the crash plan is
//! latched from). Errors against the truth: contact instant (ms), closing speed at contact
//! (km/h), opponent mass (kg, vehicles only). The occupant outcome of each estimate uses the
//! robustness study's machinery ([`crate::robustness::Sampler::outcome`]): the table looked up
//! at the estimate (closing speed, conservative mass), the pre-crash pretensioner shifted by
//! the planned contact's error, the occupant simulated on the TRUE pulse; reported as the
//! increase of the cell objective a_max + a_mean over the exact estimate (belted occupants,
//! vehicle opponents: the table covers no barrier and no unbelted occupant).
//!
//! **Reproducibility.** Run `i` of a scenario draws from generators seeded with
//! SplitMix64(seed ⊕ SplitMix64(i) ⊕ FNV-1a(scenario name)) — the sensor's noise and the
//! variation's drops and latency jitter (the variations of one run share the seed, so they
//! differ only by the variation); results are collected in index order, so threads change
//! nothing.

use crate::hash::{fnv1a, splitmix64};
use crate::robustness::{self, Estimate, Outcome, Sampler, Spread};
use anyhow::{anyhow, Context, Result};
use diagram::Diagram;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use restraint::{CycleConfig, ObjectState, ReferenceSettings, RestraintCycle, SimIo, SimLoop};
use serde::{Deserialize, Serialize};
use std::path::Path;
use world::{scenario::OpponentKind, Scenario, SensorModelSim, Truth};

const MS: u64 = 1_000_000;
/// CLOCK_MONOTONIC of scenario time 0 in the simulation (any value > the longest latency).
const T0_NS: u64 = 1_000_000_000;
/// The relative-acceleration noise of a tracker the noisy variations scale (the library's
/// sensor model reports the true acceleration): a difference quotient of the speed, m/s².
pub const TRACKER_ACCEL_NOISE_MPS2: f64 = 0.3;

/// Reference restraint of the simulated ECU (the estimate does not depend on it).
const REFERENCE: ReferenceSettings = ReferenceSettings {
    belt_limiter_kn: 8.5,
    airbag_level_kn: 12.0,
    pretensioner_time_ms: 10.0,
    airbag_time_ms: 10.0,
};

/// A change of the scenario's sensor.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Variation {
    /// Short name.
    pub name: &'static str,
    /// Factor on the distance, speed and mass noise; above 1 the relative acceleration gets
    /// this factor × [`TRACKER_ACCEL_NOISE_MPS2`].
    pub noise_scale: f64,
    /// Measurement latency varies per sample uniformly by ± this, ms (time stamps stay true).
    pub latency_jitter_ms: f64,
    /// Each sample is lost with this probability.
    pub drop_probability: f64,
}

/// The study's variations.
pub const VARIATIONS: [Variation; 5] = [
    Variation {
        name: "nominal",
        noise_scale: 1.0,
        latency_jitter_ms: 0.0,
        drop_probability: 0.0,
    },
    Variation {
        name: "noise x3",
        noise_scale: 3.0,
        latency_jitter_ms: 0.0,
        drop_probability: 0.0,
    },
    Variation {
        name: "noise x10",
        noise_scale: 10.0,
        latency_jitter_ms: 0.0,
        drop_probability: 0.0,
    },
    Variation {
        name: "latency jitter ±15 ms",
        noise_scale: 1.0,
        latency_jitter_ms: 15.0,
        drop_probability: 0.0,
    },
    Variation {
        name: "30 % samples dropped",
        noise_scale: 1.0,
        latency_jitter_ms: 0.0,
        drop_probability: 0.3,
    },
];

impl Variation {
    /// The scenario with this variation's sensor noise.
    pub fn apply(&self, s: &Scenario) -> Scenario {
        let mut s = s.clone();
        let k = self.noise_scale;
        s.sensor.distance_noise_m *= k;
        s.sensor.speed_noise_mps *= k;
        s.sensor.mass_noise_kg *= k;
        if k > 1.0 {
            s.sensor.relative_accel_noise_mps2 = s
                .sensor
                .relative_accel_noise_mps2
                .max(TRACKER_ACCEL_NOISE_MPS2)
                * k;
        }
        s
    }
}

/// One estimate of the coming contact, as held at some cycle.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Held {
    /// Estimated contact instant, s (scenario time).
    pub contact_s: f64,
    /// The contact instant the decision plans with, s.
    pub planned_contact_s: f64,
    /// σ of the contact instant, s (raw: none, NaN).
    pub contact_sigma_s: f64,
    /// Closing speed at contact, m/s.
    pub closing_speed_mps: f64,
    /// Its σ, m/s (raw: NaN).
    pub closing_speed_sigma_mps: f64,
    /// Opponent mass estimate, kg.
    pub mass_kg: f64,
    /// Its σ, kg.
    pub mass_sigma_kg: f64,
    /// The mass the table is queried at (m + k·σ), kg.
    pub lookup_mass_kg: f64,
}

/// The newest-sample closed form (the ECU's estimate before the track filter).
pub fn raw_estimate(o: &ObjectState, conservative_k: f64) -> Option<Held> {
    let c = restraint::time_to_contact(
        f64::from(o.distance_m),
        f64::from(o.closing_speed_mps),
        f64::from(o.relative_accel_mps2),
    )?;
    let contact_s = (o.timestamp_ns as f64 - T0_NS as f64) * 1e-9 + c.ttc_s;
    let (m, sg) = (
        f64::from(o.opponent_mass_kg),
        f64::from(o.opponent_mass_sigma_kg),
    );
    Some(Held {
        contact_s,
        planned_contact_s: contact_s,
        contact_sigma_s: f64::NAN,
        closing_speed_mps: c.closing_speed_mps,
        closing_speed_sigma_mps: f64::NAN,
        mass_kg: m,
        mass_sigma_kg: sg,
        lookup_mass_kg: m + conservative_k * sg,
    })
}

fn scenario_s(ns: u64) -> f64 {
    (ns as f64 - T0_NS as f64) * 1e-9
}

fn held_of(s: &restraint::Situation) -> Held {
    Held {
        contact_s: scenario_s(s.contact_estimate_ns),
        planned_contact_s: scenario_s(s.contact_ns),
        contact_sigma_s: s.contact_sigma_s,
        closing_speed_mps: s.closing_speed_mps,
        closing_speed_sigma_mps: s.closing_speed_sigma_mps,
        mass_kg: s.opponent_mass_estimate_kg,
        mass_sigma_kg: s.opponent_mass_sigma_kg,
        lookup_mass_kg: s.opponent_mass_kg,
    }
}

/// Both estimates at one cycle (for the plot).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct TracePoint {
    /// Cycle time, s (scenario time).
    pub t_s: f64,
    /// The raw estimate of the newest sample.
    pub raw: Option<Held>,
    /// The core's situation.
    pub filtered: Option<Held>,
    /// A new sample arrived in this cycle.
    pub sample: bool,
}

/// One simulated run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Run {
    /// True contact, s.
    pub contact_s: f64,
    /// True closing speed at contact, m/s.
    pub closing_speed_mps: f64,
    /// True opponent mass, kg (∞: barrier).
    pub opponent_mass_kg: f64,
    /// Raw estimate at the last cycle before contact (`None`: no sample within the object
    /// timeout, or it saw no contact).
    pub raw: Option<Held>,
    /// Filtered estimate at the last cycle before contact.
    pub filtered: Option<Held>,
    /// Samples delivered, gated out as outliers, and track starts.
    pub samples: u64,
    /// Samples the filter rejected as outliers.
    pub outliers: u64,
    /// Track (re)starts.
    pub starts: u64,
    /// Every cycle's estimates (only when asked for).
    pub trace: Vec<TracePoint>,
}

/// Simulates run `index` of `scenario` under `variation` (see the module docs).
///
/// # Errors
/// A scenario without contact or whose truth cannot be solved.
pub fn simulate(
    scenario: &Scenario,
    variation: &Variation,
    seed: u64,
    index: u64,
    trace: bool,
) -> Result<Run> {
    let run_seed = splitmix64(seed ^ splitmix64(index) ^ fnv1a(scenario.name.as_bytes()));
    let mut sc = variation.apply(scenario);
    sc.seed = run_seed;
    let truth = Truth::new(&sc).map_err(|e| anyhow!("{}: {e}", sc.name))?;
    let contact_s = truth
        .contact_s
        .ok_or_else(|| anyhow!("{}: no contact", sc.name))?;
    let closing = truth.closing_speed_at_contact_mps();
    let opp_kg = sc.opponent_mass_kg();
    let period_s = sc.sensor.object_period_ms * 1e-3;
    let latency_s = sc.sensor.latency_ms * 1e-3;
    let mut model = SensorModelSim::new(truth);
    let mut rng = ChaCha8Rng::seed_from_u64(splitmix64(run_seed ^ 0x5EED));
    let cfg = CycleConfig::default();
    let timeout_s = cfg.object_timeout_ms * 1e-3;
    let k = cfg.conservative_mass_k;
    let (mut ecu, _) = RestraintCycle::new(cfg, None, &REFERENCE)
        .map_err(|e| anyhow!("RestraintCycle::new: {e}"))?;
    let mut io = SimIo::new();
    let mut clock = SimLoop::new(T0_NS, MS);
    let mut next_pub_s = 0.0;
    let (mut raw, mut last_sample_s, mut samples) = (None, f64::NEG_INFINITY, 0u64);
    let mut out = Run {
        contact_s,
        closing_speed_mps: closing,
        opponent_mass_kg: opp_kg,
        raw: None,
        filtered: None,
        samples: 0,
        outliers: 0,
        starts: 0,
        trace: Vec::new(),
    };
    // Cycles on the 1 ms grid up to the last one before contact.
    let last_cycle = ((contact_s * 1e3).ceil() as u64).saturating_sub(1);
    for cycle in 0..=last_cycle {
        let t = cycle as f64 * 1e-3;
        let mut new_sample = false;
        while next_pub_s <= t + 1e-9 {
            let t_pub = next_pub_s;
            next_pub_s += period_s;
            if sc
                .sensor
                .dropped(world::scenario::DropoutTarget::Object, t_pub)
                || rng.gen_bool(variation.drop_probability)
            {
                continue;
            }
            // Latency jitter: the sample measured at t_pub − latency − δ is the one the
            // model publishes at t_pub − δ; its time stamp tells the truth.
            let jitter_s = if variation.latency_jitter_ms > 0.0 {
                rng.gen_range(-variation.latency_jitter_ms..=variation.latency_jitter_ms) * 1e-3
            } else {
                0.0
            };
            let delta = jitter_s.max(-latency_s);
            let (Some(mut o), Some(t_meas)) = (
                model.object(t_pub - delta),
                model.measurement_time_s(t_pub - delta),
            ) else {
                continue;
            };
            o.timestamp_ns = T0_NS + (t_meas * 1e9).round() as u64;
            io.push_object(o);
            if o.is_valid() {
                raw = raw_estimate(&o, k);
                last_sample_s = t;
                samples += 1;
                new_sample = true;
            } else {
                raw = None;
            }
        }
        clock.step(&mut ecu, &mut io);
        io.can_tx.clear();
        let fresh = t - last_sample_s <= timeout_s;
        let filtered = ecu.situation().map(|s| held_of(&s));
        if trace {
            out.trace.push(TracePoint {
                t_s: t,
                raw: raw.filter(|_| fresh),
                filtered,
                sample: new_sample,
            });
        }
        if cycle == last_cycle {
            out.raw = raw.filter(|_| fresh);
            out.filtered = filtered;
        }
    }
    let c = ecu.counters();
    out.samples = samples;
    out.outliers = c.track_outliers;
    out.starts = c.track_starts;
    Ok(out)
}

/// Errors of one estimate at contact.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Errors {
    /// Contact instant, ms.
    pub contact_ms: f64,
    /// Closing speed at contact, km/h.
    pub closing_speed_kph: f64,
    /// Opponent mass, kg (NaN for a barrier).
    pub mass_kg: f64,
    /// Outcome's objective a_max + a_mean minus that of the exact estimate, g (NaN where the
    /// table does not apply).
    pub objective_increase_g: f64,
    /// Error within 2σ (contact, speed, mass) — filtered only.
    pub within_2_sigma: [bool; 3],
}

fn errors_of(run: &Run, h: &Held, outcome: Option<(&Sampler, f64)>) -> Result<Errors> {
    let mass_err = if run.opponent_mass_kg.is_finite() {
        h.mass_kg - run.opponent_mass_kg
    } else {
        f64::NAN
    };
    let objective_increase_g = match outcome {
        Some((sampler, exact)) => {
            let o: Outcome = sampler.outcome(&Estimate {
                closing_speed_kph: h.closing_speed_mps * 3.6,
                opponent_mass_kg: h.lookup_mass_kg,
                contact_error_s: h.planned_contact_s - run.contact_s,
            })?;
            o.a_max_g + o.a_mean_g - exact
        }
        None => f64::NAN,
    };
    let e = Errors {
        contact_ms: (h.contact_s - run.contact_s) * 1e3,
        closing_speed_kph: (h.closing_speed_mps - run.closing_speed_mps) * 3.6,
        mass_kg: mass_err,
        objective_increase_g,
        within_2_sigma: [false; 3],
    };
    Ok(Errors {
        within_2_sigma: [
            e.contact_ms.abs() <= 2e3 * h.contact_sigma_s,
            e.closing_speed_kph.abs() <= 2.0 * 3.6 * h.closing_speed_sigma_mps,
            mass_err.abs() <= 2.0 * h.mass_sigma_kg,
        ],
        ..e
    })
}

/// p50 / p95 (nearest rank, as [`Spread`]; NaN entries left out).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Percentiles {
    /// Median.
    pub p50: f64,
    /// 95th percentile.
    pub p95: f64,
    /// Values counted.
    pub n: usize,
}

impl Percentiles {
    /// Of `v`, or of |v| when `abs`.
    pub fn of(v: impl Iterator<Item = f64>, abs: bool) -> Self {
        let a: Vec<f64> = v
            .filter(|x| !x.is_nan())
            .map(|x| if abs { x.abs() } else { x })
            .collect();
        let s = Spread::of(&a);
        Percentiles {
            p50: s.p50,
            p95: s.p95,
            n: a.len(),
        }
    }
}

/// One row of the result: raw vs filtered over a set of runs.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Row {
    /// Variation (and scenario, for per-scenario rows).
    pub name: String,
    /// Runs.
    pub runs: usize,
    /// Runs without a raw / filtered estimate at contact.
    pub missing: [usize; 2],
    /// |contact instant error|, ms: raw, filtered.
    pub contact_ms: [Percentiles; 2],
    /// |closing speed error|, km/h: raw, filtered.
    pub closing_speed_kph: [Percentiles; 2],
    /// |mass error|, kg: raw, filtered.
    pub mass_kg: [Percentiles; 2],
    /// Increase of the occupant objective a_max + a_mean over the exact estimate, g (signed:
    /// an interpolated cell can do slightly better than the one of the exact estimate).
    pub objective_increase_g: [Percentiles; 2],
    /// Share of the filtered errors within 2σ: contact, speed, mass.
    pub within_2_sigma: [f64; 3],
    /// Samples rejected as outliers per run (mean) and track starts per run.
    pub outliers_per_run: f64,
    /// Track starts per run (mean).
    pub starts_per_run: f64,
}

fn row(name: String, items: &[(&Run, Option<Errors>, Option<Errors>)]) -> Row {
    let col = |f: &dyn Fn(&Errors) -> f64, which: usize, abs: bool| {
        Percentiles::of(
            items.iter().filter_map(|(_, r, fi)| {
                let e = if which == 0 { r } else { fi };
                e.as_ref().map(f)
            }),
            abs,
        )
    };
    let pair = |f: &dyn Fn(&Errors) -> f64| [col(f, 0, true), col(f, 1, true)];
    let filt: Vec<&Errors> = items.iter().filter_map(|(_, _, f)| f.as_ref()).collect();
    let share = |i: usize, f: &dyn Fn(&Errors) -> f64| {
        let v: Vec<&&Errors> = filt.iter().filter(|e| !f(e).is_nan()).collect();
        v.iter().filter(|e| e.within_2_sigma[i]).count() as f64 / v.len().max(1) as f64
    };
    let n = items.len().max(1) as f64;
    Row {
        name,
        runs: items.len(),
        missing: [
            items.iter().filter(|(_, r, _)| r.is_none()).count(),
            items.iter().filter(|(_, _, f)| f.is_none()).count(),
        ],
        contact_ms: pair(&|e| e.contact_ms),
        closing_speed_kph: pair(&|e| e.closing_speed_kph),
        mass_kg: pair(&|e| e.mass_kg),
        objective_increase_g: [
            col(&|e| e.objective_increase_g, 0, false),
            col(&|e| e.objective_increase_g, 1, false),
        ],
        within_2_sigma: [
            share(0, &|e| e.contact_ms),
            share(1, &|e| e.closing_speed_kph),
            share(2, &|e| e.mass_kg),
        ],
        outliers_per_run: items.iter().map(|(r, _, _)| r.outliers as f64).sum::<f64>() / n,
        starts_per_run: items.iter().map(|(r, _, _)| r.starts as f64).sum::<f64>() / n,
    }
}

/// `format` of the result file.
pub const RESULT_FORMAT: &str = "lut-estimation-study";

/// The study's result.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StudyResult {
    /// [`RESULT_FORMAT`].
    pub format: String,
    /// Scenarios (with a contact) and runs per scenario and variation.
    pub scenarios: Vec<String>,
    /// Runs per scenario and variation.
    pub runs: u64,
    /// Base seed.
    pub seed: u64,
    /// The track filter's settings (the ECU's defaults).
    pub track: restraint::TrackConfig,
    /// One row per variation over all scenarios.
    pub variations: Vec<Row>,
    /// One row per (variation, scenario).
    pub per_scenario: Vec<Row>,
}

/// A scenario of the library the study applies to: one with a contact.
pub struct StudyScenario {
    /// The scenario.
    pub scenario: Scenario,
    /// The outcome sampler and the objective of the exact estimate, where the table applies
    /// (belted occupant, vehicle opponent).
    pub outcome: Option<(Sampler, f64)>,
}

/// Loads every `*.toml` of `dir` with a true contact (sorted by file name), except those whose
/// object list is deliberately misreported (`sensor.speed_bias_mps`, `sensor.mass_estimate_kg`:
/// a bias of every sample that no estimator can see; the crash phase handles them, restraint
/// README "Crash phase") or dead (no sample within the sensor's range: nothing to estimate).
///
/// # Errors
/// Unreadable directory or scenario, or a table that cannot serve the samplers.
pub fn load_scenarios(dir: &Path, table: &Diagram) -> Result<Vec<StudyScenario>> {
    let mut files: Vec<_> = std::fs::read_dir(dir)
        .with_context(|| format!("cannot read {}", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    files.sort();
    let mut out = Vec::new();
    for f in files {
        let s = Scenario::load(&f)?;
        let truth = Truth::new(&s).map_err(|e| anyhow!("{}: {e}", f.display()))?;
        let misreported = s.sensor.speed_bias_mps != 0.0 || s.sensor.mass_estimate_kg.is_some();
        if truth.contact_s.is_none() || misreported {
            continue;
        }
        let outcome = if s.occupant.belted && s.opponent.kind == OpponentKind::Vehicle {
            let situation = robustness::Situation {
                closing_speed_kph: truth.closing_speed_at_contact_mps() * 3.6,
                opponent_mass_kg: s.opponent_mass_kg(),
                occupant_mass_kg: s.occupant.mass_kg,
                seat_distance_mm: s.occupant.chest_to_wheel_mm,
            };
            let sampler = Sampler::with_table(table.clone(), situation)?;
            let exact = sampler.outcome(&Estimate {
                closing_speed_kph: situation.closing_speed_kph,
                opponent_mass_kg: situation.opponent_mass_kg,
                contact_error_s: 0.0,
            })?;
            Some((sampler, exact.a_max_g + exact.a_mean_g))
        } else {
            None
        };
        out.push(StudyScenario {
            scenario: s,
            outcome,
        });
    }
    Ok(out)
}

/// Runs the study: every scenario × variation × `runs` seeds (in parallel, results in index
/// order), `progress` called once per finished run.
///
/// # Errors
/// A run that cannot be simulated or evaluated.
pub fn study(
    scenarios: &[StudyScenario],
    runs: u64,
    seed: u64,
    progress: &(dyn Fn() + Sync),
) -> Result<StudyResult> {
    let jobs: Vec<(usize, usize, u64)> = (0..scenarios.len())
        .flat_map(|s| (0..VARIATIONS.len()).flat_map(move |v| (0..runs).map(move |i| (s, v, i))))
        .collect();
    type Evaluated = (Run, Option<Errors>, Option<Errors>);
    let results: Vec<Evaluated> = jobs
        .par_iter()
        .map(|&(s, v, i)| {
            let sc = &scenarios[s];
            let run = simulate(&sc.scenario, &VARIATIONS[v], seed, i, false)?;
            let o = sc.outcome.as_ref().map(|(smp, exact)| (smp, *exact));
            let raw = run
                .raw
                .as_ref()
                .map(|h| errors_of(&run, h, o))
                .transpose()?;
            let filt = run
                .filtered
                .as_ref()
                .map(|h| errors_of(&run, h, o))
                .transpose()?;
            progress();
            Ok((run, raw, filt))
        })
        .collect::<Result<_>>()?;
    let mut variations = Vec::new();
    let mut per_scenario = Vec::new();
    for (v, var) in VARIATIONS.iter().enumerate() {
        let of_var: Vec<(&Run, Option<Errors>, Option<Errors>)> = jobs
            .iter()
            .zip(&results)
            .filter(|((_, jv, _), _)| *jv == v)
            .map(|(_, (r, a, b))| (r, *a, *b))
            .collect();
        variations.push(row(var.name.to_owned(), &of_var));
        for (s, sc) in scenarios.iter().enumerate() {
            let items: Vec<_> = jobs
                .iter()
                .zip(&results)
                .filter(|((js, jv, _), _)| *js == s && *jv == v)
                .map(|(_, (r, a, b))| (r, *a, *b))
                .collect();
            per_scenario.push(row(format!("{} / {}", var.name, sc.scenario.name), &items));
        }
    }
    Ok(StudyResult {
        format: RESULT_FORMAT.into(),
        scenarios: scenarios.iter().map(|s| s.scenario.name.clone()).collect(),
        runs,
        seed,
        track: CycleConfig::default().track,
        variations,
        per_scenario,
    })
}
