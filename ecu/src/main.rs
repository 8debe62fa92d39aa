//! The fixed-rate restraint ECU process (`ecu --help`).

use clap::Parser;
use ecu::can_port::SocketCanPort;
use ecu::runtime::{app, monitor, CanPort, Cli, Command, EcuConfig, Layers};
use physics::reference::ReferenceRestraint;
use restraint::RestraintCycle;

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

/// The LUT, or `None` with a clear message: the ECU then runs DEGRADED on the reference
/// restraint instead of refusing to start (never "no protection").
fn load_lut(cfg: &EcuConfig) -> Option<diagram::Diagram> {
    match diagram::Diagram::load_any(&cfg.cycle.lut) {
        Ok(d) => {
            eprintln!(
                "ecu: lut          {} (id {:#06x}, ego {} kg class {})",
                cfg.cycle.lut.display(),
                d.lut_id(),
                d.header().ego.mass_kg,
                d.header().ego.class
            );
            Some(d)
        }
        Err(e) => {
            eprintln!(
                "ecu: error: characteristic diagram unusable: {e} — running DEGRADED with the \
                 reference restraint (build one with `lut build`, or pass --lut FILE)"
            );
            None
        }
    }
}

/// The SecOC sender, or `None` with a clear message: the ECU then starts without
/// authenticator frames and reports `FaultConfig` (see `CycleConfig::secoc_keys`) rather than
/// refusing to start — its commands still go out, the bench sees why the actuators ignore them.
fn load_secoc(cfg: &EcuConfig) -> Option<bus::secoc::SecOcTx> {
    match bus::secoc::SecOcKeys::load(&cfg.cycle.secoc_keys) {
        Ok(keys) => {
            eprintln!("ecu: secoc keys   {}", cfg.cycle.secoc_keys.display());
            // Freshness = CLOCK_REALTIME µs per cycle (CycleInfo::sync_time_us): nothing to
            // agree on with the actuators, nothing to persist across restarts.
            Some(keys.tx())
        }
        Err(e) => {
            eprintln!(
                "ecu: error: SecOC keys unusable: {e} — commands are sent WITHOUT \
                 authenticators (authenticated actuators will ignore them), EcuStatus.FaultConfig \
                 set (pass --secoc-keys FILE)"
            );
            None
        }
    }
}

fn load_reference(cfg: &EcuConfig) -> anyhow::Result<ReferenceRestraint> {
    match ReferenceRestraint::load(&cfg.cycle.reference) {
        Ok(r) => Ok(r),
        Err(e) => {
            eprintln!("ecu: warning: {e} — using the reference restraint built into this binary");
            ReferenceRestraint::builtin().map_err(anyhow::Error::msg)
        }
    }
}

fn run(cli: &Cli) -> anyhow::Result<()> {
    let layers = Layers::new(cli.run.config.as_deref(), cli.run.clone())?;
    let cfg = layers.extract()?;
    if cli.run.show_config {
        print!("{}", layers.show(&cfg));
        return Ok(());
    }
    let stop = host::install_stop_signals()?;
    let lut = load_lut(&cfg);
    let reference = load_reference(&cfg)?;
    let (mut activity, notes) = RestraintCycle::new(
        cfg.cycle.decision.clone(),
        lut.as_ref().map(ecu::lut_input),
        &ecu::reference_input(&reference.restraint),
    )
    .map_err(|e| anyhow::anyhow!("{e}"))?;
    if let Some(m) = notes.lut_rejected {
        eprintln!("ecu: warning: {m}");
    }
    activity.set_secoc(load_secoc(&cfg));
    // SocketCAN with the kernel input filter when CAN is on and the interface exists; the
    // shell's CAN decision reports a missing interface (and `--no-can` switches CAN off).
    let can: Option<Box<dyn CanPort>> = if cfg.can.enabled
        && std::path::Path::new("/sys/class/net")
            .join(&cfg.can.interface)
            .exists()
    {
        let port = SocketCanPort::open_ecu(&cfg.can.interface).map_err(|e| {
            anyhow::anyhow!(
                "cannot open CAN interface {}: {e} (bring it up with vcan-setup.sh or pass --no-can)",
                cfg.can.interface
            )
        })?;
        Some(Box::new(port))
    } else {
        None
    };
    let outcome = app::run_ecu(&cfg, &mut activity, can, stop, !cli.run.quiet)?;
    print!("{}", outcome.text);
    Ok(())
}
