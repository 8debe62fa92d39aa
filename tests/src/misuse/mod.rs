//! The misuse / single-fault / must-fire catalogue of `misuse-matrix`:
//! seeded families of scenarios, each built in code from the documented scenario schema and
//! judged by what its family requires.
//!
//! ## Misuse as physics makes it
//! A mechanical event changes the car's speed by the impulse its contact can carry,
//! Δv = J / m (J = ∫F dt); what the tunnel-mounted ECU measures on top is zero-mean structural
//! ringing, which can be large while its integral is zero. Each misuse family is therefore a
//! `ringing` `[[accel_event]]` (`world::events`: zero-mean ringing over a rigid-body pulse that
//! carries exactly `net_dv_mps`) with its envelope below, and every variant is drawn up to
//! **1.5 × the envelope's bounds** (Δv, rigid-body peak, ringing amplitude; durations and
//! frequencies over the envelope's range). S = from a published source, D = derived from the
//! stated physics (`../shared/misuse-envelopes.md` has the derivations and links).
//!
//! | family | net Δv bound (× 1.5 sampled) | rigid-body peak | ringing | duration | source |
//! |---|---|---|---|---|---|
//! | pothole (30–110 km/h) | 0.8 m/s, both front wheels (1.2) | 5 g (7.5) | 10 g at 10–300 Hz (15) | 10–30 ms, rear axle again a wheelbase / v later | D: wheel-centre force ≈ 4.5 × static corner load (23 kN typical, 45 kN worst) over 10–30 ms |
//! | kerb-strike (climbed, 10–50 km/h) | 0.8 m/s (1.2) | 7 g (10.5) | 10 g at 20–300 Hz (15) | 10–30 ms | D: the edge force leans back by θ, tan θ ≈ 1.0–1.5 for a 100–150 mm kerb |
//! | door-slam (standing) | 0.01 m/s (0.015) | — | 40 g at 125–250 Hz, lobes of 2–4 ms (60) | 20–100 ms | D: 30 kg door at ≤ 3 m/s; the ringing amplitude 15–40 g, above the table's 0.5–3 g |
//! | hood-slam (standing) | 0.06 m/s (0.09) | — | 3 g at 20–300 Hz (4.5) | 20–100 ms | D: hood / boot mass × closing speed |
//! | hammer-blow (standing) | 0.01 m/s (0.015) | — | 1 000 g at 1–10 kHz (1 500) | 0.2–2 ms | D: 1 kg head at ≤ 10 m/s; S: ISO 16750-3 shock is at the door, not the tunnel |
//! | rough-road (driving) | ≈ 0 (zero-mean band-limited) | crest factor 3 (13.5 g at 4.5 g rms) | 3 g rms (4.5), 5–40 Hz, from rest | 0.3–5 s | the envelope fixes ≥ 3 g rms for up to 5 s (≈ 10 × the table's 0.3 g); S: random-vibration drive signals are clipped at 3σ (IEC 60068-2-64 asks for a crest factor ≥ 2.5); D: a 4σ lobe at 4.5 g rms is 300 kN through the wheels |
//! | speed-bump (30–80 km/h) | 0.3 m/s per axle (0.45), net ≈ 0 | 3 g (4.5) | 3 g at 10–100 Hz (4.5) | 20–60 ms per axle, two bursts a wheelbase / v apart | D |
//! | jump-landing (30–110 km/h) | 0.6 m/s (0.9) | 5 g (7.5) | 5 g at 10–100 Hz (7.5) | 20–80 ms | D: x as the sensor sees a vertical landing |
//! | animal-strike (roe deer, 40–110 km/h) | 0.4 m/s (0.6) | one-signed | 5 g at 20–200 Hz (7.5) | 20–60 ms | D: 25 kg at 100 km/h, v·m_a/(m_a + m_car)·(1+e) |
//!
//! The one-signed half-sine sweep (the whole area a velocity change of the car:
//! a 15 g × 20 ms "pothole" is Δv 1.87 m/s, a 260 kN longitudinal peak) stays as the
//! **beyond-physics** report: printed, where each floor sits, not a gate.
//!
//! ## Single faults inside real events
//! | family | what | requirement |
//! |---|---|---|
//! | stuck-crash-sensor-in-door-slam | door slam (as above) on a standing car while the crash sensor sticks for 100 ms | no fire |
//! | spike-in-pothole | one 150–199 g crash-sensor sample inside a 0.6–0.8 m/s pothole with rebound | no fire |
//! | offset-with-pothole | a +8 g crash-sensor offset (0.1–0.5 s) starting with a 0.3 m/s pothole | no fire |
//! | satellite-fault-in-pothole | one crush-zone satellite saturated or stuck, a 60–200 g spike or a 20–200 g offset on it, within ±20 ms of a 0.6–0.8 m/s pothole with rebound (× 1.5) | no fire |
//! | misreported-low-speed | a crash below the no-fire line with one object fault: 14.5 + 14.5 km/h equal cars reported 4 000 kg; 16 + 16 km/h reported 2 800 kg; 1 000–1 300 kg opponents reported 3 000–4 000 kg at an EBS of 13–16 km/h; a 15.5 km/h barrier with the speed reported 5 m/s high | no airbag |
//! | aliased-ringing | zero-mean ringing near 4 kHz in phase with the samples (±30–49 g × 1.5, 3–4 ms), at 3.95–4.05 kHz (±30–45 g × 1.5, 20–30 ms), or at a multiple of either sampling rate (2, 4, 8, 12, 16 kHz) | no fire |
//! | low-speed-crash-and-kerb | a 12–16 km/h barrier or 12 + 12 to 15 + 15 km/h cars (unbelted: − 6 km/h), tracked, with a kerb strike of 0.5–0.8 m/s (× 1.5) 0–10 ms after contact | no airbag |
//! | braking-and-pothole | ABS braking at 0.6–1 g with a 0.72–0.76 m/s pothole with rebound (× 1.5: up to 1.14), or with a 0.5–1.3 g crash-sensor offset | no fire |
//! | near-miss | closing 40–110 km/h (and 30 + 30), the opponent evading 1–50 ms before the predicted contact, a 0.4–0.8 m/s pothole (× 1.5) within ±20 ms of it; also: the ECU must not stay in CrashDetected | no fire, back to Normal |
//!
//! ## Faults and must-fire crashes
//! Spikes, offsets, dead / stuck / noisy sensors, crashes below the no-fire line and must-fire
//! crashes (with a misreported opponent, with a dead safing sensor, with one crush-zone
//! satellite dead, stuck or saturated) keep their ranges (table in [`FAMILIES`]' docs).
//!
//! ## Must-fire crashes with one thing before or inside them (`crash_with`)
//! | family | what | requirement |
//! |---|---|---|
//! | must-fire-after-event | a must-fire barrier or equal-car crash, tracked, with one misuse event of the table above 0–200 ms before or 0–5 ms into contact (kerb, pothole, rough road, ABS braking, a shunt from behind, a door slam on a standing car struck at 70–110 km/h) | airbag, no more than 2 ms later than its clean twin's against "127 mm − 30 ms" |
//! | must-fire-sensor-fault | the same crashes with one unflagged fault of one sensor (noise 0.5–10 g rms, a 10–200 g spike, a ±2–8 g offset) | as above |
//! | must-fire-heavy-opponent | 5–10 t opponents (the world's range), standing or moving, at an EBS of 35–56 km/h, tracked true, misreported by ±1 200 kg or reported as a car | airbag |
//! | low-speed-crash-and-kerb-untracked | low-speed-crash-and-kerb with the object list dead, at low confidence or its mass over-reported | no airbag |
//!
//! ## Between the lines (`crashes`)
//! | family | what | requirement |
//! |---|---|---|
//! | grey-zone | a 20–30 km/h barrier or equal cars at 20 + 20 to 30 + 30 km/h, objects live or dead, the occupant belted or not | by outcome: the airbag must fire where the reference restraint's airbag is what keeps the occupant from bottoming out (its belt alone bottoms out in the true pulse, with its airbag at the reference time the occupant does not), and the occupant must not bottom out under what the ECU fired — unless the airbag fired by its required time and the reference restraint fired at that same instant bottoms out too (the ECU's cycle against the reference's ideal instant); elsewhere printed |
//!
//! ## Crash modes (`modes`, `physics::crash_mode`)
//! | family | what | requirement |
//! |---|---|---|
//! | no-fire-mode | an offset deformable barrier (35–50 %) at 12–24 km/h, a centre pole at 10–20 km/h, objects live or dead | no airbag |
//! | no-fire-light-offset | an 800–1 300 kg car struck with 35–60 % of the width at an ego EBS of 10–16 km/h: closing at 30–45 km/h, its struck rail crushes like a must-fire offset crash's | no airbag |
//! | must-fire-offset | an offset deformable barrier (35–50 %) at 40–64 km/h, or equal cars 35 + 35 to 56 + 56 km/h overlapping by 35–60 % | airbag |
//! | must-fire-angular | a rigid wall at 15–30°: unbelted at 32–48 km/h (FMVSS 208 oblique), belted at 40–56 km/h | airbag |
//! | must-fire-pole | a centre pole at 32–50 km/h | airbag |
//! | must-fire-underride | a standing 8–30 t truck's bed at 40–60 km/h | airbag |
//!
//! ## The occupant
//! Every variant seats a 75 kg occupant at 300 mm, belted, except: a quarter of every no-fire
//! family's variants (misuse and single faults) seat them unbelted — the ECU then judges the
//! airbag against its lower unbelted boundary, whose floors hold the same misuse events; a
//! quarter of `no-fire-crash` is unbelted at its speeds × 0.7 (the unbelted no-fire line, 14
//! km/h, over the belted one, 20), and a quarter of `low-speed-crash-and-kerb` and `-untracked`
//! at its speeds − 6 km/h (the kerb's Δv does not shrink with the line: crash and kerb
//! together stay as far below it); half of `grey-zone` is unbelted.
//!
//! Required fire time of a must-fire crash: the classic "127 mm − 30 ms" criterion — the
//! instant a free-flying (unbelted) occupant has moved 127 mm relative to the compartment in
//! the TRUE pulse, minus 30 ms.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

mod crash_with;
mod crashes;
mod events;
mod faults;
mod modes;
mod text;

use crash_with::*;
pub use crash_with::{clean_twin, ADDED, FAULTY_SENSOR_FAMILIES, LATE_VS_CLEAN_MS};
use crashes::*;
use events::*;
use faults::*;
use modes::*;

/// What a family requires.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Requirement {
    /// No restraint may fire (airbag, pyrotechnic pretensioner), and the ECU returns from a
    /// crash phase that fired nothing.
    NoFire,
    /// The airbag must not fire (a crash below the no-fire line; the belt may act).
    NoAirbag,
    /// The airbag must fire.
    MustFire,
    /// Judged by the occupant's outcome: the airbag must fire where the reference restraint's
    /// airbag is what keeps the occupant from bottoming out (its belt alone bottoms out, with
    /// the airbag it does not); elsewhere its fires are printed.
    ByOutcome,
    /// Printed, not judged: the beyond-physics sweep (where each floor sits).
    Report,
}

impl Requirement {
    /// The requirement in words (`misuse-matrix --list`).
    pub fn label(self) -> &'static str {
        match self {
            Self::NoFire => "no fire",
            Self::NoAirbag => "no airbag",
            Self::MustFire => "must fire",
            Self::ByOutcome => "by outcome",
            Self::Report => "report only",
        }
    }
}

/// One family of the matrix.
pub struct Family {
    /// Its name (`--family`).
    pub name: &'static str,
    /// What its variants sample (`misuse-matrix --list`; the sources are in the module docs).
    pub envelope: &'static str,
    /// What it requires.
    pub requirement: Requirement,
    /// The scenario file text of one variant, from its own random stream.
    make: fn(&mut ChaCha8Rng, &str, u64) -> String,
}

/// 1.5 × the envelope: every physical bound is sampled up to this multiple.
pub const MARGIN: f64 = 1.5;
const G: f64 = 9.806_65;
/// Ego wheelbase [m] (the rear axle meets an edge a wheelbase / v after the front).
const WHEELBASE_M: f64 = 2.7;

/// Every family, gate families first.
pub const FAMILIES: &[Family] = &[
    Family {
        name: "pothole",
        envelope: "driving 30–110 km/h; front axle then rear a wheelbase / v later: net Δv ≤ 0.8 m/s, rigid-body ≤ 5 g, ringing ≤ 10 g at 10–300 Hz, 10–30 ms (each × 1.5)",
        requirement: Requirement::NoFire,
        make: pothole,
    },
    Family {
        name: "kerb-strike",
        envelope: "climbing a kerb at 10–50 km/h: net Δv ≤ 0.8 m/s, rigid-body ≤ 7 g, ringing ≤ 10 g at 20–300 Hz, 10–30 ms (each × 1.5)",
        requirement: Requirement::NoFire,
        make: kerb_strike,
    },
    Family {
        name: "door-slam",
        envelope: "standing car: ringing 0.5–60 g at 125–250 Hz for 20–100 ms, net Δv ≤ 0.015 m/s",
        requirement: Requirement::NoFire,
        make: door_slam,
    },
    Family {
        name: "hood-slam",
        envelope: "standing car: ringing 0.5–4.5 g at 20–300 Hz for 20–100 ms, net Δv ≤ 0.09 m/s",
        requirement: Requirement::NoFire,
        make: hood_slam,
    },
    Family {
        name: "hammer-blow",
        envelope: "standing car: ringing 100–1 500 g at 1–10 kHz for 0.2–2 ms, net Δv ≤ 0.015 m/s",
        requirement: Requirement::NoFire,
        make: hammer_blow,
    },
    Family {
        name: "rough-road",
        envelope: "driving 30–110 km/h: 0.5–4.5 g rms, 5–40 Hz from rest, crest factor 3, for 0.3–5 s, both sensors",
        requirement: Requirement::NoFire,
        make: rough_road,
    },
    Family {
        name: "speed-bump",
        envelope: "30–80 km/h, each axle: net Δv ≤ 0.3 m/s, rigid-body ≤ 3 g, ringing ≤ 3 g at 10–100 Hz, 20–60 ms (each × 1.5)",
        requirement: Requirement::NoFire,
        make: speed_bump,
    },
    Family {
        name: "jump-landing",
        envelope: "driving 30–110 km/h: net Δv ≤ 0.6 m/s, rigid-body ≤ 5 g, ringing ≤ 5 g at 10–100 Hz, 20–80 ms (each × 1.5)",
        requirement: Requirement::NoFire,
        make: jump_landing,
    },
    Family {
        name: "animal-strike",
        envelope: "roe deer at 40–110 km/h: net Δv ≤ v·25/(25 + 1 785)·1.3, ringing ≤ 5 g at 20–200 Hz, 20–60 ms (each × 1.5)",
        requirement: Requirement::NoFire,
        make: animal_strike,
    },
    Family {
        name: "kerb-at-predicted-contact",
        envelope: "a tracked object (20–55 km/h each, 1 000–2 500 kg) evading 1 ms before the predicted contact, a kerb strike (as kerb-strike) at it; half with a V2X station, true or forged at 0–40 000 kg",
        requirement: Requirement::NoFire,
        make: kerb_at_predicted_contact,
    },
    Family {
        name: "ghost-object-and-pothole",
        envelope: "a tracked object evading 1–300 ms before the predicted contact, a pothole (as pothole) from 100 ms before the evasion to 50 ms after the contact; half with a V2X station, true or forged at 0–40 000 kg",
        requirement: Requirement::NoFire,
        make: ghost_object_and_pothole,
    },
    Family {
        name: "spike",
        envelope: "one sample of 10–200 g on the crash, the safing or both sensors, driving",
        requirement: Requirement::NoFire,
        make: spike,
    },
    Family {
        name: "crash-sensor-offset",
        envelope: "the crash sensor offset by ±2–20 g for 50–500 ms, driving",
        requirement: Requirement::NoFire,
        make: crash_sensor_offset,
    },
    Family {
        name: "safing-sensor-offset",
        envelope: "the safing sensor offset by ±2–20 g for 50–500 ms, driving",
        requirement: Requirement::NoFire,
        make: safing_sensor_offset,
    },
    Family {
        name: "crash-sensor-dead",
        envelope: "the crash sensor stops publishing and stays dead, driving",
        requirement: Requirement::NoFire,
        make: crash_sensor_dead,
    },
    Family {
        name: "safing-sensor-dead",
        envelope: "the safing sensor stops publishing and stays dead, driving",
        requirement: Requirement::NoFire,
        make: safing_sensor_dead,
    },
    Family {
        name: "sensor-stuck",
        envelope: "the crash or safing sensor stuck or saturated for 50–500 ms, driving",
        requirement: Requirement::NoFire,
        make: sensor_stuck,
    },
    Family {
        name: "sensor-noisy",
        envelope: "one sensor (crash or safing) noisy: 1–10 g rms for 0.1–0.5 s, the other quiet",
        requirement: Requirement::NoFire,
        make: sensor_noisy,
    },
    Family {
        name: "stuck-crash-sensor-in-door-slam",
        envelope: "a door slam (as door-slam) while the crash sensor sticks for 100 ms",
        requirement: Requirement::NoFire,
        make: stuck_in_door_slam,
    },
    Family {
        name: "spike-in-pothole",
        envelope: "one 150–199 g crash-sensor sample inside a 0.9–1.2 m/s pothole with rebound",
        requirement: Requirement::NoFire,
        make: spike_in_pothole,
    },
    Family {
        name: "offset-with-pothole",
        envelope: "a crash-sensor offset of 3–12 g for 0.1–0.5 s starting with a 0.15–0.45 m/s pothole",
        requirement: Requirement::NoFire,
        make: offset_with_pothole,
    },
    Family {
        name: "satellite-fault-in-pothole",
        envelope: "one crush-zone satellite saturated or stuck, a 60–200 g spike or a 20–200 g offset on it, within ±20 ms of a 0.9–1.2 m/s pothole with rebound, driving",
        requirement: Requirement::NoFire,
        make: satellite_fault_in_pothole,
    },
    Family {
        name: "aliased-ringing",
        envelope: "zero-mean ringing near 4 kHz in phase with the samples (45–73.5 g, 3–4 ms), at 3.95–4.05 kHz (45–67.5 g, 20–30 ms), or at 2–16 kHz multiples (15–75 g, 3–30 ms)",
        requirement: Requirement::NoFire,
        make: aliased_ringing,
    },
    Family {
        name: "braking-and-pothole",
        envelope: "ABS braking at 0.6–1 g, 50–110 km/h, with a 1.08–1.14 m/s pothole with rebound or a 0.75–1.95 g crash-sensor offset",
        requirement: Requirement::NoFire,
        make: braking_and_pothole,
    },
    Family {
        name: "near-miss",
        envelope: "closing 30–110 km/h, the opponent evading 1–50 ms before the predicted contact, a 0.6–1.2 m/s pothole within ±20 ms of it; also back to Normal",
        requirement: Requirement::NoFire,
        make: near_miss,
    },
    Family {
        name: "no-fire-crash",
        envelope: "barrier 8–16 km/h (a quarter unbelted at 5.6–11.2 km/h), objects live or dead",
        requirement: Requirement::NoAirbag,
        make: no_fire_crash,
    },
    Family {
        name: "misreported-low-speed",
        envelope: "below the no-fire line with one object fault: 14.5 + 14.5 km/h reported 4 000 kg, 16 + 16 km/h reported 2 800 kg, 1 000–1 300 kg opponents reported 3 000–4 000 kg (EBS 13–16 km/h), a 15.5 km/h barrier reported 5 m/s faster",
        requirement: Requirement::NoAirbag,
        make: misreported_low_speed,
    },
    Family {
        name: "low-speed-crash-and-kerb",
        envelope: "barrier 12–16 km/h or 12 + 12 to 15 + 15 km/h cars (a quarter unbelted, − 6 km/h), tracked, a 0.75–1.2 m/s kerb strike 0–10 ms after contact",
        requirement: Requirement::NoAirbag,
        make: low_speed_crash_and_kerb,
    },
    Family {
        name: "must-fire-crash",
        envelope: "barrier 35–56 km/h, objects live or dead; fire − required (127 mm − 30 ms) reported",
        requirement: Requirement::MustFire,
        make: must_fire_crash,
    },
    Family {
        name: "must-fire-car",
        envelope: "equal cars 35 + 35 to 56 + 56 km/h; half with a V2X station, true or forged at 0–40 000 kg",
        requirement: Requirement::MustFire,
        make: must_fire_car,
    },
    Family {
        name: "must-fire-misreported",
        envelope: "1 000–2 800 kg opponents at an ego EBS of 35–56 km/h, the mass reported ±1 200 kg off or the closing speed ±5 m/s; half with a true V2X station",
        requirement: Requirement::MustFire,
        make: must_fire_misreported,
    },
    Family {
        name: "must-fire-safing-dead",
        envelope: "barrier 35–56 km/h with the safing sensor dead",
        requirement: Requirement::MustFire,
        make: must_fire_safing_dead,
    },
    Family {
        name: "must-fire-satellite-fault",
        envelope: "barrier 35–56 km/h with one crush-zone satellite dead, stuck or saturated (the other satellite's relief alone)",
        requirement: Requirement::MustFire,
        make: must_fire_satellite_fault,
    },
    Family {
        name: "must-fire-after-event",
        envelope: "a must-fire crash (barrier 35–56 km/h or equal cars 35 + 35 to 56 + 56, tracked) with one misuse event 0–200 ms before or 0–5 ms into contact: kerb, pothole, rough road up to 4.5 g rms, ABS braking, a 2–8 g shunt from behind, or a door slam on a standing car struck at 70–110 km/h; fire − required within the clean twin's + 2 ms",
        requirement: Requirement::MustFire,
        make: event_before_crash,
    },
    Family {
        name: "must-fire-sensor-fault",
        envelope: "a must-fire crash (as must-fire-after-event) with one unflagged fault of the crash or the safing sensor: noise 0.5–10 g rms through the crash, a 10–200 g spike, or a ±2–8 g offset; fire − required within the clean twin's + 2 ms",
        requirement: Requirement::MustFire,
        make: fault_inside_crash,
    },
    Family {
        name: "must-fire-heavy-opponent",
        envelope: "a 5–10 t opponent, standing or moving, at an ego EBS of 35–56 km/h, tracked true, its mass misreported by ±1 200 kg, or reported as a 1 200–2 000 kg car",
        requirement: Requirement::MustFire,
        make: heavy_opponent,
    },
    Family {
        name: "low-speed-crash-and-kerb-untracked",
        envelope: "low-speed-crash-and-kerb with the tracked low-speed rule off: the object list dead, the object at 0.05–0.5 confidence, or its mass over-reported by 0–1 200 kg",
        requirement: Requirement::NoAirbag,
        make: low_speed_kerb_untracked,
    },
    Family {
        name: "grey-zone",
        envelope: "barrier 20–30 km/h or equal cars 20 + 20 to 30 + 30 km/h, objects live or dead, the occupant belted or not: the airbag must fire where the reference restraint's airbag keeps the occupant from bottoming out and its belt alone does not",
        requirement: Requirement::ByOutcome,
        make: grey_zone,
    },
    Family {
        name: "no-fire-mode",
        envelope: "below the no-fire line in the soft modes: an offset deformable barrier (35–50 %) at 12–24 km/h, a centre pole at 10–20 km/h, objects live or dead",
        requirement: Requirement::NoAirbag,
        make: no_fire_mode,
    },
    Family {
        name: "no-fire-light-offset",
        envelope: "an 800–1 300 kg car struck with 35–60 % of the width at an ego EBS of 10–16 km/h (closing 30–45 km/h: its rail crushes like a must-fire offset's), objects live or dead",
        requirement: Requirement::NoAirbag,
        make: no_fire_light_offset,
    },
    Family {
        name: "must-fire-offset",
        envelope: "an offset deformable barrier (35–50 %) at 40–64 km/h, or equal cars 35 + 35 to 56 + 56 km/h overlapping by 35–60 %, either side struck, objects live or dead",
        requirement: Requirement::MustFire,
        make: must_fire_offset,
    },
    Family {
        name: "must-fire-angular",
        envelope: "a rigid wall at 15–30°, either side first, objects live or dead: unbelted at 32–48 km/h (FMVSS 208 oblique), belted at 40–56 km/h",
        requirement: Requirement::MustFire,
        make: must_fire_angular,
    },
    Family {
        name: "must-fire-pole",
        envelope: "a centre pole at 32–50 km/h, objects live or dead",
        requirement: Requirement::MustFire,
        make: must_fire_pole,
    },
    Family {
        name: "must-fire-underride",
        envelope: "the bed of a standing 8–30 t truck at 40–60 km/h, tracked with its true mass or untracked",
        requirement: Requirement::MustFire,
        make: must_fire_underride,
    },
    Family {
        name: "beyond-physics-half-sine",
        envelope: "one-signed half-sine 3–15 g × 5–20 ms on both sensors (its whole area a Δv of the car): where each floor sits, printed, not judged",
        requirement: Requirement::Report,
        make: beyond_physics,
    },
];

/// `schema_version` of `misuse-matrix --json` (docs/using.md, "JSON results").
pub const SCHEMA_VERSION: u32 = 1;

/// Families that do not hold yet: `misuse-matrix --gate` prints them and does not fail on
/// them, so the suite gates everything that holds while the rest is open work. A family found
/// failing goes here, with a README note (restraint/README.md, "Each path after an earlier
/// event"), until it holds.
pub const OPEN: &[&str] = &[
    "must-fire-after-event",
    "must-fire-sensor-fault",
    "must-fire-pole",
];

/// Must-fire families gated on time: with `--gate`, every airbag must fire at or before its
/// "127 mm − 30 ms" time (column `after`). The other must-fire families report the figure
/// until they hold it.
pub const IN_TIME: &[&str] = &[
    "must-fire-crash",
    "must-fire-satellite-fault",
    "must-fire-safing-dead",
];

/// The family called `name`.
pub fn family(name: &str) -> Option<&'static Family> {
    FAMILIES.iter().find(|f| f.name == name)
}

/// The names of every family, for an error message.
pub fn names() -> Vec<&'static str> {
    FAMILIES.iter().map(|f| f.name).collect()
}

impl Family {
    /// The scenario text of variant `i` under `seed` (reproducible: the same text every time).
    /// A quarter of a no-fire family's variants carry an occupant the ECU does not know to be
    /// belted, whose airbag boundary is lower (`unbelted_dv_mps`): the misuse events and
    /// faults must not fire it either.
    pub fn variant(&self, i: u64, seed: u64) -> String {
        let mut r = ChaCha8Rng::seed_from_u64(seed ^ i.wrapping_mul(0x9E37_79B9_7F4A_7C15));
        let text = (self.make)(&mut r, &format!("{}-{i}", self.name), i);
        if self.requirement == Requirement::NoFire && r.gen_bool(0.25) {
            text::unbelted(&text)
        } else {
            text
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every family's variants parse and validate against the documented schema, and are
    /// reproducible.
    #[test]
    fn every_variant_is_a_valid_scenario() {
        for f in FAMILIES {
            for i in 0..40 {
                let text = f.variant(i, 7);
                assert_eq!(text, f.variant(i, 7));
                world::Scenario::parse(f.name, &text)
                    .unwrap_or_else(|e| panic!("{}: {e}\n{text}", f.name));
            }
        }
    }
}
