//! Scenario player library: plays the bench's world (the `world` crate: scenario files, the
//! true world, the sensor models, the acceleration events) tick by tick ([`player`]). The
//! `sensor-feeds` binary publishes it in real time over iceoryx2 and CAN; the offline bench
//! hands the same records to the ECU core under a simulated clock.

#![forbid(unsafe_code)]
#![warn(missing_docs)]
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod player;

pub use player::{PlayCounts, Player, TickOutput};

/// The bench's clock, from the one clock module of the bench processes (`host`).
pub use host::monotonic_ns;
/// Sleeps until CLOCK_MONOTONIC reaches `deadline_ns` (absolute: no drift accumulates).
pub use host::sleep_through_signals_until_ns as sleep_until_ns;

// A scenario name must fit the bench truth record that carries it.
const _: () = assert!(world::scenario::NAME_CAPACITY == ipc::SCENARIO_NAME_CAPACITY);
