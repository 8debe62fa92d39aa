//! The SecOC key file (TOML, std only): both streams' keys, loaded once at start.

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
        let table: toml::Table = text
            .parse()
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
