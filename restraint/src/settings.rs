//! What every module's settings share: the range check and its error, and the unit
//! conversions from the file's units (ms, g) to the cycle's (ns, m/s²). A leaf: the modules
//! that check or convert a setting import this, never [`crate::config`], so the aggregate
//! configuration sits above all of them and no import runs back up.

/// Standard gravity, m/s² (same constant as the physics crate).
pub const G_MPS2: f64 = physics::defaults::STANDARD_GRAVITY_MPS2;

/// A decision setting outside its range (the shell adds where it came from).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ConfigError {
    /// Key inside `[cycle]`.
    pub key: &'static str,
    /// The value given.
    pub value: f64,
    /// Smallest allowed value.
    pub lo: f64,
    /// Largest allowed value.
    pub hi: f64,
}

impl core::fmt::Display for ConfigError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        let Self { key, value, lo, hi } = self;
        write!(f, "cycle.{key} = {value} is outside {lo}..={hi}")
    }
}

impl core::error::Error for ConfigError {}

/// `value` of setting `key` within `lo..=hi` (NaN and infinities are outside every range).
pub(crate) fn check_range(
    key: &'static str,
    value: f64,
    lo: f64,
    hi: f64,
) -> Result<(), ConfigError> {
    if value.is_finite() && (lo..=hi).contains(&value) {
        Ok(())
    } else {
        Err(ConfigError { key, value, lo, hi })
    }
}

/// ms (config) → ns (cycle), saturating, NaN → 0.
pub(crate) fn ms_to_ns(ms: f64) -> u64 {
    // `as` from float saturates and maps NaN to 0: never panics.
    (ms * 1.0e6) as u64
}
