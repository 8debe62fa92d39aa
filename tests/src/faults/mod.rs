//! The fault-injection campaign (issue 8): real bench processes on vcan (a QEMU guest with a
//! real Debian kernel where the host has no SocketCAN), one fault per run, judged against a
//! clean baseline run.
//!
//! Each [`Case`] is a scenario run through [`crate::run_disturbed`] with one [`Fault`]. What the
//! ECU did is read from the bus (EcuStatus modes as the actuator stubs received them), the
//! stubs' report (what they acted on, what they rejected and why) and the ECU's own report
//! (its counters, rejections by reason, overruns). Every case is checked for:
//!
//! * the processes survived (no crash, no hang, clean exit on SIGTERM);
//! * **no command lost**: every command the ECU sent with its authenticator
//!   (`secoc_commands_tx`) was authenticated by the stubs — except, in attack cases, at most
//!   one genuine command per attacker frame that passed E2E (an injected command with a valid
//!   CRC and counter displaces the genuine one it collides with: a denial of that frame,
//!   never a wrong actuation; the cyclic resend restores the state);
//! * **nothing wrongly acted on**: the stubs never authenticated more commands than the ECU
//!   sent, and the airbag fired exactly when the scenario says it must;
//! * the fault-specific reaction: degraded (ReferenceFallback) within the documented time
//!   after the fault began and back to Normal after it ended, with the rejection reason the
//!   fault should produce; or the documented start-up fallback.
//!
//! Time limits carry an allowance only where the route's timing is emulated (QEMU TCG:
//! [`crate::Allowances`], named in the report). Deadline misses are reported as overruns
//! relative to the baseline run; under emulation they measure the emulator, and the report
//! says so.

mod judge;
mod report;

pub use judge::judge;
pub use report::report_text;

use crate::{Disturbance, RunConfig, RunCtx, RunResult, SideProcess};
use anyhow::{bail, Context, Result};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::Duration;

/// The crash scenario most cases disturb (the demo's case), run with [`CRASH_LEAD_S`] more
/// approach: contact at ≈ 4.19 s instead of 1.69 s.
pub const CRASH_SCENARIO: &str = "taurus-48-48-abs";
/// Extra steady approach of the crash scenario in the campaign (see [`lengthened_scenario`]).
pub const CRASH_LEAD_S: f64 = 2.5;
/// The scenario in which nothing may fire (a 15 + 15 km/h bump).
pub const QUIET_SCENARIO: &str = "low-speed-no-fire";

/// Fault window of the pre-crash faults, scenario seconds: late enough that the ECU is Normal
/// when it begins (a TCG guest on host time, `VCAN_GUEST_ICOUNT=0`, brought it there only
/// ≈ 1.0 s after the start under load: with the window at 1.0 s, 4 of 27 cases of one
/// clean-clone run missed that precondition; in virtual time it is Normal after ≈ 20 ms), early
/// enough that the documented recovery (E2E hold 500 ms; a restarted feed is back ≈ 1.2 s after
/// its restart on host time, 41 ms in virtual time, measured) completes before the pre-crash
/// phase (≈ 3.9 s with [`CRASH_LEAD_S`]).
const FAULT_FROM_S: f64 = 1.5;
const FAULT_TO_S: f64 = 1.8;
/// Delay of the `delay` mirror's copies, ms.
const DELAY_MS: f64 = 200.0;

/// What is done to a run.
#[derive(Clone, Debug, PartialEq)]
pub enum Fault {
    /// Nothing: the reference for the others.
    None,
    /// `sensor-feeds` SIGKILLed at `kill_s` and restarted at `restart_s` on the same time base.
    FeedsKilled {
        /// Kill time [scenario s].
        kill_s: f64,
        /// Restart time [scenario s].
        restart_s: f64,
    },
    /// The object list keeps repeating its last sample (old timestamp) in the window.
    StaleObjects {
        /// Window start [scenario s].
        from_s: f64,
        /// Window end [scenario s].
        to_s: f64,
    },
    /// `bus-inject mirror --mode …` on EgoVehicleState in the window.
    Bus {
        /// `crc` | `counter` | `replay` | `delay`.
        mode: &'static str,
        /// Window start [scenario s].
        from_s: f64,
        /// Window end [scenario s].
        to_s: f64,
    },
    /// `cangen` at full rate, random ids, lengths and data, for the whole scenario.
    Flood,
    /// The ECU is started with a damaged characteristic diagram.
    Lut {
        /// true: truncated to half; false: one byte in the middle flipped.
        truncated: bool,
    },
    /// An ECU and feeds on the same iceoryx2 services are SIGKILLed before the run.
    StaleService,
    /// `cansend` of forged Armed+Fire commands (valid E2E, every alive counter) each followed
    /// by a guessed authenticator.
    ForgedFire {
        /// Command + authenticator pairs sent.
        pairs: u32,
    },
    /// `cansend` of the genuine Fire command + authenticator recorded on the bus in the
    /// baseline crash run (an earlier session), replayed into a run where nothing may fire.
    ReplayedFire {
        /// Replays of the recorded pair.
        pairs: u32,
    },
    /// The scenario itself is changed (a sensor that misreports, fails or goes silent; issue
    /// 14): [`variant_scenario`] writes the variant, with the `[expect]` it must meet.
    Variant(Variant),
}

/// What a [`Fault::Variant`] changes in the played scenario.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Variant {
    /// The scenario as it is (a library case of its own).
    AsIs,
    /// The opponent truly `true_kg` (class by mass), reported as `reported_kg`.
    MassMisreport {
        /// True mass [kg].
        true_kg: f64,
        /// Reported mass [kg].
        reported_kg: f64,
    },
    /// The closing speed reported with this systematic error [m/s].
    SpeedBias {
        /// Bias [m/s].
        mps: f64,
    },
    /// The crash accelerometer silent from `before_contact_s` before the true contact on.
    AccelDead {
        /// Lead [s].
        before_contact_s: f64,
    },
    /// The crash accelerometer stuck at its reading from `before_contact_s` before contact on.
    AccelStuck {
        /// Lead [s].
        before_contact_s: f64,
    },
    /// The feed `target` (`object`, `vehicle`, `occupant`) silent from `from_s` to the end.
    Dropout {
        /// Scenario dropout target.
        target: &'static str,
        /// Start [scenario s].
        from_s: f64,
    },
    /// The object list stuck (last sample repeated) from `from_s` to the end.
    Frozen {
        /// Start [scenario s].
        from_s: f64,
    },
}

/// One case of the campaign.
#[derive(Clone, Debug)]
pub struct Case {
    /// Short name (output folder).
    pub name: &'static str,
    /// Scenario file stem in `scenarios/`.
    pub scenario: &'static str,
    /// The fault.
    pub fault: Fault,
    /// What the fault is, in words.
    pub what: &'static str,
}

/// The campaign: the baseline first (the replay case needs its recording).
pub fn cases() -> Vec<Case> {
    let (from_s, to_s) = (FAULT_FROM_S, FAULT_TO_S);
    let mut v = vec![
        Case {
            name: "baseline",
            scenario: CRASH_SCENARIO,
            fault: Fault::None,
            what: "no fault (reference run)",
        },
        Case {
            name: "feeds-killed",
            scenario: CRASH_SCENARIO,
            fault: Fault::FeedsKilled {
                kill_s: from_s,
                restart_s: to_s,
            },
            what: "sensor-feeds SIGKILLed at 1.5 s, restarted at 1.8 s",
        },
        Case {
            name: "stale-objects",
            scenario: CRASH_SCENARIO,
            fault: Fault::StaleObjects { from_s, to_s },
            what: "object list stuck 1.5–1.8 s (last sample repeated, old timestamp)",
        },
        Case {
            name: "can-crc",
            scenario: CRASH_SCENARIO,
            fault: Fault::Bus {
                mode: "crc",
                from_s,
                to_s,
            },
            what: "a corrupted-CRC copy after every EgoVehicleState, 1.5–1.8 s",
        },
        Case {
            name: "can-counter",
            scenario: CRASH_SCENARIO,
            fault: Fault::Bus {
                mode: "counter",
                from_s,
                to_s,
            },
            what: "a copy with the alive counter +5 (valid CRC) after every EgoVehicleState, 1.5–1.8 s",
        },
        Case {
            name: "can-replay",
            scenario: CRASH_SCENARIO,
            fault: Fault::Bus {
                mode: "replay",
                from_s,
                to_s,
            },
            what: "every EgoVehicleState replayed at once, 1.5–1.8 s",
        },
        Case {
            name: "can-delay",
            scenario: CRASH_SCENARIO,
            fault: Fault::Bus {
                mode: "delay",
                from_s,
                to_s,
            },
            what: "every EgoVehicleState of 1.5–1.8 s sent again 200 ms late",
        },
        Case {
            name: "cangen-flood",
            scenario: CRASH_SCENARIO,
            fault: Fault::Flood,
            what: "cangen at full rate on idle CPU time (random ids, lengths, data) for the whole scenario",
        },
        Case {
            name: "lut-corrupt",
            scenario: CRASH_SCENARIO,
            fault: Fault::Lut { truncated: false },
            what: "ECU started with a LUT file with one byte flipped",
        },
        Case {
            name: "lut-truncated",
            scenario: CRASH_SCENARIO,
            fault: Fault::Lut { truncated: true },
            what: "ECU started with a LUT file cut in half",
        },
        Case {
            name: "stale-service",
            scenario: CRASH_SCENARIO,
            fault: Fault::StaleService,
            what: "an ECU and feeds on the same iceoryx2 services SIGKILLed before the run",
        },
        Case {
            name: "forged-fire",
            scenario: QUIET_SCENARIO,
            fault: Fault::ForgedFire { pairs: 32 },
            what: "32 forged Armed+Fire commands (valid E2E, every counter) + guessed authenticators via cansend",
        },
        Case {
            name: "replayed-fire",
            scenario: QUIET_SCENARIO,
            fault: Fault::ReplayedFire { pairs: 32 },
            what: "the baseline run's genuine Fire command + authenticator replayed 32 times via cansend",
        },
    ];
    v.extend(crash_phase_cases());
    v
}

/// Issue 14's cases: the crash with a misreported opponent or closing speed and with a dead or
/// stuck accelerometer (the airbag fires, never worse than the reference restraint; the
/// accelerometer fault is on the bus before the crash), and the 15 + 15 km/h bump and a slow
/// barrier with every kind of degraded input (nothing fires).
fn crash_phase_cases() -> Vec<Case> {
    let v = |name, scenario, variant, what| Case {
        name,
        scenario,
        fault: Fault::Variant(variant),
        what,
    };
    vec![
        v(
            "mass-underestimated",
            CRASH_SCENARIO,
            Variant::MassMisreport {
                true_kg: 2500.0,
                reported_kg: 1300.0,
            },
            "opponent 2500 kg reported as 1300 kg (−1200 kg, 4 σ)",
        ),
        v(
            "mass-overestimated",
            CRASH_SCENARIO,
            Variant::MassMisreport {
                true_kg: 1300.0,
                reported_kg: 2500.0,
            },
            "opponent 1300 kg reported as 2500 kg (+1200 kg)",
        ),
        v(
            "speed-underestimated",
            CRASH_SCENARIO,
            Variant::SpeedBias { mps: -5.0 },
            "closing speed reported 5 m/s too low",
        ),
        v(
            "speed-overestimated",
            CRASH_SCENARIO,
            Variant::SpeedBias { mps: 5.0 },
            "closing speed reported 5 m/s too high",
        ),
        v(
            "accel-dead",
            CRASH_SCENARIO,
            Variant::AccelDead {
                before_contact_s: 0.6,
            },
            "crash accelerometer silent from 0.6 s before contact",
        ),
        v(
            "accel-stuck",
            CRASH_SCENARIO,
            Variant::AccelStuck {
                before_contact_s: 0.6,
            },
            "crash accelerometer stuck at its reading from 0.6 s before contact",
        ),
        v(
            "bump-objects-dead",
            QUIET_SCENARIO,
            Variant::Dropout {
                target: "object",
                from_s: 0.5,
            },
            "15 + 15 km/h bump, object list silent from 0.5 s",
        ),
        v(
            "bump-objects-stuck",
            QUIET_SCENARIO,
            Variant::Frozen { from_s: 0.5 },
            "15 + 15 km/h bump, object list stuck from 0.5 s",
        ),
        v(
            "bump-vehicle-dead",
            QUIET_SCENARIO,
            Variant::Dropout {
                target: "vehicle",
                from_s: 0.5,
            },
            "15 + 15 km/h bump, EgoVehicleState silent from 0.5 s",
        ),
        v(
            "bump-occupant-dead",
            QUIET_SCENARIO,
            Variant::Dropout {
                target: "occupant",
                from_s: 0.5,
            },
            "15 + 15 km/h bump, OccupantClassification silent from 0.5 s",
        ),
        v(
            "bump-accel-dead",
            QUIET_SCENARIO,
            Variant::AccelDead {
                before_contact_s: 0.6,
            },
            "15 + 15 km/h bump, crash accelerometer silent from 0.6 s before contact",
        ),
        Case {
            name: "bump-e2e-burst",
            scenario: QUIET_SCENARIO,
            fault: Fault::Bus {
                mode: "crc",
                from_s: 1.2,
                to_s: 1.55,
            },
            what: "15 + 15 km/h bump, a corrupted-CRC copy after every EgoVehicleState 1.2–1.55 s (over the contact at 1.5 s)",
        },
        Case {
            name: "bump-lut-corrupt",
            scenario: QUIET_SCENARIO,
            fault: Fault::Lut { truncated: false },
            what: "15 + 15 km/h bump, ECU started with a LUT file with one byte flipped",
        },
        v(
            "slow-barrier-objects-dead",
            "barrier-16-objects-dead",
            Variant::AsIs,
            "16 km/h rigid barrier, object list silent from 0.5 s",
        ),
        // Issue 30 item 5: misuse and safing cases on the real bench, judged like every case.
        v(
            "misuse-pothole",
            "misuse-pothole",
            Variant::AsIs,
            "pothole at 50 km/h, nothing ahead: nothing may fire",
        ),
        v(
            "misuse-kerb-at-predicted-contact",
            "misuse-kerb-strike-at-predicted-contact",
            Variant::AsIs,
            "50 + 50 km/h, the opponent swerves out 1 ms before the predicted contact while the car strikes a kerb: no airbag",
        ),
        v(
            "misuse-rough-road",
            "misuse-rough-road",
            Variant::AsIs,
            "3 s of 2 g rms rough road at 50 km/h: nothing may fire",
        ),
        v(
            "crash-sensor-spike-then-bump",
            "fault-crash-sensor-spike",
            Variant::AsIs,
            "a 40 g crash-sensor spike, then a 4.5 g × 40 ms bump: nothing may fire",
        ),
        v(
            "safing-sensor-dead-in-a-crash",
            "fault-safing-sensor-dead",
            Variant::AsIs,
            "48 + 48 km/h with the safing accelerometer silent from 0.5 s: the crash still fires",
        ),
    ]
}

/// Where and how the campaign runs.
#[derive(Clone, Debug)]
pub struct CampaignConfig {
    /// Output root (each case writes `out/<case>/<scenario>/`).
    pub out: PathBuf,
    /// CAN interface.
    pub can: String,
    /// Folder of the bench binaries (ecu, sensor-feeds, actuator-stubs, bus-inject).
    pub bin_dir: PathBuf,
    /// Repository root.
    pub repo: PathBuf,
    /// Extra ECU arguments for every case.
    pub ecu_args: Vec<String>,
}

/// One check of a case.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Check {
    /// What is checked.
    pub what: String,
    /// Passed.
    pub ok: bool,
    /// Measured value / reason.
    pub detail: String,
    /// A timing check (a time limit, not a function): where the route's timing is emulated a
    /// case that fails only timing checks is run again ([`crate::Allowances`]).
    #[serde(default)]
    pub timing: bool,
}

/// What one case showed.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct CaseResult {
    /// Case name.
    pub name: String,
    /// Scenario.
    pub scenario: String,
    /// The fault, in words.
    pub fault: String,
    /// What the ECU did, in words.
    pub reaction: String,
    /// EcuStatus mode changes as received: (scenario ms, mode).
    pub ecu_modes: Vec<(f64, String)>,
    /// ReferenceFallback this long after the fault began [ms].
    pub degraded_after_ms: Option<f64>,
    /// Normal again this long after the fault ended [ms].
    pub recovered_after_ms: Option<f64>,
    /// Airbag fired.
    pub airbag_fired: bool,
    /// Source of the fire command ("adaptive" / "reference").
    pub airbag_source: Option<String>,
    /// Fire command received this long after its planned time [ms].
    pub airbag_late_ms: Option<f64>,
    /// Commands the ECU sent with an authenticator.
    pub commands_sent: u64,
    /// Commands the stubs authenticated (the only ones they acted on).
    pub commands_authenticated: u64,
    /// Genuine commands not acted on (sent − authenticated, ≥ 0).
    pub commands_lost: u64,
    /// Of those, displaced by attacker frames that passed E2E (attack cases only).
    pub commands_denied_by_attack: u64,
    /// Genuine commands refused as stale because they arrived late (see `judge`; also counted
    /// in `commands_lost`).
    #[serde(default)]
    pub commands_late: u64,
    /// Frames the attacker/faulty node put on the bus (0 when not counted).
    pub frames_injected: u64,
    /// Rejections by the ECU (`ecu:`) and the stubs (`stubs:e2e:`, `stubs:secoc:`) by reason.
    pub frames_rejected: BTreeMap<String, u64>,
    /// ECU cycles and overruns.
    pub cycles: u64,
    /// Overruns (deadline misses) of the ECU.
    pub overruns: u64,
    /// Checks.
    pub checks: Vec<Check>,
    /// All checks passed.
    pub pass: bool,
    /// Runs it took (> 1: the earlier ones failed only time limits under emulated timing).
    #[serde(default)]
    pub attempts: u32,
    /// What the earlier runs missed ("run N: check: detail; …"), one entry per earlier run.
    #[serde(default)]
    pub earlier_runs: Vec<String>,
    /// Output folder.
    pub dir: String,
    /// True contact [scenario s] (None: no contact).
    #[serde(default)]
    pub contact_s: Option<f64>,
    /// Airbag fire command received [scenario s].
    #[serde(default)]
    pub fire_s: Option<f64>,
    /// The fault's extent as measured [scenario s] (window faults only).
    #[serde(default)]
    pub fault_s: Option<(f64, f64)>,
    /// Scenario duration [s].
    #[serde(default)]
    pub duration_s: f64,
}

/// Fuzzing figures (tests/fuzz-smoke.sh FUZZ_REPORT_JSON).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct FuzzTarget {
    /// Target name.
    pub target: String,
    /// Inputs executed.
    pub execs: u64,
    /// Wall time [ms].
    pub time_ms: u64,
    /// Clean (no crash, hang, OOM).
    pub ok: bool,
}

/// The whole campaign.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct Campaign {
    /// The vcan route the campaign ran on.
    pub route: crate::Route,
    /// The allowances in force on that route, each with its reason (empty: none).
    pub allowances: Vec<String>,
    /// What the timing depended on besides the route ([`crate::Route::conditions`]: the host's
    /// load at the start, QEMU's scheduling).
    #[serde(default)]
    pub conditions: String,
    /// Cases.
    pub cases: Vec<CaseResult>,
}

/// Runs every case (or those named in `only`), the baseline always first.
pub fn run_campaign(cfg: &CampaignConfig, only: &[String]) -> Result<Campaign> {
    let route = crate::Route::current();
    let allow = route.allowances();
    let mut out = Campaign {
        route,
        allowances: allow.named(),
        conditions: crate::Route::conditions(),
        cases: Vec::new(),
    };
    let all = cases();
    let mut baseline: Option<(RunResult, CaseResult)> = None;
    for (i, case) in all.iter().enumerate() {
        let wanted = only.is_empty() || only.iter().any(|n| n == case.name);
        let needs_baseline =
            matches!(case.fault, Fault::None) || (wanted && !only.is_empty() && baseline.is_none());
        if !wanted && !needs_baseline {
            continue;
        }
        eprintln!(
            "fault-campaign: [{}/{}] {} — {}",
            i + 1,
            all.len(),
            case.name,
            case.what
        );
        let (mut run, mut result) = run_case(cfg, case, i, baseline.as_ref().map(|b| &b.0))?;
        let mut attempts = 1;
        let mut earlier = Vec::new();
        while attempts < allow.time_limit_attempts
            && !result.pass
            && result.checks.iter().all(|c| c.ok || c.timing)
        {
            let missed: Vec<String> = result
                .checks
                .iter()
                .filter(|c| !c.ok)
                .map(|c| format!("{}: {}", c.what, c.detail))
                .collect();
            eprintln!(
                "fault-campaign: {}: only time limits failed ({}: {}): {}; running it again",
                case.name,
                route.name(),
                route.describe(),
                missed.join("; ")
            );
            earlier.push(format!("run {attempts}: {}", missed.join("; ")));
            (run, result) = run_case(cfg, case, i, baseline.as_ref().map(|b| &b.0))?;
            attempts += 1;
        }
        result.attempts = attempts;
        result.earlier_runs = earlier;
        eprintln!(
            "fault-campaign: {}: {}",
            case.name,
            if result.pass { "PASS" } else { "FAIL" }
        );
        if matches!(case.fault, Fault::None) {
            baseline = Some((run, result.clone()));
        }
        if wanted || matches!(case.fault, Fault::None) {
            out.cases.push(result);
        }
    }
    Ok(out)
}

/// The campaigns of guests that ran side by side (each on a share of the cases, each with its
/// own baseline, which its cases are judged against) as one: every case once, in the order of
/// [`cases`]; the baseline shown is the first guest's, or the first that failed. Route,
/// allowances and conditions are the first guest's (the guests differ only in their cases).
pub fn merge_campaigns(parts: Vec<Campaign>) -> Campaign {
    let all = cases();
    let mut parts = parts.into_iter();
    let Some(mut merged) = parts.next() else {
        return Campaign::default();
    };
    for part in parts {
        for case in part.cases {
            let is_baseline = all
                .iter()
                .any(|k| k.name == case.name && k.fault == Fault::None);
            match merged.cases.iter_mut().find(|c| c.name == case.name) {
                Some(kept) if is_baseline && kept.pass && !case.pass => *kept = case,
                Some(_) => {}
                None => merged.cases.push(case),
            }
        }
    }
    let order = |name: &str| all.iter().position(|k| k.name == name);
    merged.cases.sort_by_key(|c| order(&c.name));
    merged
}

fn scenario_path(cfg: &CampaignConfig, stem: &str) -> PathBuf {
    cfg.repo.join("scenarios").join(format!("{stem}.toml"))
}

/// The disturbance of one case.
pub(crate) struct CaseDisturbance<'a> {
    pub(crate) fault: &'a Fault,
    /// cansend arguments (forged or recorded frames) for the attack cases.
    pub(crate) frames: Vec<String>,
}

fn spawn_piped(cmd: &mut Command, what: &str) -> Result<Child> {
    cmd.stdout(Stdio::piped())
        .stderr(Stdio::inherit())
        .spawn()
        .with_context(|| format!("starting {what}"))
}

impl Disturbance for CaseDisturbance<'_> {
    fn prepare(&mut self, run: &RunConfig, _dir: &Path) -> Result<()> {
        if *self.fault != Fault::StaleService {
            return Ok(());
        }
        // An ECU and feeds on this run's services, killed without a chance to clean up.
        let mut ecu = Command::new(run.bin_dir.join("ecu"))
            .args([
                "--no-can",
                "--quiet",
                "--service-prefix",
                &run.service_prefix,
            ])
            .args(["--node-name", "stale-ecu"])
            .current_dir(&run.ecu_cwd)
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .context("starting the ECU to be killed")?;
        let mut feeds = Command::new(run.bin_dir.join("sensor-feeds"))
            .arg("--scenario")
            .arg(&run.scenario)
            .args(["--no-can", "--service-prefix", &run.service_prefix])
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .context("starting the feeds to be killed")?;
        std::thread::sleep(Duration::from_millis(700));
        for (c, what) in [(&mut ecu, "ecu"), (&mut feeds, "sensor-feeds")] {
            match c.try_wait()? {
                None => {
                    c.kill()?; // SIGKILL
                    c.wait()?;
                }
                Some(st) => bail!("the {what} to be killed had already exited ({st})"),
            }
        }
        Ok(())
    }

    fn start(&mut self, ctx: &RunCtx) -> Result<Vec<SideProcess>> {
        let can = &ctx.cfg.can;
        match self.fault {
            Fault::Bus { mode, from_s, to_s } => {
                let child = spawn_piped(
                    Command::new(ctx.bin("bus-inject"))
                        .args(["mirror", "--can", can, "--mode", mode, "--message"])
                        .arg(
                            bus::message_info(bus::EgoVehicleState::RAW_ID).map_or("?", |m| m.name),
                        )
                        .arg("--epoch-ns")
                        .arg(ctx.epoch_ns.to_string())
                        .arg("--from-s")
                        .arg(from_s.to_string())
                        .arg("--to-s")
                        .arg(to_s.to_string())
                        .arg("--delay-ms")
                        .arg(DELAY_MS.to_string()),
                    "bus-inject",
                )?;
                Ok(vec![SideProcess {
                    name: "bus-inject".to_owned(),
                    child,
                    until_stopped: false,
                }])
            }
            Fault::Flood => {
                // Full rate, but only on CPU time nobody else wants (SCHED_IDLE): the flood
                // stands for another node on the bus, with a CPU of its own, not for a process
                // that takes the bench's CPU. At nice 19 it still starved the feeds of a loaded
                // TCG guest for seconds (no accelerometer over the crash, so nothing could
                // fire: 4 of 5 runs in one campaign).
                let child = Command::new("chrt")
                    .args(["--idle", "0", "cangen", can.as_str()])
                    .args(["-g", "0", "-I", "r", "-L", "r", "-D", "r"])
                    .stdout(Stdio::piped())
                    .stderr(Stdio::null())
                    .spawn()
                    .context("starting cangen (can-utils)")?;
                Ok(vec![SideProcess {
                    name: "cangen".to_owned(),
                    child,
                    until_stopped: true,
                }])
            }
            Fault::ForgedFire { .. } | Fault::ReplayedFire { .. } => {
                // Real cansend, one process per frame, pairs 5 ms apart from t = 0.5 s.
                let wait_s = (ctx.epoch_ns as f64 - sensor_feeds::monotonic_ns() as f64).max(0.0)
                    * 1e-9
                    + 0.5;
                let mut script = format!("sleep {wait_s:.3}\n");
                for pair in self.frames.chunks(2) {
                    for f in pair {
                        let _ = writeln!(script, "cansend {can} {f} && echo sent");
                    }
                    script.push_str("sleep 0.005\n");
                }
                let child =
                    spawn_piped(Command::new("sh").args(["-c", &script]), "cansend script")?;
                Ok(vec![SideProcess {
                    name: "cansend".to_owned(),
                    child,
                    until_stopped: false,
                }])
            }
            _ => Ok(Vec::new()),
        }
    }

    fn feeds_running(
        &mut self,
        ctx: &RunCtx,
        feeds: &mut Child,
    ) -> Result<std::process::ExitStatus> {
        let Fault::FeedsKilled { kill_s, restart_s } = *self.fault else {
            return feeds.wait().context("waiting for sensor-feeds");
        };
        ctx.sleep_until_s(kill_s);
        if let Some(st) = feeds.try_wait()? {
            bail!("sensor-feeds ended ({st}) before it could be killed");
        }
        feeds.kill()?; // SIGKILL: no clean-up, a stale iceoryx2 node is left behind
        feeds.wait()?;
        ctx.sleep_until_s(restart_s);
        // Same time base: the restarted feeds resume at the current scenario time. They are
        // back once they announce the epoch (iceoryx2 set-up and the true-crash
        // pre-computation: 41 ms after the restart in the TCG guest in virtual time, ≈ 1.2 s on
        // host time); recovery is measured from then.
        let mut again = ctx
            .feeds_command()
            .stdout(Stdio::piped())
            .spawn()
            .context("restarting sensor-feeds")?;
        let resumed = crate::read_epoch(&mut again)
            .map(|_| sensor_feeds::monotonic_ns().saturating_sub(ctx.epoch_ns) as f64 * 1e-9);
        if let Ok(t_s) = resumed {
            std::fs::write(
                ctx.dir.join("feeds-restart.json"),
                format!("{{\"resumed_s\": {t_s:.4}}}"),
            )?;
        }
        again
            .wait()
            .context("waiting for the restarted sensor-feeds")
    }
}

/// The damaged LUT file for a case.
fn damaged_lut(repo: &Path, dir: &Path, truncated: bool) -> Result<PathBuf> {
    let src = repo.join("data/default.lut");
    let mut bytes = std::fs::read(&src).with_context(|| format!("reading {}", src.display()))?;
    let mid = bytes.len() / 2;
    if truncated {
        bytes.truncate(mid);
    } else if let Some(b) = bytes.get_mut(mid) {
        *b ^= 0x10;
    }
    std::fs::create_dir_all(dir)?;
    let path = dir.join(if truncated {
        "truncated.lut"
    } else {
        "corrupt.lut"
    });
    std::fs::write(&path, bytes)?;
    Ok(path)
}

/// The stale-objects variant of a scenario (adds a `freezes` window), written to `dir`.
pub(crate) fn frozen_scenario(src: &Path, dir: &Path, from_s: f64, to_s: f64) -> Result<PathBuf> {
    let text =
        std::fs::read_to_string(src).with_context(|| format!("reading {}", src.display()))?;
    let mut doc: toml::Table = text.parse().context("scenario TOML")?;
    let sensor = doc
        .entry("sensor")
        .or_insert_with(|| toml::Value::Table(toml::Table::new()));
    let Some(sensor) = sensor.as_table_mut() else {
        bail!("[sensor] is not a table");
    };
    let mut w = toml::Table::new();
    w.insert("start_s".into(), toml::Value::Float(from_s));
    w.insert("end_s".into(), toml::Value::Float(to_s));
    sensor.insert(
        "freezes".into(),
        toml::Value::Array(vec![toml::Value::Table(w)]),
    );
    std::fs::create_dir_all(dir)?;
    let path = dir.join(src.file_name().context("scenario file name")?);
    std::fs::write(&path, toml::to_string(&doc)?)?;
    Ok(path)
}

/// The variant of a scenario a [`Fault::Variant`] plays, written to `dir`, with the `[expect]`
/// it must meet: a misreported crash still fires (no worse than the reference restraint, the
/// judge checks); a dead or stuck accelerometer is on the bus before the contact and the
/// crash gets the reference restraint; every other variant keeps the base's expectations.
pub fn variant_scenario(src: &Path, dir: &Path, v: Variant) -> Result<PathBuf> {
    let base = sensor_feeds::Scenario::load(src).map_err(|e| anyhow::anyhow!("{e}"))?;
    let contact_s = sensor_feeds::Truth::new(&base)
        .map_err(|e| anyhow::anyhow!("{e}"))?
        .contact_s;
    let text =
        std::fs::read_to_string(src).with_context(|| format!("reading {}", src.display()))?;
    let mut doc: toml::Table = text.parse().context("scenario TOML")?;
    let table = |doc: &mut toml::Table, name: &str| -> Result<toml::Table> {
        match doc.remove(name) {
            Some(toml::Value::Table(t)) => Ok(t),
            None => Ok(toml::Table::new()),
            Some(_) => bail!("[{name}] is not a table"),
        }
    };
    let mut sensor = table(&mut doc, "sensor")?;
    let mut expect = table(&mut doc, "expect")?;
    let window = |start_s: f64, extra: Option<(&str, &str)>| {
        let mut w = toml::Table::new();
        w.insert("start_s".into(), toml::Value::Float(start_s));
        w.insert("end_s".into(), toml::Value::Float(1000.0));
        if let Some((k, val)) = extra {
            w.insert(k.into(), toml::Value::String(val.into()));
        }
        toml::Value::Array(vec![toml::Value::Table(w)])
    };
    let before_contact = |lead_s: f64| -> Result<f64> {
        Ok((contact_s.context("the variant needs a contact")? - lead_s).max(0.0))
    };
    match v {
        Variant::AsIs => {}
        Variant::MassMisreport {
            true_kg,
            reported_kg,
        } => {
            let mut opp = table(&mut doc, "opponent")?;
            opp.insert("mass_kg".into(), toml::Value::Float(true_kg));
            opp.remove("class");
            doc.insert("opponent".into(), toml::Value::Table(opp));
            sensor.insert("mass_estimate_kg".into(), toml::Value::Float(reported_kg));
        }
        Variant::SpeedBias { mps } => {
            sensor.insert("speed_bias_mps".into(), toml::Value::Float(mps));
            // A bias that takes the prediction beyond the table gives no pre-crash preset.
            expect.remove("pretensioner_before_contact");
        }
        Variant::AccelDead { before_contact_s } => {
            let from = before_contact(before_contact_s)?;
            sensor.insert("dropouts".into(), window(from, Some(("target", "accel"))));
        }
        Variant::AccelStuck { before_contact_s } => {
            let from = before_contact(before_contact_s)?;
            sensor.insert("accel_faults".into(), window(from, Some(("kind", "stuck"))));
        }
        Variant::Dropout { target, from_s } => {
            sensor.insert("dropouts".into(), window(from_s, Some(("target", target))));
            expect.insert("reference_fallback".into(), toml::Value::Boolean(true));
        }
        Variant::Frozen { from_s } => {
            sensor.insert("freezes".into(), window(from_s, None));
            expect.insert("reference_fallback".into(), toml::Value::Boolean(true));
        }
    }
    if matches!(v, Variant::AccelDead { .. } | Variant::AccelStuck { .. }) {
        expect.insert(
            "accel_fault_before_contact".into(),
            toml::Value::Boolean(true),
        );
        expect.remove("pretensioner_before_contact");
        if expect.get("airbag_fires") == Some(&toml::Value::Boolean(true)) {
            expect.insert("reference_fallback".into(), toml::Value::Boolean(true));
        }
    }
    doc.insert("sensor".into(), toml::Value::Table(sensor));
    doc.insert("expect".into(), toml::Value::Table(expect));
    std::fs::create_dir_all(dir)?;
    let path = dir.join(src.file_name().context("scenario file name")?);
    std::fs::write(&path, toml::to_string(&doc)?)?;
    Ok(path)
}

/// A number from a TOML table (integers are numbers too).
fn toml_f64(t: &toml::Table, key: &str) -> Option<f64> {
    match t.get(key)? {
        toml::Value::Float(f) => Some(*f),
        toml::Value::Integer(i) => Some(*i as f64),
        _ => None,
    }
}

/// The scenario with `extra_s` more of steady approach before everything happens: longer
/// duration, braking `extra_s` later, the opponent further away by `extra_s` × closing speed —
/// the same crash at `extra_s` later. In a TCG guest on host time a restarted feed is back
/// ≈ 1.2 s after its restart (measured; emulated CPUs; 41 ms in virtual time), so it needs
/// this head room to be back before the pre-crash phase on either clock.
pub fn lengthened_scenario(src: &Path, dir: &Path, extra_s: f64) -> Result<PathBuf> {
    let text =
        std::fs::read_to_string(src).with_context(|| format!("reading {}", src.display()))?;
    let mut doc: toml::Table = text.parse().context("scenario TOML")?;
    let speed = |doc: &toml::Table, part: &str| {
        doc.get(part)
            .and_then(toml::Value::as_table)
            .and_then(|t| toml_f64(t, "speed_kph"))
            .with_context(|| format!("[{part}] speed_kph"))
    };
    let closing_mps = (speed(&doc, "ego")? + speed(&doc, "opponent")?) / 3.6;
    let duration_s = toml_f64(&doc, "duration_s").context("duration_s")?;
    doc.insert(
        "duration_s".into(),
        toml::Value::Float(duration_s + extra_s),
    );
    for part in ["ego", "opponent"] {
        let Some(t) = doc.get_mut(part).and_then(toml::Value::as_table_mut) else {
            bail!("[{part}] missing");
        };
        if let Some(b) = t.get_mut("braking").and_then(toml::Value::as_table_mut) {
            let start_s = toml_f64(b, "start_s").context("braking.start_s")?;
            b.insert("start_s".into(), toml::Value::Float(start_s + extra_s));
        }
        if part == "opponent" {
            let d = toml_f64(t, "initial_distance_m").context("opponent.initial_distance_m")?;
            t.insert(
                "initial_distance_m".into(),
                toml::Value::Float(d + extra_s * closing_mps),
            );
        }
    }
    std::fs::create_dir_all(dir)?;
    let path = dir.join(src.file_name().context("scenario file name")?);
    std::fs::write(&path, toml::to_string(&doc)?)?;
    Ok(path)
}

/// The first Fire command of a candump log and the authenticator after it, as cansend args.
pub fn recorded_fire_pair(candump_log: &Path) -> Result<(String, String)> {
    let log = bus::candump::CandumpLog::read(candump_log)
        .with_context(|| format!("reading {}", candump_log.display()))?;
    let mut fire: Option<&bus::RawFrame> = None;
    for f in log.frames.iter().map(|l| &l.frame) {
        match (f.id, fire) {
            (bus::AirbagStageCmd::RAW_ID, None) => {
                if let Ok(bus::Messages::AirbagStageCmd(m)) = bus::decode(f.id, f.payload()) {
                    if matches!(m.fire(), bus::codec::AirbagStageCmdFire::Fire) {
                        fire = Some(f);
                    }
                }
            }
            (bus::AirbagStageAuth::RAW_ID, Some(cmd)) => {
                return Ok((bus::candump::cansend_arg(cmd), bus::candump::cansend_arg(f)))
            }
            _ => {}
        }
    }
    bail!(
        "{}: no Fire command followed by its authenticator",
        candump_log.display()
    )
}

fn forged_frames(bin_dir: &Path, pairs: u32) -> Result<Vec<String>> {
    let mut v = Vec::new();
    for i in 0..pairs {
        let o = Command::new(bin_dir.join("bus-inject"))
            .args(["forge-fire", "--counter"])
            .arg((i % 16).to_string())
            .arg("--freshness")
            .arg((i + 1).to_string())
            .arg("--mac")
            .arg((0x005A_5A5A_5A00_u64 + u64::from(i)).to_string())
            .output()
            .context("bus-inject forge-fire")?;
        if !o.status.success() {
            bail!("bus-inject forge-fire failed");
        }
        v.extend(
            String::from_utf8_lossy(&o.stdout)
                .split_whitespace()
                .map(str::to_owned),
        );
    }
    Ok(v)
}

fn run_case(
    cfg: &CampaignConfig,
    case: &Case,
    index: usize,
    baseline: Option<&RunResult>,
) -> Result<(RunResult, CaseResult)> {
    let out = cfg.out.join(case.name);
    let _ = std::fs::remove_dir_all(&out);
    let mut scenario = scenario_path(cfg, case.scenario);
    if case.scenario == CRASH_SCENARIO {
        scenario = lengthened_scenario(&scenario, &out.join("scenario"), CRASH_LEAD_S)?;
    }
    let mut ecu_args = cfg.ecu_args.clone();
    let mut frames = Vec::new();
    match &case.fault {
        Fault::StaleObjects { from_s, to_s } => {
            scenario = frozen_scenario(&scenario, &out.join("scenario"), *from_s, *to_s)?;
        }
        Fault::Lut { truncated } => {
            let lut = damaged_lut(&cfg.repo, &out.join("lut"), *truncated)?;
            ecu_args.push("--lut".to_owned());
            ecu_args.push(lut.display().to_string());
        }
        Fault::Variant(v) => {
            scenario = variant_scenario(&scenario, &out.join("scenario"), *v)?;
        }
        Fault::ForgedFire { pairs } => frames = forged_frames(&cfg.bin_dir, *pairs)?,
        Fault::ReplayedFire { pairs } => {
            let base = baseline.context("the replay case needs the baseline's recording")?;
            let (cmd, auth) = recorded_fire_pair(&base.dir.join("candump.log"))?;
            for _ in 0..*pairs {
                frames.push(cmd.clone());
                frames.push(auth.clone());
            }
        }
        _ => {}
    }
    let run_cfg = RunConfig {
        scenario,
        out: out.clone(),
        can: cfg.can.clone(),
        bin_dir: cfg.bin_dir.clone(),
        service_prefix: format!("fault-{}-{index}", std::process::id()),
        ecu_args,
        ecu_cwd: cfg.repo.clone(),
        stubs_args: crate::default_stubs_args(),
    };
    let mut dist = CaseDisturbance {
        fault: &case.fault,
        frames,
    };
    let run = crate::run_disturbed(&run_cfg, &mut dist)?;
    let result = judge(case, &run, baseline);
    std::fs::write(
        run.dir.join("case.json"),
        serde_json::to_string_pretty(&result)?,
    )?;
    Ok((run, result))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn merged_guests_give_every_case_once_in_campaign_order_and_keep_a_failed_baseline() {
        let case = |name: &str, pass: bool| CaseResult {
            name: name.to_owned(),
            pass,
            ..CaseResult::default()
        };
        let names: Vec<&str> = cases().iter().map(|k| k.name).collect();
        let (base, rest) = names.split_first().expect("cases");
        // two guests, each with its own baseline and every other case
        let part = |k: usize, baseline_pass: bool| Campaign {
            conditions: format!("guest {k}"),
            cases: std::iter::once(case(base, baseline_pass))
                .chain(rest.iter().skip(k).step_by(2).map(|n| case(n, true)))
                .collect(),
            ..Campaign::default()
        };
        let m = merge_campaigns(vec![part(0, true), part(1, true)]);
        let got: Vec<&str> = m.cases.iter().map(|c| c.name.as_str()).collect();
        assert_eq!(got, names);
        assert_eq!(m.conditions, "guest 0");
        assert!(m.cases.iter().all(|c| c.pass));
        // the second guest's baseline failed: the merged campaign shows the failure
        let m = merge_campaigns(vec![part(0, true), part(1, false)]);
        assert_eq!(m.cases.len(), names.len());
        assert!(!m.cases[0].pass, "the failed baseline is kept");
        assert!(merge_campaigns(Vec::new()).cases.is_empty());
    }

    fn tmp(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("faults-test-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).expect("tmp dir");
        d
    }

    /// `ID#HEX` of an AirbagStageCmd with the given Fire bit and a valid CRC.
    fn airbag(fire: bool, counter: u8) -> String {
        let mut f = bus::encode_values(
            bus::AirbagStageCmd::RAW_ID,
            &[
                0.0,
                f64::from(counter),
                1.0,
                f64::from(u8::from(fire)),
                0.0,
                3.0,
                6.0,
                0.0,
            ],
        )
        .expect("encode");
        assert!(f.reseal());
        bus::candump::cansend_arg(&f)
    }

    #[test]
    fn the_recorded_fire_pair_is_the_first_fire_command_and_the_authenticator_after_it() {
        let d = tmp("candump");
        let (no_fire, fire, later_fire) = (airbag(false, 1), airbag(true, 2), airbag(true, 3));
        let log = format!(
            "(1.000000) vcan0 {no_fire}\n(1.000001) vcan0 031#0100000011223344\n\
             (1.010000) vcan0 0A0#0011223344556677\n(1.020000) vcan0 {fire}\n\
             (1.020001) vcan0 040#0000000000000000\n(1.020002) vcan0 031#0200000055667788\n\
             (1.030000) vcan0 {later_fire}\n(1.030001) vcan0 031#0300000099AABBCC\n"
        );
        std::fs::write(d.join("candump.log"), log).expect("write");
        let (cmd, auth) = recorded_fire_pair(&d.join("candump.log")).expect("pair");
        assert_eq!(cmd, fire);
        assert_eq!(auth, "031#0200000055667788");
        std::fs::write(d.join("none.log"), format!("(1.0) vcan0 {no_fire}\n")).expect("write");
        assert!(recorded_fire_pair(&d.join("none.log")).is_err());
    }

    #[test]
    fn the_frozen_scenario_is_the_original_plus_a_freeze_window() {
        let d = tmp("frozen");
        let src = crate::repo_root().join("scenarios/taurus-48-48-abs.toml");
        let p = frozen_scenario(&src, &d, 0.4, 0.7).expect("variant");
        let orig = sensor_feeds::Scenario::load(&src).expect("original");
        let s = sensor_feeds::Scenario::load(&p).expect("variant parses and validates");
        assert_eq!(s.name, orig.name);
        assert_eq!(s.duration_s, orig.duration_s);
        assert!(!s.sensor.frozen(0.39) && s.sensor.frozen(0.4) && !s.sensor.frozen(0.7));
        assert!(!orig.sensor.frozen(0.5));
    }

    #[test]
    fn scenario_variants_change_what_they_say_and_expect_what_they_must() {
        let d = tmp("variants");
        let src = crate::repo_root().join("scenarios/taurus-48-48-abs.toml");
        let load = |v| {
            let p = variant_scenario(&src, &d, v).expect("variant");
            sensor_feeds::Scenario::load(&p).expect("variant parses and validates")
        };
        let s = load(Variant::MassMisreport {
            true_kg: 2500.0,
            reported_kg: 1300.0,
        });
        assert_eq!(s.opponent.mass_kg, Some(2500.0));
        // Class by mass: 2500 kg is class 6 ([2500, …) kg).
        assert_eq!(s.opponent_class().map(|c| c.number()), Some(6));
        assert_eq!(s.sensor.mass_estimate_kg, Some(1300.0));
        assert_eq!(s.expect.airbag_fires, Some(true));
        let contact = sensor_feeds::Truth::new(&s).unwrap().contact_s.unwrap();
        let s = load(Variant::AccelDead {
            before_contact_s: 0.6,
        });
        assert!(s
            .sensor
            .dropped(sensor_feeds::scenario::DropoutTarget::Accel, contact - 0.59));
        assert!(!s
            .sensor
            .dropped(sensor_feeds::scenario::DropoutTarget::Accel, contact - 0.61));
        assert_eq!(s.expect.accel_fault_before_contact, Some(true));
        assert_eq!(s.expect.reference_fallback, Some(true));
        let s = load(Variant::AccelStuck {
            before_contact_s: 0.6,
        });
        assert!(s.sensor.accel_fault(contact).is_some());
        let s = load(Variant::SpeedBias { mps: -5.0 });
        assert_eq!(s.sensor.speed_bias_mps, -5.0);
        let quiet = crate::repo_root().join("scenarios/low-speed-no-fire.toml");
        let p = variant_scenario(
            &quiet,
            &d,
            Variant::Dropout {
                target: "vehicle",
                from_s: 0.5,
            },
        )
        .unwrap();
        let s = sensor_feeds::Scenario::load(&p).unwrap();
        assert!(s
            .sensor
            .dropped(sensor_feeds::scenario::DropoutTarget::Vehicle, 1.0));
        assert_eq!(s.expect.airbag_fires, Some(false));
        assert_eq!(s.expect.reference_fallback, Some(true));
    }

    #[test]
    fn the_case_descriptions_name_the_fault_window() {
        let window = format!("{FAULT_FROM_S:.1}–{FAULT_TO_S:.1} s");
        let killed = format!("at {FAULT_FROM_S:.1} s, restarted at {FAULT_TO_S:.1} s");
        for c in cases().into_iter().filter(|c| c.scenario == CRASH_SCENARIO) {
            match c.fault {
                Fault::StaleObjects { .. } | Fault::Bus { .. } => {
                    assert!(c.what.contains(&window), "{}: {}", c.name, c.what);
                }
                Fault::FeedsKilled { .. } => assert!(c.what.contains(&killed), "{}", c.what),
                _ => {}
            }
        }
    }

    #[test]
    fn the_lengthened_scenario_has_the_same_crash_later() {
        let d = tmp("long");
        let src = crate::repo_root().join("scenarios/taurus-48-48-abs.toml");
        let p = lengthened_scenario(&src, &d, 2.0).expect("variant");
        let a = sensor_feeds::Scenario::load(&src).expect("original");
        let b = sensor_feeds::Scenario::load(&p).expect("variant");
        let (ta, tb) = (
            sensor_feeds::Truth::new(&a).expect("truth"),
            sensor_feeds::Truth::new(&b).expect("truth"),
        );
        let (ca, cb) = (
            ta.contact_s.expect("contact"),
            tb.contact_s.expect("contact"),
        );
        assert!((cb - ca - 2.0).abs() < 1e-3, "contact {ca} → {cb}");
        assert!(
            (tb.closing_speed_at_contact_mps() - ta.closing_speed_at_contact_mps()).abs() < 1e-3
        );
        assert!((b.duration_s - a.duration_s - 2.0).abs() < 1e-9);
    }

    #[test]
    fn damaged_luts_are_rejected_by_the_loader_and_the_original_is_not() {
        let d = tmp("lut");
        let repo = crate::repo_root();
        diagram::Diagram::load(repo.join("data/default.lut")).expect("original loads");
        for truncated in [false, true] {
            let p = damaged_lut(&repo, &d, truncated).expect("damaged copy");
            let e = diagram::Diagram::load(&p).expect_err("damaged LUT must not load");
            eprintln!("truncated={truncated}: {e}");
        }
    }

    #[test]
    fn the_campaign_has_a_baseline_first_and_unique_names() {
        let c = cases();
        assert_eq!(c.first().map(|k| &k.fault), Some(&Fault::None));
        let mut names: Vec<&str> = c.iter().map(|k| k.name).collect();
        names.sort_unstable();
        names.dedup();
        assert_eq!(names.len(), c.len());
        // The replay case needs the baseline's recording of a crash.
        let base = c
            .iter()
            .position(|k| k.fault == Fault::None)
            .expect("baseline");
        let replay = c
            .iter()
            .position(|k| matches!(k.fault, Fault::ReplayedFire { .. }))
            .expect("replay case");
        assert!(base < replay);
    }
}
