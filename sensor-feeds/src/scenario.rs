//! Scenario files: schema, loading and validation (schema documented in `scenarios/README.md`).
//!
//! Every error names the file, the line (and column) and the field, because a bench engineer
//! editing a scenario needs to know exactly where the mistake is:
//! syntax/type/unknown-field errors come from `toml`'s span; semantic errors (a negative mass,
//! a dropout window that ends before it starts) are located by searching the field's key inside
//! its table in the source text.

use serde::Deserialize;
use std::fmt;
use std::path::Path;

/// A whole scenario file.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Scenario {
    /// Short name (output folder, reports, bench truth; ≤ 64 bytes).
    pub name: String,
    /// One-line description (what the case shows).
    #[serde(default)]
    pub description: String,
    /// Seed of every random draw (noise), so a run is reproducible.
    #[serde(default = "default_seed")]
    pub seed: u64,
    /// Length of the played scenario [s] (t = 0 at start).
    pub duration_s: f64,
    /// The ego vehicle (the one carrying the ECU).
    pub ego: Vehicle,
    /// The collision opponent.
    pub opponent: Opponent,
    /// Sensor model (rates, noise, bias, dropouts, latency).
    #[serde(default)]
    pub sensor: SensorModel,
    /// The ego driver.
    pub occupant: Occupant,
    /// What the scenario is meant to show (the e2e tests assert it).
    #[serde(default)]
    pub expect: Expect,
}

fn default_seed() -> u64 {
    1
}

/// A vehicle: true mass, stiffness class, initial speed, braking.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Vehicle {
    /// True mass including payload [kg].
    pub mass_kg: f64,
    /// Stiffness class 1..=6 (absent: the class of `mass_kg`).
    pub class: Option<u8>,
    /// Initial speed [km/h] (towards the other party).
    pub speed_kph: f64,
    /// Braking manoeuvre (absent: no braking).
    pub braking: Option<Braking>,
}

/// A braking manoeuvre: deceleration ramps linearly from 0 at `start_s` to `decel_mps2` over
/// `ramp_s` (brake pressure build-up), then stays until standstill.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Braking {
    /// Brake onset [s after scenario start].
    pub start_s: f64,
    /// Full deceleration [m/s²] (positive).
    pub decel_mps2: f64,
    /// Build-up time from 0 to full deceleration [s].
    #[serde(default = "default_ramp_s")]
    pub ramp_s: f64,
    /// What the brake system reports on CAN while braking.
    #[serde(default)]
    pub state: BrakeStateName,
}

fn default_ramp_s() -> f64 {
    0.15
}

/// Brake state as sent in `EgoVehicleState.BrakeState` while the manoeuvre is active.
#[derive(Clone, Copy, Debug, Default, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum BrakeStateName {
    /// Driver braking without ABS intervention.
    #[default]
    Driver,
    /// ABS regulating (driver full braking).
    Abs,
    /// Emergency brake assist (full braking boosted).
    Eba,
    /// Autonomous emergency braking.
    Aeb,
}

/// What the ego collides with.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum OpponentKind {
    /// Another vehicle (two-mass collision).
    Vehicle,
    /// Rigid, non-deforming, immovable barrier (infinite mass, rigid face).
    Barrier,
}

/// The opponent.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Opponent {
    /// Vehicle or rigid barrier.
    pub kind: OpponentKind,
    /// True mass [kg] (vehicle only).
    pub mass_kg: Option<f64>,
    /// Stiffness class 1..=6 (vehicle only; absent: the class of `mass_kg`).
    pub class: Option<u8>,
    /// Initial speed towards the ego [km/h] (vehicle only; default 0).
    #[serde(default)]
    pub speed_kph: f64,
    /// Initial distance between the fronts [m].
    pub initial_distance_m: f64,
    /// Braking manoeuvre (vehicle only).
    pub braking: Option<Braking>,
    /// Evasive manoeuvre: from this instant [s] the opponent has left the ego's path (swerved
    /// away) — no contact can happen afterwards and the sensor reports no valid object in path.
    pub evade_s: Option<f64>,
}

/// Which feed a dropout window silences.
#[derive(Clone, Copy, Debug, Default, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum DropoutTarget {
    /// The object list (iceoryx2 ObjectState).
    #[default]
    Object,
    /// The EgoVehicleState CAN frame.
    Vehicle,
    /// The OccupantClassification CAN frame.
    Occupant,
    /// The crash accelerometer.
    Accel,
    /// Everything.
    All,
}

/// A time window in which a feed publishes nothing.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Dropout {
    /// Window start [s after scenario start].
    pub start_s: f64,
    /// Window end [s after scenario start] (exclusive).
    pub end_s: f64,
    /// Silenced feed (default: the object list).
    #[serde(default)]
    pub target: DropoutTarget,
}

/// A time window in which the object list is *stuck*: it keeps publishing its last sample
/// unchanged (same measurement timestamp, same sequence number) — a hung sensor whose transport
/// still runs. Unlike a dropout the data keeps arriving, so only its age can reveal it.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Freeze {
    /// Window start [s after scenario start].
    pub start_s: f64,
    /// Window end [s after scenario start] (exclusive).
    pub end_s: f64,
}

/// What a faulty crash accelerometer reports inside an [`AccelFault`] window.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum AccelFaultKind {
    /// Stuck at its last genuine reading (the batches keep coming, the value never changes).
    Stuck,
    /// Pinned at full scale in the deceleration direction (`accel_full_scale_g`).
    Saturated,
}

/// A time window in which the crash accelerometer is faulty but keeps publishing.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct AccelFault {
    /// Window start [s after scenario start].
    pub start_s: f64,
    /// Window end [s after scenario start] (exclusive).
    pub end_s: f64,
    /// What it reports meanwhile.
    pub kind: AccelFaultKind,
}

/// Sensor model; every field has a documented default.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct SensorModel {
    /// Object-list period [ms] (radar/camera fusion cycle).
    pub object_period_ms: f64,
    /// Measurement age at publication [ms] (the timestamp carries the measurement time).
    pub latency_ms: f64,
    /// Objects beyond this distance are not reported [m].
    pub range_m: f64,
    /// Gaussian noise on the distance [m, 1σ].
    pub distance_noise_m: f64,
    /// Gaussian noise on the closing speed [m/s, 1σ].
    pub speed_noise_mps: f64,
    /// Gaussian noise on the relative acceleration the tracker reports [m/s², 1σ] (a
    /// tracker differentiates it; 0 = the true value, and no random draw, so the noise of the
    /// other fields stays what it was without this key).
    pub relative_accel_noise_mps2: f64,
    /// Systematic error of the opponent-mass estimate [kg] (e.g. unknown payload).
    pub mass_bias_kg: f64,
    /// Per-sample Gaussian noise of the mass estimate [kg, 1σ].
    pub mass_noise_kg: f64,
    /// Systematic error of the reported closing speed [m/s] (a miscalibrated radar).
    pub speed_bias_mps: f64,
    /// Uncertainty the sensor reports with its estimate [kg, 1σ] (~300 kg payload range).
    pub mass_sigma_kg: f64,
    /// Reported mass instead of true mass + bias [kg] (a barrier has no finite mass; what a
    /// classifier would report for a wall is a modelling choice of the scenario).
    pub mass_estimate_kg: Option<f64>,
    /// Track confidence reported with every object (0..1).
    pub confidence: f64,
    /// EgoVehicleState period [ms] (DBC: 10).
    pub vehicle_period_ms: f64,
    /// OccupantClassification period [ms] (DBC: 100).
    pub occupant_period_ms: f64,
    /// Crash accelerometer sample rate [Hz] (≥ 1000, ≤ 8000: one batch per ms).
    pub accel_rate_hz: f64,
    /// Gaussian accelerometer noise [m/s², 1σ].
    pub accel_noise_mps2: f64,
    /// Measuring range of the crash accelerometer [g]: readings are clipped to ±this, and a
    /// saturated sensor reads −this.
    pub accel_full_scale_g: f64,
    /// Feed dropouts.
    pub dropouts: Vec<Dropout>,
    /// Stuck object-list windows (stale data: the last sample repeated).
    pub freezes: Vec<Freeze>,
    /// Faulty-accelerometer windows (stuck, saturated).
    pub accel_faults: Vec<AccelFault>,
}

impl Default for SensorModel {
    fn default() -> Self {
        SensorModel {
            object_period_ms: 20.0,
            latency_ms: 20.0,
            range_m: 80.0,
            distance_noise_m: 0.05,
            speed_noise_mps: 0.1,
            relative_accel_noise_mps2: 0.0,
            mass_bias_kg: 0.0,
            mass_noise_kg: 0.0,
            speed_bias_mps: 0.0,
            mass_sigma_kg: 300.0,
            mass_estimate_kg: None,
            confidence: 0.95,
            vehicle_period_ms: 10.0,
            occupant_period_ms: 100.0,
            accel_rate_hz: 4000.0,
            accel_noise_mps2: 0.5,
            accel_full_scale_g: 200.0,
            dropouts: Vec::new(),
            freezes: Vec::new(),
            accel_faults: Vec::new(),
        }
    }
}

impl SensorModel {
    /// True if `target` is silenced at scenario time `t_s`.
    pub fn dropped(&self, target: DropoutTarget, t_s: f64) -> bool {
        self.dropouts.iter().any(|d| {
            (d.target == target || d.target == DropoutTarget::All)
                && t_s >= d.start_s
                && t_s < d.end_s
        })
    }

    /// The accelerometer fault at scenario time `t_s`, if any (the first window that holds).
    pub fn accel_fault(&self, t_s: f64) -> Option<AccelFaultKind> {
        self.accel_faults
            .iter()
            .find(|f| t_s >= f.start_s && t_s < f.end_s)
            .map(|f| f.kind)
    }

    /// True if the object list is stuck at scenario time `t_s`.
    pub fn frozen(&self, t_s: f64) -> bool {
        self.freezes
            .iter()
            .any(|f| t_s >= f.start_s && t_s < f.end_s)
    }
}

/// The driver.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Occupant {
    /// Occupant mass [kg].
    pub mass_kg: f64,
    /// Chest to steering wheel / airbag module [mm] (seat position).
    #[serde(default = "default_chest_to_wheel_mm")]
    pub chest_to_wheel_mm: f64,
    /// Belt buckled.
    #[serde(default = "default_true")]
    pub belted: bool,
    /// Seat track position from the front stop [mm] (sent on CAN; informative).
    #[serde(default = "default_seat_track_mm")]
    pub seat_track_mm: f64,
}

fn default_chest_to_wheel_mm() -> f64 {
    physics::defaults::CHEST_TO_WHEEL_M * 1e3
}
fn default_true() -> bool {
    true
}
fn default_seat_track_mm() -> f64 {
    150.0
}

/// The behaviour a scenario is written to show; absent keys are not asserted.
#[derive(Clone, Debug, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Expect {
    /// A true contact happens.
    pub contact: Option<bool>,
    /// The airbag is fired.
    pub airbag_fires: Option<bool>,
    /// The pretensioner is fired before the true contact (pre-crash preset).
    pub pretensioner_before_contact: Option<bool>,
    /// The pretensioner is released again (avoided collision).
    pub pretensioner_released: Option<bool>,
    /// The ECU falls back to the conventional reference restraint (commands with
    /// `CmdSource = Reference`).
    pub reference_fallback: Option<bool>,
    /// The ECU reports the crash accelerometer faulty (`EcuStatus.FaultAccelSensor`) before the
    /// true contact.
    pub accel_fault_before_contact: Option<bool>,
}

/// A scenario-file error: where and what.
#[derive(Clone, Debug, PartialEq)]
pub struct ScenarioError {
    /// File name as given.
    pub file: String,
    /// 1-based line, when known.
    pub line: Option<usize>,
    /// 1-based column, when known.
    pub column: Option<usize>,
    /// Dotted field path (`ego.mass_kg`), when known.
    pub field: Option<String>,
    /// What is wrong.
    pub message: String,
}

impl fmt::Display for ScenarioError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.file)?;
        if let Some(l) = self.line {
            write!(f, ":{l}")?;
            if let Some(c) = self.column {
                write!(f, ":{c}")?;
            }
        }
        write!(f, ": ")?;
        if let Some(field) = &self.field {
            write!(f, "field `{field}`: ")?;
        }
        write!(f, "{}", self.message)
    }
}

impl std::error::Error for ScenarioError {}

/// 1-based (line, column) of byte offset `pos` in `text`.
fn line_col(text: &str, pos: usize) -> (usize, usize) {
    let pos = pos.min(text.len());
    let before = &text[..pos];
    let line = before.matches('\n').count() + 1;
    let col = before.rfind('\n').map_or(pos, |nl| pos - nl - 1) + 1;
    (line, col)
}

/// Dotted path of the key on `line` (1-based): the nearest `[table]` header above it plus the
/// line's own `key =` (how a type error is turned into a field name).
fn field_at_line(text: &str, line: usize) -> Option<String> {
    let lines: Vec<&str> = text.lines().collect();
    let this = lines.get(line.checked_sub(1)?)?.trim();
    let key = this
        .split_once('=')
        .map(|(k, _)| k.trim().to_owned())
        .filter(|k| !k.is_empty() && !k.starts_with('['));
    let table = lines[..line - 1].iter().rev().find_map(|l| {
        let t = l.trim();
        t.strip_prefix('[')
            .and_then(|r| r.strip_suffix(']'))
            .map(|h| h.trim_matches(|c| c == '[' || c == ']').trim().to_owned())
    });
    match (table, key) {
        (Some(t), Some(k)) => Some(format!("{t}.{k}")),
        (None, Some(k)) => Some(k),
        (Some(t), None) => Some(t),
        (None, None) => None,
    }
}

/// 1-based line of `field` (`table.key` or `key`) in `text`, for semantic errors.
fn line_of_field(text: &str, field: &str) -> Option<usize> {
    let (table, key) = match field.rsplit_once('.') {
        Some((t, k)) => (Some(t), k),
        None => (None, field),
    };
    let key = key.split('[').next().unwrap_or(key);
    let mut in_table = table.is_none();
    for (i, l) in text.lines().enumerate() {
        let t = l.trim();
        if t.starts_with('[') {
            let h = t.trim_matches(|c| c == '[' || c == ']').trim();
            in_table = Some(h) == table;
            continue;
        }
        if in_table {
            if let Some((k, _)) = t.split_once('=') {
                if k.trim() == key {
                    return Some(i + 1);
                }
            }
        }
    }
    // The key is absent (a required value missing in a table): point at the table header.
    let table = table?;
    text.lines()
        .position(|l| l.trim().trim_matches(|c| c == '[' || c == ']').trim() == table)
        .map(|i| i + 1)
}

impl Scenario {
    /// Reads, parses and validates a scenario file.
    pub fn load(path: impl AsRef<Path>) -> Result<Self, ScenarioError> {
        let path = path.as_ref();
        let file = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|e| ScenarioError {
            file: file.clone(),
            line: None,
            column: None,
            field: None,
            message: format!("cannot read: {e}"),
        })?;
        Self::parse(&file, &text)
    }

    /// Parses and validates scenario text; `file` names the source in errors.
    pub fn parse(file: &str, text: &str) -> Result<Self, ScenarioError> {
        let scenario: Scenario = toml::from_str(text).map_err(|e| {
            let (line, column) = e.span().map(|s| line_col(text, s.start)).unzip();
            let message = e.message().to_owned();
            // Unknown/missing field errors name the key themselves; others (types, ranges
            // of integers) get the key of the offending line.
            let field = line.and_then(|l| field_at_line(text, l));
            ScenarioError {
                file: file.to_owned(),
                line,
                column,
                field,
                message,
            }
        })?;
        scenario
            .validate()
            .map_err(|(field, message)| ScenarioError {
                file: file.to_owned(),
                line: line_of_field(text, &field),
                column: None,
                field: Some(field),
                message,
            })?;
        Ok(scenario)
    }

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
        if self.name.is_empty() || self.name.len() > ipc::SCENARIO_NAME_CAPACITY {
            return Err((
                "name".into(),
                format!("must be 1..={} bytes", ipc::SCENARIO_NAME_CAPACITY),
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
        match o.kind {
            OpponentKind::Vehicle => {
                let m = o.mass_kg.ok_or((
                    "opponent.mass_kg".to_owned(),
                    "required for kind = \"vehicle\"".to_owned(),
                ))?;
                range("opponent.mass_kg", m, 300.0, 10000.0, "kg")?;
                class("opponent.class", o.class)?;
                range("opponent.speed_kph", o.speed_kph, 0.0, 200.0, "km/h")?;
                braking("opponent.braking", &o.braking, self.duration_s)?;
                if let Some(te) = o.evade_s {
                    range("opponent.evade_s", te, 0.0, self.duration_s, "s")?;
                }
            }
            OpponentKind::Barrier => {
                let bad = if o.mass_kg.is_some() {
                    Some("mass_kg")
                } else if o.class.is_some() {
                    Some("class")
                } else if o.speed_kph != 0.0 {
                    Some("speed_kph")
                } else if o.braking.is_some() {
                    Some("braking")
                } else if o.evade_s.is_some() {
                    Some("evade_s")
                } else {
                    None
                };
                if let Some(k) = bad {
                    return Err((
                        format!("opponent.{k}"),
                        "a rigid barrier is immovable and non-deforming: remove this key".into(),
                    ));
                }
            }
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
        if o.kind == OpponentKind::Barrier && s.mass_estimate_kg.is_none() {
            return Err((
                "sensor.mass_estimate_kg".into(),
                "required for a barrier opponent (what the object classifier reports for it)"
                    .into(),
            ));
        }
        range("sensor.confidence", s.confidence, 0.0, 1.0, "")?;
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
        Ok(())
    }

    /// Ego stiffness class (explicit or by mass).
    pub fn ego_class(&self) -> physics::MassClass {
        class_or_mass(self.ego.class, self.ego.mass_kg)
    }

    /// Opponent stiffness class (`None` for a barrier).
    pub fn opponent_class(&self) -> Option<physics::MassClass> {
        match self.opponent.kind {
            OpponentKind::Barrier => None,
            OpponentKind::Vehicle => Some(class_or_mass(
                self.opponent.class,
                self.opponent
                    .mass_kg
                    .unwrap_or(physics::paper::TABLE5_MASS_KG),
            )),
        }
    }

    /// True opponent mass [kg] (∞ for a barrier).
    pub fn opponent_mass_kg(&self) -> f64 {
        match self.opponent.kind {
            OpponentKind::Barrier => f64::INFINITY,
            OpponentKind::Vehicle => self.opponent.mass_kg.unwrap_or(f64::NAN),
        }
    }
}

fn class_or_mass(class: Option<u8>, mass_kg: f64) -> physics::MassClass {
    class
        .and_then(|c| physics::MassClass::new(c).ok())
        .or_else(|| physics::class_for_mass_kg(mass_kg).ok())
        // Validation keeps masses inside the class table; class 4 is the paper's Taurus class.
        .unwrap_or_else(|| physics::MassClass::new(4).expect("class 4 exists"))
}

#[cfg(test)]
mod tests {
    use super::*;

    const OK: &str = r#"
name = "t"
duration_s = 3.0

[ego]
mass_kg = 1785
speed_kph = 50

[opponent]
kind = "vehicle"
mass_kg = 1785
speed_kph = 50
initial_distance_m = 40

[occupant]
mass_kg = 75
"#;

    #[test]
    fn minimal_file_gets_documented_defaults() {
        let s = Scenario::parse("t.toml", OK).expect("valid");
        assert_eq!(s.sensor.object_period_ms, 20.0);
        assert_eq!(s.sensor.mass_sigma_kg, 300.0);
        assert_eq!(s.occupant.chest_to_wheel_mm, 300.0);
        assert!(s.occupant.belted);
        assert_eq!(s.ego_class().number(), 4);
        assert_eq!(s.seed, 1);
    }

    #[test]
    fn unknown_field_names_file_line_and_field() {
        let text = OK.replace("mass_kg = 75", "mass_kg = 75\nweight = 3");
        let e = Scenario::parse("x.toml", &text).unwrap_err();
        assert_eq!(e.file, "x.toml");
        // Line 1 of OK is empty: [occupant] is line 15, mass_kg 16, the unknown key 17.
        assert_eq!(e.line, Some(17), "{e}");
        assert_eq!(e.field.as_deref(), Some("occupant.weight"), "{e}");
        assert!(e.message.contains("weight"), "{e}");
        assert!(
            e.to_string()
                .starts_with("x.toml:17:1: field `occupant.weight`"),
            "{e}"
        );
    }

    #[test]
    fn type_error_names_the_field() {
        let text = OK.replace(
            "speed_kph = 50\n\n[opponent]",
            "speed_kph = \"fast\"\n\n[opponent]",
        );
        let e = Scenario::parse("x.toml", &text).unwrap_err();
        assert_eq!(e.field.as_deref(), Some("ego.speed_kph"), "{e}");
        assert_eq!(e.line, Some(7), "{e}");
    }

    #[test]
    fn semantic_error_is_located() {
        let text = OK.replace("mass_kg = 75", "mass_kg = 500");
        let e = Scenario::parse("x.toml", &text).unwrap_err();
        assert_eq!(e.field.as_deref(), Some("occupant.mass_kg"), "{e}");
        assert_eq!(e.line, Some(16), "{e}");
        let text = OK.replace("initial_distance_m = 40", "initial_distance_m = -1");
        let e = Scenario::parse("x.toml", &text).unwrap_err();
        assert_eq!(
            e.field.as_deref(),
            Some("opponent.initial_distance_m"),
            "{e}"
        );
        assert_eq!(e.line, Some(13), "{e}");
    }

    #[test]
    fn missing_required_field_is_reported() {
        let text = OK.replace("duration_s = 3.0\n", "");
        let e = Scenario::parse("x.toml", &text).unwrap_err();
        assert!(e.message.contains("duration_s"), "{e}");
    }

    #[test]
    fn barrier_rejects_vehicle_keys_and_needs_reported_mass() {
        let text = OK.replace("kind = \"vehicle\"", "kind = \"barrier\"");
        let e = Scenario::parse("x.toml", &text).unwrap_err();
        assert_eq!(e.field.as_deref(), Some("opponent.mass_kg"), "{e}");
        let text = "name = \"b\"\nduration_s = 2\n[ego]\nmass_kg = 1785\nspeed_kph = 56\n\
                    [opponent]\nkind = \"barrier\"\ninitial_distance_m = 20\n[occupant]\nmass_kg = 75\n";
        let e = Scenario::parse("x.toml", text).unwrap_err();
        assert_eq!(e.field.as_deref(), Some("sensor.mass_estimate_kg"), "{e}");
        let ok = format!("{text}[sensor]\nmass_estimate_kg = 3000\n");
        let s = Scenario::parse("x.toml", &ok).expect("valid barrier");
        assert!(s.opponent_mass_kg().is_infinite());
        assert!(s.opponent_class().is_none());
    }

    #[test]
    fn freeze_windows() {
        let text = format!("{OK}\n[sensor]\nfreezes = [{{ start_s = 0.6, end_s = 0.9 }}]\n");
        let s = Scenario::parse("x.toml", &text).expect("valid");
        assert!(!s.sensor.frozen(0.59));
        assert!(s.sensor.frozen(0.6));
        assert!(!s.sensor.frozen(0.9));
        let bad = text.replace("end_s = 0.9", "end_s = 0.6");
        let e = Scenario::parse("x.toml", &bad).unwrap_err();
        assert_eq!(e.field.as_deref(), Some("sensor.freezes[0]"), "{e}");
        let unknown = text.replace("end_s = 0.9", "end_s = 0.9, target = \"object\"");
        assert!(Scenario::parse("x.toml", &unknown).is_err());
    }

    #[test]
    fn accel_fault_windows_and_speed_bias() {
        let text = format!(
            "{OK}\n[sensor]\nspeed_bias_mps = -2.5\naccel_faults = [{{ start_s = 0.5, end_s = 0.7, kind = \"stuck\" }}, {{ start_s = 1.0, end_s = 1.1, kind = \"saturated\" }}]\n"
        );
        let s = Scenario::parse("x.toml", &text).expect("valid");
        assert_eq!(s.sensor.speed_bias_mps, -2.5);
        assert_eq!(s.sensor.accel_fault(0.49), None);
        assert_eq!(s.sensor.accel_fault(0.5), Some(AccelFaultKind::Stuck));
        assert_eq!(s.sensor.accel_fault(1.05), Some(AccelFaultKind::Saturated));
        assert_eq!(s.sensor.accel_fault(1.1), None);
        assert_eq!(s.sensor.accel_full_scale_g, 200.0);
        let bad = text.replace("end_s = 0.7", "end_s = 0.4");
        let e = Scenario::parse("x.toml", &bad).unwrap_err();
        assert_eq!(e.field.as_deref(), Some("sensor.accel_faults[0]"), "{e}");
        let bad = text.replace("\"stuck\"", "\"sticky\"");
        assert!(Scenario::parse("x.toml", &bad).is_err());
    }

    #[test]
    fn dropout_windows() {
        let text = format!(
            "{OK}\n[sensor]\ndropouts = [{{ start_s = 1.0, end_s = 1.5 }}, {{ start_s = 2.0, end_s = 2.1, target = \"all\" }}]\n"
        );
        let s = Scenario::parse("x.toml", &text).expect("valid");
        assert!(!s.sensor.dropped(DropoutTarget::Object, 0.99));
        assert!(s.sensor.dropped(DropoutTarget::Object, 1.0));
        assert!(!s.sensor.dropped(DropoutTarget::Object, 1.5));
        assert!(!s.sensor.dropped(DropoutTarget::Accel, 1.2));
        assert!(s.sensor.dropped(DropoutTarget::Accel, 2.05));
        let bad = text.replace("end_s = 1.5", "end_s = 0.5");
        let e = Scenario::parse("x.toml", &bad).unwrap_err();
        assert_eq!(e.field.as_deref(), Some("sensor.dropouts[0]"), "{e}");
        assert!(e.line.is_some(), "{e}");
    }
}
