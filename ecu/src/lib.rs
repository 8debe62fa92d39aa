//! The fixed-rate restraint ECU.
//!
//! Two halves, kept apart on purpose:
//!
//! * [`runtime`] — the real-time *shell*: absolute-deadline loop on CLOCK_MONOTONIC,
//!   RT settings (SCHED_FIFO, mlockall, pinning, PM-QoS), preallocated timing
//!   histograms, the timing report, configuration, the iceoryx2 com layer and the
//!   `monitor` command. It knows nothing about restraints.
//! * [`cycle`] — the pure cycle logic (prediction, LUT interpolation, decision state
//!   machine): [`cycle::RestraintCycle`] implements [`runtime::Activity`] and talks to the
//!   world only through [`runtime::CycleIo`], so it runs unchanged under the real clock and
//!   under [`runtime::SimClock`] with [`runtime::SimIo`] in tests.
//! * [`can_port`] — the SocketCAN [`runtime::CanPort`] over `bus::socket::BusSocket`.

pub mod runtime;

pub mod can_port;
pub mod cycle;
