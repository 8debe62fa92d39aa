//! One characteristic-diagram lookup (the ECU's per-cycle interpolation).
//!
//! Grid of the size a default table is expected to have (9 closing speeds ×
//! 12 opponent masses × 7 occupant masses × 6 seat distances = 4536 cells,
//! ~160 KB), non-uniform closing-speed axis so the binary search is real.
//! Budget: ≤ 100 ns per query (issue 3).

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use diagram::{AirbagThresholds, Axes, BuildInfo, Cell, Diagram, EgoVehicle, Header, Query};

fn table() -> Diagram {
    let header = Header {
        ego: EgoVehicle {
            mass_kg: 1785.0,
            class: 4,
            description: "bench".into(),
        },
        build: BuildInfo::default(),
        airbag_thresholds: AirbagThresholds::DEFAULT,
    };
    let axes = Axes::new(
        vec![40.0, 48.0, 56.0, 64.0, 72.0, 80.0, 90.0, 100.0, 108.0],
        (0..12).map(|i| 800.0 + 200.0 * i as f32).collect(),
        vec![30.0, 45.0, 60.0, 75.0, 90.0, 105.0, 125.0],
        vec![200.0, 250.0, 300.0, 350.0, 400.0, 450.0],
    );
    Diagram::from_fn(header, axes, |p| {
        let s = p.query.closing_speed_kph / 108.0;
        Cell {
            belt_limiter_kn: 2.0 + 8.0 * s,
            airbag_level_kn: if s < 0.4 { 0.0 } else { 12.0 * s },
            pretensioner_time_ms: -50.0 * s,
            airbag_time_ms: 5.0 + 10.0 * (1.0 - s),
            a_max_g: 40.0 * s,
            a_mean_g: 20.0 * s,
            excursion_mm: p.query.seat_distance_mm * 0.6,
            bottoming_out: if s > 0.95 && p.query.opponent_mass_kg > 2500.0 {
                1.0
            } else {
                0.0
            },
            a_ideal_g: 15.0 * s,
        }
    })
    .expect("bench table is valid")
}

/// Deterministic spread of queries over (and slightly beyond) the axes.
fn queries(n: usize) -> Vec<Query> {
    let mut state = 0x2545_F491_4F6C_DD1Du64;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 40) as f32 / (1u64 << 24) as f32
    };
    (0..n)
        .map(|_| Query {
            closing_speed_kph: 35.0 + 80.0 * next(),
            opponent_mass_kg: 700.0 + 2400.0 * next(),
            occupant_mass_kg: 25.0 + 105.0 * next(),
            seat_distance_mm: 190.0 + 270.0 * next(),
        })
        .collect()
}

fn bench_lookup(c: &mut Criterion) {
    let d = table();
    let view = d.view();
    let qs = queries(1024);
    let mut group = c.benchmark_group("diagram");
    group.throughput(Throughput::Elements(1));
    let mut i = 0usize;
    group.bench_function("lookup_varied", |b| {
        b.iter(|| {
            i = (i + 1) & 1023;
            view.lookup(black_box(&qs[i]))
        })
    });
    let fixed = Query {
        closing_speed_kph: 77.0,
        opponent_mass_kg: 1785.0,
        occupant_mass_kg: 80.0,
        seat_distance_mm: 310.0,
    };
    group.bench_function("lookup_fixed", |b| {
        b.iter(|| view.lookup(black_box(&fixed)))
    });
    group.finish();
}

criterion_group!(benches, bench_lookup);
criterion_main!(benches);
