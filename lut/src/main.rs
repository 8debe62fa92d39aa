//! `lut` — restraint optimiser, characteristic-diagram builder and the method's studies.
//!
//! Each sub-command lives in its own module; add new ones by adding a variant to [`Command`]
//! and a module with `run(args)`.

mod cmd_optim;
mod cmd_simulate;
mod cmd_slurm;
mod cmd_stiffness;
mod cmd_study;
mod cmd_table;
mod heatmap;
mod plot;

use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};

#[derive(Parser, Debug)]
#[command(
    name = "lut",
    version,
    about = "Restraint optimiser, characteristic diagram and studies"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Predict one car-to-car collision with the two-mass model and print both vehicles' results.
    Simulate(cmd_simulate::SimulateArgs),
    /// Parameter studies of the paper.
    #[command(subcommand)]
    Study(cmd_study::StudyCommand),
    /// Stiffness-class tools.
    #[command(subcommand)]
    Stiffness(cmd_stiffness::StiffnessCommand),
    /// Optimise the conventional reference restraint for the two FMVSS 208 cases.
    Reference(cmd_optim::ReferenceArgs),
    /// Optimise the adaptive restraint for one situation (prints JSON with timing).
    Optimise(cmd_optim::OptimiseArgs),
    /// Build the characteristic diagram (or one shard of it) from a grid file.
    Build(cmd_table::BuildArgs),
    /// Merge shard files into one table.
    Merge(cmd_table::MergeArgs),
    /// Re-optimise random cells of a table and check it (non-zero exit on mismatch).
    Verify(cmd_table::VerifyArgs),
    /// Show a table's header, axes and cell statistics.
    Inspect(cmd_table::InspectArgs),
    /// Heat map of one output over two axes, the other two fixed.
    Plot(cmd_table::PlotArgs),
    /// Export a table as JSON.
    ExportJson(cmd_table::ExportArgs),
    /// Distributed runs (`--slurm N` of build / study robustness): status, collect, cancel.
    #[command(subcommand)]
    Slurm(cmd_slurm::SlurmCommand),
}

/// Errors are printed as one readable chain (`lut: error: …: …`), never as a Debug dump with a
/// backtrace (which `main() -> anyhow::Result` prints when RUST_BACKTRACE is set).
fn main() -> std::process::ExitCode {
    host::default_sigpipe();
    let matches = Cli::command().get_matches();
    let checked = check_outputs(&matches);
    let result = checked
        .and_then(|()| Ok(Cli::from_arg_matches(&matches)?))
        .and_then(run);
    host::exit_code("lut", result)
}

/// Every output path of every subcommand (`--out`, `--plot`, `--json`) is checked before the
/// work — a build or a study takes minutes — not when its result is written: its folder is
/// made and the file opened for writing (an existing folder is taken as the output folder).
fn check_outputs(m: &clap::ArgMatches) -> anyhow::Result<()> {
    for id in ["out", "plot", "json"] {
        if let Ok(Some(p)) = m.try_get_one::<std::path::PathBuf>(id) {
            if !p.is_dir() {
                host::check_output_file(p)
                    .map_err(|e| anyhow::anyhow!("--{id} {}: {e}", p.display()))?;
            }
        }
    }
    match m.subcommand() {
        Some((_, sub)) => check_outputs(sub),
        None => Ok(()),
    }
}

fn run(cli: Cli) -> anyhow::Result<()> {
    // Inside a Slurm job without cgroups every core of the node is visible: size rayon's
    // global pool (verify, studies) from the CPUs the job asked for.
    if let (Some(n), None) = (
        lut::slurm::cpus_per_task(),
        std::env::var_os("RAYON_NUM_THREADS"),
    ) {
        let _ = rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build_global();
    }
    match cli.command {
        Command::Simulate(args) => cmd_simulate::run(&args),
        Command::Study(cmd) => cmd_study::run(&cmd),
        Command::Stiffness(cmd) => cmd_stiffness::run(&cmd),
        Command::Reference(args) => cmd_optim::run_reference(&args),
        Command::Optimise(args) => cmd_optim::run_optimise(&args),
        Command::Build(args) => cmd_table::run_build(&args),
        Command::Merge(args) => cmd_table::run_merge(&args),
        Command::Verify(args) => cmd_table::run_verify(&args),
        Command::Inspect(args) => cmd_table::run_inspect(&args),
        Command::Plot(args) => cmd_table::run_plot(&args),
        Command::ExportJson(args) => cmd_table::run_export(&args),
        Command::Slurm(cmd) => cmd_slurm::run(&cmd),
    }
}
