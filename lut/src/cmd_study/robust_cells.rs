//! `lut study robust-cells`: robust cells against today's two rules on the library's nominal
//! belted car-to-car cases (`lut::robust_cells`).

use anyhow::Result;
use clap::Args;
use lut::optimise::OptimiserConfig;
use lut::robust_cells::{
    point_optimum, Judged, Situation, UncertainSet, Uncertainty, LIBRARY_CASES, LIBRARY_OCCUPANT,
};
use lut::scenario::Ego;
use lut::table::Grid;
use physics::reference::ReferenceRestraint;
use physics::RestraintSettings;
use rayon::prelude::*;
use serde_json::json;
use std::path::{Path, PathBuf};

#[derive(Args, Debug)]
pub struct RobustCellsArgs {
    /// Reference restraint file.
    #[arg(long, default_value = "data/reference-restraint.toml", value_parser = lut::paths::input_file)]
    pub reference: PathBuf,
    /// The grid whose optimiser settings the cells use.
    #[arg(long, default_value = "data/default-grid.toml", value_parser = lut::paths::input_file)]
    pub grid: PathBuf,
    /// Opponent mass half-width of the set [kg].
    #[arg(long = "mass-error-kg", alias = "mass-kg", default_value_t = Uncertainty::MISREPORT.mass_kg, value_name = "MASS_ERROR_KG")]
    pub mass_kg: f64,
    /// Closing speed half-width of the set [km/h].
    #[arg(long = "speed-error-kph", alias = "speed-kph", default_value_t = Uncertainty::MISREPORT.speed_kph, value_name = "SPEED_ERROR_KPH")]
    pub speed_kph: f64,
    /// Both errors at once (the box's corners), not only one at a time.
    #[arg(long)]
    pub corners: bool,
    /// JSON instead of the table: into FILE, or on stdout without one (or with `-`).
    #[arg(long, value_name = "FILE", num_args = 0..=1, default_missing_value = "-")]
    pub json: Option<PathBuf>,
}

/// The reference restraint's settings and the grid's optimiser settings the margin studies
/// plan with.
pub fn load_settings(
    reference: &Path,
    grid: &Path,
) -> Result<(RestraintSettings, OptimiserConfig)> {
    let reference = ReferenceRestraint::load(reference)
        .map_err(anyhow::Error::msg)?
        .settings();
    Ok((reference, Grid::load(grid)?.optimiser))
}

pub fn run(a: &RobustCellsArgs) -> Result<()> {
    let (reference, cfg) = load_settings(&a.reference, &a.grid)?;
    let u = Uncertainty {
        mass_kg: a.mass_kg,
        speed_kph: a.speed_kph,
        corners: a.corners,
    };
    let ego = Ego::default();
    let occupant = LIBRARY_OCCUPANT;
    let rows: Vec<(&str, [Judged; 3])> = LIBRARY_CASES
        .par_iter()
        .map(|&(name, v, m)| -> Result<(&str, [Judged; 3])> {
            let s = Situation {
                closing_kph: v,
                opponent_kg: m,
                occupant,
            };
            let set = UncertainSet::new(&ego, &s, &u, &reference, cfg.reserve_m)?;
            let none = point_optimum(&ego, &occupant, v, m, &cfg)?;
            let margin = point_optimum(&ego, &occupant, v, m + u.mass_kg, &cfg)?;
            let robust = set.robust_optimum(&cfg)?;
            Ok((
                name,
                [set.judge(&none)?, set.judge(&margin)?, set.judge(&robust)?],
            ))
        })
        .collect::<Result<_>>()?;
    const RULES: [&str; 3] = ["no margin", "+mass margin", "robust cell"];
    if let Some(to) = &a.json {
        let v: Vec<_> = rows
            .iter()
            .map(|(n, j)| json!({ "case": n, RULES[0]: j[0], RULES[1]: j[1], RULES[2]: j[2] }))
            .collect();
        lut::json_out::write(to, &json!({ "set": u, "cases": v }))?;
        return Ok(());
    }
    println!(
        "a_max + a_mean against the reference restraint, %: nominal (estimate = truth) / worst over the set (opponent ± {:.0} kg, closing ± {:.0} km/h, {}) / points bottoming out where the reference does not",
        u.mass_kg,
        u.speed_kph,
        if u.corners { "both at once: 9 points" } else { "one at a time: 5 points" }
    );
    println!(
        "{:<22} {:>24} {:>24} {:>24}",
        "case", RULES[0], RULES[1], RULES[2]
    );
    let cell = |j: &Judged| {
        format!(
            "{:+6.1} / {:+6.1} / {}",
            j.nominal_change_pct, j.worst_change_pct, j.bottoms_out_alone
        )
    };
    for (n, j) in &rows {
        println!(
            "{n:<22} {:>24} {:>24} {:>24}",
            cell(&j[0]),
            cell(&j[1]),
            cell(&j[2])
        );
    }
    let mean = |k: usize| {
        rows.iter()
            .map(|(_, j)| j[k].nominal_change_pct)
            .sum::<f64>()
            / rows.len() as f64
    };
    println!(
        "{:<22} {:>24.1} {:>24.1} {:>24.1}",
        "mean nominal",
        mean(0),
        mean(1),
        mean(2)
    );
    Ok(())
}
