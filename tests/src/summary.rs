//! The readable summary of one run (what `hil-bench` and the demo print).

use super::*;
use actuator_stubs::report::Report;
use std::fmt::Write as _;
use std::path::Path;

fn ms(v: Option<f64>) -> String {
    v.map_or_else(|| "—".to_owned(), |x| format!("{x:+8.1} ms"))
}

/// The readable summary of one run (`clock_offset_ns`: the run's CLOCK_REALTIME −
/// CLOCK_MONOTONIC offset, asked only for a run with a contact).
pub fn summarise(
    scenario: &world::Scenario,
    r: &Report,
    ecu: Option<&serde_json::Value>,
    dir: &Path,
    clock_offset_ns: &dyn Fn() -> Option<i64>,
    problems: &[String],
) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "=== {} ===", r.scenario);
    let _ = writeln!(s, "{}", scenario.description);
    let route = Route::current();
    let _ = writeln!(
        s,
        "route: {} — {}",
        route.name(),
        route.describe_with_load()
    );
    match &r.true_crash {
        Some(c) => {
            let _ = writeln!(
                s,
                "true crash: closing {:.1} km/h, ego Δv {:.1} km/h, compartment a_max {:.1} g, a_mean {:.1} g, crush {:.0} mm; airbag required by {} (127 mm − 30 ms)",
                c.closing_speed_kph, c.delta_v_kph, c.a_max_g, c.a_mean_g, c.crush_mm,
                c.required_ms.map_or("—".to_owned(), |t| format!("{t:+.1} ms"))
            );
        }
        None => {
            let _ = writeln!(s, "true crash: none (no contact)");
        }
    }
    let _ = writeln!(s, "\ntimeline (ms relative to TRUE contact):");
    let _ = writeln!(
        s,
        "  threat detected (ECU pre-crash)                  {}",
        ms(r.threat_detected_ms)
    );
    let _ = writeln!(
        s,
        "  settings preset (limiter level sent)             {}",
        ms(r.settings_preset_ms)
    );
    if let Some(a) = r.action("pretensioner_fire") {
        let _ = writeln!(
            s,
            "  pretensioner fire                                {}  (planned {:+.1} ms, limiter {:.2} kN, {})",
            ms(a.after_contact_ms),
            a.action.planned_ms,
            a.action.level_kn,
            a.action.source
        );
    } else {
        let _ = writeln!(
            s,
            "  pretensioner fire                                {}",
            ms(None)
        );
    }
    if r.contact_ns != 0 {
        // On candump's clock too (its `-L` stamps are CLOCK_REALTIME), to find the contact in
        // the bus log: the bench's monotonic time plus the offset the recordings measure.
        let stamp = clock_offset_ns()
            .and_then(|o| r.contact_ns.checked_add_signed(o))
            .map_or_else(String::new, |t| {
                format!(
                    "  (candump -L stamp ({}.{:06}))",
                    t / 1_000_000_000,
                    t % 1_000_000_000 / 1_000
                )
            });
        let _ = writeln!(
            s,
            "  contact                                          {}{stamp}",
            ms(Some(0.0))
        );
    } else {
        let _ = writeln!(s, "  contact                                          none");
    }
    if let Some(a) = r.action("airbag_fire") {
        let _ = writeln!(
            s,
            "  airbag fire                                      {}  (planned {:+.1} ms, level {:.2} kN, {})",
            ms(a.after_contact_ms),
            a.action.planned_ms,
            a.action.level_kn,
            a.action.source
        );
        if let Some(t) = a.after_contact_ms {
            let _ = writeln!(
                s,
                "  command latency: airbag command received {:+.1} ms after its planned time",
                t - a.action.planned_ms
            );
        }
        if let Some(m) = r.margin_ms {
            let _ = writeln!(
                s,
                "  airbag fire − required (127 mm − 30 ms)          {}  ({})",
                ms(Some(m)),
                if m <= 0.0 { "in time" } else { "LATE" }
            );
        }
    } else {
        let _ = writeln!(
            s,
            "  airbag fire                                      {}",
            ms(None)
        );
    }
    if let Some(a) = r.action("pretensioner_release") {
        let _ = writeln!(
            s,
            "  pretensioner release                             {}",
            ms(a.after_contact_ms)
        );
    }
    if r.first_reference_cmd_s.is_some() {
        let _ = writeln!(
            s,
            "  first reference-restraint command (fallback)     {}  ({:.3} s after start)",
            ms(r.first_reference_cmd_ms),
            r.first_reference_cmd_s.unwrap_or(0.0)
        );
    }
    if !r.ecu_diag_modes.is_empty() {
        let modes: Vec<String> = r
            .ecu_diag_modes
            .iter()
            .map(|(t, m)| format!("{m}@{t:+.0}"))
            .collect();
        let _ = writeln!(s, "  ECU modes (diagnostics): {}", modes.join(" → "));
    }
    if !r.ecu_modes.is_empty() {
        let modes: Vec<String> = r
            .ecu_modes
            .iter()
            .map(|(t, m)| format!("{m}@{t:+.0}"))
            .collect();
        let _ = writeln!(s, "  ECU modes (EcuStatus): {}", modes.join(" → "));
    }
    if !r.ecu_faults.is_empty() {
        let faults: Vec<String> = r
            .ecu_faults
            .iter()
            .map(|(t, f)| {
                if f.is_empty() {
                    format!("none@{t:+.0}")
                } else {
                    format!("{}@{t:+.0}", f.join("+"))
                }
            })
            .collect();
        let _ = writeln!(s, "  ECU faults (EcuStatus): {}", faults.join(" → "));
    }
    // Which opponent mass the ECU's plans were for, from its counters.
    let counter = |k: &str| crate::ecu_counter(ecu, k);
    if let (Some(lookups @ 1..), Some(v2x)) = (counter("lut_lookups"), counter("v2x_lookups")) {
        let _ = writeln!(
            s,
            "  planning mass: {v2x} of {lookups} table lookups with the V2X station as the second \
             mass source (the heavier source + v2x_mass_margin_kg), {} with the object list + \
             mass_misreport_kg",
            lookups.saturating_sub(v2x)
        );
    }
    let frames: Vec<String> = r.frames.iter().map(|(k, v)| format!("{k} {v}")).collect();
    let _ = writeln!(
        s,
        "bus: {} | E2E accepted {}, rejected {:?}",
        frames.join(", "),
        r.e2e_accepted,
        r.e2e_rejected
    );
    let _ = writeln!(
        s,
        "SecOC: {} commands authenticated (ECU sent {}), rejected {:?}, unpaired {}; pairing timeout {} ms, freshness window {} ms",
        r.secoc_accepted,
        counter("secoc_commands_tx").map_or("?".to_owned(), |n| n.to_string()),
        r.secoc_rejected,
        r.secoc_commands_dropped,
        r.secoc_pairing_timeout_ms,
        r.secoc_freshness_window_ms
    );
    if let Some(o) = &r.outcome {
        let _ = writeln!(
            s,
            "\noccupant ({} kg, {} mm, {}):",
            scenario.occupant.mass_kg,
            scenario.occupant.chest_to_wheel_mm,
            if scenario.occupant.belted {
                "belted"
            } else {
                "UNBELTED"
            }
        );
        let _ = writeln!(
            s,
            "  {:<22} {:>8} {:>8} {:>11} {:>9} {:>8} {:>8}",
            "", "a_max g", "a_mean g", "excursion", "limiter", "airbag", "fire ms"
        );
        let mut rows = vec![("adaptive (commanded)", &o.adaptive)];
        if let Some(p) = &o.adaptive_planned {
            rows.push(("adaptive (at plan time)", p));
        }
        rows.push(("reference restraint", &o.reference));
        for (name, j) in rows {
            let _ = writeln!(
                s,
                "  {:<22} {:>8.1} {:>8.1} {:>8.0} mm{} {:>6.2} kN {:>5.2} kN {:>8}",
                name,
                j.a_max_g,
                j.a_mean_g,
                j.excursion_mm,
                if j.bottomed_out { "!" } else { " " },
                j.load_limiter_kn,
                j.airbag_level_kn,
                j.airbag_ms.map_or("—".to_owned(), |t| format!("{t:.1}"))
            );
        }
        let _ = writeln!(
            s,
            "  {:<22} {:>8.1}   (constant-force bound a*, ride-down {:.0} mm)",
            "ideal", o.ideal_g, o.adaptive.available_mm
        );
        let _ = writeln!(
            s,
            "  adaptive vs reference: {:+.1} % on a_max + a_mean → {}{}",
            o.change_pct,
            if o.adaptive_no_worse {
                "no worse"
            } else {
                "WORSE"
            },
            if o.adaptive.bottomed_out {
                " (adaptive BOTTOMED OUT)"
            } else {
                ""
            }
        );
    }
    if let Some(e) = ecu {
        let p = |k: &str, q: &str| {
            e.get(k)
                .and_then(|v| v.get(q))
                .and_then(|v| v.as_f64())
                .unwrap_or(f64::NAN)
        };
        let _ = writeln!(
            s,
            "\nECU timing: {} cycles, {} overruns; wake latency p50 {:.0} / p99 {:.0} / max {:.0} µs; exec p50 {:.1} / p99 {:.1} / max {:.1} µs; activity {}",
            e.get("cycles").and_then(|v| v.as_u64()).unwrap_or(0),
            e.get("overruns").and_then(|v| v.as_u64()).unwrap_or(0),
            p("wake_latency_us", "p50"),
            p("wake_latency_us", "p99"),
            p("wake_latency_us", "max"),
            p("exec_us", "p50"),
            p("exec_us", "p99"),
            p("exec_us", "max"),
            e.get("activity").and_then(|v| v.as_str()).unwrap_or("?")
        );
        let rt = |k: &str| {
            e.pointer(&format!("/rt/{k}/detail"))
                .and_then(|v| v.as_str())
                .unwrap_or("?")
                .to_owned()
        };
        let _ = writeln!(
            s,
            "  real-time settings: {}; {}",
            rt("sched"),
            rt("mlockall")
        );
        if let Some(config) = e.get("config").and_then(|c| c.as_str()) {
            let changed = not_the_defaults(config);
            let _ = writeln!(
                s,
                "  configuration: {} ({})",
                record::ECU_CONFIG,
                if changed.is_empty() {
                    "every setting its default".to_owned()
                } else {
                    format!("not the defaults: {}", changed.join(", "))
                }
            );
        }
        let route = Route::current();
        if route.timing_emulated() {
            let _ = writeln!(s, "  (route {}: {} — these timings describe the emulator; measure on the host: README, Timing)", route.name(), route.describe());
        }
    } else {
        let _ = writeln!(s, "\nECU timing: no ecu-report.json");
    }
    for p in problems {
        let _ = writeln!(s, "PROBLEM: {p}");
    }
    let _ = writeln!(s, "output: {}", dir.display());
    s
}

/// The settings of `ecu --show-config`'s TOML that a layer other than the defaults set, as
/// `table.key = value (layer)`: each value line ends in `# <layer>`, `# defaults` for a default;
/// settings no layer set are comment lines.
pub fn not_the_defaults(config: &str) -> Vec<String> {
    let mut table = String::new();
    let mut out = Vec::new();
    for line in config.lines().map(str::trim) {
        if let Some(name) = line.strip_prefix('[').and_then(|l| l.strip_suffix(']')) {
            table = name.to_owned();
            continue;
        }
        if line.starts_with('#') {
            continue;
        }
        let Some((setting, layer)) = line.rsplit_once("  # ") else {
            continue;
        };
        if layer == "defaults" {
            continue;
        }
        let key = if table.is_empty() {
            setting.to_owned()
        } else {
            format!("{table}.{setting}")
        };
        out.push(format!("{key} ({layer})"));
    }
    out
}

#[cfg(test)]
mod config_tests {
    use super::not_the_defaults;

    #[test]
    fn only_settings_a_layer_set_are_listed_with_their_table() {
        let config = "# cycles = (not set)\nperiod_us = 500  # command line\n\n[rt]\nmlockall = false  # defaults\n\n[can]\ninterface = \"vcan1\"  # environment variable ECU_CAN__INTERFACE\n[cycle.track]\ngate_chi2 = 11.3  # config file\n";
        assert_eq!(
            not_the_defaults(config),
            [
                "period_us = 500 (command line)",
                "can.interface = \"vcan1\" (environment variable ECU_CAN__INTERFACE)",
                "cycle.track.gate_chi2 = 11.3 (config file)",
            ]
        );
    }
}
