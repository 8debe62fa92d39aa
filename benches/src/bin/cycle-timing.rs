//! `cycle-timing`: the wall-clock time of the full-cycle rows of `benches/budgets.toml`, beside
//! a reference workload timed in the same loop, so the figure that carries from machine to
//! machine is the ratio.
//!
//! Each round times, in turn, one cycle of each row — the hand-picked path (a steady
//! pre-crash cycle with a new object sample, `icount-cycle`'s) and the three searched worst
//! cases from their committed seeds (`worst-case/*.json`, each cycle replayed from a clone of
//! its prepared core, the clone untimed) — and the reference: one AES-128-CMAC over 1 KiB
//! (`bus::secoc::aes128_cmac`, 64 AES blocks; a fixed amount of work that a faster or slower,
//! busier or quieter CPU does correspondingly faster or slower). Interleaving puts every row
//! and the reference under the same load, frequency and cache state; a noisy VM moves the
//! absolute times, much less their ratio. Reported per row: p50, p99, p99.9 and max (µs) and
//! p50 / the reference's p50; the line is a p50 ≤ 1 µs for every full cycle on the
//! project's Xeon (`benches/README.md`, "Wall clock"). A report, never a
//! gate: the gated figure is the instruction count (`budget`).

use anyhow::Context;
use clap::Parser;
use cycle_benches::ecu_cycle::WorstCasePreCrash;
use cycle_benches::worst_case::{self, Prepared};
use hdrhistogram::Histogram;
use std::hint::black_box;
use std::path::PathBuf;
use std::time::Instant;

#[derive(Parser, Debug)]
#[command(
    name = "cycle-timing",
    version,
    about = "Wall-clock percentiles of the full ECU cycle rows beside a reference workload"
)]
struct Cli {
    /// Rounds (each times one cycle of every row and one reference).
    #[arg(long, default_value_t = 100_000)]
    rounds: u64,
    /// Also write the table as JSON.
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
}

/// The p50 every full cycle should stay under on the project's Xeon, µs.
const LINE_P50_US: f64 = 1.0;

struct Row {
    name: &'static str,
    hist: Histogram<u64>,
}

fn histogram() -> anyhow::Result<Histogram<u64>> {
    // 1 ns to 10 ms, 3 significant digits.
    Histogram::new_with_bounds(1, 10_000_000, 3).context("histogram bounds")
}

fn record(h: &mut Histogram<u64>, t: Instant) {
    let ns = u64::try_from(t.elapsed().as_nanos()).unwrap_or(u64::MAX);
    h.saturating_record(ns.max(1));
}

fn main() -> anyhow::Result<()> {
    let cli = Cli::parse();
    let dir = worst_case::seed_path()
        .parent()
        .map(std::path::Path::to_path_buf)
        .context("seed directory")?;
    let searched: Vec<(&'static str, Prepared)> = [
        ("searched worst, no crash event, SecOC off", "seed.json"),
        (
            "searched worst, no crash event, SecOC on",
            "seed-secoc.json",
        ),
        (
            "searched worst crash-event cycle, SecOC on",
            "seed-crash-phase.json",
        ),
    ]
    .into_iter()
    .map(|(name, file)| {
        let path = dir.join(file);
        let cases = worst_case::load_cases(&path)?;
        let case = cases
            .first()
            .with_context(|| format!("{}: no case", path.display()))?;
        Ok((name, worst_case::prepare(case)?))
    })
    .collect::<anyhow::Result<_>>()?;
    let mut hand = WorstCasePreCrash::new()?;
    let key = bus::secoc::SecOcKey::from_hex("000102030405060708090a0b0c0d0e0f")
        .map_err(|e| anyhow::anyhow!("reference key: {e:?}"))?;
    let message = [0x5au8; 1024];

    let mut rows: Vec<Row> = std::iter::once("hand-picked path (new object sample, quiet batches)")
        .chain(searched.iter().map(|(name, _)| *name))
        .map(|name| {
            Ok(Row {
                name,
                hist: histogram()?,
            })
        })
        .collect::<anyhow::Result<_>>()?;
    let mut reference = histogram()?;
    for _ in 0..cli.rounds {
        if let Some(row) = rows.first_mut() {
            let t = Instant::now();
            hand.step();
            record(&mut row.hist, t);
        }
        for ((_, prepared), row) in searched.iter().zip(rows.iter_mut().skip(1)) {
            let mut p = prepared.clone();
            let t = Instant::now();
            worst_case::measured_step(&mut p);
            record(&mut row.hist, t);
            black_box(&p);
        }
        let t = Instant::now();
        black_box(bus::secoc::aes128_cmac(&key, black_box(&message)));
        record(&mut reference, t);
    }
    hand.verify()?;

    let us = |h: &Histogram<u64>, q: f64| h.value_at_quantile(q) as f64 * 1e-3;
    let ref_p50 = us(&reference, 0.5);
    println!(
        "{:<48} {:>8} {:>8} {:>8} {:>8} {:>9}  p50 ≤ {LINE_P50_US} µs",
        "full ECU cycle (µs; RestraintCycle::step)", "p50", "p99", "p99.9", "max", "p50/ref"
    );
    let mut json_rows = Vec::new();
    for r in rows.iter() {
        let (p50, p99, p999, max) = (
            us(&r.hist, 0.5),
            us(&r.hist, 0.99),
            us(&r.hist, 0.999),
            r.hist.max() as f64 * 1e-3,
        );
        let ratio = p50 / ref_p50;
        let verdict = if p50 <= LINE_P50_US { "yes" } else { "NO" };
        println!(
            "{:<48} {p50:>8.3} {p99:>8.3} {p999:>8.3} {max:>8.2} {ratio:>9.3}  {verdict}",
            r.name
        );
        json_rows.push(serde_json::json!({
            "row": r.name, "p50_us": p50, "p99_us": p99, "p999_us": p999, "max_us": max,
            "p50_over_reference": ratio, "p50_within_line": p50 <= LINE_P50_US,
        }));
    }
    println!(
        "{:<48} {:>8.3} {:>8.3} {:>8.3} {:>8.2} {:>9}",
        "reference: AES-128-CMAC of 1 KiB (64 blocks)",
        ref_p50,
        us(&reference, 0.99),
        us(&reference, 0.999),
        reference.max() as f64 * 1e-3,
        "1"
    );
    println!(
        "{} rounds, interleaved (each round: one cycle of every row, then the reference); {}",
        cli.rounds,
        cpu_model()
    );
    if let Some(path) = cli.json {
        let doc = serde_json::json!({
            "schema_version": 1,
            "rounds": cli.rounds,
            "cpu": cpu_model(),
            "line_p50_us": LINE_P50_US,
            "reference": {"what": "AES-128-CMAC of 1 KiB", "p50_us": ref_p50,
                "p99_us": us(&reference, 0.99), "p999_us": us(&reference, 0.999),
                "max_us": reference.max() as f64 * 1e-3},
            "rows": json_rows,
        });
        std::fs::write(&path, serde_json::to_string_pretty(&doc)?)
            .with_context(|| format!("writing {}", path.display()))?;
    }
    Ok(())
}

/// The CPU model (`/proc/cpuinfo`), or "unknown CPU".
fn cpu_model() -> String {
    std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|t| {
            t.lines().find_map(|l| {
                l.strip_prefix("model name")
                    .map(|v| v.trim_start_matches([' ', '\t', ':']).to_owned())
            })
        })
        .unwrap_or_else(|| "unknown CPU".to_owned())
}
