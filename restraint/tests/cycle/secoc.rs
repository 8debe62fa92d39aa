//! The cycle's authenticators carry the synchronized time it is handed
//! (`CycleInfo::sync_time_us`) as freshness, and a receiver on the same time base accepts
//! every one of them — while a pair recorded from an earlier session is rejected.

use crate::cycle_support::{sync_time_us, Bench, MS};
use bus::secoc::{SecOcConfig, SecOcError, SecOcKeys, SecOcStream, SecOcVerifier};
use bus::RawFrame;

fn keys() -> SecOcKeys {
    let p =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../data/secoc-keys.example.toml");
    SecOcKeys::load(&p).expect("example keys")
}

/// A monitoring ECU run for `ms`; returns the frames it sent with their send time.
fn session(keys: &SecOcKeys, start_ns: u64, ms: u64) -> Vec<(u64, RawFrame)> {
    let mut b = Bench::new(Some(crate::cycle_support::test_lut()));
    b.now = start_ns;
    b.ecu.set_secoc(Some(keys.tx()));
    b.run_ms(ms);
    b.sent
        .iter()
        .map(|(t, f)| (*t, RawFrame::new(f.id, f.payload())))
        .collect()
}

#[test]
fn every_authenticator_carries_the_cycle_time_and_verifies() {
    let keys = keys();
    let frames = session(&keys, crate::cycle_support::T0, 500);
    let mut rx = SecOcStream::ALL.map(|s| keys.verifier(s, SecOcConfig::default()));
    let mut accepted = 0;
    for (t_ns, f) in &frames {
        // Received 300 µs after sending, on the same time base.
        let now_us = t_ns / 1_000 + 300;
        let sync = sync_time_us(*t_ns) + 300;
        for v in &mut rx {
            if f.id == v.stream().command_id() {
                v.hold_command(f.payload(), now_us).unwrap();
            } else if f.id == v.stream().auth_id() {
                let ok = v.verify_auth(f.payload(), now_us, sync).unwrap();
                assert_eq!(ok.freshness, sync_time_us(*t_ns), "freshness = cycle time");
                accepted += 1;
            }
        }
    }
    // Both streams send every 10 ms (and on change) in 500 ms.
    assert!(accepted >= 100, "authenticated commands: {accepted}");
    assert_eq!(
        rx.iter().map(|v| v.stats().rejected_total()).sum::<u64>(),
        0
    );
}

#[test]
fn authenticators_of_an_earlier_ecu_session_are_rejected() {
    let keys = keys();
    // Session 1 recorded; session 2 starts 3 s later (bench: next scenario) with a new ECU.
    let recorded = session(&keys, crate::cycle_support::T0, 50);
    let later_ns = crate::cycle_support::T0 + 3_000 * MS;
    let live = session(&keys, later_ns, 50);
    let mut rx: SecOcVerifier = keys.verifier(SecOcStream::AirbagStage, SecOcConfig::default());
    let stream = SecOcStream::AirbagStage;
    let mut live_ok = 0;
    for (t_ns, f) in &live {
        let sync = sync_time_us(*t_ns) + 300;
        if f.id == stream.command_id() {
            rx.hold_command(f.payload(), t_ns / 1_000).unwrap();
        } else if f.id == stream.auth_id() {
            rx.verify_auth(f.payload(), t_ns / 1_000 + 300, sync)
                .unwrap();
            live_ok += 1;
        }
    }
    assert!(live_ok >= 5);
    // The recording replayed now: every pair stale.
    let now_ns = later_ns + 60 * MS;
    let mut replayed = 0;
    for (_, f) in &recorded {
        if f.id == stream.command_id() {
            rx.hold_command(f.payload(), now_ns / 1_000).unwrap();
        } else if f.id == stream.auth_id() {
            let r = rx.verify_auth(f.payload(), now_ns / 1_000, sync_time_us(now_ns));
            assert!(matches!(r, Err(SecOcError::FreshnessStale { .. })), "{r:?}");
            replayed += 1;
        }
    }
    assert!(replayed >= 5);
    assert_eq!(rx.stats().accepted, live_ok);
}
