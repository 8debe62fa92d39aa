//! `offline-bench [--scenario FILE …] [--no-lut] [--json FILE]`: runs scenarios through the
//! restraint core under a simulated clock with the real sensor model and the actuator stubs'
//! judge (`e2e_tests::offline`), and prints the outcome table. No vcan, no processes, no
//! emulator: deterministic, ≈ 50 ms per scenario. Default: the whole library (`scenarios/`).

use anyhow::{Context, Result};
use clap::Parser;
use e2e_tests::offline::{run, table_row, OfflineConfig, TABLE_HEADER};
use std::path::PathBuf;

/// Scenario library through the ECU core, offline.
#[derive(Parser, Debug)]
#[command(name = "offline-bench", version)]
struct Cli {
    /// Scenario file(s) (default: every `*.toml` in the repository's `scenarios/`).
    #[arg(long)]
    scenario: Vec<PathBuf>,
    /// Run without the characteristic diagram (the ECU then runs on the reference restraint).
    #[arg(long)]
    no_lut: bool,
    /// Repository root (default: where this crate was built).
    #[arg(long)]
    repo: Option<PathBuf>,
    /// Also write every run's modes, faults, actions and outcome as JSON.
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
}

fn main() -> Result<()> {
    let cli = Cli::parse();
    let repo = cli.repo.clone().unwrap_or_else(e2e_tests::repo_root);
    let mut files = cli.scenario.clone();
    if files.is_empty() {
        for e in std::fs::read_dir(repo.join("scenarios")).context("scenarios/")? {
            let p = e?.path();
            if p.extension().is_some_and(|x| x == "toml") {
                files.push(p);
            }
        }
        files.sort();
    }
    let mut cfg = OfflineConfig::shipped(&repo)?;
    if cli.no_lut {
        cfg.lut = None;
    }
    println!("{TABLE_HEADER}");
    let mut json = Vec::new();
    for f in &files {
        let s = sensor_feeds::Scenario::load(f).map_err(|e| anyhow::anyhow!("{e}"))?;
        let r = run(&s, &cfg)?;
        println!("{}", table_row(&r));
        json.push(serde_json::json!({
            "scenario": r.name,
            "contact_s": r.contact_s,
            "crash_mode_ms": r.crash_mode_ms,
            "confirmed_by": r.confirmed_by,
            "modes": r.modes,
            "faults": r.faults,
            "actions": r.modules.actions,
            "outcome": r.evaluated.as_ref().map(|e| &e.outcome),
        }));
    }
    println!("(! = bottomed out; confirm = first ECU cycle in mode crash; airbag = ms after the true contact, plan = its FireTime; times on the simulated 1 kHz grid, no CAN latency)");
    if let Some(p) = &cli.json {
        std::fs::write(p, serde_json::to_string_pretty(&json)?)
            .with_context(|| format!("writing {}", p.display()))?;
    }
    Ok(())
}
