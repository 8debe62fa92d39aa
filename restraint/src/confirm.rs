//! Generic crash confirmation from the compartment accelerometer (the path that needs no
//! prediction), and the onset tracking the crash detectors share. Pure, allocation-free,
//! NaN-safe; fed with the plausible samples of [`crate::accel::AccelMonitor`].

use crate::accel::AccelSample;

/// Crash-confirmation settings in the detector's units (from the file's `confirm_*` keys:
/// [`crate::CycleConfig::confirm_params`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ConfirmParams {
    /// Wake threshold, m/s² (deceleration magnitude).
    pub wake_mps2: f64,
    /// Confirmation threshold, m/s².
    pub decel_mps2: f64,
    /// Consecutive samples over `decel_mps2`.
    pub samples: u32,
    /// Δv since wake-up, m/s.
    pub delta_v_mps: f64,
    /// Reset after this long below the wake threshold, ns.
    pub reset_gap_ns: u64,
}

/// An event in the accelerometer signal: awake from the first sample at or above the wake
/// threshold (its time is the measured onset), over after `reset_gap_ns` below it. Δv is
/// integrated from the interval that ends at the wake-up sample on.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Onset {
    awake: bool,
    onset_ns: u64,
    last_wake_ns: u64,
    delta_v_mps: f64,
    /// The previous sample's deceleration (trapezoidal integration).
    prev_decel_mps2: f64,
}

/// What one sample did to an [`Onset`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OnsetStep {
    /// Below the wake threshold with no event in progress (or the event just ended).
    Quiet,
    /// This sample woke the tracker (first sample of an event).
    Woke,
    /// Inside an event (Δv updated).
    Awake,
    /// The quiet gap passed: the event is over, the tracker reset.
    Reset,
}

impl Onset {
    /// Feeds one sample. Δv is integrated with the trapezoidal rule from the sample before
    /// the wake-up (so that it does not depend on where the sample grid falls: 1 kHz and 8 kHz
    /// sensors measure the same Δv of the same crash).
    pub fn push(&mut self, p: &ConfirmParams, s: &AccelSample) -> OnsetStep {
        let decel = s.decel_mps2;
        let prev = core::mem::replace(&mut self.prev_decel_mps2, decel);
        let step = if decel >= p.wake_mps2 {
            let woke = !self.awake;
            if woke {
                *self = Self {
                    awake: true,
                    onset_ns: s.t_ns,
                    prev_decel_mps2: decel,
                    ..Self::default()
                };
            }
            self.last_wake_ns = s.t_ns;
            if woke {
                OnsetStep::Woke
            } else {
                OnsetStep::Awake
            }
        } else if self.awake && s.t_ns.saturating_sub(self.last_wake_ns) > p.reset_gap_ns {
            *self = Self {
                prev_decel_mps2: decel,
                ..Self::default()
            };
            return OnsetStep::Reset;
        } else if self.awake {
            OnsetStep::Awake
        } else {
            return OnsetStep::Quiet;
        };
        self.delta_v_mps += 0.5 * (prev + decel) * s.dt_s;
        step
    }

    /// Onset time of the event in progress.
    pub fn onset_ns(&self) -> Option<u64> {
        self.awake.then_some(self.onset_ns)
    }

    /// An event is in progress.
    pub fn awake(&self) -> bool {
        self.awake
    }

    /// A quiet sample (below the wake threshold, no event in progress: [`Onset::push`] would
    /// return [`OnsetStep::Quiet`]): only its deceleration is kept for the next trapezoid.
    pub fn note_quiet(&mut self, decel_mps2: f64) {
        self.prev_decel_mps2 = decel_mps2;
    }

    /// Δv integrated since the onset, m/s (0 when quiet).
    pub fn delta_v_mps(&self) -> f64 {
        self.delta_v_mps
    }
}

/// Time constant of the deceleration that [`Loading`] smooths, s (0.25 ms: one to two samples
/// of the 4 kHz sensor, enough that its noise of 0.5 m/s² cannot pull a 4 g pulse under 85 %
/// of its peak, short enough not to carry a 5–15 ms pulse's crest past its fall — at 0.5 ms
/// the lag let kerb strikes at a predicted contact decide before they were seen falling).
pub const LOADING_SMOOTHING_S: f64 = 0.25e-3;

/// Whether an event's deceleration is still *loading*: its smoothed value is still close to
/// the highest it reached since the onset.
///
/// Why it discriminates: in a crash the compartment's deceleration is the contact force over
/// the ego mass, and the force grows with the crush as long as the structures are loaded (the
/// force–deflection curves only rise), so it does not fall during the tens of ms in which the
/// restraint is decided. A misuse event of the whole car — pothole, kerb strike, door slam,
/// hammer blow — is a short pulse that has peaked and is falling by the time it has carried
/// the velocity change a decision needs. A decision that also requires "still loading"
/// ([`Loading::holds`]) therefore costs a real crash nothing and lifts the no-fire limit of
/// a half-sine misuse pulse (total Δv = 2·peak·duration/π) from the Δv floor f to
/// 2f / (1 + √(1 − k²)): the pulse still holds k of its peak at most until sin θ = k past its
/// crest, where it has carried (1 + √(1 − k²))/2 of its Δv. For the default k = 0.85 that is
/// 1.31 f (less the smoothing's lag; tests in `fallback`, and `misuse-matrix`).
///
/// What it smooths is the median of the last three samples: one wild sample (a spike of an
/// otherwise healthy sensor, 10–200 g) is no crest — held as the crest, it kept a crash that
/// followed it from "loading" until the crash had carried the exemption's Δv, 20 ms late.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Loading {
    smooth_mps2: f64,
    peak_mps2: f64,
    /// The two samples before the newest, oldest first.
    prev_mps2: [f64; 2],
}

/// The median of three (finite inputs; compares, no NaN handling: [`Loading::push`] takes
/// finite samples only).
fn median3(a: f64, b: f64, c: f64) -> f64 {
    let (lo, hi) = if a <= b { (a, b) } else { (b, a) };
    if c <= lo {
        lo
    } else if c >= hi {
        hi
    } else {
        c
    }
}

impl Loading {
    /// Starts a new event at its first (wake-up) sample: from rest (the samples before it
    /// were quiet), the wake-up sample the newest of the median's three.
    pub fn start(&mut self, decel_mps2: f64) {
        *self = Self {
            smooth_mps2: 0.0,
            peak_mps2: 0.0,
            prev_mps2: [
                0.0,
                if decel_mps2.is_finite() {
                    decel_mps2
                } else {
                    0.0
                },
            ],
        };
    }

    /// One more sample of the event (`dt_s`: its interval; non-finite or non-positive
    /// intervals leave the state unchanged).
    pub fn push(&mut self, decel_mps2: f64, dt_s: f64) {
        let a = dt_s / (LOADING_SMOOTHING_S + dt_s);
        if a.is_finite() && a > 0.0 && decel_mps2.is_finite() {
            let [p0, p1] = self.prev_mps2;
            self.prev_mps2 = [p1, decel_mps2];
            self.smooth_mps2 += a * (median3(p0, p1, decel_mps2) - self.smooth_mps2);
            self.peak_mps2 = self.peak_mps2.max(self.smooth_mps2);
        }
    }

    /// The highest smoothed deceleration since the start, m/s².
    pub fn peak_mps2(&self) -> f64 {
        self.peak_mps2
    }

    /// The smoothed deceleration is at least `fraction` of its peak since the onset (a
    /// `fraction` ≤ 0 always holds: the rule switched off).
    pub fn holds(&self, fraction: f64) -> bool {
        fraction <= 0.0 || self.smooth_mps2 >= fraction * self.peak_mps2
    }
}

/// Crash confirmation from the compartment accelerometer: deceleration over a threshold for
/// N consecutive samples AND Δv integrated since wake-up over a threshold. Both are needed: the
/// persistence rejects spikes, the Δv rejects short high-g events (door slam, pothole) that
/// carry no velocity change.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct CrashDetector {
    onset: Onset,
    run: u32,
    confirmed: Option<(u64, u64)>,
}

impl CrashDetector {
    /// Feeds one plausible sample (nothing changes once confirmed: latched).
    pub fn push(&mut self, p: &ConfirmParams, s: &AccelSample) {
        if self.confirmed.is_some() {
            return;
        }
        match self.onset.push(p, s) {
            OnsetStep::Quiet | OnsetStep::Reset => {
                self.run = 0;
                return;
            }
            OnsetStep::Woke => self.run = 0,
            OnsetStep::Awake => {}
        }
        self.run = if s.decel_mps2 >= p.decel_mps2 {
            self.run.saturating_add(1)
        } else {
            0
        };
        if self.run >= p.samples && self.onset.delta_v_mps() >= p.delta_v_mps {
            if let Some(onset) = self.onset.onset_ns() {
                self.confirmed = Some((s.t_ns, onset));
            }
        }
    }

    /// An event is in progress (and not yet confirmed).
    pub fn awake(&self) -> bool {
        self.confirmed.is_none() && self.onset.awake()
    }

    /// See [`Onset::note_quiet`].
    pub fn note_quiet(&mut self, decel_mps2: f64) {
        self.onset.note_quiet(decel_mps2);
    }

    /// Time of confirmation, if confirmed (latched).
    pub fn confirmed_at_ns(&self) -> Option<u64> {
        self.confirmed.map(|c| c.0)
    }

    /// Measured contact instant: the wake-up sample of the confirmed event, or of the event in
    /// progress.
    pub fn onset_ns(&self) -> Option<u64> {
        self.confirmed.map(|c| c.1).or(self.onset.onset_ns())
    }

    /// Δv integrated since wake-up, m/s.
    pub fn delta_v_mps(&self) -> f64 {
        self.onset.delta_v_mps()
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

    fn feed(d: &mut CrashDetector, first_ns: u64, decel_mps2: &[f64]) {
        for (k, &a) in decel_mps2.iter().enumerate() {
            let s = AccelSample {
                t_ns: first_ns + k as u64 * 1_000_000,
                dt_s: 1e-3,
                decel_mps2: a,
            };
            d.push(&params(), &s);
        }
    }

    #[test]
    fn confirms_a_constant_10g_pulse_when_delta_v_reaches_threshold() {
        // 10 g at 1 kHz from a quiet 0 g: Δv after n samples (trapezoidal, the first interval
        // rising from 0) = (n − ½) · 98.0665 · 1e-3 → ≥ 0.5 at n = 6.
        let mut d = CrashDetector::default();
        feed(&mut d, 1_000_000, &[10.0 * G_MPS2; 8]);
        assert_eq!(d.onset_ns(), Some(1_000_000));
        assert_eq!(d.confirmed_at_ns(), Some(1_000_000 + 5 * 1_000_000));
    }

    #[test]
    fn a_short_spike_or_a_braking_manoeuvre_never_confirms() {
        let mut d = CrashDetector::default();
        // 30 g for 2 samples then nothing: persistence fails.
        feed(&mut d, 0, &[300.0, 300.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]);
        // 1.2 g braking for a long time: below the wake threshold.
        feed(&mut d, 20_000_000, &[11.8; 800]);
        assert_eq!(d.confirmed_at_ns(), None);
        assert_eq!(
            d.onset_ns(),
            None,
            "the spike's event reset after 10 ms quiet"
        );
    }

    #[test]
    fn the_onset_resets_after_the_quiet_gap_and_integrates_from_the_wake_sample() {
        let p = params();
        let mut o = Onset::default();
        let s = |t_ms: u64, g: f64| AccelSample {
            t_ns: t_ms * 1_000_000,
            dt_s: 1e-3,
            decel_mps2: g * G_MPS2,
        };
        assert_eq!(o.push(&p, &s(0, 1.0)), OnsetStep::Quiet);
        assert_eq!(o.push(&p, &s(1, 2.0)), OnsetStep::Woke);
        assert_eq!(o.push(&p, &s(2, 1.0)), OnsetStep::Awake);
        // Trapezoids (1 + 2)/2 and (2 + 1)/2 g over 1 ms each.
        assert!((o.delta_v_mps() - 3.0 * G_MPS2 * 1e-3).abs() < 1e-12);
        assert_eq!(o.onset_ns(), Some(1_000_000));
        // 10 ms after the last wake sample: still awake; 11 ms: reset.
        assert_eq!(o.push(&p, &s(11, 0.0)), OnsetStep::Awake);
        assert_eq!(o.push(&p, &s(12, 0.0)), OnsetStep::Reset);
        assert_eq!((o.onset_ns(), o.delta_v_mps()), (None, 0.0));
    }
}
