//! The classic required fire time of a frontal airbag, "127 mm − 30 ms": the instant a
//! free-flying (unbelted) occupant has moved 127 mm (5 in) relative to the compartment, less
//! the bag's 30 ms inflation — a bag fired later is still filling when the occupant reaches it.
//! The occupant flies free, so its motion relative to the car is the car's velocity change
//! integrated once more: x(t) = ∫∫ −a dt² of the compartment pulse.

use crate::collision::CompartmentPulse;
use crate::defaults::AIRBAG_INFLATION_S;

/// The free flight the criterion allows before the bag must be full [m] (5 in).
pub const FREE_FLIGHT_M: f64 = 0.127;

/// The required fire time of `pulse` [s after contact]: when the free-flying occupant has moved
/// [`FREE_FLIGHT_M`], less [`AIRBAG_INFLATION_S`]; `None` when the pulse never moves it that far.
pub fn required_fire_s(pulse: &CompartmentPulse<'_>) -> Option<f64> {
    let (mut v, mut x) = (0.0, 0.0);
    for (k, a) in pulse.accel_mps2.iter().enumerate() {
        v -= a * pulse.step_s;
        x += v * pulse.step_s;
        if x >= FREE_FLIGHT_M {
            return Some((k as f64 + 1.0) * pulse.step_s - AIRBAG_INFLATION_S);
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A constant deceleration a: ½·a·t² = 0.127 m at t = √(0.254 / a), less 30 ms.
    #[test]
    fn a_constant_deceleration_gives_the_closed_form() {
        let (a, step) = (200.0, 1e-5);
        let accel = [-a; 8000];
        let pulse = CompartmentPulse {
            accel_mps2: &accel,
            step_s: step,
        };
        let t = required_fire_s(&pulse).expect("moves 127 mm");
        let exact = (2.0 * FREE_FLIGHT_M / a).sqrt() - AIRBAG_INFLATION_S;
        assert!((t - exact).abs() < 2.0 * step, "{t} vs {exact}");
    }

    #[test]
    fn a_pulse_that_never_moves_the_occupant_that_far_has_none() {
        let accel = [-10.0; 100];
        let pulse = CompartmentPulse {
            accel_mps2: &accel,
            step_s: 1e-4,
        };
        assert_eq!(required_fire_s(&pulse), None);
    }
}
