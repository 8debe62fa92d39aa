//! Misuse as physics makes it: the families of mechanical events.

use super::text::*;
use super::*;

pub(super) fn drive_kph(r: &mut ChaCha8Rng) -> f64 {
    r.gen_range(30.0..110.0)
}

pub(super) fn pothole(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
    let (t0, v) = (r.gen_range(0.3..0.5), drive_kph(r));
    let ev = pothole_events(r, t0, v / 3.6, 0.9);
    driving(name, i, &ego(v, None), 0.9, "", &ev)
}

pub(super) fn kerb_strike(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
    let (t0, v) = (r.gen_range(0.3..0.5), r.gen_range(10.0..50.0));
    let ev = wheel_event(r, t0, &KERB, KERB.dv_mps);
    driving(name, i, &ego(v, None), 0.8, "", &ev)
}

/// A standing car's panel or housing event (door, hood, hammer): ringing with amplitude,
/// frequency and length drawn from their ranges and a net Δv within ±`dv_mps` × 1.5.
pub(super) fn panel_event(
    r: &mut ChaCha8Rng,
    t0: f64,
    peak_g: (f64, f64),
    f_hz: (f64, f64),
    ms: (f64, f64),
    dv_mps: f64,
) -> String {
    ringing(
        t0,
        r.gen_range(peak_g.0..peak_g.1),
        r.gen_range(f_hz.0..f_hz.1),
        r.gen_range(ms.0..ms.1),
        r.gen_range(-dv_mps..dv_mps) * MARGIN,
        r.gen_range(0.0..360.0),
        "all",
    )
}

pub(super) fn door_slam_event(r: &mut ChaCha8Rng, t0: f64) -> String {
    panel_event(
        r,
        t0,
        (0.5, 40.0 * MARGIN),
        (125.0, 250.0),
        (20.0, 100.0),
        0.01,
    )
}

pub(super) fn door_slam(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
    let t0 = r.gen_range(0.3..0.5);
    driving(name, i, &ego(0.0, None), 0.8, "", &door_slam_event(r, t0))
}

pub(super) fn hood_slam(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
    let t0 = r.gen_range(0.3..0.5);
    let ev = panel_event(
        r,
        t0,
        (0.5, 3.0 * MARGIN),
        (20.0, 300.0),
        (20.0, 100.0),
        0.06,
    );
    driving(name, i, &ego(0.0, None), 0.8, "", &ev)
}

pub(super) fn hammer_blow(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
    let t0 = r.gen_range(0.3..0.5);
    let ev = panel_event(
        r,
        t0,
        (100.0, 1000.0 * MARGIN),
        (1000.0, 10_000.0),
        (0.2, 2.0),
        0.01,
    );
    driving(name, i, &ego(0.0, None), 0.8, "", &ev)
}

pub(super) fn rough_road(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
    let t0 = r.gen_range(0.3..0.5);
    // Durations up to 5 s, most short (a long one costs its length in run time).
    let len = if r.gen_bool(0.1) {
        r.gen_range(1.0..5.0)
    } else {
        r.gen_range(0.3..1.0)
    };
    let ev = rough_road_event(t0, r.gen_range(0.5..3.0 * MARGIN), t0 + len, "all");
    let v = drive_kph(r);
    driving(name, i, &ego(v, None), t0 + len + 0.1, "", &ev)
}

pub(super) fn speed_bump(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
    let (t0, v) = (r.gen_range(0.3..0.5), r.gen_range(30.0..80.0));
    let mut ev = String::new();
    for at in [t0, t0 + WHEELBASE_M / (v / 3.6)] {
        // Each axle's burst carries a deceleration up to the bound (the up-and-down of a
        // real bump, whose net is ≈ 0, is not assumed: the conservative sign).
        let up = wheel_event(r, at, &SPEED_BUMP, SPEED_BUMP.dv_mps);
        ev += &up;
    }
    driving(name, i, &ego(v, None), 0.9, "", &ev)
}

pub(super) fn jump_landing(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
    let (t0, v) = (r.gen_range(0.3..0.5), drive_kph(r));
    let ev = wheel_event(r, t0, &JUMP_LANDING, JUMP_LANDING.dv_mps);
    driving(name, i, &ego(v, None), 0.8, "", &ev)
}

pub(super) fn animal_strike(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
    let (t0, v) = (r.gen_range(0.3..0.5), r.gen_range(40.0..110.0));
    // Roe deer (≤ 25 kg): v·m_a/(m_a + m_car)·(1 + e), e ≤ 0.3.
    let dv_bound = v / 3.6 * 25.0 / (25.0 + 1785.0) * 1.3;
    let ev = wheel_event(r, t0, &ANIMAL, dv_bound);
    driving(name, i, &ego(v, None), 0.8, "", &ev)
}

pub(super) fn kerb_at_predicted_contact(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
    let v = r.gen_range(20.0..55.0);
    let tc = r.gen_range(0.45..0.6);
    let opp = r.gen_range(1000.0..2500.0);
    let mut ev = wheel_event(r, tc, &KERB, KERB.dv_mps);
    ev += &v2x_station(r, true);
    head_on(name, i, v, opp, tc, Some(tc - 0.001), tc + 0.3, "", &ev)
}

pub(super) fn ghost_object_and_pothole(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
    let v = r.gen_range(20.0..55.0);
    let tc = r.gen_range(0.45..0.6);
    let evade = tc - r.gen_range(0.001..0.3);
    let at = r.gen_range(evade - 0.1..tc + 0.05);
    let opp = r.gen_range(1000.0..2500.0);
    let mut ev = pothole_events(r, at, v / 3.6, tc + 0.3);
    ev += &v2x_station(r, true);
    head_on(name, i, v, opp, tc, Some(evade), tc + 0.3, "", &ev)
}
