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
    host::exit_code("ecu", result)
}

/// The LUT, or `None` with a clear message: a table that is there but corrupt leaves the ECU
/// DEGRADED on the reference restraint (never "no protection"); one that is not there at all is
/// a set-up mistake and the ECU does not start, unless the user asked for `--no-lut`.
fn load_lut(cfg: &EcuConfig, no_lut: bool) -> anyhow::Result<Option<diagram::Diagram>> {
    if no_lut {
        eprintln!("ecu: lut          none (--no-lut): running DEGRADED on the reference restraint");
        return Ok(None);
    }
    let path = &cfg.cycle.lut;
    if !path.exists() {
        anyhow::bail!(
            "characteristic diagram {} not found (build one with `lut build`, pass --lut FILE, \
             or --no-lut to run DEGRADED on the reference restraint)",
            path.display()
        );
    }
    Ok(match diagram::Diagram::load_any(path) {
        Ok(d) => {
            eprintln!(
                "ecu: lut          {} (id {:#06x}, ego {} kg class {})",
                path.display(),
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
    })
}

/// The SecOC sender. Fail closed: without usable keys the ECU's fire commands would
/// go out unauthenticated, so it does not start unless the user asked for that with
/// `--no-secoc` (then `EcuStatus.FaultConfig` is set and the start-up line says so).
fn load_secoc(cfg: &EcuConfig, no_secoc: bool) -> anyhow::Result<Option<bus::secoc::SecOcTx>> {
    if no_secoc {
        eprintln!(
            "ecu: secoc keys   none (--no-secoc): commands WITHOUT authenticators, \
             EcuStatus.FaultConfig set"
        );
        return Ok(None);
    }
    let keys = bus::secoc::SecOcKeys::load(&cfg.cycle.secoc_keys).map_err(|e| {
        anyhow::anyhow!(
            "SecOC keys unusable: {e} (pass --secoc-keys FILE, or --no-secoc to send commands \
             without authenticators)"
        )
    })?;
    eprintln!("ecu: secoc keys   {}", cfg.cycle.secoc_keys.display());
    // Freshness = CLOCK_REALTIME µs per cycle (CycleInfo::sync_time_us): nothing to agree on
    // with the actuators, nothing to persist across restarts.
    Ok(Some(keys.tx()))
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
    let mut cfg = layers.extract()?;
    layers.resolve_files(&mut cfg);
    if cli.run.show_config {
        print!("{}", layers.show(&cfg));
        return Ok(());
    }
    // Every output path is checked before the run, not at its end.
    if let Some(path) = &cfg.report_json {
        host::check_output_file(path)
            .map_err(|e| anyhow::anyhow!("--json {}: {e}", path.display()))?;
    }
    let secoc = load_secoc(&cfg, cli.run.no_secoc)?;
    let lut = load_lut(&cfg, cli.run.no_lut)?;
    let stop = host::install_stop_signals()?;
    let reference = load_reference(&cfg)?;
    let (mut activity, notes) = RestraintCycle::new(
        cfg.cycle.decision.clone(),
        lut.as_ref().map(ecu::lut_input),
        &reference.restraint,
    )?;
    if let Some(m) = notes.lut_rejected {
        eprintln!("ecu: warning: {m}");
    }
    activity.set_secoc(secoc);
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
    // The report carries what the loop ran with (a bench run saves it as ecu-config.toml).
    let config = layers.show(&cfg);
    let outcome = app::run_ecu(
        &cfg,
        &mut activity,
        can,
        stop,
        !cli.run.quiet,
        Some(&config),
    )?;
    print!("{}", outcome.text);
    if let Some(path) = &cfg.report_json {
        host::results::write_json(path, &outcome.json)
            .map_err(|e| anyhow::anyhow!("cannot write the report: {e}"))?;
    }
    Ok(())
}
