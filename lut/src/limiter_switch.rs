//! A two-level load limiter switched on what the pulse shows: can it win
//! back the benefit the +1 200 kg planning margin costs, and keep the guarantee?
//!
//! The margin exists because the opponent's mass does not show in the ego pulse before the
//! restraint is committed (`restraint::crash_match`). A single load-limiter level is committed
//! at confirmation, but a switchable limiter commits its level later: it starts at a high
//! level and a pyrotechnic switch drops it to a low one (**high → low only**: real hardware
//! releases one of two torsion bars, and a switch never commanded leaves the robust level —
//! the fail-safe direction). By the switch time the opponent's mass has begun to show.
//!
//! **The rule** (per cell, planned before the crash like the table's settings):
//!
//! * phase 1: the four settings of a robust plan, its limiter at the high level H;
//! * at `at_s` after contact the limiter switches to L ≤ H **only if** the speed the ego
//!   compartment has lost by `at_s − ecu_latency` is below a threshold — midway between the
//!   losses predicted for the estimate (v̂, m̂) and for the opponent `mass_margin_kg` heavier
//!   (the same prediction the ECU already solves at confirmation). A heavier opponent or a
//!   higher closing speed loses more speed sooner, keeps H and gets the robust plan; a
//!   lighter or slower one switches. The measurement may read `evidence_error` (a fraction)
//!   low — the direction that switches a heavy crash down.
//!
//! **The optimum** is the robust cell's (`robust_cells`), with H and L as two variables: the
//! nominal point's a_max + a_mean (switched) subject to, at every point of the set, no
//! bottoming-out where the reference does not and no worse than the reference — each point
//! judged with the switch it would really get from the rule, the airbag also up to the
//! fire-delay tolerance late.
//!
//! Not modelled: the switch's own delay and spread (it acts at `at_s` exactly), a belt that
//! rebounds on the drop (the pay-out is instant); and the single-fault question this raises
//! for the ECU — a compartment accelerometer reading low would switch a heavy crash down, so
//! the decision would need two sensors that agree (the ECU has a safing sensor).
//! Not in the paper's restraint model (one adaptive level): an extension, said so wherever it
//! is reported.

use crate::optimise::{cost_with_late_airbag, effective_settings, minimise, OptimiserConfig};
use crate::robust_cells::{Judged, Situation, UncertainSet};
use crate::scenario::{Ego, Opponent, Pulse};
use anyhow::Result;
use physics::{
    defaults, simulate_occupant, simulate_occupant_switched, CompartmentPulse, LimiterSwitch,
    OccupantInput, OccupantOutcome, RestraintHardware, RestraintSettings,
};
use serde::Serialize;

/// Speed the compartment has lost by `t_s` after contact [m/s] (positive in a crash).
pub fn speed_lost_by_mps(pulse: &CompartmentPulse<'_>, t_s: f64) -> f64 {
    let n = if t_s > 0.0 {
        ((t_s / pulse.step_s) as usize + 1).min(pulse.accel_mps2.len())
    } else {
        0
    };
    -CompartmentPulse {
        step_s: pulse.step_s,
        accel_mps2: &pulse.accel_mps2[..n],
    }
    .delta_v_mps()
}

/// When to switch and on what evidence.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct SwitchRule {
    /// The limiter switches at this time after contact [s].
    pub at_s: f64,
    /// The speed lost by then is measured up to this time [s] (`at_s` − the ECU's latency).
    pub decide_s: f64,
    /// Switch only if the speed lost by `decide_s` is below this [m/s].
    pub threshold_mps: f64,
    /// Predicted speed lost by `decide_s` for the estimate and for the opponent the margin
    /// heavier [m/s]: how far apart the two are when the decision is made.
    pub predicted_mps: (f64, f64),
    /// The measured speed loss reads this fraction low (an accelerometer's sensitivity error
    /// in the direction that switches a heavy crash down: the guarantee must survive it).
    pub evidence_error: f64,
}

impl SwitchRule {
    /// The rule for situation `s` (module docs).
    ///
    /// # Errors
    /// A pulse cannot be predicted.
    pub fn new(
        ego: &Ego,
        s: &Situation,
        mass_margin_kg: f64,
        at_s: f64,
        evidence_error: f64,
        cfg: &OptimiserConfig,
    ) -> Result<Self> {
        let decide_s = (at_s - cfg.ecu_latency_s).max(0.0);
        let lost = |m: f64| -> Result<f64> {
            let m = m.min(defaults::OPPONENT_MASS_KG.max);
            let p = Pulse::predict(ego, Opponent::Car { mass_kg: m }, s.closing_kph)?;
            Ok(speed_lost_by_mps(&p.ego(), decide_s))
        };
        let (nominal, heavy) = (lost(s.opponent_kg)?, lost(s.opponent_kg + mass_margin_kg)?);
        Ok(Self {
            at_s,
            decide_s,
            threshold_mps: 0.5 * (nominal + heavy),
            predicted_mps: (nominal, heavy),
            evidence_error,
        })
    }

    /// Whether the rule switches on this (true) pulse, measured `evidence_error` low.
    pub fn switches(&self, pulse: &CompartmentPulse<'_>) -> bool {
        speed_lost_by_mps(pulse, self.decide_s) * (1.0 - self.evidence_error) < self.threshold_mps
    }
}

/// A two-level plan: the four settings (limiter at the high level) and the switch to the low.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TwoLevelPlan {
    /// Phase-1 settings; `load_limiter_n` is the high level.
    pub settings: RestraintSettings,
    /// The low level and its time (applied only where the rule switches).
    pub switch: LimiterSwitch,
}

impl TwoLevelPlan {
    /// The occupant's outcome on `pulse` under `rule`: switched or not, as the rule decides.
    ///
    /// # Errors
    /// An occupant simulation fails.
    pub fn outcome(
        &self,
        pulse: &CompartmentPulse<'_>,
        occupant: &OccupantInput,
        rule: &SwitchRule,
        hw: &RestraintHardware,
    ) -> Result<OccupantOutcome> {
        Ok(if rule.switches(pulse) {
            simulate_occupant_switched(pulse, occupant, &self.settings, &self.switch, hw)?
        } else {
            simulate_occupant(pulse, occupant, &self.settings, hw)?
        })
    }
}

/// A two-level plan judged over the set, with the points where the rule switched.
#[derive(Clone, Debug, Serialize)]
pub struct JudgedTwoLevel {
    /// As every rule is judged.
    pub judged: Judged,
    /// High and low level [kN].
    pub levels_kn: (f64, f64),
    /// Per point of the set (nominal first): did the rule switch?
    pub switched: Vec<bool>,
}

impl UncertainSet {
    /// The robust two-level optimum under `rule` (module docs).
    ///
    /// # Errors
    /// The optimiser or an occupant simulation fails.
    pub fn two_level_optimum(
        &self,
        rule: &SwitchRule,
        cfg: &OptimiserConfig,
    ) -> Result<TwoLevelPlan> {
        let hw = RestraintHardware::default();
        let space = self.search_space(cfg);
        let n = space.free_count();
        let low_min_n = defaults::LOAD_LIMITER_BOUNDS_N.min;
        // The last coordinate places the low level between the bounds' minimum and H.
        let decode = |x: &[f64]| -> (TwoLevelPlan, f64) {
            let (set, outside_sq) = space.decode(&x[..n.min(x.len())]);
            let raw = x.get(n).copied().filter(|r| !r.is_nan()).unwrap_or(1.0);
            let c = raw.clamp(0.0, 1.0);
            let settings = effective_settings(&set, cfg);
            let level_n = low_min_n + c * (settings.load_limiter_n - low_min_n).max(0.0);
            let plan = TwoLevelPlan {
                settings,
                switch: LimiterSwitch {
                    at_s: rule.at_s,
                    level_n,
                },
            };
            (plan, outside_sq + (raw - c) * (raw - c))
        };
        let cost = |x: &[f64]| -> Result<f64> {
            let (plan, outside_sq) = decode(x);
            let total = self.robust_total(cfg.reserve_m, |_, p, reserve_m| {
                let pulse = p.pulse.ego();
                cost_with_late_airbag(
                    &plan.settings,
                    &OptimiserConfig { reserve_m, ..*cfg },
                    |settings| {
                        let plan = TwoLevelPlan {
                            settings: *settings,
                            ..plan
                        };
                        plan.outcome(&pulse, &self.occupant, rule, &hw)
                    },
                )
            })?;
            Ok(total + 1.0e3 * outside_sq)
        };
        let min = minimise(n + 1, &cost, cfg)?;
        Ok(decode(&min.u).0)
    }

    /// `plan` under `rule` on the truth at every point of the set.
    ///
    /// # Errors
    /// An occupant simulation fails.
    pub fn judge_two_level(
        &self,
        plan: &TwoLevelPlan,
        rule: &SwitchRule,
    ) -> Result<JudgedTwoLevel> {
        let hw = RestraintHardware::default();
        Ok(JudgedTwoLevel {
            judged: self.judge_by(|p| plan.outcome(&p.pulse.ego(), &self.occupant, rule, &hw))?,
            levels_kn: (
                plan.settings.load_limiter_n * 1e-3,
                plan.switch.level_n * 1e-3,
            ),
            switched: self
                .points
                .iter()
                .map(|p| rule.switches(&p.pulse.ego()))
                .collect(),
        })
    }
}
