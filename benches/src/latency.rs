//! Wake-up latency data of the loop harness: cyclictest's histogram file and the ECU report.

use serde::Deserialize;

/// Percentiles in µs (p50, p99, p99.9, max), the ECU report's shape.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
pub struct PercentilesUs {
    /// Median.
    pub p50: f64,
    /// 99th percentile.
    pub p99: f64,
    /// 99.9th percentile.
    pub p999: f64,
    /// Maximum.
    pub max: f64,
}

/// cyclictest `-h MAX --histfile=F` output for one thread: counts per 1 µs bucket plus the
/// summary lines (exact max and overflow count, which the buckets cannot show).
#[derive(Debug, Clone, PartialEq)]
pub struct CyclictestHistogram {
    /// `counts[us]` = samples with latency in [us, us+1) µs.
    pub counts: Vec<u64>,
    /// Samples above the histogram range.
    pub overflows: u64,
    /// Exact maximum, µs.
    pub max_us: f64,
    /// Exact minimum, µs.
    pub min_us: f64,
    /// Average, µs.
    pub avg_us: f64,
}

fn summary_value(line: &str, key: &str) -> Option<f64> {
    let rest = line.strip_prefix(key)?;
    rest.split_whitespace().next()?.parse().ok()
}

impl CyclictestHistogram {
    /// Parses the histogram file (first thread's column).
    ///
    /// # Errors
    /// No bucket lines, or no `# Max Latencies` line.
    pub fn parse(text: &str) -> anyhow::Result<Self> {
        let mut counts = Vec::new();
        let (mut overflows, mut max_us, mut min_us, mut avg_us) = (0u64, None, 0.0, 0.0);
        for line in text.lines() {
            let line = line.trim();
            if let Some(v) = summary_value(line, "# Max Latencies:") {
                max_us = Some(v);
            } else if let Some(v) = summary_value(line, "# Min Latencies:") {
                min_us = v;
            } else if let Some(v) = summary_value(line, "# Avg Latencies:") {
                avg_us = v;
            } else if let Some(v) = summary_value(line, "# Histogram Overflows:") {
                overflows = v as u64;
            } else if !line.starts_with('#') && !line.is_empty() {
                let mut it = line.split_whitespace();
                if let (Some(b), Some(c)) = (it.next(), it.next()) {
                    if let (Ok(b), Ok(c)) = (b.parse::<usize>(), c.parse::<u64>()) {
                        if counts.len() <= b {
                            counts.resize(b + 1, 0);
                        }
                        if let Some(slot) = counts.get_mut(b) {
                            *slot += c;
                        }
                    }
                }
            }
        }
        anyhow::ensure!(
            !counts.is_empty(),
            "cyclictest histogram has no bucket lines"
        );
        let max_us =
            max_us.ok_or_else(|| anyhow::anyhow!("cyclictest histogram: no `# Max Latencies`"))?;
        Ok(Self {
            counts,
            overflows,
            max_us,
            min_us,
            avg_us,
        })
    }

    /// Total samples (including overflows).
    pub fn total(&self) -> u64 {
        self.counts.iter().sum::<u64>() + self.overflows
    }

    /// Value at quantile `q` (0..=1) with 1 µs resolution (upper edge of the bucket, so a
    /// percentile is never under-stated); a quantile that falls into the overflow region is
    /// reported as the exact max (an over-statement, and said so in the README).
    pub fn quantile_us(&self, q: f64) -> f64 {
        let total = self.total();
        if total == 0 {
            return f64::NAN;
        }
        let rank = (q * total as f64).ceil().max(1.0) as u64;
        let mut seen = 0;
        for (us, c) in self.counts.iter().enumerate() {
            seen += c;
            if seen >= rank {
                return ((us + 1) as f64).min(self.max_us.max(us as f64));
            }
        }
        self.max_us
    }

    /// The 1 µs buckets re-binned into the ECU report's log buckets (10 per decade, upper
    /// edges 0.1 µs · 10^(k/10)), as `(lower_us, upper_us, count)` from 1 µs to the last
    /// non-empty bucket; overflows go to the bucket of the exact max. A cyclictest bucket
    /// [us, us+1) goes to the log bucket containing its lower edge (cyclictest truncates to
    /// whole µs), so both histograms can be drawn on the same axes.
    pub fn log_buckets(&self) -> Vec<(f64, f64, u64)> {
        let step = 10f64.powf(0.1);
        let bucket = |us: f64| ((10.0 * (us / 0.1).log10()) - 1e-9).ceil().max(0.0) as usize;
        let mut counts: Vec<u64> = Vec::new();
        let mut add = |k: usize, n: u64| {
            if counts.len() <= k {
                counts.resize(k + 1, 0);
            }
            if let Some(c) = counts.get_mut(k) {
                *c += n;
            }
        };
        for (us, &n) in self.counts.iter().enumerate() {
            if n > 0 {
                add(bucket((us as f64).max(0.1)), n);
            }
        }
        if self.overflows > 0 {
            add(bucket(self.max_us.max(0.1)), self.overflows);
        }
        let first = counts.iter().position(|&c| c > 0).unwrap_or(counts.len());
        counts
            .iter()
            .enumerate()
            .skip(first)
            .map(|(k, &c)| {
                let upper = 0.1 * 10f64.powf(k as f64 / 10.0);
                (upper / step, upper, c)
            })
            .collect()
    }

    /// p50/p99/p99.9/max in the ECU report's shape.
    pub fn percentiles(&self) -> PercentilesUs {
        PercentilesUs {
            p50: self.quantile_us(0.5),
            p99: self.quantile_us(0.99),
            p999: self.quantile_us(0.999),
            max: self.max_us,
        }
    }
}

/// The parts of the ECU's `--json` the harness uses.
#[derive(Debug, Clone, Deserialize)]
pub struct EcuReport {
    /// Cycles run.
    pub cycles: u64,
    /// Overruns.
    pub overruns: u64,
    /// Cycle period.
    pub period_us: f64,
    /// Wake − deadline.
    pub wake_latency_us: PercentilesUs,
    /// Step duration.
    pub exec_us: PercentilesUs,
    /// Wake − deadline histogram, `[upper_us, count]` per log bucket (10 per decade, upper
    /// edges 0.1 µs · 10^(k/10)); empty from an ECU that predates it.
    #[serde(default)]
    pub wake_latency_hist_us: Vec<(f64, u64)>,
    /// Step duration histogram, same buckets.
    #[serde(default)]
    pub exec_hist_us: Vec<(f64, u64)>,
    /// Activity that ran (`passthrough` until the cycle logic lands).
    pub activity: String,
    /// RT settings as granted (kept as JSON, printed).
    pub rt: serde_json::Value,
    /// CAN status (the harness runs with `--no-can`).
    pub can: serde_json::Value,
}

#[cfg(test)]
mod tests {
    use super::*;

    const SAMPLE: &str = "# Histogram\n000000 000000\n000001 000000\n000002 000050\n000003 000040\n000004 000009\n000005 000000\n# Total: 000000099\n# Min Latencies: 00002\n# Avg Latencies: 00003\n# Max Latencies: 00250\n# Histogram Overflows: 00001\n# Histogram Overflow at cycle number:\n# Thread 0: 00042\n";

    #[test]
    fn parses_cyclictest_histogram_and_computes_percentiles() {
        let h = CyclictestHistogram::parse(SAMPLE).unwrap();
        assert_eq!(h.total(), 100);
        assert_eq!((h.overflows, h.max_us, h.min_us), (1, 250.0, 2.0));
        // 50 samples in [2,3) µs: p50 rank 50 → bucket 2 → upper edge 3 µs.
        assert_eq!(h.quantile_us(0.5), 3.0);
        // rank 99 → bucket 4 (50+40+9 = 99) → 5 µs.
        assert_eq!(h.quantile_us(0.99), 5.0);
        // rank 100 is the overflow sample → exact max.
        assert_eq!(h.quantile_us(0.999), 250.0);
        assert_eq!(h.percentiles().max, 250.0);
    }

    #[test]
    fn rebins_into_log_buckets() {
        let h = CyclictestHistogram::parse(SAMPLE).unwrap();
        let b = h.log_buckets();
        // 2 µs → k = ceil(10·log10(20)) = 14 (upper 2.512); 3 µs → 15 (3.162); 4 µs → 17
        // (10·log10(40) = 16.02 → 17, upper 5.012); the overflow at 250 µs → 34 (10·log10(2500)
        // = 33.98 → 34, upper 251.2). Contiguous from k = 14 to 34.
        assert_eq!(b.len(), 34 - 14 + 1, "{b:?}");
        let count_at = |upper: f64| {
            b.iter()
                .find(|x| (x.1 - upper).abs() < 1e-9 * upper)
                .map(|x| x.2)
        };
        assert_eq!(count_at(0.1 * 10f64.powf(1.4)), Some(50));
        assert_eq!(count_at(0.1 * 10f64.powf(1.5)), Some(40));
        assert_eq!(count_at(0.1 * 10f64.powf(1.7)), Some(9));
        assert_eq!(count_at(0.1 * 10f64.powf(3.4)), Some(1));
        assert_eq!(b.iter().map(|x| x.2).sum::<u64>(), 100);
    }

    #[test]
    fn empty_histogram_is_an_error() {
        assert!(CyclictestHistogram::parse("# Max Latencies: 00010\n").is_err());
        assert!(CyclictestHistogram::parse("000001 000003\n").is_err());
    }
}
