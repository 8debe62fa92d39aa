//! One characteristic-diagram lookup (the ECU's per-cycle interpolation).
//!
//! Grid of the size a default table is expected to have (9 closing speeds ×
//! 12 opponent masses × 7 occupant masses × 6 seat distances = 4536 cells,
//! ~160 KB), non-uniform closing-speed axis so the binary search is real.
//! Table and queries live in `cycle_benches::workload` (shared with `icount-lut`).
//! Budget: ≤ 100 ns per query (benches/budgets.toml).

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use cycle_benches::workload::{bench_queries, bench_table};
use diagram::Query;

fn bench_lookup(c: &mut Criterion) {
    let d = bench_table();
    let view = d.view();
    let qs = bench_queries(1024);
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
