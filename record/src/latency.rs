//! `record latency`: how long after the start of the ECU cycle that sent it, and after the
//! newest crash-accelerometer sample that cycle had, each command frame arrived on the bus, from
//! a recording's own times.
//!
//! A frame's cycle is the latest cycle started at or before its arrival: the cycles' start
//! times are the diagnostics records' `timestamp_ns` (the cycle's wake time on
//! CLOCK_MONOTONIC), and a cycle whose record was never published (the newest-wins diagnostics
//! path, counted in the file's metadata) is placed between its neighbours by its
//! `cycle_count`. The arrival is candump's kernel stamp mapped onto the same clock (the file's
//! `log_time`). So the cycle → bus figure is the ECU's own path — cycle work, SecOC, the socket
//! send and the kernel.
//!
//! **Sample → bus** adds the sensor's side: the sending cycle's diagnostics record names the
//! newest crash-accelerometer batch it had read (`last_accel_sequence`); that batch, as the feeds
//! published it (`/sensors/crash_accel`), gives the measurement time of its newest sample. The
//! figure is frame arrival − that sample's time: sampling-to-publish, the iceoryx2 hop, the wait
//! for the next cycle, the cycle and the bus. A frame whose cycle's record was never published
//! (the newest-wins path) has no such record and is counted, not guessed.

use anyhow::{bail, Context, Result};
use serde_json::Value;
use std::collections::{BTreeMap, HashMap};
use std::path::Path;

/// Where a latency is measured from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum From {
    /// The start of the ECU cycle that sent the frame.
    CycleStart,
    /// The newest crash-accelerometer sample the sending cycle had read.
    CrashSample,
}

/// One row of the report.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    /// What the latency is measured from.
    pub from: From,
    /// What was measured (`AirbagStageCmd (every frame)`, `airbag fire (first frame)` …).
    pub what: String,
    /// Frames measured.
    pub n: usize,
    /// Median, µs.
    pub p50_us: f64,
    /// 99th percentile (nearest rank), µs.
    pub p99_us: f64,
    /// Largest, µs.
    pub max_us: f64,
}

/// The report of one recording.
#[derive(Clone, Debug)]
pub struct Latency {
    /// Route and timing (`bench` metadata): emulated figures describe the emulator.
    pub route: String,
    /// `real`, `emulated (…)` or `unknown`.
    pub timing: String,
    /// The rows.
    pub rows: Vec<Row>,
    /// Frames that arrived before the first recorded cycle (not measured).
    pub before_first_cycle: usize,
    /// Frames whose cycle published no diagnostics record, or whose record names a batch not in
    /// the recording (no sample → bus figure).
    pub no_sample: usize,
    /// Frames sent before the first crash batch or after the feeds stopped (no sample the
    /// command could answer: not measured from a sample).
    pub outside_feeds: usize,
}

/// A cycle started this long after the feeds' last crash batch was published runs after the
/// feeds stopped (the batches come every ms while they play).
const FEEDS_STOPPED_AFTER_NS: u64 = 2_000_000;

/// Nearest-rank percentile of sorted values.
fn pct(sorted: &[f64], p: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    let rank = ((p / 100.0) * sorted.len() as f64).ceil().max(1.0) as usize;
    sorted[rank.min(sorted.len()) - 1]
}

fn row(from: From, what: String, mut v: Vec<f64>) -> Row {
    v.sort_by(f64::total_cmp);
    Row {
        from,
        what,
        n: v.len(),
        p50_us: pct(&v, 50.0),
        p99_us: pct(&v, 99.0),
        max_us: v.last().copied().unwrap_or(f64::NAN),
    }
}

/// Cycle start times by cycle count, gaps filled between known neighbours.
fn cycle_starts(known: &[(u64, u64)]) -> Vec<u64> {
    let mut out = Vec::new();
    for w in known.windows(2) {
        let ((c0, t0), (c1, t1)) = (w[0], w[1]);
        let steps = c1.saturating_sub(c0).max(1);
        for k in 0..steps {
            out.push(t0 + (t1.saturating_sub(t0)) * k / steps);
        }
    }
    if let Some((_, t)) = known.last() {
        out.push(*t);
    }
    out
}

/// Reads `path` and measures every command frame and every fire.
///
/// # Errors
/// The file cannot be read, is no MCAP, or holds no diagnostics (no cycle times).
pub fn latency(path: &Path) -> Result<Latency> {
    let bytes = std::fs::read(path).with_context(|| path.display().to_string())?;
    // Read leniently: a file without the metadata has its log times on the bench's clock.
    let meta = crate::read::bench_metadata(&bytes).unwrap_or_default();
    // Log times back on the bench's clock, where the sample times inside the messages are.
    let shift = crate::read::log_minus_bench_ns(&meta);
    let bench_ns = |log: u64| log.saturating_add_signed(-shift);
    let mut known: Vec<(u64, u64)> = Vec::new();
    // Cycle count → the newest crash batch the cycle had read; batch sequence → its newest
    // sample's time.
    let mut cycle_batch: HashMap<u64, u64> = HashMap::new();
    let mut batch_sample_ns: HashMap<u64, u64> = HashMap::new();
    let mut last_batch_ns = 0;
    let mut frames: BTreeMap<String, Vec<(u64, Value)>> = BTreeMap::new();
    for m in mcap::MessageStream::new(&bytes).with_context(|| path.display().to_string())? {
        let m = m.with_context(|| format!("{}: damaged", path.display()))?;
        let topic = m.channel.topic.as_str();
        if topic == "/ecu/diagnostics" {
            let v: Value = serde_json::from_slice(&m.data)?;
            if let Some(c) = v["cycle_count"].as_u64() {
                known.push((c, bench_ns(m.log_time)));
                if let Some(b) = v["last_accel_sequence"].as_u64() {
                    cycle_batch.insert(c, b);
                }
            }
        } else if topic == "/sensors/crash_accel" {
            let v: Value = serde_json::from_slice(&m.data)?;
            if let (Some(seq), Some(t)) = (v["sequence"].as_u64(), v["newest_sample_ns"].as_u64()) {
                batch_sample_ns.insert(seq, t);
                last_batch_ns = last_batch_ns.max(bench_ns(m.log_time));
            }
        } else if let Some(name) = topic.strip_prefix("/can/") {
            if name != "raw" {
                frames
                    .entry(name.to_owned())
                    .or_default()
                    .push((bench_ns(m.log_time), serde_json::from_slice(&m.data)?));
            }
        }
    }
    if known.is_empty() {
        bail!(
            "{}: no /ecu/diagnostics, so no cycle start times (a recording of a bench run has them)",
            path.display()
        );
    }
    known.sort_unstable();
    let starts = cycle_starts(&known);
    let first_cycle = known[0].0;
    let mut before_first_cycle = 0;
    let (mut no_sample, mut outside_feeds) = (0, 0);
    // A frame at `t`: µs since its cycle's start, and since the newest crash sample that cycle
    // had (when its record and that batch are in the recording, and the feeds were playing).
    let mut measure = |t: u64| -> Option<(f64, Option<f64>)> {
        let i = starts.partition_point(|s| *s <= t);
        if i == 0 {
            before_first_cycle += 1;
            return None;
        }
        let since_cycle = (t - starts[i - 1]) as f64 / 1e3;
        if batch_sample_ns.is_empty() {
            return Some((since_cycle, None));
        }
        let playing = starts[i - 1] <= last_batch_ns + FEEDS_STOPPED_AFTER_NS;
        let sample = match cycle_batch.get(&(first_cycle + i as u64 - 1)) {
            // Before the first batch, or after the feeds stopped (the newest sample then only
            // ages): no sample the command could answer.
            Some(0) => {
                outside_feeds += 1;
                None
            }
            Some(_) if !playing => {
                outside_feeds += 1;
                None
            }
            Some(b) => {
                let s = batch_sample_ns.get(b).filter(|s| **s <= t);
                if s.is_none() {
                    no_sample += 1;
                }
                s.map(|s| (t - s) as f64 / 1e3)
            }
            // The cycle's record was never published.
            None => {
                no_sample += 1;
                None
            }
        };
        Some((since_cycle, sample))
    };
    let mut rows = Vec::new();
    let from_ecu: Vec<&str> = bus::MESSAGES
        .iter()
        .filter(|m| m.transmitter == bus::ECU_NODE)
        .map(|m| m.name)
        .collect();
    let mut fires: BTreeMap<&str, Vec<(f64, Option<f64>)>> = BTreeMap::new();
    let mut sample_rows = Vec::new();
    for name in &from_ecu {
        let Some(list) = frames.get(*name) else {
            continue;
        };
        let (mut all, mut all_sample) = (Vec::new(), Vec::new());
        for (t, v) in list {
            let Some(l) = measure(*t) else { continue };
            all.push(l.0);
            all_sample.extend(l.1);
            let fire = match *name {
                "AirbagStageCmd" => v["Fire"] == 1,
                "BeltLimiterCmd" => v["PretensionerCmd"] == 1,
                _ => false,
            };
            if fire {
                let what = if *name == "AirbagStageCmd" {
                    "airbag fire"
                } else {
                    "pretensioner fire"
                };
                fires.entry(what).or_default().push(l);
            }
        }
        rows.push(row(From::CycleStart, format!("{name} (every frame)"), all));
        if !all_sample.is_empty() {
            sample_rows.push(row(
                From::CrashSample,
                format!("{name} (every frame)"),
                all_sample,
            ));
        }
    }
    for (what, v) in fires {
        let cycle: Vec<f64> = v.iter().map(|l| l.0).collect();
        rows.push(row(
            From::CycleStart,
            format!("{what} (first frame)"),
            cycle[..1].to_vec(),
        ));
        rows.push(row(
            From::CycleStart,
            format!("{what} (every frame)"),
            cycle,
        ));
        if let Some(first) = v[0].1 {
            sample_rows.push(row(
                From::CrashSample,
                format!("{what} (first frame)"),
                vec![first],
            ));
        }
        let sample: Vec<f64> = v.iter().filter_map(|l| l.1).collect();
        if !sample.is_empty() {
            sample_rows.push(row(
                From::CrashSample,
                format!("{what} (every frame)"),
                sample,
            ));
        }
    }
    rows.extend(sample_rows);
    Ok(Latency {
        route: meta
            .get("route")
            .cloned()
            .unwrap_or_else(|| "unknown".into()),
        timing: meta
            .get("timing")
            .cloned()
            .unwrap_or_else(|| "unknown".into()),
        rows,
        before_first_cycle,
        no_sample,
        outside_feeds,
    })
}

impl Latency {
    /// The row measuring `what` from `from`.
    pub fn row(&self, from: From, what: &str) -> Option<&Row> {
        self.rows.iter().find(|r| r.from == from && r.what == what)
    }

    /// The report as a table.
    pub fn table(&self) -> String {
        let mut s = format!("(route {}, timing {})\n", self.route, self.timing);
        for (from, title) in [
            (
                From::CycleStart,
                "from the start of the ECU cycle that sent a frame to the frame on the bus",
            ),
            (
                From::CrashSample,
                "from the newest crash-accelerometer sample that cycle had to the frame on the bus",
            ),
        ] {
            if !self.rows.iter().any(|r| r.from == from) {
                continue;
            }
            s += &format!(
                "latency {title}\n{:<36} {:>6} {:>9} {:>9} {:>9}\n",
                "frames", "n", "p50 µs", "p99 µs", "max µs"
            );
            for r in self.rows.iter().filter(|r| r.from == from) {
                s += &format!(
                    "{:<36} {:>6} {:>9.1} {:>9.1} {:>9.1}\n",
                    r.what, r.n, r.p50_us, r.p99_us, r.max_us
                );
            }
        }
        if !self.rows.iter().any(|r| r.from == From::CrashSample) {
            s += "(no sensor inputs in the recording: no sample → bus latency)\n";
        } else {
            s += &format!(
                "(not measured from a sample: {} frames from cycles whose diagnostics record was never \
                 published, {} sent before the first crash sample or after the feeds stopped)\n",
                self.no_sample, self.outside_feeds
            );
        }
        if self.before_first_cycle > 0 {
            s += &format!(
                "({} frames before the first recorded cycle, not measured)\n",
                self.before_first_cycle
            );
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percentiles_are_nearest_rank() {
        let v: Vec<f64> = (1..=100).map(f64::from).collect();
        assert_eq!(pct(&v, 50.0), 50.0);
        assert_eq!(pct(&v, 99.0), 99.0);
        assert_eq!(pct(&[7.0], 99.0), 7.0);
        assert!(pct(&[], 50.0).is_nan());
    }

    #[test]
    fn a_cycle_never_published_sits_between_its_neighbours() {
        let s = cycle_starts(&[(1, 1_000), (2, 2_000), (4, 4_100)]);
        assert_eq!(s, vec![1_000, 2_000, 3_050, 4_100]);
    }
}
