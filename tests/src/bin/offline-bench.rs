//! `offline-bench [--scenario FILE …] [--no-lut] [--json FILE] [--cycle-config FILE | --config FILE] [--plot DIR]
//! [--record DIR] [--no-expect]`: runs scenarios through the restraint core under a simulated clock with the
//! real sensor model and the actuator stubs' judge (`e2e_tests::offline`), prints the outcome
//! table (one line per run, one indented line per restraint action) and judges every
//! `[expect]` key of every file (`e2e_tests::expect`, the judge `hil-bench` uses too). No vcan,
//! no processes, no emulator: deterministic, ≈ 50 ms per scenario. Default: the whole library
//! (`scenarios/`).
//!
//! Exit status: 0 when every file ran and met its expectations; 1 when a run missed an
//! expectation or a file did not load or run (each is reported, the others still run);
//! 2 on a usage or set-up error (table, reference restraint, `--cycle-config`, `--plot`).
//!
//! `--json` writes one array, an object per file; its schema is in tests/README.md
//! ("offline-bench JSON"), checked by `tests/tests/tools/offline.rs`.

use anyhow::{Context, Result};
use clap::Parser;
use e2e_tests::expect::{check, Observed};
use e2e_tests::offline::{
    run_json, run_traced, table_header, table_row, OfflineConfig, Trace, NAME_WIDTH,
};
use std::io::Write as _;
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
    /// Repository root (default: the checkout around the current folder, found by walking up).
    #[arg(long)]
    repo: Option<PathBuf>,
    /// Also write every run's modes, faults, actions, outcome and expectations as JSON
    /// (schema: tests/README.md, "offline-bench JSON").
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
    /// A TOML file of `[cycle]` keys (as in ecu.toml's `[cycle]`, without the header) that
    /// replace the defaults: what a threshold change does to the library, before it is made.
    #[arg(long, value_name = "FILE")]
    cycle_config: Option<PathBuf>,
    /// An ECU config file (`ecu.toml`, as `ecu --config` takes it): its `[cycle]` table's
    /// settings, table and reference restraint, read by the ECU's own reader.
    #[arg(long, value_name = "FILE", conflicts_with = "cycle_config")]
    config: Option<PathBuf>,
    /// Draw each run to DIR/<scenario>.png: the accelerometers, the event's Δv against the
    /// boundaries and floors, the ECU's mode and every restraint action (created if missing).
    #[arg(long, value_name = "DIR")]
    plot: Option<PathBuf>,
    /// Record each run as a bench run is recorded: DIR/<scenario>/run.mcap (the bus, the
    /// feeds' publications, every cycle's diagnostics, the truth — on the simulated clock, no
    /// bus latency) beside the candump.log and logs it is written from (created if missing).
    #[arg(long, value_name = "DIR")]
    record: Option<PathBuf>,
    /// Do not judge the files' `[expect]` blocks (by default every key is asserted and a miss
    /// exits 1).
    #[arg(long)]
    no_expect: bool,
    /// Give every scenario without a `[v2x]` table the default V2X receiver, the opponent
    /// transmitting its true mass (scenarios/README.md, `[v2x]`): what the second opponent-mass
    /// source buys across the library.
    #[arg(long)]
    v2x: bool,
}

fn main() -> std::process::ExitCode {
    host::default_sigpipe();
    host::check_exit_code("offline-bench", run_all())
}

/// Runs every file; `Ok(false)` when a file missed an expectation, an error when one did not
/// run.
fn run_all() -> Result<bool> {
    let cli = Cli::parse();
    let repo = e2e_tests::repo_or_default(cli.repo.clone())?;
    let mut files = cli.scenario.clone();
    if files.is_empty() {
        files = e2e_tests::library_files(&repo)?;
    }
    // `--config` and `--cycle-config` exclude each other (clap).
    let mut cfg =
        OfflineConfig::from_flags(&repo, cli.config.as_deref(), cli.cycle_config.as_deref())?;
    if cli.no_lut {
        cfg.lut = None;
    }
    // Every output path is checked before the run, not at its end.
    if let Some(dir) = &cli.plot {
        host::check_output_dir(dir).with_context(|| format!("--plot {}", dir.display()))?;
    }
    if let Some(dir) = &cli.record {
        host::check_output_dir(dir).with_context(|| format!("--record {}", dir.display()))?;
    }
    if let Some(p) = &cli.json {
        host::check_output_file(p).with_context(|| format!("--json {}", p.display()))?;
    }
    // Load every file first: the table's name column fits the longest name.
    let loaded: Vec<_> = files
        .iter()
        .map(|f| (f, world::Scenario::load(f)))
        .collect();
    let width = loaded
        .iter()
        .filter_map(|(_, s)| s.as_ref().ok().map(|s| s.name.chars().count()))
        .fold(NAME_WIDTH, usize::max);
    // `--json -` keeps stdout for the JSON: the table goes to stderr then.
    let json_to_stdout = cli.json.as_deref().is_some_and(host::results::is_stdout);
    let mut out: Box<dyn std::io::Write> = if json_to_stdout {
        Box::new(std::io::stderr().lock())
    } else {
        Box::new(std::io::stdout().lock())
    };
    // A closed pipe (`| head`) ends the table quietly instead of a panic.
    let mut say = |line: &str| writeln!(out, "{line}").is_ok();
    say(&table_header(width));
    let (mut json, mut failed, mut missed) = (Vec::new(), 0usize, Vec::new());
    let (mut recorded, mut recorded_bytes) = (0usize, 0u64);
    for (file, loaded) in loaded {
        let file_name = file.display().to_string();
        let s = match loaded {
            Ok(mut s) => {
                if cli.v2x && s.v2x.is_none() {
                    s.v2x = Some(world::scenario::V2x::default());
                }
                s
            }
            Err(e) => {
                eprintln!("offline-bench: {e}");
                json.push(serde_json::json!({ "file": file_name, "error": e.to_string() }));
                failed += 1;
                continue;
            }
        };
        let mut trace = Trace {
            record: cli.record.is_some().then(Default::default),
            ..Trace::default()
        };
        let traced = cli.plot.is_some() || cli.record.is_some();
        let r = match run_traced(&s, &cfg, traced.then_some(&mut trace)) {
            Ok(r) => r,
            Err(e) => {
                eprintln!("offline-bench: {file_name}: {e:#}");
                json.push(serde_json::json!({
                    "file": file_name, "scenario": s.name, "error": format!("{e:#}")
                }));
                failed += 1;
                continue;
            }
        };
        if let Some(dir) = &cli.plot {
            e2e_tests::offline_plot::draw(&dir.join(format!("{}.png", r.name)), &r, &trace)
                .map_err(anyhow::Error::msg)?;
        }
        if let (Some(dir), Some(log)) = (&cli.record, &trace.record) {
            let w = log
                .write(&dir.join(&r.name), file)
                .with_context(|| format!("--record {}", dir.join(&r.name).display()))?;
            recorded += 1;
            recorded_bytes += w.bytes;
        }
        let mismatches = (!cli.no_expect).then(|| check(&s, &Observed::offline(&r)));
        if !say(&table_row(&r, width)) {
            return Ok(true);
        }
        if let Some(m) = &mismatches {
            missed.extend(m.iter().map(ToString::to_string));
        }
        json.push(run_json(&r, file, mismatches.as_deref()));
    }
    say("(! = bottomed out; confirm = first ECU cycle in mode crash; airbag = ms after the true contact, plan = its FireTime; required = \"127 mm − 30 ms\" of the true pulse, ms after the contact; action lines: ms after the true contact, or after the start without one; times on the simulated 1 kHz grid, no CAN latency)");
    if let Some(dir) = &cli.record {
        say(&format!(
            "recordings: {recorded} runs in {}/<scenario>/run.mcap ({:.1} MB; simulated clock, no bus latency; docs/using.md \"Recordings\")",
            dir.display(),
            recorded_bytes as f64 / 1e6
        ));
    }
    if let Some(p) = &cli.json {
        // Every record names its layout, the runs and the files that did not run alike.
        let doc = host::results::versioned_value(
            e2e_tests::offline::RUN_SCHEMA_VERSION,
            serde_json::Value::Array(json),
        );
        host::results::write_json(p, &serde_json::to_string_pretty(&doc)?)
            .with_context(|| format!("--json {}", p.display()))?;
    }
    for m in &missed {
        eprintln!("offline-bench: {m}");
    }
    // A file that did not run is an error (exit 2); a missed expectation a failed check (1).
    if failed > 0 {
        anyhow::bail!(
            "{failed} of {} files did not run, {} expectations missed",
            files.len(),
            missed.len()
        );
    }
    if !missed.is_empty() {
        eprintln!(
            "offline-bench: FAIL: {} expectations missed in {} files",
            missed.len(),
            files.len()
        );
    }
    Ok(missed.is_empty())
}
