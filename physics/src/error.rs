//! The one error type of the crate. Every public function returns it instead of panicking.

use core::fmt;

/// Why a physics call refused its input or could not finish.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PhysicsError {
    /// A scalar input was NaN, infinite or outside its admissible range; the name says which.
    InvalidInput(&'static str),
    /// A force-deflection curve violates the schema (the reason says how).
    InvalidCurve(&'static str),
    /// A curve or series combination needs more points than the fixed capacity.
    CurveTooLong,
    /// The contact did not end within [`crate::defaults::MAX_CONTACT_S`] (unphysical input).
    ContactTooLong,
    /// A sampled signal (trace, pulse) is unusable: too short, non-uniform, NaN.
    InvalidSignal(&'static str),
}

impl fmt::Display for PhysicsError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            PhysicsError::InvalidInput(what) => write!(f, "invalid input: {what}"),
            PhysicsError::InvalidCurve(why) => write!(f, "invalid force-deflection curve: {why}"),
            PhysicsError::CurveTooLong => write!(
                f,
                "curve needs more than {} points",
                crate::stiffness::CURVE_CAPACITY
            ),
            PhysicsError::ContactTooLong => {
                write!(f, "contact phase did not end (unphysical input)")
            }
            PhysicsError::InvalidSignal(why) => write!(f, "invalid signal: {why}"),
        }
    }
}

#[cfg(feature = "std")]
impl std::error::Error for PhysicsError {}
