//! Robust cells, measured before they are built: what a cell optimised for the
//! whole uncertainty set the ECU can be in would give on the library's nominal cases, against
//! the two settings the ECU can use today.
//!
//! The ECU looks the table up at its fused estimate. Since the crash phase it plans with the
//! opponent `mass_misreport_kg` (1 200 kg) heavier than reported, because the opponent's mass
//! does not show in the ego pulse before the restraint is committed — a blunt margin that costs
//! the nominal case 6–12 points of benefit. A **robust cell** is optimised instead for every
//! point of the set the truth may lie in: opponent mass m̂ ± Δm (clamped to the axis' 800 …
//! 3 000 kg), closing speed v̂ ± Δv, the airbag up to the fire-delay tolerance late.
//!
//! **Objective**: the nominal point's a_max + a_mean, subject to, at
//! every point of the set, (1) no bottoming-out where the reference restraint does not bottom
//! out (and the ride-down reserve kept where the reference keeps it), and (2) a_max + a_mean
//! no worse than the reference restraint's at that point (where both bottom out: no more
//! overshoot). Penalties keep the ordering: a bottoming-out the reference avoids costs
//! [`optimise::INFEASIBLE_OFFSET`] plus its overshoot, each g worse than the reference
//! [`WORSE_PENALTY_PER_G`]; the nominal point's own bottoming-out is penalised as in the build.
//! The airbag counts up to the fire-delay tolerance late (`robust_case_cost`).
//!
//! The set's points: the nominal point and one error at a time (m̂ ± Δm, v̂ ± Δv: the cross, as
//! the offline misreport tests vary them), or both at once too (the box's four corners) —
//! five or nine occupant simulations per setting (twice that with the late airbag).

use crate::optimise::{
    self, effective_settings, minimise, Case, OptimiserConfig, SearchSpace, INFEASIBLE_OFFSET,
};
use crate::scenario::{Ego, Opponent, Pulse};
use anyhow::{anyhow, Result};
use physics::{
    defaults, mps2_to_g, simulate_occupant, OccupantInput, OccupantOutcome, RestraintHardware,
    RestraintSettings,
};
use serde::Serialize;

/// The library's nominal belted car-to-car cases at contact — name, closing km/h, opponent kg —
/// that the margin studies (`lut study robust-cells`, `lut study limiter-switch`) compare on,
/// with [`LIBRARY_OCCUPANT`].
pub const LIBRARY_CASES: [(&str, f64, f64); 6] = [
    ("taurus-52-52-none", 104.0, 1785.0),
    ("taurus-48-48-abs", 96.0, 1785.0),
    ("taurus-31-31-abs-eba", 62.0, 1785.0),
    ("mass-sweep-1000kg", 96.0, 1000.0),
    ("mass-sweep-1300kg", 96.0, 1300.0),
    ("mass-sweep-2200kg", 96.0, 2200.0),
];

/// The library cases' occupant: 75 kg, 300 mm, belted.
pub const LIBRARY_OCCUPANT: OccupantInput = OccupantInput {
    mass_kg: 75.0,
    chest_to_wheel_m: 0.300,
    belted: true,
};

/// Penalty per g a setting is worse than the reference restraint at a point of the set.
pub const WORSE_PENALTY_PER_G: f64 = 1.0e3;

/// The half-widths of the uncertainty set.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Uncertainty {
    /// Opponent mass: ± this [kg].
    pub mass_kg: f64,
    /// Closing speed: ± this [km/h].
    pub speed_kph: f64,
    /// Both errors at once (the box's four corners too), not only one at a time (the cross).
    pub corners: bool,
}

impl Uncertainty {
    /// The bounds the ECU's guarantee is stated for: a mass misreported by ±1 200 kg, a closing
    /// speed by ±5 m/s (18 km/h).
    pub const MISREPORT: Self = Self {
        mass_kg: 1200.0,
        speed_kph: 18.0,
        corners: false,
    };
}

/// The nominal situation: closing speed, opponent mass, occupant.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Situation {
    /// Closing speed [km/h].
    pub closing_kph: f64,
    /// Opponent mass [kg].
    pub opponent_kg: f64,
    /// The occupant.
    #[serde(skip)]
    pub occupant: OccupantInput,
}

/// The set's points (nominal first): (closing km/h, opponent kg).
pub fn set_points(s: &Situation, u: &Uncertainty) -> Vec<(f64, f64)> {
    let m = |d: f64| {
        (s.opponent_kg + d).clamp(
            defaults::OPPONENT_MASS_KG.min,
            defaults::OPPONENT_MASS_KG.max,
        )
    };
    let v = |d: f64| (s.closing_kph + d).max(10.0);
    let mut pts = vec![(s.closing_kph, s.opponent_kg)];
    let cross = [(0.0, -1.0), (0.0, 1.0), (-1.0, 0.0), (1.0, 0.0)];
    let corners = [(-1.0, -1.0), (-1.0, 1.0), (1.0, -1.0), (1.0, 1.0)];
    let n = if u.corners { 8 } else { 4 };
    for (dv, dm) in cross.into_iter().chain(corners).take(n) {
        pts.push((v(dv * u.speed_kph), m(dm * u.mass_kg)));
    }
    pts.dedup();
    pts
}

/// One point of the set with its reference outcome.
pub(crate) struct Point {
    pub(crate) pulse: Pulse,
    pub(crate) reference_g: f64,
    pub(crate) reference_bottoms_out: bool,
    /// The reference's largest excursion here [m].
    pub(crate) reference_excursion_m: f64,
    /// The ride-down reserve the cell is held to here: the optimiser's where the reference
    /// keeps it, none where the reference only avoids bottoming out (or does not).
    pub(crate) reserve_m: f64,
    /// The reference's cost as the optimiser counts it (`case_cost` with `reserve_m`).
    reference_cost: f64,
}

impl Point {
    /// The reference restraint here as the ECU executes it, its airbag no earlier than
    /// `earliest_airbag_s` (`OptimiserConfig::earliest_airbag_s`: when the accelerometer-only
    /// path lets the ECU fire one for this pulse) and none where that is infinite (the ECU never
    /// fires an airbag here): the same belt. A table's setting is executed the same way, so the
    /// two are compared as the ECU runs them, with the table and without.
    pub(crate) fn reference_as_executed(
        &mut self,
        occupant: &OccupantInput,
        reference: &RestraintSettings,
        earliest_airbag_s: f64,
        reserve_m: f64,
    ) -> Result<()> {
        let set = if earliest_airbag_s.is_finite() {
            RestraintSettings {
                airbag_time_s: reference.airbag_time_s.max(earliest_airbag_s),
                ..*reference
            }
        } else {
            RestraintSettings {
                airbag_force_n: 0.0,
                ..*reference
            }
        };
        let r = simulate_occupant(
            &self.pulse.ego(),
            occupant,
            &set,
            &RestraintHardware::default(),
        )?;
        let keeps = optimise::case_cost(&r, reserve_m) < INFEASIBLE_OFFSET;
        self.reserve_m = if keeps { reserve_m } else { 0.0 };
        self.reference_g = objective_g(&r);
        self.reference_bottoms_out = r.bottomed_out;
        self.reference_excursion_m = r.max_excursion_m;
        self.reference_cost = optimise::case_cost(&r, self.reserve_m);
        Ok(())
    }
}

/// a_max + a_mean [g] of an outcome.
pub fn objective_g(o: &OccupantOutcome) -> f64 {
    mps2_to_g(o.max_decel_mps2) + mps2_to_g(o.mean_decel_mps2)
}

/// A situation's uncertainty set, its pulses predicted and the reference restraint simulated
/// at every point once, for the robust optimum and for judging any setting over it.
pub struct UncertainSet {
    pub(crate) occupant: OccupantInput,
    pub(crate) points: Vec<Point>,
}

impl UncertainSet {
    /// The set of `s` under `u` (module docs), with the reference restraint's outcome at
    /// every point; `reserve_m` is the optimiser's ride-down reserve.
    ///
    /// # Errors
    /// A pulse cannot be predicted or an occupant simulation fails.
    pub fn new(
        ego: &Ego,
        s: &Situation,
        u: &Uncertainty,
        reference: &RestraintSettings,
        reserve_m: f64,
    ) -> Result<Self> {
        Self::from_points(ego, &s.occupant, &set_points(s, u), reference, reserve_m)
    }

    /// The set of explicit (closing km/h, opponent kg) `points` (nominal first) for `occupant`,
    /// with the reference restraint's outcome at every point.
    ///
    /// # Errors
    /// A pulse cannot be predicted or an occupant simulation fails.
    pub fn from_points(
        ego: &Ego,
        occupant: &OccupantInput,
        points: &[(f64, f64)],
        reference: &RestraintSettings,
        reserve_m: f64,
    ) -> Result<Self> {
        let hw = RestraintHardware::default();
        let points = points
            .iter()
            .map(|&(v, m)| {
                let pulse = Pulse::predict(ego, Opponent::Car { mass_kg: m }, v)?;
                let r = simulate_occupant(&pulse.ego(), occupant, reference, &hw)?;
                let keeps = optimise::case_cost(&r, reserve_m) < INFEASIBLE_OFFSET;
                let reserve_m = if keeps { reserve_m } else { 0.0 };
                Ok(Point {
                    reference_g: objective_g(&r),
                    reference_bottoms_out: r.bottomed_out,
                    reference_excursion_m: r.max_excursion_m,
                    reserve_m,
                    reference_cost: optimise::case_cost(&r, reserve_m),
                    pulse,
                })
            })
            .collect::<Result<Vec<_>>>()?;
        Ok(Self {
            occupant: *occupant,
            points,
        })
    }

    /// The robust optimum (module docs); its setting.
    ///
    /// # Errors
    /// The optimiser fails.
    pub fn robust_optimum(&self, cfg: &OptimiserConfig) -> Result<RestraintSettings> {
        let (set, _) = self.robust_optimum_in(&self.search_space(cfg), cfg, |set, _| *set)?;
        Ok(set)
    }

    /// The robust objective's optimum within `space`, each point `k` simulated with
    /// `executed(setting, k)` (how the ECU would execute the setting there); the setting and the
    /// objective evaluations spent.
    ///
    /// # Errors
    /// The optimiser fails.
    pub(crate) fn robust_optimum_in(
        &self,
        space: &SearchSpace,
        cfg: &OptimiserConfig,
        executed: impl Fn(&RestraintSettings, usize) -> RestraintSettings,
    ) -> Result<(RestraintSettings, u64)> {
        let hw = RestraintHardware::default();
        let cost = |x: &[f64]| -> Result<f64> {
            let (set, outside_sq) = space.decode(x);
            let set = effective_settings(&set, cfg);
            let total = self.robust_total(cfg.reserve_m, |k, p, reserve_m| {
                optimise::robust_case_cost(
                    &Case {
                        pulse: p.pulse.ego(),
                        occupant: self.occupant,
                    },
                    &executed(&set, k),
                    &hw,
                    &OptimiserConfig { reserve_m, ..*cfg },
                )
            })?;
            Ok(total + 1.0e3 * outside_sq)
        };
        let min = minimise(space.free_count(), &cost, cfg)?;
        let (set, _) = space.decode(&min.u);
        Ok((effective_settings(&set, cfg), min.evaluations))
    }

    /// The adaptive search space with the airbag no earlier than the latest of the points'
    /// own earliest fire times: the airbag must wait for its floor wherever the truth lies
    /// (a point where the ECU never fires one does not hold the others' back).
    pub(crate) fn search_space(&self, cfg: &OptimiserConfig) -> SearchSpace {
        SearchSpace::adaptive().with_earliest_airbag_s(
            self.points
                .iter()
                .map(|p| cfg.earliest_airbag_s(&p.pulse))
                .filter(|t| t.is_finite())
                .fold(0.0, f64::max),
        )
    }

    /// The robust objective (module docs) from a setting's cost at each point, `cost(index,
    /// point, reserve_m)` counted as the optimiser does: the nominal point's cost (held to
    /// `nominal_reserve_m`, the optimiser's reserve) plus the penalties where another point is
    /// worse than the reference.
    ///
    /// # Errors
    /// `cost` fails, or the set is empty.
    pub(crate) fn robust_total(
        &self,
        nominal_reserve_m: f64,
        cost: impl Fn(usize, &Point, f64) -> Result<f64>,
    ) -> Result<f64> {
        let (nominal, others) = self
            .points
            .split_first()
            .ok_or_else(|| anyhow!("no point"))?;
        // Where the reference keeps the ride-down reserve, so must the cell; where it only
        // avoids bottoming out, so must the cell; where it bottoms out, the cell may too.
        let mut total = cost(0, nominal, nominal_reserve_m)?;
        for (k, p) in others.iter().enumerate() {
            let (cp, r) = (cost(k + 1, p, p.reserve_m)?, p.reference_cost);
            if cp > r {
                total += match (cp >= INFEASIBLE_OFFSET, r >= INFEASIBLE_OFFSET) {
                    // Bottoming out (or eating the reserve) where the reference does not.
                    (true, false) => cp,
                    // Both do: more overshoot (1 000 per mm) or more g than the reference.
                    (true, true) => cp - r,
                    (false, _) => WORSE_PENALTY_PER_G * (cp - r),
                };
            }
        }
        Ok(total)
    }

    /// `set` (planned for the situation by some rule) on the truth at every point of the set.
    ///
    /// # Errors
    /// An occupant simulation fails.
    pub fn judge(&self, set: &RestraintSettings) -> Result<Judged> {
        let hw = RestraintHardware::default();
        self.judge_by(|p| Ok(simulate_occupant(&p.pulse.ego(), &self.occupant, set, &hw)?))
    }

    /// A rule's outcome `outcome(point)` on the truth at every point of the set.
    ///
    /// # Errors
    /// `outcome` fails.
    pub(crate) fn judge_by(
        &self,
        outcome: impl Fn(&Point) -> Result<OccupantOutcome>,
    ) -> Result<Judged> {
        let mut j = Judged {
            nominal_change_pct: 0.0,
            worst_change_pct: f64::NEG_INFINITY,
            bottoms_out_alone: 0,
            worse_than_reference: 0,
        };
        for (k, p) in self.points.iter().enumerate() {
            let o = outcome(p)?;
            let change = 100.0 * (objective_g(&o) - p.reference_g) / p.reference_g;
            if k == 0 {
                j.nominal_change_pct = change;
            }
            j.worst_change_pct = j.worst_change_pct.max(change);
            if o.bottomed_out && !p.reference_bottoms_out {
                j.bottoms_out_alone += 1;
            }
            if change > 0.0 {
                j.worse_than_reference += 1;
            }
        }
        Ok(j)
    }
}

/// One setting judged over the set.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Judged {
    /// Nominal point: a_max + a_mean change against the reference, % (negative = better).
    pub nominal_change_pct: f64,
    /// Largest change against the reference over the set's points, %.
    pub worst_change_pct: f64,
    /// Points where it bottoms out and the reference does not.
    pub bottoms_out_alone: usize,
    /// Points where it is worse than the reference.
    pub worse_than_reference: usize,
}

/// The cell optimum at one (speed, mass): what the table stores there today.
///
/// # Errors
/// The pulse cannot be predicted or the optimiser fails.
pub fn point_optimum(
    ego: &Ego,
    occupant: &OccupantInput,
    closing_kph: f64,
    opponent_kg: f64,
    cfg: &OptimiserConfig,
) -> Result<RestraintSettings> {
    let pulse = Pulse::predict(
        ego,
        Opponent::Car {
            mass_kg: opponent_kg.min(defaults::OPPONENT_MASS_KG.max),
        },
        closing_kph,
    )?;
    Ok(optimise::optimise_situation(
        &pulse,
        *occupant,
        SearchSpace::adaptive(),
        &RestraintHardware::default(),
        cfg,
    )?
    .settings)
}
