//! The one in-memory [`CycleIo`] of the project: tests, benches and fuzz targets script
//! inputs into it and read what the cycle sent. Fixed capacity (`heapless`), so it allocates
//! nothing and can sit inside an allocation-counting test or an instruction-count bench.
//!
//! Queues behave like the shell's iceoryx2 ports with safe overflow: a full queue drops its
//! oldest entry (counted in `dropped`). Sent frames are kept as the newest [`SIM_QUEUE`] with a
//! running total, so a caller reads what one cycle sent with [`SimIo::sent_since`].

use bus::RawFrame;
use heapless::{Deque, HistoryBuf};

use crate::contract::{Activity, CycleInfo, CycleIo, IoError, ReceiveErrors};
use crate::signals::{
    CrashAccelSample, EcuDiagnostics, ObjectState, SatelliteFrames, SatelliteSide,
};

/// Capacity of every queue of [`SimIo`].
pub const SIM_QUEUE: usize = 64;

fn push_dropping_oldest<T, const N: usize>(q: &mut Deque<T, N>, item: T, dropped: &mut u64) {
    if q.is_full() {
        q.pop_front();
        *dropped = dropped.saturating_add(1);
    }
    // Cannot fail: a slot was freed above.
    let _ = q.push_back(item);
}

/// Scripted inputs and captured outputs.
#[derive(Debug, Clone)]
pub struct SimIo {
    /// Object states delivered on the next drain.
    pub objects: Deque<ObjectState, SIM_QUEUE>,
    /// Accelerometer batches delivered on the next drain.
    pub accel: Deque<CrashAccelSample, SIM_QUEUE>,
    /// Safing-accelerometer batches delivered on the next drain.
    pub safing: Deque<CrashAccelSample, SIM_QUEUE>,
    /// The left and the right satellite's frame batches delivered on the next drain.
    pub satellites: [Deque<SatelliteFrames, SIM_QUEUE>; 2],
    /// CAN frames delivered on the next drain.
    pub can_rx: Deque<RawFrame, SIM_QUEUE>,
    /// The newest frames sent (a ring that overwrites its oldest entry).
    pub can_tx: HistoryBuf<RawFrame, SIM_QUEUE>,
    /// Frames sent since creation.
    pub can_tx_total: u64,
    /// The newest diagnostics record.
    pub diagnostics: EcuDiagnostics,
    /// Diagnostics records published since creation.
    pub diagnostics_published: u64,
    /// Inputs dropped because their queue was full.
    pub dropped: u64,
    /// When false, CAN sends fail with [`IoError::CanDisabled`] and nothing is received.
    pub can_on: bool,
    /// Receive-error totals the I/O reports (tests raise them to inject iceoryx2 errors).
    pub receive_errors: ReceiveErrors,
}

impl Default for SimIo {
    fn default() -> Self {
        Self::new()
    }
}

impl SimIo {
    /// Empty queues, CAN on.
    pub const fn new() -> Self {
        Self {
            objects: Deque::new(),
            accel: Deque::new(),
            safing: Deque::new(),
            satellites: [Deque::new(), Deque::new()],
            can_rx: Deque::new(),
            can_tx: HistoryBuf::new(),
            can_tx_total: 0,
            diagnostics: EcuDiagnostics::ZERO,
            diagnostics_published: 0,
            dropped: 0,
            can_on: true,
            receive_errors: ReceiveErrors {
                objects: 0,
                accel: 0,
                safing: 0,
            },
        }
    }

    /// Queues an object state for the next cycle.
    pub fn push_object(&mut self, o: ObjectState) {
        push_dropping_oldest(&mut self.objects, o, &mut self.dropped);
    }

    /// Queues an accelerometer batch for the next cycle.
    pub fn push_accel(&mut self, a: CrashAccelSample) {
        push_dropping_oldest(&mut self.accel, a, &mut self.dropped);
    }

    /// Queues a safing-accelerometer batch for the next cycle.
    pub fn push_safing(&mut self, a: CrashAccelSample) {
        push_dropping_oldest(&mut self.safing, a, &mut self.dropped);
    }

    /// Queues a batch of `side`'s satellite frames for the next cycle.
    pub fn push_satellite(&mut self, side: SatelliteSide, f: SatelliteFrames) {
        if let Some(q) = self.satellites.get_mut(side as usize) {
            push_dropping_oldest(q, f, &mut self.dropped);
        }
    }

    /// Queues the same batch on the crash and the safing accelerometer: a car whose two
    /// sensors read exactly alike (benches and fuzz targets that exercise the cost or the
    /// robustness of the cycle, not the sensors' independence).
    pub fn push_both_accel(&mut self, a: CrashAccelSample) {
        self.push_accel(a);
        self.push_safing(a);
    }

    /// Queues a received CAN frame for the next cycle.
    pub fn push_can(&mut self, f: RawFrame) {
        push_dropping_oldest(&mut self.can_rx, f, &mut self.dropped);
    }

    /// The frames sent after the `total`-th (a value of [`SimIo::can_tx_total`] read before
    /// a cycle), as far as they are still kept.
    pub fn sent_since(&self, total: u64) -> impl Iterator<Item = &RawFrame> {
        let n = usize::try_from(self.can_tx_total.saturating_sub(total)).unwrap_or(usize::MAX);
        let kept = self.can_tx.len();
        self.can_tx.oldest_ordered().skip(kept.saturating_sub(n))
    }
}

impl CycleIo for SimIo {
    fn drain_objects(&mut self, f: &mut dyn FnMut(&ObjectState)) -> usize {
        let mut n = 0;
        while let Some(o) = self.objects.pop_front() {
            f(&o);
            n += 1;
        }
        n
    }

    fn drain_accel(&mut self, f: &mut dyn FnMut(&CrashAccelSample)) -> usize {
        let mut n = 0;
        while let Some(a) = self.accel.pop_front() {
            f(&a);
            n += 1;
        }
        n
    }

    fn drain_safing(&mut self, f: &mut dyn FnMut(&CrashAccelSample)) -> usize {
        let mut n = 0;
        while let Some(a) = self.safing.pop_front() {
            f(&a);
            n += 1;
        }
        n
    }

    fn drain_satellites(&mut self, f: &mut dyn FnMut(SatelliteSide, &SatelliteFrames)) -> usize {
        let mut n = 0;
        for (side, q) in SatelliteSide::BOTH
            .into_iter()
            .zip(self.satellites.iter_mut())
        {
            while let Some(b) = q.pop_front() {
                f(side, &b);
                n += 1;
            }
        }
        n
    }

    fn drain_can(&mut self, f: &mut dyn FnMut(&RawFrame)) -> usize {
        if !self.can_on {
            self.can_rx.clear();
            return 0;
        }
        let mut n = 0;
        while let Some(c) = self.can_rx.pop_front() {
            f(&c);
            n += 1;
        }
        n
    }

    fn send_can(&mut self, frame: &RawFrame) -> Result<(), IoError> {
        if !self.can_on {
            return Err(IoError::CanDisabled);
        }
        self.can_tx.write(*frame);
        self.can_tx_total = self.can_tx_total.saturating_add(1);
        Ok(())
    }

    fn publish_diagnostics(
        &mut self,
        fill: &mut dyn FnMut(&mut EcuDiagnostics),
    ) -> Result<(), IoError> {
        fill(&mut self.diagnostics);
        self.diagnostics_published = self.diagnostics_published.saturating_add(1);
        Ok(())
    }

    fn can_enabled(&self) -> bool {
        self.can_on
    }

    fn receive_errors(&self) -> ReceiveErrors {
        self.receive_errors
    }
}

/// The one virtual-time loop: an [`Activity`] run cycle after cycle on a simulated grid, every
/// cycle on time (cycle k starts at `start_ns + k · period_ns`, deadline = start, no latency,
/// no overrun). The offline bench, lut's estimation study, the benches and the core's tests
/// drive the core through it, so "cycle k at time t" means the same everywhere; the shell's
/// real-time loop (`ecu::runtime::run_activity`) is the other way to run an activity, on a
/// real or a simulated clock with late and skipped cycles.
///
/// It owns only time: the activity and the [`SimIo`] stay the caller's, who pushes each
/// cycle's inputs into the I/O before [`SimLoop::step`] and reads what the cycle sent with
/// [`SimLoop::sent`] after it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SimLoop {
    start_ns: u64,
    period_ns: u64,
    /// Synchronized time (µs) at simulated time 0; `None`: the cycles get 0 (no SecOC).
    sync_epoch_us: Option<u64>,
    cycle: u64,
    /// [`SimIo::can_tx_total`] before the last step.
    sent_before: u64,
}

impl SimLoop {
    /// A loop whose first cycle starts at `start_ns`, one cycle every `period_ns`.
    #[must_use]
    pub const fn new(start_ns: u64, period_ns: u64) -> Self {
        Self {
            start_ns,
            period_ns,
            sync_epoch_us: None,
            cycle: 0,
            sent_before: 0,
        }
    }

    /// Hands every cycle the synchronized time `epoch_us + now_ns / 1000` (SecOC freshness),
    /// as the shell's simulated clock does (`host::SimClock::SYNC_EPOCH_US`).
    #[must_use]
    pub const fn with_sync_epoch_us(self, epoch_us: u64) -> Self {
        Self {
            sync_epoch_us: Some(epoch_us),
            ..self
        }
    }

    /// Index of the next cycle (= cycles run so far).
    #[must_use]
    pub const fn cycle(&self) -> u64 {
        self.cycle
    }

    /// Start time of the next cycle, ns.
    #[must_use]
    pub const fn now_ns(&self) -> u64 {
        self.start_ns
            .saturating_add(self.cycle.saturating_mul(self.period_ns))
    }

    /// What the next cycle will be told.
    #[must_use]
    pub const fn next_info(&self) -> CycleInfo {
        let now = self.now_ns();
        let info = CycleInfo::on_time(self.cycle, self.period_ns, now);
        match self.sync_epoch_us {
            Some(epoch) => info.with_sync_time_us(epoch.saturating_add(now / 1_000)),
            None => info,
        }
    }

    /// Runs the next cycle of `activity` on `io`; its [`CycleInfo`].
    #[inline]
    pub fn step<A: Activity + ?Sized>(&mut self, activity: &mut A, io: &mut SimIo) -> CycleInfo {
        self.step_with(activity, io, |info| info)
    }

    /// [`SimLoop::step`] with the cycle's info edited first (a late deadline, a skipped slot):
    /// the tests of the core's timing checks.
    #[inline]
    pub fn step_with<A: Activity + ?Sized>(
        &mut self,
        activity: &mut A,
        io: &mut SimIo,
        edit: impl FnOnce(CycleInfo) -> CycleInfo,
    ) -> CycleInfo {
        let info = edit(self.next_info());
        self.sent_before = io.can_tx_total;
        activity.step(&info, io);
        self.cycle += 1;
        info
    }

    /// The frames the last step sent (as far as `io` still keeps them).
    pub fn sent<'io>(&self, io: &'io SimIo) -> impl Iterator<Item = &'io RawFrame> {
        io.sent_since(self.sent_before)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn full_queues_drop_the_oldest_and_sent_since_reads_one_cycle() {
        let mut io = SimIo::new();
        for i in 0..(SIM_QUEUE as u64 + 3) {
            let mut o = ObjectState::INVALID;
            o.sequence = i;
            io.push_object(o);
        }
        assert_eq!(io.dropped, 3);
        let mut first = None;
        assert_eq!(
            io.drain_objects(&mut |o| {
                first.get_or_insert(o.sequence);
            }),
            SIM_QUEUE
        );
        assert_eq!(first, Some(3));
        for id in 0..70u32 {
            io.send_can(&RawFrame::new(id, &[])).unwrap();
        }
        let before = io.can_tx_total;
        io.send_can(&RawFrame::new(0x30, &[1])).unwrap();
        io.send_can(&RawFrame::new(0x31, &[2])).unwrap();
        let ids: [u32; 2] = {
            let mut it = io.sent_since(before).map(|f| f.id);
            [it.next().unwrap(), it.next().unwrap()]
        };
        assert_eq!(ids, [0x30, 0x31]);
        assert_eq!(io.sent_since(before).count(), 2);
        io.can_on = false;
        assert_eq!(
            io.send_can(&RawFrame::new(1, &[])),
            Err(IoError::CanDisabled)
        );
    }

    /// Sends one frame per cycle carrying the cycle index and the synchronized time's low
    /// byte, so a test sees what each cycle was told.
    struct Echo;

    impl Activity for Echo {
        fn name(&self) -> &'static str {
            "echo"
        }
        fn startup(
            &mut self,
            _now_ns: u64,
            _io: &mut dyn CycleIo,
        ) -> Result<(), crate::contract::StartupError> {
            Ok(())
        }
        fn step(&mut self, info: &CycleInfo, io: &mut dyn CycleIo) {
            let _ = io.send_can(&RawFrame::new(
                0x100,
                &[info.cycle as u8, info.sync_time_us as u8],
            ));
            if info.cycle % 2 == 1 {
                let _ = io.send_can(&RawFrame::new(0x101, &[]));
            }
        }
        fn shutdown(&mut self, _now_ns: u64, _io: &mut dyn CycleIo) {}
    }

    #[test]
    fn the_virtual_loop_runs_every_cycle_on_its_grid() {
        let mut io = SimIo::new();
        let mut clock = SimLoop::new(5_000, 1_000_000).with_sync_epoch_us(7_000);
        for k in 0..5u64 {
            assert_eq!(clock.cycle(), k);
            assert_eq!(clock.now_ns(), 5_000 + k * 1_000_000);
            let info = clock.step(&mut Echo, &mut io);
            assert_eq!(
                (info.cycle, info.slot, info.now_ns, info.deadline_ns),
                (k, k, 5_000 + k * 1_000_000, 5_000 + k * 1_000_000)
            );
            assert_eq!(info.sync_time_us, 7_000 + info.now_ns / 1_000);
            assert_eq!(
                (info.wake_latency_ns, info.overruns, info.skipped_slots),
                (0, 0, 0)
            );
            // What this cycle sent, not what the earlier ones did.
            let sent: heapless::Vec<u32, 4> = clock.sent(&io).map(|f| f.id).collect();
            let want: &[u32] = if k % 2 == 1 {
                &[0x100, 0x101]
            } else {
                &[0x100]
            };
            assert_eq!(sent.as_slice(), want);
            assert_eq!(
                clock.sent(&io).next().map(|f| f.payload()[0]),
                Some(k as u8)
            );
        }
        // Without an epoch the cycles carry no synchronized time.
        assert_eq!(SimLoop::new(0, 1_000_000).next_info().sync_time_us, 0);
    }

    #[test]
    fn a_step_can_be_told_it_is_late() {
        let mut io = SimIo::new();
        let mut clock = SimLoop::new(0, 1_000_000);
        clock.step(&mut Echo, &mut io);
        let info = clock.step_with(&mut Echo, &mut io, |i| CycleInfo {
            deadline_ns: i.now_ns - 300_000,
            wake_latency_ns: 300_000,
            ..i
        });
        assert_eq!(
            (info.cycle, info.now_ns, info.deadline_ns),
            (1, 1_000_000, 700_000)
        );
        assert_eq!(
            clock.now_ns(),
            2_000_000,
            "the grid does not move with a late cycle"
        );
    }
}
