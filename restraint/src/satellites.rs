//! The crush-zone satellites: evidence that lets the tunnel's decisions come down to the
//! crash's time, never a path to Fire of their own.
//!
//! **What they measure.** Two upfront accelerometers at the rail tips (PSI5 frames,
//! `signals::psi5`) sit in the structure that crushes first. A body motion — braking, a
//! pothole, a kerb, a rough road, a door slam — moves them with the body, so over a few ms they
//! gain the tunnel's velocity change; a crash folds the structure ahead of them and they lose
//! speed metres per second faster than the body (`physics::crush_zone`: `v²·t/(0.7·depth)` at a
//! crush rate v). The **crush Δv** of a satellite is its velocity change over the last
//! `satellite_window_ms` less the tunnel accelerometer's over the same window.
//!
//! **The rule.** The frontal severity is the *smaller* of the usable satellites' crush Δv: a
//! full-width crash loads both, and no single satellite — spiking, stuck, saturated, or
//! replaced by a forged frame — can raise the smaller of two. A satellite is out of the fusion
//! while it is stale, sends corrupt frames or status words, or is **implausible**: slowing by
//! [`IMPLAUSIBLE_LAG_MPS`] less than the body — and than its twin — over the window (the
//! structure ahead of the body cannot lag it in a frontal event: a satellite dead at rest,
//! stuck or mounted backwards in a crash; both lagging alike accuse the tunnel, or show the
//! front end unloading at the crash's end, not them). The other
//! one then decides alone: one fault has taken its twin
//! out, so it is the healthy one, and it grants a relief only when it sees the front end fold
//! — a body motion moves it with the body. Neither usable: no relief. From
//! `satellite_relief_from_mps` to `satellite_relief_full_mps` it grants a relief fraction
//! r ∈ [0, 1] (held [`RELIEF_HOLD_MS`] after the severity last reached the lower line, at the
//! event's peak), which lowers what the tunnel's decisions ask by r of a capped range:
//!
//! * the airbag's and the pyrotechnic pretensioner's severity floors towards
//!   `satellite_floor_mps` (never below it, never raised);
//! * the accelerometer-only boundary towards `satellite_boundary_scale` × itself;
//! * the road-roughness lift towards 0 (a crushed front end is not a rough road);
//! * at the whole relief (r = 1: both rail tips slow `satellite_relief_full_mps` more than the
//!   body over the window) the accelerometer-only loading rule is waived. That rule holds a
//!   decision back while the event's deceleration is below 85 % of its crest — a pothole or
//!   door slam has crested by the time it carries a floor's Δv — and a door slam's or kerb's
//!   ringing running into a crash sets a crest the crash's own deceleration reaches only tens
//!   of ms later (a standing car struck at 100 km/h during a 59 g door slam: +34 ms, the
//!   occupant bottoming out; waived: +9.2 ms, the clean crash +7.2). A front end folding on
//!   both sides is no crested misuse pulse, and the floor, the boundary, persistence and the
//!   safing channel still decide.
//!
//! **Low crush.** The same evidence works the other way: while usable satellites see the
//! front end crush less than the relief's lower line — a crash below the no-fire line (a
//! 16 km/h barrier: ≈ 0.5 m/s) or no crash at all — the accelerometer-only airbag boundary
//! is lifted by `satellite_low_crush_lift_mps`, the most a misuse event of the envelope adds
//! to the tunnel's Δv (a kerb strike or pothole inside a low-speed crash: ≈ 1.2 m/s). A crash
//! whose frontal severity reaches the lower line is judged on the boundary itself from then
//! on, as long as its relief holds: the lift is all or nothing, because a pulse near the
//! must-fire line rides along the boundary for tens of ms, and any part of the lift left on
//! it moves its fire to the window's end (30 + 30 km/h against 2 475 kg, relieved 0.75: +35
//! ms with 0.3 m/s of lift left). With no usable satellite there is no lift (a satellite
//! fault can only take the lift away, and a missing one leaves the central-only logic
//! unchanged). For an occupant not known to be belted, whose no-fire line is lower
//! (`unbelted_no_fire_ebs_kph`, 14 km/h), the lift ends earlier — once the front end crushes
//! as much as `satellite_unbelted_crush_mps` (0.5 m/s: above a 14 km/h barrier's 0.45 and
//! every misuse event's ≤ 0.41), held as the relief is: a crash above that line is no
//! low-speed crash with a kerb strike in it for this occupant. Its relief counts from the same
//! line over the belted span scaled to it (0.5 to 1.0 m/s by default): the crush grows with
//! the crash speed, and a 24 km/h barrier (1.3 m/s) is as far above this occupant's 14 km/h
//! line as a 34 km/h one above the belted 20 km/h. Without it the unbelted occupant's
//! 23–25 km/h crashes waited for the 1.25 m/s floor until +13–15 ms and bottomed out, where
//! the reference airbag at +10 ms holds them.
//!
//! **The front end folds.** The relief above lowers the floors and leaves the boundary
//! (`satellite_boundary_scale`: a light opponent at a high closing speed crushes the front as
//! a must-fire crash does), and two kinds of crash still stay under the boundary for tens of
//! ms. An offset or angled crash loads the struck side's rail alone: its satellite folds at the
//! crash's crush rate while the other moves with the body, the smaller crush Δv stays near 0
//! and the relief never begins — and the tunnel, whose pulse such a crash holds low for its
//! first tens of ms (a 64 km/h offset deformable barrier ≈ 9 g, a 16 km/h wall's first 20 ms),
//! stays under its boundary. And a full-width crash that a road's lobe or a kerb strike's
//! ringing runs into is read with that event's forward swing in it (the segment restarts at
//! the crush onset, below, and the ringing gives back what it took before): its Δv, less the
//! swing, runs parallel to the boundary (a tracked 42 km/h wall on a 4 g rms road reached it
//! at +58 ms, the occupant bottoming out). When the larger crush Δv of two usable satellites
//! reaches `satellite_fold_crush_mps` — one side or both — the accelerometer-only boundary is
//! scaled by `satellite_fold_boundary_scale` (held [`RELIEF_HOLD_MS`]) and the low-crush lift
//! is off — only while the tracked prediction is a must-fire crash with the opponent's reported
//! mass lowered by the planning margin ([`Satellites::allow_fold`]). That condition is what one
//! fault cannot pass: the tunnel and a struck rail read a light car struck offset at 30–45 km/h
//! closing (its ego Δv below the no-fire line) as they read the 64 km/h offset barrier for its
//! first 27 ms, and only the opponent's mass tells them apart; with the object list dead, or an
//! opponent its report could make light enough, a fold changes nothing. The floors are never
//! lowered by it: a misuse event stays under them whatever one satellite says.
//!
//! **Crush onset.** The cycle bins also date the fold: walking back from the batch in which
//! the severity first reaches the occupant's line, over the cycles in which every usable
//! satellite slowed by [`CRUSH_BIN_MPS`] more than the tunnel, the end of the first cycle that
//! did not is the [`CrushOnset`] (given once a relief, with the tunnel's Δv since): the
//! accelerometer-only algorithm restarts its judged segment there when a road lobe or kerb
//! strike began it earlier (`fallback`, "Crush onset").
//!
//! **A frozen tunnel.** The crush is the satellites' slowing *less the tunnel's*: a body motion
//! that every sensor sees alike (a door slam's or kerb's ringing, up to ±90 g) cancels in it.
//! A tunnel accelerometer stuck at one reading no longer cancels it, and is flagged only after
//! `accel_stuck_ms` (20 ms): a door slam's ringing lobe then reads as 1.0–1.3 m/s of crush at
//! both rail tips — an unbelted occupant's whole relief — while the stuck reading carries the
//! relieved floor (a standing car, a 59 g slam, the crash sensor stuck at 6 g: the pyrotechnic
//! pretensioner fired; `stuck-crash-sensor-in-door-slam`, seed 17). A live sensor's noise
//! changes its reading every sample, so while the tunnel's newest reading has been
//! bit-identical for [`TUNNEL_FROZEN_MS`] there is no relief: the central-only logic decides.
//!
//! Every Fire still needs the tunnel's own event to cross the lowered boundary and floor, the
//! persistence and loading rules, and the safing channel's agreement: **the satellites alone
//! never fire.** With both satellites out of the fusion the tunnel's central-only logic
//! decides, unchanged. Below the lower line (a 16 km/h barrier reaches ≈ 0.5 m/s, misuse
//! ≤ 0.4 m/s) nothing changes at all.

use crate::settings::ms_to_ns;
use crate::signals::psi5::{self, Psi5Word};
use crate::signals::{SatelliteFrames, SatelliteSide};

/// How long a relief is held after the severity last reached the lower line, ms: the span of
/// the accelerometer-only boundary's knots (`fallback::WINDOW_MS`), so a crash is judged across
/// them with the evidence its first milliseconds gave. In the late window past them
/// (`fallback::LATE_WINDOW_MS`) a relief holds only while the severity keeps reaching the line.
pub const RELIEF_HOLD_MS: f64 = 60.0;

/// A tunnel accelerometer whose reading has been bit-identical for this long is frozen, ms: no
/// reference for the crush (module docs, "A frozen tunnel"). A live sensor's noise (≥ 1 LSB)
/// changes its reading every sample; 1 ms is 8 samples at 8 kHz, and a sensor stuck at one
/// reading is flagged only after `accel_stuck_ms` (20 ms).
pub const TUNNEL_FROZEN_MS: f64 = 1.0;
/// [`TUNNEL_FROZEN_MS`] in ns.
pub const TUNNEL_FROZEN_NS: u64 = (TUNNEL_FROZEN_MS * 1e6) as u64;

/// How long a satellite's status or corrupt frame, or an implausible crush, keeps it out of
/// the fusion, ms (as an accelerometer's implausible reading: `accel::INVALID_HOLD_MS`).
pub const FAULT_HOLD_MS: f64 = 500.0;

/// A satellite whose velocity change over the window falls this far below the tunnel's is
/// implausible, m/s: 30 × what its noise and quantisation can do over the window (2 m/s² rms
/// and half a 0.47 g code per 500 µs frame: ≤ 0.01 m/s), and what a satellite stuck at rest
/// shows ≈ 2 ms into a 15 g crash.
pub const IMPLAUSIBLE_LAG_MPS: f64 = 0.3;

/// A cycle bin in which the smaller usable satellite's velocity change exceeds the tunnel's by
/// this much is one in which the front end folds, m/s: 2 g over the body's for a 1 ms cycle,
/// 4 × what a satellite's noise and quantisation do in a bin (≤ 0.005 m/s), and a crash's
/// first millisecond of crush (a 20 km/h barrier: ≈ 0.05 m/s).
pub const CRUSH_BIN_MPS: f64 = 0.02;

/// Cycle bins kept: the window is at most this many cycles (a power of two).
const BINS: usize = 16;

/// What the satellites grant the tunnel's decisions now.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Relief {
    /// 0 = nothing (central-only), 1 = the whole capped range.
    pub fraction: f64,
    /// The floor the whole range brings a severity floor down to, m/s.
    pub floor_mps: f64,
    /// The factor the whole range scales the boundary by.
    pub boundary_scale: f64,
    /// What the accelerometer-only airbag boundary is lifted by now, m/s:
    /// `satellite_low_crush_lift_mps` while usable satellites have not seen the front end
    /// crush as much as the relief's lower line, 0 from then on (while the relief holds) and
    /// with no usable satellite (module docs, "Low crush").
    pub boundary_lift_mps: f64,
    /// What a tracked must-fire crash's folding front end scales the accelerometer-only
    /// boundary by (module docs, "The front end folds"): 1 = nothing.
    pub fold_scale: f64,
}

/// When the front end began to fold, as the satellites' cycle bins date it, and the tunnel's
/// velocity change since.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CrushOnset {
    /// The end of the last cycle bin that did not fold (walking back from the newest), ns:
    /// no later than the contact — a contact late in that bin carried less crush than
    /// [`CRUSH_BIN_MPS`] in it.
    pub at_ns: u64,
    /// The tunnel accelerometer's velocity change after `at_ns` up to this cycle's batch
    /// (included), as read (before any braking compensation), m/s.
    pub tunnel_dv_mps: f64,
}

impl Relief {
    /// No relief and no lift: the tunnel's own thresholds.
    pub const NONE: Self = Self {
        fraction: 0.0,
        floor_mps: 0.0,
        boundary_scale: 1.0,
        boundary_lift_mps: 0.0,
        fold_scale: 1.0,
    };

    /// A severity floor `floor_mps` with the road's `lift_mps`, as relieved: the floor moves
    /// towards the relief's (never up) and the lift towards 0, both by the fraction.
    #[inline]
    pub fn floor_mps(self, floor_mps: f64, lift_mps: f64) -> f64 {
        let r = self.fraction;
        let target = if self.floor_mps < floor_mps {
            self.floor_mps
        } else {
            floor_mps
        };
        floor_mps - r * (floor_mps - target) + (1.0 - r) * lift_mps
    }

    /// A boundary value `threshold_mps`, as relieved.
    #[inline]
    pub fn boundary_mps(self, threshold_mps: f64) -> f64 {
        threshold_mps * (1.0 - self.fraction * (1.0 - self.boundary_scale)) * self.fold_scale
    }
}

/// Settings in the fusion's units (`satellite_*` keys: `CycleConfig::satellite_params`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SatelliteParams {
    /// The car has satellites (`false`: the fusion is off and nothing is expected).
    pub enabled: bool,
    /// One data code, m/s² (full scale / 480).
    pub lsb_mps2: f64,
    /// No frame for this long → the satellite is stale, ns.
    pub timeout_ns: u64,
    /// The crush Δv window, ns.
    pub window_ns: u64,
    /// Severity from which a relief begins, m/s.
    pub relief_from_mps: f64,
    /// Severity of the whole relief, m/s.
    pub relief_full_mps: f64,
    /// The floor of the whole relief, m/s.
    pub floor_mps: f64,
    /// The boundary scale of the whole relief.
    pub boundary_scale: f64,
    /// The airbag boundary's lift while the front end does not crush, m/s.
    pub low_crush_lift_mps: f64,
    /// Severity from which the lift ends for an occupant not known to be belted, m/s.
    pub unbelted_crush_mps: f64,
    /// The front end folds: the larger crush Δv of the two satellites at least this, m/s.
    pub fold_crush_mps: f64,
    /// What a fold scales the boundary by.
    pub fold_boundary_scale: f64,
}

/// Index mask of the ring of bins.
const BIN_MASK: usize = BINS - 1;
const _: () = assert!(BINS.is_power_of_two());

/// Velocity changes per cycle of the three channels (left, right, tunnel), with the cycle's
/// time: a window sum without per-sample state, one ring for all three.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Bins {
    dv_mps: [[f64; 3]; BINS],
    at_ns: [u64; BINS],
    head: usize,
}

/// The tunnel's column in [`Bins`].
const TUNNEL: usize = 2;

impl Bins {
    const EMPTY: Self = Self {
        dv_mps: [[0.0; 3]; BINS],
        at_ns: [0; BINS],
        head: 0,
    };

    /// Opens the bins of the cycle at `now` (once: a second call in the same cycle keeps them).
    fn open(&mut self, now: u64) {
        if self.at_ns.get(self.head) == Some(&now) {
            return;
        }
        self.head = (self.head + 1) & BIN_MASK;
        if let (Some(dv), Some(at)) = (
            self.dv_mps.get_mut(self.head),
            self.at_ns.get_mut(self.head),
        ) {
            *dv = [0.0; 3];
            *at = now;
        }
    }

    /// Whether the bins of the cycle at `now` are open.
    fn open_at(&self, now: u64) -> bool {
        self.at_ns.get(self.head) == Some(&now)
    }

    fn add(&mut self, column: usize, dv_mps: f64) {
        if let Some(dv) = self
            .dv_mps
            .get_mut(self.head)
            .and_then(|r| r.get_mut(column))
        {
            *dv += dv_mps;
        }
    }

    /// Where the front end began to fold ([`CrushOnset`]): walking back from the newest bin
    /// over those in which every `usable` satellite's velocity change exceeds the tunnel's by
    /// [`CRUSH_BIN_MPS`], the first that does not. `None` when the newest bin does not fold or
    /// the ring has no bin before the fold.
    fn crush_onset(&self, usable: [bool; 2]) -> Option<CrushOnset> {
        let mut tunnel_dv_mps = 0.0;
        for k in 0..BINS {
            let i = self.head.wrapping_sub(k) & BIN_MASK;
            let (Some(dv), Some(&at)) = (self.dv_mps.get(i), self.at_ns.get(i)) else {
                break;
            };
            if at == 0 {
                break;
            }
            let [left, right, tunnel] = *dv;
            let folds = usable
                .iter()
                .zip([left - tunnel, right - tunnel])
                .all(|(ok, crush)| !*ok || crush >= CRUSH_BIN_MPS);
            if !folds {
                return (k > 0).then_some(CrushOnset {
                    at_ns: at,
                    tunnel_dv_mps,
                });
            }
            tunnel_dv_mps += tunnel;
        }
        None
    }

    /// Sums of the bins opened within `window_ns` before `now` (the current one included).
    /// The ring opens bins in time order, so the walk goes back from the newest and stops at
    /// the first one outside the window: a window of w cycles costs w bins, not the ring.
    fn sums(&self, now: u64, window_ns: u64) -> [f64; 3] {
        let mut sum = [0.0; 3];
        for k in 0..BINS {
            let i = self.head.wrapping_sub(k) & BIN_MASK;
            let (Some(dv), Some(&at)) = (self.dv_mps.get(i), self.at_ns.get(i)) else {
                break;
            };
            if at == 0 || now.saturating_sub(at) >= window_ns {
                break;
            }
            for (s, v) in sum.iter_mut().zip(dv) {
                *s += v;
            }
        }
        sum
    }
}

/// One satellite's receive state.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Channel {
    rx_ns: Option<u64>,
    faulty_until_ns: Option<u64>,
}

impl Channel {
    const NEW: Self = Self {
        rx_ns: None,
        faulty_until_ns: None,
    };

    fn usable(&self, now: u64, timeout_ns: u64) -> bool {
        let fresh = self
            .rx_ns
            .is_some_and(|t| now.saturating_sub(t) <= timeout_ns);
        let faulty = self.faulty_until_ns.is_some_and(|t| now <= t);
        fresh && !faulty
    }
}

/// Counters of what the satellites sent that the fusion could not use.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct SatelliteFaults {
    /// Frames whose parity failed or that had bits beyond the frame set.
    pub corrupt_frames: u64,
    /// Status words (|code| > 480: e.g. sensor defect).
    pub status_frames: u64,
    /// Batches with a sample period out of range or without frames.
    pub bad_batches: u64,
    /// Times a satellite lagged the body by more than [`IMPLAUSIBLE_LAG_MPS`].
    pub implausible: u64,
}

/// The fusion's state: both satellites, the tunnel's velocity change per cycle, the relief.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Satellites {
    params: SatelliteParams,
    channels: [Channel; 2],
    bins: Bins,
    /// The current cycle's time, ns.
    now_ns: u64,
    /// The peak severity of the current relief, m/s.
    peak_mps: f64,
    /// The relief holds until, ns.
    hold_until_ns: Option<u64>,
    /// The fold's boundary scale holds until, ns.
    fold_until_ns: Option<u64>,
    /// This cycle's tracked prediction allows a fold to scale the boundary
    /// ([`Self::allow_fold`]).
    fold_allowed: bool,
    /// The tunnel accelerometer's reading is frozen ([`Self::set_tunnel_frozen`]).
    tunnel_frozen: bool,
    /// When the current relief began (the cycle, ns; 0: none yet), and the satellites usable
    /// then.
    relief_began_ns: u64,
    relief_began_usable: [bool; 2],
    /// What was not usable.
    pub faults: SatelliteFaults,
    /// Accelerometer batches judged with a relief (fraction > 0).
    pub relieved_batches: u64,
}

/// The smaller crush Δv of the `usable` satellites from the window's `sums` (left, right,
/// tunnel), m/s. A tunnel reading forward (a shunt from behind, or a faulty one) is no crush
/// ahead: the satellites are measured against a tunnel that at most stands still.
fn severity_of(usable: [bool; 2], sums: [f64; 3]) -> Option<f64> {
    usable
        .iter()
        .zip(crush_of(sums))
        .filter(|(ok, _)| **ok)
        .map(|(_, s)| s)
        .fold(None, |m: Option<f64>, s| Some(m.map_or(s, |m| m.min(s))))
        .filter(|s| s.is_finite())
}

/// Each satellite's crush Δv (left, right) from the window's `sums` (left, right, tunnel),
/// m/s, against a tunnel that at most stands still.
#[inline]
fn crush_of(sums: [f64; 3]) -> [f64; 2] {
    let [left, right, tunnel] = sums;
    let tunnel = tunnel.max(0.0);
    [left - tunnel, right - tunnel]
}

/// The front end folds (module docs, "The front end folds"): both usable, the larger crush Δv
/// at least `fold_crush_mps`.
fn folds(usable: [bool; 2], sums: [f64; 3], p: &SatelliteParams) -> bool {
    let [l, r] = crush_of(sums);
    usable == [true, true] && l.max(r) >= p.fold_crush_mps
}

impl Satellites {
    /// No frames yet, no relief.
    pub fn new(params: SatelliteParams) -> Self {
        Self {
            params,
            channels: [Channel::NEW; 2],
            bins: Bins::EMPTY,
            now_ns: 0,
            peak_mps: 0.0,
            hold_until_ns: None,
            fold_until_ns: None,
            fold_allowed: false,
            tunnel_frozen: false,
            relief_began_ns: 0,
            relief_began_usable: [false; 2],
            faults: SatelliteFaults::default(),
            relieved_batches: 0,
        }
    }

    /// Starts the cycle at `now`. Its bins open with the cycle's first satellite batch: a
    /// cycle without satellite frames (a car without them, dead ones) costs nothing more.
    pub fn begin_cycle(&mut self, now: u64) {
        self.now_ns = now;
    }

    /// Whether this cycle's tracked prediction allows a fold to scale the boundary: a crash
    /// that is a must-fire one even if the object list over-reported the opponent's mass by
    /// the planning margin (module docs, "The front end folds").
    pub fn allow_fold(&mut self, allowed: bool) {
        self.fold_allowed = allowed;
    }

    /// One batch of `side`'s frames received at `now`: data codes add their velocity change
    /// to the cycle's bin; a corrupt frame or a status word is counted and takes the satellite
    /// out of the fusion for [`FAULT_HOLD_MS`].
    pub fn on_frames(&mut self, side: SatelliteSide, b: &SatelliteFrames, now: u64) {
        if !self.params.enabled {
            return;
        }
        let Some(ch) = self.channels.get_mut(side as usize) else {
            return;
        };
        let dt_s = f64::from(b.sample_period_ns) * 1e-9;
        if !(dt_s > 0.0 && dt_s <= 0.01) || b.frames().is_empty() {
            self.faults.bad_batches = self.faults.bad_batches.saturating_add(1);
            return;
        }
        let mut dv = 0.0;
        let mut bad = false;
        for f in b.frames() {
            match psi5::decode(*f) {
                Psi5Word::Data(code) => dv += f64::from(code) * self.params.lsb_mps2 * dt_s,
                Psi5Word::Status(_) => {
                    self.faults.status_frames = self.faults.status_frames.saturating_add(1);
                    bad = true;
                }
                Psi5Word::Corrupt => {
                    self.faults.corrupt_frames = self.faults.corrupt_frames.saturating_add(1);
                    bad = true;
                }
            }
        }
        if bad {
            ch.faulty_until_ns = Some(now.saturating_add(ms_to_ns(FAULT_HOLD_MS)));
        }
        ch.rx_ns = Some(now);
        self.bins.open(self.now_ns);
        self.bins.add(side as usize, dv);
    }

    /// Whether the tunnel accelerometer's newest reading has been bit-identical for
    /// [`TUNNEL_FROZEN_MS`] or longer (module docs, "A frozen tunnel"): while it has, there is
    /// no relief.
    pub fn set_tunnel_frozen(&mut self, frozen: bool) {
        self.tunnel_frozen = frozen;
    }

    /// The tunnel accelerometer's velocity change over its plausible samples of this cycle
    /// (m/s, + = slowing down), as read before any braking compensation.
    pub fn on_tunnel_dv(&mut self, dv_mps: f64) {
        if self.bins.open_at(self.now_ns) && dv_mps.is_finite() {
            self.bins.add(TUNNEL, dv_mps);
        }
    }

    /// The frontal severity at `now`: the smaller crush Δv of the usable satellites, m/s
    /// (`None`: neither is usable, or the fusion is off).
    pub fn severity_mps(&self, now: u64) -> Option<f64> {
        self.window(now)
            .and_then(|(usable, sums)| severity_of(usable, sums))
    }

    /// Which satellites are usable at `now` and the window's sums (left, right, tunnel), m/s
    /// (`None`: neither is usable, or the fusion is off — the sums are not needed then).
    fn window(&self, now: u64) -> Option<([bool; 2], [f64; 3])> {
        let p = &self.params;
        let usable = self.channels.map(|c| c.usable(now, p.timeout_ns));
        (p.enabled && usable != [false; 2]).then(|| (usable, self.bins.sums(now, p.window_ns)))
    }

    /// Takes a usable satellite that lags the body out of the fusion — and, while its twin is
    /// usable, lags its twin by as much too: when both lag the tunnel alike, the tunnel is the
    /// suspect (a spike, a body motion forward it reads and they read alike is no lag at
    /// all), or the front end is unloading (a crash's crush rate falling at its end: both rail
    /// tips slow less than the body for a few ms), and neither is taken out. Returns which
    /// satellites are still usable.
    fn check_plausible(&mut self, now: u64, usable: [bool; 2], sums: [f64; 3]) -> [bool; 2] {
        let [left, right, tunnel] = sums;
        let lags = [left - tunnel, right - tunnel].map(|d| d < -IMPLAUSIBLE_LAG_MPS);
        let behind_twin = [right - left, left - right].map(|d| d > IMPLAUSIBLE_LAG_MPS);
        let mut still = usable;
        for i in 0..2 {
            let other = 1 - i;
            let (Some(&lag), Some(&ok), Some(&behind), Some(&other_ok)) = (
                lags.get(i),
                usable.get(i),
                behind_twin.get(i),
                usable.get(other),
            ) else {
                continue;
            };
            if ok && lag && (behind || !other_ok) {
                if let (Some(ch), Some(u)) = (self.channels.get_mut(i), still.get_mut(i)) {
                    ch.faulty_until_ns = Some(now.saturating_add(ms_to_ns(FAULT_HOLD_MS)));
                    *u = false;
                }
                self.faults.implausible = self.faults.implausible.saturating_add(1);
            }
        }
        still
    }

    /// Updates the relief with the severity at `now` and returns it (`belted`: the occupant
    /// is known to be belted; else the low-crush lift ends at `unbelted_crush_mps`).
    pub fn relief(&mut self, now: u64, belted: bool) -> Relief {
        let p = self.params;
        if !p.enabled || self.tunnel_frozen {
            return Relief::NONE;
        }
        if self.hold_until_ns.is_some_and(|t| now > t) {
            self.hold_until_ns = None;
            self.peak_mps = 0.0;
        }
        // One pass over the window: the plausibility check, then the severity of what is left.
        let judged = self
            .window(now)
            .map(|(usable, sums)| (self.check_plausible(now, usable, sums), sums));
        let severity = judged.and_then(|(usable, sums)| severity_of(usable, sums));
        if self.fold_until_ns.is_some_and(|t| now > t) {
            self.fold_until_ns = None;
        }
        if self.fold_allowed && judged.is_some_and(|(usable, sums)| folds(usable, sums, &p)) {
            self.fold_until_ns = Some(now.saturating_add(ms_to_ns(RELIEF_HOLD_MS)));
        }
        let fold_scale = if self.fold_until_ns.is_some() {
            p.fold_boundary_scale
        } else {
            1.0
        };
        // The lift ends, the relief's hold begins and its fraction counts from the occupant's
        // line; an unbelted occupant's relief spans the belted one scaled to that line.
        let (line, full) = if belted {
            (p.relief_from_mps, p.relief_full_mps)
        } else {
            let scale = p.unbelted_crush_mps / p.relief_from_mps;
            (p.unbelted_crush_mps, p.relief_full_mps * scale)
        };
        if let Some(s) = severity.filter(|s| *s >= line) {
            if self.hold_until_ns.is_none() {
                // The relief begins: the fold is dated from the usable satellites now
                // (`Self::crush_onset_at`).
                self.relief_began_ns = now;
                self.relief_began_usable = judged.map_or([false; 2], |(usable, _)| usable);
            }
            self.peak_mps = self.peak_mps.max(s);
            self.hold_until_ns = Some(now.saturating_add(ms_to_ns(RELIEF_HOLD_MS)));
        }
        if self.hold_until_ns.is_none() {
            // Usable satellites that see no crush ahead: the whole lift — unless a fold scales.
            return Relief {
                boundary_lift_mps: if severity.is_some() && fold_scale == 1.0 {
                    p.low_crush_lift_mps
                } else {
                    0.0
                },
                fold_scale,
                ..Relief::NONE
            };
        }
        let span = full - line;
        let fraction = if self.peak_mps < line {
            0.0 // a peak held under the other line while the belt state changed
        } else if span > 0.0 {
            ((self.peak_mps - line) / span).clamp(0.0, 1.0)
        } else {
            1.0
        };
        if fraction > 0.0 {
            self.relieved_batches = self.relieved_batches.saturating_add(1);
        }
        Relief {
            fraction,
            floor_mps: p.floor_mps,
            boundary_scale: p.boundary_scale,
            boundary_lift_mps: 0.0,
            fold_scale,
        }
    }

    /// Whether the usable satellites have seen the front end crush by at least the relief's
    /// lower line (`satellite_relief_from_mps`) within the relief's hold at `now`: a frontal
    /// crash, which no body motion of the envelope shows (≤ 0.41 m/s of crush) and no single
    /// satellite can forge (the smaller of two usable ones counts). Read after the cycle's
    /// batches (the relief is updated in each judged one).
    pub fn front_end_crushed(&self, now: u64) -> bool {
        self.params.enabled
            && self.hold_until_ns.is_some_and(|t| now <= t)
            && self.peak_mps >= self.params.relief_from_mps
    }

    /// Where the front end began to fold ([`CrushOnset`], module docs "Crush onset"), when the
    /// relief began in this cycle (`now`): `None` in every other cycle, so the walk over the
    /// bins is made once a relief.
    #[inline]
    pub fn crush_onset_at(&self, now: u64) -> Option<CrushOnset> {
        if self.relief_began_ns != now {
            return None;
        }
        self.crush_onset_walk()
    }

    /// [`Self::crush_onset_at`]'s walk, out of the cycle's common path.
    #[inline(never)]
    fn crush_onset_walk(&self) -> Option<CrushOnset> {
        self.bins.crush_onset(self.relief_began_usable)
    }

    /// Whether `side` is missing or faulty at `now` (for the status; `false` when the car has
    /// no satellites).
    pub fn faulty(&self, side: SatelliteSide, now: u64) -> bool {
        self.params.enabled
            && self
                .channels
                .get(side as usize)
                .is_none_or(|c| !c.usable(now, self.params.timeout_ns))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::signals::psi5::{code_of, encode, SENSOR_DEFECT};

    const G: f64 = 9.806_65;
    const MS: u64 = 1_000_000;

    fn params() -> SatelliteParams {
        SatelliteParams {
            enabled: true,
            lsb_mps2: 240.0 * G / 480.0,
            timeout_ns: 5 * MS,
            window_ns: 4 * MS,
            relief_from_mps: 1.0,
            relief_full_mps: 2.0,
            floor_mps: 0.5,
            boundary_scale: 0.5,
            low_crush_lift_mps: 0.0,
            unbelted_crush_mps: 0.5,
            fold_crush_mps: 2.0,
            fold_boundary_scale: 0.4,
        }
    }

    /// Two frames (500 µs) of `decel_g` each.
    fn frames(decel_g: f64) -> SatelliteFrames {
        let code = encode(code_of(decel_g * G, 240.0 * G));
        SatelliteFrames {
            sample_period_ns: 500_000,
            count: 2,
            frames: [code; 8],
            ..SatelliteFrames::EMPTY
        }
    }

    /// Runs `ms` cycles of 1 ms with the left/right satellites at `l`, `r` g and the tunnel at
    /// `tunnel` g; returns the last relief.
    fn run(s: &mut Satellites, from_ms: u64, ms: u64, l: f64, r: f64, tunnel: f64) -> Relief {
        run_for(s, from_ms, ms, l, r, tunnel, true)
    }

    /// [`run`] for an occupant `belted` or not known to be.
    fn run_for(
        s: &mut Satellites,
        from_ms: u64,
        ms: u64,
        l: f64,
        r: f64,
        tunnel: f64,
        belted: bool,
    ) -> Relief {
        let mut relief = Relief::NONE;
        for k in from_ms..from_ms + ms {
            let now = k * MS;
            s.begin_cycle(now);
            s.on_frames(SatelliteSide::Left, &frames(l), now);
            s.on_frames(SatelliteSide::Right, &frames(r), now);
            s.on_tunnel_dv(tunnel * G * 1e-3);
            relief = s.relief(now, belted);
        }
        relief
    }

    #[test]
    fn a_body_motion_moves_satellites_and_tunnel_alike_and_grants_nothing() {
        let mut s = Satellites::new(params());
        // A 20 g pothole lobe the whole car feels: crush Δv 0.
        assert_eq!(run(&mut s, 1, 20, 20.0, 20.0, 20.0), Relief::NONE);
        assert!(s.severity_mps(20 * MS).is_some_and(|v| v.abs() < 0.05));
    }

    /// Closed form: both satellites at a g above the tunnel for ≥ 4 ms give a crush Δv of
    /// a·g·4 ms; the relief fraction is (Δv − 1)/(2 − 1).
    #[test]
    fn the_relief_grows_with_the_smaller_crush_velocity_and_is_capped() {
        let mut s = Satellites::new(params());
        // 40 g above the tunnel: 40·9.81·0.004 = 1.57 m/s → fraction 0.57 (codes: 0.5 g).
        let r = run(&mut s, 1, 10, 50.0, 45.0, 5.0);
        let expected = (40.0 * G * 0.004 - 1.0) / 1.0;
        assert!((r.fraction - expected).abs() < 0.03, "{r:?} vs {expected}");
        // A floor of 1.25 with a lift of 0.4 is brought 57 % of the way to 0.5, the lift 57 %
        // of the way to 0; the boundary 57 % of the way to half.
        let f = r.floor_mps(1.25, 0.4);
        assert!((f - (1.25 - r.fraction * 0.75 + (1.0 - r.fraction) * 0.4)).abs() < 1e-12);
        assert!((r.boundary_mps(1.0) - (1.0 - r.fraction * 0.5)).abs() < 1e-12);
        // Far more crush: capped at the whole range; a floor already below the relief's is
        // never raised.
        let r = run(&mut s, 11, 10, 150.0, 150.0, 10.0);
        assert_eq!(r.fraction, 1.0);
        assert_eq!(r.floor_mps(1.25, 0.0), 0.5);
        assert_eq!(r.floor_mps(0.3, 0.0), 0.3);
        assert_eq!(r.boundary_mps(2.0), 1.0);
    }

    #[test]
    fn one_lying_satellite_cannot_raise_the_severity() {
        let mut s = Satellites::new(params());
        // The left satellite saturated (a stuck or spiking one), the right one at rest.
        assert_eq!(run(&mut s, 1, 30, 240.0, 0.0, 0.0), Relief::NONE);
        // Mounted backwards in a 10 g body motion: its crush reads as forward acceleration,
        // which takes it out of the fusion; the right one moves with the body.
        let mut s = Satellites::new(params());
        assert_eq!(run(&mut s, 1, 30, -10.0, 10.0, 10.0), Relief::NONE);
        assert_eq!(s.faults.implausible, 1);
        assert!(s.faulty(SatelliteSide::Left, 30 * MS));
        assert!(!s.faulty(SatelliteSide::Right, 30 * MS));
    }

    /// The front end folds — one side (an offset crash's struck rail, the other moving with
    /// the body) or both: the boundary is scaled, the floors are not, and only when the tracked
    /// prediction allows it and both satellites are usable. Closed form: 60 g above the tunnel
    /// for 4 ms is 2.35 m/s of crush (≥ 2.0).
    #[test]
    fn a_folding_front_end_scales_the_boundary_only_for_a_tracked_must_fire_crash() {
        let mut s = Satellites::new(params());
        // Not allowed (no tracked must-fire crash): nothing — the lying-satellite case.
        assert_eq!(run(&mut s, 1, 10, 69.0, 9.0, 9.0), Relief::NONE);
        let mut s = Satellites::new(params());
        s.allow_fold(true);
        let r = run(&mut s, 1, 10, 69.0, 9.0, 9.0);
        assert_eq!(r.fold_scale, 0.4, "{r:?}");
        assert_eq!(r.fraction, 0.0, "the floors stay: {r:?}");
        assert_eq!(r.floor_mps(1.25, 0.3), 1.25 + 0.3);
        assert_eq!(r.boundary_lift_mps, 0.0);
        assert!((r.boundary_mps(2.0) - 0.8).abs() < 1e-12);
        // Held for the relief's hold after the fold was last seen, then gone.
        let held = run(&mut s, 11, 50, 9.0, 9.0, 9.0);
        assert_eq!(held.fold_scale, 0.4);
        let gone = run(&mut s, 61, 20, 9.0, 9.0, 9.0);
        assert_eq!(gone.fold_scale, 1.0);
        // Both sides folding: the full-width relief and the fold's scale together.
        let mut s = Satellites::new(params());
        s.allow_fold(true);
        let r = run(&mut s, 1, 10, 69.0, 69.0, 9.0);
        assert_eq!((r.fraction, r.fold_scale), (1.0, 0.4), "{r:?}");
        // The whole relief's scale (0.5 here) and the fold's multiply: 2.0 · 0.5 · 0.4.
        assert!((r.boundary_mps(2.0) - 0.4).abs() < 1e-12);
        // Under the fold's line on both sides (1.96 m/s: 59 g over the tunnel for 4 ms):
        // nothing scaled.
        let mut s = Satellites::new(params());
        s.allow_fold(true);
        assert_eq!(run(&mut s, 1, 10, 59.0, 9.0, 9.0).fold_scale, 1.0);
    }

    /// A satellite that lags the body by more than the implausibility line (dead at rest in a
    /// crash) is out for the hold; the other one's crush decides alone. Closed form: the right
    /// satellite at 60 g above a 15 g tunnel gives 60·g·4 ms = 2.35 m/s, the whole relief.
    #[test]
    fn a_satellite_lagging_the_body_is_out_and_the_other_decides() {
        let mut s = Satellites::new(params());
        // The first cycle of a 15 g tunnel: the stuck one lags by 0.15 m/s, still plausible,
        // and the smaller crush (its own) grants nothing.
        assert_eq!(run(&mut s, 1, 1, 0.0, 75.0, 15.0), Relief::NONE);
        assert!(!s.faulty(SatelliteSide::Left, MS));
        // From the second: 0.29 m/s… and the third 0.44 m/s below the tunnel: out.
        let r = run(&mut s, 2, 4, 0.0, 75.0, 15.0);
        assert!(s.faulty(SatelliteSide::Left, 5 * MS));
        assert_eq!(s.faults.implausible, 1);
        assert_eq!(r.fraction, 1.0, "{r:?}");
        // Both lagging the tunnel (a 100 g tunnel spike, both at rest): the tunnel is the
        // suspect, neither is taken out.
        let mut s = Satellites::new(params());
        assert_eq!(run(&mut s, 1, 3, 0.0, 0.0, 100.0), Relief::NONE);
        assert_eq!(s.faults.implausible, 0);
        assert!(!s.faulty(SatelliteSide::Left, 3 * MS) && !s.faulty(SatelliteSide::Right, 3 * MS));
        // Both out (the right one stale too): nothing.
        let mut s = Satellites::new(params());
        for k in 1..10u64 {
            s.begin_cycle(k * MS);
            s.on_frames(SatelliteSide::Left, &frames(0.0), k * MS);
            s.on_tunnel_dv(15.0 * G * 1e-3);
            assert_eq!(s.relief(k * MS, true), Relief::NONE);
        }
    }

    /// At a crash's end the crush rate falls and both rail tips slow less than the body for
    /// a few ms: both lag the tunnel alike, a lag that accuses neither, even where one is past
    /// the line and the other not (10 and 13 g under a 20 g tunnel: 0.39 and 0.27 m/s over
    /// the window, 0.12 m/s apart).
    #[test]
    fn both_satellites_lagging_alike_as_the_front_end_unloads_stay_in() {
        let mut s = Satellites::new(params());
        run(&mut s, 1, 10, 10.0, 13.0, 20.0);
        assert_eq!(s.faults.implausible, 0);
        assert!(
            !s.faulty(SatelliteSide::Left, 10 * MS) && !s.faulty(SatelliteSide::Right, 10 * MS)
        );
        assert!(s.severity_mps(10 * MS).is_some_and(|v| v < -0.35));
    }

    /// The low-crush lift: whole while usable satellites see no crush ahead (a body motion),
    /// none from the moment the severity reaches the relief's lower line while the relief
    /// holds, whole again after it; none with no usable satellite or none at all.
    /// For an occupant not known to be belted the lift ends at the unbelted line (0.5 m/s),
    /// held as a relief is, and the relief spans the belted one scaled to that line: 0.5 to
    /// 1.0 m/s. Closed form: 15 g above the tunnel for 4 ms is a crush Δv of 0.59 m/s,
    /// fraction (0.59 − 0.5)/0.5 unbelted and nothing belted.
    #[test]
    fn the_lift_ends_earlier_for_an_occupant_not_known_to_be_belted() {
        let lifted = SatelliteParams {
            low_crush_lift_mps: 1.2,
            unbelted_crush_mps: 0.5,
            ..params()
        };
        let crush_mps = 15.0 * G * 0.004;
        let mut belted = Satellites::new(lifted);
        let r = run_for(&mut belted, 1, 10, 20.0, 20.0, 5.0, true);
        assert_eq!((r.fraction, r.boundary_lift_mps), (0.0, 1.2));
        let mut unbelted = Satellites::new(lifted);
        let r = run_for(&mut unbelted, 1, 10, 20.0, 20.0, 5.0, false);
        let expected = (crush_mps - 0.5) / 0.5;
        assert!((r.fraction - expected).abs() < 0.03, "{r:?} vs {expected}");
        assert_eq!(r.boundary_lift_mps, 0.0);
        assert!(
            (r.floor_mps(1.25, 0.3) - (1.25 - r.fraction * 0.75 + (1.0 - r.fraction) * 0.3)).abs()
                < 1e-12
        );
        // Relieved from the 4th cycle (the window's crush passes 0.5 m/s at 4 × 0.147).
        assert_eq!(unbelted.relieved_batches, 7);
        // 1.57 m/s (40 g above the tunnel): the whole relief unbelted, 0.57 of it belted.
        let mut severe_unbelted = Satellites::new(lifted);
        assert_eq!(
            run_for(&mut severe_unbelted, 1, 10, 45.0, 45.0, 5.0, false).fraction,
            1.0
        );
        let mut severe_belted = Satellites::new(lifted);
        let r = run_for(&mut severe_belted, 1, 10, 45.0, 45.0, 5.0, true);
        assert!(
            (r.fraction - (40.0 * G * 0.004 - 1.0)).abs() < 0.03,
            "{r:?}"
        );
        // Held 60 ms after the severity last reached the line, the whole lift after it.
        assert_eq!(
            run_for(&mut unbelted, 11, 60, 0.0, 0.0, 0.0, false).boundary_lift_mps,
            0.0
        );
        assert_eq!(
            run_for(&mut unbelted, 71, 10, 0.0, 0.0, 0.0, false).boundary_lift_mps,
            1.2
        );
    }

    /// The crush onset is given once, in the cycle whose severity first reaches the line: the
    /// end of the last cycle whose bin did not fold, with the tunnel's Δv since. Closed form:
    /// 10 cycles of a 5 g body motion (satellites and tunnel alike), then both satellites at
    /// 45 g over a 15 g tunnel: a crush of 30 g·1 ms = 0.29 m/s a cycle, 1.0 m/s (the belted
    /// line) in the 4th folding cycle (1.18 m/s over the 4 ms window); the onset is cycle 10,
    /// the tunnel's 4 cycles × 15 g·1 ms after it.
    #[test]
    fn the_crush_onset_is_the_last_cycle_before_the_front_end_folds() {
        let mut s = Satellites::new(params());
        run(&mut s, 1, 10, 5.0, 5.0, 5.0);
        assert_eq!(s.crush_onset_at(10 * MS), None);
        let (mut given, mut first) = (0, None);
        for k in 11..=20u64 {
            run(&mut s, k, 1, 45.0, 45.0, 15.0);
            if let Some(o) = s.crush_onset_at(k * MS) {
                given += 1;
                first = first.or(Some((k, o)));
            }
        }
        assert_eq!(given, 1);
        let (k, o) = first.unwrap();
        assert_eq!(k, 14);
        assert_eq!(o.at_ns, 10 * MS);
        // The tunnel's bins hold the 15 g as the frames' codes carry it (0.5 g steps).
        assert!(
            (o.tunnel_dv_mps - 4.0 * 15.0 * G * 1e-3).abs() < 0.01,
            "{o:?}"
        );
        // A fold from the first bin on has no bin before it: no onset.
        let mut s = Satellites::new(params());
        run(&mut s, 1, 6, 45.0, 45.0, 15.0);
        assert!((1..=6).all(|k| s.crush_onset_at(k * MS).is_none()));
    }

    #[test]
    fn the_lift_holds_while_the_front_end_does_not_crush() {
        let lifted = SatelliteParams {
            low_crush_lift_mps: 1.2,
            ..params()
        };
        let mut s = Satellites::new(lifted);
        let r = run(&mut s, 1, 20, 20.0, 20.0, 20.0);
        assert_eq!((r.fraction, r.boundary_lift_mps), (0.0, 1.2));
        // 30 g above the tunnel: 30·g·4 ms = 1.18 m/s, past the lower line (fraction 0.18).
        let r = run(&mut s, 21, 5, 35.0, 35.0, 5.0);
        assert!(r.fraction > 0.1 && r.fraction < 0.3, "{r:?}");
        assert_eq!(r.boundary_lift_mps, 0.0);
        // The crush is over: no lift while the relief holds (60 ms), the whole lift after it.
        assert_eq!(run(&mut s, 26, 50, 0.0, 0.0, 0.0).boundary_lift_mps, 0.0);
        assert_eq!(run(&mut s, 76, 20, 0.0, 0.0, 0.0).boundary_lift_mps, 1.2);
        // Both satellites silent (stale after the 5 ms timeout): no lift.
        for k in 96..110u64 {
            s.begin_cycle(k * MS);
            s.on_tunnel_dv(0.0);
            let r = s.relief(k * MS, true);
            if k > 101 {
                assert_eq!(r, Relief::NONE, "{k}");
            }
        }
        let mut off = Satellites::new(SatelliteParams {
            enabled: false,
            ..lifted
        });
        assert_eq!(run(&mut off, 1, 10, 0.0, 0.0, 0.0), Relief::NONE);
    }

    #[test]
    fn a_tunnel_reading_forward_makes_no_crush() {
        // The tunnel pushed forward at 60 g (a shunt from behind or a faulty sensor), both
        // satellites at rest: nothing ahead crushes.
        let mut s = Satellites::new(params());
        assert_eq!(run(&mut s, 1, 20, 0.0, 0.0, -60.0), Relief::NONE);
    }

    #[test]
    fn a_relief_is_held_at_its_peak_then_ends() {
        let mut s = Satellites::new(params());
        let r = run(&mut s, 1, 5, 100.0, 100.0, 0.0);
        assert_eq!(r.fraction, 1.0);
        // The crush is over (satellites back with the body): still held…
        let r = run(&mut s, 6, 50, 10.0, 10.0, 10.0);
        assert_eq!(r.fraction, 1.0);
        // …until 60 ms after the severity last reached the lower line.
        let r = run(&mut s, 56, 20, 10.0, 10.0, 10.0);
        assert_eq!(r, Relief::NONE);
    }

    /// Out of the fusion: stale, corrupt or defective. The other satellite decides alone —
    /// nothing for a body motion it shares with the tunnel, the relief for a crush it sees.
    #[test]
    fn a_stale_corrupt_or_defective_satellite_leaves_the_other_to_decide() {
        // Stale: only the left one sends; a 20 g body motion grants nothing, a crush does.
        let mut s = Satellites::new(params());
        for k in 1..10u64 {
            s.begin_cycle(k * MS);
            s.on_frames(SatelliteSide::Left, &frames(20.0), k * MS);
            s.on_tunnel_dv(20.0 * G * 1e-3);
            assert_eq!(s.relief(k * MS, true), Relief::NONE);
        }
        assert!(s.faulty(SatelliteSide::Right, 9 * MS));
        assert!(!s.faulty(SatelliteSide::Left, 9 * MS));
        let mut r = Relief::NONE;
        for k in 10..15u64 {
            s.begin_cycle(k * MS);
            s.on_frames(SatelliteSide::Left, &frames(150.0), k * MS);
            r = s.relief(k * MS, true);
        }
        assert_eq!(r.fraction, 1.0);
        // One corrupt frame takes the right satellite out for the hold: the left one's crush
        // decides, and it is at rest.
        let mut s = Satellites::new(params());
        let mut bad = frames(150.0);
        bad.frames[1] ^= 1;
        s.begin_cycle(MS);
        s.on_frames(SatelliteSide::Right, &bad, MS);
        assert_eq!(s.faults.corrupt_frames, 1);
        assert_eq!(run(&mut s, 2, 20, 0.0, 150.0, 0.0), Relief::NONE);
        assert!(s.faulty(SatelliteSide::Right, 21 * MS));
        // A status word (sensor defect) likewise.
        let mut s = Satellites::new(params());
        let mut defect = frames(150.0);
        defect.frames[0] = encode(SENSOR_DEFECT);
        s.begin_cycle(MS);
        s.on_frames(SatelliteSide::Left, &defect, MS);
        assert_eq!(s.faults.status_frames, 1);
        assert_eq!(run(&mut s, 2, 20, 150.0, 0.0, 0.0), Relief::NONE);
        // Garbage batches are counted, never used.
        let mut s = Satellites::new(params());
        let garbage = SatelliteFrames {
            sample_period_ns: 0,
            count: u32::MAX,
            ..frames(150.0)
        };
        s.begin_cycle(MS);
        s.on_frames(SatelliteSide::Left, &garbage, MS);
        assert_eq!(s.faults.bad_batches, 1);
    }

    #[test]
    fn a_car_without_satellites_never_reports_them_faulty() {
        let mut s = Satellites::new(SatelliteParams {
            enabled: false,
            ..params()
        });
        assert_eq!(run(&mut s, 1, 10, 150.0, 150.0, 0.0), Relief::NONE);
        assert!(!s.faulty(SatelliteSide::Left, 10 * MS));
    }
}
