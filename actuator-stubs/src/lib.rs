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

/// The start of the line the stubs print on stderr once their CAN socket is open and they
/// receive: an orchestrator (the e2e harness, `hil-bench`) starts the ECU only after it, so the
/// ECU's first commands are not sent before anyone listens.
pub const READY_PREFIX: &str = "actuator-stubs: listening on";

/// The diagnostics records the stubs saw on iceoryx2, as postcard records back to back (the
/// run's recording reads them: `record`, topic `/ecu/diagnostics`).
pub const DIAGNOSTICS_LOG: &str = "diagnostics.postcard";
