//! The track filter: what the object samples say together, not what the newest one says alone.
//!
//! A Kalman filter over x = (relative distance d, closing speed v, closing acceleration a) with
//! a constant-acceleration motion and white jerk as process noise (the textbook "Wiener
//! process acceleration" model), in nalgebra fixed-size types (no allocation, `no_std`):
//!
//! ```text
//!   d' = −v,  v' = a,  a' = w (jerk, spectral density q)
//!   F(τ) = [1 −τ −τ²/2; 0 1 τ; 0 0 1]
//!   Q(τ) = q [τ⁵/20 −τ⁴/8 −τ³/6; −τ⁴/8 τ³/3 τ²/2; −τ³/6 τ²/2 τ]   (signs: d falls as v grows)
//!   z = (d, v, a) of a sample, H = I, R = diag(σ_d², σ_v², σ_a²)
//! ```
//!
//! **Time.** The state lives at the *measurement* time of the newest sample it took (the
//! sample's timestamp, not its arrival); a new sample is predicted to its own timestamp before
//! the update, and [`TrackFilter::estimate_at`] predicts to the cycle's time, so latency moves
//! nothing. A sample not newer than the state (out of order, or a stuck sensor repeating
//! itself) is refused, as is any non-finite value.
//!
//! **Outliers.** The innovation y = z − x⁻ is gated on its Mahalanobis distance yᵀS⁻¹y
//! (S = P⁻ + R, χ² with 3 degrees of freedom): a sample beyond the gate is rejected and
//! counted, the state is only predicted. After `max_outliers` rejections in a row the
//! track is restarted from the newest sample: then the world, not the samples, changed (a
//! manoeuvre the motion model did not expect).
//!
//! **Noise adaptation.** The configured R is the sensor's specification; in rain or fog it is
//! noisier, and a filter that trusts R then gates good samples out and reports too small a σ.
//! The filter keeps a scale λᵢ ≥ 1 of R **per channel** (distance, closing speed, closing
//! acceleration; covariance matching): the innovation y = z − x⁻ has E[yᵢ²] = P⁻ᵢᵢ + λᵢRᵢᵢ, so
//! λ̂ᵢ = (yᵢ² − P⁻ᵢᵢ)/Rᵢᵢ is an unbiased one-sample estimate, averaged as
//! λᵢ ← (1 − α)λᵢ + α·λ̂ᵢ (α = `noise_adaptation`, 0 = off), at least 1 (never more trust than
//! the specification), at most 100. Per channel, because the channels go wrong differently: a
//! radar whose Doppler speed is biased (5 m/s low, say) contradicts its own range track; one
//! scale for all three would stop trusting the range as much as the speed, and the track
//! would follow the biased speed (the contact predicted 100 ms late in `speed-underestimated`);
//! per channel the speed's λ grows and the range keeps the track. When λ changes, the state's
//! covariance scales by the ratio of the scales' sums (it came from samples whose noise was
//! misjudged alike; without this, a track started in bad weather keeps an overconfident
//! covariance and corrects too slowly). The gate then uses the updated λ. Each λ̂ᵢ is clipped
//! to [0, λᵢ·gate/3], so one wild sample raises λᵢ by at most a factor 1 + α(gate/3 − 1),
//! while a sensor ten times noisier than specified — whose samples all start outside the gate
//! — is recognised within a few samples instead of being rejected for ever. Outliers count for
//! λ (clipped) but never move the state. λ belongs to the sensor, not to a track: a new track
//! keeps it.
//!
//! **New track.** The state restarts from the sample (x = z, P = R) on the first sample, on
//! a new tracker object id, after a gap longer than the object timeout, after a "no object"
//! record ([`TrackFilter::end`]) and after `max_outliers` outliers in a row.
//!
//! **Opponent mass.** Fused over the track's samples with the reported σ as weight
//! (information-weighted mean m̂ = Σ(mᵢ/σᵢ²)/Σ(1/σᵢ²)). Its σ does *not* shrink as 1/√n:
//! the reported σ is mostly a systematic error (an unknown payload stays unknown however
//! often it is estimated), so a share ρ (`mass_sigma_correlation`) of each sample's variance
//! is taken as common to all samples: σ̂² = (ρ·n + 1 − ρ) / Σ(1/σᵢ²) — exact for equal σᵢ
//! (var of the mean of n errors with correlation ρ), σ̂ = σ for ρ = 1, σ/√n for ρ = 0.
//!
//! **Outputs** ([`TrackEstimate`]): time to contact and closing speed at contact under the
//! constant-acceleration extrapolation of the state at the cycle's time
//! ([`super::time_to_contact`]), each with its σ from the first-order propagation of P:
//! with t the time to contact and v_c the closing speed at contact,
//! ∂t/∂(d, v, a) = (1, −t, −t²/2)/v_c and ∂v_c/∂(d, v, a) = (a, v, d)/v_c.

use nalgebra::{Matrix3, Vector3};

use super::{time_to_contact, Contact};
use crate::config::TrackConfig;
use crate::settings::ms_to_ns;
use crate::signals::ObjectState;

/// Smallest mass σ a sample is weighted with, kg (a reported σ of 0 would otherwise outweigh
/// every other sample forever).
const MIN_MASS_SIGMA_KG: f64 = 1.0;

/// Why a sample was not taken.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Refused {
    /// A value is NaN or infinite.
    NonFinite,
    /// Not newer than the newest sample taken (out of order, or a repeat).
    NotNewer,
}

/// What a sample did to the track.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TrackEvent {
    /// The track (re)started from this sample.
    Started,
    /// The sample updated the track.
    Updated,
    /// The sample was beyond the gate: rejected, the track only predicted.
    Outlier,
    /// The sample was refused (the track is unchanged).
    Refused(Refused),
}

/// The track's view of the coming contact at one instant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrackEstimate {
    /// Time the estimate is for (the cycle's time, or the newest sample's if that is later), ns.
    pub at_ns: u64,
    /// Predicted contact: time from `at_ns` and closing speed at contact.
    pub contact: Contact,
    /// σ of the time to contact, s.
    pub ttc_sigma_s: f64,
    /// σ of the closing speed at contact, m/s.
    pub closing_speed_sigma_mps: f64,
    /// Fused opponent mass, kg.
    pub mass_kg: f64,
    /// σ of the fused opponent mass, kg.
    pub mass_sigma_kg: f64,
    /// Distance to the object at `at_ns`, m.
    pub distance_m: f64,
    /// Closing speed at `at_ns`, m/s.
    pub closing_speed_mps: f64,
}

/// Information-weighted opponent mass (see the module docs).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
struct MassFusion {
    /// Σ 1/σᵢ², 1/kg².
    info: f64,
    /// Σ mᵢ/σᵢ², 1/kg.
    weighted: f64,
    /// Samples fused.
    n: u32,
}

impl MassFusion {
    fn add(&mut self, m_kg: f64, sigma_kg: f64) {
        let s = sigma_kg.max(MIN_MASS_SIGMA_KG);
        let w = 1.0 / (s * s);
        self.info += w;
        self.weighted += w * m_kg;
        self.n = self.n.saturating_add(1);
    }

    fn estimate(&self, rho: f64) -> (f64, f64) {
        let var = (rho * f64::from(self.n) + 1.0 - rho) / self.info;
        (self.weighted / self.info, libm::sqrt(var))
    }
}

/// The filter state of one track.
#[derive(Debug, Clone, Copy, PartialEq)]
struct State {
    object_id: u32,
    /// Measurement time of the newest sample taken (or rejected as outlier), ns.
    t_ns: u64,
    x: Vector3<f64>,
    p: Matrix3<f64>,
    outliers_in_row: u32,
    mass: MassFusion,
}

/// The track filter (see the module docs). Built once, allocation-free, `Copy`-sized.
#[derive(Debug, Clone, PartialEq)]
pub struct TrackFilter {
    q: f64,
    gate_chi2: f64,
    max_outliers: u32,
    alpha: f64,
    /// Per-channel scale of R learnt from the innovations (each ≥ 1; see the module docs).
    lambda: Vector3<f64>,
    /// The diagonal of R.
    r_diag: Vector3<f64>,
    gap_ns: u64,
    rho: f64,
    state: Option<State>,
}

/// R: the specified variances `r_diag` scaled per channel by the learnt `lambda`.
fn scaled_r(r_diag: &Vector3<f64>, lambda: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::from_diagonal(&r_diag.component_mul(lambda))
}

/// F(τ) x of the module docs.
#[inline(always)]
fn predict_state(x: &Vector3<f64>, tau: f64) -> Vector3<f64> {
    let h = 0.5 * tau * tau;
    Vector3::new(x.x - tau * x.y - h * x.z, x.y + tau * x.z, x.z)
}

/// F(τ) P F(τ)ᵀ + Q(τ) for a symmetric P, written out on its six distinct entries (F is
/// unit upper triangular: half the products of a general 3×3 product are zero, and the
/// generic product is not inlined into the cycle).
#[inline(always)]
fn predict_covariance(p: &Matrix3<f64>, tau: f64, q: f64) -> Matrix3<f64> {
    let (dd, dv, da, vv, va, aa) = (p.m11, p.m12, p.m13, p.m22, p.m23, p.m33);
    let t = tau;
    let h = 0.5 * t * t;
    // Rows of F P (the third is P's), then (F P) Fᵀ.
    let (r0d, r0v, r0a) = (
        dd - t * dv - h * da,
        dv - t * vv - h * va,
        da - t * va - h * aa,
    );
    let (r1v, r1a) = (vv + t * va, va + t * aa);
    let p_dd = r0d - t * r0v - h * r0a;
    let p_dv = r0v + t * r0a;
    let p_da = r0a;
    let p_vv = r1v + t * r1a;
    let p_va = r1a;
    let q = process_noise(q, tau);
    Matrix3::new(
        p_dd + q.m11,
        p_dv + q.m12,
        p_da + q.m13,
        p_dv + q.m12,
        p_vv + q.m22,
        p_va + q.m23,
        p_da + q.m13,
        p_va + q.m23,
        aa + q.m33,
    )
}

/// Q(τ) of the module docs for jerk density `q`.
#[inline(always)]
fn process_noise(q: f64, tau: f64) -> Matrix3<f64> {
    let q1 = q * tau;
    let q2 = q1 * tau;
    let q3 = q2 * tau;
    let (dd, dv, da) = (0.05 * q3 * tau * tau, -0.125 * q3 * tau, -q3 * (1.0 / 6.0));
    let (vv, va, aa) = (q3 * (1.0 / 3.0), 0.5 * q2, q1);
    Matrix3::new(dd, dv, da, dv, vv, va, da, va, aa)
}

/// A B for 3×3 matrices, written out (the generic product is not inlined into the cycle).
#[inline(always)]
fn product(a: &Matrix3<f64>, b: &Matrix3<f64>) -> Matrix3<f64> {
    let e =
        |i: usize, j: usize| a[(i, 0)] * b[(0, j)] + a[(i, 1)] * b[(1, j)] + a[(i, 2)] * b[(2, j)];
    Matrix3::new(
        e(0, 0),
        e(0, 1),
        e(0, 2),
        e(1, 0),
        e(1, 1),
        e(1, 2),
        e(2, 0),
        e(2, 1),
        e(2, 2),
    )
}

/// Whether every value is finite: a NaN or an infinity anywhere makes the sum non-finite
/// (one check instead of one per value; finite values summing past f64::MAX also count as
/// not finite, which only restarts a track that is far outside any physics anyway).
#[inline(always)]
fn all_finite<const N: usize>(values: [f64; N]) -> bool {
    let mut sum = 0.0;
    for v in values {
        sum += v;
    }
    sum.is_finite()
}

/// A v for a 3×3 matrix, written out.
#[inline(always)]
fn apply(a: &Matrix3<f64>, v: &Vector3<f64>) -> Vector3<f64> {
    Vector3::new(
        a.m11 * v.x + a.m12 * v.y + a.m13 * v.z,
        a.m21 * v.x + a.m22 * v.y + a.m23 * v.z,
        a.m31 * v.x + a.m32 * v.y + a.m33 * v.z,
    )
}

/// gᵀ P g for a symmetric P.
#[inline(always)]
fn quadratic_form(p: &Matrix3<f64>, g: &Vector3<f64>) -> f64 {
    let (x, y, z) = (g.x, g.y, g.z);
    p.m11 * x * x
        + p.m22 * y * y
        + p.m33 * z * z
        + 2.0 * (p.m12 * x * y + p.m13 * x * z + p.m23 * y * z)
}

/// The inverse of a symmetric positive definite 3×3 matrix (adjugate over determinant);
/// `None` if it is singular or not finite.
#[inline(always)]
fn symmetric_inverse(s: &Matrix3<f64>) -> Option<Matrix3<f64>> {
    let (a, b, c, d, e, f) = (s.m11, s.m12, s.m13, s.m22, s.m23, s.m33);
    let (i11, i12, i13) = (d * f - e * e, c * e - b * f, b * e - c * d);
    let det = a * i11 + b * i12 + c * i13;
    if !(det.is_finite() && det > 0.0) {
        return None;
    }
    let r = 1.0 / det;
    let (i22, i23, i33) = (a * f - c * c, b * c - a * e, a * d - b * b);
    Some(Matrix3::new(
        i11 * r,
        i12 * r,
        i13 * r,
        i12 * r,
        i22 * r,
        i23 * r,
        i13 * r,
        i23 * r,
        i33 * r,
    ))
}

/// K P for the gain K = P S⁻¹ of a symmetric P: P S⁻¹ P is symmetric, so only one triangle
/// is computed and mirrored (column j of P is its row j).
#[inline(always)]
fn symmetric_product(k: &Matrix3<f64>, p: &Matrix3<f64>) -> Matrix3<f64> {
    let e =
        |i: usize, j: usize| k[(i, 0)] * p[(0, j)] + k[(i, 1)] * p[(1, j)] + k[(i, 2)] * p[(2, j)];
    let (m11, m21, m31, m22, m32, m33) = (e(0, 0), e(1, 0), e(2, 0), e(1, 1), e(2, 1), e(2, 2));
    Matrix3::new(m11, m21, m31, m21, m22, m32, m31, m32, m33)
}

impl TrackFilter {
    /// A filter with no track yet. `object_timeout_ms`: a gap longer than this between two
    /// samples restarts the track (the same limit after which the ECU calls the object stale).
    pub fn new(cfg: &TrackConfig, object_timeout_ms: f64) -> Self {
        let r_diag = Vector3::new(
            cfg.distance_sigma_m * cfg.distance_sigma_m,
            cfg.closing_speed_sigma_mps * cfg.closing_speed_sigma_mps,
            cfg.accel_sigma_mps2 * cfg.accel_sigma_mps2,
        );
        Self {
            q: cfg.jerk_density_m2ps5,
            gate_chi2: cfg.gate_chi2,
            max_outliers: cfg.max_outliers.max(1),
            alpha: cfg.noise_adaptation.clamp(0.0, 1.0),
            lambda: Vector3::new(1.0, 1.0, 1.0),
            r_diag,
            gap_ns: ms_to_ns(object_timeout_ms),
            rho: cfg.mass_sigma_correlation.clamp(0.0, 1.0),
            state: None,
        }
    }

    /// Whether a track is held.
    pub fn tracking(&self) -> bool {
        self.state.is_some()
    }

    /// The track ended (the sensor reports no object): the next sample starts a new one.
    pub fn end(&mut self) {
        self.state = None;
    }

    /// The largest of the per-channel measurement-noise scales λᵢ learnt so far (1: the
    /// sensor is as specified).
    pub fn noise_scale(&self) -> f64 {
        self.lambda.x.max(self.lambda.y).max(self.lambda.z)
    }

    /// The state (d m, v m/s, a m/s²) and its covariance at the newest sample's time.
    pub fn state(&self) -> Option<(u64, Vector3<f64>, Matrix3<f64>)> {
        self.state.map(|s| (s.t_ns, s.x, s.p))
    }

    fn start(&mut self, o: &ObjectState, z: Vector3<f64>, m: f64, sigma: f64) -> TrackEvent {
        let mut mass = MassFusion::default();
        mass.add(m, sigma);
        self.state = Some(State {
            object_id: o.object_id,
            t_ns: o.timestamp_ns,
            x: z,
            p: scaled_r(&self.r_diag, &self.lambda),
            outliers_in_row: 0,
            mass,
        });
        TrackEvent::Started
    }

    /// Takes one object sample (already checked for plausibility by the input monitor; the
    /// filter refuses non-finite values itself all the same).
    pub fn update(&mut self, o: &ObjectState) -> TrackEvent {
        let z = Vector3::new(
            f64::from(o.distance_m),
            f64::from(o.closing_speed_mps),
            f64::from(o.relative_accel_mps2),
        );
        let (m, sigma) = (
            f64::from(o.opponent_mass_kg),
            f64::from(o.opponent_mass_sigma_kg),
        );
        if !all_finite([z.x, z.y, z.z, m, sigma]) {
            return TrackEvent::Refused(Refused::NonFinite);
        }
        let Some(s) = self.state.as_mut() else {
            return self.start(o, z, m, sigma);
        };
        if o.object_id != s.object_id || o.timestamp_ns > s.t_ns.saturating_add(self.gap_ns) {
            return self.start(o, z, m, sigma);
        }
        if o.timestamp_ns <= s.t_ns {
            return TrackEvent::Refused(Refused::NotNewer);
        }
        let tau = (o.timestamp_ns - s.t_ns) as f64 * 1.0e-9;
        let x_pred = predict_state(&s.x, tau);
        let p_pred = predict_covariance(&s.p, tau, self.q);
        let y = z - x_pred;
        // Noise adaptation (module docs), per channel: E[yᵢ²] = P⁻ᵢᵢ + λᵢRᵢᵢ, so each sample
        // gives an unbiased estimate of λᵢ; one sample moves λᵢ by at most a factor
        // 1 + α(gate/3 − 1).
        let r = &self.r_diag;
        let (gate, alpha) = (self.gate_chi2, self.alpha);
        // max/min, not clamp: a NaN (never from finite inputs) becomes 1, not NaN.
        #[allow(clippy::manual_clamp)]
        let adapt = |l: f64, y: f64, p: f64, r: f64| {
            let seen = ((y * y - p) / r).max(0.0).min(l * gate / 3.0);
            ((1.0 - alpha) * l + alpha * seen).max(1.0).min(100.0)
        };
        let lambda = Vector3::new(
            adapt(self.lambda.x, y.x, p_pred.m11, r.x),
            adapt(self.lambda.y, y.y, p_pred.m22, r.y),
            adapt(self.lambda.z, y.z, p_pred.m33, r.z),
        );
        // The state's covariance came from samples whose noise was misjudged alike: it scales
        // with the scales' sum.
        let mut p_pred = p_pred;
        if lambda != self.lambda {
            p_pred *= lambda.sum() / self.lambda.sum();
            self.lambda = lambda;
        }
        let Some(s_inv) = symmetric_inverse(&(p_pred + scaled_r(&self.r_diag, &self.lambda)))
        else {
            return self.start(o, z, m, sigma);
        };
        let d2 = quadratic_form(&s_inv, &y);
        if !(d2 <= self.gate_chi2) {
            s.outliers_in_row += 1;
            if s.outliers_in_row >= self.max_outliers {
                return self.start(o, z, m, sigma);
            }
            // Not trusted: the track moves on by its own prediction.
            s.t_ns = o.timestamp_ns;
            s.x = x_pred;
            s.p = p_pred;
            return TrackEvent::Outlier;
        }
        let k = product(&p_pred, &s_inv);
        let x = x_pred + apply(&k, &y);
        // P − K P⁻ is symmetric in exact arithmetic; computing one triangle keeps it exactly so.
        let p = p_pred - symmetric_product(&k, &p_pred);
        let sym = [p.m11, p.m12, p.m13, p.m22, p.m23, p.m33]; // P is symmetric by construction
        if !all_finite([
            x.x, x.y, x.z, sym[0], sym[1], sym[2], sym[3], sym[4], sym[5],
        ]) {
            return self.start(o, z, m, sigma);
        }
        s.t_ns = o.timestamp_ns;
        s.x = x;
        s.p = p;
        s.outliers_in_row = 0;
        s.mass.add(m, sigma);
        TrackEvent::Updated
    }

    /// The contact estimate at `now_ns` (the state predicted from its sample's time; a sample
    /// stamped after `now_ns` is evaluated at its own time). `None`: no track, or the track
    /// does not reach us (receding, stops short).
    pub fn estimate_at(&self, now_ns: u64) -> Option<TrackEstimate> {
        let s = self.state.as_ref()?;
        let at_ns = now_ns.max(s.t_ns);
        let tau = (at_ns - s.t_ns) as f64 * 1.0e-9;
        let x = predict_state(&s.x, tau);
        let contact = time_to_contact(x.x, x.y, x.z)?;
        let (t, vc) = (contact.ttc_s, contact.closing_speed_mps);
        let inv_vc = 1.0 / vc;
        let j_t = Vector3::new(inv_vc, -t * inv_vc, -0.5 * t * t * inv_vc);
        let j_v = Vector3::new(x.z * inv_vc, x.y * inv_vc, x.x * inv_vc);
        // Jᵀ (F P Fᵀ + Q) J = (Fᵀ J)ᵀ P (Fᵀ J) + Jᵀ Q J: no propagated matrix needed.
        let q = process_noise(self.q, tau);
        let var = |j: &Vector3<f64>| {
            let h = 0.5 * tau * tau;
            let g = Vector3::new(j.x, j.y - tau * j.x, j.z + tau * j.y - h * j.x);
            quadratic_form(&s.p, &g) + quadratic_form(&q, j)
        };
        // v_c = 0 (the track barely reaches us) makes the σ infinite, not NaN.
        let sd = |var: f64| {
            if var.is_nan() {
                f64::INFINITY
            } else {
                libm::sqrt(var.max(0.0))
            }
        };
        let (mass_kg, mass_sigma_kg) = s.mass.estimate(self.rho);
        Some(TrackEstimate {
            at_ns,
            contact,
            ttc_sigma_s: sd(var(&j_t)),
            closing_speed_sigma_mps: sd(var(&j_v)),
            mass_kg,
            mass_sigma_kg,
            distance_m: x.x,
            closing_speed_mps: x.y,
        })
    }
}
