//! Library half of the `lut` package: the restraint optimiser, the reference restraint, the
//! characteristic-diagram builder and helpers shared by the `lut` binary, tests and benches.
//!
//! * [`reference`] — the conventional reference restraint (data/reference-restraint.toml):
//!   schema + loader. Needs only `physics`, `serde` and `toml`, so the ECU can depend on this
//!   package with `default-features = false` and get the loader without argmin/rayon.
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
