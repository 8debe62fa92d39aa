//! `actuator-stubs --scenario FILE --can vcan0 --out DIR`: the belt retractor and airbag modules
//! on the bus (see README.md). Receives the ECU's commands with kernel filters, checks E2E,
//! logs every frame with CLOCK_MONOTONIC receive times (DIR/commands.jsonl), acts at the
//! commanded times, and at the end (bench truth `done`, timeout or SIGTERM) judges the occupant
//! outcome of what was commanded: DIR/report.json + DIR/outcome.png.

use actuator_stubs::commands::{CommandRecord, Modules};
use actuator_stubs::outcome;
use actuator_stubs::plot;
use actuator_stubs::report::{Report, TimedAction};
use actuator_stubs::rx::Receiver;
use actuator_stubs::status::{ecu_fault_names, ecu_mode_name};
use anyhow::{Context, Result};
use bus::secoc::SecOcConfig;
use bus::socket::BusSocket;
use clap::Parser;
use host::monotonic_ns;
use ipc::{BenchTruth, BenchTruthSubscriber, ServiceNames};
use std::collections::BTreeMap;
use std::io::Write;
use std::path::PathBuf;
use std::sync::atomic::Ordering;
use world::{Scenario, Truth};

/// Belt retractor + airbag module stubs: validate, log, act on and judge commands.
#[derive(Parser, Debug)]
#[command(name = "actuator-stubs", version, subcommand_negates_reqs = true)]
struct Cli {
    /// Instead of a run: draw the pictures runs left with `--plot-later`.
    #[command(subcommand)]
    command: Option<Command>,
    /// Scenario file (the same the sensor feeds play).
    #[arg(long, required = true)]
    scenario: Option<PathBuf>,
    /// CAN interface (default: $VCAN or vcan0).
    #[arg(long, value_name = "IFACE")]
    can: Option<String>,
    /// Output folder (commands.jsonl, report.json, outcome.png).
    #[arg(long, required = true)]
    out: Option<PathBuf>,
    /// Reference restraint file (default: the repository's data/reference-restraint.toml, as
    /// the ECU reads it; missing or unreadable: the copy built into the binary).
    #[arg(long)]
    reference: Option<PathBuf>,
    /// Give up waiting for the bench truth's `done` after this many seconds.
    #[arg(long, default_value_t = 60.0)]
    timeout_s: f64,
    /// iceoryx2 service prefix (must match the sensor feeds').
    #[arg(long, default_value = ipc::DEFAULT_SERVICE_PREFIX)]
    service_prefix: String,
    /// SecOC key file (format: data/secoc-keys.example.toml). Default: that example file's
    /// keys, built into the binary (the ECU's default key file), so the stubs need no
    /// working directory. A bad file is an error: the stubs would reject every command.
    #[arg(long, value_name = "FILE")]
    secoc_keys: Option<PathBuf>,
    /// How long a held command waits for its authenticator, ms (SecOC pairing timeout; the
    /// ECU sends both in the same cycle). Longer only where the kernel stalls processes
    /// (an emulator): the report names the value.
    #[arg(long, value_name = "MS", default_value_t = SecOcConfig::DEFAULT_PAIRING_TIMEOUT_US as f64 / 1e3)]
    secoc_pairing_timeout_ms: f64,
    /// SecOC freshness window, ms: an authenticator whose time stamp is further than this
    /// from our synchronized clock is rejected as stale (replays of earlier sessions). Wider
    /// only where the kernel stalls processes (an emulator); the report names the value.
    #[arg(long, value_name = "MS", default_value_t = SecOcConfig::default().freshness_window_us as f64 / 1e3)]
    secoc_freshness_window_ms: f64,
    /// After the scenario is done, keep receiving until SIGTERM/SIGINT, then read what is
    /// still queued and finish (stop reason "done"). For orchestrators that stop the ECU first
    /// and then the stubs, so every command the ECU sent is received and counted (the fault
    /// campaign compares them with what the ECU sent).
    #[arg(long)]
    until_signal: bool,
    /// Do not draw outcome.png: leave what it is drawn from in outcome-plot.json for
    /// `actuator-stubs draw-pending`, run on the host after the run. Drawing costs
    /// 0.6–1.0 s of an emulated guest's time at the end of the run.
    #[arg(long)]
    plot_later: bool,
}

/// The ECU's default key file, for the default of `--secoc-keys`.
const EXAMPLE_KEYS: &str = include_str!("../../data/secoc-keys.example.toml");

fn load_keys(cli: &Cli) -> Result<bus::secoc::SecOcKeys> {
    match &cli.secoc_keys {
        Some(p) => bus::secoc::SecOcKeys::load(p),
        None => bus::secoc::SecOcKeys::from_toml_str(
            EXAMPLE_KEYS,
            std::path::Path::new("data/secoc-keys.example.toml (built in)"),
        ),
    }
    .map_err(|e| anyhow::anyhow!("SecOC keys: {e}"))
}

/// Receive queue the stubs ask for (≈ 8 000 CAN frames at the kernel's per-frame cost).
const RX_QUEUE_BYTES: usize = 8 << 20;

/// Ids the modules listen to (kernel filter): airbag cmd + auth, belt cmd + auth, ECU status.
const RX_IDS: [u32; 5] = [
    bus::AirbagStageCmd::RAW_ID,
    bus::AirbagStageAuth::RAW_ID,
    bus::BeltLimiterCmd::RAW_ID,
    bus::BeltLimiterAuth::RAW_ID,
    bus::EcuStatus::RAW_ID,
];

/// What the stubs do besides a run.
#[derive(clap::Subcommand, Debug)]
enum Command {
    /// Draw `outcome.png` in every run folder under ROOT (three levels) whose run left
    /// `outcome-plot.json` (`--plot-later`), and append a line to its `summary.txt`; the
    /// bench's callers run it on the host after a run in an emulated guest.
    DrawPending {
        /// The runs' output folder.
        root: PathBuf,
    },
}

fn main() -> std::process::ExitCode {
    let cli = Cli::parse();
    let result = match &cli.command {
        Some(Command::DrawPending { root }) => draw_pending(root),
        None => run(&cli),
    };
    host::exit_code("actuator-stubs", result)
}

/// `draw-pending`: each drawn picture's line; an error when one could not be drawn (the
/// others are).
fn draw_pending(root: &std::path::Path) -> Result<()> {
    let mut failed = 0;
    for d in plot::draw_pending(root).map_err(anyhow::Error::msg)? {
        match d.result {
            Ok(line) => println!("{line}"),
            Err(e) => {
                eprintln!("actuator-stubs: {}: {e}", d.dir.display());
                failed += 1;
            }
        }
    }
    anyhow::ensure!(failed == 0, "{failed} picture(s) not drawn");
    Ok(())
}

/// Offset CLOCK_REALTIME − CLOCK_MONOTONIC [ns], to map kernel (realtime) receive stamps.
fn realtime_minus_monotonic_ns() -> i128 {
    i128::from(host::realtime_ns()) - i128::from(monotonic_ns())
}

fn run(cli: &Cli) -> Result<()> {
    // clap requires both without a subcommand.
    let (Some(scenario_path), Some(out)) = (&cli.scenario, &cli.out) else {
        anyhow::bail!("--scenario and --out are required");
    };
    let scenario = Scenario::load(scenario_path)?;
    let (reference, from) = outcome::reference_restraint(cli.reference.as_deref())
        .map_err(|e| anyhow::anyhow!("reference restraint: {e}"))?;
    if let outcome::ReferenceSource::BuiltIn(why) = from {
        eprintln!("actuator-stubs: warning: reference restraint built into the binary ({why})");
    }
    let keys = load_keys(cli)?;
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    let stop = host::install_stop_signals().context("installing signal handler")?;
    let can = bus::socket::interface(cli.can.as_deref());
    let mut sock = BusSocket::open(&can, &RX_IDS)
        .with_context(|| format!("CAN interface {can} (bring it up with ./vcan-setup.sh)"))?;
    // A deep receive queue: the stubs log every frame and may be descheduled for a while on a
    // loaded bench (a flooded bus, one emulated CPU); the ECU's commands must still all arrive.
    match sock.set_receive_buffer(RX_QUEUE_BYTES) {
        Ok(n) if n >= RX_QUEUE_BYTES => {}
        Ok(n) => eprintln!("actuator-stubs: CAN receive queue {n} bytes (asked {RX_QUEUE_BYTES})"),
        Err(e) => eprintln!("actuator-stubs: CAN receive queue not enlarged: {e}"),
    }
    let names = ServiceNames::with_prefix(&cli.service_prefix);
    let (node, _) = ipc::create_node(&format!("actuator-stubs-{}", std::process::id()), false)?;
    let mut truth_sub = BenchTruthSubscriber::new(&node, &names)?;
    // ECU diagnostics: for the timeline (when the ECU entered pre-crash) and logged as seen
    // for the run's recording (`record`: /ecu/diagnostics); the judgement uses nothing but the
    // bus.
    let mut diag_sub = ipc::DiagnosticsSubscriber::new(&node, &names)?;
    let mut diag_modes: Vec<(u64, u8)> = Vec::new();
    let diag_path = out.join(actuator_stubs::DIAGNOSTICS_LOG);
    let mut diag_log = std::io::BufWriter::new(
        std::fs::File::create(&diag_path)
            .with_context(|| format!("creating {}", diag_path.display()))?,
    );
    let mut diag_log_error: Option<String> = None;
    let log_path = out.join("commands.jsonl");
    let mut log = std::io::BufWriter::new(
        std::fs::File::create(&log_path)
            .with_context(|| format!("creating {}", log_path.display()))?,
    );
    if !(cli.secoc_pairing_timeout_ms.is_finite()
        && (0.1..=1000.0).contains(&cli.secoc_pairing_timeout_ms))
    {
        anyhow::bail!("--secoc-pairing-timeout-ms must be within 0.1..=1000");
    }
    let window_limit_ms = bus::secoc::MAX_FRESHNESS_WINDOW_US as f64 / 1e3;
    if !(cli.secoc_freshness_window_ms.is_finite()
        && (0.1..=window_limit_ms).contains(&cli.secoc_freshness_window_ms))
    {
        anyhow::bail!("--secoc-freshness-window-ms must be within 0.1..={window_limit_ms}");
    }
    let secoc_config = SecOcConfig {
        pairing_timeout_us: (cli.secoc_pairing_timeout_ms * 1e3).round() as u64,
        freshness_window_us: (cli.secoc_freshness_window_ms * 1e3).round() as u64,
    };
    let mut receiver = Receiver::with_config(&keys, secoc_config);
    let mut modules = Modules::default();
    let mut frames: BTreeMap<String, u64> = BTreeMap::new();
    let mut truth = BenchTruth::EMPTY;
    let started = monotonic_ns();
    let deadline = started + (cli.timeout_s * 1e9) as u64;
    eprintln!(
        "{} {} for {}",
        actuator_stubs::READY_PREFIX,
        can,
        scenario.name
    );
    let mut done = false;
    let stop_reason = loop {
        // Read before the drain: with --until-signal, everything queued before the signal is
        // still read and acted on below.
        let signalled = stop.load(Ordering::Relaxed);
        if signalled && !cli.until_signal {
            break "signal";
        }
        if monotonic_ns() > deadline {
            break "timeout";
        }
        let mut got_any = false;
        while let Some(rx) = sock.recv().context("CAN receive")? {
            got_any = true;
            let read_mono = monotonic_ns();
            // Kernel arrival time mapped onto CLOCK_MONOTONIC (more exact than the read time);
            // fall back to the read time if absent or implausible.
            let rx_ns = rx
                .kernel_time
                .and_then(|k| k.duration_since(std::time::UNIX_EPOCH).ok())
                .map(|d| d.as_nanos() as i128 - realtime_minus_monotonic_ns())
                .filter(|k| {
                    *k > 0 && *k <= read_mono as i128 && read_mono as i128 - *k < 1_000_000_000
                })
                .map_or(read_mono, |k| k as u64);
            let f = rx.frame;
            let name = bus::message_info(f.id)
                .map_or("unknown", |i| i.name)
                .to_owned();
            *frames.entry(name.clone()).or_default() += 1;
            // The synchronized time at arrival, on the same arrival instant as rx_ns (a stubs
            // process that was descheduled must not see a genuine authenticator as stale).
            let sync_rx_us =
                host::sync_time_us().saturating_sub(read_mono.saturating_sub(rx_ns) / 1_000);
            let v = receiver.on_frame(&f, rx_ns, sync_rx_us);
            if let Some(d) = &v.act {
                modules.apply(rx_ns, d);
            }
            let rec = CommandRecord {
                rx_mono_ns: rx_ns,
                id: f.id,
                message: name,
                data_hex: bus::candump::data_hex(f.payload()),
                e2e: v.e2e,
                secoc: v.secoc,
                decoded: v.decoded,
            };
            serde_json::to_writer(&mut log, &rec)?;
            log.write_all(b"\n")?;
        }
        receiver.expire(monotonic_ns());
        diag_sub.drain(|d| {
            if diag_modes.last().map(|m| m.1) != Some(d.mode) {
                diag_modes.push((d.timestamp_ns, d.mode));
            }
            // postcard is self-delimiting for a fixed record: the log is the records back to
            // back. A write error is reported once at the end, never aborts the judging.
            if diag_log_error.is_none() {
                // Not flushed per record (host::NoFlush): the buffer goes out when full.
                if let Err(e) = postcard::to_io(d, host::NoFlush(&mut diag_log)) {
                    diag_log_error = Some(e.to_string());
                }
            }
        });
        if let Some(t) = truth_sub.latest() {
            truth = t;
            done |= truth.is_done();
            if done && !cli.until_signal {
                break "done";
            }
        }
        if signalled {
            break if done { "done" } else { "signal" };
        }
        if !got_any {
            // Wake for the next frame, or after 4 ms to drain diagnostics (a 16-record queue,
            // 16 ms of the ECU's cycles) and see the truth's end; the arrival times come from
            // the kernel, so they do not depend on when this wakes. (Every wake-up costs: on an
            // emulated bench ≈ 0.1 ms of the host's time each.)
            sock.wait_readable(4).context("CAN wait")?;
        }
    };
    log.flush()?;
    if let Err(e) = diag_log.flush() {
        diag_log_error.get_or_insert(e.to_string());
    }
    if let Some(e) = &diag_log_error {
        eprintln!("actuator-stubs: {} incomplete: {e}", diag_path.display());
    }
    let report = build_report(
        cli,
        out,
        &scenario,
        &reference,
        &truth,
        &modules,
        &diag_modes,
        frames,
        &receiver,
        stop_reason,
    )?;
    let path = out.join("report.json");
    std::fs::write(
        &path,
        host::results::to_json_pretty(Report::SCHEMA_VERSION, &report)?,
    )
    .with_context(|| format!("writing {}", path.display()))?;
    eprintln!(
        "actuator-stubs: {} ({}), report {}",
        scenario.name,
        stop_reason,
        path.display()
    );
    Ok(())
}

#[allow(clippy::too_many_arguments)]
fn build_report(
    cli: &Cli,
    out: &std::path::Path,
    scenario: &Scenario,
    reference: &physics::reference::ReferenceRestraint,
    truth: &BenchTruth,
    modules: &Modules,
    diag_modes: &[(u64, u8)],
    frames: BTreeMap<String, u64>,
    receiver: &Receiver,
    stop_reason: &str,
) -> Result<Report> {
    let contact_ns = truth.contact_ns;
    let rel_ms = |t: u64| (contact_ns != 0).then_some((t as f64 - contact_ns as f64) * 1e-6);
    let since_start_s =
        |t: u64| (truth.start_ns != 0).then_some((t as f64 - truth.start_ns as f64) * 1e-9);
    let e2e_rejected = <bus::RejectReason as bus::VariantArray>::VARIANTS
        .iter()
        .map(|r| {
            (
                r.name().to_owned(),
                receiver.checker().stats().rejected_for(*r),
            )
        })
        .filter(|(_, n)| *n > 0)
        .collect();
    let pre = outcome::commanded(
        modules,
        if contact_ns != 0 {
            contact_ns
        } else {
            u64::MAX
        },
    );
    let mode_name = |m: u8| {
        ipc::EcuMode::from_u8(m)
            .map_or("unknown", |m| m.name())
            .to_owned()
    };
    let threat_ns = diag_modes
        .iter()
        .find(|(_, m)| *m == ipc::EcuMode::PreCrash as u8)
        .map(|(t, _)| *t);
    // The preset is the first adaptive belt command after the threat (its level may equal the
    // one already on the bus, so a level change is not the criterion).
    let preset_ns = threat_ns.and_then(|th| {
        modules
            .adaptive_belt_cmds
            .iter()
            .find(|t| **t >= th)
            .copied()
    });
    let rel_or_start_ms = |t: u64| {
        rel_ms(t)
            .or_else(|| since_start_s(t).map(|s| s * 1e3))
            .unwrap_or(0.0)
    };
    let mut report = Report {
        scenario: scenario.name.clone(),
        stop_reason: stop_reason.to_owned(),
        start_ns: truth.start_ns,
        contact_ns,
        true_crash: None,
        frames,
        e2e_accepted: receiver.e2e_accepted(),
        secoc_accepted: receiver.secoc_accepted(),
        secoc_rejected: receiver.secoc_rejected(),
        secoc_commands_dropped: receiver.secoc_commands_dropped(),
        secoc_pairing_timeout_ms: cli.secoc_pairing_timeout_ms,
        secoc_freshness_window_ms: cli.secoc_freshness_window_ms,
        e2e_rejected,
        actions: modules
            .actions
            .iter()
            .map(|a| TimedAction {
                action: a.clone(),
                t_ms: since_start_s(a.t_ns).map_or(0.0, |s| s * 1e3),
                after_contact_ms: rel_ms(a.t_ns),
            })
            .collect(),
        first_armed_ms: modules.first_armed_ns.and_then(rel_ms),
        first_reference_cmd_ms: modules.first_reference_cmd_ns.and_then(rel_ms),
        first_reference_cmd_s: modules.first_reference_cmd_ns.and_then(since_start_s),
        modes_relative_to: if contact_ns != 0 { "contact" } else { "start" }.to_owned(),
        ecu_modes: modules
            .ecu_modes
            .iter()
            .map(|(t, m)| (rel_or_start_ms(*t), ecu_mode_name(*m).to_owned()))
            .collect(),
        ecu_faults: modules
            .ecu_faults
            .iter()
            .map(|(t, f)| (rel_or_start_ms(*t), ecu_fault_names(*f)))
            .collect(),
        ecu_diag_modes: diag_modes
            .iter()
            .map(|(t, m)| (rel_or_start_ms(*t), mode_name(*m)))
            .collect(),
        threat_detected_ms: threat_ns.map(rel_or_start_ms),
        settings_preset_ms: preset_ns.map(rel_or_start_ms),
        pretensioner_before_contact: contact_ns != 0 && pre.pretensioner_s.is_some_and(|t| t < 0.0),
        pretensioner_released: modules.action("pretensioner_release").is_some(),
        airbag_fired: modules.airbag_fired,
        margin_ms: None,
        outcome: None,
        plot: None,
    };
    if contact_ns == 0 {
        return Ok(report);
    }
    let t = Truth::new(scenario).map_err(|e| anyhow::anyhow!(e))?;
    let Some(judged) = outcome::evaluate(scenario, &t, modules, contact_ns, reference)
        .map_err(|e| anyhow::anyhow!(e))?
    else {
        anyhow::bail!("bench truth reports a contact but the scenario's true physics has none");
    };
    report.margin_ms = report
        .action("airbag_fire")
        .and_then(|a| a.after_contact_ms)
        .zip(judged.true_crash.required_ms)
        .map(|(fire, required)| fire - required);
    report.true_crash = Some(judged.true_crash);
    let pulse = t.pulse.ego_pulse();
    let png = out.join("outcome.png");
    let pulse_g: Vec<f64> = pulse
        .accel_mps2
        .iter()
        .map(|a| -physics::mps2_to_g(*a))
        .collect();
    if cli.plot_later {
        let data = plot::PlotData {
            title: scenario.name.clone(),
            adaptive: judged.outcome.adaptive.clone(),
            adaptive_trace: plot::Trace::of(&judged.outcome.adaptive),
            reference: judged.outcome.reference.clone(),
            reference_trace: plot::Trace::of(&judged.outcome.reference),
            pulse_g,
            pulse_step_ms: pulse.step_s * 1e3,
        };
        let note = out.join(plot::PLOT_LATER);
        match serde_json::to_vec(&data)
            .map_err(|e| e.to_string())
            .and_then(|b| std::fs::write(&note, b).map_err(|e| e.to_string()))
        {
            Ok(()) => report.plot = Some("outcome.png".into()),
            Err(e) => eprintln!("actuator-stubs: warning: {}: {e}", note.display()),
        }
    } else {
        match plot::draw(
            &png,
            &scenario.name,
            &judged.outcome.adaptive,
            &judged.outcome.reference,
            &pulse_g,
            pulse.step_s * 1e3,
        ) {
            Ok(()) => report.plot = Some("outcome.png".into()),
            Err(e) => eprintln!("actuator-stubs: warning: {e}"),
        }
    }
    report.outcome = Some(judged.outcome);
    Ok(report)
}
