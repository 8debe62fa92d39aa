//! Cyclic command frames follow the clock, not the cycle count: under scripted wake-up jitter
//! (0–0.7 ms) and 3 % overruns that skip a slot, the 10 ms repetitions of `BeltLimiterCmd`
//! keep a 10 ms mean and median period. (Timed from the cycle count, as before, the same run
//! gave mean 10.596 ms, median 10.577 ms, p99 11.757 ms: every late wake-up pushed all later
//! repetitions back.)

use crate::cycle_support::{Bench, MS, T0};

/// Deterministic xorshift for the scripted jitter (no test depends on the host's timing).
fn next(state: &mut u64) -> u64 {
    *state ^= *state << 13;
    *state ^= *state >> 7;
    *state ^= *state << 17;
    *state
}

#[test]
fn cyclic_commands_keep_their_period_under_jitter_and_skipped_slots() {
    // No LUT: DEGRADED on the reference restraint, so the belt command's content never
    // changes and every frame after the first is a cyclic repetition.
    let mut b = Bench::new(None);
    let mut rng = 0x2545_f491_4f6c_dd1d_u64;
    let mut slot = 0u64;
    while slot < 20_000 {
        let deadline = T0 + slot * MS;
        b.deadline = Some(deadline);
        b.now = deadline + next(&mut rng) % 700_000;
        b.step();
        slot += if next(&mut rng) % 100 < 3 { 2 } else { 1 };
    }
    let t: Vec<u64> = b.belt_frames().iter().map(|(t, _)| *t).collect();
    let mut d: Vec<u64> = t.windows(2).map(|w| w[1] - w[0]).collect();
    d.sort_unstable();
    let p = |q: f64| d[((d.len() - 1) as f64 * q) as usize] as f64 / 1e6;
    let mean = (t[t.len() - 1] - t[0]) as f64 / (t.len() - 1) as f64 / 1e6;
    eprintln!(
        "belt period: n {} mean {mean:.3} ms, median {:.3}, p99 {:.3}, max {:.3}",
        d.len(),
        p(0.5),
        p(0.99),
        p(1.0)
    );
    // 20 000 slots of 1 ms: one repetition per 10 ms of simulated time.
    assert!(
        (1_990..=2_000).contains(&d.len()),
        "{} repetitions",
        d.len()
    );
    assert!((mean - 10.0).abs() < 0.01, "mean period {mean:.3} ms");
    // Jitter is at most 0.7 ms either way; a skipped slot delays one repetition by 1 ms.
    assert!((p(0.5) - 10.0).abs() <= 0.35, "median {:.3} ms", p(0.5));
    assert!(
        p(0.0) >= 8.3 && p(1.0) <= 11.7,
        "{:.3}..{:.3} ms",
        p(0.0),
        p(1.0)
    );
}
