//! Plan = fire: the earliest instant after contact at which the ECU can fire a cell's airbag.
//!
//! The ECU fires a crash-phase airbag only once the event has carried the airbag's severity
//! floor since its onset (`restraint`'s `fallback_min_dv_mps`: no misuse event carries it). The
//! crush-zone satellites lower that floor while the front end crushes (`restraint::satellites`):
//! the frontal severity — a satellite's velocity change over the last `satellite_window_ms` less
//! the tunnel's — grants a relief fraction r from `satellite_relief_from_mps` (r = 0) to
//! `satellite_relief_full_mps` (r = 1), held at its peak, and the floor comes down by r of the
//! way to `satellite_floor_mps`. A table that planned its airbags on the unrelieved floor would
//! plan them later than the ECU can fire them, and the ECU fires on the plan.
//!
//! **The satellites' signal here** is the one the bench's world gives them
//! (`physics::crush_zone`, from the cell's own ego crush): a full-width frontal crash, so both
//! satellites read the same and the smaller of the two is either. Their frames reach the ECU
//! one PSI5 slot later than the tunnel's samples ([`SatelliteRelief::lag_s`]); both pass the
//! same 400 Hz anti-alias filter, whose group delay is in [`super::optimise::OptimiserConfig`]'s
//! `ecu_latency_s`. So the floor the tunnel's sample at `t` is judged against is the one the
//! satellites' crush up to `t − lag_s` grants.
//!
//! **The accelerometer-only wait.** One object fault must not move a crash over the no-fire
//! line, so below a closing speed (`restraint::CycleConfig::unguarded_closing_mps`, ≈ 83 km/h)
//! a matched airbag fires no earlier than the accelerometer-only algorithm decides must-fire
//! for the event — its boundary, floor, persistence and loading, with the same relief
//! ([`accel_only_fire_s`]: the core's own `FallbackAlgorithm` on the cell's pulse). The
//! satellites cannot lift that wait: they measure how fast the front end crushes, which a light
//! opponent at a high closing speed shares with a must-fire crash.

use physics::CompartmentPulse;

/// The satellites' relief of the airbag's floor as the ECU grants it (see module docs).
/// `floor_mps` ≤ 0 or NaN turns it off (a car without satellites, tables built before them).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SatelliteRelief {
    /// The floor the whole relief brings the airbag's down to [m/s].
    pub floor_mps: f64,
    /// Frontal severity where the relief begins [m/s].
    pub from_mps: f64,
    /// Frontal severity of the whole relief [m/s].
    pub full_mps: f64,
    /// The crush Δv window [s].
    pub window_s: f64,
    /// How much later the satellites' frames arrive than the tunnel's samples [s].
    pub lag_s: f64,
    /// Where the satellites sit behind the fascia [m].
    pub depth_m: f64,
    /// The factor the whole relief scales the accelerometer-only boundary by.
    pub boundary_scale: f64,
}

impl SatelliteRelief {
    /// No relief: the tunnel's floor alone.
    pub const OFF: Self = Self {
        floor_mps: 0.0,
        from_mps: 0.0,
        full_mps: 0.0,
        window_s: 0.0,
        lag_s: 0.0,
        depth_m: 0.0,
        boundary_scale: 1.0,
    };

    /// The ECU's relief (`restraint::CycleConfig`'s `satellite_*` *defaults*) on the bench's
    /// *default* satellites: at the rail tips (`physics::crush_zone::DEFAULT_DEPTH_M`), one
    /// 500 µs PSI5 slot of transport latency.
    pub fn ecu_default() -> Self {
        let c = restraint::CycleConfig::default();
        if !c.satellites {
            return Self::OFF;
        }
        Self {
            floor_mps: c.satellite_floor_mps,
            from_mps: c.satellite_relief_from_mps,
            full_mps: c.satellite_relief_full_mps,
            window_s: c.satellite_window_ms * 1e-3,
            lag_s: DEFAULT_SLOT_S,
            depth_m: physics::crush_zone::DEFAULT_DEPTH_M,
            boundary_scale: c.satellite_boundary_scale,
        }
    }

    /// Whether the relief is on.
    pub fn is_on(&self) -> bool {
        self.floor_mps > 0.0
            && self.window_s > 0.0
            && self.depth_m > 0.0
            && self.full_mps >= self.from_mps
    }

    /// The relief fraction the satellites' crush grants at each sample of `crush_m` (samples
    /// `step_s` apart from contact): the severity's peak so far, mapped onto [0, 1].
    fn fractions(&self, crush_m: &[f64], step_s: f64) -> Vec<f64> {
        if !(self.is_on() && step_s > 0.0) {
            return vec![0.0; crush_m.len()];
        }
        let rel = physics::crush_zone::relative_accel_mps2(crush_m, step_s, self.depth_m);
        // Crush Δv over the window ending at each sample: a running sum of the trapezoids.
        let n_window = ((self.window_s / step_s).round() as usize).max(1);
        let mut lost = vec![0.0; rel.len()];
        let mut acc = 0.0;
        for k in 1..rel.len() {
            acc -= 0.5 * (rel[k - 1] + rel[k]) * step_s;
            lost[k] = acc;
        }
        let span = self.full_mps - self.from_mps;
        let mut peak: f64 = 0.0;
        (0..rel.len())
            .map(|k| {
                let severity = lost[k] - lost[k.saturating_sub(n_window)];
                if severity >= self.from_mps {
                    let r = if span > 0.0 {
                        (severity - self.from_mps) / span
                    } else {
                        1.0
                    };
                    peak = peak.max(r.clamp(0.0, 1.0));
                }
                peak
            })
            .collect()
    }
}

impl SatelliteRelief {
    /// The satellites' lag in pulse samples of `step_s`.
    fn lag_samples(&self, step_s: f64) -> usize {
        (self.lag_s.max(0.0) / step_s.max(f64::MIN_POSITIVE)).ceil() as usize
    }
}

/// The accelerometer's sampling period the accelerometer-only decision is judged at [s]: the
/// bench's crash accelerometer (4 kHz).
pub const ACCEL_PERIOD_S: f64 = 0.25e-3;

/// Quiet samples before the contact, so the detectors start settled [s].
const LEAD_S: f64 = 0.02;

/// When the ECU's accelerometer-only algorithm (`restraint::fallback::FallbackAlgorithm` with
/// `cycle`'s boundary and airbag floor) decides must-fire on `pulse` [s after contact], the
/// floor and boundary relieved as the satellites relieve them on the ego's crush `crush_m`
/// (no road roughness, no noise, 4 kHz samples); `f64::INFINITY` when it never does.
pub fn accel_only_fire_s(
    pulse: &CompartmentPulse<'_>,
    crush_m: &[f64],
    relief: &SatelliteRelief,
    cycle: &restraint::CycleConfig,
) -> f64 {
    use restraint::accel::AccelSample;
    use restraint::fallback::{FallbackAlgorithm, FallbackDecision};
    use restraint::satellites::Relief;
    let step_s = pulse.step_s;
    if step_s.is_nan() || step_s <= 0.0 || pulse.accel_mps2.is_empty() {
        return f64::INFINITY;
    }
    let fractions = relief.fractions(crush_m, step_s);
    let lag = relief.lag_samples(step_s);
    let p = cycle.confirm_params();
    let mut algo = FallbackAlgorithm::new(cycle.fallback_dv_mps, cycle.fallback_floor());
    let end_s = LEAD_S + pulse.accel_mps2.len() as f64 * step_s;
    let n = (end_s / ACCEL_PERIOD_S) as usize;
    for k in 0..n {
        let t_s = k as f64 * ACCEL_PERIOD_S;
        let tau_s = t_s - LEAD_S;
        // The pulse between its 0.1 ms points, linearly; 0 before the contact.
        let (decel_mps2, i) = if tau_s < 0.0 {
            (0.0, None)
        } else {
            let x = tau_s / step_s;
            let i = x as usize;
            let a = pulse.accel_mps2.get(i).copied().unwrap_or(0.0);
            let b = pulse.accel_mps2.get(i + 1).copied().unwrap_or(a);
            (-(a + (b - a) * (x - i as f64)), Some(i))
        };
        let fraction = i
            .and_then(|i| i.checked_sub(lag))
            .and_then(|j| fractions.get(j))
            .copied()
            .unwrap_or(0.0);
        let now = algo.thresholds_now(
            0.0,
            Relief {
                fraction,
                floor_mps: relief.floor_mps,
                boundary_scale: relief.boundary_scale,
                // A car without satellites below the unguarded closing speed: no lift; a
                // crash without a tracked prediction: no fold's scale.
                ..Relief::NONE
            },
        );
        let s = AccelSample {
            t_ns: (t_s * 1e9).round() as u64,
            dt_s: ACCEL_PERIOD_S,
            decel_mps2,
        };
        algo.push(&p, &s, &now);
        if let FallbackDecision::Fire { at_ns, .. } = algo.decision() {
            return at_ns as f64 * 1e-9 - LEAD_S;
        }
    }
    f64::INFINITY
}

/// One 2 kHz PSI5 synchronous slot [s]: the satellites' frames arrive this much later than
/// the tunnel's samples (`sensor-feeds` plays them one slot late).
pub const DEFAULT_SLOT_S: f64 = 0.5e-3;

/// The earliest airbag time the ECU can execute on `pulse` [s after contact]: the first
/// instant its velocity change reaches the airbag's floor `floor_dv_mps` — as the satellites
/// relieve it on the ego's crush `crush_m` (same sampling as the pulse) — plus `latency_s`.
/// `f64::INFINITY` when the pulse never carries it, 0 when the floor is off (≤ 0 or NaN).
pub fn earliest_airbag_s(
    pulse: &CompartmentPulse<'_>,
    crush_m: &[f64],
    floor_dv_mps: f64,
    relief: &SatelliteRelief,
    latency_s: f64,
) -> f64 {
    if floor_dv_mps.is_nan() || floor_dv_mps <= 0.0 {
        return 0.0;
    }
    let step_s = pulse.step_s;
    let fractions = relief.fractions(crush_m, step_s);
    let lag = relief.lag_samples(step_s);
    // The relief never raises a floor (`restraint::satellites::Relief::floor_mps`).
    let target = relief.floor_mps.min(floor_dv_mps);
    let mut dv_mps = 0.0;
    let mut prev = 0.0;
    for (i, &a) in pulse.accel_mps2.iter().enumerate() {
        // Deceleration is negative acceleration; trapezoidal rule.
        dv_mps -= 0.5 * (prev + a) * step_s;
        prev = a;
        let r = i
            .checked_sub(lag)
            .and_then(|k| fractions.get(k))
            .copied()
            .unwrap_or(0.0);
        if dv_mps >= floor_dv_mps - r * (floor_dv_mps - target) {
            return i as f64 * step_s + latency_s;
        }
    }
    f64::INFINITY
}

#[cfg(test)]
mod tests {
    use super::*;

    fn relief() -> SatelliteRelief {
        SatelliteRelief {
            floor_mps: 0.5,
            from_mps: 1.0,
            full_mps: 2.0,
            window_s: 4e-3,
            lag_s: 0.5e-3,
            depth_m: 0.2,
            boundary_scale: 1.0,
        }
    }

    /// A constant body deceleration `a` and a constant crush rate `v`: closed forms.
    /// The body's Δv is a·t; the satellites' crush Δv over the window W is v²·min(t, W)/(ε·L)
    /// while the folds have not reached them (t < ε·L/v), so the full relief comes at
    /// t₁ = 2·ε·L/v² (for 2 m/s, when t₁ < W) and the floor is 0.5 m/s from t₁ + lag on.
    #[test]
    fn the_floor_comes_down_when_the_closed_form_crush_says_so() {
        let (step, a, v) = (1e-4, 200.0, 15.0);
        let n = 300;
        let accel: Vec<f64> = (0..n).map(|k| if k == 0 { 0.0 } else { -a }).collect();
        let crush: Vec<f64> = (0..n).map(|k| v * k as f64 * step).collect();
        let pulse = CompartmentPulse {
            accel_mps2: &accel,
            step_s: step,
        };
        let fold = physics::crush_zone::COMPACTED_STRAIN * 0.2;
        let t_full = 2.0 * fold / (v * v);
        // Without relief: 1.25 m/s at a = 200 → 6.25 ms.
        let off = earliest_airbag_s(&pulse, &crush, 1.25, &SatelliteRelief::OFF, 0.0);
        assert!((off - 1.25 / a).abs() < 2.0 * step, "{off}");
        // With it: the whole relief is granted at t_full + lag (1.74 ms), before the body
        // carries 0.5 m/s (2.5 ms), so the relieved floor of 0.5 m/s binds.
        let on = earliest_airbag_s(&pulse, &crush, 1.25, &relief(), 0.0);
        assert!(t_full + 0.5e-3 < 0.5 / a, "test premise");
        assert!((on - 0.5 / a).abs() < 2.0 * step, "{on}");
        // The latency is added as it is.
        let late = earliest_airbag_s(&pulse, &crush, 1.25, &relief(), 1.7e-3);
        assert!((late - on - 1.7e-3).abs() < 1e-12);
    }

    /// A crush too slow to reach the relief's lower line changes nothing; a floor already
    /// below the relief's is never raised; a floor that is off gives 0.
    #[test]
    fn no_crush_no_relief_and_the_floor_is_never_raised() {
        let (step, a) = (1e-4, 100.0);
        let accel: Vec<f64> = (0..400).map(|k| if k == 0 { 0.0 } else { -a }).collect();
        let slow: Vec<f64> = (0..400).map(|k| 2.0 * k as f64 * step).collect();
        let pulse = CompartmentPulse {
            accel_mps2: &accel,
            step_s: step,
        };
        let t = earliest_airbag_s(&pulse, &slow, 1.25, &relief(), 0.0);
        assert!((t - 1.25 / a).abs() < 2.0 * step, "{t}");
        let t = earliest_airbag_s(&pulse, &slow, 0.3, &relief(), 0.0);
        assert!((t - 0.3 / a).abs() < 2.0 * step, "{t}");
        assert_eq!(earliest_airbag_s(&pulse, &slow, 0.0, &relief(), 1e-3), 0.0);
        assert_eq!(
            earliest_airbag_s(&pulse, &slow, f64::NAN, &relief(), 1e-3),
            0.0
        );
        let never = earliest_airbag_s(&pulse, &slow, 100.0, &relief(), 0.0);
        assert!(never.is_infinite());
    }

    /// Half the relief: a severity that peaks at 1.5 m/s brings the floor halfway.
    #[test]
    fn a_partial_severity_brings_the_floor_part_of_the_way() {
        let step = 1e-4;
        let fold = physics::crush_zone::COMPACTED_STRAIN * 0.2;
        // Crush rate v with v² · W / (ε·L) = 1.5 m/s over the 4 ms window, folds later.
        let v = (1.5 * fold / 4e-3_f64).sqrt();
        assert!(
            fold / v > 4e-3,
            "test premise: the folds have not reached the sensor"
        );
        let n = 800;
        let crush: Vec<f64> = (0..n).map(|k| v * k as f64 * step).collect();
        let fr = relief().fractions(&crush, step);
        let at_window = fr[45];
        assert!((at_window - 0.5).abs() < 0.03, "{at_window}");
    }

    /// The core's accelerometer-only algorithm on a constant 20 g pulse: never before the
    /// pulse carries the airbag's floor (1.25 m/s at 6.4 ms unrelieved, 0.5 m/s at 2.6 ms with
    /// the whole relief), earlier with the relief than without; a 2 g pulse never decides.
    #[test]
    fn the_accel_only_decision_waits_for_its_floor_and_comes_earlier_with_the_relief() {
        let (step, a) = (1e-4, 20.0 * 9.806_65);
        let n = 600;
        let accel: Vec<f64> = (0..n).map(|k| if k == 0 { 0.0 } else { -a }).collect();
        let crush: Vec<f64> = (0..n).map(|k| 15.0 * k as f64 * step).collect();
        let pulse = CompartmentPulse {
            accel_mps2: &accel,
            step_s: step,
        };
        let cycle = restraint::CycleConfig::default();
        let off = accel_only_fire_s(&pulse, &crush, &SatelliteRelief::OFF, &cycle);
        let on = accel_only_fire_s(&pulse, &crush, &relief(), &cycle);
        let floor_off_s = cycle.fallback_min_dv_mps / a;
        assert!(
            off.is_finite() && off >= floor_off_s - ACCEL_PERIOD_S,
            "{off}"
        );
        assert!(on >= 0.5 / a - ACCEL_PERIOD_S && on <= off, "{on} vs {off}");
        let weak: Vec<f64> = (0..n).map(|_| -2.0 * 9.806_65).collect();
        let weak = CompartmentPulse {
            accel_mps2: &weak,
            step_s: step,
        };
        assert!(accel_only_fire_s(&weak, &crush, &relief(), &cycle).is_infinite());
    }
}
