//! `report.json`: what the modules received and did, and the occupant outcome of it.
//! Times named `*_ms` are relative to the TRUE first contact (negative = before it).

use crate::commands::Action;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// The true crash (from the scenario's true physics).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct TrueCrash {
    /// Closing speed at contact [km/h].
    pub closing_speed_kph: f64,
    /// Ego velocity change [km/h].
    pub delta_v_kph: f64,
    /// Ego compartment peak deceleration [g].
    pub a_max_g: f64,
    /// Ego compartment mean deceleration over contact [g].
    pub a_mean_g: f64,
    /// Ego crush [mm].
    pub crush_mm: f64,
    /// The airbag's required fire time, "127 mm − 30 ms" of the true pulse [ms after contact]
    /// (`physics::deadline`; `None`: the pulse never moves a free occupant 127 mm).
    #[serde(default)]
    pub required_ms: Option<f64>,
}

/// One restraint's occupant outcome and time history.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Judged {
    /// Settings used (SI; times relative to true contact).
    pub load_limiter_kn: f64,
    /// Airbag level [kN] (0 = not fired).
    pub airbag_level_kn: f64,
    /// Pretensioner time [ms after contact] (None = not fired).
    pub pretensioner_ms: Option<f64>,
    /// Airbag time [ms after contact] (None = not fired).
    pub airbag_ms: Option<f64>,
    /// Peak occupant deceleration [g].
    pub a_max_g: f64,
    /// Mean occupant deceleration over the restraint phase [g].
    pub a_mean_g: f64,
    /// Maximum forward excursion [mm].
    pub excursion_mm: f64,
    /// Available ride-down [mm].
    pub available_mm: f64,
    /// Struck through to the wheel/dash.
    pub bottomed_out: bool,
    /// Time history: t [ms after contact].
    #[serde(skip)]
    pub t_ms: Vec<f64>,
    /// Time history: occupant deceleration [g].
    #[serde(skip)]
    pub decel_g: Vec<f64>,
    /// Time history: excursion [mm].
    #[serde(skip)]
    pub excursion_trace_mm: Vec<f64>,
}

/// An action with its time on the run's two time bases — the same two keys, with the same
/// meaning, as `offline-bench --json`.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct TimedAction {
    /// The action.
    #[serde(flatten)]
    pub action: Action,
    /// Time after the scenario's start (the feeds' t = 0) [ms].
    pub t_ms: f64,
    /// Time relative to the true contact [ms] (None without contact).
    pub after_contact_ms: Option<f64>,
}

/// The outcome comparison (contact only).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Outcome {
    /// What was actually commanded.
    pub adaptive: Judged,
    /// The commanded levels at the ECU's planned times (FireTime signals) instead of the
    /// receive times: how good the plan was, independent of command timing.
    pub adaptive_planned: Option<Judged>,
    /// The conventional reference restraint (as a conventional ECU would fire it).
    pub reference: Judged,
    /// Ideal constant-force bound a* [g].
    pub ideal_g: f64,
    /// Adaptive no worse than reference (see `outcome::no_worse`).
    pub adaptive_no_worse: bool,
    /// (a_max + a_mean) adaptive / reference − 1 [%] (negative = better).
    pub change_pct: f64,
}

/// The whole report.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Report {
    /// Scenario name.
    pub scenario: String,
    /// Why the stubs stopped: "done" | "timeout" | "signal".
    pub stop_reason: String,
    /// CLOCK_MONOTONIC scenario start [ns] (0 if no bench truth was received).
    pub start_ns: u64,
    /// CLOCK_MONOTONIC true contact [ns] (0 = none).
    pub contact_ns: u64,
    /// True crash, if any.
    pub true_crash: Option<TrueCrash>,
    /// Frames received per message name.
    pub frames: BTreeMap<String, u64>,
    /// Frames accepted by the E2E checker.
    pub e2e_accepted: u64,
    /// Rejections per reason.
    pub e2e_rejected: BTreeMap<String, u64>,
    /// Commands authenticated by SecOC (the only ones the modules acted on).
    #[serde(default)]
    pub secoc_accepted: u64,
    /// SecOC rejections by reason (`bus::secoc::SecOcReject::name`): forged, replayed, stale…
    #[serde(default)]
    pub secoc_rejected: BTreeMap<String, u64>,
    /// Commands that passed E2E but never got a valid authenticator (not acted on).
    #[serde(default)]
    pub secoc_commands_dropped: u64,
    /// SecOC pairing timeout the stubs ran with [ms] (default 10).
    #[serde(default)]
    pub secoc_pairing_timeout_ms: f64,
    /// SecOC freshness window the stubs ran with [ms] (default 100).
    #[serde(default)]
    pub secoc_freshness_window_ms: f64,
    /// Module actions in order.
    pub actions: Vec<TimedAction>,
    /// First armed airbag command [ms rel. contact].
    pub first_armed_ms: Option<f64>,
    /// First command from the reference restraint (ECU fallback) [ms rel. contact].
    pub first_reference_cmd_ms: Option<f64>,
    /// First command from the reference restraint [s after scenario start].
    pub first_reference_cmd_s: Option<f64>,
    /// What the times of `ecu_modes`, `ecu_faults` and `ecu_diag_modes` count from:
    /// `"contact"` (ms relative to the true contact) or, in a run without one, `"start"` (ms
    /// after the scenario's start).
    #[serde(default)]
    pub modes_relative_to: String,
    /// ECU mode changes from EcuStatus: (ms, see `modes_relative_to`; mode name as in the DBC).
    pub ecu_modes: Vec<(f64, String)>,
    /// ECU fault-flag changes from EcuStatus (why it degraded): (ms rel. contact or since
    /// start, flags set, named as in [`crate::status::ecu_fault_names`]; empty = no fault).
    #[serde(default)]
    pub ecu_faults: Vec<(f64, Vec<String>)>,
    /// ECU mode changes from its iceoryx2 diagnostics: (ms rel. contact or since start, mode).
    pub ecu_diag_modes: Vec<(f64, String)>,
    /// ECU entered pre-crash (diagnostics) [ms rel. contact].
    pub threat_detected_ms: Option<f64>,
    /// First load-limiter level received after the threat was detected [ms rel. contact].
    pub settings_preset_ms: Option<f64>,
    /// Pretensioner fired before the true contact and still fired at contact.
    pub pretensioner_before_contact: bool,
    /// Pretensioner released at some point.
    pub pretensioner_released: bool,
    /// Airbag fired.
    pub airbag_fired: bool,
    /// The airbag's fire − `true_crash.required_ms` [ms] (negative = in time; `None`: no
    /// airbag or no required time).
    #[serde(default)]
    pub margin_ms: Option<f64>,
    /// Outcome comparison (contact only).
    pub outcome: Option<Outcome>,
    /// Plot file (relative to the report), if drawn.
    pub plot: Option<String>,
}

impl Report {
    /// `schema_version` of `report.json` (docs/using.md, "JSON results").
    pub const SCHEMA_VERSION: u32 = 1;

    /// The first action of this kind ("airbag_fire", "pretensioner_fire", …), as
    /// [`crate::commands::Modules::action`] is during the run.
    pub fn action(&self, what: &str) -> Option<&TimedAction> {
        self.actions.iter().find(|a| a.action.what == what)
    }
}
