//! Drift-free deadline arithmetic on a fixed grid.
//!
//! Deadlines are `origin + slot · period`, never `previous wake + period`: adding the
//! period to a late wake-up would carry every wake-up delay into all later cycles
//! (drift). After an overrun the loop jumps to the first slot of the grid that still lies
//! in the future, so skipped slots are counted but never "caught up" in a burst.

/// A fixed schedule grid: slot `k` is due at `origin_ns + k · period_ns`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DeadlineGrid {
    origin_ns: u64,
    period_ns: u64,
}

/// Where the loop goes after finishing a slot.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct NextSlot {
    /// The slot to run next.
    pub slot: u64,
    /// Its absolute deadline (CLOCK_MONOTONIC ns).
    pub deadline_ns: u64,
    /// Slots that were skipped because their deadline had already passed.
    pub skipped: u64,
    /// True if the finished cycle ran past the following slot's deadline.
    pub overrun: bool,
}

impl DeadlineGrid {
    /// A grid starting at `origin_ns`; `None` for a zero period.
    pub fn new(origin_ns: u64, period_ns: u64) -> Option<Self> {
        (period_ns > 0).then_some(Self {
            origin_ns,
            period_ns,
        })
    }

    /// Grid period, ns.
    pub fn period_ns(&self) -> u64 {
        self.period_ns
    }

    /// Absolute deadline of `slot` (saturates instead of wrapping).
    pub fn deadline_ns(&self, slot: u64) -> u64 {
        self.origin_ns
            .saturating_add(slot.saturating_mul(self.period_ns))
    }

    /// The slot to run after `finished_slot`, given the time `now_ns` at which it
    /// finished: `finished_slot + 1` if its deadline is still in the future, otherwise
    /// the first slot whose deadline is strictly after `now_ns` (an overrun).
    pub fn next_slot(&self, finished_slot: u64, now_ns: u64) -> NextSlot {
        let candidate = finished_slot.saturating_add(1);
        let candidate_deadline = self.deadline_ns(candidate);
        if candidate_deadline > now_ns {
            return NextSlot {
                slot: candidate,
                deadline_ns: candidate_deadline,
                skipped: 0,
                overrun: false,
            };
        }
        // now_ns >= deadline(candidate) >= origin, so the subtraction cannot underflow;
        // period_ns > 0 by construction.
        let first_future = ((now_ns - self.origin_ns) / self.period_ns).saturating_add(1);
        let slot = first_future.max(candidate);
        NextSlot {
            slot,
            deadline_ns: self.deadline_ns(slot),
            skipped: slot - candidate,
            overrun: true,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const P: u64 = 1_000_000; // 1 ms

    #[test]
    fn zero_period_rejected() {
        assert!(DeadlineGrid::new(5, 0).is_none());
    }

    #[test]
    fn on_time_cycle_goes_to_next_slot() {
        let g = DeadlineGrid::new(10 * P, P).unwrap();
        // slot 3 due at 13 ms, finished at 13.4 ms → slot 4 at 14 ms.
        let n = g.next_slot(3, 13 * P + 400_000);
        assert_eq!(
            n,
            NextSlot {
                slot: 4,
                deadline_ns: 14 * P,
                skipped: 0,
                overrun: false
            }
        );
    }

    #[test]
    fn overrun_skips_to_first_future_slot_on_the_grid() {
        let g = DeadlineGrid::new(0, P).unwrap();
        // slot 0 finished at 3.2 ms: slots 1, 2, 3 are past; next is slot 4 at 4 ms.
        let n = g.next_slot(0, 3 * P + 200_000);
        assert_eq!(n.slot, 4);
        assert_eq!(n.deadline_ns, 4 * P);
        assert_eq!(n.skipped, 3);
        assert!(n.overrun);
    }

    #[test]
    fn finishing_exactly_on_next_deadline_is_an_overrun() {
        let g = DeadlineGrid::new(0, P).unwrap();
        let n = g.next_slot(0, P);
        assert!(n.overrun);
        assert_eq!(n.slot, 2);
        assert_eq!(n.skipped, 1);
    }

    #[test]
    fn deadlines_do_not_drift_under_late_wakeups_and_overruns() {
        // Simulated clock: every wake is 300 µs late, every 7th cycle takes 2.5 periods.
        let g = DeadlineGrid::new(1_000, P).unwrap();
        let mut slot = 0u64;
        let mut deadline = g.deadline_ns(0);
        let (mut skipped_total, mut overruns) = (0u64, 0u64);
        for cycle in 0..7_000u64 {
            let wake = deadline + 300_000;
            let exec = if cycle % 7 == 6 { 5 * P / 2 } else { 100_000 };
            let n = g.next_slot(slot, wake + exec);
            // Every deadline stays exactly on the grid, whatever happened before.
            assert_eq!((n.deadline_ns - 1_000) % P, 0);
            assert!(n.deadline_ns > wake + exec);
            skipped_total += n.skipped;
            overruns += u64::from(n.overrun);
            slot = n.slot;
            deadline = n.deadline_ns;
        }
        // Closed form: a short cycle ends at k + 0.4 P → slot k+1; a long one ends at
        // k + 2.8 P → slot k+3 (2 skipped). 1000 groups of (6 short + 1 long) = 9000 slots.
        assert_eq!(slot, 9_000);
        assert_eq!(skipped_total, 2_000);
        assert_eq!(overruns, 1_000);
        assert_eq!(deadline, 1_000 + 9_000 * P);
    }

    #[test]
    fn saturates_instead_of_wrapping() {
        let g = DeadlineGrid::new(u64::MAX - 10, P).unwrap();
        assert_eq!(g.deadline_ns(5), u64::MAX);
        let n = g.next_slot(u64::MAX, u64::MAX);
        assert_eq!(n.slot, u64::MAX);
    }
}
