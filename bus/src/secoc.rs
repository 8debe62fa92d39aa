//! AUTOSAR-SecOC-style authentication of the two fire-command streams (issue 8).
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

use aes::Aes128;
use cmac::{digest::KeyInit, Cmac, Mac};

use crate::codec::{AirbagStageAuth, AirbagStageCmd, BeltLimiterAuth, BeltLimiterCmd};
use crate::{E2eMessage, RawFrame};

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

/// A 128-bit AES key. `Debug` never prints the key material.
#[derive(Clone, PartialEq, Eq)]
pub struct SecOcKey([u8; 16]);

impl core::fmt::Debug for SecOcKey {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str("SecOcKey(<redacted>)")
    }
}

/// Why a hex key string was refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum KeyParseError {
    /// Not 32 hex digits (after removing an optional `0x` and `_`/space separators).
    WrongLength {
        /// Hex digits found.
        digits: usize,
    },
    /// A character that is not a hex digit.
    NotHex {
        /// The offending character.
        found: char,
    },
    /// All bytes zero: certainly a placeholder, never a key.
    AllZero,
}

impl core::fmt::Display for KeyParseError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::WrongLength { digits } => {
                write!(f, "expected 32 hex digits (128 bits), found {digits}")
            }
            Self::NotHex { found } => write!(f, "{found:?} is not a hex digit"),
            Self::AllZero => f.write_str("all-zero key (a placeholder, not a key)"),
        }
    }
}

#[cfg(feature = "std")]
impl std::error::Error for KeyParseError {}

impl SecOcKey {
    /// Key from raw bytes.
    #[must_use]
    pub const fn from_bytes(bytes: [u8; 16]) -> Self {
        Self(bytes)
    }

    /// Key from 32 hex digits; an optional `0x` prefix and `_`, `:`, `-` or space separators are
    /// allowed (keys are often written in groups). All-zero keys are refused.
    pub fn from_hex(text: &str) -> Result<Self, KeyParseError> {
        let t = text.trim();
        let t = t
            .strip_prefix("0x")
            .or_else(|| t.strip_prefix("0X"))
            .unwrap_or(t);
        let mut out = [0u8; 16];
        let mut digits = 0usize;
        for c in t.chars() {
            if matches!(c, '_' | ':' | '-' | ' ') {
                continue;
            }
            let v = c.to_digit(16).ok_or(KeyParseError::NotHex { found: c })?;
            if let Some(byte) = out.get_mut(digits / 2) {
                // v < 16, so the cast cannot truncate.
                #[allow(clippy::cast_possible_truncation)]
                let v = v as u8;
                *byte = if digits.is_multiple_of(2) {
                    v << 4
                } else {
                    *byte | v
                };
            }
            digits += 1;
        }
        if digits != 32 {
            return Err(KeyParseError::WrongLength { digits });
        }
        if out == [0; 16] {
            return Err(KeyParseError::AllZero);
        }
        Ok(Self(out))
    }

    /// The key bytes (for tests and tools; never log them).
    #[must_use]
    pub const fn as_bytes(&self) -> &[u8; 16] {
        &self.0
    }

    fn cmac(&self) -> Cmac<Aes128> {
        <Cmac<Aes128> as KeyInit>::new(&self.0.into())
    }
}

/// AES-128-CMAC (RFC 4493) of `message`: the primitive every MAC in this module goes through,
/// exposed so that tests can check it against the RFC's published vectors.
#[must_use]
pub fn aes128_cmac(key: &SecOcKey, message: &[u8]) -> [u8; 16] {
    tag_of(key.cmac(), message)
}

fn tag_of(mut mac: Cmac<Aes128>, message: &[u8]) -> [u8; 16] {
    mac.update(message);
    mac.finalize().into_bytes().into()
}

/// The data the MAC is computed over (layout in the module docs). `command_payload` shorter
/// than 8 bytes is zero-padded; only 8-byte commands are ever authenticated.
#[must_use]
pub fn mac_preimage(
    stream: SecOcStream,
    command_payload: &[u8; 8],
    freshness: u64,
) -> [u8; PREIMAGE_LEN] {
    let mut p = [0u8; PREIMAGE_LEN];
    let data_id = stream.data_id().to_be_bytes();
    // The ids are 11-bit constants, so they fit u16.
    #[allow(clippy::cast_possible_truncation)]
    let cmd_id = (stream.command_id() as u16).to_be_bytes();
    let fv = freshness.to_be_bytes();
    for (dst, src) in p.iter_mut().zip(
        data_id
            .iter()
            .chain(cmd_id.iter())
            .chain(command_payload.iter())
            .chain(fv.iter()),
    ) {
        *dst = *src;
    }
    p
}

/// The 40-bit MAC (the leftmost 5 tag bytes as a big-endian integer) of a command with the
/// given full freshness value.
#[must_use]
pub fn truncated_mac(
    key: &SecOcKey,
    stream: SecOcStream,
    command_payload: &[u8; 8],
    freshness: u64,
) -> u64 {
    mac40(key.cmac(), stream, command_payload, freshness)
}

fn mac40(mac: Cmac<Aes128>, stream: SecOcStream, payload: &[u8; 8], freshness: u64) -> u64 {
    let tag = tag_of(mac, &mac_preimage(stream, payload, freshness));
    tag.iter()
        .take(MAC_TX_BYTES)
        .fold(0u64, |acc, b| (acc << 8) | u64::from(*b))
}

/// Constant-time check of a received 40-bit MAC (RustCrypto's `verify_truncated_left`).
fn mac40_ok(
    mac: &Cmac<Aes128>,
    stream: SecOcStream,
    payload: &[u8; 8],
    freshness: u64,
    received_mac: u64,
) -> bool {
    let mut m = mac.clone();
    m.update(&mac_preimage(stream, payload, freshness));
    let be = received_mac.to_be_bytes();
    // The 40-bit value sits in the low 5 of the 8 big-endian bytes.
    let tag = be.get(8 - MAC_TX_BYTES..).unwrap_or(&[]);
    m.verify_truncated_left(tag).is_ok()
}

/// Authenticator frame of `stream` with the given transmitted fields (through the generated
/// codec, so the layout is the DBC's).
fn auth_frame(stream: SecOcStream, freshness: u64, mac: u64) -> Result<RawFrame, SecOcError> {
    // Masked to 24 bits, so the cast cannot truncate.
    #[allow(clippy::cast_possible_truncation)]
    let fv = (freshness & FRESHNESS_TX_MASK) as u32;
    let mac = mac & ((1 << MAC_TX_BITS) - 1);
    match stream {
        SecOcStream::AirbagStage => AirbagStageAuth::new(fv, mac)
            .map(|m| RawFrame::from_message(&m))
            .map_err(|_| SecOcError::Encode),
        SecOcStream::BeltLimiter => BeltLimiterAuth::new(fv, mac)
            .map(|m| RawFrame::from_message(&m))
            .map_err(|_| SecOcError::Encode),
    }
}

/// (FreshnessValue, Mac) of a received authenticator payload.
fn auth_fields(stream: SecOcStream, payload: &[u8]) -> Result<(u64, u64), SecOcError> {
    if payload.len() != 8 {
        return Err(SecOcError::WrongDlc { got: payload.len() });
    }
    match stream {
        SecOcStream::AirbagStage => AirbagStageAuth::try_from(payload)
            .map(|m| (u64::from(m.freshness_value()), m.mac()))
            .map_err(|_| SecOcError::WrongDlc { got: payload.len() }),
        SecOcStream::BeltLimiter => BeltLimiterAuth::try_from(payload)
            .map(|m| (u64::from(m.freshness_value()), m.mac()))
            .map_err(|_| SecOcError::WrongDlc { got: payload.len() }),
    }
}

fn payload8(bytes: &[u8]) -> Result<[u8; 8], SecOcError> {
    <[u8; 8]>::try_from(bytes).map_err(|_| SecOcError::WrongDlc { got: bytes.len() })
}

/// Why an authenticator (or a command offered to SecOC) was rejected.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SecOcError {
    /// The frame is not 8 bytes long.
    WrongDlc {
        /// Received length.
        got: usize,
    },
    /// The frame id does not belong to this stream (or to any SecOC stream).
    WrongId(u32),
    /// An authenticator arrived with no command held (none received, already consumed, or
    /// dropped): nothing to authenticate.
    NoPendingCommand,
    /// The authenticator arrived too late after its command; the command was dropped.
    Stale {
        /// Time from command to authenticator.
        age_us: u64,
    },
    /// A genuine authenticator inside the freshness window whose freshness value was already
    /// used (a replayed frame).
    Replay {
        /// The (already used) full freshness value it verified with.
        freshness: u64,
    },
    /// A genuine authenticator whose time stamp is outside the freshness window around the
    /// receiver's synchronized time: an old frame replayed (e.g. recorded in an earlier session),
    /// a delayed one, or sender and receiver clocks too far apart.
    FreshnessStale {
        /// Full freshness value (µs) it verified with.
        freshness: u64,
        /// The receiver's synchronized time (µs) when it checked.
        sync_now_us: u64,
    },
    /// The MAC does not verify: forged, wrong key, or command/authenticator corrupted or
    /// mismatched.
    MacMismatch,
    /// Sender: the 64-bit freshness value is exhausted (never in practice: year 586 524).
    FreshnessExhausted,
    /// Sender: the authenticator could not be encoded (cannot happen with masked fields).
    Encode,
}

impl core::fmt::Display for SecOcError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::WrongDlc { got } => write!(f, "SecOC: wrong DLC {got} (expected 8)"),
            Self::WrongId(id) => write!(f, "SecOC: CAN id {id:#x} is not part of this stream"),
            Self::NoPendingCommand => f.write_str("SecOC: authenticator without a held command"),
            Self::Stale { age_us } => {
                write!(
                    f,
                    "SecOC: authenticator {age_us} us after its command (stale)"
                )
            }
            Self::Replay { freshness } => {
                write!(
                    f,
                    "SecOC: replayed authenticator (freshness {freshness} already used)"
                )
            }
            Self::FreshnessStale {
                freshness,
                sync_now_us,
            } => write!(
                f,
                "SecOC: stale freshness {freshness} us, receiver time {sync_now_us} us \
                 (outside the freshness window)"
            ),
            Self::MacMismatch => f.write_str("SecOC: MAC mismatch (forged or corrupted)"),
            Self::FreshnessExhausted => f.write_str("SecOC: freshness counter exhausted"),
            Self::Encode => f.write_str("SecOC: authenticator encoding failed"),
        }
    }
}

#[cfg(feature = "std")]
impl std::error::Error for SecOcError {}

/// [`SecOcError`] without details, for counting.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[repr(u8)]
pub enum SecOcReject {
    /// [`SecOcError::WrongDlc`] / [`SecOcError::WrongId`]
    Malformed = 0,
    /// [`SecOcError::NoPendingCommand`]
    NoPendingCommand = 1,
    /// [`SecOcError::Stale`] (authenticator too late after its command: pairing timeout)
    Stale = 2,
    /// [`SecOcError::Replay`]
    Replay = 3,
    /// [`SecOcError::FreshnessStale`]
    FreshnessStale = 4,
    /// [`SecOcError::MacMismatch`]
    MacMismatch = 5,
}

impl SecOcReject {
    /// Number of reasons.
    pub const COUNT: usize = 6;
    /// All reasons in index order.
    pub const ALL: [SecOcReject; Self::COUNT] = [
        Self::Malformed,
        Self::NoPendingCommand,
        Self::Stale,
        Self::Replay,
        Self::FreshnessStale,
        Self::MacMismatch,
    ];
    /// Stable short name for reports.
    #[must_use]
    pub const fn name(self) -> &'static str {
        match self {
            Self::Malformed => "malformed",
            Self::NoPendingCommand => "no_pending_command",
            Self::Stale => "stale",
            Self::Replay => "replay",
            Self::FreshnessStale => "freshness_stale",
            Self::MacMismatch => "mac_mismatch",
        }
    }
}

impl SecOcError {
    /// The reason without details (sender-only errors count as `Malformed`).
    #[must_use]
    pub const fn reason(&self) -> SecOcReject {
        match self {
            Self::WrongDlc { .. } | Self::WrongId(_) | Self::FreshnessExhausted | Self::Encode => {
                SecOcReject::Malformed
            }
            Self::NoPendingCommand => SecOcReject::NoPendingCommand,
            Self::Stale { .. } => SecOcReject::Stale,
            Self::Replay { .. } => SecOcReject::Replay,
            Self::FreshnessStale { .. } => SecOcReject::FreshnessStale,
            Self::MacMismatch => SecOcReject::MacMismatch,
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Sender

/// Sender side of one stream: holds the keyed CMAC and the last freshness value used.
#[derive(Clone)]
pub struct SecOcSender {
    stream: SecOcStream,
    mac: Cmac<Aes128>,
    last_freshness: u64,
}

impl core::fmt::Debug for SecOcSender {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("SecOcSender")
            .field("stream", &self.stream)
            .field("last_freshness", &self.last_freshness)
            .finish_non_exhaustive()
    }
}

impl SecOcSender {
    /// Sender of `stream`. There is no start value to agree on: the first authenticator takes
    /// its freshness from the synchronized clock.
    #[must_use]
    pub fn new(stream: SecOcStream, key: &SecOcKey) -> Self {
        Self {
            stream,
            mac: key.cmac(),
            last_freshness: 0,
        }
    }

    /// The stream.
    #[must_use]
    pub const fn stream(&self) -> SecOcStream {
        self.stream
    }

    /// Freshness value (µs) of the last authenticator (0 before the first).
    #[must_use]
    pub const fn last_freshness(&self) -> u64 {
        self.last_freshness
    }

    /// Authenticator frame for `command` (the exact frame that is sent, E2E fields already
    /// filled in); send it right after the command. `sync_now_us` is the synchronized time
    /// (µs; CLOCK_REALTIME since the UNIX epoch on the bench); the freshness value used is
    /// `max(last + 1, sync_now_us)`, strictly increasing whatever the clock does.
    /// No allocation, no panic.
    pub fn authenticate(
        &mut self,
        command: &RawFrame,
        sync_now_us: u64,
    ) -> Result<RawFrame, SecOcError> {
        if command.id != self.stream.command_id() {
            return Err(SecOcError::WrongId(command.id));
        }
        let payload = payload8(command.payload())?;
        let fv = self
            .last_freshness
            .checked_add(1)
            .ok_or(SecOcError::FreshnessExhausted)?
            .max(sync_now_us);
        let mac = mac40(self.mac.clone(), self.stream, &payload, fv);
        let frame = auth_frame(self.stream, fv, mac)?;
        self.last_freshness = fv;
        Ok(frame)
    }
}

/// Sender side of both streams, for the ECU: one call per command frame.
#[derive(Debug, Clone)]
pub struct SecOcTx {
    senders: [SecOcSender; 2],
}

impl SecOcTx {
    /// Both senders.
    #[must_use]
    pub fn new(airbag_key: &SecOcKey, belt_key: &SecOcKey) -> Self {
        Self {
            senders: [
                SecOcSender::new(SecOcStream::AirbagStage, airbag_key),
                SecOcSender::new(SecOcStream::BeltLimiter, belt_key),
            ],
        }
    }

    /// Authenticator for a command frame of either stream (dispatch by CAN id) at the
    /// synchronized time `sync_now_us` (see [`SecOcSender::authenticate`]); `WrongId` for any
    /// other frame.
    pub fn authenticate(
        &mut self,
        command: &RawFrame,
        sync_now_us: u64,
    ) -> Result<RawFrame, SecOcError> {
        let stream =
            SecOcStream::for_command_id(command.id).ok_or(SecOcError::WrongId(command.id))?;
        self.senders
            .get_mut(stream.index())
            .ok_or(SecOcError::WrongId(command.id))?
            .authenticate(command, sync_now_us)
    }

    /// The sender of one stream.
    #[must_use]
    pub fn sender(&self, stream: SecOcStream) -> Option<&SecOcSender> {
        self.senders.get(stream.index())
    }
}

// ---------------------------------------------------------------------------------------------
// Receiver

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
    mac: Cmac<Aes128>,
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
fn nearest_freshness(fv_tx: u64, sync_now_us: u64) -> u64 {
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

// ---------------------------------------------------------------------------------------------
// Key file (std)

#[cfg(feature = "std")]
pub use keyfile::{KeyFileError, SecOcKeys, KEY_FILE_FORMAT};

#[cfg(feature = "std")]
mod keyfile {
    use super::{KeyParseError, SecOcKey, SecOcStream};
    use std::path::{Path, PathBuf};

    /// Value of the `format` entry a key file must carry.
    pub const KEY_FILE_FORMAT: &str = "restraint-secoc-keys/1";

    /// The keys of both streams, loaded once at start.
    ///
    /// File format (TOML; `data/secoc-keys.example.toml` is an example — its keys are public,
    /// a real bench generates its own, e.g. `openssl rand -hex 16`):
    ///
    /// ```toml
    /// format = "restraint-secoc-keys/1"
    /// [keys]
    /// AirbagStageCmd = "32 hex digits"
    /// BeltLimiterCmd = "32 hex digits"
    /// ```
    #[derive(Debug, Clone, PartialEq, Eq)]
    pub struct SecOcKeys {
        keys: [SecOcKey; 2],
    }

    /// Why a key file was refused. Every variant names the file.
    #[derive(Debug)]
    pub enum KeyFileError {
        /// The file could not be read.
        Io {
            /// File.
            path: PathBuf,
            /// OS error.
            error: std::io::Error,
        },
        /// Not valid TOML.
        Toml {
            /// File.
            path: PathBuf,
            /// Parser message (with line/column).
            message: String,
        },
        /// `format` missing or not [`KEY_FILE_FORMAT`].
        Format {
            /// File.
            path: PathBuf,
            /// What was found.
            found: String,
        },
        /// A required key entry is missing or not a string.
        Missing {
            /// File.
            path: PathBuf,
            /// Entry name (`keys.AirbagStageCmd`, …).
            entry: String,
        },
        /// An entry's value is not a usable key.
        BadKey {
            /// File.
            path: PathBuf,
            /// Entry name.
            entry: String,
            /// Why.
            reason: KeyParseError,
        },
        /// An entry this program does not know (likely a typo of a stream name).
        Unknown {
            /// File.
            path: PathBuf,
            /// Entry name.
            entry: String,
        },
    }

    impl std::fmt::Display for KeyFileError {
        fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
            match self {
                Self::Io { path, error } => {
                    write!(f, "{}: cannot read SecOC key file: {error}", path.display())
                }
                Self::Toml { path, message } => {
                    write!(f, "{}: not valid TOML: {message}", path.display())
                }
                Self::Format { path, found } => write!(
                    f,
                    "{}: format = {found:?}, expected {KEY_FILE_FORMAT:?}",
                    path.display()
                ),
                Self::Missing { path, entry } => {
                    write!(f, "{}: missing string entry {entry}", path.display())
                }
                Self::BadKey {
                    path,
                    entry,
                    reason,
                } => write!(f, "{}: {entry}: {reason}", path.display()),
                Self::Unknown { path, entry } => write!(
                    f,
                    "{}: unknown entry {entry} (streams: AirbagStageCmd, BeltLimiterCmd)",
                    path.display()
                ),
            }
        }
    }

    impl std::error::Error for KeyFileError {
        fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
            match self {
                Self::Io { error, .. } => Some(error),
                Self::BadKey { reason, .. } => Some(reason),
                _ => None,
            }
        }
    }

    impl SecOcKeys {
        /// Keys given directly (tests, tools).
        #[must_use]
        pub fn new(airbag_stage: SecOcKey, belt_limiter: SecOcKey) -> Self {
            Self {
                keys: [airbag_stage, belt_limiter],
            }
        }

        /// Reads and validates a key file.
        pub fn load(path: &Path) -> Result<Self, KeyFileError> {
            let text = std::fs::read_to_string(path).map_err(|error| KeyFileError::Io {
                path: path.to_path_buf(),
                error,
            })?;
            Self::from_toml_str(&text, path)
        }

        /// Parses key-file text; `path` only labels errors.
        pub fn from_toml_str(text: &str, path: &Path) -> Result<Self, KeyFileError> {
            let p = || path.to_path_buf();
            let table: toml::Table =
                text.parse()
                    .map_err(|e: toml::de::Error| KeyFileError::Toml {
                        path: p(),
                        message: e.to_string().trim_end().to_owned(),
                    })?;
            match table.get("format") {
                Some(toml::Value::String(s)) if s == KEY_FILE_FORMAT => {}
                other => {
                    return Err(KeyFileError::Format {
                        path: p(),
                        found: other.map_or_else(|| "(missing)".to_owned(), ToString::to_string),
                    })
                }
            }
            for k in table.keys() {
                if k != "format" && k != "keys" {
                    return Err(KeyFileError::Unknown {
                        path: p(),
                        entry: k.clone(),
                    });
                }
            }
            let keys = match table.get("keys") {
                Some(toml::Value::Table(t)) => t,
                _ => {
                    return Err(KeyFileError::Missing {
                        path: p(),
                        entry: "[keys]".to_owned(),
                    })
                }
            };
            for k in keys.keys() {
                if !SecOcStream::ALL.iter().any(|s| s.name() == k) {
                    return Err(KeyFileError::Unknown {
                        path: p(),
                        entry: format!("keys.{k}"),
                    });
                }
            }
            let get = |s: SecOcStream| -> Result<SecOcKey, KeyFileError> {
                let entry = format!("keys.{}", s.name());
                match keys.get(s.name()) {
                    Some(toml::Value::String(hex)) => {
                        SecOcKey::from_hex(hex).map_err(|reason| KeyFileError::BadKey {
                            path: p(),
                            entry,
                            reason,
                        })
                    }
                    _ => Err(KeyFileError::Missing { path: p(), entry }),
                }
            };
            Ok(Self::new(
                get(SecOcStream::AirbagStage)?,
                get(SecOcStream::BeltLimiter)?,
            ))
        }

        /// Key of one stream.
        #[must_use]
        pub fn get(&self, stream: SecOcStream) -> &SecOcKey {
            match stream {
                SecOcStream::AirbagStage => &self.keys[0],
                SecOcStream::BeltLimiter => &self.keys[1],
            }
        }

        /// Sender side of both streams (ECU); freshness comes from the synchronized clock.
        #[must_use]
        pub fn tx(&self) -> super::SecOcTx {
            super::SecOcTx::new(&self.keys[0], &self.keys[1])
        }

        /// Receiver of one stream (actuator stub).
        #[must_use]
        pub fn verifier(
            &self,
            stream: SecOcStream,
            config: super::SecOcConfig,
        ) -> super::SecOcVerifier {
            super::SecOcVerifier::new(stream, self.get(stream), config)
        }
    }
}
