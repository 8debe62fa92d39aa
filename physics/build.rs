//! Turns `data/stiffness-classes.toml` (the one source of truth for the class curves) into Rust
//! consts, so the no_std ECU has the curves without parsing anything at run time.

// `!(x > 0.0)` is deliberate: it is true for NaN, which is how inputs are rejected NaN-safely.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use std::{env, fmt::Write as _, fs, path::PathBuf};

#[path = "src/schema.rs"]
#[allow(dead_code)]
mod schema;

const CAPACITY: usize = 32;

fn padded(values: &[f64], scale: f64) -> String {
    let mut s = String::from("[");
    for i in 0..CAPACITY {
        let v = values.get(i).map_or(0.0, |v| v * scale);
        write!(s, "{v:?}, ").unwrap();
    }
    s.push(']');
    s
}

fn curve_expr(deflection_mm: &[f64], force_kn: &[f64]) -> String {
    format!(
        "Curve::from_padded({}, {}, {})",
        padded(deflection_mm, 1.0e-3),
        padded(force_kn, 1.0e3),
        deflection_mm.len()
    )
}

fn main() {
    let manifest = PathBuf::from(env::var("CARGO_MANIFEST_DIR").unwrap());
    let path = manifest.join("../data/stiffness-classes.toml");
    println!("cargo:rerun-if-changed={}", path.display());
    println!("cargo:rerun-if-changed=src/schema.rs");
    let text =
        fs::read_to_string(&path).unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display()));
    let file: schema::ClassFile =
        toml::from_str(&text).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    if let Err(e) = schema::validate_file(&file) {
        panic!("{}: {e}", path.display());
    }
    assert_eq!(
        file.class.len(),
        6,
        "the shipped file must hold exactly six classes"
    );

    let mut out = String::new();
    writeln!(
        out,
        "/// Curves of the six mass classes (index 0 = class 1), from data/stiffness-classes.toml."
    )
    .unwrap();
    writeln!(out, "pub const CLASS_CURVES: [Curve; 6] = [").unwrap();
    for c in &file.class {
        writeln!(out, "    {},", curve_expr(&c.deflection_mm, &c.force_kn)).unwrap();
    }
    writeln!(out, "];").unwrap();
    writeln!(
        out,
        "/// Mass lookup ranges [kg] (lower inclusive, upper exclusive) of the six classes."
    )
    .unwrap();
    writeln!(out, "pub const CLASS_RANGES_KG: [(f64, f64); 6] = [").unwrap();
    for c in &file.class {
        let upper = if c.upper_kg.is_infinite() {
            "f64::INFINITY".to_string()
        } else {
            format!("{:?}", c.upper_kg)
        };
        writeln!(out, "    ({:?}, {upper}),", c.lower_kg).unwrap();
    }
    writeln!(out, "];").unwrap();
    writeln!(
        out,
        "/// The curve of all classes combined (paper's row \"classes 1-6\")."
    )
    .unwrap();
    writeln!(
        out,
        "pub const COMBINED_CURVE: Curve = {};",
        curve_expr(&file.combined.deflection_mm, &file.combined.force_kn)
    )
    .unwrap();

    let dest = PathBuf::from(env::var("OUT_DIR").unwrap()).join("stiffness_classes.rs");
    fs::write(dest, out).unwrap();
}
