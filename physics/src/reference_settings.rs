//! The conventional reference restraint's four settings — one type for the file
//! (`reference`, feature `std`), the optimiser and the ECU core (`restraint`, no_std), which
//! takes it as its safe fallback.

/// The reference restraint setting (file units: kN, ms; times relative to first contact).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(
    feature = "std",
    derive(serde::Serialize, serde::Deserialize),
    serde(deny_unknown_fields)
)]
pub struct ReferenceSettings {
    /// Belt load-limiter level [kN].
    pub belt_limiter_kn: f64,
    /// Airbag + column force level [kN].
    pub airbag_level_kn: f64,
    /// Pretensioner trigger time after contact [ms] (a conventional system has no pre-crash
    /// sensing, so this is ≥ 0 in practice; the bounds allow the optimiser's full range).
    pub pretensioner_time_ms: f64,
    /// Airbag trigger time after contact [ms] (paper: 10 ms).
    pub airbag_time_ms: f64,
}
