//! The fault-injection campaign: real bench processes on vcan (a QEMU guest with a
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

mod cases;
mod judge;
mod mutations;
mod report;

pub use cases::*;
pub use judge::judge;
pub(crate) use mutations::frozen_scenario;
use mutations::{damaged_lut, forged_frames};
pub use mutations::{first_airbag_fire, lengthened_scenario, recorded_fire_pair, variant_scenario};
pub use report::report_text;

use crate::{Disturbance, RunConfig, RunCtx, RunResult, SideProcess};
use anyhow::{bail, Context, Result};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::Duration;

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

impl Campaign {
    /// `schema_version` of `campaign.json` (docs/using.md, "JSON results").
    pub const SCHEMA_VERSION: u32 = 1;
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
        replay: None,
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
        let orig = world::Scenario::load(&src).expect("original");
        let s = world::Scenario::load(&p).expect("variant parses and validates");
        assert_eq!(s.name, orig.name);
        assert_eq!(s.duration_s, orig.duration_s);
        assert!(!s.sensor.frozen(0.39) && s.sensor.frozen(0.4) && !s.sensor.frozen(0.7));
        assert!(!orig.sensor.frozen(0.5));
    }

    /// A variant written elsewhere plays the same measured pulse as its original.
    #[test]
    fn a_variant_of_a_measured_pulse_scenario_reads_the_same_pulse() {
        let d = tmp("frozen-pulse");
        let src = crate::repo_root().join("scenarios/measured-pulse-half-sine-56.toml");
        let p = frozen_scenario(&src, &d, 0.4, 0.7).expect("variant");
        let orig = world::Scenario::load(&src).expect("original");
        let s = world::Scenario::load(&p).expect("variant parses and validates");
        let (a, b) = (orig.pulse.expect("pulse"), s.pulse.expect("pulse"));
        assert!(Path::new(&b.file).is_absolute(), "{}", b.file);
        assert_eq!(a.accel_mps2, b.accel_mps2);
    }

    #[test]
    fn scenario_variants_change_what_they_say_and_expect_what_they_must() {
        let d = tmp("variants");
        let src = crate::repo_root().join("scenarios/taurus-48-48-abs.toml");
        let load = |v| {
            let p = variant_scenario(&src, &d, v).expect("variant");
            world::Scenario::load(&p).expect("variant parses and validates")
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
        let contact = world::Truth::new(&s).unwrap().contact_s.unwrap();
        let s = load(Variant::AccelDead {
            before_contact_s: 0.6,
        });
        assert!(s
            .sensor
            .dropped(world::scenario::DropoutTarget::Accel, contact - 0.59));
        assert!(!s
            .sensor
            .dropped(world::scenario::DropoutTarget::Accel, contact - 0.61));
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
        let s = world::Scenario::load(&p).unwrap();
        assert!(s
            .sensor
            .dropped(world::scenario::DropoutTarget::Vehicle, 1.0));
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
        let a = world::Scenario::load(&src).expect("original");
        let b = world::Scenario::load(&p).expect("variant");
        let (ta, tb) = (
            world::Truth::new(&a).expect("truth"),
            world::Truth::new(&b).expect("truth"),
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
