//! SAE J211/1 channel frequency class (CFC) filter: a 2nd-order Butterworth low-pass run forward
//! and then backward over the data (4th-order magnitude, zero phase), with the standard's
//! design frequency ω_d = 2π · CFC · 2.0775 and bilinear pre-warping (J211/1 Appendix C).
//!
//! Works in place on a slice: no allocation, usable in no_std. Start-up transients are avoided
//! by initialising each pass as if the signal had been constant at its edge value before the
//! record (steady state of a unit-DC-gain filter).

use crate::PhysicsError;

/// Channel frequency class.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Cfc {
    /// CFC 60: vehicle structure for integration / crush (−3 dB at 100 Hz).
    Cfc60,
    /// CFC 180: vehicle structural accelerations.
    Cfc180,
    /// CFC 600: occupant chest / pelvis.
    Cfc600,
    /// CFC 1000: occupant head.
    Cfc1000,
}

impl Cfc {
    /// The class number, which is also F_H [Hz] of the J211 corridor.
    pub fn hz(self) -> f64 {
        match self {
            Cfc::Cfc60 => 60.0,
            Cfc::Cfc180 => 180.0,
            Cfc::Cfc600 => 600.0,
            Cfc::Cfc1000 => 1000.0,
        }
    }
}

/// Biquad coefficients of one pass (J211/1 Appendix C notation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CfcCoefficients {
    /// Feed-forward a0 (= a2, a1 = 2 a0).
    pub a0: f64,
    /// Feedback b1.
    pub b1: f64,
    /// Feedback b2.
    pub b2: f64,
}

/// Coefficients for a class and sampling step. Requires the sampling rate to be at least
/// 10 × CFC (J211 recommends ≥ 10× the filter's F_H) so the design stays well-conditioned.
pub fn coefficients(cfc: Cfc, step_s: f64) -> Result<CfcCoefficients, PhysicsError> {
    if !(step_s.is_finite() && step_s > 0.0) {
        return Err(PhysicsError::InvalidSignal(
            "sampling step must be finite and > 0",
        ));
    }
    if 1.0 / step_s < 10.0 * cfc.hz() {
        return Err(PhysicsError::InvalidSignal("sampling rate below 10 x CFC"));
    }
    let wd = 2.0 * core::f64::consts::PI * cfc.hz() * 2.0775;
    let wa = libm::tan(wd * step_s / 2.0);
    let sqrt2 = core::f64::consts::SQRT_2;
    let den = 1.0 + sqrt2 * wa + wa * wa;
    Ok(CfcCoefficients {
        a0: wa * wa / den,
        b1: -2.0 * (wa * wa - 1.0) / den,
        b2: (-1.0 + sqrt2 * wa - wa * wa) / den,
    })
}

fn pass<I: Iterator<Item = usize> + Clone>(data: &mut [f64], c: &CfcCoefficients, order: I) {
    let first = match order.clone().next().and_then(|i| data.get(i)) {
        Some(&v) => v,
        None => return,
    };
    let (mut x1, mut x2, mut y1, mut y2) = (first, first, first, first);
    for i in order {
        if let Some(slot) = data.get_mut(i) {
            let x0 = *slot;
            let y0 = c.a0 * (x0 + 2.0 * x1 + x2) + c.b1 * y1 + c.b2 * y2;
            x2 = x1;
            x1 = x0;
            y2 = y1;
            y1 = y0;
            *slot = y0;
        }
    }
}

/// Filter `samples` in place (forward then backward pass). Rejects non-finite samples.
pub fn filter_in_place(samples: &mut [f64], step_s: f64, cfc: Cfc) -> Result<(), PhysicsError> {
    if samples.iter().any(|v| !v.is_finite()) {
        return Err(PhysicsError::InvalidSignal("non-finite sample"));
    }
    let c = coefficients(cfc, step_s)?;
    let n = samples.len();
    pass(samples, &c, 0..n);
    pass(samples, &c, (0..n).rev());
    Ok(())
}

/// Magnitude of the phaseless (two-pass) filter at a frequency [linear gain], from the digital
/// transfer function: |H(e^{jωT})|². Used to check the design against the J211 corridor.
pub fn magnitude(cfc: Cfc, step_s: f64, freq_hz: f64) -> Result<f64, PhysicsError> {
    let c = coefficients(cfc, step_s)?;
    let w = 2.0 * core::f64::consts::PI * freq_hz * step_s;
    // H(z) = a0 (1 + 2 z^-1 + z^-2) / (1 − b1 z^-1 − b2 z^-2)
    let (c1, s1, c2, s2) = (
        libm::cos(w),
        libm::sin(w),
        libm::cos(2.0 * w),
        libm::sin(2.0 * w),
    );
    let num_re = c.a0 * (1.0 + 2.0 * c1 + c2);
    let num_im = -c.a0 * (2.0 * s1 + s2);
    let den_re = 1.0 - c.b1 * c1 - c.b2 * c2;
    let den_im = c.b1 * s1 + c.b2 * s2;
    let h2 = (num_re * num_re + num_im * num_im) / (den_re * den_re + den_im * den_im);
    Ok(h2) // single-pass |H|², which is the two-pass magnitude
}
