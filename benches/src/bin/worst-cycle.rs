//! `worst-cycle`: the searched worst case of one ECU cycle (see `cycle_benches::worst_case`).
//!
//! * `worst-cycle eval CASES.json` — prepares each case (a JSON case or list of cases) and
//!   runs its measured cycle once, printing its path; what the search and the gate run under
//!   callgrind, which counts only `measured_step`.
//! * `worst-cycle search [--generations G] [--population P] [--seed S] [--secoc on|off|any]
//!   [--cycles all|no-crash|crash] [--start FILE]… [--budget N | --budgets FILE] [--out FILE]` — a seeded (μ + λ) evolution of cases,
//!   one callgrind run per generation; starts from the `--start` cases (the committed seeds)
//!   and the hand-picked case plus random ones; writes the best case found to `--out`; exits 1
//!   if any evaluated case exceeded `--budget` instructions (printing it) — or, with
//!   `--budgets benches/budgets.toml`, the line of the row that evaluates the first `--start`
//!   file (the searched rows' lines are written once, there; test.sh searches that way).

use anyhow::Context;
use clap::{Parser, Subcommand, ValueEnum};
use cycle_benches::icount;
use cycle_benches::search;
use cycle_benches::worst_case::{self, CycleCase, MEASURED_FN};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::path::{Path, PathBuf};

#[derive(Parser, Debug)]
#[command(
    name = "worst-cycle",
    version,
    about = "Search for the ECU cycle with the most instructions"
)]
struct Cli {
    #[command(subcommand)]
    command: Cmd,
}

/// Which measured cycles count (the others score 0).
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum Cycles {
    /// Every cycle.
    All,
    /// Cycles without a crash event (no accelerometer event in progress, not CRASH or
    /// POST-CRASH): the driving and pre-crash path of the cycle budget.
    NoCrash,
    /// Cycles of a crash event (the accelerometer's event in progress, CRASH, POST-CRASH):
    /// every sample through the crash detectors.
    Crash,
}

impl Cycles {
    fn counts(self, path: &str) -> bool {
        let event = path.contains("\"crash_event\":true");
        match self {
            Cycles::All => true,
            Cycles::NoCrash => !event,
            Cycles::Crash => event,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum Secoc {
    /// Every case without SecOC (the conditions of the 6 000-instruction line).
    Off,
    /// Every case with the SecOC sender set.
    On,
    /// Searched like any other field.
    Any,
}

#[derive(Subcommand, Debug)]
enum Cmd {
    /// Run the measured cycle of each case once (a JSON case or list of cases).
    Eval {
        /// Case file.
        cases: PathBuf,
    },
    /// Evolve cases towards the most instructions of the measured cycle.
    Search {
        /// Generations (one callgrind run each).
        #[arg(long, default_value_t = 20)]
        generations: u32,
        /// Cases per generation.
        #[arg(long, default_value_t = 32)]
        population: usize,
        /// Seed of the random cases and mutations.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// SecOC in the cases.
        #[arg(long, value_enum, default_value_t = Secoc::Off)]
        secoc: Secoc,
        /// Which measured cycles count; the others score 0.
        #[arg(long, value_enum, default_value_t = Cycles::All)]
        cycles: Cycles,
        /// Cases to start from (e.g. the committed seed); missing files are skipped.
        #[arg(long)]
        start: Vec<PathBuf>,
        /// Fail (exit 1) if a case exceeds this many instructions.
        #[arg(long, conflicts_with = "budgets")]
        budget: Option<u64>,
        /// Fail (exit 1) if a case exceeds the line `FILE` (benches/budgets.toml) gives the
        /// row that evaluates the first `--start` file: the lines written once, in that file.
        #[arg(long, value_name = "FILE")]
        budgets: Option<PathBuf>,
        /// Where to write the best case found.
        #[arg(long)]
        out: Option<PathBuf>,
    },
}

/// Instructions of each case's measured cycle (one callgrind run of `eval`) and its path.
fn evaluate(cases: &[CycleCase], dir: &Path) -> anyhow::Result<Vec<(u64, String)>> {
    let file = dir.join(format!("worst-cycle-cases.{}.json", std::process::id()));
    std::fs::write(&file, serde_json::to_string(cases)?)?;
    let exe = std::env::current_exe()?;
    let file_arg = file.display().to_string();
    let (totals, stdout) = icount::collected_totals(&exe, &["eval", &file_arg], MEASURED_FN, dir)?;
    let _ = std::fs::remove_file(&file);
    let paths: Vec<String> = stdout.lines().map(str::to_owned).collect();
    anyhow::ensure!(
        totals.len() == cases.len() && paths.len() == cases.len(),
        "{} cases, {} counts, {} paths (is `{MEASURED_FN}` still the measured function?)",
        cases.len(),
        totals.len(),
        paths.len()
    );
    Ok(totals.into_iter().zip(paths).collect())
}

fn force_secoc(mut c: CycleCase, s: Secoc) -> CycleCase {
    match s {
        Secoc::Off => c.secoc = false,
        Secoc::On => c.secoc = true,
        Secoc::Any => {}
    }
    c
}

#[allow(clippy::too_many_arguments)]
fn search(
    generations: u32,
    population: usize,
    seed: u64,
    secoc: Secoc,
    cycles: Cycles,
    start: &[PathBuf],
    budget: Option<u64>,
    out: Option<&Path>,
) -> anyhow::Result<bool> {
    // The output path is checked before the search, not after it.
    if let Some(p) = out {
        host::check_output_file(p).map_err(|e| anyhow::anyhow!("--out {}: {e}", p.display()))?;
    }
    let dir = std::env::temp_dir();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let population = population.max(4);
    let survivors = (population / 4).max(1);
    let mut starts = vec![("hand-picked".to_owned(), CycleCase::hand_picked())];
    for p in start.iter().filter(|p| p.exists()) {
        for c in worst_case::load_cases(p)? {
            starts.push((p.display().to_string(), c));
        }
    }
    let mut cases: Vec<CycleCase> = starts
        .iter()
        .map(|(_, c)| force_secoc(c.clone(), secoc))
        .collect();
    while cases.len() < population {
        cases.push(force_secoc(search::random_case(&mut rng), secoc));
    }
    let mut best: Option<(u64, CycleCase, String)> = None;
    let mut start_counts: Vec<(String, u64)> = Vec::new();
    let mut over = Vec::new();
    let mut evaluated = 0usize;
    for g in 0..generations {
        let results = evaluate(&cases, &dir)?;
        evaluated += cases.len();
        if g == 0 {
            for ((name, _), (n, _)) in starts.iter().zip(&results) {
                start_counts.push((name.clone(), *n));
            }
        }
        let mut scored: Vec<(u64, CycleCase, String)> = results
            .into_iter()
            .zip(cases)
            .map(|((n, path), c)| {
                let n = if !cycles.counts(&path) { 0 } else { n };
                (n, c, path)
            })
            .collect();
        scored.sort_by_key(|s| std::cmp::Reverse(s.0));
        for (n, c, _) in &scored {
            if budget.is_some_and(|b| *n > b) {
                over.push((*n, c.clone()));
            }
        }
        let top = &scored[0];
        if best.as_ref().is_none_or(|b| top.0 > b.0) {
            best = Some(top.clone());
        }
        let median = scored[scored.len() / 2].0;
        eprintln!(
            "worst-cycle search: generation {}/{generations}: best {} instr (ever {}), median {median}, {evaluated} cases evaluated",
            g + 1,
            top.0,
            best.as_ref().map_or(0, |b| b.0),
        );
        // Next generation: the survivors, mutated children of them, a few fresh cases.
        let parents: Vec<CycleCase> = scored
            .into_iter()
            .take(survivors)
            .map(|(_, c, _)| c)
            .collect();
        cases = parents.clone();
        while cases.len() < population {
            let child = if rng.gen_bool(0.1) {
                search::random_case(&mut rng)
            } else {
                let p = &parents[rng.gen_range(0..parents.len())];
                search::mutate(p, 0.3, &mut rng)
            };
            cases.push(force_secoc(child, secoc));
        }
    }
    let (n, case, path) = best.context("no generation evaluated")?;
    println!(
        "searched {evaluated} cases in {generations} generations of {population} (seed {seed}, SecOC {secoc:?}, cycles {cycles:?})"
    );
    println!("worst case found: {n} instructions; path {path}");
    for (name, c) in &start_counts {
        println!("  start case {name}: {c} instructions");
    }
    println!("{}", serde_json::to_string_pretty(&case)?);
    if let Some(out) = out {
        std::fs::write(out, serde_json::to_string_pretty(&case)? + "\n")
            .with_context(|| format!("cannot write {}", out.display()))?;
        eprintln!("worst-cycle search: best case written to {}", out.display());
    }
    if let Some(b) = budget {
        if let Some((n, c)) = over.iter().max_by_key(|(n, _)| *n) {
            println!(
                "FAIL: {} evaluated cases exceed the budget of {b} instructions; the worst ({n}):\n{}",
                over.len(),
                serde_json::to_string_pretty(c)?
            );
            return Ok(false);
        }
        println!("PASS: no evaluated case exceeds {b} instructions");
    }
    Ok(true)
}

/// The line the budgets file `budgets` gives the row that evaluates `start`'s first file.
fn line_of(budgets: Option<&Path>, start: &[PathBuf]) -> anyhow::Result<Option<u64>> {
    let Some(path) = budgets else {
        return Ok(None);
    };
    let seed = start
        .first()
        .context("--budgets needs a --start file: the row is the one that evaluates it")?;
    let line = cycle_benches::budgets::Budgets::load(path)?
        .worst_cycle_line(seed)
        .with_context(|| {
            format!(
                "{}: no worst-cycle row evaluates {}",
                path.display(),
                seed.display()
            )
        })?;
    Ok(Some(line as u64))
}

fn main() {
    let cli = Cli::parse();
    let r = match cli.command {
        Cmd::Eval { cases } => worst_case::load_cases(&cases).and_then(|cases| {
            for c in &cases {
                println!("{}", serde_json::to_string(&worst_case::run(c)?)?);
            }
            Ok(true)
        }),
        Cmd::Search {
            generations,
            population,
            seed,
            secoc,
            cycles,
            start,
            budget,
            budgets,
            out,
        } => line_of(budgets.as_deref(), &start)
            .map(|line| line.or(budget))
            .and_then(|budget| {
                search(
                    generations,
                    population,
                    seed,
                    secoc,
                    cycles,
                    &start,
                    budget,
                    out.as_deref(),
                )
            }),
    };
    match r {
        Ok(true) => {}
        Ok(false) => std::process::exit(1),
        Err(e) => {
            eprintln!("worst-cycle: error: {e:#}");
            std::process::exit(2);
        }
    }
}
