//! `lut` — restraint optimiser, characteristic-diagram builder and the method's studies.
//!
//! Each sub-command lives in its own module; add new ones by adding a variant to [`Command`]
//! and a module with `run(args)`.

mod cmd_simulate;
mod cmd_stiffness;
mod plot;
mod study;

use clap::{Parser, Subcommand};

#[derive(Parser, Debug)]
#[command(name = "lut", version, about = "Restraint optimiser, characteristic diagram and studies")]
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
    Study(study::StudyCommand),
    /// Stiffness-class tools.
    #[command(subcommand)]
    Stiffness(cmd_stiffness::StiffnessCommand),
}

fn main() -> anyhow::Result<()> {
    match Cli::parse().command {
        Command::Simulate(args) => cmd_simulate::run(&args),
        Command::Study(cmd) => study::run(&cmd),
        Command::Stiffness(cmd) => cmd_stiffness::run(&cmd),
    }
}
