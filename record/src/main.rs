//! `record` — recordings of bench runs.
//!
//! `record mcap DIR` writes `DIR/run.mcap` from the run folder a bench run left (`hil-bench`,
//! `demo.sh`, the fault campaign write it themselves after every run); `record latency
//! run.mcap` measures cycle → bus and sample → bus latency from it.

use anyhow::{Context, Result};
use clap::{Parser, Subcommand};
use record::{write_run, write_run_mf4, RunMeta, RUN_MCAP, RUN_MF4};
use std::path::PathBuf;

#[derive(Parser, Debug)]
#[command(name = "record", version, about = "Recordings of bench runs (MCAP)")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Write the run folder's recording: CAN frames raw and decoded by the DBC, the stubs'
    /// commands, actions and verdict, on the bench's CLOCK_MONOTONIC.
    Mcap {
        /// The run folder (holds candump.log; commands.jsonl and report.json when the stubs ran).
        dir: PathBuf,
        /// Output file [default: DIR/run.mcap].
        #[arg(long, value_name = "FILE")]
        out: Option<PathBuf>,
        /// The vcan route the run took, for the file's metadata.
        #[arg(long, default_value = "unknown")]
        route: String,
        /// Whether the route's timing was emulated (a virtual CPU's) or real.
        #[arg(long, value_parser = ["emulated", "real"])]
        timing: Option<String>,
        /// The scenario file the run played (its truth goes on /truth/world).
        #[arg(long, value_name = "FILE")]
        scenario: Option<PathBuf>,
    },
    /// Write the run folder's CAN bus in the ASAM MDF 4.1 bus-logging layout (CANape, asammdf;
    /// the DBC attached) plus the ECU's diagnostics as plain channels.
    Mf4 {
        /// The run folder (holds candump.log; the stubs' diagnostics log when they ran).
        dir: PathBuf,
        /// Output file [default: DIR/run.mf4].
        #[arg(long, value_name = "FILE")]
        out: Option<PathBuf>,
    },
    /// Write the recordings runs left to be written after the fact (`RECORD_ON_HOST=1`: runs
    /// in an emulated guest leave record.pending.json), in ROOT and three levels below; each
    /// run's lines are printed and appended to its summary.txt.
    Pending {
        /// Output roots of bench runs (e.g. out/).
        #[arg(required = true)]
        roots: Vec<PathBuf>,
    },
    /// How long after the start of the ECU cycle that sent it, and after the newest crash
    /// sample that cycle had, each command frame reached the bus (p50 / p99 / max per message,
    /// and every fire), from the recording's own times.
    Latency {
        /// A run's recording (run.mcap).
        file: PathBuf,
    },
}

fn main() -> std::process::ExitCode {
    host::stop::default_sigpipe();
    host::exit_code("record", run(Cli::parse()))
}

fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Mcap {
            dir,
            out,
            route,
            timing,
            scenario,
        } => {
            let out = out.unwrap_or_else(|| dir.join(RUN_MCAP));
            host::files::check_output_file(&out)?;
            let s = write_run(
                &dir,
                &out,
                &RunMeta {
                    route,
                    timing_emulated: timing.map(|t| t == "emulated"),
                    scenario,
                    simulated_start_ns: None,
                },
            )
            .with_context(|| format!("recording {}", dir.display()))?;
            let total: u64 = s.messages.values().sum();
            println!(
                "{}: {total} messages on {} topics, {:.1} kB; log time {}",
                out.display(),
                s.messages.len(),
                s.bytes as f64 / 1e3,
                s.realtime_minus_monotonic_ns.map_or(
                    "CLOCK_REALTIME (no frame seen by both candump and the stubs)".to_owned(),
                    |o| format!("CLOCK_MONOTONIC (realtime − monotonic = {o} ns)")
                )
            );
            for (topic, n) in &s.messages {
                println!("  {topic:<28} {n}");
            }
            Ok(())
        }
        Command::Mf4 { dir, out } => {
            let out = out.unwrap_or_else(|| dir.join(RUN_MF4));
            host::files::check_output_file(&out)?;
            let s = write_run_mf4(&dir, &out)
                .with_context(|| format!("recording {}", dir.display()))?;
            println!("{}", record::mf4_summary_line(&out, &s));
            Ok(())
        }
        Command::Pending { roots } => {
            let mut failed = 0;
            for root in &roots {
                for w in record::pending::write_pending(root)? {
                    match w.result {
                        Ok(lines) => lines.iter().for_each(|l| println!("{l}")),
                        Err(e) => {
                            eprintln!("record: {}: {e}", w.dir.display());
                            failed += 1;
                        }
                    }
                }
            }
            anyhow::ensure!(failed == 0, "{failed} recordings could not be written");
            Ok(())
        }
        Command::Latency { file } => {
            print!("{}", record::latency::latency(&file)?.table());
            Ok(())
        }
    }
}
