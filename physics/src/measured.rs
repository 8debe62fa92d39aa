//! A measured crash pulse as the collision: a crash test's compartment accelerometer (a
//! [`crate::trace::Trace`] resampled from the first contact) stands in for the two-mass model's
//! ego pulse, so a scenario can be played with a real test's pulse.
//!
//! The ego's velocity change is the pulse's integral; its crush is taken against a face that
//! stands still (a barrier test, which is what measured frontal pulses are): the integral of
//! the closing speed plus the velocity change, its running maximum (the structure does not
//! unfold). With an opponent that moves, the crush at the rail tips — what the satellites fold
//! with — is therefore the barrier-equivalent one. The opponent's channels stay 0.
//!
//! The summary's figures are read off the pulse: the peak deceleration, the final velocity
//! change, the contact duration up to the last sample whose deceleration is at least
//! [`END_FRACTION`] of the peak, the crush and the instant of the largest one.

use crate::collision::{CollisionSummary, PulseBuffer, PulseSample, VehicleResult};
use crate::PhysicsError;

/// The contact ends at the last sample whose deceleration reaches this fraction of the peak
/// (a measured pulse's tail carries the accelerometer's ringing and offset, never exactly 0).
pub const END_FRACTION: f64 = 0.02;

/// Writes the ego pulse `accel_mps2` (sample k at k·`step_s` after the first contact; a crash
/// reads negative) into `out`, at most N samples, and returns the collision it describes for an
/// ego of `ego_mass_kg` closing at `closing_mps` on a face that stands still (module docs).
///
/// # Errors
/// A non-finite or non-positive step or mass, a negative or non-finite closing speed, fewer
/// than two samples, a non-finite sample, or a pulse that does not slow the car down.
pub fn measured_collision<const N: usize>(
    accel_mps2: &[f64],
    step_s: f64,
    closing_mps: f64,
    ego_mass_kg: f64,
    out: &mut PulseBuffer<N>,
) -> Result<CollisionSummary, PhysicsError> {
    if !(step_s > 0.0 && step_s.is_finite()) {
        return Err(PhysicsError::InvalidInput("step must be finite and > 0"));
    }
    if !(ego_mass_kg > 0.0 && ego_mass_kg.is_finite()) {
        return Err(PhysicsError::InvalidInput(
            "ego mass must be finite and > 0",
        ));
    }
    if !(closing_mps >= 0.0 && closing_mps.is_finite()) {
        return Err(PhysicsError::InvalidInput(
            "closing speed must be finite and ≥ 0",
        ));
    }
    let pulse = accel_mps2
        .get(..N.min(accel_mps2.len()))
        .unwrap_or_default();
    if pulse.len() < 2 {
        return Err(PhysicsError::InvalidSignal("pulse shorter than 2 samples"));
    }
    if pulse.iter().any(|a| !a.is_finite()) {
        return Err(PhysicsError::InvalidSignal("pulse sample not finite"));
    }
    out.start(step_s, pulse.len());
    let (mut v, mut x, mut x_max) = (0.0, 0.0, 0.0f64);
    let (mut a_max, mut reversal_s) = (0.0f64, None);
    let mut prev = (pulse[0], closing_mps);
    for (k, &a) in pulse.iter().enumerate() {
        if k > 0 {
            v += 0.5 * (prev.0 + a) * step_s;
            let rel = closing_mps + v;
            x += 0.5 * (prev.1 + rel) * step_s;
            if rel <= 0.0 && reversal_s.is_none() {
                reversal_s = Some(k as f64 * step_s);
            }
            prev = (a, rel);
        }
        x_max = x_max.max(x);
        a_max = a_max.max(-a);
        out.write(
            k,
            &PulseSample {
                ego_accel_mps2: a,
                ego_vel_mps: v,
                ego_crush_m: x_max,
                ..PulseSample::ZERO
            },
        );
    }
    if !(v < 0.0) {
        return Err(PhysicsError::InvalidSignal(
            "pulse does not slow the car (SAE J211: a frontal crash reads negative)",
        ));
    }
    let last = pulse
        .iter()
        .rposition(|a| -a >= END_FRACTION * a_max)
        .unwrap_or(0)
        .max(1);
    let duration_s = last as f64 * step_s;
    let delta_v_mps = -v;
    let separation_mps = (-(closing_mps + v)).max(0.0);
    Ok(CollisionSummary {
        vehicle: VehicleResult {
            crush_m: x_max,
            a_max_mps2: a_max,
            a_mean_mps2: delta_v_mps / duration_s,
            delta_v_mps,
        },
        opponent: VehicleResult::ZERO,
        contact_duration_s: duration_s,
        reversal_time_s: reversal_s.unwrap_or((pulse.len() - 1) as f64 * step_s),
        max_deflection_m: x_max,
        peak_force_n: ego_mass_kg * a_max,
        unloading_stiffness_n_per_m: 0.0,
        separation_speed_mps: separation_mps,
        absorbed_energy_j: 0.5
            * ego_mass_kg
            * (closing_mps * closing_mps - separation_mps * separation_mps),
        samples_written: pulse.len(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::collision::DefaultPulseBuffer;
    extern crate std;
    use std::vec::Vec;

    /// A half-sine of peak A over T: Δv = 2AT/π, the peak A at T/2; against a still face at
    /// the Δv's speed the crush is the stopping distance ∫(v₀ − ∫a) = A·T²/π (at T).
    #[test]
    fn a_half_sine_gives_its_closed_form_velocity_change_peak_and_crush() {
        let (a_peak, t_end, dt) = (300.0, 0.08, 1e-4);
        let n = (t_end / dt) as usize + 1;
        let pulse: Vec<f64> = (0..n)
            .map(|k| -a_peak * (core::f64::consts::PI * k as f64 * dt / t_end).sin())
            .collect();
        let dv = 2.0 * a_peak * t_end / core::f64::consts::PI;
        let mut buf = DefaultPulseBuffer::new();
        let s = measured_collision(&pulse, dt, dv, 1500.0, &mut buf).unwrap();
        assert!((s.vehicle.delta_v_mps - dv).abs() < 1e-3 * dv);
        assert!((s.vehicle.a_max_mps2 - a_peak).abs() < 1e-3 * a_peak);
        let crush = a_peak * t_end * t_end / core::f64::consts::PI;
        assert!(
            (s.vehicle.crush_m - crush).abs() < 1e-3 * crush,
            "{}",
            s.vehicle.crush_m
        );
        assert_eq!(buf.len(), n);
        assert!((buf.ego_vel_mps()[n - 1] + dv).abs() < 1e-3 * dv);
        assert!(s.separation_speed_mps < 1e-3);
    }

    #[test]
    fn a_pulse_that_speeds_the_car_up_or_is_not_finite_is_refused() {
        let mut buf = DefaultPulseBuffer::new();
        assert!(measured_collision(&[1.0; 50], 1e-4, 10.0, 1500.0, &mut buf).is_err());
        assert!(measured_collision(&[-1.0, f64::NAN], 1e-4, 10.0, 1500.0, &mut buf).is_err());
        assert!(measured_collision(&[-1.0; 50], 0.0, 10.0, 1500.0, &mut buf).is_err());
        assert!(measured_collision(&[-1.0; 50], 1e-4, -1.0, 1500.0, &mut buf).is_err());
        assert!(measured_collision(&[-1.0], 1e-4, 10.0, 1500.0, &mut buf).is_err());
    }
}
