//! What the feeds publish, tick by tick, without a clock: the object list (period, latency,
//! dropouts, stuck windows), the crash and the safing accelerometer, each in batches of ≤ 8
//! samples with its own sequence (dropouts, fault windows, spikes), the two crush-zone
//! satellites' PSI5 frames (the same sensor model, quantised to data codes with parity, each
//! frame one sync slot after its sample) and the E2E-sealed CAN frames. The `sensor-feeds` binary sleeps to each tick and publishes what [`Player::tick`]
//! produced; the offline bench (`e2e-tests`' `offline-bench`) hands the same records to the ECU
//! core under a simulated clock, so both run one model of the sensors.

use bus::{E2eProtector, RawFrame};
use ipc::{CrashAccelSample, ObjectState, SatelliteFrames, ACCEL_BATCH_CAPACITY};
use signals::psi5;
use world::scenario::{AccelFaultKind, AccelSensor, DropoutTarget, SensorModel};
use world::sensors::SensorModelSim;
use world::truth::Truth;

/// The feed grid: one tick per ms of scenario time.
pub const TICK_NS: u64 = 1_000_000;

/// Everything one tick publishes (reused: [`Player::tick`] clears it first).
#[derive(Clone, Debug, Default)]
pub struct TickOutput {
    /// Object-list records (iceoryx2 `ObjectState`).
    pub objects: Vec<ObjectState>,
    /// Crash accelerometer batches (iceoryx2 `CrashAccelSample`, `ServiceNames::crash_accel`).
    pub accel: Vec<CrashAccelSample>,
    /// Safing accelerometer batches (iceoryx2 `CrashAccelSample`,
    /// `ServiceNames::safing_accel`).
    pub safing: Vec<CrashAccelSample>,
    /// The left and the right satellite's PSI5 frames (iceoryx2 `SatelliteFrames`,
    /// `ServiceNames::satellites`); empty for a car without satellites.
    pub satellites: [Vec<SatelliteFrames>; 2],
    /// E2E-sealed `EgoVehicleState` / `OccupantClassification` frames.
    pub can: Vec<RawFrame>,
}

/// Counts of what was produced (the binary's closing line).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PlayCounts {
    /// Object records produced.
    pub objects: u64,
    /// Object records lost in a dropout window.
    pub objects_dropped: u64,
    /// Object records repeated unchanged by a stuck sensor.
    pub objects_frozen: u64,
    /// Crash accelerometer samples produced.
    pub accel_samples: u64,
    /// Crash accelerometer samples altered by a fault window (`accel_faults`).
    pub accel_faulty: u64,
    /// Safing accelerometer samples produced.
    pub safing_samples: u64,
    /// Safing accelerometer samples altered by a fault window (`accel_faults`, `sensor =
    /// "safing"`).
    pub safing_faulty: u64,
    /// Satellite frames produced (both satellites).
    pub satellite_frames: u64,
    /// Samples (of any sensor) replaced by a spike `[[accel_event]]`.
    pub spikes: u64,
    /// CAN frames produced.
    pub can_frames: u64,
}

/// One acceleration sensor's feed state.
struct AccelChannel {
    sensor: AccelSensor,
    /// Sample period [s of scenario time].
    dt_s: f64,
    /// How long after its instant a sample is delivered [s] (a satellite's one PSI5 slot).
    latency_s: f64,
    /// Measuring range [m/s²] (what a saturated sensor reads, negated).
    full_scale_mps2: f64,
    /// Index of the next sample (instant `k · dt_s`).
    next_k: u64,
    /// The last reading outside a fault window (what a stuck sensor keeps repeating).
    last: f32,
    /// Batch sequence counter.
    seq: u64,
    /// Samples produced.
    samples: u64,
    /// Samples altered by a fault window.
    faulty: u64,
}

impl AccelChannel {
    fn new(sensor: AccelSensor, model: &SensorModel, t0_s: f64) -> Self {
        let (rate_hz, _, full_scale_g) = model.accel_params(sensor);
        let dt_s = 1.0 / rate_hz;
        AccelChannel {
            sensor,
            dt_s,
            latency_s: if sensor.is_satellite() { dt_s } else { 0.0 },
            full_scale_mps2: full_scale_g * physics::defaults::STANDARD_GRAVITY_MPS2,
            next_k: (t0_s / dt_s - 1e-9).ceil().max(0.0) as u64,
            last: 0.0,
            seq: 0,
            samples: 0,
            faulty: 0,
        }
    }
}

/// Scenario time → CLOCK_MONOTONIC.
#[derive(Clone, Copy)]
struct TimeBase {
    start_ns: u64,
    /// Real time per scenario time (1 / speed-up).
    scale: f64,
}

impl TimeBase {
    fn to_ns(self, t_s: f64) -> u64 {
        self.start_ns + (t_s * 1e9 * self.scale).round() as u64
    }
}

/// The tick-by-tick sensor feeds of one scenario run.
pub struct Player {
    model: SensorModelSim,
    sensor: SensorModel,
    time: TimeBase,
    next_obj_s: f64,
    next_veh_s: f64,
    next_occ_s: f64,
    /// The V2X frame's period, ms (`None`: the scenario has no `[v2x]`).
    v2x_period_ms: Option<f64>,
    next_v2x_s: f64,
    last_object: Option<ObjectState>,
    crash: AccelChannel,
    safing: AccelChannel,
    /// The left and the right satellite (`None`: the car has none).
    satellites: Option<[AccelChannel; 2]>,
    /// Scratch for a satellite's readings before they become PSI5 frames.
    satellite_readings: Vec<CrashAccelSample>,
    protector: E2eProtector,
    counts: PlayCounts,
}

impl Player {
    /// Feeds of `truth`'s scenario on a time base that maps scenario time t to
    /// `start_ns + t·1e9·scale` ns, starting at `first_tick` (> 0: a restarted feed resuming on
    /// its first run's time base; the ticks already past are skipped, as if silent).
    pub fn new(truth: Truth, start_ns: u64, scale: f64, first_tick: u64) -> Self {
        let sensor = truth.scenario().sensor.clone();
        let t0_s = first_tick as f64 * 1e-3;
        // First instant of each feed at or after t0 (all 0 on a fresh start).
        let first_at = |period_s: f64| (t0_s / period_s - 1e-9).ceil().max(0.0) * period_s;
        let v2x_period_ms = truth.scenario().v2x.as_ref().map(|v| v.period_ms);
        Player {
            v2x_period_ms,
            next_v2x_s: v2x_period_ms.map_or(0.0, |p| first_at(p * 1e-3)),
            next_obj_s: first_at(sensor.object_period_ms * 1e-3),
            next_veh_s: first_at(sensor.vehicle_period_ms * 1e-3),
            next_occ_s: first_at(sensor.occupant_period_ms * 1e-3),
            crash: AccelChannel::new(AccelSensor::Crash, &sensor, t0_s),
            safing: AccelChannel::new(AccelSensor::Safing, &sensor, t0_s),
            satellites: sensor
                .satellites
                .then(|| AccelSensor::SATELLITES.map(|s| AccelChannel::new(s, &sensor, t0_s))),
            satellite_readings: Vec::new(),
            model: SensorModelSim::new(truth),
            sensor,
            time: TimeBase { start_ns, scale },
            last_object: None,
            protector: E2eProtector::new(),
            counts: PlayCounts::default(),
        }
    }

    /// The sensor model (and through it the true world).
    pub fn model(&self) -> &SensorModelSim {
        &self.model
    }

    /// What was produced so far.
    pub fn counts(&self) -> PlayCounts {
        PlayCounts {
            accel_samples: self.crash.samples,
            accel_faulty: self.crash.faulty,
            safing_samples: self.safing.samples,
            safing_faulty: self.safing.faulty,
            satellite_frames: self
                .satellites
                .as_ref()
                .map_or(0, |chs| chs.iter().map(|c| c.samples).sum()),
            ..self.counts
        }
    }

    /// CLOCK_MONOTONIC time of scenario time `t_s`.
    pub fn to_ns(&self, t_s: f64) -> u64 {
        self.time.to_ns(t_s)
    }

    /// Everything due at tick `tick` (scenario time `tick` ms) into `out`.
    ///
    /// # Errors
    /// A CAN frame value outside its DBC range (a model bug).
    pub fn tick(&mut self, tick: u64, out: &mut TickOutput) -> Result<(), bus::EncodeError> {
        out.objects.clear();
        out.accel.clear();
        out.safing.clear();
        out.satellites.iter_mut().for_each(Vec::clear);
        out.can.clear();
        let t = tick as f64 * 1e-3;
        self.objects(t, out);
        let feed = Feed {
            model: &mut self.model,
            sensor: &self.sensor,
            time: self.time,
            spikes: &mut self.counts.spikes,
        };
        feed.play(&mut self.crash, t, &mut out.accel);
        let feed = Feed {
            model: &mut self.model,
            sensor: &self.sensor,
            time: self.time,
            spikes: &mut self.counts.spikes,
        };
        feed.play(&mut self.safing, t, &mut out.safing);
        if let Some(channels) = self.satellites.as_mut() {
            for (ch, frames) in channels.iter_mut().zip(out.satellites.iter_mut()) {
                self.satellite_readings.clear();
                let feed = Feed {
                    model: &mut self.model,
                    sensor: &self.sensor,
                    time: self.time,
                    spikes: &mut self.counts.spikes,
                };
                feed.play(ch, t, &mut self.satellite_readings);
                let full_scale = ch.full_scale_mps2;
                frames.extend(
                    self.satellite_readings
                        .iter()
                        .map(|b| psi5_frames(b, full_scale)),
                );
            }
        }
        self.can(t, out)
    }

    fn objects(&mut self, t: f64, out: &mut TickOutput) {
        let period_s = self.sensor.object_period_ms * 1e-3;
        while self.next_obj_s <= t + 1e-9 {
            let tp = self.next_obj_s;
            self.next_obj_s += period_s;
            if self.sensor.dropped(DropoutTarget::Object, tp) {
                self.counts.objects_dropped += 1;
                continue;
            }
            let sample = match self.last_object.filter(|_| self.sensor.frozen(tp)) {
                Some(stuck) => {
                    self.counts.objects_frozen += 1;
                    Some(stuck)
                }
                None => match (self.model.object(tp), self.model.measurement_time_s(tp)) {
                    (Some(mut o), Some(tm)) => {
                        o.timestamp_ns = self.to_ns(tm);
                        Some(o)
                    }
                    _ => None,
                },
            };
            if let Some(o) = sample {
                self.last_object = Some(o);
                self.counts.objects += 1;
                out.objects.push(o);
            }
        }
    }

    fn can(&mut self, t: f64, out: &mut TickOutput) -> Result<(), bus::EncodeError> {
        while self.next_veh_s <= t + 1e-9 {
            let tp = self.next_veh_s;
            self.next_veh_s += self.sensor.vehicle_period_ms * 1e-3;
            if !self.sensor.dropped(DropoutTarget::Vehicle, tp) {
                out.can.push(self.protector.seal(self.model.ego_frame(tp)?));
                self.counts.can_frames += 1;
            }
        }
        while self.next_occ_s <= t + 1e-9 {
            let tp = self.next_occ_s;
            self.next_occ_s += self.sensor.occupant_period_ms * 1e-3;
            if !self.sensor.dropped(DropoutTarget::Occupant, tp) {
                out.can
                    .push(self.protector.seal(self.model.occupant_frame()?));
                self.counts.can_frames += 1;
            }
        }
        while let Some(period_ms) = self.v2x_period_ms.filter(|_| self.next_v2x_s <= t + 1e-9) {
            let tp = self.next_v2x_s;
            self.next_v2x_s += period_ms * 1e-3;
            if let Some(frame) = self.model.v2x_frame(tp) {
                // The noise is drawn even for a dropped frame: a dropout does not shift the rest.
                if !self.sensor.dropped(DropoutTarget::V2x, tp) {
                    out.can.push(self.protector.seal(frame?));
                    self.counts.can_frames += 1;
                }
            }
        }
        Ok(())
    }
}

/// What one acceleration sensor's feed borrows from the player for one tick.
struct Feed<'a> {
    model: &'a mut SensorModelSim,
    sensor: &'a SensorModel,
    time: TimeBase,
    spikes: &'a mut u64,
}

impl Feed<'_> {
    /// Every sample of `ch` whose instant has passed, in batches of ≤ 8; samples inside a
    /// dropout are lost (not delivered late); a spike replaces its one sample; inside a fault
    /// window they are altered.
    fn play(self, ch: &mut AccelChannel, t: f64, out: &mut Vec<CrashAccelSample>) {
        let dt_s = ch.dt_s;
        if self
            .sensor
            .dropped(SensorModel::dropout_target(ch.sensor), t)
        {
            ch.next_k = ((t / dt_s).floor() as u64) + 1;
            return;
        }
        let mut batch = CrashAccelSample::EMPTY;
        while (ch.next_k as f64) * dt_s + ch.latency_s <= t + 1e-9 {
            let ts = ch.next_k as f64 * dt_s;
            ch.next_k += 1;
            // The noise is drawn for every sample (a spike replaces the value, not the draw).
            let mut reading = self.model.reading_mps2(ch.sensor, ts) as f32;
            if let Some(v) = self.model.spike_mps2(ch.sensor, ts, dt_s) {
                *self.spikes += 1;
                reading = v as f32;
            }
            let value = match self.sensor.sensor_fault(ch.sensor, ts) {
                None => {
                    ch.last = reading;
                    reading
                }
                Some(kind) => {
                    ch.faulty += 1;
                    match kind {
                        AccelFaultKind::Stuck => ch.last,
                        AccelFaultKind::Saturated => -ch.full_scale_mps2 as f32,
                    }
                }
            };
            if batch.count == 0 {
                batch.first_timestamp_ns = self.time.to_ns(ts);
                batch.sample_period_ns = (dt_s * 1e9 * self.time.scale).round() as u32;
            }
            if let Some(slot) = batch.accel_mps2.get_mut(batch.count as usize) {
                *slot = value;
            }
            batch.count += 1;
            if batch.count as usize == ACCEL_BATCH_CAPACITY {
                push_batch(ch, &mut batch, out);
            }
        }
        if batch.count > 0 {
            push_batch(ch, &mut batch, out);
        }
    }
}

/// A satellite's readings as PSI5 frames: each reading (m/s², − = deceleration) as the data
/// code of its deceleration, with parity; the same instants and sequence.
fn psi5_frames(b: &CrashAccelSample, full_scale_mps2: f64) -> SatelliteFrames {
    let mut f = SatelliteFrames {
        first_timestamp_ns: b.first_timestamp_ns,
        sequence: b.sequence,
        sample_period_ns: b.sample_period_ns,
        count: b.count,
        ..SatelliteFrames::EMPTY
    };
    for (slot, a) in f.frames.iter_mut().zip(b.samples()) {
        *slot = psi5::encode(psi5::code_of(-f64::from(*a), full_scale_mps2));
    }
    f
}

fn push_batch(
    ch: &mut AccelChannel,
    batch: &mut CrashAccelSample,
    out: &mut Vec<CrashAccelSample>,
) {
    ch.seq += 1;
    batch.sequence = ch.seq;
    ch.samples += u64::from(batch.count);
    out.push(*batch);
    *batch = CrashAccelSample::EMPTY;
}

#[cfg(test)]
mod tests {
    use super::*;
    use world::Scenario;

    fn player(sensor: &str) -> Player {
        let text = format!(
            "name = \"t\"\nduration_s = 2\n[ego]\nmass_kg = 1785\nspeed_kph = 36\n\
             [opponent]\nkind = \"vehicle\"\nmass_kg = 1500\nspeed_kph = 36\ninitial_distance_m = 40\n\
             [sensor]\n{sensor}\n[occupant]\nmass_kg = 75\n"
        );
        let s = Scenario::parse("t.toml", &text).expect("valid");
        Player::new(Truth::new(&s).expect("truth"), 1_000, 1.0, 0)
    }

    #[test]
    fn each_tick_carries_one_ms_of_samples_and_the_periodic_records() {
        let mut p = player("accel_rate_hz = 4000");
        let mut out = TickOutput::default();
        let (mut objects, mut frames) = (0, 0);
        for tick in 0..=100 {
            p.tick(tick, &mut out).expect("tick");
            objects += out.objects.len();
            frames += out.can.len();
            // Tick 0 has the sample at t = 0; every later tick the 4 samples of the last ms.
            let want = if tick == 0 { 1 } else { 4 };
            assert_eq!(out.accel.iter().map(|b| b.count).sum::<u32>(), want);
            if let Some(b) = out.accel.first().filter(|_| tick > 0) {
                assert_eq!(b.first_timestamp_ns, 1_000 + tick * TICK_NS - 750_000);
                assert_eq!(b.sample_period_ns, 250_000);
            }
        }
        // Objects every 20 ms from the first measurement (latency 20 ms): t = 20..=100 ms.
        assert_eq!(objects, 5);
        // EgoVehicleState every 10 ms (11 in 0..=100 ms) + OccupantClassification at 0 and 100.
        assert_eq!(frames, 11 + 2);
        assert_eq!(p.counts().can_frames, 13);
    }

    #[test]
    fn a_stuck_accelerometer_repeats_its_last_reading_and_a_saturated_one_reads_full_scale() {
        let mut p = player(
            "accel_faults = [{ start_s = 0.010, end_s = 0.020, kind = \"stuck\" }, \
             { start_s = 0.030, end_s = 0.031, kind = \"saturated\" }]",
        );
        let mut out = TickOutput::default();
        let mut values = Vec::new();
        for tick in 0..=40 {
            p.tick(tick, &mut out).expect("tick");
            for b in &out.accel {
                values.extend_from_slice(b.samples());
            }
        }
        // Sample k at k/4 ms: stuck from k = 40 to 79, saturated 120..=123.
        let last_good = values[39];
        assert!(values[40..80].iter().all(|v| *v == last_good));
        assert_ne!(values[80], last_good);
        let fs = -(200.0 * physics::defaults::STANDARD_GRAVITY_MPS2) as f32;
        assert!(values[120..124].iter().all(|v| *v == fs));
        assert!(values[124].abs() < 10.0, "noise only, no crash yet");
        assert_eq!(p.counts().accel_faulty, 40 + 4);
    }

    #[test]
    fn an_accelerometer_dropout_loses_its_samples() {
        let mut p = player("dropouts = [{ start_s = 0.005, end_s = 0.010, target = \"accel\" }]");
        let mut out = TickOutput::default();
        let mut n = 0;
        for tick in 0..=20 {
            p.tick(tick, &mut out).expect("tick");
            if (5..10).contains(&tick) {
                assert!(out.accel.is_empty(), "tick {tick}");
            }
            n += out.accel.iter().map(|b| b.count).sum::<u32>();
        }
        // 81 samples at 0..=20 ms; the ticks 5..=9 publish nothing and their samples (4.25 to
        // 9 ms, 20 of them) are lost; tick 10 publishes those after 9 ms (the window is judged
        // per tick, the feed's 1 ms grid).
        assert_eq!(n, 81 - 20);
    }

    /// (scenario time [s], reading) of every sample of one feed, from the batches' time stamps.
    type Trace = Vec<(f64, f32)>;

    fn trace(batches: &[CrashAccelSample], into: &mut Trace) {
        for b in batches {
            for (j, v) in b.samples().iter().enumerate() {
                let ns = b.first_timestamp_ns + j as u64 * u64::from(b.sample_period_ns) - 1_000;
                into.push((ns as f64 * 1e-9, *v));
            }
        }
    }

    /// Plays ticks `0..=last` of `p`: the crash and the safing sensor's samples.
    fn play(p: &mut Player, last: u64) -> (Trace, Trace) {
        let (mut crash, mut safing) = (Vec::new(), Vec::new());
        let mut out = TickOutput::default();
        for tick in 0..=last {
            p.tick(tick, &mut out).expect("tick");
            trace(&out.accel, &mut crash);
            trace(&out.safing, &mut safing);
        }
        (crash, safing)
    }

    /// A player whose sensors read the truth exactly (no noise, no anti-alias filter — it is
    /// tested in `world::lowpass`; constant speeds: 0 m/s² until the contact at 2.0 s) plus
    /// `events` (`[[accel_event]]` tables).
    fn quiet(events: &str) -> Player {
        let text = format!(
            "name = \"t\"\nduration_s = 2\n[ego]\nmass_kg = 1785\nspeed_kph = 36\n\
             [opponent]\nkind = \"vehicle\"\nmass_kg = 1500\nspeed_kph = 36\ninitial_distance_m = 40\n\
             [sensor]\naccel_noise_mps2 = 0\nsafing_noise_mps2 = 0\naccel_lowpass_hz = 0\n[occupant]\nmass_kg = 75\n{events}"
        );
        let s = Scenario::parse("t.toml", &text).expect("valid");
        Player::new(Truth::new(&s).expect("truth"), 1_000, 1.0, 0)
    }

    const G: f64 = physics::defaults::STANDARD_GRAVITY_MPS2;

    #[test]
    fn the_safing_sensor_has_its_own_rate_batches_and_sequence() {
        let mut p = player("");
        let mut out = TickOutput::default();
        for tick in 0..=50 {
            p.tick(tick, &mut out).expect("tick");
            // 2 kHz: the sample at t = 0, then 2 a ms (at 0.5 and 1.0 ms of each ms).
            let want = if tick == 0 { 1 } else { 2 };
            assert_eq!(out.safing.len(), 1);
            let b = out.safing[0];
            assert_eq!(b.count, want);
            assert_eq!(b.sequence, tick + 1, "its own counter");
            if tick > 0 {
                assert_eq!(b.first_timestamp_ns, 1_000 + tick * TICK_NS - 500_000);
                assert_eq!(b.sample_period_ns, 500_000);
            }
        }
        assert_eq!(p.counts().safing_samples, 1 + 2 * 50);
        assert_eq!(p.counts().accel_samples, 1 + 4 * 50);
        let mut p = player("safing_rate_hz = 8000");
        p.tick(0, &mut out).expect("tick");
        p.tick(1, &mut out).expect("tick");
        assert_eq!(out.safing.len(), 1);
        assert_eq!(out.safing[0].count, 8);
        assert_eq!(out.safing[0].sample_period_ns, 125_000);
    }

    #[test]
    fn nothing_the_crash_sensor_and_the_object_list_publish_depends_on_the_safing_sensor() {
        let mut a = player("");
        let mut b = player(
            "safing_rate_hz = 8000\nsafing_noise_mps2 = 7\nsafing_full_scale_g = 20\n\
             dropouts = [{ start_s = 0.3, end_s = 0.4, target = \"safing\" }]\n\
             accel_faults = [{ start_s = 0.5, end_s = 0.6, kind = \"saturated\", sensor = \"safing\" }]",
        );
        let (mut x, mut y) = (TickOutput::default(), TickOutput::default());
        let mut differ = 0;
        for tick in 0..=2000 {
            a.tick(tick, &mut x).expect("tick");
            b.tick(tick, &mut y).expect("tick");
            assert_eq!(x.accel, y.accel, "tick {tick}");
            assert_eq!(x.objects, y.objects, "tick {tick}");
            assert_eq!(x.can, y.can, "tick {tick}");
            differ += usize::from(x.safing != y.safing);
        }
        assert!(differ > 1900, "{differ}");
        assert_eq!(a.counts().accel_samples, b.counts().accel_samples);
    }

    #[test]
    fn the_safing_noise_is_its_own_stream_with_its_sigma() {
        // Constant speeds, no crash before 2.0 s: the readings are the noise.
        let mut p = player("accel_noise_mps2 = 1.0\nsafing_noise_mps2 = 3.0");
        let (crash, safing) = play(&mut p, 1900);
        let stats = |v: &[f32]| {
            let n = v.len() as f64;
            let mean = v.iter().map(|x| f64::from(*x)).sum::<f64>() / n;
            let var = v
                .iter()
                .map(|x| (f64::from(*x) - mean).powi(2))
                .sum::<f64>()
                / n;
            (mean, var.sqrt())
        };
        let s: Vec<f32> = safing.iter().map(|(_, v)| *v).collect();
        let (mean, sd) = stats(&s);
        // 3801 draws: sd within ±5 % (≈ 4.4 standard errors), mean within 4 standard errors.
        assert!((sd - 3.0).abs() < 0.15, "sd {sd}");
        assert!(
            mean.abs() < 4.0 * 3.0 / (s.len() as f64).sqrt(),
            "mean {mean}"
        );
        // At the instants both sample (every 0.5 ms) the two noises are uncorrelated.
        let c: Vec<f32> = crash.iter().step_by(2).map(|(_, v)| *v).collect();
        assert_eq!(c.len(), s.len());
        assert!(crash
            .iter()
            .step_by(2)
            .zip(&safing)
            .all(|(a, b)| a.0 == b.0));
        let r = c
            .iter()
            .zip(&s)
            .map(|(a, b)| f64::from(*a) * f64::from(*b))
            .sum::<f64>()
            / (c.len() as f64 * 3.0 * stats(&c).1);
        assert!(r.abs() < 0.07, "correlation {r}");
    }

    #[test]
    fn the_safing_sensor_saturates_at_its_own_range_and_has_its_own_faults_and_dropouts() {
        // 60 + 60 km/h into each other at 1.0 s: a pulse well beyond 10 g.
        let text = "name = \"t\"\nduration_s = 1.2\n[ego]\nmass_kg = 1785\nspeed_kph = 60\n\
             [opponent]\nkind = \"vehicle\"\nmass_kg = 1785\nspeed_kph = 60\ninitial_distance_m = 33.3333333\n\
             [sensor]\nsafing_full_scale_g = 10\n\
             dropouts = [{ start_s = 0.1, end_s = 0.2, target = \"safing\" }]\n\
             accel_faults = [{ start_s = 0.3, end_s = 0.31, kind = \"saturated\", sensor = \"safing\" }, \
             { start_s = 0.4, end_s = 0.45, kind = \"stuck\", sensor = \"safing\" }]\n\
             [occupant]\nmass_kg = 75\n";
        let s = Scenario::parse("t.toml", text).expect("valid");
        let mut p = Player::new(Truth::new(&s).expect("truth"), 1_000, 1.0, 0);
        let (crash, safing) = play(&mut p, 1200);
        let fs = (10.0 * G) as f32;
        let crash_min = crash.iter().map(|x| x.1).fold(f32::MAX, f32::min);
        assert!(
            crash_min < -3.0 * fs,
            "the crash sensor sees the pulse: {crash_min}"
        );
        assert!(safing.iter().all(|x| x.1.abs() <= fs));
        assert!(safing.iter().filter(|x| x.0 > 1.0).any(|x| x.1 == -fs));
        // Dropout: the ticks 100..=199 publish nothing (samples 99.5 ms .. 199 ms lost).
        assert!(!safing.iter().any(|x| x.0 > 0.0995 && x.0 < 0.1995));
        assert!(crash.iter().any(|x| x.0 > 0.1 && x.0 < 0.2));
        // Saturated: 0.300 .. 0.3095 s reads −10 g; stuck: 0.400 .. 0.4495 s one value.
        let window = |a: f64, b: f64| -> Vec<f32> {
            safing
                .iter()
                .filter(|x| x.0 >= a - 1e-9 && x.0 < b - 1e-9)
                .map(|x| x.1)
                .collect()
        };
        assert_eq!(window(0.3, 0.31), vec![-fs; 20]);
        let stuck = window(0.4, 0.45);
        assert_eq!(stuck.len(), 100);
        assert!(stuck.iter().all(|v| *v == window(0.3995, 0.4)[0]));
        assert_eq!(p.counts().safing_faulty, 120);
        assert_eq!(p.counts().accel_faulty, 0);
    }

    #[test]
    fn a_half_sine_on_all_is_seen_by_both_sensors_and_a_sensor_fault_by_one() {
        let ev = |sensor: &str| {
            format!(
                "[[accel_event]]\nkind = \"half_sine\"\nstart_s = 0.5001\npeak_g = 10\nduration_ms = 8\nsensor = \"{sensor}\"\n"
            )
        };
        let expect = |t: f64| {
            let x = t - 0.5001;
            if (0.0..=0.008).contains(&x) {
                -10.0 * G * (std::f64::consts::PI * x / 0.008).sin()
            } else {
                0.0
            }
        };
        for (sensor, crash_sees, safing_sees) in [
            ("all", true, true),
            ("crash", true, false),
            ("safing", false, true),
        ] {
            let (crash, safing) = play(&mut quiet(&ev(sensor)), 600);
            for (samples, sees) in [(&crash, crash_sees), (&safing, safing_sees)] {
                let mut inside = 0;
                for (t, v) in samples {
                    let want = if sees { expect(*t) } else { 0.0 };
                    assert!(
                        (f64::from(*v) - want).abs() < 1e-3,
                        "{sensor} {t}: {v} vs {want}"
                    );
                    inside += usize::from(want != 0.0);
                }
                // 8 ms at 4 / 2 kHz: 32 / 16 samples inside (0.5001 is between samples).
                if sees {
                    assert!(inside == 32 || inside == 16, "{sensor}: {inside}");
                }
            }
        }
    }

    #[test]
    fn a_spike_is_exactly_one_sample_of_each_named_sensor() {
        let ev = |sensor: &str| {
            format!("[[accel_event]]\nkind = \"spike\"\nstart_s = 0.5001\npeak_g = 40\nsensor = \"{sensor}\"\n")
        };
        let fs = (40.0 * G) as f32;
        for (sensor, crash_at, safing_at) in [
            ("all", Some(0.50025), Some(0.5005)),
            ("crash", Some(0.50025), None),
            ("safing", None, Some(0.5005)),
        ] {
            let mut p = quiet(&ev(sensor));
            let (crash, safing) = play(&mut p, 600);
            for (samples, at) in [(&crash, crash_at), (&safing, safing_at)] {
                let hits: Vec<f64> = samples.iter().filter(|x| x.1 != 0.0).map(|x| x.0).collect();
                match at {
                    Some(t) => {
                        assert_eq!(hits.len(), 1, "{sensor}");
                        assert!((hits[0] - t).abs() < 1e-9, "{sensor}: {hits:?}");
                        assert!(samples.iter().any(|x| x.1 == -fs));
                    }
                    None => assert!(hits.is_empty(), "{sensor}"),
                }
            }
            // A mechanical spike (`all`) reaches the two satellites too.
            let satellites = if sensor == "all" { 2 } else { 0 };
            assert_eq!(
                p.counts().spikes,
                [crash_at, safing_at].iter().flatten().count() as u64 + satellites
            );
        }
        // On a sample instant: that sample. Beyond the range: the range (safing 50 g).
        let (crash, safing) = play(
            &mut quiet("[[accel_event]]\nkind = \"spike\"\nstart_s = 0.5\npeak_g = -120\n"),
            600,
        );
        let hit = |s: &Trace| s.iter().filter(|x| x.1 != 0.0).copied().collect::<Vec<_>>();
        assert_eq!(hit(&crash), vec![(0.5, (120.0 * G) as f32)]);
        assert_eq!(hit(&safing), vec![(0.5, (50.0 * G) as f32)]);
    }

    #[test]
    fn a_rough_road_on_all_is_one_signal_with_its_rms_in_its_band() {
        let text =
            "[[accel_event]]\nkind = \"rough_road\"\nstart_s = 0.2\nend_s = 1.8\nrms_g = 2.0\n";
        let (crash, safing) = play(&mut quiet(text), 1999);
        let inside = |s: &Trace| -> Vec<f64> {
            s.iter()
                .filter(|x| x.0 >= 0.2 && x.0 < 1.8 - 1e-9)
                .map(|x| f64::from(x.1))
                .collect()
        };
        let rms = |v: &[f64]| (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt();
        for s in [&crash, &safing] {
            let v = inside(s);
            let r = rms(&v);
            // Exactly 2 g on the 2 kHz grid; read by interpolation at the sensor's instants.
            assert!((r - 2.0 * G).abs() < 0.02 * 2.0 * G, "rms {r}");
            assert!(s
                .iter()
                .filter(|x| x.0 < 0.2 || x.0 >= 1.8)
                .all(|x| x.1 == 0.0));
            // Band-limited: consecutive 1 ms differences are small against the amplitude
            // (40 Hz edge: |Δ| ≲ 2π·40 Hz·1 ms·peak), white noise's would be √2·rms.
            let per_ms: Vec<f64> = s
                .iter()
                .filter(|x| x.0 >= 0.2 && x.0 < 1.8 - 1e-9)
                .filter(|x| (x.0 * 1e3 - (x.0 * 1e3).round()).abs() < 1e-6)
                .map(|x| f64::from(x.1))
                .collect();
            let d = per_ms.windows(2).map(|w| w[1] - w[0]).collect::<Vec<_>>();
            assert!(rms(&d) < 0.35 * r, "{} vs {r}", rms(&d));
        }
        // The same mechanical signal: equal at the instants both sample.
        let at = |s: &Trace, t: f64| s.iter().find(|x| (x.0 - t).abs() < 1e-9).map(|x| x.1);
        let mut common = 0;
        for (t, v) in &safing {
            if let Some(c) = at(&crash, *t) {
                assert_eq!(c, *v, "{t}");
                common += 1;
            }
        }
        assert_eq!(common, safing.len());
        // Reproducible from the seed; on one sensor only, the other reads 0.
        assert_eq!(play(&mut quiet(text), 1999).0, crash);
        let (crash_only, safing_none) =
            play(&mut quiet(&format!("{text}sensor = \"crash\"\n")), 1999);
        assert_eq!(crash_only, crash);
        assert!(safing_none.iter().all(|x| x.1 == 0.0));
    }

    #[test]
    fn an_offset_shifts_the_mean_of_its_sensor_inside_its_window() {
        let text = "[sensor]\naccel_noise_mps2 = 2\nsafing_noise_mps2 = 2\naccel_lowpass_hz = 0\n";
        let base = |events: &str| {
            let t = format!(
                "name = \"t\"\nduration_s = 2\n[ego]\nmass_kg = 1785\nspeed_kph = 36\n\
                 [opponent]\nkind = \"vehicle\"\nmass_kg = 1500\nspeed_kph = 36\ninitial_distance_m = 40\n\
                 {text}[occupant]\nmass_kg = 75\n{events}"
            );
            let s = Scenario::parse("t.toml", &t).expect("valid");
            play(
                &mut Player::new(Truth::new(&s).expect("truth"), 1_000, 1.0, 0),
                1500,
            )
        };
        let (c0, s0) = base("");
        let (c1, s1) = base(
            "[[accel_event]]\nkind = \"offset\"\nstart_s = 0.5\nend_s = 1.5\npeak_g = 6\nsensor = \"crash\"\n",
        );
        // Same noise draws: the difference is the offset, exactly where it holds.
        for ((t, a), (_, b)) in c0.iter().zip(&c1) {
            let want = if (0.5..1.5).contains(t) {
                -6.0 * G
            } else {
                0.0
            };
            assert!((f64::from(*b) - f64::from(*a) - want).abs() < 1e-4, "{t}");
        }
        assert_eq!(s0, s1, "the safing sensor does not drift with it");
        let mean = |s: &Trace| {
            let v: Vec<f64> = s
                .iter()
                .filter(|x| (0.5..1.5).contains(&x.0))
                .map(|x| f64::from(x.1))
                .collect();
            v.iter().sum::<f64>() / v.len() as f64
        };
        assert!((mean(&c1) + 6.0 * G).abs() < 0.1, "{}", mean(&c1));
        assert!(mean(&c0).abs() < 0.1);
    }

    #[test]
    fn events_after_contact_add_to_the_crash_pulse() {
        let crash = |events: &str| {
            let text = format!(
                "name = \"t\"\nduration_s = 1.3\n[ego]\nmass_kg = 1785\nspeed_kph = 40\n\
                 [opponent]\nkind = \"vehicle\"\nmass_kg = 1785\nspeed_kph = 40\ninitial_distance_m = 22.2222222\n\
                 [sensor]\naccel_lowpass_hz = 0\n[occupant]\nmass_kg = 75\n{events}"
            );
            let s = Scenario::parse("t.toml", &text).expect("valid");
            play(
                &mut Player::new(Truth::new(&s).expect("truth"), 1_000, 1.0, 0),
                1300,
            )
        };
        let (c0, s0) = crash("");
        let (c1, s1) = crash(
            "[[accel_event]]\nkind = \"half_sine\"\nstart_s = 1.02\npeak_g = 5\nduration_ms = 10\n",
        );
        for (x0, x1) in [(&c0, &c1), (&s0, &s1)] {
            for ((t, a), (_, b)) in x0.iter().zip(x1.iter()) {
                let x = t - 1.02;
                let want = if (0.0..=0.01).contains(&x) {
                    -5.0 * G * (std::f64::consts::PI * x / 0.01).sin()
                } else {
                    0.0
                };
                // Inside the pulse (|a| up to ~30 g): f32 rounding of both readings.
                assert!((f64::from(*b) - f64::from(*a) - want).abs() < 1e-3, "{t}");
            }
        }
        assert!(
            c0.iter().any(|x| x.0 > 1.02 && x.0 < 1.03 && x.1 < -100.0),
            "inside the pulse"
        );
    }
}
