//! Preallocated latency histograms.
//!
//! `hdrhistogram::Histogram::new_with_bounds` allocates its whole counts array up front;
//! auto-resize is off unless enabled, and `saturating_record` clamps out-of-range values
//! to the bounds instead of growing, so recording never allocates (the allocation test in
//! `tests/shell/no_alloc.rs` checks this over the whole loop).

use hdrhistogram::Histogram;

/// Highest value tracked exactly (10 s in ns); larger values clamp to it.
const HIGHEST_NS: u64 = 10_000_000_000;
/// 3 significant digits: 0.1 % relative resolution.
const SIGFIG: u8 = 3;

/// A nanosecond latency histogram with a fixed range of 1 ns … 10 s.
#[derive(Debug, Clone)]
pub struct LatencyHistogram {
    h: Histogram<u64>,
}

/// Summary percentiles, ns (0 for an empty histogram).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Percentiles {
    /// Recorded values.
    pub count: u64,
    /// Median.
    pub p50_ns: u64,
    /// 99th percentile.
    pub p99_ns: u64,
    /// 99.9th percentile.
    pub p999_ns: u64,
    /// Maximum (within the 0.1 % resolution).
    pub max_ns: u64,
}

impl LatencyHistogram {
    /// Allocates the full range now (≈ 200 KiB), never again.
    pub fn new() -> Self {
        // The bounds are constants that satisfy hdrhistogram's preconditions
        // (low ≥ 1, high ≥ 2·low, sigfig ≤ 5), so creation cannot fail.
        let mut h = Histogram::new_with_bounds(1, HIGHEST_NS, SIGFIG)
            .unwrap_or_else(|_| unreachable!("constant histogram bounds are valid"));
        h.auto(false);
        Self { h }
    }

    /// Records one value; out-of-range values clamp. No allocation.
    pub fn record_ns(&mut self, value_ns: u64) {
        self.h.saturating_record(value_ns);
    }

    /// Forgets all values (keeps the allocation).
    pub fn reset(&mut self) {
        self.h.reset();
    }

    /// The underlying histogram, for report-time bucket export (`report.rs`).
    pub(super) fn hdr(&self) -> &Histogram<u64> {
        &self.h
    }

    /// Percentile summary.
    pub fn percentiles(&self) -> Percentiles {
        if self.h.is_empty() {
            return Percentiles::default();
        }
        Percentiles {
            count: self.h.len(),
            p50_ns: self.h.value_at_quantile(0.5),
            p99_ns: self.h.value_at_quantile(0.99),
            p999_ns: self.h.value_at_quantile(0.999),
            max_ns: self.h.max(),
        }
    }
}

impl Default for LatencyHistogram {
    fn default() -> Self {
        Self::new()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn within_rel(actual: u64, expected: u64, rel: f64) -> bool {
        (actual as f64 - expected as f64).abs() <= rel * expected as f64 + 1.0
    }

    #[test]
    fn empty_is_all_zero() {
        assert_eq!(
            LatencyHistogram::new().percentiles(),
            Percentiles::default()
        );
    }

    #[test]
    fn uniform_distribution_quantiles_match_closed_form() {
        // Each of 1..=100_000 ns once: the q-quantile is q·100_000.
        let mut h = LatencyHistogram::new();
        for v in 1..=100_000u64 {
            h.record_ns(v);
        }
        let p = h.percentiles();
        assert_eq!(p.count, 100_000);
        assert!(within_rel(p.p50_ns, 50_000, 1e-3), "{p:?}");
        assert!(within_rel(p.p99_ns, 99_000, 1e-3), "{p:?}");
        assert!(within_rel(p.p999_ns, 99_900, 1e-3), "{p:?}");
        assert!(within_rel(p.max_ns, 100_000, 1e-3), "{p:?}");
    }

    #[test]
    fn two_point_distribution_separates_tail() {
        // 990 × 1 µs and 10 × 1 ms: p99 is the 990th value (1 µs), p99.9 the 999th (1 ms).
        let mut h = LatencyHistogram::new();
        for _ in 0..990 {
            h.record_ns(1_000);
        }
        for _ in 0..10 {
            h.record_ns(1_000_000);
        }
        let p = h.percentiles();
        assert!(within_rel(p.p50_ns, 1_000, 1e-3), "{p:?}");
        assert!(within_rel(p.p99_ns, 1_000, 1e-3), "{p:?}");
        assert!(within_rel(p.p999_ns, 1_000_000, 1e-3), "{p:?}");
        assert!(within_rel(p.max_ns, 1_000_000, 1e-3), "{p:?}");
    }

    #[test]
    fn out_of_range_clamps_instead_of_growing() {
        let mut h = LatencyHistogram::new();
        h.record_ns(u64::MAX);
        h.record_ns(0);
        let p = h.percentiles();
        assert_eq!(p.count, 2);
        assert!(within_rel(p.max_ns, HIGHEST_NS, 1e-3));
    }
}
