//! Prediction-matched crash confirmation and the in-crash severity estimate.
//!
//! While a crash is predicted (PRE-CRASH), the first sample at or above the wake threshold
//! freezes the prediction: the collision of the predicted situation (closing speed at contact,
//! conservative opponent mass) is solved once in closed form ([`physics::ExactCollision`]),
//! which gives the predicted onset slope j_pred of the ego deceleration (the first loading
//! segment: a = k·v·t / m_ego, k the series stiffness of both fronts) and the time of the
//! first knee of the combined curve, until which the pulse is a ramp.
//!
//! Every following sample extends a least-squares line a(t) = j (t − t₀) through the samples
//! since the wake-up (running sums, O(1) per sample). Once they are at least three and span
//! `match_min_ms` (or the ramp has reached the knee), the matcher decides:
//!
//! * **mismatch** — the fitted onset t₀ is more than `match_window_ms` from the predicted
//!   contact, the slope ratio r = j / j_pred is outside [`match_ratio_min`, `match_ratio_max`],
//!   the residual exceeds [`FIT_TOLERANCE`] of the rise (not a ramp: a pothole, a door slam),
//!   or a sample fell back under the wake threshold. The prediction is not used for this
//!   event (the generic confirmation and the accelerometer-only algorithm decide).
//! * **confirmed** — otherwise. "Follows the prediction" if |r − 1| ≤ `match_tolerance`
//!   (the preset plan holds), else "departs": the severity is re-estimated through the same
//!   model — on the first segment the slope is proportional to k·v, so the measured pulse is
//!   explained by the closing speed v·r (for the predicted structure) — and the crash is
//!   re-planned from the table at that speed (`crash`), before any actuator is committed.
//!
//! Why the closing speed and not the opponent mass: the mass does not show in the first tens
//! of ms. The ego deceleration is the contact force over the ego mass, and the force is set
//! by the crush, which a heavier opponent changes only once its own deceleration has slowed
//! the closing: at 96 km/h the ego pulses of a 1300 kg and a 2400 kg opponent agree within
//! 0.1 g for 30 ms. The mass error is covered by the robust planning mass
//! (`mass_misreport_kg`), not measured.
//!
//! The earliest confirmation this allows: wake-up (1.5 g) plus `match_min_ms`. With the
//! default 1 ms at 4 kHz that is 1.4 ms after contact at 96 km/h closing speed and 2.1 ms
//! at 40 km/h (onset slopes 3.3 and 1.4 g/ms), against 5–8 ms for the generic thresholds.

use physics::{CollisionInput, CombinedSpring, ExactCollision};

use crate::accel::AccelSample;
use crate::confirm::{ConfirmParams, Loading, Onset, OnsetStep};

/// Largest residual rms of the ramp fit, as a fraction of the fitted rise over the window.
pub const FIT_TOLERANCE: f64 = 0.2;
/// The ramp window ends at this fraction of the predicted first-knee time.
const KNEE_FRACTION: f64 = 0.9;
/// Once matched, every further sample must read at least this fraction of the fitted ramp
/// at its time (inside the ramp window) or at the knee (after it): the predicted crash keeps
/// rising along its ramp until the knee and its force only grows with the crush after it,
/// while a pothole or kerb strike that began like it has crested and falls away from the
/// line (a half-sine is at 0.45 of its extrapolated initial ramp when it has carried two
/// thirds of its Δv). The sensor's noise (0.5 m/s² at 4 kHz) is a few per cent of the ramp
/// by then.
pub const RAMP_HOLD: f64 = 0.8;

/// Matching settings in the matcher's units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MatchParams {
    /// Wake threshold and quiet gap (shared with the generic confirmation).
    pub onset: ConfirmParams,
    /// Shortest ramp that can confirm, ns.
    pub min_span_ns: u64,
    /// Fitted onset within ± this of the predicted contact, ns.
    pub window_ns: u64,
    /// |r − 1| up to this: follows the prediction.
    pub tolerance: f64,
    /// Lowest ratio still re-estimated.
    pub ratio_min: f64,
    /// Highest ratio still re-estimated.
    pub ratio_max: f64,
    /// Δv since the onset a matched pulse must reach before it confirms, m/s (the severity
    /// floor: a kerb strike at the predicted contact ramps like the crash for 2 ms).
    pub min_dv_mps: f64,
    /// At the confirming sample the pulse must still be loading ([`Loading::holds`] with this
    /// fraction; 0 = off): a kerb strike that ramps like the predicted crash has peaked and
    /// falls before it carries the floor's Δv, the predicted crash keeps rising.
    pub loading_fraction: f64,
}

/// The prediction frozen at the wake-up.
#[derive(Debug, Clone, Copy)]
pub struct PredictedPulse {
    /// The predicted collision (closed form), t = 0 at the predicted contact.
    pub collision: ExactCollision,
    /// Predicted contact, ns.
    pub contact_ns: u64,
    /// Closing speed at contact it was solved for, m/s.
    pub closing_mps: f64,
    /// Opponent mass it was solved for, kg.
    pub opponent_mass_kg: f64,
    /// Onset slope of the ego deceleration, m/s² per ms.
    pub slope_mps2_per_ms: f64,
    /// End of the first loading segment (the ramp), ms after contact.
    pub knee_ms: f64,
}

impl PredictedPulse {
    /// No prediction (the storage a [`PulseMatch`] solves into).
    pub const EMPTY: Self = Self {
        collision: ExactCollision::new(),
        contact_ns: 0,
        closing_mps: 0.0,
        opponent_mass_kg: 0.0,
        slope_mps2_per_ms: 0.0,
        knee_ms: 0.0,
    };

    /// Solves the predicted collision (`None`: no contact, or input the model refuses).
    pub fn solve(
        spring: &CombinedSpring,
        ego_mass_kg: f64,
        opponent_mass_kg: f64,
        closing_mps: f64,
        contact_ns: u64,
    ) -> Option<Self> {
        let mut p = Self::EMPTY;
        p.solve_in_place(
            spring,
            ego_mass_kg,
            opponent_mass_kg,
            closing_mps,
            contact_ns,
        )
        .then_some(p)
    }

    /// [`PredictedPulse::solve`] into this value without moving it (a few kB): false when the
    /// model refuses the input or there is no contact.
    pub fn solve_in_place(
        &mut self,
        spring: &CombinedSpring,
        ego_mass_kg: f64,
        opponent_mass_kg: f64,
        closing_mps: f64,
        contact_ns: u64,
    ) -> bool {
        let input =
            CollisionInput::with_defaults(spring, ego_mass_kg, opponent_mass_kg, closing_mps);
        if self.collision.solve_in_place(&input).is_err() {
            return false;
        }
        let Some(knee_s) = self.collision.segments().first().map(|s| s.end_s) else {
            return false;
        };
        // Slope at the start of the ramp, from the model's own state (sin ωτ ≈ ωτ: the
        // reference instant is a quarter of the ramp, or 0.25 ms).
        let tau_s = (0.25 * knee_s).min(0.25e-3);
        let slope = -self.collision.state_at(tau_s).ego_accel_mps2 / (tau_s * 1e3);
        self.contact_ns = contact_ns;
        self.closing_mps = closing_mps;
        self.opponent_mass_kg = opponent_mass_kg;
        self.slope_mps2_per_ms = slope;
        self.knee_ms = knee_s * 1e3;
        slope > 0.0 && slope.is_finite() && knee_s > 0.0
    }
}

/// The severity of a matched (or departing) pulse.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SeverityEstimate {
    /// Sample time of the confirmation, ns.
    pub confirm_ns: u64,
    /// Fitted onset (measured contact), ns.
    pub onset_ns: u64,
    /// Measured / predicted onset slope.
    pub ratio: f64,
    /// Closing speed that explains the measured slope, m/s (predicted × ratio).
    pub closing_mps: f64,
    /// Opponent mass of the prediction, kg.
    pub opponent_mass_kg: f64,
    /// |ratio − 1| within the tolerance ("follows the prediction").
    pub follows: bool,
}

/// Why a pulse did not match.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mismatch {
    /// Fitted onset too far from the predicted contact.
    Timing,
    /// Slope ratio outside the re-estimation range.
    Severity,
    /// Not a ramp (residual too large, or the deceleration fell back under the wake level).
    Shape,
}

/// The matcher's view of the current accelerometer event.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum MatchState {
    /// No event, or an event that began without a prediction (not matched).
    Idle,
    /// Collecting the ramp.
    Fitting,
    /// Confirmed (latched for good).
    Confirmed(SeverityEstimate),
    /// Not matched (until the event is over).
    Mismatch(Mismatch),
}

/// Running least-squares sums of (x = ms since the wake-up, y = deceleration m/s²).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
struct LineFit {
    n: f64,
    sx: f64,
    sy: f64,
    sxx: f64,
    sxy: f64,
    syy: f64,
    x_last: f64,
}

impl LineFit {
    fn push(&mut self, x: f64, y: f64) {
        self.n += 1.0;
        self.sx += x;
        self.sy += y;
        self.sxx += x * x;
        self.sxy += x * y;
        self.syy += y * y;
        self.x_last = x;
    }

    /// (slope, intercept, residual rms), `None` when degenerate.
    fn solve(&self) -> Option<(f64, f64, f64)> {
        let den = self.n * self.sxx - self.sx * self.sx;
        if !(self.n >= 3.0 && den > 0.0) {
            return None;
        }
        let j = (self.n * self.sxy - self.sx * self.sy) / den;
        let b = (self.sy - j * self.sx) / self.n;
        let sse = (self.syy - b * self.sy - j * self.sxy).max(0.0);
        Some((j, b, libm::sqrt(sse / self.n)))
    }
}

/// State of the prediction-matched confirmation.
#[derive(Debug, Clone)]
pub struct PulseMatch {
    params: MatchParams,
    onset: Onset,
    /// The prediction of the current event (valid while `frozen`); solved in place.
    prediction: PredictedPulse,
    frozen: bool,
    fit: LineFit,
    loading: Loading,
    state: MatchState,
    /// The ramp matched; waiting for the severity floor (state stays `Fitting`).
    matched: Option<SeverityEstimate>,
    /// The matched ramp (slope m/s² per ms, intercept m/s², x in ms since the wake-up).
    ramp: (f64, f64),
    /// After the confirmation: the first sample that fell below [`RAMP_HOLD`] of the fitted
    /// ramp (its course broke: the pulse crested like a pothole, not like the crash), ns.
    course_broken_ns: Option<u64>,
}

impl PulseMatch {
    /// Idle, with validated settings.
    pub fn new(params: MatchParams) -> Self {
        Self {
            params,
            onset: Onset::default(),
            prediction: PredictedPulse::EMPTY,
            frozen: false,
            fit: LineFit::default(),
            loading: Loading::default(),
            state: MatchState::Idle,
            matched: None,
            ramp: (0.0, 0.0),
            course_broken_ns: None,
        }
    }

    /// Its settings.
    pub fn params(&self) -> &MatchParams {
        &self.params
    }

    /// The current state.
    pub fn state(&self) -> MatchState {
        self.state
    }

    /// The prediction frozen for the current (or confirmed) event.
    pub fn prediction(&self) -> Option<&PredictedPulse> {
        self.frozen.then_some(&self.prediction)
    }

    /// An accelerometer event is in progress (the pre-crash prediction is then moot).
    pub fn awake(&self) -> bool {
        self.onset.awake()
    }

    /// See [`Onset::note_quiet`](crate::confirm::Onset::note_quiet).
    pub fn note_quiet(&mut self, decel_mps2: f64) {
        self.onset.note_quiet(decel_mps2);
    }

    /// Feeds one plausible sample. `freeze` is called at a wake-up: it solves the prediction
    /// of the coming crash into the storage it is given and says whether there is one (false:
    /// not in PRE-CRASH, or the model refused the situation).
    pub fn push(&mut self, s: &AccelSample, freeze: &mut dyn FnMut(&mut PredictedPulse) -> bool) {
        if matches!(self.state, MatchState::Confirmed(_)) {
            // The confirmed pulse is no longer fitted, but the event is followed to its end
            // (a crash phase that fired nothing ends with it; else the ECU would stay in
            // CrashDetected, the reversible pretensioner tensioned, after a pothole matched an
            // avoided collision's prediction) and its course is still watched: a fire
            // planned after the confirmation goes out only while the pulse keeps to the
            // matched ramp (such a pothole ramps like the crash for a few ms, then crests; the
            // crash keeps loading).
            if self.onset.awake() {
                let step = self.onset.push(&self.params.onset, s);
                if step == OnsetStep::Awake && self.course_broken_ns.is_none() {
                    if let Some(line_mps2) = self.ramp_line_mps2(s.t_ns) {
                        if s.decel_mps2 < RAMP_HOLD * line_mps2 {
                            self.course_broken_ns = Some(s.t_ns);
                        }
                    }
                }
            }
            return;
        }
        match self.onset.push(&self.params.onset, s) {
            OnsetStep::Quiet => return,
            OnsetStep::Reset => {
                self.state = MatchState::Idle;
                self.frozen = false;
                self.matched = None;
                self.ramp = (0.0, 0.0);
                return;
            }
            OnsetStep::Woke => {
                self.fit = LineFit::default();
                self.loading.start(s.decel_mps2);
                self.matched = None;
                self.ramp = (0.0, 0.0);
                self.frozen = freeze(&mut self.prediction);
                self.state = if self.frozen {
                    MatchState::Fitting
                } else {
                    MatchState::Idle
                };
            }
            OnsetStep::Awake => self.loading.push(s.decel_mps2, s.dt_s),
        }
        if self.state != MatchState::Fitting {
            return;
        }
        let (true, Some(wake_ns)) = (self.frozen, self.onset.onset_ns()) else {
            return;
        };
        let p = &self.prediction;
        if s.decel_mps2 < self.params.onset.wake_mps2 {
            self.state = MatchState::Mismatch(Mismatch::Shape);
            return;
        }
        let x_ms = s.t_ns.saturating_sub(wake_ns) as f64 * 1e-6;
        // Time since the (predicted-slope) contact: the ramp ends at the first knee.
        let tau_ms = x_ms + self.params.onset.wake_mps2 / p.slope_mps2_per_ms;
        let in_ramp = tau_ms <= KNEE_FRACTION * p.knee_ms;
        if let (Some(e), Some(line_mps2)) = (self.matched, self.ramp_line_mps2(s.t_ns)) {
            self.state = if s.decel_mps2 < RAMP_HOLD * line_mps2 {
                MatchState::Mismatch(Mismatch::Shape)
            } else {
                self.hold_for_floor(e, wake_ns, s.t_ns)
            };
            return;
        }
        if in_ramp {
            self.fit.push(x_ms, s.decel_mps2);
        }
        let span_ns = (self.fit.x_last * 1e6) as u64;
        let enough = span_ns >= self.params.min_span_ns && self.fit.n >= 3.0;
        if enough || !in_ramp {
            self.state = match self.decide(p, wake_ns, s.t_ns) {
                MatchState::Confirmed(e) => {
                    self.matched = Some(e);
                    if let Some((j, b, _)) = self.fit.solve() {
                        self.ramp = (j, b);
                    }
                    self.hold_for_floor(e, wake_ns, s.t_ns)
                }
                other => other,
            };
        }
    }

    /// The matched ramp's deceleration at `t_ns`, m/s²: the fitted line up to the knee, and its
    /// value at the knee after it (the predicted crash's force only grows with the crush).
    /// `None` before a match.
    fn ramp_line_mps2(&self, t_ns: u64) -> Option<f64> {
        let (true, Some(wake_ns), Some(_)) = (self.frozen, self.onset.onset_ns(), self.matched)
        else {
            return None;
        };
        let p = &self.prediction;
        let x_ms = t_ns.saturating_sub(wake_ns) as f64 * 1e-6;
        // The wake-up lies this long after the (predicted-slope) contact.
        let lead_ms = self.params.onset.wake_mps2 / p.slope_mps2_per_ms;
        let x_knee_ms = KNEE_FRACTION * p.knee_ms - lead_ms;
        let (j, b) = self.ramp;
        Some(j * x_ms.min(x_knee_ms) + b)
    }

    /// After a confirmation: when the pulse left the matched ramp (`None`: it keeps to it).
    pub fn course_broken_ns(&self) -> Option<u64> {
        self.course_broken_ns
    }

    /// A matched ramp confirms once the velocity change since the onset reaches the floor
    /// (the deceleration staying above the wake threshold meanwhile, checked by the caller)
    /// while the pulse is still loading; a pulse that stops loading first, or has not reached
    /// the floor within the match window, is not this crash.
    fn hold_for_floor(&self, e: SeverityEstimate, wake_ns: u64, t_ns: u64) -> MatchState {
        if !self.loading.holds(self.params.loading_fraction) {
            MatchState::Mismatch(Mismatch::Shape)
        } else if self.onset.delta_v_mps() >= self.params.min_dv_mps {
            MatchState::Confirmed(SeverityEstimate {
                confirm_ns: t_ns,
                ..e
            })
        } else if t_ns.saturating_sub(wake_ns) > self.params.window_ns {
            MatchState::Mismatch(Mismatch::Severity)
        } else {
            MatchState::Fitting
        }
    }

    fn decide(&self, p: &PredictedPulse, wake_ns: u64, t_ns: u64) -> MatchState {
        let Some((j, b, rms)) = self.fit.solve() else {
            return MatchState::Mismatch(Mismatch::Shape);
        };
        let rise = j * self.fit.x_last;
        if !(j > 0.0 && rms <= FIT_TOLERANCE * rise) {
            return MatchState::Mismatch(Mismatch::Shape);
        }
        // a = j·x + b = 0 at x₀ = −b/j (ms after the wake-up; negative: before it).
        let x0_ns = -b / j * 1e6;
        let onset_ns = if x0_ns < 0.0 {
            wake_ns.saturating_sub((-x0_ns) as u64)
        } else {
            wake_ns.saturating_add(x0_ns as u64)
        };
        if onset_ns.abs_diff(p.contact_ns) > self.params.window_ns {
            return MatchState::Mismatch(Mismatch::Timing);
        }
        let ratio = j / p.slope_mps2_per_ms;
        if !(ratio >= self.params.ratio_min && ratio <= self.params.ratio_max) {
            return MatchState::Mismatch(Mismatch::Severity);
        }
        MatchState::Confirmed(SeverityEstimate {
            confirm_ns: t_ns,
            onset_ns,
            ratio,
            closing_mps: p.closing_mps * ratio,
            opponent_mass_kg: p.opponent_mass_kg,
            follows: (ratio - 1.0).abs() <= self.params.tolerance,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::settings::G_MPS2;
    use physics::MassClass;

    const MS: u64 = 1_000_000;
    const CONTACT: u64 = 10_000 * MS;

    fn params() -> MatchParams {
        MatchParams {
            onset: ConfirmParams {
                wake_mps2: 1.5 * G_MPS2,
                decel_mps2: 4.0 * G_MPS2,
                samples: 3,
                delta_v_mps: 0.5,
                reset_gap_ns: 10 * MS,
            },
            min_span_ns: MS,
            window_ns: 30 * MS,
            tolerance: 0.12,
            ratio_min: 0.5,
            ratio_max: 2.5,
            min_dv_mps: 0.0,
            loading_fraction: 0.85,
        }
    }

    fn taurus_spring() -> CombinedSpring {
        let c = MassClass::new(4).expect("class 4").curve();
        CombinedSpring::series(c, Some(c)).expect("spring")
    }

    fn predicted(spring: &CombinedSpring, closing_mps: f64) -> PredictedPulse {
        PredictedPulse::solve(spring, 1785.0, 1785.0, closing_mps, CONTACT).expect("solved")
    }

    /// Feeds the ego pulse of `actual` (true contact `contact_ns`) at 4 kHz until the matcher
    /// decides, with the prediction `pred` frozen at the wake-up.
    fn run(pred: PredictedPulse, actual: &ExactCollision, contact_ns: u64) -> MatchState {
        let mut m = PulseMatch::new(params());
        for k in 0..200u64 {
            let t_ns = contact_ns + k * 250_000;
            let s = AccelSample {
                t_ns,
                dt_s: 250e-6,
                decel_mps2: -actual.state_at(k as f64 * 250e-6).ego_accel_mps2,
            };
            m.push(&s, &mut |slot| {
                *slot = pred;
                true
            });
            if !matches!(m.state(), MatchState::Idle | MatchState::Fitting) {
                break;
            }
        }
        m.state()
    }

    #[test]
    fn the_predicted_onset_slope_is_k_v_over_the_ego_mass() {
        // Oracle: on the first segment F = k x with x ≈ v t, so a_ego = k v t / m_ego, with k
        // the series stiffness of two class-4 fronts: (175.6 kN / 40 mm) / 2.
        let spring = taurus_spring();
        let p = predicted(&spring, 26.0);
        let k = 175.6e3 / 0.040 / 2.0;
        let oracle = k * 26.0 / 1785.0 * 1e-3;
        assert!(
            (p.slope_mps2_per_ms / oracle - 1.0).abs() < 2e-3,
            "{} vs {oracle}",
            p.slope_mps2_per_ms
        );
        // First knee at x = 80 mm of relative deflection, reached after ≈ 80 mm / 26 m/s.
        assert!((p.knee_ms - 80.0 / 26.0).abs() < 0.1, "{}", p.knee_ms);
    }

    #[test]
    fn the_predicted_pulse_confirms_early_and_re_estimates_the_speed_it_was_predicted_for() {
        let spring = taurus_spring();
        let pred = predicted(&spring, 26.67);
        let MatchState::Confirmed(e) = run(pred, &pred.collision, CONTACT) else {
            panic!("no confirmation");
        };
        assert!(e.follows && (e.ratio - 1.0).abs() < 0.02, "{e:?}");
        // Wake at 1.5 g ≈ 0.45 ms after contact, + 1 ms of ramp: 4 kHz samples.
        let after_ms = (e.confirm_ns - CONTACT) as f64 * 1e-6;
        assert!((1.25..=1.75).contains(&after_ms), "{after_ms} ms");
        assert!(e.onset_ns.abs_diff(CONTACT) < 100_000, "fitted onset {e:?}");
    }

    #[test]
    fn a_faster_or_slower_crash_is_re_estimated_at_its_true_closing_speed() {
        let spring = taurus_spring();
        let pred = predicted(&spring, 26.67);
        for (v, follows) in [(29.0, true), (24.0, true), (40.0, false), (15.0, false)] {
            let actual = predicted(&spring, v).collision;
            let MatchState::Confirmed(e) = run(pred, &actual, CONTACT + 3 * MS) else {
                panic!("{v}: no confirmation");
            };
            assert!((e.closing_mps / v - 1.0).abs() < 0.03, "{v}: {e:?}");
            assert_eq!(e.follows, follows, "{v}: {e:?}");
        }
    }

    #[test]
    fn a_pulse_far_from_the_predicted_contact_or_severity_or_shape_does_not_match() {
        let spring = taurus_spring();
        let pred = predicted(&spring, 26.67);
        let actual = pred.collision;
        assert_eq!(
            run(pred, &actual, CONTACT + 40 * MS),
            MatchState::Mismatch(Mismatch::Timing)
        );
        let slow = predicted(&spring, 8.0).collision;
        assert_eq!(
            run(pred, &slow, CONTACT),
            MatchState::Mismatch(Mismatch::Severity)
        );
        // A pothole: 5 g for 1 ms, then nothing.
        let mut m = PulseMatch::new(params());
        for k in 0..40u64 {
            let decel = if k < 4 { 5.0 * G_MPS2 } else { 0.0 };
            let s = AccelSample {
                t_ns: CONTACT + k * 250_000,
                dt_s: 250e-6,
                decel_mps2: decel,
            };
            m.push(&s, &mut |slot| {
                *slot = pred;
                true
            });
        }
        assert_eq!(m.state(), MatchState::Mismatch(Mismatch::Shape));
        // Without a prediction an event is not matched at all.
        let mut m = PulseMatch::new(params());
        for k in 0..40u64 {
            let s = AccelSample {
                t_ns: CONTACT + k * 250_000,
                dt_s: 250e-6,
                decel_mps2: -actual.state_at(k as f64 * 250e-6).ego_accel_mps2,
            };
            m.push(&s, &mut |_| false);
        }
        assert_eq!(m.state(), MatchState::Idle);
    }
}
