//! Force-deflection curve from a rigid-barrier test (the paper's way of building class curves
//! from NHTSA full-frontal tests).
//!
//! 1. Filter the compartment accelerometer trace with SAE J211 CFC 60 (the class J211 assigns
//!    to integration for velocity and displacement).
//! 2. Integrate twice from the impact speed: v(t) = v₀ + ∫a, crush(t) = ∫v (barrier is rigid,
//!    so the vehicle's displacement after contact is its crush).
//! 3. Force F(t) = m · (−a(t)) (vehicle mass times deceleration).
//! 4. Keep the loading phase (until v = 0, maximum crush), resample onto an even crush grid and
//!    make the curve monotone (running maximum, strictly increasing) so that it satisfies the
//!    class-file schema and the series combination.
//!
//! The trace ([`crate::trace`]) is integrated from its first sample. Sign convention: SAE J211 vehicle axis (x forward), so crash deceleration is negative.
//! A trace recorded with the opposite sign is detected (its integral would speed the car up)
//! and flipped; [`DerivedCurve::sign_flipped`] reports it.

use crate::{j211, stiffness::Curve, trace::Trace, PhysicsError};
use std::vec::Vec;

/// Options of the derivation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DeriveOptions {
    /// Test mass [kg].
    pub mass_kg: f64,
    /// Impact speed [m/s] (NCAP / FMVSS 208 full frontal: 56 km/h).
    pub impact_speed_mps: f64,
    /// Number of curve points including (0, 0), 3..=16.
    pub points: usize,
    /// Filter class (CFC 60 per J211 for integration).
    pub cfc: j211::Cfc,
}

/// A derived curve plus the raw loading-phase data behind it.
#[derive(Clone, Debug)]
pub struct DerivedCurve {
    /// The resampled monotone curve.
    pub curve: Curve,
    /// Maximum crush [m].
    pub max_crush_m: f64,
    /// Raw loading-phase crush samples [m].
    pub raw_crush_m: Vec<f64>,
    /// Raw loading-phase force samples [N].
    pub raw_force_n: Vec<f64>,
    /// The trace had deceleration positive and was flipped.
    pub sign_flipped: bool,
}

/// Derive a force-deflection curve from a barrier trace.
pub fn derive_curve(trace: &Trace, opts: &DeriveOptions) -> Result<DerivedCurve, PhysicsError> {
    if !(opts.mass_kg.is_finite() && opts.mass_kg > 0.0) {
        return Err(PhysicsError::InvalidInput(
            "test mass must be finite and > 0",
        ));
    }
    if !(opts.impact_speed_mps.is_finite() && opts.impact_speed_mps > 0.0) {
        return Err(PhysicsError::InvalidInput(
            "impact speed must be finite and > 0",
        ));
    }
    if !(3..=16).contains(&opts.points) {
        return Err(PhysicsError::InvalidInput("points must be within 3..=16"));
    }
    if trace.accel_mps2.len() < 16 {
        return Err(PhysicsError::InvalidSignal("trace shorter than 16 samples"));
    }
    let dt = trace.step_s;
    let mut a = trace.accel_mps2.clone();
    j211::filter_in_place(&mut a, dt, opts.cfc)?;
    let sum: f64 = a.iter().sum();
    let sign_flipped = sum > 0.0;
    if sign_flipped {
        a.iter_mut().for_each(|v| *v = -*v);
    }
    // Loading phase: integrate until the vehicle stops (max crush).
    let (mut v, mut x) = (opts.impact_speed_mps, 0.0);
    let mut raw_crush_m = vec![0.0];
    let mut raw_force_n = vec![0.0];
    let mut stopped = false;
    for w in a.windows(2) {
        let v_next = v + 0.5 * (w[0] + w[1]) * dt;
        if v_next <= 0.0 {
            // Stop inside this step: add the remaining travel and stop.
            let frac = if v - v_next > 0.0 {
                v / (v - v_next)
            } else {
                0.0
            };
            x += 0.5 * v * frac * dt;
            raw_crush_m.push(x);
            raw_force_n.push(opts.mass_kg * (-w[1]).max(0.0));
            stopped = true;
            break;
        }
        x += 0.5 * (v + v_next) * dt;
        v = v_next;
        raw_crush_m.push(x);
        raw_force_n.push(opts.mass_kg * (-w[1]).max(0.0));
    }
    if !stopped {
        return Err(PhysicsError::InvalidSignal(
            "vehicle never stopped: trace too short or impact speed too high",
        ));
    }
    let max_crush_m = x;
    if !(max_crush_m > 0.0) {
        return Err(PhysicsError::InvalidSignal("no crush"));
    }
    // Resample: mean force in each crush bin centred on the grid point (noise averages out),
    // then enforce strictly increasing force (running max + 1 N per point).
    let n = opts.points;
    let mut dm = [0.0f64; 16];
    let mut fm = [0.0f64; 16];
    let h = max_crush_m / (n - 1) as f64;
    for k in 1..n {
        let centre = k as f64 * h;
        let (lo, hi) = (centre - 0.5 * h, (centre + 0.5 * h).min(max_crush_m));
        let (mut s, mut c) = (0.0, 0usize);
        for (xi, fi) in raw_crush_m.iter().zip(raw_force_n.iter()) {
            if *xi >= lo && *xi <= hi {
                s += fi;
                c += 1;
            }
        }
        let f = if c > 0 {
            s / c as f64
        } else {
            interp(&raw_crush_m, &raw_force_n, centre)
        };
        dm[k] = centre;
        fm[k] = f.max(fm[k - 1] + 1.0);
    }
    let curve = Curve::from_points(&dm[..n], &fm[..n])?;
    Ok(DerivedCurve {
        curve,
        max_crush_m,
        raw_crush_m,
        raw_force_n,
        sign_flipped,
    })
}

fn interp(xs: &[f64], ys: &[f64], x: f64) -> f64 {
    for i in 1..xs.len().min(ys.len()) {
        if xs[i] >= x {
            let span = xs[i] - xs[i - 1];
            let t = if span > 0.0 {
                (x - xs[i - 1]) / span
            } else {
                1.0
            };
            return ys[i - 1] + t * (ys[i] - ys[i - 1]);
        }
    }
    ys.last().copied().unwrap_or(0.0)
}
