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

/// Iteration count from `argv[1]` for the `icount-*` binaries (default 1000). `--help` and
/// `--version` answer and exit 0; anything else that is not a whole number is an error: one
/// line `NAME: error: …` and exit 2, as every tool of the bench (a typo must not measure the
/// default count).
pub fn iterations_from_args() -> u64 {
    let mut args = std::env::args();
    let name = args
        .next()
        .as_deref()
        .and_then(|a| Path::new(a).file_name()?.to_str().map(str::to_owned))
        .unwrap_or_else(|| "icount".to_owned());
    match parse_iterations(args.next().as_deref()) {
        Ok(n) => n,
        Err(Answer::Help) => {
            println!(
                "Usage: {name} [N]\n       {name} --help | --version\n\nRuns its measured \
                 path N times (default 1000) and prints a checksum; `budget` runs it under \
                 callgrind for two N and differences the totals (benches/README.md)."
            );
            std::process::exit(0)
        }
        Err(Answer::Version) => {
            println!("{name} {}", env!("CARGO_PKG_VERSION"));
            std::process::exit(0)
        }
        Err(Answer::Bad(a)) => {
            eprintln!("{name}: error: N must be a whole number of iterations, got '{a}'");
            std::process::exit(2)
        }
    }
}

/// What an `icount-*` binary's first argument asks for besides a count.
#[derive(Debug, PartialEq)]
enum Answer {
    Help,
    Version,
    Bad(String),
}

fn parse_iterations(arg: Option<&str>) -> Result<u64, Answer> {
    match arg {
        None => Ok(1000),
        Some("-h" | "--help") => Err(Answer::Help),
        Some("-V" | "--version") => Err(Answer::Version),
        Some(a) => a.parse().map_err(|_| Answer::Bad(a.to_owned())),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_iteration_argument_is_a_count_a_question_or_an_error() {
        assert_eq!(parse_iterations(None), Ok(1000));
        assert_eq!(parse_iterations(Some("120")), Ok(120));
        assert_eq!(parse_iterations(Some("--help")), Err(Answer::Help));
        assert_eq!(parse_iterations(Some("-V")), Err(Answer::Version));
        assert_eq!(
            parse_iterations(Some("--no-such-flag")),
            Err(Answer::Bad("--no-such-flag".into()))
        );
        assert_eq!(
            parse_iterations(Some("1e3")),
            Err(Answer::Bad("1e3".into()))
        );
    }

    #[test]
    fn parses_totals_and_summary_lines() {
        let t = "version: 1\nevents: Ir\nfn=main\n1 5\nsummary: 123456\ntotals: 123457\n";
        assert_eq!(parse_callgrind_total(t), Some(123_457));
        assert_eq!(parse_callgrind_total("events: Ir\nsummary: 42\n"), Some(42));
        assert_eq!(parse_callgrind_total("events: Ir\n"), None);
    }
}
