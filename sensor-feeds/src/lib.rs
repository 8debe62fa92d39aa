//! Scenario player library: scenario files ([`scenario`]), the true world ([`truth`]: closed-form
//! pre-crash kinematics + the true collision physics after contact), the sensor model
//! ([`sensors`]: noise, bias, latency, range, dropouts; the crash and the safing
//! accelerometer) and what the acceleration sensors see besides a crash ([`events`]:
//! `[[accel_event]]`). The `sensor-feeds` binary plays it in real time; `actuator-stubs` and
//! the e2e tests use the same library to know the truth.
#![forbid(unsafe_code)]
#![warn(missing_docs)]
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod events;
pub mod player;
pub mod scenario;
pub mod sensors;
pub mod truth;

pub use player::{PlayCounts, Player, TickOutput};
pub use scenario::{Scenario, ScenarioError};
pub use sensors::SensorModelSim;
pub use truth::{Truth, WorldState};

/// The bench's clock, from the one clock module of the bench processes (`host`).
pub use host::monotonic_ns;
/// Sleeps until CLOCK_MONOTONIC reaches `deadline_ns` (absolute: no drift accumulates).
pub use host::sleep_through_signals_until_ns as sleep_until_ns;
