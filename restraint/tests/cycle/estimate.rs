//! The track filter inside the cycle: what its outputs do to the decision, the LUT query and
//! the diagnostics record (the filter's own oracles are in `track_filter.rs`).

use crate::cycle_support::*;
use physics::{CollisionInput, CombinedSpring, ExactCollision, MassClass};
use restraint::{EcuMode, ObjectState, PULSE_POINTS};

/// Contact of the approach.
const C: u64 = T0 + 1_000 * MS;

/// An approach towards `C` at 25 m/s, sampled every 10 ms from T0 + 200 ms, measured
/// `latency` before it is delivered; `tamper` may change a sample (by its delivery time).
fn approach(
    b: &mut Bench,
    until: u64,
    latency: u64,
    tamper: &mut dyn FnMut(u64, &mut ObjectState),
) {
    while b.now < until {
        if (b.now - T0).is_multiple_of(10 * MS) && b.now >= T0 + 200 * MS && b.now < C {
            let t_meas = b.now - latency;
            let mut o = object(t_meas, 25.0, 1500.0, 100.0);
            o.distance_m = ((C - t_meas) as f64 * 1e-9 * 25.0) as f32;
            tamper(b.now, &mut o);
            b.io.push_object(o);
        }
        b.step();
    }
}

#[test]
fn latency_is_compensated_the_contact_instant_does_not_move() {
    // Samples 0 or 45 ms old on delivery: the track predicts to the cycle's time, so PRE-CRASH
    // starts at the same cycle — the first whose time to contact is below the 300 ms horizon
    // (with the σ knob neutral, see `oracle_config`).
    for latency in [0, 45 * MS] {
        let mut b = Bench::oracle(Some(test_lut()));
        approach(&mut b, C - 100 * MS, latency, &mut |_, _| {});
        assert_eq!(
            b.first_mode(EcuMode::PreCrash),
            Some(C - 299 * MS),
            "latency {latency}"
        );
        let d = b.diagnostics.last().unwrap();
        assert!(
            (d.time_to_contact_s - 0.101).abs() < 1e-6,
            "{}",
            d.time_to_contact_s
        );
        assert!((d.closing_speed_mps - 25.0).abs() < 1e-5);
    }
}

#[test]
fn the_decision_plans_with_the_contact_estimate_minus_k_sigma() {
    // Default config (k = 1): PRE-CRASH starts at the first cycle whose planned contact —
    // the estimate minus one σ, both as the diagnostics record reports them — is within the
    // horizon, earlier than with k = 0 (C − 299 ms).
    let mut b = Bench::new(Some(test_lut()));
    approach(&mut b, C - 100 * MS, 0, &mut |_, _| {});
    let entry = b.first_mode(EcuMode::PreCrash).expect("PRE-CRASH");
    let horizon_s = b.ecu.config().preset_horizon_ms * 1e-3;
    let k = b.ecu.config().track.contact_time_k;
    let planned = |d: &restraint::EcuDiagnostics| {
        f64::from(d.time_to_contact_s) - k * f64::from(d.time_to_contact_sigma_s)
    };
    let i = b.step_times.iter().position(|t| *t == entry).unwrap();
    // A new sample arrives every 10 ms: the planned contact is set at the sample's cycle.
    let d_entry = &b.diagnostics[i];
    assert!(planned(d_entry) < horizon_s + 1e-6, "{d_entry:?}");
    assert!(
        (C - 320 * MS..C - 299 * MS).contains(&entry),
        "entry {}",
        (C - entry) / MS
    );
    let sigma = f64::from(d_entry.time_to_contact_sigma_s);
    assert!(sigma > 0.0 && sigma < 0.02, "σ_t {sigma}");
    // Every σ is on the record while a track is held.
    for d in &b.diagnostics[i..] {
        assert!(d.time_to_contact_sigma_s > 0.0 && d.closing_speed_sigma_mps > 0.0);
        assert!((d.opponent_mass_kg - 1500.0).abs() < 1e-3);
        assert!(d.opponent_mass_sigma_kg > 0.0 && d.opponent_mass_sigma_kg <= 100.0);
    }
}

#[test]
fn an_outlier_is_counted_and_does_not_reach_the_lut() {
    // One sample with a 4 m distance error and a +10 m/s speed error in PRE-CRASH: with the
    // newest-sample estimate it would have looked the table up at 126 km/h (outside the
    // 108 km/h axis: reference restraint for the next 10 ms); the track rejects it.
    let bad_at = C - 150 * MS;
    let mut clean = Bench::oracle(Some(test_lut()));
    approach(&mut clean, C - 100 * MS, 0, &mut |_, _| {});
    let mut b = Bench::oracle(Some(test_lut()));
    approach(&mut b, C - 100 * MS, 0, &mut |t, o| {
        if t == bad_at {
            o.distance_m -= 4.0;
            o.closing_speed_mps += 10.0;
        }
    });
    let c = b.ecu.counters();
    assert_eq!(c.track_outliers, 1);
    assert_eq!(c.track_starts, 1);
    // Same plan and the same command frames as without the outlier.
    assert_eq!(b.ecu.plan(), clean.ecu.plan());
    let frames = |x: &Bench| {
        x.sent
            .iter()
            .map(|(t, f)| (*t, f.id, f.data))
            .collect::<Vec<_>>()
    };
    assert_eq!(frames(&b), frames(&clean));
}

#[test]
fn an_out_of_order_sample_is_refused() {
    // A sample measured before the track's newest one (a re-ordering transport): refused and
    // counted; the plan and the commands stay those of the clean run.
    let mut clean = Bench::oracle(Some(test_lut()));
    approach(&mut clean, C - 100 * MS, 0, &mut |_, _| {});
    let mut b = Bench::oracle(Some(test_lut()));
    approach(&mut b, C - 100 * MS, 0, &mut |t, o| {
        if t == C - 150 * MS {
            let t_meas = t - 15 * MS;
            *o = object(t_meas, 27.0, 1500.0, 100.0);
            o.distance_m = 3.0;
        }
    });
    assert_eq!(b.ecu.counters().track_refused, 1);
    assert_eq!(b.ecu.counters().track_outliers, 0);
    assert_eq!(b.ecu.plan(), clean.ecu.plan());
}

#[test]
fn the_prediction_and_its_pulse_follow_the_sample_and_complete_before_the_next() {
    let mut b = Bench::oracle(Some(test_lut()));
    // Up to the cycle of the sample at C − 150 ms (PRE-CRASH: LUT looked up), then the next
    // cycle (no sample: the prediction is solved), then 8 more (the pulse is sampled).
    approach(&mut b, C - 149 * MS, 0, &mut |_, _| {});
    let predictions = b.ecu.counters().predictions;
    b.run_ms(1);
    assert_eq!(b.ecu.counters().predictions, predictions + 1);
    let d0 = *b.diagnostics.last().unwrap();
    assert!(d0.predicted_delta_v_mps > 5.0, "{d0:?}");
    assert_eq!(
        d0.pulse_points, 0,
        "nothing sampled in the prediction's own cycle"
    );
    b.run_ms(8);
    let mut last = 0;
    for d in &b.diagnostics[b.diagnostics.len() - 8..] {
        assert!(d.pulse_points >= last, "monotonic fill");
        last = d.pulse_points;
    }
    let d = *b.diagnostics.last().unwrap();
    assert_eq!(
        d.pulse_points as usize, PULSE_POINTS,
        "complete before the next sample"
    );
    // The same points as the physics crate's sampler of the situation's collision: 25 m/s,
    // conservative mass 1600 kg (class 3 with the oracle config), default ego.
    let opp = physics::class_for_mass_kg(1600.0).unwrap();
    let spring =
        CombinedSpring::series(MassClass::new(4).unwrap().curve(), Some(opp.curve())).unwrap();
    let sol = ExactCollision::solve(&CollisionInput::with_defaults(
        &spring, 1785.0, 1600.0, 25.0,
    ))
    .unwrap();
    let dt = f64::from(d.pulse_dt_s);
    assert!((dt - 0.150 / 64.0).abs() < 1e-9);
    for (k, (p, q)) in d
        .pulse_accel_mps2
        .iter()
        .zip(sol.samples(0.150 / 64.0).unwrap())
        .enumerate()
    {
        assert!(
            (f64::from(*p) - q.ego_accel_mps2).abs() < 1e-3,
            "point {k}: {p} vs {q:?}"
        );
    }
    assert!(d.pulse_accel_mps2.iter().any(|a| *a < -100.0));
}

#[test]
fn the_estimate_is_frozen_from_crash_confirmation_on() {
    // Approach, then a 15 g pulse from contact: confirmed at C + 3 ms. Object samples that
    // keep arriving afterwards (a tracker still reporting the opponent) run no filter and no
    // LUT query: the plan is latched, those cycles belong to the crash phase.
    let mut b = Bench::oracle(Some(test_lut()));
    approach(&mut b, C, 0, &mut |_, _| {});
    while b.now < C + 5 * MS {
        b.push_accel(-15.0 * 9.806_65);
        b.step();
    }
    assert!(matches!(
        b.ecu.phase(),
        restraint::Phase::Crash | restraint::Phase::PostCrash
    ));
    let (lookups, starts) = (b.ecu.counters().lut_lookups, b.ecu.counters().track_starts);
    let situation = b.ecu.situation();
    for k in 0..5u64 {
        let mut o = object(b.now, 25.0, 1500.0, 100.0);
        o.distance_m = 0.1 * k as f32;
        b.io.push_object(o);
        b.push_accel(-15.0 * 9.806_65);
        b.run_ms(2);
    }
    assert_eq!(b.ecu.counters().lut_lookups, lookups);
    assert_eq!(b.ecu.counters().track_starts, starts);
    assert_eq!(b.ecu.situation(), situation);
    assert!(b.ecu.counters().objects_rx >= 5);
}
