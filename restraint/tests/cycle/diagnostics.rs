//! The cycle writes every field of its diagnostics record, so an I/O may hand it the
//! previous record's buffer without clearing it (the shell's triple buffer, `SimIo`).

use crate::cycle_support::{Bench, MS, T0};
use restraint::{EcuDiagnostics, PULSE_POINTS};

/// A record whose every field differs from anything the cycle writes in these runs.
fn garbage() -> EcuDiagnostics {
    EcuDiagnostics {
        timestamp_ns: u64::MAX,
        cycle_count: u64::MAX,
        overrun_count: u64::MAX,
        last_exec_ns: u64::MAX,
        wake_latency_ns: u64::MAX,
        last_object_sequence: u64::MAX,
        last_accel_sequence: u64::MAX,
        object_samples_rx: u64::MAX,
        accel_batches_rx: u64::MAX,
        predicted_delta_v_mps: -1.0e9,
        predicted_a_max_mps2: -1.0e9,
        predicted_a_mean_mps2: -1.0e9,
        predicted_contact_time_s: -1.0e9,
        time_to_contact_s: -1.0e9,
        time_to_contact_sigma_s: -1.0e9,
        closing_speed_mps: -1.0e9,
        closing_speed_sigma_mps: -1.0e9,
        opponent_mass_kg: -1.0e9,
        opponent_mass_sigma_kg: -1.0e9,
        pulse_dt_s: -1.0e9,
        pulse_accel_mps2: [-1.0e9; PULSE_POINTS],
        pulse_points: u32::MAX,
        belt_force_limit_n: -1.0e9,
        pretensioner_time_s: -1.0e9,
        airbag_time_s: -1.0e9,
        airbag_stage: u8::MAX,
        mode: u8::MAX,
        pretensioner_fired: u8::MAX,
        airbag_fired: u8::MAX,
        degraded_reasons: u32::MAX,
    }
}

/// Runs the same scenario from a zeroed and from a garbage record before every step.
fn records(with_prediction: bool) -> (Vec<EcuDiagnostics>, Vec<EcuDiagnostics>) {
    let run = |dirty: bool| {
        let mut b = Bench::new(Some(crate::cycle_support::test_lut()));
        let contact = T0 + 250 * MS;
        for k in 0..60 {
            if with_prediction && k % 10 == 0 {
                b.push_approach(contact, 15.0, 1500.0, 100.0);
            }
            b.io.diagnostics = if dirty {
                garbage()
            } else {
                EcuDiagnostics::ZERO
            };
            b.step();
        }
        b.diagnostics
    };
    (run(false), run(true))
}

fn same(a: &EcuDiagnostics, b: &EcuDiagnostics) -> bool {
    // Compared as text, so that NaN (no time to contact) equals itself.
    let text = |d: &EcuDiagnostics| format!("{d:?}");
    text(a) == text(b)
}

#[test]
fn every_field_is_written_with_and_without_a_prediction() {
    for with_prediction in [false, true] {
        let (clean, dirty) = records(with_prediction);
        for (k, (c, d)) in clean.iter().zip(&dirty).enumerate() {
            assert!(same(c, d), "cycle {k}: {c:?} vs {d:?}");
        }
        if with_prediction {
            assert!(clean.last().is_some_and(|d| d.pulse_points > 0));
        }
    }
}

fn counter(b: &crate::cycle_support::Bench, name: &str) -> u64 {
    b.counter(name)
}

/// The wait for the first object is counted as stale but not as lost: a bench asking "did the
/// ECU notice the object list die?" must not see how fast the feeds came up. The oracle is the
/// default object timeout (100 ms): a 400 ms silence after fresh objects is ≈ 300 lost cycles.
#[test]
fn object_lost_cycles_count_dropouts_not_the_start_up_wait() {
    let mut b = Bench::new(Some(crate::cycle_support::test_lut()));
    b.run_ms(300);
    let startup_stale = counter(&b, "object_stale_cycles");
    assert!((299..=300).contains(&startup_stale), "{startup_stale}");
    assert_eq!(counter(&b, "object_lost_cycles"), 0);
    let contact = b.now + 5_000 * MS;
    let mut last_object = 0;
    for _ in 0..20 {
        last_object = b.now;
        b.push_approach(contact, 15.0, 1500.0, 100.0);
        b.run_ms(10);
    }
    assert_eq!(counter(&b, "object_stale_cycles"), startup_stale);
    assert_eq!(counter(&b, "object_lost_cycles"), 0);
    b.run_ms(400);
    // Steps at last_object + k ms, k = 0 … (now − last_object)/ms − 1; stale once k > 100.
    let silent_steps = (b.now - last_object) / MS;
    let expected = silent_steps - 101;
    let lost = counter(&b, "object_lost_cycles");
    assert!(
        lost.abs_diff(expected) <= 1,
        "{lost} lost cycles, {expected} expected"
    );
    assert_eq!(counter(&b, "object_stale_cycles"), startup_stale + lost);
}
