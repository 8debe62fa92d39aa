//! The budget gate: `cargo run --release -p cycle-benches --bin budget -- [--quick]
//! [--only REGEX] [--budgets FILE] [--no-icount] [--no-criterion] [--prebuilt]`.
//!
//! Runs the budgeted criterion benches (`cargo bench`), reads the fresh `estimates.json`,
//! measures instructions per iteration of the `icount-*` binaries under callgrind, prints one
//! table and exits 1 if any row is FAIL or MISSING (a budgeted benchmark that did not produce
//! a fresh result is a failure, never a silent pass), 2 on a usage/set-up error.

use anyhow::Context;
use clap::Parser;
use cycle_benches::budgets::{Bound, Budgets, Statistic};
use cycle_benches::gate::{self, Row, Verdict};
use cycle_benches::icount;
use regex::Regex;
use std::collections::BTreeSet;
use std::path::PathBuf;
use std::process::Command;
use std::time::SystemTime;

#[derive(Parser, Debug)]
#[command(
    name = "budget",
    version,
    about = "Run the cycle benches and fail when a budget (benches/budgets.toml) is exceeded"
)]
struct Args {
    /// Short criterion runs (0.5 s warm-up, 1 s measurement, 20 samples): a smoke gate.
    #[arg(long)]
    quick: bool,
    /// Only rows whose benchmark id / icount binary matches this regex.
    #[arg(long, value_name = "REGEX")]
    only: Option<String>,
    /// Budgets file.
    #[arg(long, value_name = "FILE", default_value = concat!(env!("CARGO_MANIFEST_DIR"), "/budgets.toml"))]
    budgets: PathBuf,
    /// Skip the callgrind rows.
    #[arg(long)]
    no_icount: bool,
    /// Skip the criterion rows.
    #[arg(long)]
    no_criterion: bool,
    /// Measure the icount binaries already built beside this one instead of building them
    /// (test.sh builds every binary once, with the test suite's feature set; a `cargo build -p
    /// cycle-benches` here would resolve features anew and rebuild the chain below it).
    #[arg(long)]
    prebuilt: bool,
}

/// The most expensive call of `function` in one callgrind run of `bin args…` (arguments
/// that name an existing file relative to `base` are made absolute).
fn collected_max(
    bin: &std::path::Path,
    row: &cycle_benches::budgets::IcountBudget,
    function: &str,
    base: &std::path::Path,
    tmp: &std::path::Path,
) -> anyhow::Result<(f64, String)> {
    let args: Vec<String> = row
        .args
        .iter()
        .map(|a| {
            let p = base.join(a);
            if p.exists() {
                p.display().to_string()
            } else {
                a.clone()
            }
        })
        .collect();
    let refs: Vec<&str> = args.iter().map(String::as_str).collect();
    let (totals, _) = icount::collected_totals(bin, &refs, function, tmp)?;
    let max =
        totals.iter().copied().max().ok_or_else(|| {
            anyhow::anyhow!("{function} was never called by {} {args:?}", row.bin)
        })?;
    Ok((
        max as f64,
        format!(
            "callgrind inside {}, max of {} call(s)",
            function.rsplit("::").next().unwrap_or(function),
            totals.len()
        ),
    ))
}

fn main() {
    match run() {
        Ok(true) => std::process::exit(0),
        Ok(false) => std::process::exit(1),
        Err(e) => {
            eprintln!("budget: error: {e:#}");
            std::process::exit(2);
        }
    }
}

fn run() -> anyhow::Result<bool> {
    let args = Args::parse();
    let budgets = Budgets::load(&args.budgets)?;
    let only = args
        .only
        .as_deref()
        .map(Regex::new)
        .transpose()
        .context("--only is not a valid regex")?;
    let selected = |s: &str| only.as_ref().is_none_or(|r| r.is_match(s));
    let mut rows = Vec::new();

    if !args.no_criterion {
        let crit: Vec<_> = budgets
            .criterion
            .iter()
            .filter(|c| selected(&c.id))
            .collect();
        let registered = gate::registered_benches()?;
        let target_dir = gate::cargo_target_dir()?;
        let start = SystemTime::now();
        let targets: BTreeSet<&str> = crit.iter().map(|c| c.bench.as_str()).collect();
        let mut target_problem = std::collections::BTreeMap::new();
        for t in targets {
            if !registered.iter().any(|r| r == t) {
                target_problem.insert(
                    t,
                    format!("bench target `{t}` is not registered in benches/Cargo.toml"),
                );
                continue;
            }
            let ids: Vec<String> = crit
                .iter()
                .filter(|c| c.bench == t)
                .map(|c| regex::escape(&c.id))
                .collect();
            let filter = format!("^({})$", ids.join("|"));
            let mut cmd = Command::new(gate::cargo());
            // `--workspace`, not `-p cycle-benches`: the same feature resolution as test.sh's
            // build and `cargo test --workspace`, so the dependencies are not compiled again.
            cmd.args([
                "bench",
                "--workspace",
                "--bench",
                t,
                "--",
                &filter,
                "--noplot",
            ]);
            if args.quick {
                cmd.args([
                    "--warm-up-time",
                    "0.5",
                    "--measurement-time",
                    "1",
                    "--sample-size",
                    "20",
                ]);
            }
            eprintln!("budget: running {cmd:?}");
            let status = cmd.status().context("cannot run cargo bench")?;
            if !status.success() {
                target_problem.insert(t, format!("`cargo bench --bench {t}` failed ({status})"));
            }
        }
        let stat = budgets.gate.statistic;
        let results = gate::read_criterion_results(&target_dir.join("criterion"), start, stat)?;
        let stat_name = match stat {
            Statistic::Median => "median",
            Statistic::Mean => "mean",
        };
        for c in crit {
            let m = results.get(&c.id);
            let detail = match (m, target_problem.get(c.bench.as_str())) {
                (Some(m), _) => format!(
                    "{stat_name} {:.4} µs, CI upper {:.4} µs",
                    m.point_us, m.upper_us
                ),
                (None, Some(p)) => p.clone(),
                (None, None) => format!("no fresh result for this id from `--bench {}`", c.bench),
            };
            rows.push(Row::evaluate(
                &c.stage,
                &c.id,
                m.map(|m| m.value(budgets.gate.compare)),
                c.budget_us,
                "µs",
                detail,
            ));
        }
    }

    if !args.no_icount {
        let ic: Vec<_> = budgets.icount.iter().filter(|i| selected(&i.bin)).collect();
        if !ic.is_empty() {
            let (built, bin_dir) = if args.prebuilt {
                let exe = std::env::current_exe().context("where is this binary?")?;
                let dir = exe
                    .parent()
                    .context("binary without a folder")?
                    .to_path_buf();
                (ic.iter().all(|i| dir.join(&i.bin).is_file()), dir)
            } else {
                let mut cmd = Command::new(gate::cargo());
                cmd.args(["build", "--release", "-p", "cycle-benches"]);
                for i in &ic {
                    cmd.args(["--bin", &i.bin]);
                }
                let built = cmd.status().context("cannot run cargo build")?.success();
                (built, gate::cargo_target_dir()?.join("release"))
            };
            let tmp = std::env::temp_dir();
            let base = args.budgets.parent().unwrap_or(std::path::Path::new("."));
            for i in ic {
                let bin = bin_dir.join(&i.bin);
                let (measured, detail) = if built {
                    let r = match &i.collect {
                        Some(f) => collected_max(&bin, i, f, base, &tmp),
                        None => {
                            icount::instructions_per_iteration(&bin, i.iterations, &tmp).map(|v| {
                                let n = i.iterations;
                                (v, format!("callgrind, N = {} vs {}", n[0], n[1]))
                            })
                        }
                    };
                    match r {
                        Ok((v, d)) => (Some(v), d),
                        Err(e) => (None, format!("{e:#}")),
                    }
                } else if args.prebuilt {
                    let missing =
                        format!("--prebuilt: no {} (build the bins first)", bin.display());
                    (None, missing)
                } else {
                    (None, "cargo build of the icount binaries failed".to_owned())
                };
                rows.push(Row::evaluate(
                    &i.stage,
                    &i.bin,
                    measured,
                    i.budget_instructions,
                    "instr",
                    detail,
                ));
            }
        }
    }

    anyhow::ensure!(!rows.is_empty(), "no budget row selected (check --only)");
    let cmp = match budgets.gate.compare {
        Bound::Point => "point estimate",
        Bound::UpperBound => "upper 95 % CI bound",
    };
    println!(
        "\nbudget gate ({}; criterion rows compare the {cmp})",
        args.budgets.display()
    );
    print!("{}", gate::render_table(&rows));
    let bad: Vec<_> = rows.iter().filter(|r| r.verdict != Verdict::Pass).collect();
    if bad.is_empty() {
        println!("budget gate: PASS ({} rows)", rows.len());
        Ok(true)
    } else {
        for r in &bad {
            println!(
                "budget gate: {} — {} ({})",
                r.verdict.as_str(),
                r.stage,
                r.what
            );
        }
        println!(
            "budget gate: FAIL ({} of {} rows not within budget)",
            bad.len(),
            rows.len()
        );
        Ok(false)
    }
}
