//! Occupant studies: `lut study opponent-mass`, `lut study reduction`, and the occupant columns
//! of `lut study stiffness`.

use crate::cmd_optim::{outcome_json, settings_json};
use crate::heatmap::{self, HeatPanel};
use crate::plot;
use anyhow::{Context, Result};
use clap::Args;
use lut::optimise::{optimise, Case, OptimiserConfig, SearchSpace};
use lut::reference::ReferenceRestraint;
use lut::scenario::{Ego, Opponent, Pulse, DEFAULT_EGO_CLASS, DEFAULT_EGO_MASS_KG};
use physics::{
    mps2_to_g, simulate_occupant, CompartmentPulse, MassClass, OccupantInput, OccupantOutcome,
    RestraintHardware,
};
use rayon::prelude::*;
use serde_json::{json, Value};
use std::path::PathBuf;

/// The paper's occupant mean acceleration in the Table 5 study: "about 20 g, scattering about
/// 1 g over the classes" (SPEC.md). The paper's per-class occupant columns are not in SPEC.
pub const PAPER_TABLE5_OCCUPANT_MEAN_G: f64 = 20.0;
/// Seed of the study optimisations (fixed: studies are reproducible).
pub const STUDY_SEED: u64 = 1;

fn study_cfg() -> OptimiserConfig {
    // The default table's effort (data/default-grid.toml).
    OptimiserConfig {
        seed: STUDY_SEED,
        particles: 40,
        pso_iterations: 50,
        nm_iterations: 200,
        ..OptimiserConfig::default()
    }
}

/// Adaptive optimum for a belted occupant in `pulse`.
pub fn adaptive(
    pulse: &CompartmentPulse<'_>,
    occupant_kg: f64,
    seat_mm: f64,
) -> Result<(OccupantOutcome, Value)> {
    let case = Case {
        pulse: *pulse,
        occupant: OccupantInput {
            mass_kg: occupant_kg,
            chest_to_wheel_m: seat_mm * 1e-3,
            belted: true,
        },
    };
    let opt = optimise(
        &[case],
        &SearchSpace::adaptive(),
        &RestraintHardware::default(),
        &study_cfg(),
    )?;
    let o = *opt.outcomes.first().context("no outcome")?;
    Ok((o, settings_json(&opt.settings)))
}

/// The occupant columns of the stiffness study (75 kg, 300 mm, belted, adaptive optimum).
pub fn stiffness_occupant(pulse: &CompartmentPulse<'_>) -> Result<Value> {
    let (o, s) = adaptive(pulse, 75.0, 300.0)?;
    let mut v = outcome_json(&o);
    v["settings"] = s;
    Ok(v)
}

#[derive(Args, Debug)]
pub struct OpponentMassArgs {
    /// Ego mass [kg].
    #[arg(long, default_value_t = DEFAULT_EGO_MASS_KG)]
    pub ego_mass_kg: f64,
    /// Ego stiffness class.
    #[arg(long, default_value_t = DEFAULT_EGO_CLASS)]
    pub ego_class: u8,
    /// Closing speed [km/h].
    #[arg(
        long = "closing-speed-kph",
        alias = "closing-kph",
        default_value_t = 108.0,
        value_name = "CLOSING_SPEED_KPH"
    )]
    pub closing_kph: f64,
    /// Occupant mass [kg].
    #[arg(
        long = "occupant-mass-kg",
        alias = "occupant-kg",
        default_value_t = 75.0,
        value_name = "OCCUPANT_MASS_KG"
    )]
    pub occupant_kg: f64,
    /// Seat distance [mm].
    #[arg(long, default_value_t = 300.0)]
    pub seat_mm: f64,
    /// JSON instead of the table: into FILE, or on stdout without one (or with `-`).
    #[arg(long, value_name = "FILE", num_args = 0..=1, default_missing_value = "-")]
    pub json: Option<PathBuf>,
    /// Plot file (.png/.svg).
    #[arg(long)]
    pub plot: Option<PathBuf>,
}

pub fn opponent_mass(a: &OpponentMassArgs) -> Result<()> {
    let ego = Ego {
        mass_kg: a.ego_mass_kg,
        class: MassClass::new(a.ego_class)?,
    };
    let masses: Vec<f64> = (0..=11).map(|i| 800.0 + 200.0 * f64::from(i)).collect();
    let rows = masses
        .par_iter()
        .map(|&m| -> Result<(f64, OccupantOutcome, Value)> {
            let p = Pulse::predict(&ego, Opponent::Car { mass_kg: m }, a.closing_kph)?;
            let (o, s) = adaptive(&p.ego(), a.occupant_kg, a.seat_mm)?;
            Ok((m, o, s))
        })
        .collect::<Result<Vec<_>>>()?;
    let json_rows: Vec<Value> = rows
        .iter()
        .map(|(m, o, s)| {
            json!({
                "opponent_mass_kg": m,
                "bottoming_out": o.bottomed_out,
                "occupant": { "excursion_mm": o.max_excursion_m * 1e3, "a_max_g": mps2_to_g(o.max_decel_mps2), "a_mean_g": mps2_to_g(o.mean_decel_mps2) },
                "a_ideal_g": mps2_to_g(o.ideal_decel_mps2),
                "settings": s,
            })
        })
        .collect();
    if let Some(to) = &a.json {
        lut::json_out::write(to, &json_rows)?;
    } else {
        println!(
            "ego {} kg class {}, {} km/h closing, occupant {} kg at {} mm (adaptive optimum)",
            a.ego_mass_kg, a.ego_class, a.closing_kph, a.occupant_kg, a.seat_mm
        );
        println!(
            "{:>8} {:>9} {:>8} {:>8} {:>8} {:>7}",
            "opp kg", "exc mm", "a_max g", "a_mean g", "a* g", "bottom"
        );
        for (m, o, _) in &rows {
            println!(
                "{m:>8.0} {:>9.1} {:>8.2} {:>8.2} {:>8.2} {:>7}",
                o.max_excursion_m * 1e3,
                mps2_to_g(o.max_decel_mps2),
                mps2_to_g(o.mean_decel_mps2),
                mps2_to_g(o.ideal_decel_mps2),
                o.bottomed_out
            );
        }
    }
    if let Some(path) = &a.plot {
        let x: Vec<f64> = rows.iter().map(|r| r.0).collect();
        let amax: Vec<f64> = rows.iter().map(|r| mps2_to_g(r.1.max_decel_mps2)).collect();
        let amean: Vec<f64> = rows
            .iter()
            .map(|r| mps2_to_g(r.1.mean_decel_mps2))
            .collect();
        let aideal: Vec<f64> = rows
            .iter()
            .map(|r| mps2_to_g(r.1.ideal_decel_mps2))
            .collect();
        let exc: Vec<f64> = rows.iter().map(|r| r.1.max_excursion_m * 1e3).collect();
        let avail: Vec<f64> = rows
            .iter()
            .map(|r| r.1.available_ride_down_m * 1e3)
            .collect();
        let bottoming: Vec<String> = rows
            .iter()
            .filter(|r| r.1.bottomed_out)
            .map(|r| format!("{:.0}", r.0))
            .collect();
        plot::draw(
            path,
            &[
                plot::Panel {
                    title: format!("occupant {} kg, {} km/h closing, ego {} kg: adaptive optimum vs opponent mass", a.occupant_kg, a.closing_kph, a.ego_mass_kg),
                    x_label: "opponent mass [kg]",
                    y_label: "occupant deceleration [g]",
                    series: vec![
                        plot::Series { label: "a_max".into(), x: &x, y: &amax },
                        plot::Series { label: "a_mean".into(), x: &x, y: &amean },
                        plot::Series { label: "ideal a*".into(), x: &x, y: &aideal },
                    ],
                },
                plot::Panel {
                    title: format!("excursion (bottoming-out at opponent kg: {})", if bottoming.is_empty() { "none".into() } else { bottoming.join(", ") }),
                    x_label: "opponent mass [kg]",
                    y_label: "excursion [mm]",
                    series: vec![plot::Series { label: "excursion".into(), x: &x, y: &exc }, plot::Series { label: "available".into(), x: &x, y: &avail }],
                },
            ],
        )?;
        eprintln!("plot written to {}", path.display());
    }
    Ok(())
}

#[derive(Args, Debug)]
pub struct ReductionArgs {
    /// Reference restraint file.
    #[arg(long, default_value = "data/reference-restraint.toml", value_parser = lut::paths::input_file)]
    pub reference: PathBuf,
    /// Opponent mass [kg] (default: the ego's own mass, the paper's symmetric case).
    #[arg(long, default_value_t = DEFAULT_EGO_MASS_KG)]
    pub opponent_mass_kg: f64,
    /// Seat distance [mm].
    #[arg(long, default_value_t = 300.0)]
    pub seat_mm: f64,
    /// JSON instead of the table: into FILE, or on stdout without one (or with `-`).
    #[arg(long, value_name = "FILE", num_args = 0..=1, default_missing_value = "-")]
    pub json: Option<PathBuf>,
    /// Heat-map picture of the reductions (.png/.svg).
    #[arg(long)]
    pub plot: Option<PathBuf>,
}

/// Closing speeds of the reduction study: 2 × (20, 24.25, …, 54) km/h.
pub const REDUCTION_CLOSING_KPH: [f64; 9] = [40.0, 48.5, 57.0, 65.5, 74.0, 82.5, 91.0, 99.5, 108.0];
/// Occupant masses of the reduction study [kg].
pub const REDUCTION_OCCUPANT_KG: [f64; 7] = [30.0, 45.0, 60.0, 75.0, 90.0, 105.0, 125.0];

fn pct(reference: f64, adaptive: f64) -> f64 {
    100.0 * (reference - adaptive) / reference
}

pub fn reduction(a: &ReductionArgs) -> Result<()> {
    let reference = ReferenceRestraint::load(&a.reference)
        .map_err(anyhow::Error::msg)?
        .settings();
    let ego = Ego::default();
    let hw = RestraintHardware::default();
    let points: Vec<(f64, f64)> = REDUCTION_CLOSING_KPH
        .iter()
        .flat_map(|&v| REDUCTION_OCCUPANT_KG.iter().map(move |&m| (v, m)))
        .collect();
    let rows = points
        .par_iter()
        .map(
            |&(v, m)| -> Result<(f64, f64, OccupantOutcome, OccupantOutcome)> {
                let p = Pulse::predict(
                    &ego,
                    Opponent::Car {
                        mass_kg: a.opponent_mass_kg,
                    },
                    v,
                )?;
                let occ = OccupantInput {
                    mass_kg: m,
                    chest_to_wheel_m: a.seat_mm * 1e-3,
                    belted: true,
                };
                let r = simulate_occupant(&p.ego(), &occ, &reference, &hw)?;
                let (o, _) = adaptive(&p.ego(), m, a.seat_mm)?;
                Ok((v, m, r, o))
            },
        )
        .collect::<Result<Vec<_>>>()?;
    let g = mps2_to_g;
    let json_rows: Vec<Value> = rows
        .iter()
        .map(|(v, m, r, o)| {
            json!({
                "closing_kph": v,
                "occupant_kg": m,
                "reference": { "a_max_g": g(r.max_decel_mps2), "a_mean_g": g(r.mean_decel_mps2), "bottoming_out": r.bottomed_out },
                "adaptive": { "a_max_g": g(o.max_decel_mps2), "a_mean_g": g(o.mean_decel_mps2), "bottoming_out": o.bottomed_out },
                "reduction_max_pct": pct(r.max_decel_mps2, o.max_decel_mps2),
                "reduction_mean_pct": pct(r.mean_decel_mps2, o.mean_decel_mps2),
                "a_ideal_g": g(o.ideal_decel_mps2),
            })
        })
        .collect();
    if let Some(to) = &a.json {
        lut::json_out::write(to, &json_rows)?;
    } else {
        println!("reduction of occupant a_max / a_mean, adaptive vs reference ({}), opponent {} kg, seat {} mm", a.reference.display(), a.opponent_mass_kg, a.seat_mm);
        println!(
            "{:>7} {:>6} {:>9} {:>9} {:>9} {:>9} {:>7} {:>7} {:>5} {:>5}",
            "kph",
            "occ kg",
            "ref max",
            "ref mean",
            "ad max",
            "ad mean",
            "red max",
            "red mean",
            "refBO",
            "adBO"
        );
        for (v, m, r, o) in &rows {
            println!(
                "{v:>7.1} {m:>6.0} {:>9.2} {:>9.2} {:>9.2} {:>9.2} {:>6.1}% {:>6.1}% {:>5} {:>5}",
                g(r.max_decel_mps2),
                g(r.mean_decel_mps2),
                g(o.max_decel_mps2),
                g(o.mean_decel_mps2),
                pct(r.max_decel_mps2, o.max_decel_mps2),
                pct(r.mean_decel_mps2, o.mean_decel_mps2),
                r.bottomed_out,
                o.bottomed_out
            );
        }
    }
    if let Some(path) = &a.plot {
        let grid = |f: &dyn Fn(&OccupantOutcome, &OccupantOutcome) -> f64| -> Vec<Vec<f64>> {
            REDUCTION_OCCUPANT_KG
                .iter()
                .map(|&m| {
                    REDUCTION_CLOSING_KPH
                        .iter()
                        .map(|&v| {
                            rows.iter()
                                .find(|r| r.0 == v && r.1 == m)
                                .map_or(f64::NAN, |r| f(&r.2, &r.3))
                        })
                        .collect()
                })
                .collect()
        };
        let marked: Vec<Vec<bool>> = REDUCTION_OCCUPANT_KG
            .iter()
            .map(|&m| {
                REDUCTION_CLOSING_KPH
                    .iter()
                    .map(|&v| {
                        rows.iter()
                            .any(|r| r.0 == v && r.1 == m && (r.2.bottomed_out || r.3.bottomed_out))
                    })
                    .collect()
            })
            .collect();
        let panel = |title: &str, z| HeatPanel {
            title: title.into(),
            x_label: "closing speed [km/h] (car-to-car)".into(),
            y_label: "occupant mass [kg]".into(),
            x: REDUCTION_CLOSING_KPH.to_vec(),
            y: REDUCTION_OCCUPANT_KG.to_vec(),
            z,
            marked: Some(marked.clone()),
            decimals: 0,
        };
        heatmap::draw(
            path,
            &[
                panel(
                    "a_max reduction [%]",
                    grid(&|r, o| pct(r.max_decel_mps2, o.max_decel_mps2)),
                ),
                panel(
                    "a_mean reduction [%]",
                    grid(&|r, o| pct(r.mean_decel_mps2, o.mean_decel_mps2)),
                ),
            ],
        )?;
        eprintln!(
            "plot written to {} (framed: reference or adaptive bottoms out)",
            path.display()
        );
    }
    Ok(())
}
