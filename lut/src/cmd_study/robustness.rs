//! `lut study robustness`: the Monte-Carlo study of the pre-crash estimate's errors
//! (lut::robustness), locally or as a Slurm job array.

use crate::cmd_slurm::SlurmArgs;
use crate::plot;
use anyhow::{anyhow, Result};
use clap::Args;
use diagram::Diagram;
use lut::distributed::Job;
use lut::robustness::{self, EstimateErrors, RobustnessJob, Situation, StudyResult};
use std::path::{Path, PathBuf};

#[derive(Args, Debug)]
pub struct RobustnessArgs {
    /// The table the ECU uses.
    #[arg(long = "lut", alias = "table", default_value = "data/default.lut", value_parser = lut::paths::input_file, value_name = "FILE")]
    pub table: PathBuf,
    /// True closing speed [km/h].
    #[arg(
        long = "closing-speed-kph",
        alias = "closing-kph",
        default_value_t = 91.0,
        value_name = "CLOSING_SPEED_KPH"
    )]
    pub closing_kph: f64,
    /// True opponent mass [kg].
    #[arg(long, default_value_t = 1800.0)]
    pub opponent_mass_kg: f64,
    /// Occupant mass [kg].
    #[arg(
        long = "occupant-mass-kg",
        alias = "occupant-kg",
        default_value_t = 75.0,
        value_name = "OCCUPANT_MASS_KG"
    )]
    pub occupant_kg: f64,
    /// Seat distance chest to wheel [mm].
    #[arg(long, default_value_t = 300.0)]
    pub seat_mm: f64,
    /// Opponent mass (payload) error: uniform in ± this [kg].
    #[arg(long, default_value_t = 300.0)]
    pub mass_error_kg: f64,
    /// Closing speed error: normal with this σ [km/h].
    #[arg(long, default_value_t = 2.0)]
    pub speed_sigma_kph: f64,
    /// Distance error of the last object sample: normal with this σ [m].
    #[arg(long, default_value_t = 0.1)]
    pub distance_sigma_m: f64,
    /// The last object sample is taken this long before contact [ms].
    #[arg(long, default_value_t = 100.0)]
    pub measurement_ttc_ms: f64,
    /// Number of samples.
    #[arg(long, default_value_t = 2000)]
    pub samples: u64,
    /// Seed (sample i uses SplitMix64(seed ⊕ SplitMix64(i))).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Result file (JSON).
    #[arg(
        long = "json",
        alias = "out",
        value_name = "FILE",
        default_value = "robustness.json"
    )]
    pub out: PathBuf,
    /// Worker threads of a local run [default: all cores].
    #[arg(long)]
    pub threads: Option<usize>,
    /// No progress output.
    #[arg(long)]
    pub quiet: bool,
    /// Histograms of a_mean and a_max (PNG, or SVG if .svg).
    #[arg(long)]
    pub plot: Option<PathBuf>,
    #[command(flatten)]
    pub slurm: SlurmArgs,
}

impl RobustnessArgs {
    fn job(&self) -> Result<RobustnessJob> {
        let e = EstimateErrors {
            mass_error_kg: self.mass_error_kg,
            speed_sigma_kph: self.speed_sigma_kph,
            distance_sigma_m: self.distance_sigma_m,
            measurement_ttc_ms: self.measurement_ttc_ms,
        };
        let ok = |v: f64| v.is_finite() && v >= 0.0;
        let sizes_ok = ok(e.mass_error_kg) && ok(e.speed_sigma_kph) && ok(e.distance_sigma_m);
        if !(sizes_ok && e.measurement_ttc_ms.is_finite() && e.measurement_ttc_ms > 0.0) {
            return Err(anyhow!(
                "error sizes must be finite and ≥ 0, --measurement-ttc-ms > 0"
            ));
        }
        if self.samples == 0 {
            return Err(anyhow!("--samples must be ≥ 1"));
        }
        let table = std::path::absolute(&self.table)?;
        let d = Diagram::load(&table)?;
        let job = RobustnessJob {
            table,
            table_crc32c: d.checksum(),
            situation: Situation {
                closing_speed_kph: self.closing_kph,
                opponent_mass_kg: self.opponent_mass_kg,
                occupant_mass_kg: self.occupant_kg,
                seat_distance_mm: self.seat_mm,
            },
            errors: e,
            samples: self.samples,
            seed: self.seed,
        };
        // Fails early on a situation outside the physics (e.g. a mass no class covers).
        robustness::Sampler::new(&job)?.evaluate(0.0, 0.0, 0.0)?;
        Ok(job)
    }
}

pub fn run(a: &RobustnessArgs) -> Result<()> {
    let job = a.job()?;
    match a.slurm.slurm {
        Some(n) => a.slurm.run(n, Job::Robustness(job), &a.out)?,
        None => {
            let r = job.run_local(a.threads, a.quiet)?;
            robustness::write_result(&r, &a.out)?;
        }
    }
    if a.slurm.no_wait {
        return Ok(());
    }
    let r = robustness::read_result(&a.out)?;
    println!("{}", robustness::summary_line(&r, &a.out));
    if let Some(p) = &a.plot {
        draw(&r, p)?;
        eprintln!("plot written to {}", p.display());
    }
    Ok(())
}

/// Percentage of all samples per histogram bin, at the bins' centres.
fn percent_bins(h: &robustness::Histogram) -> (Vec<f64>, Vec<f64>) {
    let n: u64 = h.counts.iter().sum::<u64>() + h.above;
    h.counts
        .iter()
        .enumerate()
        .map(|(i, &c)| {
            (
                h.from + (i as f64 + 0.5) * h.width,
                100.0 * c as f64 / n.max(1) as f64,
            )
        })
        .unzip()
}

/// One histogram panel with the exact-estimate value marked.
fn histogram_panel<'a>(
    title: String,
    x_label: &'a str,
    name: &str,
    bins: &'a (Vec<f64>, Vec<f64>),
    marker: &'a [[f64; 2]; 2],
) -> plot::Panel<'a> {
    plot::Panel {
        title,
        x_label,
        y_label: "samples [%]",
        series: vec![
            plot::Series {
                label: name.into(),
                x: &bins.0,
                y: &bins.1,
            },
            plot::Series {
                label: format!("exact estimate {:.2} g", marker[0][0]),
                x: &marker[0],
                y: &marker[1],
            },
        ],
    }
}

fn draw(r: &StudyResult, path: &Path) -> Result<()> {
    let mean = percent_bins(&r.a_mean_histogram);
    let max = percent_bins(&r.a_max_histogram);
    let top = |b: &(Vec<f64>, Vec<f64>)| b.1.iter().copied().fold(0.0, f64::max);
    let (xm, xx) = (r.exact_estimate.a_mean_g, r.exact_estimate.a_max_g);
    let mean_marker = [[xm, xm], [0.0, top(&mean)]];
    let max_marker = [[xx, xx], [0.0, top(&max)]];
    let s = &r.study.situation;
    let e = &r.study.errors;
    plot::draw(
        path,
        &[
            histogram_panel(
                format!(
                    "{} samples: {} km/h, {} kg opponent, {} kg occupant, {} mm; mass ±{} kg, speed σ {} km/h, distance σ {} m",
                    r.study.samples, s.closing_speed_kph, s.opponent_mass_kg, s.occupant_mass_kg,
                    s.seat_distance_mm, e.mass_error_kg, e.speed_sigma_kph, e.distance_sigma_m
                ),
                "occupant a_mean [g]",
                "a_mean",
                &mean,
                &mean_marker,
            ),
            histogram_panel(
                format!(
                    "occupant peak acceleration ({} samples above the 99th percentile, max {:.1} g, not drawn; {} of {} bottom out)",
                    r.a_max_histogram.above, r.a_max_g.max, r.bottoming_out_samples, r.study.samples
                ),
                "occupant a_max [g]",
                "a_max",
                &max,
                &max_marker,
            ),
        ],
    )
}
