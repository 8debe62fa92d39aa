//! The contract between a shell and the cycle logic (FEO-style activity).
//!
//! The shell owns time, scheduling and I/O; the activity owns the decision. The activity
//! sees the world only through [`CycleIo`] and time only through [`CycleInfo`], so the same
//! code runs under the real clock with iceoryx2/SocketCAN (the `ecu` shell), under a
//! simulated clock with [`crate::sim::SimIo`] (tests, benches, fuzzing), and on a
//! microcontroller with its own drivers. CAN frames are the bus crate's [`RawFrame`] on both
//! sides of the boundary.

use bus::RawFrame;

use crate::signals::{
    CrashAccelSample, EcuDiagnostics, ObjectState, SatelliteFrames, SatelliteSide,
};

/// Timing facts of the current cycle, handed to [`Activity::step`].
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct CycleInfo {
    /// 0-based count of executed cycles (skipped slots are not counted).
    pub cycle: u64,
    /// Grid slot of this cycle (`cycle + skipped slots so far`).
    pub slot: u64,
    /// Grid period, ns.
    pub period_ns: u64,
    /// Absolute deadline this cycle was scheduled for, ns.
    pub deadline_ns: u64,
    /// Time the cycle actually started, ns (use this as "now").
    pub now_ns: u64,
    /// `now_ns − deadline_ns`.
    pub wake_latency_ns: u64,
    /// Execution time of the previous cycle, ns (0 for the first).
    pub last_exec_ns: u64,
    /// Overruns so far.
    pub overruns: u64,
    /// Skipped slots so far.
    pub skipped_slots: u64,
    /// Synchronized global time at the start of the cycle, µs (CLOCK_REALTIME since the UNIX
    /// epoch under the real shell; a fixed epoch plus the simulated time under a simulated
    /// clock). Only for SecOC freshness, which must mean the same on the sender and the
    /// receivers; the cycle's own timing uses the monotonic `now_ns`. Handed in, not read, so
    /// the cycle stays deterministic and clock-agnostic.
    pub sync_time_us: u64,
}

impl CycleInfo {
    /// Cycle `cycle` of a simulated loop with period `period_ns`, started on time at `now_ns`
    /// (slot = cycle, deadline = now, no latency, no overrun, no skipped slot): how the offline
    /// bench, the studies, the benches, the fuzz target and the tests drive the core. The
    /// synchronized time is 0 unless [`with_sync_time_us`](Self::with_sync_time_us) sets it.
    #[must_use]
    pub const fn on_time(cycle: u64, period_ns: u64, now_ns: u64) -> Self {
        Self {
            cycle,
            slot: cycle,
            period_ns,
            deadline_ns: now_ns,
            now_ns,
            wake_latency_ns: 0,
            last_exec_ns: 0,
            overruns: 0,
            skipped_slots: 0,
            sync_time_us: 0,
        }
    }

    /// The same cycle with the synchronized time (SecOC freshness) set, µs.
    #[must_use]
    pub const fn with_sync_time_us(self, sync_time_us: u64) -> Self {
        Self {
            sync_time_us,
            ..self
        }
    }
}

/// Why an output could not be written (hot path: `Copy`, no text).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum IoError {
    /// The CAN side is switched off (`--no-can`) or unavailable.
    CanDisabled,
    /// The CAN send queue is full (non-blocking send).
    CanWouldBlock,
    /// Any other CAN error.
    CanIo,
    /// The diagnostics channel failed.
    Ipc,
}

/// Receive errors of the shell's input ports since start (iceoryx2 `receive()` failures);
/// the core turns new ones into `IPC_ERROR` and the fault bit of the input concerned.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ReceiveErrors {
    /// On the object-state port.
    pub objects: u64,
    /// On the crash-accelerometer port.
    pub accel: u64,
    /// On the safing-accelerometer port (the independent second channel).
    pub safing: u64,
}

/// Why an activity refused to start.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StartupError {
    /// An I/O channel it needs failed.
    Io(IoError),
}

impl core::fmt::Display for StartupError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Io(e) => write!(f, "activity start-up: I/O failed ({e:?})"),
        }
    }
}

impl core::error::Error for StartupError {}

/// The I/O of one cycle. Every method is non-blocking and allocation-free in a real
/// implementation; inputs are drained oldest first.
pub trait CycleIo {
    /// Hands every object state received since the last call to `f`; returns the count.
    fn drain_objects(&mut self, f: &mut dyn FnMut(&ObjectState)) -> usize;
    /// Hands every accelerometer batch received since the last call to `f`.
    fn drain_accel(&mut self, f: &mut dyn FnMut(&CrashAccelSample)) -> usize;
    /// Hands every batch of the independent safing accelerometer received since the last
    /// call to `f` (same record as the crash accelerometer, its own sensor and port).
    fn drain_safing(&mut self, f: &mut dyn FnMut(&CrashAccelSample)) -> usize;
    /// Hands every batch of the crush-zone satellites' PSI5 frames received since the last
    /// call to `f`, with the satellite it came from. An I/O without satellites hands none
    /// (the default): the cycle then decides on its own sensors, as it does when they fail.
    fn drain_satellites(&mut self, f: &mut dyn FnMut(SatelliteSide, &SatelliteFrames)) -> usize {
        let _ = f;
        0
    }
    /// Hands every CAN frame received since the last call to `f` (none when CAN is off).
    fn drain_can(&mut self, f: &mut dyn FnMut(&RawFrame)) -> usize;
    /// Queues one CAN frame for sending.
    fn send_can(&mut self, frame: &RawFrame) -> Result<(), IoError>;
    /// Publishes one diagnostics record: `fill` writes it in place, into whatever the buffer
    /// held before ([`crate::RestraintCycle`] writes every field, so an I/O need not clear
    /// the buffer for it).
    fn publish_diagnostics(
        &mut self,
        fill: &mut dyn FnMut(&mut EcuDiagnostics),
    ) -> Result<(), IoError>;
    /// Whether the CAN side is active.
    fn can_enabled(&self) -> bool;
    /// Receive errors of the input ports since start (none by default).
    fn receive_errors(&self) -> ReceiveErrors {
        ReceiveErrors::default()
    }
}

/// The cycle logic as seen by a shell.
pub trait Activity {
    /// Short name for reports.
    fn name(&self) -> &'static str;

    /// Called once before the first cycle.
    fn startup(&mut self, now_ns: u64, io: &mut dyn CycleIo) -> Result<(), StartupError>;

    /// One cycle: drain inputs, decide, write outputs. Must not allocate, lock, block or
    /// panic; it is called at the grid deadlines with `info.now_ns` as "now".
    fn step(&mut self, info: &CycleInfo, io: &mut dyn CycleIo);

    /// Called once after the last cycle.
    fn shutdown(&mut self, now_ns: u64, io: &mut dyn CycleIo);

    /// Hands each named counter for the timing report (e.g. input staleness counts) to
    /// `out`; called after shutdown.
    fn report_counters(&self, out: &mut dyn FnMut(&'static str, u64)) {
        let _ = out;
    }
}
