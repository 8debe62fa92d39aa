//! The receive path: decoding that never panics and names why a frame was rejected, and the
//! E2E checker (CRC, alive counter, DLC, ranges) the ECU's cycle runs every frame through.

use crate::codec::{self, Messages};
use crate::e2e::E2eView;
use crate::{e2e_crc, message_info, meta, RawFrame, E2E_MESSAGE_COUNT};
use strum::EnumCount;

/// Why a received frame was rejected.
///
/// Its details stripped, it is a [`RejectReason`] (derived by strum: one list of reasons,
/// not a mirrored enum), for counting rejections by reason: `COUNT`, `VARIANTS` (index order)
/// and the report names (`name`: `crc_mismatch`, …).
#[derive(Debug, Clone, Copy, PartialEq, Eq, strum::EnumDiscriminants)]
#[strum_discriminants(
    name(RejectReason),
    vis(pub),
    derive(
        Hash,
        PartialOrd,
        Ord,
        strum::EnumCount,
        strum::VariantArray,
        strum::IntoStaticStr
    ),
    strum(serialize_all = "snake_case"),
    doc = "[`RxError`] without its details."
)]
pub enum RxError {
    /// The id is not in `restraint.dbc` (or is a 29-bit id).
    UnknownId(u32),
    /// Payload length differs from the DBC message size.
    WrongDlc {
        /// DBC size.
        expected: usize,
        /// Received length.
        got: usize,
    },
    /// The E2E CRC does not match data id + payload.
    CrcMismatch {
        /// CRC computed over the received bytes.
        computed: u8,
        /// CRC byte in the frame.
        received: u8,
    },
    /// Same alive counter as the previous accepted frame: a repeated or replayed frame.
    CounterRepeated {
        /// The counter value.
        counter: u8,
    },
    /// The counter jumped: `lost` frames are missing (more than the checker tolerates).
    CounterSkipped {
        /// Number of frames missing between the previous and this one (1..=14).
        lost: u8,
    },
    /// A signal's raw value lies outside its DBC `[min|max]`.
    OutOfRange(&'static str),
}

impl RejectReason {
    /// Stable short name for reports (`crc_mismatch`, …).
    #[must_use]
    pub fn name(self) -> &'static str {
        self.into()
    }
}

impl RxError {
    /// The reason without details.
    #[must_use]
    pub fn reason(&self) -> RejectReason {
        self.into()
    }
}

impl core::fmt::Display for RxError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::UnknownId(id) => write!(f, "unknown CAN id {id:#x}"),
            Self::WrongDlc { expected, got } => write!(f, "wrong DLC {got} (expected {expected})"),
            Self::CrcMismatch { computed, received } => {
                write!(
                    f,
                    "E2E CRC mismatch: received {received:#04x}, computed {computed:#04x}"
                )
            }
            Self::CounterRepeated { counter } => write!(f, "E2E alive counter {counter} repeated"),
            Self::CounterSkipped { lost } => {
                write!(f, "E2E alive counter skipped: {lost} frame(s) lost")
            }
            Self::OutOfRange(signal) => write!(f, "signal {signal} out of range"),
        }
    }
}

#[cfg(feature = "std")]
impl std::error::Error for RxError {}

/// Stateless decode: id, DLC, E2E CRC and signal ranges (no alive-counter check; use
/// [`E2eChecker::check`] on a receive path). Never panics, never allocates.
pub fn decode(id: u32, data: &[u8]) -> Result<Messages, RxError> {
    let msg = decode_layout(id, data)?;
    if let Some(v) = meta::e2e_view(&msg) {
        check_crc(&v)?;
    }
    if let Some(signal) = meta::out_of_range_signal(&msg) {
        return Err(RxError::OutOfRange(signal));
    }
    Ok(msg)
}

fn decode_layout(id: u32, data: &[u8]) -> Result<Messages, RxError> {
    let info = message_info(id).ok_or(RxError::UnknownId(id))?;
    if data.len() != info.size {
        return Err(RxError::WrongDlc {
            expected: info.size,
            got: data.len(),
        });
    }
    let sid = u16::try_from(id)
        .ok()
        .and_then(embedded_can::StandardId::new)
        .ok_or(RxError::UnknownId(id))?;
    Messages::from_can_message(embedded_can::Id::Standard(sid), data).map_err(|e| match e {
        codec::CanError::InvalidPayloadSize => RxError::WrongDlc {
            expected: info.size,
            got: data.len(),
        },
        _ => RxError::UnknownId(id),
    })
}

fn check_crc(v: &E2eView<'_>) -> Result<(), RxError> {
    let computed = e2e_crc(v.data_id, v.crc_byte, v.payload);
    if computed == v.crc {
        Ok(())
    } else {
        Err(RxError::CrcMismatch {
            computed,
            received: v.crc,
        })
    }
}

/// Receive counters of an [`E2eChecker`].
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct RxStats {
    /// Frames accepted.
    pub accepted: u64,
    /// Frames rejected, indexed by `RejectReason as usize`.
    pub rejected: [u64; RejectReason::COUNT],
    /// Frames lost according to counter jumps (tolerated or not).
    pub lost_frames: u64,
}

impl RxStats {
    /// Rejections for one reason.
    #[must_use]
    pub fn rejected_for(&self, reason: RejectReason) -> u64 {
        self.rejected.get(reason as usize).copied().unwrap_or(0)
    }
}

const NO_COUNTER: u8 = 0xFF;

/// Receiver side: decodes a frame, checks CRC, alive counter (per message) and ranges.
///
/// Counter rule (AUTOSAR-profile style): delta = (new − last) mod 16; 0 → repeated (rejected),
/// 1 → ok, more → `delta − 1` frames lost: accepted if `lost <= max_lost`, otherwise rejected as
/// [`RxError::CounterSkipped`]. A skipped frame re-synchronises the state, so only the frame after
/// the gap is rejected, not the stream. The first frame of a message (or after
/// [`reset`](Self::reset)) is accepted with any counter.
#[derive(Debug, Clone)]
pub struct E2eChecker {
    last_counter: [u8; E2E_MESSAGE_COUNT],
    max_lost: u8,
    stats: RxStats,
}

impl Default for E2eChecker {
    fn default() -> Self {
        Self::new()
    }
}

impl E2eChecker {
    /// Strict checker: any gap in the counter is reported ([`RxError::CounterSkipped`]).
    #[must_use]
    pub const fn new() -> Self {
        Self::with_max_lost(0)
    }

    /// Checker that accepts up to `max_lost` missing frames between two received ones
    /// (AUTOSAR `MaxDeltaCounter` = `max_lost + 1`).
    #[must_use]
    pub const fn with_max_lost(max_lost: u8) -> Self {
        Self {
            last_counter: [NO_COUNTER; E2E_MESSAGE_COUNT],
            max_lost,
            stats: RxStats {
                accepted: 0,
                rejected: [0; RejectReason::COUNT],
                lost_frames: 0,
            },
        }
    }

    /// Forgets all counters (e.g. after a sender timeout), so the next frame of each message is
    /// accepted with any counter.
    pub fn reset(&mut self) {
        self.last_counter = [NO_COUNTER; E2E_MESSAGE_COUNT];
    }

    /// Counters so far.
    #[must_use]
    pub fn stats(&self) -> &RxStats {
        &self.stats
    }

    /// Full receive check of one frame; updates counter state and statistics.
    /// Never panics, never allocates.
    pub fn check(&mut self, id: u32, data: &[u8]) -> Result<Messages, RxError> {
        let r = self.check_inner(id, data);
        match &r {
            Ok(_) => self.stats.accepted = self.stats.accepted.saturating_add(1),
            Err(e) => {
                if let Some(n) = self.stats.rejected.get_mut(e.reason() as usize) {
                    *n = n.saturating_add(1);
                }
            }
        }
        r
    }

    /// [`check`](Self::check) for the first frame of a message after its sender timed out:
    /// the alive counter of that message is forgotten first, so a restarted sender (whose
    /// counter starts anew) is accepted at once instead of costing one more rejected frame.
    /// CRC, length and ranges are checked as always. (AUTOSAR E2E re-initialises its state
    /// machine after "no new data" the same way.) Never panics, never allocates.
    pub fn check_resync(&mut self, id: u32, data: &[u8]) -> Result<Messages, RxError> {
        if let Ok(msg) = decode_layout(id, data) {
            if let Some(v) = meta::e2e_view(&msg) {
                if let Some(last) = self.last_counter.get_mut(v.slot) {
                    *last = NO_COUNTER;
                }
            }
        }
        self.check(id, data)
    }

    /// [`check`](Self::check) for a [`RawFrame`].
    pub fn check_frame(&mut self, frame: &RawFrame) -> Result<Messages, RxError> {
        self.check(frame.id, frame.payload())
    }

    fn check_inner(&mut self, id: u32, data: &[u8]) -> Result<Messages, RxError> {
        let msg = decode_layout(id, data)?;
        if let Some(v) = meta::e2e_view(&msg) {
            check_crc(&v)?;
            let counter = v.counter & 0x0F;
            if let Some(last) = self.last_counter.get_mut(v.slot) {
                if *last != NO_COUNTER {
                    let delta = counter.wrapping_sub(*last) & 0x0F;
                    if delta == 0 {
                        return Err(RxError::CounterRepeated { counter });
                    }
                    let lost = delta - 1;
                    *last = counter;
                    self.stats.lost_frames = self.stats.lost_frames.saturating_add(u64::from(lost));
                    if lost > self.max_lost {
                        return Err(RxError::CounterSkipped { lost });
                    }
                } else {
                    *last = counter;
                }
            }
        }
        if let Some(signal) = meta::out_of_range_signal(&msg) {
            return Err(RxError::OutOfRange(signal));
        }
        Ok(msg)
    }
}
