//! Monte-Carlo robustness study: how the pre-crash estimate's errors spread the occupant's
//! outcome in one situation (one cell) — the paper's mass-accuracy question ("a payload
//! uncertainty of ~300 kg moves the occupant's mean acceleration by about 2 g") made
//! statistical.
//!
//! Per sample the ECU's view of the true situation is disturbed, as the ECU would see it:
//!
//! * **opponent mass** (payload): the estimate is off by a uniform error in ±`mass_error_kg`;
//! * **closing speed**: normal error, σ = `speed_sigma_kph`;
//! * **distance** at the last object sample before contact (taken `measurement_ttc_ms` before
//!   contact): normal error, σ = `distance_sigma_m`.
//!
//! The ECU looks the table up at its estimate (interpolated, out of range → the conventional
//! reference restraint, as the ECU does) and the occupant then rides down the **true** pulse
//! with that setting. The speed and distance errors also move the predicted contact: a
//! pretensioner planned before contact (t < 0) fires at predicted contact + t, i.e. off by
//! `d_est / v_est − d / v`. Airbag and post-contact pretensioner times count from the measured
//! contact (accelerometer) and keep their plan. Not modelled: the ECU's conservative mass
//! margin and its crash-confirmation floor for a pretensioner whose pre-crash time falls after
//! the real contact (it is fired late then, which is pessimistic).
//!
//! **Reproducibility:** sample `i` draws its errors from its own generator, seeded with
//! SplitMix64(seed ⊕ SplitMix64(i)) like the table's cells, so a sample's outcome does not
//! depend on which thread, shard or machine computes it, and the statistics are computed from
//! the samples in index order: a local run and a Slurm array give the same result bit for bit.

use crate::hash::splitmix64;
use crate::progress::Progress;
use crate::scenario::{Ego, Opponent, Pulse};
use crate::shard::{self, Payload, ShardFile, ShardHeader};
use crate::table::occupant_at;
use anyhow::{anyhow, bail, Context, Result};
use diagram::{Diagram, Query};
use physics::{mps2_to_g, simulate_occupant, MassClass, RestraintHardware, RestraintSettings};
use rand_xoshiro::rand_core::{RngCore, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Kind tag of robustness shard files and results.
pub const SHARD_KIND: &str = "robustness";
/// `format` field of the result JSON.
pub const RESULT_FORMAT: &str = "lut-robustness-study";

/// The pre-crash estimate's errors (see module docs).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct EstimateErrors {
    /// Opponent mass error: uniform in ±this [kg].
    pub mass_error_kg: f64,
    /// Closing speed error: normal, this σ [km/h].
    pub speed_sigma_kph: f64,
    /// Distance error at the last object sample: normal, this σ [m].
    pub distance_sigma_m: f64,
    /// The last object sample is taken this long before contact [ms].
    pub measurement_ttc_ms: f64,
}

/// The true situation (the cell).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Situation {
    /// Closing speed [km/h].
    pub closing_speed_kph: f64,
    /// Opponent mass [kg].
    pub opponent_mass_kg: f64,
    /// Occupant mass [kg].
    pub occupant_mass_kg: f64,
    /// Seat distance chest to wheel [mm].
    pub seat_distance_mm: f64,
}

/// A robustness study (also the spec of its distributed run).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RobustnessJob {
    /// The table the ECU uses (absolute path).
    pub table: PathBuf,
    /// Its CRC-32C when the study was set up (a changed table is refused).
    pub table_crc32c: u32,
    /// The true situation.
    pub situation: Situation,
    /// The estimate's errors.
    pub errors: EstimateErrors,
    /// Number of samples.
    pub samples: u64,
    /// Base seed.
    pub seed: u64,
}

/// Outcome of one sample.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Sample {
    /// Opponent mass error drawn [kg].
    pub mass_error_kg: f64,
    /// Closing speed error drawn [km/h].
    pub speed_error_kph: f64,
    /// Distance error drawn [m].
    pub distance_error_m: f64,
    /// Resulting error of a pre-crash pretensioner's firing time [ms] (0 if none).
    pub pretensioner_shift_ms: f64,
    /// The estimate was outside the table: reference restraint used.
    pub fallback: bool,
    /// Occupant peak acceleration [g].
    pub a_max_g: f64,
    /// Occupant mean acceleration [g].
    pub a_mean_g: f64,
    /// Maximum forward excursion [mm].
    pub excursion_mm: f64,
    /// Bottoming-out.
    pub bottoming_out: bool,
}

/// Samples of a shard.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Samples(pub Vec<Sample>);

impl Payload for Samples {
    fn item_count(&self) -> usize {
        self.0.len()
    }
}

/// Order statistics of one quantity.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Spread {
    /// Mean.
    pub mean: f64,
    /// Standard deviation (n − 1).
    pub sd: f64,
    /// Minimum.
    pub min: f64,
    /// 5th percentile (nearest rank).
    pub p05: f64,
    /// Median (nearest rank).
    pub p50: f64,
    /// 95th percentile (nearest rank).
    pub p95: f64,
    /// Maximum.
    pub max: f64,
}

impl Spread {
    /// Statistics of `v` (summed in the given order, so equal inputs give equal bits).
    pub fn of(v: &[f64]) -> Self {
        let n = v.len().max(1) as f64;
        let mean = v.iter().sum::<f64>() / n;
        let var = v.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / (n - 1.0).max(1.0);
        let mut s = v.to_vec();
        s.sort_by(f64::total_cmp);
        let rank = |p: f64| {
            let i = ((p * s.len() as f64).ceil() as usize).clamp(1, s.len().max(1)) - 1;
            s.get(i).copied().unwrap_or(f64::NAN)
        };
        Spread {
            mean,
            sd: var.sqrt(),
            min: s.first().copied().unwrap_or(f64::NAN),
            p05: rank(0.05),
            p50: rank(0.5),
            p95: rank(0.95),
            max: s.last().copied().unwrap_or(f64::NAN),
        }
    }
}

/// A histogram with equal bins from the minimum to the 99th percentile (for the plot; a
/// bottoming-out tail would otherwise squeeze the bulk into one bin).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Histogram {
    /// Left edge of the first bin (the minimum).
    pub from: f64,
    /// Bin width.
    pub width: f64,
    /// Counts.
    pub counts: Vec<u64>,
    /// Samples above the last bin (above the 99th percentile).
    pub above: u64,
}

impl Histogram {
    fn of(v: &[f64], bins: usize) -> Self {
        let mut s = v.to_vec();
        s.sort_by(f64::total_cmp);
        let from = s.first().copied().unwrap_or(0.0);
        let p99 = s
            .get((s.len() * 99).div_ceil(100).saturating_sub(1))
            .copied()
            .unwrap_or(from);
        let width = ((p99 - from) / bins as f64).max(1e-9);
        let mut counts = vec![0u64; bins];
        let mut above = 0;
        for x in v {
            let i = ((x - from) / width) as usize;
            match counts.get_mut(i) {
                Some(c) => *c += 1,
                None if *x <= p99 => counts[bins - 1] += 1,
                None => above += 1,
            }
        }
        Histogram {
            from,
            width,
            counts,
            above,
        }
    }
}

/// The study's result (the output file).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StudyResult {
    /// [`RESULT_FORMAT`].
    pub format: String,
    /// Identity of the study's inputs.
    pub identity: String,
    /// The study.
    pub study: RobustnessJob,
    /// The outcome with a perfect estimate.
    pub exact_estimate: Sample,
    /// Samples whose estimate fell outside the table (reference restraint).
    pub fallback_samples: u64,
    /// Samples that bottom out.
    pub bottoming_out_samples: u64,
    /// Occupant peak acceleration [g].
    pub a_max_g: Spread,
    /// Occupant mean acceleration [g].
    pub a_mean_g: Spread,
    /// Forward excursion [mm].
    pub excursion_mm: Spread,
    /// a_max + a_mean minus that of the perfect estimate [g] (the optimiser's objective).
    pub objective_increase_g: Spread,
    /// Histogram of a_mean [g].
    pub a_mean_histogram: Histogram,
    /// Histogram of a_max [g].
    pub a_max_histogram: Histogram,
}

/// Uniform in [0, 1) from the top 53 bits.
fn unit(rng: &mut Xoshiro256PlusPlus) -> f64 {
    (rng.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

/// Standard normal (Box–Muller; the first of the pair).
pub fn normal(rng: &mut Xoshiro256PlusPlus) -> f64 {
    let u1 = 1.0 - unit(rng); // (0, 1]: ln is finite
    let u2 = unit(rng);
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

/// The errors of sample `index` (depends on `seed` and `index` only).
pub fn draw_errors(e: &EstimateErrors, seed: u64, index: u64) -> (f64, f64, f64) {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(splitmix64(seed ^ splitmix64(index)));
    let mass = (2.0 * unit(&mut rng) - 1.0) * e.mass_error_kg;
    let speed = normal(&mut rng) * e.speed_sigma_kph;
    let dist = normal(&mut rng) * e.distance_sigma_m;
    (mass, speed, dist)
}

/// What every sample shares: the table, the true pulse, the reference restraint.
pub struct Sampler {
    table: Diagram,
    pulse: Pulse,
    reference: RestraintSettings,
    hw: RestraintHardware,
    situation: Situation,
    errors: EstimateErrors,
    seed: u64,
}

/// What the ECU made of the situation: the LUT query's closing speed and opponent mass and
/// the error of the contact instant it plans the pre-crash pretensioner with.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Estimate {
    /// Closing speed the table is queried at [km/h].
    pub closing_speed_kph: f64,
    /// Opponent mass the table is queried at [kg] (the ECU's conservative m + k·σ).
    pub opponent_mass_kg: f64,
    /// Planned contact minus true contact [s] (a pre-crash pretensioner fires this late).
    pub contact_error_s: f64,
}

/// The occupant's outcome with the restraint set for an [`Estimate`], on the true pulse.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Outcome {
    /// Resulting error of a pre-crash pretensioner's firing time [ms] (0 if none).
    pub pretensioner_shift_ms: f64,
    /// The estimate was outside the table: reference restraint used.
    pub fallback: bool,
    /// Occupant peak acceleration [g].
    pub a_max_g: f64,
    /// Occupant mean acceleration [g].
    pub a_mean_g: f64,
    /// Maximum forward excursion [mm].
    pub excursion_mm: f64,
    /// Bottoming-out.
    pub bottoming_out: bool,
}

impl Sampler {
    /// Load the table (checking it is the one the study was set up with) and predict the true
    /// pulse once.
    pub fn new(job: &RobustnessJob) -> Result<Self> {
        let table = Diagram::load(&job.table)?;
        if table.checksum() != job.table_crc32c {
            bail!(
                "{}: CRC-32C 0x{:08x}, but the study was set up with 0x{:08x} (table changed)",
                job.table.display(),
                table.checksum(),
                job.table_crc32c
            );
        }
        Ok(Sampler {
            errors: job.errors,
            seed: job.seed,
            ..Self::with_table(table, job.situation)?
        })
    }

    /// A sampler of one true situation with a loaded table (no error distribution: for
    /// [`Sampler::outcome`] at estimates made elsewhere, e.g. `lut study estimation`). An
    /// infinite opponent mass is a rigid barrier.
    pub fn with_table(table: Diagram, situation: Situation) -> Result<Self> {
        let h = table.header();
        let ego = Ego {
            mass_kg: f64::from(h.ego.mass_kg),
            class: MassClass::new(h.ego.class)?,
        };
        let s = &situation;
        let opponent = if s.opponent_mass_kg.is_infinite() {
            Opponent::Barrier
        } else {
            Opponent::Car {
                mass_kg: s.opponent_mass_kg,
            }
        };
        let pulse = Pulse::predict(&ego, opponent, s.closing_speed_kph)?;
        let reference = crate::reference::ReferenceRestraint::builtin()
            .map_err(|e| anyhow!("reference restraint: {e}"))?
            .settings();
        Ok(Sampler {
            table,
            pulse,
            reference,
            hw: RestraintHardware::default(),
            situation,
            errors: EstimateErrors {
                mass_error_kg: 0.0,
                speed_sigma_kph: 0.0,
                distance_sigma_m: 0.0,
                measurement_ttc_ms: 0.0,
            },
            seed: 0,
        })
    }

    /// The occupant's outcome when the ECU looks the table up at `e` (interpolated, out of
    /// range → the conventional reference restraint, as the ECU does) and the occupant rides
    /// down the **true** pulse; a pretensioner planned before contact fires `e.contact_error_s`
    /// late, airbag and post-contact pretensioner times count from the measured contact.
    pub fn outcome(&self, e: &Estimate) -> Result<Outcome> {
        let s = &self.situation;
        let q = Query {
            closing_speed_kph: e.closing_speed_kph as f32,
            opponent_mass_kg: e.opponent_mass_kg as f32,
            occupant_mass_kg: s.occupant_mass_kg as f32,
            seat_distance_mm: s.seat_distance_mm as f32,
        };
        let l = self.table.lookup(&q);
        let fallback = l.out_of_range.any();
        let mut set = if fallback {
            self.reference
        } else {
            RestraintSettings {
                load_limiter_n: f64::from(l.values.belt_limiter_kn) * 1e3,
                airbag_force_n: f64::from(l.airbag_command_kn()) * 1e3,
                pretensioner_time_s: f64::from(l.values.pretensioner_time_ms) * 1e-3,
                airbag_time_s: f64::from(l.values.airbag_time_ms) * 1e-3,
            }
        };
        let mut shift_ms = 0.0;
        if set.pretensioner_time_s < 0.0 && e.contact_error_s.is_finite() {
            set.pretensioner_time_s += e.contact_error_s;
            shift_ms = e.contact_error_s * 1e3;
        }
        let q_true = Query {
            closing_speed_kph: s.closing_speed_kph as f32,
            opponent_mass_kg: s.opponent_mass_kg as f32,
            occupant_mass_kg: s.occupant_mass_kg as f32,
            seat_distance_mm: s.seat_distance_mm as f32,
        };
        let o = simulate_occupant(&self.pulse.ego(), &occupant_at(&q_true), &set, &self.hw)?;
        Ok(Outcome {
            pretensioner_shift_ms: shift_ms,
            fallback,
            a_max_g: mps2_to_g(o.max_decel_mps2),
            a_mean_g: mps2_to_g(o.mean_decel_mps2),
            excursion_mm: o.max_excursion_m * 1e3,
            bottoming_out: o.bottomed_out,
        })
    }

    /// Outcome with the given estimate errors: the table is queried at the disturbed speed
    /// and mass; the contact is predicted from the disturbed distance and speed at the last
    /// object sample (`measurement_ttc_ms` before contact), i.e. off by `d_est/v_est − d/v`.
    pub fn evaluate(
        &self,
        mass_err_kg: f64,
        speed_err_kph: f64,
        dist_err_m: f64,
    ) -> Result<Sample> {
        let s = &self.situation;
        let est_kph = s.closing_speed_kph + speed_err_kph;
        let t_s = self.errors.measurement_ttc_ms * 1e-3;
        let v_mps = s.closing_speed_kph / 3.6;
        let est_ttc_s = (v_mps * t_s + dist_err_m) / (est_kph / 3.6);
        let o = self.outcome(&Estimate {
            closing_speed_kph: est_kph,
            opponent_mass_kg: s.opponent_mass_kg + mass_err_kg,
            contact_error_s: est_ttc_s - t_s,
        })?;
        Ok(Sample {
            mass_error_kg: mass_err_kg,
            speed_error_kph: speed_err_kph,
            distance_error_m: dist_err_m,
            pretensioner_shift_ms: o.pretensioner_shift_ms,
            fallback: o.fallback,
            a_max_g: o.a_max_g,
            a_mean_g: o.a_mean_g,
            excursion_mm: o.excursion_mm,
            bottoming_out: o.bottoming_out,
        })
    }

    /// Sample `index`.
    pub fn sample(&self, index: u64) -> Result<Sample> {
        let (m, v, d) = draw_errors(&self.errors, self.seed, index);
        self.evaluate(m, v, d)
    }

    /// Samples `range` in parallel (results in index order).
    pub fn samples(
        &self,
        range: std::ops::Range<usize>,
        threads: Option<usize>,
        progress: &Progress,
    ) -> Result<Vec<Sample>> {
        let mut b = rayon::ThreadPoolBuilder::new();
        if let Some(n) = threads {
            b = b.num_threads(n);
        }
        let pool = b.build().context("cannot start the rayon thread pool")?;
        pool.install(|| {
            range
                .into_par_iter()
                .map(|i| {
                    let s = self.sample(i as u64);
                    progress.inc();
                    s
                })
                .collect()
        })
    }
}

impl RobustnessJob {
    /// Identity: the table's content (CRC), situation, errors, samples, seed — not the path.
    pub fn identity(&self) -> Result<String> {
        shard::identity_of(
            SHARD_KIND,
            &(
                self.table_crc32c,
                &self.situation,
                &self.errors,
                self.samples,
                self.seed,
            ),
        )
    }

    /// Number of samples.
    pub fn samples(&self) -> usize {
        self.samples as usize
    }

    /// Compute shard `k` of `n` (encoded shard file).
    pub fn compute_shard(
        &self,
        k: usize,
        n: usize,
        threads: Option<usize>,
        progress: &Progress,
    ) -> Result<Vec<u8>> {
        let header = ShardHeader::new(SHARD_KIND, &self.identity()?, k, n, self.samples())?;
        let samples = Sampler::new(self)?.samples(header.range(), threads, progress)?;
        ShardFile {
            header,
            payload: Samples(samples),
        }
        .to_bytes()
    }

    /// Statistics of all samples (in index order).
    pub fn summarise(&self, samples: &[Sample]) -> Result<StudyResult> {
        let ctx = Sampler::new(self)?;
        let exact = ctx.evaluate(0.0, 0.0, 0.0)?;
        let col = |f: fn(&Sample) -> f64| samples.iter().map(f).collect::<Vec<f64>>();
        let exact_obj = exact.a_max_g + exact.a_mean_g;
        let a_mean = col(|s| s.a_mean_g);
        let a_max = col(|s| s.a_max_g);
        Ok(StudyResult {
            format: RESULT_FORMAT.into(),
            identity: self.identity()?,
            study: self.clone(),
            exact_estimate: exact,
            fallback_samples: samples.iter().filter(|s| s.fallback).count() as u64,
            bottoming_out_samples: samples.iter().filter(|s| s.bottoming_out).count() as u64,
            a_max_g: Spread::of(&a_max),
            a_mean_g: Spread::of(&a_mean),
            excursion_mm: Spread::of(&col(|s| s.excursion_mm)),
            objective_increase_g: Spread::of(
                &samples
                    .iter()
                    .map(|s| s.a_max_g + s.a_mean_g - exact_obj)
                    .collect::<Vec<_>>(),
            ),
            a_mean_histogram: Histogram::of(&a_mean, 40),
            a_max_histogram: Histogram::of(&a_max, 40),
        })
    }

    /// Run the whole study here.
    pub fn run_local(&self, threads: Option<usize>, quiet: bool) -> Result<StudyResult> {
        let progress = Progress::new(self.samples(), "sampling", "samples", quiet);
        let samples = Sampler::new(self)?.samples(0..self.samples(), threads, &progress)?;
        progress.finish();
        self.summarise(&samples)
    }

    /// Merge shards, summarise, write the result atomically.
    pub fn collect(
        &self,
        identity: &str,
        shards: &[(String, Vec<u8>)],
        out: &Path,
    ) -> Result<String> {
        let decoded = shards
            .iter()
            .map(|(o, b)| Ok((o.clone(), read_shard(o, b)?)))
            .collect::<Result<Vec<_>>>()?;
        let heads: Vec<(&str, &ShardHeader)> = decoded
            .iter()
            .map(|(o, s)| (o.as_str(), &s.header))
            .collect();
        let order = shard::check_tiling(&heads, Some(identity))?;
        let samples: Vec<Sample> = order
            .iter()
            .flat_map(|&i| decoded[i].1.payload.0.iter().copied())
            .collect();
        let r = self.summarise(&samples)?;
        write_result(&r, out)?;
        Ok(summary_line(&r, out))
    }
}

/// Read and check one robustness shard file.
pub fn read_shard(origin: &str, bytes: &[u8]) -> Result<ShardFile<Samples>> {
    ShardFile::<Samples>::from_bytes(origin, SHARD_KIND, bytes)
}

/// Write the result JSON atomically.
pub fn write_result(r: &StudyResult, out: &Path) -> Result<()> {
    let mut text = crate::json_out::text(r)?;
    text.push('\n');
    Ok(diagram::write_atomically(out, text.as_bytes())?)
}

/// Read a result JSON.
pub fn read_result(path: &Path) -> Result<StudyResult> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
    let r: StudyResult = serde_json::from_str(&text)
        .with_context(|| format!("{}: not a study result", path.display()))?;
    if r.format != RESULT_FORMAT {
        bail!(
            "{}: format {:?}, not {RESULT_FORMAT:?}",
            path.display(),
            r.format
        );
    }
    Ok(r)
}

/// `out` holds the result of the study with `identity`.
pub fn output_matches(out: &Path, identity: &str) -> bool {
    read_result(out).is_ok_and(|r| r.identity == identity)
}

/// One line about a result.
pub fn summary_line(r: &StudyResult, out: &Path) -> String {
    format!(
        "{}: {} samples; a_mean {:.2} g (sd {:.2}, 5–95 % {:.2}–{:.2}), a_max {:.2} g (sd {:.2}, 5–95 % {:.2}–{:.2}); exact estimate {:.2} / {:.2} g; {} bottoming-out, {} outside the table",
        out.display(),
        r.study.samples,
        r.a_mean_g.mean,
        r.a_mean_g.sd,
        r.a_mean_g.p05,
        r.a_mean_g.p95,
        r.a_max_g.mean,
        r.a_max_g.sd,
        r.a_max_g.p05,
        r.a_max_g.p95,
        r.exact_estimate.a_mean_g,
        r.exact_estimate.a_max_g,
        r.bottoming_out_samples,
        r.fallback_samples
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn moments(v: &[f64]) -> (f64, f64) {
        let s = Spread::of(v);
        (s.mean, s.sd)
    }

    // The sampler against distribution theory: uniform ±a has mean 0, sd a/√3; the normal
    // draws have mean 0 and the requested σ. Tolerances are ~4 standard errors at n = 20 000.
    #[test]
    fn error_draws_follow_their_distributions() {
        let e = EstimateErrors {
            mass_error_kg: 300.0,
            speed_sigma_kph: 2.0,
            distance_sigma_m: 0.1,
            measurement_ttc_ms: 100.0,
        };
        let n = 20_000u64;
        let d: Vec<(f64, f64, f64)> = (0..n).map(|i| draw_errors(&e, 42, i)).collect();
        let m: Vec<f64> = d.iter().map(|x| x.0).collect();
        let v: Vec<f64> = d.iter().map(|x| x.1).collect();
        let x: Vec<f64> = d.iter().map(|x| x.2).collect();
        assert!(m.iter().all(|&m| (-300.0..300.0).contains(&m)));
        let se = 1.0 / (n as f64).sqrt();
        let (mm, ms) = moments(&m);
        assert!(mm.abs() < 4.0 * 173.2 * se, "{mm}");
        assert!((ms / (300.0 / 3f64.sqrt()) - 1.0).abs() < 4.0 * se, "{ms}");
        let (vm, vs) = moments(&v);
        assert!(
            vm.abs() < 4.0 * 2.0 * se && (vs / 2.0 - 1.0).abs() < 4.0 * se * 0.71 + 0.01,
            "{vm} {vs}"
        );
        let (xm, xs) = moments(&x);
        assert!(
            xm.abs() < 4.0 * 0.1 * se && (xs / 0.1 - 1.0).abs() < 0.03,
            "{xm} {xs}"
        );
        // About 68.3 % of normal draws within one σ.
        let within = v.iter().filter(|v| v.abs() < 2.0).count() as f64 / n as f64;
        assert!((within - 0.6827).abs() < 0.015, "{within}");
        // Reproducible per index, different across indices and seeds.
        assert_eq!(draw_errors(&e, 42, 7), d[7]);
        assert_ne!(draw_errors(&e, 43, 7), d[7]);
    }

    #[test]
    fn spread_uses_nearest_rank() {
        let v: Vec<f64> = (1..=100).rev().map(f64::from).collect();
        let s = Spread::of(&v);
        assert_eq!(
            (s.min, s.p05, s.p50, s.p95, s.max),
            (1.0, 5.0, 50.0, 95.0, 100.0)
        );
        assert!((s.mean - 50.5).abs() < 1e-12);
        assert!((s.sd - 29.011_491_975_882_016).abs() < 1e-9);
        let h = Histogram::of(&v, 4);
        assert_eq!((h.from, h.above), (1.0, 1));
        assert_eq!(h.counts, vec![25, 24, 25, 25]);
    }
}
