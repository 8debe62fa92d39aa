//! Why a command or an authenticator was refused.

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

/// [`SecOcError`] without details, for counting. `COUNT`, `VARIANTS` (index order) and the
/// report names (`name`) are derived (strum).
#[derive(
    Debug,
    Clone,
    Copy,
    PartialEq,
    Eq,
    Hash,
    PartialOrd,
    Ord,
    strum::EnumCount,
    strum::VariantArray,
    strum::IntoStaticStr,
)]
#[strum(serialize_all = "snake_case")]
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
    /// Stable short name for reports (`mac_mismatch`, …).
    #[must_use]
    pub fn name(self) -> &'static str {
        self.into()
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
