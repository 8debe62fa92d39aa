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
    SecOcVerifier::new(stream, &key(k), SecOcConfig::default(), 0)
}

#[test]
fn authenticator_layout_is_the_documented_one() {
    let mut e2e = E2eProtector::new();
    let cmd = airbag_fire(&mut e2e);
    let mut s = SecOcSender::new(
        SecOcStream::AirbagStage,
        &key(K_AIRBAG),
        0x0123_4567_89AB_CDEF,
    );
    let auth = s.authenticate(&cmd).unwrap();
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
    assert_eq!(s.next_freshness(), 0x0123_4567_89AB_CDF0);
}

#[test]
fn genuine_pairs_verify_for_both_streams() {
    let mut e2e = E2eProtector::new();
    let mut tx = SecOcTx::new(&key(K_AIRBAG), &key(K_BELT), 1);
    let mut rx_a = verifier(SecOcStream::AirbagStage, K_AIRBAG);
    let mut rx_b = verifier(SecOcStream::BeltLimiter, K_BELT);
    for i in 0..50u64 {
        let t = i * 10_000;
        let a = airbag_fire(&mut e2e);
        let a_auth = tx.authenticate(&a).unwrap();
        let b = belt_fire(&mut e2e);
        let b_auth = tx.authenticate(&b).unwrap();
        assert_eq!(rx_a.on_frame(a.id, a.payload(), t), Ok(None));
        let ok = rx_a
            .on_frame(a_auth.id, a_auth.payload(), t + 150)
            .unwrap()
            .unwrap();
        assert_eq!(ok.payload, a.data);
        assert_eq!(ok.freshness, i + 1);
        assert_eq!(ok.pairing_delay_us, 150);
        assert!(matches!(
            decode(0x030, &ok.payload),
            Ok(Messages::AirbagStageCmd(_))
        ));
        rx_b.hold_command(b.payload(), t).unwrap();
        let ok = rx_b.verify_auth(b_auth.payload(), t + 10_000).unwrap();
        assert_eq!(ok.payload, b.data);
    }
    assert_eq!(rx_a.stats().accepted, 50);
    assert_eq!(rx_a.stats().rejected_total(), 0);
    assert_eq!(rx_b.stats().accepted, 50);
    // Streams are separated: a belt authenticator never authenticates an airbag command.
    let a = airbag_fire(&mut e2e);
    let b_auth = tx.authenticate(&belt_fire(&mut e2e)).unwrap();
    rx_a.hold_command(a.payload(), 0).unwrap();
    assert!(rx_a.verify_auth(b_auth.payload(), 0).is_err());
    assert!(matches!(
        rx_a.on_frame(0x041, b_auth.payload(), 0),
        Err(SecOcError::WrongId(0x041))
    ));
    assert!(matches!(
        tx.authenticate(&RawFrame::new(0x0A0, &[0; 8])),
        Err(SecOcError::WrongId(0x0A0))
    ));
}

#[test]
fn every_single_bit_flip_is_rejected() {
    let mut e2e = E2eProtector::new();
    let mut s = SecOcSender::new(SecOcStream::AirbagStage, &key(K_AIRBAG), 1);
    let cmd = airbag_fire(&mut e2e);
    let auth = s.authenticate(&cmd).unwrap();
    let fresh = verifier(SecOcStream::AirbagStage, K_AIRBAG);
    let mut rejected = 0;
    for bit in 0..64 {
        let mut c = cmd.data;
        c[bit / 8] ^= 1 << (bit % 8);
        let mut rx = fresh.clone();
        rx.hold_command(&c, 0).unwrap();
        let r = rx.verify_auth(auth.payload(), 1);
        assert_eq!(r, Err(SecOcError::MacMismatch), "command bit {bit}");
        rejected += 1;

        let mut a = auth.data;
        a[bit / 8] ^= 1 << (bit % 8);
        let mut rx = fresh.clone();
        rx.hold_command(cmd.payload(), 0).unwrap();
        let r = rx.verify_auth(&a, 1);
        assert!(r.is_err(), "auth bit {bit}: {r:?}");
        assert_eq!(rx.stats().accepted, 0);
        // The command is still held: the genuine authenticator after a forged one still works.
        assert_eq!(rx.verify_auth(auth.payload(), 2).unwrap().payload, cmd.data);
        rejected += 1;
    }
    assert_eq!(rejected, 128);
}

#[test]
fn replays_are_rejected_and_named() {
    let mut e2e = E2eProtector::new();
    let mut s = SecOcSender::new(SecOcStream::AirbagStage, &key(K_AIRBAG), 1);
    let mut rx = verifier(SecOcStream::AirbagStage, K_AIRBAG);
    let pairs: Vec<(RawFrame, RawFrame)> = (0..5)
        .map(|_| {
            let c = airbag_fire(&mut e2e);
            let a = s.authenticate(&c).unwrap();
            (c, a)
        })
        .collect();
    for (c, a) in &pairs {
        rx.hold_command(c.payload(), 0).unwrap();
        rx.verify_auth(a.payload(), 0).unwrap();
    }
    for (i, (c, a)) in pairs.iter().enumerate() {
        rx.hold_command(c.payload(), 100).unwrap();
        assert_eq!(
            rx.verify_auth(a.payload(), 100),
            Err(SecOcError::Replay {
                freshness: i as u64 + 1
            })
        );
    }
    // The authenticator alone, replayed right after its command was consumed.
    assert_eq!(
        rx.verify_auth(pairs[4].1.payload(), 100),
        Err(SecOcError::Replay { freshness: 5 })
    );
    rx.expire(1_000_000);
    assert_eq!(
        rx.verify_auth(pairs[4].1.payload(), 1_000_000),
        Err(SecOcError::NoPendingCommand)
    );
    assert_eq!(rx.stats().rejected_for(SecOcReject::Replay), 6);
    assert_eq!(rx.stats().rejected_for(SecOcReject::NoPendingCommand), 1);
    assert_eq!(rx.last_accepted(), 5);
}

#[test]
fn wrong_key_is_rejected() {
    let mut e2e = E2eProtector::new();
    let mut s = SecOcSender::new(SecOcStream::AirbagStage, &key(K_BELT), 1);
    let mut rx = verifier(SecOcStream::AirbagStage, K_AIRBAG);
    for _ in 0..20 {
        let c = airbag_fire(&mut e2e);
        let a = s.authenticate(&c).unwrap();
        rx.hold_command(c.payload(), 0).unwrap();
        assert_eq!(rx.verify_auth(a.payload(), 0), Err(SecOcError::MacMismatch));
    }
    assert_eq!(rx.stats().rejected_for(SecOcReject::MacMismatch), 20);
    assert_eq!(rx.stats().accepted, 0);
}

#[test]
fn acceptance_window_and_24_bit_wrap() {
    let mut e2e = E2eProtector::new();
    let k = key(K_AIRBAG);
    let cfg = SecOcConfig {
        max_forward_jump: 3,
        ..SecOcConfig::default()
    };
    // Wrap of the transmitted 24 bits: the full counter continues, the receiver follows it.
    let start = (1u64 << 24) - 4;
    let mut s = SecOcSender::new(SecOcStream::AirbagStage, &k, start + 1);
    let mut rx = SecOcVerifier::new(SecOcStream::AirbagStage, &k, cfg, start);
    for i in 1..=10u64 {
        let c = airbag_fire(&mut e2e);
        let a = s.authenticate(&c).unwrap();
        assert_eq!(
            a.data[0..3],
            (((start + i) & FRESHNESS_TX_MASK) as u32).to_le_bytes()[..3]
        );
        rx.hold_command(c.payload(), 0).unwrap();
        assert_eq!(rx.verify_auth(a.payload(), 0).unwrap().freshness, start + i);
    }
    // Lost authenticators: a jump of 3 is accepted, a jump of 4 is not.
    for (lost, accepted) in [(2u64, true), (3, false)] {
        let last = rx.last_accepted();
        for _ in 0..lost {
            s.authenticate(&airbag_fire(&mut e2e)).unwrap();
        }
        let c = airbag_fire(&mut e2e);
        let a = s.authenticate(&c).unwrap();
        rx.hold_command(c.payload(), 0).unwrap();
        let r = rx.verify_auth(a.payload(), 0);
        if accepted {
            assert_eq!(r.unwrap().freshness, last + lost + 1);
        } else {
            assert_eq!(
                r,
                Err(SecOcError::FreshnessOutOfWindow {
                    freshness: last + lost + 1,
                    last
                })
            );
        }
    }
    // Near the end of the 64-bit space: the last value cannot be used, no overflow panic.
    let mut s = SecOcSender::new(SecOcStream::AirbagStage, &k, u64::MAX - 1);
    let mut rx = SecOcVerifier::new(SecOcStream::AirbagStage, &k, cfg, u64::MAX - 2);
    let c = airbag_fire(&mut e2e);
    let a = s.authenticate(&c).unwrap();
    rx.hold_command(c.payload(), 0).unwrap();
    assert_eq!(
        rx.verify_auth(a.payload(), 0).unwrap().freshness,
        u64::MAX - 1
    );
    assert_eq!(s.authenticate(&c), Err(SecOcError::FreshnessExhausted));
    rx.hold_command(c.payload(), 0).unwrap();
    assert_eq!(
        rx.verify_auth(a.payload(), 0),
        Err(SecOcError::Replay {
            freshness: u64::MAX - 1
        })
    );
}

#[test]
fn pairing_timeout_orphans_and_superseded_commands() {
    let mut e2e = E2eProtector::new();
    let k = key(K_AIRBAG);
    let mut s = SecOcSender::new(SecOcStream::AirbagStage, &k, 1);
    let mut rx = verifier(SecOcStream::AirbagStage, K_AIRBAG);
    // Orphan authenticator.
    let c = airbag_fire(&mut e2e);
    let a = s.authenticate(&c).unwrap();
    assert_eq!(
        rx.verify_auth(a.payload(), 0),
        Err(SecOcError::NoPendingCommand)
    );
    // Delayed authenticator: stale, and the command is gone.
    rx.hold_command(c.payload(), 1_000).unwrap();
    assert_eq!(
        rx.verify_auth(a.payload(), 11_001),
        Err(SecOcError::Stale { age_us: 10_001 })
    );
    assert!(!rx.has_pending());
    assert_eq!(
        rx.verify_auth(a.payload(), 11_002),
        Err(SecOcError::NoPendingCommand)
    );
    // Exactly at the timeout is still in time (the same, unused freshness value).
    rx.hold_command(c.payload(), 20_000).unwrap();
    assert_eq!(rx.verify_auth(a.payload(), 30_000).unwrap().freshness, 1);
    // A forged command slipped in between replaces the genuine one: the genuine authenticator
    // then fails (one command denied, never a wrong actuation).
    let c2 = airbag_fire(&mut e2e);
    let a2 = s.authenticate(&c2).unwrap();
    rx.hold_command(c2.payload(), 40_000).unwrap();
    let mut forged = c2.data;
    forged[3] ^= 0x10;
    rx.hold_command(&forged, 40_010).unwrap();
    assert_eq!(
        rx.verify_auth(a2.payload(), 40_020),
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
        rx.verify_auth(&[0; 9], 0),
        Err(SecOcError::WrongDlc { got: 9 })
    );
    assert_eq!(rx.stats().rejected_for(SecOcReject::Malformed), 2);
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
/// the E2E CRC, but has no key: 100 000 guessed authenticators with fresh, in-window freshness
/// values and random MACs are all rejected. (Chance of one success: 1e5 / 2^40 ~ 1e-7.)
#[test]
fn forgery_without_key_is_never_accepted() {
    let mut e2e = E2eProtector::new();
    let mut rng = SplitMix(0x5EC0_C0DE);
    let mut rx = verifier(SecOcStream::AirbagStage, K_AIRBAG);
    let tries = 100_000u64;
    let mut accepted = 0;
    for i in 0..tries {
        let c = airbag_fire(&mut e2e);
        rx.hold_command(c.payload(), i).unwrap();
        let fv = (1 + rng.next() % 1000) as u32;
        let mac = rng.next() & ((1 << 40) - 1);
        let a = bus::AirbagStageAuth::new(fv, mac).unwrap();
        if rx.verify_auth(embedded_can::Frame::data(&a), i).is_ok() {
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
        let mut tx = keys.tx(1);
        let mut rx = keys.verifier(SecOcStream::BeltLimiter, SecOcConfig::default(), 0);
        let c = belt_fire(&mut e2e);
        let a = tx.authenticate(&c).unwrap();
        rx.hold_command(c.payload(), 0).unwrap();
        assert!(rx.verify_auth(a.payload(), 0).is_ok());
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
