//! `hil-bench --scenario FILE [--scenario FILE …] [--out DIR]`: runs scenarios through the real
//! bench processes on a CAN interface that must already exist (run it through
//! `./vcan-setup.sh --run -- target/release/hil-bench …`). One guest boot, many scenarios.
//! Every scenario's `[expect]` keys are judged (`e2e_tests::expect`, as `offline-bench` does;
//! `--no-expect` skips it): a miss is printed (`hil-bench: MISSED <scenario>: [expect] <key> =
//! <expected>, measured <value>`) and the exit status is 1.
//!
//! `hil-bench --replay OUT/<name>/run.mcap --out DIR`: the recorded run's feeds and CAN inputs
//! played into the ECU again (`sensor-feeds --replay`), the stubs judging against its scenario
//! (`--scenario`, default the repository's `scenarios/<name>.toml`), and the new run compared
//! with the recorded one (`e2e_tests::replay`): every restraint action within one ECU cycle of
//! its recorded time after the contact, the same modes. A difference is listed and exits 1.

use anyhow::{Context, Result};
use clap::Parser;
use e2e_tests::{run_scenario, RunConfig};
use std::path::PathBuf;

/// HIL bench orchestrator: candump + actuator-stubs + ecu + sensor-feeds per scenario.
#[derive(Parser, Debug)]
#[command(name = "hil-bench", version)]
struct Cli {
    /// Scenario file(s), run one after the other (with `--replay`: the scenario the stubs
    /// judge against, default the repository's `scenarios/<recorded name>.toml`).
    #[arg(long, required_unless_present = "replay")]
    scenario: Vec<PathBuf>,
    /// Replay a recorded run (its `run.mcap`) into the ECU and compare the new run with it.
    #[arg(long, value_name = "RUN.mcap")]
    replay: Option<PathBuf>,
    /// Output root; each scenario writes OUT/<name>/.
    #[arg(long, default_value = "out")]
    out: PathBuf,
    /// CAN interface (default: $VCAN or vcan0).
    #[arg(long)]
    can: Option<String>,
    /// Folder of the bench binaries (default: this binary's folder).
    #[arg(long)]
    bin_dir: Option<PathBuf>,
    /// Extra ECU argument (repeatable), e.g. --ecu-arg=--config --ecu-arg=ecu.toml (after
    /// the bench's own `--sched-fifo 80 --mlockall`).
    #[arg(long, allow_hyphen_values = true)]
    ecu_arg: Vec<String>,
    /// Repository root (the ECU's working directory; default: the checkout around the current
    /// folder, found by walking up).
    #[arg(long)]
    repo: Option<PathBuf>,
    /// Print only the one-line verdicts, not the full summaries.
    #[arg(long = "quiet", alias = "brief")]
    brief: bool,
    /// Do not judge the scenarios' `[expect]` blocks (by default every key is asserted, with
    /// the judge `offline-bench` uses, and a miss exits 1).
    #[arg(long)]
    no_expect: bool,
    /// Also write each run's `run.mf4`: the CAN bus in the ASAM MDF 4.1 bus-logging layout
    /// (CANape, asammdf; the DBC attached) and the ECU's diagnostics (every run writes
    /// `run.mcap` anyway).
    #[arg(long)]
    mf4: bool,
}

fn main() -> std::process::ExitCode {
    host::default_sigpipe();
    host::check_exit_code("hil-bench", run())
}

/// One scenario run; where the route's timing is emulated, a run the machine starved
/// ([`e2e_tests::route::starved_run`]) is run again, up to the route's allowance — but never a
/// run whose fire / no-fire outcome contradicts the scenario's `[expect] airbag_fires`: that
/// verdict stands as measured. Every retry is in the summary, in `report.json`
/// (`retries`: why each earlier run was not taken) and on the `--quiet` line. With real
/// timers: one run, judged as it is.
fn run_until_measured(cfg: &RunConfig) -> Result<(e2e_tests::RunResult, Vec<String>)> {
    let route = e2e_tests::Route::current();
    let attempts = route.allowances().time_limit_attempts;
    let scenario = world::Scenario::load(&cfg.scenario).ok();
    let mut earlier = Vec::new();
    let mut attempt = 1;
    loop {
        let mut r = run_scenario(cfg)?;
        let contradicts = scenario
            .as_ref()
            .and_then(|s| s.expect.airbag_fires)
            .is_some_and(|want| want != r.report.airbag_fired);
        let starved = scenario
            .as_ref()
            .and_then(|s| e2e_tests::route::starved_run(s, &r.report));
        match starved {
            Some(why) if attempt < attempts && !contradicts => {
                eprintln!(
                    "hil-bench: {}: run {attempt} starved by the emulated machine ({why}); running it again",
                    r.name
                );
                earlier.push(format!("run {attempt}: {why}"));
                attempt += 1;
            }
            _ => {
                if !earlier.is_empty() {
                    let note = format!(
                        "emulated timing ({}): run {attempt}; the earlier ones were starved: {}\n",
                        route.name(),
                        earlier.join("; ")
                    );
                    r.summary.push_str(&note);
                    std::fs::write(r.dir.join("summary.txt"), &r.summary)?;
                    record_retries(&r.dir.join("report.json"), &earlier)?;
                }
                return Ok((r, earlier));
            }
        }
    }
}

/// Adds `retries` (why each earlier run was not taken) to the stubs' `report.json`.
fn record_retries(path: &std::path::Path, earlier: &[String]) -> Result<()> {
    let Ok(text) = std::fs::read_to_string(path) else {
        return Ok(()); // no report written: the run's own error says why
    };
    let mut v: serde_json::Value =
        serde_json::from_str(&text).map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
    if let Some(o) = v.as_object_mut() {
        o.insert("retries".into(), serde_json::json!(earlier));
    }
    std::fs::write(path, serde_json::to_string_pretty(&v)?)?;
    Ok(())
}

/// `--replay`: one run of the recording's feeds, compared with the recorded run.
fn replay(cli: &Cli, run: &std::path::Path, bin_dir: PathBuf, can: String) -> Result<bool> {
    let bytes = std::fs::read(run).with_context(|| format!("--replay {}", run.display()))?;
    let recorded =
        record::read::report(&bytes).with_context(|| format!("--replay {}", run.display()))?;
    let name = recorded["scenario"]
        .as_str()
        .with_context(|| format!("--replay {}: its report names no scenario", run.display()))?
        .to_owned();
    let repo = e2e_tests::repo_or_default(cli.repo.clone())?;
    let scenario = match cli.scenario.as_slice() {
        [] => repo.join("scenarios").join(format!("{name}.toml")),
        [one] => one.clone(),
        _ => anyhow::bail!("--replay takes one --scenario at most"),
    };
    if !scenario.is_file() {
        anyhow::bail!(
            "the recording's scenario `{name}` is not {}: name its file with --scenario",
            scenario.display()
        );
    }
    // The recording's own folder is not overwritten by its replay.
    let into = cli.out.join(&name);
    if let (Ok(a), Some(Ok(b))) = (
        into.canonicalize(),
        run.parent().map(std::path::Path::canonicalize),
    ) {
        if a == b {
            anyhow::bail!(
                "--out {} would overwrite the recording it replays: give another --out",
                cli.out.display()
            );
        }
    }
    let cfg = RunConfig {
        scenario,
        out: cli.out.clone(),
        can,
        bin_dir,
        service_prefix: format!("hil-bench-{}-replay", std::process::id()),
        ecu_args: [e2e_tests::default_ecu_args(), cli.ecu_arg.clone()].concat(),
        ecu_cwd: repo,
        stubs_args: e2e_tests::default_stubs_args(),
        replay: Some(run.to_path_buf()),
    };
    let r = run_scenario(&cfg)?;
    let path = r.dir.join("report.json");
    let replayed: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(&path).with_context(|| path.display().to_string())?,
    )
    .with_context(|| path.display().to_string())?;
    let c = e2e_tests::replay::compare(&recorded, &replayed);
    if !cli.brief {
        println!("{}", r.summary);
    }
    println!("replay of {} into {}:", run.display(), r.dir.display());
    for l in &c.lines {
        println!("  {l}");
    }
    if c.differences.is_empty() {
        println!(
            "{name}: replay: no difference (every action within {} ms of its recorded time, the same modes)",
            e2e_tests::replay::TOLERANCE_MS
        );
    } else {
        for d in &c.differences {
            println!("{name}: replay: DIFFERENT: {d}");
        }
    }
    Ok(c.differences.is_empty() && r.problems.is_empty())
}

fn run() -> Result<bool> {
    let cli = Cli::parse();
    let bin_dir = match cli.bin_dir.clone() {
        Some(d) => d,
        None => std::env::current_exe()?
            .parent()
            .map(PathBuf::from)
            .unwrap_or_default(),
    };
    let can = bus::socket::interface(cli.can.as_deref());
    // The output folder is checked before the runs, not after them.
    host::check_output_dir(&cli.out).with_context(|| format!("--out {}", cli.out.display()))?;
    if let Some(run) = &cli.replay {
        return replay(&cli, run, bin_dir, can);
    }
    let mut all_ok = true;
    let mut errors = 0;
    for (i, scenario) in cli.scenario.iter().enumerate() {
        let cfg = RunConfig {
            scenario: scenario.clone(),
            out: cli.out.clone(),
            can: can.clone(),
            bin_dir: bin_dir.clone(),
            service_prefix: format!("hil-bench-{}-{i}", std::process::id()),
            ecu_args: [e2e_tests::default_ecu_args(), cli.ecu_arg.clone()].concat(),
            ecu_cwd: e2e_tests::repo_or_default(cli.repo.clone())?,
            stubs_args: e2e_tests::default_stubs_args(),
            replay: None,
        };
        match run_until_measured(&cfg) {
            Ok((r, retries)) => {
                let missed = if cli.no_expect {
                    Vec::new()
                } else {
                    match world::Scenario::load(scenario) {
                        Ok(s) => e2e_tests::expect::check(
                            &s,
                            &e2e_tests::expect::Observed::bench(&r.report, r.ecu_report.as_ref()),
                        )
                        .iter()
                        .map(ToString::to_string)
                        .collect(),
                        Err(e) => vec![format!("{e}")],
                    }
                };
                if cli.brief {
                    let verdict = r
                        .report
                        .outcome
                        .as_ref()
                        .map_or("no contact".to_owned(), |o| {
                            format!(
                                "{:+.1} % vs reference ({})",
                                o.change_pct,
                                if o.adaptive_no_worse {
                                    "no worse"
                                } else {
                                    "WORSE"
                                }
                            )
                        });
                    let retried = if retries.is_empty() {
                        String::new()
                    } else {
                        format!(
                            " (run {}; retried: {})",
                            retries.len() + 1,
                            retries.join("; ")
                        )
                    };
                    println!(
                        "{}: airbag {}, {verdict}{retried}",
                        r.name,
                        if r.report.airbag_fired {
                            "fired"
                        } else {
                            "not fired"
                        }
                    );
                } else {
                    println!("{}", r.summary);
                }
                for m in &missed {
                    println!("hil-bench: MISSED {m}");
                }
                let mut recorded = true;
                if cli.mf4 {
                    let out = r.dir.join(record::RUN_MF4);
                    // Where the run's recording is left to the host, so is its MF4.
                    match record::pending::defer_mf4(&r.dir).and_then(|deferred| {
                        if deferred {
                            Ok(format!(
                                "recording (MDF 4.1): {} to be written on the host after the run",
                                out.display()
                            ))
                        } else {
                            record::write_run_mf4(&r.dir, &out)
                                .map(|s| record::mf4_summary_line(&out, &s))
                        }
                    }) {
                        Ok(line) => println!("{line}"),
                        Err(e) => {
                            eprintln!("hil-bench: {}: {e:#}", out.display());
                            recorded = false;
                        }
                    }
                }
                all_ok &= r.problems.is_empty() && missed.is_empty() && recorded;
            }
            Err(e) => {
                // A run that could not be made (the ECU did not start, a process failed) is an
                // error, not a verdict: said on --quiet's line too, and the exit status is 2.
                if cli.brief {
                    println!("{}: run aborted: {e:#}", scenario.display());
                }
                eprintln!("hil-bench: {}: {e:#}", scenario.display());
                errors += 1;
            }
        }
    }
    anyhow::ensure!(
        errors == 0,
        "{errors} of {} runs could not be made (above)",
        cli.scenario.len()
    );
    Ok(all_ok)
}
