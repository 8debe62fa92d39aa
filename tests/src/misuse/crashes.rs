//! Crashes: below the no-fire line, must-fire, misreported, and the beyond-physics sweep.

use super::text::*;
use super::*;

/// A barrier below the no-fire line, objects live or dead; a quarter of them with the
/// occupant unbelted, below the unbelted line.
pub(super) fn no_fire_crash(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
    let (v, tc) = (r.gen_range(8.0..16.0), r.gen_range(0.35..0.5));
    let dead = if r.gen_bool(0.5) { OBJECTS_DEAD } else { "" };
    if r.gen_bool(0.25) {
        unbelted(&barrier(name, i, v * UNBELTED_LINE_RATIO, tc, dead, ""))
    } else {
        barrier(name, i, v, tc, dead, "")
    }
}

pub(super) fn must_fire_crash(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
    let (v, tc) = (r.gen_range(35.0..56.0), r.gen_range(0.35..0.5));
    let dead = if r.gen_bool(0.5) { OBJECTS_DEAD } else { "" };
    barrier(name, i, v, tc, dead, "")
}

/// A crash between the no-fire and the must-fire lines: a 20–30 km/h barrier or equal cars
/// at 20 + 20 to 30 + 30 km/h, objects live or dead, the occupant belted or not.
pub(super) fn grey_zone(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
    let (v, tc) = (r.gen_range(20.0..30.0), r.gen_range(0.35..0.5));
    let dead = if r.gen_bool(0.5) { OBJECTS_DEAD } else { "" };
    let text = if r.gen_bool(0.5) {
        barrier(name, i, v, tc, dead, "")
    } else {
        equal_class(head_on(name, i, v, 1785.0, tc, None, tc + 0.25, dead, ""))
    };
    if r.gen_bool(0.5) {
        text
    } else {
        unbelted(&text)
    }
}

pub(super) fn must_fire_car(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
    let (v, tc) = (r.gen_range(35.0..56.0), r.gen_range(0.35..0.5));
    let v2x = v2x_station(r, true);
    equal_class(head_on(name, i, v, 1785.0, tc, None, tc + 0.25, "", &v2x))
}

pub(super) fn must_fire_misreported(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
    // Opponent 1000–2800 kg at speeds for an ego EBS of 35–56 km/h, the object sensor's mass
    // off by ±1200 kg or its closing speed by ±5 m/s.
    let m = r.gen_range(1000.0..2800.0);
    let ebs = r.gen_range(35.0..56.0);
    let v = ebs * (1785.0 + m) / m / 2.0;
    let tc = r.gen_range(0.35..0.5);
    let keys = if r.gen_bool(0.5) {
        format!("mass_bias_kg = {}\n", r.gen_range(-1200.0..1200.0))
    } else {
        format!("speed_bias_mps = {}\n", r.gen_range(-5.0..5.0))
    };
    // A true station only: the object list is this case's one fault.
    let v2x = v2x_station(r, false);
    head_on(name, i, v, m, tc, None, tc + 0.25, &keys, &v2x)
}

pub(super) fn must_fire_safing_dead(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
    let (v, tc) = (r.gen_range(35.0..56.0), r.gen_range(0.35..0.5));
    barrier(
        name,
        i,
        v,
        tc,
        "dropouts = [{ start_s = 0.2, end_s = 100.0, target = \"safing\" }]\n",
        "",
    )
}

pub(super) fn beyond_physics(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
    let t0 = r.gen_range(0.3..0.5);
    let ev = half_sine(t0, r.gen_range(3.0..15.0), r.gen_range(5.0..20.0), "all");
    let v = drive_kph(r);
    driving(name, i, &ego(v, None), 0.8, "", &ev)
}
