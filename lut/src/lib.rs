//! Library half of the `lut` package: the restraint optimiser, the reference restraint, the
//! characteristic-diagram builder and helpers shared by the `lut` binary, tests and benches.
//!
//! * [`reference`] — the FMVSS 208 load cases of the conventional reference restraint; its file
//!   schema + loader is `physics::reference` (re-exported here).
//! * [`scenario`] — predict the ego compartment pulse of a situation once.
//! * [`optimise`] — particle swarm + Nelder–Mead over the four restraint variables, penalty
//!   method for the no-bottoming-out constraint.
//! * [`table`] — grid files, cell optimisation, build / shard / merge / verify.
#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod optimise;
pub mod reference;
pub mod scenario;
pub mod table;
