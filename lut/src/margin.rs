//! The planning margin as a property of the table: every cell's setting, planned for
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
//! ([`diagram::EXTRA_LIGHTER_OPPONENT_KG`]); `lut verify` checks every cell and enforces a stated span.
//!
//! The airbag is judged as the ECU fires it: at the cell's planned time, or later where the
//! lighter truth's pulse carries the airbag's severity floor only later (plan = fire,
//! [`OptimiserConfig::earliest_airbag_s`]). Where the reference strikes through too, the cell
//! must not strike deeper. A static setting: the crash phase's re-planning is the ECU's, tested
//! closed loop by the offline misreport grids.

use crate::optimise::{OptimiserConfig, SearchSpace};
use crate::robust_cells::{objective_g, UncertainSet};
use crate::scenario::Ego;
use anyhow::{anyhow, Result};
use diagram::Diagram;
use physics::{
    simulate_occupant, OccupantInput, OccupantOutcome, RestraintHardware, RestraintSettings,
};
use serde::Serialize;

/// The span the shipped rule needs: the truth up to twice the misreport bound (1 200 kg)
/// lighter than the plan.
pub const DEFAULT_SPAN_KG: f64 = 2400.0;
/// Step between the checked true masses [kg].
pub const DEFAULT_STEP_KG: f64 = 200.0;

/// The reference restraint the margin is judged against: the shipped one
/// (`data/reference-restraint.toml`, built in).
///
/// # Errors
/// The built-in file does not parse (a build defect).
pub fn reference_settings() -> Result<RestraintSettings> {
    // Parsed once: a build asks for it in every cell.
    static REFERENCE: std::sync::OnceLock<Result<RestraintSettings, String>> =
        std::sync::OnceLock::new();
    REFERENCE
        .get_or_init(|| {
            physics::reference::ReferenceRestraint::builtin()
                .map(|r| r.settings())
                .map_err(|e| format!("the built-in reference restraint: {e}"))
        })
        .clone()
        .map_err(|e| anyhow!(e))
}

/// The span a table states in its header, if any.
///
/// # Errors
/// The key is there but not a finite, non-negative number.
pub fn stated_span_kg(d: &Diagram) -> Result<Option<f64>> {
    d.header()
        .lighter_opponent_span_kg()
        .map_err(|e| anyhow!(e))
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
    /// Lighter true masses where both strike through and the setting deeper (beyond
    /// [`WORSE_TOL_REL`]).
    pub strikes_deeper: usize,
    /// Lighter true masses where neither strikes through and the setting's a_max + a_mean is
    /// worse than the reference's (beyond [`WORSE_TOL_REL`]): the benefit, reported, not part
    /// of `ok`.
    pub worse_than_reference: usize,
    /// The safety part holds: no bottoming-out alone, no deeper strike-through.
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

/// The lighter opponents a check runs over: from the plan down to the plan − `lighter_opponent_kg` by
/// `step_kg`, never below `floor_kg` (the mass axis' lightest).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Span {
    /// How far below the plan [kg].
    pub lighter_opponent_kg: f64,
    /// Step between the checked masses [kg].
    pub step_kg: f64,
    /// The lightest checked mass [kg].
    pub floor_kg: f64,
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
    /// The truths of grid point `q` (planned mass = `q`'s) for `occupant` over `span`; `cfg`
    /// gives the airbag floor and the ride-down reserve.
    ///
    /// # Errors
    /// A pulse cannot be predicted or an occupant simulation fails.
    pub fn new(
        ego: &Ego,
        q: &diagram::Query,
        occupant: &OccupantInput,
        span: &Span,
        reference: &RestraintSettings,
        cfg: &OptimiserConfig,
    ) -> Result<Self> {
        let v = f64::from(q.closing_speed_kph);
        let masses_kg = truths(
            f64::from(q.opponent_mass_kg),
            span.lighter_opponent_kg,
            span.step_kg,
            span.floor_kg,
        );
        let points: Vec<(f64, f64)> = masses_kg.iter().map(|&m| (v, m)).collect();
        let mut set = UncertainSet::from_points(ego, occupant, &points, reference, cfg.reserve_m)?;
        let earliest_airbag_s: Vec<f64> = set
            .points
            .iter()
            .map(|p| cfg.earliest_airbag_s(&p.pulse))
            .collect();
        // The reference as the ECU executes it at each truth: its airbag no earlier than the
        // truth's pulse lets the ECU fire one, and none where it never does.
        for (p, &t) in set.points.iter_mut().zip(&earliest_airbag_s) {
            if !t.is_finite() || t > reference.airbag_time_s {
                p.reference_as_executed(occupant, reference, t, cfg.reserve_m)?;
            }
        }
        Ok(Self {
            set,
            masses_kg,
            earliest_airbag_s,
        })
    }

    /// `set` as the ECU executes it at truth `k`: the airbag no earlier than that truth's
    /// pulse lets the ECU fire it, and none where it never does.
    fn executed(&self, set: &RestraintSettings, k: usize) -> RestraintSettings {
        let mut s = *set;
        if s.airbag_force_n > 0.0 {
            let floor_s = self.earliest_airbag_s.get(k).copied().unwrap_or(0.0);
            if floor_s.is_finite() {
                s.airbag_time_s = s.airbag_time_s.max(floor_s);
            } else {
                s.airbag_force_n = 0.0;
            }
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
            strikes_deeper: 0,
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
                if o.bottomed_out
                    && o.max_excursion_m > point.reference_excursion_m * (1.0 + WORSE_TOL_REL)
                {
                    row.strikes_deeper += 1;
                }
            } else if o.bottomed_out {
                row.bottoms_out_alone += 1;
            } else if og > point.reference_g * (1.0 + WORSE_TOL_REL) {
                row.worse_than_reference += 1;
            }
        }
        row.ok = row.bottoms_out_alone == 0 && row.strikes_deeper == 0;
        Ok(row)
    }
}

impl LighterSet {
    /// The robust setting: the nominal truth's cost as the build counts it, plus penalties
    /// wherever a lighter truth is worse than the reference or bottoms out where it does not
    /// (`robust_cells`' objective, the airbag as executed at each truth); the airbag no earlier
    /// than the nominal pulse's floor, as in every cell. Returns the setting and the occupant
    /// simulations spent.
    ///
    /// # Errors
    /// The optimiser fails.
    pub fn robust_optimum(&self, cfg: &OptimiserConfig) -> Result<(RestraintSettings, u64)> {
        let nominal_floor_s = self.earliest_airbag_s.first().copied().unwrap_or(0.0);
        let space = SearchSpace::adaptive().with_earliest_airbag_s(nominal_floor_s);
        let (set, evaluations) = self
            .set
            .robust_optimum_in(&space, cfg, |set, k| self.executed(set, k))?;
        Ok((set, evaluations * 2 * self.set.points.len() as u64))
    }
}

/// What the check of a table (`verify::check_margin`) found, for a report.
#[derive(Clone, Debug, Serialize)]
pub struct MarginSummary {
    /// Cells checked.
    pub cells: usize,
    /// Cells whose safety part holds (`MarginRow::ok`).
    pub hold: usize,
    /// Cells that bottom out at a lighter truth where the reference does not.
    pub bottom_out_alone: usize,
    /// Cells that strike through deeper than the reference at a lighter truth where both do.
    pub strike_deeper: usize,
    /// Cells worse than the reference (a_max + a_mean) at a lighter truth: the benefit part.
    pub worse: usize,
    /// Median of those cells' worst change, %.
    pub worse_p50_change_pct: f64,
    /// The worst cell: the worst failing the safety part, else the worst of the benefit part.
    pub worst: Option<MarginRow>,
}

impl MarginSummary {
    /// Summarise `rows`.
    pub fn of(rows: &[MarginRow]) -> Self {
        let worse: Vec<&MarginRow> = rows.iter().filter(|r| r.worse_than_reference > 0).collect();
        let mut changes: Vec<f64> = worse.iter().map(|r| r.worst_change_pct).collect();
        changes.sort_by(f64::total_cmp);
        let by_change =
            |a: &&MarginRow, b: &&MarginRow| a.worst_change_pct.total_cmp(&b.worst_change_pct);
        let failing = rows.iter().filter(|r| !r.ok).max_by(by_change);
        Self {
            cells: rows.len(),
            hold: rows.iter().filter(|r| r.ok).count(),
            bottom_out_alone: rows.iter().filter(|r| r.bottoms_out_alone > 0).count(),
            strike_deeper: rows.iter().filter(|r| r.strikes_deeper > 0).count(),
            worse: worse.len(),
            worse_p50_change_pct: changes.get(changes.len() / 2).copied().unwrap_or(f64::NAN),
            worst: failing
                .or_else(|| worse.iter().copied().max_by(by_change))
                .cloned(),
        }
    }

    /// Every cell holds the safety part.
    pub fn holds(&self) -> bool {
        self.hold == self.cells
    }
}
