//! Frames as they go on the wire and the DBC's tables about them: ids, sizes, signal layouts,
//! the bit packing the generated codecs use, and the raw-frame E2E edits of the bench's
//! attackers and fuzzers (positions from the DBC, never typed).

use crate::{e2e_crc, signals_of, CAN_EFF_FLAG, E2E_SIGNALS, MESSAGES};

/// One row of the generated message table.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MessageInfo {
    /// DBC message name.
    pub name: &'static str,
    /// 11-bit identifier.
    pub id: u32,
    /// Payload length (DLC) in bytes.
    pub size: usize,
    /// `GenMsgCycleTime`; `None` for event frames (the SecOC authenticators).
    pub cycle_time_ms: Option<u32>,
    /// `E2EDataId`; `None` for frames without E2E protection.
    pub e2e_data_id: Option<u16>,
    /// Sending node.
    pub transmitter: &'static str,
}

/// One signal of the generated signal tables (`<Message>::SIGNALS`, [`signals_of`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SignalInfo {
    /// DBC signal name.
    pub name: &'static str,
    /// DBC start bit (Intel byte order: LSB position).
    pub start_bit: u32,
    /// Width in bits.
    pub size: u32,
    /// Two's-complement raw value.
    pub signed: bool,
    /// phys = raw * factor + offset.
    pub factor: f64,
    /// phys = raw * factor + offset.
    pub offset: f64,
    /// DBC physical minimum.
    pub min: f64,
    /// DBC physical maximum.
    pub max: f64,
    /// Smallest valid raw value (from `min`).
    pub raw_min: i64,
    /// Largest valid raw value (from `max`).
    pub raw_max: i64,
    /// DBC unit.
    pub unit: &'static str,
    /// The signal's value table (`VAL_`: raw value → DBC name; empty when it has none).
    pub values: &'static [(i64, &'static str)],
    /// The DBC's comment on the signal (`CM_ SG_`; empty when it has none).
    pub comment: &'static str,
}

impl SignalInfo {
    /// The raw value of this signal in `payload` as the bits lie (no E2E or range check: what
    /// a bus logger or cantools shows for any frame with this id, forged ones included).
    #[must_use]
    pub fn raw(&self, payload: &[u8]) -> i64 {
        intel_raw(le_word(payload), self.start_bit, self.size, self.signed)
    }

    /// The physical value, `raw · factor + offset`.
    #[must_use]
    #[allow(clippy::cast_precision_loss)]
    pub fn value(&self, payload: &[u8]) -> f64 {
        self.raw(payload) as f64 * self.factor + self.offset
    }
}

/// Why a frame could not be encoded.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EncodeErrorKind {
    /// Value outside the DBC `[min|max]` of the signal.
    OutOfRange,
    /// NaN or infinite value.
    NotFinite,
    /// [`encode_values`]: id not in the DBC.
    UnknownId,
    /// [`encode_values`]: slice length differs from the signal count.
    WrongSignalCount,
}

/// Encoding failure, naming message and signal.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct EncodeError {
    /// DBC message name.
    pub message: &'static str,
    /// DBC signal name ("" if not signal-specific).
    pub signal: &'static str,
    /// What was wrong.
    pub kind: EncodeErrorKind,
}

impl core::fmt::Display for EncodeError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(
            f,
            "cannot encode {}.{}: {:?}",
            self.message, self.signal, self.kind
        )
    }
}

#[cfg(feature = "std")]
impl std::error::Error for EncodeError {}

/// A payload (≤ 8 bytes) as a little-endian word: the DBC's Intel signals are bit ranges of
/// it. The generated encoders, range checks and E2E accessors pack and unpack with shifts on
/// this word (a few instructions per signal) instead of dbc-codegen's bit-slice accessors
/// (≈ 100 per signal), measured in the ECU cycle's instruction budget (benches/README.md).
#[inline(always)]
pub(crate) fn le_word(bytes: &[u8]) -> u64 {
    let mut b = [0u8; 8];
    for (d, s) in b.iter_mut().zip(bytes) {
        *d = *s;
    }
    u64::from_le_bytes(b)
}

/// All-ones in the low `size` bits (`size` ≤ 64).
#[inline(always)]
const fn low_mask(size: u32) -> u64 {
    if size >= 64 {
        u64::MAX
    } else {
        (1u64 << size) - 1
    }
}

/// Raw value of the Intel signal of `size` bits (< 64) at `start` in `w`, sign-extended when
/// `signed`.
#[inline(always)]
pub(crate) const fn intel_raw(w: u64, start: u32, size: u32, signed: bool) -> i64 {
    let v = (w >> start) & low_mask(size);
    if signed && size > 0 && size < 64 {
        ((v << (64 - size)) as i64) >> (64 - size)
    } else {
        v as i64
    }
}

/// `w` with the Intel signal of `size` bits at `start` set to `raw` (two's complement, cut to
/// `size` bits; the caller range-checked it).
#[inline(always)]
pub(crate) const fn with_intel_raw(w: u64, start: u32, size: u32, raw: i64) -> u64 {
    let m = low_mask(size) << start;
    (w & !m) | (((raw as u64) << start) & m)
}

/// Physical → raw with rounding to the nearest step; `None` for NaN/inf or outside
/// `[raw_min, raw_max]` (a half step of tolerance absorbs float noise such as 11.9999 kN).
#[must_use]
pub(crate) fn raw_from_f64(
    v: f64,
    raw_min: i128,
    raw_max: i128,
    factor: f64,
    offset: f64,
) -> Option<i128> {
    if !v.is_finite() || factor == 0.0 {
        return None;
    }
    let x = (v - offset) / factor;
    // round half away from zero without std (libm-free): trunc via cast after offsetting.
    if x < raw_min as f64 - 0.5 || x > raw_max as f64 + 0.5 {
        return None;
    }
    let r = if x >= 0.0 { x + 0.5 } else { x - 0.5 };
    // f64 → i64 is one instruction, f64 → i128 a library call; i64 holds every raw value
    // below 2⁶² exactly (all of this bus's signals, 40-bit MACs included).
    let r = if r.abs() < 4.6e18 {
        i128::from(r as i64)
    } else {
        r as i128
    };
    Some(r.clamp(raw_min, raw_max))
}

/// The DBC name of `raw` in a generated value table (`<Message>::<SIGNAL>_VALUES`).
#[must_use]
pub fn value_name(table: &[(i64, &'static str)], raw: i64) -> Option<&'static str> {
    table.iter().find(|(v, _)| *v == raw).map(|(_, n)| *n)
}

/// Looks a frame id up in the generated table.
#[must_use]
pub fn message_info(id: u32) -> Option<&'static MessageInfo> {
    MESSAGES.iter().find(|m| m.id == id)
}

/// A frame as it goes on the wire: Linux `can_id` convention (bit 31 = extended id).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RawFrame {
    /// Identifier; for 29-bit frames [`CAN_EFF_FLAG`] is set.
    pub id: u32,
    /// Number of valid bytes in `data` (0..=8).
    pub len: u8,
    /// Payload, zero-padded.
    pub data: [u8; 8],
}

impl RawFrame {
    /// Builds a frame from any id and up to 8 bytes (longer input is truncated to 8, and the
    /// receiver will then see a wrong DLC rather than a panic).
    #[must_use]
    pub fn new(id: u32, bytes: &[u8]) -> Self {
        let mut data = [0u8; 8];
        let len = bytes.len().min(8);
        for (d, b) in data.iter_mut().zip(bytes.iter()) {
            *d = *b;
        }
        Self {
            id,
            len: len as u8,
            data,
        }
    }

    /// The valid payload bytes.
    #[must_use]
    pub fn payload(&self) -> &[u8] {
        let len = usize::from(self.len).min(8);
        self.data.get(..len).unwrap_or(&[])
    }

    /// The E2E layout of this frame's message from the DBC: data id, CRC signal, counter
    /// signal; `None` for a frame without E2E protection.
    fn e2e_layout(&self) -> Option<(u16, &'static SignalInfo, &'static SignalInfo)> {
        let data_id = message_info(self.id)?.e2e_data_id?;
        let signals = signals_of(self.id)?;
        let find = |name: &str| signals.iter().find(|s| s.name == name);
        Some((data_id, find(E2E_SIGNALS.0)?, find(E2E_SIGNALS.1)?))
    }

    /// The alive counter of an E2E-protected frame (positions from the DBC).
    #[must_use]
    pub fn e2e_counter(&self) -> Option<u8> {
        let (_, _, counter) = self.e2e_layout()?;
        let raw = intel_raw(
            le_word(self.payload()),
            counter.start_bit,
            counter.size,
            false,
        );
        u8::try_from(raw).ok()
    }

    /// Writes `counter` (cut to the signal's width) into the alive counter and re-seals the
    /// CRC, as a node whose counter jumped would send it; `false` for an unprotected frame.
    /// For the bench's attackers and fuzzers: nothing outside `bus` types a byte position.
    pub fn set_e2e_counter(&mut self, counter: u8) -> bool {
        let Some((_, _, c)) = self.e2e_layout() else {
            return false;
        };
        let w = with_intel_raw(
            le_word(self.payload()),
            c.start_bit,
            c.size,
            i64::from(counter),
        );
        let len = usize::from(self.len).min(8);
        self.data[..len].copy_from_slice(&w.to_le_bytes()[..len]);
        self.reseal()
    }

    /// Recomputes the E2E CRC over the frame as it now is; `false` for an unprotected frame.
    pub fn reseal(&mut self) -> bool {
        let Some((data_id, crc, _)) = self.e2e_layout() else {
            return false;
        };
        let byte = (crc.start_bit / 8) as usize;
        let value = e2e_crc(data_id, byte, self.payload());
        match self.data.get_mut(byte) {
            Some(b) if byte < usize::from(self.len) => {
                *b = value;
                true
            }
            _ => false,
        }
    }

    /// Whether the E2E CRC matches the frame (positions from the DBC); `None` for an
    /// unprotected frame. An oracle for fuzzers that does not go through the checker.
    #[must_use]
    pub fn e2e_crc_ok(&self) -> Option<bool> {
        let mut resealed = *self;
        resealed.reseal().then(|| resealed.data == self.data)
    }

    /// Inverts the CRC byte (a corrupted frame); `false` for an unprotected frame.
    pub fn corrupt_crc(&mut self) -> bool {
        let Some((_, crc, _)) = self.e2e_layout() else {
            return false;
        };
        let byte = (crc.start_bit / 8) as usize;
        match self.data.get_mut(byte) {
            Some(b) if byte < usize::from(self.len) => {
                *b = !*b;
                true
            }
            _ => false,
        }
    }

    /// Frame of a generated message, unchanged (E2E fields as they are).
    #[must_use]
    pub fn from_message<F: embedded_can::Frame>(msg: &F) -> Self {
        let id = match msg.id() {
            embedded_can::Id::Standard(s) => u32::from(s.as_raw()),
            embedded_can::Id::Extended(e) => e.as_raw() | CAN_EFF_FLAG,
        };
        Self::new(id, msg.data())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::encode_values;

    /// What the generated encoder packs, the table-driven reader reads back, for every signal
    /// of every message (at its minimum, maximum and a value in between).
    #[test]
    #[allow(clippy::cast_precision_loss)]
    fn every_signal_reads_back_what_the_encoder_packed() {
        for m in MESSAGES {
            let sigs = signals_of(m.id).unwrap();
            for pick in [0.0, 0.37, 1.0] {
                let raws: std::vec::Vec<i64> = sigs
                    .iter()
                    .map(|s| s.raw_min + ((s.raw_max - s.raw_min) as f64 * pick) as i64)
                    .collect();
                let vals: std::vec::Vec<f64> = sigs
                    .iter()
                    .zip(&raws)
                    .map(|(s, r)| *r as f64 * s.factor + s.offset)
                    .collect();
                let f = encode_values(m.id, &vals).unwrap();
                for ((s, r), v) in sigs.iter().zip(&raws).zip(&vals) {
                    assert_eq!(s.raw(f.payload()), *r, "{}.{}", m.name, s.name);
                    assert!((s.value(f.payload()) - v).abs() <= 1e-9 * v.abs().max(1.0));
                }
            }
        }
    }
}
