//! Outcome picture: occupant deceleration and forward excursion over time, adaptive vs
//! reference, with the compartment pulse and the available ride-down for context.

use crate::report::Judged;
use plotters::prelude::*;
use serde::{Deserialize, Serialize};
use std::io::Write;
use std::path::{Path, PathBuf};

/// File name of a picture left to be drawn after the run (`actuator-stubs --plot-later`):
/// drawing costs 0.6–1.0 s of an emulated guest's time at the end of every run, on the run's
/// critical path, and a few ms on the host. [`draw_pending`] (`actuator-stubs draw-pending
/// ROOT`) draws them there.
pub const PLOT_LATER: &str = "outcome-plot.json";

/// Everything [`draw`] needs, as written for [`draw_later`] (the time histories are not in
/// report.json).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct PlotData {
    /// Picture title (the scenario name).
    pub title: String,
    /// Adaptive outcome.
    pub adaptive: Judged,
    /// Its time histories.
    pub adaptive_trace: Trace,
    /// Reference outcome.
    pub reference: Judged,
    /// Its time histories.
    pub reference_trace: Trace,
    /// Compartment deceleration [g], one value per `pulse_step_ms`.
    pub pulse_g: Vec<f64>,
    /// Pulse step [ms].
    pub pulse_step_ms: f64,
}

/// A judged outcome's time histories.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct Trace {
    /// t [ms after contact].
    pub t_ms: Vec<f64>,
    /// Occupant deceleration [g].
    pub decel_g: Vec<f64>,
    /// Excursion [mm].
    pub excursion_mm: Vec<f64>,
}

impl Trace {
    /// The time histories of `j`.
    pub fn of(j: &Judged) -> Self {
        Self {
            t_ms: j.t_ms.clone(),
            decel_g: j.decel_g.clone(),
            excursion_mm: j.excursion_trace_mm.clone(),
        }
    }

    fn into_judged(self, mut j: Judged) -> Judged {
        j.t_ms = self.t_ms;
        j.decel_g = self.decel_g;
        j.excursion_trace_mm = self.excursion_mm;
        j
    }
}

/// Draws `dir/outcome.png` from `dir/`[`PLOT_LATER`] when a run left it, and removes the
/// note; `Ok(false)` when there is none.
///
/// # Errors
/// The note cannot be read or parsed, or the picture cannot be drawn.
pub fn draw_later(dir: &Path) -> Result<bool, String> {
    let note = dir.join(PLOT_LATER);
    if !note.exists() {
        return Ok(false);
    }
    let text = std::fs::read_to_string(&note).map_err(|e| format!("{}: {e}", note.display()))?;
    let d: PlotData =
        serde_json::from_str(&text).map_err(|e| format!("{}: invalid: {e}", note.display()))?;
    draw(
        &dir.join("outcome.png"),
        &d.title,
        &d.adaptive_trace.into_judged(d.adaptive),
        &d.reference_trace.into_judged(d.reference),
        &d.pulse_g,
        d.pulse_step_ms,
    )?;
    std::fs::remove_file(&note).map_err(|e| format!("{}: {e}", note.display()))?;
    Ok(true)
}

/// One picture drawn by [`draw_pending`]: its run folder and the summary line, or what failed.
#[derive(Debug)]
pub struct Drawn {
    /// The run folder.
    pub dir: PathBuf,
    /// The line appended to its `summary.txt`, or why the picture was not drawn.
    pub result: Result<String, String>,
}

/// Draws every picture left in `root` and its sub-folders (three levels, as the run folders
/// lie: `OUT/<scenario>/`, the campaign's `OUT/<guest>/<case>/<scenario>/`) and appends a line
/// to each folder's `summary.txt`. A folder that fails keeps its note and says why; the others
/// are drawn.
///
/// # Errors
/// `root` cannot be read.
pub fn draw_pending(root: &Path) -> Result<Vec<Drawn>, String> {
    let dirs = host::files::run_folders_holding(root, PLOT_LATER).map_err(|e| e.to_string())?;
    Ok(dirs
        .into_iter()
        .map(|dir| {
            let result = draw_later(&dir).and_then(|_| {
                let line = format!(
                    "outcome picture: {} (drawn on the host after the run)",
                    dir.join("outcome.png").display()
                );
                let summary = dir.join("summary.txt");
                std::fs::OpenOptions::new()
                    .create(true)
                    .append(true)
                    .open(&summary)
                    .and_then(|mut f| writeln!(f, "{line}"))
                    .map_err(|e| format!("{}: {e}", summary.display()))?;
                Ok(line)
            });
            Drawn { dir, result }
        })
        .collect())
}

/// Draws the two-panel PNG; `pulse_g` is the compartment deceleration [g] at `pulse_step_ms`.
pub fn draw(
    path: &Path,
    title: &str,
    adaptive: &Judged,
    reference: &Judged,
    pulse_g: &[f64],
    pulse_step_ms: f64,
) -> Result<(), String> {
    let err = |e: &dyn std::fmt::Display| format!("plot {}: {e}", path.display());
    let root = BitMapBackend::new(path, (1000, 800)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| err(&e))?;
    let (top, bottom) = root.split_vertically(400);
    let t_end = adaptive
        .t_ms
        .last()
        .copied()
        .unwrap_or(0.0)
        .max(reference.t_ms.last().copied().unwrap_or(0.0))
        .max(pulse_g.len() as f64 * pulse_step_ms)
        .max(10.0);
    let max_g = adaptive
        .decel_g
        .iter()
        .chain(&reference.decel_g)
        .chain(pulse_g)
        .fold(1.0f64, |m, v| if v.is_finite() { m.max(*v) } else { m });
    let min_g = adaptive
        .decel_g
        .iter()
        .chain(&reference.decel_g)
        .fold(0.0f64, |m, v| m.min(*v));
    let mut c = ChartBuilder::on(&top)
        .caption(
            format!("{title}: occupant deceleration"),
            ("sans-serif", 20),
        )
        .margin(10)
        .x_label_area_size(35)
        .y_label_area_size(55)
        .build_cartesian_2d(0.0..t_end, min_g.min(0.0)..max_g * 1.1)
        .map_err(|e| err(&e))?;
    c.configure_mesh()
        .x_desc("time after true contact [ms]")
        .y_desc("deceleration [g]")
        .draw()
        .map_err(|e| err(&e))?;
    let pulse_series = pulse_g
        .iter()
        .enumerate()
        .map(|(i, g)| (i as f64 * pulse_step_ms, *g));
    c.draw_series(LineSeries::new(pulse_series, RGBColor(150, 150, 150)))
        .map_err(|e| err(&e))?
        .label("compartment (true pulse)")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], RGBColor(150, 150, 150)));
    for (j, name, color) in [
        (adaptive, "adaptive (as commanded)", BLUE),
        (reference, "reference restraint", RED),
    ] {
        c.draw_series(LineSeries::new(
            j.t_ms.iter().copied().zip(j.decel_g.iter().copied()),
            color.stroke_width(2),
        ))
        .map_err(|e| err(&e))?
        .label(format!(
            "{name}: a_max {:.1} g, a_mean {:.1} g",
            j.a_max_g, j.a_mean_g
        ))
        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2)));
    }
    c.configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()
        .map_err(|e| err(&e))?;

    let max_mm = adaptive
        .excursion_trace_mm
        .iter()
        .chain(&reference.excursion_trace_mm)
        .fold(adaptive.available_mm, |m, v| m.max(*v));
    let mut c = ChartBuilder::on(&bottom)
        .caption("occupant forward excursion", ("sans-serif", 20))
        .margin(10)
        .x_label_area_size(35)
        .y_label_area_size(55)
        .build_cartesian_2d(0.0..t_end, 0.0..max_mm * 1.1)
        .map_err(|e| err(&e))?;
    c.configure_mesh()
        .x_desc("time after true contact [ms]")
        .y_desc("excursion [mm]")
        .draw()
        .map_err(|e| err(&e))?;
    let avail = adaptive.available_mm;
    c.draw_series(LineSeries::new(
        [(0.0, avail), (t_end, avail)],
        BLACK.stroke_width(1),
    ))
    .map_err(|e| err(&e))?
    .label(format!(
        "available ride-down {avail:.0} mm (bottoming-out above)"
    ))
    .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK));
    for (j, name, color) in [(adaptive, "adaptive", BLUE), (reference, "reference", RED)] {
        c.draw_series(LineSeries::new(
            j.t_ms
                .iter()
                .copied()
                .zip(j.excursion_trace_mm.iter().copied()),
            color.stroke_width(2),
        ))
        .map_err(|e| err(&e))?
        .label(format!(
            "{name}: max {:.0} mm{}",
            j.excursion_mm,
            if j.bottomed_out { " BOTTOMED OUT" } else { "" }
        ))
        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2)));
    }
    c.configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()
        .map_err(|e| err(&e))?;
    root.present().map_err(|e| err(&e))?;
    Ok(())
}
