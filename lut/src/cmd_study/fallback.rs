//! `lut study fallback`: the ECU's accelerometer-only airbag algorithm over a sweep of barrier
//! and car-to-car crashes — where it fires, when, and whether that meets the no-fire line, the
//! must-fire line and the occupant's deadline (`lut::fallback_study`). `--derive` calibrates
//! the boundary from the sweep's no-fire cases and prints it as the `[cycle]` key.

use anyhow::Result;
use clap::Args;
use lut::fallback_study::{
    calibrate, families, must_fire_line, run_sweep, violations, Family, Row, Sweep,
};
use restraint::CycleConfig;
use std::path::PathBuf;

use crate::plot;

#[derive(Args, Debug)]
pub struct FallbackArgs {
    /// Calibrate the boundary from this sweep's no-fire cases and evaluate with it (default:
    /// evaluate the shipped `fallback_dv_mps`).
    #[arg(long)]
    pub derive: bool,
    /// Margin of the derived boundary over the no-fire envelope.
    #[arg(long, default_value_t = 0.10)]
    pub margin: f64,
    /// Plot fire times over EBS (SVG if .svg, else PNG).
    #[arg(long, value_name = "FILE")]
    pub plot: Option<PathBuf>,
    /// Evaluate (or with `--derive` calibrate) the boundary for an occupant not known to be
    /// belted, `unbelted_dv_mps`, against its no-fire line `unbelted_no_fire_ebs_kph`.
    #[arg(long)]
    pub unbelted: bool,
    /// Write every case as JSON.
    #[arg(long, value_name = "FILE")]
    pub json: Option<PathBuf>,
}

/// `{:.2}` knots as a TOML array.
fn knots(t: &[f64]) -> String {
    let v: Vec<String> = t.iter().map(|x| format!("{x:.2}")).collect();
    format!("[{}]", v.join(", "))
}

/// The airbag boundary the sweep judges: `fallback_dv_mps` for a belted occupant,
/// `unbelted_dv_mps` for one not known to be belted.
fn boundary_mut(cfg: &mut CycleConfig, belted: bool) -> &mut [f64; restraint::fallback::KNOTS] {
    if belted {
        &mut cfg.fallback_dv_mps
    } else {
        &mut cfg.unbelted_dv_mps
    }
}

fn ms(t: Option<f64>) -> String {
    t.map_or("—".into(), |t| format!("{t:.1} ms"))
}

pub fn run(args: &FallbackArgs) -> Result<()> {
    let started = std::time::Instant::now();
    let sweep = Sweep {
        belted: !args.unbelted,
        ..Sweep::calibration()
    };
    let mut cfg = CycleConfig::default();
    let t_ref_ms = physics::reference::ReferenceRestraint::builtin()
        .map_err(anyhow::Error::msg)?
        .restraint
        .airbag_time_ms;
    let no_fire = cfg.no_fire_line_kph(sweep.belted);
    let key = if sweep.belted {
        "fallback_dv_mps"
    } else {
        "unbelted_dv_mps"
    };
    if args.derive {
        let rows = run_sweep(&cfg, &sweep)?;
        let derived = calibrate(&rows, no_fire, args.margin);
        *boundary_mut(&mut cfg, sweep.belted) = derived;
        println!(
            "derived from the Δv curves of the no-fire cases below {no_fire:.0} km/h (margin {:.0} %):\n{key} = {}",
            args.margin * 100.0,
            knots(&derived)
        );
    }
    let rows = run_sweep(&cfg, &sweep)?;
    println!(
        "boundary Δv(τ) [m/s] at τ = 0, 4, … {:.0} ms: {}",
        restraint::fallback::WINDOW_MS,
        knots(boundary_mut(&mut cfg, sweep.belted))
    );
    let must = if sweep.belted {
        let must = must_fire_line(&rows).unwrap_or(f64::INFINITY);
        println!(
            "no-fire line: EBS < {no_fire:.0} km/h (and an onset below it); must-fire line: EBS ≥ {must:.1} km/h (the belt alone lets the 75 kg occupant at 300 mm bottom out)"
        );
        must
    } else {
        // Held by the airbag alone, an unbelted occupant strikes the wheel in every crash
        // above the belted no-fire line.
        let must = cfg.no_fire_ebs_kph;
        println!(
            "occupant not known to be belted (`unbelted_dv_mps`): no-fire line: EBS < {no_fire:.0} km/h (and an onset below it); must-fire line: EBS ≥ {must:.1} km/h (the belted no-fire line: the airbag alone holds this occupant)"
        );
        must
    };
    println!(
        "{} cases × {} sensor variants (4 kHz seeds 1–3, 4 kHz with 1 g braking through the crash, 1 kHz) in {:.1} s",
        rows.len(),
        sweep.sensors.len(),
        started.elapsed().as_secs_f64()
    );
    println!(
        "\n{:<14} {:>12} {:>12} {:>14} {:>13} {:>6}",
        "opponent", "no fire up to", "fires from", "fire at must", "least slack", "grey"
    );
    for family in families() {
        let fam: Vec<&Row> = rows.iter().filter(|r| r.spec.family == family).collect();
        let quiet = fam
            .iter()
            .filter(|r| !r.fires(t_ref_ms))
            .map(|r| r.req.ebs_kph)
            .fold(f64::NAN, f64::max);
        let fired = fam
            .iter()
            .filter(|r| r.fires(t_ref_ms))
            .map(|r| r.req.ebs_kph)
            .fold(f64::NAN, f64::min);
        let at_must = fam
            .iter()
            .filter(|r| r.req.ebs_kph >= must)
            .min_by(|a, b| a.req.ebs_kph.total_cmp(&b.req.ebs_kph))
            .and_then(|r| r.airbag_ms(0, t_ref_ms));
        let slack = fam
            .iter()
            .filter(|r| r.req.ebs_kph >= must)
            .flat_map(|r| (0..r.measured.len()).map(move |i| (r, i)))
            .filter_map(|(r, i)| {
                Some(
                    r.deadline_ms(i, t_ref_ms)? - r.airbag_ms(i, t_ref_ms).unwrap_or(f64::INFINITY),
                )
            })
            .fold(f64::INFINITY, f64::min);
        // Fired below the EBS line where the onset looked severe (a light opponent).
        let grey = fam
            .iter()
            .filter(|r| r.req.ebs_kph < no_fire && r.fires(t_ref_ms))
            .count();
        println!(
            "{:<14} {:>8.1} km/h {:>7.1} km/h {:>14} {:>13} {:>6}",
            family.label(),
            quiet,
            fired,
            ms(at_must),
            if slack.is_finite() {
                format!("{slack:+.1} ms")
            } else {
                "—".into()
            },
            grey,
        );
    }
    println!("\nbarrier, default sensor: onset → decision → airbag, against the deadline");
    for r in rows
        .iter()
        .filter(|r| r.spec.family == Family::Barrier && (r.req.ebs_kph.round() as i64) % 4 == 0)
    {
        let m = &r.measured[0];
        println!(
            "  EBS {:4.0} km/h: onset {:>7}, decision {:>8}, airbag {:>8}, deadline {:>8}{}",
            r.req.ebs_kph,
            ms(m.onset_ms),
            ms(m.decision_ms),
            ms(r.airbag_ms(0, t_ref_ms)),
            ms(r.deadline_ms(0, t_ref_ms)),
            if r.req.ebs_kph >= must {
                "  must fire"
            } else {
                ""
            }
        );
    }
    let bad = violations(&rows, no_fire, must, t_ref_ms, 0.0);
    for b in &bad {
        println!("VIOLATION: {b}");
    }
    println!("{} violation(s)", bad.len());
    if let Some(path) = &args.plot {
        draw(path, &rows, no_fire, must, t_ref_ms)?;
        eprintln!("plot written to {}", path.display());
    }
    if let Some(path) = &args.json {
        let cases: Vec<serde_json::Value> = rows
            .iter()
            .map(|r| {
                serde_json::json!({
                    "opponent": r.spec.family.label(),
                    "closing_kph": r.spec.closing_kph,
                    "ebs_kph": r.req.ebs_kph,
                    "belt_only_bottoms_out": r.req.belt_only_bottoms_out,
                    "deadline_ms": r.deadline_ms(0, t_ref_ms),
                    "decision_ms": r.measured[0].decision_ms,
                    "airbag_ms": (0..r.measured.len()).map(|i| r.airbag_ms(i, t_ref_ms)).collect::<Vec<_>>(),
                })
            })
            .collect();
        lut::json_out::write(path, &cases)?;
    }
    if !bad.is_empty() {
        anyhow::bail!("{} requirement violation(s) on the sweep", bad.len());
    }
    Ok(())
}

fn draw(
    path: &std::path::Path,
    rows: &[Row],
    no_fire: f64,
    must: f64,
    t_ref_ms: f64,
) -> Result<()> {
    let mut data: Vec<(String, Vec<f64>, Vec<f64>)> = Vec::new();
    for family in [
        Family::Barrier,
        Family::Car { opponent_kg: 800.0 },
        Family::Car {
            opponent_kg: 1785.0,
        },
        Family::Car {
            opponent_kg: 3000.0,
        },
    ] {
        let (x, y): (Vec<f64>, Vec<f64>) = rows
            .iter()
            .filter(|r| r.spec.family == family)
            .filter_map(|r| r.airbag_ms(0, t_ref_ms).map(|t| (r.req.ebs_kph, t)))
            .unzip();
        data.push((format!("airbag, {}", family.label()), x, y));
    }
    let (x, y): (Vec<f64>, Vec<f64>) = rows
        .iter()
        .filter(|r| r.spec.family == Family::Barrier && r.req.ebs_kph >= no_fire)
        .filter_map(|r| r.deadline_ms(0, t_ref_ms).map(|l| (r.req.ebs_kph, l)))
        .unzip();
    data.push(("deadline (barrier, 75 kg, 300 mm)".into(), x, y));
    data.push((
        format!("no-fire line {no_fire:.0} km/h"),
        vec![no_fire, no_fire],
        vec![0.0, 60.0],
    ));
    data.push((
        format!("must-fire line {must:.0} km/h"),
        vec![must, must],
        vec![0.0, 60.0],
    ));
    let series = data
        .iter()
        .map(|(label, x, y)| plot::Series {
            label: label.clone(),
            x,
            y,
        })
        .collect();
    plot::draw(
        path,
        &[plot::Panel {
            title: "Accelerometer-only algorithm: airbag time over crash severity".into(),
            x_label: "equivalent barrier speed EBS [km/h]",
            y_label: "airbag [ms after contact]",
            series,
        }],
    )
}
