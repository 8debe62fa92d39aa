//! One-body occupant model in the compartment frame.
//!
//! ```text
//!   m x'' = −m a_c(t) − F_belt − F_airbag − F_bottom − F_seatback − F_seat
//! ```
//! x: forward excursion of the chest relative to the compartment (0 at contact), a_c: compartment
//! acceleration (negative while the car is decelerated, so −m a_c throws the occupant forward).
//! Restraint forces are positive when they push the occupant rearward; the occupant's absolute
//! deceleration is (ΣF)/m.
//!
//! * Belt (shoulder + lap lumped): slack s(t) that the pretensioner removes linearly within
//!   [`RestraintHardware::pretensioner_duration_s`] of its trigger (pre-crash trigger allowed);
//!   force k_b (x − s(t) − p) for positive stretch, capped at the load-limiter level; pay-out p
//!   at the cap is permanent (unloading starts from the paid-out length).
//! * Airbag + column: fires at its trigger time, bag depth grows linearly to
//!   min(depth, D) within the inflation time; force k_a · penetration, capped at the force
//!   level; level 0 = no fire.
//! * Bottoming-out: excursion beyond the available ride-down D − module thickness meets a very
//!   stiff contact (wheel / dash) and sets the flag.
//! * Seat friction μ m g, regularised over a small relative speed.
//!
//! Time 0 is first contact (pulse sample 0). Integration: semi-implicit Euler at the pulse step;
//! after the pulse ends the compartment is taken as unaccelerated. The simulation stops once the
//! compartment acceleration is over (last non-zero sample) and the occupant moves rearward, i.e.
//! after its maximum forward excursion.
//!
//! Mean occupant deceleration definition: the occupant's velocity change from restraint onset
//! (first instant with belt or airbag force) until the instant of maximum forward excursion,
//! divided by that time span (= time-average of the deceleration over the restraint phase).

use crate::{collision::CompartmentPulse, defaults, PhysicsError};

/// Occupant description (from occupant sensing).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OccupantInput {
    /// Occupant mass [kg].
    pub mass_kg: f64,
    /// Chest to steering wheel / airbag module distance D [m] (seat position).
    pub chest_to_wheel_m: f64,
    /// Belt buckled; an unbelted occupant is held by the airbag only.
    pub belted: bool,
}

impl Default for OccupantInput {
    fn default() -> Self {
        OccupantInput {
            mass_kg: defaults::OCCUPANT_MASS_REFERENCE_KG,
            chest_to_wheel_m: defaults::CHEST_TO_WHEEL_M,
            belted: true,
        }
    }
}

/// The four adaptive restraint variables (what the optimiser chooses).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RestraintSettings {
    /// Belt load-limiter level, lumped [N].
    pub load_limiter_n: f64,
    /// Airbag + column force level [N]; 0 = airbag not fired.
    pub airbag_force_n: f64,
    /// Pretensioner trigger time relative to first contact [s] (negative = pre-crash).
    pub pretensioner_time_s: f64,
    /// Airbag trigger time relative to first contact [s].
    pub airbag_time_s: f64,
}

/// A two-level load limiter's one switch: from [`RestraintSettings::load_limiter_n`] to
/// `level_n` at `at_s` after first contact.
///
/// Why: the opponent's mass does not show in the ego pulse before the restraint is committed
/// (≈ 30 ms at 96 km/h), so a single level must be planned for the heaviest opponent the
/// sensing could be wrong about. Switchable load limiters exist as hardware (a pyrotechnic
/// switch that releases one of two torsion bars: **high → low** only, so a switch that is
/// never commanded leaves the robust level — the fail-safe direction). Not in the paper's
/// restraint model, which has one adaptive level: this is an extension, studied in
/// `lut study limiter-switch`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LimiterSwitch {
    /// Switch time relative to first contact [s].
    pub at_s: f64,
    /// Load-limiter level from then on, lumped [N].
    pub level_n: f64,
}

/// Restraint hardware constants (defaults in [`crate::defaults`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RestraintHardware {
    /// Belt slack [m].
    pub belt_slack_m: f64,
    /// Belt stiffness [N/m].
    pub belt_stiffness_n_per_m: f64,
    /// Time to remove all slack after the pretensioner trigger [s].
    pub pretensioner_duration_s: f64,
    /// Airbag + column stiffness [N/m].
    pub airbag_stiffness_n_per_m: f64,
    /// Maximum bag depth from the wheel [m] (bounded by D at run time).
    pub airbag_depth_m: f64,
    /// Trigger to full inflation [s].
    pub airbag_inflation_s: f64,
    /// Compressed module thickness [m].
    pub module_thickness_m: f64,
    /// Seat friction coefficient.
    pub seat_friction_coeff: f64,
    /// Relative speed of full friction [m/s].
    pub seat_friction_regularisation_mps: f64,
    /// Contact stiffness after bottoming out [N/m].
    pub bottoming_stiffness_n_per_m: f64,
    /// Seat-back stiffness for rearward motion [N/m].
    pub seatback_stiffness_n_per_m: f64,
    /// Longest simulated time [s].
    pub max_sim_s: f64,
}

impl Default for RestraintHardware {
    fn default() -> Self {
        RestraintHardware {
            belt_slack_m: defaults::BELT_SLACK_M,
            belt_stiffness_n_per_m: defaults::BELT_STIFFNESS_N_PER_M,
            pretensioner_duration_s: defaults::PRETENSIONER_DURATION_S,
            airbag_stiffness_n_per_m: defaults::AIRBAG_STIFFNESS_N_PER_M,
            airbag_depth_m: defaults::AIRBAG_DEPTH_M,
            airbag_inflation_s: defaults::AIRBAG_INFLATION_S,
            module_thickness_m: defaults::MODULE_THICKNESS_M,
            seat_friction_coeff: defaults::SEAT_FRICTION_COEFF,
            seat_friction_regularisation_mps: defaults::SEAT_FRICTION_REGULARISATION_MPS,
            bottoming_stiffness_n_per_m: defaults::BOTTOMING_STIFFNESS_N_PER_M,
            seatback_stiffness_n_per_m: defaults::SEATBACK_STIFFNESS_N_PER_M,
            max_sim_s: defaults::OCCUPANT_MAX_SIM_S,
        }
    }
}

/// Result of one occupant simulation.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct OccupantOutcome {
    /// Peak occupant deceleration [m/s²].
    pub max_decel_mps2: f64,
    /// Mean occupant deceleration over the restraint phase [m/s²] (definition in module docs).
    pub mean_decel_mps2: f64,
    /// Maximum forward excursion relative to the compartment [m].
    pub max_excursion_m: f64,
    /// Available ride-down D − module thickness [m].
    pub available_ride_down_m: f64,
    /// The occupant struck through to the wheel/dash (excursion > available ride-down).
    pub bottomed_out: bool,
    /// Peak belt force [N].
    pub max_belt_force_n: f64,
    /// Peak airbag force [N].
    pub max_airbag_force_n: f64,
    /// Permanent belt pay-out at the end [m].
    pub belt_payout_m: f64,
    /// Instant of maximum excursion [s after contact].
    pub max_excursion_time_s: f64,
    /// Ideal constant-force lower bound a* for this pulse and seat position [m/s²].
    pub ideal_decel_mps2: f64,
}

/// Ideal constant-force restraint bound a* = Δv² / (2 (D_veh + s_avail)) [m/s²]: the lowest
/// constant deceleration that stops the occupant relative to the compartment's final velocity
/// within the compartment's own ride-down D_veh plus the available excursion s_avail.
pub fn ideal_constant_force_decel_mps2(
    pulse: &CompartmentPulse<'_>,
    available_ride_down_m: f64,
) -> f64 {
    ideal_bound(
        pulse.delta_v_mps(),
        pulse.ride_down_displacement_m() + available_ride_down_m,
    )
}

fn ideal_bound(dv: f64, d: f64) -> f64 {
    if d > 0.0 && dv.is_finite() {
        dv * dv / (2.0 * d)
    } else {
        0.0
    }
}

fn validate(
    pulse: &CompartmentPulse<'_>,
    occ: &OccupantInput,
    set: &RestraintSettings,
    hw: &RestraintHardware,
) -> Result<(), PhysicsError> {
    if !defaults::STEP_BOUNDS_S.contains(pulse.step_s) {
        return Err(PhysicsError::InvalidSignal(
            "pulse step must be within 1 µs..=5 ms",
        ));
    }
    if !(occ.mass_kg.is_finite() && occ.mass_kg >= 1.0 && occ.mass_kg <= 500.0) {
        return Err(PhysicsError::InvalidInput(
            "occupant mass must be within 1..=500 kg",
        ));
    }
    if !(occ.chest_to_wheel_m.is_finite()
        && occ.chest_to_wheel_m > hw.module_thickness_m
        && occ.chest_to_wheel_m <= 2.0)
    {
        return Err(PhysicsError::InvalidInput(
            "chest-to-wheel distance must exceed the module",
        ));
    }
    let ok = |v: f64| v.is_finite() && v >= 0.0;
    if !(ok(set.load_limiter_n) && ok(set.airbag_force_n)) {
        return Err(PhysicsError::InvalidInput(
            "restraint force levels must be finite and ≥ 0",
        ));
    }
    if !(set.pretensioner_time_s.is_finite() && set.airbag_time_s.is_finite()) {
        return Err(PhysicsError::InvalidInput(
            "restraint trigger times must be finite",
        ));
    }
    let hw_ok = ok(hw.belt_slack_m)
        && ok(hw.belt_stiffness_n_per_m)
        && ok(hw.pretensioner_duration_s)
        && ok(hw.airbag_stiffness_n_per_m)
        && ok(hw.airbag_depth_m)
        && ok(hw.airbag_inflation_s)
        && ok(hw.module_thickness_m)
        && ok(hw.seat_friction_coeff)
        && hw.seat_friction_regularisation_mps > 0.0
        && ok(hw.bottoming_stiffness_n_per_m)
        && ok(hw.seatback_stiffness_n_per_m)
        && ok(hw.max_sim_s)
        && hw.max_sim_s <= 10.0;
    if !hw_ok {
        return Err(PhysicsError::InvalidInput(
            "restraint hardware constants out of range",
        ));
    }
    Ok(())
}

/// Simulate the occupant's response to a compartment pulse for given restraint settings.
/// Allocation-free, never panics; invalid input → `Err`.
pub fn simulate_occupant(
    pulse: &CompartmentPulse<'_>,
    occ: &OccupantInput,
    set: &RestraintSettings,
    hw: &RestraintHardware,
) -> Result<OccupantOutcome, PhysicsError> {
    simulate_occupant_observed(pulse, occ, set, hw, |_, _, _| {})
}

/// [`simulate_occupant`] that also hands every step's `(t_s, excursion_m, decel_mps2)` to
/// `observe` (time histories for plots, e.g. the bench's outcome report); the no-op observer
/// of [`simulate_occupant`] compiles away.
pub fn simulate_occupant_observed(
    pulse: &CompartmentPulse<'_>,
    occ: &OccupantInput,
    set: &RestraintSettings,
    hw: &RestraintHardware,
    observe: impl FnMut(f64, f64, f64),
) -> Result<OccupantOutcome, PhysicsError> {
    simulate(pulse, occ, set, None, hw, observe)
}

/// [`simulate_occupant`] with a two-level load limiter: the cap is
/// [`RestraintSettings::load_limiter_n`] until `switch.at_s`, then `switch.level_n`. A belt
/// above the new level pays out at once down to it (pay-out stays permanent).
///
/// # Errors
/// Invalid input, or a switch level / time that is not finite and non-negative.
pub fn simulate_occupant_switched(
    pulse: &CompartmentPulse<'_>,
    occ: &OccupantInput,
    set: &RestraintSettings,
    switch: &LimiterSwitch,
    hw: &RestraintHardware,
) -> Result<OccupantOutcome, PhysicsError> {
    if !(switch.at_s.is_finite() && switch.level_n.is_finite() && switch.level_n >= 0.0) {
        return Err(PhysicsError::InvalidInput(
            "limiter switch time or level not finite and non-negative",
        ));
    }
    simulate(pulse, occ, set, Some(*switch), hw, |_, _, _| {})
}

fn simulate(
    pulse: &CompartmentPulse<'_>,
    occ: &OccupantInput,
    set: &RestraintSettings,
    switch: Option<LimiterSwitch>,
    hw: &RestraintHardware,
    mut observe: impl FnMut(f64, f64, f64),
) -> Result<OccupantOutcome, PhysicsError> {
    validate(pulse, occ, set, hw)?;
    let dt = pulse.step_s;
    let m = occ.mass_kg;
    let inv_m = 1.0 / m;
    let d_wheel = occ.chest_to_wheel_m;
    let s_avail = d_wheel - hw.module_thickness_m;
    let bag_depth = hw.airbag_depth_m.min(d_wheel);
    let friction_n = hw.seat_friction_coeff * m * defaults::STANDARD_GRAVITY_MPS2;
    let inv_v_reg = 1.0 / hw.seat_friction_regularisation_mps;
    let inv_pt = if hw.pretensioner_duration_s > 0.0 {
        1.0 / hw.pretensioner_duration_s
    } else {
        f64::INFINITY
    };
    let inv_inf = if hw.airbag_inflation_s > 0.0 {
        1.0 / hw.airbag_inflation_s
    } else {
        f64::INFINITY
    };
    let airbag_fires = set.airbag_force_n > 0.0;
    let mut belt_force_cap = set.load_limiter_n;
    let (switch_at_s, switched_cap_n) =
        switch.map_or((f64::INFINITY, belt_force_cap), |w| (w.at_s, w.level_n));
    let k_belt = hw.belt_stiffness_n_per_m;
    // One pass: reject NaN/∞/> 1000 g samples and find the last non-zero sample. After it nothing
    // can push the occupant further forward once it moves rearward (restraint forces are
    // dissipative or restoring), so the simulation may stop there: this halves the cost for
    // predicted pulses, which end at separation.
    let mut n_active = 0;
    for (i, a) in pulse.accel_mps2.iter().enumerate() {
        if !(a.abs() <= 1.0e4) {
            return Err(PhysicsError::InvalidSignal(
                "pulse contains non-finite or > 1000 g samples",
            ));
        }
        if *a != 0.0 {
            n_active = i + 1;
        }
    }
    let max_steps = (hw.max_sim_s / dt) as usize;

    let (mut x, mut v, mut payout) = (0.0f64, 0.0f64, 0.0f64);
    let mut out = OccupantOutcome {
        available_ride_down_m: s_avail,
        ..OccupantOutcome::default()
    };
    let mut onset_time: Option<f64> = None;
    let mut decel_integral = 0.0; // ∫ decel dt since restraint onset
    let mut mean_at_max = 0.0;
    // Compartment velocity change and its integral (for a*), accumulated on the way.
    let (mut a_prev, mut v_c, mut int_v_c, mut steps_done) = (0.0f64, 0.0f64, 0.0f64, 0usize);

    for i in 0..max_steps {
        let t = i as f64 * dt;
        let a_c = pulse.accel_mps2.get(i).copied().unwrap_or(0.0);
        if i > 0 {
            let v_next = v_c + 0.5 * (a_prev + a_c) * dt;
            int_v_c += 0.5 * (v_c + v_next) * dt;
            v_c = v_next;
        }
        a_prev = a_c;
        steps_done = i;
        if t >= switch_at_s {
            belt_force_cap = switched_cap_n;
        }
        // Belt.
        let mut f_belt = 0.0;
        if occ.belted {
            let removed = ((t - set.pretensioner_time_s) * inv_pt).clamp(0.0, 1.0);
            let slack = hw.belt_slack_m * (1.0 - removed);
            let stretch = x - slack - payout;
            if stretch > 0.0 {
                f_belt = k_belt * stretch;
                if f_belt > belt_force_cap {
                    // Pay-out at the limiter is permanent.
                    payout = if k_belt > 0.0 {
                        x - slack - belt_force_cap / k_belt
                    } else {
                        payout
                    };
                    f_belt = belt_force_cap;
                }
            }
        }
        // Airbag + column.
        let mut f_bag = 0.0;
        if airbag_fires && t >= set.airbag_time_s {
            let depth = bag_depth * ((t - set.airbag_time_s) * inv_inf).min(1.0);
            let penetration = x + depth - d_wheel;
            if penetration > 0.0 {
                f_bag = (hw.airbag_stiffness_n_per_m * penetration).min(set.airbag_force_n);
            }
        }
        // Wheel / dash contact and seat back.
        let mut f_contact = 0.0;
        if x > s_avail {
            f_contact = hw.bottoming_stiffness_n_per_m * (x - s_avail);
            out.bottomed_out = true;
        } else if x < 0.0 {
            f_contact = hw.seatback_stiffness_n_per_m * x;
        }
        let f_seat = friction_n * (v * inv_v_reg).clamp(-1.0, 1.0);
        let f_total = f_belt + f_bag + f_contact + f_seat;
        let decel = f_total * inv_m;

        if onset_time.is_none() && (f_belt > 0.0 || f_bag > 0.0) {
            onset_time = Some(t);
        }
        if onset_time.is_some() {
            decel_integral += decel * dt;
        }
        out.max_decel_mps2 = out.max_decel_mps2.max(decel);
        out.max_belt_force_n = out.max_belt_force_n.max(f_belt);
        out.max_airbag_force_n = out.max_airbag_force_n.max(f_bag);

        observe(t, x, decel);
        // Semi-implicit Euler.
        v += (-a_c - decel) * dt;
        x += v * dt;
        if x > out.max_excursion_m {
            out.max_excursion_m = x;
            out.max_excursion_time_s = t + dt;
            if let Some(t0) = onset_time {
                let span = t + dt - t0;
                mean_at_max = if span > 0.0 {
                    decel_integral / span
                } else {
                    0.0
                };
            }
        }
        if i >= n_active && v <= 0.0 {
            break;
        }
    }
    out.mean_decel_mps2 = mean_at_max;
    out.belt_payout_m = payout;
    out.ideal_decel_mps2 = if steps_done + 1 >= n_active {
        // Beyond the last non-zero sample v_c is constant, so ∫(v − v_end) stops growing.
        let d_veh = int_v_c - v_c * steps_done as f64 * dt;
        ideal_bound(v_c, d_veh + s_avail)
    } else {
        ideal_constant_force_decel_mps2(pulse, s_avail)
    };
    Ok(out)
}
