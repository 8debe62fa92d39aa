//! The scenario text the families are written in (the documented schema, scenarios/README.md):
//! sections, `[[accel_event]]` pulses, and the wheel events with their physical envelopes.

use super::*;

/// The `[sensor]` key of a crash with the object list dead from 0.2 s on (no prediction).
pub(super) const OBJECTS_DEAD: &str =
    "dropouts = [{ start_s = 0.2, end_s = 100.0, target = \"object\" }]\n";

pub(super) const OCCUPANT: &str =
    "[occupant]\nmass_kg = 75\nchest_to_wheel_mm = 300\nbelted = true\n";

/// `text` with its occupant unbelted.
pub(super) fn unbelted(text: &str) -> String {
    text.replace("belted = true", "belted = false")
}

/// The unbelted no-fire line over the belted one (the ECU's defaults, 14 / 20 km/h): a
/// crash's speed below the belted line scaled by this stays as far below the unbelted one.
pub(super) const UNBELTED_LINE_RATIO: f64 = 14.0 / 20.0;
/// The belted no-fire line less the unbelted one, km/h: a crash with a misuse event in it
/// (whose Δv does not scale with the line) moved down by this stays as far below the unbelted
/// line as it was below the belted one.
pub(super) const UNBELTED_LINE_SHIFT_KPH: f64 = 20.0 - 14.0;

/// The ego section at `kph` (optionally braking from `brake_s` at `brake_g`, ABS).
pub(super) fn ego(kph: f64, brake: Option<(f64, f64)>) -> String {
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
pub(super) fn driving(
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
pub(super) fn head_on(
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

/// `text` with its opponent vehicle in the ego's stiffness class (4): an equal car.
pub(super) fn equal_class(text: String) -> String {
    text.replace(
        "[opponent]\nkind = \"vehicle\"\n",
        "[opponent]\nkind = \"vehicle\"\nclass = 4\n",
    )
}

/// A `[v2x]` table half the time (drawn last, so a family's other draws stay what they were):
/// a station that reports the opponent's true mass, or — `forged` — half of those a station
/// that reports any mass from 0 to 40 t (a forged or misconfigured one).
pub(super) fn v2x_station(r: &mut ChaCha8Rng, forged: bool) -> String {
    match r.gen_range(0..4) {
        0 | 1 => String::new(),
        2 if forged => format!("\n[v2x]\nmass_kg = {}\n", r.gen_range(0.0..40_000.0)),
        _ => "\n[v2x]\n".to_owned(),
    }
}

/// A rigid barrier at `v` km/h, contact at `tc` s.
pub(super) fn barrier(
    name: &str,
    seed: u64,
    v: f64,
    tc: f64,
    sensor: &str,
    events: &str,
) -> String {
    driving(name, seed, &ego(v, None), tc + 0.25, sensor, events).replace(
        "initial_distance_m = 900.0",
        &format!("initial_distance_m = {}", v / 3.6 * tc),
    )
}

/// A `ringing` event (`world::events`).
#[allow(clippy::too_many_arguments)]
pub(super) fn ringing(
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
pub(super) fn offset_event(start_s: f64, peak_g: f64, end_s: f64, sensor: &str) -> String {
    format!(
        "[[accel_event]]\nkind = \"offset\"\nstart_s = {start_s}\npeak_g = {peak_g}\nend_s = {end_s}\nsensor = \"{sensor}\"\n"
    )
}

/// A `spike` event.
pub(super) fn spike_event(start_s: f64, peak_g: f64, sensor: &str) -> String {
    format!("[[accel_event]]\nkind = \"spike\"\nstart_s = {start_s}\npeak_g = {peak_g}\nsensor = \"{sensor}\"\n")
}

/// A `rough_road` event.
pub(super) fn rough_road_event(start_s: f64, rms_g: f64, end_s: f64, sensor: &str) -> String {
    format!(
        "[[accel_event]]\nkind = \"rough_road\"\nstart_s = {start_s}\nrms_g = {rms_g}\nend_s = {end_s}\nsensor = \"{sensor}\"\n"
    )
}

pub(super) fn half_sine(start_s: f64, peak_g: f64, ms: f64, sensor: &str) -> String {
    format!(
        "[[accel_event]]\nkind = \"half_sine\"\nstart_s = {start_s}\npeak_g = {peak_g}\n\
         duration_ms = {ms}\nsensor = \"{sensor}\"\n"
    )
}

/// The envelope of a mechanical event through the wheels (module docs' table, unscaled: the
/// variants draw up to [`MARGIN`] × each bound).
pub(super) struct WheelEnvelope {
    /// Net Δv bound, m/s.
    pub(super) dv_mps: f64,
    /// Rigid-body peak bound, g (the Δv is lowered where the duration cannot carry it).
    pub(super) body_peak_g: f64,
    /// Ringing amplitude bound, g.
    pub(super) ring_g: f64,
    /// Ringing frequencies, Hz.
    pub(super) f_hz: (f64, f64),
    /// Durations, ms.
    pub(super) ms: (f64, f64),
}

pub(super) const POTHOLE: WheelEnvelope = WheelEnvelope {
    dv_mps: 0.8,
    body_peak_g: 5.0,
    ring_g: 10.0,
    f_hz: (10.0, 300.0),
    ms: (10.0, 30.0),
};
pub(super) const KERB: WheelEnvelope = WheelEnvelope {
    dv_mps: 0.8,
    body_peak_g: 7.0,
    ring_g: 10.0,
    f_hz: (20.0, 300.0),
    ms: (10.0, 30.0),
};
pub(super) const SPEED_BUMP: WheelEnvelope = WheelEnvelope {
    dv_mps: 0.3,
    body_peak_g: 3.0,
    ring_g: 3.0,
    f_hz: (10.0, 100.0),
    ms: (20.0, 60.0),
};
pub(super) const JUMP_LANDING: WheelEnvelope = WheelEnvelope {
    dv_mps: 0.6,
    body_peak_g: 5.0,
    ring_g: 5.0,
    f_hz: (10.0, 100.0),
    ms: (20.0, 80.0),
};
/// Roe deer; its Δv bound depends on the speed (`animal_strike`).
pub(super) const ANIMAL: WheelEnvelope = WheelEnvelope {
    dv_mps: 0.4,
    body_peak_g: 10.0,
    ring_g: 5.0,
    f_hz: (20.0, 200.0),
    ms: (20.0, 60.0),
};

/// One event of `env` at `start_s` (its Δv bound `dv_mps`, usually `env.dv_mps`): a rigid-body
/// pulse drawn up to 1.5 × the bounds with zero-mean ringing, random phase.
pub(super) fn wheel_event(
    r: &mut ChaCha8Rng,
    start_s: f64,
    env: &WheelEnvelope,
    dv_mps: f64,
) -> String {
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
pub(super) fn lobe_cap_g(f_hz: f64, dv_bound_mps: f64) -> f64 {
    std::f64::consts::PI * f_hz * dv_bound_mps * MARGIN / G
}

/// A pothole: front axle at `start_s`, the rear axle a wheelbase / v later (`v_mps`; left out
/// when it would not be over [`JUDGED_AFTER_S`] before `end_s`: a run that ends inside an event
/// cannot say whether its crash phase ends).
pub(super) fn pothole_events(r: &mut ChaCha8Rng, start_s: f64, v_mps: f64, end_s: f64) -> String {
    let front = wheel_event(r, start_s, &POTHOLE, POTHOLE.dv_mps);
    let rear_at = start_s + WHEELBASE_M / v_mps.max(1.0);
    if rear_at + POTHOLE.ms.1 * 1e-3 + JUDGED_AFTER_S >= end_s {
        return front;
    }
    front + &wheel_event(r, rear_at, &POTHOLE, POTHOLE.dv_mps)
}

/// A run goes on at least this long after its last event, s (the event's quiet gap, 10 ms,
/// and the decisions' window after it).
pub(super) const JUDGED_AFTER_S: f64 = 0.1;

/// A pothole with rebound of exactly `dv` m/s: the far edge's rigid-body pulse with ringing
/// (wheel hop) whose first lobe after the crest is the rebound.
pub(super) fn pothole_with_rebound(r: &mut ChaCha8Rng, start_s: f64, dv: f64) -> String {
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
