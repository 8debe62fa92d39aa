//! SAE J211/1 CFC filter: magnitude inside the standard's corridor, zero phase, DC gain 1.
//!
//! Corridor (SAE J211/1 Figure 1 / ISO 6487): F_L = 0.1 Hz, F_H = CFC, F_N = 1.667·CFC (approx.
//! 100 Hz for CFC 60, 300 Hz for CFC 180).
//!  * F_L..F_H: upper +0.5 dB, lower −0.5 dB at F_L falling to −1 dB at F_H,
//!  * at F_N: upper +0.5 dB, lower −4 dB (straight on log-f between F_H and F_N),
//!  * above F_N: upper falls 9 dB/octave from +0.5 dB; lower falls 24 dB/octave from −4 dB down
//!    to −30 dB, below which it is unbounded.
//!
//! Measured by filtering long sinusoids (the real in-place filter), not only by the formula.

use physics::j211::{filter_in_place, magnitude, Cfc};

fn corridor_db(cfc_hz: f64, f: f64) -> (f64, f64) {
    let (fl, fh, fnn) = (0.1, cfc_hz, cfc_hz * 5.0 / 3.0);
    if f <= fh {
        let t = (f / fl).log10() / (fh / fl).log10();
        (-0.5 - 0.5 * t, 0.5)
    } else if f <= fnn {
        let t = (f / fh).log2() / (fnn / fh).log2();
        (-1.0 - 3.0 * t, 0.5)
    } else {
        let oct = (f / fnn).log2();
        let lower = -4.0 - 24.0 * oct;
        (
            if lower < -30.0 {
                f64::NEG_INFINITY
            } else {
                lower
            },
            0.5 - 9.0 * oct,
        )
    }
}

fn measured_gain(cfc: Cfc, step_s: f64, f: f64) -> f64 {
    let n = 40_000;
    let mut x: Vec<f64> = (0..n)
        .map(|i| (2.0 * std::f64::consts::PI * f * i as f64 * step_s).sin())
        .collect();
    filter_in_place(&mut x, step_s, cfc).unwrap();
    // Amplitude over the middle half (away from edge transients).
    let mid = &x[n / 4..3 * n / 4];
    mid.iter().fold(0.0f64, |m, v| m.max(v.abs()))
}

#[test]
fn magnitude_within_j211_corridor() {
    let step_s = 1.0e-4; // 10 kHz
    for (cfc, hz) in [(Cfc::Cfc60, 60.0), (Cfc::Cfc180, 180.0)] {
        for &ratio in &[0.05, 0.2, 0.5, 0.8, 1.0, 1.3, 1.667, 2.0, 3.0, 5.0] {
            let f = ratio * hz;
            let (lo, hi) = corridor_db(hz, f);
            let g_formula_db = 20.0 * magnitude(cfc, step_s, f).unwrap().log10();
            let g_meas_db = 20.0 * measured_gain(cfc, step_s, f).log10();
            for g in [g_formula_db, g_meas_db] {
                assert!(
                    g >= lo - 1e-9 && g <= hi + 1e-9,
                    "{cfc:?} {f} Hz: {g} dB not in [{lo}, {hi}]"
                );
            }
            assert!(
                (g_formula_db - g_meas_db).abs() < 0.05,
                "{f} Hz: {g_formula_db} vs {g_meas_db}"
            );
        }
    }
}

#[test]
fn phaseless_and_unit_dc_gain() {
    let step_s = 1.0e-4;
    // Symmetric pulse stays symmetric about its centre (zero phase) and a constant stays constant.
    let n = 2001;
    let mut x: Vec<f64> = (0..n)
        .map(|i| {
            let t = (i as f64 - 1000.0) * step_s;
            (-(t / 0.01).powi(2)).exp()
        })
        .collect();
    filter_in_place(&mut x, step_s, Cfc::Cfc60).unwrap();
    let peak = x
        .iter()
        .enumerate()
        .max_by(|a, b| a.1.total_cmp(b.1))
        .unwrap()
        .0;
    assert_eq!(peak, 1000);
    let mut c = vec![3.5; 500];
    filter_in_place(&mut c, step_s, Cfc::Cfc180).unwrap();
    assert!(c.iter().all(|v| (v - 3.5).abs() < 1e-9));
}

#[test]
fn rejects_bad_input() {
    assert!(filter_in_place(&mut [1.0, f64::NAN], 1e-4, Cfc::Cfc60).is_err());
    assert!(filter_in_place(&mut [1.0, 2.0], 0.01, Cfc::Cfc60).is_err()); // 100 Hz < 10 × CFC
    assert!(filter_in_place(&mut [1.0, 2.0], f64::NAN, Cfc::Cfc60).is_err());
}
