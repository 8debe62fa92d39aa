//! AUTOSAR-style E2E protection, sender side: CRC-8 SAE J1850 over the data id and the
//! payload, and one 4-bit alive counter per protected message.

use crate::{RawFrame, E2E_MESSAGE_COUNT};

/// The CRC of the E2E scheme: CRC-8 SAE J1850 (poly 0x1D, init 0xFF, xor-out 0xFF), the one
/// AUTOSAR `Crc_CalculateCRC8` implements.
pub const E2E_CRC: crc::Crc<u8> = crc::Crc::<u8>::new(&crc::CRC_8_SAE_J1850);

/// CRC over the data id (low byte, high byte) and every payload byte except the CRC byte.
///
/// The data id is never sent; including it means a frame that is valid for one message can never
/// pass as another one (masquerading), which is what AUTOSAR E2E profile 1/11 do with it.
#[must_use]
pub fn e2e_crc(data_id: u16, crc_byte: usize, payload: &[u8]) -> u8 {
    let mut digest = E2E_CRC.digest();
    digest.update(&data_id.to_le_bytes());
    // The bytes before and after the CRC byte as two runs (one `update` per byte costs a call
    // and a branch each: this runs for every frame in and out of the cycle).
    let (before, after) = match payload.get(crc_byte..) {
        Some([_, rest @ ..]) => (&payload[..crc_byte], rest),
        _ => (payload, &[][..]), // the CRC byte beyond the payload: every byte counts
    };
    digest.update(before);
    digest.update(after);
    digest.finalize()
}

/// A generated message that carries E2E protection. Implemented by generated code for every
/// message with an `E2EDataId` attribute; the positions come from the DBC.
pub trait E2eMessage {
    /// DBC message name.
    const NAME: &'static str;
    /// `E2EDataId` attribute of the message.
    const DATA_ID: u16;
    /// Byte index of the CRC in the payload.
    const CRC_BYTE: usize;
    /// Index of this message in [`E2eProtector`]/[`E2eChecker`] state arrays.
    const SLOT: usize;
    /// The payload bytes.
    fn payload(&self) -> &[u8];
    /// The 4-bit alive counter as received.
    fn e2e_counter(&self) -> u8;
    /// The CRC byte as received.
    fn e2e_crc(&self) -> u8;
    /// Overwrites the alive counter (masked to 4 bits).
    fn set_e2e_counter(&mut self, counter: u8);
    /// Overwrites the CRC byte.
    fn set_e2e_crc(&mut self, crc: u8);
}

/// E2E fields of one received frame, taken through the generated [`E2eMessage`] impl.
#[derive(Debug, Clone, Copy)]
pub(crate) struct E2eView<'a> {
    pub(crate) slot: usize,
    pub(crate) data_id: u16,
    pub(crate) crc_byte: usize,
    pub(crate) counter: u8,
    pub(crate) crc: u8,
    pub(crate) payload: &'a [u8],
}

impl<'a> E2eView<'a> {
    pub(crate) fn of<M: E2eMessage>(m: &'a M) -> Self {
        Self {
            slot: M::SLOT,
            data_id: M::DATA_ID,
            crc_byte: M::CRC_BYTE,
            counter: m.e2e_counter(),
            crc: m.e2e_crc(),
            payload: m.payload(),
        }
    }
}

/// Sender side: one alive counter per protected message, so each stream counts 0,1,..,15,0,..
/// independently (as AUTOSAR E2E does per data id).
#[derive(Debug, Clone)]
pub struct E2eProtector {
    next_counter: [u8; E2E_MESSAGE_COUNT],
}

impl Default for E2eProtector {
    fn default() -> Self {
        Self::new()
    }
}

impl E2eProtector {
    /// All counters start at 0.
    #[must_use]
    pub const fn new() -> Self {
        Self {
            next_counter: [0; E2E_MESSAGE_COUNT],
        }
    }

    /// Writes the next alive counter and the CRC into `msg` (call after setting all signals).
    pub fn protect<M: E2eMessage>(&mut self, msg: &mut M) {
        let counter = self.next_counter.get(M::SLOT).copied().unwrap_or(0);
        msg.set_e2e_counter(counter);
        let crc = e2e_crc(M::DATA_ID, M::CRC_BYTE, msg.payload());
        msg.set_e2e_crc(crc);
        if let Some(c) = self.next_counter.get_mut(M::SLOT) {
            *c = (counter + 1) & 0x0F;
        }
    }

    /// [`protect`](Self::protect)s `msg` and returns the wire frame.
    pub fn seal<M: E2eMessage + embedded_can::Frame>(&mut self, mut msg: M) -> RawFrame {
        self.protect(&mut msg);
        RawFrame::from_message(&msg)
    }

    /// The counter the next [`protect`](Self::protect) of `M` will use.
    #[must_use]
    pub fn next_counter<M: E2eMessage>(&self) -> u8 {
        self.next_counter.get(M::SLOT).copied().unwrap_or(0)
    }
}
