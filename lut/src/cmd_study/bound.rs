//! `lut study bound`: the table's a_max / a* and what keeps the optima from the bound
//! (`lut::bound`).

use anyhow::{anyhow, Result};
use clap::Args;
use diagram::Diagram;
use lut::bound::{levers, table_ratios};
use serde_json::json;
use std::path::PathBuf;

#[derive(Args, Debug)]
pub struct BoundArgs {
    /// The table.
    #[arg(long = "lut", alias = "table", default_value = "data/default.lut", value_parser = lut::paths::input_file, value_name = "FILE")]
    pub table: PathBuf,
    /// Cells re-optimised under each lever.
    #[arg(long, default_value_t = 24)]
    pub samples: usize,
    /// Seed of the cell sample.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// JSON instead of the table: into FILE, or on stdout without one (or with `-`).
    #[arg(long, value_name = "FILE", num_args = 0..=1, default_missing_value = "-")]
    pub json: Option<PathBuf>,
}

pub fn run(a: &BoundArgs) -> Result<()> {
    let d = Diagram::load_any(&a.table).map_err(|e| anyhow!("{}: {e}", a.table.display()))?;
    let t = table_ratios(&d)?;
    let rows = levers(&d, a.samples, a.seed)?;
    if let Some(to) = &a.json {
        lut::json_out::write(to, &json!({ "table": t, "levers": rows }))?;
        return Ok(());
    }
    let at = |q: &diagram::Query| {
        format!(
            "{:.1} km/h, opponent {:.0} kg, occupant {:.0} kg, seat {:.0} mm",
            q.closing_speed_kph, q.opponent_mass_kg, q.occupant_mass_kg, q.seat_distance_mm
        )
    };
    println!(
        "a_max / a* over {} cells of {} ({} bottoming out or without a*, left out):",
        t.cells,
        a.table.display(),
        t.left_out
    );
    println!("  p50 {:.2}, p90 {:.2}", t.p50, t.p90);
    println!("  best  {:.2} at {}", t.best.ratio, at(&t.best.query));
    println!("  worst {:.2} at {}", t.worst.ratio, at(&t.worst.query));
    println!("  closing km/h   p50   worst");
    for (v, p50, worst) in &t.by_closing_speed {
        println!("  {v:>11.1} {p50:>5.2} {worst:>7.2}");
    }
    println!(
        "\nlevers: {} cells (seed {}) re-optimised with one limitation of the restraint model lifted",
        a.samples, a.seed
    );
    println!(
        "  {:<18} {:>8} {:>7} {:>7} {:>14}",
        "lever", "feasible", "p50", "worst", "a_max+a_mean g"
    );
    for r in &rows {
        println!(
            "  {:<18} {:>8} {:>7.2} {:>7.2} {:>14.1}",
            r.lever.name, r.feasible, r.p50, r.worst, r.objective_p50_g
        );
    }
    Ok(())
}
