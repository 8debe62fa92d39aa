//! `misuse-matrix`'s own interface (issue 32 item 5): `--list` names every family with its
//! requirement and what it samples, an unknown name lists the valid ones, `--quiet` prints the
//! table only.

use e2e_tests::misuse::FAMILIES;
use std::process::Command;

fn matrix(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_misuse-matrix"))
        .args(args)
        .output()
        .expect("misuse-matrix runs");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn list_names_every_family_with_its_requirement_and_envelope() {
    let (code, stdout, _) = matrix(&["--list"]);
    assert_eq!(code, 0);
    for f in FAMILIES {
        let line = stdout
            .lines()
            .find(|l| l.split_whitespace().next() == Some(f.name))
            .unwrap_or_else(|| panic!("{} not listed:\n{stdout}", f.name));
        assert!(line.contains(f.requirement.label()), "{line}");
        assert!(line.contains(f.envelope), "{line}");
    }
}

#[test]
fn an_unknown_family_lists_the_valid_names() {
    let (code, _, stderr) = matrix(&["--family", "potholes", "--variants", "10"]);
    assert_ne!(code, 0);
    assert!(stderr.contains("\"potholes\""), "{stderr}");
    for f in FAMILIES {
        assert!(stderr.contains(f.name), "{} not offered: {stderr}", f.name);
    }
}

#[test]
fn quiet_prints_the_table_only() {
    let (code, stdout, stderr) = matrix(&[
        "--family",
        "door-slam",
        "--family",
        "must-fire-crash",
        "--variants",
        "20",
        "--quiet",
    ]);
    assert_eq!(code, 0, "{stderr}");
    assert!(stderr.is_empty(), "{stderr}");
    assert!(
        stdout.lines().any(|l| l.starts_with("door-slam")),
        "{stdout}"
    );
    assert!(
        stdout.lines().any(|l| l.starts_with("must-fire-crash")),
        "{stdout}"
    );
}

/// Runs `bin args`, reads one line of its output and closes the pipe: how `| head -1` ends it.
fn closed_pipe(bin: &str, args: &[&str]) -> (std::process::ExitStatus, String) {
    use std::io::{BufRead, BufReader, Read};
    let mut child = Command::new(bin)
        .args(args)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("runs");
    let mut first = String::new();
    BufReader::new(child.stdout.take().expect("stdout"))
        .read_line(&mut first)
        .expect("a line");
    // The reader is dropped here: the pipe is closed.
    let mut err = String::new();
    child
        .stderr
        .take()
        .expect("stderr")
        .read_to_string(&mut err)
        .expect("stderr");
    (child.wait().expect("exit"), err)
}

#[test]
fn a_closed_pipe_ends_the_tools_quietly() {
    // Issue 22 item 3: `offline-bench | head -1` and `lut inspect … | head -1` panicked
    // (exit 101, "failed printing to stdout: Broken pipe").
    let root = e2e_tests::repo_root();
    let lut = root.join("data/default.lut");
    let lut_bin = root.join("target/release/lut");
    for (bin, args) in [
        (env!("CARGO_BIN_EXE_offline-bench"), vec![]),
        (env!("CARGO_BIN_EXE_misuse-matrix"), vec!["--list"]),
        (
            lut_bin.to_str().expect("path"),
            vec!["inspect", lut.to_str().expect("path")],
        ),
    ] {
        if !std::path::Path::new(bin).exists() {
            panic!("{bin} not built (test.sh builds every binary first)");
        }
        let (status, err) = closed_pipe(bin, &args);
        assert!(!err.contains("panicked"), "{bin}: {err}");
        assert_ne!(status.code(), Some(101), "{bin}: {err}");
    }
}

#[test]
fn every_tool_answers_version_with_its_own_name() {
    // Issue 22 item 5: `budget` and `worst_cycle` lacked `--version`.
    let release = e2e_tests::repo_root().join("target/release");
    for tool in [
        "ecu",
        "sensor-feeds",
        "actuator-stubs",
        "lut",
        "hil-bench",
        "offline-bench",
        "misuse-matrix",
        "fault-campaign",
        "bus-inject",
        "budget",
        "worst_cycle",
        "loop-vs-cyclictest",
    ] {
        let bin = release.join(tool);
        assert!(
            bin.exists(),
            "{tool} not built (test.sh builds every binary first)"
        );
        let out = Command::new(&bin).arg("--version").output().expect("runs");
        let text = String::from_utf8_lossy(&out.stdout);
        assert!(
            out.status.success() && text.starts_with(&format!("{tool} ")),
            "{tool}: {text}"
        );
    }
}
