//! The semantic checks of a parsed scenario: ranges, classes, what a barrier may not have,
//! windows that end after they start. Each error names its dotted field (`ego.mass_kg`,
//! `sensor.dropouts[1]`); `location` turns it into a line.

use super::{AccelEvent, AccelEventKind, Braking, OpponentKind, Scenario};

/// Range of `peak_g` [g] (+ = deceleration; 0 is allowed for every kind: a no-op half-sine or
/// offset, a spike that reads 0).
pub const EVENT_PEAK_G: (f64, f64) = (-200.0, 200.0);
/// Range of a half-sine's `duration_ms` [ms].
pub const EVENT_DURATION_MS: (f64, f64) = (0.1, 200.0);
/// Range of a ringing's `peak_g` [g] (a hammer blow on the housing rings at > 1 000 g).
pub const RINGING_PEAK_G: (f64, f64) = (-2000.0, 2000.0);
/// Range of a ringing's `frequency_hz` [Hz].
pub const EVENT_FREQUENCY_HZ: (f64, f64) = (1.0, 100_000.0);
/// Range of a ringing's `net_dv_mps` [m/s].
pub const EVENT_NET_DV_MPS: (f64, f64) = (-20.0, 20.0);
/// Range of a ringing's `phase_deg` [deg].
pub const EVENT_PHASE_DEG: (f64, f64) = (-360.0, 360.0);
/// Range of a rough road's `rms_g` [g].
pub const EVENT_RMS_G: (f64, f64) = (0.0, 20.0);

impl Scenario {
    /// Semantic checks; `Err((field path, message))`.
    pub fn validate(&self) -> Result<(), (String, String)> {
        fn range(
            field: &str,
            v: f64,
            lo: f64,
            hi: f64,
            unit: &str,
        ) -> Result<(), (String, String)> {
            if v.is_finite() && v >= lo && v <= hi {
                Ok(())
            } else {
                Err((
                    field.to_owned(),
                    format!("{v} is outside {lo}..={hi} {unit}"),
                ))
            }
        }
        fn class(field: &str, c: Option<u8>) -> Result<(), (String, String)> {
            match c {
                Some(n) if !(1..=6).contains(&n) => Err((
                    field.to_owned(),
                    format!("class {n} does not exist (1..=6)"),
                )),
                _ => Ok(()),
            }
        }
        fn braking(
            prefix: &str,
            b: &Option<Braking>,
            duration_s: f64,
        ) -> Result<(), (String, String)> {
            if let Some(b) = b {
                range(
                    &format!("{prefix}.start_s"),
                    b.start_s,
                    0.0,
                    duration_s,
                    "s",
                )?;
                range(
                    &format!("{prefix}.decel_mps2"),
                    b.decel_mps2,
                    0.1,
                    15.0,
                    "m/s²",
                )?;
                range(&format!("{prefix}.ramp_s"), b.ramp_s, 0.0, 2.0, "s")?;
            }
            Ok(())
        }
        if self.name.is_empty() || self.name.len() > super::NAME_CAPACITY {
            return Err((
                "name".into(),
                format!("must be 1..={} bytes", super::NAME_CAPACITY),
            ));
        }
        if !self
            .name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_')
        {
            return Err((
                "name".into(),
                "use only letters, digits, '-' and '_' (it names the output folder)".into(),
            ));
        }
        range("duration_s", self.duration_s, 0.1, 60.0, "s")?;
        range("ego.mass_kg", self.ego.mass_kg, 500.0, 4000.0, "kg")?;
        class("ego.class", self.ego.class)?;
        range("ego.speed_kph", self.ego.speed_kph, 0.0, 200.0, "km/h")?;
        braking("ego.braking", &self.ego.braking, self.duration_s)?;
        let o = &self.opponent;
        range(
            "opponent.initial_distance_m",
            o.initial_distance_m,
            0.1,
            1000.0,
            "m",
        )?;
        range("ego.width_m", self.ego.width_m, 1.4, 2.6, "m")?;
        let kind = o.kind.name();
        let unused = |key: &str, why: &str| {
            Err((
                format!("opponent.{key}"),
                format!("not used by kind = \"{kind}\" ({why}): remove this key"),
            ))
        };
        if o.kind.is_fixed() {
            let bad = [
                ("mass_kg", o.mass_kg.is_some()),
                ("class", o.class.is_some()),
                ("speed_kph", o.speed_kph != 0.0),
                ("braking", o.braking.is_some()),
                ("evade_s", o.evade_s.is_some()),
            ];
            if let Some((k, _)) = bad.iter().find(|(_, b)| *b) {
                return unused(k, "it is fixed in place, of unbounded mass");
            }
        } else {
            let (low_kg, high_kg) = match o.kind {
                OpponentKind::Underride => (3000.0, 40000.0),
                _ => (300.0, 10000.0),
            };
            let m = o.mass_kg.ok_or((
                "opponent.mass_kg".to_owned(),
                format!("required for kind = \"{kind}\""),
            ))?;
            range("opponent.mass_kg", m, low_kg, high_kg, "kg")?;
            if o.kind == OpponentKind::Underride && o.class.is_some() {
                return unused("class", "the ego meets the bed, not the truck's front");
            }
            class("opponent.class", o.class)?;
            range("opponent.speed_kph", o.speed_kph, 0.0, 200.0, "km/h")?;
            braking("opponent.braking", &o.braking, self.duration_s)?;
            if let Some(te) = o.evade_s {
                range("opponent.evade_s", te, 0.0, self.duration_s, "s")?;
            }
        }
        if let Some(p) = o.overlap_percent {
            if matches!(o.kind, OpponentKind::Pole | OpponentKind::Underride) {
                return unused("overlap_percent", "it strikes the centre of the front");
            }
            range("opponent.overlap_percent", p, 10.0, 100.0, "%")?;
        }
        if let Some(a) = o.angle_deg {
            if o.kind != OpponentKind::Barrier {
                return unused("angle_deg", "an angled impact is a rigid barrier's");
            }
            range("opponent.angle_deg", a, 0.0, 45.0, "°")?;
            if a > 0.0 && o.overlap_percent.is_some_and(|p| p < 100.0) {
                return Err((
                    "opponent.angle_deg".into(),
                    "an angled barrier strikes the whole front, corner first: remove \
                     overlap_percent or the angle"
                        .into(),
                ));
            }
        }
        if o.struck_side.is_some()
            && matches!(
                self.crash_mode(),
                physics::crash_mode::CrashMode::FullFrontal
                    | physics::crash_mode::CrashMode::Pole
                    | physics::crash_mode::CrashMode::Underride
            )
        {
            return unused(
                "struck_side",
                "only an offset or angled impact strikes one side first",
            );
        }
        let s = &self.sensor;
        range(
            "sensor.object_period_ms",
            s.object_period_ms,
            1.0,
            1000.0,
            "ms",
        )?;
        range("sensor.latency_ms", s.latency_ms, 0.0, 500.0, "ms")?;
        range("sensor.range_m", s.range_m, 1.0, 1000.0, "m")?;
        range(
            "sensor.distance_noise_m",
            s.distance_noise_m,
            0.0,
            10.0,
            "m",
        )?;
        range(
            "sensor.speed_noise_mps",
            s.speed_noise_mps,
            0.0,
            10.0,
            "m/s",
        )?;
        range(
            "sensor.relative_accel_noise_mps2",
            s.relative_accel_noise_mps2,
            0.0,
            50.0,
            "m/s²",
        )?;
        range("sensor.mass_bias_kg", s.mass_bias_kg, -3000.0, 3000.0, "kg")?;
        range("sensor.mass_noise_kg", s.mass_noise_kg, 0.0, 3000.0, "kg")?;
        range(
            "sensor.speed_bias_mps",
            s.speed_bias_mps,
            -30.0,
            30.0,
            "m/s",
        )?;
        range("sensor.mass_sigma_kg", s.mass_sigma_kg, 0.0, 3000.0, "kg")?;
        if let Some(m) = s.mass_estimate_kg {
            range("sensor.mass_estimate_kg", m, 100.0, 100000.0, "kg")?;
        }
        // A key that would be silently ignored is an error that says which wins.
        if s.mass_estimate_kg.is_some() && s.mass_bias_kg != 0.0 {
            return Err((
                "sensor.mass_bias_kg".into(),
                "ignored with `mass_estimate_kg`, which is the reported mass as given (the bias \
                 applies to the true mass only without it): remove one of the two"
                    .into(),
            ));
        }
        if o.kind.is_fixed() && s.mass_estimate_kg.is_none() {
            return Err((
                "sensor.mass_estimate_kg".into(),
                format!(
                    "required for kind = \"{}\" (what the object classifier reports for it)",
                    o.kind.name()
                ),
            ));
        }
        range("sensor.confidence", s.confidence, 0.0, 1.0, "")?;
        if let Some(v) = &self.v2x {
            range("v2x.period_ms", v.period_ms, 10.0, 1000.0, "ms")?;
            range("v2x.latency_ms", v.latency_ms, 0.0, 500.0, "ms")?;
            range(
                "v2x.range_m",
                v.range_m,
                1.0,
                400.0,
                "m (the frame's range)",
            )?;
            range("v2x.distance_noise_m", v.distance_noise_m, 0.0, 20.0, "m")?;
            range("v2x.speed_noise_mps", v.speed_noise_mps, 0.0, 10.0, "m/s")?;
            range(
                "v2x.mass_sigma_kg",
                v.mass_sigma_kg,
                0.0,
                2550.0,
                "kg (the frame's range)",
            )?;
            if let Some(m) = v.mass_kg {
                range("v2x.mass_kg", m, 0.0, 40000.0, "kg (the frame's range)")?;
            }
        }
        range(
            "sensor.vehicle_period_ms",
            s.vehicle_period_ms,
            1.0,
            1000.0,
            "ms",
        )?;
        range(
            "sensor.occupant_period_ms",
            s.occupant_period_ms,
            1.0,
            5000.0,
            "ms",
        )?;
        range(
            "sensor.accel_rate_hz",
            s.accel_rate_hz,
            1000.0,
            8000.0,
            "Hz",
        )?;
        range(
            "sensor.accel_noise_mps2",
            s.accel_noise_mps2,
            0.0,
            50.0,
            "m/s²",
        )?;
        range(
            "sensor.accel_full_scale_g",
            s.accel_full_scale_g,
            10.0,
            1000.0,
            "g",
        )?;
        range(
            "sensor.safing_rate_hz",
            s.safing_rate_hz,
            1000.0,
            8000.0,
            "Hz",
        )?;
        range(
            "sensor.safing_noise_mps2",
            s.safing_noise_mps2,
            0.0,
            50.0,
            "m/s²",
        )?;
        range(
            "sensor.safing_full_scale_g",
            s.safing_full_scale_g,
            10.0,
            1000.0,
            "g",
        )?;
        if s.accel_lowpass_hz != 0.0 {
            range(
                "sensor.accel_lowpass_hz",
                s.accel_lowpass_hz,
                50.0,
                2000.0,
                "Hz (or 0: no filter)",
            )?;
        }
        range(
            "sensor.satellite_depth_m",
            s.satellite_depth_m,
            0.05,
            0.5,
            "m",
        )?;
        range(
            "sensor.satellite_rate_hz",
            s.satellite_rate_hz,
            1000.0,
            8000.0,
            "Hz",
        )?;
        range(
            "sensor.satellite_noise_mps2",
            s.satellite_noise_mps2,
            0.0,
            50.0,
            "m/s²",
        )?;
        range(
            "sensor.satellite_full_scale_g",
            s.satellite_full_scale_g,
            50.0,
            1000.0,
            "g",
        )?;
        if s.satellite_lowpass_hz != 0.0 {
            range(
                "sensor.satellite_lowpass_hz",
                s.satellite_lowpass_hz,
                50.0,
                2000.0,
                "Hz (or 0: no filter)",
            )?;
        }
        let windows = s
            .dropouts
            .iter()
            .enumerate()
            .map(|(i, d)| (format!("sensor.dropouts[{i}]"), d.start_s, d.end_s))
            .chain(
                s.freezes
                    .iter()
                    .enumerate()
                    .map(|(i, d)| (format!("sensor.freezes[{i}]"), d.start_s, d.end_s)),
            )
            .chain(
                s.accel_faults
                    .iter()
                    .enumerate()
                    .map(|(i, d)| (format!("sensor.accel_faults[{i}]"), d.start_s, d.end_s)),
            );
        for (f, start_s, end_s) in windows {
            if !(start_s.is_finite() && end_s.is_finite() && start_s >= 0.0 && end_s > start_s) {
                return Err((
                    f,
                    format!("window {start_s}..{end_s} s must satisfy 0 <= start_s < end_s"),
                ));
            }
        }
        let occ = &self.occupant;
        range("occupant.mass_kg", occ.mass_kg, 30.0, 150.0, "kg")?;
        range(
            "occupant.chest_to_wheel_mm",
            occ.chest_to_wheel_mm,
            150.0,
            600.0,
            "mm",
        )?;
        range(
            "occupant.seat_track_mm",
            occ.seat_track_mm,
            0.0,
            400.0,
            "mm",
        )?;
        for (i, e) in self.accel_events.iter().enumerate() {
            validate_event(i, e, self.duration_s)?;
        }
        Ok(())
    }
}

/// Whether an `[[accel_event]]` kind takes a key.
#[derive(Clone, Copy, PartialEq)]
enum Key {
    Need,
    May,
    No,
}

/// The checks of `accel_event[i]`: onset within the run, the kind's keys present and no
/// other kind's, ranges, `end_s` after `start_s`.
fn validate_event(i: usize, e: &AccelEvent, duration_s: f64) -> Result<(), (String, String)> {
    let field = |key: &str| format!("accel_event[{i}].{key}");
    let in_range = |key: &str, v: f64, (lo, hi): (f64, f64), unit: &str| {
        if v.is_finite() && v >= lo && v <= hi {
            Ok(())
        } else {
            Err((field(key), format!("{v} is outside {lo}..={hi} {unit}")))
        }
    };
    in_range("start_s", e.start_s, (0.0, duration_s), "s (the run)")?;
    let kind = e.kind.name();
    // Which keys the kind takes: peak_g, duration_ms, rms_g, end_s, frequency_hz,
    // net_dv_mps, phase_deg (Need: required, May: optional, No: rejected).
    use Key::{May, Need, No};
    let needs = match e.kind {
        AccelEventKind::HalfSine => [Need, Need, No, No, No, No, No],
        AccelEventKind::Spike => [Need, No, No, No, No, No, No],
        AccelEventKind::RoughRoad => [No, No, Need, Need, No, No, No],
        AccelEventKind::Offset => [Need, No, No, Need, No, No, No],
        AccelEventKind::Ringing => [Need, Need, No, No, Need, May, May],
    };
    let keys = [
        ("peak_g", e.peak_g),
        ("duration_ms", e.duration_ms),
        ("rms_g", e.rms_g),
        ("end_s", e.end_s),
        ("frequency_hz", e.frequency_hz),
        ("net_dv_mps", e.net_dv_mps),
        ("phase_deg", e.phase_deg),
    ];
    for ((key, value), needed) in keys.into_iter().zip(needs) {
        match (value, needed) {
            (None, Need) => {
                return Err((field(key), format!("required for kind = \"{kind}\"")));
            }
            (Some(_), No) => {
                return Err((
                    field(key),
                    format!("not used by kind = \"{kind}\": remove this key"),
                ));
            }
            _ => {}
        }
    }
    if let Some(v) = e.peak_g {
        let bounds = if e.kind == AccelEventKind::Ringing {
            RINGING_PEAK_G
        } else {
            EVENT_PEAK_G
        };
        in_range("peak_g", v, bounds, "g")?;
    }
    if let Some(v) = e.duration_ms {
        in_range("duration_ms", v, EVENT_DURATION_MS, "ms")?;
    }
    if let Some(v) = e.rms_g {
        in_range("rms_g", v, EVENT_RMS_G, "g")?;
    }
    if let Some(v) = e.frequency_hz {
        in_range("frequency_hz", v, EVENT_FREQUENCY_HZ, "Hz")?;
    }
    if let Some(v) = e.net_dv_mps {
        in_range("net_dv_mps", v, EVENT_NET_DV_MPS, "m/s")?;
    }
    if let Some(v) = e.phase_deg {
        in_range("phase_deg", v, EVENT_PHASE_DEG, "deg")?;
    }
    if let Some(end) = e.end_s {
        if !(end.is_finite() && end > e.start_s) {
            return Err((
                field("end_s"),
                format!("{end} s must be after start_s = {} s", e.start_s),
            ));
        }
    }
    Ok(())
}
