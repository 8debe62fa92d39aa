//! Borrowed, validated view of a diagram and its allocation-free lookup.
//!
//! This is the part that runs on the ECU cycle: no allocation, no panics
//! (all slice access goes through `get`), NaN-safe, bounded time (four
//! binary searches over at most [`crate::limits::MAX_AXIS_LEN`] points and a
//! fixed 16-corner × 9-field weighted sum).

use crate::validate::{check_axes, check_cells, check_thresholds};
use crate::{
    AirbagStage, AirbagThresholds, AxisFlags, Cell, Problem, Query, AXIS_COUNT, CELL_FIELDS,
};

/// A validated, borrowed characteristic diagram (`no_std`, `Copy`).
///
/// Invariants established by [`DiagramView::new`] and relied on by
/// [`DiagramView::lookup`]: every axis has ≥ 2 strictly increasing finite
/// points, the NaN fallback lies inside each axis, `cells.len()` equals the
/// product of the axis lengths, and every cell value is finite. Hence every
/// lookup output is finite.
#[derive(Debug, Clone, Copy)]
pub struct DiagramView<'a> {
    axes: [&'a [f32]; AXIS_COUNT],
    strides: [usize; AXIS_COUNT],
    cells: &'a [Cell],
    nan_fallback: Query,
    thresholds: AirbagThresholds,
}

/// Result of one interpolation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Lookup {
    /// Multilinearly interpolated continuous values. `values.bottoming_out`
    /// is the interpolated 0/1 flag (a weight in 0..=1), for information
    /// only — use [`Lookup::bottoming_out`] for the decision.
    pub values: Cell,
    /// `true` if ANY of the 16 surrounding grid cells that received a
    /// non-zero interpolation weight is flagged as bottoming out: a
    /// situation between a feasible and an infeasible optimum is reported as
    /// infeasible (conservative; the system must report it, not hide it).
    pub bottoming_out: bool,
    /// Airbag stage derived from the interpolated `values.airbag_level_kn`
    /// by the table's [`AirbagThresholds`] (after interpolation).
    pub airbag_stage: AirbagStage,
    /// Per axis: the input was outside the axis range (and was clamped to
    /// the edge) or was NaN (and was replaced by the NaN fallback).
    pub out_of_range: AxisFlags,
    /// Per axis: the input was NaN (a subset of `out_of_range`).
    pub nan_input: AxisFlags,
    /// The point actually interpolated (after clamping / NaN replacement).
    pub used: Query,
}

impl Lookup {
    /// `true` if the airbag should be fired (stage ≠ `NoFire`).
    pub fn airbag_fires(&self) -> bool {
        self.airbag_stage != AirbagStage::NoFire
    }

    /// Airbag level to command, kN: the interpolated level, or 0 when the
    /// derived stage is `NoFire`.
    pub fn airbag_command_kn(&self) -> f32 {
        if self.airbag_fires() {
            self.values.airbag_level_kn
        } else {
            0.0
        }
    }
}

/// Weighted sum over the corner cells of one lookup.
struct Accumulator<'a> {
    /// Weighted sum of the corner cells' fields.
    sum: [f32; CELL_FIELDS],
    bottoming: bool,
    cells: &'a [Cell],
    /// Weights of the lower / upper neighbour on the last axis.
    w3: [f32; 2],
}

impl Accumulator<'_> {
    /// Add the two adjacent cells `start`, `start + 1` (differing only in the
    /// last axis) with total weight `w`.
    #[inline(always)]
    fn pair(&mut self, start: usize, w: f32) {
        let (w_lo, w_hi) = (w * self.w3[0], w * self.w3[1]);
        // In range by the view's invariants (lower ≤ len-2 on every axis);
        // `get` keeps a violated invariant from panicking.
        let Some([lo, hi]) = self.cells.get(start..start.wrapping_add(2)) else {
            return;
        };
        let (a, b) = (lo.to_array(), hi.to_array());
        for ((acc, x), y) in self.sum.iter_mut().zip(a.iter()).zip(b.iter()) {
            *acc += w_lo * x + w_hi * y;
        }
        self.bottoming |=
            ((w_lo > 0.0) & (lo.bottoming_out > 0.5)) | ((w_hi > 0.0) & (hi.bottoming_out > 0.5));
    }
}

/// Where a query coordinate falls on one axis.
#[derive(Clone, Copy)]
struct Located {
    /// Lower grid index of the interval (`0..len-1`).
    lower: usize,
    /// Fraction in `[0, 1]` towards `lower + 1`.
    t: f32,
    used: f32,
    out_of_range: bool,
    nan: bool,
}

/// Index of the last axis point `<= x`, for `axis[0] <= x` (else 0).
///
/// Branchless binary search: the comparison feeds a conditional move, not
/// a branch, so the time does not depend on the data and there are no
/// mispredictions; `core`'s `partition_point` cost ~3x the instructions here.
#[inline(always)]
fn last_le(axis: &[f32], x: f32) -> usize {
    let mut base = 0usize;
    let mut size = axis.len();
    while size > 1 {
        let half = size / 2;
        let mid = base + half;
        // mid < base + size <= len: `get` never fails, it only avoids a panic path.
        let le = axis.get(mid).is_some_and(|&a| a <= x);
        base = if le { mid } else { base };
        size -= half;
    }
    base
}

/// Locate `x` on a validated axis (≥ 2 increasing finite points).
#[inline(always)]
fn locate(axis: &[f32], x: f32, nan_fallback: f32) -> Located {
    let nan = x.is_nan();
    let x = if nan { nan_fallback } else { x };
    let n = axis.len();
    let first = axis.first().copied().unwrap_or(0.0);
    let last = axis.last().copied().unwrap_or(0.0);
    let last_interval = n.saturating_sub(2);
    if x <= first {
        return Located {
            lower: 0,
            t: 0.0,
            used: first,
            out_of_range: nan || x < first,
            nan,
        };
    }
    if x >= last {
        return Located {
            lower: last_interval,
            t: 1.0,
            used: last,
            out_of_range: nan || x > last,
            nan,
        };
    }
    // first < x < last: the interval [lower, lower+1] with
    // a[lower] <= x < a[lower+1] lies inside the axis.
    let lower = last_le(axis, x).min(last_interval);
    let a0 = axis.get(lower).copied().unwrap_or(first);
    let a1 = axis.get(lower + 1).copied().unwrap_or(last);
    // a1 > a0 (strictly increasing), x in [a0, a1): t in [0, 1). The clamp is
    // belt and braces against rounding.
    let t = ((x - a0) / (a1 - a0)).clamp(0.0, 1.0);
    Located {
        lower,
        t,
        used: x,
        out_of_range: nan,
        nan,
    }
}

impl<'a> DiagramView<'a> {
    /// Validate and wrap borrowed axes (storage order, see [`crate::AxisId`])
    /// and row-major cells.
    pub fn new(
        axes: [&'a [f32]; AXIS_COUNT],
        cells: &'a [Cell],
        nan_fallback: Query,
        thresholds: AirbagThresholds,
    ) -> Result<Self, Problem> {
        check_axes(axes, &nan_fallback)?;
        check_cells(axes.map(|a| a.len()), cells)?;
        check_thresholds(&thresholds)?;
        Ok(Self::from_validated(axes, cells, nan_fallback, thresholds))
    }

    /// Wrap parts that were already validated with the same rules (by
    /// `Diagram::new`), skipping the O(cells) re-check.
    pub(crate) fn from_validated(
        axes: [&'a [f32]; AXIS_COUNT],
        cells: &'a [Cell],
        nan_fallback: Query,
        thresholds: AirbagThresholds,
    ) -> Self {
        let lens = axes.map(|a| a.len());
        let mut strides = [1usize; AXIS_COUNT];
        let mut acc = 1usize;
        for (s, &n) in strides.iter_mut().zip(lens.iter()).rev() {
            *s = acc;
            acc = acc.saturating_mul(n);
        }
        DiagramView {
            axes,
            strides,
            cells,
            nan_fallback,
            thresholds,
        }
    }

    /// Axis points in storage order.
    pub fn axes(&self) -> [&'a [f32]; AXIS_COUNT] {
        self.axes
    }

    /// Axis lengths in storage order.
    pub fn lens(&self) -> [usize; AXIS_COUNT] {
        self.axes.map(|a| a.len())
    }

    /// Row-major cells.
    pub fn cells(&self) -> &'a [Cell] {
        self.cells
    }

    /// Cell at grid coordinates, if inside the grid.
    pub fn cell_at(&self, idx: [usize; AXIS_COUNT]) -> Option<&'a Cell> {
        crate::cell_index(self.lens(), idx).and_then(|i| self.cells.get(i))
    }

    /// The point used in place of NaN inputs, per axis.
    pub fn nan_fallback(&self) -> Query {
        self.nan_fallback
    }

    /// The airbag stage thresholds of this table.
    pub fn thresholds(&self) -> AirbagThresholds {
        self.thresholds
    }

    /// Multilinear interpolation over the 16 surrounding grid points.
    ///
    /// * Inputs outside an axis are clamped to its edge; the axis is flagged
    ///   in [`Lookup::out_of_range`]. ±∞ behaves like any out-of-range value.
    /// * NaN inputs are replaced by the table's NaN fallback point for that
    ///   axis and flagged in both `out_of_range` and `nan_input`. The caller
    ///   (ECU) must treat either flag as degraded input (SPEC: fall back to the
    ///   reference restraint); the fallback only guarantees a finite output.
    /// * At grid points the result equals the stored cell exactly.
    /// * Discrete outputs are derived after interpolation: `airbag_stage`
    ///   from the interpolated level, `bottoming_out` from the contributing
    ///   corners.
    ///
    /// Allocation-free, panic-free, and never returns NaN.
    #[inline]
    pub fn lookup(&self, q: &Query) -> Lookup {
        let xs = q.to_array();
        let fb = self.nan_fallback.to_array();
        let mut loc = [Located {
            lower: 0,
            t: 0.0,
            used: 0.0,
            out_of_range: false,
            nan: false,
        }; AXIS_COUNT];
        for a in 0..AXIS_COUNT {
            let axis = self.axes.get(a).copied().unwrap_or(&[]);
            let x = xs.get(a).copied().unwrap_or(f32::NAN);
            let f = fb.get(a).copied().unwrap_or(0.0);
            if let Some(l) = loc.get_mut(a) {
                *l = locate(axis, x, f);
            }
        }
        let [l0, l1, l2, l3] = loc;
        let [s0, s1, s2, s3] = self.strides;
        let base = l0.lower * s0 + l1.lower * s1 + l2.lower * s2 + l3.lower * s3;
        // Per-axis weights of the lower and upper neighbour.
        let w = |l: &Located| [1.0 - l.t, l.t];
        let (w0, w1, w2, w3) = (w(&l0), w(&l1), w(&l2), w(&l3));

        // The last axis has stride 1, so the two corners that differ only in
        // it are adjacent in memory: 8 two-cell windows instead of 16
        // scattered cells, explicitly unrolled (a loop with computed indices
        // into the weight arrays costs ~2x the instructions).
        let mut acc = Accumulator {
            sum: [0.0f32; CELL_FIELDS],
            bottoming: false,
            cells: self.cells,
            w3,
        };
        let (w0l, w0h, w1l, w1h) = (w0[0], w0[1], w1[0], w1[1]);
        let (w01ll, w01lh, w01hl, w01hh) = (w0l * w1l, w0l * w1h, w0h * w1l, w0h * w1h);
        acc.pair(base, w01ll * w2[0]);
        acc.pair(base + s2, w01ll * w2[1]);
        acc.pair(base + s1, w01lh * w2[0]);
        acc.pair(base + s1 + s2, w01lh * w2[1]);
        acc.pair(base + s0, w01hl * w2[0]);
        acc.pair(base + s0 + s2, w01hl * w2[1]);
        acc.pair(base + s0 + s1, w01hh * w2[0]);
        acc.pair(base + s0 + s1 + s2, w01hh * w2[1]);
        let Accumulator { sum, bottoming, .. } = acc;
        let values = Cell::from_array(sum);
        Lookup {
            values,
            bottoming_out: bottoming,
            airbag_stage: self.thresholds.stage(values.airbag_level_kn),
            out_of_range: AxisFlags(loc.map(|l| l.out_of_range)),
            nan_input: AxisFlags(loc.map(|l| l.nan)),
            used: Query::from_array(loc.map(|l| l.used)),
        }
    }
}
