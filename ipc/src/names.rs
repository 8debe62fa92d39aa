//! Service names and port settings: the ONE place. Every opener requests exactly these, which
//! is what makes `open_or_create` succeed from any side.

// ---------------------------------------------------------------------------------------

/// Default prefix of every service name. Tests pass a unique prefix so that parallel
/// test runs on one machine never see each other's samples.
pub const DEFAULT_SERVICE_PREFIX: &str = "restraint-bench";

/// Suffix of the opponent-object / pre-crash state service (sensor feeds → ECU).
pub const OBJECT_STATE_SUFFIX: &str = "ecu/in/object_state";
/// Suffix of the compartment crash-accelerometer service (sensor feeds → ECU).
pub const CRASH_ACCEL_SUFFIX: &str = "ecu/in/crash_accel";
/// Suffix of the safing-accelerometer service (sensor feeds → ECU): the independent second
/// acceleration channel every Fire needs (SPEC "Single-fault tolerance"), on its own service
/// so that nothing of the crash accelerometer's transport is shared with it.
pub const SAFING_ACCEL_SUFFIX: &str = "ecu/in/safing_accel";
/// Suffixes of the left and the right crush-zone satellite's services (sensor feeds → ECU):
/// each satellite's PSI5 frames on its own service, as each has its own PSI5 channel.
pub const SATELLITE_SUFFIXES: [&str; 2] = ["ecu/in/satellite_left", "ecu/in/satellite_right"];
/// Suffix of the ECU diagnostics service (ECU → monitors).
pub const DIAGNOSTICS_SUFFIX: &str = "ecu/out/diagnostics";
/// Suffix of the bench-truth service (sensor feeds → actuator stubs; never read by the ECU).
pub const BENCH_TRUTH_SUFFIX: &str = "bench/truth";

/// Static settings of one publish-subscribe service. Every opener uses exactly these.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PortSettings {
    /// Samples a subscriber queue holds before the oldest is overwritten (safe overflow).
    pub subscriber_buffer: usize,
    /// Samples a late-joining subscriber receives on connect.
    pub history: usize,
    /// Publishers allowed on the service (e.g. a feed and a replay tool).
    pub max_publishers: usize,
    /// Subscribers allowed on the service (ECU, monitors, loggers, tests).
    pub max_subscribers: usize,
    /// Nodes allowed to open the service.
    pub max_nodes: usize,
    /// Samples a subscriber may hold at once; the ECU holds one at a time.
    pub max_borrowed: usize,
}

/// Object state arrives every ~10–20 ms; the ECU only needs the newest, a small queue
/// absorbs a stalled cycle without losing the latest value (safe overflow drops oldest).
pub const OBJECT_STATE_PORTS: PortSettings = PortSettings {
    subscriber_buffer: 8,
    history: 1,
    max_publishers: 2,
    max_subscribers: 8,
    max_nodes: 16,
    max_borrowed: 2,
};

/// Accelerometer batches arrive at ≥ 1 kHz of batches of up to
/// [`ACCEL_BATCH_CAPACITY`](crate::ACCEL_BATCH_CAPACITY) samples; every sample matters for
/// crash confirmation, so the queue covers ~64 ms of a stalled ECU at 1 kHz batches.
pub const CRASH_ACCEL_PORTS: PortSettings = PortSettings {
    subscriber_buffer: 64,
    history: 0,
    max_publishers: 2,
    max_subscribers: 8,
    max_nodes: 16,
    max_borrowed: 2,
};

/// The safing accelerometer's batches: the same record and the same reasoning as the crash
/// accelerometer's ([`CRASH_ACCEL_PORTS`]); at its default 2 kHz the queue covers the same
/// ~64 ms of a stalled ECU (one batch per ms whatever the rate).
pub const SAFING_ACCEL_PORTS: PortSettings = CRASH_ACCEL_PORTS;

/// A satellite's frame batches: one batch per ms (two frames at the 500 µs sync period),
/// every frame matters for the crush Δv, so the queue covers the same ~64 ms of a stalled ECU
/// as the accelerometers'.
pub const SATELLITE_PORTS: PortSettings = CRASH_ACCEL_PORTS;

/// Diagnostics are published every ECU cycle; monitors only show the newest.
pub const DIAGNOSTICS_PORTS: PortSettings = PortSettings {
    subscriber_buffer: 16,
    history: 1,
    max_publishers: 1,
    max_subscribers: 8,
    max_nodes: 16,
    max_borrowed: 2,
};

/// Bench truth is published every ~10 ms and at the end; the stubs need only the newest
/// (history 1 so a late-starting stub still learns the start time).
pub const BENCH_TRUTH_PORTS: PortSettings = PortSettings {
    subscriber_buffer: 8,
    history: 1,
    max_publishers: 1,
    max_subscribers: 8,
    max_nodes: 16,
    max_borrowed: 2,
};

/// Fully qualified service names for one prefix.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ServiceNames {
    /// Opponent-object state service.
    pub object_state: String,
    /// Crash accelerometer service.
    pub crash_accel: String,
    /// Safing accelerometer service.
    pub safing_accel: String,
    /// Left satellite service.
    pub satellite_left: String,
    /// Right satellite service.
    pub satellite_right: String,
    /// ECU diagnostics service.
    pub diagnostics: String,
    /// Bench-truth service (sensor feeds → actuator stubs).
    pub bench_truth: String,
}

impl ServiceNames {
    /// Names under `prefix` (no trailing slash), e.g. `restraint-bench/ecu/in/object_state`.
    pub fn with_prefix(prefix: &str) -> Self {
        let p = prefix.trim_end_matches('/');
        Self {
            object_state: format!("{p}/{OBJECT_STATE_SUFFIX}"),
            crash_accel: format!("{p}/{CRASH_ACCEL_SUFFIX}"),
            safing_accel: format!("{p}/{SAFING_ACCEL_SUFFIX}"),
            satellite_left: format!("{p}/{}", SATELLITE_SUFFIXES[0]),
            satellite_right: format!("{p}/{}", SATELLITE_SUFFIXES[1]),
            diagnostics: format!("{p}/{DIAGNOSTICS_SUFFIX}"),
            bench_truth: format!("{p}/{BENCH_TRUTH_SUFFIX}"),
        }
    }
}

impl Default for ServiceNames {
    fn default() -> Self {
        Self::with_prefix(DEFAULT_SERVICE_PREFIX)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn service_names_use_prefix_once() {
        let n = ServiceNames::with_prefix("x/");
        assert_eq!(n.object_state, "x/ecu/in/object_state");
        assert_eq!(n.crash_accel, "x/ecu/in/crash_accel");
        assert_eq!(n.safing_accel, "x/ecu/in/safing_accel");
        assert_eq!(n.satellite_left, "x/ecu/in/satellite_left");
        assert_eq!(n.satellite_right, "x/ecu/in/satellite_right");
        assert_eq!(n.diagnostics, "x/ecu/out/diagnostics");
        assert_eq!(n.bench_truth, "x/bench/truth");
    }
}
