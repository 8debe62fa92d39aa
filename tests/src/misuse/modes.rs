//! The crash-mode matrix (`physics::crash_mode`): must-fire and no-fire crashes in every mode
//! besides the full frontal — a 40 % offset deformable barrier, a car struck with part of its
//! width, an angled wall, a centre pole, a truck's bed — at the speeds a crash-sensing
//! calibration is judged on, the object list alive or dead, the struck side either.

use super::text::*;
use super::*;

/// A crash into a fixed opponent of `kind` (its `keys` after the kind) at `v` km/h, contact
/// at `tc` s, judged for 0.35 s after it (the softer modes' contacts last up to 200 ms).
fn fixed(name: &str, i: u64, kind: &str, keys: &str, v: f64, tc: f64, sensor: &str) -> String {
    driving(name, i, &ego(v, None), tc + 0.35, sensor, "").replace(
        "kind = \"barrier\"\ninitial_distance_m = 900.0",
        &format!(
            "kind = \"{kind}\"\n{keys}initial_distance_m = {}",
            v / 3.6 * tc
        ),
    )
}

fn struck_side(r: &mut ChaCha8Rng) -> &'static str {
    if r.gen_bool(0.5) {
        "struck_side = \"left\"\n"
    } else {
        "struck_side = \"right\"\n"
    }
}

fn objects(r: &mut ChaCha8Rng) -> &'static str {
    if r.gen_bool(0.5) {
        OBJECTS_DEAD
    } else {
        ""
    }
}

/// A 40 % (35–50 %) offset deformable barrier at 40–64 km/h, or equal cars at 35 + 35 to
/// 56 + 56 km/h overlapping by 35–60 % of the width.
pub(super) fn must_fire_offset(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
    let tc = r.gen_range(0.35..0.5);
    let overlap: f64 = r.gen_range(35.0..60.0);
    let side = struck_side(r);
    let dead = objects(r);
    if r.gen_bool(0.5) {
        let v = r.gen_range(40.0..64.0);
        let keys = format!("overlap_percent = {:.1}\n{side}", f64::min(overlap, 50.0));
        fixed(name, i, "offset_barrier", &keys, v, tc, dead)
    } else {
        let v = r.gen_range(35.0..56.0);
        equal_class(head_on(name, i, v, 1785.0, tc, None, tc + 0.35, dead, "")).replace(
            "kind = \"vehicle\"\n",
            &format!("kind = \"vehicle\"\noverlap_percent = {overlap:.1}\n{side}"),
        )
    }
}

/// A rigid wall at 15–30° to the front: unbelted at 32–48 km/h (the FMVSS 208 oblique test,
/// ±30° at up to 40 km/h unbelted), belted at 40–56 km/h (at 30° the wall arrests 0.75 of the
/// speed: 40 km/h is a 33 km/h wall's Δv, over the belted must-fire line).
pub(super) fn must_fire_angular(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
    let belted = r.gen_bool(0.5);
    let v = if belted {
        r.gen_range(40.0..56.0)
    } else {
        r.gen_range(32.0..48.0)
    };
    let tc = r.gen_range(0.35..0.5);
    let keys = format!(
        "angle_deg = {:.1}\n{}",
        r.gen_range(15.0..30.0),
        struck_side(r)
    );
    let text = fixed(name, i, "barrier", &keys, v, tc, objects(r));
    if belted {
        text
    } else {
        unbelted(&text)
    }
}

/// A centre pole at 32–50 km/h.
pub(super) fn must_fire_pole(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
    let (v, tc) = (r.gen_range(32.0..50.0), r.gen_range(0.35..0.5));
    fixed(name, i, "pole", "", v, tc, objects(r))
}

/// The bed of a standing 8–30 t truck at 40–60 km/h, tracked with its true mass or untracked.
pub(super) fn must_fire_underride(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
    let (v, tc) = (r.gen_range(40.0..60.0), r.gen_range(0.35..0.5));
    let keys = format!("mass_kg = {:.0}\n", r.gen_range(8_000.0..30_000.0));
    fixed(name, i, "underride", &keys, v, tc, objects(r)).replace("mass_estimate_kg = 3000\n", "")
}

/// Below the no-fire line in the soft modes: an offset deformable barrier at 12–24 km/h, a
/// centre pole at 10–20 km/h.
pub(super) fn no_fire_mode(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
    let tc = r.gen_range(0.35..0.5);
    let dead = objects(r);
    if r.gen_bool(0.5) {
        let v = r.gen_range(12.0..24.0);
        let keys = format!(
            "overlap_percent = {:.1}\n{}",
            r.gen_range(35.0..50.0),
            struck_side(r)
        );
        fixed(name, i, "offset_barrier", &keys, v, tc, dead)
    } else {
        fixed(name, i, "pole", "", r.gen_range(10.0..20.0), tc, dead)
    }
}

/// A light car (800–1 300 kg, its own class) struck with 35–60 % of the width at an ego EBS
/// of 10–16 km/h — a closing speed of 30–45 km/h: its struck rail crushes like a must-fire
/// offset crash's while the ego's velocity change stays below the no-fire line. Objects
/// alive (true mass) or dead.
pub(super) fn no_fire_light_offset(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
    let m = r.gen_range(800.0..1300.0);
    let ebs = r.gen_range(10.0..16.0);
    let v = ebs * (1785.0 + m) / m / 2.0;
    let tc = r.gen_range(0.35..0.5);
    let overlap = r.gen_range(35.0..60.0);
    let side = struck_side(r);
    head_on(name, i, v, m, tc, None, tc + 0.35, objects(r), "").replace(
        "kind = \"vehicle\"\n",
        &format!("kind = \"vehicle\"\noverlap_percent = {overlap:.1}\n{side}"),
    )
}
