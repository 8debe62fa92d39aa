//! The true world of a scenario: closed-form pre-crash kinematics and, from the true first
//! contact on, the true collision physics (`physics::simulate_collision` with the TRUE masses
//! and stiffness classes). The sensor model only ever *observes* this.
//!
//! Axes: each vehicle's own forward direction (towards the other party); speeds ≥ 0 before
//! contact (braking stops a vehicle, it never reverses). The gap between the fronts is
//! `initial_distance − s_ego(t) − s_opp(t)` and therefore never increases before contact,
//! which makes the contact instant a clean bisection root.

use crate::scenario::{Braking, FrontSide, Scenario};
use physics::crash_mode::{CrashMode, RAIL_INBOARD_FRACTION};
use physics::{CollisionInput, CollisionSummary, CombinedSpring, DefaultPulseBuffer};

/// The crush of the front at the rail tip on `side`, from the ego's crush along x (its
/// deepest, at the struck side or the centre): what the satellite there folds with.
///
/// * full width: the same at both tips;
/// * offset: the tips inside the overlap as the struck part; a tip outside it is not reached
///   (the structure beside the overlap shears, it does not fold back);
/// * angled wall: a tip `y` in from the struck corner once the wall has advanced `y·tan θ`;
/// * pole: the tips lie beside the pole, the beam wraps round it and pulls them back only when
///   the engine is reached (`POLE_GAP_M`): late and weak;
/// * underride: the tips pass under the bed: never.
pub fn satellite_crush_m(scenario: &Scenario, side: FrontSide, crush_m: &[f64]) -> Vec<f64> {
    let struck = scenario.opponent.struck_side.unwrap_or_default() == side;
    // Lateral position of this side's rail tip from the struck edge, as a share of the width.
    let y = if struck {
        RAIL_INBOARD_FRACTION
    } else {
        1.0 - RAIL_INBOARD_FRACTION
    };
    let shifted = |gap: f64| crush_m.iter().map(|c| (c - gap).max(0.0)).collect();
    match scenario.crash_mode() {
        CrashMode::FullFrontal => crush_m.to_vec(),
        CrashMode::Offset { overlap } if overlap >= y => crush_m.to_vec(),
        CrashMode::Offset { .. } | CrashMode::Underride => vec![0.0; crush_m.len()],
        CrashMode::Angular { angle_rad } => shifted(y * scenario.ego.width_m * angle_rad.tan()),
        CrashMode::Pole => shifted(physics::crash_mode::POLE_GAP_M),
    }
}

/// Speed [m/s], travelled distance [m] and acceleration [m/s², negative = braking] of one
/// braking vehicle at time `t_s`, in closed form.
///
/// Deceleration ramps linearly 0 → A over r, then stays A until standstill:
/// ramp (τ = t − t_b ≤ r): v = v0 − A τ²/(2r), s = v0 τ − A τ³/(6r);
/// plateau: v = v_r − A (τ − r), s = s_r + v_r (τ − r) − A (τ − r)²/2.
pub fn braking_motion(v0_mps: f64, braking: Option<&Braking>, t_s: f64) -> (f64, f64, f64) {
    let Some(b) = braking else {
        return (v0_mps, v0_mps * t_s, 0.0);
    };
    if t_s <= b.start_s {
        return (v0_mps, v0_mps * t_s, 0.0);
    }
    let s0 = v0_mps * b.start_s;
    let a = b.decel_mps2;
    let r = b.ramp_s;
    let tau = t_s - b.start_s;
    // Standstill inside the ramp? v(τ) = 0 at τ = sqrt(2 r v0 / A).
    let v_r = v0_mps - 0.5 * a * r;
    if v_r <= 0.0 {
        let tau_stop = (2.0 * r * v0_mps / a).sqrt();
        let tt = tau.min(tau_stop);
        let v = v0_mps - a * tt * tt / (2.0 * r);
        let s = v0_mps * tt - a * tt * tt * tt / (6.0 * r);
        let acc = if tau < tau_stop { -a * tau / r } else { 0.0 };
        return (v.max(0.0), s0 + s, acc);
    }
    if tau <= r {
        let v = v0_mps - a * tau * tau / (2.0 * r);
        let s = v0_mps * tau - a * tau * tau * tau / (6.0 * r);
        let acc = if r > 0.0 { -a * tau / r } else { -a };
        return (v, s0 + s, acc);
    }
    let s_r = v0_mps * r - a * r * r / 6.0;
    let tau_stop = v_r / a;
    let tp = (tau - r).min(tau_stop);
    let v = v_r - a * tp;
    let s = s_r + v_r * tp - 0.5 * a * tp * tp;
    let acc = if tau - r < tau_stop { -a } else { 0.0 };
    (v.max(0.0), s0 + s, acc)
}

/// The state the sensors observe at one instant (serialized field by field into a run's
/// recording, topic `/truth/world`).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct WorldState {
    /// Gap between the fronts [m] (0 while in contact).
    pub distance_m: f64,
    /// Closing speed [m/s] (positive = approaching; negative after separation).
    pub closing_speed_mps: f64,
    /// Rate of change of the closing speed [m/s²].
    pub relative_accel_mps2: f64,
    /// Ego speed over ground [m/s] (may be negative after a crash with a heavier opponent).
    pub ego_speed_mps: f64,
    /// Ego compartment longitudinal acceleration [m/s²] (negative = deceleration).
    pub ego_accel_mps2: f64,
    /// Ego is braking.
    pub ego_braking: bool,
    /// The opponent is in the ego's path (false after an evasive manoeuvre).
    pub in_path: bool,
}

/// The true world: kinematics, contact and crash pulse.
pub struct Truth {
    scenario: Scenario,
    /// True first contact [s after scenario start], `None` if the collision is avoided or
    /// happens after the run ends.
    pub contact_s: Option<f64>,
    /// Ego speed at contact [m/s].
    pub ego_speed_at_contact_mps: f64,
    /// Opponent speed at contact [m/s].
    pub opp_speed_at_contact_mps: f64,
    /// True collision summary (contact only).
    pub collision: Option<CollisionSummary>,
    /// True compartment pulses from first contact (0.1 ms steps).
    pub pulse: Box<DefaultPulseBuffer>,
    /// Each crush-zone satellite's acceleration relative to the body (left, right), on the
    /// pulse's grid ([`physics::crush_zone`]; empty without contact).
    satellite_rel_mps2: [Vec<f64>; 2],
    /// From this long after the contact the pulse's body and satellite channels are exactly
    /// 0 (separated, or the buffer's end) [s]; [`Self::at_rest_over`] reads it.
    pulse_rest_s: f64,
}

impl Truth {
    /// Solves the scenario: contact instant (bisection to 1 µs) and the true crash.
    pub fn new(scenario: &Scenario) -> Result<Self, String> {
        let mut truth = Truth {
            scenario: scenario.clone(),
            contact_s: None,
            ego_speed_at_contact_mps: 0.0,
            opp_speed_at_contact_mps: 0.0,
            collision: None,
            pulse: Box::new(DefaultPulseBuffer::new()),
            satellite_rel_mps2: [Vec::new(), Vec::new()],
            pulse_rest_s: 0.0,
        };
        // After an evasive manoeuvre the opponent is out of the path: no contact afterwards.
        let end = scenario
            .opponent
            .evade_s
            .map_or(scenario.duration_s, |te| te.min(scenario.duration_s));
        if truth.pre_contact_gap_m(end) > 0.0 {
            return Ok(truth);
        }
        let (mut lo, mut hi) = (0.0, end);
        while hi - lo > 1e-6 {
            let mid = 0.5 * (lo + hi);
            if truth.pre_contact_gap_m(mid) > 0.0 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let tc = hi;
        let (ve, _, _) = truth.ego_motion(tc);
        let (vo, _, _) = truth.opp_motion(tc);
        let closing = ve + vo;
        truth.contact_s = Some(tc);
        truth.ego_speed_at_contact_mps = ve;
        truth.opp_speed_at_contact_mps = vo;
        let summary = match &scenario.pulse {
            Some(p) => physics::measured::measured_collision(
                &p.accel_mps2,
                physics::defaults::STEP_S,
                closing,
                scenario.ego.mass_kg,
                &mut truth.pulse,
            )
            .map_err(|e| format!("measured pulse: {e}"))?,
            None => truth.modelled_collision(closing)?,
        };
        truth.collision = Some(summary);
        for side in [FrontSide::Left, FrontSide::Right] {
            let crush = satellite_crush_m(scenario, side, truth.pulse.ego_crush_m());
            truth.satellite_rel_mps2[side as usize] = physics::crush_zone::relative_accel_mps2(
                &crush,
                truth.pulse.step_s(),
                scenario.sensor.satellite_depth_m,
            );
        }
        // The last non-zero sample of any channel, and one more grid step, so that every
        // interpolation from there on reads two zeros whatever the rounding of t / step.
        let last = |ch: &[f64]| ch.iter().rposition(|a| *a != 0.0);
        let [left, right] = &truth.satellite_rel_mps2;
        let last_moving = [truth.pulse.ego_accel_mps2(), left, right]
            .into_iter()
            .filter_map(last)
            .max();
        let step = truth.pulse.step_s();
        let buffer_s = truth.pulse.len() as f64 * step;
        truth.pulse_rest_s = last_moving.map_or(0.0, |i| ((i + 2) as f64 * step).min(buffer_s));
        Ok(truth)
    }

    /// The two-mass model's crash at `closing` m/s (the crash mode's engaged curve in series
    /// with the opponent's face), its pulse written into `self.pulse`.
    fn modelled_collision(&mut self, closing: f64) -> Result<CollisionSummary, String> {
        let mode = self.scenario.crash_mode();
        let engaged = mode
            .engage(self.scenario.ego_class().curve(), self.scenario.ego.width_m)
            .map_err(|e| format!("crash mode: {e:?}"))?;
        let face = self
            .scenario
            .opponent_face()
            .map_err(|e| format!("opponent face: {e:?}"))?;
        let spring =
            CombinedSpring::series(&engaged.curve, face.as_ref()).map_err(|e| format!("{e:?}"))?;
        let mut input = CollisionInput::with_defaults(
            &spring,
            self.scenario.ego.mass_kg,
            self.scenario.opponent_mass_kg(),
            // Along the collision's normal: an angled wall arrests only that share.
            closing * engaged.axis_cos,
        );
        if mode != CrashMode::FullFrontal {
            // The partial modes' soft stages last longer than the full frontal's 150 ms: the
            // whole buffer, so the pulse ends with the contact.
            input.duration_s = (self.pulse.capacity() - 1) as f64 * input.step_s;
        }
        let mut summary = physics::simulate_collision(&input, &mut self.pulse)
            .map_err(|e| format!("true collision physics: {e:?}"))?;
        self.pulse.project_ego_onto_axis(engaged.axis_cos);
        let c = engaged.axis_cos;
        summary.vehicle.a_max_mps2 *= c;
        summary.vehicle.a_mean_mps2 *= c;
        summary.vehicle.delta_v_mps *= c;
        summary.vehicle.crush_m /= c;
        Ok(summary)
    }

    /// The scenario this truth was solved for.
    pub fn scenario(&self) -> &Scenario {
        &self.scenario
    }

    fn ego_motion(&self, t: f64) -> (f64, f64, f64) {
        let e = &self.scenario.ego;
        braking_motion(physics::kph_to_mps(e.speed_kph), e.braking.as_ref(), t)
    }

    fn opp_motion(&self, t: f64) -> (f64, f64, f64) {
        let o = &self.scenario.opponent;
        if o.kind.is_fixed() {
            (0.0, 0.0, 0.0)
        } else {
            braking_motion(physics::kph_to_mps(o.speed_kph), o.braking.as_ref(), t)
        }
    }

    /// Gap between the fronts if nothing had collided [m].
    fn pre_contact_gap_m(&self, t: f64) -> f64 {
        let (_, se, _) = self.ego_motion(t);
        let (_, so, _) = self.opp_motion(t);
        self.scenario.opponent.initial_distance_m - se - so
    }

    /// True closing speed at contact [m/s] (0 without contact).
    pub fn closing_speed_at_contact_mps(&self) -> f64 {
        if self.contact_s.is_some() {
            self.ego_speed_at_contact_mps + self.opp_speed_at_contact_mps
        } else {
            0.0
        }
    }

    /// The airbag's required fire time, "127 mm − 30 ms" of the true ego pulse, ms after
    /// contact (`physics::deadline`; `None` without contact, or when the pulse never moves a
    /// free occupant 127 mm): what every judge of fire time measures against.
    pub fn required_fire_ms(&self) -> Option<f64> {
        self.contact_s?;
        physics::deadline::required_fire_s(&self.pulse.ego_pulse()).map(|s| s * 1e3)
    }

    /// Ego compartment acceleration at `k`-th pulse position (linear interpolation of the
    /// 0.1 ms pulse; 0 after the pulse).
    fn pulse_at(&self, channel: &[f64], t_since_contact_s: f64) -> f64 {
        let step = self.pulse.step_s();
        if !(step > 0.0) || channel.is_empty() {
            return 0.0;
        }
        let x = t_since_contact_s / step;
        // The floor's index without a libm call: `as` truncates towards 0 and saturates, so
        // every x < 1 (a negative one, NaN) gives 0 as `x.floor() as usize` does.
        let i = x as usize;
        match (channel.get(i), channel.get(i + 1)) {
            (Some(a), Some(b)) => a + (b - a) * (x - i as f64),
            (Some(a), None) => *a,
            _ => *channel.last().unwrap_or(&0.0),
        }
    }

    /// The true world at scenario time `t_s`.
    pub fn state(&self, t_s: f64) -> WorldState {
        match self.contact_s {
            Some(tc) if t_s >= tc => self.crash_state(t_s - tc),
            _ => {
                let (ve, _, ae) = self.ego_motion(t_s);
                let (vo, _, ao) = self.opp_motion(t_s);
                WorldState {
                    distance_m: self.pre_contact_gap_m(t_s).max(0.0),
                    closing_speed_mps: ve + vo,
                    relative_accel_mps2: ae + ao,
                    ego_speed_mps: ve,
                    ego_accel_mps2: ae,
                    ego_braking: ae < 0.0,
                    in_path: self.scenario.opponent.evade_s.is_none_or(|te| t_s < te),
                }
            }
        }
    }

    /// The ego compartment's true acceleration at `t_s` [m/s²] (= `state(t_s).ego_accel_mps2`,
    /// without the rest of the state: the accelerometers' filter reads it on substeps).
    pub fn ego_accel_mps2(&self, t_s: f64) -> f64 {
        match self.contact_s {
            // After the pulse's end nothing pushes the car: a contact that outlasts the buffer
            // (a slow underride) ends with it.
            Some(tc) if t_s - tc >= self.pulse.len() as f64 * self.pulse.step_s() => 0.0,
            Some(tc) if t_s >= tc => self.pulse_at(self.pulse.ego_accel_mps2(), t_s - tc),
            _ => self.ego_motion(t_s).2,
        }
    }

    /// Whether the ego body and both crush-zone satellites feel exactly no acceleration all
    /// over `[t0_s, t1_s]` ([`Self::ego_accel_mps2`] and [`Self::satellite_accel_mps2`]
    /// return 0 at every instant there): before the contact and before any braking begins,
    /// or after the pulse has come to rest. `false` where it cannot say so cheaply (braking,
    /// the pulse). A braking plateau is steady too, but a filter never settles on it exactly,
    /// so there is nothing to gain from saying so.
    pub fn at_rest_over(&self, t0_s: f64, t1_s: f64) -> bool {
        match self.contact_s {
            Some(tc) if t0_s - tc >= self.pulse_rest_s => true,
            Some(tc) if t1_s >= tc => false,
            _ => self
                .scenario
                .ego
                .braking
                .as_ref()
                .is_none_or(|b| t1_s <= b.start_s),
        }
    }

    /// What the crush-zone satellite on `side` feels at `t_s` [m/s²]: the body's acceleration
    /// and, from contact, the crush of the structure ahead of it ([`physics::crush_zone`]) as
    /// far as the crash mode reaches its rail tip ([`satellite_crush_m`]).
    pub fn satellite_accel_mps2(&self, side: FrontSide, t_s: f64) -> f64 {
        let body = self.ego_accel_mps2(t_s);
        match self.contact_s {
            Some(tc) if t_s >= tc && t_s - tc < self.pulse.len() as f64 * self.pulse.step_s() => {
                body + self.pulse_at(&self.satellite_rel_mps2[side as usize], t_s - tc)
            }
            _ => body,
        }
    }

    fn crash_state(&self, dt: f64) -> WorldState {
        let p = &self.pulse;
        let dve = self.pulse_at(p.ego_vel_mps(), dt);
        let dvo = self.pulse_at(p.opp_vel_mps(), dt);
        let ae = self.pulse_at(p.ego_accel_mps2(), dt);
        let ao = self.pulse_at(p.opp_accel_mps2(), dt);
        let closing = self.closing_speed_at_contact_mps() + dve + dvo;
        let contact_s = self.collision.map_or(0.0, |c| c.contact_duration_s);
        // After separation the fronts move apart at the (constant) separation speed.
        let distance = if dt > contact_s {
            (dt - contact_s) * (-closing).max(0.0)
        } else {
            0.0
        };
        WorldState {
            distance_m: distance,
            closing_speed_mps: closing,
            relative_accel_mps2: ae + ao,
            ego_speed_mps: self.ego_speed_at_contact_mps + dve,
            ego_accel_mps2: ae,
            ego_braking: false,
            in_path: true,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenario::{BrakeStateName, Scenario};

    fn braking(start_s: f64, decel: f64, ramp: f64) -> Braking {
        Braking {
            start_s,
            decel_mps2: decel,
            ramp_s: ramp,
            state: BrakeStateName::Abs,
        }
    }

    #[test]
    fn constant_decel_obeys_v2_equals_v02_minus_2as() {
        // No ramp: textbook v² = v0² − 2 a s, stop distance v0²/(2a) = 20²/(2·8) = 25 m.
        let b = braking(1.0, 8.0, 0.0);
        let (v, s, a) = braking_motion(20.0, Some(&b), 2.0);
        assert!((v - 12.0).abs() < 1e-9);
        assert!((s - (20.0 + (400.0 - 144.0) / 16.0)).abs() < 1e-9);
        assert_eq!(a, -8.0);
        let (v, s, a) = braking_motion(20.0, Some(&b), 10.0);
        assert_eq!(v, 0.0);
        assert!((s - 45.0).abs() < 1e-9);
        assert_eq!(a, 0.0);
    }

    #[test]
    fn ramp_loses_half_a_r_of_speed() {
        // Linear ramp 0 → 10 m/s² over 0.2 s: Δv = ½·10·0.2 = 1 m/s; s = v0 r − A r²/6.
        let b = braking(0.0, 10.0, 0.2);
        let (v, s, a) = braking_motion(20.0, Some(&b), 0.2);
        assert!((v - 19.0).abs() < 1e-12);
        assert!((s - (4.0 - 10.0 * 0.04 / 6.0)).abs() < 1e-12);
        assert!((a + 10.0).abs() < 1e-12);
    }

    #[test]
    fn vehicle_stopping_inside_the_ramp_stays_stopped() {
        let b = braking(0.0, 10.0, 1.0);
        // v0 = 2 m/s stops at τ = sqrt(2·1·2/10) = 0.632 s, after s = v0 τ − A τ³/6 = 2/3 τ·2.
        let tau: f64 = (0.4f64).sqrt();
        let (v, s, a) = braking_motion(2.0, Some(&b), 5.0);
        assert_eq!(v, 0.0);
        assert_eq!(a, 0.0);
        assert!((s - (2.0 * tau - 10.0 * tau.powi(3) / 6.0)).abs() < 1e-12);
    }

    fn parse(text: &str) -> Scenario {
        Scenario::parse("t.toml", text).expect("valid")
    }

    #[test]
    fn constant_speed_head_on_contact_time_and_equal_mass_delta_v() {
        // 50 + 50 km/h, 30 m: contact at 30 / (2·13.889) = 1.08 s. Equal masses and classes:
        // Δv_ego = (1 + e) v_close / 2 (SPEC oracle) with e = 0.1.
        let s = parse(
            "name = \"t\"\nduration_s = 2\n[ego]\nmass_kg = 1785\nspeed_kph = 50\n\
             [opponent]\nkind = \"vehicle\"\nmass_kg = 1785\nspeed_kph = 50\ninitial_distance_m = 30\n\
             [occupant]\nmass_kg = 75\n",
        );
        let t = Truth::new(&s).expect("truth");
        let tc = t.contact_s.expect("contact");
        assert!((tc - 30.0 / (100.0 / 3.6)).abs() < 2e-6, "{tc}");
        let v = 100.0 / 3.6;
        let dv = t.collision.expect("crash").vehicle.delta_v_mps;
        assert!((dv - 1.1 * v / 2.0).abs() < 0.01 * v, "{dv}");
        let before = t.state(tc - 0.1);
        assert!((before.distance_m - 0.1 * v).abs() < 1e-4, "{before:?}");
        assert!((before.closing_speed_mps - v).abs() < 1e-9);
        let during = t.state(tc + 0.02);
        assert_eq!(during.distance_m, 0.0);
        assert!(
            during.ego_accel_mps2 < -50.0,
            "crash pulse decelerates: {during:?}"
        );
        let after = t.state(tc + 0.3);
        // Separated: receding at e·v_close.
        assert!(
            (after.closing_speed_mps + 0.1 * v).abs() < 0.01 * v,
            "{after:?}"
        );
    }

    #[test]
    fn at_rest_means_exactly_no_acceleration_on_body_and_satellites() {
        // A braked 50 + 50 km/h crash and a 40 km/h offset crash (its pulse runs the whole
        // buffer): every window the truth calls at rest reads exactly 0 at 10 µs steps, and
        // the windows cover the drive before the braking and the run after the pulse.
        let braked = "name = \"t\"\nduration_s = 1.5\n[ego]\nmass_kg = 1785\nspeed_kph = 50\n\
             [ego.braking]\nstart_s = 0.2\ndecel_mps2 = 8\n\
             [opponent]\nkind = \"vehicle\"\nmass_kg = 1785\nspeed_kph = 50\ninitial_distance_m = 20\n\
             [occupant]\nmass_kg = 75\n";
        let offset = "name = \"t\"\nduration_s = 1.5\n[ego]\nmass_kg = 1785\nspeed_kph = 40\n\
             [opponent]\nkind = \"offset_barrier\"\noverlap_percent = 40\ninitial_distance_m = 5\n[sensor]\nmass_estimate_kg = 3000\n\
             [occupant]\nmass_kg = 75\n";
        for text in [braked, offset] {
            let t = Truth::new(&parse(text)).expect("truth");
            let tc = t.contact_s.expect("contact");
            let (mut rest_before, mut rest_after) = (0, 0);
            for k in 0..1500 {
                let t1 = k as f64 * 1e-3;
                let t0 = t1 - 0.02;
                if !t.at_rest_over(t0, t1) {
                    continue;
                }
                if t1 < tc {
                    rest_before += 1;
                } else {
                    rest_after += 1;
                }
                for j in 0..=2000 {
                    let ts = t0 + (t1 - t0) * j as f64 / 2000.0;
                    assert_eq!(t.ego_accel_mps2(ts), 0.0, "{ts}");
                    for side in [FrontSide::Left, FrontSide::Right] {
                        assert_eq!(t.satellite_accel_mps2(side, ts), 0.0, "{ts}");
                    }
                }
            }
            assert!(
                rest_before >= 100 && rest_after >= 100,
                "{rest_before} {rest_after}"
            );
        }
    }

    #[test]
    fn barrier_crash_equals_half_speed_car_to_car() {
        // SPEC oracle: two equal cars at closing speed 2v ≡ one car into a rigid barrier at v.
        let car = parse(
            "name = \"c\"\nduration_s = 2\n[ego]\nmass_kg = 1785\nclass = 4\nspeed_kph = 48\n\
             [opponent]\nkind = \"vehicle\"\nmass_kg = 1785\nclass = 4\nspeed_kph = 48\ninitial_distance_m = 20\n\
             [occupant]\nmass_kg = 75\n",
        );
        let wall = parse(
            "name = \"w\"\nduration_s = 2\n[ego]\nmass_kg = 1785\nclass = 4\nspeed_kph = 48\n\
             [opponent]\nkind = \"barrier\"\ninitial_distance_m = 10\n\
             [sensor]\nmass_estimate_kg = 3000\n[occupant]\nmass_kg = 75\n",
        );
        let a = Truth::new(&car).unwrap().collision.unwrap();
        let b = Truth::new(&wall).unwrap().collision.unwrap();
        assert!(
            (a.vehicle.delta_v_mps - b.vehicle.delta_v_mps).abs() < 0.02 * b.vehicle.delta_v_mps
        );
        assert!((a.vehicle.crush_m - b.vehicle.crush_m).abs() < 0.03 * b.vehicle.crush_m);
    }

    #[test]
    fn evasion_before_contact_avoids_the_crash() {
        // 50 + 50 km/h from 50 m: contact would be at 1.8 s; the opponent swerves at 1.76 s.
        let text = "name = \"e\"\nduration_s = 3\n[ego]\nmass_kg = 1785\nspeed_kph = 50\n\
             [opponent]\nkind = \"vehicle\"\nmass_kg = 1785\nspeed_kph = 50\ninitial_distance_m = 50\nevade_s = 1.76\n\
             [occupant]\nmass_kg = 75\n";
        let t = Truth::new(&parse(text)).unwrap();
        assert!(t.contact_s.is_none());
        assert!(t.state(1.7).in_path);
        assert!(!t.state(1.77).in_path);
        let late = parse(&text.replace("1.76", "1.85"));
        let t = Truth::new(&late).unwrap();
        assert!((t.contact_s.unwrap() - 1.8).abs() < 1e-5);
    }

    #[test]
    fn avoided_collision_has_no_contact() {
        // Both stop from 30 km/h at 8 m/s² (no ramp): 2 · 8.333²/16 = 8.68 m < 10 m.
        let s = parse(
            "name = \"a\"\nduration_s = 3\n[ego]\nmass_kg = 1500\nspeed_kph = 30\n\
             [ego.braking]\nstart_s = 0\ndecel_mps2 = 8\nramp_s = 0\n\
             [opponent]\nkind = \"vehicle\"\nmass_kg = 1500\nspeed_kph = 30\ninitial_distance_m = 10\n\
             [opponent.braking]\nstart_s = 0\ndecel_mps2 = 8\nramp_s = 0\n\
             [occupant]\nmass_kg = 75\n",
        );
        let t = Truth::new(&s).unwrap();
        assert!(t.contact_s.is_none());
        assert!(t.collision.is_none());
        let end = t.state(3.0);
        assert!((end.distance_m - (10.0 - 2.0 * (30.0f64 / 3.6).powi(2) / 16.0)).abs() < 1e-9);
    }
}
