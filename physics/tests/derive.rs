//! Derivation round trip: known curve → simulated rigid-barrier trace + noise → derived curve.
#![cfg(feature = "std")]

use physics::{
    collision::{simulate_collision, CollisionInput, PulseBuffer},
    derive::{derive_curve, DeriveOptions},
    j211::Cfc,
    trace::{parse_csv as parse_trace_csv, Trace as BarrierTrace},
    CombinedSpring, Curve,
};

fn known_curve() -> Curve {
    // SPEC's starting-point curve (mm, kN).
    let d = [0.0, 40.0, 120.0, 550.0, 650.0, 800.0].map(|v| v * 1e-3);
    let f = [0.0, 150.0, 290.0, 310.0, 630.0, 1170.0].map(|v| v * 1e3);
    Curve::from_points(&d, &f).unwrap()
}

fn barrier_trace(curve: &Curve, mass_kg: f64, speed_mps: f64, noise_g: f64) -> (BarrierTrace, f64) {
    let spring = CombinedSpring::series(curve, None).unwrap();
    let mut buf = Box::new(PulseBuffer::<4096>::new());
    let input = CollisionInput {
        spring: &spring,
        ego_mass_kg: mass_kg,
        opp_mass_kg: f64::INFINITY,
        closing_speed_mps: speed_mps,
        restitution: 0.1,
        step_s: 1e-4,
        duration_s: 0.25,
    };
    let s = simulate_collision(&input, &mut buf).unwrap();
    // Deterministic noise: LCG white noise ±noise_g plus a 450 Hz structural ringing.
    let mut state: u64 = 0x2545_F491_4F6C_DD1D;
    let accel = buf
        .ego_accel_mps2()
        .iter()
        .enumerate()
        .map(|(i, a)| {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let u = (state >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0;
            let ring = (2.0 * std::f64::consts::PI * 450.0 * i as f64 * 1e-4).sin();
            a + noise_g * 9.80665 * (u + ring)
        })
        .collect();
    (
        BarrierTrace {
            start_s: 0.0,
            step_s: 1e-4,
            accel_mps2: accel,
        },
        s.vehicle.crush_m,
    )
}

#[test]
fn round_trip_recovers_the_curve() {
    let curve = known_curve();
    let (mass, v0) = (1785.0, 56.0 / 3.6);
    let (trace, crush_true) = barrier_trace(&curve, mass, v0, 3.0);
    let opts = DeriveOptions {
        mass_kg: mass,
        impact_speed_mps: v0,
        points: 16,
        cfc: Cfc::Cfc60,
    };
    let derived = derive_curve(&trace, &opts).unwrap();
    assert!(!derived.sign_flipped);
    assert!(
        (derived.max_crush_m / crush_true - 1.0).abs() < 0.01,
        "{} vs {crush_true}",
        derived.max_crush_m
    );
    // Compare at crush points away from the sharp knees (CFC 60 rounds them by design).
    for &x_mm in &[80.0, 200.0, 300.0, 400.0, 500.0, 600.0] {
        let x = x_mm * 1e-3;
        if x > 0.95 * crush_true {
            continue;
        }
        let (f_true, f_got) = (curve.force_at_n(x), derived.curve.force_at_n(x));
        assert!(
            (f_got - f_true).abs() < 0.06 * f_true + 10e3,
            "{x_mm} mm: derived {f_got} N vs true {f_true} N"
        );
    }
    // Energy to max crush matches the impact energy within 3 %.
    let e_kin = 0.5 * mass * v0 * v0;
    let e_curve = derived.curve.energy_to_deflection_j(derived.max_crush_m);
    assert!((e_curve / e_kin - 1.0).abs() < 0.03, "{e_curve} vs {e_kin}");
}

#[test]
fn flipped_sign_trace_is_detected() {
    let curve = known_curve();
    let (mut trace, _) = barrier_trace(&curve, 1500.0, 14.0, 0.0);
    trace.accel_mps2.iter_mut().for_each(|a| *a = -*a);
    let opts = DeriveOptions {
        mass_kg: 1500.0,
        impact_speed_mps: 14.0,
        points: 12,
        cfc: Cfc::Cfc60,
    };
    assert!(derive_curve(&trace, &opts).unwrap().sign_flipped);
}

#[test]
fn csv_parsing_and_errors() {
    let mut csv = String::from("# test\ntime_ms,accel_g\n");
    for i in 0..20 {
        csv.push_str(&format!("{},{}\n", i as f64 * 0.1, -10.0));
    }
    let t = parse_trace_csv(&csv).unwrap();
    assert!((t.step_s - 1e-4).abs() < 1e-12);
    assert!((t.accel_mps2[3] + 98.0665).abs() < 1e-9);
    assert!(parse_trace_csv("time_s,force\n0,1\n").is_err());
    assert!(parse_trace_csv("time_s,accel_g\n0,1\n0.1,x\n")
        .unwrap_err()
        .contains("line 3"));
    let mut uneven = String::from("time_s,accel_g\n");
    for i in 0..20 {
        uneven.push_str(&format!("{},0\n", (i * i) as f64 * 1e-4));
    }
    assert!(parse_trace_csv(&uneven)
        .unwrap_err()
        .contains("non-uniform"));
}
