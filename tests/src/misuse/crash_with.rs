//! Must-fire crashes with one thing before or inside them: a misuse event of the envelope
//! table, one unflagged sensor fault, a heavy opponent, an object fault that makes the table
//! plan the belt only — and, on the other side of the line, low-speed crashes with a kerb
//! strike when the tracked low-speed rule cannot help.
//!
//! A must-fire variant is the clean crash's text, then [`ADDED`], then what this family adds:
//! the matrix runs the clean twin (the text before the marker) too and bounds the variant's
//! fire − required by the twin's + [`LATE_VS_CLEAN_MS`].

use super::text::*;
use super::*;

/// The line between a must-fire variant's clean crash and what its family adds to it.
pub const ADDED: &str = "# added to the clean crash\n";

/// How much later than its clean twin a must-fire variant may fire its airbag, ms (against
/// "127 mm − 30 ms" of each; a µs more for the sum of two sample grids).
pub const LATE_VS_CLEAN_MS: f64 = 2.0;

/// Families whose variants carry a sensor fault: not counted in the two healthy sensors'
/// severity agreement the matrix reports.
pub const FAULTY_SENSOR_FAMILIES: &[&str] = &["must-fire-sensor-fault"];

/// The clean twin of a variant's text (itself when the family adds nothing after [`ADDED`]).
pub fn clean_twin(text: &str) -> Option<&str> {
    text.split_once(ADDED).map(|(clean, _)| clean)
}

/// A must-fire crash, tracked: a rigid barrier at 35–56 km/h or equal cars at 35 + 35 to
/// 56 + 56 km/h (class 4 as the ego), contact at `tc`.
fn must_fire_base(r: &mut ChaCha8Rng, name: &str, i: u64, tc: f64, min_kph: f64) -> String {
    let v = r.gen_range(min_kph..56.0);
    if r.gen_bool(0.5) {
        barrier(name, i, v, tc, "", "")
    } else {
        equal_class(head_on(name, i, v, 1785.0, tc, None, tc + 0.25, "", ""))
    }
}

/// One misuse event of the envelope table 0–200 ms before, or during the first 5 ms of, the
/// contact of a must-fire crash: a kerb strike, a pothole, a rough road up to contact, ABS
/// braking, a shunt from behind, or a door slam on a standing car struck at 70–110 km/h.
pub(super) fn event_before_crash(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
    let tc = r.gen_range(0.45..0.6);
    let at = tc - r.gen_range(-0.005..0.2);
    match r.gen_range(0..6) {
        0 => {
            let text = must_fire_base(r, name, i, tc, 35.0);
            text + ADDED + &wheel_event(r, at, &KERB, KERB.dv_mps)
        }
        1 => {
            let text = must_fire_base(r, name, i, tc, 35.0);
            text + ADDED + &wheel_event(r, at, &POTHOLE, POTHOLE.dv_mps)
        }
        2 => {
            let text = must_fire_base(r, name, i, tc, 35.0);
            let start = tc - r.gen_range(0.05..0.4);
            let rms = r.gen_range(0.5..3.0 * MARGIN);
            let end = tc + r.gen_range(-0.02..0.1);
            text + ADDED + &rough_road_event(start, rms, end, "all")
        }
        3 => {
            // ABS braking from 0–200 ms before contact: the crash is slower than its clean
            // twin, so the bases start at 45 km/h to stay above the must-fire line.
            let text = must_fire_base(r, name, i, tc, 45.0);
            let g = r.gen_range(0.6..1.0);
            text + ADDED
                + &format!(
                    "[ego.braking]\nstart_s = {}\ndecel_mps2 = {}\nstate = \"abs\"\n",
                    at.min(tc),
                    g * G
                )
        }
        4 => {
            // A shunt from behind: a forward (negative) rigid-body pulse of 2–8 g × 40–120 ms,
            // over by contact at the latest.
            let text = must_fire_base(r, name, i, tc, 35.0);
            let ms = r.gen_range(40.0..120.0);
            let start = tc - r.gen_range(ms * 1e-3..0.2_f64.max(ms * 1e-3 + 0.01));
            text + ADDED + &half_sine(start, -r.gen_range(2.0..8.0), ms, "all")
        }
        _ => {
            // A standing car: a door slammed 0–200 ms before it is struck by an equal car.
            let v = r.gen_range(70.0..110.0);
            let text = format!(
                "name = \"{name}\"\nseed = {i}\nduration_s = {}\n{}\
                 [opponent]\nkind = \"vehicle\"\nclass = 4\nmass_kg = 1785\nspeed_kph = {v}\n\
                 initial_distance_m = {}\n[sensor]\n{OCCUPANT}",
                tc + 0.25,
                ego(0.0, None),
                v / 3.6 * tc,
            );
            text + ADDED + &door_slam_event(r, at.min(tc - 0.02))
        }
    }
}

/// One unflagged fault of one sensor inside a must-fire crash: noise of 0.5–10 g rms from
/// before contact through the crash, a spike of 10–200 g, or an offset of ±2–8 g, on the
/// crash or the safing sensor.
pub(super) fn fault_inside_crash(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
    let tc = r.gen_range(0.45..0.6);
    let text = must_fire_base(r, name, i, tc, 35.0);
    let sensor = ["crash", "safing"][r.gen_range(0..2)];
    let fault = match r.gen_range(0..3) {
        0 => {
            let start = tc - r.gen_range(0.0..0.2);
            rough_road_event(start, r.gen_range(0.5..10.0), tc + 0.2, sensor)
        }
        1 => spike_event(
            tc + r.gen_range(-0.01..0.03),
            r.gen_range(10.0..200.0),
            sensor,
        ),
        _ => {
            let start = tc - r.gen_range(0.0..0.2);
            let g = r.gen_range(2.0..8.0) * if r.gen_bool(0.5) { 1.0 } else { -1.0 };
            offset_event(start, g, tc + 0.2, sensor)
        }
    };
    text + ADDED + &fault
}

/// A heavy opponent (5–10 t, the world's range) standing or moving, the ego at an EBS of
/// 35–56 km/h, tracked with its true mass, misreported by ±1 200 kg, or reported as a car.
pub(super) fn heavy_opponent(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
    let m = r.gen_range(5000.0..10000.0);
    let ebs = r.gen_range(35.0..56.0);
    let closing = ebs * (1785.0 + m) / m;
    let tc = r.gen_range(0.45..0.6);
    let standing = r.gen_bool(0.5);
    let (ego_kph, opp_kph) = if standing {
        (closing, 0.0)
    } else {
        let opp = r.gen_range(0.2..0.6) * closing;
        (closing - opp, opp)
    };
    let keys = match r.gen_range(0..3) {
        0 => String::new(),
        1 => format!("mass_bias_kg = {}\n", r.gen_range(-1200.0..1200.0)),
        _ => format!("mass_estimate_kg = {}\n", r.gen_range(1200.0..2000.0)),
    };
    format!(
        "name = \"{name}\"\nseed = {i}\nduration_s = {}\n{}\
         [opponent]\nkind = \"vehicle\"\nmass_kg = {m}\nspeed_kph = {opp_kph}\n\
         initial_distance_m = {}\n[sensor]\n{keys}{OCCUPANT}",
        tc + 0.25,
        ego(ego_kph, None),
        closing / 3.6 * tc,
    )
}

/// Below the no-fire line with a kerb strike (as `low-speed-crash-and-kerb`) when the tracked
/// low-speed rule cannot help: the object list dead, the object at low confidence, or its
/// mass over-reported by up to 1 200 kg.
pub(super) fn low_speed_kerb_untracked(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
    let text = super::faults::low_speed_crash_and_kerb(r, name, i);
    // A barrier is reported as `mass_estimate_kg` (3 000 kg): no bias to add to it.
    let faults = if text.contains("mass_estimate_kg") {
        2
    } else {
        3
    };
    let keys = match r.gen_range(0..faults) {
        0 => OBJECTS_DEAD.to_owned(),
        1 => format!("confidence = {}\n", r.gen_range(0.05..0.5)),
        _ => format!("mass_bias_kg = {}\n", r.gen_range(0.0..1200.0)),
    };
    text.replacen("[sensor]\n", &format!("[sensor]\n{keys}"), 1)
}
