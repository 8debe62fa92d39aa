//! Closed-form oracles of the two-mass model (SPEC "Closed-form oracles").

use physics::{
    collision::{simulate_collision, CollisionInput, PulseBuffer},
    CombinedSpring, Curve,
};
use std::f64::consts::PI;

type Buf = PulseBuffer<4096>;

fn run(
    spring: &CombinedSpring,
    m1: f64,
    m2: f64,
    v: f64,
    e: f64,
    step_s: f64,
) -> (physics::CollisionSummary, Box<Buf>) {
    let mut buf = Box::new(Buf::new());
    let input = CollisionInput {
        spring,
        ego_mass_kg: m1,
        opp_mass_kg: m2,
        closing_speed_mps: v,
        restitution: e,
        step_s,
        duration_s: 0.4,
    };
    let s = simulate_collision(&input, &mut buf).expect("valid input");
    (s, buf)
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

#[test]
fn linear_spring_elastic_matches_closed_form() {
    let (m1, m2, v, k) = (1500.0, 1100.0, 20.0, 1.2e6);
    let mu = m1 * m2 / (m1 + m2);
    let spring = CombinedSpring::linear(k).unwrap();
    let (s, _) = run(&spring, m1, m2, v, 1.0, 1.0e-4);
    assert!(
        rel(s.max_deflection_m, v * (mu / k).sqrt()) < 1e-3,
        "{}",
        s.max_deflection_m
    );
    assert!(
        rel(s.peak_force_n, v * (k * mu).sqrt()) < 1e-3,
        "{}",
        s.peak_force_n
    );
    assert!(
        rel(s.contact_duration_s, PI * (mu / k).sqrt()) < 1e-3,
        "{}",
        s.contact_duration_s
    );
    // e = 1 ⇒ unloading along the loading line.
    assert!(rel(s.unloading_stiffness_n_per_m, k) < 2e-3);
}

#[test]
fn delta_v_partition_momentum_and_energy() {
    let (m1, m2, v, e) = (1785.0, 2900.0, 25.0, 0.1);
    let c4 = physics::MassClass::new(4).unwrap().curve();
    let c6 = physics::MassClass::new(6).unwrap().curve();
    let spring = CombinedSpring::series(c4, Some(c6)).unwrap();
    let (s, buf) = run(&spring, m1, m2, v, e, 1.0e-4);
    let dv1 = (1.0 + e) * v * m2 / (m1 + m2);
    let dv2 = (1.0 + e) * v * m1 / (m1 + m2);
    assert!(rel(s.vehicle.delta_v_mps, dv1) < 1e-9);
    assert!(rel(s.opponent.delta_v_mps, dv2) < 1e-9);
    // Momentum at every sample: m1 Δv1(t) (ego forward axis) equals m2 Δv2(t) (opposite axis).
    for (a, b) in buf.ego_vel_mps().iter().zip(buf.opp_vel_mps()) {
        assert!((m1 * a - m2 * b).abs() < 1e-6 * m1 * v);
    }
    // Final pulse velocities equal −Δv (the pulse integrates to the same Δv).
    let last = buf.len() - 1;
    assert!(rel(-buf.ego_vel_mps()[last], dv1) < 1e-9);
    // Integrating the sampled acceleration reproduces Δv (trapezoid, coarse tolerance).
    assert!(rel(-buf.ego_pulse().delta_v_mps(), dv1) < 0.01);
    let mu = m1 * m2 / (m1 + m2);
    assert!(rel(s.absorbed_energy_j, 0.5 * mu * v * v * (1.0 - e * e)) < 1e-12);
    // Energy bookkeeping independent of the summary: kinetic energy after separation.
    let v1_end = buf.ego_vel_mps()[last];
    let v2_end = buf.opp_vel_mps()[last];
    // Ground frame: ego starts at +v m2/(m1+m2)... use relative-frame energy: ½μ(u_end)².
    let u_end = v - (-v1_end) - (-v2_end);
    assert!(
        rel(
            0.5 * mu * (v * v - u_end * u_end),
            0.5 * mu * v * v * (1.0 - e * e)
        ) < 1e-9
    );
}

#[test]
fn restitution_exact_for_several_e_and_curves() {
    for &e in &[0.0, 0.1, 0.3, 0.7] {
        for class in 1..=6u8 {
            let c = physics::MassClass::new(class).unwrap().curve();
            let spring = CombinedSpring::series(c, Some(c)).unwrap();
            let (s, buf) = run(&spring, 1400.0, 2100.0, 24.0, e, 1.0e-4);
            let last = buf.len() - 1;
            let u_end = 24.0 + buf.ego_vel_mps()[last] + buf.opp_vel_mps()[last];
            let e_measured = -u_end / 24.0;
            assert!(
                (e_measured - e).abs() < 1e-9,
                "class {class} e {e}: {e_measured}"
            );
            assert!((s.separation_speed_mps - e * 24.0).abs() < 1e-9);
        }
    }
}

#[test]
fn bilinear_hysteresis_e_equals_sqrt_k_over_ku() {
    let k = 2.0e6;
    for &e in &[0.1, 0.2, 0.5, 0.9] {
        let spring = CombinedSpring::linear(k).unwrap();
        let (s, _) = run(&spring, 1200.0, 1600.0, 15.0, e, 1.0e-4);
        let e_oracle = (k / s.unloading_stiffness_n_per_m).sqrt();
        assert!(
            (e_oracle - e).abs() < 1e-3 * e,
            "e {e}: sqrt(k/k_u) = {e_oracle}"
        );
    }
}

#[test]
fn two_equal_cars_equal_one_car_into_barrier_at_half_speed() {
    let c = physics::MassClass::new(4).unwrap().curve();
    let pair = CombinedSpring::series(c, Some(c)).unwrap();
    let single = CombinedSpring::series(c, None).unwrap();
    let (car, bc) = run(&pair, 1785.0, 1785.0, 30.0, 0.1, 1.0e-4);
    let (wall, bw) = run(&single, 1785.0, f64::INFINITY, 15.0, 0.1, 1.0e-4);
    assert!(rel(car.vehicle.crush_m, wall.vehicle.crush_m) < 1e-6);
    assert!(rel(car.vehicle.a_max_mps2, wall.vehicle.a_max_mps2) < 1e-6);
    assert!(rel(car.contact_duration_s, wall.contact_duration_s) < 1e-6);
    assert!(rel(car.vehicle.delta_v_mps, wall.vehicle.delta_v_mps) < 1e-9);
    assert!((car.opponent.crush_m - car.vehicle.crush_m).abs() < 1e-9);
    assert_eq!(wall.opponent.a_max_mps2, 0.0);
    for (a, b) in bc.ego_accel_mps2().iter().zip(bw.ego_accel_mps2()) {
        assert!((a - b).abs() < 1e-6 * 400.0);
    }
}

#[test]
fn series_combination_adds_deflections_at_equal_force() {
    let a = Curve::from_points(&[0.0, 0.1, 0.5], &[0.0, 100e3, 300e3]).unwrap();
    let b = Curve::from_points(&[0.0, 0.2, 0.4], &[0.0, 150e3, 400e3]).unwrap();
    let s = CombinedSpring::series(&a, Some(&b)).unwrap();
    for &f in &[50e3, 100e3, 150e3, 250e3, 300e3, 350e3] {
        let x = a.deflection_at_force_m(f) + b.deflection_at_force_m(f);
        assert!((s.force_at_n(x) - f).abs() < 1e-6 * f);
        assert!((s.ego_deflection_m(x) - a.deflection_at_force_m(f)).abs() < 1e-12);
    }
    // Two linear springs k1, k2 in series: 1/k = 1/k1 + 1/k2.
    let (k1, k2) = (1.0e6, 3.0e6);
    let s = CombinedSpring::series(
        &Curve::linear(k1).unwrap(),
        Some(&Curve::linear(k2).unwrap()),
    )
    .unwrap();
    assert!(rel(s.force_at_n(0.1), 0.1 / (1.0 / k1 + 1.0 / k2)) < 1e-12);
}

#[test]
fn accuracy_improves_with_smaller_step() {
    // Linear spring: error of the peak force against v√(kμ) shrinks with the step (2nd order).
    let (m1, m2, v, k) = (1785.0, 1785.0, 30.0, 1.5e6);
    let mu = m1 * m2 / (m1 + m2);
    let spring = CombinedSpring::linear(k).unwrap();
    let exact = v * (k * mu).sqrt();
    let err = |dt| rel(run(&spring, m1, m2, v, 1.0, dt).0.peak_force_n, exact);
    let (e1, e2) = (err(1.0e-3), err(1.0e-4));
    assert!(e2 < e1 && e2 < 1e-4, "{e1} {e2}");
}

#[test]
fn class_lookup_by_mass() {
    let cases = [
        (900.0, 1),
        (1199.9, 1),
        (1200.0, 2),
        (1399.0, 2),
        (1400.0, 3),
        (1785.0, 4),
        (2000.0, 5),
        (2499.0, 5),
        (2500.0, 6),
        (3500.0, 6),
    ];
    for (m, c) in cases {
        assert_eq!(physics::class_for_mass_kg(m).unwrap().number(), c, "{m} kg");
    }
    assert!(physics::class_for_mass_kg(f64::NAN).is_err());
    assert!(physics::class_for_mass_kg(-1.0).is_err());
}
