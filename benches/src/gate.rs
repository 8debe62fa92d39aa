//! Budget evaluation: criterion's `estimates.json` (and callgrind counts) against budgets.toml.
//!
//! Criterion has no thresholds of its own; it writes, per benchmark,
//! `<target>/criterion/<dir>/new/benchmark.json` (with the `full_id`) and
//! `.../new/estimates.json` (point estimates and bootstrap confidence intervals, in ns).
//! Only results written *during this gate run* count: a stale result of an earlier run (or of a
//! bench since deleted) must never make a missing benchmark look measured.

use crate::budgets::{Bound, Statistic};
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::SystemTime;

#[derive(Deserialize)]
struct BenchmarkJson {
    full_id: String,
}

#[derive(Deserialize)]
struct Interval {
    upper_bound: f64,
}

#[derive(Deserialize)]
struct Estimate {
    point_estimate: f64,
    confidence_interval: Interval,
}

#[derive(Deserialize)]
struct EstimatesJson {
    mean: Estimate,
    median: Estimate,
}

/// One benchmark's result, in µs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Measured {
    /// Chosen point estimate, µs.
    pub point_us: f64,
    /// Upper bound of its 95 % CI, µs.
    pub upper_us: f64,
}

impl Measured {
    /// The figure compared with the budget.
    pub fn value(&self, bound: Bound) -> f64 {
        match bound {
            Bound::Point => self.point_us,
            Bound::UpperBound => self.upper_us,
        }
    }
}

/// All criterion results under `criterion_dir` written at or after `since`, by full id.
///
/// # Errors
/// Unreadable or malformed JSON files (a broken result is an error, not a skip).
pub fn read_criterion_results(
    criterion_dir: &Path,
    since: SystemTime,
    statistic: Statistic,
) -> anyhow::Result<BTreeMap<String, Measured>> {
    let mut out = BTreeMap::new();
    let mut stack = vec![criterion_dir.to_path_buf()];
    while let Some(dir) = stack.pop() {
        let Ok(rd) = std::fs::read_dir(&dir) else {
            continue;
        };
        for entry in rd.flatten() {
            let p = entry.path();
            if p.is_dir() {
                if p.file_name().is_some_and(|n| n == "new") {
                    if let Some((id, m)) = read_one(&p, since, statistic)? {
                        out.insert(id, m);
                    }
                } else {
                    stack.push(p);
                }
            }
        }
    }
    Ok(out)
}

fn read_one(
    new_dir: &Path,
    since: SystemTime,
    statistic: Statistic,
) -> anyhow::Result<Option<(String, Measured)>> {
    let est_path = new_dir.join("estimates.json");
    let bench_path = new_dir.join("benchmark.json");
    let (Ok(meta), true) = (std::fs::metadata(&est_path), bench_path.exists()) else {
        return Ok(None);
    };
    if meta.modified()? < since {
        return Ok(None);
    }
    let b: BenchmarkJson = serde_json::from_str(&std::fs::read_to_string(&bench_path)?)
        .map_err(|e| anyhow::anyhow!("{}: {e}", bench_path.display()))?;
    let e: EstimatesJson = serde_json::from_str(&std::fs::read_to_string(&est_path)?)
        .map_err(|e| anyhow::anyhow!("{}: {e}", est_path.display()))?;
    let est = match statistic {
        Statistic::Median => e.median,
        Statistic::Mean => e.mean,
    };
    Ok(Some((
        b.full_id,
        Measured {
            point_us: est.point_estimate / 1000.0,
            upper_us: est.confidence_interval.upper_bound / 1000.0,
        },
    )))
}

/// Outcome of one budget row.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Verdict {
    /// Within budget.
    Pass,
    /// Over budget.
    Fail,
    /// No fresh measurement: the bench (or its target) does not exist or did not run. A failure.
    Missing,
}

impl Verdict {
    /// Text for the table.
    pub fn as_str(self) -> &'static str {
        match self {
            Verdict::Pass => "PASS",
            Verdict::Fail => "FAIL",
            Verdict::Missing => "MISSING",
        }
    }
}

/// One evaluated row of the gate table.
#[derive(Debug, Clone)]
pub struct Row {
    /// Stage name.
    pub stage: String,
    /// Benchmark id or binary.
    pub what: String,
    /// Measured figure (µs or instructions), if any.
    pub measured: Option<f64>,
    /// Budget in the same unit.
    pub budget: f64,
    /// "µs" or "instr".
    pub unit: &'static str,
    /// Verdict.
    pub verdict: Verdict,
    /// Extra text (why missing, point estimate, …).
    pub detail: String,
}

impl Row {
    /// Builds a row; `measured = None` is [`Verdict::Missing`].
    pub fn evaluate(
        stage: &str,
        what: &str,
        measured: Option<f64>,
        budget: f64,
        unit: &'static str,
        detail: String,
    ) -> Row {
        let verdict = match measured {
            None => Verdict::Missing,
            // NaN never passes.
            Some(m) if m <= budget => Verdict::Pass,
            Some(_) => Verdict::Fail,
        };
        Row {
            stage: stage.to_owned(),
            what: what.to_owned(),
            measured,
            budget,
            unit,
            verdict,
            detail,
        }
    }

    /// Budget minus measured, as a percentage of the budget (negative = over budget).
    pub fn margin_pct(&self) -> Option<f64> {
        self.measured
            .map(|m| 100.0 * (self.budget - m) / self.budget)
    }
}

fn fmt_num(v: f64, unit: &str) -> String {
    if unit == "µs" {
        format!("{v:.4} µs")
    } else {
        format!("{v:.0} {unit}")
    }
}

/// The printed table: stage, measured, budget, margin, verdict.
pub fn render_table(rows: &[Row]) -> String {
    let mut s = String::new();
    let w_stage = rows
        .iter()
        .map(|r| r.stage.chars().count())
        .max()
        .unwrap_or(5)
        .max(5);
    s.push_str(&format!(
        "{:<w_stage$}  {:>16}  {:>16}  {:>8}  {:<7}  {}\n",
        "stage", "measured", "budget", "margin", "verdict", "benchmark / detail"
    ));
    for r in rows {
        let measured = r
            .measured
            .map_or_else(|| "-".to_owned(), |m| fmt_num(m, r.unit));
        let margin = r
            .margin_pct()
            .map_or_else(|| "-".to_owned(), |m| format!("{m:+.0} %"));
        s.push_str(&format!(
            "{:<w_stage$}  {:>16}  {:>16}  {:>8}  {:<7}  {}{}\n",
            r.stage,
            measured,
            fmt_num(r.budget, r.unit),
            margin,
            r.verdict.as_str(),
            r.what,
            if r.detail.is_empty() {
                String::new()
            } else {
                format!(" ({})", r.detail)
            }
        ));
    }
    s
}

/// Where cargo puts build output for this workspace (`CARGO_TARGET_DIR` honoured by cargo).
///
/// # Errors
/// `cargo metadata` failed.
pub fn cargo_target_dir() -> anyhow::Result<PathBuf> {
    let out = std::process::Command::new(cargo())
        .args(["metadata", "--format-version", "1", "--no-deps"])
        .output()?;
    anyhow::ensure!(out.status.success(), "cargo metadata failed");
    let v: serde_json::Value = serde_json::from_slice(&out.stdout)?;
    let dir = v
        .get("target_directory")
        .and_then(|d| d.as_str())
        .ok_or_else(|| anyhow::anyhow!("cargo metadata: no target_directory"))?;
    Ok(PathBuf::from(dir))
}

/// Bench targets `[[bench]]` registered in the cycle-benches package.
///
/// # Errors
/// `cargo metadata` failed.
pub fn registered_benches() -> anyhow::Result<Vec<String>> {
    let out = std::process::Command::new(cargo())
        .args(["metadata", "--format-version", "1", "--no-deps"])
        .output()?;
    anyhow::ensure!(out.status.success(), "cargo metadata failed");
    let v: serde_json::Value = serde_json::from_slice(&out.stdout)?;
    let mut names = Vec::new();
    for p in v["packages"].as_array().into_iter().flatten() {
        if p["name"] == "cycle-benches" {
            for t in p["targets"].as_array().into_iter().flatten() {
                let is_bench = t["kind"]
                    .as_array()
                    .is_some_and(|k| k.iter().any(|k| k == "bench"));
                if let (true, Some(n)) = (is_bench, t["name"].as_str()) {
                    names.push(n.to_owned());
                }
            }
        }
    }
    Ok(names)
}

/// The cargo executable that started us (falls back to `cargo` on PATH).
pub fn cargo() -> std::ffi::OsString {
    std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn verdicts_at_and_around_the_budget() {
        let r = |m| Row::evaluate("s", "id", m, 1.0, "µs", String::new()).verdict;
        assert_eq!(r(Some(0.5)), Verdict::Pass);
        assert_eq!(r(Some(1.0)), Verdict::Pass);
        assert_eq!(r(Some(1.0001)), Verdict::Fail);
        assert_eq!(r(Some(f64::NAN)), Verdict::Fail);
        assert_eq!(r(None), Verdict::Missing);
    }

    #[test]
    fn reads_fresh_results_and_ignores_stale_ones() {
        let dir = std::env::temp_dir().join(format!("gate-test-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let write = |name: &str, full_id: &str| {
            let d = dir.join(name).join("new");
            std::fs::create_dir_all(&d).unwrap();
            std::fs::write(
                d.join("benchmark.json"),
                format!("{{\"full_id\":\"{full_id}\"}}"),
            )
            .unwrap();
            std::fs::write(
                d.join("estimates.json"),
                r#"{"mean":{"point_estimate":2500.0,"confidence_interval":{"upper_bound":2600.0}},
                    "median":{"point_estimate":2000.0,"confidence_interval":{"upper_bound":2100.0}}}"#,
            )
            .unwrap();
        };
        write("old", "a/old");
        std::thread::sleep(std::time::Duration::from_millis(20));
        let since = SystemTime::now();
        std::thread::sleep(std::time::Duration::from_millis(20));
        write("grp/fresh", "a/fresh");
        let m = read_criterion_results(&dir, since, Statistic::Median).unwrap();
        assert_eq!(m.len(), 1, "{m:?}");
        let f = m["a/fresh"];
        // ns → µs
        assert!((f.point_us - 2.0).abs() < 1e-12 && (f.upper_us - 2.1).abs() < 1e-12);
        let m = read_criterion_results(&dir, since, Statistic::Mean).unwrap();
        assert!((m["a/fresh"].point_us - 2.5).abs() < 1e-12);
        let _ = std::fs::remove_dir_all(&dir);
    }
}
