//! The timing report (text on stdout, JSON with `--json`).

use std::collections::BTreeMap;
use std::fmt::Write as _;

use hdrhistogram::Histogram;
use serde::Serialize;

use super::histogram::Percentiles;
use super::rt::RtState;
use super::run::LoopStats;

/// Percentiles in µs as they appear in the report.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PercentilesUs {
    /// Median, µs.
    pub p50: f64,
    /// 99th percentile, µs.
    pub p99: f64,
    /// 99.9th percentile, µs.
    pub p999: f64,
    /// Maximum, µs.
    pub max: f64,
}

impl From<Percentiles> for PercentilesUs {
    fn from(p: Percentiles) -> Self {
        let us = |ns: u64| ns as f64 / 1_000.0;
        Self {
            p50: us(p.p50_ns),
            p99: us(p.p99_ns),
            p999: us(p.p999_ns),
            max: us(p.max_ns),
        }
    }
}

/// Log-spaced histogram buckets per decade in the report (upper edges 0.1 µs · 10^(k/10)).
pub const HIST_BUCKETS_PER_DECADE: u32 = 10;
/// Upper edge of bucket k = 0, µs.
pub const HIST_LOWEST_UPPER_US: f64 = 0.1;

/// Index of the log bucket holding `value_us` (values ≤ the lowest edge go to bucket 0).
fn log_bucket(value_us: f64) -> usize {
    let k = f64::from(HIST_BUCKETS_PER_DECADE) * (value_us / HIST_LOWEST_UPPER_US).log10();
    // Tolerance so a value on an edge (1.0 µs) stays in the bucket it closes.
    (k - 1e-9).ceil().max(0.0) as usize
}

/// Upper edge of log bucket `k`, µs.
fn log_bucket_upper_us(k: usize) -> f64 {
    HIST_LOWEST_UPPER_US * 10f64.powf(k as f64 / f64::from(HIST_BUCKETS_PER_DECADE))
}

/// `[upper_us, count]` per log-spaced bucket, contiguous from the first to the last non-empty
/// bucket (zeros in between). Why: percentiles alone cannot be plotted as a distribution next
/// to cyclictest's histogram. Computed at report time from the preallocated hdrhistogram (each
/// of its sub-buckets assigned by its median-equivalent value, 0.1 % resolution); the loop
/// itself never allocates for it.
fn log_buckets_us(h: &Histogram<u64>) -> Vec<(f64, u64)> {
    let mut counts: Vec<u64> = Vec::new();
    for v in h.iter_recorded() {
        let us = h.median_equivalent(v.value_iterated_to()) as f64 / 1_000.0;
        let k = log_bucket(us);
        if counts.len() <= k {
            counts.resize(k + 1, 0);
        }
        if let Some(c) = counts.get_mut(k) {
            *c += v.count_since_last_iteration();
        }
    }
    let first = counts.iter().position(|&c| c > 0).unwrap_or(counts.len());
    counts
        .iter()
        .enumerate()
        .skip(first)
        .map(|(k, &c)| (log_bucket_upper_us(k), c))
        .collect()
}

/// CAN side status.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct CanStatus {
    /// Whether CAN I/O ran.
    pub enabled: bool,
    /// Interface name.
    pub interface: String,
    /// Why it is on/off.
    pub reason: String,
}

/// iceoryx2 status and counters.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct IpcStatus {
    /// Service-name prefix.
    pub service_prefix: String,
    /// Dead nodes cleaned up at start-up.
    pub stale_nodes_cleaned: u64,
    /// Dead nodes that could not be cleaned up.
    pub stale_nodes_failed: u64,
    /// Object states received.
    pub object_rx: u64,
    /// Object receive errors.
    pub object_rx_errors: u64,
    /// Accelerometer batches received.
    pub accel_rx: u64,
    /// Accelerometer receive errors.
    pub accel_rx_errors: u64,
    /// Safing accelerometer batches received.
    pub safing_rx: u64,
    /// Safing accelerometer receive errors.
    pub safing_rx_errors: u64,
    /// Satellite frame batches received (left, right).
    pub satellite_rx: [u64; 2],
    /// Satellite receive errors (left, right).
    pub satellite_rx_errors: [u64; 2],
    /// Diagnostics records written by the cycle.
    pub diagnostics_written: u64,
    /// Diagnostics records sent over iceoryx2 (newest-wins; ≤ written).
    pub diagnostics_tx: u64,
    /// Diagnostics loan/send failures.
    pub diagnostics_tx_errors: u64,
}

/// The complete report. JSON keys are part of the bench interface: `cycles`, `overruns`,
/// `wake_latency_us{p50,p99,p999,max}`, `exec_us{…}` are guaranteed.
#[derive(Debug, Serialize)]
pub struct TimingReport<'a> {
    /// Executed cycles.
    pub cycles: u64,
    /// Overrunning cycles.
    pub overruns: u64,
    /// Grid slots skipped because of overruns.
    pub skipped_slots: u64,
    /// Configured period, µs.
    pub period_us: f64,
    /// Wall time from first deadline to end, s.
    pub duration_s: f64,
    /// Wake-up latency (actual wake − deadline).
    pub wake_latency_us: PercentilesUs,
    /// Cycle execution time.
    pub exec_us: PercentilesUs,
    /// Wake-up latency histogram: `[upper_us, count]`, 10 log-spaced buckets per decade
    /// (upper edges 0.1 µs · 10^(k/10)), contiguous from the first to the last non-empty one.
    pub wake_latency_hist_us: Vec<(f64, u64)>,
    /// Execution-time histogram, same buckets.
    pub exec_hist_us: Vec<(f64, u64)>,
    /// Name of the activity that ran.
    pub activity: &'static str,
    /// Activity counters (input staleness etc.).
    pub counters: BTreeMap<&'static str, u64>,
    /// RT settings in effect.
    pub rt: &'a RtState,
    /// CAN status.
    pub can: CanStatus,
    /// iceoryx2 status (absent when run without iceoryx2, e.g. in tests).
    pub ipc: Option<IpcStatus>,
    /// Why the loop ended (`cycles`, `signal`).
    pub stop_reason: &'static str,
    /// The effective configuration the ECU ran with, as `ecu --show-config` prints it (TOML,
    /// each value followed by the layer it came from; absent when the caller gave none).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub config: Option<&'a str>,
}

impl<'a> TimingReport<'a> {
    /// Builds the report from the loop statistics.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        stats: &LoopStats,
        period_ns: u64,
        activity: &'static str,
        counters: &[(&'static str, u64)],
        rt: &'a RtState,
        can: CanStatus,
        ipc: Option<IpcStatus>,
        stop_reason: &'static str,
    ) -> Self {
        Self {
            cycles: stats.cycles,
            overruns: stats.overruns,
            skipped_slots: stats.skipped_slots,
            period_us: period_ns as f64 / 1_000.0,
            duration_s: stats.end_ns.saturating_sub(stats.first_deadline_ns) as f64 / 1e9,
            wake_latency_us: stats.wake_latency.percentiles().into(),
            exec_us: stats.exec.percentiles().into(),
            wake_latency_hist_us: log_buckets_us(stats.wake_latency.hdr()),
            exec_hist_us: log_buckets_us(stats.exec.hdr()),
            activity,
            counters: counters.iter().copied().collect(),
            rt,
            can,
            ipc,
            stop_reason,
            config: None,
        }
    }

    /// `schema_version` of the `--json` document (docs/using.md, "JSON results").
    pub const SCHEMA_VERSION: u32 = 1;

    /// Pretty JSON, `schema_version` first.
    pub fn to_json(&self) -> serde_json::Result<String> {
        host::results::to_json_pretty(Self::SCHEMA_VERSION, self)
    }

    /// Human-readable text.
    pub fn to_text(&self) -> String {
        let mut s = String::new();
        let row = |s: &mut String, name: &str, p: &PercentilesUs| {
            let _ = writeln!(
                s,
                "  {name:<14} p50 {:>9.1}  p99 {:>9.1}  p99.9 {:>9.1}  max {:>9.1}  µs",
                p.p50, p.p99, p.p999, p.max
            );
        };
        let _ = writeln!(
            s,
            "ECU timing report ({}, stopped by {})",
            self.activity, self.stop_reason
        );
        let _ = writeln!(
            s,
            "  cycles {}  overruns {}  skipped slots {}  period {:.1} µs  duration {:.3} s",
            self.cycles, self.overruns, self.skipped_slots, self.period_us, self.duration_s
        );
        row(&mut s, "wake latency", &self.wake_latency_us);
        row(&mut s, "exec time", &self.exec_us);
        let _ = writeln!(s, "  RT settings:");
        for l in self.rt.summary_lines() {
            let _ = writeln!(s, "    {l}");
        }
        let _ = writeln!(
            s,
            "    {:<12} {:<6} {} ({})",
            "can",
            if self.can.enabled { "ON" } else { "off" },
            self.can.interface,
            self.can.reason
        );
        if let Some(ipc) = &self.ipc {
            let _ = writeln!(
                s,
                "  iceoryx2 [{}]: objects rx {} (err {}), accel rx {} (err {}), safing rx {} (err {}), satellites rx {}/{} (err {}/{}), diagnostics written {} tx {} (err {}), stale nodes cleaned {}",
                ipc.service_prefix,
                ipc.object_rx,
                ipc.object_rx_errors,
                ipc.accel_rx,
                ipc.accel_rx_errors,
                ipc.safing_rx,
                ipc.safing_rx_errors,
                ipc.satellite_rx[0],
                ipc.satellite_rx[1],
                ipc.satellite_rx_errors[0],
                ipc.satellite_rx_errors[1],
                ipc.diagnostics_written,
                ipc.diagnostics_tx,
                ipc.diagnostics_tx_errors,
                ipc.stale_nodes_cleaned
            );
        }
        if !self.counters.is_empty() {
            let _ = write!(s, "  counters:");
            for (k, v) in &self.counters {
                let _ = write!(s, " {k}={v}");
            }
            let _ = writeln!(s);
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::super::config::RtConfig;
    use super::super::rt;
    use super::*;

    #[test]
    fn json_has_the_guaranteed_schema() {
        let mut stats = LoopStats::default();
        for v in [1_000u64, 2_000, 3_000] {
            stats.wake_latency.record_ns(v);
            stats.exec.record_ns(v * 10);
        }
        stats.cycles = 3;
        stats.overruns = 1;
        let rt = rt::apply(&RtConfig {
            prefault_stack_kib: 0,
            ..RtConfig::default()
        });
        let r = TimingReport::new(
            &stats,
            1_000_000,
            "test",
            &[("object_stale_cycles", 2)],
            &rt,
            CanStatus {
                enabled: false,
                interface: "vcan0".into(),
                reason: "--no-can".into(),
            },
            None,
            "cycles",
        );
        let v: serde_json::Value = serde_json::from_str(&r.to_json().unwrap()).unwrap();
        assert_eq!(v["cycles"], 3);
        assert_eq!(v["overruns"], 1);
        for h in ["wake_latency_us", "exec_us"] {
            for k in ["p50", "p99", "p999", "max"] {
                assert!(v[h][k].is_f64(), "{h}.{k} missing in {v}");
            }
        }
        // 3 values 1,2,3 µs: median 2 µs, max 3 µs (±0.1 %).
        assert!((v["wake_latency_us"]["p50"].as_f64().unwrap() - 2.0).abs() < 0.01);
        assert!((v["exec_us"]["max"].as_f64().unwrap() - 30.0).abs() < 0.05);
        assert_eq!(v["rt"]["sched"]["policy"], "SCHED_OTHER");
        assert_eq!(v["rt"]["sched"]["granted"], false);
        assert_eq!(v["rt"]["mlockall"]["requested"], false);
        assert_eq!(v["can"]["enabled"], false);
        assert_eq!(v["can"]["reason"], "--no-can");
        assert_eq!(v["counters"]["object_stale_cycles"], 2);
        // Log buckets, closed form k = ceil(10·log10(v / 0.1 µs)), upper edge 0.1·10^(k/10):
        // 1 µs → k 10 (edge 1.0), 2 µs → 13.01 → k 14 (2.512), 3 µs → 14.77 → k 15 (3.162);
        // contiguous k = 10..=15 → 6 buckets, the empty ones 0.
        let hist = v["wake_latency_hist_us"].as_array().unwrap();
        let buckets: Vec<(f64, u64)> = hist
            .iter()
            .map(|b| (b[0].as_f64().unwrap(), b[1].as_u64().unwrap()))
            .collect();
        assert_eq!(buckets.len(), 15 - 10 + 1, "{buckets:?}");
        let expect = |upper: f64, n: u64| {
            assert!(
                buckets
                    .iter()
                    .any(|&(u, c)| (u - upper).abs() < 1e-9 * upper && c == n),
                "no bucket ({upper}, {n}) in {buckets:?}"
            );
        };
        expect(1.0, 1);
        expect(0.1 * 10f64.powf(1.4), 1); // 2.512 µs holds 2 µs
        expect(0.1 * 10f64.powf(1.5), 1); // 3.162 µs holds 3 µs
        assert_eq!(buckets.iter().map(|b| b.1).sum::<u64>(), 3);
        assert_eq!(
            v["exec_hist_us"]
                .as_array()
                .unwrap()
                .iter()
                .map(|b| b[1].as_u64().unwrap())
                .sum::<u64>(),
            3
        );
        let text = r.to_text();
        assert!(text.contains("cycles 3  overruns 1"), "{text}");
        assert!(text.contains("p99.9"), "{text}");
    }
}
