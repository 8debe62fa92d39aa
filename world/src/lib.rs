//! The bench's world, without I/O: scenario files ([`scenario`]: schema, validation, where an
//! error is in the file), the true world ([`truth`]: closed-form pre-crash kinematics + the
//! true collision physics after contact), the sensor models ([`sensors`]: noise, bias,
//! latency, range; the crash and the safing accelerometer, the crush-zone satellites over
//! `physics::crush_zone`) and what the acceleration sensors
//! see besides a crash ([`events`]: `[[accel_event]]`).
//!
//! No transport, clock or thread: `sensor-feeds` plays this world in real time over iceoryx2
//! and CAN; `actuator-stubs`, `lut`, the e2e tests and the fuzzer use it to know the truth.
#![forbid(unsafe_code)]
#![warn(missing_docs)]
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod events;
pub mod lowpass;
mod noise;
pub mod scenario;
pub mod sensors;
pub mod truth;

pub use scenario::{Scenario, ScenarioError};
pub use sensors::SensorModelSim;
pub use truth::{Truth, WorldState};
