//! Deterministic instruction counts: a binary that runs a path `n` times, executed under
//! `valgrind --tool=callgrind` for two `n`; the difference of the totals divided by the
//! difference of `n` is the cost of one iteration with process start-up, set-up (tables,
//! buffers) and exit excluded. On this VM it is identical run to run, unlike wall-clock time.

use std::path::Path;
use std::process::Command;

/// Parses the `summary:`/`totals:` line of a callgrind output file (first event = Ir).
pub fn parse_callgrind_total(text: &str) -> Option<u64> {
    let line = text
        .lines()
        .find(|l| l.starts_with("totals:"))
        .or_else(|| text.lines().find(|l| l.starts_with("summary:")))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

/// Total instructions of `bin n` under callgrind.
///
/// # Errors
/// valgrind missing or failing, or no total in its output.
pub fn callgrind_total(bin: &Path, n: u64, out_dir: &Path) -> anyhow::Result<u64> {
    let out_file = out_dir.join(format!(
        "callgrind.{}.{n}.{}",
        bin.file_name().and_then(|f| f.to_str()).unwrap_or("bin"),
        std::process::id()
    ));
    let out = Command::new("valgrind")
        .arg("--tool=callgrind")
        .arg(format!("--callgrind-out-file={}", out_file.display()))
        .arg(bin)
        .arg(n.to_string())
        .output()
        .map_err(|e| anyhow::anyhow!("cannot start valgrind (apt-get install valgrind): {e}"))?;
    anyhow::ensure!(
        out.status.success(),
        "valgrind {} {n} failed: {}",
        bin.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(&out_file)?;
    let _ = std::fs::remove_file(&out_file);
    parse_callgrind_total(&text)
        .ok_or_else(|| anyhow::anyhow!("no totals in {}", out_file.display()))
}

/// Instructions per iteration from runs with `n[0]` and `n[1]` iterations.
///
/// # Errors
/// See [`callgrind_total`]; also a count that shrinks with more iterations.
pub fn instructions_per_iteration(bin: &Path, n: [u64; 2], out_dir: &Path) -> anyhow::Result<f64> {
    let a = callgrind_total(bin, n[0], out_dir)?;
    let b = callgrind_total(bin, n[1], out_dir)?;
    anyhow::ensure!(
        b > a,
        "{}: {b} instructions for {} iterations ≤ {a} for {}",
        bin.display(),
        n[1],
        n[0]
    );
    Ok((b - a) as f64 / (n[1] - n[0]) as f64)
}

/// Instructions of every call of `function` (a demangled path, e.g.
/// `cycle_benches::worst_case::measured_step`) in one run of `bin args…`, in call order:
/// callgrind collects only inside the function (`--collect-atstart=no --toggle-collect`) and
/// dumps after each call (`--dump-after`), so start-up, set-up and everything between the
/// calls is excluded exactly. Also returns the program's stdout.
///
/// # Errors
/// valgrind missing or failing, or a dump without totals.
pub fn collected_totals(
    bin: &Path,
    args: &[&str],
    function: &str,
    out_dir: &Path,
) -> anyhow::Result<(Vec<u64>, String)> {
    let stem = out_dir.join(format!(
        "callgrind.{}.collect.{}",
        bin.file_name().and_then(|f| f.to_str()).unwrap_or("bin"),
        std::process::id()
    ));
    let out = Command::new("valgrind")
        .arg("--tool=callgrind")
        .arg("--collect-atstart=no")
        .arg(format!("--toggle-collect={function}"))
        .arg(format!("--dump-after={function}"))
        .arg(format!("--callgrind-out-file={}", stem.display()))
        .arg(bin)
        .args(args)
        .output()
        .map_err(|e| anyhow::anyhow!("cannot start valgrind (apt-get install valgrind): {e}"))?;
    let mut totals = Vec::new();
    // Dump k goes to `<stem>.k`; the final file (nothing collected after the last call) is
    // `<stem>`.
    for k in 1.. {
        let part = std::path::PathBuf::from(format!("{}.{k}", stem.display()));
        let Ok(text) = std::fs::read_to_string(&part) else {
            break;
        };
        let _ = std::fs::remove_file(&part);
        totals.push(
            parse_callgrind_total(&text)
                .ok_or_else(|| anyhow::anyhow!("no totals in {}", part.display()))?,
        );
    }
    let _ = std::fs::remove_file(&stem);
    anyhow::ensure!(
        out.status.success(),
        "valgrind {} {args:?} failed: {}",
        bin.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    Ok((totals, String::from_utf8_lossy(&out.stdout).into_owned()))
}

/// Iteration count from `argv[1]` for the `icount_*` binaries (default 1000).
pub fn iterations_from_args() -> u64 {
    std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(1000)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_totals_and_summary_lines() {
        let t = "version: 1\nevents: Ir\nfn=main\n1 5\nsummary: 123456\ntotals: 123457\n";
        assert_eq!(parse_callgrind_total(t), Some(123_457));
        assert_eq!(parse_callgrind_total("events: Ir\nsummary: 42\n"), Some(42));
        assert_eq!(parse_callgrind_total("events: Ir\n"), None);
    }
}
