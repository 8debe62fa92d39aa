//! Single sensor faults, alone and inside real events.

use super::text::*;
use super::*;

pub(super) fn spike(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
    let t0 = r.gen_range(0.3..0.5);
    let sensor = ["all", "crash", "safing"][r.gen_range(0..3)];
    let g = r.gen_range(10.0..200.0);
    let ev = spike_event(t0, g, sensor);
    let v = drive_kph(r);
    driving(name, i, &ego(v, None), 0.8, "", &ev)
}

pub(super) fn offset(r: &mut ChaCha8Rng, name: &str, i: u64, sensor: &str) -> String {
    let t0 = r.gen_range(0.3..0.5);
    let g = r.gen_range(2.0..20.0) * if r.gen_bool(0.5) { 1.0 } else { -1.0 };
    let len = r.gen_range(0.05..0.5);
    let ev = offset_event(t0, g, t0 + len, sensor);
    let v = drive_kph(r);
    // The run goes on JUDGED_AFTER_S after the offset: a run that ends inside the event cannot
    // say whether its crash phase ends.
    let duration_s = (t0 + len + JUDGED_AFTER_S).max(1.0);
    driving(name, i, &ego(v, None), duration_s, "", &ev)
}

pub(super) fn crash_sensor_offset(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
    offset(r, name, i, "crash")
}

pub(super) fn safing_sensor_offset(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
    offset(r, name, i, "safing")
}

pub(super) fn dead(r: &mut ChaCha8Rng, name: &str, i: u64, target: &str) -> String {
    let t0 = r.gen_range(0.3..0.5);
    let v = drive_kph(r);
    let sensor =
        format!("dropouts = [{{ start_s = {t0}, end_s = 100.0, target = \"{target}\" }}]\n");
    driving(name, i, &ego(v, None), 1.0, &sensor, "")
}

pub(super) fn crash_sensor_dead(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
    dead(r, name, i, "accel")
}

pub(super) fn safing_sensor_dead(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
    dead(r, name, i, "safing")
}

pub(super) fn sensor_stuck(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
    let t0 = r.gen_range(0.3..0.5);
    let sensor = ["crash", "safing"][r.gen_range(0..2)];
    let kind = ["stuck", "saturated"][r.gen_range(0..2)];
    let len = r.gen_range(0.05..0.5);
    let v = drive_kph(r);
    let keys = format!(
        "accel_faults = [{{ start_s = {t0}, end_s = {}, kind = \"{kind}\", sensor = \"{sensor}\" }}]\n",
        t0 + len
    );
    driving(name, i, &ego(v, None), 1.0, &keys, "")
}

pub(super) fn sensor_noisy(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
    let t0 = r.gen_range(0.3..0.5);
    let sensor = ["crash", "safing"][r.gen_range(0..2)];
    let (rms, len) = (r.gen_range(1.0..10.0), r.gen_range(0.1..0.5));
    let ev = rough_road_event(t0, rms, t0 + len, sensor);
    let v = drive_kph(r);
    driving(name, i, &ego(v, None), 1.0, "", &ev)
}

pub(super) fn stuck_in_door_slam(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
    let t0 = r.gen_range(0.3..0.5);
    let ev = door_slam_event(r, t0);
    let stuck_at = t0 + r.gen_range(0.0..0.02);
    let keys = format!(
        "accel_faults = [{{ start_s = {stuck_at}, end_s = {}, kind = \"stuck\", sensor = \"crash\" }}]\n",
        stuck_at + 0.1
    );
    driving(name, i, &ego(0.0, None), 0.8, &keys, &ev)
}

pub(super) fn spike_in_pothole(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
    let t0 = r.gen_range(0.3..0.5);
    let dv = r.gen_range(0.6..0.8) * MARGIN;
    let mut ev = pothole_with_rebound(r, t0, dv);
    ev += &spike_event(
        t0 + r.gen_range(0.0..0.03),
        r.gen_range(150.0..199.0),
        "crash",
    );
    let v = drive_kph(r);
    driving(name, i, &ego(v, None), 0.8, "", &ev)
}

pub(super) fn offset_with_pothole(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
    let t0 = r.gen_range(0.3..0.5);
    let mut ev = {
        let dv = r.gen_range(0.1..0.3) * MARGIN;
        pothole_with_rebound(r, t0, dv)
    };
    let end_s = t0 + r.gen_range(0.1..0.5);
    ev += &offset_event(t0, r.gen_range(2.0..8.0) * MARGIN, end_s, "crash");
    let v = drive_kph(r);
    // The run goes on 0.1 s after the offset: whether the crash phase ends is judged after
    // the event, not while the faulty sensor still reports it.
    driving(name, i, &ego(v, None), end_s.max(0.9) + 0.1, "", &ev)
}

pub(super) fn aliased_ringing(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
    let t0: f64 = r.gen_range(0.3..0.5);
    // The crash sensor samples at k / 4 kHz: a crest on a sample instant.
    let on_grid = (t0 * 4000.0).round() / 4000.0;
    let ev = match r.gen_range(0..3) {
        0 => ringing(
            on_grid,
            r.gen_range(30.0..49.0) * MARGIN,
            4000.0,
            r.gen_range(3.0..4.0),
            0.0,
            0.0,
            "all",
        ),
        1 => ringing(
            on_grid,
            r.gen_range(30.0..45.0) * MARGIN,
            r.gen_range(3950.0..4050.0),
            r.gen_range(20.0..30.0),
            0.0,
            0.0,
            "all",
        ),
        _ => ringing(
            on_grid,
            r.gen_range(10.0..50.0) * MARGIN,
            [2000.0, 4000.0, 6000.0, 8000.0, 12000.0, 16000.0][r.gen_range(0..6)],
            r.gen_range(3.0..30.0),
            0.0,
            [0.0, 90.0, 180.0][r.gen_range(0..3)],
            "all",
        ),
    };
    let v = if r.gen_bool(0.5) { 0.0 } else { drive_kph(r) };
    driving(name, i, &ego(v, None), 0.8, "", &ev)
}

pub(super) fn braking_and_pothole(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
    let brake_at = r.gen_range(0.1..0.3);
    let t0 = brake_at + r.gen_range(0.2..0.5);
    let g = r.gen_range(0.6..1.0);
    let v = r.gen_range(50.0..110.0);
    let ev = if r.gen_bool(0.5) {
        {
            let dv = r.gen_range(0.72..0.76) * MARGIN;
            pothole_with_rebound(r, t0, dv)
        }
    } else {
        offset_event(
            t0,
            r.gen_range(0.5..1.3) * MARGIN,
            t0 + r.gen_range(0.1..0.5),
            "crash",
        )
    };
    driving(name, i, &ego(v, Some((brake_at, g))), 1.2, "", &ev)
}

pub(super) fn near_miss(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
    let v = r.gen_range(15.0..55.0); // each car: closing 30–110 km/h
    let tc = r.gen_range(0.45..0.6);
    let evade = tc - r.gen_range(0.001..0.05);
    let at = tc + r.gen_range(-0.02..0.02);
    let opp = r.gen_range(1000.0..2500.0);
    let ev = {
        let dv = r.gen_range(0.4..0.8) * MARGIN;
        pothole_with_rebound(r, at, dv)
    };
    head_on(name, i, v, opp, tc, Some(evade), tc + 0.4, "", &ev)
}

pub(super) fn misreported_low_speed(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
    let tc = r.gen_range(0.35..0.5);
    match r.gen_range(0..4) {
        0 => head_on(
            name,
            i,
            14.5,
            1785.0,
            tc,
            None,
            tc + 0.25,
            "mass_bias_kg = 2215\n",
            "",
        ),
        1 => head_on(
            name,
            i,
            16.0,
            1785.0,
            tc,
            None,
            tc + 0.25,
            "mass_bias_kg = 1015\n",
            "",
        ),
        2 => {
            // An opponent of 1 000–1 300 kg reported as 3 000–4 000 kg at an ego EBS of
            // 13–16 km/h (plastic: EBS = closing · m_opp / (m_ego + m_opp)).
            let m = r.gen_range(1000.0..1300.0);
            let ebs = r.gen_range(13.0..16.0);
            let v = ebs * (1785.0 + m) / m / 2.0;
            let bias = r.gen_range(3000.0..4000.0) - m;
            head_on(
                name,
                i,
                v,
                m,
                tc,
                None,
                tc + 0.25,
                &format!("mass_bias_kg = {bias}\n"),
                "",
            )
        }
        _ => barrier(name, i, 15.5, tc, "speed_bias_mps = 5.0\n", ""),
    }
}

pub(super) fn low_speed_crash_and_kerb(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
    // A quarter with the occupant unbelted, crash and kerb together as far below the unbelted
    // line: the kerb's Δv does not shrink with the line, so the crash's speed moves down by
    // the lines' difference.
    let belted = r.gen_bool(0.75);
    let dv_kph = if belted { 0.0 } else { UNBELTED_LINE_SHIFT_KPH };
    let tc = r.gen_range(0.35..0.5);
    let at = tc + r.gen_range(0.0..0.01);
    let kerb = {
        let dv = r.gen_range(0.5..0.8) * MARGIN;
        pothole_with_rebound(r, at, dv)
    };
    let text = if r.gen_bool(0.5) {
        barrier(name, i, r.gen_range(12.0..16.0) - dv_kph, tc, "", &kerb)
    } else {
        head_on(
            name,
            i,
            r.gen_range(12.0..15.0) - dv_kph,
            1785.0,
            tc,
            None,
            tc + 0.25,
            "",
            &kerb,
        )
    };
    if belted {
        text
    } else {
        unbelted(&text)
    }
}

/// One crush-zone satellite faulty while the whole car takes a pothole: saturated or stuck, a
/// 60–200 g spike, or a 20–200 g offset (a deceleration, the direction a crush reads), on either
/// satellite, starting within ±20 ms of the pothole. The other satellite sees only the body.
pub(super) fn satellite_fault_in_pothole(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
    let t0 = r.gen_range(0.3..0.5);
    let dv = r.gen_range(0.6..0.8) * MARGIN;
    let mut ev = pothole_with_rebound(r, t0, dv);
    let sat = ["satellite-left", "satellite-right"][r.gen_range(0..2)];
    let tf = t0 + r.gen_range(-0.02..0.02);
    let len = r.gen_range(0.02..0.3);
    let mut keys = String::new();
    match r.gen_range(0..3) {
        0 => {
            let kind = ["stuck", "saturated"][r.gen_range(0..2)];
            keys = format!(
                "accel_faults = [{{ start_s = {tf}, end_s = {}, kind = \"{kind}\", sensor = \"{sat}\" }}]\n",
                tf + len
            );
        }
        1 => ev += &spike_event(tf, r.gen_range(60.0..200.0), sat),
        _ => ev += &offset_event(tf, r.gen_range(20.0..200.0), tf + len, sat),
    }
    let v = drive_kph(r);
    let duration_s = (tf + len + JUDGED_AFTER_S).max(0.8);
    driving(name, i, &ego(v, None), duration_s, &keys, &ev)
}

/// A must-fire barrier crash with one crush-zone satellite dead, stuck at rest from before the
/// crash, or saturated from 50 ms before contact: the faulty one is out of the fusion (stale,
/// or lagging the body once the crash begins) or cannot raise the smaller crush Δv; the other
/// one's relief decides.
pub(super) fn must_fire_satellite_fault(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
    let (v, tc) = (r.gen_range(35.0..56.0), r.gen_range(0.35..0.5));
    let sat = ["satellite-left", "satellite-right"][r.gen_range(0..2)];
    let keys = match r.gen_range(0..3) {
        0 => format!("dropouts = [{{ start_s = 0.2, end_s = 100.0, target = \"{sat}\" }}]\n"),
        1 => format!(
            "accel_faults = [{{ start_s = 0.2, end_s = 100.0, kind = \"stuck\", sensor = \"{sat}\" }}]\n"
        ),
        _ => format!(
            "accel_faults = [{{ start_s = {}, end_s = 100.0, kind = \"saturated\", sensor = \"{sat}\" }}]\n",
            tc - 0.05
        ),
    };
    barrier(name, i, v, tc, &keys, "")
}
