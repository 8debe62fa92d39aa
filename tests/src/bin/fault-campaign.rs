//! `fault-campaign`: the fault-injection campaign and the robustness report.
//!
//! * `fault-campaign run [--out DIR] [--case NAME …]` runs the cases (tests/src/faults/) on a
//!   CAN interface that must exist — start it through
//!   `./vcan-setup.sh --run -- target/release/fault-campaign run …` — and writes
//!   `DIR/campaign.json` and the timeline picture `DIR/campaign.png`; exit 1 if a case failed.
//! * `fault-campaign host-timing [--out DIR]` runs the iceoryx2 faults on the host kernel (CAN
//!   side off, named in the output) with the ECU at SCHED_FIFO 80: deadline misses where
//!   timers are real (tests/src/host_timing.rs).
//! * `fault-campaign report --campaign DIR/campaign.json [--fuzz fuzz.json]
//!   [--host-timing host-timing.json]` prints the robustness report: cases tried, faults
//!   survived, commands lost, deadline misses, frames rejected by reason, and the fuzzing
//!   figures of `tests/fuzz-smoke.sh` (FUZZ_REPORT_JSON).

use anyhow::{Context, Result};
use clap::{Parser, Subcommand};
use e2e_tests::faults::{report_text, run_campaign, Campaign, CampaignConfig, FuzzTarget};
use e2e_tests::host_timing::{host_timing_text, run_host_timing, HostTiming, HostTimingConfig};
use std::path::PathBuf;

#[derive(Parser, Debug)]
#[command(
    name = "fault-campaign",
    version,
    about = "Fault-injection campaign and robustness report"
)]
struct Cli {
    #[command(subcommand)]
    cmd: Cmd,
}

#[derive(Subcommand, Debug)]
enum Cmd {
    /// Run the campaign (needs a CAN interface; see vcan-setup.sh --run).
    Run {
        /// Output root.
        #[arg(long, default_value = "out/faults")]
        out: PathBuf,
        /// Only these cases (the baseline always runs).
        #[arg(long = "case")]
        cases: Vec<String>,
        /// CAN interface (default: $VCAN or vcan0).
        #[arg(long)]
        can: Option<String>,
        /// Folder of the bench binaries (default: this binary's folder).
        #[arg(long)]
        bin_dir: Option<PathBuf>,
        /// Repository root (default: the checkout around the current folder, found by walking up).
        #[arg(long)]
        repo: Option<PathBuf>,
        /// Also print the robustness report with these fuzzing figures.
        #[arg(long)]
        fuzz: Option<PathBuf>,
        /// Extra ECU argument for every case (repeatable; after the bench's own
        /// `--sched-fifo 80 --mlockall`).
        #[arg(long, allow_hyphen_values = true)]
        ecu_arg: Vec<String>,
    },
    /// Deadline misses of the iceoryx2 faults on the host kernel (no CAN: `--no-can`), ECU at
    /// SCHED_FIFO 80 pinned to `--cpu`; writes OUT/host-timing.json. Needs root (or rtprio).
    HostTiming {
        /// Output root.
        #[arg(long, default_value = "out/host-timing")]
        out: PathBuf,
        /// CPU the ECU is pinned to.
        #[arg(long, default_value_t = 1)]
        cpu: u32,
        /// Folder of the bench binaries (default: this binary's folder).
        #[arg(long)]
        bin_dir: Option<PathBuf>,
        /// Repository root (default: the checkout around the current folder, found by walking up).
        #[arg(long)]
        repo: Option<PathBuf>,
    },
    /// Print the robustness report of a finished campaign.
    Report {
        /// campaign.json of a run.
        #[arg(long)]
        campaign: PathBuf,
        /// Fuzzing figures (tests/fuzz-smoke.sh with FUZZ_REPORT_JSON).
        #[arg(long)]
        fuzz: Option<PathBuf>,
        /// Host timing of the iceoryx2 faults (`fault-campaign host-timing`).
        #[arg(long)]
        host_timing: Option<PathBuf>,
        /// Also draw the campaign timeline into this PNG.
        #[arg(long)]
        plot: Option<PathBuf>,
    },
}

fn main() -> std::process::ExitCode {
    host::default_sigpipe();
    host::check_exit_code("fault-campaign", run())
}

/// The folder of this binary (where the other bench binaries are built).
fn this_dir() -> Result<PathBuf> {
    Ok(std::env::current_exe()?
        .parent()
        .map(PathBuf::from)
        .unwrap_or_default())
}

fn load_fuzz(path: Option<&PathBuf>) -> Result<Option<Vec<FuzzTarget>>> {
    path.map(|p| {
        let text =
            std::fs::read_to_string(p).with_context(|| format!("reading {}", p.display()))?;
        serde_json::from_str(&text).with_context(|| format!("parsing {}", p.display()))
    })
    .transpose()
}

fn run() -> Result<bool> {
    match Cli::parse().cmd {
        Cmd::Run {
            out,
            cases,
            can,
            bin_dir,
            repo,
            fuzz,
            ecu_arg,
        } => {
            let bin_dir = match bin_dir {
                Some(d) => d,
                None => this_dir()?,
            };
            let cfg = CampaignConfig {
                out: out.clone(),
                can: bus::socket::interface(can.as_deref()),
                bin_dir,
                repo: e2e_tests::repo_or_default(repo)?,
                ecu_args: [e2e_tests::default_ecu_args(), ecu_arg].concat(),
            };
            // The output folder is checked before the campaign's minutes, not after them.
            host::check_output_dir(&out).with_context(|| format!("--out {}", out.display()))?;
            let campaign = run_campaign(&cfg, &cases)?;
            let path = out.join("campaign.json");
            std::fs::write(
                &path,
                host::results::to_json_pretty(Campaign::SCHEMA_VERSION, &campaign)?,
            )?;
            let png = out.join("campaign.png");
            e2e_tests::timeline::draw_timeline(&campaign, &png)?;
            println!(
                "{}",
                report_text(&campaign, load_fuzz(fuzz.as_ref())?.as_deref())
            );
            println!("campaign: {}\ntimeline: {}", path.display(), png.display());
            Ok(campaign.cases.iter().all(|c| c.pass))
        }
        Cmd::HostTiming {
            out,
            cpu,
            bin_dir,
            repo,
        } => {
            let cfg = HostTimingConfig {
                out: out.clone(),
                bin_dir: match bin_dir {
                    Some(d) => d,
                    None => this_dir()?,
                },
                repo: e2e_tests::repo_or_default(repo)?,
                cpu,
            };
            host::check_output_dir(&out).with_context(|| format!("--out {}", out.display()))?;
            let h = run_host_timing(&cfg)?;
            let path = out.join("host-timing.json");
            std::fs::write(
                &path,
                host::results::to_json_pretty(HostTiming::SCHEMA_VERSION, &h)?,
            )?;
            println!("{}", host_timing_text(&h));
            println!("host timing: {}", path.display());
            Ok(true)
        }
        Cmd::Report {
            campaign,
            fuzz,
            host_timing,
            plot,
        } => {
            let text = std::fs::read_to_string(&campaign)
                .with_context(|| format!("reading {}", campaign.display()))?;
            let c: Campaign = serde_json::from_str(&text)
                .with_context(|| format!("parsing {}", campaign.display()))?;
            println!("{}", report_text(&c, load_fuzz(fuzz.as_ref())?.as_deref()));
            if let Some(p) = plot {
                e2e_tests::timeline::draw_timeline(&c, &p)?;
                println!("timeline: {}", p.display());
            }
            if let Some(p) = host_timing {
                let text = std::fs::read_to_string(&p)
                    .with_context(|| format!("reading {}", p.display()))?;
                let h: HostTiming = serde_json::from_str(&text)
                    .with_context(|| format!("parsing {}", p.display()))?;
                println!("{}", host_timing_text(&h));
            }
            Ok(c.cases.iter().all(|c| c.pass))
        }
    }
}
