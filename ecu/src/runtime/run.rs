//! The absolute-deadline cycle loop.

use std::sync::atomic::{AtomicBool, Ordering};

use super::deadline::DeadlineGrid;
use super::histogram::LatencyHistogram;
use host::{Clock, SleepOutcome};
use restraint::{Activity, CycleInfo, CycleIo};

/// Loop parameters.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LoopConfig {
    /// Grid period, ns (> 0).
    pub period_ns: u64,
    /// Stop after this many executed cycles (`None`: until the stop flag is set).
    pub max_cycles: Option<u64>,
}

/// Everything the loop measures. Create it (and its histograms) before the loop: the loop
/// itself only writes into it.
#[derive(Debug, Clone, Default)]
pub struct LoopStats {
    /// Executed cycles.
    pub cycles: u64,
    /// Cycles that ended at or after the next slot's deadline.
    pub overruns: u64,
    /// Grid slots skipped because of overruns.
    pub skipped_slots: u64,
    /// Sleeps interrupted by a signal.
    pub interrupted_sleeps: u64,
    /// Wake-up latency (actual wake − deadline), ns.
    pub wake_latency: LatencyHistogram,
    /// Cycle execution time (activity step), ns.
    pub exec: LatencyHistogram,
    /// Time of the first deadline, ns.
    pub first_deadline_ns: u64,
    /// Time the loop ended, ns.
    pub end_ns: u64,
}

/// Runs `activity`: `startup`, the cycle loop, `shutdown`.
///
/// The first deadline is one period after the call. Each iteration sleeps until the slot
/// deadline (absolute), runs one `step`, records wake latency and execution time into the
/// preallocated histograms and moves to the next slot of the grid (skipping past slots
/// on overrun). Stops when `stop` is set (checked before and after every sleep) or after
/// `cfg.max_cycles`. The loop body performs no allocation.
pub fn run_activity<C, A, IO>(
    clock: &mut C,
    activity: &mut A,
    io: &mut IO,
    cfg: &LoopConfig,
    stop: &AtomicBool,
    stats: &mut LoopStats,
) -> anyhow::Result<()>
where
    C: Clock + ?Sized,
    A: Activity + ?Sized,
    IO: CycleIo,
{
    let Some(grid) = DeadlineGrid::new(clock.now_ns().saturating_add(cfg.period_ns), cfg.period_ns)
    else {
        anyhow::bail!("cycle period must be > 0 ns");
    };
    activity.startup(clock.now_ns(), io)?;

    let mut slot = 0u64;
    let mut deadline_ns = grid.deadline_ns(0);
    stats.first_deadline_ns = deadline_ns;
    let mut last_exec_ns = 0u64;

    'cycles: loop {
        if stop.load(Ordering::Relaxed) || cfg.max_cycles.is_some_and(|m| stats.cycles >= m) {
            break;
        }
        while clock.sleep_until_ns(deadline_ns) == SleepOutcome::Interrupted {
            stats.interrupted_sleeps += 1;
            if stop.load(Ordering::Relaxed) {
                break 'cycles;
            }
        }
        let wake_ns = clock.now_ns();
        let sync_time_us = clock.sync_time_us();
        let wake_latency_ns = wake_ns.saturating_sub(deadline_ns);
        let info = CycleInfo {
            cycle: stats.cycles,
            slot,
            period_ns: grid.period_ns(),
            deadline_ns,
            now_ns: wake_ns,
            wake_latency_ns,
            last_exec_ns,
            overruns: stats.overruns,
            skipped_slots: stats.skipped_slots,
            sync_time_us,
        };
        activity.step(&info, io);
        let end_ns = clock.now_ns();
        last_exec_ns = end_ns.saturating_sub(wake_ns);

        stats.wake_latency.record_ns(wake_latency_ns);
        stats.exec.record_ns(last_exec_ns);
        stats.cycles += 1;

        let next = grid.next_slot(slot, end_ns);
        stats.overruns += u64::from(next.overrun);
        stats.skipped_slots += next.skipped;
        slot = next.slot;
        deadline_ns = next.deadline_ns;
    }

    stats.end_ns = clock.now_ns();
    activity.shutdown(stats.end_ns, io);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use host::SimClock;
    use restraint::{SimIo, StartupError};

    /// Models execution cost on the simulated clock and records what it saw.
    struct Scripted {
        clock: SimClock,
        exec_ns: fn(u64) -> u64,
        seen: Vec<CycleInfo>,
        started: bool,
        stopped: bool,
    }

    impl Activity for Scripted {
        fn name(&self) -> &'static str {
            "scripted"
        }
        fn startup(&mut self, _now_ns: u64, _io: &mut dyn CycleIo) -> Result<(), StartupError> {
            self.started = true;
            Ok(())
        }
        fn step(&mut self, info: &CycleInfo, _io: &mut dyn CycleIo) {
            self.seen.push(*info);
            self.clock.advance_ns((self.exec_ns)(info.cycle));
        }
        fn shutdown(&mut self, _now_ns: u64, _io: &mut dyn CycleIo) {
            self.stopped = true;
        }
    }

    fn run(
        period_ns: u64,
        cycles: u64,
        latency_ns: u64,
        exec_ns: fn(u64) -> u64,
    ) -> (Scripted, LoopStats) {
        let mut clock = SimClock::new(5_000);
        clock.set_wake_latency_ns(latency_ns);
        let mut act = Scripted {
            clock: clock.clone(),
            exec_ns,
            seen: Vec::new(),
            started: false,
            stopped: false,
        };
        let mut stats = LoopStats::default();
        run_activity(
            &mut clock,
            &mut act,
            &mut SimIo::new(),
            &LoopConfig {
                period_ns,
                max_cycles: Some(cycles),
            },
            &AtomicBool::new(false),
            &mut stats,
        )
        .unwrap();
        (act, stats)
    }

    #[test]
    fn steady_loop_runs_every_slot_on_the_grid() {
        let (act, stats) = run(1_000_000, 1_000, 20_000, |_| 150_000);
        assert!(act.started && act.stopped);
        assert_eq!(stats.cycles, 1_000);
        assert_eq!(stats.overruns, 0);
        for (k, info) in act.seen.iter().enumerate() {
            assert_eq!(info.slot, k as u64);
            assert_eq!(info.deadline_ns, 5_000 + (k as u64 + 1) * 1_000_000);
            assert_eq!(info.wake_latency_ns, 20_000);
            // The simulated synchronized time: fixed epoch + simulated time at wake-up.
            assert_eq!(
                info.sync_time_us,
                SimClock::SYNC_EPOCH_US + (info.deadline_ns + 20_000) / 1_000
            );
        }
        let w = stats.wake_latency.percentiles();
        assert!(w.p50_ns.abs_diff(20_000) <= 20, "{w:?}");
        let e = stats.exec.percentiles();
        assert!(e.max_ns.abs_diff(150_000) <= 150, "{e:?}");
    }

    #[test]
    fn overruns_skip_slots_without_drift() {
        // Every 10th cycle takes 3.5 periods: finishes at k + 3.5 → next slot k + 4.
        let (act, stats) = run(1_000_000, 100, 0, |c| {
            if c % 10 == 9 {
                3_500_000
            } else {
                100_000
            }
        });
        assert_eq!(stats.overruns, 10);
        assert_eq!(stats.skipped_slots, 30);
        let last = act.seen.last().unwrap();
        // 99 cycles before the last one, 9 of them long: slot 99 + 9·3.
        assert_eq!(last.slot, 99 + 27);
        assert_eq!(last.deadline_ns, 5_000 + (last.slot + 1) * 1_000_000);
    }

    #[test]
    fn stop_flag_ends_loop_before_first_cycle() {
        let mut clock = SimClock::new(0);
        let mut act = Scripted {
            clock: clock.clone(),
            exec_ns: |_| 0,
            seen: Vec::new(),
            started: false,
            stopped: false,
        };
        let mut stats = LoopStats::default();
        run_activity(
            &mut clock,
            &mut act,
            &mut SimIo::new(),
            &LoopConfig {
                period_ns: 1_000,
                max_cycles: None,
            },
            &AtomicBool::new(true),
            &mut stats,
        )
        .unwrap();
        assert_eq!(stats.cycles, 0);
        assert!(act.stopped);
    }
}
