//! The collision model of [`crate::collision`] solved in closed form, segment by segment — no
//! step size, no step-size error.
//!
//! The combined crush spring is piecewise linear in the relative deflection x while loading and
//! a straight line while unloading, so on every piece the relative motion obeys
//!
//! ```text
//!   x'' = −(a₀ + s (x − x₀)),   a₀ = F(x₀)/μ,  s = k/μ
//! ```
//!
//! whose flow is known: with S(τ) and C(τ) = ∫S
//!
//! ```text
//!   s > 0 (harmonic, ω = √s):        S = sin(ωτ)/ω    C = (1 − cos ωτ)/ω² = 2 sin²(ωτ/2)/ω²
//!   s = 0 (uniformly decelerated):   S = τ            C = τ²/2
//!   s < 0 (hyperbolic, κ = √−s):     S = sinh(κτ)/κ   C = 2 sinh²(κτ/2)/κ²
//!   x − x₀ = u₀ S − a₀ C,   u = u₀ − a₀ S − s u₀ C,   a = a₀ + s (x − x₀)
//! ```
//!
//! Events: (1) a knee x_{i+1} is crossed when u₀² − Δx (a₀ + a₁) > 0 (energy; exact for a force
//! linear in x); the time to it is, with P = a₁u₀ − a₀u₁ and D = a₀a₁ + s u₀u₁,
//! Δt = atan(√s·P/D)/√s (s > 0), P/D (s = 0), atanh(√−s·P/D)/√−s (s < 0) — the phase
//! difference of the two states, one `atan` per knee. (2) Otherwise the reversal (maximum
//! crush) lies in this segment at d = u₀² / (a₀ + √(a₀² + s u₀²)) (the root of
//! u₀² = 2a₀d + s d² without cancellation), reached after the same formula with u₁ = 0.
//! (3) Unloading is one more linear segment from (x_r, u = 0, F_r) with the slope
//! k_u = F_r/δ that the model derives from e at the reversal point; it ends at the quarter
//! period π/(2ω_u) with the force back at zero (separation). Beyond the curve's last point the
//! last segment continues with its last slope, as in the integrator.
//!
//! Everything the integrator reports is reproduced with the same definitions
//! ([`crate::collision::Masses`] is shared): a_max = F_r/m, a_mean = Δv / contact duration,
//! contact from first contact to separation.
//!
//! API: [`predict_summary`] (the summary only — what the ECU needs every cycle, no storage),
//! [`ExactCollision`] (the events, [`ExactCollision::state_at`] any instant,
//! [`ExactCollision::samples`] an allocation-free sample iterator at any step,
//! [`ExactCollision::write_pulse`] a [`PulseBuffer`]), and [`simulate_collision_exact`], a
//! drop-in replacement of [`crate::simulate_collision`].

use crate::{
    collision::{
        sample_count, validate_grid, validate_physics, CollisionInput, CollisionSummary, Masses,
        PulseBuffer, PulseSample, Reversal,
    },
    defaults,
    stiffness::CURVE_CAPACITY,
    PhysicsError,
};

/// One piece of the relative motion on which the contact force is linear in the deflection:
/// `x'' = −(a₀ + s (x − x₀))` from `start_s` to `end_s` (loading segments of the curve, the
/// segment of the reversal, then the unloading line).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Segment {
    /// Time at which the motion enters the segment [s after first contact].
    pub start_s: f64,
    /// Time at which it leaves it (next knee, the reversal, or separation) [s].
    pub end_s: f64,
    /// Relative deflection at entry [m].
    pub x0_m: f64,
    /// Closing speed at entry [m/s] (0 at the start of unloading).
    pub closing_speed0_mps: f64,
    /// Relative deceleration at entry, contact force / μ [m/s²].
    pub decel0_mps2: f64,
    /// Slope of the force over the deflection divided by μ, k/μ [1/s²] (ω² when positive).
    pub stiffness_per_mass_per_s2: f64,
    /// Ego crush at entry [m].
    pub ego0_m: f64,
    /// Ego crush per relative deflection in this segment [-].
    pub ego_share: f64,
}

impl Segment {
    const ZERO: Segment = Segment {
        start_s: 0.0,
        end_s: 0.0,
        x0_m: 0.0,
        closing_speed0_mps: 0.0,
        decel0_mps2: 0.0,
        stiffness_per_mass_per_s2: 0.0,
        ego0_m: 0.0,
        ego_share: 0.0,
    };

    /// Deflection change, closing speed and deceleration τ after entry (see module docs).
    #[inline]
    fn advance(&self, tau_s: f64) -> (f64, f64, f64) {
        let (sn, cn) = propagator(self.stiffness_per_mass_per_s2, tau_s);
        step(
            self.closing_speed0_mps,
            self.decel0_mps2,
            self.stiffness_per_mass_per_s2,
            sn,
            cn,
        )
    }
}

/// (S, C) of the module docs for slope `s` = k/μ after `tau_s`.
#[inline]
fn propagator(s: f64, tau_s: f64) -> (f64, f64) {
    if s > 0.0 {
        let w = libm::sqrt(s);
        // Half angle: 1 − cos θ = 2 sin²(θ/2) keeps full precision for small θ.
        let (sh, ch) = libm::sincos(0.5 * w * tau_s);
        (2.0 * sh * ch / w, 2.0 * sh * sh / s)
    } else if s < 0.0 {
        let k = libm::sqrt(-s);
        let half = 0.5 * k * tau_s;
        let (sh, ch) = (libm::sinh(half), libm::cosh(half));
        (2.0 * sh * ch / k, -2.0 * sh * sh / s)
    } else {
        (tau_s, 0.5 * tau_s * tau_s)
    }
}

/// Flow of `x'' = −(a + s (x − x₀))` with propagator (S, C): (Δx, u, a) after the step.
#[inline(always)]
fn step(u: f64, a: f64, s: f64, sn: f64, cn: f64) -> (f64, f64, f64) {
    let dx = u * sn - a * cn;
    (dx, u - a * sn - s * u * cn, a + s * dx)
}

/// Time to go from (u₀, a₀) to (u₁, a₁) on a segment of slope `s`, given P = a₁u₀ − a₀u₁ and
/// D = a₀a₁ + s u₀u₁: with r = P/D (= tan(ωΔt)/ω, Δt, tanh(κΔt)/κ), Δt = atan(√s r)/√s etc.
/// A series in s r² for |s r²| < 1e-5 covers s → 0 from both sides without 0/0.
#[inline]
fn segment_time_s(s: f64, p: f64, d: f64) -> f64 {
    let r = p / d;
    let z = s * r * r;
    if z.abs() < 1.0e-5 {
        r * (1.0 - z * (1.0 / 3.0 - z * 0.2))
    } else if s > 0.0 {
        let w = libm::sqrt(s);
        // r = +∞ (D = 0: a linear spring from x = 0 to its reversal) gives the quarter period.
        libm::atan(w * r) / w
    } else {
        let k = libm::sqrt(-s);
        // |κ r| < 1 for any consistent pair of states; otherwise ∞ → refused by the caller.
        let q = k * r;
        if q < 1.0 {
            libm::atanh(q) / k
        } else {
            f64::INFINITY
        }
    }
}

/// What [`walk`] finds: the reversal, the unloading and the values the pulse needs afterwards.
struct Solution {
    masses: Masses,
    /// Unloading segment (zero length when e = 0).
    unloading: Segment,
    summary: CollisionSummary,
    /// Closing speed after separation [m/s] (= −e v₀; the integrator's convention).
    after_closing_mps: f64,
    /// Permanent relative deflection after separation [m].
    x_perm_m: f64,
    /// Ego share of the deflection during unloading.
    ego_frac: f64,
}

/// Walk the loading segments from first contact to the reversal, calling `record` for each
/// (with its end time), then derive the unloading. `None` for v₀ = 0 (no contact).
fn walk(
    input: &CollisionInput<'_>,
    mut record: impl FnMut(&Segment),
) -> Result<Option<Solution>, PhysicsError> {
    validate_physics(input)?;
    let masses = Masses::new(input);
    let v0 = masses.v0;
    if v0 == 0.0 {
        return Ok(None);
    }
    let sp = input.spring;
    let inv_mu = masses.inv_mu;
    let last = sp.len.min(CURVE_CAPACITY).saturating_sub(2);
    let (mut t, mut u, mut usq) = (0.0f64, v0, v0 * v0);
    let mut i = 0usize;
    let rev = loop {
        let a0 = sp.force_n[i] * inv_mu;
        let s = sp.stiffness_n_per_m[i] * inv_mu;
        let mut seg = Segment {
            start_s: t,
            end_s: t,
            x0_m: sp.x_m[i],
            closing_speed0_mps: u,
            decel0_mps2: a0,
            stiffness_per_mass_per_s2: s,
            ego0_m: sp.ego_m[i],
            ego_share: sp.ego_share[i],
        };
        if i < last {
            let dx = sp.x_m[i + 1] - sp.x_m[i];
            let a1 = sp.force_n[i + 1] * inv_mu;
            let u1sq = usq - dx * (a0 + a1);
            if u1sq > 0.0 {
                let u1 = libm::sqrt(u1sq);
                // P = a₁u₀ − a₀u₁ = Δx (a₀(a₀+a₁)/(u₀+u₁) + s u₀): no cancellation.
                let p = dx * (a0 * (a0 + a1) / (u + u1) + s * u);
                t += segment_time_s(s, p, a0 * a1 + s * u * u1);
                seg.end_s = t;
                record(&seg);
                (u, usq) = (u1, u1sq);
                i += 1;
                continue;
            }
        }
        // The reversal lies in this segment (the last one extends the last slope to ∞).
        let root = a0 + libm::sqrt(a0 * a0 + s * usq);
        if !(root > 0.0) {
            // No force (or a falling one) left to stop the motion: the integrator runs into
            // its contact-time limit here.
            return Err(PhysicsError::ContactTooLong);
        }
        let d = usq / root;
        let a_r = a0 + s * d;
        t += segment_time_s(s, a_r * u, a0 * a_r);
        seg.end_s = t;
        record(&seg);
        break Reversal {
            t_rev: t,
            x_rev: sp.x_m[i] + d,
            f_rev: sp.force_n[i] + sp.stiffness_n_per_m[i] * d,
            x_ego_rev: sp.ego_m[i] + d * sp.ego_share[i],
        };
    };
    if !(rev.t_rev <= defaults::MAX_CONTACT_S) {
        return Err(PhysicsError::ContactTooLong);
    }
    let unl = masses.unloading(input.restitution, &rev);
    let ego_frac = if rev.x_rev > 0.0 {
        rev.x_ego_rev / rev.x_rev
    } else {
        1.0
    };
    let unloading = Segment {
        start_s: rev.t_rev,
        end_s: unl.t_sep,
        x0_m: rev.x_rev,
        closing_speed0_mps: 0.0,
        decel0_mps2: rev.f_rev * inv_mu,
        stiffness_per_mass_per_s2: if unl.omega > 0.0 {
            unl.omega * unl.omega
        } else {
            0.0
        },
        ego0_m: rev.x_ego_rev,
        ego_share: ego_frac,
    };
    let summary = masses.summary(&rev, &unl, 0);
    if !summary_is_finite(&summary) {
        // Masses or speeds so extreme that the numbers are not representable.
        return Err(PhysicsError::InvalidInput(
            "masses and speed give a non-representable collision",
        ));
    }
    Ok(Some(Solution {
        masses,
        unloading,
        summary,
        after_closing_mps: -unl.v_sep,
        x_perm_m: rev.x_rev - unl.delta,
        ego_frac,
    }))
}

fn summary_is_finite(s: &CollisionSummary) -> bool {
    [
        s.vehicle.crush_m,
        s.vehicle.a_max_mps2,
        s.vehicle.a_mean_mps2,
        s.vehicle.delta_v_mps,
        s.opponent.crush_m,
        s.opponent.a_max_mps2,
        s.opponent.a_mean_mps2,
        s.opponent.delta_v_mps,
        s.contact_duration_s,
        s.max_deflection_m,
        s.peak_force_n,
        s.absorbed_energy_j,
    ]
    .iter()
    .all(|v| v.is_finite())
}

/// The collision summary in closed form — no pulse, no storage; `input.step_s` and
/// `input.duration_s` are not used (nothing is sampled). The cheap per-cycle prediction.
/// Never panics; invalid input → `Err` exactly as [`crate::simulate_collision`].
pub fn predict_summary(input: &CollisionInput<'_>) -> Result<CollisionSummary, PhysicsError> {
    Ok(walk(input, |_| {})?.map_or_else(CollisionSummary::default, |s| s.summary))
}

/// A collision solved in closed form: its events (knee crossings, reversal, separation) and
/// the state of both compartments at any instant. Owns its data (a few kB, `Copy`), so it can
/// be kept and sampled later at any rate.
#[derive(Clone, Copy, Debug)]
pub struct ExactCollision {
    segments: [Segment; CURVE_CAPACITY],
    len: usize,
    masses: Masses,
    summary: CollisionSummary,
    after: PulseSample,
}

impl Default for ExactCollision {
    fn default() -> Self {
        Self::new()
    }
}

impl ExactCollision {
    /// No collision (no contact: zero summary, zero states). The starting value of a kept,
    /// reused solution (see [`ExactCollision::solve_in_place`]).
    pub const fn new() -> Self {
        ExactCollision {
            segments: [Segment::ZERO; CURVE_CAPACITY],
            len: 0,
            masses: Masses::ZERO,
            summary: CollisionSummary::ZERO,
            after: PulseSample::ZERO,
        }
    }

    /// Solve the collision (`input.step_s` / `duration_s` are not used). Never panics.
    pub fn solve(input: &CollisionInput<'_>) -> Result<Self, PhysicsError> {
        let mut sol = ExactCollision::new();
        sol.solve_in_place(input)?;
        Ok(sol)
    }

    /// Solve into this (caller-owned, reused) value without copying it — the form for a
    /// per-cycle prediction that is kept for later sampling. On `Err` it holds no collision.
    pub fn solve_in_place(
        &mut self,
        input: &CollisionInput<'_>,
    ) -> Result<&CollisionSummary, PhysicsError> {
        self.len = 0;
        self.summary = CollisionSummary::ZERO;
        self.after = PulseSample::ZERO;
        let (segments, len) = (&mut self.segments, &mut self.len);
        let walked = walk(input, |seg| {
            if let Some(slot) = segments.get_mut(*len) {
                *slot = *seg;
                *len += 1;
            }
        });
        let sol = match walked {
            Ok(Some(sol)) => sol,
            Ok(None) => return Ok(&self.summary),
            Err(e) => {
                self.len = 0;
                return Err(e);
            }
        };
        // Loading segments ≤ CURVE_CAPACITY − 1, so the unloading always fits.
        if sol.unloading.end_s > sol.unloading.start_s {
            if let Some(slot) = self.segments.get_mut(self.len) {
                *slot = sol.unloading;
                self.len += 1;
            }
        }
        let x_ego = sol.ego_frac * sol.x_perm_m;
        self.after = sol
            .masses
            .sample(0.0, sol.after_closing_mps, x_ego, sol.x_perm_m - x_ego);
        self.masses = sol.masses;
        self.summary = sol.summary;
        Ok(&self.summary)
    }

    /// The summary (identical to [`predict_summary`]; `samples_written` = 0).
    pub fn summary(&self) -> &CollisionSummary {
        &self.summary
    }

    /// The pieces of the motion in time order: loading segments up to the reversal, then the
    /// unloading line (absent for e = 0). Empty without contact (v₀ = 0).
    pub fn segments(&self) -> &[Segment] {
        &self.segments[..self.len.min(CURVE_CAPACITY)]
    }

    /// Both compartments at `t_s` after first contact. Before contact (t < 0, NaN) the contact
    /// state (all zero); after separation the final state (zero force, −Δv, permanent crush).
    pub fn state_at(&self, t_s: f64) -> PulseSample {
        if !(t_s > 0.0) {
            return self.state_in(0, 0.0);
        }
        match self.segments().iter().position(|s| t_s < s.end_s) {
            Some(i) => self.state_in(i, t_s - self.segments[i].start_s),
            None => self.after,
        }
    }

    /// State `tau_s` into segment `i` (i beyond the segments: the final state; no contact: 0).
    fn state_in(&self, i: usize, tau_s: f64) -> PulseSample {
        match self.segments().get(i) {
            Some(seg) => {
                let (dx, u, a) = seg.advance(tau_s);
                self.sample_of(seg, dx, u, a)
            }
            None if self.len == 0 => PulseSample::default(),
            None => self.after,
        }
    }

    #[inline(always)]
    fn sample_of(&self, seg: &Segment, dx: f64, u: f64, a: f64) -> PulseSample {
        let x = seg.x0_m + dx;
        let x_ego = seg.ego0_m + dx * seg.ego_share;
        self.masses.sample(a * self.masses.mu, u, x_ego, x - x_ego)
    }

    /// Allocation-free iterator over the states at t = k·`step_s`, k = 0, 1, … (endless: after
    /// separation it repeats the final state; bound it with `take`/`zip`). Within a segment it
    /// advances with the segment's exact flow map over one step (a rotation for s > 0, a few
    /// multiply-adds per sample), re-entering each segment from its exact start state.
    /// `step_s` must be finite and > 0.
    pub fn samples(&self, step_s: f64) -> Result<Samples<'_>, PhysicsError> {
        Ok(Samples {
            sol: self,
            cursor: SampleCursor::new(step_s)?,
        })
    }

    /// Write both pulses into `out` at `step_s` for `duration_s` (bounded by the capacity), the
    /// grid of [`crate::simulate_collision`]. Returns the number of samples written.
    pub fn write_pulse<const N: usize>(
        &self,
        step_s: f64,
        duration_s: f64,
        out: &mut PulseBuffer<N>,
    ) -> Result<usize, PhysicsError> {
        validate_grid(step_s, duration_s)?;
        let n = sample_count(duration_s, step_s, N);
        out.start(step_s, n);
        for (k, s) in self.samples(step_s)?.take(n).enumerate() {
            out.write(k, &s);
        }
        Ok(n)
    }
}

/// Iterator of [`ExactCollision::samples`]: a [`SampleCursor`] over a borrowed solution.
#[derive(Clone, Debug)]
pub struct Samples<'a> {
    sol: &'a ExactCollision,
    cursor: SampleCursor,
}

impl Iterator for Samples<'_> {
    type Item = PulseSample;

    // Inlined into the caller's loop so that channels the caller does not read are never
    // computed (the ECU's diagnostics read only the ego acceleration).
    #[inline(always)]
    fn next(&mut self) -> Option<PulseSample> {
        Some(self.cursor.next(self.sol))
    }
}

/// Where a sampler stands in a solution (next sample index, segment, the segment's one-step
/// flow map and the previous state), without borrowing the solution: a caller that keeps its
/// [`ExactCollision`] can sample a few points per call and resume later (the ECU fills its
/// diagnostics pulse a chunk per cycle this way), at the cost of the iterator, with no
/// re-entry. Used with another solution than the one it started on it yields that solution's
/// states at wrong instants, but never panics.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SampleCursor {
    step_s: f64,
    /// Index of the next sample (signed: one-instruction conversion to f64).
    k: i64,
    /// Segment of the next sample (cursor; = number of segments after separation).
    seg: usize,
    /// The cursor moved since the last sample: evaluate from the segment's start state.
    fresh: bool,
    /// Propagator (S, C) of one step in the current segment.
    sn: f64,
    cn: f64,
    /// (Δx from the segment's entry, closing speed, deceleration) at the previous sample.
    state: (f64, f64, f64),
}

impl SampleCursor {
    /// Before the sample at t = 0 of a grid with `step_s` (finite, > 0).
    pub fn new(step_s: f64) -> Result<Self, PhysicsError> {
        if !(step_s.is_finite() && step_s > 0.0) {
            return Err(PhysicsError::InvalidInput(
                "sampling step must be finite and > 0",
            ));
        }
        Ok(SampleCursor {
            step_s,
            k: 0,
            seg: 0,
            fresh: true,
            sn: 0.0,
            cn: 0.0,
            state: (0.0, 0.0, 0.0),
        })
    }

    /// Index of the sample the next [`SampleCursor::next`] returns.
    pub fn index(&self) -> u64 {
        self.k.max(0) as u64
    }

    /// The sampling step, s.
    pub fn step_s(&self) -> f64 {
        self.step_s
    }

    /// Whether the next [`SampleCursor::next`] on `sol` enters a segment — evaluates the
    /// segment's flow from its start (a `sincos` and a `sqrt` each for the entry state and the
    /// one-step map, ≈ 300 instructions) instead of one multiply-add step (≈ 40). A caller
    /// with a per-call work limit stops before it.
    pub fn next_enters(&self, sol: &ExactCollision) -> bool {
        let t = self.k as f64 * self.step_s;
        let segs = sol.segments();
        let next = segs
            .iter()
            .skip(self.seg)
            .position(|s| t < s.end_s)
            .map(|i| i + self.seg);
        next.is_some_and(|i| self.fresh || i != self.seg)
    }

    /// The state of `sol` at t = index · step, then moves on by one step. Within a segment it
    /// advances with the segment's exact flow map over one step (a rotation for s > 0, a few
    /// multiply-adds), re-entering each segment from its exact start state.
    #[inline(always)]
    pub fn next(&mut self, sol: &ExactCollision) -> PulseSample {
        let t = self.k as f64 * self.step_s;
        self.k = self.k.saturating_add(1);
        loop {
            let Some(seg) = sol.segments().get(self.seg) else {
                // After separation (or no contact at all).
                return sol.after;
            };
            if t >= seg.end_s {
                self.seg += 1;
                self.fresh = true;
                continue;
            }
            let s = seg.stiffness_per_mass_per_s2;
            if self.fresh {
                // Enter the segment from its exact start state; then step with its flow map.
                self.state = seg.advance(t - seg.start_s);
                (self.sn, self.cn) = propagator(s, self.step_s);
                self.fresh = false;
            } else {
                let (dx0, u, a) = self.state;
                let (ddx, u1, a1) = step(u, a, s, self.sn, self.cn);
                self.state = (dx0 + ddx, u1, a1);
            }
            let (dx, u, a) = self.state;
            return sol.sample_of(seg, dx, u, a);
        }
    }
}

/// Drop-in replacement of [`crate::simulate_collision`]: the same validation, the same pulse
/// grid (sample k at k · `input.step_s` up to `input.duration_s` or the capacity) and the same
/// summary — computed in closed form, so the step only sets where the pulse is sampled.
pub fn simulate_collision_exact<const N: usize>(
    input: &CollisionInput<'_>,
    out: &mut PulseBuffer<N>,
) -> Result<CollisionSummary, PhysicsError> {
    validate_grid(input.step_s, input.duration_s)?;
    let sol = ExactCollision::solve(input)?;
    let n = sol.write_pulse(input.step_s, input.duration_s, out)?;
    Ok(CollisionSummary {
        samples_written: n,
        ..sol.summary
    })
}

#[cfg(test)]
mod tests {
    //! The per-segment formulas against textbook closed forms, including the flat and falling
    //! segments that validated curves (strictly increasing force) never produce.
    use super::*;

    fn rel(a: f64, b: f64) -> f64 {
        (a - b).abs() / b.abs()
    }

    /// (Δx, u, a) τ after a segment entry at (u₀, a₀) with slope s.
    fn advance(u0: f64, a0: f64, s: f64, tau: f64) -> (f64, f64, f64) {
        Segment {
            closing_speed0_mps: u0,
            decel0_mps2: a0,
            stiffness_per_mass_per_s2: s,
            ..Segment::default()
        }
        .advance(tau)
    }

    /// Time between two states (speed, deceleration) of one segment: P and D as in the walk.
    fn time_between(s: f64, (u0, a0): (f64, f64), (u1, a1): (f64, f64)) -> f64 {
        segment_time_s(s, a1 * u0 - a0 * u1, a0 * a1 + s * u0 * u1)
    }

    #[test]
    fn uniform_deceleration_segment() {
        // s = 0, a = 200 m/s²: u = u₀ − aτ, x = u₀τ − aτ²/2; time from 20 to 10 m/s is 50 ms.
        let (u0, a) = (20.0, 200.0);
        let (dx, u, a1) = step(u0, a, 0.0, 0.03, 0.5 * 0.03 * 0.03);
        let (pdx, pu) = propagator(0.0, 0.03);
        assert_eq!((pdx, pu), (0.03, 0.5 * 0.03 * 0.03));
        assert!(rel(dx, u0 * 0.03 - 0.5 * a * 0.03 * 0.03) < 1e-15);
        assert!(rel(u, u0 - a * 0.03) < 1e-15);
        assert_eq!(a1, a);
        let u1 = 10.0;
        let t = segment_time_s(0.0, a * u0 - a * u1, a * a);
        assert!(rel(t, 0.05) < 1e-15, "{t}");
    }

    #[test]
    fn harmonic_segment_matches_sin_cos() {
        // x'' = −(a₀ + s (x − x₀)): x − x₀ = u₀ sin(ωτ)/ω − a₀ (1 − cos ωτ)/ω².
        let (u0, a0, s, tau): (f64, f64, f64, f64) = (15.0, 300.0, 4.0e3, 0.012);
        let w: f64 = s.sqrt();
        let (dx, u, a) = advance(u0, a0, s, tau);
        let dx_ref = u0 * (w * tau).sin() / w - a0 * (1.0 - (w * tau).cos()) / s;
        let u_ref = u0 * (w * tau).cos() - a0 * (w * tau).sin() / w;
        assert!(rel(dx, dx_ref) < 1e-13 && rel(u, u_ref) < 1e-13);
        assert!(rel(a, a0 + s * dx_ref) < 1e-13);
        // Time back from the two states: phase difference.
        let t = time_between(s, (u0, a0), (u, a));
        assert!(rel(t, tau) < 1e-12, "{t}");
    }

    #[test]
    fn hyperbolic_segment_matches_sinh_cosh() {
        // Falling force (s < 0): x − x₀ = u₀ sinh(κτ)/κ − a₀ (cosh κτ − 1)/κ².
        let (u0, a0, s, tau): (f64, f64, f64, f64) = (15.0, 300.0, -900.0, 0.02);
        let k: f64 = (-s).sqrt();
        let (dx, u, a) = advance(u0, a0, s, tau);
        let dx_ref = u0 * (k * tau).sinh() / k - a0 * ((k * tau).cosh() - 1.0) / (k * k);
        let u_ref = u0 * (k * tau).cosh() - a0 * (k * tau).sinh() / k;
        assert!(rel(dx, dx_ref) < 1e-13 && rel(u, u_ref) < 1e-13);
        let t = time_between(s, (u0, a0), (u, a));
        assert!(rel(t, tau) < 1e-12, "{t}");
    }

    #[test]
    fn tiny_slopes_converge_to_uniform_deceleration() {
        // s → 0 from both sides: the series branch must agree with the exact branches at the
        // switch-over and with (u₀ − u₁)/a in the limit.
        let (u0, a) = (20.0, 200.0);
        // s r² ≈ 5e-6 for s = ±2e-3 (inside the series branch, near its limit).
        for s in [1e-12, -1e-12, 1e-6, -1e-6, 2e-3, -2e-3, 1e-2, -1e-2] {
            let tau = 0.05;
            let (_, u, a1) = advance(u0, a, s, tau);
            let t = time_between(s, (u0, a), (u, a1));
            assert!(rel(t, tau) < 1e-13, "s {s}: {t}");
        }
    }

    #[test]
    fn linear_spring_from_rest_position_reverses_after_a_quarter_period() {
        // a₀ = 0 ⇒ D = 0 at the reversal: atan(∞) = π/2.
        let s: f64 = 1.0e4;
        let t = segment_time_s(s, 100.0 * 5.0, 0.0);
        assert!(rel(t, core::f64::consts::FRAC_PI_2 / s.sqrt()) < 1e-15);
    }
}
