//! Physics: one collision prediction (150 ms of crash, symmetric Table 5 case with the
//! combined curve) at the offline 0.1 ms step (LUT building) and at the 0.5 ms step the ECU
//! integrated at before it switched to the closed form (`FORMER_ECU_STEP_S`, for comparison),
//! and one occupant simulation on that pulse (LUT building, thousands per cell).
//!
//! The closed-form solution (`physics::exact`) of the same cases: the summary alone (what the
//! ECU needs per cycle), solve + the 64 diagnostics points, and the 150 ms pulse at 0.1 ms
//! (LUT building); `*_varied` rows cycle through `PredictionWorkload` (108 cases over the
//! default table's opponent-mass × closing-speed axes) for both methods.

use criterion::{criterion_group, criterion_main, Criterion};
use cycle_benches::workload::{PredictionWorkload, FORMER_ECU_STEP_S};
use physics::{
    collision::{simulate_collision, CollisionInput, DefaultPulseBuffer},
    kph_to_mps, predict_summary, simulate_collision_exact, simulate_occupant, stiffness,
    CombinedSpring, ExactCollision, MassClass, OccupantInput, RestraintHardware, RestraintSettings,
};
use std::hint::black_box;

fn bench_physics(c: &mut Criterion) {
    let curve = &stiffness::COMBINED_CURVE;
    let spring = CombinedSpring::series(curve, Some(curve)).expect("valid curves");
    let mut buf = Box::new(DefaultPulseBuffer::new());
    let input = CollisionInput::with_defaults(&spring, 1785.0, 1785.0, kph_to_mps(108.0));

    c.bench_function("collision_prediction_150ms_default_step", |b| {
        b.iter(|| simulate_collision(black_box(&input), &mut buf).expect("valid"))
    });
    let ecu_input = CollisionInput {
        step_s: FORMER_ECU_STEP_S,
        ..input
    };
    c.bench_function("collision_prediction_150ms_ecu_step", |b| {
        b.iter(|| simulate_collision(black_box(&ecu_input), &mut buf).expect("valid"))
    });

    // The closed-form solution of the same inputs.
    c.bench_function("collision_summary_exact", |b| {
        b.iter(|| predict_summary(black_box(&ecu_input)).expect("valid"))
    });
    let diag_step_s = physics::defaults::PULSE_DURATION_S / ipc::PULSE_POINTS as f64;
    c.bench_function("collision_exact_solve_and_64_samples", |b| {
        let mut points = [0.0f32; ipc::PULSE_POINTS];
        let mut sol = Box::new(ExactCollision::new());
        b.iter(|| {
            sol.solve_in_place(black_box(&ecu_input)).expect("valid");
            for (dst, p) in points
                .iter_mut()
                .zip(sol.samples(diag_step_s).expect("valid step"))
            {
                *dst = p.ego_accel_mps2 as f32;
            }
            black_box(&points);
        })
    });
    c.bench_function("collision_exact_pulse_150ms_default_step", |b| {
        b.iter(|| simulate_collision_exact(black_box(&input), &mut buf).expect("valid"))
    });
    let w = PredictionWorkload::new();
    let mut i = 0usize;
    c.bench_function("collision_summary_exact_varied", |b| {
        b.iter(|| {
            i = i.wrapping_add(1);
            predict_summary(black_box(&w.input(i, ecu_input.step_s))).expect("valid")
        })
    });
    c.bench_function("collision_prediction_150ms_ecu_step_varied", |b| {
        b.iter(|| {
            i = i.wrapping_add(1);
            simulate_collision(black_box(&w.input(i, ecu_input.step_s)), &mut buf).expect("valid")
        })
    });

    // Series combination of two class curves (done once per opponent-class change in the ECU).
    let (c4, c6) = (
        MassClass::new(4).unwrap().curve(),
        MassClass::new(6).unwrap().curve(),
    );
    c.bench_function("series_combination_two_classes", |b| {
        b.iter(|| CombinedSpring::series(black_box(c4), Some(black_box(c6))).expect("valid"))
    });

    simulate_collision(&input, &mut buf).expect("valid");
    let occupant = OccupantInput::default();
    let settings = RestraintSettings {
        load_limiter_n: 6_000.0,
        airbag_force_n: 8_000.0,
        pretensioner_time_s: 0.0,
        airbag_time_s: 0.010,
    };
    let hw = RestraintHardware::default();
    c.bench_function("occupant_simulation", |b| {
        b.iter(|| {
            simulate_occupant(
                &buf.ego_pulse(),
                black_box(&occupant),
                black_box(&settings),
                &hw,
            )
            .expect("valid")
        })
    });
}

criterion_group!(benches, bench_physics);
criterion_main!(benches);
