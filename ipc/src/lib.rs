//! iceoryx2 transport of the bench processes: service names and port settings ([`names`]),
//! what travels ([`payload`]) and the node/port plumbing ([`port`]).
//!
//! Every process of the bench (ECU, sensor feeds, monitors, tests) talks over the services
//! defined here:
//!
//! | service (under the prefix) | record | publisher → subscribers | ports |
//! |---|---|---|---|
//! | `ecu/in/object_state` | `ObjectState` | sensor feeds → ECU | [`OBJECT_STATE_PORTS`] |
//! | `ecu/in/crash_accel` | `CrashAccelSample` (≤ 8 samples a batch) | sensor feeds → ECU (crash accelerometer) | [`CRASH_ACCEL_PORTS`] |
//! | `ecu/in/safing_accel` | `CrashAccelSample` (≤ 8 samples a batch) | sensor feeds → ECU (safing accelerometer, the independent second channel) | [`SAFING_ACCEL_PORTS`] |
//! | `ecu/in/satellite_left`, `ecu/in/satellite_right` | `SatelliteFrames` (≤ 8 PSI5 frames a batch) | sensor feeds → ECU (crush-zone satellites, one service each) | [`SATELLITE_PORTS`] |
//! | `ecu/out/diagnostics` | `EcuDiagnostics` | ECU → monitors | [`DIAGNOSTICS_PORTS`] |
//! | `bench/truth` | [`BenchTruth`] | sensor feeds → actuator stubs, tests (never the ECU) | [`BENCH_TRUTH_PORTS`] |
//! Keeping the payload layouts, the service names and **all** port settings in
//! this one crate is what makes `open_or_create` succeed from any side: iceoryx2 refuses to
//! open a service whose static settings are incompatible with the ones requested, so every
//! opener must request the same ones.
//!
//! The ECU's records are the `signals` crate's types (re-exported here), carried in a
//! transport wrapper so the core never depends on iceoryx2 and the transport never on the core. The subscriber wrappers are
//! poll-only (`receive()` every cycle, no event waits) and their hot-path methods neither
//! allocate nor block; errors on the hot path are counted, not formatted. The ports are generic
//! over the topic, but opening one (iceoryx2's service, subscriber and publisher builders, the
//! bulk of its code) happens in per-topic functions of this crate ([`port::Topic::subscribe`]),
//! compiled once here: a release build does not share generic instances between crates, and
//! every binary that opened a port used to compile its own copy (the sensor-feeds binary
//! 6.2 → 1.7 s to compile, the actuator stubs' 6.3 → 2.2 s).
//!
//! Without the default `transport` feature the crate is [`names`] only (no iceoryx2): what the
//! ECU's configuration needs for its defaults where the transport is not built (fuzz).

#[cfg(feature = "transport")]
pub use iceoryx2;

pub mod names;
#[cfg(feature = "transport")]
pub mod payload;
#[cfg(feature = "transport")]
pub mod port;

pub use names::*;
#[cfg(feature = "transport")]
pub use payload::{BenchTruth, Shm, ShmRecord, SCENARIO_NAME_CAPACITY};
#[cfg(feature = "transport")]
pub use port::*;
pub use signals::{
    CrashAccelSample, Degraded, EcuDiagnostics, EcuMode, ObjectState, SatelliteFrames,
    ACCEL_BATCH_CAPACITY, PULSE_POINTS, SATELLITE_BATCH_CAPACITY, VALID,
};
