//! The track filter (`restraint::estimate::track`) against independent oracles:
//!
//! * closed form: noise-free samples on a constant-acceleration approach are reproduced
//!   exactly, whatever the latency; the fused mass and its σ are the closed-form weighted mean;
//! * a textbook Kalman filter written with nalgebra's generic matrix algebra (the Bar-Shalom
//!   constant-acceleration model in position coordinates, mapped to distance, Joseph-form
//!   update) reproduces the filter's state and covariance sample by sample;
//! * Monte Carlo: the first-order σ of time to contact and closing speed at contact against
//!   the spread of the closed-form contact over draws from the filter's state distribution;
//! * noisy truth: over many seeded noise realizations the filtered contact estimate is more
//!   accurate than the newest sample's closed form, and its σ is honest (normalised errors);
//! * refused inputs: NaN/inf and samples that are not newer change nothing; outliers are
//!   rejected and a persistent change restarts the track.

use nalgebra::{Matrix3, Vector3};
use proptest::prelude::*;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use restraint::{ObjectState, Refused, TrackConfig, TrackEvent, TrackFilter, VALID};

const MS: u64 = 1_000_000;
const T0: u64 = 1_000_000_000;

/// A constant-acceleration approach: distance d0 at t = 0, closing speed v0, closing
/// acceleration a (rate of change of the closing speed).
#[derive(Debug, Clone, Copy)]
struct Approach {
    d0: f64,
    v0: f64,
    a: f64,
}

impl Approach {
    fn d(&self, t: f64) -> f64 {
        self.d0 - self.v0 * t - 0.5 * self.a * t * t
    }
    fn v(&self, t: f64) -> f64 {
        self.v0 + self.a * t
    }
    /// Contact time and closing speed at contact from t = 0 (the root of d(t) = 0 by the
    /// textbook quadratic formula; `None` if it stops short).
    fn contact(&self) -> Option<(f64, f64)> {
        let disc = self.v0 * self.v0 + 2.0 * self.a * self.d0;
        if disc < 0.0 {
            return None;
        }
        let t = if self.a.abs() < 1e-12 {
            self.d0 / self.v0
        } else {
            (-self.v0 + disc.sqrt()) / self.a
        };
        Some((t, self.v(t)))
    }
}

fn sample(t_ns: u64, d: f64, v: f64, a: f64, m: f64, sigma: f64) -> ObjectState {
    ObjectState {
        timestamp_ns: t_ns,
        sequence: t_ns / MS,
        distance_m: d as f32,
        closing_speed_mps: v as f32,
        relative_accel_mps2: a as f32,
        opponent_mass_kg: m as f32,
        opponent_mass_sigma_kg: sigma as f32,
        confidence: 1.0,
        object_id: 7,
        valid: VALID,
        _reserved: [0; 3],
    }
}

/// The exact f32 value a sample carries (the filter sees f32 measurements).
fn f32_of(x: f64) -> f64 {
    f64::from(x as f32)
}

fn ns(t_s: f64) -> u64 {
    T0 + (t_s * 1e9).round() as u64
}

#[test]
fn noise_free_constant_acceleration_is_reproduced_exactly_at_any_latency() {
    // Values exactly representable in f32 at the sample instants (multiples of 1/64 s), so
    // the samples lie exactly on the trajectory and every innovation is zero.
    let ap = Approach {
        d0: 40.0,
        v0: 22.0,
        a: -4.0,
    };
    let (tc, vc) = ap.contact().unwrap();
    let mut f = TrackFilter::new(&TrackConfig::default(), 100.0);
    let mut sigmas = Vec::new();
    for k in 0..40 {
        let t = k as f64 / 64.0;
        let ev = f.update(&sample(ns(t), ap.d(t), ap.v(t), ap.a, 1500.0, 200.0));
        assert_eq!(
            ev,
            if k == 0 {
                TrackEvent::Started
            } else {
                TrackEvent::Updated
            }
        );
        for latency_ms in [0u64, 7, 35, 90] {
            let now = ns(t) + latency_ms * MS;
            let e = f.estimate_at(now).expect("contact ahead");
            let contact_s = (e.at_ns - T0) as f64 * 1e-9 + e.contact.ttc_s;
            assert!(
                (contact_s - tc).abs() < 1e-6,
                "k {k} lat {latency_ms}: {e:?}"
            );
            assert!(
                (e.contact.closing_speed_mps - vc).abs() < 1e-9 * vc,
                "{e:?}"
            );
            assert_eq!(e.at_ns, now);
        }
        sigmas.push(f.estimate_at(ns(t)).unwrap().ttc_sigma_s);
    }
    // More samples of the same track: the contact time becomes more certain.
    assert!(sigmas[39] < 0.5 * sigmas[0], "{sigmas:?}");
}

/// The textbook filter: Bar-Shalom's constant-acceleration ("Wiener process acceleration")
/// model for (position, velocity, acceleration), mapped to (distance = −position, closing
/// speed, closing acceleration) by T = diag(−1, 1, 1); generic nalgebra products, gain from
/// the inverse, Joseph-form covariance update.
struct Textbook {
    x: Vector3<f64>,
    p: Matrix3<f64>,
    r: Matrix3<f64>,
    q: f64,
    gate: f64,
}

impl Textbook {
    fn f_and_q(&self, tau: f64) -> (Matrix3<f64>, Matrix3<f64>) {
        let fp = Matrix3::new(1.0, tau, tau * tau / 2.0, 0.0, 1.0, tau, 0.0, 0.0, 1.0);
        let (t2, t3, t4, t5) = (tau.powi(2), tau.powi(3), tau.powi(4), tau.powi(5));
        let qp = self.q
            * Matrix3::new(
                t5 / 20.0,
                t4 / 8.0,
                t3 / 6.0,
                t4 / 8.0,
                t3 / 3.0,
                t2 / 2.0,
                t3 / 6.0,
                t2 / 2.0,
                tau,
            );
        let t = Matrix3::from_diagonal(&Vector3::new(-1.0, 1.0, 1.0));
        (t * fp * t, t * qp * t.transpose())
    }

    /// Returns whether the sample was inside the gate.
    fn step(&mut self, tau: f64, z: Vector3<f64>) -> bool {
        let (f, q) = self.f_and_q(tau);
        let x = f * self.x;
        let p = f * self.p * f.transpose() + q;
        let s = p + self.r;
        let s_inv = s.try_inverse().unwrap();
        let y = z - x;
        if (y.transpose() * s_inv * y).x > self.gate {
            self.x = x;
            self.p = p;
            return false;
        }
        let k = p * s_inv;
        let i_k = Matrix3::identity() - k;
        self.x = x + k * y;
        self.p = i_k * p * i_k.transpose() + k * self.r * k.transpose();
        true
    }
}

#[test]
fn state_and_covariance_match_a_textbook_kalman_filter() {
    // The plain filter (the noise adaptation scales R; tested on its own below).
    let cfg = TrackConfig {
        noise_adaptation: 0.0,
        ..TrackConfig::default()
    };
    let mut f = TrackFilter::new(&cfg, 100.0);
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let ap = Approach {
        d0: 45.0,
        v0: 18.0,
        a: -2.0,
    };
    let mut t_ns = T0;
    let mut oracle: Option<Textbook> = None;
    let (mut outliers, mut updates) = (0, 0);
    for k in 0..60 {
        // Irregular sampling (5–40 ms), noise, and a gross distance error every 17th sample.
        let prev_ns = t_ns;
        t_ns += rng.gen_range(5..40) * MS + rng.gen_range(0..MS);
        let t = (t_ns - T0) as f64 * 1e-9;
        let jump = if k % 17 == 16 { 3.0 } else { 0.0 };
        let z = Vector3::new(
            f32_of(ap.d(t) + 0.1 * rng.gen_range(-1.0..1.0) + jump),
            f32_of(ap.v(t) + 0.2 * rng.gen_range(-1.0..1.0)),
            f32_of(ap.a + rng.gen_range(-1.0..1.0)),
        );
        let ev = f.update(&sample(t_ns, z.x, z.y, z.z, 1500.0, 200.0));
        let (state_ns, x, p) = f.state().unwrap();
        assert_eq!(state_ns, t_ns);
        let Some(o) = oracle.as_mut() else {
            assert_eq!(ev, TrackEvent::Started);
            let r = Matrix3::from_diagonal(&Vector3::new(
                cfg.distance_sigma_m.powi(2),
                cfg.closing_speed_sigma_mps.powi(2),
                cfg.accel_sigma_mps2.powi(2),
            ));
            assert_eq!((x, p), (z, r));
            oracle = Some(Textbook {
                x: z,
                p: r,
                r,
                q: cfg.jerk_density_m2ps5,
                gate: cfg.gate_chi2,
            });
            continue;
        };
        let inside = o.step((t_ns - prev_ns) as f64 * 1e-9, z);
        assert_eq!(
            ev,
            if inside {
                TrackEvent::Updated
            } else {
                TrackEvent::Outlier
            },
            "sample {k}"
        );
        outliers += usize::from(!inside);
        updates += usize::from(inside);
        for i in 0..3 {
            assert!(
                (x[i] - o.x[i]).abs() <= 1e-9 * (1.0 + o.x[i].abs()),
                "x {k}: {x} vs {}",
                o.x
            );
            for j in 0..3 {
                let tol = 1e-9 * (o.p[(i, i)] * o.p[(j, j)]).sqrt();
                assert!(
                    (p[(i, j)] - o.p[(i, j)]).abs() <= tol,
                    "P {k}: {p} vs {}",
                    o.p
                );
            }
        }
    }
    // The run exercised both branches.
    assert_eq!(outliers, 3, "each 3 m jump is gated out");
    assert!(updates > 50);
}

/// Standard normal draw (Box–Muller).
fn gauss(rng: &mut ChaCha8Rng) -> f64 {
    let u1: f64 = rng.gen_range(f64::MIN_POSITIVE..1.0);
    let u2: f64 = rng.gen();
    (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
}

#[test]
fn contact_sigma_matches_monte_carlo_over_the_state_distribution() {
    // A track from noisy samples; then the spread of the closed-form contact over 40 000
    // draws from N(x, P) against the filter's first-order σ.
    let ap = Approach {
        d0: 30.0,
        v0: 20.0,
        a: -3.0,
    };
    // A tracker whose acceleration is good to 0.2 m/s² and a calm track (q = 20), so the
    // draws stay in the regime where every one of them reaches us (the linearisation's).
    let cfg = TrackConfig {
        accel_sigma_mps2: 0.2,
        jerk_density_m2ps5: 20.0,
        ..TrackConfig::default()
    };
    let mut f = TrackFilter::new(&cfg, 100.0);
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    for k in 0..25 {
        let t = f64::from(k) * 0.02;
        let (d, v, a) = (
            ap.d(t) + 0.05 * gauss(&mut rng),
            ap.v(t) + 0.1 * gauss(&mut rng),
            ap.a + 0.2 * gauss(&mut rng),
        );
        f.update(&sample(ns(t), d, v, a, 1500.0, 200.0));
    }
    let (t_ns, x, p) = f.state().unwrap();
    // 30 ms latency: the estimate is for the cycle's time.
    let now = t_ns + 30 * MS;
    let e = f.estimate_at(now).unwrap();
    // The state at `now` (F x, F P Fᵀ + Q) by the textbook construction above.
    let tb = Textbook {
        x,
        p,
        r: Matrix3::zeros(),
        q: cfg.jerk_density_m2ps5,
        gate: f64::INFINITY,
    };
    let (fm, q) = tb.f_and_q(0.030);
    let (xm, pm) = (fm * x, fm * p * fm.transpose() + q);
    let l = pm.cholesky().expect("positive definite").l();
    let n = 40_000;
    let (mut st, mut st2, mut sv, mut sv2) = (0.0, 0.0, 0.0, 0.0);
    for _ in 0..n {
        let w = Vector3::new(gauss(&mut rng), gauss(&mut rng), gauss(&mut rng));
        let s = xm + l * w;
        let (tc, vc) = Approach {
            d0: s.x,
            v0: s.y,
            a: s.z,
        }
        .contact()
        .expect("every draw reaches us");
        st += tc;
        st2 += tc * tc;
        sv += vc;
        sv2 += vc * vc;
    }
    let sd = |s: f64, s2: f64| (s2 / n as f64 - (s / n as f64).powi(2)).sqrt();
    let (sd_t, sd_v) = (sd(st, st2), sd(sv, sv2));
    // 40 000 draws: the sample sd is within ±1.5 % of the true one at 4 standard errors; the
    // linearisation adds a little (P is small against the state).
    assert!(
        (e.ttc_sigma_s / sd_t - 1.0).abs() < 0.03,
        "{} vs {sd_t}",
        e.ttc_sigma_s
    );
    assert!(
        (e.closing_speed_sigma_mps / sd_v - 1.0).abs() < 0.03,
        "{} vs {sd_v}",
        e.closing_speed_sigma_mps
    );
}

#[test]
fn opponent_mass_is_the_weighted_mean_with_the_closed_form_sigma() {
    let ap = Approach {
        d0: 40.0,
        v0: 10.0,
        a: 0.0,
    };
    let masses = [1400.0, 1650.0, 1525.0, 1480.0, 1590.0];
    for rho in [0.0, 0.5, 1.0] {
        let cfg = TrackConfig {
            mass_sigma_correlation: rho,
            ..TrackConfig::default()
        };
        let mut f = TrackFilter::new(&cfg, 100.0);
        for (k, m) in masses.iter().enumerate() {
            let t = k as f64 * 0.02;
            f.update(&sample(ns(t), ap.d(t), ap.v(t), 0.0, *m, 300.0));
        }
        let e = f.estimate_at(ns(0.1)).unwrap();
        let n = masses.len() as f64;
        let mean = masses.iter().sum::<f64>() / n;
        // Var of the mean of n errors of σ² with pairwise correlation ρ.
        let sigma = 300.0 * (rho + (1.0 - rho) / n).sqrt();
        assert!((e.mass_kg - mean).abs() < 1e-9, "{e:?}");
        assert!((e.mass_sigma_kg - sigma).abs() < 1e-9, "ρ {rho}: {e:?}");
    }
    // Unequal σ, independent errors: inverse-variance weighting.
    let cfg = TrackConfig {
        mass_sigma_correlation: 0.0,
        ..TrackConfig::default()
    };
    let mut f = TrackFilter::new(&cfg, 100.0);
    let s = [(1000.0, 100.0), (2000.0, 200.0), (1600.0, 0.0)];
    for (k, (m, sg)) in s.iter().enumerate() {
        let t = k as f64 * 0.02;
        f.update(&sample(ns(t), ap.d(t), ap.v(t), 0.0, *m, *sg));
    }
    let e = f.estimate_at(ns(0.05)).unwrap();
    // A reported σ of 0 counts as 1 kg (it would otherwise outweigh everything forever).
    let w = [1e-4, 0.25e-4, 1.0];
    let mean = (1000.0 * w[0] + 2000.0 * w[1] + 1600.0 * w[2]) / w.iter().sum::<f64>();
    assert!((e.mass_kg - mean).abs() < 1e-6, "{e:?}");
    assert!((e.mass_sigma_kg - 1.0 / w.iter().sum::<f64>().sqrt()).abs() < 1e-9);
}

#[test]
fn non_finite_and_not_newer_samples_are_refused_and_change_nothing() {
    let mut f = TrackFilter::new(&TrackConfig::default(), 100.0);
    assert_eq!(
        f.update(&sample(ns(0.0), 30.0, 20.0, 0.0, 1500.0, 200.0)),
        TrackEvent::Started
    );
    assert_eq!(
        f.update(&sample(ns(0.02), 29.6, 20.0, 0.0, 1500.0, 200.0)),
        TrackEvent::Updated
    );
    let before = (f.state(), f.estimate_at(ns(0.05)));
    for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        for field in 0..5 {
            let mut v = [29.2, 20.0, 0.0, 1500.0, 200.0];
            v[field] = bad;
            let o = sample(ns(0.04), v[0], v[1], v[2], v[3], v[4]);
            assert_eq!(
                f.update(&o),
                TrackEvent::Refused(Refused::NonFinite),
                "field {field} = {bad}"
            );
        }
    }
    // Older than the track (out of order), and a repeat (a stuck sensor).
    for t in [0.01, 0.02] {
        assert_eq!(
            f.update(&sample(ns(t), 29.8, 20.0, 0.0, 1500.0, 200.0)),
            TrackEvent::Refused(Refused::NotNewer)
        );
    }
    assert_eq!((f.state(), f.estimate_at(ns(0.05))), before);
    // Without a track, a non-finite sample starts nothing.
    let mut g = TrackFilter::new(&TrackConfig::default(), 100.0);
    let o = sample(ns(0.0), f64::NAN, 20.0, 0.0, 1500.0, 200.0);
    assert_eq!(g.update(&o), TrackEvent::Refused(Refused::NonFinite));
    assert!(!g.tracking());
}

#[test]
fn outliers_are_not_trusted_and_a_persistent_change_restarts_the_track() {
    let cfg = TrackConfig::default();
    let mut f = TrackFilter::new(&cfg, 100.0);
    let ap = Approach {
        d0: 30.0,
        v0: 20.0,
        a: 0.0,
    };
    for k in 0..10 {
        let t = f64::from(k) * 0.02;
        f.update(&sample(ns(t), ap.d(t), ap.v(t), 0.0, 1500.0, 200.0));
    }
    let (t9, x9, _) = f.state().unwrap();
    // The object "jumps" 2 m closer: the track does not believe it, it only predicts.
    for k in 0..cfg.max_outliers {
        let t = f64::from(10 + k) * 0.02;
        let ev = f.update(&sample(ns(t), ap.d(t) - 2.0, ap.v(t), 0.0, 1500.0, 200.0));
        if k + 1 < cfg.max_outliers {
            assert_eq!(ev, TrackEvent::Outlier, "sample {k}");
            let (tn, x, _) = f.state().unwrap();
            let tau = (tn - t9) as f64 * 1e-9;
            // The prediction of a constant speed track: d − v τ (the track holds a = 0).
            assert!((x.x - (x9.x - x9.y * tau)).abs() < 1e-6, "{x} vs {x9}");
            let e = f.estimate_at(tn).unwrap();
            let truth_ttc = ap.d(t) / ap.v(t);
            assert!((e.contact.ttc_s - truth_ttc).abs() < 1e-3, "{e:?}");
        } else {
            // The same story three times in a row: the world changed; start again from it.
            assert_eq!(ev, TrackEvent::Started);
            let (_, x, _) = f.state().unwrap();
            assert!((x.x - f32_of(ap.d(t) - 2.0)).abs() < 1e-12);
        }
    }
}

#[test]
fn a_new_object_a_gap_or_the_end_of_the_track_starts_a_new_track() {
    let mut f = TrackFilter::new(&TrackConfig::default(), 100.0);
    let o = |t: f64| sample(ns(t), 30.0 - 20.0 * t, 20.0, 0.0, 1500.0, 200.0);
    assert_eq!(f.update(&o(0.0)), TrackEvent::Started);
    assert_eq!(f.update(&o(0.02)), TrackEvent::Updated);
    let mut other = o(0.04);
    other.object_id = 8;
    assert_eq!(f.update(&other), TrackEvent::Started);
    assert_eq!(f.update(&o(0.06)), TrackEvent::Started); // id 7 again: a new track too
    assert_eq!(f.update(&o(0.16)), TrackEvent::Updated); // 100 ms: still the same track
    assert_eq!(f.update(&o(0.2601)), TrackEvent::Started); // > 100 ms gap
    f.end();
    assert!(!f.tracking() && f.estimate_at(ns(0.3)).is_none());
    assert_eq!(f.update(&o(0.28)), TrackEvent::Started);
}

/// One noisy run of `ap` sampled every `period` with `latency`: the filtered and the
/// newest-sample (closed form from that sample alone) contact estimates at the cycle after the
/// last sample at least `lead_s` before contact: (filtered error of contact time and closing
/// speed and their normalised squares, raw errors — `None` when the raw sample, with its noisy
/// acceleration, says the object stops short).
fn noisy_run(
    ap: &Approach,
    noise: (f64, f64, f64),
    period_s: f64,
    latency_s: f64,
    lead_s: f64,
    rng: &mut ChaCha8Rng,
) -> ([f64; 4], Option<(f64, f64)>) {
    let (tc, vc) = ap.contact().unwrap();
    let cfg = TrackConfig {
        distance_sigma_m: noise.0,
        closing_speed_sigma_mps: noise.1,
        accel_sigma_mps2: noise.2,
        ..TrackConfig::default()
    };
    let mut f = TrackFilter::new(&cfg, 100.0);
    let mut t = 0.0;
    let mut last = None;
    while t < tc - lead_s {
        let z = (
            ap.d(t) + noise.0 * gauss(rng),
            ap.v(t) + noise.1 * gauss(rng),
            ap.a + noise.2 * gauss(rng),
        );
        f.update(&sample(ns(t), z.0, z.1, z.2, 1500.0, 200.0));
        last = Some((t, z));
        t += period_s;
    }
    let (ts, z) = last.unwrap();
    let now = ns(ts + latency_s);
    let e = f.estimate_at(now).expect("the filtered track reaches us");
    let ft = (e.at_ns - T0) as f64 * 1e-9 + e.contact.ttc_s - tc;
    let fv = e.contact.closing_speed_mps - vc;
    let raw = Approach {
        d0: z.0,
        v0: z.1,
        a: z.2,
    }
    .contact()
    .map(|(t, v)| (ts + t - tc, v - vc));
    (
        [
            ft,
            fv,
            (ft / e.ttc_sigma_s).powi(2),
            (fv / e.closing_speed_sigma_mps).powi(2),
        ],
        raw,
    )
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    /// Against noisy truth: for any approach and sensor of the bench's range, over 100 noise
    /// realizations the filtered contact time and closing speed at contact are more accurate
    /// (RMS over all realizations) than the newest sample's own closed form (RMS over the
    /// realizations in which it sees a contact at all: with a noisy acceleration it sometimes
    /// says the object stops short), and the filter's σ is not overconfident: the mean
    /// normalised squared error stays below 2 (1 for an exact σ). On these jerk-free
    /// approaches it is well below 1 — the filter's jerk density models manoeuvres the truth
    /// does not make, so its σ is conservative here; the matched-model test below checks the
    /// covariance itself.
    #[test]
    fn filtered_contact_beats_the_newest_sample_and_its_sigma_is_honest(
        d0 in 25.0..60.0f64,
        v0 in 10.0..35.0f64,
        a in -8.0..1.0f64,
        noise_d in 0.03..0.3f64,
        noise_v in 0.05..0.5f64,
        noise_a in 0.2..1.5f64,
        period_ms in 10u32..=20,
        latency_ms in 0u32..=50,
        seed in any::<u64>(),
    ) {
        let ap = Approach { d0, v0, a };
        let Some((tc, vc)) = ap.contact() else { return Ok(()); };
        // A collision, not a touch (≥ 5 m/s at contact), after at least 15 samples of the
        // track before the evaluation point.
        prop_assume!(vc >= 5.0 && tc > 0.15 + 15.0 * f64::from(period_ms) * 1e-3);
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let n = 100;
        let (mut filt, mut raw, mut raw_n) = ([0.0f64; 4], [0.0f64; 2], 0u32);
        for _ in 0..n {
            let (f, r) = noisy_run(
                &ap,
                (noise_d, noise_v, noise_a),
                f64::from(period_ms) * 1e-3,
                f64::from(latency_ms) * 1e-3,
                0.15,
                &mut rng,
            );
            for (s, x) in filt.iter_mut().zip([f[0] * f[0], f[1] * f[1], f[2], f[3]]) {
                *s += x / f64::from(n);
            }
            if let Some((t, v)) = r {
                raw[0] += t * t;
                raw[1] += v * v;
                raw_n += 1;
            }
        }
        let raw_rms = |s: f64| (s / f64::from(raw_n.max(1))).sqrt();
        prop_assert!(filt[0].sqrt() < raw_rms(raw[0]), "contact time RMS filtered {} raw {}", filt[0].sqrt(), raw_rms(raw[0]));
        prop_assert!(filt[1].sqrt() < raw_rms(raw[1]), "closing speed RMS filtered {} raw {}", filt[1].sqrt(), raw_rms(raw[1]));
        prop_assert!(filt[2] < 2.0, "normalised contact time error² {}", filt[2]);
        prop_assert!(filt[3] < 2.0, "normalised closing speed error² {}", filt[3]);
    }
}

/// Mean normalised state error x̃ᵀ P⁻¹ x̃ over 400 runs × 30 samples of a truth that *is*
/// the filter's model (white jerk of the filter's density, sampled exactly: x' = F x + w,
/// w ~ N(0, Q(τ)); measurements with noise `noise_factor` × the configured R), and the
/// samples gated out per run.
fn normalised_state_error(cfg: &TrackConfig, noise_factor: f64) -> (f64, f64) {
    let r = noise_factor
        * Vector3::new(
            cfg.distance_sigma_m,
            cfg.closing_speed_sigma_mps,
            cfg.accel_sigma_mps2,
        );
    let tb = Textbook {
        x: Vector3::zeros(),
        p: Matrix3::zeros(),
        r: Matrix3::zeros(),
        q: cfg.jerk_density_m2ps5,
        gate: f64::INFINITY,
    };
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let (mut sum, mut n, mut outliers) = (0.0, 0u32, 0u32);
    let runs = 400;
    for _ in 0..runs {
        let mut f = TrackFilter::new(cfg, 100.0);
        let mut x = Vector3::new(60.0, 25.0, -2.0);
        let mut t_ns = T0;
        for k in 0..30 {
            if k > 0 {
                let tau_ns = rng.gen_range(10..=20) * MS;
                t_ns += tau_ns;
                let (fm, q) = tb.f_and_q(tau_ns as f64 * 1e-9);
                let l = q.cholesky().expect("Q positive definite").l();
                let w = Vector3::new(gauss(&mut rng), gauss(&mut rng), gauss(&mut rng));
                x = fm * x + l * w;
            }
            let z = x + r.component_mul(&Vector3::new(
                gauss(&mut rng),
                gauss(&mut rng),
                gauss(&mut rng),
            ));
            // The f32 rounding of the record is far below the noise.
            if f.update(&sample(t_ns, z.x, z.y, z.z, 1500.0, 200.0)) == TrackEvent::Outlier {
                outliers += 1;
            }
            // The first samples of a run are the adaptation's transient; count the rest.
            if k >= 10 {
                let (_, xe, p) = f.state().unwrap();
                let e = xe - x;
                let v = (e.transpose() * p.try_inverse().unwrap() * e).x;
                sum += v;
                n += 1;
            }
        }
    }
    (sum / f64::from(n), f64::from(outliers) / f64::from(runs))
}

/// Matched model: x̃ᵀ P⁻¹ x̃ is χ² with 3 degrees of freedom, mean 3; the mean over the
/// 8 000 counted samples (runs independent, samples within a run correlated) must be within
/// 3 ± 0.3. A filter that mis-propagated or mis-updated its covariance fails this.
#[test]
fn state_error_is_consistent_with_the_covariance_under_the_matched_model() {
    let cfg = TrackConfig {
        gate_chi2: 1e6, // no gating, no adaptation: the consistency of the plain filter
        noise_adaptation: 0.0,
        ..TrackConfig::default()
    };
    let (mean, _) = normalised_state_error(&cfg, 1.0);
    assert!(
        (mean - 3.0).abs() < 0.3,
        "mean normalised state error² {mean} (χ²₃: 3)"
    );
}

/// A sensor five times noisier than configured (rain): without the noise adaptation the
/// covariance is far too small (measured: normalised error 71, 18 of 30 good samples gated
/// out per run); with it (the default) the error is near the covariance again and only the
/// first samples of a track are gated. Measured 5.2 (σ ≈ 1.3× too small) with the per-channel
/// scales, against 3.6 with one scale for all three channels: three one-sample estimates
/// fluctuate more than one; the per-channel scales are kept because a single biased channel
/// (a radar's Doppler speed 5 m/s low) otherwise drags the whole track (module docs), so
/// < 6 is asserted, not 3 ± 0.6. For the sensor as specified the adaptation makes the
/// covariance somewhat conservative (λ ≥ 1 fluctuates above 1).
#[test]
fn noise_adaptation_keeps_the_covariance_honest_for_a_noisier_sensor() {
    let plain = TrackConfig {
        noise_adaptation: 0.0,
        ..TrackConfig::default()
    };
    let (mean_plain, outliers_plain) = normalised_state_error(&plain, 5.0);
    let (mean, outliers) = normalised_state_error(&TrackConfig::default(), 5.0);
    assert!(mean_plain > 20.0, "plain filter: {mean_plain}");
    assert!(
        outliers_plain > 3.0,
        "plain filter gates good samples: {outliers_plain}/run"
    );
    assert!((2.4..6.0).contains(&mean), "adapted: {mean} (χ²₃: 3)");
    // The first samples of a track, before λ has grown, are still gated (measured 2.2 per 30
    // with the per-channel scales, 1.4 with one scale).
    assert!(outliers < 3.0, "adapted: {outliers} outliers/run");
    // And for the sensor as specified the adaptation costs little.
    let (mean_nominal, _) = normalised_state_error(&TrackConfig::default(), 1.0);
    assert!(
        (2.3..=3.3).contains(&mean_nominal),
        "nominal, adapted: {mean_nominal}"
    );
}
