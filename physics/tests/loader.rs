//! The std loader reads the shipped data file into the same curves as the build-time consts,
//! and rejects invalid user files with a message naming the problem.
#![cfg(feature = "std")]

use physics::stiffness::{load_class_file, parse_class_file, CLASS_CURVES, COMBINED_CURVE};
use std::path::Path;

#[test]
fn shipped_file_equals_generated_consts() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../data/stiffness-classes.toml");
    let set = load_class_file(&path).unwrap();
    assert_eq!(set.classes.len(), 6);
    for (i, (_, _, c)) in set.classes.iter().enumerate() {
        assert_eq!(c, &CLASS_CURVES[i]);
    }
    assert_eq!(set.combined, COMBINED_CURVE);
    assert!(set.provenance.contains("not NHTSA"));
}

const GOOD: &str = r#"
[meta]
description = "d"
provenance = "p"
[[class]]
id = 1
lower_kg = 0.0
upper_kg = inf
deflection_mm = [0, 100, 500]
force_kn = [0, 200, 400]
[combined]
deflection_mm = [0, 100, 500]
force_kn = [0, 200, 400]
"#;

#[test]
fn validation_errors_are_specific() {
    assert!(parse_class_file(GOOD).is_ok());
    let non_monotone = GOOD.replacen("[0, 100, 500]", "[0, 500, 100]", 1);
    assert!(parse_class_file(&non_monotone)
        .unwrap_err()
        .contains("deflection must be strictly increasing"));
    let negative = GOOD.replacen("[0, 200, 400]", "[0, -200, 400]", 1);
    assert!(parse_class_file(&negative)
        .unwrap_err()
        .contains("force must be strictly increasing"));
    let nan = GOOD.replacen("[0, 200, 400]", "[0, nan, 400]", 1);
    assert!(parse_class_file(&nan).unwrap_err().contains("non-finite"));
    let short = GOOD.replacen("force_kn = [0, 200, 400]", "force_kn = [0, 200]", 1);
    assert!(parse_class_file(&short).unwrap_err().contains("length"));
    assert!(parse_class_file("not toml").is_err());
}
