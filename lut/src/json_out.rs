//! `--json [FILE]`: where a `lut` command's JSON result goes — FILE, or stdout for `-` and for
//! a bare `--json` (instead of the command's table). Every result carries `schema_version`
//! ([`SCHEMA_VERSION`]; a list of rows carries it in each row).

use anyhow::{Context, Result};
use std::path::Path;

/// `schema_version` of every `lut … --json` result (docs/using.md, "JSON results").
pub const SCHEMA_VERSION: u32 = 1;

/// `value` as pretty JSON with its `schema_version` (no trailing newline).
///
/// # Errors
/// The value does not serialize.
pub fn text(value: &impl serde::Serialize) -> Result<String> {
    let doc = host::results::versioned_value(SCHEMA_VERSION, serde_json::to_value(value)?);
    Ok(serde_json::to_string_pretty(&doc)?)
}

/// Writes `value` as pretty JSON, with its `schema_version`, to `to` (`-`: stdout).
///
/// # Errors
/// The value does not serialize, or the file cannot be written.
pub fn write(to: &Path, value: &impl serde::Serialize) -> Result<()> {
    let text = text(value)?;
    host::results::write_json(to, &text).with_context(|| format!("--json {}", to.display()))?;
    if !host::results::is_stdout(to) {
        eprintln!("{} written", to.display());
    }
    Ok(())
}
