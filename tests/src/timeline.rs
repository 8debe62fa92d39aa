//! The campaign at a glance: one row per case, the ECU's mode over scenario time as the
//! actuator stubs saw it on EcuStatus (green Normal, amber ReferenceFallback, red crash /
//! deployed), the fault's measured extent as a hatched band, the true contact as a black tick
//! and the airbag fire command as a red diamond. A reader sees in one picture that every fault
//! is detected, outlasted and recovered from before the crash.

use crate::faults::Campaign;
use anyhow::{Context, Result};
use plotters::prelude::*;
use std::path::Path;

const ROW_PX: u32 = 34;

fn mode_color(mode: &str) -> RGBColor {
    match mode {
        "Normal" => RGBColor(76, 175, 80),
        "ReferenceFallback" => RGBColor(255, 179, 0),
        "CrashDetected" | "Deployed" => RGBColor(211, 47, 47),
        "Fault" => RGBColor(123, 31, 162),
        _ => RGBColor(189, 189, 189),
    }
}

/// Draws the timeline of `c` into `path` (PNG).
pub fn draw_timeline(c: &Campaign, path: &Path) -> Result<()> {
    let n = c.cases.len().max(1);
    let end_s = c.cases.iter().map(|r| r.duration_s).fold(1.0_f64, f64::max);
    let size = (1100, 90 + ROW_PX * n as u32);
    let root = BitMapBackend::new(path, size).into_drawing_area();
    root.fill(&WHITE)?;
    let names: Vec<String> = c.cases.iter().map(|r| r.name.clone()).collect();
    let mut chart = ChartBuilder::on(&root)
        .caption(
            format!(
                "fault campaign: ECU mode on EcuStatus ({}) — hatched: fault, |: contact, ◆: airbag fire",
                c.route.name()
            ),
            ("sans-serif", 16),
        )
        .margin(10)
        .x_label_area_size(30)
        .y_label_area_size(120)
        .build_cartesian_2d(0.0..end_s, -0.5..n as f64 - 0.5)?;
    // Row i sits at y = n − 1 − i (first case on top); labels at the integer rows.
    chart
        .configure_mesh()
        .disable_y_mesh()
        .x_desc("scenario time [s]")
        .y_labels(n)
        .y_label_formatter(&|y| {
            let k = y.round();
            if (y - k).abs() > 0.01 || k < 0.0 {
                return String::new();
            }
            let i = n as f64 - 1.0 - k;
            if i < 0.0 {
                return String::new();
            }
            names.get(i as usize).cloned().unwrap_or_default()
        })
        .draw()?;
    for (i, r) in c.cases.iter().enumerate() {
        let y0 = (n - 1 - i) as f64 - 0.3;
        let y1 = y0 + 0.6;
        // Mode segments (each mode holds until the next change).
        let mut segs: Vec<(f64, f64, &str)> = Vec::new();
        let mut prev: Option<(f64, &str)> = None;
        for (t_ms, m) in &r.ecu_modes {
            let t = (t_ms / 1e3).max(0.0);
            if let Some((t0, m0)) = prev {
                segs.push((t0, t, m0));
            }
            prev = Some((t, m.as_str()));
        }
        if let Some((t0, m0)) = prev {
            segs.push((t0, r.duration_s.max(t0), m0));
        }
        chart.draw_series(
            segs.iter()
                .filter(|(a, b, _)| b > a)
                .map(|(a, b, m)| Rectangle::new([(*a, y0), (*b, y1)], mode_color(m).filled())),
        )?;
        if let Some((a, b)) = r.fault_s {
            // Hatch: thin diagonal-ish stripes across the fault's extent.
            let mut t = a;
            let mut stripes = Vec::new();
            while t < b {
                stripes.push(PathElement::new(
                    vec![(t, y0 - 0.1), ((t + 0.03).min(b), y1 + 0.1)],
                    BLACK.stroke_width(1),
                ));
                t += 0.03;
            }
            chart.draw_series(stripes)?;
            chart.draw_series(std::iter::once(Rectangle::new(
                [(a, y0 - 0.1), (b, y1 + 0.1)],
                BLACK.stroke_width(1),
            )))?;
        }
        if let Some(tc) = r.contact_s {
            chart.draw_series(std::iter::once(PathElement::new(
                vec![(tc, y0 - 0.15), (tc, y1 + 0.15)],
                BLACK.stroke_width(3),
            )))?;
        }
        if let Some(tf) = r.fire_s {
            chart.draw_series(std::iter::once(Polygon::new(
                vec![
                    (tf, y1 + 0.18),
                    (tf + 0.025, (y0 + y1) / 2.0),
                    (tf, y0 - 0.18),
                    (tf - 0.025, (y0 + y1) / 2.0),
                ],
                RGBColor(183, 28, 28).filled(),
            )))?;
        }
        if !r.pass {
            chart.draw_series(std::iter::once(Text::new(
                "FAIL",
                (end_s * 0.80, y1),
                ("sans-serif", 16).into_font().color(&BLACK),
            )))?;
        }
    }
    root.present()
        .with_context(|| format!("writing {}", path.display()))?;
    Ok(())
}
