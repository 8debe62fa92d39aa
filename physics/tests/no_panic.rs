//! Property tests: public functions never panic on arbitrary (NaN, ∞, huge) input; they return
//! errors, and valid input yields finite results.

use physics::{
    collision::{simulate_collision, CollisionInput, PulseBuffer},
    j211, simulate_occupant, stiffness, CombinedSpring, CompartmentPulse, Curve, OccupantInput,
    RestraintHardware, RestraintSettings,
};
use physics::{
    exact::{predict_summary, simulate_collision_exact, ExactCollision},
    CollisionSummary, PulseSample,
};
use proptest::prelude::*;

fn summary_is_finite(s: &CollisionSummary) -> bool {
    [s.vehicle, s.opponent].iter().all(|v| {
        [v.crush_m, v.a_max_mps2, v.a_mean_mps2, v.delta_v_mps]
            .iter()
            .all(|x| x.is_finite())
    }) && s.contact_duration_s.is_finite()
        && s.reversal_time_s.is_finite()
        && s.max_deflection_m.is_finite()
        && s.peak_force_n.is_finite()
}

fn sample_is_finite(p: &PulseSample) -> bool {
    [
        p.ego_accel_mps2,
        p.ego_vel_mps,
        p.ego_crush_m,
        p.opp_accel_mps2,
        p.opp_vel_mps,
        p.opp_crush_m,
    ]
    .iter()
    .all(|x| x.is_finite())
}

fn any_f64() -> impl Strategy<Value = f64> {
    prop_oneof![
        Just(f64::NAN),
        Just(f64::INFINITY),
        Just(f64::NEG_INFINITY),
        Just(0.0),
        Just(-0.0),
        Just(f64::MIN_POSITIVE),
        Just(1e300),
        any::<f64>(),
        -1e4..1e4f64,
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 300, ..ProptestConfig::default() })]

    #[test]
    fn collision_never_panics(m1 in any_f64(), m2 in any_f64(), v in any_f64(), e in any_f64(),
                              dt in any_f64(), dur in any_f64(), class in 0usize..7) {
        let curve = if class < 6 { &stiffness::CLASS_CURVES[class] } else { &stiffness::COMBINED_CURVE };
        let spring = CombinedSpring::series(curve, Some(curve)).unwrap();
        let mut buf = Box::new(PulseBuffer::<256>::new());
        let input = CollisionInput { spring: &spring, ego_mass_kg: m1, opp_mass_kg: m2, closing_speed_mps: v,
                                     restitution: e, step_s: dt, duration_s: dur };
        if let Ok(s) = simulate_collision(&input, &mut buf) {
            prop_assert!(s.vehicle.crush_m.is_finite() && s.vehicle.a_max_mps2.is_finite());
            prop_assert!(buf.ego_accel_mps2().iter().all(|a| a.is_finite()));
        }
    }

    #[test]
    fn exact_collision_never_panics(m1 in any_f64(), m2 in any_f64(), v in any_f64(), e in any_f64(),
                                    dt in any_f64(), dur in any_f64(), t in any_f64(), class in 0usize..7) {
        let curve = if class < 6 { &stiffness::CLASS_CURVES[class] } else { &stiffness::COMBINED_CURVE };
        let spring = CombinedSpring::series(curve, Some(curve)).unwrap();
        let input = CollisionInput { spring: &spring, ego_mass_kg: m1, opp_mass_kg: m2, closing_speed_mps: v,
                                     restitution: e, step_s: dt, duration_s: dur };
        if let Ok(s) = predict_summary(&input) {
            prop_assert!(summary_is_finite(&s), "{s:?}");
        }
        let mut buf = Box::new(PulseBuffer::<256>::new());
        if simulate_collision_exact(&input, &mut buf).is_ok() {
            prop_assert!(buf.ego_accel_mps2().iter().chain(buf.opp_crush_m()).all(|a| a.is_finite()));
        }
        if let Ok(sol) = ExactCollision::solve(&input) {
            prop_assert!(sample_is_finite(&sol.state_at(t)));
            if let Ok(it) = sol.samples(dt) {
                for p in it.take(64) {
                    prop_assert!(sample_is_finite(&p));
                }
            }
        }
    }

    #[test]
    fn collision_valid_inputs_give_finite_physical_results(m1 in 500.0..3500.0f64, m2 in 500.0..3500.0f64,
            v in 0.5..60.0f64, e in 0.0..=1.0f64, a in 0usize..6, b in 0usize..6) {
        let spring = CombinedSpring::series(&stiffness::CLASS_CURVES[a], Some(&stiffness::CLASS_CURVES[b])).unwrap();
        let mut buf = Box::new(PulseBuffer::<2048>::new());
        let mut input = CollisionInput::with_defaults(&spring, m1, m2, v);
        input.restitution = e;
        let s = simulate_collision(&input, &mut buf).unwrap();
        prop_assert!(s.contact_duration_s > 0.0 && s.contact_duration_s < 1.0);
        prop_assert!((s.vehicle.crush_m + s.opponent.crush_m - s.max_deflection_m).abs() < 1e-9);
        prop_assert!(s.vehicle.a_mean_mps2 <= s.vehicle.a_max_mps2);
    }

    #[test]
    fn curve_constructors_never_panic(d in proptest::collection::vec(any_f64(), 0..40),
                                      f in proptest::collection::vec(any_f64(), 0..40), x in any_f64(), k in any_f64()) {
        if let Ok(c) = Curve::from_points(&d, &f) {
            let _ = c.force_at_n(x);
            let _ = c.deflection_at_force_m(x);
            let _ = c.energy_to_deflection_j(x);
            if let Ok(s) = CombinedSpring::series(&c, Some(&c)) {
                let _ = s.force_at_n(x);
            }
        }
        let _ = Curve::linear(k);
        let _ = physics::class_for_mass_kg(x);
    }

    #[test]
    fn occupant_never_panics(pulse in proptest::collection::vec(any_f64(), 0..300), dt in any_f64(),
                             mass in any_f64(), d in any_f64(), belted in any::<bool>(),
                             lim in any_f64(), bag in any_f64(), tp in any_f64(), ta in any_f64()) {
        let p = CompartmentPulse { step_s: dt, accel_mps2: &pulse };
        let occ = OccupantInput { mass_kg: mass, chest_to_wheel_m: d, belted };
        let set = RestraintSettings { load_limiter_n: lim, airbag_force_n: bag, pretensioner_time_s: tp, airbag_time_s: ta };
        if let Ok(o) = simulate_occupant(&p, &occ, &set, &RestraintHardware::default()) {
            prop_assert!(o.max_excursion_m.is_finite() && o.max_decel_mps2.is_finite() && o.mean_decel_mps2.is_finite());
        }
    }

    #[test]
    fn filter_never_panics(mut x in proptest::collection::vec(any_f64(), 0..200), dt in any_f64()) {
        let _ = j211::filter_in_place(&mut x, dt, j211::Cfc::Cfc60);
        let _ = j211::magnitude(j211::Cfc::Cfc180, dt, dt);
    }
}

#[cfg(feature = "std")]
proptest! {
    #![proptest_config(ProptestConfig { cases: 100, ..ProptestConfig::default() })]
    #[test]
    fn derive_never_panics(a in proptest::collection::vec(any_f64(), 0..300), dt in any_f64(),
                           m in any_f64(), v in any_f64(), n in 0usize..20) {
        let trace = physics::trace::Trace { start_s: 0.0, step_s: dt, accel_mps2: a };
        let opts = physics::derive::DeriveOptions { mass_kg: m, impact_speed_mps: v, points: n, cfc: j211::Cfc::Cfc60 };
        let _ = physics::derive::derive_curve(&trace, &opts);
    }

    #[test]
    fn csv_parser_never_panics(s in ".{0,400}") {
        let _ = physics::trace::parse(&s);
        let _ = physics::stiffness::parse_class_file(&s);
    }
}
