// Schema of `data/stiffness-classes.toml`, shared by build.rs (which turns the file into Rust
// consts for the no_std ECU) and by the std loader for user-supplied class files.
// Kept free of crate-internal paths so that build.rs can `#[path]`-include it.

use serde::Deserialize;

/// Whole stiffness-class file.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ClassFile {
    /// Provenance and description.
    pub meta: Meta,
    /// The mass classes, in ascending mass order.
    pub class: Vec<ClassEntry>,
    /// The curve representing all classes together.
    pub combined: CurveEntry,
}

/// Free-text provenance of the data.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Meta {
    /// What the file holds.
    pub description: String,
    /// Where the numbers come from (measured / constructed / calibrated).
    pub provenance: String,
}

/// One mass class with its lookup range and curve.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ClassEntry {
    /// Class number, 1-based.
    pub id: u8,
    /// Lookup range lower end [kg] (inclusive).
    pub lower_kg: f64,
    /// Lookup range upper end [kg] (exclusive); `inf` for the last class.
    pub upper_kg: f64,
    /// Example vehicles (documentation only).
    #[serde(default)]
    pub examples: String,
    /// Deflection points [mm], strictly increasing from 0.
    pub deflection_mm: Vec<f64>,
    /// Force points [kN], strictly increasing from 0.
    pub force_kn: Vec<f64>,
}

/// A curve without a mass range.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CurveEntry {
    /// Deflection points [mm], strictly increasing from 0.
    pub deflection_mm: Vec<f64>,
    /// Force points [kN], strictly increasing from 0.
    pub force_kn: Vec<f64>,
}

/// Largest number of points a file curve may have (half the in-memory capacity, so that the
/// series combination of any two file curves always fits).
pub const FILE_CURVE_MAX_POINTS: usize = 16;

/// Check one curve: equal lengths, 2..=16 points, finite, starts at (0, 0), deflection and force
/// strictly increasing (force must be invertible for the series combination).
pub fn validate_points(deflection_mm: &[f64], force_kn: &[f64]) -> Result<(), &'static str> {
    if deflection_mm.len() != force_kn.len() {
        return Err("deflection_mm and force_kn differ in length");
    }
    if deflection_mm.len() < 2 {
        return Err("a curve needs at least 2 points");
    }
    if deflection_mm.len() > FILE_CURVE_MAX_POINTS {
        return Err("a curve may have at most 16 points");
    }
    if deflection_mm
        .iter()
        .chain(force_kn.iter())
        .any(|v| !v.is_finite())
    {
        return Err("non-finite value");
    }
    if deflection_mm[0] != 0.0 || force_kn[0] != 0.0 {
        return Err("a curve must start at (0 mm, 0 kN)");
    }
    if deflection_mm.windows(2).any(|w| w[1] <= w[0]) {
        return Err("deflection must be strictly increasing");
    }
    if force_kn.windows(2).any(|w| w[1] <= w[0]) {
        return Err("force must be strictly increasing (non-negative, monotone)");
    }
    Ok(())
}

/// Check the whole file: every curve valid, classes numbered 1..n in order with contiguous,
/// non-overlapping mass ranges.
pub fn validate_file(file: &ClassFile) -> Result<(), String> {
    if file.class.is_empty() || file.class.len() > 6 {
        return Err(format!(
            "expected 1..=6 classes, found {}",
            file.class.len()
        ));
    }
    for (i, c) in file.class.iter().enumerate() {
        if usize::from(c.id) != i + 1 {
            return Err(format!(
                "class #{} has id {}, expected {}",
                i + 1,
                c.id,
                i + 1
            ));
        }
        validate_points(&c.deflection_mm, &c.force_kn)
            .map_err(|e| format!("class {}: {e}", c.id))?;
        if !(c.lower_kg >= 0.0) || c.lower_kg.is_infinite() || !(c.upper_kg > c.lower_kg) {
            return Err(format!("class {}: bad mass range", c.id));
        }
        if i > 0 && file.class[i - 1].upper_kg != c.lower_kg {
            return Err(format!(
                "class {}: mass range not contiguous with class {}",
                c.id, i
            ));
        }
    }
    validate_points(&file.combined.deflection_mm, &file.combined.force_kn)
        .map_err(|e| format!("combined: {e}"))?;
    Ok(())
}
