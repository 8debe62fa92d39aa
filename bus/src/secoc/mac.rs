//! The MAC: AES-128-CMAC over the 20-byte preimage, truncated to 40 bits, and the
//! authenticator frame that carries it (layout in the module docs of [`super`]).

use aes::Aes128;
use cmac::{Cmac, Mac};

use super::{
    SecOcError, SecOcKey, SecOcStream, FRESHNESS_TX_MASK, MAC_TX_BITS, MAC_TX_BYTES, PREIMAGE_LEN,
};
use crate::codec::{AirbagStageAuth, BeltLimiterAuth};
use crate::RawFrame;

/// AES-128-CMAC (RFC 4493) of `message`: the primitive every MAC in this module goes through,
/// exposed so that tests can check it against the RFC's published vectors.
#[must_use]
pub fn aes128_cmac(key: &SecOcKey, message: &[u8]) -> [u8; 16] {
    tag_of(key.cmac(), message)
}

pub(super) fn tag_of(mut mac: Cmac<Aes128>, message: &[u8]) -> [u8; 16] {
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

pub(super) fn mac40(
    mac: Cmac<Aes128>,
    stream: SecOcStream,
    payload: &[u8; 8],
    freshness: u64,
) -> u64 {
    let tag = tag_of(mac, &mac_preimage(stream, payload, freshness));
    tag.iter()
        .take(MAC_TX_BYTES)
        .fold(0u64, |acc, b| (acc << 8) | u64::from(*b))
}

/// Constant-time check of a received 40-bit MAC (RustCrypto's `verify_truncated_left`).
pub(super) fn mac40_ok(
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
