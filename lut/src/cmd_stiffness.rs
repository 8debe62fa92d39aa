//! `lut stiffness ...`: build force-deflection curves from barrier tests.

use crate::plot;
use anyhow::{Context, Result};
use clap::{Args, Subcommand};
use physics::{
    derive::{derive_curve, DeriveOptions},
    j211::Cfc,
    kph_to_mps,
};
use serde_json::json;
use std::path::PathBuf;

#[derive(Subcommand, Debug)]
pub enum StiffnessCommand {
    /// Force-deflection curve from a rigid-barrier accelerometer trace (CSV with header
    /// `time_s,accel_g` | `time_s,accel_mps2` | `time_ms,...`, or an ISO-MME channel file;
    /// J211 sign: deceleration negative).
    /// Prints the curve in the data/stiffness-classes.toml schema.
    Derive(DeriveArgs),
}

#[derive(Args, Debug)]
pub struct DeriveArgs {
    /// The trace file (CSV or ISO-MME channel file).
    #[arg(long, value_name = "FILE")]
    pub trace: PathBuf,
    /// Test mass [kg].
    #[arg(long = "ego-mass-kg", alias = "mass-kg", value_name = "EGO_MASS_KG")]
    pub mass_kg: f64,
    /// Impact speed of the test [km/h] (NCAP / FMVSS 208 full frontal: 56).
    #[arg(
        long = "closing-speed-kph",
        alias = "impact-kph",
        default_value_t = 56.0,
        value_name = "CLOSING_SPEED_KPH"
    )]
    pub impact_kph: f64,
    /// Number of curve points including the origin (3..=16).
    #[arg(long, default_value_t = 12)]
    pub points: usize,
    /// JSON instead of the table: into FILE, or on stdout without one (or with `-`).
    #[arg(long, value_name = "FILE", num_args = 0..=1, default_missing_value = "-")]
    pub json: Option<PathBuf>,
    /// Plot raw loading-phase force and the derived curve over crush (SVG if .svg, else PNG).
    #[arg(long, value_name = "FILE")]
    pub plot: Option<PathBuf>,
}

pub fn run(cmd: &StiffnessCommand) -> Result<()> {
    match cmd {
        StiffnessCommand::Derive(args) => derive(args),
    }
}

fn derive(args: &DeriveArgs) -> Result<()> {
    let text = std::fs::read_to_string(&args.trace)
        .with_context(|| format!("cannot read trace {}", args.trace.display()))?;
    let trace = physics::trace::parse(&text)
        .map_err(|e| anyhow::anyhow!("{}: {e}", args.trace.display()))?;
    let opts = DeriveOptions {
        mass_kg: args.mass_kg,
        impact_speed_mps: kph_to_mps(args.impact_kph),
        points: args.points,
        cfc: Cfc::Cfc60,
    };
    let d = derive_curve(&trace, &opts)
        .with_context(|| format!("deriving a curve from {}", args.trace.display()))?;
    let mm: Vec<f64> = d
        .curve
        .deflection_m()
        .iter()
        .map(|v| (v * 1e4).round() / 10.0)
        .collect();
    let kn: Vec<f64> = d
        .curve
        .force_n()
        .iter()
        .map(|v| (v * 1e-2).round() / 10.0)
        .collect();
    if d.sign_flipped {
        eprintln!("note: trace had deceleration positive (not SAE J211 sign); flipped");
    }
    if let Some(to) = &args.json {
        let out = json!({ "mass_kg": args.mass_kg, "impact_kph": args.impact_kph, "max_crush_mm": d.max_crush_m * 1e3,
                          "sign_flipped": d.sign_flipped, "deflection_mm": mm, "force_kn": kn });
        lut::json_out::write(to, &out)?;
    } else {
        let list = |v: &[f64]| {
            v.iter()
                .map(|x| format!("{x:.1}"))
                .collect::<Vec<_>>()
                .join(", ")
        };
        println!(
            "# derived from {} (mass {} kg, impact {} km/h, CFC 60); max crush {:.1} mm",
            args.trace.display(),
            args.mass_kg,
            args.impact_kph,
            d.max_crush_m * 1e3
        );
        println!("deflection_mm = [{}]", list(&mm));
        println!("force_kn = [{}]", list(&kn));
    }
    if let Some(path) = &args.plot {
        let raw_x: Vec<f64> = d.raw_crush_m.iter().map(|v| v * 1e3).collect();
        let raw_y: Vec<f64> = d.raw_force_n.iter().map(|v| v * 1e-3).collect();
        plot::draw(
            path,
            &[plot::Panel {
                title: format!("Force-deflection from {}", args.trace.display()),
                x_label: "crush [mm]",
                y_label: "F [kN]",
                series: vec![
                    plot::Series {
                        label: "filtered m*a (loading)".into(),
                        x: &raw_x,
                        y: &raw_y,
                    },
                    plot::Series {
                        label: "derived curve".into(),
                        x: &mm,
                        y: &kn,
                    },
                ],
            }],
        )?;
        eprintln!("plot written to {}", path.display());
    }
    Ok(())
}
