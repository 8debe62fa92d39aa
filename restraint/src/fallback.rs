//! The accelerometer-only airbag algorithm: how the ECU discriminates crash severity when it
//! has no usable prediction (degraded inputs, no object tracked, a tracked object predicted
//! below the no-fire line, or a pulse that does not match the prediction), as a conventional
//! airbag ECU does.
//!
//! **Velocity-time boundary.** From the onset (first sample ≥ `confirm_wake_g`, the same
//! [`Onset`] as the generic confirmation) the velocity change Δv(τ) is integrated and compared
//! sample by sample with a threshold T(τ), piecewise linear through knots every
//! [`KNOT_SPACING_MS`] from 0 to [`WINDOW_MS`]: the first sample with Δv(τ) ≥ T(τ) is a
//! must-fire decision. Past [`WINDOW_MS`] the boundary stays at its last knot — the most Δv a
//! crash below the no-fire line carries at any time — until [`LATE_WINDOW_MS`]: a soft crash
//! (an offset barrier's honeycomb, a pole's bumper beam, a truck bed's hood) whose hard stage
//! comes late is fired late rather than not at all; a crash that has not reached it by then
//! is a no-fire (the decision is closed). Why it discriminates: in the two-mass model the pulse
//! rises with the closing speed (the onset slope is k·v/m), so at every τ a more severe crash
//! has more Δv; a bump saturates at its small total Δv, a severe crash crosses the boundary
//! within a few ms. The boundary is the velocity-time curve of a crash just above the no-fire
//! line (calibrated by `lut study fallback` on barrier and car-to-car pulses of the model,
//! restraint/README.md, "Crash phase"), so crashes below the no-fire line stay under it
//! and crashes above the must-fire line cross it in time.
//!
//! **Re-onset.** An event lasts until the deceleration has stayed under the wake threshold for
//! the quiet gap (10 ms), so a crash that follows a kerb strike, a pothole or a rough road
//! within it belongs to the earlier event. It is not judged from that event's onset: the
//! boundary would be read at the earlier event's τ (higher) and the loading rule against its
//! crest. When the deceleration rises through the wake threshold again after at least
//! [`RE_ONSET_GAP_MS`] below it (twice that within [`RE_ONSET_EARLY_MS`] of the segment's
//! start) and the event has not decided must-fire, the judged segment starts anew there (Δv,
//! τ, loading, persistence), and a closed no-fire is pending again.
//! A crash rising out of a misuse event's lobe seldom falls to the wake threshold in between
//! (a kerb strike's ringing or a rough road's lobe running into the contact); it falls into a
//! *valley*, under [`VALLEY_FRACTION`] of the segment's crest, and then rises past that crest —
//! the pulse departs from the earlier event's severity. The segment then restarts at the
//! valley's lowest sample (Δv and τ from there), if that sample reads under [`VALLEY_MAX_G`]
//! — under the wake threshold within [`RE_ONSET_EARLY_MS`] of the segment's start, where a
//! kerb strike's ringing pulls a low-speed crash's first ramp down to a few g —: a higher
//! trough is ringing on top of a crash already loading. A lobe that stays under the
//! earlier crest (a kerb strike's ringing on top of a low-speed crash) keeps the segment it is
//! in.
//! The decision still belongs to the event ([`FallbackDecision::Fire`]'s `onset_ns`); what it
//! adds is bounded by what it judges — one lobe of the signal, from rest or from a valley,
//! against the same boundary and floors as a first event.
//!
//! **Early restarts.** A restart within [`RE_ONSET_EARLY_MS`] of its segment's start may sit
//! inside one misuse event: a kerb strike's ringing that arrives in a low-speed crash first
//! cancels the crash's ramp (the dip or valley) and then swings forward, and the restarted
//! segment reads that forward swing without the backward one before it — more than the
//! event's net Δv. The satellites' low-crush lift bounds what a misuse event adds over the
//! whole event, so while it is on, the airbag must reach its lifted boundary read from the
//! replaced segment (the *parent*: its start, its Δv) as well. A 15.6 km/h barrier with a
//! 1.18 m/s kerb ringing 5 ms into it crossed the restarted segment's lifted boundary by
//! 9 mm/s at τ = 7 ms, the parent's not at all (`low-speed-crash-and-kerb-untracked`, 22 223
//! variants each of seeds 3, 11 and 13: 2 airbags → 0). Once the satellites see the front end
//! crush the lift is off and the restarted segment decides alone, as does a later restart.
//!
//! **Crush onset.** A rough road's lobe can run into the contact with neither a dip nor a
//! valley, and a severe crash's Δv rises as steeply as the boundary: read from the lobe's
//! onset, a 55 km/h barrier crossed the boundary only where it levels off, 40 ms late, and a
//! 42 km/h one not within the window. The crush-zone satellites date the contact on their own:
//! the front end folds (each satellite slows faster than the tunnel) from the contact on and
//! never before it, which no body motion does. When their severity first reaches the
//! occupant's line they give the end of the last cycle before the fold
//! ([`crate::satellites::CrushOnset`]); a segment that began [`CRUSH_RESTART_MIN_MS`] or more
//! before it restarts there, with the tunnel's Δv since (braking compensated as the samples
//! are) — the crash judged from its own contact, as without the lobe. In the library's crashes
//! (barriers of 22–56 km/h, cars of 31 + 31 and 48 + 48 km/h) the onset lies 0.5–0.9 ms after
//! the contact and 0.5–1.0 ms before the tunnel's own wake-up, where the same crash alone
//! starts its segment: the restarted segment reads a crash no more favourably than the crash
//! alone.
//!
//! It sees what a conventional sensor sees: the opponent's mass does not show in the first
//! tens of ms (see `crash_match`), so for car-to-car crashes it discriminates by closing
//! speed and structure; a light opponent's crash ends early and stays under the boundary.

use crate::accel::AccelSample;
use crate::confirm::{ConfirmParams, Loading, Onset, OnsetStep};
use crate::satellites::Relief;
use crate::settings::ConfigError;

/// Number of threshold knots (0, 4, … 60 ms).
pub const KNOTS: usize = 16;
/// Spacing of the knots, ms.
pub const KNOT_SPACING_MS: f64 = 4.0;
/// The decision window after the onset, ms (the last knot).
pub const WINDOW_MS: f64 = KNOT_SPACING_MS * (KNOTS - 1) as f64;
/// How long after its segment's onset an event is judged at all, ms: past [`WINDOW_MS`]
/// against the boundary's last knot. The library's softest must-fire crash, a truck bed's
/// underride at 40 km/h, reaches it ≈ 130 ms after the contact.
pub const LATE_WINDOW_MS: f64 = 150.0;

/// How long the deceleration must stay under the wake threshold inside an event before a new
/// rise is judged from its own start, ms (module docs, "Re-onset"). Shorter than the quiet
/// gap that ends the event; longer than the dips of a crash pulse's own noise.
pub const RE_ONSET_GAP_MS: f64 = 1.0;
/// A valley is where the deceleration falls under this fraction of the judged segment's crest
/// (module docs, "Re-onset"). Calibrated on the misuse matrix, both sides: at 0.5
/// `low-speed-crash-and-kerb-untracked` fired 2 airbags in 2 632 variants (seed 11: a 14 km/h
/// barrier's 10 g ramp falling to 5 g before a kerb lobe); at 0.4 it fires none and
/// `must-fire-after-event` misses 1 crash in 2 632 (seed 11), at 0.35 3 (a rough road's 6.5 g
/// lobe falling to 2.3 g at the contact), at 0 (the wake threshold's dip alone) 3 in 1 000
/// (seed 7).
pub const VALLEY_FRACTION: f64 = 0.4;
const RE_ONSET_GAP_NS: u64 = (RE_ONSET_GAP_MS * 1e6) as u64;
/// Within this long of the judged segment's start, ms, a re-onset needs twice
/// [`RE_ONSET_GAP_MS`] under the wake threshold: a kerb strike's ringing 0–10 ms into a
/// low-speed crash cancels the crash's first ramp for about a millisecond, and a segment
/// restarted there reads the crash's plateau plus the next ringing lobe against the boundary's
/// first knots (a 15 km/h barrier with a 1.1 m/s kerb fired; `low-speed-crash-and-kerb-untracked`,
/// seed 11). A crash after an earlier event rises later than this, or from a longer dip.
pub const RE_ONSET_EARLY_MS: f64 = 10.0;
const RE_ONSET_EARLY_NS: u64 = (RE_ONSET_EARLY_MS * 1e6) as u64;
/// A valley restarts the segment only where its lowest sample reads under this, g (twice the
/// default wake threshold): a valley higher than that is a ringing trough on top of a crash
/// already loading — its plateau under the dip — not the rest a crash rises out of. Calibrated
/// on both sides (100 035 variants each of seeds 3 and 11): without it
/// `low-speed-crash-and-kerb-untracked` fired 2 airbags (13.9 and 9.8 km/h barriers whose
/// kerb's trough sat at 6.5 and 4.5 g); with it `must-fire-after-event` misses 5 of 2 565 on
/// seed 3 instead of 4.
pub const VALLEY_MAX_G: f64 = 3.0;
const VALLEY_MAX_MPS2: f64 = VALLEY_MAX_G * crate::settings::G_MPS2;

/// The crush onset restarts a segment only this much after its start, ms: a segment that began
/// within it is the crash's own (its wake-up lags the contact by up to ≈ 1 ms, the satellites'
/// bins date the fold to the cycle).
pub const CRUSH_RESTART_MIN_MS: f64 = 2.0;
const CRUSH_RESTART_MIN_NS: u64 = (CRUSH_RESTART_MIN_MS * 1e6) as u64;

/// From this Δv of the judged segment on, the loading rule no longer applies, m/s. The rule
/// separates a crested misuse pulse (≤ 1.2 m/s: the matrix's envelope × 1.5) from a crash near
/// the severity floor; far above it, a crest seen earlier is ringing or a spike on top of a
/// crash (a kerb strike's ringing running into it, one wild sample at contact), and holding the
/// decision to that crest misses the crash. Not lower: a crash below the no-fire line with a
/// kerb strike in it carries up to ≈ 5 m/s in the window (16 km/h and 1.2 m/s), and at 2.5 m/s
/// the `low-speed-crash-and-kerb-untracked` family fired 23 more airbags of 445 (seed 7).
pub const LOADING_EXEMPT_DV_MPS: f64 = 5.0;

/// Default boundary, m/s at 0, 4, … 60 ms after the onset: the upper envelope (+10 %) of the
/// Δv(τ) curves of every no-fire crash of the calibration sweep as this algorithm measures
/// them, from `lut study fallback --derive` (restraint/README.md, "Crash phase";
/// `lut/tests/fallback.rs` checks that the sweep still derives exactly these numbers).
pub const DEFAULT_DV_MPS: [f64; KNOTS] = [
    0.10, 0.25, 0.70, 1.25, 1.90, 2.55, 3.30, 4.10, 4.90, 5.55, 6.50, 7.05, 7.35, 7.35, 7.35, 7.35,
];

/// Default boundary for an occupant not known to be belted, m/s at 0, 4, … 60 ms: the same
/// envelope (+10 %) over the calibration sweep's crashes below the unbelted no-fire line (14
/// km/h), from `lut study fallback --derive --unbelted` (`lut/tests/fallback.rs` checks it).
pub const DEFAULT_UNBELTED_DV_MPS: [f64; KNOTS] = [
    0.10, 0.20, 0.55, 1.00, 1.55, 2.15, 2.75, 3.45, 3.90, 4.55, 5.10, 5.25, 5.25, 5.25, 5.25, 5.25,
];

/// Default boundary of the pyrotechnic pretensioner on the conventional path: 0.6 × the
/// airbag's [`DEFAULT_DV_MPS`] (restraint/README.md, "No-fire lines").
pub const DEFAULT_PRETENSIONER_DV_MPS: [f64; KNOTS] = [
    0.06, 0.15, 0.42, 0.75, 1.14, 1.53, 1.98, 2.46, 2.94, 3.33, 3.90, 4.23, 4.41, 4.41, 4.41, 4.41,
];

/// The threshold must be finite, positive at τ = 0 (a decision needs some Δv) and
/// non-decreasing (Δv only grows during a crash).
pub fn validate_thresholds(key: &'static str, t: &[f64; KNOTS]) -> Result<(), ConfigError> {
    let bad = |i: usize, lo: f64| ConfigError {
        key,
        value: t.get(i).copied().unwrap_or(f64::NAN),
        lo,
        hi: 50.0,
    };
    let mut prev = 0.01;
    for (i, &v) in t.iter().enumerate() {
        if !(v.is_finite() && v >= prev && v <= 50.0) {
            return Err(bad(i, prev));
        }
        prev = v;
    }
    Ok(())
}

/// T(τ) for τ in ms (piecewise linear; the last knot's value beyond the window).
pub fn threshold_mps(t: &[f64; KNOTS], tau_ms: f64) -> f64 {
    let x = (tau_ms / KNOT_SPACING_MS).max(0.0);
    let i = x as usize; // saturating cast: NaN → 0, huge → usize::MAX
    match (t.get(i), t.get(i.saturating_add(1))) {
        (Some(a), Some(b)) => a + (b - a) * (x - i as f64),
        (Some(a), None) => *a,
        _ => t[KNOTS - 1],
    }
}

/// The algorithm's decision about the current event. Every decision belongs to one event
/// (one onset) and ends with it: a new event starts [`FallbackDecision::Pending`] again, so a
/// must-fire of an event that is over can never open a restraint for a later one.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FallbackDecision {
    /// No event, or inside the window and under the boundary.
    Pending,
    /// Must-fire: the boundary was reached at `at_ns` by the event that began at `onset_ns`.
    Fire {
        /// Sample time of the decision, ns.
        at_ns: u64,
        /// Onset of the event it belongs to, ns.
        onset_ns: u64,
    },
    /// No-fire: the window passed, or the event ended, under the boundary (at this sample
    /// time, ns). A new event starts pending again.
    NoFire(u64),
}

impl FallbackDecision {
    /// The must-fire of the event that began at `onset_ns` (and of no other), if decided.
    pub fn fire_of(self, onset_ns: u64) -> Option<u64> {
        match self {
            Self::Fire { at_ns, onset_ns: o } if o == onset_ns => Some(at_ns),
            _ => None,
        }
    }
}

/// What, besides the boundary, a must-fire needs at the sample that decides it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FireFloor {
    /// Δv since the onset at least this, m/s: the severity floor. A short high-g event (door
    /// slam, hammer blow, a spike) can cross the boundary's first knots, which are low so
    /// that a severe crash is recognised in its first ms; it never carries this much Δv.
    pub min_dv_mps: f64,
    /// Deceleration at least this for `samples` consecutive samples ending at the deciding
    /// sample, m/s² (the generic confirmation's persistence: a single-sample spike's Δv
    /// cannot decide, however large it is).
    pub decel_mps2: f64,
    /// See `decel_mps2`.
    pub samples: u32,
    /// The deciding sample's smoothed deceleration must still be at least this fraction of
    /// its peak since the onset ([`Loading`]: a crash is still loading its structures, a
    /// pothole or door slam that has carried this much Δv is already falling). 0 = off.
    pub loading_fraction: f64,
}

/// What a sample's decisions are judged against now besides the boundaries' shapes: each
/// restraint's severity floor with the road's lift and the satellites' relief, and the
/// boundaries' scale — fixed for a batch ([`FallbackAlgorithm::thresholds_now`]), so a sample
/// pays one compare for each.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Thresholds {
    /// The airbag's: Δv since the onset at least this, m/s.
    pub min_dv_mps: f64,
    /// The pyrotechnic pretensioner's: Δv since the onset at least this, m/s.
    pub pretensioner_min_dv_mps: f64,
    /// The boundaries' values times this.
    pub boundary_scale: f64,
    /// The loading rule is waived: the crush-zone satellites grant their whole relief.
    pub loading_waived: bool,
}

/// A valley of the judged segment (`FallbackAlgorithm::follow_valley`).
#[derive(Debug, Clone, Copy, PartialEq)]
struct Valley {
    /// Its lowest sample, ns.
    t_ns: u64,
    /// The event's Δv before that sample's interval, m/s.
    dv_mps: f64,
    /// The lowest sample's deceleration, m/s².
    decel_mps2: f64,
    /// The segment's crest before the valley, m/s².
    crest_before_mps2: f64,
}

/// A judged segment that an early restart replaced ([`FallbackAlgorithm::parent`]).
#[derive(Debug, Clone, Copy, PartialEq)]
struct Parent {
    /// Its start, ns.
    onset_ns: u64,
    /// The event's Δv before its first interval, m/s.
    base_dv_mps: f64,
}

/// One restraint's boundary and its decision on the current event.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Head {
    thresholds: [f64; KNOTS],
    /// The severity floor's Δv, m/s (before the road's lift and the satellites' relief).
    min_dv_mps: f64,
    decision: FallbackDecision,
}

impl Head {
    fn new(thresholds: [f64; KNOTS], min_dv_mps: f64) -> Self {
        Self {
            thresholds,
            min_dv_mps,
            decision: FallbackDecision::Pending,
        }
    }

    fn fired(&self) -> bool {
        matches!(self.decision, FallbackDecision::Fire { .. })
    }

    fn pending(&self) -> bool {
        self.decision == FallbackDecision::Pending
    }

    /// A pending decision closes as no-fire at `t_ns` (its event ended, or its window passed).
    fn close(&mut self, t_ns: u64) {
        if self.pending() {
            self.decision = FallbackDecision::NoFire(t_ns);
        }
    }

    /// Whether `dv` at `tau_ms` reaches the boundary (scaled, lifted) and the floor (asked
    /// first: under it, which most samples of an event are, the boundary is not read).
    fn reached(&self, tau_ms: f64, dv: f64, scale: f64, lift_mps: f64, floor_mps: f64) -> bool {
        dv >= floor_mps && dv >= scale * threshold_mps(&self.thresholds, tau_ms) + lift_mps
    }
}

/// State of the accelerometer-only algorithm: one pass over each sample (onset, Δv, loading,
/// persistence, re-onset) that both restraints' boundaries read — the airbag's and the
/// pyrotechnic pretensioner's differ only in their boundary and severity floor. One event at a
/// time; each decision belongs to the event and is forgotten when the next one begins.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FallbackAlgorithm {
    /// The airbag's head; its boundary is the occupant's of [`Self::airbag_boundaries`].
    airbag: Head,
    /// The airbag's boundaries for a belted occupant and for one not known to be belted.
    airbag_boundaries: [[f64; KNOTS]; 2],
    /// The airbag judges for a belted occupant ([`Self::set_belted`]).
    belted: bool,
    pretensioner: Head,
    floor: FireFloor,
    onset: Onset,
    loading: Loading,
    run: u32,
    /// Start of the judged segment of the event (its onset, or the latest re-onset), ns.
    segment_onset_ns: u64,
    /// The event's Δv before the segment's first interval, m/s: the segment's Δv is the
    /// event's less this (one integral for both).
    segment_base_dv_mps: f64,
    /// The segment that a restart within [`RE_ONSET_EARLY_MS`] of its start replaced (the
    /// earliest of a chain of such restarts): while the satellites' low-crush lift is on, the
    /// airbag's boundary is read from it as well (module docs, "Early restarts").
    parent: Option<Parent>,
    /// Since when the deceleration has been under the wake threshold inside the event, ns.
    dip_since_ns: Option<u64>,
    /// The latest valley of the segment: its lowest sample's time (ns) and the event's Δv
    /// there (m/s), and the segment's crest before it (m/s²).
    valley: Option<Valley>,
    /// The deceleration is under [`VALLEY_FRACTION`] of the crest now (a valley is open).
    in_valley: bool,
    /// What the airbag's boundary is lifted by for the samples to come, m/s
    /// ([`Self::lift_boundary`]).
    boundary_lift_mps: f64,
}

impl FallbackAlgorithm {
    /// The algorithm with a validated airbag boundary and floor; the pretensioner's is the
    /// same until [`Self::with_pretensioner`] sets its own.
    pub fn new(thresholds: [f64; KNOTS], floor: FireFloor) -> Self {
        Self {
            airbag: Head::new(thresholds, floor.min_dv_mps),
            airbag_boundaries: [thresholds; 2],
            belted: true,
            pretensioner: Head::new(thresholds, floor.min_dv_mps),
            floor,
            onset: Onset::default(),
            loading: Loading::default(),
            run: 0,
            segment_onset_ns: 0,
            segment_base_dv_mps: 0.0,
            parent: None,
            dip_since_ns: None,
            valley: None,
            in_valley: false,
            boundary_lift_mps: 0.0,
        }
    }

    /// The pyrotechnic pretensioner's validated boundary and severity floor (Δv, m/s; the
    /// floor's persistence and loading rule are the airbag's).
    pub fn with_pretensioner(mut self, thresholds: [f64; KNOTS], min_dv_mps: f64) -> Self {
        self.pretensioner = Head::new(thresholds, min_dv_mps);
        self
    }

    /// The airbag's validated boundary for an occupant not known to be belted (the belted
    /// one until this sets it; the floors are the same for both).
    pub fn with_unbelted(mut self, thresholds: [f64; KNOTS]) -> Self {
        self.airbag_boundaries[1] = thresholds;
        if !self.belted {
            self.airbag.thresholds = thresholds;
        }
        self
    }

    /// The occupant of the samples to come is known to be belted (`belted`), or not: the
    /// airbag's boundary is then the unbelted one. Its floor does not depend on the occupant:
    /// the floors hold the misuse events, whoever sits in the car. Set once a batch; a sample
    /// pays nothing for it.
    #[inline]
    pub fn set_belted(&mut self, belted: bool) {
        if belted != self.belted {
            self.belted = belted;
            self.airbag.thresholds = self.airbag_boundaries[usize::from(!belted)];
        }
    }

    /// The airbag's boundary now (the occupant's, [`Self::set_belted`]).
    pub fn airbag_boundary(&self) -> &[f64; KNOTS] {
        &self.airbag.thresholds
    }

    /// Whether a velocity change `dv_mps` at `tau_ms` after an onset reaches the airbag's
    /// (the occupant's) and the pyrotechnic pretensioner's boundaries and floors under `t`,
    /// the airbag's boundary lifted by `boundary_lift_mps`: the judgement of one sample of
    /// another sensor, without the persistence and loading rules
    /// ([`crate::crash::CrashMonitor::backup_boundaries`]).
    pub fn boundaries_reached(
        &self,
        tau_ms: f64,
        dv_mps: f64,
        t: Thresholds,
        boundary_lift_mps: f64,
    ) -> (bool, bool) {
        let scale = t.boundary_scale;
        (
            self.airbag
                .reached(tau_ms, dv_mps, scale, boundary_lift_mps, t.min_dv_mps),
            self.pretensioner
                .reached(tau_ms, dv_mps, scale, 0.0, t.pretensioner_min_dv_mps),
        )
    }

    /// Lifts the boundary by `lift_mps` for the samples to come (the satellites' low-crush
    /// lift, [`crate::satellites::Relief::boundary_lift_mps`]; set once a batch, 0 by default).
    pub fn lift_boundary(&mut self, lift_mps: f64) {
        self.boundary_lift_mps = lift_mps;
    }

    /// Starts the judged segment at sample `s` (the event's wake-up, or a re-onset; `base`:
    /// the event's Δv before `s`'s interval), its Δv from the interval that ends at `s` on, as
    /// [`Onset`]'s. A restraint that has fired in the event keeps its decision.
    fn start_segment(&mut self, s: &AccelSample, base_dv_mps: f64) {
        self.start_segment_at(s.t_ns, s, base_dv_mps);
    }

    /// [`Self::start_segment`] with the segment's τ and Δv counted from `onset_ns` (a valley
    /// before `s`).
    fn start_segment_at(&mut self, onset_ns: u64, s: &AccelSample, base_dv_mps: f64) {
        self.start_segment_from(onset_ns, s.decel_mps2, base_dv_mps);
    }

    /// Restarts the judged segment inside the event (a re-onset or a valley at `onset_ns`):
    /// a restart within [`RE_ONSET_EARLY_MS`] of the segment's start keeps that segment as the
    /// parent, a later one judges alone.
    fn restart_segment_at(&mut self, onset_ns: u64, s: &AccelSample, base_dv_mps: f64) {
        self.parent = if self.early_in_segment(onset_ns) {
            self.parent.or(Some(Parent {
                onset_ns: self.segment_onset_ns,
                base_dv_mps: self.segment_base_dv_mps,
            }))
        } else {
            None
        };
        self.start_segment_at(onset_ns, s, base_dv_mps);
    }

    /// The judged segment from `onset_ns` with the event's Δv `base_dv_mps` there, the
    /// loading rule from `decel_mps2`; a decision not fired is pending again.
    fn start_segment_from(&mut self, onset_ns: u64, decel_mps2: f64, base_dv_mps: f64) {
        self.segment_onset_ns = onset_ns;
        self.segment_base_dv_mps = base_dv_mps;
        self.dip_since_ns = None;
        self.valley = None;
        self.in_valley = false;
        self.loading.start(decel_mps2);
        for h in [&mut self.airbag, &mut self.pretensioner] {
            if !h.fired() {
                h.decision = FallbackDecision::Pending;
            }
        }
    }

    /// The thresholds of the samples to come: each floor with `floor_lift_mps` (what the
    /// road's roughness adds to it now, [`crate::roughness`]) and `relief` (what the crush-zone
    /// satellites take off the floors, the lift and the boundaries now, [`crate::satellites`]).
    pub fn thresholds_now(&self, floor_lift_mps: f64, relief: Relief) -> Thresholds {
        Thresholds {
            min_dv_mps: relief.floor_mps(self.airbag.min_dv_mps, floor_lift_mps),
            pretensioner_min_dv_mps: relief.floor_mps(self.pretensioner.min_dv_mps, floor_lift_mps),
            boundary_scale: relief.boundary_mps(1.0),
            loading_waived: relief.fraction >= 1.0,
        }
    }

    /// Feeds one plausible sample (`p`: the wake threshold and quiet gap of the onset; `t`:
    /// [`Self::thresholds_now`]).
    pub fn push(&mut self, p: &ConfirmParams, s: &AccelSample, t: &Thresholds) {
        let before_dv = self.onset.delta_v_mps();
        match self.onset.push(p, s) {
            OnsetStep::Quiet => return,
            OnsetStep::Reset => {
                // An event that ended under the boundary was a no-fire; a fired event is over.
                self.airbag.close(s.t_ns);
                self.pretensioner.close(s.t_ns);
                self.run = 0;
                self.dip_since_ns = None;
                return;
            }
            OnsetStep::Woke => {
                // A new event: no decision of an earlier one carries over.
                self.airbag.decision = FallbackDecision::Pending;
                self.pretensioner.decision = FallbackDecision::Pending;
                self.run = 0;
                self.parent = None;
                self.start_segment(s, 0.0);
            }
            OnsetStep::Awake => {
                let above = s.decel_mps2 >= p.wake_mps2;
                let not_fired = !(self.airbag.fired() && self.pretensioner.fired());
                let re_onset = above
                    && self
                        .dip_since_ns
                        .is_some_and(|d| s.t_ns.saturating_sub(d) >= self.re_onset_gap_ns(s.t_ns))
                    && not_fired;
                if re_onset {
                    self.restart_segment_at(s.t_ns, s, before_dv);
                } else {
                    self.loading.push(s.decel_mps2, s.dt_s);
                    if above {
                        self.dip_since_ns = None;
                    } else if self.dip_since_ns.is_none() {
                        self.dip_since_ns = Some(s.t_ns);
                    }
                    self.follow_valley(p, s, before_dv, not_fired);
                }
            }
        }
        self.run = if s.decel_mps2 >= self.floor.decel_mps2 {
            self.run.saturating_add(1)
        } else {
            0
        };
        if !(self.airbag.pending() || self.pretensioner.pending()) {
            return;
        }
        let Some(onset) = self.onset.onset_ns() else {
            return;
        };
        let tau_ms = s.t_ns.saturating_sub(self.segment_onset_ns) as f64 * 1e-6;
        let dv = self.onset.delta_v_mps() - self.segment_base_dv_mps;
        if tau_ms > LATE_WINDOW_MS {
            self.airbag.close(s.t_ns);
            self.pretensioner.close(s.t_ns);
            return;
        }
        // Persistence and loading are both restraints' (asked once, and only of a sample
        // whose Δv reaches a boundary).
        let fire = FallbackDecision::Fire {
            at_ns: s.t_ns,
            onset_ns: onset,
        };
        let scale = t.boundary_scale;
        let lift = self.boundary_lift_mps;
        let airbag = self.airbag.pending()
            && self.airbag.reached(tau_ms, dv, scale, lift, t.min_dv_mps)
            && self.parent.is_none_or(|q| {
                // The low-crush lift bounds what a misuse event adds over the whole event, not
                // over the swing a segment restarted inside it reads (module docs).
                let tau_ms = s.t_ns.saturating_sub(q.onset_ns) as f64 * 1e-6;
                let dv = self.onset.delta_v_mps() - q.base_dv_mps;
                lift <= 0.0 || self.airbag.reached(tau_ms, dv, scale, lift, t.min_dv_mps)
            });
        let pretensioner = self.pretensioner.pending()
            && self
                .pretensioner
                .reached(tau_ms, dv, scale, 0.0, t.pretensioner_min_dv_mps);
        if (airbag || pretensioner)
            && self.run >= self.floor.samples
            && (t.loading_waived || self.loading())
        {
            if airbag {
                self.airbag.decision = fire;
            }
            if pretensioner {
                self.pretensioner.decision = fire;
            }
        }
    }

    /// The dip under the wake threshold a re-onset at `t_ns` needs, ns: twice
    /// [`RE_ONSET_GAP_MS`] within [`RE_ONSET_EARLY_MS`] of the segment's start.
    fn re_onset_gap_ns(&self, t_ns: u64) -> u64 {
        if self.early_in_segment(t_ns) {
            2 * RE_ONSET_GAP_NS
        } else {
            RE_ONSET_GAP_NS
        }
    }

    /// `t_ns` lies within [`RE_ONSET_EARLY_MS`] of the judged segment's start.
    #[inline]
    fn early_in_segment(&self, t_ns: u64) -> bool {
        t_ns.saturating_sub(self.segment_onset_ns) < RE_ONSET_EARLY_NS
    }

    /// Follows the segment's valleys (module docs, "Re-onset"): the lowest sample of the latest
    /// dip under [`VALLEY_FRACTION`] of the crest is kept, and once the deceleration (as
    /// [`Loading`] smooths it) rises past the crest before that dip, the segment restarts at
    /// the valley. A valley needs a crest of more than 1 / [`VALLEY_FRACTION`] times the wake
    /// threshold: under it, the dip under the wake threshold is the re-onset's rule (a quiet
    /// stretch's noise is no valley).
    fn follow_valley(
        &mut self,
        p: &ConfirmParams,
        s: &AccelSample,
        before_dv: f64,
        not_fired: bool,
    ) {
        let crest = self.loading.peak_mps2();
        let level = VALLEY_FRACTION * crest;
        if level > p.wake_mps2 && s.decel_mps2 < level {
            match &mut self.valley {
                // Deeper into the open valley: its lowest sample moves, its crest stays.
                Some(v) if self.in_valley => {
                    if s.decel_mps2 < v.decel_mps2 {
                        (v.t_ns, v.dv_mps, v.decel_mps2) = (s.t_ns, before_dv, s.decel_mps2);
                    }
                }
                _ => {
                    self.valley = Some(Valley {
                        t_ns: s.t_ns,
                        dv_mps: before_dv,
                        decel_mps2: s.decel_mps2,
                        crest_before_mps2: crest,
                    })
                }
            }
            self.in_valley = true;
            return;
        }
        self.in_valley = false;
        if let Some(v) = self.valley {
            // Early in a segment the trough must reach the wake threshold, as a re-onset's dip
            // must be longer there (`RE_ONSET_EARLY_MS`).
            let trough_max = if self.early_in_segment(v.t_ns) {
                p.wake_mps2
            } else {
                VALLEY_MAX_MPS2
            };
            if not_fired && crest > v.crest_before_mps2 && v.decel_mps2 <= trough_max {
                self.restart_segment_at(v.t_ns, s, v.dv_mps);
            }
        }
    }

    /// Restarts the judged segment where the crush-zone satellites date the front end's first
    /// fold (module docs, "Crush onset"): at `at_ns`, with `since_dv_mps` of the event's Δv
    /// after it (the tunnel's, braking compensated as the samples are), the loading rule from
    /// the latest sample's `decel_mps2`. Only inside an event whose segment began at least
    /// [`CRUSH_RESTART_MIN_MS`] earlier and not both restraints fired; returns whether it did.
    pub fn restart_at_crush(&mut self, at_ns: u64, since_dv_mps: f64, decel_mps2: f64) -> bool {
        let later = at_ns.saturating_sub(self.segment_onset_ns) >= CRUSH_RESTART_MIN_NS;
        if !(self.onset.awake() && later && since_dv_mps.is_finite())
            || (self.airbag.fired() && self.pretensioner.fired())
        {
            return false;
        }
        let base = self.onset.delta_v_mps() - since_dv_mps;
        self.parent = None;
        self.start_segment_from(at_ns, decel_mps2, base);
        true
    }

    /// The airbag's decision.
    pub fn decision(&self) -> FallbackDecision {
        self.airbag.decision
    }

    /// The pyrotechnic pretensioner's decision.
    pub fn pretensioner_decision(&self) -> FallbackDecision {
        self.pretensioner.decision
    }

    /// Onset of the event in progress.
    pub fn onset_ns(&self) -> Option<u64> {
        self.onset.onset_ns()
    }

    /// Start of the segment of the event in progress that is being judged (its onset, or the
    /// latest re-onset), ns: the decision window runs from here.
    pub fn segment_onset_ns(&self) -> Option<u64> {
        self.onset.awake().then_some(self.segment_onset_ns)
    }

    /// The velocity change of the current event since its onset, m/s (0 when quiet).
    pub fn event_dv_mps(&self) -> f64 {
        self.onset.delta_v_mps()
    }

    /// The event is still loading (its judged segment's smoothed deceleration at least
    /// `loading_fraction` of its peak, or the segment past [`LOADING_EXEMPT_DV_MPS`]): what the
    /// loading rule asks of a deciding sample, asked of the newest one.
    pub fn loading(&self) -> bool {
        let dv = self.onset.delta_v_mps() - self.segment_base_dv_mps;
        dv >= LOADING_EXEMPT_DV_MPS || self.loading.holds(self.floor.loading_fraction)
    }

    /// Whether an event is in progress.
    pub fn awake(&self) -> bool {
        self.onset.awake()
    }

    /// See [`Onset::note_quiet`](crate::confirm::Onset::note_quiet).
    pub fn note_quiet(&mut self, decel_mps2: f64) {
        self.onset.note_quiet(decel_mps2);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::settings::G_MPS2;

    fn params() -> ConfirmParams {
        ConfirmParams {
            wake_mps2: 1.5 * G_MPS2,
            decel_mps2: 4.0 * G_MPS2,
            samples: 3,
            delta_v_mps: 0.5,
            reset_gap_ns: 10_000_000,
        }
    }

    /// The oracle boundary: linear, 0.1 + 0.1·τ/4 m/s.
    fn linear() -> [f64; KNOTS] {
        core::array::from_fn(|i| 0.1 + 0.1 * i as f64)
    }

    /// No floor beyond the boundary: one sample of persistence at 0 g, no Δv floor.
    const NO_FLOOR: FireFloor = FireFloor {
        min_dv_mps: 0.0,
        decel_mps2: 0.0,
        samples: 1,
        loading_fraction: 0.0,
    };

    fn floor() -> FireFloor {
        FireFloor {
            min_dv_mps: 1.0,
            decel_mps2: 4.0 * G_MPS2,
            samples: 3,
            loading_fraction: 0.85,
        }
    }

    /// Runs a constant deceleration `g` from t = 0 for `ms` at 1 kHz.
    fn run(f: &mut FallbackAlgorithm, g: f64, ms: u64) {
        run_for(f, g, ms, true);
    }

    /// [`run`] for an occupant `belted` or not known to be.
    fn run_for(f: &mut FallbackAlgorithm, g: f64, ms: u64, belted: bool) {
        f.set_belted(belted);
        for k in 0..ms {
            f.push(
                &params(),
                &AccelSample {
                    t_ns: 1_000_000_000 + k * 1_000_000,
                    dt_s: 1e-3,
                    decel_mps2: g * G_MPS2,
                },
                &f.thresholds_now(0.0, Relief::NONE),
            );
        }
    }

    /// A 2 g road lobe for 20 ms (under the linear boundary all along), then a 5 g crash. Read
    /// from the lobe's onset the crash meets the boundary τ + 20 ms ahead; restarted at the
    /// crush onset the satellites give three samples into the crash (the end of the lobe's last
    /// sample, with the tunnel's Δv since), it fires within a sample of the same crash without
    /// the lobe.
    #[test]
    fn a_crush_onset_restarts_the_segment_as_if_the_lobe_had_not_been() {
        const MS: u64 = 1_000_000;
        let t0 = 1_000_000_000;
        let sample = |k: u64, g: f64| AccelSample {
            t_ns: t0 + k * MS,
            dt_s: 1e-3,
            decel_mps2: g * G_MPS2,
        };
        let fire_at = |f: &FallbackAlgorithm| match f.decision() {
            FallbackDecision::Fire { at_ns, .. } => (at_ns - t0) / MS,
            d => panic!("{d:?}"),
        };
        let th = Thresholds {
            min_dv_mps: 0.0,
            pretensioner_min_dv_mps: 0.0,
            boundary_scale: 1.0,
            loading_waived: false,
        };
        let mut clean = FallbackAlgorithm::new(linear(), NO_FLOOR);
        for k in 20..80 {
            clean.push(&params(), &sample(k, 5.0), &th);
        }
        let g = |k: u64| if k < 20 { 2.0 } else { 5.0 };
        let (mut lobe, mut restarted) = (
            FallbackAlgorithm::new(linear(), NO_FLOOR),
            FallbackAlgorithm::new(linear(), NO_FLOOR),
        );
        for k in 0..80 {
            lobe.push(&params(), &sample(k, g(k)), &th);
            restarted.push(&params(), &sample(k, g(k)), &th);
            if k == 22 {
                let since_dv_mps = 3.0 * 5.0 * G_MPS2 * 1e-3;
                assert!(restarted.restart_at_crush(t0 + 19 * MS, since_dv_mps, 5.0 * G_MPS2));
                assert_eq!(restarted.segment_onset_ns(), Some(t0 + 19 * MS));
            }
        }
        let clean_at = fire_at(&clean);
        assert!(
            fire_at(&restarted).abs_diff(clean_at) <= 1,
            "{} vs {clean_at}",
            fire_at(&restarted)
        );
        assert!(
            fire_at(&lobe) > clean_at + 2,
            "{} vs {clean_at}",
            fire_at(&lobe)
        );
        // Not within 2 ms of the segment's start, not outside an event.
        let mut f = FallbackAlgorithm::new(linear(), NO_FLOOR);
        f.push(&params(), &sample(0, 5.0), &th);
        assert!(!f.restart_at_crush(t0 + MS, 0.0, 5.0 * G_MPS2));
        let mut quiet = FallbackAlgorithm::new(linear(), NO_FLOOR);
        assert!(!quiet.restart_at_crush(t0 + 19 * MS, 0.0, 0.0));
    }

    #[test]
    fn the_boundary_is_piecewise_linear_through_its_knots() {
        let t = DEFAULT_DV_MPS;
        assert_eq!(threshold_mps(&t, 0.0), t[0]);
        assert!((threshold_mps(&t, 6.0) - 0.5 * (t[1] + t[2])).abs() < 1e-12);
        assert_eq!(threshold_mps(&t, 40.0), t[10]);
        assert_eq!(threshold_mps(&t, 60.0), t[15]);
        assert_eq!(threshold_mps(&t, 1e9), t[15]);
        assert_eq!(threshold_mps(&t, f64::NAN), t[0]);
        validate_thresholds("fallback_dv_mps", &t).expect("default boundary is valid");
        let mut bad = t;
        bad[3] = bad[2] - 0.1;
        assert_eq!(
            validate_thresholds("fallback_dv_mps", &bad)
                .unwrap_err()
                .key,
            "fallback_dv_mps"
        );
        bad = t;
        bad[0] = 0.0;
        assert!(validate_thresholds("fallback_dv_mps", &bad).is_err());
        validate_thresholds("pretensioner_dv_mps", &DEFAULT_PRETENSIONER_DV_MPS)
            .expect("default pretensioner boundary is valid");
    }

    #[test]
    fn a_constant_pulse_fires_where_its_velocity_line_meets_the_boundary() {
        // Oracle: Δv after n samples of a = n·a·1 ms (the wake sample counts), τ = (n − 1) ms;
        // fire at the first n with n·a·1e-3 ≥ T(n − 1). Boundary 0.1 + 0.1·τ/4 m/s (linear).
        let lin = linear();
        // Δv after n samples of a from rest (trapezoidal): (n − ½)·a·1 ms, at τ = n − 1 ms.
        let mut f = FallbackAlgorithm::new(lin, NO_FLOOR);
        run(&mut f, 5.0, 80); // a = 49.03 m/s²: (n − ½)·0.04903 ≥ 0.075 + 0.025 n → n ≥ 4.14
        assert_eq!(
            f.decision(),
            FallbackDecision::Fire {
                at_ns: 1_000_000_000 + 4_000_000,
                onset_ns: 1_000_000_000
            }
        );
        // 2 g: (n − ½)·0.0196 ≥ 0.075 + 0.025 n never holds inside the 60 ms window (slope
        // 0.0196 < 0.025); past it the boundary stays at its last knot, 1.6 m/s, which the
        // velocity line meets at (n − ½)·0.0196133 ≥ 1.6 → n = 83, τ = 82 ms: a late fire.
        let mut f = FallbackAlgorithm::new(lin, NO_FLOOR);
        run(&mut f, 2.0, 80);
        assert_eq!(
            f.decision(),
            FallbackDecision::Pending,
            "under the last knot"
        );
        let mut f = FallbackAlgorithm::new(lin, NO_FLOOR);
        run(&mut f, 2.0, 200);
        assert_eq!(
            f.decision(),
            FallbackDecision::Fire {
                at_ns: 1_000_000_000 + 82_000_000,
                onset_ns: 1_000_000_000
            }
        );
        // A boundary of 5 m/s throughout: 2 g carries 2.9 m/s by 150 ms — closed, no fire, at
        // the first sample after the late window.
        let mut f = FallbackAlgorithm::new([5.0; KNOTS], NO_FLOOR);
        run(&mut f, 2.0, 200);
        assert_eq!(
            f.decision(),
            FallbackDecision::NoFire(1_000_000_000 + 151_000_000)
        );
    }

    #[test]
    fn an_occupant_not_known_to_be_belted_is_judged_against_the_unbelted_boundary() {
        // The oracle above: 2 g never meets the linear boundary (slope 0.0196 < 0.025 m/s per
        // ms); against half of it (0.05 + 0.0125 n) it fires at the first n with
        // (n − ½)·0.0196 ≥ 0.0375 + 0.0125 n → n ≥ 6.7, the sample at τ = 6 ms. The
        // pretensioner keeps its own boundary whoever sits in the car.
        let lin = linear();
        let half = lin.map(|v| v / 2.0);
        let fresh = || {
            FallbackAlgorithm::new(lin, NO_FLOOR)
                .with_unbelted(half)
                .with_pretensioner(lin, 0.0)
        };
        // Past the 60 ms window, under the boundary's last knot: still judged (late window).
        let mut belted = fresh();
        run_for(&mut belted, 2.0, 80, true);
        assert_eq!(belted.decision(), FallbackDecision::Pending);
        let mut unbelted = fresh();
        run_for(&mut unbelted, 2.0, 80, false);
        assert_eq!(
            unbelted.decision(),
            FallbackDecision::Fire {
                at_ns: 1_000_000_000 + 6_000_000,
                onset_ns: 1_000_000_000
            }
        );
        assert_eq!(unbelted.pretensioner_decision(), FallbackDecision::Pending);
        assert_eq!(unbelted.airbag_boundary(), &half);
        unbelted.set_belted(true);
        assert_eq!(unbelted.airbag_boundary(), &lin);
    }

    #[test]
    fn the_pretensioner_reads_the_same_pass_against_its_own_boundary() {
        // The oracle above on the pretensioner's boundary (linear 0.1 + 0.1·τ/4 m/s), the
        // airbag's out of reach: the pretensioner decides at τ = 4 ms, the airbag closes under
        // the boundary at the first sample after the late window (150 ms).
        let lin = linear();
        let mut f =
            FallbackAlgorithm::new([f64::INFINITY; KNOTS], NO_FLOOR).with_pretensioner(lin, 0.0);
        run(&mut f, 5.0, 160);
        assert_eq!(
            f.pretensioner_decision(),
            FallbackDecision::Fire {
                at_ns: 1_000_000_000 + 4_000_000,
                onset_ns: 1_000_000_000
            }
        );
        assert_eq!(
            f.decision(),
            FallbackDecision::NoFire(1_000_000_000 + 151_000_000)
        );
    }

    #[test]
    fn a_boundary_lift_moves_the_fire_to_where_the_velocity_line_meets_the_lifted_boundary() {
        // The same oracle with the boundary lifted by 0.3 m/s: 5 g fires at the first n with
        // (n − ½)·0.04903 ≥ 0.375 + 0.025 n → n ≥ 16.1, the sample at τ = 16 ms.
        let lin = linear();
        let mut f = FallbackAlgorithm::new(lin, NO_FLOOR);
        f.lift_boundary(0.3);
        run(&mut f, 5.0, 80);
        assert_eq!(
            f.decision(),
            FallbackDecision::Fire {
                at_ns: 1_000_000_000 + 16_000_000,
                onset_ns: 1_000_000_000
            }
        );
    }

    #[test]
    fn braking_never_wakes_it_and_a_new_event_after_the_quiet_gap_is_judged_afresh() {
        let mut f = FallbackAlgorithm::new(DEFAULT_DV_MPS, NO_FLOOR);
        run(&mut f, 1.2, 200);
        assert_eq!(
            (f.decision(), f.onset_ns()),
            (FallbackDecision::Pending, None)
        );
        let mut f = FallbackAlgorithm::new([0.1; KNOTS], NO_FLOOR);
        run(&mut f, 2.0, 1); // Δv 0.0196 < 0.1: pending
        assert_eq!(f.decision(), FallbackDecision::Pending);
    }

    /// Feeds `g(k)` for sample k = 0.. at 1 kHz from t = 1 s.
    fn run_fn(f: &mut FallbackAlgorithm, ms: u64, g: impl Fn(u64) -> f64) {
        run_fn_from(f, 0, ms, g);
    }

    /// Feeds `g(k)` for samples k = `from`.. (`ms` of them) at 1 kHz, sample k at 1 s + k ms.
    fn run_fn_from(f: &mut FallbackAlgorithm, from: u64, ms: u64, g: impl Fn(u64) -> f64) {
        for k in from..from + ms {
            f.push(
                &params(),
                &AccelSample {
                    t_ns: 1_000_000_000 + k * 1_000_000,
                    dt_s: 1e-3,
                    decel_mps2: g(k) * G_MPS2,
                },
                &f.thresholds_now(0.0, Relief::NONE),
            );
        }
    }

    #[test]
    fn an_event_is_loading_while_its_deceleration_holds_near_its_crest() {
        // 2 g/ms up to 20 g, 5 ms at 20 g, then down at 2 g/ms: loading on the ramp and the
        // plateau; three samples into the fall (14 g, 70 % of the crest; the smoothing's 0.25 ms
        // lags it by < 1 g) it is not, as every sample after.
        let g = |k: u64| match k {
            0..=9 => 2.0 * (k + 1) as f64,
            10..=14 => 20.0,
            _ => (20.0 - 2.0 * (k - 14) as f64).max(0.0),
        };
        let mut f = FallbackAlgorithm::new([f64::INFINITY; KNOTS], floor());
        for k in 0..15 {
            run_fn_from(&mut f, k, 1, g);
            assert!(f.loading(), "sample {k}: {} g", g(k));
        }
        run_fn_from(&mut f, 15, 3, g);
        assert!(!f.loading());
        // A segment past LOADING_EXEMPT_DV_MPS is loading whatever its deceleration: 20 g for
        // 30 ms carries 5.9 m/s, then 3 g.
        let mut f = FallbackAlgorithm::new([f64::INFINITY; KNOTS], floor());
        run_fn(&mut f, 40, |k| if k < 30 { 20.0 } else { 3.0 });
        assert!(f.loading());
    }

    /// A 30 g crest (three samples: the loading rule's median takes it) and then a 10 g
    /// crash, under the loading rule's 85 % of that crest for good: with less than the whole
    /// relief the decision waits for `LOADING_EXEMPT_DV_MPS` (≈ 45 ms); with the whole relief
    /// it fires where the Δv meets the floor (1.0 m/s: 0.88 m/s of the crest plus 0.1 m/s per
    /// ms), two samples after the crest.
    #[test]
    fn the_whole_relief_waives_the_loading_rule() {
        let relief = |fraction: f64| Relief {
            fraction,
            floor_mps: 1.0,
            boundary_scale: 1.0,
            boundary_lift_mps: 0.0,
            fold_scale: 1.0,
        };
        let fire_ms = |fraction: f64| {
            let mut f = FallbackAlgorithm::new(linear(), floor());
            for k in 0..60u64 {
                f.push(
                    &params(),
                    &AccelSample {
                        t_ns: 1_000_000_000 + k * 1_000_000,
                        dt_s: 1e-3,
                        decel_mps2: if k < 3 { 30.0 } else { 10.0 } * G_MPS2,
                    },
                    &f.thresholds_now(0.0, relief(fraction)),
                );
                if let FallbackDecision::Fire { at_ns, .. } = f.decision() {
                    return Some((at_ns - 1_000_000_000) / 1_000_000);
                }
            }
            None
        };
        let waived = fire_ms(1.0).expect("fires");
        assert!((4..=5).contains(&waived), "{waived} ms");
        let held = fire_ms(0.99).expect("fires past the exemption");
        assert!(held >= 40, "{held} ms");
        assert!(fire_ms(0.0).is_some_and(|t| t >= 40));
    }

    #[test]
    fn a_spike_never_decides_and_a_decision_ends_with_its_event() {
        // Reproduction: one 15 g sample (Δv 0.147 m/s ≥ T(1 ms) = 0.1375) used to
        // latch a must-fire for good; a 4.5 g × 40 ms bump 0.5 s later then fired the airbag.
        for spike_g in [15.0, 25.0, 40.0, 60.0, 150.0] {
            let mut f = FallbackAlgorithm::new(DEFAULT_DV_MPS, floor());
            run_fn(&mut f, 30, |k| if k == 5 { spike_g } else { 0.0 });
            assert!(
                !matches!(f.decision(), FallbackDecision::Fire { .. }),
                "{spike_g} g spike: {:?}",
                f.decision()
            );
        }
        // Without the floor the old behaviour is visible: the spike alone decides must-fire…
        let mut f = FallbackAlgorithm::new(DEFAULT_DV_MPS, NO_FLOOR);
        run_fn(&mut f, 30, |k| if k == 5 { 15.0 } else { 0.0 });
        // …and ended with its event (reset after the 10 ms quiet gap): a later event starts
        // pending and cannot use it.
        assert!(matches!(f.decision(), FallbackDecision::Fire { .. }));
        run_fn(&mut f, 1, |_| 4.5);
        assert_eq!(f.decision(), FallbackDecision::Pending);
        assert_eq!(
            FallbackDecision::Fire {
                at_ns: 7,
                onset_ns: 5
            }
            .fire_of(6),
            None
        );
    }

    /// Feeds `n` samples at 8 kHz (so short events are resolved) of the deceleration
    /// `g_at(t_ms)`, in g; returns the decision.
    fn feed_8khz(f: &mut FallbackAlgorithm, n: u64, g_at: impl Fn(f64) -> f64) -> FallbackDecision {
        for k in 0..n {
            f.push(
                &params(),
                &AccelSample {
                    t_ns: 1_000_000_000 + k * 125_000,
                    dt_s: 125e-6,
                    decel_mps2: g_at(k as f64 * 0.125) * G_MPS2,
                },
                &f.thresholds_now(0.0, Relief::NONE),
            );
        }
        f.decision()
    }

    /// Feeds a half-sine of `peak_g` × `dur_ms` (8 kHz) starting at 10 ms, `n` samples in
    /// all; returns the decision.
    fn half_sine_n(
        f: &mut FallbackAlgorithm,
        peak_g: f64,
        dur_ms: f64,
        n: u64,
    ) -> FallbackDecision {
        feed_8khz(f, n, |t_ms| {
            let x = (t_ms - 10.0) / dur_ms;
            if (0.0..=1.0).contains(&x) {
                peak_g * (core::f64::consts::PI * x).sin()
            } else {
                0.0
            }
        })
    }

    /// [`half_sine_n`] over 150 ms.
    fn half_sine(f: &mut FallbackAlgorithm, peak_g: f64, dur_ms: f64) -> FallbackDecision {
        half_sine_n(f, peak_g, dur_ms, 1200)
    }

    #[test]
    fn a_pulse_that_has_peaked_cannot_decide_and_a_rising_one_decides_as_before() {
        // Oracle (closed form, `Loading` docs): a half-sine of total Δv D = 2·A·T/π still
        // holds k = 0.85 of its crest until it has carried (1 + √(1 − k²))/2 = 0.764 D. With
        // the floor f = 1.0 m/s and the boundary out of the way (flat 0.05 m/s) it can decide
        // only if 0.764 D ≥ 1.0, i.e. D ≥ 1.31 m/s; without the rule, from D ≥ 1.0 m/s.
        let flat = [0.05; KNOTS];
        let mut no_rule = floor();
        no_rule.loading_fraction = 0.0;
        for (peak_g, dur_ms) in [(15.0, 12.0), (12.0, 15.0), (10.0, 18.0), (20.0, 9.0)] {
            let dv = 2.0 * peak_g * G_MPS2 * dur_ms * 1e-3 / core::f64::consts::PI;
            assert!(
                (1.10..1.28).contains(&dv),
                "{peak_g} g × {dur_ms} ms: Δv {dv}"
            );
            let with = half_sine(&mut FallbackAlgorithm::new(flat, floor()), peak_g, dur_ms);
            let without = half_sine(&mut FallbackAlgorithm::new(flat, no_rule), peak_g, dur_ms);
            assert!(
                !matches!(with, FallbackDecision::Fire { .. }),
                "{peak_g} × {dur_ms}: {with:?}"
            );
            assert!(
                matches!(without, FallbackDecision::Fire { .. }),
                "{peak_g} × {dur_ms}: {without:?}"
            );
        }
        // Well above the limit (D ≈ 1.6 m/s) the pulse decides while still near its crest.
        let d = half_sine(&mut FallbackAlgorithm::new(flat, floor()), 20.0, 13.0);
        assert!(matches!(d, FallbackDecision::Fire { .. }), "{d:?}");
        // A rising pulse (a crash's ramp, 2 g/ms) decides at the same sample with the rule
        // as without it.
        let ramp = |fl: FireFloor| {
            feed_8khz(&mut FallbackAlgorithm::new(flat, fl), 400, |t_ms| {
                (2.0 * t_ms).min(25.0)
            })
        };
        assert_eq!(ramp(floor()), ramp(no_rule));
        assert!(matches!(ramp(floor()), FallbackDecision::Fire { .. }));
    }

    #[test]
    fn a_crash_after_an_earlier_lobe_of_the_same_event_is_judged_from_its_own_start() {
        // A 25 g × 2 ms lobe (1 kHz; Δv 0.37 m/s, under the 1.0 m/s floor), 3 ms at 1 g (under
        // the 1.5 g wake, inside the 10 ms quiet gap: one event), then 20 g. Judged from the
        // lobe's onset the 20 g plateau never reaches 85 % of the lobe's 25 g crest and the
        // crash is missed; judged from its own rise it fires as from rest. Oracle: Δv after the
        // re-onset = ½(1 + 20) g·1 ms + n·20 g·1 ms ≥ 1.0 m/s first at n = 5 (the boundary is
        // lower), 5 ms after the rise at 5 ms.
        let mut f = FallbackAlgorithm::new(DEFAULT_DV_MPS, floor());
        run_fn(&mut f, 30, |k| match k {
            0..=1 => 25.0,
            2..=4 => 1.0,
            _ => 20.0,
        });
        assert_eq!(
            f.decision(),
            FallbackDecision::Fire {
                at_ns: 1_000_000_000 + 10_000_000,
                onset_ns: 1_000_000_000
            },
            "fires 5 ms after the re-onset, the decision belongs to the event"
        );
        assert_eq!(f.segment_onset_ns(), Some(1_000_000_000 + 5_000_000));
        // A dip that is neither under the wake threshold nor a valley (11 g: 0.44 of the 25 g
        // crest) keeps the lobe's onset, and its crest: the plateau cannot load until the
        // segment's Δv passes LOADING_EXEMPT_DV_MPS (5.0 m/s). Oracle: Δv = ½·25 g·1 ms +
        // 25 g·1 ms + ½·36 g·1 ms + ½·31 g·1 ms + n·20 g·1 ms ≥ 5.0 first at n = 22, the sample
        // at 25 ms (the boundary there is 3.5 m/s).
        let mut f = FallbackAlgorithm::new(DEFAULT_DV_MPS, floor());
        run_fn(&mut f, 25, |k| match k {
            0..=1 => 25.0,
            2 => 11.0,
            _ => 20.0,
        });
        assert_eq!(f.decision(), FallbackDecision::Pending);
        assert_eq!(f.segment_onset_ns(), Some(1_000_000_000));
        run_fn_from(&mut f, 25, 1, |_| 20.0);
        assert_eq!(
            f.decision(),
            FallbackDecision::Fire {
                at_ns: 1_000_000_000 + 25_000_000,
                onset_ns: 1_000_000_000
            }
        );
    }

    #[test]
    fn a_crash_rising_out_of_a_valley_past_the_earlier_crest_is_judged_from_the_valley() {
        // A 6 g lobe for 20 ms (Δv 1.15 m/s, under the 2.55 m/s boundary at 20 ms), 3 ms at 2 g
        // (over the 1.5 g wake: one segment by the dip rule; under 0.4 × 6 g: a valley), then
        // 20 g. Oracle, in g·ms from the valley's first sample (k = 20): ½(6 + 2) + 2 + 2 +
        // ½(2 + 20) + 20 n ≥ 1.0 m/s = 102 g·ms first at n = 5, the sample k = 28 (τ = 8 ms
        // from the valley, boundary 0.70 m/s). Judged from the lobe's onset the crash's 0.196
        // m/s per ms never catches the boundary's 0.2 and fires only where it flattens (k = 54).
        let g = |k: u64| match k {
            0..=19 => 6.0,
            20..=22 => 2.0,
            _ => 20.0,
        };
        let mut f = FallbackAlgorithm::new(DEFAULT_DV_MPS, floor());
        run_fn(&mut f, 28, g);
        assert_eq!(f.decision(), FallbackDecision::Pending);
        assert_eq!(f.segment_onset_ns(), Some(1_000_000_000 + 20_000_000));
        run_fn_from(&mut f, 28, 1, g);
        assert_eq!(
            f.decision(),
            FallbackDecision::Fire {
                at_ns: 1_000_000_000 + 28_000_000,
                onset_ns: 1_000_000_000
            }
        );
        // A second lobe that stays under the first one's crest (12 g, a valley at 2 g, then
        // 10 g) is no departure: the segment stays where it began.
        let mut f = FallbackAlgorithm::new([f64::INFINITY; KNOTS], floor());
        run_fn(&mut f, 30, |k| match k {
            0..=9 => 12.0,
            10..=12 => 2.0,
            _ => 10.0,
        });
        assert_eq!(f.segment_onset_ns(), Some(1_000_000_000));
    }

    /// A 3 g crash ramp whose kerb ringing pulls it under the wake threshold for 2 ms (a re-onset
    /// inside RE_ONSET_EARLY_MS), then a 20 g ringing lobe for 16 ms, then 5 g. Against a
    /// boundary of 0.1 m/s per ms with the 1.2 m/s low-crush lift, the restarted segment reads
    /// the lobe alone over the lifted boundary at τ ≈ 12 ms; the whole event, read from its
    /// onset, does not get there before the lobe ends: no airbag. Without the lift the restarted
    /// segment decides alone (fires); after a 12 ms ramp the restart is no early one and decides
    /// alone under the lift too.
    #[test]
    fn an_early_restart_under_the_low_crush_lift_is_judged_from_its_parent_too() {
        let steep: [f64; KNOTS] = core::array::from_fn(|i| 0.1 + 0.4 * i as f64);
        for (ramp_ms, lift_mps, fires) in [(5, 1.2, false), (5, 0.0, true), (12, 1.2, true)] {
            let mut f = FallbackAlgorithm::new(steep, floor());
            f.lift_boundary(lift_mps);
            run_fn(&mut f, ramp_ms + 30, |k| match k {
                k if k < ramp_ms => 3.0,
                k if k < ramp_ms + 2 => 0.5,
                k if k < ramp_ms + 18 => 20.0,
                _ => 5.0,
            });
            let restart = 1_000_000_000 + (ramp_ms + 2) * 1_000_000;
            assert_eq!(f.segment_onset_ns(), Some(restart), "ramp {ramp_ms} ms");
            assert_eq!(
                matches!(f.decision(), FallbackDecision::Fire { .. }),
                fires,
                "ramp {ramp_ms} ms, lift {lift_mps} m/s: {:?}",
                f.decision()
            );
        }
    }

    #[test]
    fn early_in_a_segment_a_re_onset_needs_a_longer_dip_and_a_valley_a_low_trough() {
        // A 3.5 g lobe (too low a crest for a valley: 0.4 × 3.5 g is under the wake), one
        // sample at 1 g (a 1 ms dip under the 1.5 g wake), then 20 g. 5 ms into the segment
        // (inside RE_ONSET_EARLY_MS) the dip must last 2 ms: no re-onset; 12 ms into it, 1 ms
        // is enough.
        for (lobe_ms, restarts) in [(5, false), (12, true)] {
            let mut f = FallbackAlgorithm::new([f64::INFINITY; KNOTS], floor());
            run_fn(&mut f, lobe_ms + 5, |k| match k {
                k if k < lobe_ms => 3.5,
                k if k == lobe_ms => 1.0,
                _ => 20.0,
            });
            let rise = 1_000_000_000 + (lobe_ms + 1) * 1_000_000;
            let expected = if restarts { rise } else { 1_000_000_000 };
            assert_eq!(f.segment_onset_ns(), Some(expected), "lobe {lobe_ms} ms");
        }
        // A 15 g lobe for 12 ms, a trough at 4 g (under 0.4 × 15 g, over VALLEY_MAX_G) and a
        // rise to 25 g: ringing on a crash already loading, the segment stays; the same with
        // the trough at 2 g restarts at it.
        for (trough_g, restarts) in [(4.0, false), (2.0, true)] {
            let mut f = FallbackAlgorithm::new([f64::INFINITY; KNOTS], floor());
            run_fn(&mut f, 20, |k| match k {
                0..=11 => 15.0,
                12..=13 => trough_g,
                _ => 25.0,
            });
            let expected = if restarts {
                1_000_000_000 + 12_000_000
            } else {
                1_000_000_000
            };
            assert_eq!(f.segment_onset_ns(), Some(expected), "trough {trough_g} g");
        }
        // Within RE_ONSET_EARLY_MS of the segment's start a valley's trough must reach the wake
        // threshold: an 8 g crash ramp whose kerb ringing pulls it to 2.5 g for a sample at
        // 8 ms, then a 40 g lobe, is the crash's plateau under the ringing (a 13.8 km/h barrier
        // fired so); the same trough at 1 g (a dip too short for a re-onset) is rest the lobe
        // rises out of, and at 2.5 g 12 ms in it restarts.
        for (trough_ms, trough_g, restarts) in [(8, 2.5, false), (8, 1.0, true), (12, 2.5, true)] {
            let mut f = FallbackAlgorithm::new([f64::INFINITY; KNOTS], floor());
            run_fn(&mut f, trough_ms + 8, |k| match k {
                k if k < trough_ms => 2.0 + k as f64 * 0.75,
                k if k == trough_ms => trough_g,
                _ => 40.0,
            });
            let expected = if restarts {
                1_000_000_000 + trough_ms * 1_000_000
            } else {
                1_000_000_000
            };
            assert_eq!(
                f.segment_onset_ns(),
                Some(expected),
                "trough {trough_g} g at {trough_ms} ms"
            );
        }
    }

    #[test]
    fn one_wild_sample_is_no_crest_for_the_loading_rule() {
        // A 10 g plateau with one 100 g sample in it: the median of three takes the sample out
        // of the smoothed deceleration, so the plateau is still loading right after it (held
        // as a crest, 10 g would be 12 % of it).
        let mut f = FallbackAlgorithm::new([f64::INFINITY; KNOTS], floor());
        run_fn(&mut f, 20, |k| if k == 10 { 100.0 } else { 10.0 });
        assert!(f.loading());
    }

    #[test]
    fn short_high_g_events_stay_under_the_floor_and_a_barrier_crash_fires() {
        // Half-sines (peak g, ms): door slam, hammer blow, pothole, the 4.5 g bump. Δv of a
        // half-sine = 2/π · peak · duration: 0.50, 0.31, 0.94, 1.77 m/s (the bump spreads its
        // Δv over 40 ms, far under the boundary).
        for (peak, dur) in [(40.0, 2.0), (100.0, 0.5), (15.0, 10.0), (4.5, 40.0)] {
            let mut f = FallbackAlgorithm::new(DEFAULT_DV_MPS, floor());
            half_sine_n(&mut f, peak, dur, 800);
            assert!(
                !matches!(f.decision(), FallbackDecision::Fire { .. }),
                "{peak} g × {dur} ms: {:?}",
                f.decision()
            );
        }
        // 20 g constant (a severe barrier crash's plateau): Δv = (n − ½)·0.196 m/s, T(τ) is
        // below it from the 2nd sample on, the floor 1.0 m/s is reached at n = 6 (τ = 5 ms).
        let mut f = FallbackAlgorithm::new(DEFAULT_DV_MPS, floor());
        run(&mut f, 20.0, 20);
        assert_eq!(
            f.decision(),
            FallbackDecision::Fire {
                at_ns: 1_000_000_000 + 5_000_000,
                onset_ns: 1_000_000_000
            }
        );
    }
}
