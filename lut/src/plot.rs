//! Small plotting helpers (plotters): SVG when the file name ends in `.svg`, PNG otherwise.

use anyhow::{Context, Result};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;

/// One named line.
pub struct Series<'a> {
    pub label: String,
    pub x: &'a [f64],
    pub y: &'a [f64],
}

/// One chart panel.
pub struct Panel<'a> {
    pub title: String,
    pub x_label: &'a str,
    pub y_label: &'a str,
    pub series: Vec<Series<'a>>,
}

const SIZE: (u32, u32) = (1000, 420);

/// Something drawable on any plotters backend. A trait rather than a closure because the
/// drawing code must be generic over the backend (SVG and bitmap are different types), and
/// closures cannot be generic.
pub trait Figure {
    /// Draws the whole figure on `root` (already sized; not yet presented).
    fn draw_on<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()>
    where
        DB::ErrorType: 'static;
}

/// Renders `figure` into `path` at `size` pixels: SVG when the file name ends in `.svg`
/// (any case), PNG otherwise. The one place that picks the backend for every plot of `lut`.
pub fn render(path: &Path, size: (u32, u32), figure: &(impl Figure + ?Sized)) -> Result<()> {
    // The folder is made and the file opened here, so a bad path is one readable line
    // (`writing x.png: Permission denied`) rather than the backend's debug text.
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    std::fs::File::create(path).with_context(|| format!("writing {}", path.display()))?;
    let is_svg = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("svg"));
    if is_svg {
        let root = SVGBackend::new(path, size).into_drawing_area();
        figure.draw_on(&root)?;
        root.present()
            .with_context(|| format!("writing {}", path.display()))?;
    } else {
        let root = BitMapBackend::new(path, size).into_drawing_area();
        figure.draw_on(&root)?;
        root.present()
            .with_context(|| format!("writing {}", path.display()))?;
    }
    Ok(())
}

/// Draw panels stacked vertically into `path`.
pub fn draw(path: &Path, panels: &[Panel<'_>]) -> Result<()> {
    let size = (SIZE.0, SIZE.1 * panels.len().max(1) as u32);
    render(path, size, panels)
}

impl Figure for [Panel<'_>] {
    fn draw_on<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()>
    where
        DB::ErrorType: 'static,
    {
        draw_on(root, self)
    }
}

fn bounds(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = values
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    let pad = ((hi - lo) * 0.05).max(1e-9);
    (lo - pad, hi + pad)
}

fn draw_on<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, panels: &[Panel<'_>]) -> Result<()>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let areas = root.split_evenly((panels.len().max(1), 1));
    for (area, panel) in areas.iter().zip(panels) {
        let (x0, x1) = bounds(panel.series.iter().flat_map(|s| s.x.iter().copied()));
        let (y0, y1) = bounds(panel.series.iter().flat_map(|s| s.y.iter().copied()));
        let mut chart = ChartBuilder::on(area)
            .caption(&panel.title, ("sans-serif", 20))
            .margin(10)
            .x_label_area_size(35)
            .y_label_area_size(55)
            .build_cartesian_2d(x0..x1, y0..y1)?;
        chart
            .configure_mesh()
            .x_desc(panel.x_label)
            .y_desc(panel.y_label)
            .draw()?;
        for (i, s) in panel.series.iter().enumerate() {
            let color = Palette99::pick(i).to_rgba();
            chart
                .draw_series(LineSeries::new(
                    s.x.iter().zip(s.y).map(|(&x, &y)| (x, y)),
                    color.stroke_width(2),
                ))?
                .label(s.label.clone())
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], color));
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .draw()?;
    }
    Ok(())
}
