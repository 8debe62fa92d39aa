//! The binary file format (versioned, checksummed postcard) and the JSON
//! export/import.
//!
//! Binary layout (all integers little-endian):
//!
//! | offset | size | content                                              |
//! |-------:|-----:|------------------------------------------------------|
//! | 0      | 8    | magic `89 52 4C 55 54 0D 0A 1A` (`\x89RLUT\r\n\x1a`) |
//! | 8      | 2    | format version (`u16`, currently [`FORMAT_VERSION`]) |
//! | 10     | 2    | reserved, must be 0                                  |
//! | 12     | 4    | payload length in bytes (`u32`)                      |
//! | 16     | 4    | CRC-32C (Castagnoli) over bytes 0..16 + the payload  |
//! | 20     | n    | payload: postcard encoding of [`DiagramData`]        |
//!
//! The magic's non-ASCII first byte and CR LF / SUB bytes catch text-mode
//! transfers and truncation the way PNG's signature does.

use std::fs;
use std::path::Path;

use crc::{Crc, CRC_32_ISCSI};
use serde::{Deserialize, Serialize};

use crate::data::{Axes, DiagramData, Header};
use crate::{Cell, Problem};

/// File magic number.
pub const MAGIC: [u8; 8] = [0x89, b'R', b'L', b'U', b'T', b'\r', b'\n', 0x1A];

/// Current (and only readable) binary + JSON format version. Bump it on ANY
/// change of the payload's structure or meaning; readers reject other
/// versions instead of guessing.
pub const FORMAT_VERSION: u16 = 1;

/// Bytes before the payload.
pub const PREAMBLE_LEN: usize = 20;

/// Value of the `"format"` field of the JSON export.
pub const JSON_FORMAT_NAME: &str = "restraint-characteristic-diagram";

/// What [`FileProblem::BadMagic`] names for a diagram file.
const DIAGRAM_FILE_KIND: &str = "restraint characteristic diagram";

const CRC32C: Crc<u32> = Crc::<u32>::new(&CRC_32_ISCSI);

/// A problem with a diagram file, naming the file.
#[derive(Debug, thiserror::Error)]
#[error("{file}: {problem}")]
pub struct LoadError {
    /// File name (as given by the caller).
    pub file: String,
    /// What is wrong.
    pub problem: FileProblem,
}

/// What is wrong with a diagram file.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum FileProblem {
    /// The file could not be read or written.
    #[error("I/O error: {0}")]
    Io(#[from] std::io::Error),
    /// Shorter than the fixed preamble.
    #[error("truncated: {len} bytes, shorter than the {need}-byte preamble")]
    TruncatedPreamble {
        /// File length.
        len: usize,
        /// Preamble length.
        need: usize,
    },
    /// Wrong magic number.
    #[error("bad magic {found:02x?}: not a {kind} file")]
    BadMagic {
        /// The first 8 bytes.
        found: [u8; 8],
        /// What kind of file was expected.
        kind: &'static str,
    },
    /// Unknown format version.
    #[error("unsupported format version {found} (this build reads version {supported})")]
    UnsupportedVersion {
        /// Stored version.
        found: u16,
        /// Version this build reads.
        supported: u16,
    },
    /// Reserved preamble field not zero.
    #[error("reserved preamble field is 0x{found:04x}, must be 0")]
    Reserved {
        /// Stored value.
        found: u16,
    },
    /// Fewer payload bytes than the preamble declares.
    #[error("truncated: preamble declares {declared} payload bytes, file holds {actual}")]
    TruncatedPayload {
        /// Declared payload length.
        declared: usize,
        /// Bytes present after the preamble.
        actual: usize,
    },
    /// More bytes than the preamble declares.
    #[error("{extra} unexpected bytes after the declared {declared}-byte payload")]
    TrailingBytes {
        /// Declared payload length.
        declared: usize,
        /// Extra bytes.
        extra: usize,
    },
    /// Stored and computed checksums differ.
    #[error("checksum mismatch (stored 0x{stored:08x}, computed 0x{computed:08x})")]
    ChecksumMismatch {
        /// CRC in the file / JSON.
        stored: u32,
        /// CRC of the content.
        computed: u32,
    },
    /// The payload passed the checksum but does not decode.
    #[error("payload does not decode: {0}")]
    Decode(String),
    /// JSON syntax or structure error.
    #[error("JSON: {0}")]
    Json(String),
    /// JSON `"format"` field is not [`JSON_FORMAT_NAME`].
    #[error("JSON format {found:?} is not {expected:?}")]
    JsonFormat {
        /// Found value.
        found: String,
        /// Expected value.
        expected: &'static str,
    },
    /// JSON `"lut_id"` does not match the content.
    #[error("LUT id mismatch (stored {stored:#06x}, computed {computed:#06x})")]
    LutIdMismatch {
        /// Stored id.
        stored: u16,
        /// Id of the content.
        computed: u16,
    },
    /// The content decodes but is not a valid diagram.
    #[error("{0}")]
    Invalid(#[from] Problem),
}

pub(crate) fn err(file: &str, problem: impl Into<FileProblem>) -> LoadError {
    LoadError {
        file: file.to_owned(),
        problem: problem.into(),
    }
}

/// Postcard payload of `data`.
fn payload_of(data: &DiagramData) -> Vec<u8> {
    // Serialising plain structs, Vecs, Strings and a BTreeMap into a Vec
    // cannot fail in postcard; an empty payload would be rejected on load.
    postcard::to_allocvec(data).unwrap_or_default()
}

fn preamble(magic: &[u8; 8], version: u16, payload_len: u32) -> [u8; 16] {
    let mut p = [0u8; 16];
    p[..8].copy_from_slice(magic);
    p[8..10].copy_from_slice(&version.to_le_bytes());
    p[10..12].copy_from_slice(&0u16.to_le_bytes());
    p[12..16].copy_from_slice(&payload_len.to_le_bytes());
    p
}

fn crc_of(pre: &[u8], payload: &[u8]) -> u32 {
    let mut d = CRC32C.digest();
    d.update(pre);
    d.update(payload);
    d.finalize()
}

/// Wrap `payload` in the checksummed envelope of the module docs (magic, version, length,
/// CRC-32C). Shared with other files of the toolchain (the LUT builder's shard files) so that
/// every file it writes detects truncation and corruption the same way.
pub fn frame(magic: &[u8; 8], version: u16, payload: &[u8]) -> Vec<u8> {
    let len = u32::try_from(payload.len()).unwrap_or(u32::MAX);
    let pre = preamble(magic, version, len);
    let crc = crc_of(&pre, payload);
    let mut out = Vec::with_capacity(PREAMBLE_LEN + payload.len());
    out.extend_from_slice(&pre);
    out.extend_from_slice(&crc.to_le_bytes());
    out.extend_from_slice(payload);
    out
}

/// Check the envelope written by [`frame`] (magic, version, reserved field, length, CRC-32C)
/// and return the payload. `kind` names the expected file kind in the bad-magic error.
pub fn unframe<'a>(
    magic: &[u8; 8],
    kind: &'static str,
    version: u16,
    bytes: &'a [u8],
) -> Result<&'a [u8], FileProblem> {
    if bytes.len() < PREAMBLE_LEN {
        return Err(FileProblem::TruncatedPreamble {
            len: bytes.len(),
            need: PREAMBLE_LEN,
        });
    }
    let mut found = [0u8; 8];
    found.copy_from_slice(&bytes[..8]);
    if &found != magic {
        return Err(FileProblem::BadMagic { found, kind });
    }
    let stored_version = read_u16(bytes, 8);
    if stored_version != version {
        return Err(FileProblem::UnsupportedVersion {
            found: stored_version,
            supported: version,
        });
    }
    let reserved = read_u16(bytes, 10);
    if reserved != 0 {
        return Err(FileProblem::Reserved { found: reserved });
    }
    let declared = read_u32(bytes, 12) as usize;
    let stored = read_u32(bytes, 16);
    let payload = &bytes[PREAMBLE_LEN..];
    if payload.len() < declared {
        return Err(FileProblem::TruncatedPayload {
            declared,
            actual: payload.len(),
        });
    }
    if payload.len() > declared {
        return Err(FileProblem::TrailingBytes {
            declared,
            extra: payload.len() - declared,
        });
    }
    let computed = crc_of(&bytes[..16], payload);
    if computed != stored {
        return Err(FileProblem::ChecksumMismatch { stored, computed });
    }
    Ok(payload)
}

/// Encode with an explicit version, WITHOUT validating (tests craft broken files with it).
fn encode_with_version(data: &DiagramData, version: u16) -> Vec<u8> {
    frame(&MAGIC, version, &payload_of(data))
}

pub(crate) fn checksum_of(data: &DiagramData) -> u32 {
    let payload = payload_of(data);
    let len = u32::try_from(payload.len()).unwrap_or(u32::MAX);
    crc_of(&preamble(&MAGIC, FORMAT_VERSION, len), &payload)
}

fn read_u16(b: &[u8], at: usize) -> u16 {
    let mut a = [0u8; 2];
    if let Some(s) = b.get(at..at + 2) {
        a.copy_from_slice(s);
    }
    u16::from_le_bytes(a)
}

fn read_u32(b: &[u8], at: usize) -> u32 {
    let mut a = [0u8; 4];
    if let Some(s) = b.get(at..at + 4) {
        a.copy_from_slice(s);
    }
    u32::from_le_bytes(a)
}

/// Decode the envelope and payload without validating the content.
pub(crate) fn decode_unvalidated(bytes: &[u8]) -> Result<DiagramData, FileProblem> {
    let payload = unframe(&MAGIC, DIAGRAM_FILE_KIND, FORMAT_VERSION, bytes)?;
    let (data, rest) = postcard::take_from_bytes::<DiagramData>(payload)
        .map_err(|e| FileProblem::Decode(e.to_string()))?;
    if !rest.is_empty() {
        return Err(FileProblem::Decode(format!(
            "{} bytes left after the diagram",
            rest.len()
        )));
    }
    Ok(data)
}

/// JSON export (serialise side, borrows the diagram).
#[derive(Serialize)]
struct JsonOut<'a> {
    format: &'static str,
    format_version: u16,
    crc32c: u32,
    lut_id: u16,
    header: &'a Header,
    axes: &'a Axes,
    cells: &'a [Cell],
}

/// JSON import. `crc32c` and `lut_id` are optional so a hand-edited table
/// can be imported after deleting them; when present they must match.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct JsonIn {
    format: String,
    format_version: u16,
    #[serde(default)]
    crc32c: Option<u32>,
    #[serde(default)]
    lut_id: Option<u16>,
    header: Header,
    axes: Axes,
    cells: Vec<Cell>,
}

/// The JSON export of `data` (pretty-printed), carrying the binary encoding's CRC-32C and the
/// LUT id so that an import reproduces the identical table.
pub(crate) fn json_string(data: &DiagramData, crc32c: u32, lut_id: u16) -> String {
    let out = JsonOut {
        format: JSON_FORMAT_NAME,
        format_version: FORMAT_VERSION,
        crc32c,
        lut_id,
        header: &data.header,
        axes: &data.axes,
        cells: &data.cells,
    };
    // Only plain data with finite floats and string map keys: cannot fail.
    serde_json::to_string_pretty(&out).unwrap_or_default()
}

/// A JSON export's data, not validated, with the CRC-32C and LUT id it carries (if any);
/// format name and version checked.
pub(crate) fn decode_json(
    text: &str,
) -> Result<(DiagramData, Option<u32>, Option<u16>), FileProblem> {
    let j: JsonIn = serde_json::from_str(text).map_err(|e| FileProblem::Json(e.to_string()))?;
    if j.format != JSON_FORMAT_NAME {
        return Err(FileProblem::JsonFormat {
            found: j.format,
            expected: JSON_FORMAT_NAME,
        });
    }
    if j.format_version != FORMAT_VERSION {
        return Err(FileProblem::UnsupportedVersion {
            found: j.format_version,
            supported: FORMAT_VERSION,
        });
    }
    let data = DiagramData {
        header: j.header,
        axes: j.axes,
        cells: j.cells,
    };
    Ok((data, j.crc32c, j.lut_id))
}

impl DiagramData {
    /// Encode into the binary file format WITHOUT validating the content.
    /// For tools and tests that need to produce a (possibly broken) file;
    /// use [`crate::Diagram::to_bytes`] for real tables.
    pub fn to_bytes_unvalidated(&self) -> Vec<u8> {
        encode_with_version(self, FORMAT_VERSION)
    }

    /// Like [`DiagramData::to_bytes_unvalidated`] with an arbitrary format
    /// version in the preamble (checksum computed over it), for testing
    /// version handling.
    pub fn to_bytes_with_version(&self, version: u16) -> Vec<u8> {
        encode_with_version(self, version)
    }
}

/// Write `bytes` to `path` atomically: a temporary file beside it, flushed to disk, then
/// renamed over `path`, so a reader (or a crash) sees the old file or the new one, never a
/// partial one.
pub fn write_atomically(path: &Path, bytes: &[u8]) -> Result<(), LoadError> {
    let name = path.display().to_string();
    let mut tmp = path.as_os_str().to_owned();
    tmp.push(format!(".tmp{}", std::process::id()));
    let tmp = std::path::PathBuf::from(tmp);
    let written = fs::File::create(&tmp).and_then(|mut f| {
        std::io::Write::write_all(&mut f, bytes)?;
        f.sync_all()
    });
    if let Err(e) = written {
        let _ = fs::remove_file(&tmp);
        return Err(err(&name, e));
    }
    fs::rename(&tmp, path).map_err(|e| {
        let _ = fs::remove_file(&tmp);
        err(&name, e)
    })
}
