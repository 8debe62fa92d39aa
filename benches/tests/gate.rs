//! The budget gate fails when a budget is below the measured figure, passes when it is above,
//! and fails (MISSING) when a budgeted benchmark produced no result. Only cheap rows are used
//! (one frame-decode bench with `--quick`, the LUT instruction count with small N), and the
//! budgets are absurdly low or generous, so the verdicts do not depend on machine load.

use std::path::PathBuf;
use std::process::{Command, Output};

const HEADER: &str = "[gate]\nstatistic = \"median\"\ncompare = \"upper_bound\"\n";

fn budgets_file(name: &str, body: &str) -> PathBuf {
    let p = std::env::temp_dir().join(format!("cycle-benches-{name}-{}.toml", std::process::id()));
    std::fs::write(&p, format!("{HEADER}{body}")).unwrap();
    p
}

fn gate(budgets: &PathBuf, extra: &[&str]) -> (i32, String) {
    let out: Output = Command::new(env!("CARGO_BIN_EXE_budget"))
        .arg("--budgets")
        .arg(budgets)
        .args(extra)
        .output()
        .expect("run the budget gate");
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    (out.status.code().unwrap_or(-1), text)
}

fn criterion_row(id: &str, budget_us: f64) -> String {
    format!("[[criterion]]\nstage = \"frame decode\"\nbench = \"frames\"\nid = \"{id}\"\nbudget_us = {budget_us}\n")
}

fn icount_row(budget: f64) -> String {
    format!("[[icount]]\nstage = \"LUT lookup\"\nbin = \"icount-lut\"\nbudget_instructions = {budget}\niterations = [100, 300]\n")
}

/// The gate table row for `what` (criterion's own output, printed before the table, also
/// names the benchmark, so only the text after the table header is searched).
fn verdict_line<'a>(text: &'a str, what: &str) -> &'a str {
    let table = text.find("\nbudget gate (").map_or(text, |i| &text[i..]);
    table
        .lines()
        .find(|l| l.contains(what) && !l.starts_with("budget gate:"))
        .unwrap_or_else(|| panic!("no table row for {what} in:\n{text}"))
}

#[test]
fn criterion_budget_below_measured_fails_and_generous_budget_passes() {
    let id = "frames/decode_cycle_inputs";
    // 1 ps: below anything a real decode of two CAN frames can take.
    let low = budgets_file("low", &criterion_row(id, 1e-6));
    let (code, text) = gate(&low, &["--quick", "--no-icount"]);
    assert_eq!(code, 1, "{text}");
    assert!(verdict_line(&text, id).contains("FAIL"), "{text}");
    assert!(text.contains("budget gate: FAIL"), "{text}");

    // 1 s per decode: above anything a working machine measures.
    let high = budgets_file("high", &criterion_row(id, 1e6));
    let (code, text) = gate(&high, &["--quick", "--no-icount"]);
    assert_eq!(code, 0, "{text}");
    assert!(verdict_line(&text, id).contains("PASS"), "{text}");

    // A budgeted id that no bench produces is MISSING, and MISSING fails.
    let missing = budgets_file("missing", &criterion_row("frames/no_such_bench", 1e6));
    let (code, text) = gate(&missing, &["--quick", "--no-icount"]);
    assert_eq!(code, 1, "{text}");
    assert!(
        verdict_line(&text, "frames/no_such_bench").contains("MISSING"),
        "{text}"
    );

    for p in [low, high, missing] {
        let _ = std::fs::remove_file(p);
    }
}

#[test]
fn unregistered_bench_target_is_missing_not_passing() {
    let row = "[[criterion]]\nstage = \"full cycle\"\nbench = \"no_such_target\"\nid = \"x/y\"\nbudget_us = 1e6\n";
    let p = budgets_file("unregistered", row);
    let (code, text) = gate(&p, &["--quick", "--no-icount"]);
    assert_eq!(code, 1, "{text}");
    let line = verdict_line(&text, "x/y");
    assert!(
        line.contains("MISSING") && line.contains("not registered"),
        "{text}"
    );
    let _ = std::fs::remove_file(p);
}

#[test]
fn instruction_count_gate_fails_below_and_passes_above_the_measured_count() {
    if Command::new("valgrind").arg("--version").output().is_err() {
        panic!("valgrind is required for the instruction-count gate (apt-get install valgrind)");
    }
    // One lookup is hundreds of instructions (4-D multilinear interpolation of 16 corners):
    // 10 is far below, 100 000 far above.
    let low = budgets_file("icount-low", &icount_row(10.0));
    let (code, text) = gate(&low, &["--no-criterion", "--prebuilt"]);
    assert_eq!(code, 1, "{text}");
    assert!(verdict_line(&text, "icount-lut").contains("FAIL"), "{text}");

    let high = budgets_file("icount-high", &icount_row(100_000.0));
    let (code, text) = gate(&high, &["--no-criterion", "--prebuilt"]);
    assert_eq!(code, 0, "{text}");
    assert!(verdict_line(&text, "icount-lut").contains("PASS"), "{text}");
    for p in [low, high] {
        let _ = std::fs::remove_file(p);
    }
}

#[test]
fn collected_count_of_the_searched_worst_case_fails_below_and_passes_above() {
    if Command::new("valgrind").arg("--version").output().is_err() {
        panic!("valgrind is required for the instruction-count gate (apt-get install valgrind)");
    }
    // The committed seed's one measured cycle is thousands of instructions: 10 is far below,
    // 1 000 000 far above. The seed path is relative to the budgets file's folder, so the row
    // names it absolutely here (the temporary file lives elsewhere).
    let seed = concat!(env!("CARGO_MANIFEST_DIR"), "/worst-case/seed.json");
    let row = |budget: f64| {
        format!(
            "[[icount]]\nstage = \"searched\"\nbin = \"worst-cycle\"\ncollect = \"cycle_benches::worst_case::measured_step\"\nargs = [\"eval\", \"{seed}\"]\nbudget_instructions = {budget}\n"
        )
    };
    let low = budgets_file("collect-low", &row(10.0));
    let (code, text) = gate(&low, &["--no-criterion", "--prebuilt"]);
    assert_eq!(code, 1, "{text}");
    assert!(
        verdict_line(&text, "worst-cycle").contains("FAIL"),
        "{text}"
    );
    let high = budgets_file("collect-high", &row(1e6));
    let (code, text) = gate(&high, &["--no-criterion", "--prebuilt"]);
    assert_eq!(code, 0, "{text}");
    let line = verdict_line(&text, "worst-cycle");
    assert!(
        line.contains("PASS") && line.contains("max of 1 call"),
        "{text}"
    );
    // A function that is never called is MISSING, not a pass with 0 instructions.
    let wrong = budgets_file(
        "collect-wrong",
        &row(1e6).replace("measured_step", "no_such_function"),
    );
    let (code, text) = gate(&wrong, &["--no-criterion", "--prebuilt"]);
    assert_eq!(code, 1, "{text}");
    assert!(
        verdict_line(&text, "worst-cycle").contains("MISSING"),
        "{text}"
    );
    for p in [low, high, wrong] {
        let _ = std::fs::remove_file(p);
    }
}

#[test]
fn a_prebuilt_binary_that_is_not_there_is_missing_not_passing() {
    let row = "[[icount]]\nstage = \"absent\"\nbin = \"icount_no_such_bin\"\nbudget_instructions = 1e6\niterations = [1, 2]\n";
    let p = budgets_file("prebuilt-absent", row);
    let (code, text) = gate(&p, &["--no-criterion", "--prebuilt"]);
    assert_eq!(code, 1, "{text}");
    let line = verdict_line(&text, "icount_no_such_bin");
    assert!(
        line.contains("MISSING") && line.contains("--prebuilt: no"),
        "{text}"
    );
    let _ = std::fs::remove_file(p);
}
