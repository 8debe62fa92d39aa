//! The crash phase's paths under a simulated 1 kHz clock: every path to Fire and the no-fire
//! cases each is tested against (README "Decision table"), the in-crash severity re-estimate,
//! and the crash accelerometer's faults — detected, reported on the bus within their limits,
//! before a crash that follows. Expected values are closed form (linear test LUT, onset ramps
//! k·v·t / m_ego, constant pulses), as in `cycle/scenarios.rs`.

use crate::cycle_support::*;
use bus::codec::{
    AirbagStageCmdCmdSource, AirbagStageCmdFire, EcuStatusEcuMode, OccupantClassificationBeltBuckle,
};
use restraint::crash::ConfirmKind;
use restraint::crash_match::{MatchState, Mismatch};
use restraint::{Degraded, EcuMode, Phase};

/// Contact of the standard approach.
const C: u64 = T0 + 1_000 * MS;

fn no_airbag_fired(b: &Bench) -> bool {
    b.airbag_frames()
        .iter()
        .all(|(_, f)| f.fire() == AirbagStageCmdFire::NoFire)
}

fn first_fire(b: &Bench) -> Option<(u64, bus::AirbagStageCmd)> {
    b.first_airbag_fire()
}

/// First step time from `from` on at which the diagnostics carry `reason`.
fn first_reason(b: &Bench, from: u64, reason: Degraded) -> Option<u64> {
    b.step_times
        .iter()
        .zip(&b.diagnostics)
        .find(|(t, d)| **t >= from && d.degraded_reasons & reason.bits() != 0)
        .map(|(t, _)| *t)
}

/// First EcuStatus frame from `from` on with the accelerometer fault bit and the fallback mode.
fn first_accel_fault_on_bus(b: &Bench, from: u64) -> Option<u64> {
    b.status_frames()
        .into_iter()
        .find(|(t, s)| {
            *t >= from
                && s.fault_accel_sensor()
                && s.ecu_mode() == EcuStatusEcuMode::ReferenceFallback
        })
        .map(|(t, _)| t)
}

// --- Path 1: the prediction-matched crash -------------------------------------------------

#[test]
fn a_misestimated_closing_speed_is_re_estimated_from_the_onset_and_re_planned() {
    // The radar says 20 m/s; the crash has the onset of 28 m/s (ratio 1.4: "departs").
    let mut b = Bench::new(Some(test_lut()));
    run_scenario(
        &mut b,
        C + 100 * MS,
        T0 + 200 * MS,
        C,
        20.0,
        C,
        Some(C),
        &|ms| ramp_g(28.0, ms),
    );
    let Some(ConfirmKind::Matched(e)) = b.ecu.crash_kind() else {
        panic!("{:?}", b.ecu.crash_kind());
    };
    assert!(!e.follows, "{e:?}");
    assert!((e.closing_mps / 28.0 - 1.0).abs() < 0.02, "{e:?}");
    // Ramp 33.9 m/s² per ms: Δv(C + k ms) = 33.9·k²/2 mm/s reaches the 0.3 m/s floor
    // (`match_min_dv_mps`) at k = 5 (0.271 at k = 4).
    assert_eq!(b.first_mode(EcuMode::Crash), Some(C + 5 * MS));
    // Re-planned at the measured speed (≈ 101 km/h) and the robust mass 1500 + 1200 kg.
    let plan = b.ecu.crash_plan();
    let (v, m) = (e.closing_mps * 3.6, 2700.0);
    assert!((f64::from(plan.belt_limiter_kn) - belt_kn(v, m)).abs() < 1e-4);
    assert!((f64::from(plan.airbag_time_ms) - airbag_ms(v, m)).abs() < 1e-3);
    let (t, f) = first_fire(&b).expect("adaptive airbag");
    assert_eq!(f.cmd_source(), AirbagStageCmdCmdSource::Adaptive);
    assert_eq!(f.force_level(), q(airbag_kn(v, m), 0.05));
    // 5 + 0.1·101 = 15.1 ms after the fitted onset (≈ C).
    assert!((C + 15 * MS..=C + 16 * MS).contains(&t), "{t}");
}

#[test]
fn a_pulse_the_prediction_cannot_explain_goes_the_conventional_way() {
    // Predicted 25 m/s, but the onset is that of 8 m/s (ratio 0.32 < 0.5): not this crash.
    // Then a 15 g plateau: the generic thresholds confirm and the accelerometer-only
    // algorithm fires the REFERENCE airbag.
    let mut b = Bench::new(Some(test_lut()));
    run_scenario(
        &mut b,
        C + 100 * MS,
        T0 + 200 * MS,
        C,
        25.0,
        C,
        Some(C),
        &|ms| if ms < 6 { ramp_g(8.0, ms) } else { 15.0 },
    );
    assert_eq!(
        b.ecu.crash().matcher().state(),
        MatchState::Mismatch(Mismatch::Severity)
    );
    assert!(matches!(
        b.ecu.crash_kind(),
        Some(ConfirmKind::Generic {
            prediction_refuted: true
        })
    ));
    let (t, f) = first_fire(&b).expect("reference airbag");
    assert_eq!(f.cmd_source(), AirbagStageCmdCmdSource::Reference);
    assert_eq!(f.force_level(), 12.0);
    // The reference time, 10 ms after the measured onset (the wake-up sample at C + 2 ms,
    // 1.97 g ≥ 1.5 g) — or, where later, the first sample at which the event's Δv reaches the
    // floor `fallback_min_dv_mps` (1.25 m/s: the accelerometer-only path may be
    // late where no-misuse-fires requires it). The Δv from the input itself: trapezoids from
    // the sample before the wake-up.
    let g = |ms: u64| if ms < 6 { ramp_g(8.0, ms) } else { 15.0 };
    let floor = restraint::CycleConfig::default().fallback_min_dv_mps;
    let mut dv = 0.0;
    let mut floor_ms = None;
    for ms in 2..100u64 {
        dv += 0.5 * f64::from(g(ms - 1) + g(ms)) * f64::from(G) * 1e-3;
        if dv >= floor {
            floor_ms = Some(ms);
            break;
        }
    }
    let floor_ms = floor_ms.expect("the plateau carries the floor");
    assert_eq!(t, C + 12.max(floor_ms) * MS);
}

#[test]
fn a_pothole_at_the_predicted_contact_of_an_avoided_collision_fires_nothing() {
    // The opponent swerves away 30 ms before the predicted contact (receding: avoided), and a
    // pothole hits the car at the predicted contact: 8 g for 2 ms. No ramp, no Δv: nothing
    // confirms, nothing fires, the pretensioner is released.
    let mut b = Bench::new(Some(test_lut()));
    run_scenario(
        &mut b,
        C - 30 * MS,
        T0 + 200 * MS,
        C,
        25.0,
        C,
        None,
        &|_| 0.0,
    );
    let mut o = object(b.now, -2.0, 1500.0, 100.0);
    o.distance_m = 3.0;
    b.io.push_object(o);
    run_scenario(
        &mut b,
        C + 200 * MS,
        u64::MAX,
        0,
        0.0,
        u64::MAX,
        Some(C),
        &|ms| if ms < 2 { 8.0 } else { 0.0 },
    );
    assert_eq!(b.first_mode(EcuMode::Crash), None);
    assert!(no_airbag_fired(&b));
    assert_eq!(b.ecu.pretensioner(), restraint::Pretensioner::Released);
}

#[test]
fn a_pothole_while_the_crash_is_still_predicted_does_not_match_and_does_not_confirm() {
    // The object still predicts contact at C (a sensor that has not seen the swerve yet): a
    // 2 ms, 8 g pothole at C is a step, not the predicted ramp — mismatch (shape), and it
    // carries no Δv for the generic thresholds. Nothing fires.
    let mut b = Bench::new(Some(test_lut()));
    run_scenario(
        &mut b,
        C + 40 * MS,
        T0 + 200 * MS,
        C,
        25.0,
        C,
        Some(C),
        &|ms| if ms < 2 { 8.0 } else { 0.0 },
    );
    assert!(matches!(
        b.ecu.crash().matcher().state(),
        MatchState::Mismatch(_) | MatchState::Idle
    ));
    assert_eq!(b.first_mode(EcuMode::Crash), None);
    assert!(no_airbag_fired(&b));
}

// --- Path 3: the accelerometer-only algorithm ----------------------------------------------

#[test]
fn without_a_prediction_a_bump_fires_nothing_and_a_severe_crash_fires_the_reference_in_time() {
    // Monitoring ("no track" objects): a 4.5 g bump (Δv grows 0.044 m/s per ms, under the
    // boundary), and a 20 g crash (0.196 m/s per ms: over the boundary at τ = 1 ms).
    let mut b = Bench::new(Some(test_lut()));
    run_scenario(
        &mut b,
        C + 100 * MS,
        u64::MAX,
        0,
        0.0,
        u64::MAX,
        Some(C),
        &|ms| {
            if ms < 40 {
                4.5
            } else {
                0.0
            }
        },
    );
    assert!(
        b.first_mode(EcuMode::Crash).is_some(),
        "the bump is a crash for the belt"
    );
    assert!(no_airbag_fired(&b));
    let mut b = Bench::new(Some(test_lut()));
    run_unpredicted_crash(&mut b, C, 20.0);
    let (t, f) = first_fire(&b).expect("reference airbag");
    assert_eq!(f.cmd_source(), AirbagStageCmdCmdSource::Reference);
    // The reference fires when the accelerometer-only algorithm decides: 20 g carries the
    // airbag's floor in the 7th ms, well before the paper's nominal 10 ms.
    assert_eq!(t, floor_reached_at(C, 20.0));
    assert!(t < C + 10 * MS);
}

#[test]
fn the_conventional_airbags_must_fire_fires_the_pretensioner_at_the_same_instant() {
    // No prediction, a constant 12 g crash: Δv grows 12 g × 1 ms = 0.118 m/s per sample, over
    // the airbag's boundary and its 1.25 m/s floor at τ ≈ 11 ms; the pretensioner's own floor
    // (1.5 m/s) only at 1.5 / 0.118 = 12.7 ms. A crash that needs the airbag needs the belt at
    // the same instant, never after it.
    let cfg = restraint::CycleConfig::default();
    assert!(cfg.pretensioner_min_dv_mps > cfg.fallback_min_dv_mps);
    let mut b = Bench::new(Some(test_lut()));
    run_unpredicted_crash(&mut b, C, 12.0);
    let (bag, _) = first_fire(&b).expect("reference airbag");
    let (pretensioner, _) = b.first_pretensioner_fire().expect("pretensioner");
    let own_floor_ns = C + (cfg.pretensioner_min_dv_mps / (12.0 * f64::from(G)) * 1e9) as u64;
    assert_eq!(pretensioner, bag);
    assert!(bag < own_floor_ns, "{} ms", (bag - C) as f64 * 1e-6);
}

// --- Accelerometer faults ---------------------------------------------------------------

#[test]
fn a_dead_accelerometer_is_on_the_bus_within_its_timeout_plus_one_status_period() {
    // Timeout 50 ms, EcuStatus every 20 ms and on change: on the bus within 70 ms.
    let mut b = Bench::new(Some(test_lut()));
    idle_until(&mut b, T0 + 300 * MS);
    b.accel_live = false;
    let dead_from = b.now; // last sample at dead_from − 1 ms
    idle_until(&mut b, T0 + 500 * MS);
    // Stale strictly after 50 ms without a batch (received at dead_from − 1 ms).
    assert_eq!(
        first_reason(&b, dead_from, Degraded::ACCEL_STALE),
        Some(dead_from + 50 * MS)
    );
    assert_eq!(b.mode_at(dead_from + 50 * MS), EcuMode::Degraded as u8);
    let on_bus = first_accel_fault_on_bus(&b, dead_from).expect("FaultAccelSensor on the bus");
    assert!(
        on_bus <= dead_from + 70 * MS,
        "{} ms",
        (on_bus - dead_from) / MS
    );
    // Back: healthy on the first batch.
    b.accel_live = true;
    let back = b.now;
    idle_until(&mut b, back + 10 * MS);
    assert_eq!(b.mode_at(back), EcuMode::Monitoring as u8);
}

#[test]
fn a_stuck_accelerometer_is_flagged_after_the_stuck_time() {
    let mut b = Bench::new(Some(test_lut()));
    idle_until(&mut b, T0 + 300 * MS);
    b.accel_dither = false; // bit-identical 0.0 from now on
    let from = b.now;
    idle_until(&mut b, T0 + 400 * MS);
    // 20 ms of identical readings: the 21st identical sample (from + 20 ms) is stuck.
    assert_eq!(
        first_reason(&b, from, Degraded::ACCEL_INVALID),
        Some(from + 20 * MS)
    );
    assert!(first_accel_fault_on_bus(&b, from).is_some_and(|t| t <= from + 40 * MS));
    assert_eq!(b.ecu.crash().confirmation(), None);
}

#[test]
fn saturated_out_of_range_and_time_travelling_samples_are_implausible_at_once() {
    for (what, reading) in [
        ("saturated", -200.0 * G),
        ("out of range", -1.0e6),
        ("not a number", f32::NAN),
    ] {
        let mut b = Bench::new(Some(test_lut()));
        idle_until(&mut b, T0 + 100 * MS);
        let t = b.now;
        b.push_accel(reading);
        idle_until(&mut b, T0 + 200 * MS);
        assert_eq!(
            first_reason(&b, T0, Degraded::ACCEL_INVALID),
            Some(t),
            "{what}"
        );
        // Held 500 ms, and never integrated: no crash from a saturated sensor.
        assert_eq!(b.ecu.crash().confirmation(), None, "{what}");
        assert!(no_airbag_fired(&b), "{what}");
    }
    // A batch older than the last one (non-monotonic time).
    let mut b = Bench::new(Some(test_lut()));
    idle_until(&mut b, T0 + 100 * MS);
    b.io.push_accel(accel_batch(b.now - 50 * MS, 0.3));
    let t = b.now;
    idle_until(&mut b, T0 + 150 * MS);
    assert_eq!(first_reason(&b, T0, Degraded::ACCEL_INVALID), Some(t));
}

#[test]
fn ipc_receive_errors_set_their_reason_and_the_fault_bit_of_their_input() {
    let mut b = Bench::new(Some(test_lut()));
    idle_until(&mut b, T0 + 100 * MS);
    b.io.receive_errors.accel += 1;
    let t = b.now;
    idle_until(&mut b, T0 + 700 * MS);
    assert_eq!(first_reason(&b, T0, Degraded::IPC_ERROR), Some(t));
    assert!(first_accel_fault_on_bus(&b, t).is_some_and(|x| x <= t + 20 * MS));
    // Held 500 ms after the error, then healthy.
    assert_eq!(b.mode_at(t + 500 * MS), EcuMode::Degraded as u8);
    assert_eq!(b.mode_at(t + 501 * MS), EcuMode::Monitoring as u8);
    b.io.receive_errors.objects += 3;
    let t = b.now;
    idle_until(&mut b, t + 30 * MS);
    assert!(b
        .status_frames()
        .iter()
        .any(|(x, s)| *x >= t && s.fault_object_input() && !s.fault_accel_sensor()));
}

// --- Path 2: a dead accelerometer at a predicted crash ------------------------------------

/// The approach to C with the accelerometer dead from C − 400 ms; from `decel_at` on the
/// vehicle frames report `decel_g` of deceleration.
fn dead_accel_crash(b: &mut Bench, closing_mps: f32, decel_at: u64, decel_g: f32) {
    while b.now < C + 200 * MS {
        b.accel_live = b.now < C - 400 * MS;
        if b.now >= decel_at {
            b.ego_long_accel_mps2 = -decel_g * G;
        }
        let next = b.now + MS;
        // The car's deceleration from `decel_at` on: the live safing sensor reads it.
        let g = if b.now >= decel_at { decel_g } else { 0.0 };
        run_scenario(b, next, T0 + 200 * MS, C, closing_mps, C, Some(C), &|_| g);
    }
}

#[test]
fn a_predicted_crash_with_a_dead_accelerometer_is_confirmed_by_the_vehicle_deceleration() {
    let mut b = Bench::new(Some(test_lut()));
    dead_accel_crash(&mut b, 25.0, C + 2 * MS, 8.0);
    // Flagged long before the crash (the safing sensor is healthy and sees the crash).
    assert!(first_accel_fault_on_bus(&b, C - 400 * MS).is_some_and(|t| t <= C - 330 * MS));
    assert_eq!(
        b.first_mode(EcuMode::PreCrash),
        None,
        "degraded: no adaptive preset"
    );
    // The first vehicle frame after the deceleration (every 10 ms: C + 10 ms) confirms.
    assert_eq!(b.ecu.crash_kind(), Some(ConfirmKind::Backup));
    let (t, f) = first_fire(&b).expect("reference airbag");
    assert_eq!(f.cmd_source(), AirbagStageCmdCmdSource::Reference);
    // At max(confirmation, contact + 10 ms), the contact measured by the healthy safing
    // sensor's onset (the deceleration starts at C + 2 ms, within the match window of the
    // predicted C): C + 12 ms.
    assert_eq!(t, C + 12 * MS);
}

#[test]
fn a_dead_accelerometer_fires_nothing_without_both_a_predicted_crash_and_a_crash_deceleration() {
    // Predicted crash, but the vehicle never decelerates beyond braking (avoided at the last
    // moment): no fire.
    let mut b = Bench::new(Some(test_lut()));
    dead_accel_crash(&mut b, 25.0, C, 1.0);
    assert_eq!(b.ecu.crash_kind(), None);
    assert!(no_airbag_fired(&b));
    // A crash deceleration 60 ms after the predicted contact (outside the ± 30 ms window).
    let mut b = Bench::new(Some(test_lut()));
    dead_accel_crash(&mut b, 25.0, C + 60 * MS, 8.0);
    assert!(no_airbag_fired(&b));
    // A predicted bump below the no-fire line (4 m/s): no fire even with the deceleration.
    let mut b = Bench::new(Some(test_lut()));
    dead_accel_crash(&mut b, 4.0, C + 2 * MS, 8.0);
    assert!(no_airbag_fired(&b));
    // No prediction at all (no object), crash deceleration on CAN: no fire.
    let mut b = Bench::new(Some(test_lut()));
    idle_until(&mut b, C - 400 * MS);
    b.accel_live = false;
    idle_until(&mut b, C);
    b.ego_long_accel_mps2 = -8.0 * G;
    idle_until(&mut b, C + 100 * MS);
    assert_eq!(b.ecu.crash_kind(), None);
    assert!(no_airbag_fired(&b));
    assert_ne!(b.ecu.phase(), Phase::Crash);
}

#[test]
fn a_matched_pulse_that_fires_nothing_ends_its_crash_phase_with_the_event() {
    // A crash phase ends with its event. Predicted at 20 m/s (72 km/h: below the closing
    // speed from which a matched crash may fire on the prediction alone, so its airbag waits
    // for the measured pulse). The object list stops at C (the opponent evaded); at C a pothole ramps exactly
    // like the predicted crash for 6 ms (≈ 0.44 m/s: the matcher confirms) and then falls
    // away — 0.7 m/s in all, below every floor. Nothing fires, and once the event is over the
    // ECU leaves CrashDetected and releases the reversible pre-crash pretensioner.
    let b = prediction_then_a_cresting_ramp(20.0, 4);
    assert!(
        b.first_mode(EcuMode::Crash).is_some(),
        "the pulse confirmed"
    );
    assert!(no_airbag_fired(&b));
    assert_ne!(
        b.mode_at(b.now - MS),
        EcuMode::Crash as u8,
        "stuck in CrashDetected"
    );
    // Degraded: the object list stopped (stale); not the crash phase.
    assert!(!matches!(b.ecu.phase(), Phase::Crash | Phase::PostCrash));
    assert_ne!(b.ecu.pretensioner(), restraint::Pretensioner::Fired);
}

#[test]
fn a_matched_pulse_that_leaves_its_ramp_before_the_planned_fire_is_decided_conventionally() {
    // A near miss, a kerb at a predicted contact. Predicted at 28 m/s (101 km/h: above
    // the closing speed from which a matched crash fires on its plan). The pulse ramps exactly
    // like the predicted crash for 6 ms — the matcher confirms at C + 5 ms, the plan's airbag
    // is due at ≈ C + 15 ms — and then falls to nothing within 2 ms, as a pothole or kerb
    // strike crests (0.8 m/s in all). The pulse left the matched ramp before the fire went out:
    // the accelerometer-only boundary decides the event, and it says no-fire.
    let b = prediction_then_a_cresting_ramp(28.0, 2);
    assert_eq!(b.first_mode(EcuMode::Crash), Some(C + 5 * MS), "matched");
    assert!(no_airbag_fired(&b), "{:?}", first_fire(&b));
    assert!(!matches!(b.ecu.phase(), Phase::Crash | Phase::PostCrash));
}

#[test]
fn a_crash_phase_whose_event_ended_unfired_follows_the_next_event() {
    // A road lobe at the predicted contact ramps like the predicted crash (20 m/s, below the
    // closing speed from which a matched crash fires on its plan alone) for 6 ms and falls in
    // 2 ms (≈ 0.58 m/s, under every floor): it confirms the crash phase and fires nothing.
    // Its event ends after the 10 ms quiet gap, with the sample at C + 18 ms; the crash itself
    // begins with the next one, 20 g constant, and the ECU reads both in one cycle (a batch
    // of several samples): no cycle sees the accelerometer quiet between the two events. The
    // crash's must-fire belongs to its own event, not the lobe's, and the crash phase follows
    // it: the reference airbag fires when the crash carries its floor, as for the same crash
    // with no lobe before it (`floor_reached_at`).
    let crash = C + 19 * MS;
    let pulse = |ms: u64| match ms {
        0..6 => ramp_g(20.0, ms),
        6..8 => ramp_g(20.0, 6) * (8 - ms) as f32 / 2.0,
        8..19 => 0.0,
        _ => 20.0,
    };
    let mut b = Bench::new(Some(test_lut()));
    run_scenario(
        &mut b,
        crash - MS,
        T0 + 200 * MS,
        C,
        20.0,
        C,
        Some(C),
        &pulse,
    );
    let confirmed = b.first_mode(EcuMode::Crash).expect("the lobe confirmed");
    assert!(
        confirmed < crash,
        "confirmed at {confirmed}, before the crash"
    );
    assert_eq!(b.ecu.phase(), Phase::Crash);
    // The quiet gap's last sample goes out with the next cycle's batch.
    let last_quiet = accel_batch(b.now, 0.0);
    b.io.push_accel(last_quiet);
    b.io.push_safing(last_quiet);
    b.now += MS;
    b.cycle += 1;
    run_scenario(
        &mut b,
        crash + 100 * MS,
        u64::MAX,
        0,
        0.0,
        0,
        Some(C),
        &pulse,
    );
    let (t, _) = first_fire(&b).expect("the crash fires the airbag");
    let floor = floor_reached_at(crash, 20.0);
    assert!(
        (floor..=floor + 2 * MS).contains(&t),
        "airbag at C + {} ms, floor at C + {} ms",
        (t - C) / MS,
        (floor - C) / MS
    );
}

/// A crash predicted at `closing_mps` for C (object list from 200 ms, until C) and a pulse at C
/// that ramps exactly like the predicted crash for 6 ms, then falls linearly to nothing over
/// `fall_ms` (a pothole or kerb strike that began like the crash and crested); 300 ms run on.
fn prediction_then_a_cresting_ramp(closing_mps: f64, fall_ms: u64) -> Bench {
    let mut b = Bench::new(Some(test_lut()));
    let crest = ramp_g(closing_mps, 6);
    run_scenario(
        &mut b,
        C + 300 * MS,
        T0 + 200 * MS,
        C,
        closing_mps as f32,
        C,
        Some(C),
        &|ms| {
            if ms < 6 {
                ramp_g(closing_mps, ms)
            } else if ms < 6 + fall_ms {
                crest * (6 + fall_ms - ms) as f32 / fall_ms as f32
            } else {
                0.0
            }
        },
    );
    b
}

/// The first ms k after C at which the 1 kHz samples `g(0..=k)` carry `floor_mps` since the
/// first sample at or above the 1.5 g wake threshold (trapezoidal rule, as the detectors
/// integrate): the closed-form instant a floor is reached.
fn floor_reached_ms(g: &dyn Fn(u64) -> f32, floor_mps: f64) -> u64 {
    let onset = (0..).find(|&k| g(k) >= 1.5).unwrap();
    let mut dv = 0.0;
    for k in onset + 1.. {
        dv += 0.5 * f64::from(g(k - 1) + g(k)) * f64::from(G) * 1e-3;
        if dv >= floor_mps {
            return k;
        }
    }
    unreachable!()
}

/// A crash predicted at 28 m/s for C (the standard approach) with the airbag's floor at
/// `floor_mps`, and the pulse `g(ms after C)`, run until `end`.
fn predicted_28_mps_with_airbag_floor(floor_mps: f64, end: u64, g: &dyn Fn(u64) -> f32) -> Bench {
    let cfg = restraint::CycleConfig {
        fallback_min_dv_mps: floor_mps,
        ..ideal_sensor_config()
    };
    let mut b = Bench::with_config(cfg, Some(test_lut()));
    run_scenario(&mut b, end, T0 + 200 * MS, C, 28.0, C, Some(C), g);
    b
}

#[test]
fn a_matched_airbag_waits_until_its_crash_carries_the_floor() {
    // A near miss: a pothole at the predicted contact can follow the predicted ramp
    // up to a +3 ms plan; no misuse event carries the floor. Floor raised to 2.5 m/s so that
    // it is reached after the plan (+15.1 ms, as above): the airbag waits for it.
    let g = |ms: u64| ramp_g(28.0, ms);
    let b = predicted_28_mps_with_airbag_floor(2.5, C + 100 * MS, &g);
    assert!(matches!(b.ecu.crash_kind(), Some(ConfirmKind::Matched(_))));
    let k = floor_reached_ms(&g, 2.5);
    assert!(k > 16, "the floor comes after the plan: {k}");
    let (t, f) = first_fire(&b).expect("adaptive airbag");
    assert_eq!(f.cmd_source(), AirbagStageCmdCmdSource::Adaptive);
    assert!(
        (C + k * MS..=C + (k + 1) * MS).contains(&t),
        "{t} vs C + {k} ms"
    );
}

#[test]
fn a_matched_pulse_that_follows_its_ramp_past_the_plan_below_the_floor_fires_no_airbag() {
    // The same crash prediction; the pulse follows the predicted ramp past the plan's airbag
    // time (+15.1 ms) and then stops: ≈ 2.2 m/s, below the (raised) 3 m/s airbag floor. The
    // matched airbag is never commanded. The event did carry the pretensioner's 1.5 m/s
    // floor, so the belt the pre-crash plan tensioned is latched as the crash's pretensioner
    // fire and the crash phase ends in post-crash (a pretensioner not yet fired would have
    // fired there too).
    let b = matched_ramp_stopped_at_without_airbag(17);
    assert_eq!(b.ecu.phase(), Phase::PostCrash);
}

#[test]
fn a_matched_pulse_below_both_floors_fires_nothing_and_ends_with_its_event() {
    // As above, stopped at +10 ms: ≈ 0.8 m/s, under the pretensioner's 1.5 m/s floor as a near
    // miss's pothole is. Nothing of the crash phase fires; the belt the pre-crash plan
    // tensioned is not latched and the crash phase ends with the event.
    let b = matched_ramp_stopped_at_without_airbag(10);
    assert!(!matches!(b.ecu.phase(), Phase::Crash | Phase::PostCrash));
}

/// The crash predicted at 28 m/s with the airbag's floor raised to 3 m/s, its pulse following
/// the predicted ramp until `stop_ms` after C and then stopping, run to C + 200 ms: checks it
/// was matched and fired no airbag.
fn matched_ramp_stopped_at_without_airbag(stop_ms: u64) -> Bench {
    let g = |ms: u64| if ms < stop_ms { ramp_g(28.0, ms) } else { 0.0 };
    let b = predicted_28_mps_with_airbag_floor(3.0, C + 200 * MS, &g);
    assert!(b.first_mode(EcuMode::Crash).is_some(), "matched");
    assert!(no_airbag_fired(&b), "{:?}", first_fire(&b));
    b
}

/// An approach of an `opp_kg` object closing at `closing_mps` for contact C (object list every
/// 10 ms from T0 + 200 ms until C, "no track" after; `objects`: false = no object at all), and
/// the pulse `pulse_g(ms after C)` on both sensors; runs until C + 300 ms.
fn crash_with_object(
    cfg: restraint::CycleConfig,
    objects: bool,
    closing_mps: f32,
    opp_kg: f32,
    pulse_g: &dyn Fn(u64) -> f32,
) -> Bench {
    let mut b = Bench::with_config(cfg, Some(test_lut()));
    while b.now < C + 300 * MS {
        if (b.now - T0).is_multiple_of(10 * MS) {
            if objects && b.now >= T0 + 200 * MS && b.now < C {
                b.push_approach(C, closing_mps, opp_kg, 100.0);
            } else {
                let mut o = restraint::ObjectState::INVALID;
                o.timestamp_ns = b.now;
                b.io.push_object(o);
            }
        }
        if b.now >= C {
            b.push_accel(-pulse_g((b.now - C) / MS) * G);
        }
        b.step();
    }
    b
}

#[test]
fn a_tracked_low_speed_crash_with_a_kerb_strike_fires_no_airbag_unless_it_is_far_more_severe() {
    // The tracked low-speed limit. A tracked object closing at 4.2 m/s (15 km/h; EBS < 20 km/h
    // even 1 200 kg heavier than its 1 500 kg): the airbag needs the event's Δv above closing × 1.3 + 1.2 =
    // 6.66 m/s. A 15 g × 40 ms pulse (5.9 m/s: a low-speed crash with a kerb strike on top,
    // which the conventional boundary alone fires) stays below it.
    let cfg = ideal_sensor_config;
    let low = |ms: u64| if ms < 40 { 15.0 } else { 0.0 };
    let b = crash_with_object(cfg(), true, 4.2, 1500.0, &low);
    assert!(b.first_mode(EcuMode::Crash).is_some(), "confirmed");
    assert!(no_airbag_fired(&b), "{:?}", first_fire(&b));
    // The same pulse without the tracked object: the accelerometer-only boundary fires it, so
    // it is the low-speed limit that holds the airbag back.
    let b = crash_with_object(cfg(), false, 4.2, 1500.0, &low);
    assert!(
        first_fire(&b).is_some(),
        "the pulse alone fires (else the test shows nothing)"
    );
    // Far more severe than the tracked object can make it (25 g × 60 ms = 14.7 m/s): fires,
    // once the event carried the limit.
    let severe = |ms: u64| if ms < 60 { 25.0 } else { 0.0 };
    let b = crash_with_object(cfg(), true, 4.2, 1500.0, &severe);
    let (t, _) = first_fire(&b).expect("a crash beyond the limit fires");
    // Δv(k ms) ≈ 25 g · k ms = 0.245 k m/s: 6.66 m/s at k ≈ 27.
    assert!(
        (C + 26 * MS..=C + 30 * MS).contains(&t),
        "{}",
        (t - C) as f64 * 1e-6
    );
}

#[test]
fn a_standing_object_is_not_credited_with_its_reported_mass() {
    // A tracked object closing at 7.8 m/s (28 km/h) reported at 3 000 kg: 1 200 kg heavier it
    // puts a moving opponent's crash at an EBS of 19.6 km/h, under the 20 km/h line, and the
    // low-speed limit (7.8 × 1.3 + 1.2 = 11.3 m/s) holds the airbag back from a 15 g × 40 ms
    // pulse (5.9 m/s). Standing (its closing speed the ego's own), it may be a wall the
    // object sensor cannot weigh: its EBS is the closing speed, 28 km/h, and the
    // conventional boundary decides — and fires.
    let pulse = |ms: u64| if ms < 40 { 15.0 } else { 0.0 };
    let run = |ego_speed_mps: f32| {
        let mut b = Bench::with_config(ideal_sensor_config(), Some(test_lut()));
        b.ego_speed_mps = ego_speed_mps;
        while b.now < C + 300 * MS {
            if (b.now - T0).is_multiple_of(10 * MS) && b.now >= T0 + 200 * MS && b.now < C {
                b.push_approach(C, 7.8, 3000.0, 100.0);
            }
            if b.now >= C {
                b.push_accel(-pulse((b.now - C) / MS) * G);
            }
            b.step();
        }
        assert!(b.first_mode(EcuMode::Crash).is_some(), "confirmed");
        first_fire(&b)
    };
    assert!(run(15.0).is_none(), "a moving 3 000 kg opponent: held");
    assert!(run(7.8).is_some(), "a standing object: the boundary fires");
}

/// How long the low-speed crash below ramps like the prediction before it levels off, ms.
const RAMP_MS: u64 = 8;

#[test]
fn an_opponent_reported_heavy_does_not_move_a_low_speed_crash_across_the_no_fire_line() {
    // A misreported low-speed crash. 14.5 + 14.5 km/h (8.06 m/s closing) against an equal car
    // reported as 4 000 kg: EBS 20.0 km/h on the report (armed), 14.5 km/h in truth. The true pulse ramps
    // like the prediction (the onset slope is the structures' stiffness × closing speed, not
    // the mass) for 8 ms and then levels off at ≈ 8 g for 60 ms (≈ 4.5 m/s). Every layer says
    // no: below ≈ 83 km/h closing a matched plan does not fire on the prediction alone, the
    // pulse leaves the matched ramp before it carries the floor, and the accelerometer-only
    // boundary is not reached.
    let pulse = |ms: u64| {
        if ms < 60 {
            ramp_g(8.06, ms.min(RAMP_MS))
        } else {
            0.0
        }
    };
    let b = crash_with_object(ideal_sensor_config(), true, 8.06, 4000.0, &pulse);
    assert!(b.first_mode(EcuMode::Crash).is_some(), "confirmed");
    assert!(no_airbag_fired(&b), "{:?}", first_fire(&b));
}

// --- The occupant's buckle ------------------------------------------------------------------

/// A constant 12 g crash without a prediction, judged with a belted airbag boundary out of
/// reach (50 m/s at every knot) and the default unbelted one, for the buckle `buckle` (`None`:
/// no occupant frame at all): whether the airbag fires.
fn conventional_airbag_for(buckle: Option<OccupantClassificationBeltBuckle>) -> bool {
    let cfg = restraint::CycleConfig {
        fallback_dv_mps: [50.0; restraint::fallback::KNOTS],
        ..ideal_sensor_config()
    };
    let mut b = Bench::with_config(cfg, Some(test_lut()));
    match buckle {
        Some(s) => b.buckle = s,
        None => b.send_occupant = false,
    }
    run_unpredicted_crash(&mut b, C, 12.0);
    !no_airbag_fired(&b)
}

#[test]
fn an_occupant_not_known_to_be_belted_is_judged_against_the_unbelted_boundary() {
    // The belted boundary is out of reach; the unbelted one (the default) is crossed by 12 g
    // within its window. A switch fault, a missing state or a missing frame count as unbelted
    // (a failed buckle switch must not leave an unbelted occupant without the airbag).
    use OccupantClassificationBeltBuckle as Buckle;
    assert!(!conventional_airbag_for(Some(Buckle::Buckled)));
    assert!(conventional_airbag_for(Some(Buckle::Unbuckled)));
    assert!(conventional_airbag_for(Some(Buckle::SwitchFault)));
    assert!(conventional_airbag_for(Some(Buckle::NotAvailable)));
    assert!(conventional_airbag_for(None));
}
