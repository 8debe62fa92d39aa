//! The conventional (non-adaptive) reference restraint: schema and loader of
//! `data/reference-restraint.toml`.
//!
//! SPEC: force levels optimised with the same optimiser for the two FMVSS 208 rigid-barrier
//! load cases (56 km/h belted 75 kg, 48 km/h unbelted 75 kg), fire time 10 ms after contact.
//! The file is written by `lut reference --out data/reference-restraint.toml`; it is used by
//! the studies (the baseline the adaptive restraint is compared with) and by the ECU as its safe
//! fallback. The schema and loader are `physics::reference` (re-exported here).

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

// The file's schema and loader live in `physics::reference` (the ECU's fallback must not
// pull in the optimiser); this module adds only the load cases the optimiser uses.
pub use physics::reference::{
    ReferenceCaseResult, ReferenceRestraint, ReferenceSettings, BUILTIN_TOML,
};

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn builtin_file_loads_and_fires_at_reference_time() {
        let r = ReferenceRestraint::builtin().expect("shipped file must load");
        assert_eq!(r.restraint.airbag_time_ms, 10.0);
        assert_eq!(r.case.len(), FMVSS208_CASES.len());
    }
}
