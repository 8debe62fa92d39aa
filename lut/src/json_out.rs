//! `--json [FILE]`: where a `lut` command's JSON result goes — FILE, or stdout for `-` and for
//! a bare `--json` (instead of the command's table).

use anyhow::{Context, Result};
use std::path::Path;

/// Writes `value` as pretty JSON to `to` (`-`: stdout).
///
/// # Errors
/// The value does not serialize, or the file cannot be written.
pub fn write(to: &Path, value: &impl serde::Serialize) -> Result<()> {
    let text = serde_json::to_string_pretty(value)?;
    if to == Path::new("-") {
        println!("{text}");
        return Ok(());
    }
    std::fs::write(to, text + "\n").with_context(|| format!("--json {}", to.display()))?;
    eprintln!("{} written", to.display());
    Ok(())
}
