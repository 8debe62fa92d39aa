//! Wiring of the ECU process: config → CAN decision → iceoryx2 → RT settings → loop →
//! report. Kept in the library so tests can run the whole process in-process.

use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};

use ipc::ServiceNames;

use super::com::{CanPort, IceoryxIo};
use super::config::EcuConfig;
use super::report::{CanStatus, IpcStatus, TimingReport};
use super::rt;
use super::run::{run_activity, LoopConfig, LoopStats};
use host::MonotonicClock;
use restraint::Activity;

/// Decides whether the CAN side runs. `Err` when CAN is requested but the interface is
/// missing (the operator must bring up vcan0 or pass `--no-can`: never silently off).
pub fn can_decision(cfg: &EcuConfig, can_port_available: bool) -> anyhow::Result<CanStatus> {
    let interface = cfg.can.interface.clone();
    if !cfg.can.enabled {
        return Ok(CanStatus {
            enabled: false,
            interface,
            reason: "switched off by --no-can / can.enabled = false".into(),
        });
    }
    if !Path::new("/sys/class/net").join(&interface).exists() {
        anyhow::bail!(
            "CAN interface {interface} does not exist on this host (no SocketCAN/vcan?): \
             bring it up with vcan-setup.sh or run with --no-can"
        );
    }
    Ok(if can_port_available {
        CanStatus {
            enabled: true,
            interface,
            reason: "SocketCAN port open".into(),
        }
    } else {
        CanStatus {
            enabled: false,
            interface,
            reason: "interface present but no CAN port was handed to the shell".into(),
        }
    })
}

/// The finished run.
pub struct RunOutcome {
    /// Text report.
    pub text: String,
    /// JSON report.
    pub json: String,
    /// Loop statistics.
    pub stats: LoopStats,
}

/// The line the ECU prints on stderr when its ports are open and its cycle loop starts.
pub const READY_LINE: &str = "ecu: cycle loop running";

/// Runs the ECU process body with `activity` until `stop` or `cfg.cycles`.
pub fn run_ecu(
    cfg: &EcuConfig,
    activity: &mut dyn Activity,
    can_port: Option<Box<dyn CanPort>>,
    stop: &AtomicBool,
    verbose: bool,
    config: Option<&str>,
) -> anyhow::Result<RunOutcome> {
    let can = can_decision(cfg, can_port.is_some())?;
    let can_port = if can.enabled { can_port } else { None };
    let names = ServiceNames::with_prefix(&cfg.ipc.service_prefix);
    let (node, cleanup) = ipc::create_node(&cfg.ipc.node_name, false)?;
    let mut io = IceoryxIo::new(
        &node,
        &names,
        can_port,
        std::time::Duration::from_micros(cfg.period_us),
    )?;

    // Preallocate everything the loop writes before locking memory and going RT.
    let mut stats = LoopStats::default();
    let rt_state = rt::apply(&cfg.rt);
    if verbose {
        eprintln!(
            "ecu: period {} µs, activity {}, services {}/…, node {}",
            cfg.period_us,
            activity.name(),
            cfg.ipc.service_prefix,
            cfg.ipc.node_name
        );
        if cleanup.cleaned + cleanup.failed > 0 {
            eprintln!(
                "ecu: iceoryx2 stale resources: {} dead node(s) cleaned, {} failed",
                cleanup.cleaned, cleanup.failed
            );
        }
        for l in rt_state.summary_lines() {
            eprintln!("ecu: {l}");
        }
        eprintln!(
            "ecu: can          {:<6} {} ({})",
            if can.enabled { "ON" } else { "off" },
            can.interface,
            can.reason
        );
    }
    for o in [
        &rt_state.sched.outcome,
        &rt_state.mlockall,
        &rt_state.cpu_affinity,
        &rt_state.pm_qos,
    ] {
        if o.requested && !o.granted {
            eprintln!("ecu: warning: {} — continuing without it", o.detail);
        }
    }

    // Ports open, RT settings applied: from here on the ECU receives. Printed also with
    // --quiet, for whoever starts the feeds only then (the e2e harness waits for it).
    eprintln!("{READY_LINE}");
    let loop_cfg = LoopConfig {
        period_ns: cfg.period_us.saturating_mul(1_000),
        max_cycles: cfg.cycles,
    };
    run_activity(
        &mut MonotonicClock,
        activity,
        &mut io,
        &loop_cfg,
        stop,
        &mut stats,
    )?;

    io.shutdown(); // sends the final diagnostics record
    let mut counters = Vec::new();
    activity.report_counters(&mut |name, v| counters.push((name, v)));
    let (o, a, sf, d) = (
        io.object_counters(),
        io.accel_counters(),
        io.safing_counters(),
        io.diagnostics_counters(),
    );
    let sat = io.satellite_counters();
    let ipc_status = IpcStatus {
        service_prefix: cfg.ipc.service_prefix.clone(),
        stale_nodes_cleaned: cleanup.cleaned,
        stale_nodes_failed: cleanup.failed,
        object_rx: o.received,
        object_rx_errors: o.errors,
        accel_rx: a.received,
        accel_rx_errors: a.errors,
        safing_rx: sf.received,
        safing_rx_errors: sf.errors,
        satellite_rx: sat.map(|c| c.received),
        satellite_rx_errors: sat.map(|c| c.errors),
        diagnostics_written: io.diagnostics_written(),
        diagnostics_tx: d.sent,
        diagnostics_tx_errors: d.errors,
    };
    let stop_reason = if stop.load(Ordering::Relaxed) {
        "signal"
    } else {
        "cycles"
    };
    let mut report = TimingReport::new(
        &stats,
        loop_cfg.period_ns,
        activity.name(),
        &counters,
        &rt_state,
        can,
        Some(ipc_status),
        stop_reason,
    );
    report.config = config;
    let text = report.to_text();
    let json = report.to_json()?;
    drop(report);
    drop(rt_state);
    Ok(RunOutcome { text, json, stats })
}
