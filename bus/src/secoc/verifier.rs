//! The receiver side: holds a command until its authenticator verifies.

use strum::EnumCount;

use super::mac::{auth_fields, mac40_ok, payload8, KeyedCmac};
use super::{
    SecOcError, SecOcKey, SecOcReject, SecOcStream, FRESHNESS_TX_MASK, FRESHNESS_TX_SPAN,
    MAX_FRESHNESS_WINDOW_US,
};

/// Receiver tuning.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SecOcConfig {
    /// Freshness window, µs: the largest accepted difference between an authenticator's time
    /// stamp and the receiver's synchronized time, either way. Covers bus latency, scheduling
    /// stalls and the clock difference of sender and receiver. Clamped to
    /// `1..=`[`MAX_FRESHNESS_WINDOW_US`].
    ///
    /// (This replaces the counter scheme's `max_forward_jump`: with time stamps, lost
    /// authenticators only leave gaps in time, there is no count of them to bound.)
    pub freshness_window_us: u64,
    /// Longest time from a command frame to its authenticator (receiver's monotonic time).
    pub pairing_timeout_us: u64,
}

impl SecOcConfig {
    /// *Default* freshness window: 100 ms. On the bench sender and receiver read the same
    /// CLOCK_REALTIME, so the difference is the bus latency (< 1 ms) plus scheduling stalls
    /// (tens of ms under user-mode Linux); a vehicle's synchronized time base is good to well
    /// under a millisecond. A replay needs a recording younger than this *and* an unused
    /// freshness value — the latter is impossible (`last_accepted`), so the window only bounds
    /// how long a *suppressed* genuine pair (held back from the receiver) stays usable.
    pub const DEFAULT_FRESHNESS_WINDOW_US: u64 = 100_000;
    /// *Default* pairing timeout: one 10-ms command cycle. The sender puts the authenticator
    /// on the bus right after the command, so anything later is a delayed or injected frame.
    pub const DEFAULT_PAIRING_TIMEOUT_US: u64 = 10_000;
}

impl Default for SecOcConfig {
    fn default() -> Self {
        Self {
            freshness_window_us: Self::DEFAULT_FRESHNESS_WINDOW_US,
            pairing_timeout_us: Self::DEFAULT_PAIRING_TIMEOUT_US,
        }
    }
}

/// Counters of a [`SecOcVerifier`].
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct SecOcStats {
    /// Commands authenticated (returned by [`SecOcVerifier::verify_auth`]).
    pub accepted: u64,
    /// Authenticators rejected, indexed by `SecOcReject as usize`.
    pub rejected: [u64; SecOcReject::COUNT],
    /// Held commands that never got a valid authenticator (replaced, timed out or stale).
    pub commands_dropped: u64,
}

impl SecOcStats {
    /// Rejections for one reason.
    #[must_use]
    pub fn rejected_for(&self, reason: SecOcReject) -> u64 {
        self.rejected.get(reason as usize).copied().unwrap_or(0)
    }

    /// All rejections.
    #[must_use]
    pub fn rejected_total(&self) -> u64 {
        self.rejected.iter().fold(0u64, |a, b| a.saturating_add(*b))
    }
}

/// A command whose authenticator verified: act on `payload` (decode with
/// [`crate::decode`]`(stream.command_id(), &payload)`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct AuthenticatedCommand {
    /// The stream.
    pub stream: SecOcStream,
    /// The command's 8 payload bytes as received (and as authenticated).
    pub payload: [u8; 8],
    /// Full freshness value it verified with.
    pub freshness: u64,
    /// Time from command to authenticator.
    pub pairing_delay_us: u64,
}

#[derive(Debug, Clone, Copy)]
struct Pending {
    payload: [u8; 8],
    received_at_us: u64,
}

/// Receiver side of one stream: holds the last command until its authenticator verifies.
/// No allocation, no panic; at most three CMACs per authenticator (one to accept, two more
/// to classify a rejection).
#[derive(Clone)]
pub struct SecOcVerifier {
    stream: SecOcStream,
    mac: KeyedCmac,
    config: SecOcConfig,
    last_accepted: u64,
    pending: Option<Pending>,
    stats: SecOcStats,
}

impl core::fmt::Debug for SecOcVerifier {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("SecOcVerifier")
            .field("stream", &self.stream)
            .field("config", &self.config)
            .field("last_accepted", &self.last_accepted)
            .field("pending", &self.pending.is_some())
            .field("stats", &self.stats)
            .finish_non_exhaustive()
    }
}

impl SecOcVerifier {
    /// Verifier of `stream`. It starts with `last_accepted = 0`: with time-stamp freshness
    /// there is no start value to agree on (the window rejects earlier sessions' frames).
    #[must_use]
    pub fn new(stream: SecOcStream, key: &SecOcKey, config: SecOcConfig) -> Self {
        Self {
            stream,
            mac: key.cmac(),
            config: SecOcConfig {
                freshness_window_us: config.freshness_window_us.clamp(1, MAX_FRESHNESS_WINDOW_US),
                ..config
            },
            last_accepted: 0,
            pending: None,
            stats: SecOcStats::default(),
        }
    }

    /// The stream.
    #[must_use]
    pub const fn stream(&self) -> SecOcStream {
        self.stream
    }

    /// The configuration in use (window clamped).
    #[must_use]
    pub const fn config(&self) -> &SecOcConfig {
        &self.config
    }

    /// Last accepted full freshness value (µs; 0 before the first).
    #[must_use]
    pub const fn last_accepted(&self) -> u64 {
        self.last_accepted
    }

    /// Counters so far.
    #[must_use]
    pub const fn stats(&self) -> &SecOcStats {
        &self.stats
    }

    /// Whether a command is held waiting for its authenticator.
    #[must_use]
    pub const fn has_pending(&self) -> bool {
        self.pending.is_some()
    }

    /// Holds a received command (call after it passed the E2E check). Replaces (and counts as
    /// dropped) a held command that was never authenticated.
    pub fn hold_command(&mut self, command_payload: &[u8], now_us: u64) -> Result<(), SecOcError> {
        let payload = match payload8(command_payload) {
            Ok(p) => p,
            Err(e) => return Err(self.count(e)),
        };
        if self.pending.is_some() {
            self.stats.commands_dropped = self.stats.commands_dropped.saturating_add(1);
        }
        self.pending = Some(Pending {
            payload,
            received_at_us: now_us,
        });
        Ok(())
    }

    /// Drops a held command older than the pairing timeout (call once per receive loop, so a
    /// command whose authenticator never comes does not wait forever). Returns whether one was
    /// dropped.
    pub fn expire(&mut self, now_us: u64) -> bool {
        match self.pending {
            Some(p) if now_us.saturating_sub(p.received_at_us) > self.config.pairing_timeout_us => {
                self.pending = None;
                self.stats.commands_dropped = self.stats.commands_dropped.saturating_add(1);
                true
            }
            _ => false,
        }
    }

    /// Verifies an authenticator frame's payload against the held command (rules in the module
    /// docs). `now_us` is the receiver's monotonic time (pairing timeout, same clock as
    /// [`Self::hold_command`]); `sync_now_us` its synchronized time (freshness, same time base
    /// as the sender's). On success the command is consumed and returned.
    pub fn verify_auth(
        &mut self,
        auth_payload: &[u8],
        now_us: u64,
        sync_now_us: u64,
    ) -> Result<AuthenticatedCommand, SecOcError> {
        match self.verify_inner(auth_payload, now_us, sync_now_us) {
            Ok(c) => {
                self.stats.accepted = self.stats.accepted.saturating_add(1);
                Ok(c)
            }
            Err(e) => Err(self.count(e)),
        }
    }

    /// Routes one received frame of this stream: a command is held (`Ok(None)`), an
    /// authenticator verified (`Ok(Some(..))` = act now). The caller must have E2E-checked a
    /// command frame before. Other ids: [`SecOcError::WrongId`]. Times as in
    /// [`Self::verify_auth`].
    pub fn on_frame(
        &mut self,
        id: u32,
        payload: &[u8],
        now_us: u64,
        sync_now_us: u64,
    ) -> Result<Option<AuthenticatedCommand>, SecOcError> {
        if id == self.stream.command_id() {
            self.hold_command(payload, now_us).map(|()| None)
        } else if id == self.stream.auth_id() {
            self.verify_auth(payload, now_us, sync_now_us).map(Some)
        } else {
            Err(self.count(SecOcError::WrongId(id)))
        }
    }

    fn count(&mut self, e: SecOcError) -> SecOcError {
        if let Some(n) = self.stats.rejected.get_mut(e.reason() as usize) {
            *n = n.saturating_add(1);
        }
        e
    }

    fn verify_inner(
        &mut self,
        auth_payload: &[u8],
        now_us: u64,
        sync_now_us: u64,
    ) -> Result<AuthenticatedCommand, SecOcError> {
        let (fv_tx, mac_rx) = auth_fields(self.stream, auth_payload)?;
        let pending = self.pending.ok_or(SecOcError::NoPendingCommand)?;
        let age_us = now_us.saturating_sub(pending.received_at_us);
        if age_us > self.config.pairing_timeout_us {
            self.pending = None;
            self.stats.commands_dropped = self.stats.commands_dropped.saturating_add(1);
            return Err(SecOcError::Stale { age_us });
        }
        let ok = |fv: u64| mac40_ok(&self.mac, self.stream, &pending.payload, fv, mac_rx);
        let stale = |freshness: u64| SecOcError::FreshnessStale {
            freshness,
            sync_now_us,
        };
        let v = nearest_freshness(fv_tx, sync_now_us);
        if ok(v) {
            if v.abs_diff(sync_now_us) > self.config.freshness_window_us {
                return Err(stale(v));
            }
            if v <= self.last_accepted {
                return Err(SecOcError::Replay { freshness: v });
            }
            self.last_accepted = v;
            self.pending = None;
            return Ok(AuthenticatedCommand {
                stream: self.stream,
                payload: pending.payload,
                freshness: v,
                pairing_delay_us: age_us,
            });
        }
        // Classification only (the frame is rejected whatever comes out): a genuine frame
        // from the neighbouring 2^24-µs spans (8.4 s .. 25 s away) is stale, not forged.
        let neighbours = [
            v.checked_sub(FRESHNESS_TX_SPAN),
            v.checked_add(FRESHNESS_TX_SPAN),
        ];
        match neighbours.into_iter().flatten().find(|fv| ok(*fv)) {
            Some(fv) => Err(stale(fv)),
            None => Err(SecOcError::MacMismatch),
        }
    }
}

/// The full freshness value congruent to the received bits `fv_tx` (mod 2^24) nearest to
/// `sync_now_us`; at exactly 2^23 µs either way the earlier one. Correct while sender and
/// receiver clocks (plus latency) differ by less than 2^23 µs ≈ 8.4 s.
pub(super) fn nearest_freshness(fv_tx: u64, sync_now_us: u64) -> u64 {
    // Distance forward from `sync_now_us` to the next value with these low bits, < 2^24.
    let ahead = fv_tx.wrapping_sub(sync_now_us) & FRESHNESS_TX_MASK;
    let behind = FRESHNESS_TX_SPAN - ahead;
    let later = sync_now_us.checked_add(ahead);
    let earlier = sync_now_us.checked_sub(behind);
    let preferred = if ahead < FRESHNESS_TX_SPAN / 2 {
        later.or(earlier)
    } else {
        earlier.or(later)
    };
    // Both `None` would need a u64 range below 2^24: impossible; fall back to the bits.
    preferred.unwrap_or(fv_tx)
}
