//! `offline-bench --plot DIR`: one PNG per run with what an engineer looks at first when a
//! misuse case fires — the two accelerometers as published, the event's Δv against the
//! accelerometer-only boundaries and floors (with the road's roughness lift), the ECU's mode and
//! every restraint action, on one time axis (ms after the scenario start).
//!
//! The window is the part of the run where something happens (the true contact, every
//! accelerometer event, every action, 60 ms before to 120 ms after), the whole run when nothing
//! does: a 20 ms pothole in a 5 s drive would otherwise be a line.

use crate::offline::{OfflineRun, Trace, TraceCycle, START_NS};
use plotters::prelude::*;
use restraint::signals::EcuMode;
use std::path::Path;

const BEFORE_MS: f64 = 60.0;
const AFTER_MS: f64 = 120.0;

/// Each module action at its time [ms after start], labelled `what (source)`.
fn timed_actions(run: &OfflineRun) -> Vec<(f64, String)> {
    run.modules
        .actions
        .iter()
        .map(|a| {
            (
                a.t_ns.saturating_sub(START_NS) as f64 * 1e-6,
                format!("{} ({})", a.what, a.source),
            )
        })
        .collect()
}

/// The time window [ms after start] the picture shows.
fn window(run: &OfflineRun, trace: &Trace, actions: &[(f64, String)]) -> (f64, f64) {
    let end = trace.cycles.last().map_or(1.0, |c| c.t_ms).max(1.0);
    let mut marks: Vec<f64> = actions.iter().map(|(t, _)| *t).collect();
    marks.extend(run.contact_s.map(|c| c * 1e3));
    marks.extend(
        trace
            .cycles
            .iter()
            .filter(|c| c.airbag_boundary_mps.is_some())
            .map(|c| c.t_ms),
    );
    let lo = marks.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = marks.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if lo.is_finite() && hi.is_finite() {
        (
            (lo - BEFORE_MS).max(0.0),
            (hi + AFTER_MS).min(end).max(lo + 1.0),
        )
    } else {
        (0.0, end)
    }
}

fn mode_label(m: u8) -> &'static str {
    EcuMode::from_u8(m).map_or("?", EcuMode::name)
}

/// Draws `run`'s trace to `path` (PNG).
///
/// # Errors
/// The file cannot be written (the message names it).
pub fn draw(path: &Path, run: &OfflineRun, trace: &Trace) -> Result<(), String> {
    let err = |e: &dyn std::fmt::Display| format!("plot {}: {e}", path.display());
    let all_actions = timed_actions(run);
    let (t0, t1) = window(run, trace, &all_actions);
    let inside = |t: f64| t >= t0 && t <= t1;
    let root = BitMapBackend::new(path, (1200, 1000)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| err(&e))?;
    let root = root
        .titled(&run.name, ("sans-serif", 22))
        .map_err(|e| err(&e))?;
    let areas = root.split_by_breakpoints::<i32, i32, _, _>([], [360, 700]);
    let actions: Vec<(f64, String)> = all_actions
        .into_iter()
        .filter(|(t, _)| inside(*t))
        .collect();
    let contact_ms = run.contact_s.map(|c| c * 1e3).filter(|t| inside(*t));

    // 1. The sensors.
    let g_range = trace
        .crash_g
        .iter()
        .chain(&trace.safing_g)
        .filter(|(t, _)| inside(*t))
        .fold((-1.0f64, 1.0f64), |(lo, hi), (_, g)| {
            if g.is_finite() {
                (lo.min(*g), hi.max(*g))
            } else {
                (lo, hi)
            }
        });
    let pad = 0.08 * (g_range.1 - g_range.0);
    let mut c = ChartBuilder::on(&areas[0])
        .caption(
            "accelerometers as published (deceleration, positive = slowing)",
            ("sans-serif", 18),
        )
        .margin(8)
        .x_label_area_size(30)
        .y_label_area_size(55)
        .build_cartesian_2d(t0..t1, (g_range.0 - pad)..(g_range.1 + pad))
        .map_err(|e| err(&e))?;
    c.configure_mesh()
        .y_desc("deceleration [g]")
        .draw()
        .map_err(|e| err(&e))?;
    for (data, name, color) in [
        (&trace.safing_g, "safing sensor", RGBColor(230, 140, 0)),
        (&trace.crash_g, "crash sensor", BLUE),
    ] {
        c.draw_series(LineSeries::new(
            data.iter()
                .copied()
                .filter(|(t, g)| inside(*t) && g.is_finite()),
            color,
        ))
        .map_err(|e| err(&e))?
        .label(name)
        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color));
    }
    marks(
        &mut c,
        contact_ms,
        &actions,
        g_range.0 - pad,
        g_range.1 + pad,
    )
    .map_err(|e| err(&e))?;
    c.configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()
        .map_err(|e| err(&e))?;

    // 2. The decision: Δv against the boundaries and floors.
    let cycles: Vec<_> = trace.cycles.iter().filter(|c| inside(c.t_ms)).collect();
    let dv_hi = cycles
        .iter()
        .map(|c| {
            c.event_dv_mps
                .max(c.airbag_floor_mps)
                .max(c.pretensioner_floor_mps)
        })
        .fold(1.0f64, f64::max)
        * 1.25;
    let dv_lo = cycles.iter().map(|c| c.event_dv_mps).fold(0.0f64, f64::min);
    let mut c = ChartBuilder::on(&areas[1])
        .caption(
            "event Δv since its onset against the accelerometer-only boundaries (max of boundary and floor)",
            ("sans-serif", 18),
        )
        .margin(8)
        .x_label_area_size(30)
        .y_label_area_size(55)
        .build_cartesian_2d(t0..t1, dv_lo..dv_hi)
        .map_err(|e| err(&e))?;
    c.configure_mesh()
        .y_desc("Δv [m/s]")
        .draw()
        .map_err(|e| err(&e))?;
    let airbag = RED;
    let pret = RGBColor(140, 0, 160);
    for (name, color, pick) in [
        (
            "airbag: boundary, floor + roughness lift",
            airbag,
            (|c: &TraceCycle| (c.airbag_boundary_mps, c.airbag_floor_mps)) as Pick,
        ),
        ("pyrotechnic pretensioner: the same", pret, |c| {
            (c.pretensioner_boundary_mps, c.pretensioner_floor_mps)
        }),
    ] {
        // The decision line: only while an event is in progress (τ defined).
        for (i, seg) in segments(&cycles, pick).into_iter().enumerate() {
            let s = c
                .draw_series(LineSeries::new(seg, color.stroke_width(2)))
                .map_err(|e| err(&e))?;
            if i == 0 {
                s.label(name).legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2))
                });
            }
        }
        // The floor itself (lifted by a rough road), thin, always.
        c.draw_series(LineSeries::new(
            cycles.iter().map(|cyc| (cyc.t_ms, pick(cyc).1)),
            color.mix(0.45),
        ))
        .map_err(|e| err(&e))?;
    }
    c.draw_series(LineSeries::new(
        cycles.iter().map(|cyc| (cyc.t_ms, cyc.event_dv_mps)),
        BLACK.stroke_width(2),
    ))
    .map_err(|e| err(&e))?
    .label("event Δv (crash sensor)")
    .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK.stroke_width(2)));
    marks(&mut c, contact_ms, &actions, dv_lo, dv_hi).map_err(|e| err(&e))?;
    c.configure_series_labels()
        .position(SeriesLabelPosition::UpperLeft)
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()
        .map_err(|e| err(&e))?;

    // 3. The mode.
    let mut c = ChartBuilder::on(&areas[2])
        .caption("ECU mode and restraint actions", ("sans-serif", 18))
        .margin(8)
        .x_label_area_size(35)
        .y_label_area_size(85)
        .build_cartesian_2d(t0..t1, -0.5f64..5.5f64)
        .map_err(|e| err(&e))?;
    c.configure_mesh()
        .x_desc("time after the scenario start [ms]")
        .y_labels(6)
        .y_label_formatter(&|v| {
            let r = v.round();
            if (v - r).abs() < 1e-6 && (0.0..=5.0).contains(&r) {
                mode_label(r as u8).to_owned()
            } else {
                String::new()
            }
        })
        .draw()
        .map_err(|e| err(&e))?;
    c.draw_series(LineSeries::new(
        cycles.iter().map(|cyc| (cyc.t_ms, f64::from(cyc.mode))),
        BLACK.stroke_width(2),
    ))
    .map_err(|e| err(&e))?;
    marks(&mut c, contact_ms, &actions, -0.5, 5.5).map_err(|e| err(&e))?;
    for (i, (t, what)) in actions.iter().enumerate() {
        c.draw_series(std::iter::once(Text::new(
            what.clone(),
            (*t, 5.2 - 0.5 * (i % 4) as f64),
            ("sans-serif", 14).into_font().color(&action_color(what)),
        )))
        .map_err(|e| err(&e))?;
    }
    root.present().map_err(|e| err(&e))
}

type Pick = fn(&TraceCycle) -> (Option<f64>, f64);

/// The runs of cycles with an event in progress, each as (ms, max(boundary, floor)).
fn segments(cycles: &[&TraceCycle], pick: Pick) -> Vec<Vec<(f64, f64)>> {
    let mut out: Vec<Vec<(f64, f64)>> = Vec::new();
    let mut open = false;
    for c in cycles {
        match pick(c) {
            (Some(b), floor) => {
                if !open {
                    out.push(Vec::new());
                    open = true;
                }
                if let Some(seg) = out.last_mut() {
                    seg.push((c.t_ms, b.max(floor)));
                }
            }
            (None, _) => open = false,
        }
    }
    out
}

fn action_color(what: &str) -> RGBColor {
    if what.starts_with("airbag") {
        RED
    } else if what.starts_with("pretensioner_fire") {
        RGBColor(140, 0, 160)
    } else {
        RGBColor(0, 130, 0)
    }
}

type Chart<'a, 'b> = ChartContext<
    'a,
    BitMapBackend<'b>,
    Cartesian2d<plotters::coord::types::RangedCoordf64, plotters::coord::types::RangedCoordf64>,
>;

/// The true contact (grey, dashed) and every action (coloured) as vertical lines.
fn marks(
    c: &mut Chart<'_, '_>,
    contact_ms: Option<f64>,
    actions: &[(f64, String)],
    lo: f64,
    hi: f64,
) -> Result<(), String> {
    if let Some(t) = contact_ms {
        c.draw_series(DashedLineSeries::new(
            [(t, lo), (t, hi)],
            6,
            4,
            RGBColor(120, 120, 120).stroke_width(1),
        ))
        .map_err(|e| e.to_string())?;
    }
    for (t, what) in actions {
        c.draw_series(LineSeries::new([(*t, lo), (*t, hi)], action_color(what)))
            .map_err(|e| e.to_string())?;
    }
    Ok(())
}
