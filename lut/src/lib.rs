//! Library half of the `lut` package: the restraint optimiser, the reference restraint, the
//! characteristic-diagram builder and helpers shared by the `lut` binary, tests and benches.
//!
//! * [`reference`] — the FMVSS 208 load cases of the conventional reference restraint; its file
//!   schema + loader is `physics::reference` (re-exported here).
//! * `scenario` (feature `tools`) — predict the ego compartment pulse of a situation once.
//! * `optimise` (feature `tools`) — particle swarm + Nelder–Mead over the four restraint
//!   variables, penalty method for the no-bottoming-out constraint.
//! * `table` (feature `tools`) — grid files, cell optimisation, build / shard / merge / verify.
#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod reference;

#[cfg(feature = "tools")]
pub mod optimise;
#[cfg(feature = "tools")]
pub mod scenario;
#[cfg(feature = "tools")]
pub mod table;
