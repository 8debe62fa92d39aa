//! Two-mass collision model with one combined non-linear crush spring.
//!
//! ```text
//!   μ x'' = −F(x),   x = relative deflection (closing positive), μ = m_ego m_opp/(m_ego+m_opp)
//!   loading  (x' > 0): F = c_def(x), the series combination of both fronts
//!   unloading (x' ≤ 0): straight line from the reversal point (x_r, F_r) to (x_r − δ, 0),
//!                       δ = μ (e v₀)² / F_r  ⇒ stiffness k_u = F_r / δ
//! ```
//! The unloading slope is derived from the restitution coefficient *at the reversal point*:
//! the elastic energy stored under the unloading line, ½ F_r δ, is exactly the rebound kinetic
//! energy ½ μ (e v₀)², so the separation speed is e·v₀ exactly. For a linear load curve k this
//! gives k_u = k/e², i.e. the bilinear oracle e = √(k/k_u).
//!
//! Integration: loading uses velocity Verlet at the fixed step (symplectic, 2nd order, one
//! force evaluation per step with a segment cursor); the reversal instant is located inside
//! its step by linear interpolation of the closing speed; the unloading phase is a linear
//! oscillator and is evaluated in closed form, so restitution, momentum and Δv are exact.
//!
//! Sign conventions of the pulse (SAE J211 vehicle axes, x forward, per vehicle): acceleration
//! is negative while the vehicle is decelerated by the crash; velocity is the change of the
//! vehicle's own forward velocity since first contact (0 → −Δv); crush is positive.
//! Peak and mean values in [`VehicleResult`] are magnitudes (positive).
//!
//! Mean deceleration definition: a_mean = Δv / contact duration, where contact lasts from first
//! contact until the contact force returns to zero at separation. Because the contact force
//! never changes sign this equals the time-average of |a| over the contact phase.

use crate::{defaults, stiffness::CombinedSpring, PhysicsError};

/// Inputs of one collision prediction.
#[derive(Clone, Copy, Debug)]
pub struct CollisionInput<'a> {
    /// Combined crush spring (see [`CombinedSpring::series`]); precompute it once per class pair.
    pub spring: &'a CombinedSpring,
    /// Ego vehicle mass [kg].
    pub ego_mass_kg: f64,
    /// Opponent mass [kg]; `f64::INFINITY` models a rigid barrier.
    pub opp_mass_kg: f64,
    /// Closing speed at first contact [m/s] (sum of both speeds in a head-on crash).
    pub closing_speed_mps: f64,
    /// Coefficient of restitution 0..=1.
    pub restitution: f64,
    /// Fixed integration and sampling step [s].
    pub step_s: f64,
    /// Length of the pulse to write [s] (the contact phase is always simulated to its end).
    pub duration_s: f64,
}

impl<'a> CollisionInput<'a> {
    /// Input with the defaults of [`crate::defaults`] (e = 0.1, 0.1 ms step, 150 ms pulse).
    pub fn with_defaults(
        spring: &'a CombinedSpring,
        ego_mass_kg: f64,
        opp_mass_kg: f64,
        closing_speed_mps: f64,
    ) -> Self {
        CollisionInput {
            spring,
            ego_mass_kg,
            opp_mass_kg,
            closing_speed_mps,
            restitution: defaults::RESTITUTION,
            step_s: defaults::STEP_S,
            duration_s: defaults::PULSE_DURATION_S,
        }
    }
}

/// Per-vehicle result of a collision.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct VehicleResult {
    /// Maximum dynamic crush of this vehicle's front [m].
    pub crush_m: f64,
    /// Peak deceleration magnitude [m/s²] (at the reversal point, where the force peaks).
    pub a_max_mps2: f64,
    /// Mean deceleration magnitude Δv / contact duration [m/s²].
    pub a_mean_mps2: f64,
    /// Velocity change magnitude over the crash [m/s].
    pub delta_v_mps: f64,
}

/// Summary of one collision prediction.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CollisionSummary {
    /// Ego vehicle.
    pub vehicle: VehicleResult,
    /// Opponent (zero accelerations for a rigid barrier).
    pub opponent: VehicleResult,
    /// First contact to separation [s].
    pub contact_duration_s: f64,
    /// Instant of maximum deflection [s].
    pub reversal_time_s: f64,
    /// Maximum relative deflection (sum of both crushes) [m].
    pub max_deflection_m: f64,
    /// Peak contact force [N].
    pub peak_force_n: f64,
    /// Unloading stiffness derived from e at the reversal point [N/m] (∞ for e = 0).
    pub unloading_stiffness_n_per_m: f64,
    /// Relative separation speed [m/s] (= e · closing speed).
    pub separation_speed_mps: f64,
    /// Energy dissipated in the crush zones [J].
    pub absorbed_energy_j: f64,
    /// Number of pulse samples written (sample k at time k · step).
    pub samples_written: usize,
}

impl VehicleResult {
    /// All zero (no collision).
    pub const ZERO: VehicleResult = VehicleResult {
        crush_m: 0.0,
        a_max_mps2: 0.0,
        a_mean_mps2: 0.0,
        delta_v_mps: 0.0,
    };
}

impl CollisionSummary {
    /// All zero (no collision) — `Default` as a const, for statics and const constructors.
    pub const ZERO: CollisionSummary = CollisionSummary {
        vehicle: VehicleResult::ZERO,
        opponent: VehicleResult::ZERO,
        contact_duration_s: 0.0,
        reversal_time_s: 0.0,
        max_deflection_m: 0.0,
        peak_force_n: 0.0,
        unloading_stiffness_n_per_m: 0.0,
        separation_speed_mps: 0.0,
        absorbed_energy_j: 0.0,
        samples_written: 0,
    };
}

/// Caller-owned, fixed-capacity storage of both compartment pulses (structure of arrays so that
/// each channel is a plain slice, e.g. for the occupant model or the accelerometer feed).
#[derive(Clone, Debug)]
pub struct PulseBuffer<const N: usize> {
    step_s: f64,
    len: usize,
    ego_accel_mps2: [f64; N],
    ego_vel_mps: [f64; N],
    ego_crush_m: [f64; N],
    opp_accel_mps2: [f64; N],
    opp_vel_mps: [f64; N],
    opp_crush_m: [f64; N],
}

/// Pulse buffer for the default 150 ms at 0.1 ms (2048 samples, ~98 kB: keep it static or boxed
/// on small stacks).
pub type DefaultPulseBuffer = PulseBuffer<{ defaults::PULSE_CAPACITY }>;

impl<const N: usize> Default for PulseBuffer<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> PulseBuffer<N> {
    /// Empty buffer.
    pub const fn new() -> Self {
        PulseBuffer {
            step_s: 0.0,
            len: 0,
            ego_accel_mps2: [0.0; N],
            ego_vel_mps: [0.0; N],
            ego_crush_m: [0.0; N],
            opp_accel_mps2: [0.0; N],
            opp_vel_mps: [0.0; N],
            opp_crush_m: [0.0; N],
        }
    }
    /// Sample capacity.
    pub const fn capacity(&self) -> usize {
        N
    }
    /// Maps a pulse solved along a collision's normal onto the ego's x axis, `axis_cos` being
    /// the cosine between them (`crash_mode::Engaged::axis_cos`): the ego's acceleration and
    /// velocity change times it, its crush along x divided by it. 1 leaves the pulse as it is;
    /// anything outside (0, 1] is ignored.
    pub fn project_ego_onto_axis(&mut self, axis_cos: f64) {
        if !(axis_cos > 0.0 && axis_cos < 1.0) {
            return;
        }
        let n = self.len();
        for k in 0..n {
            self.ego_accel_mps2[k] *= axis_cos;
            self.ego_vel_mps[k] *= axis_cos;
            self.ego_crush_m[k] /= axis_cos;
        }
    }
    /// Samples written by the last simulation.
    pub fn len(&self) -> usize {
        self.len.min(N)
    }
    /// True when nothing has been simulated.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }
    /// Sampling step [s].
    pub fn step_s(&self) -> f64 {
        self.step_s
    }
    /// Ego compartment acceleration [m/s²], sample k at k · step.
    pub fn ego_accel_mps2(&self) -> &[f64] {
        &self.ego_accel_mps2[..self.len()]
    }
    /// Ego velocity change since contact [m/s].
    pub fn ego_vel_mps(&self) -> &[f64] {
        &self.ego_vel_mps[..self.len()]
    }
    /// Ego crush [m].
    pub fn ego_crush_m(&self) -> &[f64] {
        &self.ego_crush_m[..self.len()]
    }
    /// Opponent compartment acceleration [m/s²] (own axes).
    pub fn opp_accel_mps2(&self) -> &[f64] {
        &self.opp_accel_mps2[..self.len()]
    }
    /// Opponent velocity change since contact [m/s] (own axes).
    pub fn opp_vel_mps(&self) -> &[f64] {
        &self.opp_vel_mps[..self.len()]
    }
    /// Opponent crush [m].
    pub fn opp_crush_m(&self) -> &[f64] {
        &self.opp_crush_m[..self.len()]
    }
    /// The ego compartment pulse as input of the occupant model.
    pub fn ego_pulse(&self) -> CompartmentPulse<'_> {
        CompartmentPulse {
            step_s: self.step_s,
            accel_mps2: self.ego_accel_mps2(),
        }
    }
    /// The opponent compartment pulse.
    pub fn opp_pulse(&self) -> CompartmentPulse<'_> {
        CompartmentPulse {
            step_s: self.step_s,
            accel_mps2: self.opp_accel_mps2(),
        }
    }

    /// Set the sampling grid of the next write: `len` samples (at most N) at `step_s`.
    pub(crate) fn start(&mut self, step_s: f64, len: usize) {
        self.step_s = step_s;
        self.len = len.min(N);
    }

    #[inline(always)]
    pub(crate) fn write(&mut self, k: usize, s: &PulseSample) {
        if k < N {
            self.ego_accel_mps2[k] = s.ego_accel_mps2;
            self.ego_vel_mps[k] = s.ego_vel_mps;
            self.ego_crush_m[k] = s.ego_crush_m;
            self.opp_accel_mps2[k] = s.opp_accel_mps2;
            self.opp_vel_mps[k] = s.opp_vel_mps;
            self.opp_crush_m[k] = s.opp_crush_m;
        }
    }
}

/// A compartment acceleration signal sampled at a fixed step, first sample at first contact.
/// Anything can be wrapped (predicted pulse, measured accelerometer samples).
#[derive(Clone, Copy, Debug)]
pub struct CompartmentPulse<'a> {
    /// Sampling step [s].
    pub step_s: f64,
    /// Acceleration along the vehicle's forward axis [m/s²] (negative = deceleration).
    pub accel_mps2: &'a [f64],
}

impl CompartmentPulse<'_> {
    /// Velocity change over the whole pulse [m/s] (negative for a crash), trapezoidal rule.
    pub fn delta_v_mps(&self) -> f64 {
        let mut v = 0.0;
        for w in self.accel_mps2.windows(2) {
            v += 0.5 * (w[0] + w[1]) * self.step_s;
        }
        v
    }

    /// Compartment displacement in the frame of its final velocity [m] (D_veh of SPEC's ideal
    /// bound): ∫ (v(t) − v_end) dt. Positive for a crash pulse.
    pub fn ride_down_displacement_m(&self) -> f64 {
        let v_end = self.delta_v_mps();
        let (mut v, mut d) = (0.0, 0.0);
        let mut prev_rel = -v_end;
        for w in self.accel_mps2.windows(2) {
            v += 0.5 * (w[0] + w[1]) * self.step_s;
            let rel = v - v_end;
            d += 0.5 * (prev_rel + rel) * self.step_s;
            prev_rel = rel;
        }
        d
    }
}

/// State of both compartments at one instant after first contact (the pulse channels of
/// [`PulseBuffer`] at one sample; sign conventions in the module documentation).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PulseSample {
    /// Ego compartment acceleration [m/s²] (negative = deceleration).
    pub ego_accel_mps2: f64,
    /// Ego velocity change since first contact [m/s] (0 → −Δv).
    pub ego_vel_mps: f64,
    /// Ego crush [m].
    pub ego_crush_m: f64,
    /// Opponent compartment acceleration [m/s²] (own axes; 0 for a barrier).
    pub opp_accel_mps2: f64,
    /// Opponent velocity change since first contact [m/s] (own axes).
    pub opp_vel_mps: f64,
    /// Opponent crush [m].
    pub opp_crush_m: f64,
}

impl PulseSample {
    /// At rest, no force, no crush (the state at first contact and without a collision).
    pub const ZERO: PulseSample = PulseSample {
        ego_accel_mps2: 0.0,
        ego_vel_mps: 0.0,
        ego_crush_m: 0.0,
        opp_accel_mps2: 0.0,
        opp_vel_mps: 0.0,
        opp_crush_m: 0.0,
    };
}

/// The mass terms of one collision and what follows from them alone: the reduced mass, each
/// vehicle's share of the relative velocity change (momentum conservation), the per-vehicle
/// pulse sample of a relative state and the summary. Shared by the integrator and the exact
/// solution ([`crate::exact`]) so that both report the same quantities the same way.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Masses {
    pub inv_m_ego: f64,
    pub inv_m_opp: f64,
    /// Reduced mass μ = m_ego m_opp / (m_ego + m_opp) [kg] (= m_ego for a barrier).
    pub mu: f64,
    pub inv_mu: f64,
    pub ratio_ego: f64,
    pub ratio_opp: f64,
    /// Closing speed at first contact [m/s].
    pub v0: f64,
}

/// The reversal (maximum crush) and the unloading that follows from it.
pub(crate) struct Reversal {
    pub t_rev: f64,
    pub x_rev: f64,
    pub f_rev: f64,
    pub x_ego_rev: f64,
}

/// Linear unloading from the reversal point: y(t) = x_r − δ (1 − cos ω (t − t_rev)).
pub(crate) struct Unloading {
    pub delta: f64,
    pub omega: f64,
    pub k_u: f64,
    pub t_sep: f64,
    pub v_sep: f64,
}

impl Masses {
    pub const ZERO: Masses = Masses {
        inv_m_ego: 0.0,
        inv_m_opp: 0.0,
        mu: 0.0,
        inv_mu: 0.0,
        ratio_ego: 0.0,
        ratio_opp: 0.0,
        v0: 0.0,
    };

    pub fn new(input: &CollisionInput<'_>) -> Self {
        let inv_m_ego = 1.0 / input.ego_mass_kg;
        let inv_m_opp = if input.opp_mass_kg.is_infinite() {
            0.0
        } else {
            1.0 / input.opp_mass_kg
        };
        let inv_mu = inv_m_ego + inv_m_opp;
        let mu = 1.0 / inv_mu;
        Masses {
            inv_m_ego,
            inv_m_opp,
            mu,
            inv_mu,
            ratio_ego: mu * inv_m_ego,
            ratio_opp: mu * inv_m_opp,
            v0: input.closing_speed_mps,
        }
    }

    /// Both compartments at contact force `force_n`, closing speed `closing_mps` and crushes.
    #[inline(always)]
    pub fn sample(&self, force_n: f64, closing_mps: f64, x_ego: f64, x_opp: f64) -> PulseSample {
        PulseSample {
            ego_accel_mps2: -force_n * self.inv_m_ego,
            ego_vel_mps: -self.ratio_ego * (self.v0 - closing_mps),
            ego_crush_m: x_ego,
            opp_accel_mps2: -force_n * self.inv_m_opp,
            opp_vel_mps: -self.ratio_opp * (self.v0 - closing_mps),
            opp_crush_m: x_opp,
        }
    }

    /// Unloading line from the reversal point, δ = μ (e v₀)² / F_r (bounded by the crush) — the
    /// model's definition, in one place.
    pub fn unloading(&self, restitution: f64, rev: &Reversal) -> Unloading {
        let v_sep = restitution * self.v0;
        if v_sep > 0.0 && rev.f_rev > 0.0 {
            let delta = (self.mu * v_sep * v_sep / rev.f_rev).min(rev.x_rev);
            let k_u = rev.f_rev / delta;
            let omega = libm::sqrt(k_u * self.inv_mu);
            Unloading {
                delta,
                omega,
                k_u,
                t_sep: rev.t_rev + core::f64::consts::FRAC_PI_2 / omega,
                v_sep,
            }
        } else {
            Unloading {
                delta: 0.0,
                omega: 0.0,
                k_u: f64::INFINITY,
                t_sep: rev.t_rev,
                v_sep,
            }
        }
    }

    /// The summary of a collision from its reversal and unloading.
    pub fn summary(&self, rev: &Reversal, unl: &Unloading, samples: usize) -> CollisionSummary {
        let dv_rel = self.v0 + unl.v_sep;
        let duration = unl.t_sep;
        let vehicle_result = |inv_m: f64, ratio: f64, crush: f64| {
            let dv = ratio * dv_rel;
            VehicleResult {
                crush_m: crush,
                a_max_mps2: rev.f_rev * inv_m,
                a_mean_mps2: if duration > 0.0 { dv / duration } else { 0.0 },
                delta_v_mps: dv,
            }
        };
        CollisionSummary {
            vehicle: vehicle_result(self.inv_m_ego, self.ratio_ego, rev.x_ego_rev),
            opponent: vehicle_result(self.inv_m_opp, self.ratio_opp, rev.x_rev - rev.x_ego_rev),
            contact_duration_s: duration,
            reversal_time_s: rev.t_rev,
            max_deflection_m: rev.x_rev,
            peak_force_n: rev.f_rev,
            unloading_stiffness_n_per_m: unl.k_u,
            separation_speed_mps: unl.v_sep,
            absorbed_energy_j: 0.5 * self.mu * (self.v0 * self.v0 - unl.v_sep * unl.v_sep),
            samples_written: samples,
        }
    }
}

/// Number of samples of the grid 0..=duration at `step_s`, bounded by the capacity.
pub(crate) fn sample_count(duration_s: f64, step_s: f64, capacity: usize) -> usize {
    let wanted = libm::floor(duration_s / step_s + 1.0e-9) + 1.0;
    if wanted >= capacity as f64 {
        capacity
    } else {
        wanted as usize
    }
}

/// The physical inputs (masses, speed, restitution, spring): what the exact solution needs.
pub(crate) fn validate_physics(input: &CollisionInput<'_>) -> Result<(), PhysicsError> {
    if !(input.ego_mass_kg.is_finite() && input.ego_mass_kg > 0.0) {
        return Err(PhysicsError::InvalidInput(
            "ego mass must be finite and > 0",
        ));
    }
    if !(input.opp_mass_kg > 0.0) {
        return Err(PhysicsError::InvalidInput(
            "opponent mass must be > 0 (∞ = barrier)",
        ));
    }
    if !(input.closing_speed_mps.is_finite() && input.closing_speed_mps >= 0.0) {
        return Err(PhysicsError::InvalidInput(
            "closing speed must be finite and ≥ 0",
        ));
    }
    if input.closing_speed_mps > 200.0 {
        return Err(PhysicsError::InvalidInput("closing speed above 200 m/s"));
    }
    if !defaults::RESTITUTION_BOUNDS.contains(input.restitution) {
        return Err(PhysicsError::InvalidInput(
            "restitution must be within 0..=1",
        ));
    }
    if input.spring.len < 2 {
        return Err(PhysicsError::InvalidCurve(
            "combined spring has fewer than 2 points",
        ));
    }
    Ok(())
}

/// The sampling grid (step and pulse length).
pub(crate) fn validate_grid(step_s: f64, duration_s: f64) -> Result<(), PhysicsError> {
    if !defaults::STEP_BOUNDS_S.contains(step_s) {
        return Err(PhysicsError::InvalidInput(
            "step must be within 1 µs..=5 ms",
        ));
    }
    if !(0.0..=10.0).contains(&duration_s) {
        return Err(PhysicsError::InvalidInput(
            "duration must be within 0..=10 s",
        ));
    }
    Ok(())
}

/// Predict a collision: simulate the contact phase to its end and write both compartment pulses
/// (sample k at t = k · step, k = 0 at first contact, up to `duration_s` or the buffer capacity,
/// whichever is shorter). Allocation-free; never panics; NaN/out-of-range input → `Err`.
pub fn simulate_collision<const N: usize>(
    input: &CollisionInput<'_>,
    out: &mut PulseBuffer<N>,
) -> Result<CollisionSummary, PhysicsError> {
    validate_physics(input)?;
    validate_grid(input.step_s, input.duration_s)?;
    let spring = input.spring;
    let dt = input.step_s;
    let m = Masses::new(input);
    let inv_mu = m.inv_mu;
    let v0 = m.v0;
    // Samples to write: the pulse grid 0..=duration, bounded by the buffer.
    let n_out = sample_count(input.duration_s, dt, N);
    out.start(dt, n_out);

    if v0 == 0.0 {
        for k in 0..n_out {
            out.write(k, &PulseSample::default());
        }
        return Ok(CollisionSummary {
            samples_written: n_out,
            ..CollisionSummary::default()
        });
    }

    let max_steps = libm::ceil(defaults::MAX_CONTACT_S / dt) as usize;
    out.write(0, &m.sample(0.0, v0, 0.0, 0.0));

    // ---- loading: velocity Verlet with a segment cursor (x only grows while loading).
    let (mut x, mut u, mut f) = (0.0f64, v0, 0.0f64);
    let mut seg = 0usize;
    let mut k = 0usize;
    let u_new = loop {
        let u_half = u - 0.5 * f * inv_mu * dt;
        let xn = x + u_half * dt;
        seg = spring.segment_from(seg, xn);
        let fnew = spring.force_n[seg] + (xn - spring.x_m[seg]) * spring.stiffness_n_per_m[seg];
        let un = u_half - 0.5 * fnew * inv_mu * dt;
        if un <= 0.0 {
            break un;
        }
        x = xn;
        u = un;
        f = fnew;
        k += 1;
        if k < n_out {
            let x_ego = spring.ego_m[seg] + (x - spring.x_m[seg]) * spring.ego_share[seg];
            out.write(k, &m.sample(f, u, x_ego, x - x_ego));
        }
        if k >= max_steps {
            return Err(PhysicsError::ContactTooLong);
        }
    };

    // ---- reversal inside step k → k+1: closing speed falls from u > 0 to u_new ≤ 0.
    let tau = if u - u_new > 0.0 {
        dt * u / (u - u_new)
    } else {
        0.0
    };
    let x_rev = x + 0.5 * u * tau;
    let rev = Reversal {
        t_rev: k as f64 * dt + tau,
        x_rev,
        f_rev: spring.force_at_n(x_rev),
        x_ego_rev: spring.ego_deflection_m(x_rev),
    };
    let ego_frac = if x_rev > 0.0 {
        rev.x_ego_rev / x_rev
    } else {
        1.0
    };
    // Linear unloading y(t) = x_p + δ cos(ω (t − t_rev)), in closed form.
    let unl = m.unloading(input.restitution, &rev);
    let x_perm = x_rev - unl.delta;
    let final_sample = m.sample(
        0.0,
        -unl.v_sep,
        ego_frac * x_perm,
        (1.0 - ego_frac) * x_perm,
    );
    let mut kk = k + 1;
    while kk < n_out {
        let t = kk as f64 * dt;
        if t < unl.t_sep && unl.omega > 0.0 {
            let phase = unl.omega * (t - rev.t_rev);
            let (s, c) = (libm::sin(phase), libm::cos(phase));
            let y = x_perm + unl.delta * c;
            out.write(
                kk,
                &m.sample(
                    rev.f_rev * c,
                    -unl.delta * unl.omega * s,
                    ego_frac * y,
                    (1.0 - ego_frac) * y,
                ),
            );
        } else {
            out.write(kk, &final_sample);
        }
        kk += 1;
    }
    Ok(m.summary(&rev, &unl, n_out))
}
