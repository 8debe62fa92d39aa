//! The restraint optimiser: particle swarm (global) then Nelder–Mead (polish), both from argmin,
//! over the four restraint variables, for one or several load cases that share one setting.
//!
//! **Objective** (SPEC): occupant a_max + a_mean in g, summed over the cases.
//! **Constraint**: no bottoming-out, with a ride-down reserve: the excursion must stay
//! [`OptimiserConfig::reserve_m`] (*default* 10 mm) short of the available ride-down. Without
//! the reserve the optimum sits exactly on the constraint (it uses all the ride-down there is),
//! and rounding the setting to the file's precision, interpolating between cells or shifting a
//! trigger by one 0.1 ms step tips it into bottoming-out. Penalty that keeps the feasibility
//! ordering: a feasible case costs a_max + a_mean (capped at [`FEASIBLE_COST_CAP`]), an
//! infeasible one [`INFEASIBLE_OFFSET`] + 1000 · overshoot [mm] + a_max + a_mean, so every
//! setting that violates the constraint in any case is worse than every setting that violates
//! it in none, and among infeasible settings the one with the least overshoot wins. The
//! reported `bottoming_out` flag is the physical one (excursion beyond the available ride-down),
//! never hidden; an optimum that only eats into the reserve is reported with its excursion.
//!
//! **Plan = fire**: the ECU fires a crash-phase airbag only once its event has
//! carried the airbag's severity floor (no misuse event does), lowered by the crush-zone
//! satellites while the front end crushes, so each cell's airbag time is searched from
//! [`OptimiserConfig::earliest_airbag_s`] on — the instant the cell's own pulse carries the
//! floor as relieved by its own crush, plus the ECU's latency ([`crate::fire_floor`]) — and the
//! bus's FireTime is when the bag fires.
//!
//! **Fire-delay robustness**: what is left between plan and fire (a lighter opponent than the
//! planning mass carries the floor later, the batch is read a cycle later, the CAN transfer):
//! every setting that fires the airbag is also evaluated with the airbag
//! [`OptimiserConfig::fire_delay_tolerance_s`] (*default* 3 ms) later, and the worse of the two
//! costs counts: the optimum must stay free of bottoming-out when the bag comes that much late.
//! The reported outcomes are those at the planned times. The conventional
//! reference restraint (`lut reference`) keeps the paper's fixed definition (tolerance 0).
//!
//! **Search space**: the optimisers work on the unit cube (one coordinate per free variable,
//! mapped linearly onto its bounds), which gives Nelder–Mead a well-scaled simplex. Outside the
//! cube the setting is clamped and a quadratic steering penalty is added, so the simplex comes
//! back in.
//!
//! **Airbag no-fire**: a level below [`OptimiserConfig::no_fire_below_n`] is evaluated as "do
//! not fire" (0 N), because that is what the ECU does with it (diagram `AirbagThresholds`);
//! the optimum reports the effective setting and the reference airbag time in no-fire cells.
//!
//! **Determinism**: the swarm's RNG is a Xoshiro256++ seeded from [`OptimiserConfig::seed`];
//! everything else is deterministic floating point, so the same inputs give bit-identical optima.

use anyhow::{anyhow, Result};
use argmin::core::{CostFunction, Error as ArgminError, Executor, State};
use argmin::solver::{neldermead::NelderMead, particleswarm::ParticleSwarm};
use physics::{
    defaults, mps2_to_g, simulate_occupant, CompartmentPulse, OccupantInput, OccupantOutcome,
    RestraintHardware, RestraintSettings,
};
use rand_xoshiro::{rand_core::SeedableRng, Xoshiro256PlusPlus};
use std::cell::Cell as Counter;

/// Cost added once per infeasible (bottoming-out) case. Larger than any sum of feasible costs
/// (each capped at [`FEASIBLE_COST_CAP`], at most 9 cases), so feasibility ordering holds.
pub const INFEASIBLE_OFFSET: f64 = 1.0e6;
/// Cap of one feasible case's cost [g]; physically a_max + a_mean stays far below (the
/// restraint forces are bounded by 24 kN + friction: < 100 g even for a 30 kg occupant).
pub const FEASIBLE_COST_CAP: f64 = 1.0e5;
/// Penalty per mm of strike-through beyond the available ride-down (infeasible cases).
pub const STRIKE_THROUGH_PENALTY_PER_MM: f64 = 1.0e3;

/// One optimisation variable: free within bounds, or held fixed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Var {
    /// Held at this value (SI units).
    Fixed(f64),
    /// Free within [min, max] (SI units).
    Free {
        /// Lower bound.
        min: f64,
        /// Upper bound.
        max: f64,
    },
}

impl Var {
    fn free(b: defaults::Bounds) -> Self {
        Var::Free {
            min: b.min,
            max: b.max,
        }
    }
}

/// The four restraint variables (SI units: N, s).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SearchSpace {
    /// Belt load-limiter level [N].
    pub load_limiter_n: Var,
    /// Airbag + column force level [N] (0 = no fire).
    pub airbag_force_n: Var,
    /// Pretensioner trigger time [s] relative to contact.
    pub pretensioner_time_s: Var,
    /// Airbag trigger time [s] relative to contact.
    pub airbag_time_s: Var,
}

impl SearchSpace {
    /// The adaptive restraint: all four variables free within SPEC's bounds
    /// (physics::defaults: 1–12 kN, 0–12 kN, −100…+20 ms, +3…+40 ms).
    pub fn adaptive() -> Self {
        SearchSpace {
            load_limiter_n: Var::free(defaults::LOAD_LIMITER_BOUNDS_N),
            airbag_force_n: Var::free(defaults::AIRBAG_FORCE_BOUNDS_N),
            pretensioner_time_s: Var::free(defaults::PRETENSIONER_TIME_BOUNDS_S),
            airbag_time_s: Var::free(defaults::AIRBAG_TIME_BOUNDS_S),
        }
    }

    /// The conventional reference restraint: force levels free, both trigger times fixed at
    /// the reference fire time (10 ms after contact, SPEC/paper). The pretensioner of a
    /// conventional system fires on the same crash-confirmation signal as the airbag (no
    /// pre-crash sensing), hence the same 10 ms.
    pub fn reference() -> Self {
        SearchSpace {
            load_limiter_n: Var::free(defaults::LOAD_LIMITER_BOUNDS_N),
            airbag_force_n: Var::free(defaults::AIRBAG_FORCE_BOUNDS_N),
            pretensioner_time_s: Var::Fixed(defaults::REFERENCE_FIRE_TIME_S),
            airbag_time_s: Var::Fixed(defaults::REFERENCE_FIRE_TIME_S),
        }
    }

    /// This space with the airbag fired no earlier than `earliest_s` after contact (plan =
    /// fire: [`OptimiserConfig::earliest_airbag_s`]); a free airbag time keeps its upper bound,
    /// and is held there when `earliest_s` lies beyond it. An infinite `earliest_s` (the ECU
    /// never fires an airbag on this pulse) plans none: 0 N.
    pub fn with_earliest_airbag_s(self, earliest_s: f64) -> Self {
        if earliest_s == f64::INFINITY {
            if let Var::Free { max, .. } = self.airbag_time_s {
                return SearchSpace {
                    airbag_force_n: Var::Fixed(0.0),
                    airbag_time_s: Var::Fixed(max),
                    ..self
                };
            }
        }
        let airbag_time_s = match self.airbag_time_s {
            Var::Free { min, max } if earliest_s > min => {
                if earliest_s >= max {
                    Var::Fixed(max)
                } else {
                    Var::Free {
                        min: earliest_s,
                        max,
                    }
                }
            }
            v => v,
        };
        SearchSpace {
            airbag_time_s,
            ..self
        }
    }

    fn vars(&self) -> [Var; 4] {
        [
            self.load_limiter_n,
            self.airbag_force_n,
            self.pretensioner_time_s,
            self.airbag_time_s,
        ]
    }

    /// Number of free variables.
    pub fn free_count(&self) -> usize {
        self.vars()
            .iter()
            .filter(|v| matches!(v, Var::Free { .. }))
            .count()
    }

    /// Map unit-cube coordinates of the free variables to settings (clamped into the bounds);
    /// also returns the squared distance of `u` from the cube (for the steering penalty).
    pub fn decode(&self, u: &[f64]) -> (RestraintSettings, f64) {
        let mut out = [0.0f64; 4];
        let mut it = u.iter();
        let mut outside_sq = 0.0;
        for (o, var) in out.iter_mut().zip(self.vars()) {
            *o = match var {
                Var::Fixed(v) => v,
                Var::Free { min, max } => {
                    let raw = it.next().copied().unwrap_or(0.5);
                    let raw = if raw.is_nan() { 0.5 } else { raw };
                    let c = raw.clamp(0.0, 1.0);
                    outside_sq += (raw - c) * (raw - c);
                    min + c * (max - min)
                }
            };
        }
        let set = RestraintSettings {
            load_limiter_n: out[0],
            airbag_force_n: out[1],
            pretensioner_time_s: out[2],
            airbag_time_s: out[3],
        };
        (set, outside_sq)
    }
}

/// Optimiser effort and seed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OptimiserConfig {
    /// RNG seed of the particle swarm.
    pub seed: u64,
    /// Swarm size.
    pub particles: usize,
    /// Swarm iterations.
    pub pso_iterations: u64,
    /// Nelder–Mead iterations (polish).
    pub nm_iterations: u64,
    /// Nelder–Mead stops when the simplex's cost standard deviation falls below this [g].
    pub nm_sd_tolerance: f64,
    /// Airbag levels below this are evaluated as no-fire [N] (diagram's *default* 1 kN).
    pub no_fire_below_n: f64,
    /// Ride-down reserve [m]: the excursion must stay this far short of the available
    /// ride-down (see module docs).
    pub reserve_m: f64,
    /// A firing airbag is also evaluated this much later; the worse cost counts [s]
    /// (see module docs, "Fire-delay robustness"). 0 disables it.
    pub fire_delay_tolerance_s: f64,
    /// Plan = fire: the ECU's crash-phase airbag waits until the event has carried
    /// this velocity change since its onset [m/s] (`restraint`'s `fallback_min_dv_mps`, which
    /// the matched path's fires wait for too: no misuse event carries it), so a cell's airbag is
    /// planned no earlier than its own pulse reaches it plus [`Self::ecu_latency_s`]. 0 = off.
    pub airbag_floor_dv_mps: f64,
    /// What the ECU adds to the instant the floor is reached [s]: the accelerometer's
    /// anti-alias group delay (`accel_delay_ms`) and one 1 ms cycle until the decision runs.
    pub ecu_latency_s: f64,
    /// How the crush-zone satellites lower [`Self::airbag_floor_dv_mps`] while the front end
    /// crushes (`SatelliteRelief::OFF`: the floor alone).
    pub satellite_relief: crate::fire_floor::SatelliteRelief,
    /// Below this closing speed [m/s] the ECU's matched airbag also waits for its
    /// accelerometer-only decision (`restraint::CycleConfig::unguarded_closing_mps`: one object
    /// fault must not move a crash over the no-fire line; [`crate::fire_floor`]). −∞ = never.
    pub accel_only_below_mps: f64,
}

/// *Default* airbag floor of the plan [m/s]: the ECU's (`restraint::CycleConfig`).
pub fn default_airbag_floor_dv_mps() -> f64 {
    restraint::CycleConfig::default().fallback_min_dv_mps
}

/// *Default* ECU latency after the floor [s]: the accelerometer's group delay + one cycle.
pub fn default_ecu_latency_s() -> f64 {
    (restraint::CycleConfig::default().accel_delay_ms + 1.0) * 1e-3
}

impl OptimiserConfig {
    /// The earliest airbag time the ECU can execute on `pulse` [s after contact]: the first
    /// instant its velocity change reaches [`Self::airbag_floor_dv_mps`] as the satellites
    /// relieve it ([`Self::satellite_relief`]), plus [`Self::ecu_latency_s`]. Below
    /// [`Self::accel_only_below_mps`] the ECU waits for its accelerometer-only decision, and the
    /// plan takes that decision as a car without satellites reaches it (the later of the two:
    /// the plan stays executable when the evidence the relief needs is weaker than this cell's
    /// own crush). `f64::INFINITY` when the pulse never carries the floor or never decides, 0
    /// when the floor is off ([`crate::fire_floor`]).
    pub fn earliest_airbag_s(&self, pulse: &crate::scenario::Pulse) -> f64 {
        use crate::fire_floor::{accel_only_fire_s, earliest_airbag_s, SatelliteRelief};
        let ego = pulse.ego();
        let crush = pulse.ego_crush_m();
        let guarded = pulse.closing_mps < self.accel_only_below_mps;
        let relief = if guarded {
            SatelliteRelief::OFF
        } else {
            self.satellite_relief
        };
        let floor_s = earliest_airbag_s(
            &ego,
            crush,
            self.airbag_floor_dv_mps,
            &relief,
            self.ecu_latency_s,
        );
        if floor_s > 0.0 && guarded {
            let cycle = restraint::CycleConfig::default();
            let accel_only_s = accel_only_fire_s(&ego, crush, &relief, &cycle);
            floor_s.max(accel_only_s + self.ecu_latency_s)
        } else {
            floor_s
        }
    }
}

/// *Default* fire-delay tolerance [s]: how late the ECU can execute the table's plans now that
/// each plan waits for its cell's pulse to carry the airbag's floor (plan = fire,
/// [`OptimiserConfig::airbag_floor_dv_mps`]): a lighter opponent than the planning mass carries
/// it later, the batch is read up to a cycle later — 1.7 ms worst against the shipped table —
/// plus the CAN transfer, rounded up (`lut/tests/optimiser.rs` recomputes it with the ECU core's
/// matcher and floor against the shipped table's plans).
pub const DEFAULT_FIRE_DELAY_TOLERANCE_S: f64 = 0.003;

/// *Default* ride-down reserve [m].
pub const DEFAULT_RESERVE_M: f64 = 0.010;

impl Default for OptimiserConfig {
    /// *Defaults* chosen by measurement (lut/README.md "optimiser effort"): 24 particles × 30
    /// iterations + ≤ 150 Nelder–Mead iterations ≈ 1 000 occupant simulations per optimum.
    fn default() -> Self {
        OptimiserConfig {
            seed: 1,
            particles: 24,
            pso_iterations: 30,
            nm_iterations: 150,
            nm_sd_tolerance: 1.0e-4,
            no_fire_below_n: f64::from(diagram::AirbagThresholds::DEFAULT.no_fire_below_kn) * 1.0e3,
            reserve_m: DEFAULT_RESERVE_M,
            fire_delay_tolerance_s: DEFAULT_FIRE_DELAY_TOLERANCE_S,
            airbag_floor_dv_mps: default_airbag_floor_dv_mps(),
            ecu_latency_s: default_ecu_latency_s(),
            satellite_relief: crate::fire_floor::SatelliteRelief::ecu_default(),
            accel_only_below_mps: restraint::CycleConfig::default().unguarded_closing_mps(),
        }
    }
}

/// One load case: a compartment pulse and the occupant in it.
#[derive(Clone, Copy, Debug)]
pub struct Case<'a> {
    /// Ego compartment pulse (predicted once, reused for every evaluation).
    pub pulse: CompartmentPulse<'a>,
    /// The occupant.
    pub occupant: OccupantInput,
}

/// Cost of one case's outcome with ride-down reserve `reserve_m` (see module docs).
pub fn case_cost(o: &OccupantOutcome, reserve_m: f64) -> f64 {
    let sum_g = mps2_to_g(o.max_decel_mps2) + mps2_to_g(o.mean_decel_mps2);
    let limit_m = o.available_ride_down_m - reserve_m;
    if o.bottomed_out || o.max_excursion_m > limit_m {
        let over_mm = ((o.max_excursion_m - limit_m) * 1.0e3).max(0.0);
        INFEASIBLE_OFFSET + STRIKE_THROUGH_PENALTY_PER_MM * over_mm + sum_g.min(FEASIBLE_COST_CAP)
    } else {
        sum_g.min(FEASIBLE_COST_CAP)
    }
}

/// The setting the hardware actually gets: airbag levels below the no-fire threshold become 0
/// (and the airbag time of a no-fire setting the reference time, as stored in the diagram).
pub fn effective_settings(set: &RestraintSettings, cfg: &OptimiserConfig) -> RestraintSettings {
    let mut s = *set;
    // NaN compares false and is treated as no-fire.
    let fires = s.airbag_force_n >= cfg.no_fire_below_n;
    if !fires {
        s.airbag_force_n = 0.0;
        s.airbag_time_s = defaults::REFERENCE_FIRE_TIME_S;
    }
    s
}

/// Cost of one case for the optimiser: [`case_cost`] at the planned times, and — when the
/// airbag fires and a tolerance is set — the worse of that and the cost with the airbag
/// `fire_delay_tolerance_s` late (module docs, "Fire-delay robustness").
pub fn robust_case_cost(
    c: &Case<'_>,
    set: &RestraintSettings,
    hw: &RestraintHardware,
    cfg: &OptimiserConfig,
) -> Result<f64> {
    cost_with_late_airbag(set, cfg, |s| {
        Ok(simulate_occupant(&c.pulse, &c.occupant, s, hw)?)
    })
}

/// The fire-delay rule of [`robust_case_cost`] for any way of simulating a setting
/// (`outcome`): the worse of [`case_cost`] on time and with the airbag
/// `fire_delay_tolerance_s` late, when it fires and a tolerance is set.
///
/// # Errors
/// `outcome` fails.
pub fn cost_with_late_airbag(
    set: &RestraintSettings,
    cfg: &OptimiserConfig,
    outcome: impl Fn(&RestraintSettings) -> Result<OccupantOutcome>,
) -> Result<f64> {
    let on_time = case_cost(&outcome(set)?, cfg.reserve_m);
    if !(set.airbag_force_n > 0.0 && cfg.fire_delay_tolerance_s > 0.0) {
        return Ok(on_time);
    }
    let late = RestraintSettings {
        airbag_time_s: set.airbag_time_s + cfg.fire_delay_tolerance_s,
        ..*set
    };
    Ok(on_time.max(case_cost(&outcome(&late)?, cfg.reserve_m)))
}

/// Evaluate one setting on all cases: total cost (with ride-down reserve `reserve_m`) and
/// per-case outcomes.
pub fn evaluate(
    cases: &[Case<'_>],
    set: &RestraintSettings,
    hw: &RestraintHardware,
    reserve_m: f64,
) -> Result<(f64, Vec<OccupantOutcome>)> {
    let mut total = 0.0;
    let mut outcomes = Vec::with_capacity(cases.len());
    for c in cases {
        let o = simulate_occupant(&c.pulse, &c.occupant, set, hw)?;
        total += case_cost(&o, reserve_m);
        outcomes.push(o);
    }
    Ok((total, outcomes))
}

/// Result of one optimisation.
#[derive(Clone, Debug, PartialEq)]
pub struct Optimum {
    /// The optimal (effective) setting.
    pub settings: RestraintSettings,
    /// Its total cost (see module docs).
    pub cost: f64,
    /// Per-case occupant outcomes at the optimum (includes the ideal bound a*).
    pub outcomes: Vec<OccupantOutcome>,
    /// Occupant simulations spent (objective evaluations × cases).
    pub occupant_simulations: u64,
}

impl Optimum {
    /// True if any case still bottoms out at the optimum (no feasible setting was found).
    pub fn bottoming_out(&self) -> bool {
        self.outcomes.iter().any(|o| o.bottomed_out)
    }
}

/// argmin problem: a cost closure on the unit cube with an evaluation counter.
struct UnitCubeProblem<'a> {
    cost: &'a dyn Fn(&[f64]) -> Result<f64>,
    evaluations: &'a Counter<u64>,
}

impl CostFunction for UnitCubeProblem<'_> {
    type Param = Vec<f64>;
    type Output = f64;
    fn cost(&self, u: &Self::Param) -> Result<f64, ArgminError> {
        self.evaluations.set(self.evaluations.get() + 1);
        (self.cost)(u).map_err(|e| ArgminError::msg(e.to_string()))
    }
}

/// Result of [`minimise`].
#[derive(Clone, Debug, PartialEq)]
pub struct Minimum {
    /// Best point (may lie slightly outside the cube if the cost allows it; callers clamp).
    pub u: Vec<f64>,
    /// Its cost.
    pub cost: f64,
    /// Cost evaluations spent.
    pub evaluations: u64,
}

/// Minimise `cost` over the unit cube [0, 1]^n: particle swarm (seeded, global), then
/// Nelder–Mead from a 0.05-wide simplex at the swarm's best (stepping inwards at the faces).
/// The better of both results is returned. `cost` must be finite; it is also called slightly
/// outside the cube by Nelder–Mead, where it should clamp and penalise.
pub fn minimise(
    n: usize,
    cost: &dyn Fn(&[f64]) -> Result<f64>,
    cfg: &OptimiserConfig,
) -> Result<Minimum> {
    let evaluations = Counter::new(0);
    if n == 0 {
        let c = cost(&[])?;
        return Ok(Minimum {
            u: Vec::new(),
            cost: c,
            evaluations: 1,
        });
    }
    let problem = || UnitCubeProblem {
        cost,
        evaluations: &evaluations,
    };
    let pso = ParticleSwarm::new((vec![0.0; n], vec![1.0; n]), cfg.particles.max(2))
        .with_rng_generator(Xoshiro256PlusPlus::seed_from_u64(cfg.seed));
    let res = Executor::new(problem(), pso)
        .configure(|s| s.max_iters(cfg.pso_iterations))
        .timer(false)
        .run()
        .map_err(|e| anyhow!("particle swarm: {e}"))?;
    let state = res.state();
    let mut best_u = state
        .get_best_param()
        .map(|p| p.position.clone())
        .ok_or_else(|| anyhow!("particle swarm returned no particle"))?;
    let mut best_cost = state.get_best_cost();
    if cfg.nm_iterations > 0 {
        let step = 0.05;
        let mut simplex = vec![best_u.clone()];
        for i in 0..n {
            let mut p = best_u.clone();
            p[i] = if p[i] + step <= 1.0 {
                p[i] + step
            } else {
                p[i] - step
            };
            simplex.push(p);
        }
        let nm = NelderMead::new(simplex)
            .with_sd_tolerance(cfg.nm_sd_tolerance)
            .map_err(|e| anyhow!("Nelder–Mead: {e}"))?;
        let res = Executor::new(problem(), nm)
            .configure(|s| s.max_iters(cfg.nm_iterations))
            .timer(false)
            .run()
            .map_err(|e| anyhow!("Nelder–Mead: {e}"))?;
        let state = res.state();
        if let Some(p) = state.get_best_param() {
            if state.get_best_cost() < best_cost {
                best_cost = state.get_best_cost();
                best_u = p.to_vec();
            }
        }
    }
    Ok(Minimum {
        u: best_u,
        cost: best_cost,
        evaluations: evaluations.get(),
    })
}

/// Find the setting that minimises the summed cost of `cases` within `space`.
pub fn optimise(
    cases: &[Case<'_>],
    space: &SearchSpace,
    hw: &RestraintHardware,
    cfg: &OptimiserConfig,
) -> Result<Optimum> {
    if cases.is_empty() {
        return Err(anyhow!("optimise: no load case"));
    }
    let n = space.free_count();
    let cost = |u: &[f64]| -> Result<f64> {
        let (set, outside_sq) = space.decode(u);
        let set = effective_settings(&set, cfg);
        let mut total = 0.0;
        for c in cases {
            total += robust_case_cost(c, &set, hw, cfg)?;
        }
        Ok(total + 1.0e3 * outside_sq)
    };
    let min = minimise(n, &cost, cfg)?;
    let best_u = min.u;
    let (set, _) = space.decode(&best_u);
    let settings = effective_settings(&set, cfg);
    let (cost, outcomes) = evaluate(cases, &settings, hw, cfg.reserve_m)?;
    let evaluations = min.evaluations + 1;
    Ok(Optimum {
        settings,
        cost,
        outcomes,
        occupant_simulations: evaluations * cases.len() as u64,
    })
}

/// The optimum of one situation within `space` on `hw`, the airbag no earlier than the pulse
/// carries its floor (`OptimiserConfig::earliest_airbag_s`).
///
/// # Errors
/// The optimiser fails.
pub fn optimise_situation(
    pulse: &crate::scenario::Pulse,
    occupant: OccupantInput,
    space: SearchSpace,
    hw: &RestraintHardware,
    cfg: &OptimiserConfig,
) -> Result<Optimum> {
    let case = Case {
        pulse: pulse.ego(),
        occupant,
    };
    let space = space.with_earliest_airbag_s(cfg.earliest_airbag_s(pulse));
    optimise(&[case], &space, hw, cfg)
}
