//! The cycle's counters for the timing report. Each job counts into the same record; it has
//! a module of its own so that the jobs depend on it, not on the cycle that composes them.

/// Counters for the timing report.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct CycleCounters {
    /// Object states received.
    pub objects_rx: u64,
    /// Object states rejected as invalid (NaN, out of range, implausible).
    pub objects_invalid: u64,
    /// Cycles with stale object data (including the wait for the first object at start-up).
    pub object_stale_cycles: u64,
    /// Cycles with stale object data after objects had arrived: dropouts only. A bench that
    /// asks "did the ECU notice the object list die?" compares this one — the start-up wait
    /// depends on how fast the feeds come up, not on the fault.
    pub object_lost_cycles: u64,
    /// Accelerometer batches received.
    pub accel_batches_rx: u64,
    /// Accelerometer samples received.
    pub accel_samples_rx: u64,
    /// CAN frames received.
    pub can_frames_rx: u64,
    /// Object tracks started (first sample, new object id, after a gap or after outliers in
    /// a row).
    pub track_starts: u64,
    /// Object samples rejected by the track filter's gate (not trusted).
    pub track_outliers: u64,
    /// Object samples refused by the track filter (not newer than the track, non-finite).
    pub track_refused: u64,
    /// Collision predictions computed.
    pub predictions: u64,
    /// Predictions that failed (input outside the physics model).
    pub prediction_errors: u64,
    /// LUT lookups.
    pub lut_lookups: u64,
    /// Lookups planned with the V2X station's mass as the second source (`v2x_mass_margin_kg`).
    pub v2x_lookups: u64,
    /// Lookups outside the table (reference used).
    pub lut_out_of_range: u64,
    /// Lookups whose optimum still bottoms out (reported, not hidden).
    pub lut_bottoming_out: u64,
    /// Cycles spent degraded.
    pub degraded_cycles: u64,
    /// CAN frames sent.
    pub can_tx: u64,
    /// CAN send failures.
    pub can_tx_errors: u64,
    /// Commands sent together with their SecOC authenticator (both frames taken by the socket).
    pub secoc_commands_tx: u64,
    /// Command encode failures (value outside the DBC after clamping: should stay 0).
    pub encode_errors: u64,
    /// Diagnostics publish failures.
    pub diagnostics_failures: u64,
}
