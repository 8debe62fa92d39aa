//! The shipped scenario library loads, and its kinematics reproduce the impact speeds the
//! cases are named after (the paper's Taurus cases, the FMVSS 208 barrier speeds).

use std::path::PathBuf;
use world::{Scenario, Truth};

fn library() -> Vec<PathBuf> {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../scenarios");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .expect("scenarios/ exists")
        .map(|e| e.expect("entry").path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    files.sort();
    files
}

#[test]
fn every_library_file_loads_and_its_name_matches_the_file() {
    let files = library();
    assert!(files.len() >= 15, "library has {} files", files.len());
    for f in files {
        let s = Scenario::load(&f).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(
            Some(s.name.as_str()),
            f.file_stem().and_then(|x| x.to_str()),
            "{}",
            f.display()
        );
        let t = Truth::new(&s).unwrap_or_else(|e| panic!("{}: {e}", f.display()));
        assert_eq!(
            t.contact_s.is_some(),
            s.expect.contact.unwrap_or(true),
            "{}",
            f.display()
        );
        if let Some(tc) = t.contact_s {
            // Enough pre-crash time for tracking, enough post-crash time for the restraint.
            assert!(
                tc >= 1.0 && s.duration_s - tc >= 0.4,
                "{}: contact at {tc} s of {} s",
                f.display(),
                s.duration_s
            );
        }
    }
}

fn impact_kph(name: &str) -> (f64, f64) {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(format!("../scenarios/{name}.toml"));
    let t = Truth::new(&Scenario::load(path).expect("load")).expect("truth");
    assert!(t.contact_s.is_some(), "{name}: no contact");
    (
        t.ego_speed_at_contact_mps * 3.6,
        t.opp_speed_at_contact_mps * 3.6,
    )
}

#[test]
fn paper_cases_meet_at_their_published_speeds() {
    for (name, kph) in [
        ("taurus-52-52-none", 52.0),
        ("taurus-48-48-abs", 48.0),
        ("taurus-31-31-abs-eba", 31.0),
    ] {
        let (e, o) = impact_kph(name);
        assert!(
            (e - kph).abs() < 0.2 && (o - kph).abs() < 0.2,
            "{name}: {e:.2} + {o:.2} km/h"
        );
    }
    for (name, kph) in [
        ("fmvss208-56-belted", 56.0),
        ("fmvss208-48-unbelted", 48.0),
        ("barrier-16-objects-dead", 16.0),
        ("barrier-35-objects-dead", 35.0),
    ] {
        let (e, o) = impact_kph(name);
        assert!((e - kph).abs() < 0.05 && o == 0.0, "{name}: {e:.2} km/h");
    }
    let (e, o) = impact_kph("low-speed-no-fire");
    assert!(
        e < 20.0 && o < 20.0,
        "below the 20 km/h no-fire limit: {e} {o}"
    );
}

#[test]
fn the_docs_count_and_list_every_library_file() {
    // Counts and lists written by hand drift as files are added: every file has a row in
    // scenarios/README's library table (its name in backticks), and the count the landing page
    // and the results give is the library's.
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..");
    let table = std::fs::read_to_string(root.join("scenarios/README.md")).expect("README");
    let table = table
        .split("## Library")
        .nth(1)
        .expect("the library section");
    let files = library();
    let missing: Vec<String> = files
        .iter()
        .filter_map(|f| f.file_stem().and_then(|x| x.to_str()))
        .filter(|n| !table.contains(&format!("`{n}`")))
        .map(str::to_owned)
        .collect();
    assert!(
        missing.is_empty(),
        "not in scenarios/README.md's library table: {missing:?}"
    );
    for (doc, said) in [
        (
            "docs/results.md",
            format!("The whole scenario library ({} files", files.len()),
        ),
        ("README.md", format!("| {} scenarios through", files.len())),
    ] {
        let text = std::fs::read_to_string(root.join(doc)).expect(doc);
        assert!(
            text.contains(&said),
            "{doc} should say \"{said}\" (the library has {} files)",
            files.len()
        );
    }
}
