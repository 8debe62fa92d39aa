//! Recordings written after the fact, on the host. On a guest route the bench runs inside an
//! emulated machine where writing a recording costs ≈ 15× its host time (the demo's: 0.5 s of
//! a 4.1 s run in the guest, 12 %; 0.04 s on the host); the stubs' outcome picture goes the
//! same way (`actuator-stubs --plot-later`, then `actuator-stubs draw-pending ROOT`). A caller
//! that runs the bench in a guest and can act when it ends (`demo.sh`, the test harness) sets
//! `RECORD_ON_HOST=1`: each run then leaves [`PENDING`] (what the recording needs to know that the folder cannot say) and
//! the caller runs [`write_pending`] (`record pending ROOT`) on the host afterwards. Without
//! the variable a run records itself, wherever it runs.

use crate::{write_run, write_run_mf4, RunMeta, WriteSummary, RUN_MCAP, RUN_MF4};
use anyhow::{Context, Result};
use serde::{Deserialize, Serialize};
use std::io::Write;
use std::path::{Path, PathBuf};

/// A run folder's note that its recording is still to be written.
pub const PENDING: &str = "record.pending.json";

/// The environment variable that asks runs to leave their recording to the caller.
pub const RECORD_ON_HOST: &str = "RECORD_ON_HOST";

/// What [`PENDING`] holds.
#[derive(Clone, Debug, Serialize, Deserialize)]
struct Pending {
    meta: RunMeta,
    /// Write `run.mf4` too.
    mf4: bool,
}

/// Whether runs should leave their recording to the caller ([`RECORD_ON_HOST`] set, not "0").
pub fn deferred() -> bool {
    std::env::var(RECORD_ON_HOST).is_ok_and(|v| !v.is_empty() && v != "0")
}

/// Leaves `dir`'s recording to [`write_pending`].
///
/// # Errors
/// The note cannot be written.
pub fn defer(dir: &Path, meta: &RunMeta) -> Result<()> {
    let mut meta = meta.clone();
    // The host resolves it from its own working directory.
    meta.scenario = meta.scenario.map(|p| std::path::absolute(&p).unwrap_or(p));
    write_note(dir, &Pending { meta, mf4: false })
}

/// Asks for `run.mf4` too where `dir`'s recording is pending; `false` when it is not (then the
/// caller writes the MF4 itself).
///
/// # Errors
/// The note cannot be read or written.
pub fn defer_mf4(dir: &Path) -> Result<bool> {
    let path = dir.join(PENDING);
    if !path.exists() {
        return Ok(false);
    }
    let mut p = read_note(&path)?;
    p.mf4 = true;
    write_note(dir, &p)?;
    Ok(true)
}

fn write_note(dir: &Path, p: &Pending) -> Result<()> {
    let path = dir.join(PENDING);
    std::fs::write(&path, serde_json::to_vec_pretty(p)?).with_context(|| path.display().to_string())
}

fn read_note(path: &Path) -> Result<Pending> {
    let text = std::fs::read_to_string(path).with_context(|| path.display().to_string())?;
    serde_json::from_str(&text).with_context(|| format!("{}: invalid", path.display()))
}

/// The run summary's line for a recording.
pub fn summary_line(dir: &Path, s: &WriteSummary, cost: &str) -> String {
    format!(
        "recording: {} ({} messages on {} topics, {:.0} kB, {cost}; open in Foxglove, docs/using.md \"Recordings\")",
        dir.join(RUN_MCAP).display(),
        s.messages.values().sum::<u64>(),
        s.messages.len(),
        s.bytes as f64 / 1e3,
    )
}

/// One pending recording, written.
#[derive(Debug)]
pub struct Written {
    /// The run folder.
    pub dir: PathBuf,
    /// Its summary lines (also appended to its `summary.txt`), or what failed.
    pub result: Result<Vec<String>, String>,
}

/// Writes every pending recording in `root` and its sub-folders (three levels: `OUT/<scenario>/`,
/// the campaign's `OUT/<guest>/<case>/<scenario>/`), appends each one's lines to its `summary.txt` and
/// removes its note. A folder that fails keeps its note and says why; the others are written.
///
/// # Errors
/// `root` cannot be read.
pub fn write_pending(root: &Path) -> Result<Vec<Written>> {
    let dirs = host::files::run_folders_holding(root, PENDING)?;
    Ok(dirs
        .into_iter()
        .map(|dir| {
            let result = write_one(&dir).map_err(|e| format!("{e:#}"));
            Written { dir, result }
        })
        .collect())
}

fn write_one(dir: &Path) -> Result<Vec<String>> {
    let note = dir.join(PENDING);
    let p = read_note(&note)?;
    let started = std::time::Instant::now();
    let s = write_run(dir, &dir.join(RUN_MCAP), &p.meta)?;
    let mut lines = vec![summary_line(
        dir,
        &s,
        &format!(
            "written on the host after the run in {:.2} s",
            started.elapsed().as_secs_f64()
        ),
    )];
    if p.mf4 {
        let m = write_run_mf4(dir, &dir.join(RUN_MF4))?;
        lines.push(crate::mf4::summary_line(&dir.join(RUN_MF4), &m));
    }
    let summary = dir.join("summary.txt");
    let mut f = std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(&summary)
        .with_context(|| summary.display().to_string())?;
    for l in &lines {
        writeln!(f, "{l}")?;
    }
    std::fs::remove_file(&note).with_context(|| note.display().to_string())?;
    Ok(lines)
}
