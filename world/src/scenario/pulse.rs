//! `[pulse]`: a measured crash pulse for the ego — a crash test's compartment accelerometer,
//! as a CSV trace or an ISO-MME channel file (`physics::trace`) — instead of the two-mass
//! model's. The approach (contact instant, closing speed, the object list) stays the
//! scenario's; from the contact on the ego's body follows the file (`physics::measured`), and
//! the sensors read it through their own model, the anti-alias filter included.

use serde::Deserialize;
use std::path::Path;

/// Coarsest sampling a measured pulse may have [s]: a crash pulse's first milliseconds decide
/// the fire, and crash-test channels are recorded at 10–20 kHz (SAE J211: ≥ 5 × the channel
/// class's corner frequency, CFC 1000 for the compartment's accelerometers).
pub const MAX_SAMPLING_INTERVAL_S: f64 = 1e-3;

/// The `[pulse]` table.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct MeasuredPulse {
    /// The channel file (CSV or ISO-MME), relative to the scenario file's folder; time 0 is
    /// the first contact, SAE J211 sign (a frontal crash reads negative).
    pub file: String,
    /// The channel from the first contact on, on the truth's grid
    /// (`physics::defaults::STEP_S`, at most the pulse buffer's length) [m/s²]: read by
    /// `Scenario::load` / `Scenario::parse`.
    #[serde(skip)]
    pub accel_mps2: Vec<f64>,
}

impl MeasuredPulse {
    /// Reads the file named relative to the folder of `scenario_file` and resamples it onto the
    /// truth's grid from the contact on.
    pub(super) fn read(&mut self, scenario_file: &str) -> Result<(), String> {
        let path = Path::new(scenario_file)
            .parent()
            .unwrap_or(Path::new(""))
            .join(&self.file);
        let text = std::fs::read_to_string(&path)
            .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
        let trace = physics::trace::parse(&text).map_err(|e| format!("{}: {e}", path.display()))?;
        if trace.step_s > MAX_SAMPLING_INTERVAL_S {
            return Err(format!(
                "{}: sampled every {} ms, coarser than {} ms",
                path.display(),
                trace.step_s * 1e3,
                MAX_SAMPLING_INTERVAL_S * 1e3
            ));
        }
        if trace.start_s > 0.0 {
            return Err(format!(
                "{}: its first sample is {} ms after the contact (time 0): the pulse's beginning is missing",
                path.display(),
                trace.start_s * 1e3
            ));
        }
        let samples =
            trace.from_contact(physics::defaults::STEP_S, physics::defaults::PULSE_CAPACITY);
        if samples.len() < 2 {
            return Err(format!(
                "{}: no samples after the contact (time 0)",
                path.display()
            ));
        }
        let pulse = physics::CompartmentPulse {
            step_s: physics::defaults::STEP_S,
            accel_mps2: &samples,
        };
        if !(pulse.delta_v_mps() < 0.0) {
            return Err(format!(
                "{}: the pulse does not slow the car (SAE J211: a frontal crash reads negative)",
                path.display()
            ));
        }
        self.accel_mps2 = samples;
        Ok(())
    }
}
