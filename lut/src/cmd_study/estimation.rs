//! `lut study estimation`: the ECU's track filter against the newest-sample estimate
//! (lut::estimation), a table of the errors at contact and the occupant outcome, and a plot of
//! one case's estimate with its σ band against the truth.

use crate::plot;
use anyhow::{anyhow, Context, Result};
use clap::Args;
use diagram::Diagram;
use lut::estimation::{self, Held, Percentiles, Row, StudyResult, VARIATIONS};
use lut::progress::Progress;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::PathBuf;

#[derive(Args, Debug)]
pub struct EstimationArgs {
    /// Folder of scenario files (every one with a contact is used).
    #[arg(long, default_value = "scenarios", value_parser = lut::paths::input_file)]
    pub scenarios: PathBuf,
    /// The table the occupant outcome is looked up in.
    #[arg(long = "lut", alias = "table", default_value = "data/default.lut", value_parser = lut::paths::input_file, value_name = "FILE")]
    pub table: PathBuf,
    /// Noise seeds per scenario and variation.
    #[arg(long, default_value_t = 40)]
    pub runs: u64,
    /// Base seed (run i uses SplitMix64(seed ⊕ SplitMix64(i))).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Result file (JSON).
    #[arg(
        long = "json",
        alias = "out",
        value_name = "FILE",
        default_value = "estimation.json"
    )]
    pub out: PathBuf,
    /// Worker threads [default: all cores].
    #[arg(long)]
    pub threads: Option<usize>,
    /// No progress output.
    #[arg(long)]
    pub quiet: bool,
    /// Plot one case: estimate ± σ against the truth (PNG, or SVG if .svg).
    #[arg(long)]
    pub plot: Option<PathBuf>,
    /// Scenario of the plot.
    #[arg(long, default_value = "noisy-mass-estimate")]
    pub plot_scenario: String,
    /// Variation of the plot (index into the study's variations: 0 nominal, 1 noise ×3, …).
    #[arg(long, default_value_t = 1)]
    pub plot_variation: usize,
}

pub fn run(a: &EstimationArgs) -> Result<()> {
    anyhow::ensure!(a.runs >= 1, "--runs must be ≥ 1");
    let table = Diagram::load(&a.table).map_err(|e| anyhow!("{}: {e}", a.table.display()))?;
    let scenarios = estimation::load_scenarios(&a.scenarios, &table)?;
    anyhow::ensure!(
        !scenarios.is_empty(),
        "{}: no scenario with a contact",
        a.scenarios.display()
    );
    let total = scenarios.len() * VARIATIONS.len() * a.runs as usize;
    let progress = Progress::new(total, "estimation study", "runs", a.quiet);
    let mut pool = rayon::ThreadPoolBuilder::new();
    if let Some(n) = a.threads {
        pool = pool.num_threads(n);
    }
    let pool = pool.build().context("cannot start the rayon thread pool")?;
    let r = pool.install(|| estimation::study(&scenarios, a.runs, a.seed, &|| progress.inc()))?;
    progress.finish();
    let mut text = lut::json_out::text(&r)?;
    text.push('\n');
    diagram::write_atomically(&a.out, text.as_bytes())?;
    print!("{}", table_text(&r));
    eprintln!("result written to {}", a.out.display());
    if let Some(p) = &a.plot {
        let sc = scenarios
            .iter()
            .find(|s| s.scenario.name == a.plot_scenario)
            .ok_or_else(|| anyhow!("no scenario {:?} with a contact", a.plot_scenario))?;
        let var = VARIATIONS
            .get(a.plot_variation)
            .ok_or_else(|| anyhow!("--plot-variation must be < {}", VARIATIONS.len()))?;
        let run = estimation::simulate(&sc.scenario, var, a.seed, 0, true)?;
        plot::render(
            p,
            (1000, 900),
            &TraceFigure {
                title: format!("{} ({}), run 0", sc.scenario.name, var.name),
                run: &run,
            },
        )?;
        eprintln!("plot written to {}", p.display());
    }
    Ok(())
}

fn cell(p: &[Percentiles; 2], digits: usize) -> String {
    let f = |x: f64| format!("{x:.digits$}");
    format!(
        "{} / {} | {} / {}",
        f(p[0].p50),
        f(p[0].p95),
        f(p[1].p50),
        f(p[1].p95)
    )
}

/// The per-variation table (markdown): raw p50 / p95 | filtered p50 / p95.
pub fn table_text(r: &StudyResult) -> String {
    let mut s = format!(
        "{} scenarios × {} runs per variation (seed {}); at the last cycle before contact; raw p50 / p95 | filtered p50 / p95\n\n",
        r.scenarios.len(),
        r.runs,
        r.seed
    );
    s.push_str("| variation | contact instant, ms | closing speed, km/h | opponent mass, kg | occupant a_max + a_mean over exact, g | filtered within 2σ (t / v / m) | outliers, starts per run | no estimate (raw / filtered) |\n|---|---|---|---|---|---|---|---|\n");
    let rows: &[Row] = &r.variations;
    for row in rows {
        s.push_str(&format!(
            "| {} | {} | {} | {} | {} | {:.0} % / {:.0} % / {:.0} % | {:.2}, {:.2} | {} / {} of {} |\n",
            row.name,
            cell(&row.contact_ms, 1),
            cell(&row.closing_speed_kph, 2),
            cell(&row.mass_kg, 0),
            cell(&row.objective_increase_g, 2),
            100.0 * row.within_2_sigma[0],
            100.0 * row.within_2_sigma[1],
            100.0 * row.within_2_sigma[2],
            row.outliers_per_run,
            row.starts_per_run,
            row.missing[0],
            row.missing[1],
            row.runs
        ));
    }
    s
}

/// Estimate ± σ against the truth over the last second before contact.
struct TraceFigure<'a> {
    title: String,
    run: &'a estimation::Run,
}

impl TraceFigure<'_> {
    /// One panel: `value` of the filtered (band ± σ) and raw estimates against `truth`.
    #[allow(clippy::too_many_arguments)]
    fn panel<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        caption: &str,
        y_label: &str,
        truth: f64,
        value: &dyn Fn(&Held) -> f64,
        sigma: &dyn Fn(&Held) -> f64,
        half_range: f64,
    ) -> Result<()>
    where
        DB::ErrorType: 'static,
    {
        let tc = self.run.contact_s;
        let pts: Vec<_> = self
            .run
            .trace
            .iter()
            .filter(|p| p.t_s >= tc - 1.0)
            .collect();
        let x = |t: f64| (t - tc) * 1e3;
        let mut chart = ChartBuilder::on(area)
            .caption(caption, ("sans-serif", 18))
            .margin(10)
            .x_label_area_size(35)
            .y_label_area_size(60)
            .build_cartesian_2d(-1000.0..0.0, (truth - half_range)..(truth + half_range))?;
        chart
            .configure_mesh()
            .x_desc("time before the true contact [ms]")
            .y_desc(y_label)
            .draw()?;
        let band: Vec<(f64, f64, f64)> = pts
            .iter()
            .filter_map(|p| {
                p.filtered
                    .map(|h| (x(p.t_s), value(&h), sigma(&h)))
                    .filter(|(_, v, s)| v.is_finite() && s.is_finite())
            })
            .collect();
        let mut poly: Vec<(f64, f64)> = band.iter().map(|(t, v, s)| (*t, v + s)).collect();
        poly.extend(band.iter().rev().map(|(t, v, s)| (*t, v - s)));
        chart
            .draw_series(std::iter::once(Polygon::new(poly, BLUE.mix(0.2).filled())))?
            .label("filtered ± σ")
            .legend(|(x, y)| Rectangle::new([(x, y - 5), (x + 15, y + 5)], BLUE.mix(0.2).filled()));
        chart
            .draw_series(LineSeries::new(
                band.iter().map(|(t, v, _)| (*t, *v)),
                &BLUE,
            ))?
            .label("filtered (restraint core)")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 15, y)], BLUE));
        chart
            .draw_series(
                pts.iter()
                    .filter(|p| p.sample)
                    .filter_map(|p| p.raw.map(|h| (x(p.t_s), value(&h))))
                    .map(|(t, v)| Circle::new((t, v), 3, RED.filled())),
            )?
            .label("newest sample alone (no track filter)")
            .legend(|(x, y)| Circle::new((x + 7, y), 3, RED.filled()));
        chart
            .draw_series(LineSeries::new(
                [(-1000.0, truth), (0.0, truth)],
                BLACK.stroke_width(2),
            ))?
            .label("truth")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 15, y)], BLACK.stroke_width(2)));
        chart
            .configure_series_labels()
            .border_style(BLACK)
            .background_style(WHITE.mix(0.8))
            .position(SeriesLabelPosition::UpperLeft)
            .draw()?;
        Ok(())
    }
}

impl plot::Figure for TraceFigure<'_> {
    fn draw_on<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()>
    where
        DB::ErrorType: 'static,
    {
        root.fill(&WHITE)?;
        let (top, rest) = root.split_vertically(40);
        top.titled(&self.title, ("sans-serif", 22))?;
        let areas = rest.split_evenly((3, 1));
        let tc = self.run.contact_s;
        let r = self.run;
        self.panel(
            &areas[0],
            "predicted contact instant − true contact",
            "ms",
            0.0,
            &|h| (h.contact_s - tc) * 1e3,
            &|h| h.contact_sigma_s * 1e3,
            60.0,
        )?;
        self.panel(
            &areas[1],
            "closing speed at contact",
            "km/h",
            r.closing_speed_mps * 3.6,
            &|h| h.closing_speed_mps * 3.6,
            &|h| h.closing_speed_sigma_mps * 3.6,
            14.0,
        )?;
        let m = if r.opponent_mass_kg.is_finite() {
            r.opponent_mass_kg
        } else {
            0.0
        };
        self.panel(
            &areas[2],
            "opponent mass (the LUT is queried at m + σ)",
            "kg",
            m,
            &|h| h.mass_kg,
            &|h| h.mass_sigma_kg,
            1500.0,
        )?;
        Ok(())
    }
}
