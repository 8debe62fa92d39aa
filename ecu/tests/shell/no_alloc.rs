//! Allocation discipline: the steady-state loop (iceoryx2 receive + zero-copy publish,
//! histogram recording, deadline arithmetic, absolute sleep) performs no heap allocation.
//!
//! A counting global allocator counts allocations made *on the ECU cycle thread* while
//! the flag is on; a feed thread keeps publishing inputs and reading diagnostics so the
//! loop really receives every cycle and its diagnostics really reach a subscriber (via
//! the companion publisher thread, see `runtime::com`).

use crate::alloc_counter::{allocations_here, set_counting};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

use crate::support;

use ecu::runtime::{
    run_activity, Activity, CycleInfo, CycleIo, IceoryxIo, LoopConfig, LoopStats, MonotonicClock,
};
use ipc::{
    AccelPublisher, CrashAccelSample, DiagnosticsSubscriber, ObjectPublisher, ObjectState,
    ServiceNames, VALID,
};
use restraint::StartupError;
use support::passthrough::PassthroughActivity;

const WARMUP_CYCLES: u64 = 1_000;
const MEASURED_CYCLES: u64 = 10_000;

/// Wraps the pass-through activity and switches counting on after warm-up.
struct Counted {
    inner: PassthroughActivity,
    objects_at_start: u64,
    accel_at_start: u64,
    /// `CycleInfo::sync_time_us` of the last cycle (read from CLOCK_REALTIME inside the
    /// counted loop).
    last_sync_time_us: u64,
}

impl Activity for Counted {
    fn name(&self) -> &'static str {
        "counted"
    }
    fn startup(&mut self, now_ns: u64, io: &mut dyn CycleIo) -> Result<(), StartupError> {
        self.inner.startup(now_ns, io)
    }
    fn step(&mut self, info: &CycleInfo, io: &mut dyn CycleIo) {
        if info.cycle == WARMUP_CYCLES {
            self.objects_at_start = self.inner.objects_rx();
            self.accel_at_start = self.inner.accel_batches_rx();
            set_counting(true);
        }
        self.last_sync_time_us = info.sync_time_us;
        self.inner.step(info, io);
    }
    fn shutdown(&mut self, now_ns: u64, io: &mut dyn CycleIo) {
        set_counting(false);
        self.inner.shutdown(now_ns, io);
    }
}

#[test]
fn steady_state_loop_with_iceoryx2_allocates_nothing() {
    let names = ServiceNames::with_prefix(&format!("ecu-noalloc-{}", std::process::id()));
    let (node, _) = ipc::create_node("ecu-noalloc", false).unwrap();
    let mut io = IceoryxIo::new(&node, &names, None, Duration::from_micros(100)).unwrap();

    // Feed thread: object state every ~1 ms, accel batch every ~250 µs, diagnostics drained.
    let done = Arc::new(AtomicBool::new(false));
    let feed = {
        let names = names.clone();
        let done = done.clone();
        std::thread::spawn(move || {
            let (node, _) = ipc::create_node("ecu-noalloc-feed", false).unwrap();
            let mut objects = ObjectPublisher::new(&node, &names).unwrap();
            let mut accel = AccelPublisher::new(&node, &names).unwrap();
            let mut diag = DiagnosticsSubscriber::new(&node, &names).unwrap();
            let mut seq = 0u64;
            let mut diag_seen = 0usize;
            while !done.load(Ordering::Relaxed) {
                seq += 1;
                accel
                    .publish_with(CrashAccelSample::EMPTY, |a| {
                        a.sequence = seq;
                        a.count = 8;
                        a.sample_period_ns = 125_000;
                        a.accel_mps2 = [-9.81; 8];
                    })
                    .unwrap();
                if seq.is_multiple_of(4) {
                    objects
                        .publish_with(ObjectState::INVALID, |o| {
                            o.sequence = seq / 4;
                            o.distance_m = 20.0;
                            o.closing_speed_mps = 15.0;
                            o.valid = VALID;
                        })
                        .unwrap();
                }
                diag_seen += diag.drain(|_| {});
                std::thread::sleep(Duration::from_micros(250));
            }
            diag_seen
        })
    };

    let mut activity = Counted {
        inner: PassthroughActivity::new(),
        objects_at_start: 0,
        accel_at_start: 0,
        last_sync_time_us: 0,
    };
    let mut stats = LoopStats::default();
    run_activity(
        &mut MonotonicClock,
        &mut activity,
        &mut io,
        &LoopConfig {
            period_ns: 100_000,
            max_cycles: Some(WARMUP_CYCLES + MEASURED_CYCLES),
        },
        &AtomicBool::new(false),
        &mut stats,
    )
    .unwrap();
    let allocations = allocations_here();
    io.shutdown();
    done.store(true, Ordering::Relaxed);
    let diag_seen = feed.join().unwrap();

    assert_eq!(stats.cycles, WARMUP_CYCLES + MEASURED_CYCLES);
    // The measured window really exercised receive and publish.
    assert!(activity.inner.objects_rx() > activity.objects_at_start);
    assert!(activity.inner.accel_batches_rx() > activity.accel_at_start);
    assert!(io.diagnostics_written() >= MEASURED_CYCLES);
    assert!(io.diagnostics_counters().sent > 0);
    assert!(diag_seen > 0);
    let wall_us = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .unwrap()
        .as_micros() as u64;
    assert!(
        wall_us.abs_diff(activity.last_sync_time_us) < 10_000_000,
        "sync time {} vs wall clock {wall_us}",
        activity.last_sync_time_us
    );
    assert_eq!(
        allocations, 0,
        "{allocations} heap allocations in {MEASURED_CYCLES} steady-state cycles"
    );
}

#[test]
fn counting_allocator_detects_allocations() {
    // Guards the guard: the counter must see an allocation on a counted thread.
    std::thread::spawn(|| {
        set_counting(true);
        let before = allocations_here();
        let v = std::hint::black_box(vec![1u8; 64]);
        let after = allocations_here();
        set_counting(false);
        drop(v);
        assert!(after > before);
    })
    .join()
    .unwrap();
}
