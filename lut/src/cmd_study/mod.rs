//! `lut study ...`: the paper's parameter studies and the bench's own (robustness, fallback, estimation), one file per study beyond Table 5.

use crate::{cmd_simulate::vehicle_json, plot};
use anyhow::Result;
use clap::{Args, Subcommand};
use physics::{
    collision::{simulate_collision, CollisionInput, DefaultPulseBuffer},
    kph_to_mps, mps2_to_g, paper, stiffness, CombinedSpring,
};
use serde_json::json;
use std::path::PathBuf;

mod bound;
mod estimation;
mod fallback;
mod limiter_switch;
mod occupant;
mod robust_cells;
mod robustness;

#[derive(Subcommand, Debug)]
pub enum StudyCommand {
    /// Table 5: symmetric 1785 kg vs 1785 kg at 108 km/h for each stiffness class, beside the
    /// paper's published vehicle results.
    Stiffness(StiffnessStudyArgs),
    /// Adaptive occupant loading over opponent mass 800..3000 kg (200 kg steps).
    OpponentMass(occupant::OpponentMassArgs),
    /// Closing speed × occupant mass: reference restraint vs adaptive optimum, reductions in %.
    Reduction(occupant::ReductionArgs),
    /// Monte-Carlo: the pre-crash estimate's errors (payload, speed, distance) → spread of the
    /// occupant's outcome in one cell; locally or as a Slurm job array (--slurm N).
    Robustness(robustness::RobustnessArgs),
    /// The ECU's accelerometer-only airbag algorithm over a sweep of barrier and car-to-car
    /// crashes: no-fire and must-fire lines, fire times against the occupant's deadline;
    /// `--derive` calibrates its boundary.
    Fallback(fallback::FallbackArgs),
    /// How close the table's optima come to the ideal constant-force bound a*, and which
    /// limitation of the restraint model (belt slack, airbag fill time, force ceilings) keeps
    /// them from it.
    Bound(bound::BoundArgs),
    /// Robust cells (optimised over the opponent-mass and closing-speed uncertainty set)
    /// against no margin and today's +1 200 kg planning on the library's nominal cases.
    RobustCells(robust_cells::RobustCellsArgs),
    /// A two-level load limiter that switches high → low when the pulse shows the opponent is
    /// not the margin heavier, against no margin and today's +1 200 kg planning.
    LimiterSwitch(limiter_switch::LimiterSwitchArgs),
    /// The ECU's track filter against the newest sample alone over the scenario library and
    /// noisier sensors: errors at contact, occupant outcome, a plot of one case.
    Estimation(estimation::EstimationArgs),
}

#[derive(Args, Debug)]
pub struct StiffnessStudyArgs {
    /// JSON instead of the table: into FILE, or on stdout without one (or with `-`).
    #[arg(long, value_name = "FILE", num_args = 0..=1, default_missing_value = "-")]
    pub json: Option<PathBuf>,
    /// Plot the vehicle pulses of all classes (SVG if .svg, else PNG).
    #[arg(long, value_name = "FILE")]
    pub plot: Option<PathBuf>,
}

pub fn run(cmd: &StudyCommand) -> Result<()> {
    match cmd {
        StudyCommand::Stiffness(args) => stiffness_study(args),
        StudyCommand::OpponentMass(args) => occupant::opponent_mass(args),
        StudyCommand::Reduction(args) => occupant::reduction(args),
        StudyCommand::Robustness(args) => robustness::run(args),
        StudyCommand::Fallback(args) => fallback::run(args),
        StudyCommand::Estimation(args) => estimation::run(args),
        StudyCommand::Bound(args) => bound::run(args),
        StudyCommand::RobustCells(args) => robust_cells::run(args),
        StudyCommand::LimiterSwitch(args) => limiter_switch::run(args),
    }
}

fn pct(model: f64, paper: f64) -> f64 {
    100.0 * (model / paper - 1.0)
}

fn stiffness_study(args: &StiffnessStudyArgs) -> Result<()> {
    let mut rows = Vec::new();
    let mut pulses: Vec<(String, Vec<f64>, Vec<f64>)> = Vec::new();
    let mut buf = Box::new(DefaultPulseBuffer::new());
    for (i, p) in paper::TABLE5.iter().enumerate() {
        let curve = if i < 6 {
            &stiffness::CLASS_CURVES[i]
        } else {
            &stiffness::COMBINED_CURVE
        };
        let spring = CombinedSpring::series(curve, Some(curve))?;
        let input = CollisionInput::with_defaults(
            &spring,
            paper::TABLE5_MASS_KG,
            paper::TABLE5_MASS_KG,
            kph_to_mps(paper::TABLE5_CLOSING_KPH),
        );
        let s = simulate_collision(&input, &mut buf)?;
        let v = &s.vehicle;
        rows.push(json!({
            "class": p.class,
            "vehicle": vehicle_json(v, s.contact_duration_s),
            // Occupant: adaptive optimum for the 75 kg occupant at 300 mm in this class's pulse.
            "occupant": occupant::stiffness_occupant(&buf.ego_pulse())?,
            "paper": {
                "vehicle": { "crush_mm": p.crush_mm, "a_max_g": p.a_max_g, "a_mean_g": p.a_mean_g },
                "occupant": { "a_mean_g_approx": occupant::PAPER_TABLE5_OCCUPANT_MEAN_G },
            },
            "error_pct": {
                "crush_mm": pct(v.crush_m * 1e3, p.crush_mm),
                "a_max_g": pct(mps2_to_g(v.a_max_mps2), p.a_max_g),
                "a_mean_g": pct(mps2_to_g(v.a_mean_mps2), p.a_mean_g),
            },
        }));
        let t: Vec<f64> = (0..buf.len())
            .map(|k| k as f64 * buf.step_s() * 1e3)
            .collect();
        let a: Vec<f64> = buf.ego_accel_mps2().iter().map(|x| mps2_to_g(*x)).collect();
        pulses.push((format!("class {}", p.class), t, a));
    }
    if let Some(to) = &args.json {
        lut::json_out::write(to, &rows)?;
    } else {
        println!(
            "Table 5 case: {} kg vs {} kg, {} km/h, e = {}",
            paper::TABLE5_MASS_KG,
            paper::TABLE5_MASS_KG,
            paper::TABLE5_CLOSING_KPH,
            physics::defaults::RESTITUTION
        );
        println!(
            "{:<6} {:>22} {:>22} {:>22}",
            "class", "crush mm (paper, %)", "a_max g (paper, %)", "a_mean g (paper, %)"
        );
        for (r, p) in rows.iter().zip(paper::TABLE5.iter()) {
            let v = &r["vehicle"];
            let e = &r["error_pct"];
            let f = |x: &serde_json::Value| x.as_f64().unwrap_or(f64::NAN);
            let o = &r["occupant"];
            println!(
                "{:<6} {:>7.1} ({:>6.1},{:+5.1}) {:>7.2} ({:>6.2},{:+5.1}) {:>7.2} ({:>6.2},{:+5.1}) | {:>6.1} {:>6.2} {:>6.2}{}",
                p.class,
                f(&v["crush_mm"]), p.crush_mm, f(&e["crush_mm"]),
                f(&v["a_max_g"]), p.a_max_g, f(&e["a_max_g"]),
                f(&v["a_mean_g"]), p.a_mean_g, f(&e["a_mean_g"]),
                f(&o["excursion_mm"]), f(&o["a_max_g"]), f(&o["a_mean_g"]),
                if o["bottoming_out"].as_bool().unwrap_or(true) { " BOTTOMING-OUT" } else { "" },
            );
        }
    }
    if let Some(path) = &args.plot {
        let series = pulses
            .iter()
            .map(|(l, t, a)| plot::Series {
                label: l.clone(),
                x: t,
                y: a,
            })
            .collect();
        plot::draw(
            path,
            &[plot::Panel {
                title: "Table 5 case: vehicle pulse per stiffness class".into(),
                x_label: "t [ms]",
                y_label: "a [g]",
                series,
            }],
        )?;
        eprintln!("plot written to {}", path.display());
    }
    Ok(())
}
