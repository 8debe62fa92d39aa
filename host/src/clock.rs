//! Clocks: the real CLOCK_MONOTONIC one and a simulated one for deterministic tests, and the
//! synchronized time of SecOC freshness. Every bench process reads time through here.

use std::cell::Cell;
use std::rc::Rc;

use nix::sys::time::TimeSpec;
use nix::time::{clock_gettime, clock_nanosleep, ClockId, ClockNanosleepFlags};

/// Time source and absolute sleep of the cycle loop.
pub trait Clock {
    /// Current time, ns (monotonic, arbitrary epoch).
    fn now_ns(&self) -> u64;
    /// Sleeps until the absolute time `deadline_ns` (or returns early when a signal
    /// interrupts the sleep; the loop re-checks its stop flag and sleeps again).
    fn sleep_until_ns(&mut self, deadline_ns: u64) -> SleepOutcome;
    /// Current synchronized global time, µs (SecOC freshness: the ECU stamps its
    /// authenticators with it, the actuators check them against it). Allocation-free.
    fn sync_time_us(&self) -> u64;
}

/// How a sleep ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SleepOutcome {
    /// The deadline was reached.
    Reached,
    /// A signal interrupted the sleep before the deadline.
    Interrupted,
}

/// CLOCK_MONOTONIC with `clock_nanosleep(TIMER_ABSTIME)`.
///
/// Absolute sleeps are what makes the grid drift-free: the kernel wakes us at the grid
/// point itself, not "period after whenever we went to sleep".
#[derive(Debug, Default, Clone, Copy)]
pub struct MonotonicClock;

/// CLOCK_MONOTONIC now, ns: the bench's one time base for timestamps and deadlines, shared
/// by every process on the machine. CLOCK_MONOTONIC with a valid pointer cannot fail
/// (EINVAL/EFAULT only); 0 if it ever did.
pub fn monotonic_ns() -> u64 {
    match clock_gettime(ClockId::CLOCK_MONOTONIC) {
        Ok(ts) => timespec_to_ns(&ts),
        Err(_) => 0,
    }
}

/// CLOCK_REALTIME now, ns since the UNIX epoch (0 before 1970). Kernel receive timestamps of
/// SocketCAN frames are on this clock.
pub fn realtime_ns() -> u64 {
    match clock_gettime(ClockId::CLOCK_REALTIME) {
        Ok(ts) => timespec_to_ns(&ts),
        Err(_) => 0,
    }
}

/// The synchronized time of the bench, µs: CLOCK_REALTIME since the UNIX epoch (every process
/// on the machine reads the same clock; a vehicle would use StbM/gPTP time). The ECU stamps
/// its SecOC authenticators with it, the actuators judge freshness against it. 0 if the clock
/// is before 1970 (then nothing is fresh). `clock_gettime` goes through the vDSO: no system
/// call, no allocation.
pub fn sync_time_us() -> u64 {
    realtime_ns() / 1_000
}

/// Sleeps until CLOCK_MONOTONIC reaches `deadline_ns` (absolute: no drift accumulates), or a
/// signal interrupts the sleep.
pub fn sleep_until_ns(deadline_ns: u64) -> SleepOutcome {
    let secs = deadline_ns / 1_000_000_000;
    let nanos = deadline_ns % 1_000_000_000;
    let ts = TimeSpec::new(
        i64::try_from(secs).unwrap_or(i64::MAX),
        // < 1e9 always fits.
        nanos as _,
    );
    match clock_nanosleep(
        ClockId::CLOCK_MONOTONIC,
        ClockNanosleepFlags::TIMER_ABSTIME,
        &ts,
    ) {
        Ok(_) => SleepOutcome::Reached,
        Err(_) => SleepOutcome::Interrupted,
    }
}

/// Sleeps until CLOCK_MONOTONIC reaches `deadline_ns`, through any signal (for loops that do
/// not poll a stop flag between sleeps).
pub fn sleep_through_signals_until_ns(deadline_ns: u64) {
    while sleep_until_ns(deadline_ns) == SleepOutcome::Interrupted && monotonic_ns() < deadline_ns {
    }
}

impl Clock for MonotonicClock {
    fn now_ns(&self) -> u64 {
        monotonic_ns()
    }

    fn sleep_until_ns(&mut self, deadline_ns: u64) -> SleepOutcome {
        sleep_until_ns(deadline_ns)
    }

    fn sync_time_us(&self) -> u64 {
        sync_time_us()
    }
}

fn timespec_to_ns(ts: &TimeSpec) -> u64 {
    let s = u64::try_from(ts.tv_sec()).unwrap_or(0);
    let n = u64::try_from(ts.tv_nsec()).unwrap_or(0);
    s.saturating_mul(1_000_000_000).saturating_add(n)
}

/// A simulated clock: sleeping jumps time to the deadline plus a scripted wake latency;
/// the activity (or the test) advances time to model execution cost via [`SimClock::advance_ns`].
///
/// Cloning shares the same time, so a test can hand one clone to the loop and keep one.
#[derive(Debug, Clone, Default)]
pub struct SimClock {
    now: Rc<Cell<u64>>,
    wake_latency_ns: Rc<Cell<u64>>,
}

impl SimClock {
    /// Synchronized time at simulated time 0, µs since the UNIX epoch (2025-06-15 15:06:40
    /// UTC): a fixed value, so simulated runs are reproducible.
    pub const SYNC_EPOCH_US: u64 = 1_750_000_000_000_000;

    /// A clock at `start_ns`.
    pub fn new(start_ns: u64) -> Self {
        let c = Self::default();
        c.now.set(start_ns);
        c
    }

    /// Moves time forward by `dt_ns` (e.g. to model cycle execution time).
    pub fn advance_ns(&self, dt_ns: u64) {
        self.now.set(self.now.get().saturating_add(dt_ns));
    }

    /// Every following wake-up happens this long after its deadline.
    pub fn set_wake_latency_ns(&self, latency_ns: u64) {
        self.wake_latency_ns.set(latency_ns);
    }
}

impl Clock for SimClock {
    fn now_ns(&self) -> u64 {
        self.now.get()
    }

    /// [`SimClock::SYNC_EPOCH_US`] plus the simulated time: deterministic, and a plausible
    /// wall-clock value so that SecOC freshness behaves as on the bench.
    fn sync_time_us(&self) -> u64 {
        Self::SYNC_EPOCH_US.saturating_add(self.now.get() / 1_000)
    }

    fn sleep_until_ns(&mut self, deadline_ns: u64) -> SleepOutcome {
        let now = self.now.get();
        if deadline_ns > now {
            self.now
                .set(deadline_ns.saturating_add(self.wake_latency_ns.get()));
        }
        SleepOutcome::Reached
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn monotonic_clock_never_goes_back_and_sleep_reaches_deadline() {
        let mut c = MonotonicClock;
        let t0 = c.now_ns();
        let deadline = t0 + 200_000;
        while c.sleep_until_ns(deadline) == SleepOutcome::Interrupted {}
        let t1 = c.now_ns();
        assert!(t1 >= deadline, "woke at {t1} before deadline {deadline}");
    }

    #[test]
    fn real_sync_time_is_the_wall_clock() {
        let c = MonotonicClock;
        let before = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .unwrap()
            .as_micros();
        let sync = u128::from(c.sync_time_us());
        let after = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .unwrap()
            .as_micros();
        assert!(
            before <= sync && sync <= after,
            "{before} <= {sync} <= {after}"
        );
    }

    #[test]
    fn sim_clock_jumps_to_deadline_plus_latency() {
        let mut c = SimClock::new(100);
        c.set_wake_latency_ns(7);
        c.sleep_until_ns(1_000);
        assert_eq!(c.now_ns(), 1_007);
        // A deadline in the past does not move time.
        c.sleep_until_ns(500);
        assert_eq!(c.now_ns(), 1_007);
        let shared = c.clone();
        shared.advance_ns(3);
        assert_eq!(c.now_ns(), 1_010);
        shared.advance_ns(5_000);
        assert_eq!(c.sync_time_us(), 1_750_000_000_000_006);
    }
}
