//! `lut simulate`: one collision prediction with the two-mass model.

use crate::plot;
use anyhow::{bail, Context, Result};
use clap::Args;
use physics::{
    class_for_mass_kg,
    collision::{simulate_collision, CollisionInput, CollisionSummary, DefaultPulseBuffer},
    defaults, kph_to_mps, mps2_to_g, CombinedSpring, MassClass, VehicleResult,
};
use serde_json::{json, Value};
use std::path::PathBuf;

#[derive(Args, Debug)]
pub struct SimulateArgs {
    /// Ego vehicle mass [kg].
    #[arg(long)]
    pub ego_mass_kg: f64,
    /// Opponent vehicle mass [kg].
    #[arg(
        long = "opponent-mass-kg",
        alias = "opp-mass-kg",
        value_name = "OPPONENT_MASS_KG"
    )]
    pub opp_mass_kg: f64,
    /// Closing speed [km/h] (sum of both vehicles' speeds).
    #[arg(
        long = "closing-speed-kph",
        alias = "closing-kph",
        value_name = "CLOSING_SPEED_KPH"
    )]
    pub closing_kph: f64,
    /// Ego stiffness class 1..6 (default: looked up from the mass).
    #[arg(long)]
    pub ego_class: Option<u8>,
    /// Opponent stiffness class 1..6 (default: looked up from the mass).
    #[arg(
        long = "opponent-class",
        alias = "opp-class",
        value_name = "OPPONENT_CLASS"
    )]
    pub opp_class: Option<u8>,
    /// Use one linear combined spring of this stiffness [kN/m] instead of the class curves
    /// (split as two equal fronts of twice the stiffness, so each vehicle takes half the crush).
    #[arg(long)]
    pub linear_stiffness_kn_per_m: Option<f64>,
    /// Coefficient of restitution (default 0.1).
    #[arg(long, default_value_t = defaults::RESTITUTION)]
    pub restitution: f64,
    /// JSON instead of the table: into FILE, or on stdout without one (or with `-`).
    #[arg(long, value_name = "FILE", num_args = 0..=1, default_missing_value = "-")]
    pub json: Option<PathBuf>,
    /// Draw acceleration and velocity over time (SVG if the name ends in .svg, else PNG).
    #[arg(long, value_name = "FILE")]
    pub plot: Option<PathBuf>,
}

/// The JSON object of one vehicle.
pub fn vehicle_json(v: &VehicleResult, contact_s: f64) -> Value {
    json!({
        "crush_mm": v.crush_m * 1e3,
        "a_max_g": mps2_to_g(v.a_max_mps2),
        "a_mean_g": mps2_to_g(v.a_mean_mps2),
        "delta_v_mps": v.delta_v_mps,
        "contact_ms": contact_s * 1e3,
    })
}

fn class_or_lookup(explicit: Option<u8>, mass_kg: f64, who: &str) -> Result<MassClass> {
    match explicit {
        Some(n) => MassClass::new(n).with_context(|| format!("--{who}-class {n}")),
        None => class_for_mass_kg(mass_kg).with_context(|| format!("--{who}-mass-kg {mass_kg}")),
    }
}

pub fn run(args: &SimulateArgs) -> Result<()> {
    for (name, v) in [
        ("ego-mass-kg", args.ego_mass_kg),
        ("opp-mass-kg", args.opp_mass_kg),
        ("closing-kph", args.closing_kph),
    ] {
        if !v.is_finite() || v < 0.0 {
            bail!("--{name} must be a finite, non-negative number (got {v})");
        }
    }
    let ego_class = class_or_lookup(args.ego_class, args.ego_mass_kg, "ego")?;
    let opp_class = class_or_lookup(args.opp_class, args.opp_mass_kg, "opp")?;
    let spring = match args.linear_stiffness_kn_per_m {
        // Two equal fronts of 2K in series give the combined K; each vehicle takes half the crush.
        Some(k) => {
            let half =
                physics::Curve::linear(2.0 * k * 1e3).context("--linear-stiffness-kn-per-m")?;
            CombinedSpring::series(&half, Some(&half))?
        }
        None => CombinedSpring::series(ego_class.curve(), Some(opp_class.curve()))?,
    };
    let mut input = CollisionInput::with_defaults(
        &spring,
        args.ego_mass_kg,
        args.opp_mass_kg,
        kph_to_mps(args.closing_kph),
    );
    input.restitution = args.restitution;
    let mut buf = Box::new(DefaultPulseBuffer::new());
    let s = simulate_collision(&input, &mut buf).context("collision simulation")?;

    let t_ms: Vec<f64> = (0..buf.len())
        .map(|k| k as f64 * buf.step_s() * 1e3)
        .collect();
    let g = |v: &[f64]| v.iter().map(|a| mps2_to_g(*a)).collect::<Vec<_>>();
    let mm = |v: &[f64]| v.iter().map(|a| a * 1e3).collect::<Vec<_>>();
    if let Some(to) = &args.json {
        let out = json!({
            "inputs": {
                "ego_mass_kg": args.ego_mass_kg, "opp_mass_kg": args.opp_mass_kg,
                "closing_kph": args.closing_kph, "restitution": args.restitution,
                "ego_class": if args.linear_stiffness_kn_per_m.is_some() { Value::Null } else { json!(ego_class.number()) },
                "opp_class": if args.linear_stiffness_kn_per_m.is_some() { Value::Null } else { json!(opp_class.number()) },
                "linear_stiffness_kn_per_m": args.linear_stiffness_kn_per_m,
                "step_ms": input.step_s * 1e3,
            },
            "vehicle": vehicle_json(&s.vehicle, s.contact_duration_s),
            "opponent": vehicle_json(&s.opponent, s.contact_duration_s),
            "peak_force_kn": s.peak_force_n * 1e-3,
            "absorbed_energy_kj": s.absorbed_energy_j * 1e-3,
            "pulse": {
                "t_ms": t_ms,
                "vehicle": { "accel_g": g(buf.ego_accel_mps2()), "vel_mps": buf.ego_vel_mps(), "crush_mm": mm(buf.ego_crush_m()) },
                "opponent": { "accel_g": g(buf.opp_accel_mps2()), "vel_mps": buf.opp_vel_mps(), "crush_mm": mm(buf.opp_crush_m()) },
            },
        });
        lut::json_out::write(to, &out)?;
    } else {
        print_table(args, ego_class, opp_class, &s);
    }
    if let Some(path) = &args.plot {
        let (ea, oa) = (g(buf.ego_accel_mps2()), g(buf.opp_accel_mps2()));
        plot::draw(
            path,
            &[
                plot::Panel {
                    title: format!(
                        "Compartment acceleration, {:.0} kg vs {:.0} kg at {:.0} km/h",
                        args.ego_mass_kg, args.opp_mass_kg, args.closing_kph
                    ),
                    x_label: "t [ms]",
                    y_label: "a [g]",
                    series: vec![
                        plot::Series {
                            label: "vehicle".into(),
                            x: &t_ms,
                            y: &ea,
                        },
                        plot::Series {
                            label: "opponent".into(),
                            x: &t_ms,
                            y: &oa,
                        },
                    ],
                },
                plot::Panel {
                    title: "Velocity change".into(),
                    x_label: "t [ms]",
                    y_label: "dv [m/s]",
                    series: vec![
                        plot::Series {
                            label: "vehicle".into(),
                            x: &t_ms,
                            y: buf.ego_vel_mps(),
                        },
                        plot::Series {
                            label: "opponent".into(),
                            x: &t_ms,
                            y: buf.opp_vel_mps(),
                        },
                    ],
                },
            ],
        )?;
        eprintln!("plot written to {}", path.display());
    }
    Ok(())
}

fn print_table(args: &SimulateArgs, ego: MassClass, opp: MassClass, s: &CollisionSummary) {
    match args.linear_stiffness_kn_per_m {
        Some(k) => println!("linear combined spring {k} kN/m, e = {}", args.restitution),
        None => println!(
            "classes: vehicle {} / opponent {}, e = {}",
            ego.number(),
            opp.number(),
            args.restitution
        ),
    }
    println!(
        "{:<10} {:>10} {:>9} {:>9} {:>10} {:>11}",
        "", "crush_mm", "a_max_g", "a_mean_g", "dv_mps", "contact_ms"
    );
    for (name, v) in [("vehicle", &s.vehicle), ("opponent", &s.opponent)] {
        println!(
            "{:<10} {:>10.1} {:>9.2} {:>9.2} {:>10.2} {:>11.1}",
            name,
            v.crush_m * 1e3,
            mps2_to_g(v.a_max_mps2),
            mps2_to_g(v.a_mean_mps2),
            v.delta_v_mps,
            s.contact_duration_s * 1e3
        );
    }
}
