//! The restraint ECU's logic, as a `no_std` core with no allocator.
//!
//! Per cycle: drain inputs (CAN through the bus crate's E2E checker, object states,
//! accelerometer batches) → estimate (a track filter over the object samples: time to contact,
//! closing speed at contact and opponent mass with their σ; occupant) → collision prediction
//! (`physics::ExactCollision`, closed form, only when a new object sample arrived) →
//! characteristic-diagram query (`diagram::DiagramView`) → decision state machine →
//! E2E-protected, SecOC-authenticated CAN commands (on change and cyclically) → diagnostics
//! record. One module per job, each with its own state:
//!
//! | module | job |
//! |---|---|
//! | [`config`] | every setting (`[cycle]`, `[cycle.track]`) with its default, range check and conversion into the modules' parameters |
//! | [`settings`] | what the settings share: the range error, ms → ns, g → m/s² (a leaf: no module imports `config` to check or convert) |
//! | [`inputs`] | input monitoring: E2E, freshness, plausibility, degraded reasons |
//! | [`accel`] | crash-accelerometer plausibility: stale, stuck, saturated, out of range, time |
//! | [`confirm`] | generic crash confirmation from the compartment accelerometer |
//! | [`crash_match`] | prediction-matched confirmation and the in-crash severity estimate |
//! | [`fallback`] | the accelerometer-only airbag algorithm (no usable prediction) |
//! | [`roughness`] | road roughness: the recent forward velocity excursion, added to every fire's floor |
//! | [`pair_monitor`] | the two accelerometers' plausibility against each other and the vehicle frame: offset, noise |
//! | [`satellites`] | the crush-zone satellites' PSI5 frames → the frontal severity that lowers the tunnel's thresholds (never a fire of its own) |
//! | [`agreement`] | the two accelerometers' severity agreement (velocity traces over the same window) |
//! | [`crash`] | the crash phase's evidence: which path confirmed, the backup, the re-plan |
//! | [`estimate`] | track filter ([`estimate::track`]), situation, closed-form collision prediction, LUT query, diagnostics pulse |
//! | [`decision`] | the state machine: preset, arm, fire, release, fall back |
//! | [`outputs`] | command, status and diagnostics encoding, clock-timed cyclic sends |
//! | [`contract`] | the activity contract a shell runs the cycle through |
//! | [`signals`] | the non-CAN inputs and outputs (object, accelerometer, diagnostics) |
//! | [`sim`] | the in-memory I/O of tests, benches and fuzz targets, and the virtual-time loop that drives the core through it |
//!
//! **The rule this crate enforces**: no `std`, no `alloc`, no operating system. It gets a
//! [`diagram::DiagramView`], the reference restraint as numbers, SecOC keys as bytes and time as
//! an argument; files, clocks, sockets and shared memory are the shell's (`ecu`). The compiler
//! checks the crate itself (`#![no_std]`, and no `extern crate alloc`);
//! `tests/dependency_tree.rs` fails when its normal dependency tree gains a std-only crate.

#![no_std]
#![forbid(unsafe_code)]
#![warn(missing_docs)]
// `!(x >= y)` is deliberate: it is true for NaN, which is how NaN inputs fail safe.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod accel;
pub mod agreement;
pub mod config;
pub mod confirm;
pub mod contract;
pub mod counters;
pub mod crash;
pub mod crash_match;
mod cycle;
pub mod decision;
pub mod estimate;
pub mod fallback;
pub mod inputs;
pub mod outputs;
pub mod pair_monitor;
pub mod plan;
pub mod roughness;
pub mod safing;
pub mod satellites;
pub mod settings;
/// The records shared with the transport: the `signals` crate, under the core's name for it.
pub use ::signals;
pub mod sim;

pub use config::{CycleConfig, TrackConfig, MAX_E2E_BURST};
pub use confirm::{ConfirmParams, CrashDetector};
pub use contract::{Activity, CycleInfo, CycleIo, IoError, ReceiveErrors, StartupError};
pub use counters::CycleCounters;
pub use cycle::{RestraintCycle, StartupNotes};
pub use decision::{Phase, Pretensioner};
pub use estimate::track::{Refused, TrackEstimate, TrackEvent, TrackFilter};
pub use estimate::{time_to_contact, Contact, Lut, LutMismatch, Situation};
pub use inputs::{input_can_ids, Occupant};
pub use outputs::bus_mode;
pub use plan::{PlanSource, ReferenceSettings, RestraintPlan};
pub use settings::{ConfigError, G_MPS2};
pub use signals::{
    CrashAccelSample, Degraded, EcuDiagnostics, EcuMode, ObjectState, ACCEL_BATCH_CAPACITY,
    PULSE_POINTS, VALID,
};
pub use sim::{SimIo, SimLoop};
