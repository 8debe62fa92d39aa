//! Restraint optimiser throughput (bench target of the `lut` package, see lut/Cargo.toml:
//! `cargo bench -p lut --bench optimiser`).
//!
//! * `optimiser/one_optimum` — one adaptive optimum (default `OptimiserConfig`: swarm 24 × 30 +
//!   Nelder–Mead ≤ 150) for 75 kg at 300 mm, 1785 kg vs 1785 kg at 80 km/h, pulse precomputed
//!   (the builder also simulates the collision once per cell).
//! * `optimiser/occupant_simulation` — one occupant simulation on that pulse (elements/s =
//!   occupant simulations per second per core).
//! * `optimiser/collision` — the one collision prediction per cell, for scale.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use lut::optimise::{optimise, Case, OptimiserConfig, SearchSpace};
use lut::reference::ReferenceRestraint;
use lut::scenario::{Ego, Opponent, Pulse};
use physics::{simulate_occupant, OccupantInput, RestraintHardware};

fn bench_optimiser(c: &mut Criterion) {
    let ego = Ego::default();
    let opp = Opponent::Car { mass_kg: 1785.0 };
    let pulse = Pulse::predict(&ego, opp, 80.0).expect("pulse");
    let occupant = OccupantInput {
        mass_kg: 75.0,
        chest_to_wheel_m: 0.3,
        belted: true,
    };
    let hw = RestraintHardware::default();
    let cfg = OptimiserConfig::default();
    let reference = ReferenceRestraint::builtin().expect("reference").settings();

    let mut g = c.benchmark_group("optimiser");
    g.sample_size(20);
    g.throughput(Throughput::Elements(1));
    g.bench_function("one_optimum", |b| {
        b.iter(|| {
            let case = Case {
                pulse: pulse.ego(),
                occupant: black_box(occupant),
            };
            optimise(&[case], &SearchSpace::adaptive(), &hw, &cfg).expect("optimum")
        })
    });
    g.sample_size(100);
    g.bench_function("occupant_simulation", |b| {
        b.iter(|| {
            simulate_occupant(
                &pulse.ego(),
                black_box(&occupant),
                black_box(&reference),
                &hw,
            )
            .expect("sim")
        })
    });
    g.bench_function("collision", |b| {
        b.iter(|| Pulse::predict(&ego, black_box(opp), black_box(80.0)).expect("pulse"))
    });
    g.finish();
}

criterion_group!(benches, bench_optimiser);
criterion_main!(benches);
