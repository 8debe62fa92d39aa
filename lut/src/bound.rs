//! How close the table's optima come to the ideal constant-force bound, and what keeps them
//! from it (the demo's 48 + 48 km/h optimum peaks at 2.0 × a*).
//!
//! **a\*** is the occupant's ideal deceleration in the model (`OccupantOutcome::ideal_decel_mps2`):
//! the constant deceleration that stops the occupant, relative to the compartment's pulse, in
//! exactly the available ride-down — the lower bound of any restraint's peak. So a_max / a\* ≥ 1
//! for every setting; how far above 1 an optimum stays is the price of what the restraint
//! cannot do.
//!
//! **Levers.** A sample of cells is re-optimised (same optimiser, seed and constraints as the
//! build) with one limitation of the restraint model lifted at a time, and with all of them:
//!
//! | lever | what changes |
//! |---|---|
//! | no belt slack | `belt_slack_m` = 0: the belt couples the occupant from the first mm (the pretensioner removes 0 slack) |
//! | instant airbag | `airbag_inflation_s` = 1 ms instead of the module's fill time |
//! | no force ceilings | load limiter and airbag force bounds raised from 12 kN to 24 kN |
//! | stiff belt and bag | belt and airbag stiffness × 10: the force builds up over a tenth of the excursion |
//! | no margins | no ride-down reserve (10 mm), no fire-delay tolerance (3 ms), the airbag free to fire from contact (no crash-confirmation floor) |
//!
//! The lever that moves a_max / a\* most is what limits the optimum in this model; the
//! figures are in docs/results.md ("Towards the bound").

use crate::optimise::{OptimiserConfig, SearchSpace, Var};
use crate::table::{optimise_query, sample_cells, Grid};
use anyhow::{anyhow, Result};
use diagram::{Diagram, Query};
use physics::{defaults, mps2_to_g, RestraintHardware};
use rayon::prelude::*;
use serde::Serialize;

/// One restraint-model limitation, lifted (or none: `as built`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Lever {
    /// Short name.
    pub name: &'static str,
    /// Belt slack set to 0.
    pub no_belt_slack: bool,
    /// Airbag fill time set to 1 ms.
    pub instant_airbag: bool,
    /// Force bounds raised to 24 kN.
    pub no_force_ceilings: bool,
    /// Belt and airbag stiffness × 10.
    pub stiff_restraint: bool,
    /// No ride-down reserve, no fire-delay tolerance, no earliest airbag time.
    pub no_margins: bool,
}

/// The levers the study compares, `as built` first, all of them last.
pub const LEVERS: [Lever; 7] = [
    Lever::new("as built", [false; 5]),
    Lever::new("no belt slack", [true, false, false, false, false]),
    Lever::new("instant airbag", [false, true, false, false, false]),
    Lever::new("no force ceilings", [false, false, true, false, false]),
    Lever::new("stiff belt and bag", [false, false, false, true, false]),
    Lever::new("no margins", [false, false, false, false, true]),
    Lever::new("all of them", [true; 5]),
];

/// Stiffness factor of the `stiff belt and bag` lever.
pub const STIFFNESS_FACTOR: f64 = 10.0;

/// Raised force ceiling of the `no force ceilings` lever [N].
pub const RAISED_CEILING_N: f64 = 24.0e3;
/// Fill time of the `instant airbag` lever [s].
pub const INSTANT_FILL_S: f64 = 1.0e-3;

impl Lever {
    const fn new(name: &'static str, f: [bool; 5]) -> Self {
        Self {
            name,
            no_belt_slack: f[0],
            instant_airbag: f[1],
            no_force_ceilings: f[2],
            stiff_restraint: f[3],
            no_margins: f[4],
        }
    }

    /// The hardware with this lever's limitations lifted.
    pub fn hardware(&self) -> RestraintHardware {
        let mut hw = RestraintHardware::default();
        if self.no_belt_slack {
            hw.belt_slack_m = 0.0;
        }
        if self.instant_airbag {
            hw.airbag_inflation_s = INSTANT_FILL_S;
        }
        if self.stiff_restraint {
            hw.belt_stiffness_n_per_m *= STIFFNESS_FACTOR;
            hw.airbag_stiffness_n_per_m *= STIFFNESS_FACTOR;
        }
        hw
    }

    /// The cell's optimiser configuration with this lever's margins.
    pub fn config(&self, mut cfg: OptimiserConfig) -> OptimiserConfig {
        if self.no_margins {
            cfg.reserve_m = 0.0;
            cfg.fire_delay_tolerance_s = 0.0;
            cfg.airbag_floor_dv_mps = 0.0;
            cfg.accel_only_below_mps = f64::NEG_INFINITY;
        }
        cfg
    }

    /// The adaptive search space with this lever's ceilings.
    pub fn space(&self) -> SearchSpace {
        let mut s = SearchSpace::adaptive();
        if self.no_force_ceilings {
            s.load_limiter_n = Var::Free {
                min: defaults::LOAD_LIMITER_BOUNDS_N.min,
                max: RAISED_CEILING_N,
            };
            s.airbag_force_n = Var::Free {
                min: defaults::AIRBAG_FORCE_BOUNDS_N.min,
                max: RAISED_CEILING_N,
            };
        }
        s
    }
}

/// a_max / a* of one cell.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct CellRatio {
    /// Cell index.
    pub index: usize,
    /// The cell's axis values.
    #[serde(skip)]
    pub query: Query,
    /// a_max / a*.
    pub ratio: f64,
}

/// The table's a_max / a* over its cells.
#[derive(Clone, Debug, Serialize)]
pub struct TableRatios {
    /// Cells counted (free of bottoming-out, a* > 0).
    pub cells: usize,
    /// Cells left out (bottoming-out or no a*).
    pub left_out: usize,
    /// Median.
    pub p50: f64,
    /// 90th percentile.
    pub p90: f64,
    /// Smallest (how close the best cell comes).
    pub best: CellRatio,
    /// Largest.
    pub worst: CellRatio,
    /// Per closing speed of the grid: (km/h, p50, worst).
    pub by_closing_speed: Vec<(f64, f64, f64)>,
}

/// Nearest-rank percentile of sorted values.
fn pct(sorted: &[f64], p: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    let rank = ((p / 100.0) * sorted.len() as f64).ceil().max(1.0) as usize;
    sorted[rank.min(sorted.len()) - 1]
}

/// a_max / a* of every cell of `d` that does not bottom out.
///
/// # Errors
/// The table's grid cannot be rebuilt from its header, or it has no usable cell.
pub fn table_ratios(d: &Diagram) -> Result<TableRatios> {
    let grid = Grid::from_table(d)?;
    let mut all = Vec::new();
    let mut left_out = 0;
    for (i, c) in d.cells().iter().enumerate() {
        let p = grid
            .axes
            .point(i)
            .ok_or_else(|| anyhow!("cell {i} outside the grid"))?;
        if c.is_bottoming_out() || c.a_ideal_g <= 0.0 || !c.a_ideal_g.is_finite() {
            left_out += 1;
            continue;
        }
        all.push(CellRatio {
            index: i,
            query: p.query,
            ratio: f64::from(c.a_max_g) / f64::from(c.a_ideal_g),
        });
    }
    let mut sorted: Vec<f64> = all.iter().map(|c| c.ratio).collect();
    sorted.sort_by(f64::total_cmp);
    let by = |pick: fn(f64, f64) -> bool| {
        all.iter()
            .copied()
            .reduce(|a, b| if pick(b.ratio, a.ratio) { b } else { a })
    };
    let worst = by(|b, a| b > a).ok_or_else(|| anyhow!("the table has no usable cell"))?;
    let best = by(|b, a| b < a).ok_or_else(|| anyhow!("the table has no usable cell"))?;
    let mut speeds: Vec<f64> = all
        .iter()
        .map(|c| f64::from(c.query.closing_speed_kph))
        .collect();
    speeds.sort_by(f64::total_cmp);
    speeds.dedup();
    let by_closing_speed = speeds
        .iter()
        .map(|v| {
            let mut r: Vec<f64> = all
                .iter()
                .filter(|c| f64::from(c.query.closing_speed_kph) == *v)
                .map(|c| c.ratio)
                .collect();
            r.sort_by(f64::total_cmp);
            (*v, pct(&r, 50.0), r.last().copied().unwrap_or(f64::NAN))
        })
        .collect();
    Ok(TableRatios {
        cells: all.len(),
        left_out,
        p50: pct(&sorted, 50.0),
        p90: pct(&sorted, 90.0),
        best,
        worst,
        by_closing_speed,
    })
}

/// One lever over the sampled cells.
#[derive(Clone, Debug, Serialize)]
pub struct LeverRow {
    /// The lever.
    pub lever: Lever,
    /// Sampled cells whose optimum is free of bottoming-out.
    pub feasible: usize,
    /// a_max / a* of the feasible optima: median.
    pub p50: f64,
    /// … largest.
    pub worst: f64,
    /// Objective a_max + a_mean [g]: median over the feasible optima.
    pub objective_p50_g: f64,
}

/// `n` cells of `d`'s grid, picked with `seed` (SplitMix64, as `lut verify` does), each
/// re-optimised under every lever of [`LEVERS`].
///
/// # Errors
/// The grid cannot be rebuilt, or an optimisation fails.
pub fn levers(d: &Diagram, n: usize, seed: u64) -> Result<Vec<LeverRow>> {
    let grid = Grid::from_table(d)?;
    let picks = sample_cells(grid.axes.cell_count(), n, seed);
    LEVERS
        .iter()
        .map(|lever| {
            let outcomes: Vec<(f64, f64, bool)> = picks
                .par_iter()
                .map(|&i| optimise_with(&grid, i, lever))
                .collect::<Result<_>>()?;
            let feasible: Vec<&(f64, f64, bool)> = outcomes.iter().filter(|o| !o.2).collect();
            let mut ratios: Vec<f64> = feasible.iter().map(|o| o.0).collect();
            ratios.sort_by(f64::total_cmp);
            let mut objectives: Vec<f64> = feasible.iter().map(|o| o.1).collect();
            objectives.sort_by(f64::total_cmp);
            Ok(LeverRow {
                lever: *lever,
                feasible: feasible.len(),
                p50: pct(&ratios, 50.0),
                worst: ratios.last().copied().unwrap_or(f64::NAN),
                objective_p50_g: pct(&objectives, 50.0),
            })
        })
        .collect()
}

/// Cell `i` of `grid` re-optimised under `lever`: (a_max / a*, a_max + a_mean [g], bottomed
/// out).
///
/// # Errors
/// `i` is outside the grid, or the optimisation fails.
pub fn optimise_with(grid: &Grid, i: usize, lever: &Lever) -> Result<(f64, f64, bool)> {
    let p = grid
        .axes
        .point(i)
        .ok_or_else(|| anyhow!("cell {i} outside the grid"))?;
    let cfg = lever.config(grid.cell_config(i));
    let o = optimise_query(&grid.ego, &p.query, lever.space(), &lever.hardware(), &cfg)?;
    let out = o
        .outcomes
        .first()
        .ok_or_else(|| anyhow!("cell {i}: no outcome"))?;
    let ratio = out.max_decel_mps2 / out.ideal_decel_mps2;
    Ok((
        ratio,
        mps2_to_g(out.max_decel_mps2) + mps2_to_g(out.mean_decel_mps2),
        out.bottomed_out,
    ))
}
