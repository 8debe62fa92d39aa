//! The restraint cycle allocates nothing in steady state: a counting global allocator over
//! ≥ 10 000 cycles in PRE-CRASH (a new object sample every 10 ms → collision prediction + LUT
//! lookup + state machine + E2E command encode) and ≥ 10 000 cycles through crash
//! confirmation, airbag fire and POST-CRASH with 8-sample accelerometer batches every cycle.
//! SecOC is on (the example key file): every command frame is followed by its AES-CMAC
//! authenticator, computed inside the counted cycles.
//! The com layer of this test ([`SimIo`]) is itself allocation-free (fixed-capacity queues).

mod alloc_counter;

use alloc_counter::{allocations_here, set_counting};
mod cycle_support;

use cycle_support::{MS, REFERENCE, T0};
use restraint::{Activity, CrashAccelSample, CycleConfig, CycleInfo, Phase, RestraintCycle, SimIo};

#[test]
fn no_allocation_in_precrash_and_crash_cycles() {
    let lut = cycle_support::test_lut();
    let (mut ecu, _) = RestraintCycle::new(
        CycleConfig::default(),
        Some(cycle_support::lut_of(&lut)),
        &REFERENCE,
    )
    .unwrap();
    let keys =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../data/secoc-keys.example.toml");
    ecu.set_secoc(Some(bus::secoc::SecOcKeys::load(&keys).unwrap().tx()));
    let mut bench = cycle_support::Bench::new(None); // only for its sealed CAN frames
    let mut io = SimIo::new();
    let mut auth_tx = 0u64;
    let mut now = T0;
    let mut allocations = 0u64;
    let mut precrash_cycles = 0u64;
    let mut crash_cycles = 0u64;
    let mut predictions_before = 0;
    // Phase A: 1000 warm-up + 10 000 counted cycles in PRE-CRASH (contact always 250 ms
    // ahead, new sample every 10 ms). Phase B: contact, 10 000 counted crash cycles.
    let total = 1_000 + 10_000 + 10_010;
    let crash_from = 11_000u64;
    for k in 0..total {
        let ms = k;
        if ms < crash_from && ms.is_multiple_of(10) {
            let mut o = cycle_support::object(now, 25.0, 1500.0, 100.0);
            o.distance_m = 6.25; // 250 ms at 25 m/s
            io.push_object(o);
        }
        if ms >= crash_from {
            let mut a = CrashAccelSample::EMPTY;
            a.first_timestamp_ns = now;
            a.sample_period_ns = 125_000;
            a.count = 8;
            a.accel_mps2 = [-150.0; 8];
            io.push_accel(a);
        }
        if ms.is_multiple_of(10) {
            io.push_can(bench.vehicle_frame(25.0));
        }
        if ms.is_multiple_of(100) {
            io.push_can(bench.occupant_frame());
        }
        let info = CycleInfo {
            cycle: k,
            slot: k,
            period_ns: MS,
            deadline_ns: now,
            now_ns: now,
            sync_time_us: cycle_support::sync_time_us(now),
            ..CycleInfo::default()
        };
        if k == 1_000 {
            predictions_before = ecu.counters().predictions;
        }
        let count = k >= 1_000;
        set_counting(count);
        let before = allocations_here();
        let sent_before = io.can_tx_total;
        ecu.step(&info, &mut io);
        allocations += allocations_here() - before;
        set_counting(false);
        auth_tx += io
            .sent_since(sent_before)
            .filter(|f| bus::secoc::SecOcStream::for_auth_id(f.id).is_some())
            .count() as u64;
        if count {
            match ecu.phase() {
                Phase::PreCrash => precrash_cycles += 1,
                Phase::Crash | Phase::PostCrash => crash_cycles += 1,
                _ => {}
            }
        }
        now += MS;
    }
    assert_eq!(allocations, 0, "heap allocations in the cycle");
    assert!(
        precrash_cycles >= 10_000,
        "steady pre-crash: {precrash_cycles}"
    );
    assert!(crash_cycles >= 10_000, "crash / post-crash: {crash_cycles}");
    assert!(ecu.airbag_fired());
    // The worst-case path really ran: a prediction per new object sample.
    assert_eq!(ecu.counters().predictions - predictions_before, 1_000);
    assert!(io.can_tx_total > 2_000);
    // Commands go out every 10 ms on two streams, each with its authenticator.
    assert!(auth_tx > 2_000, "authenticators sent: {auth_tx}");
}
