//! `ecu monitor`: live view of the ECU diagnostics service.

use std::io::Write;
use std::time::Duration;

use ipc::{Degraded, DiagnosticsSubscriber, EcuDiagnostics, EcuMode, ServiceNames};

use super::cli::MonitorArgs;
use super::config::Layers;

/// Names of the set bits of a degraded-reason word.
pub fn degraded_names(bits: u32) -> String {
    const NAMES: [(Degraded, &str); 9] = [
        (Degraded::OBJECT_STALE, "object-stale"),
        (Degraded::OBJECT_INVALID, "object-invalid"),
        (Degraded::ACCEL_STALE, "accel-stale"),
        (Degraded::ACCEL_INVALID, "accel-invalid"),
        (Degraded::CAN_STALE, "can-stale"),
        (Degraded::E2E_FAILURE, "e2e"),
        (Degraded::LUT_INVALID, "lut-invalid"),
        (Degraded::CAN_DISABLED, "can-off"),
        (Degraded::IPC_ERROR, "ipc-error"),
    ];
    let v: Vec<&str> = NAMES
        .iter()
        .filter(|(b, _)| bits & b.bits() != 0)
        .map(|(_, n)| *n)
        .collect();
    if v.is_empty() {
        "-".into()
    } else {
        v.join(",")
    }
}

/// The track filter's estimate with its σ (`-` without a track).
pub fn format_estimate(d: &EcuDiagnostics) -> String {
    if !d.time_to_contact_s.is_finite() {
        return "ttc - v - m -".to_owned();
    }
    format!(
        "ttc {:.3}±{:.3} s v {:.1}±{:.1} m/s m {:.0}±{:.0} kg",
        d.time_to_contact_s,
        d.time_to_contact_sigma_s,
        d.closing_speed_mps,
        d.closing_speed_sigma_mps,
        d.opponent_mass_kg,
        d.opponent_mass_sigma_kg,
    )
}

/// The mode as `EcuStatus` names it on the bus (the DBC's value table), with the decision's
/// finer phase in brackets: `Normal (pre-crash)`, `ReferenceFallback (degraded)`.
pub fn mode_label(d: &EcuDiagnostics) -> String {
    match EcuMode::from_u8(d.mode) {
        Some(m) => {
            let on_bus = u8::from(restraint::bus_mode(m, d.airbag_fired != 0));
            let bus_name =
                bus::value_name(bus::EcuStatus::ECU_MODE_VALUES, i64::from(on_bus)).unwrap_or("?");
            format!("{bus_name} ({})", m.name())
        }
        None => format!("unknown ({})", d.mode),
    }
}

/// One status line for a diagnostics record.
pub fn format_line(d: &EcuDiagnostics, rx_rate_hz: f64) -> String {
    format!(
        "cycle {:>9} {:>7.0} Hz | mode {:<30} | {} | Δv {:>5.1} m/s a_max {:>6.1} m/s² | belt {:>5.2} kN pt {:>+6.1} ms bag st{} {:>+6.1} ms | wake {:>6.1} µs exec {:>6.1} µs overruns {} | obj#{} acc#{} | degraded {}",
        d.cycle_count,
        rx_rate_hz,
        mode_label(d),
        format_estimate(d),
        d.predicted_delta_v_mps,
        d.predicted_a_max_mps2,
        // kN and ms, as the rest of the bench says them.
        d.belt_force_limit_n / 1e3,
        d.pretensioner_time_s * 1e3,
        d.airbag_stage,
        d.airbag_time_s * 1e3,
        d.wake_latency_ns as f64 / 1e3,
        d.last_exec_ns as f64 / 1e3,
        d.overrun_count,
        d.last_object_sequence,
        d.last_accel_sequence,
        degraded_names(d.degraded_reasons),
    )
}

/// Runs the monitor until Ctrl-C (iceoryx2's node handles SIGINT/SIGTERM here) or
/// `--count` refreshes.
pub fn run(args: &MonitorArgs) -> anyhow::Result<()> {
    // The same layers as the ECU (defaults ← file ← ECU_* ← flags): a monitor started beside
    // an ECU with the same file and environment watches that ECU's services.
    let prefix = Layers::new(args.config.as_deref(), args.clone())?
        .extract()?
        .ipc
        .service_prefix;
    anyhow::ensure!(
        args.rate_hz.is_finite() && args.rate_hz > 0.0 && args.rate_hz <= 1_000.0,
        "--rate-hz must be in (0, 1000]"
    );
    let names = ServiceNames::with_prefix(&prefix);
    let node_name = format!("ecu-monitor-{}", std::process::id());
    let (node, _) = ipc::create_node(&node_name, true)?;
    let mut sub = DiagnosticsSubscriber::new(&node, &names)?;
    let period = Duration::from_secs_f64(1.0 / args.rate_hz);
    eprintln!("monitoring {} (Ctrl-C to exit)", names.diagnostics);
    let mut refreshes = 0u64;
    let mut last_cycle: Option<u64> = None;
    let mut out = std::io::stdout();
    while node.wait(period).is_ok() {
        let latest = sub.latest();
        let line = match latest {
            Some(d) => {
                let rate = last_cycle.map_or(0.0, |c| {
                    d.cycle_count.saturating_sub(c) as f64 * args.rate_hz
                });
                last_cycle = Some(d.cycle_count);
                format_line(&d, rate)
            }
            None => "waiting for ECU diagnostics …".to_owned(),
        };
        if args.lines {
            writeln!(out, "{line}")?;
        } else {
            write!(out, "\r\x1b[2K{line}")?;
        }
        out.flush()?;
        refreshes += 1;
        if args.count.is_some_and(|c| refreshes >= c) {
            break;
        }
    }
    if !args.lines {
        writeln!(out)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn degraded_bits_are_named() {
        assert_eq!(degraded_names(0), "-");
        assert_eq!(
            degraded_names((Degraded::OBJECT_STALE | Degraded::CAN_DISABLED).bits()),
            "object-stale,can-off"
        );
    }

    #[test]
    fn line_shows_mode_and_timing() {
        let mut d = EcuDiagnostics::ZERO;
        d.mode = EcuMode::PreCrash as u8;
        d.wake_latency_ns = 12_300;
        d.overrun_count = 4;
        let l = format_line(&d, 1000.0);
        assert!(l.contains("ttc - v - m -"), "{l}");
        d.time_to_contact_s = 0.25;
        d.time_to_contact_sigma_s = 0.004;
        d.closing_speed_mps = 25.0;
        d.closing_speed_sigma_mps = 0.12;
        d.opponent_mass_kg = 1512.0;
        d.opponent_mass_sigma_kg = 212.0;
        let l = format_line(&d, 1000.0);
        assert!(
            l.contains("ttc 0.250±0.004 s v 25.0±0.1 m/s m 1512±212 kg"),
            "{l}"
        );
        assert!(l.contains("mode Normal (pre-crash)"), "{l}");
        assert!(l.contains("wake   12.3 µs"), "{l}");
        assert!(l.contains("overruns 4"), "{l}");
        d.belt_force_limit_n = 8967.0;
        d.pretensioner_time_s = 0.010;
        d.airbag_stage = 2;
        d.airbag_time_s = -0.0123;
        let l = format_line(&d, 1000.0);
        assert!(
            l.contains("belt  8.97 kN pt  +10.0 ms bag st2  -12.3 ms"),
            "{l}"
        );
    }

    /// The bus's names (bus/restraint.dbc, `VAL_ 272 EcuMode`) for every diagnostics mode,
    /// the phase in brackets (else the monitor says `degraded` where the bus says
    /// `ReferenceFallback`).
    #[test]
    fn modes_are_named_as_on_the_bus() {
        let cases = [
            (EcuMode::Startup, false, "Init (startup)"),
            (EcuMode::Monitoring, false, "Normal (monitoring)"),
            (EcuMode::PreCrash, false, "Normal (pre-crash)"),
            (EcuMode::Degraded, false, "ReferenceFallback (degraded)"),
            (EcuMode::Crash, false, "CrashDetected (crash)"),
            (EcuMode::Crash, true, "Deployed (crash)"),
            (EcuMode::PostCrash, true, "Deployed (post-crash)"),
        ];
        for (mode, fired, want) in cases {
            let mut d = EcuDiagnostics::ZERO;
            d.mode = mode as u8;
            d.airbag_fired = u8::from(fired);
            assert_eq!(mode_label(&d), want);
        }
        let mut d = EcuDiagnostics::ZERO;
        d.mode = 200;
        assert_eq!(mode_label(&d), "unknown (200)");
    }
}
