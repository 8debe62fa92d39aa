//! `hil-bench --replay`: a replayed run judged against the run it replays — the same restraint
//! actions (kind, source, level) within one ECU cycle of their recorded times after the
//! contact, and the ECU's modes in the same order. Both sides are the stubs' reports
//! (`report.json`; the recording's is its `/stubs/verdict` with its `/stubs/actions`).

use serde_json::Value;

/// How far apart a replayed time may be from the recorded one, ms: one ECU cycle — a fire is
/// decided in the cycle that reads the deciding sample, and the cycle's phase against the
/// feeds' ticks is a new one in every run — plus the delivery jitter of the two runs' frames
/// (the stubs stamp a command on arrival: 0.01–0.2 ms apart on the emulated route). A replay
/// of the demo's run measured +0.01, −0.27, +0.73 and +1.00 ms.
pub const TOLERANCE_MS: f64 = 1.25;

/// What the replay did against the recording.
#[derive(Debug, Clone, PartialEq)]
pub struct Comparison {
    /// One line per action and for the modes, each saying what was recorded and replayed.
    pub lines: Vec<String>,
    /// The differences (empty: the replay is the recorded run within the tolerance).
    pub differences: Vec<String>,
}

/// The restraint actions of a report: (what, source, level, ms after the contact).
fn actions(report: &Value) -> Vec<(String, String, f64, Option<f64>)> {
    report["actions"]
        .as_array()
        .map(Vec::as_slice)
        .unwrap_or(&[])
        .iter()
        .map(|a| {
            (
                a["what"].as_str().unwrap_or("?").to_owned(),
                a["source"].as_str().unwrap_or("").to_owned(),
                a["level_kn"].as_f64().unwrap_or(f64::NAN),
                a["after_contact_ms"].as_f64(),
            )
        })
        .collect()
}

/// The ECU's diagnostic modes in order (names only: their times before the contact include
/// the processes' start, which no replay repeats).
fn modes(report: &Value) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    for m in report["ecu_diag_modes"]
        .as_array()
        .map(Vec::as_slice)
        .unwrap_or(&[])
    {
        if let Some(name) = m.get(1).and_then(Value::as_str) {
            if out.last().map(String::as_str) != Some(name) {
                out.push(name.to_owned());
            }
        }
    }
    out
}

fn at(ms: Option<f64>) -> String {
    ms.map_or("—".to_owned(), |t| format!("{t:+.1} ms"))
}

/// Compares the `replayed` report with the `recorded` one.
pub fn compare(recorded: &Value, replayed: &Value) -> Comparison {
    let (mut lines, mut differences) = (Vec::new(), Vec::new());
    let (rec, rep) = (actions(recorded), actions(replayed));
    for k in 0..rec.len().max(rep.len()) {
        match (rec.get(k), rep.get(k)) {
            (Some(a), Some(b)) => {
                let dt = match (a.3, b.3) {
                    (Some(x), Some(y)) => Some(y - x),
                    _ => None,
                };
                lines.push(format!(
                    "{:<22} recorded {:>10}  replayed {:>10}  ({})",
                    a.0,
                    at(a.3),
                    at(b.3),
                    dt.map_or("no contact".to_owned(), |d| format!("{d:+.2} ms"))
                ));
                if a.0 != b.0 || a.1 != b.1 {
                    differences.push(format!(
                        "action {}: recorded {} ({}), replayed {} ({})",
                        k + 1,
                        a.0,
                        a.1,
                        b.0,
                        b.1
                    ));
                } else if (a.2 - b.2).abs() > 1e-6 {
                    differences.push(format!(
                        "{}: level recorded {} kN, replayed {} kN",
                        a.0, a.2, b.2
                    ));
                } else if dt.is_some_and(|d| d.abs() > TOLERANCE_MS)
                    || a.3.is_some() != b.3.is_some()
                {
                    differences.push(format!(
                        "{}: recorded {}, replayed {} — more than {TOLERANCE_MS} ms apart",
                        a.0,
                        at(a.3),
                        at(b.3)
                    ));
                }
            }
            (Some(a), None) => {
                lines.push(format!("{:<22} recorded {:>10}  replayed —", a.0, at(a.3)));
                differences.push(format!("{} at {}: not in the replay", a.0, at(a.3)));
            }
            (None, Some(b)) => {
                lines.push(format!("{:<22} recorded —  replayed {:>10}", b.0, at(b.3)));
                differences.push(format!("{} at {}: only in the replay", b.0, at(b.3)));
            }
            (None, None) => {}
        }
    }
    let (mr, mp) = (modes(recorded), modes(replayed));
    lines.push(format!("modes recorded: {}", mr.join(" → ")));
    if mr == mp {
        lines.push("modes replayed: the same".to_owned());
    } else {
        lines.push(format!("modes replayed: {}", mp.join(" → ")));
        differences.push(format!(
            "modes: recorded {}, replayed {}",
            mr.join(" → "),
            mp.join(" → ")
        ));
    }
    Comparison { lines, differences }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn report(airbag_ms: f64, modes: &[&str]) -> Value {
        json!({
            "actions": [
                {"what": "pretensioner_fire", "source": "adaptive", "level_kn": 10.8, "after_contact_ms": -97.5},
                {"what": "airbag_fire", "source": "adaptive", "level_kn": 3.4, "after_contact_ms": airbag_ms},
            ],
            "ecu_diag_modes": modes.iter().enumerate().map(|(i, m)| json!([i as f64, m])).collect::<Vec<_>>(),
        })
    }

    const MODES: [&str; 4] = ["degraded", "monitoring", "pre-crash", "post-crash"];

    #[test]
    fn a_replay_within_one_cycle_and_the_same_modes_is_no_difference() {
        let c = compare(&report(7.6, &MODES), &report(8.5, &MODES));
        assert!(c.differences.is_empty(), "{c:?}");
        assert!(c.lines.iter().any(|l| l.contains("+0.90 ms")), "{c:?}");
    }

    #[test]
    fn a_later_fire_a_missing_action_or_other_modes_are_differences() {
        let c = compare(&report(7.6, &MODES), &report(8.9, &MODES));
        assert_eq!(c.differences.len(), 1, "{c:?}");
        assert!(c.differences[0].contains("airbag_fire"), "{c:?}");
        let mut fewer = report(7.6, &MODES);
        fewer["actions"].as_array_mut().expect("actions").pop();
        let c = compare(&report(7.6, &MODES), &fewer);
        assert!(c.differences[0].contains("not in the replay"), "{c:?}");
        let c = compare(
            &report(7.6, &MODES),
            &report(7.6, &["degraded", "monitoring", "crash", "post-crash"]),
        );
        assert!(c.differences[0].starts_with("modes"), "{c:?}");
        let mut other = report(7.6, &MODES);
        other["actions"][1]["source"] = json!("reference");
        assert_eq!(compare(&report(7.6, &MODES), &other).differences.len(), 1);
    }
}
