//! What a run folder holds, read once for every recording format: candump's frames, the stubs'
//! commands, report and diagnostics, and the realtime − monotonic offset between them.

use anyhow::{Context, Result};
use bus::candump::CandumpLog;
use serde::Deserialize;
use serde_json::Value;
use signals::{EcuDiagnostics, FeedLogRecord};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// What a recording takes from the actuator stubs' `report.json` to place it on the run's
/// timeline (`actuator_stubs::report::Report` owns the schema; the report is recorded as it
/// is, every other field included).
#[derive(Debug, Deserialize)]
pub(crate) struct ReportTimes {
    /// Scenario name.
    pub scenario: String,
    /// CLOCK_MONOTONIC scenario start [ns] (0 if the stubs received no bench truth).
    pub start_ns: u64,
    /// CLOCK_MONOTONIC true contact [ns] (0 = none).
    pub contact_ns: u64,
    /// The modules' actions, in the report's order.
    pub actions: Vec<ActionTime>,
}

/// When one of the stubs' actions happened.
#[derive(Debug, Deserialize)]
pub(crate) struct ActionTime {
    /// ms after the scenario's start.
    pub t_ms: f64,
}

/// A run folder's files, parsed.
pub(crate) struct RunFiles {
    pub candump_path: PathBuf,
    pub log: CandumpLog,
    /// `commands.jsonl` (empty without it) and how many of its lines were unreadable.
    pub commands: Vec<Value>,
    pub commands_unreadable: usize,
    /// `report.json`: the times a recording places on its timeline, and the report as it is
    /// (`None` without it).
    pub report: Option<(ReportTimes, Value)>,
    /// The stubs' diagnostics log: records and trailing bytes of a partial last record.
    pub diagnostics: (Vec<EcuDiagnostics>, usize),
    /// The feeds' log of what they published, and trailing bytes of a partial last record.
    pub feeds: (Vec<FeedLogRecord>, usize),
    /// CLOCK_REALTIME − CLOCK_MONOTONIC, ns (`None`: no frame seen by both candump and the
    /// stubs).
    pub offset: Option<i64>,
}

impl RunFiles {
    /// Reads `dir`: `candump.log` is required, `commands.jsonl`, `report.json` and the
    /// diagnostics log are read when present.
    pub fn read(dir: &Path) -> Result<Self> {
        let candump_path = dir.join("candump.log");
        let log = CandumpLog::read(&candump_path)
            .with_context(|| format!("reading {}", candump_path.display()))?;
        let commands_path = dir.join("commands.jsonl");
        let (commands, commands_unreadable) = if commands_path.exists() {
            read_jsonl(&commands_path)?
        } else {
            (Vec::new(), 0)
        };
        let report_path = dir.join("report.json");
        // Read once as JSON (recorded as it is) and its times from that.
        let report: Option<(ReportTimes, Value)> = if report_path.exists() {
            let text = std::fs::read_to_string(&report_path)
                .with_context(|| report_path.display().to_string())?;
            let json: Value = serde_json::from_str(&text)
                .with_context(|| format!("{}: invalid", report_path.display()))?;
            let typed = ReportTimes::deserialize(&json)
                .with_context(|| format!("{}: invalid", report_path.display()))?;
            Some((typed, json))
        } else {
            None
        };
        let diagnostics = read_postcard(&dir.join(crate::DIAGNOSTICS_LOG))?;
        let feeds = read_postcard(&dir.join(crate::FEEDS_LOG))?;
        let offset = clock_offset_ns(&log, &commands);
        Ok(Self {
            candump_path,
            log,
            commands,
            commands_unreadable,
            report,
            diagnostics,
            feeds,
            offset,
        })
    }
}

/// A run folder's CLOCK_REALTIME − CLOCK_MONOTONIC offset, ns, as its recordings use it — from
/// `candump.log` and `commands.jsonl` alone (`None`: no frame both saw, or no commands): what
/// puts a bench time on candump's clock.
///
/// # Errors
/// `candump.log` or `commands.jsonl` cannot be read.
pub fn run_clock_offset_ns(dir: &Path) -> Result<Option<i64>> {
    let candump_path = dir.join("candump.log");
    let log = CandumpLog::read(&candump_path)
        .with_context(|| format!("reading {}", candump_path.display()))?;
    let commands_path = dir.join("commands.jsonl");
    if !commands_path.exists() {
        return Ok(None);
    }
    let (commands, _) = read_jsonl(&commands_path)?;
    Ok(clock_offset_ns(&log, &commands))
}

/// candump's realtime stamps against the stubs' monotonic times of the same frames: the median
/// difference, ns (module docs).
fn clock_offset_ns(log: &CandumpLog, commands: &[Value]) -> Option<i64> {
    let mut by_frame: HashMap<(u32, String), Vec<u64>> = HashMap::new();
    for f in &log.frames {
        by_frame
            .entry((f.frame.id, bus::candump::data_hex(f.frame.payload())))
            .or_default()
            .push(f.t_us * 1_000);
    }
    let mut diffs: Vec<i64> = Vec::new();
    for c in commands {
        let (Some(id), Some(hex), Some(mono)) = (
            c["id"].as_u64(),
            c["data_hex"].as_str(),
            c["rx_mono_ns"].as_u64(),
        ) else {
            continue;
        };
        let Ok(id) = u32::try_from(id) else { continue };
        // Only payloads candump logged once: the E2E counter and CRC make nearly every command
        // frame unique, and a repeated payload could pair with the wrong stamp.
        if let Some([stamp]) = by_frame.get(&(id, hex.to_owned())).map(Vec::as_slice) {
            diffs.push(*stamp as i64 - mono as i64);
        }
    }
    if diffs.is_empty() {
        return None;
    }
    diffs.sort_unstable();
    Some(diffs[diffs.len() / 2])
}

/// A postcard log (the stubs' diagnostics, the feeds' publications): records back to back; a
/// process killed mid-write leaves a partial last record: its bytes are counted, not an error.
/// A file that is not there is an empty log.
fn read_postcard<T: serde::de::DeserializeOwned>(path: &Path) -> Result<(Vec<T>, usize)> {
    if !path.exists() {
        return Ok((Vec::new(), 0));
    }
    let bytes = std::fs::read(path).with_context(|| path.display().to_string())?;
    let mut rest = bytes.as_slice();
    let mut out = Vec::new();
    while !rest.is_empty() {
        match postcard::take_from_bytes::<T>(rest) {
            Ok((d, r)) => {
                out.push(d);
                rest = r;
            }
            Err(_) => break,
        }
    }
    Ok((out, rest.len()))
}

/// Cycles whose record is not in the log (gaps in `cycle_count`). The ECU publishes from a
/// helper thread the newest record of its triple buffer (the cycle never waits for iceoryx2), so
/// a record overwritten before that thread ran was never published: ≈ 5 % of the cycles in the
/// emulated guest, single records; a stall of the stubs beyond their queue would add more.
pub(crate) fn missed_cycles(d: &[EcuDiagnostics]) -> u64 {
    d.windows(2)
        .map(|w| {
            w[1].cycle_count
                .saturating_sub(w[0].cycle_count)
                .saturating_sub(1)
        })
        .sum()
}

/// A JSON-lines log and how many of its lines were no JSON object (a process killed mid-line
/// leaves a partial last line: counted in the metadata, the rest recorded).
fn read_jsonl(path: &Path) -> Result<(Vec<Value>, usize)> {
    let text = std::fs::read_to_string(path).with_context(|| path.display().to_string())?;
    let mut bad = 0;
    let values = text
        .lines()
        .filter(|l| !l.trim().is_empty())
        .filter_map(|l| match serde_json::from_str::<Value>(l) {
            Ok(v) if v.is_object() => Some(v),
            _ => {
                bad += 1;
                None
            }
        })
        .collect();
    Ok((values, bad))
}
