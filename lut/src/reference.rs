//! The conventional (non-adaptive) reference restraint: schema and loader of
//! `data/reference-restraint.toml`.
//!
//! SPEC: force levels optimised with the same optimiser for the two FMVSS 208 rigid-barrier
//! load cases (56 km/h belted 75 kg, 48 km/h unbelted 75 kg), fire time 10 ms after contact.
//! The file is written by `lut reference --out data/reference-restraint.toml`; it is used by
//! the studies (the baseline the adaptive restraint is compared with) and by the ECU as its safe
//! fallback. This module needs only `physics`, `serde` and `toml` (no argmin / rayon): depend on
//! `lut` with `default-features = false` to use it.

use physics::{defaults, RestraintSettings};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// One FMVSS 208 load case of the reference optimisation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LoadCase {
    /// Short name.
    pub name: &'static str,
    /// Rigid-barrier impact speed [km/h].
    pub barrier_kph: f64,
    /// Belted occupant?
    pub belted: bool,
    /// Occupant mass [kg].
    pub occupant_kg: f64,
}

/// The two FMVSS 208 load cases of SPEC (rigid barrier, 75 kg, default seat position).
pub const FMVSS208_CASES: [LoadCase; 2] = [
    LoadCase {
        name: "fmvss208-56kph-belted-75kg",
        barrier_kph: 56.0,
        belted: true,
        occupant_kg: 75.0,
    },
    LoadCase {
        name: "fmvss208-48kph-unbelted-75kg",
        barrier_kph: 48.0,
        belted: false,
        occupant_kg: 75.0,
    },
];

/// The reference restraint setting (file units: kN, ms).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ReferenceSettings {
    /// Belt load-limiter level [kN].
    pub belt_limiter_kn: f64,
    /// Airbag + column force level [kN].
    pub airbag_level_kn: f64,
    /// Pretensioner trigger time after contact [ms].
    pub pretensioner_time_ms: f64,
    /// Airbag trigger time after contact [ms].
    pub airbag_time_ms: f64,
}

/// Predicted occupant outcome of the reference setting in one load case (documentation of
/// what the optimiser achieved; not read back by anything safety-relevant).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ReferenceCaseResult {
    /// Load-case name.
    pub name: String,
    /// Rigid-barrier speed [km/h].
    pub barrier_kph: f64,
    /// Belted?
    pub belted: bool,
    /// Occupant mass [kg].
    pub occupant_kg: f64,
    /// Seat distance (chest to wheel) [mm].
    pub seat_distance_mm: f64,
    /// Occupant peak acceleration [g].
    pub a_max_g: f64,
    /// Occupant mean acceleration [g].
    pub a_mean_g: f64,
    /// Forward excursion [mm].
    pub excursion_mm: f64,
    /// Available ride-down [mm].
    pub available_mm: f64,
    /// Bottoming-out.
    pub bottoming_out: bool,
    /// Ideal constant-force bound a* [g].
    pub a_ideal_g: f64,
}

/// The whole file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ReferenceRestraint {
    /// The setting.
    pub restraint: ReferenceSettings,
    /// Outcomes in the load cases it was optimised for.
    #[serde(default)]
    pub case: Vec<ReferenceCaseResult>,
}

impl ReferenceRestraint {
    /// Parse and validate TOML text; `origin` names the source in errors.
    pub fn parse(origin: &str, text: &str) -> Result<Self, String> {
        let r: ReferenceRestraint = toml::from_str(text).map_err(|e| format!("{origin}: {e}"))?;
        r.validate().map_err(|e| format!("{origin}: {e}"))?;
        Ok(r)
    }

    /// Read, parse and validate a reference-restraint file.
    pub fn load(path: impl AsRef<Path>) -> Result<Self, String> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path)
            .map_err(|e| format!("{}: cannot read: {e}", path.display()))?;
        Self::parse(&path.display().to_string(), &text)
    }

    /// The shipped `data/reference-restraint.toml`, embedded at compile time (one source of
    /// truth: the file; no copy in code).
    pub fn builtin() -> Result<Self, String> {
        Self::parse("data/reference-restraint.toml (built in)", BUILTIN_TOML)
    }

    /// Check every value is finite and inside the optimiser's hardware bounds.
    pub fn validate(&self) -> Result<(), String> {
        let s = &self.restraint;
        let check = |name: &str, v: f64, b: defaults::Bounds, scale: f64| {
            if b.contains(v * scale) {
                Ok(())
            } else {
                Err(format!(
                    "restraint.{name} = {v} is outside {}..={}",
                    b.min / scale,
                    b.max / scale
                ))
            }
        };
        check(
            "belt_limiter_kn",
            s.belt_limiter_kn,
            defaults::LOAD_LIMITER_BOUNDS_N,
            1e3,
        )?;
        check(
            "airbag_level_kn",
            s.airbag_level_kn,
            defaults::AIRBAG_FORCE_BOUNDS_N,
            1e3,
        )?;
        check(
            "pretensioner_time_ms",
            s.pretensioner_time_ms,
            defaults::PRETENSIONER_TIME_BOUNDS_S,
            1e-3,
        )?;
        check(
            "airbag_time_ms",
            s.airbag_time_ms,
            defaults::AIRBAG_TIME_BOUNDS_S,
            1e-3,
        )?;
        Ok(())
    }

    /// The setting in SI units for [`physics::simulate_occupant`].
    pub fn settings(&self) -> RestraintSettings {
        let s = &self.restraint;
        RestraintSettings {
            load_limiter_n: s.belt_limiter_kn * 1e3,
            airbag_force_n: s.airbag_level_kn * 1e3,
            pretensioner_time_s: s.pretensioner_time_ms * 1e-3,
            airbag_time_s: s.airbag_time_ms * 1e-3,
        }
    }
}

/// Text of the shipped reference-restraint file.
pub const BUILTIN_TOML: &str = include_str!("../../data/reference-restraint.toml");

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rejects_out_of_range_and_unknown_fields() {
        let ok = "[restraint]\nbelt_limiter_kn = 4.0\nairbag_level_kn = 6.0\npretensioner_time_ms = 10.0\nairbag_time_ms = 10.0\n";
        assert!(ReferenceRestraint::parse("t", ok).is_ok());
        let bad = ok.replace("4.0", "40.0");
        let e = ReferenceRestraint::parse("t", &bad).unwrap_err();
        assert!(e.contains("belt_limiter_kn"), "{e}");
        let bad = ok.replace("airbag_time_ms = 10.0", "airbag_time_ms = 1.0");
        assert!(ReferenceRestraint::parse("t", &bad).is_err());
        let bad = format!("{ok}extra = 1\n");
        assert!(ReferenceRestraint::parse("t", &bad).is_err());
        let bad = ok.replace("4.0", "nan");
        assert!(ReferenceRestraint::parse("t", &bad).is_err());
    }

    #[test]
    fn builtin_file_loads_and_fires_at_reference_time() {
        let r = ReferenceRestraint::builtin().expect("shipped file must load");
        assert_eq!(r.restraint.airbag_time_ms, 10.0);
        assert_eq!(r.case.len(), FMVSS208_CASES.len());
    }
}
