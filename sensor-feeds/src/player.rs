//! What the feeds publish, tick by tick, without a clock: the object list (period, latency,
//! dropouts, stuck windows), the crash accelerometer in batches of ≤ 8 samples (dropouts and
//! accelerometer faults) and the E2E-sealed CAN frames. The `sensor-feeds` binary sleeps to each
//! tick and publishes what [`Player::tick`] produced; the offline bench (`e2e-tests`'
//! `offline-bench`) hands the same records to the ECU core under a simulated clock, so both run
//! one model of the sensors.

use crate::scenario::{AccelFaultKind, DropoutTarget, SensorModel};
use crate::sensors::SensorModelSim;
use crate::truth::Truth;
use bus::{E2eProtector, RawFrame};
use ipc::{CrashAccelSample, ObjectState, ACCEL_BATCH_CAPACITY};

/// The feed grid: one tick per ms of scenario time.
pub const TICK_NS: u64 = 1_000_000;

/// Everything one tick publishes (reused: [`Player::tick`] clears it first).
#[derive(Clone, Debug, Default)]
pub struct TickOutput {
    /// Object-list records (iceoryx2 `ObjectState`).
    pub objects: Vec<ObjectState>,
    /// Accelerometer batches (iceoryx2 `CrashAccelSample`).
    pub accel: Vec<CrashAccelSample>,
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
    /// Accelerometer samples produced.
    pub accel_samples: u64,
    /// Accelerometer samples altered by an accelerometer fault window.
    pub accel_faulty: u64,
    /// CAN frames produced.
    pub can_frames: u64,
}

/// The tick-by-tick sensor feeds of one scenario run.
pub struct Player {
    model: SensorModelSim,
    sensor: SensorModel,
    start_ns: u64,
    /// Real time per scenario time (1 / speed-up).
    scale: f64,
    next_obj_s: f64,
    next_veh_s: f64,
    next_occ_s: f64,
    next_accel_k: u64,
    last_object: Option<ObjectState>,
    /// The last genuine accelerometer reading (what a stuck sensor keeps repeating).
    last_accel: f32,
    accel_seq: u64,
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
        let accel_dt_s = 1.0 / sensor.accel_rate_hz;
        // First instant of each feed at or after t0 (all 0 on a fresh start).
        let first_at = |period_s: f64| (t0_s / period_s - 1e-9).ceil().max(0.0) * period_s;
        Player {
            next_obj_s: first_at(sensor.object_period_ms * 1e-3),
            next_veh_s: first_at(sensor.vehicle_period_ms * 1e-3),
            next_occ_s: first_at(sensor.occupant_period_ms * 1e-3),
            next_accel_k: (t0_s / accel_dt_s - 1e-9).ceil().max(0.0) as u64,
            model: SensorModelSim::new(truth),
            sensor,
            start_ns,
            scale,
            last_object: None,
            last_accel: 0.0,
            accel_seq: 0,
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
        self.counts
    }

    /// CLOCK_MONOTONIC time of scenario time `t_s`.
    pub fn to_ns(&self, t_s: f64) -> u64 {
        self.start_ns + (t_s * 1e9 * self.scale).round() as u64
    }

    /// Everything due at tick `tick` (scenario time `tick` ms) into `out`.
    ///
    /// # Errors
    /// A CAN frame value outside its DBC range (a model bug).
    pub fn tick(&mut self, tick: u64, out: &mut TickOutput) -> Result<(), bus::EncodeError> {
        out.objects.clear();
        out.accel.clear();
        out.can.clear();
        let t = tick as f64 * 1e-3;
        self.objects(t, out);
        self.accel(t, out);
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

    /// Every sample whose instant has passed, in batches of ≤ 8; samples inside a dropout are
    /// lost (not delivered late); inside a fault window they are altered.
    fn accel(&mut self, t: f64, out: &mut TickOutput) {
        let dt_s = 1.0 / self.sensor.accel_rate_hz;
        if self.sensor.dropped(DropoutTarget::Accel, t) {
            self.next_accel_k = ((t / dt_s).floor() as u64) + 1;
            return;
        }
        let mut batch = CrashAccelSample::EMPTY;
        while (self.next_accel_k as f64) * dt_s <= t + 1e-9 {
            let ts = self.next_accel_k as f64 * dt_s;
            self.next_accel_k += 1;
            let genuine = self.model.accel_mps2(ts) as f32;
            let value = match self.sensor.accel_fault(ts) {
                None => {
                    self.last_accel = genuine;
                    genuine
                }
                Some(kind) => {
                    self.counts.accel_faulty += 1;
                    match kind {
                        AccelFaultKind::Stuck => self.last_accel,
                        AccelFaultKind::Saturated => {
                            -(self.sensor.accel_full_scale_g
                                * physics::defaults::STANDARD_GRAVITY_MPS2)
                                as f32
                        }
                    }
                }
            };
            if batch.count == 0 {
                batch.first_timestamp_ns = self.to_ns(ts);
                batch.sample_period_ns = (dt_s * 1e9 * self.scale).round() as u32;
            }
            if let Some(slot) = batch.accel_mps2.get_mut(batch.count as usize) {
                *slot = value;
            }
            batch.count += 1;
            if batch.count as usize == ACCEL_BATCH_CAPACITY {
                self.push_batch(&mut batch, out);
            }
        }
        if batch.count > 0 {
            self.push_batch(&mut batch, out);
        }
    }

    fn push_batch(&mut self, batch: &mut CrashAccelSample, out: &mut TickOutput) {
        self.accel_seq += 1;
        batch.sequence = self.accel_seq;
        self.counts.accel_samples += u64::from(batch.count);
        out.accel.push(*batch);
        *batch = CrashAccelSample::EMPTY;
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
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Scenario;

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
}
