//! The misuse / single-fault / must-fire catalogue of `misuse-matrix` (issues 20, 30, 31):
//! seeded families of scenarios, each built in code from the documented scenario schema and
//! judged by what its family requires.
//!
//! ## Misuse as physics makes it (issue 30)
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
//! | door-slam (standing) | 0.01 m/s (0.015) | — | 40 g at 125–250 Hz, lobes of 2–4 ms (60) | 20–100 ms | D: 30 kg door at ≤ 3 m/s; the ringing amplitude is issue 31's (15–40 g), above the table's 0.5–3 g |
//! | hood-slam (standing) | 0.06 m/s (0.09) | — | 3 g at 20–300 Hz (4.5) | 20–100 ms | D: hood / boot mass × closing speed |
//! | hammer-blow (standing) | 0.01 m/s (0.015) | — | 1 000 g at 1–10 kHz (1 500) | 0.2–2 ms | D: 1 kg head at ≤ 10 m/s; S: ISO 16750-3 shock is at the door, not the tunnel |
//! | rough-road (driving) | ≈ 0 (zero-mean band-limited) | crest factor 3 (13.5 g at 4.5 g rms) | 3 g rms (4.5), 5–40 Hz, from rest | 0.3–5 s | issue 30 fixes ≥ 3 g rms for up to 5 s (≈ 10 × the table's 0.3 g); S: random-vibration drive signals are clipped at 3σ (IEC 60068-2-64 asks for a crest factor ≥ 2.5); D: a 4σ lobe at 4.5 g rms is 300 kN through the wheels |
//! | speed-bump (30–80 km/h) | 0.3 m/s per axle (0.45), net ≈ 0 | 3 g (4.5) | 3 g at 10–100 Hz (4.5) | 20–60 ms per axle, two bursts a wheelbase / v apart | D |
//! | jump-landing (30–110 km/h) | 0.6 m/s (0.9) | 5 g (7.5) | 5 g at 10–100 Hz (7.5) | 20–80 ms | D: x as the sensor sees a vertical landing |
//! | animal-strike (roe deer, 40–110 km/h) | 0.4 m/s (0.6) | one-signed | 5 g at 20–200 Hz (7.5) | 20–60 ms | D: 25 kg at 100 km/h, v·m_a/(m_a + m_car)·(1+e) |
//!
//! The one-signed half-sine sweep of issue 20 (the whole area a velocity change of the car:
//! a 15 g × 20 ms "pothole" is Δv 1.87 m/s, a 260 kN longitudinal peak) stays as the
//! **beyond-physics** report: printed, where each floor sits, not a gate.
//!
//! ## Single faults inside real events (issue 31)
//! | family | what | requirement |
//! |---|---|---|
//! | stuck-crash-sensor-in-door-slam | door slam (as above) on a standing car while the crash sensor sticks for 100 ms | no fire |
//! | spike-in-pothole | one 150–199 g crash-sensor sample inside a 0.6–0.8 m/s pothole with rebound | no fire |
//! | offset-with-pothole | a +8 g crash-sensor offset (0.1–0.5 s) starting with a 0.3 m/s pothole | no fire |
//! | misreported-low-speed | a crash below the no-fire line with one object fault: 14.5 + 14.5 km/h equal cars reported 4 000 kg; 16 + 16 km/h reported 2 800 kg; 1 000–1 300 kg opponents reported 3 000–4 000 kg at an EBS of 13–16 km/h; a 15.5 km/h barrier with the speed reported 5 m/s high | no airbag |
//! | aliased-ringing | zero-mean ringing near 4 kHz in phase with the samples (±30–49 g × 1.5, 3–4 ms), at 3.95–4.05 kHz (±30–45 g × 1.5, 20–30 ms), or at a multiple of either sampling rate (2, 4, 8, 12, 16 kHz) | no fire |
//! | low-speed-crash-and-kerb | a 12–16 km/h barrier or 12 + 12 to 15 + 15 km/h cars, tracked, with a kerb strike of 0.5–0.8 m/s (× 1.5) 0–10 ms after contact | no airbag |
//! | braking-and-pothole | ABS braking at 0.6–1 g with a 0.72–0.76 m/s pothole with rebound (× 1.5: up to 1.14), or with a 0.5–1.3 g crash-sensor offset | no fire |
//! | near-miss | closing 40–110 km/h (and 30 + 30), the opponent evading 1–50 ms before the predicted contact, a 0.4–0.8 m/s pothole (× 1.5) within ±20 ms of it; also: the ECU must not stay in CrashDetected | no fire, back to Normal |
//!
//! ## Faults and must-fire crashes (issue 20)
//! Spikes, offsets, dead / stuck / noisy sensors, crashes below the no-fire line and must-fire
//! crashes (with a misreported opponent, with a dead safing sensor) keep their ranges of issue 20
//! (table in [`FAMILIES`]' docs).
//!
//! Required fire time of a must-fire crash: the classic "127 mm − 30 ms" criterion — the
//! instant a free-flying (unbelted) occupant has moved 127 mm relative to the compartment in
//! the TRUE pulse, minus 30 ms.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

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

/// 1.5 × the envelope: every physical bound is sampled up to this multiple (issue 30).
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
        envelope: "a tracked object (20–55 km/h each, 1 000–2 500 kg) evading 1 ms before the predicted contact, a kerb strike (as kerb-strike) at it",
        requirement: Requirement::NoFire,
        make: kerb_at_predicted_contact,
    },
    Family {
        name: "ghost-object-and-pothole",
        envelope: "a tracked object evading 1–300 ms before the predicted contact, a pothole (as pothole) from 100 ms before the evasion to 50 ms after the contact",
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
        envelope: "barrier 8–16 km/h, objects live or dead",
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
        envelope: "barrier 12–16 km/h or 12 + 12 to 15 + 15 km/h cars, tracked, a 0.75–1.2 m/s kerb strike 0–10 ms after contact",
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
        envelope: "equal cars 35 + 35 to 56 + 56 km/h",
        requirement: Requirement::MustFire,
        make: must_fire_car,
    },
    Family {
        name: "must-fire-misreported",
        envelope: "1 000–2 800 kg opponents at an ego EBS of 35–56 km/h, the mass reported ±1 200 kg off or the closing speed ±5 m/s",
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
        name: "beyond-physics-half-sine",
        envelope: "one-signed half-sine 3–15 g × 5–20 ms on both sensors (its whole area a Δv of the car): where each floor sits, printed, not judged",
        requirement: Requirement::Report,
        make: beyond_physics,
    },
];

/// Families that do not hold yet: `misuse-matrix --gate` prints them and does not fail on
/// them, so the suite gates everything that holds while the rest is open work. Empty since
/// issues 30/31 closed their last families (rough road: the floors' roughness lift); a family
/// found failing goes here, with its counts (500 variants, seed 7, as the gate runs them) and
/// a README note, until it holds.
pub const OPEN: &[&str] = &[];

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
    pub fn variant(&self, i: u64, seed: u64) -> String {
        let mut r = ChaCha8Rng::seed_from_u64(seed ^ i.wrapping_mul(0x9E37_79B9_7F4A_7C15));
        (self.make)(&mut r, &format!("{}-{i}", self.name), i)
    }
}

// ---- scenario text ------------------------------------------------------------------------

const OCCUPANT: &str = "[occupant]\nmass_kg = 75\nchest_to_wheel_mm = 300\nbelted = true\n";

/// The ego section at `kph` (optionally braking from `brake_s` at `brake_g`, ABS).
fn ego(kph: f64, brake: Option<(f64, f64)>) -> String {
    let mut s = format!("[ego]\nmass_kg = 1785\nclass = 4\nspeed_kph = {kph}\n");
    if let Some((start_s, g)) = brake {
        s += &format!(
            "[ego.braking]\nstart_s = {start_s}\ndecel_mps2 = {}\nstate = \"abs\"\n",
            g * G
        );
    }
    s
}

/// A car driving with no object in range (a barrier 900 m ahead, beyond the 80 m sensor range).
fn driving(
    name: &str,
    seed: u64,
    ego_text: &str,
    duration_s: f64,
    sensor: &str,
    events: &str,
) -> String {
    format!(
        "name = \"{name}\"\nseed = {seed}\nduration_s = {duration_s}\n{ego_text}\
         [opponent]\nkind = \"barrier\"\ninitial_distance_m = 900.0\n\
         [sensor]\nmass_estimate_kg = 3000\n{sensor}{OCCUPANT}{events}"
    )
}

/// A head-on approach of two cars at `v` km/h each, contact at `tc` s, an opponent of
/// `opp_kg` (evading at `evade_s`), `sensor` keys, `events`.
#[allow(clippy::too_many_arguments)]
fn head_on(
    name: &str,
    seed: u64,
    v: f64,
    opp_kg: f64,
    tc: f64,
    evade_s: Option<f64>,
    duration_s: f64,
    sensor: &str,
    events: &str,
) -> String {
    let evade = evade_s.map_or(String::new(), |t| format!("evade_s = {t}\n"));
    format!(
        "name = \"{name}\"\nseed = {seed}\nduration_s = {duration_s}\n{}\
         [opponent]\nkind = \"vehicle\"\nmass_kg = {opp_kg}\nspeed_kph = {v}\ninitial_distance_m = {}\n{evade}\
         [sensor]\n{sensor}{OCCUPANT}{events}",
        ego(v, None),
        2.0 * v / 3.6 * tc
    )
}

/// A rigid barrier at `v` km/h, contact at `tc` s.
fn barrier(name: &str, seed: u64, v: f64, tc: f64, sensor: &str, events: &str) -> String {
    driving(name, seed, &ego(v, None), tc + 0.25, sensor, events).replace(
        "initial_distance_m = 900.0",
        &format!("initial_distance_m = {}", v / 3.6 * tc),
    )
}

/// A `ringing` event (`world::events`).
#[allow(clippy::too_many_arguments)]
fn ringing(
    start_s: f64,
    peak_g: f64,
    f_hz: f64,
    ms: f64,
    net_dv: f64,
    phase_deg: f64,
    sensor: &str,
) -> String {
    format!(
        "[[accel_event]]\nkind = \"ringing\"\nstart_s = {start_s}\npeak_g = {peak_g}\nfrequency_hz = {f_hz}\n\
         duration_ms = {ms}\nnet_dv_mps = {net_dv}\nphase_deg = {phase_deg}\nsensor = \"{sensor}\"\n"
    )
}

/// An `offset` event.
fn offset_event(start_s: f64, peak_g: f64, end_s: f64, sensor: &str) -> String {
    format!(
        "[[accel_event]]\nkind = \"offset\"\nstart_s = {start_s}\npeak_g = {peak_g}\nend_s = {end_s}\nsensor = \"{sensor}\"\n"
    )
}

/// A `spike` event.
fn spike_event(start_s: f64, peak_g: f64, sensor: &str) -> String {
    format!("[[accel_event]]\nkind = \"spike\"\nstart_s = {start_s}\npeak_g = {peak_g}\nsensor = \"{sensor}\"\n")
}

/// A `rough_road` event.
fn rough_road_event(start_s: f64, rms_g: f64, end_s: f64, sensor: &str) -> String {
    format!(
        "[[accel_event]]\nkind = \"rough_road\"\nstart_s = {start_s}\nrms_g = {rms_g}\nend_s = {end_s}\nsensor = \"{sensor}\"\n"
    )
}

fn half_sine(start_s: f64, peak_g: f64, ms: f64, sensor: &str) -> String {
    format!(
        "[[accel_event]]\nkind = \"half_sine\"\nstart_s = {start_s}\npeak_g = {peak_g}\n\
         duration_ms = {ms}\nsensor = \"{sensor}\"\n"
    )
}

/// The envelope of a mechanical event through the wheels (module docs' table, unscaled: the
/// variants draw up to [`MARGIN`] × each bound).
struct WheelEnvelope {
    /// Net Δv bound, m/s.
    dv_mps: f64,
    /// Rigid-body peak bound, g (the Δv is lowered where the duration cannot carry it).
    body_peak_g: f64,
    /// Ringing amplitude bound, g.
    ring_g: f64,
    /// Ringing frequencies, Hz.
    f_hz: (f64, f64),
    /// Durations, ms.
    ms: (f64, f64),
}

const POTHOLE: WheelEnvelope = WheelEnvelope {
    dv_mps: 0.8,
    body_peak_g: 5.0,
    ring_g: 10.0,
    f_hz: (10.0, 300.0),
    ms: (10.0, 30.0),
};
const KERB: WheelEnvelope = WheelEnvelope {
    dv_mps: 0.8,
    body_peak_g: 7.0,
    ring_g: 10.0,
    f_hz: (20.0, 300.0),
    ms: (10.0, 30.0),
};
const SPEED_BUMP: WheelEnvelope = WheelEnvelope {
    dv_mps: 0.3,
    body_peak_g: 3.0,
    ring_g: 3.0,
    f_hz: (10.0, 100.0),
    ms: (20.0, 60.0),
};
const JUMP_LANDING: WheelEnvelope = WheelEnvelope {
    dv_mps: 0.6,
    body_peak_g: 5.0,
    ring_g: 5.0,
    f_hz: (10.0, 100.0),
    ms: (20.0, 80.0),
};
/// Roe deer; its Δv bound depends on the speed (`animal_strike`).
const ANIMAL: WheelEnvelope = WheelEnvelope {
    dv_mps: 0.4,
    body_peak_g: 10.0,
    ring_g: 5.0,
    f_hz: (20.0, 200.0),
    ms: (20.0, 60.0),
};

/// One event of `env` at `start_s` (its Δv bound `dv_mps`, usually `env.dv_mps`): a rigid-body
/// pulse drawn up to 1.5 × the bounds with zero-mean ringing, random phase.
fn wheel_event(r: &mut ChaCha8Rng, start_s: f64, env: &WheelEnvelope, dv_mps: f64) -> String {
    let ms = r.gen_range(env.ms.0..env.ms.1);
    let cap = env.body_peak_g * MARGIN * G * 2.0 * ms * 1e-3 / std::f64::consts::PI;
    let dv = r.gen_range(0.0..dv_mps * MARGIN).min(cap);
    let f_hz = r.gen_range(env.f_hz.0..env.f_hz.1);
    ringing(
        start_s,
        r.gen_range(0.0..env.ring_g * MARGIN)
            .min(lobe_cap_g(f_hz, env.dv_mps)),
        f_hz,
        ms,
        dv,
        r.gen_range(0.0..360.0),
        "all",
    )
}

/// The largest ringing amplitude at `f_hz` whose lobe stays within the impulse the contact
/// can carry, g: a lobe of a·sin(2πft) is a velocity change a / (πf) of the tunnel — below a
/// few hundred Hz the tunnel moves with the body, so a lobe is a partial impulse of the car
/// through the same contact and cannot exceed the family's Δv bound (× [`MARGIN`]) either.
/// (The first matrix drew 15 g at 10–15 Hz: lobes of 2–3 m/s, a 1 785 kg car's velocity
/// swinging by more than a 25 km/h barrier crash changes it.)
fn lobe_cap_g(f_hz: f64, dv_bound_mps: f64) -> f64 {
    std::f64::consts::PI * f_hz * dv_bound_mps * MARGIN / G
}

/// A pothole: front axle at `start_s`, the rear axle a wheelbase / v later (`v_mps`; left out
/// when it would not be over [`JUDGED_AFTER_S`] before `end_s`: a run that ends inside an event
/// cannot say whether its crash phase ends).
fn pothole_events(r: &mut ChaCha8Rng, start_s: f64, v_mps: f64, end_s: f64) -> String {
    let front = wheel_event(r, start_s, &POTHOLE, POTHOLE.dv_mps);
    let rear_at = start_s + WHEELBASE_M / v_mps.max(1.0);
    if rear_at + POTHOLE.ms.1 * 1e-3 + JUDGED_AFTER_S >= end_s {
        return front;
    }
    front + &wheel_event(r, rear_at, &POTHOLE, POTHOLE.dv_mps)
}

/// A run goes on at least this long after its last event, s (the event's quiet gap, 10 ms,
/// and the decisions' window after it).
const JUDGED_AFTER_S: f64 = 0.1;

/// A pothole with rebound of exactly `dv` m/s: the far edge's rigid-body pulse with ringing
/// (wheel hop) whose first lobe after the crest is the rebound.
fn pothole_with_rebound(r: &mut ChaCha8Rng, start_s: f64, dv: f64) -> String {
    let ms = r.gen_range(10.0..30.0);
    let f_hz = r.gen_range(10.0..60.0);
    ringing(
        start_s,
        r.gen_range(2.0..10.0 * MARGIN)
            .min(lobe_cap_g(f_hz, POTHOLE.dv_mps)),
        f_hz,
        ms,
        dv,
        r.gen_range(0.0..360.0),
        "all",
    )
}

// ---- misuse as physics makes it ----------------------------------------------------------

fn drive_kph(r: &mut ChaCha8Rng) -> f64 {
    r.gen_range(30.0..110.0)
}

fn pothole(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
    let (t0, v) = (r.gen_range(0.3..0.5), drive_kph(r));
    let ev = pothole_events(r, t0, v / 3.6, 0.9);
    driving(name, i, &ego(v, None), 0.9, "", &ev)
}

fn kerb_strike(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
    let (t0, v) = (r.gen_range(0.3..0.5), r.gen_range(10.0..50.0));
    let ev = wheel_event(r, t0, &KERB, KERB.dv_mps);
    driving(name, i, &ego(v, None), 0.8, "", &ev)
}

/// A standing car's panel or housing event (door, hood, hammer): ringing with amplitude,
/// frequency and length drawn from their ranges and a net Δv within ±`dv_mps` × 1.5.
fn panel_event(
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

fn door_slam_event(r: &mut ChaCha8Rng, t0: f64) -> String {
    panel_event(
        r,
        t0,
        (0.5, 40.0 * MARGIN),
        (125.0, 250.0),
        (20.0, 100.0),
        0.01,
    )
}

fn door_slam(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
    let t0 = r.gen_range(0.3..0.5);
    driving(name, i, &ego(0.0, None), 0.8, "", &door_slam_event(r, t0))
}

fn hood_slam(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
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

fn hammer_blow(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
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

fn rough_road(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
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

fn speed_bump(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
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

fn jump_landing(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
    let (t0, v) = (r.gen_range(0.3..0.5), drive_kph(r));
    let ev = wheel_event(r, t0, &JUMP_LANDING, JUMP_LANDING.dv_mps);
    driving(name, i, &ego(v, None), 0.8, "", &ev)
}

fn animal_strike(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
    let (t0, v) = (r.gen_range(0.3..0.5), r.gen_range(40.0..110.0));
    // Roe deer (≤ 25 kg): v·m_a/(m_a + m_car)·(1 + e), e ≤ 0.3.
    let dv_bound = v / 3.6 * 25.0 / (25.0 + 1785.0) * 1.3;
    let ev = wheel_event(r, t0, &ANIMAL, dv_bound);
    driving(name, i, &ego(v, None), 0.8, "", &ev)
}

fn kerb_at_predicted_contact(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
    let v = r.gen_range(20.0..55.0);
    let tc = r.gen_range(0.45..0.6);
    let opp = r.gen_range(1000.0..2500.0);
    let ev = wheel_event(r, tc, &KERB, KERB.dv_mps);
    head_on(name, i, v, opp, tc, Some(tc - 0.001), tc + 0.3, "", &ev)
}

fn ghost_object_and_pothole(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
    let v = r.gen_range(20.0..55.0);
    let tc = r.gen_range(0.45..0.6);
    let evade = tc - r.gen_range(0.001..0.3);
    let at = r.gen_range(evade - 0.1..tc + 0.05);
    let opp = r.gen_range(1000.0..2500.0);
    let ev = pothole_events(r, at, v / 3.6, tc + 0.3);
    head_on(name, i, v, opp, tc, Some(evade), tc + 0.3, "", &ev)
}

// ---- single faults (issue 20) ------------------------------------------------------------

fn spike(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
    let t0 = r.gen_range(0.3..0.5);
    let sensor = ["all", "crash", "safing"][r.gen_range(0..3)];
    let g = r.gen_range(10.0..200.0);
    let ev = spike_event(t0, g, sensor);
    let v = drive_kph(r);
    driving(name, i, &ego(v, None), 0.8, "", &ev)
}

fn offset(r: &mut ChaCha8Rng, name: &str, i: u64, sensor: &str) -> String {
    let t0 = r.gen_range(0.3..0.5);
    let g = r.gen_range(2.0..20.0) * if r.gen_bool(0.5) { 1.0 } else { -1.0 };
    let len = r.gen_range(0.05..0.5);
    let ev = offset_event(t0, g, t0 + len, sensor);
    let v = drive_kph(r);
    driving(name, i, &ego(v, None), 1.0, "", &ev)
}

fn crash_sensor_offset(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
    offset(r, name, i, "crash")
}

fn safing_sensor_offset(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
    offset(r, name, i, "safing")
}

fn dead(r: &mut ChaCha8Rng, name: &str, i: u64, target: &str) -> String {
    let t0 = r.gen_range(0.3..0.5);
    let v = drive_kph(r);
    let sensor =
        format!("dropouts = [{{ start_s = {t0}, end_s = 100.0, target = \"{target}\" }}]\n");
    driving(name, i, &ego(v, None), 1.0, &sensor, "")
}

fn crash_sensor_dead(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
    dead(r, name, i, "accel")
}

fn safing_sensor_dead(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
    dead(r, name, i, "safing")
}

fn sensor_stuck(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
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

fn sensor_noisy(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
    let t0 = r.gen_range(0.3..0.5);
    let sensor = ["crash", "safing"][r.gen_range(0..2)];
    let (rms, len) = (r.gen_range(1.0..10.0), r.gen_range(0.1..0.5));
    let ev = rough_road_event(t0, rms, t0 + len, sensor);
    let v = drive_kph(r);
    driving(name, i, &ego(v, None), 1.0, "", &ev)
}

// ---- single faults inside real events (issue 31) ------------------------------------------

fn stuck_in_door_slam(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
    let t0 = r.gen_range(0.3..0.5);
    let ev = door_slam_event(r, t0);
    let stuck_at = t0 + r.gen_range(0.0..0.02);
    let keys = format!(
        "accel_faults = [{{ start_s = {stuck_at}, end_s = {}, kind = \"stuck\", sensor = \"crash\" }}]\n",
        stuck_at + 0.1
    );
    driving(name, i, &ego(0.0, None), 0.8, &keys, &ev)
}

fn spike_in_pothole(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
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

fn offset_with_pothole(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
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

fn aliased_ringing(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
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

fn braking_and_pothole(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
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

fn near_miss(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
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

fn misreported_low_speed(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
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

fn low_speed_crash_and_kerb(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
    let tc = r.gen_range(0.35..0.5);
    let at = tc + r.gen_range(0.0..0.01);
    let kerb = {
        let dv = r.gen_range(0.5..0.8) * MARGIN;
        pothole_with_rebound(r, at, dv)
    };
    if r.gen_bool(0.5) {
        barrier(name, i, r.gen_range(12.0..16.0), tc, "", &kerb)
    } else {
        head_on(
            name,
            i,
            r.gen_range(12.0..15.0),
            1785.0,
            tc,
            None,
            tc + 0.25,
            "",
            &kerb,
        )
    }
}

// ---- crashes (issue 20) ------------------------------------------------------------------

fn no_fire_crash(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
    let (v, tc) = (r.gen_range(8.0..16.0), r.gen_range(0.35..0.5));
    let dead = if r.gen_bool(0.5) {
        "dropouts = [{ start_s = 0.2, end_s = 100.0, target = \"object\" }]\n"
    } else {
        ""
    };
    barrier(name, i, v, tc, dead, "")
}

fn must_fire_crash(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
    let (v, tc) = (r.gen_range(35.0..56.0), r.gen_range(0.35..0.5));
    let dead = if r.gen_bool(0.5) {
        "dropouts = [{ start_s = 0.2, end_s = 100.0, target = \"object\" }]\n"
    } else {
        ""
    };
    barrier(name, i, v, tc, dead, "")
}

fn must_fire_car(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
    let (v, tc) = (r.gen_range(35.0..56.0), r.gen_range(0.35..0.5));
    head_on(name, i, v, 1785.0, tc, None, tc + 0.25, "", "").replace(
        "[opponent]\nkind = \"vehicle\"\n",
        "[opponent]\nkind = \"vehicle\"\nclass = 4\n",
    )
}

fn must_fire_misreported(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
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
    head_on(name, i, v, m, tc, None, tc + 0.25, &keys, "")
}

fn must_fire_safing_dead(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
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

fn beyond_physics(r: &mut ChaCha8Rng, name: &str, i: u64) -> String {
    let t0 = r.gen_range(0.3..0.5);
    let ev = half_sine(t0, r.gen_range(3.0..15.0), r.gen_range(5.0..20.0), "all");
    let v = drive_kph(r);
    driving(name, i, &ego(v, None), 0.8, "", &ev)
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
