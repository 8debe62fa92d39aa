//! What the sensor models ask of a scenario's `[sensor]` table at a scenario time: which
//! input is silenced, faulty or frozen, and each accelerometer's parameters. The schema is in
//! the parent module; `sensor-feeds` and the offline bench ask these questions every sample.

use super::{AccelFaultKind, AccelSensor, DropoutTarget, SensorModel};

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
    /// silences it or faulty-reading window (`None`: it never fails). `[[accel_event]]`
    /// entries are not counted: a spike or an offset is a reading, not a sensor that stopped
    /// being plausible.
    pub fn accel_fails_at_s(&self) -> Option<f64> {
        self.fails_at_s(AccelSensor::Crash)
    }

    /// When the safing accelerometer first fails [s after start] (as
    /// [`Self::accel_fails_at_s`] for the crash accelerometer).
    pub fn safing_fails_at_s(&self) -> Option<f64> {
        self.fails_at_s(AccelSensor::Safing)
    }

    /// When `sensor` first fails: its earliest dropout or faulty-reading window.
    pub fn fails_at_s(&self, sensor: AccelSensor) -> Option<f64> {
        let target = Self::dropout_target(sensor);
        let silenced = self
            .dropouts
            .iter()
            .filter(|d| d.target == target || d.target == DropoutTarget::All)
            .map(|d| d.start_s);
        let faulty = self
            .accel_faults
            .iter()
            .filter(|f| f.sensor == sensor)
            .map(|f| f.start_s);
        silenced.chain(faulty).reduce(f64::min)
    }

    /// The dropout target that silences `sensor`.
    pub fn dropout_target(sensor: AccelSensor) -> DropoutTarget {
        match sensor {
            AccelSensor::Crash => DropoutTarget::Accel,
            AccelSensor::Safing => DropoutTarget::Safing,
            AccelSensor::SatelliteLeft => DropoutTarget::SatelliteLeft,
            AccelSensor::SatelliteRight => DropoutTarget::SatelliteRight,
        }
    }

    /// The crash accelerometer's fault at scenario time `t_s`, if any (the first window that
    /// holds).
    pub fn accel_fault(&self, t_s: f64) -> Option<AccelFaultKind> {
        self.sensor_fault(AccelSensor::Crash, t_s)
    }

    /// `sensor`'s fault at scenario time `t_s`, if any (the first of its windows that holds).
    pub fn sensor_fault(&self, sensor: AccelSensor, t_s: f64) -> Option<AccelFaultKind> {
        self.accel_faults
            .iter()
            .find(|f| f.sensor == sensor && t_s >= f.start_s && t_s < f.end_s)
            .map(|f| f.kind)
    }

    /// Sample rate [Hz], noise [m/s², 1σ] and measuring range [g] of `sensor`.
    pub fn accel_params(&self, sensor: AccelSensor) -> (f64, f64, f64) {
        match sensor {
            AccelSensor::Crash => (
                self.accel_rate_hz,
                self.accel_noise_mps2,
                self.accel_full_scale_g,
            ),
            AccelSensor::Safing => (
                self.safing_rate_hz,
                self.safing_noise_mps2,
                self.safing_full_scale_g,
            ),
            AccelSensor::SatelliteLeft | AccelSensor::SatelliteRight => (
                self.satellite_rate_hz,
                self.satellite_noise_mps2,
                self.satellite_full_scale_g,
            ),
        }
    }

    /// −3 dB corner of `sensor`'s low-pass before sampling [Hz] (0 = none).
    pub fn lowpass_hz(&self, sensor: AccelSensor) -> f64 {
        if sensor.is_satellite() {
            self.satellite_lowpass_hz
        } else {
            self.accel_lowpass_hz
        }
    }

    /// True if the object list is stuck at scenario time `t_s`.
    pub fn frozen(&self, t_s: f64) -> bool {
        self.freezes
            .iter()
            .any(|f| t_s >= f.start_s && t_s < f.end_s)
    }
}
