//! SecOC tests. Oracles independent of the code under test: the published RFC 4493 AES-CMAC
//! vectors (typed from the RFC), a preimage assembled byte by byte here from the documented
//! layout, and a bit-by-bit Intel extractor of the authenticator fields.

use bus::codec::{
    AirbagStageCmdArm, AirbagStageCmdCmdSource, AirbagStageCmdFire, AirbagStageCmdStage,
};
use bus::codec::{BeltLimiterCmdCmdSource, BeltLimiterCmdPretensionerCmd};
use bus::secoc::{
    aes128_cmac, SecOcConfig, SecOcError, SecOcKey, SecOcReject, SecOcSender, SecOcStream, SecOcTx,
    SecOcVerifier, FRESHNESS_TX_MASK,
};
use bus::{decode, AirbagStageCmd, BeltLimiterCmd, E2eProtector, Messages, RawFrame};

fn hex(s: &str) -> Vec<u8> {
    let s: String = s.chars().filter(|c| !c.is_whitespace()).collect();
    (0..s.len())
        .step_by(2)
        .map(|i| u8::from_str_radix(&s[i..i + 2], 16).unwrap())
        .collect()
}

fn key(s: &str) -> SecOcKey {
    SecOcKey::from_hex(s).unwrap()
}

const K_AIRBAG: &str = "0686aa35a35e8753147788e1923f8dfd";
const K_BELT: &str = "e199ff01308b254c1a3d3b81d1300395";

/// RFC 4493 section 4, "Test Vectors", AES-128 key and examples 1-4.
#[test]
fn rfc4493_vectors() {
    let k = key("2b7e1516 28aed2a6 abf71588 09cf4f3c");
    let m = hex(
        "6bc1bee2 2e409f96 e93d7e11 7393172a ae2d8a57 1e03ac9c 9eb76fac 45af8e51
         30c81c46 a35ce411 e5fbc119 1a0a52ef f69f2445 df4f9b17 ad2b417b e66c3710",
    );
    let cases: [(usize, &str); 4] = [
        (0, "bb1d6929 e9593728 7fa37d12 9b756746"),
        (16, "070a16b4 6b4d4144 f79bdd9d d04a287c"),
        (40, "dfa66747 de9ae630 30ca3261 1497c827"),
        (64, "51f0bebf 7e3b9d92 fc497417 79363cfe"),
    ];
    for (len, tag) in cases {
        assert_eq!(
            aes128_cmac(&k, &m[..len]).to_vec(),
            hex(tag),
            "Mlen = {len}"
        );
    }
}

fn airbag_fire(tx: &mut E2eProtector) -> RawFrame {
    tx.seal(
        AirbagStageCmd::encode(
            AirbagStageCmdArm::Armed,
            AirbagStageCmdFire::Fire,
            AirbagStageCmdCmdSource::Adaptive,
            AirbagStageCmdStage::Stage1,
            6.5,
            12.0,
        )
        .unwrap(),
    )
}

fn belt_fire(tx: &mut E2eProtector) -> RawFrame {
    tx.seal(
        BeltLimiterCmd::encode(
            BeltLimiterCmdPretensionerCmd::Fire,
            BeltLimiterCmdCmdSource::Adaptive,
            4.0,
            -20.0,
        )
        .unwrap(),
    )
}

/// Intel (little-endian bit numbering) field extractor: bit i of the frame is bit i%8 of byte i/8.
fn intel_field(data: &[u8; 8], start: u32, size: u32) -> u64 {
    (0..size).fold(0u64, |acc, i| {
        let bit = start + i;
        let b = u64::from((data[(bit / 8) as usize] >> (bit % 8)) & 1);
        acc | (b << i)
    })
}

fn verifier(stream: SecOcStream, k: &str) -> SecOcVerifier {
    SecOcVerifier::new(stream, &key(k), SecOcConfig::default())
}

/// A synchronized time (µs since the UNIX epoch, 2025-06-15): where the bench's CLOCK_REALTIME
/// would be.
const T0: u64 = 1_750_000_000_000_000;
/// 2^24 µs, the span of the transmitted freshness bits (typed here, not taken from the crate).
const SPAN: u64 = 16_777_216;
const MS: u64 = 1_000;
const S: u64 = 1_000_000;

#[test]
fn authenticator_layout_is_the_documented_one() {
    let mut e2e = E2eProtector::new();
    let cmd = airbag_fire(&mut e2e);
    let mut s = SecOcSender::new(SecOcStream::AirbagStage, &key(K_AIRBAG));
    assert_eq!(s.last_freshness(), 0);
    // The freshness value is the synchronized time handed in.
    let auth = s.authenticate(&cmd, 0x0123_4567_89AB_CDEF).unwrap();
    assert_eq!(auth.id, 0x031);
    assert_eq!(auth.len, 8);
    // preimage: data id 0x1330 BE, CAN id 0x030 BE, 8 payload bytes, freshness u64 BE.
    let mut pre = vec![0x13, 0x30, 0x00, 0x30];
    pre.extend_from_slice(&cmd.data);
    pre.extend_from_slice(&[0x01, 0x23, 0x45, 0x67, 0x89, 0xAB, 0xCD, 0xEF]);
    let tag = aes128_cmac(&key(K_AIRBAG), &pre);
    let mac_expected = tag[..5].iter().fold(0u64, |a, b| (a << 8) | u64::from(*b));
    assert_eq!(intel_field(&auth.data, 0, 24), 0xAB_CDEF);
    assert_eq!(intel_field(&auth.data, 24, 40), mac_expected);
    assert_eq!(s.last_freshness(), 0x0123_4567_89AB_CDEF);
}

#[test]
fn genuine_pairs_verify_for_both_streams() {
    let mut e2e = E2eProtector::new();
    let mut tx = SecOcTx::new(&key(K_AIRBAG), &key(K_BELT));
    let mut rx_a = verifier(SecOcStream::AirbagStage, K_AIRBAG);
    let mut rx_b = verifier(SecOcStream::BeltLimiter, K_BELT);
    for i in 0..50u64 {
        // Monotonic receive time (arbitrary epoch) and synchronized time advance together.
        let t = i * 10_000;
        let sync = T0 + t;
        let a = airbag_fire(&mut e2e);
        let a_auth = tx.authenticate(&a, sync).unwrap();
        let b = belt_fire(&mut e2e);
        let b_auth = tx.authenticate(&b, sync).unwrap();
        assert_eq!(rx_a.on_frame(a.id, a.payload(), t, sync + 120), Ok(None));
        let ok = rx_a
            .on_frame(a_auth.id, a_auth.payload(), t + 150, sync + 150)
            .unwrap()
            .unwrap();
        assert_eq!(ok.payload, a.data);
        assert_eq!(ok.freshness, sync, "freshness = the sender's time stamp");
        assert_eq!(ok.pairing_delay_us, 150);
        assert!(matches!(
            decode(0x030, &ok.payload),
            Ok(Messages::AirbagStageCmd(_))
        ));
        rx_b.hold_command(b.payload(), t).unwrap();
        let ok = rx_b
            .verify_auth(b_auth.payload(), t + 10_000, sync + 10_000)
            .unwrap();
        assert_eq!(ok.payload, b.data);
        assert_eq!(ok.freshness, sync);
    }
    assert_eq!(rx_a.stats().accepted, 50);
    assert_eq!(rx_a.stats().rejected_total(), 0);
    assert_eq!(rx_b.stats().accepted, 50);
    // Streams are separated: a belt authenticator never authenticates an airbag command.
    let sync = T0 + S;
    let a = airbag_fire(&mut e2e);
    let b_auth = tx.authenticate(&belt_fire(&mut e2e), sync).unwrap();
    rx_a.hold_command(a.payload(), 0).unwrap();
    assert!(rx_a.verify_auth(b_auth.payload(), 0, sync).is_err());
    assert!(matches!(
        rx_a.on_frame(0x041, b_auth.payload(), 0, sync),
        Err(SecOcError::WrongId(0x041))
    ));
    assert!(matches!(
        tx.authenticate(&RawFrame::new(0x0A0, &[0; 8]), sync),
        Err(SecOcError::WrongId(0x0A0))
    ));
}

#[test]
fn every_single_bit_flip_is_rejected() {
    let mut e2e = E2eProtector::new();
    let mut s = SecOcSender::new(SecOcStream::AirbagStage, &key(K_AIRBAG));
    let cmd = airbag_fire(&mut e2e);
    let auth = s.authenticate(&cmd, T0).unwrap();
    let fresh = verifier(SecOcStream::AirbagStage, K_AIRBAG);
    let mut rejected = 0;
    for bit in 0..64 {
        let mut c = cmd.data;
        c[bit / 8] ^= 1 << (bit % 8);
        let mut rx = fresh.clone();
        rx.hold_command(&c, 0).unwrap();
        let r = rx.verify_auth(auth.payload(), 1, T0 + 1);
        assert_eq!(r, Err(SecOcError::MacMismatch), "command bit {bit}");
        rejected += 1;

        let mut a = auth.data;
        a[bit / 8] ^= 1 << (bit % 8);
        let mut rx = fresh.clone();
        rx.hold_command(cmd.payload(), 0).unwrap();
        let r = rx.verify_auth(&a, 1, T0 + 1);
        assert!(r.is_err(), "auth bit {bit}: {r:?}");
        assert_eq!(rx.stats().accepted, 0);
        // The command is still held: the genuine authenticator after a forged one still works.
        assert_eq!(
            rx.verify_auth(auth.payload(), 2, T0 + 2).unwrap().payload,
            cmd.data
        );
        rejected += 1;
    }
    assert_eq!(rejected, 128);
}

#[test]
fn replays_within_the_window_are_rejected_and_named() {
    let mut e2e = E2eProtector::new();
    let mut s = SecOcSender::new(SecOcStream::AirbagStage, &key(K_AIRBAG));
    let mut rx = verifier(SecOcStream::AirbagStage, K_AIRBAG);
    // Five genuine pairs 10 ms apart, each accepted 200 µs after it was sent.
    let pairs: Vec<(RawFrame, RawFrame, u64)> = (0..5)
        .map(|i| {
            let sync = T0 + i * 10 * MS;
            let c = airbag_fire(&mut e2e);
            let a = s.authenticate(&c, sync).unwrap();
            (c, a, sync)
        })
        .collect();
    for (c, a, sync) in &pairs {
        rx.hold_command(c.payload(), 0).unwrap();
        assert_eq!(
            rx.verify_auth(a.payload(), 0, sync + 200)
                .unwrap()
                .freshness,
            *sync
        );
    }
    // Replayed 10 ms after the last one: all inside the 100-ms window, all already used.
    let replay_at = T0 + 50 * MS;
    for (c, a, sync) in &pairs {
        rx.hold_command(c.payload(), 100).unwrap();
        assert_eq!(
            rx.verify_auth(a.payload(), 100, replay_at),
            Err(SecOcError::Replay { freshness: *sync })
        );
    }
    // The authenticator alone, replayed right after its command was consumed.
    assert_eq!(
        rx.verify_auth(pairs[4].1.payload(), 100, replay_at),
        Err(SecOcError::Replay {
            freshness: pairs[4].2
        })
    );
    rx.expire(1_000_000);
    assert_eq!(
        rx.verify_auth(pairs[4].1.payload(), 1_000_000, replay_at),
        Err(SecOcError::NoPendingCommand)
    );
    // A second after the original, the same pair is no longer a replay in the window: stale.
    rx.hold_command(pairs[4].0.payload(), 2_000_000).unwrap();
    assert_eq!(
        rx.verify_auth(pairs[4].1.payload(), 2_000_000, pairs[4].2 + S),
        Err(SecOcError::FreshnessStale {
            freshness: pairs[4].2,
            sync_now_us: pairs[4].2 + S
        })
    );
    assert_eq!(rx.stats().rejected_for(SecOcReject::Replay), 6);
    assert_eq!(rx.stats().rejected_for(SecOcReject::NoPendingCommand), 1);
    assert_eq!(rx.stats().rejected_for(SecOcReject::FreshnessStale), 1);
    assert_eq!(rx.last_accepted(), T0 + 40 * MS);
}

#[test]
fn wrong_key_is_rejected() {
    let mut e2e = E2eProtector::new();
    let mut s = SecOcSender::new(SecOcStream::AirbagStage, &key(K_BELT));
    let mut rx = verifier(SecOcStream::AirbagStage, K_AIRBAG);
    for i in 0..20 {
        let sync = T0 + i * 10 * MS;
        let c = airbag_fire(&mut e2e);
        let a = s.authenticate(&c, sync).unwrap();
        rx.hold_command(c.payload(), 0).unwrap();
        assert_eq!(
            rx.verify_auth(a.payload(), 0, sync),
            Err(SecOcError::MacMismatch)
        );
    }
    assert_eq!(rx.stats().rejected_for(SecOcReject::MacMismatch), 20);
    assert_eq!(rx.stats().accepted, 0);
}

/// One genuine pair authenticated at the sender's `sender_sync`, checked by a new receiver at
/// its `receiver_sync`.
fn check_at(cfg: SecOcConfig, sender_sync: u64, receiver_sync: u64) -> Result<u64, SecOcError> {
    let mut e2e = E2eProtector::new();
    let mut s = SecOcSender::new(SecOcStream::AirbagStage, &key(K_AIRBAG));
    let mut rx = SecOcVerifier::new(SecOcStream::AirbagStage, &key(K_AIRBAG), cfg);
    let c = airbag_fire(&mut e2e);
    let a = s.authenticate(&c, sender_sync).unwrap();
    rx.hold_command(c.payload(), 0).unwrap();
    rx.verify_auth(a.payload(), 0, receiver_sync)
        .map(|ok| ok.freshness)
}

#[test]
fn freshness_window_around_the_receivers_clock() {
    let cfg = SecOcConfig::default();
    assert_eq!(cfg.freshness_window_us, 100_000);
    // Sender clock ahead of / behind the receiver's by 50 ms: accepted, by 150 ms: stale.
    for off in [50 * MS, 100 * MS] {
        assert_eq!(check_at(cfg, T0 + off, T0), Ok(T0 + off));
        assert_eq!(check_at(cfg, T0 - off, T0), Ok(T0 - off));
    }
    for off in [100 * MS + 1, 150 * MS, 4 * S] {
        for sender in [T0 + off, T0 - off] {
            assert_eq!(
                check_at(cfg, sender, T0),
                Err(SecOcError::FreshnessStale {
                    freshness: sender,
                    sync_now_us: T0
                }),
                "offset {off} us"
            );
        }
    }
    // A window wider than half the transmitted span is clamped to 2^23 - 1 µs: everything
    // accepted is reconstructed unambiguously.
    let wide = SecOcConfig {
        freshness_window_us: u64::MAX,
        ..cfg
    };
    let rx = SecOcVerifier::new(SecOcStream::AirbagStage, &key(K_AIRBAG), wide);
    assert_eq!(rx.config().freshness_window_us, SPAN / 2 - 1);
    assert_eq!(check_at(wide, T0 + 8_300 * MS, T0), Ok(T0 + 8_300 * MS));
    assert_eq!(check_at(wide, T0 - 8_300 * MS, T0), Ok(T0 - 8_300 * MS));
    // Beyond 2^23 µs ≈ 8.39 s the 24 bits reconstruct to the neighbouring span: the MAC fails
    // there, the neighbour check finds the genuine value and names it stale.
    for sender in [T0 + 8_500 * MS, T0 - 8_500 * MS, T0 + 20 * S, T0 - 20 * S] {
        assert_eq!(
            check_at(wide, sender, T0),
            Err(SecOcError::FreshnessStale {
                freshness: sender,
                sync_now_us: T0
            })
        );
    }
    // More than ~25 s away it cannot be told from a forgery (upper bits not transmitted).
    assert_eq!(check_at(cfg, T0 - 60 * S, T0), Err(SecOcError::MacMismatch));
}

#[test]
fn wrap_of_the_transmitted_24_bits() {
    let cfg = SecOcConfig::default();
    // A multiple of 2^24 µs near T0; sender and receiver on either side of it.
    let edge = (T0 / SPAN + 1) * SPAN;
    for (sender, receiver) in [
        (edge - 20, edge + 30),
        (edge + 20, edge - 30),
        (edge - 40 * MS, edge + 40 * MS),
        (edge + 40 * MS, edge - 40 * MS),
        (edge, edge - 1),
        (edge - 1, edge),
    ] {
        assert_eq!(check_at(cfg, sender, receiver), Ok(sender));
    }
    // A continuous session across the edge.
    let mut e2e = E2eProtector::new();
    let mut s = SecOcSender::new(SecOcStream::AirbagStage, &key(K_AIRBAG));
    let mut rx = verifier(SecOcStream::AirbagStage, K_AIRBAG);
    for i in 0..20u64 {
        let sync = edge - 100 * MS + i * 10 * MS;
        let c = airbag_fire(&mut e2e);
        let a = s.authenticate(&c, sync).unwrap();
        assert_eq!(intel_field(&a.data, 0, 24), sync % SPAN);
        rx.hold_command(c.payload(), 0).unwrap();
        assert_eq!(
            rx.verify_auth(a.payload(), 0, sync + 300)
                .unwrap()
                .freshness,
            sync
        );
    }
    assert_eq!(rx.stats().accepted, 20);
}

#[test]
fn sender_clock_stepping_back_keeps_freshness_increasing() {
    let mut e2e = E2eProtector::new();
    let mut s = SecOcSender::new(SecOcStream::AirbagStage, &key(K_AIRBAG));
    let mut rx = verifier(SecOcStream::AirbagStage, K_AIRBAG);
    // The shared clock reads: forward, two frames in one µs, then a 30-ms step back.
    let clock = [
        T0,
        T0 + 10 * MS,
        T0 + 10 * MS,
        T0 - 20 * MS,
        T0 - 10 * MS,
        T0,
        T0 + 10 * MS + 5,
        T0 + 20 * MS,
    ];
    let expected = [
        T0,
        T0 + 10 * MS,
        T0 + 10 * MS + 1,
        T0 + 10 * MS + 2,
        T0 + 10 * MS + 3,
        T0 + 10 * MS + 4,
        T0 + 10 * MS + 5,
        T0 + 20 * MS,
    ];
    for (now, want) in clock.iter().zip(expected) {
        let c = airbag_fire(&mut e2e);
        let a = s.authenticate(&c, *now).unwrap();
        assert_eq!(s.last_freshness(), want);
        rx.hold_command(c.payload(), 0).unwrap();
        // Same machine: the receiver's clock stepped back too (+ 200 µs bus latency).
        assert_eq!(
            rx.verify_auth(a.payload(), 0, now + 200).unwrap().freshness,
            want
        );
    }
    // A step back larger than the window: the sender's values run ahead of the clock and
    // are stale until it has caught up (documented limit).
    let c = airbag_fire(&mut e2e);
    let a = s.authenticate(&c, T0 - S).unwrap();
    assert_eq!(s.last_freshness(), T0 + 20 * MS + 1);
    rx.hold_command(c.payload(), 0).unwrap();
    assert!(matches!(
        rx.verify_auth(a.payload(), 0, T0 - S + 200),
        Err(SecOcError::FreshnessStale { .. })
    ));
    // End of the 64-bit space: the last value is usable once, then the sender refuses.
    let mut s = SecOcSender::new(SecOcStream::AirbagStage, &key(K_AIRBAG));
    let c = airbag_fire(&mut e2e);
    let a = s.authenticate(&c, u64::MAX).unwrap();
    let mut rx = verifier(SecOcStream::AirbagStage, K_AIRBAG);
    rx.hold_command(c.payload(), 0).unwrap();
    assert_eq!(
        rx.verify_auth(a.payload(), 0, u64::MAX).unwrap().freshness,
        u64::MAX
    );
    assert_eq!(
        s.authenticate(&c, u64::MAX),
        Err(SecOcError::FreshnessExhausted)
    );
    rx.hold_command(c.payload(), 0).unwrap();
    assert_eq!(
        rx.verify_auth(a.payload(), 0, u64::MAX),
        Err(SecOcError::Replay {
            freshness: u64::MAX
        })
    );
}

/// The replay hole: a genuine Armed + Fire pair recorded in one session (candump during
/// a crash test) and replayed in a later one (cansend). With a restarting counter it was
/// ahead of the new session's counter and accepted; with time stamps it is stale.
#[test]
fn pair_recorded_in_an_earlier_session_is_rejected() {
    // Session 1 at T0: the recording.
    let mut e2e1 = E2eProtector::new();
    let mut tx1 = SecOcTx::new(&key(K_AIRBAG), &key(K_BELT));
    let fire = airbag_fire(&mut e2e1);
    let fire_auth = tx1.authenticate(&fire, T0).unwrap();

    // Later sessions (new sender, new receiver), running and accepting their own traffic;
    // the recorded pair is replayed in the middle.
    for (later_s, expected) in [
        (60, SecOcError::MacMismatch),
        (
            20,
            SecOcError::FreshnessStale {
                freshness: T0,
                sync_now_us: T0 + 20 * S + 50 * MS,
            },
        ),
        (
            3,
            SecOcError::FreshnessStale {
                freshness: T0,
                sync_now_us: T0 + 3 * S + 50 * MS,
            },
        ),
    ] {
        let start = T0 + later_s * S;
        let mut e2e = E2eProtector::new();
        let mut tx = SecOcTx::new(&key(K_AIRBAG), &key(K_BELT));
        let mut rx = verifier(SecOcStream::AirbagStage, K_AIRBAG);
        for i in 0..10u64 {
            let sync = start + i * 10 * MS;
            let c = airbag_fire(&mut e2e);
            let a = tx.authenticate(&c, sync).unwrap();
            rx.hold_command(c.payload(), i * 10_000).unwrap();
            let ok = rx.verify_auth(a.payload(), i * 10_000 + 200, sync + 200);
            assert_eq!(ok.unwrap().freshness, sync);
            if i == 4 {
                rx.hold_command(fire.payload(), i * 10_000 + 1_000).unwrap();
                assert_eq!(
                    rx.verify_auth(fire_auth.payload(), i * 10_000 + 1_100, start + 50 * MS),
                    Err(expected),
                    "replayed {later_s} s later"
                );
            }
        }
        assert_eq!(rx.stats().accepted, 10, "session traffic still accepted");
        assert_eq!(rx.stats().rejected_total(), 1);
    }
}

/// The pairing timeout runs on the receiver's monotonic time (`now_us`), independent of the
/// synchronized time used for freshness (`sync_now_us`, held fixed here).
#[test]
fn pairing_timeout_orphans_and_superseded_commands() {
    let mut e2e = E2eProtector::new();
    let k = key(K_AIRBAG);
    let mut s = SecOcSender::new(SecOcStream::AirbagStage, &k);
    let mut rx = verifier(SecOcStream::AirbagStage, K_AIRBAG);
    let sync = T0 + MS;
    // Orphan authenticator.
    let c = airbag_fire(&mut e2e);
    let a = s.authenticate(&c, T0).unwrap();
    assert_eq!(
        rx.verify_auth(a.payload(), 0, sync),
        Err(SecOcError::NoPendingCommand)
    );
    // Delayed authenticator: stale, and the command is gone.
    rx.hold_command(c.payload(), 1_000).unwrap();
    assert_eq!(
        rx.verify_auth(a.payload(), 11_001, sync),
        Err(SecOcError::Stale { age_us: 10_001 })
    );
    assert!(!rx.has_pending());
    assert_eq!(
        rx.verify_auth(a.payload(), 11_002, sync),
        Err(SecOcError::NoPendingCommand)
    );
    // Exactly at the timeout is still in time (the same, unused freshness value).
    rx.hold_command(c.payload(), 20_000).unwrap();
    assert_eq!(
        rx.verify_auth(a.payload(), 30_000, sync).unwrap().freshness,
        T0
    );
    // A forged command slipped in between replaces the genuine one: the genuine authenticator
    // then fails (one command denied, never a wrong actuation).
    let c2 = airbag_fire(&mut e2e);
    let a2 = s.authenticate(&c2, T0 + 10).unwrap();
    rx.hold_command(c2.payload(), 40_000).unwrap();
    let mut forged = c2.data;
    forged[3] ^= 0x10;
    rx.hold_command(&forged, 40_010).unwrap();
    assert_eq!(
        rx.verify_auth(a2.payload(), 40_020, sync),
        Err(SecOcError::MacMismatch)
    );
    // expire() drops a command whose authenticator never came.
    assert!(!rx.expire(45_000));
    assert!(rx.expire(50_011));
    assert_eq!(rx.stats().commands_dropped, 3);
    assert_eq!(rx.stats().rejected_for(SecOcReject::Stale), 1);
    assert_eq!(rx.stats().rejected_for(SecOcReject::NoPendingCommand), 2);
    assert_eq!(
        rx.hold_command(&[0; 7], 0),
        Err(SecOcError::WrongDlc { got: 7 })
    );
    assert_eq!(
        rx.verify_auth(&[0; 9], 0, sync),
        Err(SecOcError::WrongDlc { got: 9 })
    );
    assert_eq!(rx.stats().rejected_for(SecOcReject::Malformed), 2);
}

#[test]
fn reject_reasons_have_stable_distinct_names() {
    let names: Vec<&str> = <SecOcReject as bus::VariantArray>::VARIANTS
        .iter()
        .map(|r| r.name())
        .collect();
    assert_eq!(
        names,
        [
            "malformed",
            "no_pending_command",
            "stale",
            "replay",
            "freshness_stale",
            "mac_mismatch"
        ]
    );
    for (i, r) in <SecOcReject as bus::VariantArray>::VARIANTS
        .iter()
        .enumerate()
    {
        assert_eq!(*r as usize, i);
    }
    let e = SecOcError::FreshnessStale {
        freshness: 1,
        sync_now_us: 2,
    };
    assert_eq!(e.reason(), SecOcReject::FreshnessStale);
}

/// SplitMix64 (Steele, Lea, Flood 2014): a fixed, seedable generator for the forgery attempts.
struct SplitMix(u64);
impl SplitMix {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
}

/// An attacker on the bus (cansend) knows the frame layout, sees every genuine frame, computes
/// the E2E CRC, but has no key: 100 000 guessed authenticators with fresh freshness bits (the
/// receiver's time plus 0..1 ms) and random MACs, and 100 000 with random freshness bits, are
/// all rejected. (Chance of one success: 2e5 / 2^40 ~ 2e-7.)
#[test]
fn forgery_without_key_is_never_accepted() {
    let mut e2e = E2eProtector::new();
    let mut rng = SplitMix(0x5EC0_C0DE);
    let mut rx = verifier(SecOcStream::AirbagStage, K_AIRBAG);
    let tries = 200_000u64;
    let mut accepted = 0;
    for i in 0..tries {
        let sync = T0 + i * 10;
        let c = airbag_fire(&mut e2e);
        rx.hold_command(c.payload(), i).unwrap();
        let fv = if i % 2 == 0 {
            (sync + 1 + rng.next() % 1000) & FRESHNESS_TX_MASK
        } else {
            rng.next() & FRESHNESS_TX_MASK
        };
        let mac = rng.next() & ((1 << 40) - 1);
        let a = bus::AirbagStageAuth::new(fv as u32, mac).unwrap();
        if rx
            .verify_auth(embedded_can::Frame::data(&a), i, sync)
            .is_ok()
        {
            accepted += 1;
        }
    }
    assert_eq!(accepted, 0);
    assert_eq!(rx.stats().rejected_for(SecOcReject::MacMismatch), tries);
    assert_eq!(rx.last_accepted(), 0);
}

#[cfg(feature = "std")]
mod key_file {
    use super::*;
    use bus::secoc::{KeyFileError, KeyParseError, SecOcKeys};
    use std::path::Path;

    fn example_path() -> std::path::PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../data/secoc-keys.example.toml")
    }

    #[test]
    fn example_file_loads_and_drives_a_bench_pair() {
        let keys = SecOcKeys::load(&example_path()).unwrap();
        assert_eq!(keys.get(SecOcStream::AirbagStage), &key(K_AIRBAG));
        assert_eq!(keys.get(SecOcStream::BeltLimiter), &key(K_BELT));
        assert_eq!(
            format!("{:?}", keys.get(SecOcStream::AirbagStage)),
            "SecOcKey(<redacted>)"
        );
        let mut e2e = E2eProtector::new();
        let mut tx = keys.tx();
        let mut rx = keys.verifier(SecOcStream::BeltLimiter, SecOcConfig::default());
        let c = belt_fire(&mut e2e);
        let a = tx.authenticate(&c, T0).unwrap();
        rx.hold_command(c.payload(), 0).unwrap();
        assert_eq!(
            rx.verify_auth(a.payload(), 0, T0 + 300).unwrap().freshness,
            T0
        );
    }

    fn err(text: &str) -> KeyFileError {
        SecOcKeys::from_toml_str(text, Path::new("k.toml")).unwrap_err()
    }

    #[test]
    fn key_file_errors_are_specific() {
        let ok_keys =
            format!("[keys]\nAirbagStageCmd = \"{K_AIRBAG}\"\nBeltLimiterCmd = \"{K_BELT}\"\n");
        let fmt = "format = \"restraint-secoc-keys/1\"\n";
        assert!(SecOcKeys::from_toml_str(&format!("{fmt}{ok_keys}"), Path::new("k")).is_ok());
        assert!(matches!(err(&ok_keys), KeyFileError::Format { .. }));
        assert!(matches!(
            err("format = \"x\"\n"),
            KeyFileError::Format { .. }
        ));
        assert!(matches!(err("format = = 1"), KeyFileError::Toml { .. }));
        let e = err(&format!("{fmt}[keys]\nAirbagStageCmd = \"{K_AIRBAG}\"\n"));
        assert!(
            matches!(&e, KeyFileError::Missing { entry, .. } if entry == "keys.BeltLimiterCmd"),
            "{e}"
        );
        let e = err(&format!("{fmt}{ok_keys}AirbagStage = \"{K_AIRBAG}\"\n"));
        assert!(
            matches!(&e, KeyFileError::Unknown { entry, .. } if entry == "keys.AirbagStage"),
            "{e}"
        );
        let e = err(&format!(
            "{fmt}[keys]\nAirbagStageCmd = \"{}\"\nBeltLimiterCmd = \"{K_BELT}\"\n",
            &K_AIRBAG[..30]
        ));
        assert!(matches!(
            e,
            KeyFileError::BadKey {
                reason: KeyParseError::WrongLength { digits: 30 },
                ..
            }
        ));
        let e = err(&format!(
            "{fmt}[keys]\nAirbagStageCmd = \"{K_AIRBAG}\"\nBeltLimiterCmd = \"{}g\"\n",
            &K_BELT[..31]
        ));
        assert!(matches!(
            e,
            KeyFileError::BadKey {
                reason: KeyParseError::NotHex { found: 'g' },
                ..
            }
        ));
        let e = err(&format!(
            "{fmt}[keys]\nAirbagStageCmd = \"{K_AIRBAG}\"\nBeltLimiterCmd = \"{}\"\n",
            "0".repeat(32)
        ));
        assert!(matches!(
            e,
            KeyFileError::BadKey {
                reason: KeyParseError::AllZero,
                ..
            }
        ));
        let e = SecOcKeys::load(Path::new("/nonexistent/keys.toml")).unwrap_err();
        assert!(e.to_string().contains("/nonexistent/keys.toml"), "{e}");
        // Grouped notation is accepted.
        assert_eq!(key("0x0686aa35_a35e8753:14778-8e1 923f8dfd"), key(K_AIRBAG));
    }
}
