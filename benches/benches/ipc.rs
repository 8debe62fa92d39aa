//! iceoryx2 cost of one ECU cycle's I/O: receive the samples that arrive in one 1 ms cycle
//! (one object state, one accelerometer batch) and publish one diagnostics record
//! (loan uninitialised shared memory → write in place → send), plus the feed side.

use criterion::{criterion_group, criterion_main, Criterion};
use ipc::{
    AccelPublisher, AccelSubscriber, CrashAccelSample, DiagnosticsPublisher, DiagnosticsSubscriber,
    EcuDiagnostics, ObjectPublisher, ObjectState, ObjectSubscriber, ServiceNames, VALID,
};
use std::hint::black_box;

fn ipc_cycle(c: &mut Criterion) {
    let names = ServiceNames::with_prefix(&format!("bench-ipc-{}", std::process::id()));
    let (node, _) = ipc::create_node("bench-ipc", false).expect("node");
    let mut obj_pub = ObjectPublisher::new(&node, &names).expect("object publisher");
    let mut acc_pub = AccelPublisher::new(&node, &names).expect("accel publisher");
    let mut obj_sub = ObjectSubscriber::new(&node, &names).expect("object subscriber");
    let mut acc_sub = AccelSubscriber::new(&node, &names).expect("accel subscriber");
    let mut diag_pub = DiagnosticsPublisher::new(&node, &names).expect("diag publisher");
    let mut diag_sub = DiagnosticsSubscriber::new(&node, &names).expect("diag subscriber");

    let mut seq = 0u64;
    let mut feed = |obj_pub: &mut ObjectPublisher, acc_pub: &mut AccelPublisher| {
        seq += 1;
        let _ = obj_pub.publish_with(ObjectState::INVALID, |o| {
            o.sequence = seq;
            o.distance_m = 12.5;
            o.closing_speed_mps = 14.0;
            o.valid = VALID;
        });
        let _ = acc_pub.publish_with(CrashAccelSample::EMPTY, |a| {
            a.sequence = seq;
            a.count = 8;
        });
    };

    c.bench_function("ipc/feed_publish_object_and_accel", |b| {
        b.iter(|| {
            feed(&mut obj_pub, &mut acc_pub);
            // Keep the subscriber queues from saturating.
            obj_sub.drain(|_| {});
            acc_sub.drain(|_| {});
        })
    });

    c.bench_function("ipc/ecu_receive_cycle_inputs", |b| {
        b.iter_batched(
            || feed(&mut obj_pub, &mut acc_pub),
            |()| {
                let mut sum = 0.0f32;
                obj_sub.drain(|o| sum += o.distance_m);
                acc_sub.drain(|a| sum += a.samples().iter().sum::<f32>());
                black_box(sum)
            },
            criterion::BatchSize::SmallInput,
        )
    });

    c.bench_function("ipc/ecu_publish_diagnostics_loan_write_send", |b| {
        let mut cycle = 0u64;
        b.iter(|| {
            cycle += 1;
            let _ = diag_pub.publish_with(EcuDiagnostics::ZERO, |d| {
                d.cycle_count = cycle;
                d.pulse_points = 64;
                for (i, p) in d.pulse_accel_mps2.iter_mut().enumerate() {
                    *p = -(i as f32);
                }
            });
            diag_sub.drain(|d| {
                black_box(d.cycle_count);
            });
        })
    });

    c.bench_function("ipc/ecu_receive_inputs_and_publish_diagnostics", |b| {
        let mut cycle = 0u64;
        b.iter_batched(
            || feed(&mut obj_pub, &mut acc_pub),
            |()| {
                cycle += 1;
                let mut last = 0u64;
                obj_sub.drain(|o| last = o.sequence);
                acc_sub.drain(|a| last = last.max(a.sequence));
                let _ = diag_pub.publish_with(EcuDiagnostics::ZERO, |d| {
                    d.cycle_count = cycle;
                    d.last_object_sequence = last;
                });
                diag_sub.drain(|_| {});
            },
            criterion::BatchSize::SmallInput,
        )
    });
}

criterion_group!(benches, ipc_cycle);
criterion_main!(benches);
