//! The fixed-rate restraint ECU process (`ecu --help`).

use clap::Parser;
use ecu::runtime::{app, monitor, Cli, Command, EcuConfig, PassthroughActivity};

fn main() -> std::process::ExitCode {
    let cli = Cli::parse();
    let result = match &cli.command {
        Some(Command::Monitor(args)) => monitor::run(args),
        None => run(&cli),
    };
    match result {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("ecu: error: {e:#}");
            std::process::ExitCode::FAILURE
        }
    }
}

fn run(cli: &Cli) -> anyhow::Result<()> {
    let cfg = EcuConfig::resolve(&cli.run)?;
    let stop = app::install_stop_signals()?;
    // INTEGRATION POINT: replace the pass-through activity by the pure cycle logic and
    // pass the bus crate's SocketCAN port instead of `None`.
    let mut activity = PassthroughActivity::new();
    let outcome = app::run_ecu(&cfg, &mut activity, None, stop, !cli.run.quiet)?;
    print!("{}", outcome.text);
    Ok(())
}
