//! Belt retractor and airbag module stubs: the library half.
//!
//! * [`commands`] — decoded command records (JSONL log) and the module state machines
//!   (pretensioner fire/release, airbag fire while armed) acting at receive times.
//! * [`outcome`] — the judge: occupant outcome of what was actually commanded against the TRUE
//!   pulse, beside the reference restraint and the ideal bound.
//! * [`rx`] — per-frame E2E check and SecOC pairing: the modules act only on authenticated
//!   commands.
//! * [`report`] — the `report.json` schema (also read by the `hil-bench` orchestrator).
//! * [`status`] — the `EcuStatus` vocabulary (fault flags, mode names) from the DBC.
//! * [`plot`] — occupant deceleration and excursion over time, adaptive vs reference (PNG).
#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod commands;
pub mod outcome;
pub mod plot;
pub mod report;
pub mod rx;
pub mod status;
