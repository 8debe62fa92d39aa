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
//! Trace sign convention: SAE J211 vehicle axis (x forward), so crash deceleration is negative.
//! A trace recorded with the opposite sign is detected (its integral would speed the car up)
//! and flipped; [`DerivedCurve::sign_flipped`] reports it.

use crate::{j211, stiffness::Curve, PhysicsError};
use std::{string::String, vec::Vec};

/// An accelerometer trace at a uniform step, first sample at (or before) first contact.
#[derive(Clone, Debug, PartialEq)]
pub struct BarrierTrace {
    /// Sampling step [s].
    pub step_s: f64,
    /// Compartment acceleration [m/s²].
    pub accel_mps2: Vec<f64>,
}

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

/// Parse a CSV trace: header `time_s,accel_g` or `time_s,accel_mps2` (or `time_ms` for the
/// first column); then one sample per line; `#` comments and blank lines ignored. The step must
/// be uniform within 1 %.
pub fn parse_trace_csv(text: &str) -> Result<BarrierTrace, String> {
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim()))
        .filter(|(_, l)| !l.is_empty() && !l.starts_with('#'));
    let (_, header) = lines.next().ok_or("empty trace file")?;
    let cols: Vec<String> = header
        .split(',')
        .map(|c| c.trim().to_ascii_lowercase())
        .collect();
    if cols.len() < 2 {
        return Err(format!("header must name two columns, got `{header}`"));
    }
    let time_scale = match cols[0].as_str() {
        "time_s" | "t_s" => 1.0,
        "time_ms" | "t_ms" => 1.0e-3,
        other => {
            return Err(format!(
                "first column must be time_s or time_ms, got `{other}`"
            ))
        }
    };
    let accel_scale = match cols[1].as_str() {
        "accel_g" | "a_g" => crate::defaults::STANDARD_GRAVITY_MPS2,
        "accel_mps2" | "a_mps2" => 1.0,
        other => {
            return Err(format!(
                "second column must be accel_g or accel_mps2, got `{other}`"
            ))
        }
    };
    let mut times = Vec::new();
    let mut accel = Vec::new();
    for (line_no, line) in lines {
        let mut it = line.split(',');
        let parse = |s: Option<&str>| -> Result<f64, String> {
            let s = s.ok_or(format!("line {line_no}: missing column"))?.trim();
            let v: f64 = s
                .parse()
                .map_err(|_| format!("line {line_no}: not a number: `{s}`"))?;
            if v.is_finite() {
                Ok(v)
            } else {
                Err(format!("line {line_no}: non-finite value"))
            }
        };
        times.push(parse(it.next())? * time_scale);
        accel.push(parse(it.next())? * accel_scale);
    }
    if times.len() < 16 {
        return Err(format!(
            "trace has {} samples, need at least 16",
            times.len()
        ));
    }
    let step_s = (times[times.len() - 1] - times[0]) / (times.len() - 1) as f64;
    if !(step_s > 0.0) {
        return Err("time column must increase".into());
    }
    for (i, w) in times.windows(2).enumerate() {
        if ((w[1] - w[0]) - step_s).abs() > 0.01 * step_s {
            return Err(format!("non-uniform time step at sample {}", i + 2));
        }
    }
    Ok(BarrierTrace {
        step_s,
        accel_mps2: accel,
    })
}

/// Derive a force-deflection curve from a barrier trace.
pub fn derive_curve(
    trace: &BarrierTrace,
    opts: &DeriveOptions,
) -> Result<DerivedCurve, PhysicsError> {
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
