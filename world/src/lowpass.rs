//! The accelerometers' anti-alias filter: what a production airbag accelerometer does to the
//! acceleration before it is sampled.
//!
//! **Source.** Analog Devices ADXL180 (an iMEMS crash and safing accelerometer for airbag
//! systems), data sheet Rev. 0, "Signal range and filtering", p. 39: "a third-order, low-pass
//! Bessel filter" whose −3 dB corner is selectable at 100, 200, **400** (the default code
//! `FC = 00`) or 800 Hz. The bench's default is that: 3 poles, Bessel, −3 dB at 400 Hz
//! (`[sensor] accel_lowpass_hz`, 0 = an ideal sampler without filter). What it does: a 4 kHz structural ringing that an unfiltered 4 kHz sampler sees
//! at its crests as a one-signed deceleration (aliased to 0 Hz) is attenuated ≈ 60 dB before
//! sampling; a crash pulse (< 100 Hz content) passes, delayed by the filter's group delay
//! (1/ω₀ = [`group_delay_s`], 0.70 ms at 400 Hz).
//!
//! **Model.** The normalised Bessel polynomial of order 3, H(s) = 15 / (s³ + 6s² + 15s + 15)
//! (unit group delay at DC; its −3 dB frequency is ω = 1.7557), scaled to the corner, as a
//! state-space system in scaled derivatives (x₁ = y, x₂ = ẏ/ω₀, x₃ = ÿ/ω₀², so the states
//! have one magnitude), stepped on substeps fine enough for what the input contains
//! ([`crate::events::AccelEvents::substeps`]): the filter acts on the continuous signal, so
//! content at any frequency — multiples of either sampling rate included — is filtered as the
//! analog part of the sensor would, not aliased first. Most of what a sensor feels is linear
//! between the points it is tabulated on (the crash pulse and the crush every 0.1 ms, a rough
//! road's track every 0.5 ms, braking ramps and plateaus): over such a substep the filter is
//! stepped exactly, by its first-order-hold discretisation ([`AntiAlias::read_linear`]: one
//! input point and a 3 × 3 product a substep); a half-sine or a ringing, curved inside any
//! substep, is integrated with classical Runge–Kutta ([`AntiAlias::read`], three input points
//! and four derivatives a substep).

/// The normalised third-order Bessel polynomial's −3 dB frequency (unit DC group delay).
const BESSEL3_CORNER: f64 = 1.755_7;

/// Longest substep [s] for the crash pulse and smooth content (20 kHz: the true pulse is
/// tabulated on a coarser grid and has no content near it).
pub const DEFAULT_STEP_S: f64 = 50e-6;

/// A gap between two readings longer than this [s] (a dropout) is not integrated through:
/// the filter restarts this long before the new reading (≈ 30 time constants at 400 Hz). It is
/// also the longest span one reading integrates over.
pub const RESTART_GAP_S: f64 = 0.02;

/// The group delay at DC of a third-order Bessel low-pass with −3 dB at `corner_hz` [s].
pub fn group_delay_s(corner_hz: f64) -> f64 {
    BESSEL3_CORNER / (2.0 * std::f64::consts::PI * corner_hz)
}

/// One sensor's filter, stepped along the scenario's time.
#[derive(Clone, Debug)]
pub struct AntiAlias {
    /// ω₀ = 1 / group delay [rad/s]; 0 = no filter (the reading is the input).
    omega0: f64,
    /// Time of the state [s] (`None` before the first reading).
    t_s: Option<f64>,
    x: [f64; 3],
    /// The exact steps of the two latest substep lengths ([`Self::read_linear`]), the newer
    /// first: a span that is a whole number of maximal substeps up to rounding divides into
    /// that number or one more, reading by reading.
    holds: [Option<Hold>; 2],
    /// The input at the state's time where [`Self::read_linear`] read it last: `(t, u)`.
    end_input: Option<(f64, f64)>,
}

/// One substep of the filter, exact for an input linear over it (first-order hold): with
/// u(τ) = u₀ + (u₁ − u₀)·τ/h, x(h) = Φ·x(0) + γ₀·u₀ + γ₁·(u₁ − u₀), where Φ, γ₀ and γ₁ are
/// blocks of exp(M·h) of the system augmented by the input and its increment,
/// M·h = [[A·h, B·h, 0], [0, 0, 1], [0, 0, 0]].
#[derive(Clone, Copy, Debug, PartialEq)]
struct Hold {
    h_s: f64,
    phi: [[f64; 3]; 3],
    from_u0: [f64; 3],
    from_du: [f64; 3],
}

/// A cached [`Hold`] serves substeps whose length differs from its own by at most this
/// fraction: readings at a fixed rate give the same substep up to rounding of the times
/// (≈ 10⁻¹³), and a 10⁻⁹ longer or shorter step moves the state by 10⁻¹⁰ of its change.
const HOLD_REUSE_TOLERANCE: f64 = 1e-9;

impl Hold {
    /// exp(M·h) by scaling and squaring: the Taylor series to the 16th power of M·h / 2ˢ,
    /// whose ∞-norm is ≤ ½ (a truncation of < 10⁻²⁰), squared s times.
    fn new(omega0: f64, h_s: f64) -> Self {
        type M5 = nalgebra::SMatrix<f64, 5, 5>;
        let wh = omega0 * h_s;
        let mut m = M5::zeros();
        m[(0, 1)] = wh;
        m[(1, 2)] = wh;
        m[(2, 0)] = -15.0 * wh;
        m[(2, 1)] = -15.0 * wh;
        m[(2, 2)] = -6.0 * wh;
        m[(2, 3)] = 15.0 * wh;
        m[(3, 4)] = 1.0;
        let norm = m
            .row_iter()
            .map(|r| r.iter().map(|v| v.abs()).sum::<f64>())
            .fold(0.0, f64::max);
        let squarings = (norm / 0.5).log2().ceil().max(0.0) as i32;
        let a = m / 2f64.powi(squarings);
        let (mut e, mut term) = (M5::identity(), M5::identity());
        for k in 1..=16 {
            term = term * a / k as f64;
            e += term;
        }
        for _ in 0..squarings {
            e = e * e;
        }
        Hold {
            h_s,
            phi: [0, 1, 2].map(|i| [0, 1, 2].map(|j| e[(i, j)])),
            from_u0: [0, 1, 2].map(|i| e[(i, 3)]),
            from_du: [0, 1, 2].map(|i| e[(i, 4)]),
        }
    }

    /// The step for substeps of `h_s` from `holds` (the two latest lengths, the newer first),
    /// derived and kept as the newer when neither serves it.
    fn cached(holds: &mut [Option<Hold>; 2], omega0: f64, h_s: f64) -> &Hold {
        let [newer, older] = holds;
        if !newer.is_some_and(|hold| hold.serves(h_s)) {
            if older.is_some_and(|hold| hold.serves(h_s)) {
                core::mem::swap(newer, older);
            } else {
                *older = newer.take();
            }
        }
        newer.get_or_insert_with(|| Hold::new(omega0, h_s))
    }

    fn serves(&self, h_s: f64) -> bool {
        (self.h_s - h_s).abs() <= HOLD_REUSE_TOLERANCE * h_s
    }

    #[inline]
    fn step(&self, x: &[f64; 3], u0: f64, u1: f64) -> [f64; 3] {
        let du = u1 - u0;
        let (p, g0, g1) = (&self.phi, &self.from_u0, &self.from_du);
        let row = |p: &[f64; 3], g0: f64, g1: f64| {
            p[0] * x[0] + p[1] * x[1] + p[2] * x[2] + g0 * u0 + g1 * du
        };
        [
            row(&p[0], g0[0], g1[0]),
            row(&p[1], g0[1], g1[1]),
            row(&p[2], g0[2], g1[2]),
        ]
    }
}

impl AntiAlias {
    /// A filter with −3 dB at `corner_hz` (≤ 0: none).
    pub fn new(corner_hz: f64) -> Self {
        AntiAlias {
            omega0: if corner_hz > 0.0 {
                1.0 / group_delay_s(corner_hz)
            } else {
                0.0
            },
            t_s: None,
            x: [0.0; 3],
            holds: [None; 2],
            end_input: None,
        }
    }

    fn derivative(&self, x: &[f64; 3], u: f64) -> [f64; 3] {
        let w = self.omega0;
        [
            w * x[1],
            w * x[2],
            w * (15.0 * (u - x[0]) - 15.0 * x[1] - 6.0 * x[2]),
        ]
    }

    /// The filter's output at `t_s` for the input `input(t)`, integrated from the previous
    /// reading with classical Runge–Kutta on substeps of at most `max_step_s` (for an input
    /// curved inside them: a half-sine, a ringing). A reading earlier than the state (a
    /// restarted feed) or the first one starts the filter settled on the input.
    pub fn read(&mut self, t_s: f64, max_step_s: f64, input: impl Fn(f64) -> f64) -> f64 {
        let Some((start, n, h)) = self.begin(t_s, max_step_s, &input) else {
            return self.x[0];
        };
        let mut t = start;
        let mut u0 = input(t);
        for _ in 0..n {
            let (um, u1) = (input(t + 0.5 * h), input(t + h));
            let x = self.x;
            let k1 = self.derivative(&x, u0);
            let k2 = self.derivative(&add(&x, &k1, 0.5 * h), um);
            let k3 = self.derivative(&add(&x, &k2, 0.5 * h), um);
            let k4 = self.derivative(&add(&x, &k3, h), u1);
            for i in 0..3 {
                self.x[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
            }
            t += h;
            u0 = u1;
        }
        self.finish(t_s)
    }

    /// [`Self::read`] for an input linear over each substep of at most `max_step_s` (the
    /// caller knows it: content tabulated on a grid no finer than the substeps, and no curved
    /// event) but at `kink_s`, where its slope may jump (the contact, where a crash pulse
    /// begins): each substep is the filter's exact response to the line through the input at
    /// its ends ([`Hold`]), and the substep holding the kink is two, split at it. A kink
    /// elsewhere inside a substep is read as the chord across it — a pulse's knees, whose
    /// slope changes little next to the contact's.
    pub fn read_linear(
        &mut self,
        t_s: f64,
        max_step_s: f64,
        kink_s: Option<f64>,
        input: impl Fn(f64) -> f64,
    ) -> f64 {
        let Some((start, n, h)) = self.begin(t_s, max_step_s, &input) else {
            return self.x[0];
        };
        let Self {
            omega0,
            x,
            holds,
            end_input,
            ..
        } = self;
        let omega0 = *omega0;
        let hold = Hold::cached(holds, omega0, h);
        // The substeps end at `start + k·h` and the last at `t_s` itself, so the input there is
        // the next reading's first, kept instead of read again.
        let mut u0 = match *end_input {
            Some((t, u)) if t == start => u,
            _ => input(start),
        };
        let mut t0 = start;
        for k in 1..=n {
            let t = if k == n { t_s } else { start + k as f64 * h };
            let u1 = input(t);
            *x = match kink_s.filter(|&tk| t0 < tk && tk < t) {
                Some(tk) => {
                    let uk = input(tk);
                    let x = Hold::new(omega0, tk - t0).step(x, u0, uk);
                    Hold::new(omega0, t - tk).step(&x, uk, u1)
                }
                None => hold.step(x, u0, u1),
            };
            (t0, u0) = (t, u1);
        }
        let reading = self.finish(t_s);
        self.end_input = Some((t_s, u0));
        reading
    }

    /// Where a reading at `t_s` starts and its substeps: `(start, count, length)`; `None` when
    /// there is nothing to integrate (no filter: the state is the input; the first reading or
    /// one earlier than the state: the filter starts settled on the input).
    #[inline(always)]
    fn begin(
        &mut self,
        t_s: f64,
        max_step_s: f64,
        input: &impl Fn(f64) -> f64,
    ) -> Option<(f64, usize, f64)> {
        if self.omega0 <= 0.0 {
            self.x = [input(t_s), 0.0, 0.0];
            return None;
        }
        let start = match self.t_s {
            Some(t0) if t0 <= t_s && t_s - t0 <= RESTART_GAP_S => t0,
            Some(t0) if t0 <= t_s => {
                let t0 = t_s - RESTART_GAP_S;
                self.x = [input(t0), 0.0, 0.0];
                t0
            }
            _ => {
                self.x = [input(t_s), 0.0, 0.0];
                self.t_s = Some(t_s);
                self.end_input = None;
                return None;
            }
        };
        let span = t_s - start;
        let h_max = max_step_s.clamp(1e-7, DEFAULT_STEP_S);
        let n = (span / h_max).ceil().max(1.0) as usize;
        Some((start, n, span / n as f64))
    }

    /// The reading after the substeps up to `t_s`.
    fn finish(&mut self, t_s: f64) -> f64 {
        // A settled state decays towards zero without reaching it: after ≈ 0.5 s of a
        // constant input the derivative states are subnormal numbers, on which some CPUs
        // (Intel's, not AMD's Zen) take ≈ 100 cycles per operation — the misuse matrix ran 3×
        // slower on a Xeon for it. Far below any reading's resolution, they are zero.
        for x in &mut self.x {
            if x.abs() < FLUSH_BELOW {
                *x = 0.0;
            }
        }
        self.t_s = Some(t_s);
        self.end_input = None;
        self.x[0]
    }

    /// [`Self::read`] for an input that holds `value` over everything the reading integrates
    /// (the caller knows it: a quiet stretch of the scenario, over the last [`RESTART_GAP_S`]
    /// at least) while the filter is settled on it: then every derivative is exactly zero, so
    /// `read` would return the state unchanged, bit for bit, after its substeps — this returns
    /// it without them. `None`: not settled on `value`, or a reading `read` restarts — read it.
    /// Most of a drive is such a stretch (the car at constant speed before the event or the
    /// contact, at rest after the pulse), and the substeps are most of a run's time.
    pub fn read_settled(&mut self, t_s: f64, value: f64) -> Option<f64> {
        if self.omega0 <= 0.0 {
            return Some(value);
        }
        let t0 = self.t_s?;
        if !(t0 <= t_s && t_s - t0 <= RESTART_GAP_S) || self.x != [value, 0.0, 0.0] {
            return None;
        }
        self.t_s = Some(t_s);
        self.end_input = Some((t_s, value));
        Some(self.x[0])
    }
}

/// States smaller than this are set to zero (see [`AntiAlias::read`]): 10⁻¹⁰⁰ m/s² is
/// nothing a sensor reads, and 10²⁰⁰ above the subnormal range.
const FLUSH_BELOW: f64 = 1e-100;

fn add(x: &[f64; 3], k: &[f64; 3], h: f64) -> [f64; 3] {
    [x[0] + h * k[0], x[1] + h * k[1], x[2] + h * k[2]]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Steady-state gain of the filter at `f_hz`, read at `rate_hz` with substeps of a
    /// twentieth of the period.
    fn gain(corner_hz: f64, f_hz: f64, rate_hz: f64) -> f64 {
        let mut lp = AntiAlias::new(corner_hz);
        let w = 2.0 * std::f64::consts::PI * f_hz;
        let mut peak: f64 = 0.0;
        let n = (0.2 * rate_hz) as usize;
        for k in 0..n {
            let t = k as f64 / rate_hz;
            let y = lp.read(t, 0.05 / f_hz, |t| (w * t).sin());
            if k > n / 2 {
                peak = peak.max(y.abs());
            }
        }
        peak
    }

    /// Closed form: |H(jω)| of 15 / (s³ + 6s² + 15s + 15) at the normalised frequency.
    fn closed_form(f_hz: f64, corner_hz: f64) -> f64 {
        let w = 2.0 * std::f64::consts::PI * f_hz * group_delay_s(corner_hz);
        let re = 15.0 - 6.0 * w * w;
        let im = 15.0 * w - w * w * w;
        15.0 / (re * re + im * im).sqrt()
    }

    #[test]
    fn the_filter_is_the_bessel_polynomial_minus_3_db_at_its_corner() {
        assert!((closed_form(400.0, 400.0) - std::f64::consts::FRAC_1_SQRT_2).abs() < 1e-3);
        for f in [50.0, 400.0, 1000.0, 4000.0] {
            let g = gain(400.0, f, 40.0 * f);
            let want = closed_form(f, 400.0);
            assert!(
                (g - want).abs() < 0.01 * want.max(0.01),
                "{f} Hz: {g} vs {want}"
            );
        }
        // Group delay: 0.70 ms at 400 Hz.
        assert!((group_delay_s(400.0) - 0.699e-3).abs() < 2e-6);
    }

    /// Sampled exactly at the crests of a 4 kHz ringing (the aliasing case: an ideal sampler
    /// reads +peak every time), the filtered sensor reads < 1 % of it, as it does at 16 kHz
    /// (a multiple of the sampling rate) and 8 kHz.
    #[test]
    fn ringing_at_multiples_of_the_sampling_rate_does_not_alias() {
        for f in [4000.0, 8000.0, 16000.0] {
            let mut lp = AntiAlias::new(400.0);
            let w = 2.0 * std::f64::consts::PI * f;
            let mut worst: f64 = 0.0;
            for k in 0..800 {
                let t = k as f64 / 4000.0;
                let y = lp.read(t, 0.05 / f, |t| (w * t).cos());
                if k > 40 {
                    worst = worst.max(y.abs());
                }
            }
            assert!(worst < 0.01, "{f} Hz: {worst}");
        }
    }

    /// Settled on a constant input the derivative states decay towards zero; they must reach
    /// it rather than linger as subnormal numbers (≈ 100 cycles an operation on Intel CPUs).
    #[test]
    fn a_settled_filter_holds_no_subnormal_state() {
        for input in [0.0, 9.81, -3.0e-3] {
            let mut lp = AntiAlias::new(400.0);
            lp.read(0.0, DEFAULT_STEP_S, |_| 1.0);
            for k in 1..=3000 {
                lp.read(k as f64 * 1e-3, DEFAULT_STEP_S, |_| input);
                assert!(
                    lp.x.iter().all(|v| *v == 0.0 || v.is_normal()),
                    "input {input}, {k} ms: {:?}",
                    lp.x
                );
            }
        }
    }

    #[test]
    fn no_filter_reads_the_input_and_a_step_settles_without_overshoot_beyond_bessel() {
        let mut none = AntiAlias::new(0.0);
        assert_eq!(none.read(0.3, DEFAULT_STEP_S, |t| t * 2.0), 0.6);
        let mut lp = AntiAlias::new(400.0);
        lp.read(0.0, DEFAULT_STEP_S, |_| 0.0);
        let mut peak: f64 = 0.0;
        for k in 1..200 {
            peak = peak.max(lp.read(k as f64 * 25e-5, DEFAULT_STEP_S, |_| 1.0));
        }
        // A third-order Bessel's step response overshoots 0.75 %.
        assert!(peak > 1.0 && peak < 1.01, "{peak}");
    }

    /// The exact step against the closed form: the Bessel filter's response to a unit ramp
    /// from rest, y(t) = t − 1/ω₀ + …, whose error terms decay: after 40 time constants the
    /// output lags the ramp by exactly the group delay (the DC group delay of H is 1/ω₀).
    /// And against Runge–Kutta at a 100 times finer step through a crash-like pulse: equal to
    /// 10⁻⁹ of the pulse, where Runge–Kutta at the reading's own substeps errs by more.
    #[test]
    fn the_exact_step_lags_a_ramp_by_the_group_delay_and_matches_a_fine_integration() {
        let mut lp = AntiAlias::new(400.0);
        let delay = group_delay_s(400.0);
        lp.read_linear(0.0, DEFAULT_STEP_S, None, |_| 0.0);
        let mut y = 0.0;
        let n = 4 * 28; // 28 ms at 4 kHz: 40 time constants
        for k in 1..=n {
            y = lp.read_linear(k as f64 * 25e-5, DEFAULT_STEP_S, None, |t| t);
        }
        let t = n as f64 * 25e-5;
        assert!((y - (t - delay)).abs() < 1e-12, "{y} vs {}", t - delay);

        // A 20 g trapezoid pulse whose kinks fall on readings (neither method resolves a kink
        // inside a substep), read at 4 kHz.
        let pulse = |t: f64| {
            let ms = t * 1e3;
            196.0
                * ((ms - 3.0) / 12.0)
                    .clamp(0.0, 1.0)
                    .min(((43.0 - ms) / 20.0).clamp(0.0, 1.0))
        };
        let (mut exact, mut fine, mut rk4) = (
            AntiAlias::new(400.0),
            AntiAlias::new(400.0),
            AntiAlias::new(400.0),
        );
        let (mut worst_exact, mut worst_rk4): (f64, f64) = (0.0, 0.0);
        for k in 0..240 {
            let t = k as f64 * 25e-5;
            let e = exact.read_linear(t, DEFAULT_STEP_S, None, pulse);
            let f = fine.read(t, DEFAULT_STEP_S / 100.0, pulse);
            let r = rk4.read(t, DEFAULT_STEP_S, pulse);
            worst_exact = worst_exact.max((e - f).abs());
            worst_rk4 = worst_rk4.max((r - f).abs());
        }
        assert!(worst_exact < 196.0 * 1e-9, "{worst_exact}");
        assert!(worst_rk4 > worst_exact, "{worst_rk4} vs {worst_exact}");
    }

    #[test]
    fn a_settled_filter_on_a_quiet_input_reads_as_the_substeps_would_bit_for_bit() {
        // At rest, a 50 g × 10 ms bump at 0.1 s, at rest again. One filter always substeps;
        // the other skips the substeps whenever the last 20 ms were quiet. They read alike, bit
        // for bit; the skip is taken before the bump and once the states have decayed to 0,
        // never while they have not.
        let bump = |t: f64| {
            if (0.1..0.11).contains(&t) {
                -490.0
            } else {
                0.0
            }
        };
        let (mut slow, mut fast) = (AntiAlias::new(400.0), AntiAlias::new(400.0));
        let (mut skipped_before, mut skipped_after, mut unsettled) = (0, 0, 0);
        for k in 0..1600 {
            let t = k as f64 * 5e-4;
            let a = slow.read(t, DEFAULT_STEP_S, bump);
            let quiet = t < 0.1 || t - RESTART_GAP_S > 0.11;
            let b = match quiet.then(|| fast.read_settled(t, 0.0)).flatten() {
                Some(b) => {
                    if t < 0.1 {
                        skipped_before += 1;
                    } else {
                        skipped_after += 1;
                    }
                    b
                }
                None => {
                    unsettled += usize::from(quiet && k > 0);
                    fast.read(t, DEFAULT_STEP_S, bump)
                }
            };
            assert_eq!(a.to_bits(), b.to_bits(), "{t}: {a} vs {b}");
        }
        assert!(skipped_before >= 190, "{skipped_before}");
        assert!(skipped_after >= 300, "{skipped_after}");
        // Between the bump and the flush the quiet input found the filter unsettled.
        assert!(unsettled > 0);
    }
}
