//! `cycle-timing`'s contract: one row per full-cycle row of the budget (the hand-picked path
//! and the three searched seeds), each with its percentiles in order and its ratio to the
//! reference, and the reference itself — whatever the clock reads.

use std::process::Command;

#[test]
fn cycle_timing_reports_every_full_cycle_row_beside_the_reference() {
    let dir = std::env::temp_dir().join(format!("cycle-timing-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let json = dir.join("timing.json");
    let out = Command::new(env!("CARGO_BIN_EXE_cycle-timing"))
        .args(["--rounds", "300", "--json"])
        .arg(&json)
        .output()
        .expect("cycle-timing runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).expect("json written")).expect("json");
    assert_eq!(doc["schema_version"], 1);
    assert_eq!(doc["rounds"], 300);
    let rows = doc["rows"].as_array().expect("rows");
    let names: Vec<&str> = rows.iter().filter_map(|r| r["row"].as_str()).collect();
    assert_eq!(names.len(), 4, "{names:?}");
    assert!(names[0].starts_with("hand-picked"), "{names:?}");
    for want in [
        "SecOC off",
        "no crash event, SecOC on",
        "crash-event cycle, SecOC on",
    ] {
        assert!(names.iter().any(|n| n.contains(want)), "{want}: {names:?}");
    }
    let reference = doc["reference"]["p50_us"].as_f64().expect("reference p50");
    assert!(reference > 0.0);
    for r in rows {
        let q = |k: &str| r[k].as_f64().unwrap_or(f64::NAN);
        let (p50, p99, p999, max) = (q("p50_us"), q("p99_us"), q("p999_us"), q("max_us"));
        assert!(
            p50 > 0.0 && p50 <= p99 && p99 <= p999 && p999 <= max * 1.001,
            "{r}"
        );
        assert!(
            (q("p50_over_reference") - p50 / reference).abs() < 1e-9,
            "{r}"
        );
        assert_eq!(r["p50_within_line"].as_bool(), Some(p50 <= 1.0), "{r}");
    }
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("p50/ref") && text.contains("reference: AES-128-CMAC"),
        "{text}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
