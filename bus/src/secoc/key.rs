//! The 128-bit stream keys and their hex form.

use super::mac::KeyedCmac;

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

    pub(super) fn cmac(&self) -> KeyedCmac {
        KeyedCmac::new(&self.0)
    }
}
