//! `bus::secoc::SecOcVerifier` driven by arbitrary interleavings of genuine traffic (a real
//! `SecOcSender` with the key), lost authenticators, replays, time jumps (the synchronized
//! clock also backwards) and attacker frames (arbitrary ids, lengths and bytes).
//!
//! Oracles:
//! - safety: every accepted command is one the genuine sender authenticated, with the very
//!   freshness value it used, and accepted freshness values strictly increase (no replay, no
//!   forgery gets through);
//! - liveness: a genuine command + authenticator delivered back to back, whose freshness is
//!   within the window of the (shared) synchronized clock, is accepted;
//! - accounting: accepted + rejected equals the authenticators offered.
#![no_main]

use bus::secoc::{SecOcConfig, SecOcError, SecOcKey, SecOcSender, SecOcStream, SecOcVerifier};
use bus::RawFrame;
use libfuzzer_sys::fuzz_target;

const WINDOW_US: u64 = 64;
/// Synchronized time at the start (µs since the UNIX epoch, 2025).
const SYNC0_US: u64 = 1_750_000_000_000_000;
const TIMEOUT_US: u64 = 10_000;

fuzz_target!(|data: &[u8]| {
    let key = SecOcKey::from_bytes(*b"fuzz-secoc-key!!");
    let stream = if data.first().is_some_and(|b| b & 1 == 1) {
        SecOcStream::BeltLimiter
    } else {
        SecOcStream::AirbagStage
    };
    let cfg = SecOcConfig {
        freshness_window_us: WINDOW_US,
        pairing_timeout_us: TIMEOUT_US,
    };
    let mut tx = SecOcSender::new(stream, &key);
    let mut rx = SecOcVerifier::new(stream, &key, cfg);
    // Genuine (command payload, freshness, auth frame) the sender produced, for replays/oracle.
    let mut genuine: Vec<([u8; 8], u64, RawFrame)> = Vec::new();
    let mut now_us = 0u64;
    // Shared by sender and receiver (one machine); may step back.
    let mut sync_us = SYNC0_US;
    let mut offered = 0u64;
    let mut accepted = 0u64;
    let mut last_ok = 0u64;
    let mut input = Reader(data.get(1..).unwrap_or(&[]));
    while let Some(op) = input.next() {
        let outcome: Option<Result<bus::secoc::AuthenticatedCommand, SecOcError>> = match op % 8 {
            // Genuine pair, back to back.
            0 | 1 => {
                let b = input.bytes(8);
                let mut p = [0u8; 8];
                p[..b.len()].copy_from_slice(&b);
                let cmd = RawFrame::new(stream.command_id(), &p);
                let Ok(auth) = tx.authenticate(&cmd, sync_us) else {
                    return;
                };
                let fv = tx.last_freshness();
                genuine.push((p, fv, auth));
                let in_window = fv.abs_diff(sync_us) <= WINDOW_US;
                rx.hold_command(&p, now_us).expect("8 bytes");
                let r = rx.verify_auth(auth.payload(), now_us, sync_us);
                if in_window {
                    assert!(r.is_ok(), "genuine in-window pair rejected: {r:?}");
                }
                Some(r)
            }
            // Authenticator lost on the bus (the sender used up a freshness value).
            2 => {
                let n = u64::from(input.next().unwrap_or(0) % 80);
                for _ in 0..n {
                    let _ = tx.authenticate(&RawFrame::new(stream.command_id(), &[0; 8]), sync_us);
                }
                None
            }
            // Replay of an earlier genuine command and/or authenticator.
            3 => {
                let sel = usize::from(input.next().unwrap_or(0));
                let mode = input.next().unwrap_or(0);
                if genuine.is_empty() {
                    None
                } else {
                    let (p, _, auth) = genuine[sel % genuine.len()];
                    if mode & 1 == 1 {
                        rx.hold_command(&p, now_us).expect("8 bytes");
                    }
                    Some(rx.verify_auth(auth.payload(), now_us, sync_us))
                }
            }
            // Time passes; with bit 4 of the second byte the synchronized clock steps back
            // instead (monotonic time never does).
            4 => {
                let b = input.bytes(2);
                let mode = b.get(1).copied().unwrap_or(0);
                let dt = u64::from(b.first().copied().unwrap_or(0)) << (mode % 16);
                if mode & 0x10 != 0 {
                    sync_us = sync_us.saturating_sub(dt);
                } else {
                    now_us = now_us.saturating_add(dt);
                    sync_us = sync_us.saturating_add(dt);
                    rx.expire(now_us);
                }
                None
            }
            // Attacker command frame (any length).
            5 => {
                let n = usize::from(input.next().unwrap_or(8) % 10);
                let b = input.bytes(n);
                let _ = rx.hold_command(&b, now_us);
                None
            }
            // Attacker authenticator (any length).
            6 => {
                let n = usize::from(input.next().unwrap_or(8) % 10);
                let b = input.bytes(n);
                Some(rx.verify_auth(&b, now_us, sync_us))
            }
            // Attacker frame with any id through the router.
            _ => {
                let b = input.bytes(3);
                let id = u32::from(u16::from_le_bytes([
                    b.first().copied().unwrap_or(0),
                    b.get(1).copied().unwrap_or(0),
                ])) & 0x7FF;
                let n = usize::from(b.get(2).copied().unwrap_or(8) % 10);
                let payload = input.bytes(n);
                match rx.on_frame(id, &payload, now_us, sync_us) {
                    Ok(Some(c)) => Some(Ok(c)),
                    Ok(None) => None,
                    Err(e) if id == stream.auth_id() => Some(Err(e)),
                    Err(_) => None,
                }
            }
        };
        if let Some(r) = outcome {
            offered += 1;
            if let Ok(c) = r {
                accepted += 1;
                assert!(
                    genuine
                        .iter()
                        .any(|(p, fv, _)| *p == c.payload && *fv == c.freshness),
                    "accepted a command the sender never authenticated: {c:?}"
                );
                assert!(c.freshness > last_ok, "freshness did not increase");
                last_ok = c.freshness;
            }
        }
    }
    let s = rx.stats();
    assert_eq!(s.accepted, accepted);
    // Router/hold errors for non-auth frames are counted too (malformed), so >=.
    assert!(s.accepted + s.rejected_total() >= offered);
});

/// Consumes the fuzz input byte by byte; yields nothing (or short slices) at the end.
struct Reader<'a>(&'a [u8]);

impl Reader<'_> {
    fn next(&mut self) -> Option<u8> {
        let (b, rest) = self.0.split_first()?;
        self.0 = rest;
        Some(*b)
    }

    fn bytes(&mut self, n: usize) -> Vec<u8> {
        let (a, b) = self.0.split_at(n.min(self.0.len()));
        self.0 = b;
        a.to_vec()
    }
}
