//! Frame handling of the modules: E2E check, then SecOC pairing of the command frames.
//!
//! Why a separate step: the modules must *act* only on a command whose authenticator
//! (`AirbagStageAuth` / `BeltLimiterAuth`, sent by the ECU right after the command) verifies —
//! a frame forged with `cansend`, even with a correct E2E CRC and counter (both are public
//! algorithms), then does nothing. Every frame is still logged with both verdicts.
//!
//! Flow per frame:
//! * command (`0x030` / `0x040`): E2E check; if it passes, the payload is *held* by the
//!   stream's [`SecOcVerifier`] (verdict `"held"`), nothing happens yet;
//! * authenticator (`0x031` / `0x041`): not an E2E frame (E2E verdict `"n/a"`, not counted as
//!   accepted or rejected); verified against the held command; on success the held payload —
//!   the bytes the MAC covered, not a later frame — is decoded and acted on at this frame's
//!   receive time;
//! * anything else (`EcuStatus`, foreign frames): E2E only, as before.
//!
//! Two clocks: the pairing timeout runs on the receive time (CLOCK_MONOTONIC), the SecOC
//! freshness check on the synchronized time ([`host::sync_time_us`], CLOCK_REALTIME — the ECU stamps
//! its authenticators with the same clock), so a genuine pair recorded in an earlier session
//! and replayed later is stale.

use std::collections::BTreeMap;

use bus::secoc::{SecOcConfig, SecOcKeys, SecOcReject, SecOcStream, SecOcVerifier};
use bus::{E2eChecker, RawFrame};

use crate::commands::{decode, Decoded};

/// Verdicts on one received frame.
#[derive(Clone, Debug, PartialEq)]
pub struct Verdict {
    /// "ok", the E2E/decoding rejection reason, or "n/a" (authenticator frames carry no E2E).
    pub e2e: String,
    /// SecOC verdict: `None` for frames outside SecOC; "held" (command waiting for its
    /// authenticator), "ok" (authenticator verified), or the rejection reason
    /// ([`SecOcReject::name`]).
    pub secoc: Option<String>,
    /// Decoded content for the log (E2E-accepted frames; for a verified authenticator the
    /// command it authenticated).
    pub decoded: Option<Decoded>,
    /// What the modules act on now: a verified command, or an accepted non-SecOC frame.
    pub act: Option<Decoded>,
}

/// E2E checker plus one SecOC verifier per authenticated command stream.
#[derive(Debug)]
pub struct Receiver {
    checker: E2eChecker,
    verifiers: [SecOcVerifier; 2],
    e2e_accepted: u64,
}

impl Receiver {
    /// Receiver with the stream keys and the default SecOC configuration (100-ms freshness
    /// window around the synchronized time).
    pub fn new(keys: &SecOcKeys) -> Self {
        Self::with_config(keys, SecOcConfig::default())
    }

    /// Receiver with an explicit SecOC configuration (freshness window, pairing timeout).
    pub fn with_config(keys: &SecOcKeys, config: SecOcConfig) -> Self {
        let v = |s| keys.verifier(s, config);
        Self {
            checker: E2eChecker::new(),
            verifiers: [v(SecOcStream::AirbagStage), v(SecOcStream::BeltLimiter)],
            e2e_accepted: 0,
        }
    }

    fn verifier(&mut self, stream: SecOcStream) -> &mut SecOcVerifier {
        match stream {
            SecOcStream::AirbagStage => &mut self.verifiers[0],
            SecOcStream::BeltLimiter => &mut self.verifiers[1],
        }
    }

    /// Handles one frame received at `rx_ns` (CLOCK_MONOTONIC) and read at synchronized time
    /// `sync_now_us` ([`sync_now_us`]; only authenticators use it).
    pub fn on_frame(&mut self, f: &RawFrame, rx_ns: u64, sync_now_us: u64) -> Verdict {
        let now_us = rx_ns / 1_000;
        if let Some(stream) = SecOcStream::for_auth_id(f.id) {
            let verdict = self
                .verifier(stream)
                .verify_auth(f.payload(), now_us, sync_now_us);
            let (secoc, decoded) = match verdict {
                Ok(cmd) => match bus::decode(stream.command_id(), &cmd.payload) {
                    Ok(msg) => ("ok".to_owned(), Some(decode(&msg))),
                    // The payload passed E2E when it was held, so this cannot happen; never
                    // act on something that does not decode.
                    Err(e) => (format!("decode: {}", e.reason().name()), None),
                },
                Err(e) => (e.reason().name().to_owned(), None),
            };
            return Verdict {
                e2e: "n/a".to_owned(),
                secoc: Some(secoc),
                act: decoded.clone(),
                decoded,
            };
        }
        let (e2e, decoded) = match self.checker.check_frame(f) {
            Ok(msg) => {
                self.e2e_accepted += 1;
                ("ok".to_owned(), Some(decode(&msg)))
            }
            Err(e) => (e.reason().name().to_owned(), None),
        };
        match SecOcStream::for_command_id(f.id) {
            Some(stream) => {
                let secoc = decoded.as_ref().map(|_| {
                    match self.verifier(stream).hold_command(f.payload(), now_us) {
                        Ok(()) => "held".to_owned(),
                        Err(e) => e.reason().name().to_owned(),
                    }
                });
                Verdict {
                    e2e,
                    secoc,
                    decoded,
                    act: None,
                }
            }
            None => Verdict {
                e2e,
                secoc: None,
                act: decoded.clone(),
                decoded,
            },
        }
    }

    /// Drops held commands whose authenticator did not come within the pairing timeout.
    pub fn expire(&mut self, now_ns: u64) {
        for v in &mut self.verifiers {
            v.expire(now_ns / 1_000);
        }
    }

    /// The E2E checker (statistics).
    pub fn checker(&self) -> &E2eChecker {
        &self.checker
    }

    /// Frames that passed the E2E check.
    pub fn e2e_accepted(&self) -> u64 {
        self.e2e_accepted
    }

    /// Commands authenticated, both streams.
    pub fn secoc_accepted(&self) -> u64 {
        self.verifiers.iter().map(|v| v.stats().accepted).sum()
    }

    /// Held commands that never got a valid authenticator, both streams.
    pub fn secoc_commands_dropped(&self) -> u64 {
        self.verifiers
            .iter()
            .map(|v| v.stats().commands_dropped)
            .sum()
    }

    /// SecOC rejections by reason (only reasons that occurred), both streams.
    pub fn secoc_rejected(&self) -> BTreeMap<String, u64> {
        <SecOcReject as bus::VariantArray>::VARIANTS
            .iter()
            .map(|r| {
                let n: u64 = self
                    .verifiers
                    .iter()
                    .map(|v| v.stats().rejected_for(*r))
                    .sum();
                (r.name().to_owned(), n)
            })
            .filter(|(_, n)| *n > 0)
            .collect()
    }
}
