//! Clocks: the real CLOCK_MONOTONIC one and a simulated one for deterministic tests.

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
    /// Current synchronized global time, µs (SecOC freshness; see
    /// [`super::CycleInfo::sync_time_us`]). Allocation-free.
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

impl Clock for MonotonicClock {
    fn now_ns(&self) -> u64 {
        // CLOCK_MONOTONIC with a valid pointer cannot fail (EINVAL/EFAULT only).
        match clock_gettime(ClockId::CLOCK_MONOTONIC) {
            Ok(ts) => timespec_to_ns(&ts),
            Err(_) => 0,
        }
    }

    fn sleep_until_ns(&mut self, deadline_ns: u64) -> SleepOutcome {
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

    /// CLOCK_REALTIME in µs since the UNIX epoch: the bench's synchronized time base (every
    /// process on the machine reads the same clock; a vehicle would use StbM/gPTP time).
    /// `clock_gettime` goes through the vDSO: no system call, no allocation.
    fn sync_time_us(&self) -> u64 {
        match clock_gettime(ClockId::CLOCK_REALTIME) {
            Ok(ts) => timespec_to_ns(&ts) / 1_000,
            Err(_) => 0,
        }
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
