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
