//! The ECU restraint cycle (`restraint::RestraintCycle::step`) on three paths, set up by
//! `cycle_benches::ecu_cycle` (shared with the `icount-cycle` instruction-count binary):
//!
//! * `decision_only` — PRE-CRASH, no new input (inputs refreshed in untimed cycles): state
//!   machine, scheduled fires, cyclic command/heartbeat encode + E2E, diagnostics record.
//! * `full_precrash_worst_case` — PRE-CRASH with a NEW object sample every cycle: track
//!   filter + LUT interpolation + state machine + command encode (the hand-picked path).
//! * `crash_confirmation` — the cycle whose 8-sample accelerometer batch confirms the crash
//!   (detector + transition + fire scheduling + commands); state rebuilt outside the timing.
//! * `searched_worst_case` — the measured cycle of the committed seed of the worst-case
//!   search (`benches/worst-case/seed.json`, `worst_case::measured_step`), replayed from a
//!   clone of the prepared cycle (the clone is outside the timing).

use criterion::{criterion_group, criterion_main, BatchSize, Criterion};
use cycle_benches::ecu_cycle::{self, DecisionOnly, WorstCasePreCrash};
use cycle_benches::worst_case;
use restraint::Phase;
use std::time::{Duration, Instant};

fn bench_cycle(c: &mut Criterion) {
    let mut g = c.benchmark_group("cycle");

    let mut d = DecisionOnly::new().expect("set-up");
    g.bench_function("decision_only", |b| {
        b.iter_custom(|iters| {
            let mut total = Duration::ZERO;
            for _ in 0..iters {
                d.refresh_if_due();
                let t = Instant::now();
                d.step();
                total += t.elapsed();
            }
            total
        })
    });
    d.verify()
        .expect("decision_only measured the PRE-CRASH path");

    let mut w = WorstCasePreCrash::new().expect("set-up");
    g.bench_function("full_precrash_worst_case", |b| b.iter(|| w.step()));
    w.verify()
        .expect("full_precrash_worst_case measured the worst-case path");

    g.bench_function("crash_confirmation", |b| {
        b.iter_batched(
            || ecu_cycle::crash_confirmation_setup().expect("set-up"),
            |(mut ecu, mut io, mut clock)| {
                clock.step(&mut ecu, &mut io);
                assert!(matches!(ecu.phase(), Phase::Crash | Phase::PostCrash));
                ecu
            },
            BatchSize::LargeInput,
        )
    });
    let seed = worst_case::load_cases(&worst_case::seed_path()).expect("committed seed");
    let prepared = worst_case::prepare(seed.first().expect("one case")).expect("set-up");
    g.bench_function("searched_worst_case", |b| {
        b.iter_batched_ref(
            || prepared.clone(),
            worst_case::measured_step,
            BatchSize::SmallInput,
        )
    });
    g.finish();
}

criterion_group!(benches, bench_cycle);
criterion_main!(benches);
