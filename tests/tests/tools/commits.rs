//! Commit subjects: `crate: imperative subject`, at most 72 characters, then a blank line and
//! the body (CONTRIBUTING.md). `git log --oneline` is how the history is read; a subject that
//! wraps there is a paragraph, and the why and the figures belong in the body. Checked on every
//! commit after [`MARKER`] (the history before it stays as it was written).

use std::process::Command;

/// The last commit written before the rule was checked.
const MARKER: &str = "9a4b9ed";

/// The longest subject, in characters (not bytes: "≤" and "−" are one each).
const MAX_SUBJECT_CHARS: usize = 72;

/// What is wrong with one subject, if anything.
fn subject_problem(subject: &str) -> Option<String> {
    let chars = subject.chars().count();
    let prefix = subject.split_once(": ").map(|(p, _)| p);
    let prefix_ok = prefix.is_some_and(|p| {
        !p.is_empty()
            && p.chars()
                .all(|c| c.is_ascii_alphanumeric() || "-_./, ".contains(c))
    });
    if chars > MAX_SUBJECT_CHARS {
        Some(format!("{chars} characters (at most {MAX_SUBJECT_CHARS})"))
    } else if !prefix_ok {
        Some("no `crate: ` prefix".to_owned())
    } else {
        None
    }
}

fn git(args: &[&str]) -> Option<String> {
    let out = Command::new("git")
        .args(args)
        .current_dir(e2e_tests::repo_root())
        .output()
        .ok()?;
    out.status
        .success()
        .then(|| String::from_utf8_lossy(&out.stdout).into_owned())
}

#[test]
fn the_rule_takes_a_good_subject_and_refuses_a_long_or_unprefixed_one() {
    assert_eq!(
        subject_problem("restraint: hold the matched fire below the floor"),
        None
    );
    // 72 characters exactly, with multi-byte characters counted once.
    let at_limit = format!("lut: {}≤", "x".repeat(66));
    assert_eq!(at_limit.chars().count(), 72);
    assert_eq!(subject_problem(&at_limit), None);
    let long = format!("{at_limit}x");
    assert_eq!(
        subject_problem(&long).as_deref(),
        Some("73 characters (at most 72)")
    );
    assert!(subject_problem("hold the matched fire below the floor").is_some());
    assert!(subject_problem(": nothing before the colon").is_some());
}

#[test]
fn every_commit_after_the_marker_has_a_short_prefixed_subject() {
    let Some(top) = git(&["rev-parse", "--is-inside-work-tree"]) else {
        panic!("the repository is not a git checkout: the commit subjects cannot be checked")
    };
    assert_eq!(top.trim(), "true");
    // A shallow clone may not hold the marker (nor know which of its commits come after it):
    // then the newest commit is checked, and the test says so.
    let has_marker = git(&["cat-file", "-e", &format!("{MARKER}^{{commit}}")]).is_some();
    let range = if has_marker {
        vec![format!("{MARKER}..HEAD")]
    } else {
        eprintln!("commit {MARKER} is not in this clone: checking the newest commit only");
        vec!["-1".to_owned(), "HEAD".to_owned()]
    };
    let mut args = vec!["log".to_owned(), "--format=%h%x09%s".to_owned()];
    args.extend(range);
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let log = git(&args).expect("git log");
    let problems: Vec<String> = log
        .lines()
        .filter_map(|l| {
            let (hash, subject) = l.split_once('\t')?;
            subject_problem(subject).map(|p| format!("{hash} {subject:?}: {p}"))
        })
        .collect();
    assert!(
        problems.is_empty(),
        "commit subjects that break the rule (CONTRIBUTING.md):\n{}",
        problems.join("\n")
    );
}
