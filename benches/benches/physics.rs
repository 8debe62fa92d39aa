//! Physics: one collision prediction (150 ms of crash, symmetric Table 5 case with the
//! combined curve) at the offline 0.1 ms step (LUT building) and at the ECU's per-cycle step
//! (`restraint::CycleConfig::default().prediction_step_ms`, 0.5 ms — what runs inside the
//! cycle), and one occupant simulation on that pulse (LUT building, thousands per cell).

use criterion::{criterion_group, criterion_main, Criterion};
use physics::{
    collision::{simulate_collision, CollisionInput, DefaultPulseBuffer},
    kph_to_mps, simulate_occupant, stiffness, CombinedSpring, MassClass, OccupantInput,
    RestraintHardware, RestraintSettings,
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
        step_s: restraint::CycleConfig::default().prediction_step_ms * 1e-3,
        ..input
    };
    c.bench_function("collision_prediction_150ms_ecu_step", |b| {
        b.iter(|| simulate_collision(black_box(&ecu_input), &mut buf).expect("valid"))
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
