//! Every JSON result carries the `schema_version` docs/using.md documents for it.

use e2e_tests::docs::documented_schema_version;
use e2e_tests::repo_root;

fn documented(document: &str) -> u32 {
    documented_schema_version(&repo_root(), document)
        .unwrap_or_else(|| panic!("docs/using.md, \"JSON results\", names no {document}"))
}

#[test]
fn each_writer_s_version_is_the_documented_one() {
    assert_eq!(
        actuator_stubs::report::Report::SCHEMA_VERSION,
        documented("`report.json`")
    );
    assert_eq!(
        ecu::runtime::report::TimingReport::SCHEMA_VERSION,
        documented("`ecu-report.json`")
    );
    assert_eq!(
        e2e_tests::faults::Campaign::SCHEMA_VERSION,
        documented("`campaign.json`")
    );
    assert_eq!(
        e2e_tests::host_timing::HostTiming::SCHEMA_VERSION,
        documented("`host-timing.json`")
    );
}

#[test]
fn offline_bench_and_the_matrix_write_it() {
    let dir = std::env::temp_dir().join(format!("schema-versions-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let runs = dir.join("runs.json");
    let scenario = repo_root().join("scenarios/barrier-35-objects-dead.toml");
    let (code, _, err) = super::run_tool(
        env!("CARGO_BIN_EXE_offline-bench"),
        &[
            "--scenario",
            scenario.to_str().unwrap(),
            "--json",
            runs.to_str().unwrap(),
        ],
    );
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&runs).unwrap()).unwrap();
    let want = documented("`offline-bench --json`");
    let all = v.as_array().expect("an array of runs");
    assert!(!all.is_empty());
    for run in all {
        assert_eq!(run["schema_version"], want, "{run}");
    }
    let matrix = dir.join("matrix.json");
    let (code, _, err) = super::run_tool(
        env!("CARGO_BIN_EXE_misuse-matrix"),
        &[
            "--family",
            "pothole",
            "--variants",
            "4",
            "--quiet",
            "--json",
            matrix.to_str().unwrap(),
        ],
    );
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&matrix).unwrap()).unwrap();
    assert_eq!(v["schema_version"], documented("`misuse-matrix --json`"));
    let _ = std::fs::remove_dir_all(&dir);
}
