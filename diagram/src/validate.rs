//! Validation rules shared by the owned diagram, the borrowed view and the
//! file loader. Everything here is `no_std` and allocation-free so the ECU
//! can re-check a view it builds itself.

use crate::{cell_count, AirbagThresholds, AxisId, Cell, Query, AXIS_COUNT, CELL_FIELDS};

/// Plausible value ranges. A table outside them is rejected as corrupt or
/// built for a different unit system; they are deliberately wider than the
/// paper's ranges so that an extended study table still loads.
pub mod limits {
    use crate::AXIS_COUNT;

    /// Inclusive plausible range `(min, max)` of each axis, storage order:
    /// closing speed 0–250 km/h, opponent mass 100–60 000 kg,
    /// occupant mass 1–300 kg, seat distance 0–1500 mm.
    pub const AXIS_RANGE: [(f32, f32); AXIS_COUNT] =
        [(0.0, 250.0), (100.0, 60_000.0), (1.0, 300.0), (0.0, 1500.0)];

    /// Maximum points on one axis (keeps binary search and memory bounded).
    pub const MAX_AXIS_LEN: usize = 4096;

    /// Maximum number of cells (≈ 360 MB of `f32` at 9 fields per cell).
    pub const MAX_CELLS: usize = 10_000_000;

    /// Inclusive plausible range of each [`crate::Cell`] field, in
    /// [`crate::Cell::FIELD_NAMES`] order: limiter 0–30 kN, airbag 0–30 kN,
    /// pretensioner −1000…+1000 ms, airbag time 0–1000 ms, a_max/a_mean
    /// 0–1000 g, excursion 0–3000 mm, bottoming-out exactly 0 or 1 (checked
    /// separately), a* 0–1000 g.
    pub const CELL_RANGE: [(f32, f32); crate::CELL_FIELDS] = [
        (0.0, 30.0),
        (0.0, 30.0),
        (-1000.0, 1000.0),
        (0.0, 1000.0),
        (0.0, 1000.0),
        (0.0, 1000.0),
        (0.0, 3000.0),
        (0.0, 1.0),
        (0.0, 1000.0),
    ];

    /// Plausible ego-vehicle mass, kg.
    pub const EGO_MASS_KG: (f32, f32) = (100.0, 60_000.0);

    /// Plausible airbag threshold range, kN.
    pub const THRESHOLD_KN: (f32, f32) = (0.0, 30.0);
}

/// What is wrong with a diagram (without the file name; see `LoadError`).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum Problem {
    /// An axis has fewer than 2 points (interpolation needs an interval).
    #[error("axis {axis}: needs at least 2 points, has {len}")]
    AxisTooShort {
        /// Axis.
        axis: AxisId,
        /// Its length.
        len: usize,
    },
    /// An axis has more than [`limits::MAX_AXIS_LEN`] points.
    #[error("axis {axis}: {len} points, more than the limit {max}")]
    AxisTooLong {
        /// Axis.
        axis: AxisId,
        /// Its length.
        len: usize,
        /// The limit.
        max: usize,
    },
    /// An axis value is NaN or infinite.
    #[error("axis {axis}: point {index} is not finite ({value})")]
    AxisNotFinite {
        /// Axis.
        axis: AxisId,
        /// Point index.
        index: usize,
        /// Offending value.
        value: f32,
    },
    /// An axis is not strictly increasing.
    #[error("axis {axis}: not strictly increasing at point {index} ({prev} then {value})")]
    AxisNotIncreasing {
        /// Axis.
        axis: AxisId,
        /// Index of the point that is not above its predecessor.
        index: usize,
        /// Predecessor value.
        prev: f32,
        /// Offending value.
        value: f32,
    },
    /// An axis value is outside [`limits::AXIS_RANGE`].
    #[error("axis {axis}: point {index} = {value} outside plausible range {min}..={max}")]
    AxisImplausible {
        /// Axis.
        axis: AxisId,
        /// Point index.
        index: usize,
        /// Offending value.
        value: f32,
        /// Range minimum.
        min: f32,
        /// Range maximum.
        max: f32,
    },
    /// The NaN fallback point of an axis is not finite or outside the axis.
    #[error("axis {axis}: NaN fallback {value} is not inside the axis range {min}..={max}")]
    FallbackOutsideAxis {
        /// Axis.
        axis: AxisId,
        /// Offending value.
        value: f32,
        /// Axis first point.
        min: f32,
        /// Axis last point.
        max: f32,
    },
    /// The number of cells differs from the product of the axis lengths.
    #[error("cell count {found} does not match the product of the axis lengths {expected}")]
    CellCount {
        /// Product of the axis lengths.
        expected: usize,
        /// Cells present.
        found: usize,
    },
    /// Too many cells (see [`limits::MAX_CELLS`]), or the product overflows.
    #[error("grid too large: more than {max} cells")]
    TooManyCells {
        /// The limit.
        max: usize,
    },
    /// A cell value is NaN or infinite.
    #[error("cell {index} {coords:?}: {field} is not finite ({value})")]
    CellNotFinite {
        /// Row-major cell index.
        index: usize,
        /// Grid coordinates.
        coords: [usize; AXIS_COUNT],
        /// Field name.
        field: &'static str,
        /// Offending value.
        value: f32,
    },
    /// A cell value is outside [`limits::CELL_RANGE`] (or bottoming-out not 0/1).
    #[error("cell {index} {coords:?}: {field} = {value} outside plausible range {min}..={max}")]
    CellImplausible {
        /// Row-major cell index.
        index: usize,
        /// Grid coordinates.
        coords: [usize; AXIS_COUNT],
        /// Field name.
        field: &'static str,
        /// Offending value.
        value: f32,
        /// Range minimum.
        min: f32,
        /// Range maximum.
        max: f32,
    },
    /// A cell index appeared twice or was out of range in `from_indexed_cells`.
    #[error("cell index {index} given twice or outside the grid of {count} cells")]
    CellIndexInvalid {
        /// Offending index.
        index: usize,
        /// Cells in the grid.
        count: usize,
    },
    /// A cell was never given in `from_indexed_cells`.
    #[error("cell {index} {coords:?} missing")]
    CellMissing {
        /// Row-major cell index.
        index: usize,
        /// Grid coordinates.
        coords: [usize; AXIS_COUNT],
    },
    /// The airbag thresholds are not finite, out of range or not ordered.
    #[error("airbag thresholds invalid: no fire below {no_fire_below_kn} kN, stage 2 from {stage2_from_kn} kN (need 0 <= no-fire <= stage2 <= 30)")]
    Thresholds {
        /// Stored value.
        no_fire_below_kn: f32,
        /// Stored value.
        stage2_from_kn: f32,
    },
    /// The ego-vehicle description is implausible.
    #[error("header: ego vehicle mass {mass_kg} kg outside plausible range, or class {class} not in 1..=6")]
    EgoVehicle {
        /// Stored mass.
        mass_kg: f32,
        /// Stored class.
        class: u8,
    },
}

/// Check one axis.
pub(crate) fn check_axis(axis: AxisId, points: &[f32]) -> Result<(), Problem> {
    let len = points.len();
    if len < 2 {
        return Err(Problem::AxisTooShort { axis, len });
    }
    if len > limits::MAX_AXIS_LEN {
        return Err(Problem::AxisTooLong {
            axis,
            len,
            max: limits::MAX_AXIS_LEN,
        });
    }
    let (min, max) = limits::AXIS_RANGE
        .get(axis.index())
        .copied()
        .unwrap_or((f32::NEG_INFINITY, f32::INFINITY));
    let mut prev: Option<f32> = None;
    for (index, &value) in points.iter().enumerate() {
        if !value.is_finite() {
            return Err(Problem::AxisNotFinite { axis, index, value });
        }
        if !(min..=max).contains(&value) {
            return Err(Problem::AxisImplausible {
                axis,
                index,
                value,
                min,
                max,
            });
        }
        if let Some(p) = prev {
            if value <= p {
                return Err(Problem::AxisNotIncreasing {
                    axis,
                    index,
                    prev: p,
                    value,
                });
            }
        }
        prev = Some(value);
    }
    Ok(())
}

/// Check all axes, the NaN fallback point, and return the cell count.
pub(crate) fn check_axes(
    axes: [&[f32]; AXIS_COUNT],
    nan_fallback: &Query,
) -> Result<usize, Problem> {
    for (axis, points) in AxisId::ALL.iter().zip(axes.iter()) {
        check_axis(*axis, points)?;
    }
    for ((axis, points), value) in AxisId::ALL
        .iter()
        .zip(axes.iter())
        .zip(nan_fallback.to_array())
    {
        let min = points.first().copied().unwrap_or(f32::NAN);
        let max = points.last().copied().unwrap_or(f32::NAN);
        if !(value >= min && value <= max) {
            return Err(Problem::FallbackOutsideAxis {
                axis: *axis,
                value,
                min,
                max,
            });
        }
    }
    let lens = axes.map(|a| a.len());
    match cell_count(lens) {
        Some(n) if n <= limits::MAX_CELLS => Ok(n),
        _ => Err(Problem::TooManyCells {
            max: limits::MAX_CELLS,
        }),
    }
}

/// Check one cell's values.
pub(crate) fn check_cell(
    index: usize,
    coords: [usize; AXIS_COUNT],
    cell: &Cell,
) -> Result<(), Problem> {
    let values = cell.to_array();
    for f in 0..CELL_FIELDS {
        let (Some(&value), Some(&field), Some(&(min, max))) = (
            values.get(f),
            Cell::FIELD_NAMES.get(f),
            limits::CELL_RANGE.get(f),
        ) else {
            continue;
        };
        if !value.is_finite() {
            return Err(Problem::CellNotFinite {
                index,
                coords,
                field,
                value,
            });
        }
        let bottoming_ok = field != "bottoming_out" || value == 0.0 || value == 1.0;
        if !(min..=max).contains(&value) || !bottoming_ok {
            return Err(Problem::CellImplausible {
                index,
                coords,
                field,
                value,
                min,
                max,
            });
        }
    }
    Ok(())
}

/// Check all cells against the axes' lengths.
pub(crate) fn check_cells(lens: [usize; AXIS_COUNT], cells: &[Cell]) -> Result<(), Problem> {
    let expected = cell_count(lens).ok_or(Problem::TooManyCells {
        max: limits::MAX_CELLS,
    })?;
    if cells.len() != expected {
        return Err(Problem::CellCount {
            expected,
            found: cells.len(),
        });
    }
    for (index, cell) in cells.iter().enumerate() {
        let coords = crate::cell_coords(lens, index).unwrap_or([0; AXIS_COUNT]);
        check_cell(index, coords, cell)?;
    }
    Ok(())
}

/// Check the airbag stage thresholds.
pub(crate) fn check_thresholds(t: &AirbagThresholds) -> Result<(), Problem> {
    let (lo, hi) = limits::THRESHOLD_KN;
    let ok = t.no_fire_below_kn.is_finite()
        && t.stage2_from_kn.is_finite()
        && lo <= t.no_fire_below_kn
        && t.no_fire_below_kn <= t.stage2_from_kn
        && t.stage2_from_kn <= hi;
    if ok {
        Ok(())
    } else {
        Err(Problem::Thresholds {
            no_fire_below_kn: t.no_fire_below_kn,
            stage2_from_kn: t.stage2_from_kn,
        })
    }
}
