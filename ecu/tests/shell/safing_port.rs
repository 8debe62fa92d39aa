//! The ECU shell's safing-accelerometer port (`IceoryxIo::drain_safing`): it receives
//! the safing service's batches in order, never the crash accelerometer's, counts its receive
//! errors apart, and — a cycle-path call — neither allocates nor blocks.

use crate::alloc_counter::{allocations_here, set_counting};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use ecu::runtime::{CycleIo, IceoryxIo};
use ipc::{AccelPublisher, CrashAccelSample, SafingPublisher, ServiceNames};

#[test]
fn drain_safing_receives_its_own_service_in_order_without_allocating() {
    let names = ServiceNames::with_prefix(&format!("ecu-safing-{}", std::process::id()));
    let (node, _) = ipc::create_node("ecu-safing", false).unwrap();
    let mut io = IceoryxIo::new(&node, &names, None, Duration::from_micros(100)).unwrap();

    const BATCHES: u64 = 2_000;
    let done = Arc::new(AtomicBool::new(false));
    let feed = {
        let names = names.clone();
        let done = done.clone();
        std::thread::spawn(move || {
            let (node, _) = ipc::create_node("ecu-safing-feed", false).unwrap();
            let mut safing = SafingPublisher::new(&node, &names).unwrap();
            let mut crash = AccelPublisher::new(&node, &names).unwrap();
            for seq in 1..=BATCHES {
                // Safing: 2 samples at 2 kHz reading −seq; crash: +seq on its own service.
                safing
                    .publish_with(CrashAccelSample::EMPTY, |a| {
                        a.sequence = seq;
                        a.count = 2;
                        a.sample_period_ns = 500_000;
                        a.accel_mps2[..2].fill(-(seq as f32));
                    })
                    .unwrap();
                crash
                    .publish_with(CrashAccelSample::EMPTY, |a| {
                        a.sequence = seq;
                        a.count = 1;
                        a.accel_mps2[0] = seq as f32;
                    })
                    .unwrap();
                std::thread::sleep(Duration::from_micros(100));
            }
            done.store(true, Ordering::Relaxed);
        })
    };

    // The cycle side: drain with counting on, only around the port calls (the one-time
    // connection to the publisher excepted, see below).
    let mut seen: Vec<u64> = Vec::with_capacity(BATCHES as usize);
    let mut crash_seen = 0usize;
    let mut bad_values = 0u64;
    let mut allocations = 0;
    let deadline = Instant::now() + Duration::from_secs(30);
    loop {
        let finished = done.load(Ordering::Relaxed);
        let before = allocations_here();
        set_counting(true);
        let mut batch = [0u64; 64];
        let mut n = 0;
        io.drain_safing(&mut |a| {
            if a.samples().iter().any(|v| *v != -(a.sequence as f32)) {
                bad_values += 1;
            }
            if let Some(slot) = batch.get_mut(n) {
                *slot = a.sequence;
            }
            n += 1;
        });
        let errors = io.receive_errors();
        set_counting(false);
        // The first receive that finds the feed's publisher connects to it (iceoryx2 sets the
        // connection up, 37 allocations here, once, as for every subscriber: the other no-alloc
        // test warms its loop up for the same reason); every later drain is counted.
        if !seen.is_empty() {
            allocations += allocations_here() - before;
        }
        assert_eq!(errors.safing, 0);
        seen.extend_from_slice(&batch[..n.min(64)]);
        crash_seen += io.drain_accel(&mut |_| {});
        if finished && n == 0 {
            break;
        }
        assert!(Instant::now() < deadline, "feed did not finish");
        std::thread::sleep(Duration::from_micros(250));
    }
    feed.join().unwrap();
    io.shutdown();

    assert_eq!(allocations, 0, "drain_safing allocated on the cycle thread");
    assert_eq!(
        bad_values, 0,
        "a crash-accelerometer record came through the safing port"
    );
    // In order, nothing lost (the 64-batch queue is drained every 250 µs).
    assert_eq!(seen, (1..=BATCHES).collect::<Vec<_>>());
    assert_eq!(crash_seen, BATCHES as usize);
    assert_eq!(io.safing_counters().received, BATCHES);
    assert_eq!(io.safing_counters().errors, 0);
}
