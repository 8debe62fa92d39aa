//! Scenario files (schema documented in `scenarios/README.md`): the schema here, the semantic
//! checks in [`validate`](self::validate), where an error is in the file in `location`.
//!
//! Every error names the file, the line (and column) and the field, because a bench engineer
//! editing a scenario needs to know exactly where the mistake is: syntax, type and
//! unknown-field errors carry `toml`'s span; semantic errors (a negative mass, a dropout window
//! that ends before it starts) are located by the span of their key in the parsed document.

mod location;
mod pulse;
mod sensor_model;
mod validate;

pub use location::ScenarioError;
pub use pulse::MeasuredPulse;

/// Longest scenario `name` [bytes]: what the bench truth record carries
/// (`ipc::SCENARIO_NAME_CAPACITY`; `sensor-feeds` asserts the two agree at compile time).
pub const NAME_CAPACITY: usize = 64;

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
    /// What the acceleration sensors see besides a crash (`[[accel_event]]`): misuse events
    /// the whole car feels and single-sensor faults ([`AccelEvent`]).
    #[serde(default, rename = "accel_event")]
    pub accel_events: Vec<AccelEvent>,
    /// The ego's V2X receiver (`[v2x]`; absent: the ego has none, as before): a second
    /// opponent-mass source, independent of the object list ([`V2x`]).
    #[serde(default)]
    pub v2x: Option<V2x>,
    /// A measured crash pulse for the ego from the contact on (`[pulse]`; absent: the
    /// two-mass model's, [`MeasuredPulse`]).
    #[serde(default)]
    pub pulse: Option<MeasuredPulse>,
}

/// The ego's V2X receiver and what the station ahead says of itself (`V2xOpponentMass` on
/// CAN): the opponent's own mass including its load, with range and closing speed from the two
/// stations' GNSS. Its noise has its own random stream, so adding `[v2x]` changes no other draw.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct V2x {
    /// Frame period [ms] (DBC: 100; CAM / BSM at 10 Hz).
    pub period_ms: f64,
    /// Age of the station's position and speed at reception [ms].
    pub latency_ms: f64,
    /// Stations beyond this distance are not received [m].
    pub range_m: f64,
    /// Gaussian noise of the GNSS range [m, 1σ].
    pub distance_noise_m: f64,
    /// Gaussian noise of the GNSS closing speed [m/s, 1σ].
    pub speed_noise_mps: f64,
    /// The opponent transmits (false: the ego's module is alive and reports no station).
    pub opponent_equipped: bool,
    /// Mass the station reports instead of its true mass [kg] (a misconfigured or forged
    /// station).
    pub mass_kg: Option<f64>,
    /// σ the station gives its mass [kg] (its own vehicle data, load included).
    pub mass_sigma_kg: f64,
}

impl Default for V2x {
    fn default() -> Self {
        V2x {
            period_ms: 100.0,
            latency_ms: 100.0,
            range_m: 300.0,
            distance_noise_m: 1.0,
            speed_noise_mps: 0.2,
            opponent_equipped: true,
            mass_kg: None,
            mass_sigma_kg: 100.0,
        }
    }
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
    /// Front width [m] (the ego's: where an offset or angled impact reaches its rails;
    /// default `physics::crash_mode::DEFAULT_WIDTH_M`, 1.8 m).
    #[serde(default = "default_width_m")]
    pub width_m: f64,
}

fn default_width_m() -> f64 {
    physics::crash_mode::DEFAULT_WIDTH_M
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

/// What the ego collides with (the crash modes: `physics::crash_mode`).
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum OpponentKind {
    /// Another vehicle (two-mass collision), over `overlap_percent` of the ego's width.
    Vehicle,
    /// Rigid, non-deforming, immovable barrier (infinite mass, rigid face), over
    /// `overlap_percent` of the ego's width or at `angle_deg` to its front.
    Barrier,
    /// A UN R94 offset deformable barrier: honeycomb face on a fixed block, struck over
    /// `overlap_percent` (default 40) of the ego's width.
    OffsetBarrier,
    /// A rigid pole on the ego's centre line, between its rails.
    Pole,
    /// The rear of a truck's bed (`mass_kg` the truck's): the ego's bumper and rails pass under.
    Underride,
}

impl OpponentKind {
    /// The name used in scenario files.
    pub fn name(self) -> &'static str {
        match self {
            OpponentKind::Vehicle => "vehicle",
            OpponentKind::Barrier => "barrier",
            OpponentKind::OffsetBarrier => "offset_barrier",
            OpponentKind::Pole => "pole",
            OpponentKind::Underride => "underride",
        }
    }

    /// Fixed in place and of unbounded mass (a barrier, a pole): the object classifier's
    /// report of its mass is all the ECU can have.
    pub fn is_fixed(self) -> bool {
        matches!(
            self,
            OpponentKind::Barrier | OpponentKind::OffsetBarrier | OpponentKind::Pole
        )
    }
}

/// A side of the ego's front.
#[derive(Clone, Copy, Debug, Default, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum FrontSide {
    /// The left (driver's, left-hand traffic's) side.
    #[default]
    Left,
    /// The right side.
    Right,
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
    /// Share of the ego's front width struck [%] (vehicle and barrier: default 100;
    /// offset_barrier: default 40).
    pub overlap_percent: Option<f64>,
    /// Angle between a rigid barrier's face and the ego's front [°] (barrier only; default 0).
    pub angle_deg: Option<f64>,
    /// The side an offset or angled impact strikes first (default left).
    pub struck_side: Option<FrontSide>,
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
    /// The safing accelerometer (the independent second acceleration channel).
    Safing,
    /// The V2X receiver's `V2xOpponentMass` frame.
    V2x,
    /// The left crush-zone satellite's PSI5 frames.
    SatelliteLeft,
    /// The right crush-zone satellite's PSI5 frames.
    SatelliteRight,
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

/// One of the car's acceleration sensors: the ECU's two and the two crush-zone satellites.
#[derive(Clone, Copy, Debug, Default, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum AccelSensor {
    /// The crash accelerometer (the main algorithm's sensor).
    #[default]
    Crash,
    /// The safing accelerometer (the safing function's independent sensor).
    Safing,
    /// The left crush-zone satellite (left rail tip).
    SatelliteLeft,
    /// The right crush-zone satellite (right rail tip).
    SatelliteRight,
}

impl AccelSensor {
    /// The two crush-zone satellites, left first.
    pub const SATELLITES: [AccelSensor; 2] =
        [AccelSensor::SatelliteLeft, AccelSensor::SatelliteRight];

    /// The name used in scenario files (`crash`, `safing`, `satellite-left`,
    /// `satellite-right`).
    pub fn name(self) -> &'static str {
        match self {
            AccelSensor::Crash => "crash",
            AccelSensor::Safing => "safing",
            AccelSensor::SatelliteLeft => "satellite-left",
            AccelSensor::SatelliteRight => "satellite-right",
        }
    }

    /// A crush-zone satellite (on the front structure, not in the ECU).
    pub fn is_satellite(self) -> bool {
        matches!(
            self,
            AccelSensor::SatelliteLeft | AccelSensor::SatelliteRight
        )
    }
}

/// A time window in which one acceleration sensor is faulty but keeps publishing.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct AccelFault {
    /// Window start [s after scenario start].
    pub start_s: f64,
    /// Window end [s after scenario start] (exclusive).
    pub end_s: f64,
    /// What it reports meanwhile.
    pub kind: AccelFaultKind,
    /// The faulty sensor (default: the crash accelerometer).
    #[serde(default)]
    pub sensor: AccelSensor,
}

/// What an [`AccelEvent`] does to the acceleration readings.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum AccelEventKind {
    /// A half-sine deceleration pulse `peak_g · sin(π (t − start_s) / duration)` for
    /// `t ∈ [start_s, start_s + duration_ms]`, added to the true deceleration (pothole, kerb
    /// strike, door slam, hammer blow).
    HalfSine,
    /// One sample — the first at or after `start_s` — reads `peak_g` instead of its value.
    Spike,
    /// Band-limited random deceleration (road excitation, 5–40 Hz, from rest at `start_s`,
    /// peaks clipped at 3 × the rms) with `rms_g` over
    /// `[start_s, end_s)`.
    RoughRoad,
    /// The reading shifted by `peak_g` over `[start_s, end_s)` (a biased sensor, or with
    /// `sensor = "all"` a sustained body acceleration).
    Offset,
    /// A misuse event as physics makes it: zero-mean structural ringing of amplitude `peak_g`
    /// at `frequency_hz` under a Hann envelope of `duration_ms`, starting at `phase_deg`
    /// (default 0: a crest at `start_s`), over a one-signed rigid-body pulse (a half-sine of the
    /// same duration) that carries the event's net velocity change `net_dv_mps` (default 0;
    /// positive: the car slows down). The ringing integrates to exactly zero, so the event changes
    /// the car's speed by `net_dv_mps` and nothing more — the bound its contact's impulse sets
    /// (`net_dv = J / m`; `world::events` and `../shared/misuse-envelopes.md`).
    Ringing,
}

impl AccelEventKind {
    /// The name used in scenario files.
    pub fn name(self) -> &'static str {
        match self {
            AccelEventKind::HalfSine => "half_sine",
            AccelEventKind::Spike => "spike",
            AccelEventKind::RoughRoad => "rough_road",
            AccelEventKind::Offset => "offset",
            AccelEventKind::Ringing => "ringing",
        }
    }
}

/// Which acceleration sensors an [`AccelEvent`] reaches.
#[derive(Clone, Copy, Debug, Default, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum EventSensor {
    /// Mechanical: the whole car feels it, every acceleration sensor sees it (each with its
    /// own noise, range and rate).
    #[default]
    All,
    /// A fault of the crash accelerometer alone.
    Crash,
    /// A fault of the safing accelerometer alone.
    Safing,
    /// A fault of the left crush-zone satellite alone.
    SatelliteLeft,
    /// A fault of the right crush-zone satellite alone.
    SatelliteRight,
}

impl EventSensor {
    /// The name used in scenario files (`all`, `crash`, `safing`, `satellite-left`,
    /// `satellite-right`).
    pub fn name(self) -> &'static str {
        match self {
            EventSensor::All => "all",
            EventSensor::Crash => "crash",
            EventSensor::Safing => "safing",
            EventSensor::SatelliteLeft => "satellite-left",
            EventSensor::SatelliteRight => "satellite-right",
        }
    }

    /// True if `sensor` sees events of this reach.
    pub fn reaches(self, sensor: AccelSensor) -> bool {
        match self {
            EventSensor::All => true,
            EventSensor::Crash => sensor == AccelSensor::Crash,
            EventSensor::Safing => sensor == AccelSensor::Safing,
            EventSensor::SatelliteLeft => sensor == AccelSensor::SatelliteLeft,
            EventSensor::SatelliteRight => sensor == AccelSensor::SatelliteRight,
        }
    }
}

/// One `[[accel_event]]`: what the acceleration sensors see besides a crash. Which keys a kind
/// needs (and which it rejects) is checked by validation: `peak_g` for `half_sine`, `spike`,
/// `offset` and `ringing`; `duration_ms` for `half_sine` and `ringing`; `rms_g` for
/// `rough_road` only; `end_s` for `rough_road` and `offset`; `frequency_hz` (required),
/// `net_dv_mps` and `phase_deg` (optional) for `ringing` only. Signs as the crash:
/// `peak_g > 0` is a deceleration.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct AccelEvent {
    /// What happens.
    pub kind: AccelEventKind,
    /// Onset [s after scenario start].
    pub start_s: f64,
    /// Peak deceleration of a half-sine, the reading of a spike, the shift of an offset [g]
    /// (+ = deceleration).
    pub peak_g: Option<f64>,
    /// Length of a half-sine or of a ringing's envelope [ms].
    pub duration_ms: Option<f64>,
    /// Ringing frequency [Hz] (`ringing`).
    pub frequency_hz: Option<f64>,
    /// Net velocity change of a `ringing` event [m/s, + = the car slows down; default 0].
    pub net_dv_mps: Option<f64>,
    /// Phase of a `ringing` event's carrier at `start_s` [deg; default 0: a crest].
    pub phase_deg: Option<f64>,
    /// Root mean square of a rough road over its window [g].
    pub rms_g: Option<f64>,
    /// End of a rough road or offset [s after scenario start] (exclusive).
    pub end_s: Option<f64>,
    /// Which sensors see it (default: all — a mechanical event).
    #[serde(default)]
    pub sensor: EventSensor,
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
    /// Safing accelerometer sample rate [Hz] (≥ 1000, ≤ 8000: one batch per ms).
    pub safing_rate_hz: f64,
    /// Gaussian noise of the safing accelerometer [m/s², 1σ] (its own random stream).
    pub safing_noise_mps2: f64,
    /// Measuring range of the safing accelerometer [g]: readings are clipped to ±this, and a
    /// saturated safing sensor reads −this.
    pub safing_full_scale_g: f64,
    /// −3 dB corner of both accelerometers' anti-alias low-pass before sampling [Hz]: a
    /// third-order Bessel, as the ADXL180 airbag accelerometer's default (`world::lowpass`);
    /// 0 = an ideal sampler without filter.
    pub accel_lowpass_hz: f64,
    /// The car has the two crush-zone satellites (left and right rail tip); `false`: the
    /// ECU's own sensors only, as a car without upfront sensors.
    pub satellites: bool,
    /// Where the satellites sit behind the fascia [m] (rail tips: bumper beam and crash boxes
    /// ahead of them; `world::truth`, "Crush-zone satellites").
    pub satellite_depth_m: f64,
    /// Satellite sample rate [Hz]: one PSI5 synchronous frame per sync pulse (2000 = 500 µs),
    /// delivered one slot (1 / rate) after its sample.
    pub satellite_rate_hz: f64,
    /// Gaussian noise of each satellite [m/s², 1σ] (own random streams).
    pub satellite_noise_mps2: f64,
    /// Measuring range of the satellites [g]: ±480 PSI5 data codes span ±this.
    pub satellite_full_scale_g: f64,
    /// −3 dB corner of the satellites' low-pass before sampling [Hz] (the same third-order
    /// Bessel model as the ECU's sensors; 0 = none).
    pub satellite_lowpass_hz: f64,
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
            safing_rate_hz: 2000.0,
            safing_noise_mps2: 1.0,
            safing_full_scale_g: 50.0,
            accel_lowpass_hz: 400.0,
            satellites: true,
            satellite_depth_m: physics::crush_zone::DEFAULT_DEPTH_M,
            satellite_rate_hz: 2000.0,
            satellite_noise_mps2: 2.0,
            satellite_full_scale_g: 240.0,
            satellite_lowpass_hz: 400.0,
            dropouts: Vec::new(),
            freezes: Vec::new(),
            accel_faults: Vec::new(),
        }
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
    /// The ECU planned with the V2X station's mass as the second source (its `v2x_lookups`
    /// counter is not 0).
    pub v2x_planned: Option<bool>,
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
        let mut scenario: Scenario = toml::from_str(text).map_err(|e| {
            let (line, column) = e
                .span()
                .map(|s| toml_location::line_col(text, s.start))
                .unzip();
            let message = e.message().to_owned();
            // Unknown/missing field errors name the key themselves; others (types, ranges
            // of integers) get the key of the offending line.
            let field = e
                .span()
                .and_then(|s| toml_location::field_at(text, s.start));
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
                line: toml_location::line_of_field(text, &field),
                column: None,
                field: Some(field),
                message,
            })?;
        if let Some(p) = scenario.pulse.as_mut() {
            p.read(file).map_err(|message| ScenarioError {
                file: file.to_owned(),
                line: toml_location::line_of_field(text, "pulse.file"),
                column: None,
                field: Some("pulse.file".to_owned()),
                message,
            })?;
        }
        Ok(scenario)
    }

    /// Ego stiffness class (explicit or by mass).
    pub fn ego_class(&self) -> physics::MassClass {
        class_or_mass(self.ego.class, self.ego.mass_kg)
    }

    /// Opponent stiffness class (a vehicle's; `None` for everything else).
    pub fn opponent_class(&self) -> Option<physics::MassClass> {
        match self.opponent.kind {
            OpponentKind::Vehicle => Some(class_or_mass(
                self.opponent.class,
                self.opponent
                    .mass_kg
                    .unwrap_or(physics::paper::TABLE5_MASS_KG),
            )),
            _ => None,
        }
    }

    /// True opponent mass [kg] (∞ for a barrier or a pole).
    pub fn opponent_mass_kg(&self) -> f64 {
        if self.opponent.kind.is_fixed() {
            f64::INFINITY
        } else {
            self.opponent.mass_kg.unwrap_or(f64::NAN)
        }
    }

    /// The struck share of the ego's front width, 0–1.
    pub fn overlap(&self) -> f64 {
        let default = match self.opponent.kind {
            OpponentKind::OffsetBarrier => 40.0,
            _ => 100.0,
        };
        self.opponent.overlap_percent.unwrap_or(default) / 100.0
    }

    /// How the ego meets its opponent: which of its front's load paths engage, and when.
    pub fn crash_mode(&self) -> physics::crash_mode::CrashMode {
        use physics::crash_mode::CrashMode;
        let o = &self.opponent;
        match o.kind {
            OpponentKind::Pole => CrashMode::Pole,
            OpponentKind::Underride => CrashMode::Underride,
            _ => match o.angle_deg {
                Some(a) if a > 0.0 => CrashMode::Angular {
                    angle_rad: a.to_radians(),
                },
                _ if self.overlap() < 1.0 => CrashMode::Offset {
                    overlap: self.overlap(),
                },
                _ => CrashMode::FullFrontal,
            },
        }
    }

    /// The opponent's own face in series with the ego's front: a vehicle's class curve, a
    /// deformable barrier's honeycomb over the struck width; `None` for a rigid face.
    pub fn opponent_face(&self) -> Result<Option<physics::Curve>, physics::PhysicsError> {
        Ok(match self.opponent.kind {
            OpponentKind::Vehicle => self.opponent_class().map(|c| *c.curve()),
            OpponentKind::OffsetBarrier => Some(physics::crash_mode::odb_face_curve(
                self.overlap() * self.ego.width_m,
            )?),
            _ => None,
        })
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
    fn v2x_table_defaults_ranges_and_located_errors() {
        let s = Scenario::parse("x.toml", OK).expect("valid");
        assert!(s.v2x.is_none(), "no [v2x]: no receiver");
        let s = Scenario::parse("x.toml", &format!("{OK}\n[v2x]\n")).expect("valid");
        assert_eq!(s.v2x, Some(V2x::default()));
        let v = V2x::default();
        assert_eq!(
            (v.period_ms, v.latency_ms, v.range_m),
            (100.0, 100.0, 300.0)
        );
        assert_eq!(
            (v.mass_kg, v.mass_sigma_kg, v.opponent_equipped),
            (None, 100.0, true)
        );
        // Out of the frame's range, or a period the bench cannot play: the key and its line.
        for (key, bad) in [
            ("period_ms", "5"),
            ("range_m", "500"),
            ("mass_kg", "50000"),
            ("mass_sigma_kg", "-1"),
        ] {
            let text = format!("{OK}\n[v2x]\n{key} = {bad}\n");
            let e = Scenario::parse("x.toml", &text).unwrap_err();
            assert_eq!(
                e.field.as_deref(),
                Some(format!("v2x.{key}").as_str()),
                "{e}"
            );
            assert_eq!(e.line, Some(text.lines().count()), "{e}");
        }
        let e = Scenario::parse("x.toml", &format!("{OK}\n[v2x]\nmass = 1\n")).unwrap_err();
        assert!(e.message.contains("unknown field `mass`"), "{e}");
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
    fn a_mass_bias_beside_a_reported_mass_is_an_error_that_names_the_winner() {
        // `mass_estimate_kg` is the reported mass as given; a bias beside it
        // was silently ignored.
        let text = format!("{OK}\n[sensor]\nmass_estimate_kg = 3000\nmass_bias_kg = 500\n");
        let e = Scenario::parse("x.toml", &text).unwrap_err();
        assert_eq!(e.field.as_deref(), Some("sensor.mass_bias_kg"), "{e}");
        assert!(e.message.contains("mass_estimate_kg"), "{e}");
        assert!(e.line.is_some(), "{e}");
        let text = format!("{OK}\n[sensor]\nmass_estimate_kg = 3000\nmass_bias_kg = 0\n");
        Scenario::parse("x.toml", &text).expect("a zero bias changes nothing");
    }

    /// Every key serde accepts in each table (from its own `deny_unknown_fields` message)
    /// is documented in scenarios/README.md: the docs are tested against the schema.
    #[test]
    fn scenarios_readme_documents_every_key_the_schema_accepts() {
        let readme = std::fs::read_to_string(
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenarios/README.md"),
        )
        .expect("scenarios/README.md");
        let schema = readme
            .split("## Schema")
            .nth(1)
            .and_then(|s| s.split("\n## ").next())
            .expect("the schema section");
        // A document with one unknown key in `table`: serde lists the keys it knows.
        let known = |table: &str, prefix: &str| -> Vec<String> {
            let text = format!("{prefix}{table}bogus_key = 1\n");
            let msg = match toml::from_str::<Scenario>(&text) {
                Err(e) => e.message().to_owned(),
                Ok(_) => panic!("{table}: bogus key accepted"),
            };
            let list = msg
                .split("expected one of ")
                .nth(1)
                .or_else(|| msg.split("expected ").nth(1))
                .unwrap_or_else(|| panic!("{table}: {msg}"));
            list.split('`')
                .skip(1)
                .step_by(2)
                .map(str::to_owned)
                .collect()
        };
        let top = "name = \"x\"\nduration_s = 1\n";
        let full = format!(
            "{top}[ego]\nmass_kg = 1785\nspeed_kph = 50\n[opponent]\nkind = \"barrier\"\n\
             initial_distance_m = 9\n[occupant]\nmass_kg = 75\n"
        );
        let tables = [
            ("", String::new()),
            ("[ego]\n", top.to_owned()),
            (
                "[ego.braking]\nstart_s = 0\ndecel_mps2 = 1\n",
                top.to_owned(),
            ),
            ("[opponent]\n", top.to_owned()),
            ("[sensor]\n", full.clone()),
            ("[occupant]\n", top.to_owned()),
            ("[expect]\n", full.clone()),
            ("[v2x]\n", full.clone()),
            (
                "[[accel_event]]\nkind = \"spike\"\nstart_s = 0\n",
                full.clone(),
            ),
        ];
        let mut missing = Vec::new();
        for (table, prefix) in &tables {
            let keys = known(table, prefix);
            assert!(keys.len() > 2, "{table}: {keys:?}");
            for k in keys {
                // A key in backticks; a table as its header (`[ego]`, `[[accel_event]]`,
                // `[ego.braking]`).
                let documented = [format!("`{k}`"), format!("[{k}]"), format!(".{k}]")]
                    .iter()
                    .any(|form| schema.contains(form.as_str()));
                if !documented {
                    missing.push(format!("{}{k}", table.lines().next().unwrap_or("")));
                }
            }
        }
        assert!(
            missing.is_empty(),
            "keys not in scenarios/README.md: {missing:?}"
        );
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

    #[test]
    fn safing_sensor_defaults_and_ranges() {
        let s = Scenario::parse("t.toml", OK).expect("valid");
        assert_eq!(s.sensor.safing_rate_hz, 2000.0);
        assert_eq!(s.sensor.safing_noise_mps2, 1.0);
        assert_eq!(s.sensor.safing_full_scale_g, 50.0);
        assert_eq!(
            s.sensor.accel_params(AccelSensor::Safing),
            (2000.0, 1.0, 50.0)
        );
        assert_eq!(
            s.sensor.accel_params(AccelSensor::Crash),
            (4000.0, 0.5, 200.0)
        );
        assert!(s.accel_events.is_empty());
        // OK ends on line 16: [sensor] is line 17, the key line 18.
        for (key, bad, msg) in [
            ("safing_rate_hz", "500", "500 is outside 1000..=8000 Hz"),
            ("safing_rate_hz", "9000", "9000 is outside 1000..=8000 Hz"),
            ("safing_noise_mps2", "-1", "-1 is outside 0..=50 m/s²"),
            ("safing_full_scale_g", "5", "5 is outside 10..=1000 g"),
        ] {
            let text = format!("{OK}[sensor]\n{key} = {bad}\n");
            let e = Scenario::parse("x.toml", &text).unwrap_err();
            assert_eq!(
                e.to_string(),
                format!("x.toml:18: field `sensor.{key}`: {msg}"),
                "{key}"
            );
        }
    }

    #[test]
    fn accel_faults_name_their_sensor() {
        let text = format!(
            "{OK}[sensor]\naccel_faults = [{{ start_s = 0.5, end_s = 0.7, kind = \"stuck\" }}, \
             {{ start_s = 0.6, end_s = 0.8, kind = \"saturated\", sensor = \"safing\" }}]\n\
             dropouts = [{{ start_s = 0.2, end_s = 0.3, target = \"safing\" }}]\n"
        );
        let s = Scenario::parse("x.toml", &text).expect("valid");
        assert_eq!(s.sensor.accel_faults[0].sensor, AccelSensor::Crash);
        assert_eq!(s.sensor.accel_fault(0.65), Some(AccelFaultKind::Stuck));
        assert_eq!(s.sensor.accel_fault(0.75), None, "the safing window");
        assert_eq!(
            s.sensor.sensor_fault(AccelSensor::Safing, 0.75),
            Some(AccelFaultKind::Saturated)
        );
        assert_eq!(s.sensor.sensor_fault(AccelSensor::Safing, 0.55), None);
        assert_eq!(s.sensor.accel_fails_at_s(), Some(0.5));
        assert_eq!(s.sensor.safing_fails_at_s(), Some(0.2));
        assert!(s.sensor.dropped(DropoutTarget::Safing, 0.25));
        assert!(!s.sensor.dropped(DropoutTarget::Accel, 0.25));
        let all = text.replace("target = \"safing\"", "target = \"all\"");
        let s = Scenario::parse("x.toml", &all).expect("valid");
        assert!(s.sensor.dropped(DropoutTarget::Safing, 0.25));
        assert!(s.sensor.dropped(DropoutTarget::Accel, 0.25));
        assert_eq!(s.sensor.accel_fails_at_s(), Some(0.2));
        let bad = text.replace("sensor = \"safing\"", "sensor = \"all\"");
        let e = Scenario::parse("x.toml", &bad).unwrap_err();
        assert_eq!(e.line, Some(18), "{e}");
        assert!(e.message.contains("unknown variant `all`"), "{e}");
    }

    /// `OK` + `extra`, and the 1-based line of the first line of `extra` containing `needle`.
    fn with(extra: &str, needle: &str) -> (String, Option<usize>) {
        let text = format!("{OK}{extra}");
        let line = text.lines().position(|l| l.contains(needle)).map(|i| i + 1);
        (text, line)
    }

    const EVENTS: &str = "
[[accel_event]]
kind = \"half_sine\"
start_s = 1.80
peak_g = 7.5
duration_ms = 4.0

[[accel_event]]
kind = \"spike\"
start_s = 0.5
peak_g = 40
sensor = \"crash\"

[[accel_event]]
kind = \"rough_road\"
start_s = 0.2
rms_g = 2.0
end_s = 2.5

[[accel_event]]
kind = \"offset\"
start_s = 1.0
peak_g = -6
end_s = 2.0
sensor = \"safing\"
";

    #[test]
    fn accel_events_parse_with_their_documented_defaults() {
        let s = Scenario::parse("x.toml", &format!("{OK}{EVENTS}")).expect("valid");
        let e = &s.accel_events;
        assert_eq!(e.len(), 4);
        assert_eq!(e[0].kind, AccelEventKind::HalfSine);
        assert_eq!(e[0].sensor, EventSensor::All, "default: all");
        assert_eq!((e[0].peak_g, e[0].duration_ms), (Some(7.5), Some(4.0)));
        assert_eq!((e[0].rms_g, e[0].end_s), (None, None));
        assert_eq!(e[1].kind, AccelEventKind::Spike);
        assert_eq!(e[1].sensor, EventSensor::Crash);
        assert_eq!(e[2].kind, AccelEventKind::RoughRoad);
        assert_eq!((e[2].rms_g, e[2].end_s), (Some(2.0), Some(2.5)));
        assert_eq!(e[3].kind, AccelEventKind::Offset);
        assert_eq!(e[3].sensor, EventSensor::Safing);
        assert!(EventSensor::All.reaches(AccelSensor::Safing));
        assert!(!EventSensor::Crash.reaches(AccelSensor::Safing));
        // The same as inline tables; 0 g is allowed for every kind.
        let inline = "accel_event = [{ kind = \"spike\", start_s = 0.5, peak_g = 0 }]\n";
        let s = Scenario::parse("x.toml", &format!("{inline}{OK}")).expect("valid");
        assert_eq!(s.accel_events[0].peak_g, Some(0.0));
    }

    #[test]
    fn a_ringing_event_takes_its_keys_and_rejects_the_others() {
        let ok = "[[accel_event]]\nkind = \"ringing\"\nstart_s = 0.5\npeak_g = 30\nduration_ms = 20\nfrequency_hz = 4000\n";
        let s = Scenario::parse("x.toml", &format!("{OK}{ok}")).expect("valid");
        let e = s.accel_events[0];
        assert_eq!(e.kind, AccelEventKind::Ringing);
        assert_eq!(
            (e.frequency_hz, e.net_dv_mps, e.phase_deg),
            (Some(4000.0), None, None)
        );
        let full = format!("{ok}net_dv_mps = 0.3\nphase_deg = 90\n");
        let s = Scenario::parse("x.toml", &format!("{OK}{full}")).expect("valid");
        assert_eq!(s.accel_events[0].net_dv_mps, Some(0.3));
        for (text, field) in [
            (
                ok.replace("frequency_hz = 4000\n", ""),
                "accel_event[0].frequency_hz",
            ),
            (format!("{ok}rms_g = 1\n"), "accel_event[0].rms_g"),
            (ok.replace("4000", "0.5"), "accel_event[0].frequency_hz"),
            (
                format!("{ok}net_dv_mps = 30\n"),
                "accel_event[0].net_dv_mps",
            ),
            (
                EVENTS.replacen(
                    "duration_ms = 4.0\n",
                    "duration_ms = 4.0\nnet_dv_mps = 0.2\n",
                    1,
                ),
                "accel_event[0].net_dv_mps",
            ),
        ] {
            let err = Scenario::parse("x.toml", &format!("{OK}{text}"))
                .expect_err(field)
                .to_string();
            assert!(err.contains(field), "{field}: {err}");
        }
    }

    #[test]
    fn accel_event_keys_are_checked_per_kind_with_their_line() {
        // (what to change in EVENTS, the line it points at, the error after the location)
        let cases: &[(&str, &str, &str, &str)] = &[
            // A required key that is missing points at its entry's header.
            (
                "peak_g = 7.5\nduration_ms = 4.0\n",
                "peak_g = 7.5\n",
                "[[accel_event]]",
                "field `accel_event[0].duration_ms`: required for kind = \"half_sine\"",
            ),
            (
                "rms_g = 2.0\n",
                "peak_g = 2.0\n",
                "peak_g = 2.0",
                "field `accel_event[2].peak_g`: not used by kind = \"rough_road\": remove this key",
            ),
            (
                "peak_g = 40\n",
                "peak_g = 40\nduration_ms = 3\n",
                "duration_ms = 3",
                "field `accel_event[1].duration_ms`: not used by kind = \"spike\": remove this key",
            ),
            (
                "peak_g = 40\n",
                "peak_g = 40\nend_s = 3\n",
                "end_s = 3",
                "field `accel_event[1].end_s`: not used by kind = \"spike\": remove this key",
            ),
            (
                "peak_g = 7.5\n",
                "peak_g = 7.5\nrms_g = 1\n",
                "rms_g = 1",
                "field `accel_event[0].rms_g`: not used by kind = \"half_sine\": remove this key",
            ),
            (
                "end_s = 2.0\n",
                "\n",
                "kind = \"offset\"",
                "field `accel_event[3].end_s`: required for kind = \"offset\"",
            ),
            (
                "rms_g = 2.0\n",
                "\n",
                "kind = \"rough_road\"",
                "field `accel_event[2].rms_g`: required for kind = \"rough_road\"",
            ),
            (
                "start_s = 1.80\n",
                "start_s = 3.5\n",
                "start_s = 3.5",
                "field `accel_event[0].start_s`: 3.5 is outside 0..=3 s (the run)",
            ),
            (
                "start_s = 0.5\n",
                "start_s = -0.1\n",
                "start_s = -0.1",
                "field `accel_event[1].start_s`: -0.1 is outside 0..=3 s (the run)",
            ),
            (
                "end_s = 2.5\n",
                "end_s = 0.2\n",
                "end_s = 0.2",
                "field `accel_event[2].end_s`: 0.2 s must be after start_s = 0.2 s",
            ),
            (
                "peak_g = 7.5\n",
                "peak_g = 250\n",
                "peak_g = 250",
                "field `accel_event[0].peak_g`: 250 is outside -200..=200 g",
            ),
            (
                "duration_ms = 4.0\n",
                "duration_ms = 0.05\n",
                "duration_ms = 0.05",
                "field `accel_event[0].duration_ms`: 0.05 is outside 0.1..=200 ms",
            ),
            (
                "duration_ms = 4.0\n",
                "duration_ms = 201\n",
                "duration_ms = 201",
                "field `accel_event[0].duration_ms`: 201 is outside 0.1..=200 ms",
            ),
            (
                "rms_g = 2.0\n",
                "rms_g = 25\n",
                "rms_g = 25",
                "field `accel_event[2].rms_g`: 25 is outside 0..=20 g",
            ),
            (
                "rms_g = 2.0\n",
                "rms_g = -1\n",
                "rms_g = -1",
                "field `accel_event[2].rms_g`: -1 is outside 0..=20 g",
            ),
        ];
        for (from, to, needle, want) in cases {
            assert!(EVENTS.contains(from), "{from}");
            let events = EVENTS.replacen(from, to, 1);
            let (text, _) = with(&events, "");
            // The line: of the changed key, or of the entry's header for a missing key.
            let entry = want
                .split("accel_event[")
                .nth(1)
                .and_then(|x| x.split(']').next())
                .and_then(|x| x.parse::<usize>().ok())
                .expect("entry");
            let line = if *needle == "[[accel_event]]" || want.contains("required") {
                text.lines()
                    .enumerate()
                    .filter(|(_, l)| l.trim() == "[[accel_event]]")
                    .nth(entry)
                    .map(|(i, _)| i + 1)
            } else {
                text.lines().position(|l| l.contains(needle)).map(|i| i + 1)
            };
            let e = Scenario::parse("x.toml", &text).unwrap_err();
            let line = line.expect("line");
            assert_eq!(
                e.to_string(),
                format!("x.toml:{line}: {want}"),
                "{from} -> {to}"
            );
        }
    }

    #[test]
    fn accel_event_syntax_errors_name_file_line_column_and_field() {
        // Unknown key, unknown kind, unknown sensor, wrong type: toml's own errors, with the
        // column, located in the entry.
        let cases = [
            (
                "duration_ms = 4.0\n",
                "duration_ms = 4.0\nwidth_ms = 2\n",
                "width_ms = 2",
                1,
                "accel_event[0].width_ms",
                "unknown field `width_ms`",
            ),
            (
                "kind = \"spike\"",
                "kind = \"spikes\"",
                "\"spikes\"",
                8,
                "accel_event[1].kind",
                "unknown variant `spikes`",
            ),
            (
                "sensor = \"safing\"",
                "sensor = \"both\"",
                "\"both\"",
                10,
                "accel_event[3].sensor",
                "unknown variant `both`",
            ),
            (
                "peak_g = 40\n",
                "peak_g = \"forty\"\n",
                "\"forty\"",
                10,
                "accel_event[1].peak_g",
                "invalid type",
            ),
        ];
        for (from, to, needle, column, field, msg) in cases {
            let (text, line) = with(&EVENTS.replacen(from, to, 1), needle);
            let e = Scenario::parse("x.toml", &text).unwrap_err();
            assert_eq!((e.line, e.column), (line, Some(column)), "{e}");
            assert_eq!(e.field.as_deref(), Some(field), "{e}");
            assert!(e.message.contains(msg), "{e}");
            assert!(
                e.to_string().starts_with(&format!(
                    "x.toml:{}:{column}: field `{field}`: ",
                    line.unwrap()
                )),
                "{e}"
            );
        }
        // A misspelt table name is an unknown top-level key.
        let e = Scenario::parse(
            "x.toml",
            &format!("{OK}[[accel_events]]\nkind = \"spike\"\n"),
        )
        .unwrap_err();
        assert_eq!(e.field.as_deref(), Some("accel_events[0]"), "{e}");
        assert!(e.message.contains("unknown field `accel_events`"), "{e}");
    }
}
