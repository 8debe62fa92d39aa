//! Crash confirmation from the compartment accelerometer. Pure, allocation-free, NaN-safe.

/// Standard gravity, m/s² (same constant as the physics crate).
pub const G_MPS2: f64 = physics::defaults::STANDARD_GRAVITY_MPS2;

/// Crash-confirmation settings in the detector's units.
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

/// Longest sample period the integrator accepts, ns (10 ms: slower than any crash sensor).
const MAX_SAMPLE_PERIOD_NS: u32 = 10_000_000;

/// Crash confirmation from the compartment accelerometer: deceleration over a threshold for
/// N consecutive samples AND Δv integrated since wake-up over a threshold. Both are needed: the
/// persistence rejects spikes, the Δv rejects short high-g events (door slam, pothole) that
/// carry no velocity change.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct CrashDetector {
    awake: bool,
    onset_ns: u64,
    last_wake_ns: u64,
    run: u32,
    delta_v_mps: f64,
    confirmed_at_ns: Option<u64>,
    /// Non-finite samples skipped so far.
    pub invalid_samples: u64,
    /// Batches with an unusable sample period.
    pub invalid_batches: u64,
}

impl CrashDetector {
    /// Feeds one batch (`first_ns`, `period_ns`, samples in m/s², negative = deceleration).
    /// Returns true if this batch contained invalid data.
    pub fn feed(
        &mut self,
        p: &ConfirmParams,
        first_ns: u64,
        period_ns: u32,
        samples: &[f32],
    ) -> bool {
        if period_ns == 0 || period_ns > MAX_SAMPLE_PERIOD_NS {
            self.invalid_batches = self.invalid_batches.saturating_add(1);
            return true;
        }
        let dt_s = f64::from(period_ns) * 1.0e-9;
        let mut invalid = false;
        let mut t = first_ns;
        for &a in samples {
            let now = t;
            t = t.saturating_add(u64::from(period_ns));
            if !a.is_finite() {
                self.invalid_samples = self.invalid_samples.saturating_add(1);
                invalid = true;
                continue;
            }
            if self.confirmed_at_ns.is_some() {
                continue; // latched
            }
            let decel = -f64::from(a);
            if decel >= p.wake_mps2 {
                if !self.awake {
                    self.awake = true;
                    self.onset_ns = now;
                    self.delta_v_mps = 0.0;
                    self.run = 0;
                }
                self.last_wake_ns = now;
            } else if self.awake && now.saturating_sub(self.last_wake_ns) > p.reset_gap_ns {
                *self = Self {
                    invalid_samples: self.invalid_samples,
                    invalid_batches: self.invalid_batches,
                    ..Self::default()
                };
                continue;
            }
            if !self.awake {
                continue;
            }
            self.delta_v_mps += decel * dt_s;
            self.run = if decel >= p.decel_mps2 {
                self.run.saturating_add(1)
            } else {
                0
            };
            if self.run >= p.samples && self.delta_v_mps >= p.delta_v_mps {
                self.confirmed_at_ns = Some(now);
            }
        }
        invalid
    }

    /// Time of confirmation, if confirmed (latched).
    pub fn confirmed_at_ns(&self) -> Option<u64> {
        self.confirmed_at_ns
    }

    /// Measured contact instant (first sample over the wake threshold of the confirmed event,
    /// or of the event in progress).
    pub fn onset_ns(&self) -> Option<u64> {
        self.awake.then_some(self.onset_ns)
    }

    /// Δv integrated since wake-up, m/s.
    pub fn delta_v_mps(&self) -> f64 {
        self.delta_v_mps
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params() -> ConfirmParams {
        ConfirmParams {
            wake_mps2: 1.5 * G_MPS2,
            decel_mps2: 4.0 * G_MPS2,
            samples: 3,
            delta_v_mps: 0.5,
            reset_gap_ns: 10_000_000,
        }
    }

    #[test]
    fn confirms_a_constant_10g_pulse_when_delta_v_reaches_threshold() {
        // 10 g at 1 kHz: Δv after n samples = n · 98.0665 · 1e-3 → ≥ 0.5 at n = 6.
        let mut d = CrashDetector::default();
        let s = [-10.0 * G_MPS2 as f32; 8];
        d.feed(&params(), 1_000_000, 1_000_000, &s);
        assert_eq!(d.onset_ns(), Some(1_000_000));
        assert_eq!(d.confirmed_at_ns(), Some(1_000_000 + 5 * 1_000_000));
    }

    #[test]
    fn a_short_spike_or_a_braking_manoeuvre_never_confirms() {
        let mut d = CrashDetector::default();
        // 30 g for 2 samples then nothing: persistence fails.
        d.feed(
            &params(),
            0,
            1_000_000,
            &[-300.0, -300.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        );
        // 1.2 g braking for a long time: below the wake threshold.
        for k in 0..100u64 {
            d.feed(
                &params(),
                20_000_000 + k * 8_000_000,
                1_000_000,
                &[-11.8; 8],
            );
        }
        assert_eq!(d.confirmed_at_ns(), None);
        // NaN samples are skipped and counted.
        assert!(d.feed(&params(), 0, 1_000_000, &[f32::NAN]));
        assert_eq!(d.invalid_samples, 1);
    }
}
