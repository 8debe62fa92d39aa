//! Scenario player library: scenario files ([`scenario`]), the true world ([`truth`]: closed-form
//! pre-crash kinematics + the true collision physics after contact) and the sensor model
//! ([`sensors`]: noise, bias, latency, range, dropouts). The `sensor-feeds` binary plays it in
//! real time; `actuator-stubs` and the e2e tests use the same library to know the truth.
#![forbid(unsafe_code)]
#![warn(missing_docs)]
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod scenario;
pub mod sensors;
pub mod truth;

pub use scenario::{Scenario, ScenarioError};
pub use sensors::SensorModelSim;
pub use truth::{Truth, WorldState};

/// CLOCK_MONOTONIC now [ns] (the bench's one clock, shared by every process).
pub fn monotonic_ns() -> u64 {
    match nix::time::clock_gettime(nix::time::ClockId::CLOCK_MONOTONIC) {
        Ok(ts) => (ts.tv_sec() as u64).saturating_mul(1_000_000_000) + ts.tv_nsec() as u64,
        Err(_) => 0,
    }
}

/// Sleeps until CLOCK_MONOTONIC reaches `deadline_ns` (absolute: no drift accumulates).
pub fn sleep_until_ns(deadline_ns: u64) {
    use nix::sys::time::TimeSpec;
    use nix::time::{clock_nanosleep, ClockId, ClockNanosleepFlags};
    let ts = TimeSpec::new(
        (deadline_ns / 1_000_000_000) as i64,
        (deadline_ns % 1_000_000_000) as i64,
    );
    while let Err(nix::errno::Errno::EINTR) = clock_nanosleep(
        ClockId::CLOCK_MONOTONIC,
        ClockNanosleepFlags::TIMER_ABSTIME,
        &ts,
    ) {}
}
