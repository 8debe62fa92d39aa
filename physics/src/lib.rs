//! Crash-pulse and occupant physics of the situation-adaptive restraint method (no_std core).
//!
//! * [`stiffness`] — piecewise-linear force-deflection curves, series combination, the six mass
//!   classes (generated at build time from `data/stiffness-classes.toml`).
//! * [`collision`] — two masses joined by one combined non-linear spring with restitution-exact
//!   unloading; writes the compartment pulses into a caller-owned fixed buffer.
//! * [`exact`] — the same model solved in closed form segment by segment (no step size): the
//!   cheap summary, any-instant states, sampled pulses. The integrator stays as its oracle.
//! * [`occupant`] — one rigid occupant body with belt, airbag + column, seat friction,
//!   bottoming-out detection, and the ideal constant-force bound a*.
//! * [`crash_mode`] — full frontal, offset, angular, pole and underride: the part of the ego's
//!   class curve each engages, and when.
//! * [`crush_zone`] (feature `std`) — what a crush-zone (upfront) satellite feels ahead of the
//!   body: the front structure's graded fold from the ego's crush.
//! * [`measured`] — a measured crash pulse as the collision (the ego's pulse from a crash test).
//! * [`j211`] — SAE J211 CFC filter (phaseless, in place, no allocation).
//! * [`trace`] (feature `std`) — a measured accelerometer channel: CSV or ISO-MME.
//! * [`derive`] (feature `std`) — force-deflection curve from a rigid-barrier accelerometer trace.
//! * [`deadline`] — the classic required fire time of a frontal airbag, "127 mm − 30 ms".
//! * [`defaults`] — every modelling default in one place.
//! * [`paper`] — the published numbers we calibrate against (typed from SPEC.md).
//!
//! Units: SI internally (m, s, kg, N); names carry the unit suffix. Nothing here allocates or
//! panics on input (property-tested); invalid input returns [`PhysicsError`].
#![cfg_attr(not(feature = "std"), no_std)]
#![forbid(unsafe_code)]
// `!(x > 0.0)` is deliberate: it is true for NaN, which is how inputs are rejected NaN-safely.
#![allow(clippy::neg_cmp_op_on_partial_ord)]
#![warn(missing_docs)]

pub mod collision;
pub mod crash_mode;
#[cfg(feature = "std")]
pub mod crush_zone;
pub mod deadline;
pub mod defaults;
#[cfg(feature = "std")]
pub mod derive;
mod error;
pub mod exact;
pub mod j211;
pub mod measured;
pub mod occupant;
pub mod paper;
#[cfg(feature = "std")]
pub mod reference;
pub mod reference_settings;
pub mod stiffness;
#[cfg(feature = "std")]
pub mod trace;

pub use collision::{
    simulate_collision, CollisionInput, CollisionSummary, CompartmentPulse, DefaultPulseBuffer,
    PulseBuffer, PulseSample, VehicleResult,
};
pub use error::PhysicsError;
pub use exact::{predict_summary, simulate_collision_exact, ExactCollision, SampleCursor};
pub use occupant::{
    ideal_constant_force_decel_mps2, simulate_occupant, simulate_occupant_observed,
    simulate_occupant_switched, LimiterSwitch, OccupantInput, OccupantOutcome, RestraintHardware,
    RestraintSettings,
};
pub use reference_settings::ReferenceSettings;
pub use stiffness::{class_for_mass_kg, CombinedSpring, Curve, MassClass};

/// Convert an acceleration in m/s² to multiples of standard gravity.
pub fn mps2_to_g(accel_mps2: f64) -> f64 {
    accel_mps2 / defaults::STANDARD_GRAVITY_MPS2
}

/// Ego equivalent barrier speed, km/h: the ego's speed change to the common velocity of a
/// two-mass collision, v_close · m_opp / (m_ego + m_opp) (v/2 for equal masses, v for a rigid
/// barrier).
pub fn equivalent_barrier_speed_kph(closing_mps: f64, ego_kg: f64, opp_kg: f64) -> f64 {
    let share = if opp_kg.is_infinite() {
        1.0
    } else {
        opp_kg / (ego_kg + opp_kg)
    };
    closing_mps * share * 3.6
}

/// Convert km/h to m/s.
pub fn kph_to_mps(speed_kph: f64) -> f64 {
    speed_kph / 3.6
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ebs_is_half_for_equal_masses_and_full_for_a_barrier() {
        assert!((equivalent_barrier_speed_kph(30.0, 1500.0, 1500.0) - 54.0).abs() < 1e-9);
        assert!((equivalent_barrier_speed_kph(15.0, 1500.0, f64::INFINITY) - 54.0).abs() < 1e-9);
    }
}
