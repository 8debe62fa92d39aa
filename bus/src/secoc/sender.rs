//! The sender side: freshness and authenticator of each command frame.

use super::mac::{auth_frame, mac40, payload8, KeyedCmac};
use super::{SecOcError, SecOcKey, SecOcStream};
use crate::RawFrame;

/// Sender side of one stream: holds the keyed CMAC and the last freshness value used.
#[derive(Clone)]
pub struct SecOcSender {
    stream: SecOcStream,
    mac: KeyedCmac,
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
        let mac = mac40(&self.mac, self.stream, &payload, fv);
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
