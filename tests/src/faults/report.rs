//! The robustness report: the campaign's figures, the fuzzing figures, the verdict last.

use super::{Campaign, FuzzTarget};
use std::collections::BTreeMap;
use std::fmt::Write as _;

/// The robustness report: the campaign's figures and the fuzzing figures.
pub fn report_text(c: &Campaign, fuzz: Option<&[FuzzTarget]>) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "=== robustness report ===");
    let _ = writeln!(
        s,
        "fault campaign on vcan, route {}: {}{}",
        c.route.name(),
        c.route.describe(),
        if c.conditions.is_empty() {
            String::new()
        } else {
            format!(" ({})", c.conditions)
        }
    );
    for a in &c.allowances {
        let _ = writeln!(s, "  allowance: {a}");
    }
    let _ = writeln!(
        s,
        "  {:<14} {:<5} {:>6} {:>7} {:>6} {:>8} {:>9}  reaction",
        "case", "", "sent", "lost", "inj", "overrun", "late ms"
    );
    for r in &c.cases {
        let _ = writeln!(
            s,
            "  {:<14} {:<5} {:>6} {:>7} {:>6} {:>8} {:>9}  {}{}",
            r.name,
            if r.pass { "PASS" } else { "FAIL" },
            r.commands_sent,
            match (r.commands_denied_by_attack, r.commands_late) {
                (0, 0) => r.commands_lost.to_string(),
                (a, 0) => format!("{}({a}a)", r.commands_lost),
                (0, l) => format!("{}({l}L)", r.commands_lost),
                (a, l) => format!("{}({a}a,{l}L)", r.commands_lost),
            },
            r.frames_injected,
            r.overruns,
            r.airbag_late_ms
                .map_or("—".to_owned(), |l| format!("{l:+.1}")),
            r.reaction,
            if r.attempts > 1 {
                format!(" (run {}: the earlier missed a time limit)", r.attempts)
            } else {
                String::new()
            }
        );
        for ch in r.checks.iter().filter(|c| !c.ok) {
            let _ = writeln!(s, "      FAILED: {}: {}", ch.what, ch.detail);
        }
        for e in &r.earlier_runs {
            let _ = writeln!(s, "      time limit missed in {e}");
        }
    }
    let tried = c.cases.len();
    let faults = c.cases.iter().filter(|r| r.name != "baseline").count();
    let survived = c
        .cases
        .iter()
        .filter(|r| r.name != "baseline" && r.pass)
        .count();
    let mut by_reason: BTreeMap<&str, u64> = BTreeMap::new();
    for r in &c.cases {
        for (k, n) in &r.frames_rejected {
            *by_reason.entry(k).or_default() += n;
        }
    }
    let lost: u64 = c
        .cases
        .iter()
        .map(|r| r.commands_lost - r.commands_denied_by_attack)
        .sum();
    let denied: u64 = c.cases.iter().map(|r| r.commands_denied_by_attack).sum();
    let late: u64 = c.cases.iter().map(|r| r.commands_late).sum();
    let base_overruns = c
        .cases
        .iter()
        .find(|r| r.name == "baseline")
        .map_or(0, |r| r.overruns);
    let extra_overruns: u64 = c
        .cases
        .iter()
        .filter(|r| r.name != "baseline")
        .map(|r| r.overruns.saturating_sub(base_overruns))
        .sum();
    let _ = writeln!(
        s,
        "\ncases tried        {tried} ({faults} faults + baseline)"
    );
    let _ = writeln!(s, "faults survived    {survived} of {faults}");
    let _ = writeln!(
        s,
        "commands lost      {lost}   (genuine commands not acted on, attacks excluded)"
    );
    let _ = writeln!(s, "denied by attack   {denied}   (genuine frames displaced by attacker frames; resent next cycle)");
    let _ = writeln!(
        s,
        "arrived late       {late}   (genuine commands refused as stale: delivered after the freshness window or the pairing timeout; counted as lost)"
    );
    let _ = writeln!(
        s,
        "deadline misses    {extra_overruns} beyond the baseline's {base_overruns} (sum over fault cases){}",
        if c.route.timing_emulated() {
            " — emulated timers, not a real-time figure"
        } else {
            ""
        }
    );
    let _ = writeln!(s, "frames rejected by reason:");
    for (k, n) in &by_reason {
        let _ = writeln!(s, "  {k:<40} {n}");
    }
    match fuzz {
        Some(f) => {
            let execs: u64 = f.iter().map(|t| t.execs).sum();
            let ms: u64 = f.iter().map(|t| t.time_ms).sum();
            let _ = writeln!(
                s,
                "inputs fuzzed      {execs} in {:.1} s over {} targets ({} clean)",
                ms as f64 / 1e3,
                f.len(),
                f.iter().filter(|t| t.ok).count()
            );
            for t in f {
                let _ = writeln!(
                    s,
                    "  {:<16} {:>10} execs {:>6.1} s {}",
                    t.target,
                    t.execs,
                    t.time_ms as f64 / 1e3,
                    if t.ok { "clean" } else { "FAILED" }
                );
            }
        }
        None => {
            let _ = writeln!(
                s,
                "inputs fuzzed      (no fuzz figures given: tests/fuzz-smoke.sh writes them)"
            );
        }
    }
    // The verdict last, where a truncated log still shows it.
    let failed: Vec<String> = c
        .cases
        .iter()
        .filter(|r| !r.pass)
        .map(|r| {
            let what: Vec<&str> = r
                .checks
                .iter()
                .filter(|k| !k.ok)
                .map(|k| k.what.as_str())
                .collect();
            format!("{} ({})", r.name, what.join("; "))
        })
        .collect();
    let _ = writeln!(
        s,
        "verdict            {}",
        if failed.is_empty() {
            "every case passed".to_owned()
        } else {
            format!("FAILED: {}", failed.join(", "))
        }
    );
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::faults::{CaseResult, Check};

    fn case(name: &str, pass: bool) -> CaseResult {
        CaseResult {
            name: name.into(),
            pass,
            commands_sent: 900,
            commands_authenticated: 900,
            ..CaseResult::default()
        }
    }

    #[test]
    fn the_report_ends_with_the_verdict_and_shows_earlier_runs() {
        let mut flood = case("cangen-flood", true);
        flood.attempts = 2;
        flood.earlier_runs = vec!["run 1: fire command on time: received +31.0 ms".into()];
        let mut bad = case("can-crc", false);
        bad.checks = vec![
            Check {
                what: "ECU report written".into(),
                ok: true,
                detail: String::new(),
                timing: false,
            },
            Check {
                what: "recovers after the fault".into(),
                ok: false,
                detail: "never recovered".into(),
                timing: true,
            },
        ];
        let c = Campaign {
            route: crate::Route::QemuTcg,
            allowances: crate::Route::QemuTcg.allowances().named(),
            conditions: "host load 0.50 at the start, QEMU at SCHED_RR 5".into(),
            cases: vec![case("baseline", true), flood, bad],
        };
        let text = report_text(&c, None);
        assert!(text.contains("route qemu-tcg"), "{text}");
        assert!(text.contains("host load 0.50"), "{text}");
        assert!(text.contains("allowance: "), "{text}");
        assert!(
            text.contains("time limit missed in run 1: fire command on time"),
            "{text}"
        );
        assert!(text.contains("faults survived    1 of 2"), "{text}");
        let last = text.lines().last().unwrap_or("");
        assert_eq!(
            last,
            "verdict            FAILED: can-crc (recovers after the fault)"
        );
        let ok = Campaign {
            cases: vec![case("baseline", true)],
            ..Campaign::default()
        };
        assert!(report_text(&ok, None).ends_with("verdict            every case passed\n"));
    }
}
