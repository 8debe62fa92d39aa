//! The cycle writes every field of its diagnostics record, so an I/O may hand it the
//! previous record's buffer without clearing it (the shell's triple buffer, `SimIo`).

mod cycle_support;

use cycle_support::{Bench, MS, T0};
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
        let mut b = Bench::new(Some(cycle_support::test_lut()));
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
