//! The MAC: AES-128-CMAC over the 20-byte preimage, truncated to 40 bits, and the
//! authenticator frame that carries it (layout in the module docs of [`super`]).

use aes::cipher::{BlockCipherEncrypt, KeyInit};
use aes::Aes128;
use ctutils::CtEq;

use super::{
    SecOcError, SecOcKey, SecOcStream, FRESHNESS_TX_MASK, MAC_TX_BITS, MAC_TX_BYTES, PREIMAGE_LEN,
};
use crate::codec::{AirbagStageAuth, BeltLimiterAuth};
use crate::RawFrame;

/// AES-128-CMAC (RFC 4493) of `message`: the primitive every MAC in this module goes through,
/// exposed so that tests can check it against the RFC's published vectors.
#[must_use]
pub fn aes128_cmac(key: &SecOcKey, message: &[u8]) -> [u8; 16] {
    key.cmac().tag(message)
}

/// AES-128-CMAC (RFC 4493) keyed once: the block cipher's key schedule (RustCrypto's `aes`,
/// AES-NI where the CPU has it) and both subkeys are derived when the key is set, so a tag
/// costs one AES block per 16 bytes of message and a few XORs. RustCrypto's `cmac` derives
/// the subkeys again in every finalisation (one more AES block) and is reused by cloning its
/// whole keyed state; with two authenticators a cycle that was ≈ 2 600 of a full cycle's
/// instructions (`benches/budgets.toml`).
#[derive(Clone)]
pub(super) struct KeyedCmac {
    cipher: Aes128,
    /// K1: the last block is complete.
    k1: [u8; 16],
    /// K2: the last block is padded with 10*.
    k2: [u8; 16],
}

impl KeyedCmac {
    pub(super) fn new(key: &[u8; 16]) -> Self {
        let cipher = Aes128::new(key.into());
        let mut l = aes::Block::default();
        cipher.encrypt_block(&mut l);
        let k1 = dbl(l.into());
        Self {
            cipher,
            k1,
            k2: dbl(k1),
        }
    }

    /// The 16-byte tag of `message` (RFC 4493 §2.4): every block but the last chained through
    /// the cipher; the last XORed with K1 when complete, else padded with 10* and XORed with
    /// K2. No allocation, no panic.
    pub(super) fn tag(&self, message: &[u8]) -> [u8; 16] {
        // The last block: the final 1–16 bytes (an empty message is one empty block).
        let split = message.len().saturating_sub(1) / 16 * 16;
        let (head, last) = message.split_at(split.min(message.len()));
        let mut x = aes::Block::default();
        for block in head.chunks_exact(16) {
            xor(&mut x, block);
            self.cipher.encrypt_block(&mut x);
        }
        let mut m = [0u8; 16];
        for (d, s) in m.iter_mut().zip(last) {
            *d = *s;
        }
        let subkey = if last.len() == 16 {
            &self.k1
        } else {
            if let Some(pad) = m.get_mut(last.len()) {
                *pad = 0x80;
            }
            &self.k2
        };
        xor(&mut x, &m);
        xor(&mut x, subkey);
        self.cipher.encrypt_block(&mut x);
        x.into()
    }
}

/// Doubling in GF(2¹²⁸) with the CMAC polynomial (RFC 4493 §2.3), without a branch on the
/// key-derived bit.
fn dbl(block: [u8; 16]) -> [u8; 16] {
    let v = u128::from_be_bytes(block);
    ((v << 1) ^ ((v >> 127) * 0x87)).to_be_bytes()
}

fn xor(x: &mut aes::Block, data: &[u8]) {
    for (a, b) in x.iter_mut().zip(data) {
        *a ^= *b;
    }
}

/// The data the MAC is computed over (layout in the module docs). `command_payload` shorter
/// than 8 bytes is zero-padded; only 8-byte commands are ever authenticated.
#[must_use]
pub fn mac_preimage(
    stream: SecOcStream,
    command_payload: &[u8; 8],
    freshness: u64,
) -> [u8; PREIMAGE_LEN] {
    let [d0, d1] = stream.data_id().to_be_bytes();
    // The ids are 11-bit constants, so they fit u16.
    #[allow(clippy::cast_possible_truncation)]
    let [c0, c1] = (stream.command_id() as u16).to_be_bytes();
    let [p0, p1, p2, p3, p4, p5, p6, p7] = *command_payload;
    let [f0, f1, f2, f3, f4, f5, f6, f7] = freshness.to_be_bytes();
    [
        d0, d1, c0, c1, p0, p1, p2, p3, p4, p5, p6, p7, f0, f1, f2, f3, f4, f5, f6, f7,
    ]
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
    mac40(&key.cmac(), stream, command_payload, freshness)
}

pub(super) fn mac40(
    mac: &KeyedCmac,
    stream: SecOcStream,
    payload: &[u8; 8],
    freshness: u64,
) -> u64 {
    let tag = mac.tag(&mac_preimage(stream, payload, freshness));
    tag.iter()
        .take(MAC_TX_BYTES)
        .fold(0u64, |acc, b| (acc << 8) | u64::from(*b))
}

/// Constant-time check of a received 40-bit MAC (the leftmost 5 tag bytes, compared as
/// RustCrypto's `verify_truncated_left` does, with `ctutils`).
pub(super) fn mac40_ok(
    mac: &KeyedCmac,
    stream: SecOcStream,
    payload: &[u8; 8],
    freshness: u64,
    received_mac: u64,
) -> bool {
    let tag = mac.tag(&mac_preimage(stream, payload, freshness));
    let be = received_mac.to_be_bytes();
    // The 40-bit value sits in the low 5 of the 8 big-endian bytes.
    let (Some(received), Some(ours)) = (be.get(8 - MAC_TX_BYTES..), tag.get(..MAC_TX_BYTES)) else {
        return false;
    };
    ours.ct_eq(received).into()
}

/// Authenticator frame of `stream` with the given transmitted fields (through the generated
/// codec, so the layout is the DBC's).
pub(super) fn auth_frame(
    stream: SecOcStream,
    freshness: u64,
    mac: u64,
) -> Result<RawFrame, SecOcError> {
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
pub(super) fn auth_fields(stream: SecOcStream, payload: &[u8]) -> Result<(u64, u64), SecOcError> {
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

pub(super) fn payload8(bytes: &[u8]) -> Result<[u8; 8], SecOcError> {
    <[u8; 8]>::try_from(bytes).map_err(|_| SecOcError::WrongDlc { got: bytes.len() })
}

#[cfg(test)]
mod tests {
    use super::KeyedCmac;
    use cmac::{Cmac, Mac};
    use proptest::prelude::*;

    proptest! {
        /// The keyed CMAC is RustCrypto's CMAC, tag for tag, for every key and message length
        /// (empty, a partial last block, whole blocks).
        #[test]
        fn the_keyed_cmac_is_the_reference_cmac(
            key in any::<[u8; 16]>(),
            message in proptest::collection::vec(any::<u8>(), 0..80),
        ) {
            let mut reference = <Cmac<aes::Aes128> as cmac::digest::KeyInit>::new(&key.into());
            reference.update(&message);
            let want: [u8; 16] = reference.finalize().into_bytes().into();
            prop_assert_eq!(KeyedCmac::new(&key).tag(&message), want);
        }
    }
}
