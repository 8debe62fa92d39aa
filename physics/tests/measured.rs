//! The two-mass model's own barrier pulse, played back as a measurement, is the same crash:
//! the velocity change, the peak, the crush and the instant of the largest crush that the
//! model computed from its spring, read off the pulse alone.

use physics::{
    measured::measured_collision, simulate_collision, CollisionInput, CombinedSpring, Curve,
    PulseBuffer,
};

#[test]
fn a_modelled_barrier_pulse_played_back_is_the_same_crash() {
    let d = [0.0, 0.1, 0.3, 0.5, 0.7, 0.9];
    let f = [0.0, 150.0, 290.0, 310.0, 630.0, 1170.0].map(|v| v * 1e3);
    let curve = Curve::from_points(&d, &f).unwrap();
    let spring = CombinedSpring::series(&curve, None).unwrap();
    for kph in [16.0, 35.0, 56.0] {
        let v0 = kph / 3.6;
        let mut model = Box::new(PulseBuffer::<4096>::new());
        let input = CollisionInput {
            spring: &spring,
            ego_mass_kg: 1785.0,
            opp_mass_kg: f64::INFINITY,
            closing_speed_mps: v0,
            restitution: 0.1,
            step_s: 1e-4,
            duration_s: 0.25,
        };
        let m = simulate_collision(&input, &mut model).unwrap();
        let mut played = Box::new(PulseBuffer::<4096>::new());
        let p = measured_collision(model.ego_accel_mps2(), 1e-4, v0, 1785.0, &mut played).unwrap();
        let close = |a: f64, b: f64, tol: f64| (a - b).abs() <= tol * b.abs().max(1e-9);
        assert!(
            close(p.vehicle.delta_v_mps, m.vehicle.delta_v_mps, 1e-3),
            "{kph}: {p:?} {m:?}"
        );
        assert!(
            close(p.vehicle.a_max_mps2, m.vehicle.a_max_mps2, 1e-3),
            "{kph}: {p:?} {m:?}"
        );
        assert!(
            close(p.vehicle.crush_m, m.vehicle.crush_m, 2e-3),
            "{kph}: {p:?} {m:?}"
        );
        assert!(
            (p.reversal_time_s - m.reversal_time_s).abs() <= 2e-4,
            "{kph}: {p:?} {m:?}"
        );
        assert!(
            close(p.separation_speed_mps, m.separation_speed_mps, 2e-2),
            "{kph}: {p:?} {m:?}"
        );
        for (a, b) in played.ego_vel_mps().iter().zip(model.ego_vel_mps()) {
            assert!((a - b).abs() < 1e-3, "{kph}: {a} {b}");
        }
    }
}
