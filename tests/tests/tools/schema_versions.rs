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
    assert_eq!(lut::json_out::SCHEMA_VERSION, documented("`lut` results"));
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

/// `--json -`: the document alone on stdout (the table, where there is one, on stderr), so
/// `… --json - | jq` reads it; every record carries its tool's documented version.
#[test]
fn json_to_stdout_is_the_versioned_document_alone() {
    let root = repo_root();
    let scenario = root.join("scenarios/barrier-35-objects-dead.toml");
    let lut_bin = root.join("target/release/lut");
    let lut = root.join("data/default.lut");
    let lut_bin = lut_bin.to_str().expect("path");
    let lut = lut.to_str().expect("path");
    for (exe, args, document) in [
        (
            env!("CARGO_BIN_EXE_offline-bench"),
            vec!["--scenario", scenario.to_str().unwrap(), "--json", "-"],
            "`offline-bench --json`",
        ),
        (
            env!("CARGO_BIN_EXE_misuse-matrix"),
            vec!["--family", "pothole", "--variants", "2", "--json", "-"],
            "`misuse-matrix --json`",
        ),
        (
            lut_bin,
            vec!["inspect", lut, "--json", "-"],
            "`lut` results",
        ),
        (
            lut_bin,
            vec!["verify", lut, "--cells", "2", "--json", "-"],
            "`lut` results",
        ),
    ] {
        let (code, out, err) = super::run_tool(exe, &args);
        assert_eq!(code, 0, "{args:?}: {err}");
        let v: serde_json::Value = serde_json::from_str(&out)
            .unwrap_or_else(|e| panic!("{args:?}: stdout is not one JSON document ({e}): {out}"));
        let want = documented(document);
        match v.as_array() {
            Some(records) => {
                assert!(!records.is_empty(), "{args:?}");
                for r in records {
                    assert_eq!(r["schema_version"], want, "{args:?}: {r}");
                }
            }
            None => assert_eq!(v["schema_version"], want, "{args:?}: {v}"),
        }
    }
}
