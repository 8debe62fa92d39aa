//! CAN frame cost of one ECU cycle: receive-check + decode of all input frames of a worst-case
//! cycle (`EgoVehicleState` and `OccupantClassification` arriving together; id, DLC, CRC-8,
//! alive counter, DBC ranges, raw → physical) and encode + E2E seal of the cycle's three output
//! frames (`AirbagStageCmd`, `BeltLimiterCmd`, `EcuStatus`). Budgets: benches/budgets.toml.

use criterion::{criterion_group, criterion_main, Criterion};
use cycle_benches::workload::{CommandEncoder, Commands, CycleInputFrames};
use std::hint::black_box;

fn bench_frames(c: &mut Criterion) {
    let mut inputs = CycleInputFrames::new().expect("bench frames are in range");
    c.bench_function("frames/decode_cycle_inputs", |b| {
        b.iter(|| black_box(inputs.decode_next()))
    });

    let mut enc = CommandEncoder::new();
    let mut out = [bus::RawFrame::new(0, &[]); 3];
    c.bench_function("frames/encode_cycle_commands", |b| {
        b.iter(|| {
            let r = enc.encode(black_box(&Commands::FIRE), &mut out);
            black_box((r.is_ok(), &out));
        })
    });
}

criterion_group!(benches, bench_frames);
criterion_main!(benches);
