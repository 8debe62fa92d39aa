//! Heat maps (plotters) of one quantity over two axes: each grid value is drawn as a cell whose
//! edges lie halfway to its neighbours (non-uniform axes stay honest), coloured blue (low) →
//! red (high), with the value written in it. SVG if the name ends in `.svg`, else PNG.

use crate::plot::{render, Figure};
use anyhow::Result;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;

/// One heat-map panel: `z[iy][ix]` at (`x[ix]`, `y[iy]`); NaN cells are drawn grey.
pub struct HeatPanel {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub x: Vec<f64>,
    pub y: Vec<f64>,
    pub z: Vec<Vec<f64>>,
    /// Cells to mark with a black frame (e.g. bottoming-out), same shape as `z`.
    pub marked: Option<Vec<Vec<bool>>>,
    /// Number format precision of the cell labels.
    pub decimals: usize,
}

fn edges(v: &[f64]) -> Vec<f64> {
    let n = v.len();
    let mut e = Vec::with_capacity(n + 1);
    if n == 1 {
        return vec![v[0] - 0.5, v[0] + 0.5];
    }
    e.push(v[0] - 0.5 * (v[1] - v[0]));
    for w in v.windows(2) {
        e.push(0.5 * (w[0] + w[1]));
    }
    e.push(v[n - 1] + 0.5 * (v[n - 1] - v[n - 2]));
    e
}

fn colour(t: f64) -> HSLColor {
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    };
    HSLColor(0.66 * (1.0 - t), 0.75, 0.55)
}

/// Draw panels side by side into `path`.
pub fn draw(path: &Path, panels: &[HeatPanel]) -> Result<()> {
    let size = (720 * panels.len().max(1) as u32, 600);
    render(path, size, panels)
}

impl Figure for [HeatPanel] {
    fn draw_on<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()>
    where
        DB::ErrorType: 'static,
    {
        draw_on(root, self)
    }
}

fn draw_on<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, panels: &[HeatPanel]) -> Result<()>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let areas = root.split_evenly((1, panels.len().max(1)));
    for (area, p) in areas.iter().zip(panels) {
        let xe = edges(&p.x);
        let ye = edges(&p.y);
        let (lo, hi) =
            p.z.iter()
                .flatten()
                .filter(|v| v.is_finite())
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                    (a.min(v), b.max(v))
                });
        let span = if hi > lo { hi - lo } else { 1.0 };
        let mut chart = ChartBuilder::on(area)
            .caption(
                format!(
                    "{} (min {lo:.prec$}, max {hi:.prec$})",
                    p.title,
                    prec = p.decimals
                ),
                ("sans-serif", 18),
            )
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(xe[0]..xe[xe.len() - 1], ye[0]..ye[ye.len() - 1])?;
        chart
            .configure_mesh()
            .disable_mesh()
            .x_desc(p.x_label.as_str())
            .y_desc(p.y_label.as_str())
            .draw()?;
        for (iy, row) in p.z.iter().enumerate() {
            for (ix, &v) in row.iter().enumerate() {
                let (x0, x1, y0, y1) = (xe[ix], xe[ix + 1], ye[iy], ye[iy + 1]);
                let fill: ShapeStyle = if v.is_finite() {
                    colour((v - lo) / span).filled()
                } else {
                    RGBColor(200, 200, 200).filled()
                };
                chart.draw_series(std::iter::once(Rectangle::new([(x0, y0), (x1, y1)], fill)))?;
                let marked = p
                    .marked
                    .as_ref()
                    .and_then(|m| m.get(iy))
                    .and_then(|r| r.get(ix))
                    .copied()
                    .unwrap_or(false);
                if marked {
                    chart.draw_series(std::iter::once(Rectangle::new(
                        [(x0, y0), (x1, y1)],
                        BLACK.stroke_width(3),
                    )))?;
                }
                if p.x.len() <= 16 && p.y.len() <= 16 {
                    let label = if v.is_finite() {
                        format!("{v:.*}", p.decimals)
                    } else {
                        "–".into()
                    };
                    chart.draw_series(std::iter::once(Text::new(
                        label,
                        (0.5 * (x0 + x1), 0.5 * (y0 + y1)),
                        ("sans-serif", 13).into_font().color(&BLACK).pos(
                            plotters::style::text_anchor::Pos::new(
                                plotters::style::text_anchor::HPos::Center,
                                plotters::style::text_anchor::VPos::Center,
                            ),
                        ),
                    )))?;
                }
            }
        }
    }
    Ok(())
}
