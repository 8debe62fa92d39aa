//! Occupant model sanity: physical orderings and limits, not model-computed numbers.

use physics::{
    collision::{simulate_collision, CollisionInput, DefaultPulseBuffer},
    kph_to_mps, mps2_to_g, simulate_occupant, simulate_occupant_switched, stiffness,
    CombinedSpring, CompartmentPulse, LimiterSwitch, OccupantInput, OccupantOutcome,
    RestraintHardware, RestraintSettings,
};

fn pulse(closing_kph: f64) -> Box<DefaultPulseBuffer> {
    let c = &stiffness::COMBINED_CURVE;
    let spring = CombinedSpring::series(c, Some(c)).unwrap();
    let mut buf = Box::new(DefaultPulseBuffer::new());
    simulate_collision(
        &CollisionInput::with_defaults(&spring, 1785.0, 1785.0, kph_to_mps(closing_kph)),
        &mut buf,
    )
    .unwrap();
    buf
}

fn occ(
    buf: &DefaultPulseBuffer,
    mass_kg: f64,
    belted: bool,
    set: RestraintSettings,
) -> OccupantOutcome {
    let input = OccupantInput {
        mass_kg,
        chest_to_wheel_m: 0.3,
        belted,
    };
    simulate_occupant(
        &buf.ego_pulse(),
        &input,
        &set,
        &RestraintHardware::default(),
    )
    .unwrap()
}

fn set(limiter_kn: f64, bag_kn: f64) -> RestraintSettings {
    RestraintSettings {
        load_limiter_n: limiter_kn * 1e3,
        airbag_force_n: bag_kn * 1e3,
        pretensioner_time_s: 0.0,
        airbag_time_s: 0.010,
    }
}

#[test]
fn heavier_occupant_same_forces_larger_excursion() {
    let buf = pulse(80.0);
    let light = occ(&buf, 50.0, true, set(5.0, 5.0));
    let heavy = occ(&buf, 110.0, true, set(5.0, 5.0));
    assert!(
        heavy.max_excursion_m > light.max_excursion_m + 0.01,
        "{light:?} {heavy:?}"
    );
}

#[test]
fn bottoming_detected_when_forces_too_low_and_not_with_strong_restraint() {
    let buf = pulse(108.0);
    let weak = occ(&buf, 75.0, true, set(1.0, 0.0));
    assert!(weak.bottomed_out, "{weak:?}");
    assert!(weak.max_excursion_m > weak.available_ride_down_m);
    let strong = occ(&buf, 75.0, true, set(12.0, 12.0));
    assert!(!strong.bottomed_out, "{strong:?}");
    assert!(strong.max_excursion_m < strong.available_ride_down_m);
    // Available ride-down is D − module thickness (300 − 60 mm).
    assert!((strong.available_ride_down_m - 0.240).abs() < 1e-12);
}

#[test]
fn belt_only_and_airbag_only_respect_their_force_caps() {
    let buf = pulse(60.0);
    let belt_only = occ(&buf, 75.0, true, set(4.0, 0.0));
    assert_eq!(belt_only.max_airbag_force_n, 0.0);
    assert!(belt_only.max_belt_force_n <= 4000.0 + 1e-9);
    assert!(
        belt_only.max_belt_force_n > 3999.0,
        "limiter should be reached: {belt_only:?}"
    );
    assert!(belt_only.belt_payout_m > 0.0, "pay-out at the limiter");

    let bag_only = occ(&buf, 75.0, false, set(4.0, 6.0));
    assert_eq!(bag_only.max_belt_force_n, 0.0);
    assert!(bag_only.max_airbag_force_n <= 6000.0 + 1e-9 && bag_only.max_airbag_force_n > 0.0);
    assert_eq!(bag_only.belt_payout_m, 0.0);
}

#[test]
fn decelerations_are_ordered_and_above_the_ideal_bound() {
    let buf = pulse(108.0);
    let o = occ(&buf, 75.0, true, set(12.0, 12.0));
    eprintln!(
        "{o:?} a_max {} g a_mean {} g a* {} g",
        mps2_to_g(o.max_decel_mps2),
        mps2_to_g(o.mean_decel_mps2),
        mps2_to_g(o.ideal_decel_mps2)
    );
    assert!(!o.bottomed_out);
    assert!(o.mean_decel_mps2 > 0.0 && o.mean_decel_mps2 <= o.max_decel_mps2);
    // No restraint can beat the ideal constant force within the same ride-down.
    assert!(o.max_decel_mps2 >= o.ideal_decel_mps2, "{o:?}");
    // a* = Δv² / (2 (D_veh + s_avail)); its order of magnitude for this case: 10..25 g.
    // The bound accumulated inside the simulation equals the stand-alone computation.
    let standalone =
        physics::ideal_constant_force_decel_mps2(&buf.ego_pulse(), o.available_ride_down_m);
    assert!(
        (o.ideal_decel_mps2 / standalone - 1.0).abs() < 1e-9,
        "{} vs {standalone}",
        o.ideal_decel_mps2
    );
    let a_star_g = mps2_to_g(o.ideal_decel_mps2);
    assert!((10.0..25.0).contains(&a_star_g), "{a_star_g}");
}

#[test]
fn pre_crash_pretensioner_reduces_excursion() {
    let buf = pulse(70.0);
    let mut early = set(6.0, 6.0);
    early.pretensioner_time_s = -0.050;
    let mut late = set(6.0, 6.0);
    late.pretensioner_time_s = 0.020;
    let e = occ(&buf, 75.0, true, early);
    let l = occ(&buf, 75.0, true, late);
    assert!(e.max_excursion_m < l.max_excursion_m - 0.005, "{e:?} {l:?}");
}

#[test]
fn no_crash_no_motion() {
    let pulse = [0.0f64; 500];
    let p = physics::CompartmentPulse {
        step_s: 1e-4,
        accel_mps2: &pulse,
    };
    let o = simulate_occupant(
        &p,
        &OccupantInput::default(),
        &set(6.0, 6.0),
        &RestraintHardware::default(),
    )
    .unwrap();
    assert_eq!(o.max_excursion_m, 0.0);
    assert_eq!(o.max_decel_mps2, 0.0);
    assert!(!o.bottomed_out);
}

#[test]
fn constant_pulse_ideal_bound_closed_form() {
    // Compartment at constant 20 g for 50 ms, then at rest: Δv = 9.80665 m/s,
    // D_veh = ½ a T² = 0.24517 m in the final-velocity frame.
    let a = 20.0 * 9.80665;
    let n = 501; // 0..=50 ms at 0.1 ms, then zeros
    let mut s = vec![0.0; 1000];
    s[..n].iter_mut().for_each(|v| *v = -a);
    let p = physics::CompartmentPulse {
        step_s: 1e-4,
        accel_mps2: &s,
    };
    let dv = a * 0.05;
    let d_veh = 0.5 * a * 0.05 * 0.05;
    let bound = physics::ideal_constant_force_decel_mps2(&p, 0.24);
    let oracle = dv * dv / (2.0 * (d_veh + 0.24));
    assert!((bound / oracle - 1.0).abs() < 0.01, "{bound} {oracle}");
}

// Two-level load limiter: the switched model reduces to the single-level one
// at both ends, and meets a closed-form oracle in between.

fn settings(limiter_kn: f64) -> RestraintSettings {
    RestraintSettings {
        load_limiter_n: limiter_kn * 1e3,
        airbag_force_n: 6e3,
        pretensioner_time_s: -0.02,
        airbag_time_s: 0.012,
    }
}

#[test]
fn a_switch_after_the_run_is_the_single_high_level_and_one_before_contact_the_low_one() {
    let buf = pulse(96.0);
    let (occ, hw) = (OccupantInput::default(), RestraintHardware::default());
    let high = simulate_occupant(&buf.ego_pulse(), &occ, &settings(7.0), &hw).unwrap();
    let low = simulate_occupant(&buf.ego_pulse(), &occ, &settings(4.0), &hw).unwrap();
    let late = LimiterSwitch {
        at_s: 5.0,
        level_n: 4e3,
    };
    let early = LimiterSwitch {
        at_s: -0.1,
        level_n: 4e3,
    };
    let sw = |s: &LimiterSwitch| {
        simulate_occupant_switched(&buf.ego_pulse(), &occ, &settings(7.0), s, &hw).unwrap()
    };
    assert_eq!(sw(&late), high);
    assert_eq!(sw(&early), low);
    // In between: less force than the high level throughout, more than the low one.
    let mid = sw(&LimiterSwitch {
        at_s: 0.040,
        level_n: 4e3,
    });
    assert!(
        high.max_excursion_m < mid.max_excursion_m && mid.max_excursion_m < low.max_excursion_m,
        "{high:?}\n{mid:?}\n{low:?}"
    );
    assert!(mid.belt_payout_m > high.belt_payout_m);
}

#[test]
fn constant_pulse_with_a_switch_meets_the_closed_form_excursion() {
    // A belt without slack or seat friction and no airbag; 20 g for 60 ms, the cap 12 kN until
    // 30 ms, then 8 kN; 80 kg. The belt first stretches as a spring (x'' = A − k x / m, from
    // rest: x = A m/k (1 − cos ωt)) until k x reaches the cap, then the chest moves relative to
    // the compartment at A − F/m, and after the pulse it is stopped at F/m.
    let (a, m, f1, f2, k) = (20.0 * 9.80665, 80.0, 12e3, 8e3, 1e7);
    let (t_sw, t_end) = (0.030, 0.060);
    let mut s = vec![0.0; 3000];
    s[..600].iter_mut().for_each(|v| *v = -a);
    let pulse = CompartmentPulse {
        step_s: 1e-4,
        accel_mps2: &s,
    };
    let hw = RestraintHardware {
        belt_slack_m: 0.0,
        belt_stiffness_n_per_m: k,
        seat_friction_coeff: 0.0,
        ..RestraintHardware::default()
    };
    let occ = OccupantInput {
        mass_kg: m,
        chest_to_wheel_m: 0.45,
        belted: true,
    };
    let set = RestraintSettings {
        load_limiter_n: f1,
        airbag_force_n: 0.0,
        pretensioner_time_s: -0.1,
        airbag_time_s: 0.0,
    };
    let o = simulate_occupant_switched(
        &pulse,
        &occ,
        &set,
        &LimiterSwitch {
            at_s: t_sw,
            level_n: f2,
        },
        &hw,
    )
    .unwrap();
    let w = (k / m).sqrt();
    let theta = (1.0 - f1 / (a * m)).acos();
    let (t0, v0, x0) = (theta / w, a / w * theta.sin(), f1 / k);
    let (a1, a2) = (a - f1 / m, a - f2 / m);
    let d1 = t_sw - t0;
    let (v1, x1) = (v0 + a1 * d1, x0 + v0 * d1 + 0.5 * a1 * d1 * d1);
    let d2 = t_end - t_sw;
    let (v2, x2) = (v1 + a2 * d2, x1 + v1 * d2 + 0.5 * a2 * d2 * d2);
    let x_max = x2 + v2 * v2 / (2.0 * f2 / m);
    assert!(
        (o.max_excursion_m / x_max - 1.0).abs() < 0.005,
        "{} vs closed form {x_max}",
        o.max_excursion_m
    );
    assert!((o.max_belt_force_n / f1 - 1.0).abs() < 1e-9);
    assert!((o.max_decel_mps2 * m / f1 - 1.0).abs() < 0.01);
    assert!(!o.bottomed_out);
}

#[test]
fn a_switch_that_is_not_a_finite_level_is_refused() {
    let buf = pulse(56.0);
    let (occ, hw) = (OccupantInput::default(), RestraintHardware::default());
    for s in [
        LimiterSwitch {
            at_s: f64::NAN,
            level_n: 4e3,
        },
        LimiterSwitch {
            at_s: 0.04,
            level_n: -1.0,
        },
        LimiterSwitch {
            at_s: 0.04,
            level_n: f64::INFINITY,
        },
    ] {
        assert!(
            simulate_occupant_switched(&buf.ego_pulse(), &occ, &settings(6.0), &s, &hw).is_err()
        );
    }
}
