//! Whole-scenario tests of the restraint cycle under a simulated 1 kHz clock.
//!
//! Expected times and values are closed form: the test LUT's cells are linear in closing
//! speed and opponent mass (multilinear interpolation reproduces them exactly), objects move
//! at constant speed (TTC = d / v; the track filter reproduces such noise-free samples
//! exactly, see `crate::cycle_support::oracle_config`), and the crash pulse is either the onset ramp
//! of the predicted collision (slope k·v/m_ego, k the series stiffness of the two fronts'
//! first segments: the prediction-matched path) or a constant deceleration (Δv after n
//! samples = (n − ½)·a·1 ms, trapezoidal from rest: the generic confirmation and the
//! accelerometer-only algorithm). Every command is decoded with the bus crate (CRC checked).

use crate::cycle_support::*;
use bus::codec::{
    AirbagStageCmdArm, AirbagStageCmdCmdSource, AirbagStageCmdFire, AirbagStageCmdStage,
    BeltLimiterCmdCmdSource, BeltLimiterCmdPretensionerCmd, EcuStatusEcuMode,
};
use restraint::crash::ConfirmKind;
use restraint::{Degraded, EcuMode, ObjectState, Phase, Pretensioner};

/// Contact of the standard approach scenario.
const C: u64 = T0 + 1_000 * MS;

#[test]
fn precrash_preset_pretensioner_at_planned_time_then_airbag_at_planned_time_and_level() {
    let mut b = Bench::oracle(Some(test_lut()));
    run_scenario(
        &mut b,
        C + 200 * MS,
        T0 + 200 * MS,
        C,
        25.0,
        C,
        Some(C),
        &|ms| ramp_g(25.0, ms),
    );

    // Oracle: 25 m/s = 90 km/h; every lookup is at the robust planning mass, the reported
    // 1500 kg + 1200 kg (`mass_misreport_kg`) = 2700 kg (above the conservative 1600 kg).
    let (v, m) = (90.0, 2700.0);
    // PRE-CRASH at the first cycle whose time to the predicted contact (extrapolated from
    // the newest sample) is below the 300 ms horizon: C − 299 ms.
    assert_eq!(b.first_mode(EcuMode::PreCrash), Some(C - 299 * MS));
    assert_eq!(b.mode_at(C - 300 * MS), EcuMode::Monitoring as u8);

    // Pretensioner: first Fire command at contact − 45 ms (1 ms cycle resolution), with the
    // pre-crash plan.
    let belts = b.belt_frames();
    let (t_pt, f) = belts
        .iter()
        .find(|(_, f)| f.pretensioner_cmd() == BeltLimiterCmdPretensionerCmd::Fire)
        .expect("pretensioner fired");
    assert_eq!(*t_pt, C - 45 * MS);
    assert!((f.load_limiter_level() - q(belt_kn(v, m), 0.05)).abs() < 1e-4);
    assert!((f.pretensioner_fire_time() - (-45.0)).abs() < 0.051);
    assert_eq!(f.cmd_source(), BeltLimiterCmdCmdSource::Adaptive);

    // Prediction-matched confirmation: the ramp (k·v/m_ego = 30.3 m/s² per ms) wakes the
    // detectors at C + 1 ms (3.1 g ≥ 1.5 g); at 1 kHz the fit needs 3 samples spanning ≥ 1 ms
    // (matched with the C + 3 ms sample, predicted slope, ratio 1, onset C), and the velocity
    // change since the onset must reach `match_min_dv_mps` = 0.3 m/s: trapezoids from the
    // 0 g sample at C give Δv(C + k ms) = 30.3·k²/2 mm/s = 0.136, 0.242, 0.379 m/s for
    // k = 3, 4, 5: confirmed with the C + 5 ms sample.
    assert_eq!(b.first_mode(EcuMode::Crash), Some(C + 5 * MS));
    let Some(ConfirmKind::Matched(e)) = b.ecu.crash_kind() else {
        panic!("not prediction-matched: {:?}", b.ecu.crash_kind());
    };
    assert!((e.ratio - 1.0).abs() < 0.01 && e.follows, "{e:?}");
    assert!(e.onset_ns.abs_diff(C) < 20_000, "fitted onset {e:?}");
    // The pulse follows the prediction: the preset plan (90 km/h, the robust mass) holds.
    let (v_re, m_robust) = (v, m);
    let plan = b.ecu.crash_plan();
    assert!(
        (f64::from(plan.belt_limiter_kn) - belt_kn(v_re, m_robust)).abs() < 1e-4,
        "{plan:?}"
    );
    assert!((f64::from(plan.airbag_level_kn) - airbag_kn(v_re, m_robust)).abs() < 1e-4);
    assert!((f64::from(plan.airbag_time_ms) - airbag_ms(v_re, m_robust)).abs() < 1e-3);
    // Airbag: first Fire in the cycle nearest onset + t_ab (≈ C + 14 ms), with the planned
    // stage and level (5.4 kN: Stage 1, between 1 and 6 kN).
    let due = e.onset_ns + (airbag_ms(v_re, m_robust) * 1e6) as u64;
    let fire_cycle = T0 + (due - T0 + MS / 2) / MS * MS;
    assert_eq!(fire_cycle, C + 14 * MS);
    let bags = b.airbag_frames();
    let (t_ab, a) = bags
        .iter()
        .find(|(_, f)| f.fire() == AirbagStageCmdFire::Fire)
        .expect("airbag fired");
    assert_eq!(*t_ab, fire_cycle);
    assert_eq!(a.arm(), AirbagStageCmdArm::Armed);
    assert_eq!(a.stage(), AirbagStageCmdStage::Stage1);
    assert!((a.force_level() - q(airbag_kn(v_re, m_robust), 0.05)).abs() < 1e-4);
    assert_eq!(a.cmd_source(), AirbagStageCmdCmdSource::Adaptive);
    // Never before confirmation, and armed during pre-crash.
    assert!(bags
        .iter()
        .filter(|(t, _)| *t < C + 3 * MS)
        .all(|(_, f)| f.fire() == AirbagStageCmdFire::NoFire));
    assert!(bags
        .iter()
        .filter(|(t, _)| *t >= C - 299 * MS)
        .all(|(_, f)| f.arm() == AirbagStageCmdArm::Armed));
    assert_eq!(b.first_mode(EcuMode::PostCrash), Some(fire_cycle));
    assert_eq!(b.ecu.phase(), Phase::PostCrash);

    // Cyclic + on change: never more than 10 ms between two frames of a command.
    for w in bags.windows(2) {
        assert!(w[1].0 - w[0].0 <= 10 * MS);
    }
    for w in belts.windows(2) {
        assert!(w[1].0 - w[0].0 <= 10 * MS);
    }
    // Status heartbeat ≤ 20 ms apart, and Deployed at the end.
    let st = b.status_frames();
    for w in st.windows(2) {
        assert!(w[1].0 - w[0].0 <= 20 * MS);
    }
    assert_eq!(st.last().unwrap().1.ecu_mode(), EcuStatusEcuMode::Deployed);
    assert_eq!(st.last().unwrap().1.lut_id(), test_lut().lut_id());
    // Every frame passes a strict receiver (alive counters consecutive per message).
    let mut rx = bus::E2eChecker::new();
    for (_, f) in &b.sent {
        rx.check(f.id, f.payload()).expect("E2E-valid stream");
    }
    // Diagnostics carry the predicted pulse.
    let d = b.diagnostics.last().unwrap();
    assert!(d.pulse_points > 10 && d.predicted_delta_v_mps > 5.0);
    assert!(d.pulse_accel_mps2.iter().any(|&a| a < -100.0));
}

#[test]
fn avoided_collision_releases_pretensioner_and_never_fires_the_airbag() {
    let mut b = Bench::oracle(Some(test_lut()));
    // Approach as before until the pretensioner has fired (C − 45 ms) ...
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
    assert_eq!(b.ecu.pretensioner(), Pretensioner::Fired);
    // ... then the opponent turns away: receding object. The track filter does not trust
    // the first samples that contradict the track (outliers, counted); the third in a row
    // (`track.max_outliers`) restarts the track from the newest sample, which recedes.
    let max_outliers = b.ecu.config().track.max_outliers;
    let mut t_avoid = b.now;
    for k in 0..max_outliers {
        assert_eq!(b.ecu.phase(), Phase::PreCrash, "sample {k}");
        let mut o = crate::cycle_support::object(b.now, -2.0, 1500.0, 100.0);
        o.distance_m = 3.0 + 0.02 * k as f32;
        b.io.push_object(o);
        t_avoid = b.now;
        b.step();
        b.run_ms(9);
    }
    assert_eq!(b.ecu.counters().track_outliers, u64::from(max_outliers - 1));
    assert_eq!(b.ecu.phase(), Phase::Monitoring);
    run_scenario(
        &mut b,
        C + 300 * MS,
        u64::MAX,
        0,
        0.0,
        u64::MAX,
        None,
        &|_| 0.0,
    );
    let belts = b.belt_frames();
    let (t_rel, _) = belts
        .iter()
        .find(|(_, f)| f.pretensioner_cmd() == BeltLimiterCmdPretensionerCmd::Release)
        .expect("released");
    assert_eq!(*t_rel, t_avoid);
    assert!(b
        .airbag_frames()
        .iter()
        .all(|(_, f)| f.fire() == AirbagStageCmdFire::NoFire));
    let last = b.airbag_frames().last().unwrap().1;
    assert_eq!(last.arm(), AirbagStageCmdArm::Disarmed);
}

#[test]
fn lost_object_counts_as_avoided() {
    let mut b = Bench::oracle(Some(test_lut()));
    run_scenario(
        &mut b,
        C - 20 * MS,
        T0 + 200 * MS,
        C,
        25.0,
        C,
        None,
        &|_| 0.0,
    );
    assert_eq!(b.ecu.phase(), Phase::PreCrash);
    // Tracker reports "no object" (valid = 0) from C − 20 ms on.
    run_scenario(
        &mut b,
        C + 200 * MS,
        u64::MAX,
        0,
        0.0,
        u64::MAX,
        None,
        &|_| 0.0,
    );
    assert_eq!(b.mode_at(C - 20 * MS), EcuMode::Monitoring as u8);
    assert_eq!(b.ecu.pretensioner(), Pretensioner::Released);
    assert!(!b.ecu.airbag_fired());
}

#[test]
fn stale_object_data_degrades_after_the_timeout_and_the_reference_fires() {
    let mut b = Bench::oracle(Some(test_lut()));
    // "No track" samples until T0 + 300 ms (last one at T0 + 290 ms), then silence.
    let crash = T0 + 600 * MS;
    run_scenario(
        &mut b,
        crash + 100 * MS,
        u64::MAX,
        0,
        0.0,
        T0 + 300 * MS,
        Some(crash),
        &|_| 15.0,
    );
    // Last object received at T0 + 290 ms; stale when older than 100 ms.
    assert_eq!(b.mode_at(T0 + 390 * MS), EcuMode::Monitoring as u8);
    assert_eq!(b.first_mode(EcuMode::Degraded), Some(T0 + 391 * MS));
    let d = &b.diagnostics[400];
    assert_ne!(d.degraded_reasons & Degraded::OBJECT_STALE.bits(), 0);
    // Reference: pretensioner and airbag when the accelerometer-only algorithm decides,
    // reference levels.
    let bag = b.first_airbag_fire().expect("reference airbag fired");
    assert_eq!(bag.0, floor_reached_at(crash, 15.0));
    assert_eq!(bag.1.force_level(), 12.0);
    assert_eq!(bag.1.stage(), AirbagStageCmdStage::BothStages);
    assert_eq!(bag.1.cmd_source(), AirbagStageCmdCmdSource::Reference);
    let belt = b
        .belt_frames()
        .into_iter()
        .find(|(_, f)| f.pretensioner_cmd() == BeltLimiterCmdPretensionerCmd::Fire)
        .expect("reference pretensioner fired");
    // The belt with the airbag: a crash that needs the airbag needs it at the same instant.
    assert_eq!(belt.0, bag.0);
    assert_eq!(belt.1.load_limiter_level(), 8.5);
    assert_eq!(belt.1.cmd_source(), BeltLimiterCmdCmdSource::Reference);
    let st = b.status_frames();
    assert!(st.iter().any(
        |(_, s)| s.ecu_mode() == EcuStatusEcuMode::ReferenceFallback && s.fault_object_input()
    ));
}

#[test]
fn crash_without_pre_crash_detection_fires_the_reference() {
    // The sensor is alive but never sees the opponent ("no track" throughout).
    let mut b = Bench::oracle(Some(test_lut()));
    let crash = T0 + 500 * MS;
    run_scenario(
        &mut b,
        crash + 50 * MS,
        u64::MAX,
        0,
        0.0,
        u64::MAX,
        Some(crash),
        &|_| 15.0,
    );
    assert_eq!(b.first_mode(EcuMode::PreCrash), None);
    assert_eq!(b.first_mode(EcuMode::Degraded), None);
    let bag = b.first_airbag_fire().expect("fired");
    // The reference fires when the accelerometer-only algorithm decides.
    assert_eq!(bag.0, floor_reached_at(crash, 15.0));
    assert_eq!(bag.1.cmd_source(), AirbagStageCmdCmdSource::Reference);
}

#[test]
fn sensor_dropout_before_pre_crash_then_crash_fires_the_reference() {
    let mut b = Bench::oracle(Some(test_lut()));
    // Approach seen from T0 + 200 ms, but the sensor dies at C − 400 ms (before the horizon).
    run_scenario(
        &mut b,
        C + 50 * MS,
        T0 + 200 * MS,
        C,
        25.0,
        C - 400 * MS,
        Some(C),
        &|_| 15.0,
    );
    assert_eq!(b.first_mode(EcuMode::PreCrash), None);
    assert_eq!(
        b.first_mode(EcuMode::Degraded),
        Some(C - 410 * MS + 101 * MS)
    );
    let bag = b.first_airbag_fire().expect("fired");
    assert_eq!(bag.0, floor_reached_at(C, 15.0));
    assert_eq!(bag.1.force_level(), 12.0);
}

#[test]
fn e2e_failure_burst_degrades_for_the_hold_time() {
    let mut b = Bench::oracle(Some(test_lut()));
    let mut bad_tx = bus::E2eProtector::new();
    let corrupt = |tx: &mut bus::E2eProtector| {
        let m = bus::OccupantClassification::encode(
            bus::codec::OccupantClassificationBeltBuckle::Buckled,
            bus::codec::OccupantClassificationOccupantClass::MidAdult,
            90,
            75.0,
            300,
            150,
        )
        .unwrap();
        let mut f = tx.seal(m);
        f.data[5] ^= 0x10; // payload bit flip → CRC mismatch
        f
    };
    // Two rejections 150 ms apart: no burst.
    run_scenario(
        &mut b,
        T0 + 200 * MS,
        u64::MAX,
        0,
        0.0,
        u64::MAX,
        None,
        &|_| 0.0,
    );
    for _ in 0..2 {
        b.io.push_can(corrupt(&mut bad_tx));
        let end = b.now + 150 * MS;
        run_scenario(&mut b, end, u64::MAX, 0, 0.0, u64::MAX, None, &|_| 0.0);
    }
    assert_eq!(b.first_mode(EcuMode::Degraded), None);
    // Three within 100 ms: burst at the third.
    let mut t3 = 0;
    for _ in 0..3 {
        b.io.push_can(corrupt(&mut bad_tx));
        t3 = b.now;
        let end = b.now + 10 * MS;
        run_scenario(&mut b, end, u64::MAX, 0, 0.0, u64::MAX, None, &|_| 0.0);
    }
    run_scenario(
        &mut b,
        t3 + 700 * MS,
        u64::MAX,
        0,
        0.0,
        u64::MAX,
        None,
        &|_| 0.0,
    );
    assert_eq!(b.first_mode(EcuMode::Degraded), Some(t3));
    let i = b.step_times.iter().position(|&t| t == t3).unwrap();
    assert_ne!(
        b.diagnostics[i].degraded_reasons & Degraded::E2E_FAILURE.bits(),
        0
    );
    // Held 500 ms after the last rejection, then back to monitoring.
    assert_eq!(b.mode_at(t3 + 500 * MS), EcuMode::Degraded as u8);
    assert_eq!(b.mode_at(t3 + 501 * MS), EcuMode::Monitoring as u8);
    assert_eq!(
        b.ecu
            .e2e_stats()
            .rejected_for(bus::RejectReason::CrcMismatch),
        5
    );
}

#[test]
fn missing_lut_runs_degraded_from_the_start_and_fires_the_reference() {
    let mut b = Bench::oracle(None);
    run_scenario(
        &mut b,
        C + 50 * MS,
        T0 + 200 * MS,
        C,
        25.0,
        C,
        Some(C),
        &|_| 15.0,
    );
    assert_eq!(b.mode_at(T0), EcuMode::Degraded as u8);
    assert_ne!(
        b.diagnostics[0].degraded_reasons & Degraded::LUT_INVALID.bits(),
        0
    );
    assert_eq!(b.first_mode(EcuMode::PreCrash), None);
    let bag = b.first_airbag_fire().expect("fired");
    assert_eq!(bag.0, floor_reached_at(C, 15.0));
    assert_eq!(bag.1.cmd_source(), AirbagStageCmdCmdSource::Reference);
    let st = b.status_frames();
    assert!(st.iter().all(|(_, s)| s.fault_lut() && s.lut_id() == 0));
}

#[test]
fn low_closing_speed_fires_nothing_and_the_event_ends_back_in_monitoring() {
    let mut b = Bench::oracle(Some(test_lut()));
    // 4 m/s against 1600 kg (conservative): EBS = 4·1600/3385·3.6 = 6.8 km/h < 20 km/h.
    // 4.5 g: Δv = (n − ½)·0.04413 m/s after n samples → ≥ 0.5 m/s at n = 12 (C + 11 ms).
    // The accelerometer-only algorithm decides the airbag: Δv(τ) = 0.0221 + 0.0441·τ stays
    // under its boundary (0.25 m/s at 4 ms, then rising 0.11–0.16 m/s per ms) until the
    // 60 ms window closes. The pyrotechnic pretensioner has its own boundary (0.6 × the
    // airbag's: 0.15 m/s at 4 ms, then rising 0.07–0.12 m/s per ms, 4.41 m/s from 48 ms):
    // Δv(τ) crosses its first knot at τ ≈ 3 ms but the floor (0.8 m/s, reached at 17.6 ms,
    // where the boundary is 1.30 m/s) is never met with the boundary: no pretensioner either.
    run_scenario(
        &mut b,
        C + 100 * MS,
        T0 + 200 * MS,
        C,
        4.0,
        C,
        Some(C),
        &|ms| if ms < 100 { 4.5 } else { 0.0 },
    );
    assert_eq!(b.first_mode(EcuMode::PreCrash), None);
    assert_eq!(b.first_mode(EcuMode::Crash), Some(C + 11 * MS));
    assert!(matches!(
        b.ecu.crash_kind(),
        Some(ConfirmKind::Generic { .. })
    ));
    // While the event lasts the crash phase holds (CrashDetected on the bus).
    assert_eq!(b.mode_at(C + 99 * MS), EcuMode::Crash as u8);
    // The pulse ends at C + 100 ms; the event is over 10 ms of quiet later (the first sample
    // more than 10 ms after the last awake one, C + 110 ms): nothing fired, so the decision
    // ends with its event and the ECU monitors again — DEGRADED here, because this test's
    // object list ended at the contact (stale since C + 90 ms), not latched in POST-CRASH.
    b.run_until(C + 130 * MS);
    assert_eq!(b.first_mode(EcuMode::PostCrash), None);
    assert_eq!(b.mode_at(C + 109 * MS), EcuMode::Crash as u8);
    assert_eq!(b.mode_at(C + 111 * MS), EcuMode::Degraded as u8);
    assert_eq!(b.ecu.crash_kind(), None);
    assert!(b
        .airbag_frames()
        .iter()
        .all(|(_, f)| f.fire() == AirbagStageCmdFire::NoFire));
    assert!(b
        .belt_frames()
        .iter()
        .all(|(_, f)| f.pretensioner_cmd() != BeltLimiterCmdPretensionerCmd::Fire));
    // The belt keeps the reference limiter level.
    assert_eq!(b.belt_frames().last().unwrap().1.load_limiter_level(), 8.5);
}

#[test]
fn nan_object_fields_degrade_until_a_valid_sample_arrives() {
    let mut b = Bench::oracle(Some(test_lut()));
    run_scenario(
        &mut b,
        T0 + 200 * MS,
        u64::MAX,
        0,
        0.0,
        u64::MAX,
        None,
        &|_| 0.0,
    );
    let mut o = crate::cycle_support::object(b.now, f32::NAN, 1500.0, 100.0);
    o.distance_m = f32::INFINITY;
    b.io.push_object(o);
    let t_bad = b.now;
    b.step();
    assert_eq!(b.mode_at(t_bad), EcuMode::Degraded as u8);
    assert_ne!(
        b.diagnostics.last().unwrap().degraded_reasons & Degraded::OBJECT_INVALID.bits(),
        0
    );
    let end = b.now + 30 * MS;
    run_scenario(&mut b, end, u64::MAX, 0, 0.0, u64::MAX, None, &|_| 0.0);
    assert_eq!(b.ecu.phase(), Phase::Monitoring);
}

/// A vehicle gateway that restarts (its alive counter starts again at 0) after a silence
/// longer than the vehicle timeout: the ECU takes its first new frame at once (the stream is
/// resynchronised after the timeout), so it is fresh again on that frame — no E2E rejection,
/// no extra period of staleness. The same counter jump WITHOUT a preceding timeout is still
/// rejected.
#[test]
fn restarted_sender_is_accepted_after_its_timeout_but_a_counter_jump_is_not() {
    let mut b = Bench::oracle(Some(test_lut()));
    // "No track" object samples keep the object input fresh throughout.
    let idle = |b: &mut Bench, ms: u64| {
        let end = b.now + ms * MS;
        run_scenario(b, end, u64::MAX, 0, 0.0, u64::MAX, None, &|_| 0.0);
    };
    idle(&mut b, 300);
    assert_eq!(b.mode_at(b.now - MS), EcuMode::Monitoring as u8);
    b.send_vehicle = false;
    idle(&mut b, 150); // > 100 ms vehicle timeout
    let stale_at = b.now - MS;
    assert_ne!(
        b.diagnostics.last().unwrap().degraded_reasons & Degraded::CAN_STALE.bits(),
        0
    );
    // The restarted gateway: a fresh protector, counter 0.
    let mut restarted = bus::E2eProtector::new();
    let m =
        bus::EgoVehicleState::encode(bus::codec::EgoVehicleStateBrakeState::Released, 15.0, 0.0)
            .unwrap();
    b.io.push_can(restarted.seal(m));
    let resumed = b.now;
    idle(&mut b, 1);
    let d = *b.diagnostics.last().unwrap();
    assert_eq!(
        d.degraded_reasons & Degraded::CAN_STALE.bits(),
        0,
        "vehicle fresh on the first frame after the restart (stale since {stale_at})"
    );
    assert_eq!(b.mode_at(resumed), EcuMode::Monitoring as u8);
    assert_eq!(
        b.ecu
            .e2e_stats()
            .rejected_for(bus::RejectReason::CounterSkipped),
        0
    );
    // Live stream (not timed out): a jump of the counter is rejected as before.
    for _ in 0..5 {
        let _ = restarted.seal(m); // counters 1..=5 never sent
    }
    b.io.push_can(restarted.seal(m));
    idle(&mut b, 1);
    assert_eq!(
        b.ecu
            .e2e_stats()
            .rejected_for(bus::RejectReason::CounterSkipped),
        1
    );
}

/// A stuck sensor that keeps repeating its last "no track" record (old timestamp): the record
/// is as stale as any sample, so the ECU degrades (OBJECT_INVALID) once it is older than the
/// object timeout, and recovers on the first fresh record.
#[test]
fn stuck_no_track_records_degrade_like_stale_samples() {
    let mut b = Bench::oracle(Some(test_lut()));
    let end = b.now + 300 * MS;
    run_scenario(&mut b, end, u64::MAX, 0, 0.0, u64::MAX, None, &|_| 0.0);
    assert_eq!(b.mode_at(b.now - MS), EcuMode::Monitoring as u8);
    let mut stuck = ObjectState::INVALID;
    stuck.timestamp_ns = b.now;
    let frozen_at = b.now;
    for _ in 0..30 {
        b.io.push_object(stuck); // the same record every 10 ms
        b.run_ms(10);
    }
    let first_degraded = b
        .step_times
        .iter()
        .zip(&b.diagnostics)
        .find(|(t, d)| {
            **t >= frozen_at && d.degraded_reasons & Degraded::OBJECT_INVALID.bits() != 0
        })
        .map(|(t, _)| *t)
        .expect("degraded while the record is stuck");
    let after_ms = (first_degraded - frozen_at) / MS;
    assert!(
        (100..=111).contains(&after_ms),
        "degraded {after_ms} ms after the record was taken (timeout 100 ms, records every 10 ms)"
    );
    // Fresh again.
    let end = b.now + 20 * MS;
    run_scenario(&mut b, end, u64::MAX, 0, 0.0, u64::MAX, None, &|_| 0.0);
    assert_eq!(
        b.diagnostics.last().unwrap().degraded_reasons & Degraded::OBJECT_INVALID.bits(),
        0
    );
}
