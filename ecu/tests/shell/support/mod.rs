//! Test support of the shell's tests.
pub mod passthrough;
