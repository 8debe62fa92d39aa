//! The conventional (non-adaptive) reference restraint: schema and loader of
//! `data/reference-restraint.toml` (feature `std`).
//!
//! SPEC: force levels optimised for the two FMVSS 208 rigid-barrier load cases (56 km/h belted
//! 75 kg, 48 km/h unbelted 75 kg), fire time 10 ms after contact. The file is written by
//! `lut reference`; the ECU reads it as its safe fallback ("never no protection") and the
//! studies as their baseline. It lives here, not in `lut`, so that the ECU can load it without
//! depending on the optimiser's heavy dependencies. The schema matches the file exactly
//! (`deny_unknown_fields`): a `[restraint]` table with the four settings and optional `[[case]]`
//! tables documenting what the optimiser achieved.

use crate::defaults;
use crate::occupant::RestraintSettings;
use serde::{Deserialize, Serialize};
use std::format;
use std::path::Path;
use std::string::{String, ToString};
use std::vec::Vec;

pub use crate::reference_settings::ReferenceSettings;

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
    /// Outcomes in the load cases it was optimised for (optional).
    #[serde(default)]
    pub case: Vec<ReferenceCaseResult>,
}

/// Text of the shipped reference-restraint file, embedded at compile time so that a process
/// whose `--reference` file is missing still has a protective fallback (one source of truth:
/// the data file; no copy of its numbers in code).
pub const BUILTIN_TOML: &str = include_str!("../../data/reference-restraint.toml");

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

    /// The shipped `data/reference-restraint.toml` (see [`BUILTIN_TOML`]).
    pub fn builtin() -> Result<Self, String> {
        Self::parse("data/reference-restraint.toml (built in)", BUILTIN_TOML)
    }

    /// Every value finite and inside the optimiser's hardware bounds ([`defaults`]).
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

    /// The setting in SI units for [`crate::simulate_occupant`].
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

#[cfg(test)]
mod tests {
    use super::*;

    const OK: &str = "[restraint]\nbelt_limiter_kn = 4.0\nairbag_level_kn = 6.0\n\
                      pretensioner_time_ms = 10.0\nairbag_time_ms = 10.0\n";

    #[test]
    fn parses_minimal_file_and_converts_to_si() {
        let r = ReferenceRestraint::parse("t", OK).unwrap();
        let s = r.settings();
        assert_eq!(s.load_limiter_n, 4000.0);
        assert_eq!(s.airbag_force_n, 6000.0);
        assert!((s.airbag_time_s - 0.010).abs() < 1e-12);
        assert!(r.case.is_empty());
    }

    #[test]
    fn rejects_out_of_range_nan_and_unknown_fields() {
        let e = ReferenceRestraint::parse("t", &OK.replace("4.0", "40.0")).unwrap_err();
        assert!(e.contains("belt_limiter_kn"), "{e}");
        assert!(ReferenceRestraint::parse("t", &OK.replace("4.0", "nan")).is_err());
        assert!(ReferenceRestraint::parse(
            "t",
            &OK.replace("airbag_time_ms = 10.0", "airbag_time_ms = 1.0")
        )
        .is_err());
        assert!(ReferenceRestraint::parse("t", &format!("{OK}extra = 1\n")).is_err());
        assert!(ReferenceRestraint::parse("t", "[restraint]\nbelt_limiter_kn = 4.0\n").is_err());
    }

    #[test]
    fn shipped_file_loads_and_fires_at_the_paper_reference_time() {
        let r = ReferenceRestraint::builtin().expect("shipped file must load");
        // SPEC: the conventional reference fires 10 ms after contact.
        assert_eq!(r.restraint.airbag_time_ms, 10.0);
        assert_eq!(
            r.restraint.airbag_time_ms * 1e-3,
            defaults::REFERENCE_FIRE_TIME_S
        );
    }
}
