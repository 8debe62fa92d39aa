//! AUTOSAR-SecOC-style authentication of the two fire-command streams.
//!
//! E2E protection (CRC + alive counter) detects corruption, but anyone on the bus can compute a
//! CRC: `cansend vcan0 030#…` with a correct CRC would fire an airbag. SecOC adds what E2E lacks,
//! a secret: every command frame is followed by a companion *authenticator* frame carrying a
//! freshness value and a truncated AES-128-CMAC, and the actuator acts on a command only once its
//! authenticator verifies.
//!
//! # Streams
//!
//! | stream | command | authenticator | data id |
//! |---|---|---|---|
//! | [`SecOcStream::AirbagStage`] | `AirbagStageCmd` 0x030 | `AirbagStageAuth` 0x031 | 0x1330 |
//! | [`SecOcStream::BeltLimiter`] | `BeltLimiterCmd` 0x040 | `BeltLimiterAuth` 0x041 | 0x1440 |
//!
//! The data id is the command's E2E data id (`E2EDataId` in the DBC); each stream has its own
//! 128-bit key and its own freshness sequence.
//!
//! # What the MAC covers (the "data to authenticate")
//!
//! ```text
//! preimage (20 bytes) = data id      (u16, big-endian)
//!                     ‖ command id   (u16, big-endian, the 11-bit CAN id)
//!                     ‖ command payload (all 8 bytes as sent: E2E CRC, alive counter, signals)
//!                     ‖ freshness    (u64, big-endian, the FULL value in µs, not the 24 sent bits)
//! tag   = AES-128-CMAC(stream key, preimage)            (RFC 4493, 16 bytes)
//! Mac   = tag[0..5] read as a big-endian integer          (the 40 most significant bits)
//! ```
//!
//! Big-endian ("network order") is what AUTOSAR SecOC uses for the data id and the freshness
//! value. Truncating to the *leftmost* bits is the SecOC/NIST SP 800-38B rule. The frame
//! carries `FreshnessValue` = low 24 bits of the freshness value and `Mac` as DBC signals (Intel byte
//! order, via the generated codec), so `cantools` shows both.
//!
//! # Pairing a command with its authenticator
//!
//! The sender transmits the command frame and, immediately after it, the authenticator computed
//! over that exact command payload. The receiver ([`SecOcVerifier`]):
//!
//! 1. runs its normal E2E check on the command frame; if that passes it calls
//!    [`SecOcVerifier::hold_command`], which stores the 8 payload bytes and the receive time.
//!    Only the latest command is held: a newer command replaces an unauthenticated older one
//!    (counted in [`SecOcStats::commands_dropped`]).
//! 2. on the authenticator frame calls [`SecOcVerifier::verify_auth`]. It fails with
//!    [`SecOcError::NoPendingCommand`] if nothing is held, with [`SecOcError::Stale`] if the
//!    authenticator arrives more than [`SecOcConfig::pairing_timeout_us`] after the command (the
//!    held command is then dropped), and otherwise reconstructs the full freshness value and
//!    checks the MAC over the *held* payload. Only on success does it return the payload
//!    ([`AuthenticatedCommand`]) for the actuator to decode and act on; the command is consumed,
//!    so it can be acted on once.
//!
//! Because the MAC covers the full payload including the E2E alive counter and CRC, an
//! authenticator can only pair with the one command it was computed for: a forged command
//! slipped in between (which replaces the held one) makes the genuine authenticator fail as
//! [`SecOcError::MacMismatch`] — a denial of that one command, never a wrong actuation. A failed
//! MAC check does *not* discard the held command, so a forged authenticator cannot block the
//! genuine one that follows.
//!
//! # Freshness: a synchronized time stamp
//!
//! The full freshness value is a `u64` count of microseconds on a *synchronized global time
//! base* (AUTOSAR SecOC with StbM time; on the bench CLOCK_REALTIME µs since the UNIX epoch —
//! all processes run on one machine; a vehicle would use its StbM/gPTP time). The sender
//! ([`SecOcSender::authenticate`]) uses `fv = max(previous fv + 1, sync_now_us)`: the current
//! time, but strictly increasing even for two authenticators in one microsecond or after a
//! backwards step of the clock.
//!
//! The receiver ([`SecOcVerifier::verify_auth`]) reconstructs `v` = the value congruent to the
//! received 24 bits (mod 2^24) that is nearest to its *own* `sync_now_us`, and accepts iff
//!
//! 1. the MAC verifies for `v`, and
//! 2. `|v − sync_now_us| <= `[`SecOcConfig::freshness_window_us`] (default 100 ms: bus latency
//!    plus scheduling stalls and the clock difference of sender and receiver), and
//! 3. `v > last_accepted` (each value is used at most once).
//!
//! On a failure it classifies the frame, spending at most two more CMACs:
//! - the MAC verifies for `v` but `v` is outside the window → [`SecOcError::FreshnessStale`]
//!   (genuine but old — a recording replayed later, a delayed frame — or from a clock that is
//!   too far off);
//! - the MAC verifies for `v` inside the window but `v <= last_accepted` →
//!   [`SecOcError::Replay`] (a genuine frame sent again right after the original);
//! - the MAC does not verify for `v` but for `v ∓ 2^24` (a genuine frame between ~8 s and ~25 s
//!   old or ahead, whose 24 bits reconstruct to the wrong span) → [`SecOcError::FreshnessStale`];
//! - otherwise → [`SecOcError::MacMismatch`]: forged, wrong key, corrupted — *or* a genuine
//!   frame recorded more than ~25 s earlier: the frame does not carry the upper 40 bits of its
//!   old time stamp, so without searching further spans (CMACs an attacker could make the
//!   receiver spend) it cannot be told apart from a forgery. It is rejected either way.
//!
//! Why time and not a counter: a counter restarts with every ECU start unless it is persisted,
//! and a receiver that accepts any value ahead of its own accepts a genuine fire command
//! recorded in an *earlier* session (its counter is ahead of the new session's), so a
//! `candump` from a crash test replayed with `cansend` later fired the airbag. A time stamp
//! needs no persistence: whatever was recorded earlier than the window is stale, and within the
//! window `last_accepted` rejects each value's second use.
//!
//! Limits (say them out loud):
//! - 2^24 µs ≈ 16.8 s: the nearest-congruent reconstruction is right while the sender's and the
//!   receiver's clocks (plus the latency) differ by less than 2^23 µs ≈ 8.4 s; the window is
//!   clamped below that ([`MAX_FRESHNESS_WINDOW_US`]), so whatever is accepted was
//!   reconstructed unambiguously. Beyond 8.4 s offset nothing is accepted (the MAC binds the
//!   full 64-bit value).
//! - A sender clock stepping back by more than the window makes the sender's values run ahead
//!   of the time (`previous + 1`) until the clock has caught up; the receiver rejects them as
//!   stale meanwhile. A small step (inside the window) is harmless. A synchronized time base
//!   does not step back in operation; on the bench, a CLOCK_REALTIME step would need NTP
//!   `step` — the bench never sets the clock while running.
//! - The security rests on the time base: whoever can set the receiver's clock back can make
//!   a recording fresh again (as with any time-based SecOC freshness; StbM time is itself
//!   authenticated in a vehicle).
//!
//! Start-up: nothing to agree on and nothing to persist. A new sender starts at the current
//! time, a new receiver with `last_accepted = 0` accepts whatever is fresh in the window.
//! A frame from an earlier session is outside the window (stale or MAC mismatch, as above);
//! within the window but already used it is a [`SecOcError::Replay`].
//!
//! # no_std
//!
//! Everything here except the key-file loader (feature `std`) is `no_std`, allocation-free and
//! panic-free: the ECU cycle calls [`SecOcTx::authenticate`] directly.

mod error;
mod key;
#[cfg(feature = "std")]
mod keyfile;
mod mac;
mod sender;
mod verifier;

pub use error::{SecOcError, SecOcReject};
pub use key::{KeyParseError, SecOcKey};
#[cfg(feature = "std")]
pub use keyfile::{KeyFileError, SecOcKeys, KEY_FILE_FORMAT};
pub use mac::{aes128_cmac, mac_preimage, truncated_mac};
pub use sender::{SecOcSender, SecOcTx};
pub use verifier::{AuthenticatedCommand, SecOcConfig, SecOcStats, SecOcVerifier};

use crate::codec::{AirbagStageAuth, AirbagStageCmd, BeltLimiterAuth, BeltLimiterCmd};
use crate::E2eMessage;

/// Bits of the freshness counter sent in the authenticator frame.
pub const FRESHNESS_TX_BITS: u32 = 24;
/// Mask of the transmitted freshness bits.
pub const FRESHNESS_TX_MASK: u64 = (1 << FRESHNESS_TX_BITS) - 1;
/// Bits of the truncated MAC sent in the authenticator frame.
pub const MAC_TX_BITS: u32 = 40;
/// Bytes of the CMAC tag that are sent (the leftmost ones).
pub const MAC_TX_BYTES: usize = 5;
/// Length of the data the MAC is computed over (see the module docs).
pub const PREIMAGE_LEN: usize = 20;
/// Span of the transmitted freshness bits: 2^24 µs ≈ 16.8 s.
pub const FRESHNESS_TX_SPAN: u64 = 1 << FRESHNESS_TX_BITS;
/// Largest allowed freshness window, µs: below half the transmitted span (2^23 µs ≈ 8.4 s), so
/// that every value inside the window is reconstructed unambiguously from its 24 bits.
pub const MAX_FRESHNESS_WINDOW_US: u64 = FRESHNESS_TX_SPAN / 2 - 1;

/// An authenticated command stream.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum SecOcStream {
    /// `AirbagStageCmd` (0x030) authenticated by `AirbagStageAuth` (0x031).
    AirbagStage,
    /// `BeltLimiterCmd` (0x040) authenticated by `BeltLimiterAuth` (0x041).
    BeltLimiter,
}

impl SecOcStream {
    /// Both streams.
    pub const ALL: [SecOcStream; 2] = [Self::AirbagStage, Self::BeltLimiter];

    /// CAN id of the command frame.
    #[must_use]
    pub const fn command_id(self) -> u32 {
        match self {
            Self::AirbagStage => AirbagStageCmd::RAW_ID,
            Self::BeltLimiter => BeltLimiterCmd::RAW_ID,
        }
    }

    /// CAN id of the authenticator frame.
    #[must_use]
    pub const fn auth_id(self) -> u32 {
        match self {
            Self::AirbagStage => AirbagStageAuth::RAW_ID,
            Self::BeltLimiter => BeltLimiterAuth::RAW_ID,
        }
    }

    /// Data id bound into the MAC (the command's E2E data id from the DBC).
    #[must_use]
    pub const fn data_id(self) -> u16 {
        match self {
            Self::AirbagStage => <AirbagStageCmd as E2eMessage>::DATA_ID,
            Self::BeltLimiter => <BeltLimiterCmd as E2eMessage>::DATA_ID,
        }
    }

    /// DBC name of the command frame; also the entry name in the key file.
    #[must_use]
    pub const fn name(self) -> &'static str {
        match self {
            Self::AirbagStage => <AirbagStageCmd as E2eMessage>::NAME,
            Self::BeltLimiter => <BeltLimiterCmd as E2eMessage>::NAME,
        }
    }

    /// Stream whose command frame has this id.
    #[must_use]
    pub fn for_command_id(id: u32) -> Option<Self> {
        Self::ALL.into_iter().find(|s| s.command_id() == id)
    }

    /// Stream whose authenticator frame has this id.
    #[must_use]
    pub fn for_auth_id(id: u32) -> Option<Self> {
        Self::ALL.into_iter().find(|s| s.auth_id() == id)
    }

    const fn index(self) -> usize {
        match self {
            Self::AirbagStage => 0,
            Self::BeltLimiter => 1,
        }
    }
}
