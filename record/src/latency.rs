//! `record latency`: how long after the start of the ECU cycle that sent it each command frame
//! arrived on the bus, from a recording's own times (issue 23 item 4).
//!
//! A frame's cycle is the latest cycle started at or before its arrival: the cycles' start
//! times are the diagnostics records' `timestamp_ns` (the cycle's wake time on
//! CLOCK_MONOTONIC), and a cycle whose record was never published (the newest-wins diagnostics
//! path, counted in the file's metadata) is placed between its neighbours by its
//! `cycle_count`. The arrival is candump's kernel stamp mapped onto the same clock (the file's
//! `log_time`). So the figure is the ECU's own path — cycle work, SecOC, the socket send and the
//! kernel — not the sensor's: the accelerometer batches are not in the recording.

use anyhow::{bail, Context, Result};
use serde_json::Value;
use std::collections::BTreeMap;
use std::path::Path;

/// One row of the report.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
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
}

/// Nearest-rank percentile of sorted values.
fn pct(sorted: &[f64], p: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    let rank = ((p / 100.0) * sorted.len() as f64).ceil().max(1.0) as usize;
    sorted[rank.min(sorted.len()) - 1]
}

fn row(what: String, mut v: Vec<f64>) -> Row {
    v.sort_by(f64::total_cmp);
    Row {
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
    let meta = mcap::Summary::read(&bytes)
        .ok()
        .flatten()
        .and_then(|s| {
            s.metadata_indexes
                .iter()
                .find(|i| i.name == "bench")
                .and_then(|i| mcap::read::metadata(&bytes, i).ok())
        })
        .map(|m| m.metadata)
        .unwrap_or_default();
    let mut known: Vec<(u64, u64)> = Vec::new();
    let mut frames: BTreeMap<String, Vec<(u64, Value)>> = BTreeMap::new();
    for m in mcap::MessageStream::new(&bytes).with_context(|| path.display().to_string())? {
        let m = m.with_context(|| format!("{}: damaged", path.display()))?;
        let topic = m.channel.topic.as_str();
        if topic == "/ecu/diagnostics" {
            let v: Value = serde_json::from_slice(&m.data)?;
            if let Some(c) = v["cycle_count"].as_u64() {
                known.push((c, m.log_time));
            }
        } else if let Some(name) = topic.strip_prefix("/can/") {
            if name != "raw" {
                frames
                    .entry(name.to_owned())
                    .or_default()
                    .push((m.log_time, serde_json::from_slice(&m.data)?));
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
    let mut before_first_cycle = 0;
    let mut since_cycle = |t: u64| -> Option<f64> {
        let i = starts.partition_point(|s| *s <= t);
        if i == 0 {
            before_first_cycle += 1;
            return None;
        }
        Some((t - starts[i - 1]) as f64 / 1e3)
    };
    let mut rows = Vec::new();
    let from_ecu: Vec<&str> = bus::MESSAGES
        .iter()
        .filter(|m| m.transmitter == "RestraintEcu")
        .map(|m| m.name)
        .collect();
    let mut fires: BTreeMap<&str, Vec<f64>> = BTreeMap::new();
    for name in &from_ecu {
        let Some(list) = frames.get(*name) else {
            continue;
        };
        let mut all = Vec::new();
        for (t, v) in list {
            let Some(l) = since_cycle(*t) else { continue };
            all.push(l);
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
        rows.push(row(format!("{name} (every frame)"), all));
    }
    for (what, v) in fires {
        rows.push(row(format!("{what} (first frame)"), v[..1].to_vec()));
        rows.push(row(format!("{what} (every frame)"), v));
    }
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
    })
}

impl Latency {
    /// The report as a table.
    pub fn table(&self) -> String {
        let mut s = format!(
            "latency from the start of the ECU cycle that sent a frame to the frame on the bus\n\
             (route {}, timing {})\n{:<36} {:>6} {:>9} {:>9} {:>9}\n",
            self.route, self.timing, "frames", "n", "p50 µs", "p99 µs", "max µs"
        );
        for r in &self.rows {
            s += &format!(
                "{:<36} {:>6} {:>9.1} {:>9.1} {:>9.1}\n",
                r.what, r.n, r.p50_us, r.p99_us, r.max_us
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
