//! The planning margin as a property of the table (issue 24): every cell's setting, planned for
//! an opponent of the cell's mass M, judged on the true pulse of every opponent from M down to
//! M − `span_kg` — no worse than the reference restraint, and no bottoming-out where the
//! reference does not bottom out.
//!
//! Why lighter only: the ECU plans with the heavier side of what it knows. Without V2X it plans
//! for the object list's mass plus `mass_misreport_kg` (1 200 kg); with a V2X station for the
//! heavier of the two sources plus `v2x_mass_margin_kg` (300 kg). So the truth is at most the
//! plan (one source light by up to the misreport bound) and at least the plan minus twice the
//! bound (a source heavy by it), or the plan minus 1 200 + 300 kg with a station. Both sets lie
//! inside [M − 2 400 kg, M]. A table may state the span it holds for in its header
//! ([`EXTRA_SPAN_KG`]); `lut verify` checks every cell and enforces a stated span.
//!
//! The airbag is judged as the ECU fires it: at the cell's planned time, or later where the
//! lighter truth's pulse carries the airbag's severity floor only later (plan = fire,
//! [`OptimiserConfig::earliest_airbag_s`]). Where the reference strikes through too, the cell
//! must not strike deeper. A static setting: the crash phase's re-planning is the ECU's, tested
//! closed loop by the offline misreport grids.

use crate::optimise::OptimiserConfig;
use crate::robust_cells::{objective_g, UncertainSet};
use crate::scenario::Ego;
use crate::table::{occupant_at, settings_of, Grid};
use anyhow::{anyhow, Result};
use diagram::Diagram;
use physics::{simulate_occupant, OccupantOutcome, RestraintHardware, RestraintSettings};
use rayon::prelude::*;
use serde::Serialize;

/// Header key (`build.extra`) of the span the table is verified for: a setting planned for
/// opponent mass M holds for every true opponent from M − this [kg] to M.
pub const EXTRA_SPAN_KG: &str = "robust.lighter_opponent_kg";
/// The span the shipped rule needs: the truth up to twice the misreport bound (1 200 kg)
/// lighter than the plan.
pub const DEFAULT_SPAN_KG: f64 = 2400.0;
/// Step between the checked true masses [kg].
pub const DEFAULT_STEP_KG: f64 = 200.0;

/// The span a table states in its header, if any.
///
/// # Errors
/// The key is there but not a finite, non-negative number.
pub fn stated_span_kg(d: &Diagram) -> Result<Option<f64>> {
    match d.header().build.extra.get(EXTRA_SPAN_KG) {
        None => Ok(None),
        Some(v) => match v.parse::<f64>() {
            Ok(x) if x.is_finite() && x >= 0.0 => Ok(Some(x)),
            _ => Err(anyhow!(
                "table header: {EXTRA_SPAN_KG} = {v:?} is not a mass ≥ 0 kg"
            )),
        },
    }
}

/// One cell checked over the lighter truths.
#[derive(Clone, Debug, Serialize)]
pub struct MarginRow {
    /// Cell index.
    pub index: usize,
    /// Grid coordinates.
    pub coords: [usize; 4],
    /// The planned opponent mass (the cell's) [kg].
    pub planned_kg: f64,
    /// The lighter true mass where the setting did worst against the reference [kg].
    pub worst_truth_kg: f64,
    /// a_max + a_mean change against the reference there, % (negative = better).
    pub worst_change_pct: f64,
    /// Lighter true masses where the setting bottoms out and the reference does not.
    pub bottoms_out_alone: usize,
    /// Lighter true masses where it is worse than the reference (beyond [`WORSE_TOL_REL`]).
    pub worse_than_reference: usize,
    /// Passed.
    pub ok: bool,
}

/// Relative tolerance on "no worse than the reference" (the cells are stored as f32).
pub const WORSE_TOL_REL: f64 = 0.001;

/// The true masses checked for a plan of `planned_kg`: the plan, then down by `step_kg` to
/// `planned_kg − span_kg`, clamped to `floor_kg` (the axis' lightest), without repeats.
pub fn truths(planned_kg: f64, span_kg: f64, step_kg: f64, floor_kg: f64) -> Vec<f64> {
    let mut out = vec![planned_kg];
    let mut push = |m: f64| {
        let m = m.max(floor_kg);
        if out.last().is_some_and(|&l| l > m) {
            out.push(m);
        }
    };
    let mut k = 1.0;
    while k * step_kg < span_kg {
        push(planned_kg - k * step_kg);
        k += 1.0;
    }
    push(planned_kg - span_kg);
    out
}

/// A grid point's lighter truths — its pulse and the reference restraint's outcome at each —
/// for checking a setting planned there and for the robust setting that holds over them.
pub struct LighterSet {
    set: UncertainSet,
    masses_kg: Vec<f64>,
    /// The earliest airbag fire time at each truth (its pulse's severity floor).
    earliest_airbag_s: Vec<f64>,
}

impl LighterSet {
    /// The truths of grid point `q` (planned mass = `q`'s) over `span_kg` by `step_kg`, down to
    /// `floor_kg`; `cfg` gives the airbag floor and the ride-down reserve.
    ///
    /// # Errors
    /// A pulse cannot be predicted or an occupant simulation fails.
    pub fn new(
        ego: &Ego,
        q: &diagram::Query,
        span_kg: f64,
        step_kg: f64,
        floor_kg: f64,
        reference: &RestraintSettings,
        cfg: &OptimiserConfig,
    ) -> Result<Self> {
        let v = f64::from(q.closing_speed_kph);
        let masses_kg = truths(f64::from(q.opponent_mass_kg), span_kg, step_kg, floor_kg);
        let points: Vec<(f64, f64)> = masses_kg.iter().map(|&m| (v, m)).collect();
        let set =
            UncertainSet::from_points(ego, &occupant_at(q), &points, reference, cfg.reserve_m)?;
        let earliest_airbag_s = set
            .points
            .iter()
            .map(|p| cfg.earliest_airbag_s(&p.pulse.ego()))
            .collect();
        Ok(Self {
            set,
            masses_kg,
            earliest_airbag_s,
        })
    }

    /// `set` as the ECU executes it at truth `k`: the airbag no earlier than that truth's
    /// pulse carries the floor.
    fn executed(&self, set: &RestraintSettings, k: usize) -> RestraintSettings {
        let mut s = *set;
        if s.airbag_force_n > 0.0 {
            let floor_s = self.earliest_airbag_s.get(k).copied().unwrap_or(0.0);
            s.airbag_time_s = s.airbag_time_s.max(floor_s);
        }
        s
    }

    fn outcome(&self, set: &RestraintSettings, k: usize) -> Result<OccupantOutcome> {
        let p = self
            .set
            .points
            .get(k)
            .ok_or_else(|| anyhow!("no truth {k}"))?;
        let hw = RestraintHardware::default();
        Ok(simulate_occupant(
            &p.pulse.ego(),
            &self.set.occupant,
            &self.executed(set, k),
            &hw,
        )?)
    }

    /// `set`, planned for the nominal (heaviest) truth, judged at every lighter one.
    ///
    /// # Errors
    /// An occupant simulation fails.
    pub fn judge(&self, p: &diagram::GridPoint, set: &RestraintSettings) -> Result<MarginRow> {
        let mut row = MarginRow {
            index: p.index,
            coords: p.coords,
            planned_kg: self.masses_kg.first().copied().unwrap_or(f64::NAN),
            worst_truth_kg: f64::NAN,
            worst_change_pct: f64::NEG_INFINITY,
            bottoms_out_alone: 0,
            worse_than_reference: 0,
            ok: true,
        };
        for (k, (point, &m)) in self
            .set
            .points
            .iter()
            .zip(&self.masses_kg)
            .enumerate()
            .skip(1)
        {
            let o = self.outcome(set, k)?;
            let og = objective_g(&o);
            let change = 100.0 * (og - point.reference_g) / point.reference_g;
            if change > row.worst_change_pct {
                row.worst_change_pct = change;
                row.worst_truth_kg = m;
            }
            if point.reference_bottoms_out {
                // Both may strike through: then no deeper than the reference.
                if o.max_excursion_m > point.reference_excursion_m * (1.0 + WORSE_TOL_REL) {
                    row.worse_than_reference += 1;
                }
            } else if o.bottomed_out {
                row.bottoms_out_alone += 1;
            } else if og > point.reference_g * (1.0 + WORSE_TOL_REL) {
                row.worse_than_reference += 1;
            }
        }
        row.ok = row.bottoms_out_alone == 0 && row.worse_than_reference == 0;
        Ok(row)
    }
}

/// Check every cell of `d` (module docs) over `span_kg` in steps of `step_kg`.
///
/// # Errors
/// The header lacks the optimiser settings, or a pulse / simulation fails.
pub fn check_cells(
    d: &Diagram,
    reference: &RestraintSettings,
    span_kg: f64,
    step_kg: f64,
) -> Result<Vec<MarginRow>> {
    let grid = Grid::from_table(d)?;
    let floor_kg = grid
        .axes
        .opponent_mass_kg
        .first()
        .map(|&m| f64::from(m))
        .ok_or_else(|| anyhow!("no mass axis"))?;
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
            LighterSet::new(
                &grid.ego,
                &p.query,
                span_kg,
                step_kg,
                floor_kg,
                reference,
                &grid.optimiser,
            )?
            .judge(&p, &settings_of(c))
        })
        .collect()
}

/// What [`check_cells`] found, for a report.
#[derive(Clone, Debug, Serialize)]
pub struct MarginSummary {
    /// Cells checked.
    pub cells: usize,
    /// Cells that hold.
    pub hold: usize,
    /// Cells that bottom out at a lighter truth where the reference does not (the safety part).
    pub bottom_out_alone: usize,
    /// Cells worse than the reference at a lighter truth, no bottoming-out alone.
    pub worse_only: usize,
    /// Of the failing cells: those the table marks bottoming-out at their own mass (no
    /// setting avoids it there; the stored one is the least overshoot).
    pub failing_infeasible_at_plan: usize,
    /// Median and worst a_max + a_mean change of the failing cells, %.
    pub failing_p50_change_pct: f64,
    /// The worst failing cell.
    pub worst: Option<MarginRow>,
}

impl MarginSummary {
    /// Summarise `rows` of table `d`.
    pub fn of(d: &Diagram, rows: &[MarginRow]) -> Self {
        let failing: Vec<&MarginRow> = rows.iter().filter(|r| !r.ok).collect();
        let mut changes: Vec<f64> = failing.iter().map(|r| r.worst_change_pct).collect();
        changes.sort_by(f64::total_cmp);
        let bottom_out_alone = failing.iter().filter(|r| r.bottoms_out_alone > 0).count();
        Self {
            cells: rows.len(),
            hold: rows.len() - failing.len(),
            bottom_out_alone,
            worse_only: failing.len() - bottom_out_alone,
            failing_infeasible_at_plan: failing
                .iter()
                .filter(|r| {
                    d.cells()
                        .get(r.index)
                        .is_some_and(diagram::Cell::is_bottoming_out)
                })
                .count(),
            failing_p50_change_pct: changes.get(changes.len() / 2).copied().unwrap_or(f64::NAN),
            worst: failing
                .iter()
                .max_by(|a, b| a.worst_change_pct.total_cmp(&b.worst_change_pct))
                .map(|r| (*r).clone()),
        }
    }

    /// Every cell holds.
    pub fn holds(&self) -> bool {
        self.hold == self.cells
    }
}
