//! `lut study limiter-switch`: a two-level load limiter switched on what the pulse shows,
//! against today's rules on the library's nominal belted car-to-car cases
//! (`lut::limiter_switch`).

use super::robust_cells::load_settings;
use crate::plot;
use anyhow::{bail, Result};
use clap::Args;
use lut::limiter_switch::{speed_lost_by_mps, JudgedTwoLevel, SwitchRule};
use lut::robust_cells::{
    point_optimum, Judged, Situation, UncertainSet, Uncertainty, LIBRARY_CASES, LIBRARY_OCCUPANT,
};
use lut::scenario::{Ego, Opponent, Pulse};
use rayon::prelude::*;
use serde_json::json;
use std::path::PathBuf;

#[derive(Args, Debug)]
pub struct LimiterSwitchArgs {
    /// Reference restraint file.
    #[arg(long, default_value = "data/reference-restraint.toml", value_parser = lut::paths::input_file)]
    pub reference: PathBuf,
    /// The grid whose optimiser settings the plans use.
    #[arg(long, default_value = "data/default-grid.toml", value_parser = lut::paths::input_file)]
    pub grid: PathBuf,
    /// Switch times after contact [ms], comma-separated.
    #[arg(long, value_delimiter = ',', default_values_t = [30.0, 40.0, 50.0])]
    pub switch_ms: Vec<f64>,
    /// Opponent mass half-width of the set (and the margin of today's rule) [kg].
    #[arg(long = "mass-error-kg", alias = "mass-kg", default_value_t = Uncertainty::MISREPORT.mass_kg, value_name = "MASS_ERROR_KG")]
    pub mass_kg: f64,
    /// Closing speed half-width of the set [km/h].
    #[arg(long = "speed-error-kph", alias = "speed-kph", default_value_t = Uncertainty::MISREPORT.speed_kph, value_name = "SPEED_ERROR_KPH")]
    pub speed_kph: f64,
    /// The measured speed loss reads this much low [%] (sensitivity error of the accelerometer,
    /// in the direction that switches a heavy crash down).
    #[arg(long, default_value_t = 0.0)]
    pub evidence_error_pct: f64,
    /// Both errors at once (the box's corners), not only one at a time.
    #[arg(long)]
    pub corners: bool,
    /// JSON instead of the table: into FILE, or on stdout without one (or with `-`).
    #[arg(long, value_name = "FILE", num_args = 0..=1, default_missing_value = "-")]
    pub json: Option<PathBuf>,
    /// Also plot (SVG if .svg, else PNG) how little the heavier opponent shows in the speed the
    /// ego has lost, for the 48 + 48 km/h Taurus case.
    #[arg(long, value_name = "FILE")]
    pub plot: Option<PathBuf>,
}

struct Row {
    name: &'static str,
    none: Judged,
    margin: Judged,
    switched: Vec<(SwitchRule, JudgedTwoLevel)>,
}

pub fn run(a: &LimiterSwitchArgs) -> Result<()> {
    if a.switch_ms.is_empty() || a.switch_ms.iter().any(|t| !(*t > 0.0 && *t <= 200.0)) {
        bail!("--switch-ms: times in (0, 200] ms");
    }
    if !(0.0..50.0).contains(&a.evidence_error_pct) {
        bail!("--evidence-error-pct: in [0, 50)");
    }
    let (reference, cfg) = load_settings(&a.reference, &a.grid)?;
    let u = Uncertainty {
        mass_kg: a.mass_kg,
        speed_kph: a.speed_kph,
        corners: a.corners,
    };
    let ego = Ego::default();
    let occupant = LIBRARY_OCCUPANT;
    if let Some(path) = &a.plot {
        plot_evidence(path, &ego, u.mass_kg)?;
    }
    let rows: Vec<Row> = LIBRARY_CASES
        .par_iter()
        .map(|&(name, v, m)| -> Result<Row> {
            let s = Situation {
                closing_kph: v,
                opponent_kg: m,
                occupant,
            };
            let set = UncertainSet::new(&ego, &s, &u, &reference, cfg.reserve_m)?;
            let none = set.judge(&point_optimum(&ego, &occupant, v, m, &cfg)?)?;
            let margin = set.judge(&point_optimum(&ego, &occupant, v, m + u.mass_kg, &cfg)?)?;
            let switched = a
                .switch_ms
                .iter()
                .map(|t_ms| {
                    let rule = SwitchRule::new(
                        &ego,
                        &s,
                        u.mass_kg,
                        t_ms * 1e-3,
                        a.evidence_error_pct * 1e-2,
                        &cfg,
                    )?;
                    let plan = set.two_level_optimum(&rule, &cfg)?;
                    Ok((rule, set.judge_two_level(&plan, &rule)?))
                })
                .collect::<Result<_>>()?;
            Ok(Row {
                name,
                none,
                margin,
                switched,
            })
        })
        .collect::<Result<_>>()?;
    if let Some(to) = &a.json {
        let v: Vec<_> = rows
            .iter()
            .map(|r| {
                let sw: Vec<_> = r
                    .switched
                    .iter()
                    .map(|(rule, j)| json!({ "rule": rule, "outcome": j }))
                    .collect();
                json!({ "case": r.name, "no margin": r.none, "+mass margin": r.margin, "two-level": sw })
            })
            .collect();
        lut::json_out::write(to, &json!({ "set": u, "cases": v }))?;
        return Ok(());
    }
    print_table(a, &u, &rows);
    Ok(())
}

fn print_table(a: &LimiterSwitchArgs, u: &Uncertainty, rows: &[Row]) {
    println!(
        "a_max + a_mean against the reference restraint, %: nominal / worst over the set (opponent ± {:.0} kg, closing ± {:.0} km/h, {}) / points bottoming out where the reference does not",
        u.mass_kg,
        u.speed_kph,
        if u.corners { "both at once: 9 points" } else { "one at a time: 5 points" }
    );
    let cell = |j: &Judged| {
        format!(
            "{:+.1} / {:+.1} / {}",
            j.nominal_change_pct, j.worst_change_pct, j.bottoms_out_alone
        )
    };
    let mut head = format!("{:<22} {:>21} {:>21}", "case", "no margin", "+mass margin");
    for t in &a.switch_ms {
        head += &format!(" {:>21}", format!("two-level @{t:.0} ms"));
    }
    println!("{head}");
    for r in rows {
        let mut line = format!(
            "{:<22} {:>21} {:>21}",
            r.name,
            cell(&r.none),
            cell(&r.margin)
        );
        for (_, j) in &r.switched {
            line += &format!(" {:>21}", cell(&j.judged));
        }
        println!("{line}");
    }
    let n = rows.len() as f64;
    let mut line = format!(
        "{:<22} {:>21.1} {:>21.1}",
        "mean nominal",
        rows.iter().map(|r| r.none.nominal_change_pct).sum::<f64>() / n,
        rows.iter()
            .map(|r| r.margin.nominal_change_pct)
            .sum::<f64>()
            / n
    );
    for k in 0..a.switch_ms.len() {
        let mean = rows
            .iter()
            .map(|r| r.switched[k].1.judged.nominal_change_pct)
            .sum::<f64>()
            / n;
        line += &format!(" {mean:>21.1}");
    }
    println!("{line}");
    println!();
    println!("two-level plans: high → low level [kN]; speed lost by the decision, predicted for the estimate / the opponent {:.0} kg heavier [m/s] (read {:.1} % low); points of the set switched (nominal first)", u.mass_kg, a.evidence_error_pct);
    for r in rows {
        for (rule, j) in &r.switched {
            println!(
                "{:<22} @{:>3.0} ms  {:>5.2} → {:>5.2} kN   {:>5.2} / {:>5.2} m/s   {}",
                r.name,
                rule.at_s * 1e3,
                j.levels_kn.0,
                j.levels_kn.1,
                rule.predicted_mps.0,
                rule.predicted_mps.1,
                j.switched
                    .iter()
                    .map(|s| if *s { "S" } else { "-" })
                    .collect::<String>()
            );
        }
    }
}

/// Speed lost against time for the estimate and the opponent `margin_kg` heavier (48 + 48 km/h
/// Taurus), and their difference against the estimate's loss.
fn plot_evidence(path: &std::path::Path, ego: &Ego, margin_kg: f64) -> Result<()> {
    let (closing_kph, opponent_kg) = (96.0, 1785.0);
    let heavy_kg = (opponent_kg + margin_kg).min(physics::defaults::OPPONENT_MASS_KG.max);
    let t_ms: Vec<f64> = (0..=150).map(f64::from).collect();
    let lost = |m: f64| -> Result<Vec<f64>> {
        let p = Pulse::predict(ego, Opponent::Car { mass_kg: m }, closing_kph)?;
        Ok(t_ms
            .iter()
            .map(|t| speed_lost_by_mps(&p.ego(), t * 1e-3))
            .collect())
    };
    let (est, heavy) = (lost(opponent_kg)?, lost(heavy_kg)?);
    let pct: Vec<f64> = est
        .iter()
        .zip(&heavy)
        .map(|(e, h)| if *e > 0.1 { 100.0 * (h - e) / e } else { 0.0 })
        .collect();
    let one = vec![1.0; t_ms.len()];
    plot::draw(
        path,
        &[
            plot::Panel {
                title: format!(
                    "Ego speed lost, {closing_kph:.0} km/h closing: opponent {opponent_kg:.0} kg vs {heavy_kg:.0} kg"
                ),
                x_label: "time after contact [ms]",
                y_label: "speed lost [m/s]",
                series: vec![
                    plot::Series {
                        label: format!("{opponent_kg:.0} kg (the estimate)"),
                        x: &t_ms,
                        y: &est,
                    },
                    plot::Series {
                        label: format!("{heavy_kg:.0} kg"),
                        x: &t_ms,
                        y: &heavy,
                    },
                ],
            },
            plot::Panel {
                title: "How much more the heavier opponent's crash has taken, against a 1 % accelerometer error".into(),
                x_label: "time after contact [ms]",
                y_label: "difference [% of the estimate's]",
                series: vec![
                    plot::Series {
                        label: "heavier − estimate".into(),
                        x: &t_ms,
                        y: &pct,
                    },
                    plot::Series {
                        label: "1 % sensitivity error".into(),
                        x: &t_ms,
                        y: &one,
                    },
                ],
            },
        ],
    )
}
