//! What the acceleration sensors see besides a crash: the scenario's `[[accel_event]]` entries
//! (misuse events the whole car feels, single-sensor faults) as signals of scenario time.
//!
//! Every signal is a closed-form or precomputed function of time, never of a sensor's sample
//! grid, so two sensors with different rates see the same mechanical event (`sensor = "all"`)
//! at their own instants, and a restarted feed sees the same signal again. Signs as the
//! readings: the values returned here are accelerations [m/s², negative = deceleration];
//! a file's `peak_g > 0` is a deceleration.
//!
//! | kind | signal |
//! |---|---|
//! | `half_sine` | `−peak_g·g·sin(π (t − start_s) / duration)` for `t ∈ [start_s, start_s + duration]`, added |
//! | `spike` | the first sample at or after `start_s` reads `−peak_g·g` (replaces the reading) |
//! | `rough_road` | band-limited random signal with `rms_g` over `[start_s, end_s)`, added ([`ROUGH_ROAD_BAND_HZ`]; the car's response from rest at `start_s`, clipped at [`ROUGH_ROAD_CREST_FACTOR`] × rms) |
//! | `offset` | `−peak_g·g` over `[start_s, end_s)`, added |
//! | `ringing` | `d/dt[−peak_g·g/ω · sin(ωτ + φ) · sin²(πτ/T)] − (π·net_dv/2T) · sin(πτ/T)` for `τ = t − start_s ∈ [0, T]`, `T = duration_ms`, `ω = 2π·frequency_hz`, `φ = phase_deg`: zero-mean ringing (≈ `peak_g` at its crests when ω ≫ π/T) over a rigid-body pulse that carries exactly `net_dv_mps`, added |
//!
//! Why `ringing` is written as a derivative: the ringing is the acceleration of a velocity
//! wiggle that starts and ends at rest (`sin²` is 0 at both ends), so its integral — the
//! velocity change it gives the car — is exactly zero whatever the frequency, phase or
//! envelope; what the car's speed changes by is `net_dv_mps` alone, the bound a misuse
//! contact's impulse sets (Δv = J / m). A one-signed `half_sine` instead moves the whole car
//! by its area (2·peak·duration/π).

use crate::scenario::{AccelEvent, AccelEventKind, AccelSensor, EventSensor, Scenario};
use physics::defaults::STANDARD_GRAVITY_MPS2 as G;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// Pass band of a rough road's signal [Hz]: body vertical/pitch and longitudinal excitation of
/// a car on a rough surface lies between the body mode (~1–2 Hz, mostly vertical) and the
/// wheel-hop mode (~10–15 Hz) and its harmonics; 5–40 Hz is the part a compartment
/// accelerometer's longitudinal channel sees. Realised as white Gaussian noise through a
/// 2nd-order Butterworth high-pass at 5 Hz and a 2nd-order Butterworth low-pass at 40 Hz (−3 dB
/// at both edges, 40 dB/decade skirts).
pub const ROUGH_ROAD_BAND_HZ: (f64, f64) = (5.0, 40.0);

/// Grid on which a rough road's signal is generated [Hz]; sensors read it by linear
/// interpolation (the band ends at 40 Hz: the interpolation error is < 1 % of the amplitude).
pub const ROUGH_ROAD_GRID_HZ: f64 = 2000.0;

/// Largest |value| of a rough road's track, as a multiple of its rms (crest factor): random
/// vibration tests clip their drive signal at 3σ (IEC 60068-2-64 asks for a crest factor of at
/// least 2.5; shaker controllers clip at 3). Why here: a Gaussian track's 4σ lobe at 4.5 g rms
/// is an 18 g, 20 ms pulse — a 300 kN longitudinal force through the wheels and 1.9 m/s of
/// rigid-body Δv, more than four wheels can carry (the pothole's worst 45 kN per wheel) and
/// what a 20 km/h barrier crash carries; a road does not make it.
pub const ROUGH_ROAD_CREST_FACTOR: f64 = 3.0;

/// ChaCha8 stream of rough road `accel_event[i]`: `ROUGH_ROAD_STREAM_BASE + i` (stream 0 is the
/// object list and crash accelerometer, [`crate::sensors::SAFING_STREAM`] the safing sensor).
pub const ROUGH_ROAD_STREAM_BASE: u64 = 0x100;

/// Tolerance of sample instants against event edges [s] (the feed grid's own `1e-9` is for
/// ms ticks; sample instants are `k / rate`).
const EDGE_S: f64 = 1e-12;

/// One prepared event.
#[derive(Clone, Debug)]
enum Signal {
    HalfSine {
        start_s: f64,
        duration_s: f64,
        peak_mps2: f64,
    },
    Spike {
        start_s: f64,
        value_mps2: f64,
    },
    RoughRoad {
        start_s: f64,
        end_s: f64,
        /// Acceleration [m/s²] at `start_s + j / ROUGH_ROAD_GRID_HZ`.
        track: Vec<f64>,
    },
    Offset {
        start_s: f64,
        end_s: f64,
        shift_mps2: f64,
    },
    Ringing(Ringing),
}

/// A `ringing` event, prepared (module docs).
#[derive(Clone, Copy, Debug)]
struct Ringing {
    start_s: f64,
    duration_s: f64,
    /// Ringing amplitude [m/s², negative = deceleration first].
    amp_mps2: f64,
    omega_rad_s: f64,
    phase_rad: f64,
    /// Peak of the rigid-body half-sine [m/s², negative = deceleration].
    body_peak_mps2: f64,
}

/// How a reading steps the anti-alias filter ([`AccelEvents::substeps`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Substeps {
    /// The longest substep [s].
    pub max_step_s: f64,
    /// The input is linear over each substep ([`crate::lowpass::AntiAlias::read_linear`]).
    pub linear: bool,
}

impl Signal {
    /// Where an additive signal acts: `[start, end]` [s] (`None`: a spike, which replaces a
    /// sample instead of adding to the input).
    fn additive_span_s(&self) -> Option<(f64, f64)> {
        match self {
            Signal::HalfSine {
                start_s,
                duration_s,
                ..
            } => Some((*start_s, start_s + duration_s)),
            Signal::Ringing(r) => Some((r.start_s, r.start_s + r.duration_s)),
            Signal::RoughRoad { start_s, end_s, .. } | Signal::Offset { start_s, end_s, .. } => {
                Some((*start_s, *end_s))
            }
            Signal::Spike { .. } => None,
        }
    }
}

impl Ringing {
    fn at(&self, t_s: f64) -> Option<f64> {
        let tau = t_s - self.start_s;
        if !(tau >= -EDGE_S && tau <= self.duration_s + EDGE_S) {
            return None;
        }
        let tau = tau.clamp(0.0, self.duration_s);
        let k = std::f64::consts::PI / self.duration_s;
        let (s1, c1) = (k * tau).sin_cos();
        let window = s1 * s1;
        let window_rate = k * 2.0 * s1 * c1;
        let (sw, cw) = (self.omega_rad_s * tau + self.phase_rad).sin_cos();
        let ringing = self.amp_mps2 * (cw * window + sw * window_rate / self.omega_rad_s);
        Some(ringing + self.body_peak_mps2 * s1)
    }
}

#[derive(Clone, Debug)]
struct Event {
    reach: EventSensor,
    signal: Signal,
}

/// The scenario's acceleration events, ready to be read at any instant.
#[derive(Clone, Debug, Default)]
pub struct AccelEvents {
    events: Vec<Event>,
}

impl AccelEvents {
    /// Prepares `scenario`'s `[[accel_event]]` entries (validated: every kind has its keys).
    /// Rough roads are generated here, from the scenario's seed on their own streams, up to
    /// the end of the run at most.
    pub fn new(scenario: &Scenario) -> Self {
        let events = scenario
            .accel_events
            .iter()
            .enumerate()
            .map(|(i, e)| Event {
                reach: e.sensor,
                signal: prepare(scenario, i, e),
            })
            .collect();
        AccelEvents { events }
    }

    /// True if the scenario has no events.
    pub fn is_empty(&self) -> bool {
        self.events.is_empty()
    }

    /// The sum of the additive events (half-sine, rough road, offset) `sensor` sees at `t_s`
    /// [m/s², negative = deceleration]; `None` when none is active (the reading is then the
    /// sensor's alone, bit for bit).
    pub fn added_mps2(&self, sensor: AccelSensor, t_s: f64) -> Option<f64> {
        let mut sum = None;
        for e in self.events.iter().filter(|e| e.reach.reaches(sensor)) {
            let v = match &e.signal {
                Signal::HalfSine {
                    start_s,
                    duration_s,
                    peak_mps2,
                } => {
                    let x = t_s - start_s;
                    (x >= -EDGE_S && x <= duration_s + EDGE_S).then(|| {
                        let phase = (x / duration_s).clamp(0.0, 1.0);
                        peak_mps2 * (std::f64::consts::PI * phase).sin()
                    })
                }
                Signal::RoughRoad {
                    start_s,
                    end_s,
                    track,
                } => (t_s >= start_s - EDGE_S && t_s < end_s - EDGE_S)
                    .then(|| interpolate(track, (t_s - start_s) * ROUGH_ROAD_GRID_HZ)),
                Signal::Offset {
                    start_s,
                    end_s,
                    shift_mps2,
                } => (t_s >= start_s - EDGE_S && t_s < end_s - EDGE_S).then_some(*shift_mps2),
                Signal::Ringing(r) => r.at(t_s),
                Signal::Spike { .. } => None,
            };
            if let Some(v) = v {
                sum = Some(sum.unwrap_or(0.0) + v);
            }
        }
        sum
    }

    /// Whether no additive event reaching `sensor` is active anywhere in `[t0_s, t1_s]`
    /// ([`Self::added_mps2`] is `None` throughout; a spike replaces a sample and is not read
    /// through the filter).
    pub fn quiet_over(&self, sensor: AccelSensor, t0_s: f64, t1_s: f64) -> bool {
        // Each window with a margin beyond the edge tolerance `added_mps2` applies.
        let overlaps = |(a, b): (f64, f64)| a <= t1_s + 2.0 * EDGE_S && b >= t0_s - 2.0 * EDGE_S;
        !self
            .events
            .iter()
            .filter(|e| e.reach.reaches(sensor))
            .filter_map(|e| e.signal.additive_span_s())
            .any(overlaps)
    }

    /// How the accelerometers' anti-alias filter ([`crate::lowpass`]) steps through what the
    /// additive events reaching `sensor` put into `[t0_s, t1_s]`: the longest substep that
    /// resolves them — a twentieth of a half-sine's or a ringing envelope's length, a twelfth
    /// of a ringing's period, a rough road's grid step; [`crate::lowpass::DEFAULT_STEP_S`] when
    /// none is active — and whether the input is linear over each substep (no half-sine or
    /// ringing: a rough road is linear between its grid points, an offset is a constant).
    pub fn substeps(&self, sensor: AccelSensor, t0_s: f64, t1_s: f64) -> Substeps {
        let overlaps = |(a, b): (f64, f64)| a <= t1_s + EDGE_S && b >= t0_s - EDGE_S;
        let mut out = Substeps {
            max_step_s: crate::lowpass::DEFAULT_STEP_S,
            linear: true,
        };
        for e in self.events.iter().filter(|e| e.reach.reaches(sensor)) {
            if !e.signal.additive_span_s().is_some_and(overlaps) {
                continue;
            }
            // The substep that resolves the event, and whether it is curved inside one.
            let (step_s, curved) = match &e.signal {
                Signal::HalfSine { duration_s, .. } => (duration_s / 20.0, true),
                Signal::Ringing(r) => (
                    (r.duration_s / 20.0).min(std::f64::consts::TAU / (12.0 * r.omega_rad_s)),
                    true,
                ),
                // Linear between its grid points.
                Signal::RoughRoad { .. } => (1.0 / ROUGH_ROAD_GRID_HZ, false),
                // An offset is a constant the default step resolves; a spike is no input.
                Signal::Offset { .. } | Signal::Spike { .. } => continue,
            };
            out.max_step_s = out.max_step_s.min(step_s);
            out.linear &= !curved;
        }
        out
    }

    /// The reading of a spike that replaces `sensor`'s sample at `t_s`, whose samples are
    /// `dt_s` apart: the sample is the first at or after the spike's `start_s`, i.e. `t_s` lies
    /// in `[start_s, start_s + dt_s)` (exactly one sample of a grid does). The last spike
    /// wins when two hit the same sample.
    pub fn spike_mps2(&self, sensor: AccelSensor, t_s: f64, dt_s: f64) -> Option<f64> {
        self.events
            .iter()
            .rev()
            .filter(|e| e.reach.reaches(sensor))
            .find_map(|e| match e.signal {
                Signal::Spike {
                    start_s,
                    value_mps2,
                } if t_s >= start_s - EDGE_S && t_s < start_s + dt_s - EDGE_S => Some(value_mps2),
                _ => None,
            })
    }
}

fn prepare(scenario: &Scenario, index: usize, e: &AccelEvent) -> Signal {
    let peak_mps2 = -e.peak_g.unwrap_or(0.0) * G;
    let end_s = e.end_s.unwrap_or(e.start_s);
    match e.kind {
        AccelEventKind::HalfSine => Signal::HalfSine {
            start_s: e.start_s,
            duration_s: e.duration_ms.unwrap_or(1.0) * 1e-3,
            peak_mps2,
        },
        AccelEventKind::Ringing => {
            let duration_s = e.duration_ms.unwrap_or(1.0) * 1e-3;
            Signal::Ringing(Ringing {
                start_s: e.start_s,
                duration_s,
                amp_mps2: peak_mps2,
                omega_rad_s: 2.0 * std::f64::consts::PI * e.frequency_hz.unwrap_or(1.0),
                phase_rad: e.phase_deg.unwrap_or(0.0).to_radians(),
                body_peak_mps2: -e.net_dv_mps.unwrap_or(0.0) * std::f64::consts::PI
                    / (2.0 * duration_s),
            })
        }
        AccelEventKind::Spike => Signal::Spike {
            start_s: e.start_s,
            value_mps2: peak_mps2,
        },
        AccelEventKind::Offset => Signal::Offset {
            start_s: e.start_s,
            end_s,
            shift_mps2: peak_mps2,
        },
        AccelEventKind::RoughRoad => {
            let mut rng = ChaCha8Rng::seed_from_u64(scenario.seed);
            rng.set_stream(ROUGH_ROAD_STREAM_BASE + index as u64);
            // Nothing is sampled after the run: generate up to its end (+ 2 grid points).
            let last_s = end_s.min(scenario.duration_s.max(e.start_s));
            let track = rough_road(&mut rng, last_s - e.start_s, -e.rms_g.unwrap_or(0.0) * G);
            Signal::RoughRoad {
                start_s: e.start_s,
                end_s,
                track,
            }
        }
    }
}

/// Linear interpolation of `track` at fractional index `x ≥ 0` (the last point beyond it).
fn interpolate(track: &[f64], x: f64) -> f64 {
    // `as` truncates, which is the floor for x ≥ 0 (NaN → 0) — without the libm call that a
    // baseline x86-64 build makes of `floor`.
    let i = x.max(0.0) as usize;
    match (track.get(i), track.get(i + 1)) {
        (Some(a), Some(b)) => a + (b - a) * (x - i as f64),
        (Some(a), None) => *a,
        _ => track.last().copied().unwrap_or(0.0),
    }
}

/// A rough road's track over `length_s` on the [`ROUGH_ROAD_GRID_HZ`] grid: the car's response
/// to a road that begins at `start_s` — white Gaussian noise through the band-pass starting
/// from rest, so the signal builds up over the first ≈ 10 ms instead of switching on mid-lobe
/// (an acceleration step of many g no suspension transmits) — clipped at
/// [`ROUGH_ROAD_CREST_FACTOR`] × its rms and scaled so the rms of the track's points inside the
/// window is exactly `|rms_mps2|` (the sign of `rms_mps2` only says the convention; the signal
/// is symmetric).
fn rough_road(rng: &mut ChaCha8Rng, length_s: f64, rms_mps2: f64) -> Vec<f64> {
    let n = (length_s.max(0.0) * ROUGH_ROAD_GRID_HZ).ceil() as usize + 2;
    let mut filter = BandPass::new(ROUGH_ROAD_BAND_HZ, ROUGH_ROAD_GRID_HZ);
    let mut track: Vec<f64> = (0..n)
        .map(|_| filter.step(crate::noise::gauss(rng)))
        .collect();
    // The rms over the window's own points (j / grid < length).
    let inside = ((length_s.max(0.0) * ROUGH_ROAD_GRID_HZ).ceil() as usize).clamp(1, n);
    let rms = |t: &[f64]| (t[..inside].iter().map(|v| v * v).sum::<f64>() / inside as f64).sqrt();
    // Clip, then restore the rms: the clipped lobes' lost power raises the rest by a few %, so
    // a few rounds bring the crest factor to its bound (within 0.1 %) at the exact rms.
    for _ in 0..8 {
        let limit = ROUGH_ROAD_CREST_FACTOR * rms(&track);
        track.iter_mut().for_each(|v| *v = v.clamp(-limit, limit));
    }
    let r = rms(&track);
    let gain = if r > 0.0 { rms_mps2.abs() / r } else { 0.0 };
    track.iter_mut().for_each(|v| *v *= gain);
    track
}

/// The rough road's band-pass: a 2nd-order Butterworth high-pass at `f_lo` cascaded with a
/// 2nd-order Butterworth low-pass at `f_hi` (RBJ cookbook biquads, bilinear transform
/// prewarped at each corner): −3 dB at both edges, 40 dB/decade skirts, ≈ 0 dB between.
struct BandPass {
    high: Biquad,
    low: Biquad,
}

impl BandPass {
    fn new((lo_hz, hi_hz): (f64, f64), fs_hz: f64) -> Self {
        BandPass {
            high: Biquad::butterworth(lo_hz, fs_hz, true),
            low: Biquad::butterworth(hi_hz, fs_hz, false),
        }
    }

    fn step(&mut self, x: f64) -> f64 {
        self.low.step(self.high.step(x))
    }
}

/// One 2nd-order section, direct form I, normalised (a0 = 1).
struct Biquad {
    b: [f64; 3],
    a: [f64; 2],
    x: [f64; 2],
    y: [f64; 2],
}

impl Biquad {
    /// Butterworth (Q = 1/√2) high-pass (`high`) or low-pass at `f_hz`.
    fn butterworth(f_hz: f64, fs_hz: f64, high: bool) -> Self {
        let w0 = 2.0 * std::f64::consts::PI * f_hz / fs_hz;
        let (sin, cos) = w0.sin_cos();
        let alpha = sin / (2.0 * std::f64::consts::FRAC_1_SQRT_2);
        let a0 = 1.0 + alpha;
        let (b0, b1) = if high {
            ((1.0 + cos) / 2.0, -(1.0 + cos))
        } else {
            ((1.0 - cos) / 2.0, 1.0 - cos)
        };
        Biquad {
            b: [b0 / a0, b1 / a0, b0 / a0],
            a: [-2.0 * cos / a0, (1.0 - alpha) / a0],
            x: [0.0; 2],
            y: [0.0; 2],
        }
    }

    fn step(&mut self, x: f64) -> f64 {
        let y = self.b[0] * x + self.b[1] * self.x[0] + self.b[2] * self.x[1]
            - self.a[0] * self.y[0]
            - self.a[1] * self.y[1];
        self.x = [x, self.x[0]];
        self.y = [y, self.y[0]];
        y
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Gain of the band-pass at `f` Hz, measured on a long sine.
    fn gain_at(f: f64) -> f64 {
        let mut bp = BandPass::new(ROUGH_ROAD_BAND_HZ, ROUGH_ROAD_GRID_HZ);
        let n = (20.0 * ROUGH_ROAD_GRID_HZ) as usize;
        let mut peak: f64 = 0.0;
        for j in 0..n {
            let y = bp.step((2.0 * std::f64::consts::PI * f * j as f64 / ROUGH_ROAD_GRID_HZ).sin());
            if j > n / 2 {
                peak = peak.max(y.abs());
            }
        }
        peak
    }

    #[test]
    fn the_band_pass_is_minus_3_db_at_its_edges_and_flat_between() {
        let (lo, hi) = ROUGH_ROAD_BAND_HZ;
        let centre = (lo * hi).sqrt();
        // Between: each section's own roll-off, 1/√(1 + (5/14.1)⁴) · 1/√(1 + (14.1/40)⁴).
        assert!(
            (gain_at(centre) - 0.984).abs() < 0.005,
            "{}",
            gain_at(centre)
        );
        for f in [lo, hi] {
            let g = gain_at(f);
            assert!(
                (g - std::f64::consts::FRAC_1_SQRT_2).abs() < 0.01,
                "{f} Hz: {g}"
            );
        }
        // 40 dB/decade: a decade out, 1 %.
        assert!(gain_at(0.5) < 0.011 && gain_at(400.0) < 0.011);
    }

    #[test]
    fn a_track_has_its_rms_and_is_reproducible() {
        let make = || {
            let mut rng = ChaCha8Rng::seed_from_u64(3);
            rng.set_stream(ROUGH_ROAD_STREAM_BASE);
            rough_road(&mut rng, 2.0, -2.0 * G)
        };
        let t = make();
        assert_eq!(t, make());
        let inside = &t[..4000];
        let rms = (inside.iter().map(|v| v * v).sum::<f64>() / 4000.0).sqrt();
        assert!((rms - 2.0 * G).abs() < 1e-9, "{rms}");
        // Crest factor 3 (clipped), and a Gaussian track reaches it in 2 s (≈ 100 lobes).
        let peak = inside.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        assert!(
            (2.9 * 2.0 * G..=3.0 * 2.0 * G * 1.002).contains(&peak),
            "{}",
            peak / G
        );
        // From rest: the response builds up; its first ms are far below the rms.
        assert!(
            t[0].abs() < 0.5 * G && t[1].abs() < 0.5 * G,
            "{} {}",
            t[0],
            t[1]
        );
    }

    /// The velocity change a `ringing` event gives the car is its `net_dv_mps` and nothing
    /// more, at any frequency and phase (trapezoid over a grid 200× finer than the carrier),
    /// and its crests reach `peak_g` (+ the body pulse) — checked against the closed forms.
    #[test]
    fn ringing_carries_exactly_its_net_dv_and_reaches_its_peak() {
        for (f_hz, phase_deg, net_dv, peak_g, ms) in [
            (300.0, 0.0, 0.0, 20.0, 30.0),
            (4000.0, 0.0, 0.0, 45.0, 25.0),
            (4000.0, 90.0, 0.3, 45.0, 4.0),
            (8000.0, 33.0, -0.2, 30.0, 3.0),
            (150.0, 180.0, 0.6, 5.0, 20.0),
        ] {
            let r = Ringing {
                start_s: 0.1,
                duration_s: ms * 1e-3,
                amp_mps2: -peak_g * G,
                omega_rad_s: 2.0 * std::f64::consts::PI * f_hz,
                phase_rad: f64::to_radians(phase_deg),
                body_peak_mps2: -net_dv * std::f64::consts::PI / (2.0 * ms * 1e-3),
            };
            let h = 1.0 / (200.0 * f_hz);
            let n = (ms * 1e-3 / h).ceil() as usize + 1;
            let (mut dv, mut prev, mut peak) = (0.0, r.at(0.1).unwrap_or(0.0), 0.0_f64);
            for k in 1..=n {
                let a = r.at(0.1 + k as f64 * h).unwrap_or(0.0);
                dv += 0.5 * (a + prev) * h;
                peak = peak.max(a.abs());
                prev = a;
            }
            let body = (net_dv * std::f64::consts::PI / (2.0 * ms * 1e-3)).abs();
            assert!(
                (-dv - net_dv).abs() < 1e-4,
                "{f_hz} Hz {phase_deg}°: Δv {} for {net_dv}",
                -dv
            );
            assert!(
                peak <= peak_g * G * 1.05 + body && peak >= peak_g * G * 0.9,
                "{f_hz} Hz: peak {} g for {peak_g} g",
                peak / G
            );
            assert_eq!(r.at(0.1 - 1e-6), None);
            assert_eq!(r.at(0.1 + ms * 1e-3 + 1e-6), None);
        }
    }

    #[test]
    fn a_quiet_span_has_no_added_acceleration_anywhere_in_it() {
        // One event of each additive kind on the crash sensor and a spike: wherever
        // `quiet_over` says a 20 ms span is quiet, `added_mps2` is None at 10 µs steps in it,
        // and the spans around each event are not quiet.
        let s = Scenario::parse(
            "t.toml",
            "name = \"t\"\nduration_s = 1\n[ego]\nmass_kg = 1785\nspeed_kph = 0\n\
             [opponent]\nkind = \"barrier\"\ninitial_distance_m = 100\n[sensor]\nmass_estimate_kg = 3000\n[occupant]\nmass_kg = 75\n\
             [[accel_event]]\nkind = \"half_sine\"\nstart_s = 0.1\npeak_g = 5\nduration_ms = 10\n\
             [[accel_event]]\nkind = \"rough_road\"\nstart_s = 0.3\nend_s = 0.4\nrms_g = 1\n\
             [[accel_event]]\nkind = \"offset\"\nstart_s = 0.5\nend_s = 0.55\npeak_g = 2\nsensor = \"crash\"\n\
             [[accel_event]]\nkind = \"ringing\"\nstart_s = 0.7\npeak_g = 20\nfrequency_hz = 200\nduration_ms = 30\n\
             [[accel_event]]\nkind = \"spike\"\nstart_s = 0.9\npeak_g = 50\n",
        )
        .expect("valid");
        let ev = AccelEvents::new(&s);
        let mut quiet = 0;
        for k in 0..1000 {
            let t1 = k as f64 * 1e-3;
            let t0 = t1 - 0.02;
            if !ev.quiet_over(AccelSensor::Crash, t0, t1) {
                continue;
            }
            quiet += 1;
            for j in 0..=2000 {
                let ts = t0 + (t1 - t0) * j as f64 / 2000.0;
                assert_eq!(ev.added_mps2(AccelSensor::Crash, ts), None, "{ts}");
            }
        }
        // 1 000 spans less those touching the four additive events (≈ 30 + 120 + 70 + 50).
        assert!((600..=800).contains(&quiet), "{quiet}");
        for t1 in [0.105, 0.35, 0.52, 0.715] {
            assert!(!ev.quiet_over(AccelSensor::Crash, t1 - 0.02, t1), "{t1}");
        }
        // The offset is the crash sensor's alone.
        assert!(ev.quiet_over(AccelSensor::Safing, 0.5, 0.52));
    }
}
