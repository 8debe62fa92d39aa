//! Judging one run of the campaign: every check of [`judge`], and which of them are time
//! limits (retried where the route's timing is emulated) rather than function checks.

use super::{Case, CaseResult, Check, Fault, Variant, DELAY_MS};
use crate::route::STARVED_INPUT_FLAGS;
use crate::{fault_seen, FaultSeen, RunResult, FIRE_LATE_ALLOWANCE_MS};
use actuator_stubs::report::{Report, TimedAction};
use std::collections::BTreeMap;
use std::fmt::Write as _;

mod accel;
mod commands;
mod reaction;

use accel::*;
use commands::*;
use reaction::*;

/// ECU configuration the limits below come from (ecu/ecu.toml defaults).
const OBJECT_TIMEOUT_MS: f64 = 100.0;
const VEHICLE_TIMEOUT_MS: f64 = 100.0;
const E2E_HOLD_MS: f64 = 500.0;
/// EgoVehicleState period (DBC) times the E2E burst count (3): worst time to a burst.
const E2E_BURST_MS: f64 = 30.0;
/// Object-list period of the scenarios (20 ms): a fresh sample after a fault ends.
const OBJECT_PERIOD_MS: f64 = 20.0;
/// OccupantClassification period (DBC).
const OCCUPANT_PERIOD_MS: f64 = 100.0;
/// Scheduling slack on a documented detection time (one object period of a loaded host).
const DETECTION_SLACK_MS: f64 = 20.0;

const ACCEL_HEALTHY_CHECK: &str = "accelerometer healthy on the bus when it failed";
const ACCEL_DETECTION_TIME_CHECK: &str =
    "accelerometer fault on the bus within the documented time";

/// Checks that are time limits (see [`Check::timing`]).
const TIMING_CHECKS: [&str; 6] = [
    "fire command on time",
    "ECU in Normal when the fault began",
    "fault detected: ECU degrades to the reference restraint",
    "recovers after the fault",
    ACCEL_HEALTHY_CHECK,
    ACCEL_DETECTION_TIME_CHECK,
];

const FIRES_CHECK: &str = "airbag fires exactly when the scenario requires";

/// Checks that fail when the ECU fell back to the reference restraint at the crash (see
/// [`starved_inputs_at_fire`]).
const STARVATION_CHECKS: [&str; 4] = [
    FIRES_CHECK,
    "crash handled by the adaptive path after recovery",
    "services usable after a killed process (crash handled adaptively)",
    "same airbag plan as the baseline",
];

/// If the airbag was fired by the reference restraint while the ECU's only active faults were
/// stale inputs (see [`STARVED_INPUT_FLAGS`]): those faults, joined with "+".
fn starved_inputs_at_fire(
    fire: Option<&TimedAction>,
    ecu_faults: &[(f64, Vec<String>)],
) -> Option<String> {
    let fire = fire?;
    let t = fire.after_contact_ms?;
    if fire.action.source != "reference" {
        return None;
    }
    only_starved_faults_at(ecu_faults, t, &[]).map(|flags| flags.join("+"))
}

/// The ECU's active faults at `t_ms` if there are some and all are stale inputs or overruns
/// ([`STARVED_INPUT_FLAGS`]) or flags in `own` (what the case's fault sets by design).
fn only_starved_faults_at<'a>(
    ecu_faults: &'a [(f64, Vec<String>)],
    t_ms: f64,
    own: &[&str],
) -> Option<&'a [String]> {
    let (_, flags) = ecu_faults.iter().rev().find(|(tf, _)| *tf <= t_ms)?;
    (!flags.is_empty()
        && flags
            .iter()
            .all(|f| STARVED_INPUT_FLAGS.contains(&f.as_str()) || own.contains(&f.as_str())))
    .then_some(flags.as_slice())
}

/// If a crash came (`contact`) and nothing fired while the ECU's only active faults at the
/// contact were stale inputs, the crash accelerometer among them (see [`STARVED_INPUT_FLAGS`]),
/// besides those the case's own fault sets (`own`, see [`own_flags`]): those faults. Without any
/// acceleration sample no ECU can fire; where the emulator (or a restarted feed it slowed down)
/// starved the accelerometer over the crash, the missing fire is a time limit there, a
/// function failure with real timers.
fn starved_without_fire(
    fire: Option<&TimedAction>,
    contact: bool,
    ecu_faults: &[(f64, Vec<String>)],
    own: &[&str],
) -> Option<String> {
    if fire.is_some() || !contact {
        return None;
    }
    let flags = only_starved_faults_at(ecu_faults, 0.0, own)?;
    flags
        .iter()
        .any(|f| f == "accel_sensor")
        .then(|| flags.join("+"))
}

/// The EcuStatus fault flags a case's fault sets by design: the bus faults and the flood put
/// frames that fail E2E on EgoVehicleState's id (`e2e`). They are the fault's effect, not a
/// sign that the ECU went wrong, so they do not hide a starved accelerometer.
fn own_flags(fault: &Fault) -> &'static [&'static str] {
    match fault {
        Fault::Bus { .. } | Fault::Flood => &["e2e"],
        _ => &[],
    }
}

/// Scenario time [s] of a report time (ms rel. contact, or since start without contact).
fn scenario_s(r: &Report, t_ms: f64) -> f64 {
    if r.contact_ns != 0 && r.start_ns != 0 {
        (r.contact_ns as f64 - r.start_ns as f64) * 1e-9 + t_ms * 1e-3
    } else {
        t_ms * 1e-3
    }
}

fn counter(ecu: Option<&serde_json::Value>, name: &str) -> u64 {
    ecu.and_then(|e| e.get("counters"))
        .and_then(|c| c.get(name))
        .and_then(serde_json::Value::as_u64)
        .unwrap_or(0)
}

/// The checks of one case, each a function check or a time limit ([`Check::timing`]).
struct Checks {
    list: Vec<Check>,
    /// See [`starved_inputs_at_fire`].
    starved: Option<String>,
}

impl Checks {
    fn new(starved: Option<String>) -> Self {
        Self {
            list: Vec::new(),
            starved,
        }
    }

    fn check(&mut self, what: &str, ok: bool, detail: String) {
        self.check_timed(what, ok, detail, false);
    }

    /// [`Self::check`] for a check that is a time limit in this run only (`timing`), e.g.
    /// commands lost only because they arrived late.
    fn check_timed(&mut self, what: &str, ok: bool, detail: String, timing: bool) {
        // A fire of the reference restraint with the ECU degraded only by inputs that went
        // stale is the specified fallback; under emulation the emulator's stalls can starve
        // the inputs, so a check it fails is a timing failure there (run again) and a
        // function failure with real timers.
        let starved_fire = STARVATION_CHECKS.contains(&what) && self.starved.is_some();
        let detail = match (&self.starved, starved_fire && !ok) {
            (Some(f), true) => format!(
                "{detail} (reference restraint: the ECU's only faults at the fire were {f})"
            ),
            _ => detail,
        };
        self.list.push(Check {
            what: what.to_owned(),
            ok,
            detail,
            timing: timing
                || TIMING_CHECKS.contains(&what)
                || (starved_fire && crate::Route::current().allowances().starved_fire_is_timing),
        });
    }
}

/// Judges one run.
pub fn judge(case: &Case, run: &RunResult, baseline: Option<&RunResult>) -> CaseResult {
    let r = &run.report;
    // The scenario file the run played (the campaign's variant where the case made one).
    let played = world::Scenario::load(&run.scenario).ok();
    let ecu = run.ecu_report.as_ref();
    let fire = r.action("airbag_fire");
    let mut checks = Checks::new(starved_inputs_at_fire(fire, &r.ecu_faults).or_else(|| {
        starved_without_fire(
            fire,
            r.contact_ns != 0,
            &r.ecu_faults,
            own_flags(&case.fault),
        )
    }));

    checks.check(
        "bench processes ran and stopped cleanly",
        run.problems.is_empty(),
        if run.problems.is_empty() {
            "ecu, sensor-feeds, actuator-stubs exit 0".into()
        } else {
            run.problems.join("; ")
        },
    );
    checks.check(
        "ECU report written",
        ecu.is_some(),
        "ecu-report.json".into(),
    );
    let rejected = rejections_by_reason(ecu, r);
    let summary = disturbance_summary(run);
    let frames_injected = if case.fault == Fault::Flood {
        flood_frames(run)
    } else {
        injected(run, summary.as_ref())
    };
    let commands = judge_commands(&mut checks, case, run, frames_injected);

    let must_fire = played.as_ref().and_then(|s| s.expect.airbag_fires);
    if let Some(want) = must_fire {
        checks.check(
            FIRES_CHECK,
            r.airbag_fired == want,
            format!("expected {want}, fired {}", r.airbag_fired),
        );
    }
    let late = fire.and_then(|a| a.after_contact_ms.map(|t| t - a.action.planned_ms));
    if let (Some(a), Some(l)) = (fire, late) {
        // The reference restraint fires at the ECU's decision, which its nominal time (the
        // bus's FireTime) bounds from above; a plan fires at its time.
        let earliest_ms = if a.action.source == "reference" {
            f64::NEG_INFINITY
        } else {
            -1.0
        };
        checks.check(
            "fire command on time",
            (earliest_ms..=FIRE_LATE_ALLOWANCE_MS).contains(&l)
                && a.after_contact_ms.is_some_and(|t| t >= 0.0),
            format!(
                "received {:+.1} ms after its planned {:+.1} ms (allowance {FIRE_LATE_ALLOWANCE_MS} ms)",
                l, a.action.planned_ms
            ),
        );
    }
    let modes: Vec<(f64, String)> = r
        .ecu_modes
        .iter()
        .map(|(t, m)| (scenario_s(r, *t) * 1e3, m.clone()))
        .collect();

    let window = fault_window(case, summary.as_ref());
    let reaction = window.map_or_else(Reaction::default, |w| {
        judge_reaction(&mut checks, case, w, &modes, &rejected)
    });
    if window.is_some() && must_fire == Some(true) {
        checks.check(
            "crash handled by the adaptive path after recovery",
            fire.is_some_and(|a| a.action.source == "adaptive"),
            fire.map_or("no fire".into(), |a| format!("source {}", a.action.source)),
        );
    }
    judge_fault(
        &mut checks,
        case,
        run,
        &modes,
        fire,
        frames_injected,
        played.as_ref().map_or(f64::NAN, |s| s.duration_s),
        must_fire,
    );
    // Same decision as without the fault where the fault is over before the threat.
    if window.is_some()
        || matches!(
            case.fault,
            Fault::StaleService | Fault::Bus { mode: "errors", .. }
        )
    {
        judge_same_plan(&mut checks, baseline, fire);
    }

    let overruns = ecu
        .and_then(|e| e.get("overruns"))
        .and_then(serde_json::Value::as_u64)
        .unwrap_or(0);
    let cycles = ecu
        .and_then(|e| e.get("cycles"))
        .and_then(serde_json::Value::as_u64)
        .unwrap_or(0);
    let description = describe_reaction(
        case,
        Some(r),
        &modes,
        reaction.degraded_after_ms,
        reaction.recovered_after_ms,
        fire,
    );
    // The case's precondition: where the ECU was not in Normal when the fault began (a time
    // limit: the emulator starved it before), its other checks measured nothing the case is
    // about; they count as time limits too (run again where timing is emulated; with real
    // timers the failed precondition fails the case anyway).
    if checks
        .list
        .iter()
        .any(|c| c.what == "ECU in Normal when the fault began" && !c.ok)
    {
        for c in checks.list.iter_mut().filter(|c| !c.ok) {
            c.timing = true;
        }
    }
    let pass = checks.list.iter().all(|c| c.ok);
    CaseResult {
        name: case.name.to_owned(),
        scenario: case.scenario.to_owned(),
        fault: case.what.to_owned(),
        reaction: description,
        ecu_modes: modes,
        degraded_after_ms: reaction.degraded_after_ms,
        recovered_after_ms: reaction.recovered_after_ms,
        airbag_fired: r.airbag_fired,
        airbag_source: fire.map(|a| a.action.source.clone()),
        airbag_late_ms: late,
        commands_sent: commands.sent,
        commands_authenticated: commands.authenticated,
        commands_lost: commands.lost,
        commands_denied_by_attack: commands.denied,
        commands_late: commands.late,
        frames_injected,
        frames_rejected: rejected,
        cycles,
        overruns,
        checks: checks.list,
        pass,
        attempts: 1,
        earlier_runs: Vec::new(),
        dir: run.dir.display().to_string(),
        contact_s: (r.contact_ns != 0 && r.start_ns != 0)
            .then_some((r.contact_ns as f64 - r.start_ns as f64) * 1e-9),
        fire_s: fire
            .and_then(|a| a.after_contact_ms)
            .map(|t| scenario_s(r, t)),
        fault_s: window,
        duration_s: played.as_ref().map_or(0.0, |s| s.duration_s),
    }
}

/// Rejections by the ECU (`ecu:`) and the stubs (`stubs:e2e:`, `stubs:secoc:`) by reason.
fn rejections_by_reason(ecu: Option<&serde_json::Value>, r: &Report) -> BTreeMap<String, u64> {
    let mut rejected: BTreeMap<String, u64> = BTreeMap::new();
    if let Some(c) = ecu
        .and_then(|e| e.get("counters"))
        .and_then(|c| c.as_object())
    {
        for (k, v) in c {
            if let (Some(reason), Some(n)) = (k.strip_prefix("can_rejected_"), v.as_u64()) {
                if n > 0 {
                    rejected.insert(format!("ecu:e2e:{reason}"), n);
                }
            }
        }
        for k in ["objects_invalid", "accel_invalid_batches"] {
            let n = c.get(k).and_then(|v| v.as_u64()).unwrap_or(0);
            if n > 0 {
                rejected.insert(format!("ecu:{k}"), n);
            }
        }
    }
    for (k, n) in &r.e2e_rejected {
        rejected.insert(format!("stubs:e2e:{k}"), *n);
    }
    for (k, n) in &r.secoc_rejected {
        rejected.insert(format!("stubs:secoc:{k}"), *n);
    }
    rejected
}

/// The airbag plan (fire time, level) is the baseline's: a fault that is over before the
/// threat leaves no trace in the decision.
fn judge_same_plan(checks: &mut Checks, baseline: Option<&RunResult>, fire: Option<&TimedAction>) {
    let base_fire = baseline.and_then(|b| b.report.action("airbag_fire"));
    if let (Some(b), Some(a)) = (base_fire, fire) {
        let dt = a.action.planned_ms - b.action.planned_ms;
        let dl = a.action.level_kn - b.action.level_kn;
        checks.check(
            "same airbag plan as the baseline",
            dt.abs() <= 5.0 && dl.abs() <= 1.0,
            format!(
                "planned {:+.1} ms / {:.2} kN vs baseline {:+.1} ms / {:.2} kN",
                a.action.planned_ms, a.action.level_kn, b.action.planned_ms, b.action.level_kn
            ),
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_missing_fire_with_the_accelerometer_starved_over_the_contact_is_a_time_limit_only() {
        let faults = |at_contact: &[&str]| -> Vec<(f64, Vec<String>)> {
            vec![
                (-2600.0, vec!["accel_sensor".to_owned()]),
                (
                    -2285.0,
                    at_contact.iter().map(|f| (*f).to_owned()).collect(),
                ),
                (142.0, vec!["occupant_input".to_owned()]),
            ]
        };
        let all = faults(&["vehicle_input", "object_input", "accel_sensor", "overrun"]);
        assert!(starved_without_fire(None, true, &all, &[]).is_some());
        // The accelerometer alive: a missing fire is the ECU's own.
        assert_eq!(
            starved_without_fire(None, true, &faults(&["object_input"]), &[]),
            None
        );
        // A corrupt input or a bad table is no starvation...
        let e2e = faults(&["accel_sensor", "e2e"]);
        assert_eq!(starved_without_fire(None, true, &e2e, &[]), None);
        // ...unless the case's own fault sets it: the cangen flood of a clean-clone run, whose
        // feeds the loaded emulator starved for 2 s (no accelerometer, no objects) while the
        // flood's frames kept EgoVehicleState in its E2E hold.
        let flood = vec![
            (
                -2128.7,
                vec!["accel_sensor".to_owned(), "overrun".to_owned()],
            ),
            (
                -1736.5,
                ["object_input", "accel_sensor", "e2e", "overrun"]
                    .map(str::to_owned)
                    .to_vec(),
            ),
            (
                -53.0,
                ["object_input", "accel_sensor", "e2e", "overrun"]
                    .map(str::to_owned)
                    .to_vec(),
            ),
        ];
        assert_eq!(
            starved_without_fire(None, true, &flood, own_flags(&Fault::Flood)).as_deref(),
            Some("object_input+accel_sensor+e2e+overrun")
        );
        assert_eq!(
            starved_without_fire(None, true, &flood, own_flags(&Fault::None)),
            None
        );
        // No crash, or a fire: nothing to excuse.
        assert_eq!(starved_without_fire(None, false, &all, &[]), None);
    }

    #[test]
    fn the_start_up_reference_fallback_is_not_a_fallback() {
        let m = |v: &[(f64, &str)]| {
            v.iter()
                .map(|(t, m)| (*t, (*m).to_owned()))
                .collect::<Vec<_>>()
        };
        // sensor-dropout offline: start → Normal → the dropout → crash.
        let dropout = m(&[
            (-1691.0, "ReferenceFallback"),
            (-1671.0, "Normal"),
            (-810.0, "ReferenceFallback"),
            (7.0, "CrashDetected"),
        ]);
        assert_eq!(crate::fell_back_after_normal(&dropout), Some(-810.0));
        let clean = m(&[
            (-2000.0, "ReferenceFallback"),
            (-1980.0, "Normal"),
            (2.0, "Deployed"),
        ]);
        assert_eq!(crate::fell_back_after_normal(&clean), None);
        let never_normal = m(&[(-2000.0, "ReferenceFallback"), (5.0, "CrashDetected")]);
        assert_eq!(crate::fell_back_after_normal(&never_normal), None);
    }

    #[test]
    fn a_reference_fire_with_only_stale_inputs_is_told_apart_from_other_faults() {
        let fire = |source: &str| TimedAction {
            action: actuator_stubs::commands::Action {
                t_ns: 0,
                what: "airbag_fire".into(),
                level_kn: 12.0,
                planned_ms: 10.0,
                source: source.into(),
            },
            t_ms: 1814.0,
            after_contact_ms: Some(14.0),
        };
        let faults = |names: &[&str]| -> Vec<(f64, Vec<String>)> {
            vec![
                (-900.0, vec!["e2e".to_owned()]),
                (-500.0, Vec::new()),
                (-30.0, names.iter().map(|n| (*n).to_owned()).collect()),
                (20.0, Vec::new()),
            ]
        };
        let stale = faults(&["vehicle_input", "object_input"]);
        assert_eq!(
            starved_inputs_at_fire(Some(&fire("reference")), &stale).as_deref(),
            Some("vehicle_input+object_input")
        );
        // The adaptive path fired: not a fallback.
        assert_eq!(
            starved_inputs_at_fire(Some(&fire("adaptive")), &stale),
            None
        );
        // Corrupt data or a bad LUT is not starvation.
        for other in [&["object_input", "e2e"][..], &["lut"], &["config"], &[]] {
            assert_eq!(
                starved_inputs_at_fire(Some(&fire("reference")), &faults(other)),
                None,
                "{other:?}"
            );
        }
        // No fire, no verdict.
        assert_eq!(starved_inputs_at_fire(None, &stale), None);
    }
}
