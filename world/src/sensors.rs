//! The sensor model: what the ECU's sensors report about the true world (noise, bias, latency,
//! range), as bench payloads and CAN frames. Pure and seeded (ChaCha8), so a run is reproducible
//! and testable without a clock.
//!
//! Two acceleration sensors measure the same true compartment acceleration independently: the
//! crash accelerometer (`accel_*` keys; its noise comes from the scenario's main stream, shared
//! with the object list, as it always has) and the safing accelerometer (`safing_*` keys; its
//! own stream [`SAFING_STREAM`], so adding it changed no other draw). Both see the scenario's
//! `[[accel_event]]` entries that reach them ([`crate::events`]).

use crate::events::AccelEvents;
use crate::lowpass::AntiAlias;
use crate::scenario::{AccelSensor, BrakeStateName, FrontSide, Scenario};
use crate::truth::Truth;
use bus::codec::V2xOpponentMassStationStatus;
use bus::codec::{
    EgoVehicleStateBrakeState, OccupantClassificationBeltBuckle,
    OccupantClassificationOccupantClass,
};
use bus::{EgoVehicleState, EncodeError, OccupantClassification, V2xOpponentMass};
use rand::SeedableRng;

use crate::noise::gauss;
use rand_chacha::ChaCha8Rng;
use signals::ObjectState;

/// Tracker id of the opponent (one tracked object).
pub const OPPONENT_OBJECT_ID: u32 = 7;

/// ChaCha8 stream of the safing accelerometer's noise (same key — the scenario's `seed` — as
/// the main stream 0, which the object list and the crash accelerometer draw from).
pub const SAFING_STREAM: u64 = 1;

/// ChaCha8 stream of the V2X receiver's GNSS noise (`[v2x]`; its own, so a scenario with and
/// without `[v2x]` draws the same object-list and accelerometer noise).
pub const V2X_STREAM: u64 = 2;

/// ChaCha8 streams of the left and the right satellite's noise (their own, so a car with and
/// without satellites draws the same noise for every other sensor).
pub const SATELLITE_STREAMS: [u64; 2] = [3, 4];

/// Seeded sensor model over a solved [`Truth`].
pub struct SensorModelSim {
    truth: Truth,
    rng: ChaCha8Rng,
    safing_rng: ChaCha8Rng,
    v2x_rng: ChaCha8Rng,
    satellite_rngs: [ChaCha8Rng; 2],
    events: AccelEvents,
    /// The anti-alias filters of the crash and the safing accelerometer and of the left and
    /// the right satellite.
    lowpass: [AntiAlias; 4],
    object_sequence: u64,
}

impl SensorModelSim {
    /// Model over `truth`, seeded with the scenario's seed.
    pub fn new(truth: Truth) -> Self {
        let seed = truth.scenario().seed;
        let mut safing_rng = ChaCha8Rng::seed_from_u64(seed);
        safing_rng.set_stream(SAFING_STREAM);
        let mut v2x_rng = ChaCha8Rng::seed_from_u64(seed);
        v2x_rng.set_stream(V2X_STREAM);
        let satellite_rngs = SATELLITE_STREAMS.map(|stream| {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            rng.set_stream(stream);
            rng
        });
        let sensor = &truth.scenario().sensor;
        let lowpass = [
            AccelSensor::Crash,
            AccelSensor::Safing,
            AccelSensor::SatelliteLeft,
            AccelSensor::SatelliteRight,
        ]
        .map(|s| AntiAlias::new(sensor.lowpass_hz(s)));
        SensorModelSim {
            v2x_rng,
            satellite_rngs,
            events: AccelEvents::new(truth.scenario()),
            lowpass,
            truth,
            rng: ChaCha8Rng::seed_from_u64(seed),
            safing_rng,
            object_sequence: 0,
        }
    }

    /// The scenario's acceleration events.
    pub fn events(&self) -> &AccelEvents {
        &self.events
    }

    /// The true world.
    pub fn truth(&self) -> &Truth {
        &self.truth
    }

    fn scenario(&self) -> &Scenario {
        self.truth.scenario()
    }

    /// The object list entry published at scenario time `t_s`, measured at
    /// `t_s − latency` (`None` before the first measurement exists). `timestamp_ns` is left 0:
    /// the caller maps the measurement time [`Self::measurement_time_s`] onto CLOCK_MONOTONIC.
    pub fn object(&mut self, t_s: f64) -> Option<ObjectState> {
        let s = self.scenario().sensor.clone();
        let t_meas = self.measurement_time_s(t_s)?;
        let w = self.truth.state(t_meas);
        self.object_sequence += 1;
        let mut o = ObjectState::INVALID;
        o.sequence = self.object_sequence;
        o.object_id = OPPONENT_OBJECT_ID;
        if w.distance_m > s.range_m || !w.in_path {
            // Nothing in range: an explicit "no valid object" record keeps the stream alive.
            return Some(o);
        }
        let true_mass = self.scenario().opponent_mass_kg();
        let mass = s.mass_estimate_kg.unwrap_or(true_mass + s.mass_bias_kg)
            + s.mass_noise_kg * gauss(&mut self.rng);
        o.distance_m = (w.distance_m + s.distance_noise_m * gauss(&mut self.rng)).max(0.0) as f32;
        o.closing_speed_mps = (w.closing_speed_mps
            + s.speed_bias_mps
            + s.speed_noise_mps * gauss(&mut self.rng)) as f32;
        // Drawn only when configured: files without the key keep their noise streams.
        let accel_noise = if s.relative_accel_noise_mps2 > 0.0 {
            s.relative_accel_noise_mps2 * gauss(&mut self.rng)
        } else {
            0.0
        };
        o.relative_accel_mps2 = (w.relative_accel_mps2 + accel_noise) as f32;
        o.opponent_mass_kg = mass.max(1.0) as f32;
        o.opponent_mass_sigma_kg = s.mass_sigma_kg as f32;
        o.confidence = s.confidence as f32;
        o.valid = signals::VALID;
        Some(o)
    }

    /// Measurement time of a record published at `t_s` (`None` if before scenario start).
    pub fn measurement_time_s(&self, t_s: f64) -> Option<f64> {
        let t = t_s - self.scenario().sensor.latency_ms * 1e-3;
        (t >= 0.0).then_some(t)
    }

    /// Compartment (crash) accelerometer reading at `t_s` [m/s²]: braking deceleration before
    /// contact, the TRUE crash pulse after it, the additive `[[accel_event]]`s it sees, plus
    /// sensor noise, clipped to the measuring range.
    pub fn accel_mps2(&mut self, t_s: f64) -> f64 {
        self.reading_mps2(AccelSensor::Crash, t_s)
    }

    /// Safing accelerometer reading at `t_s` [m/s²]: the same true acceleration and mechanical
    /// events as the crash accelerometer, its own events, noise (own stream) and range.
    pub fn safing_mps2(&mut self, t_s: f64) -> f64 {
        self.reading_mps2(AccelSensor::Safing, t_s)
    }

    /// `sensor`'s reading at `t_s` [m/s²] (one noise draw from its stream per call): the
    /// true acceleration and the events it sees, through the sensor's anti-alias low-pass
    /// ([`crate::lowpass`], stepped from this sensor's previous reading), plus the sensor's
    /// noise, clipped to its range. Readings of one sensor come in time order (an earlier one
    /// restarts its filter, as a restarted feed does).
    pub fn reading_mps2(&mut self, sensor: AccelSensor, t_s: f64) -> f64 {
        let (_, noise_sd, full_scale_g) = self.truth.scenario().sensor.accel_params(sensor);
        let [lp_crash, lp_safing, lp_left, lp_right] = &mut self.lowpass;
        let [rng_left, rng_right] = &mut self.satellite_rngs;
        let (rng, filter) = match sensor {
            AccelSensor::Crash => (&mut self.rng, lp_crash),
            AccelSensor::Safing => (&mut self.safing_rng, lp_safing),
            AccelSensor::SatelliteLeft => (rng_left, lp_left),
            AccelSensor::SatelliteRight => (rng_right, lp_right),
        };
        let full_scale = full_scale_g * physics::defaults::STANDARD_GRAVITY_MPS2;
        let noise = noise_sd * gauss(rng);
        let (truth, events) = (&self.truth, &self.events);
        let side = match sensor {
            AccelSensor::SatelliteLeft => Some(FrontSide::Left),
            AccelSensor::SatelliteRight => Some(FrontSide::Right),
            AccelSensor::Crash | AccelSensor::Safing => None,
        };
        let input = |t: f64| {
            let a = match side {
                Some(side) => truth.satellite_accel_mps2(side, t),
                None => truth.ego_accel_mps2(t),
            };
            // Only when an event is active: otherwise the sum is the one it always was.
            match events.added_mps2(sensor, t) {
                Some(e) => a + e,
                None => a,
            }
        };
        // The longest span this reading integrates: a quiet one (no acceleration, no event)
        // leaves a settled filter as it is; else what the input holds over it sets the step
        // and whether it is linear over the substeps.
        let from_s = t_s - crate::lowpass::RESTART_GAP_S;
        let quiet = truth.at_rest_over(from_s, t_s) && events.quiet_over(sensor, from_s, t_s);
        let a = match quiet.then(|| filter.read_settled(t_s, 0.0)).flatten() {
            Some(a) => a,
            None => match events.substeps(sensor, from_s, t_s) {
                s if s.linear => filter.read_linear(t_s, s.max_step_s, truth.contact_s, input),
                s => filter.read(t_s, s.max_step_s, input),
            },
        };
        (a + noise).clamp(-full_scale, full_scale)
    }

    /// The reading a spike `[[accel_event]]` forces on `sensor`'s sample at `t_s` (samples
    /// `dt_s` apart), clipped to the sensor's measuring range; `None`: no spike there.
    pub fn spike_mps2(&self, sensor: AccelSensor, t_s: f64, dt_s: f64) -> Option<f64> {
        let (_, _, full_scale_g) = self.truth.scenario().sensor.accel_params(sensor);
        let full_scale = full_scale_g * physics::defaults::STANDARD_GRAVITY_MPS2;
        self.events
            .spike_mps2(sensor, t_s, dt_s)
            .map(|v| v.clamp(-full_scale, full_scale))
    }

    /// The `EgoVehicleState` frame content at `t_s` (E2E bytes are filled by the protector).
    pub fn ego_frame(&self, t_s: f64) -> Result<EgoVehicleState, EncodeError> {
        let w = self.truth.state(t_s);
        let brake = if w.ego_braking {
            match self.scenario().ego.braking.as_ref().map(|b| b.state) {
                Some(BrakeStateName::Abs) => EgoVehicleStateBrakeState::AbsActive,
                Some(BrakeStateName::Eba) => EgoVehicleStateBrakeState::EmergencyBrakeAssist,
                Some(BrakeStateName::Aeb) => EgoVehicleStateBrakeState::AutonomousEmergencyBraking,
                _ => EgoVehicleStateBrakeState::DriverBraking,
            }
        } else {
            EgoVehicleStateBrakeState::Released
        };
        // The DBC's EgoSpeed is a non-negative speed over ground and EgoLongAccel is limited
        // to ±150 m/s²: a crash pulse beyond that is clipped on this (vehicle-dynamics) frame,
        // the crash accelerometer carries the full pulse.
        EgoVehicleState::encode(
            brake,
            w.ego_speed_mps.clamp(0.0, 100.0) as f32,
            w.ego_accel_mps2.clamp(-150.0, 150.0) as f32,
        )
    }

    /// The `V2xOpponentMass` frame content at `t_s` (`None`: the scenario has no `[v2x]`):
    /// the station's position and speed `latency_ms` old, with GNSS noise; `NoStation` when
    /// the opponent does not transmit (not equipped, a barrier), is out of reception range or
    /// has left the ego's path. The reported mass is the station's own (true, load included)
    /// unless `[v2x] mass_kg` says otherwise.
    pub fn v2x_frame(&mut self, t_s: f64) -> Option<Result<V2xOpponentMass, EncodeError>> {
        let v = self.scenario().v2x.clone()?;
        let w = self.truth.state((t_s - v.latency_ms * 1e-3).max(0.0));
        let true_mass = self.scenario().opponent_mass_kg();
        let station =
            v.opponent_equipped && true_mass.is_finite() && w.in_path && w.distance_m <= v.range_m;
        if !station {
            return Some(V2xOpponentMass::encode(
                V2xOpponentMassStationStatus::NoStation,
                0.0,
                0.0,
                0.0,
                0.0,
            ));
        }
        let range = w.distance_m + v.distance_noise_m * gauss(&mut self.v2x_rng);
        let closing = w.closing_speed_mps + v.speed_noise_mps * gauss(&mut self.v2x_rng);
        Some(V2xOpponentMass::encode(
            V2xOpponentMassStationStatus::Valid,
            v.mass_kg.unwrap_or(true_mass).clamp(0.0, 40_000.0) as f32,
            v.mass_sigma_kg.clamp(0.0, 2550.0) as f32,
            range.clamp(0.0, 400.0) as f32,
            closing.clamp(-100.0, 100.0) as f32,
        ))
    }

    /// The `OccupantClassification` frame content (the occupant does not change in a run).
    pub fn occupant_frame(&self) -> Result<OccupantClassification, EncodeError> {
        let occ = &self.scenario().occupant;
        let buckle = if occ.belted {
            OccupantClassificationBeltBuckle::Buckled
        } else {
            OccupantClassificationBeltBuckle::Unbuckled
        };
        OccupantClassification::encode(
            buckle,
            occupant_class(occ.mass_kg),
            95,
            occ.mass_kg as f32,
            occ.chest_to_wheel_mm.round() as u16,
            occ.seat_track_mm.round() as u16,
        )
    }
}

/// Size class the occupant classifier reports for a mass (thresholds: 5th-percentile female
/// ≈ 50 kg, 95th-percentile male ≈ 100 kg; SmallAdult < 55 kg ≤ MidAdult ≤ 90 kg < LargeAdult).
pub fn occupant_class(mass_kg: f64) -> OccupantClassificationOccupantClass {
    if mass_kg < 55.0 {
        OccupantClassificationOccupantClass::SmallAdult
    } else if mass_kg <= 90.0 {
        OccupantClassificationOccupantClass::MidAdult
    } else {
        OccupantClassificationOccupantClass::LargeAdult
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sim(extra_sensor: &str) -> SensorModelSim {
        sim_with(extra_sensor, "")
    }

    /// The scenario of [`sim`] with `tables` appended (e.g. a `[v2x]` table).
    fn sim_with(extra_sensor: &str, tables: &str) -> SensorModelSim {
        let text = format!(
            "name = \"t\"\nduration_s = 3\nseed = 42\n[ego]\nmass_kg = 1785\nspeed_kph = 36\n\
             [opponent]\nkind = \"vehicle\"\nmass_kg = 1500\nspeed_kph = 36\ninitial_distance_m = 40\n\
             [sensor]\n{extra_sensor}\n[occupant]\nmass_kg = 110\nbelted = false\n{tables}"
        );
        let s = Scenario::parse("t.toml", &text).expect("valid");
        SensorModelSim::new(Truth::new(&s).expect("truth"))
    }

    #[test]
    fn noise_free_object_is_the_delayed_truth() {
        let mut m = sim("latency_ms = 50\ndistance_noise_m = 0\nspeed_noise_mps = 0\nmass_bias_kg = 300\nmass_sigma_kg = 250");
        assert!(
            m.object(0.04).is_none(),
            "no measurement before t = latency"
        );
        let o = m.object(1.05).expect("object");
        // Measured at 1.0 s: 40 − 2·10 m/s·1 s = 20 m, closing 20 m/s.
        assert!((o.distance_m - 20.0).abs() < 1e-4, "{o:?}");
        assert!((o.closing_speed_mps - 20.0).abs() < 1e-4);
        assert_eq!(o.opponent_mass_kg, 1800.0);
        assert_eq!(o.opponent_mass_sigma_kg, 250.0);
        assert!(o.is_valid());
        assert_eq!(o.sequence, 1);
    }

    #[test]
    fn noise_has_the_configured_spread_and_is_reproducible() {
        let mut a = sim("latency_ms = 0\ndistance_noise_m = 0.5\nmass_noise_kg = 100");
        let mut b = sim("latency_ms = 0\ndistance_noise_m = 0.5\nmass_noise_kg = 100");
        let n = 4000;
        let (mut sum, mut sum2) = (0.0, 0.0);
        for _ in 0..n {
            let x = a.object(0.5).unwrap();
            let y = b.object(0.5).unwrap();
            assert_eq!(x, y, "same seed, same stream");
            let e = x.opponent_mass_kg as f64 - 1500.0;
            sum += e;
            sum2 += e * e;
        }
        let mean = sum / n as f64;
        let sd = (sum2 / n as f64 - mean * mean).sqrt();
        // Sample sd of 4000 normal draws: within ±6 % of σ = 100 kg (≈ 4 standard errors).
        assert!((sd - 100.0).abs() < 6.0, "sd {sd}");
        assert!(mean.abs() < 7.0, "mean {mean}");
    }

    #[test]
    fn relative_accel_noise_is_drawn_only_when_configured() {
        // Without the key the other fields' noise is what it was (same draws); with it the
        // acceleration scatters around the truth (0 here: constant speeds) with its σ.
        let mut a = sim("latency_ms = 0\ndistance_noise_m = 0.5");
        let mut b = sim("latency_ms = 0\ndistance_noise_m = 0.5\nrelative_accel_noise_mps2 = 0");
        let mut c = sim("latency_ms = 0\ndistance_noise_m = 0.5\nrelative_accel_noise_mps2 = 2");
        let n = 4000;
        let mut sum2 = 0.0;
        for _ in 0..n {
            let (x, y, z) = (
                a.object(0.5).unwrap(),
                b.object(0.5).unwrap(),
                c.object(0.5).unwrap(),
            );
            assert_eq!(x, y);
            assert_eq!(x.relative_accel_mps2, 0.0);
            sum2 += f64::from(z.relative_accel_mps2).powi(2);
        }
        let sd = (sum2 / f64::from(n)).sqrt();
        assert!((sd - 2.0).abs() < 0.12, "sd {sd}");
    }

    #[test]
    fn out_of_range_reports_no_valid_object() {
        let mut m = sim("latency_ms = 0\nrange_m = 10");
        let o = m.object(0.0).unwrap();
        assert!(!o.is_valid());
    }

    #[test]
    fn occupant_frame_carries_the_occupant() {
        let m = sim("");
        let f = m.occupant_frame().unwrap();
        assert!((f.occupant_mass() - 110.0).abs() < 0.051);
        assert_eq!(f.chest_to_wheel(), 300);
        assert_eq!(
            u8::from(f.belt_buckle()),
            u8::from(OccupantClassificationBeltBuckle::Unbuckled)
        );
        assert_eq!(
            u8::from(f.occupant_class()),
            u8::from(OccupantClassificationOccupantClass::LargeAdult)
        );
    }

    #[test]
    fn ego_frame_before_contact_is_speed_and_no_braking() {
        let m = sim("");
        let f = m.ego_frame(0.5).unwrap();
        assert!((f.ego_speed() - 10.0).abs() < 0.006);
        assert_eq!(
            u8::from(f.brake_state()),
            u8::from(EgoVehicleStateBrakeState::Released)
        );
    }

    /// The scenario of [`sim`] (a noisy mass estimate) with a `[v2x]` table (`v2x` = its keys).
    fn sim_v2x(v2x: &str) -> SensorModelSim {
        sim_with("mass_noise_kg = 50", &format!("[v2x]\n{v2x}\n"))
    }

    #[test]
    fn v2x_reports_the_true_mass_and_the_delayed_gnss_range() {
        let mut m = sim_v2x("latency_ms = 100\ndistance_noise_m = 0\nspeed_noise_mps = 0");
        let f = m.v2x_frame(1.1).expect("[v2x]").expect("in range");
        assert_eq!(f.station_status(), V2xOpponentMassStationStatus::Valid);
        assert_eq!(f.opponent_mass(), 1500);
        assert_eq!(f.mass_sigma(), 100);
        // Position of 1.0 s: 40 − 2·10 m/s·1 s = 20 m, closing 20 m/s (DBC steps 0.1 m, 0.05 m/s).
        assert!(
            (f.station_range() - 20.0).abs() < 0.051,
            "{}",
            f.station_range()
        );
        assert!(
            (f.closing_speed() - 20.0).abs() < 0.026,
            "{}",
            f.closing_speed()
        );
        // A forged or misconfigured station: the mass it says.
        let mut forged = sim_v2x("mass_kg = 700");
        let f = forged.v2x_frame(1.1).expect("[v2x]").expect("in range");
        assert_eq!(f.opponent_mass(), 700);
        // Not equipped, out of reception range: the module says no station.
        for keys in ["opponent_equipped = false", "range_m = 10"] {
            let f = sim_v2x(keys)
                .v2x_frame(0.2)
                .expect("[v2x]")
                .expect("in range");
            assert_eq!(
                f.station_status(),
                V2xOpponentMassStationStatus::NoStation,
                "{keys}"
            );
        }
        // No `[v2x]`: no frame at all.
        assert!(sim("").v2x_frame(1.0).is_none());
    }

    #[test]
    fn v2x_noise_has_its_own_stream() {
        // The object list's noise is the same with and without `[v2x]`, however many V2X
        // frames are drawn in between.
        let mut with = sim_v2x("distance_noise_m = 2");
        let mut without = sim("mass_noise_kg = 50");
        let mut ranges = Vec::new();
        for k in 0..20 {
            let t = 0.1 + 0.05 * f64::from(k);
            let f = with.v2x_frame(t).expect("[v2x]").expect("in range");
            ranges.push(f.station_range());
            assert_eq!(with.object(t), without.object(t), "t = {t}");
        }
        // ... and the V2X range is noisy (σ 2 m), not the truth repeated.
        assert!(ranges.windows(2).any(|w| w[0] != w[1]));
    }
}
