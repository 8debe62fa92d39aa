//! Checking a built characteristic diagram (`lut verify`, the distributed build's collect job):
//! random cells re-simulated and re-optimised independently, and the planning margin over
//! every cell.

use crate::hash::splitmix64;
use crate::margin;
use crate::optimise::{self, Case, OptimiserConfig};
use crate::table::{
    cell_objective_g, occupant_at, optimise_point, pulse_at, sample_cells, settings_of, Grid,
};
use anyhow::{anyhow, bail, Result};
use diagram::Diagram;
use physics::{mps2_to_g, RestraintHardware, RestraintSettings};
use rayon::prelude::*;
use serde::Serialize;

/// Tolerance of `lut verify` when re-simulating a cell's stored setting: the stored setting is
/// rounded to f32, which can move a trigger time across a 0.1 ms integration step.
pub const RESIM_TOL_ABS_G: f64 = 0.05;
/// Relative part of the re-simulation tolerance.
pub const RESIM_TOL_REL: f64 = 0.005;
/// Tolerance of `lut verify` when comparing the table's objective with an independent
/// re-optimisation (another seed): the table may be worse by at most this much (absolute) ...
pub const REOPT_TOL_ABS_G: f64 = 1.0;
/// ... or this fraction, whichever is larger.
pub const REOPT_TOL_REL: f64 = 0.03;

/// One verified cell.
#[derive(Clone, Debug, Serialize)]
pub struct VerifyRow {
    /// Cell index.
    pub index: usize,
    /// Grid coordinates.
    pub coords: [usize; 4],
    /// Stored objective [g].
    pub table_objective_g: f64,
    /// Objective of the stored setting re-simulated now [g].
    pub resimulated_objective_g: f64,
    /// Objective of an independent re-optimisation [g].
    pub reoptimised_objective_g: f64,
    /// Stored bottoming-out flag.
    pub table_bottoming_out: bool,
    /// Bottoming-out of the independent re-optimisation.
    pub reoptimised_bottoming_out: bool,
    /// Passed.
    pub ok: bool,
    /// Why not.
    pub problem: Option<String>,
}

/// Re-optimise `n` random cells (chosen with `seed`, and re-optimised with seeds derived from
/// `seed`, independent of the build's) and check the table: (1) the stored setting re-simulated
/// reproduces the stored objective and flag within [`RESIM_TOL_ABS_G`]/[`RESIM_TOL_REL`];
/// (2) the independent optimum is not better than the table by more than
/// [`REOPT_TOL_ABS_G`]/[`REOPT_TOL_REL`], and not feasible where the table says infeasible.
pub fn verify(d: &Diagram, n: usize, seed: u64) -> Result<Vec<VerifyRow>> {
    let grid = Grid::from_table(d)?;
    let picks = sample_cells(grid.axes.cell_count(), n, seed);
    let hw = RestraintHardware::default();
    picks
        .par_iter()
        .map(|&i| {
            let p = grid.axes.point(i).ok_or_else(|| anyhow!("cell {i} outside the grid"))?;
            let c = d.cells().get(i).ok_or_else(|| anyhow!("cell {i} missing"))?;
            let table_obj = cell_objective_g(c);
            let pulse = pulse_at(&grid.ego, &p.query)?;
            let case = Case { pulse: pulse.ego(), occupant: occupant_at(&p.query) };
            let (_, outs) = optimise::evaluate(&[case], &settings_of(c), &hw, grid.optimiser.reserve_m)?;
            let resim = outs.first().ok_or_else(|| anyhow!("no outcome"))?;
            let resim_obj = mps2_to_g(resim.max_decel_mps2) + mps2_to_g(resim.mean_decel_mps2);
            let cfg = OptimiserConfig { seed: splitmix64(seed ^ 0xA5A5_5A5A ^ i as u64), ..grid.optimiser };
            let re = optimise_point(&grid, &p, &cfg)?;
            let re_obj = cell_objective_g(&re.cell);
            let mut problem = None;
            if resim.bottomed_out != c.is_bottoming_out() {
                problem = Some(format!("stored setting re-simulated: bottoming_out {} but table says {}", resim.bottomed_out, c.is_bottoming_out()));
            } else if (resim_obj - table_obj).abs() > RESIM_TOL_ABS_G.max(RESIM_TOL_REL * table_obj) {
                problem = Some(format!("stored setting re-simulated: objective {resim_obj:.3} g vs stored {table_obj:.3} g"));
            } else if c.is_bottoming_out() && !re.optimum.bottoming_out() {
                problem = Some("table says bottoming-out but an independent optimisation found a feasible setting".into());
            } else if !c.is_bottoming_out() && table_obj - re_obj > REOPT_TOL_ABS_G.max(REOPT_TOL_REL * re_obj) {
                problem = Some(format!("independent optimum {re_obj:.3} g is better than the table's {table_obj:.3} g beyond tolerance"));
            }
            Ok(VerifyRow {
                index: i,
                coords: p.coords,
                table_objective_g: table_obj,
                resimulated_objective_g: resim_obj,
                reoptimised_objective_g: re_obj,
                table_bottoming_out: c.is_bottoming_out(),
                reoptimised_bottoming_out: re.optimum.bottoming_out(),
                ok: problem.is_none(),
                problem,
            })
        })
        .collect()
}

/// The planning margin's check of every cell of `d` (`lut::margin`) over `span_kg` in steps of
/// `step_kg`, against the `reference` restraint: what `lut verify` reports and enforces.
///
/// # Errors
/// The header lacks the optimiser settings, or a pulse / simulation fails.
pub fn check_margin(
    d: &Diagram,
    reference: &RestraintSettings,
    span_kg: f64,
    step_kg: f64,
) -> Result<Vec<margin::MarginRow>> {
    let grid = Grid::from_table(d)?;
    (0..grid.axes.cell_count())
        .into_par_iter()
        .map(|i| {
            let p = grid
                .axes
                .point(i)
                .ok_or_else(|| anyhow!("cell {i} outside the grid"))?;
            let c = d
                .cells()
                .get(i)
                .ok_or_else(|| anyhow!("cell {i} missing"))?;
            grid.lighter_set(&p, span_kg, step_kg, reference, &grid.optimiser)?
                .judge(&p, &settings_of(c))
        })
        .collect()
}

/// Checks `d` against the planning margin its header states, if any (`lut build --slurm`'s
/// collect job; `lut verify` reports more): `Ok(Some(line))` when every cell holds it,
/// `Ok(None)` when it states none.
///
/// # Errors
/// A cell does not hold the stated span, or the check fails.
pub fn enforce_stated_margin(d: &Diagram) -> Result<Option<String>> {
    let Some(span_kg) = margin::stated_span_kg(d)? else {
        return Ok(None);
    };
    let rows = check_margin(
        d,
        &margin::reference_settings()?,
        span_kg,
        margin::DEFAULT_STEP_KG,
    )?;
    let s = margin::MarginSummary::of(&rows);
    if !s.holds() {
        bail!(
            "the table breaks the planning margin of {span_kg:.0} kg its header states in {} of {} cells",
            s.cells - s.hold,
            s.cells
        );
    }
    Ok(Some(format!(
        "planning margin of {span_kg:.0} kg holds in all {} cells",
        s.cells
    )))
}
