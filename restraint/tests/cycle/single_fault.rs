//! No single fault may fire a restraint. The two deployments a reviewer reproduced
//! with this bench (a spike that latched a must-fire; a prediction plus a short kerb strike),
//! and the safing channel's single faults, under the simulated 1 kHz clock. The seeded matrix
//! over thousands of variants is `misuse-matrix` (e2e-tests crate).

use crate::cycle_support::*;
use restraint::{Degraded, Pretensioner};

/// Contact of the standard approach.
const C: u64 = T0 + 1_000 * MS;

fn airbag_fired(b: &Bench) -> bool {
    b.first_airbag_fire().is_some()
}

fn pretensioner_fired(b: &Bench) -> bool {
    b.first_pretensioner_fire().is_some()
}

/// A rectangular deceleration the whole car feels (both sensors), `g` × `dur_ms`.
fn bump(b: &mut Bench, g: f32, dur_ms: u64) {
    for _ in 0..dur_ms {
        b.push_accel(-g * G);
        b.push_object_none();
        b.step();
    }
}

trait NoTrack {
    fn push_object_none(&mut self);
}

impl NoTrack for Bench {
    /// A "no track" object sample on the 10 ms grid, as `drive` sends.
    fn push_object_none(&mut self) {
        if (self.now - T0).is_multiple_of(10 * MS) {
            let mut o = restraint::ObjectState::INVALID;
            o.timestamp_ns = self.now;
            self.io.push_object(o);
        }
    }
}

#[test]
fn reproduction_1_a_spike_then_a_bump_fires_nothing() {
    // Normal driving, no object tracked. One accelerometer sample of 15/25/40/60 g (a fault
    // of the crash sensor, or an electrical spike on both), then 0.5 s later a 4.5 g × 40 ms
    // bump — which alone fires nothing. A decision that outlived its event would let the spike
    // latch a must-fire of the accelerometer-only algorithm for good, and the bump's
    // confirmation fire the airbag (at +511 ms).
    for spike_g in [15.0f32, 25.0, 40.0, 60.0] {
        for both_sensors in [false, true] {
            let mut b = Bench::new(Some(test_lut()));
            idle_until(&mut b, T0 + 500 * MS);
            if both_sensors {
                b.push_accel(-spike_g * G);
            } else {
                b.push_crash_sensor_fault(-spike_g * G);
            }
            idle_until(&mut b, T0 + 1_000 * MS);
            bump(&mut b, 4.5, 40); // Δv 1.77 m/s = 6.4 km/h
            idle_until(&mut b, T0 + 1_300 * MS);
            let what = format!("{spike_g} g spike (both sensors: {both_sensors})");
            assert!(!airbag_fired(&b), "{what}: airbag fired");
            assert!(!pretensioner_fired(&b), "{what}: pretensioner fired");
            assert_eq!(b.ecu.pretensioner(), Pretensioner::Idle, "{what}");
        }
    }
}

#[test]
fn reproduction_2_a_prediction_plus_a_kerb_strike_at_the_predicted_contact_fires_no_airbag() {
    // An object predicted to hit at C that does not (near miss, evasion, a ghost: the object
    // list reports no track from C on), and at C a ramp-shaped kerb strike: 4 ms up to 7.4 g
    // at 20 m/s closing (Δv ≈ 0.15 m/s), or 5 ms up to 6.9 g at 14 m/s. The
    // prediction-matched path must not fire the adaptive airbag on it.
    for (closing, ramp_ms, peak_g) in [(20.0f32, 4u64, 7.4f32), (14.0, 5, 6.9)] {
        let mut b = Bench::new(Some(test_lut()));
        run_scenario(&mut b, C, T0 + 200 * MS, C, closing, C, None, &|_| 0.0);
        for k in 1..=ramp_ms {
            b.push_accel(-peak_g * k as f32 / ramp_ms as f32 * G);
            b.push_object_none();
            b.step();
        }
        idle_until(&mut b, C + 300 * MS);
        let what = format!("{closing} m/s, {peak_g} g × {ramp_ms} ms");
        assert!(!airbag_fired(&b), "{what}: airbag fired");
        // The reversible pre-crash pretensioner fired on the prediction and is released.
        assert_eq!(b.ecu.pretensioner(), Pretensioner::Released, "{what}");
    }
}

#[test]
fn one_faulty_crash_accelerometer_alone_fires_nothing() {
    // Offset by 6 g for 1 s (a drifting sensor), stuck at −20 g, or a 25 g × 40 ms burst of
    // the crash sensor alone: the main algorithm confirms a "crash" of its own sensor, the
    // safing sensor sees a quiet car and never agrees.
    let faults: [(&str, &dyn Fn(u64) -> f32); 3] = [
        ("offset 6 g", &|_| -6.0 * G),
        ("stuck at −20 g", &|_| -20.0 * G),
        ("25 g burst", &|k| if k < 40 { -25.0 * G } else { 0.0 }),
    ];
    for (name, reading) in faults {
        let mut b = Bench::new(Some(test_lut()));
        idle_until(&mut b, T0 + 500 * MS);
        for k in 0..1_000u64 {
            b.push_crash_sensor_fault(reading(k));
            b.push_object_none();
            b.step();
        }
        idle_until(&mut b, T0 + 1_700 * MS);
        assert!(!airbag_fired(&b), "{name}: airbag fired");
        assert!(!pretensioner_fired(&b), "{name}: pretensioner fired");
        if name != "25 g burst" {
            // A stuck or offset sensor keeps the main path confirming; the safing function
            // vetoes (or the fire is never decided) — either way nothing left the ECU.
            assert!(b.ecu.safing().delta_v_mps() < 0.05, "{name}");
        }
    }
}

#[test]
fn one_faulty_safing_accelerometer_alone_fires_nothing_and_is_flagged() {
    let mut b = Bench::new(Some(test_lut()));
    idle_until(&mut b, T0 + 500 * MS);
    for k in 0..200u64 {
        b.push_safing_sensor_fault(if k < 100 { -30.0 * G } else { -5.0 * G });
        b.push_object_none();
        b.step();
    }
    idle_until(&mut b, T0 + 900 * MS);
    assert!(!airbag_fired(&b) && !pretensioner_fired(&b));
    // A dead safing sensor is on the bus within its timeout + one status period.
    b.safing_live = false;
    idle_until(&mut b, T0 + 1_000 * MS);
    assert!(b.ecu.degraded_reasons().contains(Degraded::SAFING_STALE));
    assert!(!b.ecu.degraded_reasons().intersects(Degraded::DEGRADING));
    let flagged = b
        .status_frames()
        .into_iter()
        .find(|(_, s)| s.fault_safing_sensor())
        .map(|(t, _)| t)
        .expect("FaultSafingSensor on the bus");
    assert!(flagged <= T0 + 900 * MS + 50 * MS + 21 * MS, "{flagged}");
}

#[test]
fn a_real_crash_with_a_dead_safing_sensor_fires_when_the_vehicle_deceleration_agrees() {
    // Crash without pre-crash information (objects "no track"): 20 g from C. The safing
    // sensor is dead, so the ECU takes the gateway's EgoLongAccel (every 10 ms) as the
    // second agreement: the reference airbag fires once a vehicle frame shows ≥ 2 g.
    let mut b = Bench::new(Some(test_lut()));
    b.safing_live = false;
    idle_until(&mut b, C);
    b.ego_long_accel_mps2 = -15.0 * G;
    run_unpredicted_crash(&mut b, C, 20.0);
    let (t, _) = b.first_airbag_fire().expect("the airbag fires");
    // The reference fires when the accelerometer-only algorithm decides; the vehicle frame at
    // C (sent every 10 ms from T0) already shows the deceleration, so the substitute agrees
    // in time.
    assert_eq!(t, floor_reached_at(C, 20.0));
    // Without any second agreement (vehicle frame shows only braking) nothing fires.
    let mut b = Bench::new(Some(test_lut()));
    b.safing_live = false;
    idle_until(&mut b, C);
    b.ego_long_accel_mps2 = -G; // 1 g of braking
    run_scenario(
        &mut b,
        C + 200 * MS,
        u64::MAX,
        0,
        0.0,
        u64::MAX,
        Some(C),
        &|_| 20.0,
    );
    assert!(!airbag_fired(&b));
    assert!(b.ecu.vetoed_fires() > 0);
}

#[test]
fn a_real_crash_with_a_dead_safing_sensor_fires_when_the_satellites_see_the_front_end_fold() {
    // As above, but the vehicle frame shows only braking: the two crush-zone satellites stand
    // in. Their rail tips slow at 100 g while the body slows at 20 g (80 g × 4 ms = 3.1 m/s
    // of crush Δv, above the relief's 1 m/s line): the airbag fires in the cycle it fires with
    // a healthy safing sensor. Satellites that move with the body (a body motion, no crush)
    // stand in for nothing.
    use restraint::signals::{psi5::code_of, SatelliteSide};
    let run = |safing_live: bool, crushed: bool| {
        let mut b = Bench::new(Some(test_lut()));
        b.safing_live = safing_live;
        b.ego_long_accel_mps2 = -G; // 1 g of braking: the vehicle frame never agrees
        while b.now < C + 100 * MS {
            let sat_g = match (b.now >= C, crushed) {
                (false, _) => 0.0,
                (true, true) => 100.0,
                (true, false) => 20.0,
            };
            let code = code_of(sat_g * f64::from(G), 240.0 * f64::from(G));
            for side in SatelliteSide::BOTH {
                b.io.push_satellite(side, satellite_frames(b.now, code));
            }
            if (b.now - T0).is_multiple_of(10 * MS) {
                b.push_object_none();
            }
            if b.now >= C {
                b.push_accel(-20.0 * G);
            }
            b.step();
        }
        b
    };
    let healthy = run(true, true)
        .first_airbag_fire()
        .expect("healthy: the airbag fires");
    let dead = run(false, true)
        .first_airbag_fire()
        .expect("dead: the airbag fires");
    assert_eq!(dead.0, healthy.0);
    assert!(healthy.0 < C + 10 * MS, "{}", healthy.0 - C);
    let b = run(false, false);
    assert!(!airbag_fired(&b) && !pretensioner_fired(&b));
    assert!(b.ecu.vetoed_fires() > 0);
}

/// A crash-sensor fault inside a real misuse event that satisfies the safing
/// sensor. `tolerance_dv_mps` = the severity agreement's absolute tolerance (5 m/s: off).
fn fault_inside_event(case: &str, tolerance_dv_mps: f64) -> Bench {
    let cfg = restraint::CycleConfig {
        severity_tolerance_dv_mps: tolerance_dv_mps,
        ..ideal_sensor_config()
    };
    let mut b = Bench::with_config(cfg, Some(test_lut()));
    idle_until(&mut b, T0 + 500 * MS);
    for k in 0..400u64 {
        let t_s = k as f64 * 1e-3;
        match case {
            // A door slam: 30 g of zero-mean ringing at 125 Hz for 48 ms on both sensors (a
            // lobe is 0.75 m/s: the safing channel closes); the crash sensor sticks at the
            // crest of k = 10 for 100 ms.
            "stuck crash sensor in a door slam" => {
                let ring = if k < 48 {
                    -(30.0 * (2.0 * std::f64::consts::PI * 125.0 * t_s).sin()) as f32 * G
                } else {
                    0.0
                };
                b.push_accel(ring);
                if (10..110).contains(&k) {
                    b.push_crash_sensor_fault(-30.0 * G);
                }
            }
            // A pothole (6 g × 20 ms half-sine, 0.75 m/s) on both; the crash sensor alone
            // reads +8 g more from its start for 300 ms.
            "offset from a pothole" => {
                let pothole = if k < 20 {
                    6.0 * (std::f64::consts::PI * t_s / 0.020).sin() as f32
                } else {
                    0.0
                };
                b.push_accel(-pothole * G);
                if k < 300 {
                    b.push_crash_sensor_fault(-(pothole + 8.0) * G);
                }
            }
            _ => unreachable!(),
        }
        b.push_object_none();
        b.step();
    }
    idle_until(&mut b, T0 + 1_500 * MS);
    b
}

#[test]
fn a_crash_sensor_fault_inside_a_real_misuse_event_fires_nothing() {
    for case in ["stuck crash sensor in a door slam", "offset from a pothole"] {
        let b = fault_inside_event(case, 0.10);
        assert!(!airbag_fired(&b), "{case}: airbag fired");
        assert!(!pretensioner_fired(&b), "{case}: pretensioner fired");
        assert!(b.ecu.agreement().disagreements() >= 1, "{case}");
        // The crash phase ends with the event: back to monitoring.
        assert_eq!(b.ecu.phase(), restraint::Phase::Monitoring, "{case}");
        // Without the severity agreement the safing channel (closed by the real event) lets
        // the faulty sensor fire: the test sees what it guards against.
        let off = fault_inside_event(case, 5.0);
        assert!(
            airbag_fired(&off) || pretensioner_fired(&off),
            "{case}: fires nothing even without the agreement"
        );
    }
}

/// ABS braking at 1 g (vehicle frames say so) and a 7 g × 20 ms half-sine
/// pothole (0.891 m/s) at 300 ms; `compensate`: `braking_compensation_max_g` 1.2 or 0. Returns
/// the bench after the run and the accelerometer-only algorithm's event Δv at the pothole's last sample.
fn pothole_while_braking(compensate: bool) -> (Bench, f64) {
    let cfg = restraint::CycleConfig {
        braking_compensation_max_g: if compensate { 1.2 } else { 0.0 },
        ..ideal_sensor_config()
    };
    let mut b = Bench::with_config(cfg, Some(test_lut()));
    b.accel_dither = false;
    idle_until(&mut b, T0 + 300 * MS);
    b.abs_braking = true;
    b.ego_long_accel_mps2 = -G;
    let mut dv = f64::NAN;
    for k in 0..700u64 {
        let pothole = if (300..=320).contains(&k) {
            7.0 * (std::f64::consts::PI * (k - 300) as f64 / 20.0).sin() as f32
        } else {
            0.0
        };
        b.push_accel(-(1.0 + pothole) * G);
        b.push_object_none();
        b.step();
        if k == 320 {
            dv = b.ecu.crash().event_dv_mps();
        }
    }
    (b, dv)
}

#[test]
fn sustained_braking_the_vehicle_frame_explains_is_not_crash_evidence() {
    // The half-sine's Δv in closed form: 2·a·T/π; sampled at 1 kHz with trapezoids it is
    // the same within 0.3 %.
    let pothole_dv = 2.0 * 7.0 * f64::from(G) * 0.020 / std::f64::consts::PI;
    let (b, dv) = pothole_while_braking(true);
    assert!(
        (dv - pothole_dv).abs() < 0.01,
        "compensated Δv {dv} vs pothole {pothole_dv}"
    );
    assert!(!airbag_fired(&b) && !pretensioner_fired(&b));
    // Without the compensation the detectors also count the braking: 1 g over the 20 ms
    // the event has lasted (0.196 m/s) on top.
    let (_, raw) = pothole_while_braking(false);
    let with_braking = pothole_dv + f64::from(G) * 0.020;
    assert!(
        (raw - with_braking).abs() < 0.02,
        "raw Δv {raw} vs {with_braking}"
    );
}

/// Zero-mean rectangular swings the whole car feels, `cycles` of them: `g` forward for
/// `half_ms`, then `g` backward for `half_ms` (a rough road's velocity goes as far forward as
/// back; a crash only slows the car).
fn swings(b: &mut Bench, g: f32, half_ms: u64, cycles: u32) {
    for _ in 0..cycles {
        for forward in [true, false] {
            for _ in 0..half_ms {
                b.push_accel(if forward { g * G } else { -g * G });
                b.push_object_none();
                b.step();
            }
        }
    }
}

fn rough_road_run(roughness_k: f64) -> Bench {
    let cfg = restraint::CycleConfig {
        roughness_k,
        ..ideal_sensor_config()
    };
    let mut b = Bench::with_config(cfg, Some(test_lut()));
    idle_until(&mut b, T0 + 500 * MS);
    // Each backward half carries 8 g × 30 ms = 2.35 m/s since its onset: past the
    // pretensioner's boundary (1.53 m/s at 20 ms) and its 1.5 m/s floor.
    swings(&mut b, 8.0, 30, 4);
    idle_until(&mut b, T0 + 1_000 * MS);
    b
}

#[test]
fn a_rough_roads_backward_swings_fire_nothing_its_forward_swings_lift_the_floors() {
    // A rough road: the forward swings lift every floor by 2 × the held forward
    // excursion beyond 0.05 m/s (here ≈ 1.8 m/s → +3.5 m/s), so no backward swing carries its
    // floor.
    let b = rough_road_run(restraint::CycleConfig::default().roughness_k);
    assert!(!pretensioner_fired(&b), "pretensioner fired");
    assert!(!airbag_fired(&b), "airbag fired");
    // Nor does the ECU put CrashDetected on the bus for them: the generic confirmation's Δv
    // carries the lift too (the mode flickered CrashDetected ↔ Normal on every swing).
    assert_eq!(
        b.first_mode(restraint::EcuMode::Crash),
        None,
        "CrashDetected"
    );
    // Without the roughness measure the same swings confirm a crash and fire the pyrotechnic
    // pretensioner.
    let without = rough_road_run(0.0);
    assert!(
        pretensioner_fired(&without),
        "the swings are not severe enough to test"
    );
    assert!(without.first_mode(restraint::EcuMode::Crash).is_some());
}

#[test]
fn a_crash_on_a_smooth_road_is_not_delayed_by_the_roughness_measure() {
    let fire_at = |roughness_k: f64| {
        let cfg = restraint::CycleConfig {
            roughness_k,
            ..ideal_sensor_config()
        };
        let mut b = Bench::with_config(cfg, Some(test_lut()));
        idle_until(&mut b, T0 + 500 * MS);
        bump(&mut b, 20.0, 80); // a 20 g × 80 ms barrier-like pulse: Δv 15.7 m/s
        idle_until(&mut b, T0 + 700 * MS);
        b.first_airbag_fire().map(|(t, _)| t)
    };
    let with = fire_at(restraint::CycleConfig::default().roughness_k);
    assert!(with.is_some(), "the crash fired no airbag");
    assert_eq!(with, fire_at(0.0));
}

/// A predicted crash (20 m/s towards contact `C`, 20 g from `C`) in which one accelerometer
/// reads `offset_g` more (crash sensor, `crash_sensor` true) or less (safing sensor) than the
/// car; the gateway's EgoLongAccel shows `vehicle_g` from `C` on.
fn crash_with_one_sensor_off(crash_sensor: bool, offset_g: f32, vehicle_g: f32) -> Bench {
    let mut b = Bench::new(Some(test_lut()));
    idle_until(&mut b, T0 + 100 * MS);
    while b.now < C + 150 * MS {
        if (b.now - T0).is_multiple_of(10 * MS) && b.now < C {
            b.push_approach(C, 20.0, 1500.0, 100.0);
        }
        if b.now >= C {
            b.ego_long_accel_mps2 = -vehicle_g * G;
            b.push_accel(-20.0 * G);
            if crash_sensor {
                b.push_crash_sensor_fault(-(20.0 + offset_g) * G);
            } else {
                b.push_safing_sensor_fault(-(20.0 - offset_g) * G);
            }
        }
        b.step();
    }
    b
}

#[test]
fn a_disagreeing_pair_in_a_predicted_crash_is_decided_by_the_vehicle_deceleration() {
    // Two sensors that disagree cannot say which of them is wrong; the object list's predicted
    // crash and the vehicle frame's 15 g are two further sources, and the reference restraint
    // fires on them — whichever sensor is off.
    for (crash_sensor, what) in [
        (true, "crash sensor 10 g high"),
        (false, "safing sensor 15 g low"),
    ] {
        let offset = if crash_sensor { 10.0 } else { 15.0 };
        let b = crash_with_one_sensor_off(crash_sensor, offset, 15.0);
        assert!(
            b.ecu.agreement().disagreements() >= 1 || !crash_sensor,
            "{what}"
        );
        let (t, cmd) = b
            .first_airbag_fire()
            .unwrap_or_else(|| panic!("{what}: no airbag"));
        assert_eq!(
            cmd.cmd_source(),
            bus::codec::AirbagStageCmdCmdSource::Reference,
            "{what}"
        );
        if crash_sensor {
            // The safing sensor reads the smaller of the two, the true 20 g: it measures the
            // crash as the crash sensor's own boundary and floor would, and the backup fires
            // then — when 20 g has carried the airbag's floor.
            assert_eq!(t, floor_reached_at(C, 20.0), "{what}");
        } else {
            // The safing sensor's 5 g reaches no boundary: not before the reference time
            // (contact + 10 ms), and at the latest one vehicle frame period after the first
            // frame that shows the crash (at C, every 10 ms) and the cycle.
            assert!((C + 10 * MS..=C + 21 * MS).contains(&t), "{what}: {t}");
        }
        assert!(pretensioner_fired(&b), "{what}");
    }
    // The vehicle frame showing only braking (1 g) and a safing sensor that reads 5 g: nothing
    // fires — the crash sensor's event alone decides nothing.
    let b = crash_with_one_sensor_off(false, 15.0, 1.0);
    assert!(!airbag_fired(&b), "airbag without the vehicle deceleration");
    // With the crash sensor 10 g high and the vehicle frame at 1 g, both accelerometers read at
    // least the true 20 g: the smaller reading and the predicted crash decide it.
    let b = crash_with_one_sensor_off(true, 10.0, 1.0);
    assert_eq!(
        b.first_airbag_fire().map(|(t, _)| t),
        Some(floor_reached_at(C, 20.0))
    );
}

#[test]
fn a_crash_sensor_reading_less_times_the_backup_by_its_own_decision() {
    // The crash sensor reads 5 g low (15 g of the true 20 g), the safing sensor the truth: the
    // pair disagrees with the safing sensor reading more, and the predicted crash with the
    // vehicle frame's 15 g decides it for the backup. The crash sensor's is the smaller reading
    // whichever of the two is wrong, so its own accelerometer-only decision times the backup's
    // airbag: when 15 g has carried the floor, before the reference time (contact + 10 ms).
    let b = crash_with_one_sensor_off(true, -5.0, 15.0);
    let (t, cmd) = b.first_airbag_fire().expect("no airbag");
    assert_eq!(
        cmd.cmd_source(),
        bus::codec::AirbagStageCmdCmdSource::Reference
    );
    assert_eq!(t, floor_reached_at(C, 15.0));
    assert!(t < C + 10 * MS);
    assert!(pretensioner_fired(&b));
}

#[test]
fn a_safing_sensor_reading_more_never_measures_a_crash_for_the_backup() {
    // A predicted crash that does not come (a near miss at C) with an 8 g, 10 ms pothole on both
    // sensors; the safing sensor alone reads 25 g more from C (a fault) and the vehicle frame
    // shows 1 g. The pair disagrees with the safing sensor reading more: its reading is the
    // larger of the two and may be the wrong one, so it never stands in for the crash
    // sensor's measurement — nothing fires.
    let mut b = Bench::new(Some(test_lut()));
    idle_until(&mut b, T0 + 100 * MS);
    b.ego_long_accel_mps2 = -G;
    while b.now < C + 150 * MS {
        if (b.now - T0).is_multiple_of(10 * MS) && b.now < C {
            b.push_approach(C, 20.0, 1500.0, 100.0);
        }
        let car_g = if (C..C + 10 * MS).contains(&b.now) {
            8.0
        } else {
            0.0
        };
        b.push_accel(-car_g * G);
        if (C..C + 30 * MS).contains(&b.now) {
            b.push_safing_sensor_fault(-(car_g + 25.0) * G);
        }
        b.step();
    }
    // The pothole confirms a crash phase and the pair check sees the disagreement.
    let crash_phase = [restraint::EcuMode::Crash, restraint::EcuMode::PostCrash]
        .into_iter()
        .any(|m| b.first_mode(m).is_some());
    assert!(crash_phase, "no crash phase");
    assert!(!airbag_fired(&b), "airbag");
    // The reversible pre-crash belt of the predicted crash is released: no pyrotechnic fire
    // latched it.
    assert_ne!(b.ecu.pretensioner(), Pretensioner::Fired, "pretensioner");
}

/// The degraded reasons the cycle at `t` published.
fn reasons_at(b: &Bench, t: u64) -> Degraded {
    let i = b
        .step_times
        .iter()
        .position(|&s| s == t)
        .expect("a cycle at t");
    Degraded::from_bits_truncate(b.diagnostics[i].degraded_reasons)
}

/// From `C − 50 ms` the crash accelerometer alone reads `offset_g` more deceleration than the
/// car (negative: it reads the car pushed forward) — an offset every per-sensor check passes;
/// with `crash`, a predicted crash (as above) with 20 g from `C` and the vehicle frame showing
/// 15 g from `C`; without, the car cruises on.
fn crash_sensor_offset_from_before_contact(offset_g: f32, crash: bool) -> Bench {
    let mut b = Bench::new(Some(test_lut()));
    idle_until(&mut b, T0 + 100 * MS);
    while b.now < C + 150 * MS {
        if crash && (b.now - T0).is_multiple_of(10 * MS) && b.now < C {
            b.push_approach(C, 20.0, 1500.0, 100.0);
        }
        let car_g = if crash && b.now >= C { 20.0 } else { 0.0 };
        if crash && b.now >= C {
            b.ego_long_accel_mps2 = -15.0 * G;
        }
        b.push_accel(-car_g * G);
        if b.now >= C - 50 * MS {
            // A live sensor's noise: never bit-identical (the stuck check stays quiet).
            let noise_mps2 = if (b.now / MS).is_multiple_of(2) {
                0.05
            } else {
                -0.05
            };
            b.push_crash_sensor_fault(-(car_g + offset_g) * G + noise_mps2);
        }
        b.step();
    }
    b
}

#[test]
fn a_crash_sensor_offset_before_contact_is_flagged_and_the_backup_fires_in_time() {
    for offset_g in [-6.0, -2.0, 3.0, 8.0] {
        let b = crash_sensor_offset_from_before_contact(offset_g, true);
        // The pair check attributes a step 13 ms after it appears (`pair_monitor` oracle);
        // the fault is on the bus at the next status frame.
        let flagged = b
            .status_frames()
            .into_iter()
            .find(|(t, s)| *t >= C - 50 * MS && s.fault_accel_sensor())
            .map(|(t, _)| t);
        assert!(
            flagged.is_some_and(|t| t <= C - 20 * MS),
            "{offset_g} g: flagged at {flagged:?}"
        );
        assert!(!reasons_at(&b, C - 10 * MS).contains(Degraded::SAFING_INVALID));
        // The backup path, confirmed by the vehicle frame at C and timed by the healthy safing
        // sensor: the reference airbag when its 20 g have carried the accelerometer-only
        // floor (the clean crash's own time), whatever the crash sensor reads.
        let (t, cmd) = b
            .first_airbag_fire()
            .unwrap_or_else(|| panic!("{offset_g} g: no airbag"));
        assert_eq!(
            cmd.cmd_source(),
            bus::codec::AirbagStageCmdCmdSource::Reference
        );
        assert_eq!(t, floor_reached_at(C, 20.0), "{offset_g} g");
        assert!(pretensioner_fired(&b), "{offset_g} g");
    }
}

#[test]
fn a_flagged_crash_sensor_fires_nothing_without_a_crash() {
    // The same offsets on a car cruising on: flagged, and nothing fires — the flag only takes
    // a path away (the backup path needs a predicted crash and the vehicle deceleration).
    for offset_g in [-6.0, 3.0, 8.0, 30.0] {
        let b = crash_sensor_offset_from_before_contact(offset_g, false);
        assert!(
            reasons_at(&b, C).contains(Degraded::ACCEL_INVALID),
            "{offset_g} g: not flagged"
        );
        assert!(!airbag_fired(&b), "{offset_g} g: airbag");
        assert!(!pretensioner_fired(&b), "{offset_g} g: pretensioner");
    }
}

/// Two 500 µs PSI5 frames carrying `code` (0: at rest), measured at `t_ns`.
fn satellite_frames(t_ns: u64, code: i16) -> restraint::signals::SatelliteFrames {
    use restraint::signals::{psi5, SatelliteFrames};
    SatelliteFrames {
        first_timestamp_ns: t_ns,
        sample_period_ns: 500_000,
        count: 2,
        frames: [psi5::encode(code); 8],
        ..SatelliteFrames::EMPTY
    }
}

#[test]
fn a_silent_or_defective_satellite_raises_its_own_status_bit_and_degrades_nothing() {
    use restraint::signals::{psi5::SENSOR_DEFECT, SatelliteSide};
    let mut b = Bench::new(Some(test_lut()));
    // Both satellites at rest every cycle; from T0 + 400 ms the left one is silent, from
    // T0 + 600 ms the right one sends the sensor-defect status word.
    let silent_from = T0 + 400 * MS;
    let defect_from = T0 + 600 * MS;
    while b.now < T0 + 800 * MS {
        if b.now < silent_from {
            b.io.push_satellite(SatelliteSide::Left, satellite_frames(b.now, 0));
        }
        let right = if b.now < defect_from {
            0
        } else {
            SENSOR_DEFECT
        };
        b.io.push_satellite(SatelliteSide::Right, satellite_frames(b.now, right));
        if (b.now - T0).is_multiple_of(10 * MS) {
            b.push_object_none();
        }
        b.step();
    }
    let status = b.status_frames();
    let first =
        |f: &dyn Fn(&bus::EcuStatus) -> bool| status.iter().find(|(_, s)| f(s)).map(|(t, _)| *t);
    // Both healthy from the first frames on: neither bit after the start-up.
    assert!(status
        .iter()
        .filter(|(t, _)| (T0 + 100 * MS..silent_from).contains(t))
        .all(|(_, s)| !s.fault_satellite_left() && !s.fault_satellite_right()));
    // Silent: within the satellite timeout (50 ms) + one status period (20 ms) of the last frame.
    let left = first(&|s| s.fault_satellite_left()).expect("FaultSatelliteLeft");
    assert!(
        (silent_from + 40 * MS..=silent_from + 50 * MS + 21 * MS).contains(&left),
        "{left}"
    );
    // Defective: in the cycle of the status word (a change goes out at once).
    let right = first(&|s| s.fault_satellite_right()).expect("FaultSatelliteRight");
    assert!(
        (defect_from..=defect_from + 2 * MS).contains(&right),
        "{right}"
    );
    // Reported, never degrading: the ECU's mode and plan stay.
    assert!(b
        .ecu
        .degraded_reasons()
        .contains(Degraded::SATELLITE_LEFT | Degraded::SATELLITE_RIGHT));
    assert!(!b.ecu.degraded_reasons().intersects(Degraded::DEGRADING));
}
