//! The contract between the real-time shell and the cycle logic (FEO-style activity).
//!
//! The shell owns time, scheduling and I/O; the activity owns the decision. The activity
//! sees the world only through [`CycleIo`] and time only through [`CycleInfo`], so the
//! same code runs under the real clock with iceoryx2/CAN and under a simulated clock
//! with [`super::SimIo`].

use ipc::{CrashAccelSample, EcuDiagnostics, ObjectState};

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
    /// epoch under the real runtime; a fixed epoch plus the simulated time under
    /// [`super::SimClock`]). Only for SecOC freshness, which must mean the same on the sender
    /// and the receivers; the cycle's own timing uses the monotonic `now_ns`. Handed in, not
    /// read, so that the cycle stays deterministic and clock-agnostic.
    pub sync_time_us: u64,
}

/// A classic CAN frame as seen by the cycle (independent of the socket library).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct CanFrame {
    /// 11- or 29-bit identifier.
    pub id: u32,
    /// True for a 29-bit identifier.
    pub extended: bool,
    /// Data length 0..=8 (readers clamp larger values).
    pub len: u8,
    /// Payload; bytes past `len` are unspecified.
    pub data: [u8; 8],
}

impl CanFrame {
    /// The valid payload bytes (a corrupt `len` is clamped, never panics).
    pub fn payload(&self) -> &[u8] {
        let n = usize::from(self.len).min(8);
        self.data.get(..n).unwrap_or(&[])
    }
}

/// Why an output could not be written (hot path: `Copy`, no text).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum IoError {
    /// The CAN side is switched off (`--no-can`) or unavailable.
    CanDisabled,
    /// The CAN socket's send queue is full (non-blocking send).
    CanWouldBlock,
    /// Any other CAN socket error.
    CanIo,
    /// The iceoryx2 loan/send failed.
    Ipc,
}

/// The com layer of one cycle. Every method is non-blocking and allocation-free in the
/// real implementation; inputs are drained oldest first.
pub trait CycleIo {
    /// Hands every object state received since the last call to `f`; returns the count.
    fn drain_objects(&mut self, f: &mut dyn FnMut(&ObjectState)) -> usize;
    /// Hands every accelerometer batch received since the last call to `f`.
    fn drain_accel(&mut self, f: &mut dyn FnMut(&CrashAccelSample)) -> usize;
    /// Hands every CAN frame received since the last call to `f` (none when CAN is off).
    fn drain_can(&mut self, f: &mut dyn FnMut(&CanFrame)) -> usize;
    /// Queues one CAN frame for sending.
    fn send_can(&mut self, frame: &CanFrame) -> Result<(), IoError>;
    /// Publishes one diagnostics record: `fill` writes it in place into the loaned
    /// shared-memory chunk (pre-initialised to [`EcuDiagnostics::ZERO`]).
    fn publish_diagnostics(
        &mut self,
        fill: &mut dyn FnMut(&mut EcuDiagnostics),
    ) -> Result<(), IoError>;
    /// Whether the CAN side is active.
    fn can_enabled(&self) -> bool;
}

/// The cycle logic as seen by the shell.
pub trait Activity {
    /// Short name for reports.
    fn name(&self) -> &'static str;

    /// Called once before the first cycle (may allocate, may fail).
    fn startup(&mut self, now_ns: u64, io: &mut dyn CycleIo) -> anyhow::Result<()>;

    /// One cycle: drain inputs, decide, write outputs. Must not allocate, lock, block or
    /// panic; it is called at the grid deadlines with `info.now_ns` as "now".
    fn step(&mut self, info: &CycleInfo, io: &mut dyn CycleIo);

    /// Called once after the last cycle (may allocate).
    fn shutdown(&mut self, now_ns: u64, io: &mut dyn CycleIo);

    /// Named counters for the timing report (e.g. input staleness counts); called after
    /// shutdown.
    fn report_counters(&self, out: &mut Vec<(&'static str, u64)>) {
        let _ = out;
    }
}
