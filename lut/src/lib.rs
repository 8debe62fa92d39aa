//! Library half of the `lut` package: the restraint optimiser, the reference restraint, the
//! characteristic-diagram builder and helpers shared by the `lut` binary, tests and benches.
//!
//! * [`reference`] — the FMVSS 208 load cases of the conventional reference restraint; its file
//!   schema + loader is `physics::reference` (re-exported here).
//! * [`scenario`] — predict the ego compartment pulse of a situation once.
//! * [`fire_floor`] — plan = fire: the earliest airbag the ECU can fire on a cell's pulse, with
//!   the crush-zone satellites' relief of its severity floor.
//! * [`optimise`] — particle swarm + Nelder–Mead over the four restraint variables, penalty
//!   method for the no-bottoming-out constraint.
//! * [`table`] — grid files, cell optimisation, build / shard / merge.
//! * [`verify`] — checking a built table: cells re-optimised, the planning margin.
//! * [`hash`] — seeds and fingerprints the same on every machine (SplitMix64, FNV-1a).
//! * [`shard`] — shard files a distributed run can trust (identity, range, checksum).
//! * [`progress`] — progress bar / lines / progress file of long computations.
//! * [`slurm`] — the Slurm client tools (sbatch, squeue, scontrol, scancel).
//! * [`distributed`] — a computation split into N shards run as a Slurm job array plus a
//!   dependent collect job: submit, watch, resume, status, collect.
//! * [`robustness`] — the Monte-Carlo study of the pre-crash estimate's errors.
//! * [`robust_cells`] / [`limiter_switch`] — the planning margin's cost: cells robust over the
//!   uncertainty set, and a two-level load limiter switched on what the pulse shows.
//! * [`margin`] — the planning margin as a property of the table: every cell's setting on the
//!   lighter opponents it may meet, against the reference restraint (`lut verify`).
//! * [`estimation`] — the ECU's track filter against the newest-sample estimate over the
//!   scenario library and noisier sensors (`lut study estimation`).
#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod bound;
pub mod distributed;
pub mod estimation;
pub mod fallback_study;
pub mod fire_floor;
pub mod hash;
pub mod json_out;
pub mod limiter_switch;
pub mod margin;
pub mod optimise;
pub mod paths;
pub mod progress;
pub mod reference;
pub mod robust_cells;
pub mod robustness;
pub mod scenario;
pub mod shard;
pub mod slurm;
pub mod table;
pub mod verify;
