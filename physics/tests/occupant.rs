//! Occupant model sanity (issue 2): physical orderings and limits, not model-computed numbers.

use physics::{
    collision::{simulate_collision, CollisionInput, DefaultPulseBuffer},
    kph_to_mps, mps2_to_g, simulate_occupant, stiffness, CombinedSpring, OccupantInput,
    OccupantOutcome, RestraintHardware, RestraintSettings,
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
