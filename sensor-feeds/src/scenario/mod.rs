//! Scenario files (schema documented in `scenarios/README.md`): the schema here, the semantic
//! checks in [`validate`](self::validate), where an error is in the file in `location`.
//!
//! Every error names the file, the line (and column) and the field, because a bench engineer
//! editing a scenario needs to know exactly where the mistake is: syntax, type and
//! unknown-field errors carry `toml`'s span; semantic errors (a negative mass, a dropout window
//! that ends before it starts) are located by the span of their key in the parsed document.

mod location;
mod validate;

pub use location::ScenarioError;

use serde::Deserialize;
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

    /// When the crash accelerometer first fails [s after start]: the earliest dropout that
    /// silences it or faulty-reading window (`None`: it never fails).
    pub fn accel_fails_at_s(&self) -> Option<f64> {
        let silenced = self
            .dropouts
            .iter()
            .filter(|d| matches!(d.target, DropoutTarget::Accel | DropoutTarget::All))
            .map(|d| d.start_s);
        let faulty = self.accel_faults.iter().map(|f| f.start_s);
        silenced.chain(faulty).reduce(f64::min)
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
            let (line, column) = e.span().map(|s| location::line_col(text, s.start)).unzip();
            let message = e.message().to_owned();
            // Unknown/missing field errors name the key themselves; others (types, ranges
            // of integers) get the key of the offending line.
            let field = e.span().and_then(|s| location::field_at(text, s.start));
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
                line: location::line_of_field(text, &field),
                column: None,
                field: Some(field),
                message,
            })?;
        Ok(scenario)
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
    fn errors_in_an_array_of_tables_name_the_entry_and_its_line() {
        // The same windows written as [[sensor.dropouts]] tables: the second one is wrong.
        let text = format!(
            "{OK}\n[[sensor.dropouts]]\nstart_s = 1.0\nend_s = 1.5\n\n[[sensor.dropouts]]\nstart_s = 2.0\nend_s = 1.9\n"
        );
        let second_header = text
            .lines()
            .enumerate()
            .filter(|(_, l)| l.trim() == "[[sensor.dropouts]]")
            .nth(1)
            .map(|(i, _)| i + 1);
        let e = Scenario::parse("x.toml", &text).unwrap_err();
        assert_eq!(e.field.as_deref(), Some("sensor.dropouts[1]"), "{e}");
        assert_eq!(e.line, second_header, "{e}");
        // A type error inside the first entry names the entry's key.
        let bad = text.replacen("start_s = 1.0", "start_s = \"soon\"", 1);
        let e = Scenario::parse("x.toml", &bad).unwrap_err();
        assert_eq!(
            e.field.as_deref(),
            Some("sensor.dropouts[0].start_s"),
            "{e}"
        );
        let line = bad
            .lines()
            .position(|l| l.contains("\"soon\""))
            .map(|i| i + 1);
        assert_eq!(e.line, line, "{e}");
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
