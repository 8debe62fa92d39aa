//! Two-level load limiter (issue 24 item 4): the switched model reduces to the single-level one
//! at both ends, and meets a closed-form oracle in between.

use physics::{
    collision::{simulate_collision, CollisionInput, DefaultPulseBuffer},
    kph_to_mps, simulate_occupant, simulate_occupant_switched, stiffness, CombinedSpring,
    CompartmentPulse, LimiterSwitch, OccupantInput, RestraintHardware, RestraintSettings,
};

fn taurus_pulse(closing_kph: f64) -> Box<DefaultPulseBuffer> {
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
    let buf = taurus_pulse(96.0);
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
    let buf = taurus_pulse(56.0);
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
