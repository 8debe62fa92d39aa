//! The restraint cycle allocates nothing in steady state: a counting global allocator over
//! ≥ 10 000 cycles in PRE-CRASH (a new object sample every 10 ms → collision prediction + LUT
//! lookup + state machine + E2E command encode; an 8-sample accelerometer batch every cycle)
//! and ≥ 10 000 cycles through the prediction-matched crash confirmation (the frozen
//! closed-form prediction, the ramp fit, the re-plan from the table), airbag fire and
//! POST-CRASH with the predicted crash pulse in 8-sample batches every cycle.
//! Both crush-zone satellites send their PSI5 frames every cycle (a crushing front end after
//! the contact: the fusion grants its relief inside the counted cycles).
//! SecOC is on (the example key file): every command frame is followed by its AES-CMAC
//! authenticator, computed inside the counted cycles.
//! The com layer of this test ([`SimIo`]) is itself allocation-free (fixed-capacity queues).

mod alloc_counter;

use alloc_counter::{allocations_here, set_counting};
#[path = "cycle/cycle_support/mod.rs"]
mod cycle_support;

use cycle_support::{MS, REFERENCE, T0};
use physics::{CombinedSpring, ExactCollision, MassClass};
use restraint::crash::ConfirmKind;
use restraint::signals::{psi5, SatelliteFrames, SatelliteSide};
use restraint::{CrashAccelSample, CycleConfig, Phase, RestraintCycle, SimIo, SimLoop, G_MPS2};

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
    let mut clock = SimLoop::new(T0, MS).with_sync_epoch_us(cycle_support::SYNC_EPOCH_US);
    let mut allocations = 0u64;
    let mut precrash_cycles = 0u64;
    let mut crash_cycles = 0u64;
    let mut predictions_before = 0;
    // Phase A: 1000 warm-up + 10 000 counted cycles in PRE-CRASH (contact always 250 ms
    // ahead, new sample every 10 ms). Phase B: contact, 10 000 counted crash cycles.
    let total = 1_000 + 10_000 + 10_010;
    let crash_from = 11_000u64;
    // The crash the objects predict (25 m/s against the conservative 1600 kg, class 3), from
    // the contact at `crash_from` on: computed outside the counted cycles.
    let spring = CombinedSpring::series(
        MassClass::new(4).unwrap().curve(),
        Some(MassClass::new(3).unwrap().curve()),
    )
    .unwrap();
    let crash = ExactCollision::solve(&physics::CollisionInput::with_defaults(
        &spring, 1785.0, 1600.0, 25.0,
    ))
    .unwrap();
    let contact_ns = T0 + crash_from * MS;
    for k in 0..total {
        let now = clock.now_ns();
        let ms = k;
        if ms < crash_from && ms.is_multiple_of(10) {
            // Contact always 250 ms ahead, and in the last 250 ms at `contact_ns`.
            let mut o = cycle_support::object(now, 25.0, 1500.0, 100.0);
            o.distance_m = (25.0 * ((contact_ns - now) as f64 * 1e-9).min(0.25)) as f32;
            io.push_object(o);
        }
        // 8 samples at 8 kHz ending at `now`: noise-like dither before the contact, the
        // predicted pulse after it.
        let mut a = CrashAccelSample::EMPTY;
        a.first_timestamp_ns = now - 7 * 125_000;
        a.sample_period_ns = 125_000;
        a.count = 8;
        for (i, s) in a.accel_mps2.iter_mut().enumerate() {
            let t = a.first_timestamp_ns + i as u64 * 125_000;
            let dither = if (k + i as u64).is_multiple_of(2) {
                0.05
            } else {
                -0.05
            };
            let pulse = if t >= contact_ns {
                crash
                    .state_at((t - contact_ns) as f64 * 1e-9)
                    .ego_accel_mps2
            } else {
                0.0
            };
            *s = (pulse + dither) as f32;
        }
        io.push_both_accel(a);
        // Both satellites: two PSI5 frames per ms, the body's deceleration before the contact
        // and a crushing front end (the body's + 60 g) after it.
        let crush_g = if now >= contact_ns { 60.0 } else { 0.0 };
        let decel_g = -f64::from(a.accel_mps2[7]) / G_MPS2 + crush_g;
        let code = psi5::encode(psi5::code_of(decel_g * G_MPS2, 240.0 * G_MPS2));
        let frames = SatelliteFrames {
            first_timestamp_ns: now - 500_000,
            sequence: k + 1,
            sample_period_ns: 500_000,
            count: 2,
            frames: [code; 8],
        };
        io.push_satellite(SatelliteSide::Left, frames);
        io.push_satellite(SatelliteSide::Right, frames);
        if ms.is_multiple_of(10) {
            io.push_can(bench.vehicle_frame(25.0));
        }
        if ms.is_multiple_of(100) {
            io.push_can(bench.occupant_frame());
        }
        if k == 1_000 {
            predictions_before = ecu.counters().predictions;
        }
        let count = k >= 1_000;
        set_counting(count);
        let before = allocations_here();
        clock.step(&mut ecu, &mut io);
        allocations += allocations_here() - before;
        set_counting(false);
        auth_tx += clock
            .sent(&io)
            .filter(|f| bus::secoc::SecOcStream::for_auth_id(f.id).is_some())
            .count() as u64;
        if count {
            match ecu.phase() {
                Phase::PreCrash => precrash_cycles += 1,
                Phase::Crash | Phase::PostCrash => crash_cycles += 1,
                _ => {}
            }
        }
    }
    assert_eq!(allocations, 0, "heap allocations in the cycle");
    assert!(
        precrash_cycles >= 10_000,
        "steady pre-crash: {precrash_cycles}"
    );
    assert!(crash_cycles >= 10_000, "crash / post-crash: {crash_cycles}");
    assert!(ecu.airbag_fired());
    assert!(
        ecu.satellites().relieved_batches > 0,
        "the satellites' relief ran"
    );
    assert!(
        matches!(ecu.crash_kind(), Some(ConfirmKind::Matched(_))),
        "the matched path ran: {:?}",
        ecu.crash_kind()
    );
    // The worst-case path really ran: a prediction per new object sample.
    assert_eq!(ecu.counters().predictions - predictions_before, 1_000);
    assert!(io.can_tx_total > 2_000);
    // Commands go out every 10 ms on two streams, each with its authenticator.
    assert!(auth_tx > 2_000, "authenticators sent: {auth_tx}");
}
