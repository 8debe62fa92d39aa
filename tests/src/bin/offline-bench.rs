//! `offline-bench [--scenario FILE …] [--no-lut] [--json FILE] [--cycle-config FILE]`: runs scenarios through the
//! restraint core under a simulated clock with the real sensor model and the actuator stubs'
//! judge (`e2e_tests::offline`), and prints the outcome table. No vcan, no processes, no
//! emulator: deterministic, ≈ 50 ms per scenario. Default: the whole library (`scenarios/`).
//!
//! Time bases of `--json` (one array, an object per scenario): `actions[].t_ns` is the ECU's
//! simulated clock, which starts at 1 s (scenario time + 1 s, so that no time stamp is 0);
//! `actions[].t_ms` is the same instant in ms after the scenario start; `modes`, `faults` and
//! `crash_mode_ms` are ms after the true contact (`contact_s`, s after the start), or after
//! the scenario start when there is no contact. `severity_excess_mps`: the largest crash −
//! safing sensor Δv over a confirmed event (restraint's severity agreement; `null`: none judged).

use anyhow::{Context, Result};
use clap::Parser;
use e2e_tests::offline::{run_traced, table_row, OfflineConfig, Trace, START_NS, TABLE_HEADER};
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
    /// A TOML file of `[cycle]` keys (as in ecu.toml's `[cycle]`, without the header) that
    /// replace the defaults: what a threshold change does to the library, before it is made.
    #[arg(long, value_name = "FILE")]
    cycle_config: Option<PathBuf>,
    /// Draw each run to DIR/<scenario>.png: the accelerometers, the event's Δv against the
    /// boundaries and floors, the ECU's mode and every restraint action (created if missing).
    #[arg(long, value_name = "DIR")]
    plot: Option<PathBuf>,
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
    if let Some(path) = &cli.cycle_config {
        cfg = cfg.with_cycle_file(path)?;
    }
    if cli.no_lut {
        cfg.lut = None;
    }
    if let Some(dir) = &cli.plot {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    println!("{TABLE_HEADER}");
    let mut json = Vec::new();
    for f in &files {
        let s = sensor_feeds::Scenario::load(f).map_err(|e| anyhow::anyhow!("{e}"))?;
        let mut trace = Trace::default();
        let r = run_traced(&s, &cfg, cli.plot.is_some().then_some(&mut trace))?;
        if let Some(dir) = &cli.plot {
            e2e_tests::offline_plot::draw(&dir.join(format!("{}.png", r.name)), &r, &trace)
                .map_err(anyhow::Error::msg)?;
        }
        println!("{}", table_row(&r));
        json.push(serde_json::json!({
            "scenario": r.name,
            "contact_s": r.contact_s,
            "crash_mode_ms": r.crash_mode_ms,
            "confirmed_by": r.confirmed_by,
            "severity_excess_mps": r.severity_excess_mps,
            "modes": r.modes,
            "faults": r.faults,
            "actions": actions_json(&r.modules.actions)?,
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

/// The actions as recorded, each with `t_ms` (ms after the scenario start) added.
fn actions_json<T: serde::Serialize>(actions: &[T]) -> Result<Vec<serde_json::Value>> {
    actions
        .iter()
        .map(|a| {
            let mut v = serde_json::to_value(a)?;
            if let Some(t_ns) = v.get("t_ns").and_then(serde_json::Value::as_u64) {
                let t_ms = t_ns.saturating_sub(START_NS) as f64 * 1e-6;
                v["t_ms"] = serde_json::json!(t_ms);
            }
            Ok(v)
        })
        .collect()
}
