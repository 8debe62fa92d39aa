//! The timing report (text on stdout, JSON with `--report-json`).

use std::collections::BTreeMap;
use std::fmt::Write as _;

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
            activity,
            counters: counters.iter().copied().collect(),
            rt,
            can,
            ipc,
            stop_reason,
        }
    }

    /// Pretty JSON.
    pub fn to_json(&self) -> serde_json::Result<String> {
        serde_json::to_string_pretty(self)
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
                "  iceoryx2 [{}]: objects rx {} (err {}), accel rx {} (err {}), diagnostics written {} tx {} (err {}), stale nodes cleaned {}",
                ipc.service_prefix,
                ipc.object_rx,
                ipc.object_rx_errors,
                ipc.accel_rx,
                ipc.accel_rx_errors,
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
        let text = r.to_text();
        assert!(text.contains("cycles 3  overruns 1"), "{text}");
        assert!(text.contains("p99.9"), "{text}");
    }
}
