//! Judging one run of the campaign: every check of [`judge`], and which of them are time
//! limits (retried where the route's timing is emulated) rather than function checks.

use super::{Case, CaseResult, Check, Fault, Variant, DELAY_MS};
use crate::route::STARVED_INPUT_FLAGS;
use crate::{fault_seen, FaultSeen, RunResult, FIRE_LATE_ALLOWANCE_MS};
use actuator_stubs::report::{Report, TimedAction};
use std::collections::BTreeMap;
use std::fmt::Write as _;

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

/// Flood frames on the bus: everything candump saw minus what the ECU sent and the vehicle
/// and occupant frames of the feeds (a random frame with one of those two ids is counted as
/// the feeds'; 2 of 2048 ids).
fn flood_frames(run: &RunResult) -> u64 {
    let Ok(log) = bus::candump::CandumpLog::read(&run.dir.join("candump.log")) else {
        return 0;
    };
    let feeds = log
        .frames
        .iter()
        .filter(|f| {
            matches!(
                f.frame.id,
                bus::EgoVehicleState::RAW_ID | bus::OccupantClassification::RAW_ID
            )
        })
        .count() as u64;
    (log.frames.len() as u64).saturating_sub(feeds + counter(run.ecu_report.as_ref(), "can_tx"))
}

/// Frames on the SecOC command and authenticator ids that the ECU did not send: what the stubs
/// received there − 2 × what the ECU sent (a command + authenticator pair each). Exact when
/// every genuine frame reached the stubs; genuine frames missing at the stubs make it smaller,
/// so the "no genuine command lost" bound it sets only gets stricter.
fn flood_frames_on_command_ids(frames: &BTreeMap<String, u64>, sent: u64) -> u64 {
    let received: u64 = bus::secoc::SecOcStream::ALL
        .iter()
        .flat_map(|s| [s.command_id(), s.auth_id()])
        .filter_map(|id| bus::message_info(id).and_then(|m| frames.get(m.name)))
        .sum();
    received.saturating_sub(2 * sent)
}

/// What the disturbance measured about itself, as JSON: the restarted feeds' resumption
/// (`feeds-restart.json`), else the last JSON line a side process printed (bus-inject's
/// `injected`, `first_s`, `last_s`).
fn disturbance_summary(run: &RunResult) -> Option<serde_json::Value> {
    let from_file = std::fs::read_to_string(run.dir.join("feeds-restart.json"))
        .ok()
        .and_then(|t| serde_json::from_str(&t).ok());
    from_file.or_else(|| {
        run.disturbance_output
            .iter()
            .find_map(|(_, out)| out.lines().rev().find_map(|l| serde_json::from_str(l).ok()))
    })
}

/// Frames the disturbance put on the bus: bus-inject's JSON summary, or one "sent" line per
/// successful cansend.
fn injected(run: &RunResult, summary: Option<&serde_json::Value>) -> u64 {
    summary
        .and_then(|v| v.get("injected"))
        .and_then(serde_json::Value::as_u64)
        .unwrap_or_else(|| {
            run.disturbance_output
                .iter()
                .map(|(_, out)| out.lines().filter(|l| *l == "sent").count() as u64)
                .sum()
        })
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
    let played = sensor_feeds::Scenario::load(&run.scenario).ok();
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
        checks.check(
            "fire command on time",
            (-1.0..=FIRE_LATE_ALLOWANCE_MS).contains(&l) && a.after_contact_ms.is_some_and(|t| t >= 0.0),
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
    if window.is_some() || case.fault == Fault::StaleService {
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

/// What became of the commands the ECU sent.
struct Commands {
    sent: u64,
    authenticated: u64,
    lost: u64,
    denied: u64,
    late: u64,
}

/// Whether the commands lost beyond the `allowed` ones are all accounted for by `late` ones.
/// Commands lost only because they came after the freshness window are a time limit: a
/// failure with real timers, run again where the route's timing is emulated (the emulator
/// stalled the ECU or the stubs); a command lost any other way is a function failure on every
/// route.
fn lost_only_late(lost: u64, allowed: u64, late: u64) -> bool {
    lost > allowed && lost - allowed <= late
}

/// Checks that every genuine command was acted on and nothing else.
fn judge_commands(
    checks: &mut Checks,
    case: &Case,
    run: &RunResult,
    frames_injected: u64,
) -> Commands {
    let r = &run.report;
    let sent = counter(run.ecu_report.as_ref(), "secoc_commands_tx");
    let authenticated = r.secoc_accepted;
    // Genuine commands the stubs refused because they arrived too late (freshness window or
    // pairing timeout): reported as "late" and counted as lost on every route (refusing them
    // is right, but a real bench must deliver in time). (The replay case's stale frames are
    // the attacker's, not genuine.)
    let late = if matches!(case.fault, Fault::ReplayedFire { .. }) {
        0
    } else {
        ["freshness_stale", "stale"]
            .iter()
            .map(|k| r.secoc_rejected.get(*k).copied().unwrap_or(0))
            .sum::<u64>()
    };
    // A held command whose authenticator came after the pairing timeout shows as a dropped
    // command plus an authenticator with no pending command (seen once in the TCG guest's
    // baseline: the emulator stalled the stubs between the two frames sent back to back).
    // Without frames from an attacker on the SecOC ids that pair can have no other cause.
    let attack = matches!(
        case.fault,
        Fault::ForgedFire { .. } | Fault::ReplayedFire { .. } | Fault::Flood
    );
    let paired_late = if attack {
        0
    } else {
        let alone = r
            .secoc_rejected
            .get("no_pending_command")
            .copied()
            .unwrap_or(0);
        r.secoc_commands_dropped.min(alone)
    };
    let late = late + paired_late;
    let lost = sent.saturating_sub(authenticated);
    checks.check(
        "ECU sent authenticated commands",
        sent > 0,
        format!("{sent} command + authenticator pairs"),
    );
    checks.check(
        "nothing acted on that the ECU did not send",
        authenticated <= sent,
        format!("stubs authenticated {authenticated}, ECU sent {sent}"),
    );
    // Attacker frames on the command ids: each can displace at most one genuine command (it
    // either replaces the held command or desynchronises the E2E counter for the next one).
    let e2e_passing_attacks = match case.fault {
        // cansend pairs: command + authenticator; only the command frames can displace.
        Fault::ForgedFire { .. } | Fault::ReplayedFire { .. } => frames_injected / 2,
        // Random frames that landed on a command or authenticator id.
        Fault::Flood => flood_frames_on_command_ids(&r.frames, sent),
        _ => 0,
    };
    let denied = lost.min(e2e_passing_attacks);
    let lost_only_late = lost_only_late(lost, e2e_passing_attacks, late);
    checks.check_timed(
        "no genuine command lost",
        lost <= e2e_passing_attacks,
        format!(
            "{lost} of {sent} not acted on{}{}",
            if attack {
                format!(
                    "; ≤ {e2e_passing_attacks} allowed (one per attacker frame that can collide)"
                )
            } else {
                String::new()
            },
            if late > 0 {
                format!("; {late} of them arrived late and were refused as stale")
            } else {
                String::new()
            }
        ),
        lost_only_late,
    );
    Commands {
        sent,
        authenticated,
        lost,
        denied,
        late,
    }
}

/// The fault's extent [scenario s] for the faults with a window: as planned, or as the
/// disturbance measured it (the injector's first and last frame, the restarted feeds' actual
/// resumption).
fn fault_window(case: &Case, summary: Option<&serde_json::Value>) -> Option<(f64, f64)> {
    let planned = match case.fault {
        Fault::FeedsKilled { kill_s, restart_s } => (kill_s, restart_s),
        Fault::StaleObjects { from_s, to_s } => (from_s, to_s),
        Fault::Bus {
            mode: "delay",
            from_s,
            to_s,
        } => (from_s + DELAY_MS * 1e-3, to_s + DELAY_MS * 1e-3),
        Fault::Bus { from_s, to_s, .. } => (from_s, to_s),
        _ => return None,
    };
    let measured = |key: &str| {
        summary
            .and_then(|v| v.get(key))
            .and_then(serde_json::Value::as_f64)
    };
    let (from_s, to_s) = planned;
    Some(match case.fault {
        Fault::FeedsKilled { .. } => (from_s, measured("resumed_s").unwrap_or(to_s).max(to_s)),
        Fault::Bus { .. } => (
            measured("first_s").unwrap_or(from_s),
            measured("last_s").unwrap_or(to_s),
        ),
        _ => planned,
    })
}

/// How fast the ECU reacted to a fault with a window.
#[derive(Default)]
struct Reaction {
    degraded_after_ms: Option<f64>,
    recovered_after_ms: Option<f64>,
}

/// Checks that the ECU degraded within the documented time after the fault began, for the
/// right reason, and recovered within the documented time after it ended.
fn judge_reaction(
    checks: &mut Checks,
    case: &Case,
    (from_s, to_s): (f64, f64),
    modes: &[(f64, String)],
    rejected: &BTreeMap<String, u64>,
) -> Reaction {
    // One scheduling period of a loaded 2-vCPU host on top of the documented limits (every
    // route: measured in the QEMU TCG guest too, detection ≤ 82 ms of 120, recovery ≤ 45 ms of 100).
    let slack_ms = 20.0;
    let from_ms = from_s * 1e3;
    let to_ms = to_s * 1e3;
    let deg = modes
        .iter()
        .find(|(t, m)| *t >= from_ms - 5.0 && m == "ReferenceFallback")
        .map(|(t, _)| *t);
    let degraded_after_ms = deg.map(|t| t - from_ms);
    // Recovery counts from the last degradation that began inside the fault window: a fault
    // with gaps (an injector slowed down by a loaded host) may let the ECU recover and
    // degrade again before its end.
    let last_deg = deg.and_then(|d| {
        modes
            .iter()
            .rev()
            .find(|(t, m)| *t >= d && *t <= to_ms + 5.0 && m == "ReferenceFallback")
            .map(|(t, _)| *t)
    });
    let rec = last_deg.and_then(|d| {
        modes
            .iter()
            .find(|(t, m)| *t > d && m == "Normal")
            .map(|(t, m)| (*t, m.clone()))
    });
    let recovered_after_ms = rec.as_ref().map(|(t, _)| t - to_ms);
    let mode_at_start = modes
        .iter()
        .rev()
        .find(|(t, _)| *t < from_ms)
        .map_or("none", |(_, m)| m.as_str());
    checks.check(
        "ECU in Normal when the fault began",
        mode_at_start == "Normal",
        format!("{mode_at_start} at {from_ms:.0} ms"),
    );
    let (detect_limit_ms, recover_limit_ms, reason) = match case.fault {
        // Back when the first sample of every timed-out input arrives: the occupant frame
        // (100 ms period) is the slowest.
        Fault::FeedsKilled { .. } => (
            OBJECT_TIMEOUT_MS.max(VEHICLE_TIMEOUT_MS),
            OCCUPANT_PERIOD_MS,
            None,
        ),
        Fault::StaleObjects { .. } => (
            OBJECT_TIMEOUT_MS + OBJECT_PERIOD_MS,
            OBJECT_PERIOD_MS,
            Some("ecu:objects_invalid"),
        ),
        Fault::Bus { mode, .. } => (
            E2E_BURST_MS,
            E2E_HOLD_MS,
            Some(match mode {
                "crc" => "ecu:e2e:crc_mismatch",
                "replay" => "ecu:e2e:counter_repeated",
                _ => "ecu:e2e:counter_skipped",
            }),
        ),
        _ => (0.0, 0.0, None),
    };
    checks.check(
        "fault detected: ECU degrades to the reference restraint",
        degraded_after_ms.is_some_and(|d| d <= detect_limit_ms + slack_ms),
        degraded_after_ms.map_or("never degraded".into(), |d| {
            format!(
                "ReferenceFallback {d:.0} ms after the fault began (documented ≤ {detect_limit_ms:.0} ms + {slack_ms:.0} ms slack)"
            )
        }),
    );
    // A crash confirmed after the fault began, before the recovery was due, latches the ECU
    // (CrashDetected, Deployed: the specified post-crash state); it does not return to Normal,
    // so there is no recovery to wait for.
    let due_ms = to_ms + recover_limit_ms + slack_ms;
    let latched = modes.iter().find(|(t, m)| {
        *t >= from_ms - 5.0 && *t <= due_ms && (m == "CrashDetected" || m == "Deployed")
    });
    match latched {
        Some((t, m)) if rec.is_none() => checks.check(
            "recovers after the fault",
            true,
            format!("not expected: crash latched ({m} at {t:.0} ms, the fault began at {from_ms:.0} ms)"),
        ),
        _ => checks.check(
            "recovers after the fault",
            recovered_after_ms.is_some_and(|d| d <= recover_limit_ms + slack_ms),
            rec.as_ref().map_or("never recovered".into(), |(t, m)| {
                format!(
                    "{m} {:.0} ms after the fault ended (documented ≤ {recover_limit_ms:.0} ms + {slack_ms:.0} ms slack; at {:.0} ms)",
                    t - to_ms,
                    t
                )
            }),
        ),
    }
    if let Some(reason) = reason {
        let n = rejected.get(reason).copied().unwrap_or(0);
        checks.check(
            "the ECU rejected the faulty input for the right reason",
            n > 0,
            format!("{reason} = {n}"),
        );
    }
    Reaction {
        degraded_after_ms,
        recovered_after_ms,
    }
}

/// The checks only some faults have: the LUT faults' start-up fallback, the stale service's
/// usable services, the attacks' rejected frames, the flood's inputs.
#[allow(clippy::too_many_arguments)]
fn judge_fault(
    checks: &mut Checks,
    case: &Case,
    run: &RunResult,
    modes: &[(f64, String)],
    fire: Option<&TimedAction>,
    frames_injected: u64,
    duration_s: f64,
    must_fire: Option<bool>,
) {
    let ecu = run.ecu_report.as_ref();
    match case.fault {
        Fault::Lut { .. } => {
            let stderr =
                std::fs::read_to_string(run.dir.join("ecu-stderr.txt")).unwrap_or_default();
            let said = stderr
                .lines()
                .find(|l| l.to_lowercase().contains("lut"))
                .unwrap_or("")
                .to_owned();
            checks.check(
                "the ECU names the bad LUT file",
                said.contains("DEGRADED")
                    || said.to_lowercase().contains("error")
                    || said.to_lowercase().contains("reject"),
                said,
            );
            checks.check(
                "never Normal without a valid LUT",
                !modes.iter().any(|(_, m)| m == "Normal"),
                format!("{} mode changes", modes.len()),
            );
            if must_fire != Some(false) {
                checks.check(
                    "still protected: the reference restraint fires",
                    fire.is_some_and(|a| a.action.source == "reference"),
                    fire.map_or("no fire".into(), |a| format!("source {}", a.action.source)),
                );
            }
        }
        Fault::Variant(v) => judge_variant(checks, v, &run.report),
        Fault::StaleService => {
            let cleaned = ecu
                .and_then(|e| e.pointer("/ipc/stale_nodes_cleaned"))
                .and_then(serde_json::Value::as_u64)
                .unwrap_or(0);
            checks.check(
                "services usable after a killed process (crash handled adaptively)",
                fire.is_some_and(|a| a.action.source == "adaptive"),
                format!(
                    "{}; stale nodes removed by the ECU's explicit clean-up: {cleaned} (iceoryx2 also cleans dead nodes at node creation)",
                    fire.map_or("no fire".into(), |a| format!("source {}", a.action.source))
                ),
            );
        }
        Fault::ForgedFire { .. } | Fault::ReplayedFire { .. } => {
            let r = &run.report;
            let secoc_rejected: u64 = r.secoc_rejected.values().sum();
            checks.check(
                "attacker frames were on the bus",
                frames_injected > 0,
                format!("{frames_injected} frames via cansend"),
            );
            checks.check(
                "SecOC rejected the attacker's authenticators",
                secoc_rejected > 0,
                format!("{:?}", r.secoc_rejected),
            );
        }
        Fault::Flood => {
            let rx = counter(ecu, "can_frames_rx");
            checks.check(
                "ECU kept receiving its inputs under the flood",
                rx > 0,
                format!(
                    "{rx} input frames received (kernel filter drops the rest); flood ≈ {frames_injected} frames, {:.0} frames/s (a 500 kbit/s bus carries ≈ 4 000 frames/s)",
                    frames_injected as f64 / duration_s
                ),
            );
            checks.check(
                "the flood was on the bus",
                frames_injected > 0,
                format!("{frames_injected} frames"),
            );
        }
        Fault::None
        | Fault::FeedsKilled { .. }
        | Fault::StaleObjects { .. }
        | Fault::Bus { .. } => {}
    }
}

/// For a dead or stuck accelerometer variant: when the sensor failed (ms rel. contact) and
/// how its fault flag showed after that.
fn accel_failure_seen(v: Variant, r: &Report) -> Option<(f64, FaultSeen)> {
    let (Variant::AccelDead { before_contact_s } | Variant::AccelStuck { before_contact_s }) = v
    else {
        return None;
    };
    let from_ms = -before_contact_s * 1e3;
    Some((from_ms, fault_seen(&r.ecu_faults, "accel_sensor", from_ms)))
}

/// Documented bound on "sensor failed → fault bit on the bus": the monitor's limit (no batch
/// for `accel_timeout_ms`, the same reading for `accel_stuck_ms`) plus one EcuStatus period.
fn accel_fault_bound_ms(v: Variant) -> f64 {
    let cfg = restraint::CycleConfig::default();
    let limit = match v {
        Variant::AccelStuck { .. } => cfg.accel_stuck_ms,
        _ => cfg.accel_timeout_ms,
    };
    limit + bus::EcuStatus::MESSAGE_CYCLE_TIME_MS as f64
}

/// Issue 14's checks of a scenario variant: a misreported crash is no worse than the reference
/// restraint (judged on the commanded levels at the planned times where the route's timing is
/// emulated, as the bench's library test does); a dead or stuck accelerometer is on the bus
/// before the contact.
fn judge_variant(checks: &mut Checks, v: Variant, r: &Report) {
    match v {
        Variant::MassMisreport { .. } | Variant::SpeedBias { .. } => {
            let emulated = crate::Route::current().timing_emulated();
            let verdict = r.outcome.as_ref().map(|o| {
                let judged = match (&o.adaptive_planned, emulated) {
                    (Some(planned), true) => planned,
                    _ => &o.adaptive,
                };
                (
                    actuator_stubs::outcome::no_worse(judged, &o.reference),
                    format!(
                        "{:+.1} % a_max + a_mean vs the reference restraint{}{}",
                        o.change_pct,
                        if judged.bottomed_out {
                            ", bottomed out"
                        } else {
                            ""
                        },
                        if emulated {
                            " (commanded levels at planned times)"
                        } else {
                            ""
                        }
                    ),
                )
            });
            checks.check(
                "no worse than the reference restraint",
                verdict.as_ref().is_some_and(|(ok, _)| *ok),
                verdict.map_or("no outcome (no contact?)".into(), |(_, d)| d),
            );
        }
        Variant::AccelDead { .. } | Variant::AccelStuck { .. } => {
            let Some((from_ms, seen)) = accel_failure_seen(v, r) else {
                return;
            };
            // A precondition, like "ECU in Normal when the fault began": a fault bit still set
            // (an emulated start-up that starved the sensor) hides the detection.
            checks.check(
                ACCEL_HEALTHY_CHECK,
                !matches!(seen, FaultSeen::AlreadySet(_)),
                match seen {
                    FaultSeen::AlreadySet(t) => format!(
                        "FaultAccelSensor set since {t:+.0} ms, the sensor failed at {from_ms:+.0} ms"
                    ),
                    _ => "fault bit clear".into(),
                },
            );
            if let FaultSeen::AlreadySet(_) = seen {
                return;
            }
            checks.check(
                "accelerometer fault on the bus before the crash",
                matches!(seen, FaultSeen::Raised(t) if t < 0.0),
                match seen {
                    FaultSeen::Raised(t) => format!(
                        "FaultAccelSensor at {t:+.0} ms rel. contact, the sensor failed at \
                         {from_ms:+.0} ms"
                    ),
                    _ => format!("never reported after the sensor failed at {from_ms:+.0} ms"),
                },
            );
            if let FaultSeen::Raised(t) = seen {
                let bound_ms = accel_fault_bound_ms(v) + DETECTION_SLACK_MS;
                checks.check(
                    ACCEL_DETECTION_TIME_CHECK,
                    t - from_ms <= bound_ms,
                    format!(
                        "{:.0} ms (monitor limit + one EcuStatus period + {DETECTION_SLACK_MS:.0} ms: \
                         {bound_ms:.0} ms)",
                        t - from_ms
                    ),
                );
            }
        }
        Variant::AsIs | Variant::Dropout { .. } | Variant::Frozen { .. } => {}
    }
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

fn describe_reaction(
    case: &Case,
    report: Option<&Report>,
    modes: &[(f64, String)],
    degraded: Option<f64>,
    recovered: Option<f64>,
    fire: Option<&TimedAction>,
) -> String {
    let mut s = String::new();
    if let Some(d) = degraded {
        let _ = write!(s, "degraded after {d:.0} ms");
        match recovered {
            Some(r) if matches!(case.fault, Fault::FeedsKilled { .. }) => {
                let _ = write!(s, ", recovered {r:.0} ms after the feeds were back");
            }
            Some(r) => {
                let _ = write!(s, ", recovered {r:.0} ms after the fault ended");
            }
            None => s.push_str(", did not recover"),
        }
        s.push_str("; ");
    } else if matches!(case.fault, Fault::Lut { .. }) {
        s.push_str("reference restraint from start; ");
    }
    if let (Fault::Variant(v), Some(r)) = (&case.fault, report) {
        if let Some((from_ms, FaultSeen::Raised(t))) = accel_failure_seen(*v, r) {
            let _ = write!(
                s,
                "accelerometer fault on the bus {:.0} ms after the sensor failed; ",
                t - from_ms
            );
        }
        if let (Variant::MassMisreport { .. } | Variant::SpeedBias { .. }, Some(o)) =
            (v, r.outcome.as_ref())
        {
            let _ = write!(s, "{:+.1} % vs reference; ", o.change_pct);
        }
    }
    match fire {
        Some(a) => {
            let _ = write!(
                s,
                "airbag fired ({}) at {:+.1} ms",
                a.action.source,
                a.after_contact_ms.unwrap_or(f64::NAN)
            );
        }
        None => s.push_str("airbag not fired"),
    }
    let _ = write!(s, "; {} mode changes", modes.len());
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn commands_lost_only_by_lateness_are_a_time_limit_and_others_are_not() {
        assert!(!lost_only_late(0, 0, 0), "nothing lost: no failure at all");
        assert!(lost_only_late(1, 0, 1));
        assert!(
            lost_only_late(3, 1, 2),
            "beyond the attack allowance, all late"
        );
        assert!(!lost_only_late(2, 0, 1), "one lost without being late");
        assert!(
            !lost_only_late(1, 1, 0),
            "within the attack allowance: passes anyway"
        );
    }

    #[test]
    fn flood_frames_on_the_command_ids_are_the_receptions_beyond_the_genuine_pairs() {
        let frames: BTreeMap<String, u64> = [
            ("AirbagStageCmd", 103),
            ("AirbagStageAuth", 101),
            ("BeltLimiterCmd", 100),
            ("BeltLimiterAuth", 102),
            ("EcuStatus", 999),
            ("EgoVehicleState", 999),
        ]
        .into_iter()
        .map(|(k, v)| (k.to_owned(), v))
        .collect();
        // 200 genuine pairs = 400 frames on the four ids; 6 more arrived there.
        assert_eq!(flood_frames_on_command_ids(&frames, 200), 6);
        // Fewer receptions than genuine frames: no attacker frame is assumed.
        assert_eq!(flood_frames_on_command_ids(&frames, 300), 0);
    }

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
    fn an_accelerometer_fault_counts_only_when_it_rises_after_the_sensor_failed() {
        let f = |names: &[&str]| names.iter().map(|n| (*n).to_owned()).collect::<Vec<_>>();
        // The accel-dead case of a clean-clone run: the start-up report (no samples yet) long
        // before the failure at −600 ms, then the detection 52 ms after it.
        let run = vec![
            (
                -3760.4,
                f(&["vehicle_input", "object_input", "accel_sensor"]),
            ),
            (-3685.1, f(&["vehicle_input", "object_input", "overrun"])),
            (-3669.5, f(&["overrun"])),
            (-548.4, f(&["accel_sensor", "overrun"])),
            (29.7, f(&["object_input", "accel_sensor", "overrun"])),
        ];
        assert_eq!(
            fault_seen(&run, "accel_sensor", -600.0),
            FaultSeen::Raised(-548.4)
        );
        // Without the detection the start-up report must not stand in for it.
        let undetected: Vec<_> = run.iter().take(3).cloned().collect();
        assert_eq!(
            fault_seen(&undetected, "accel_sensor", -600.0),
            FaultSeen::Never
        );
        // Still set from start-up when the sensor failed: nothing can be seen.
        let starved = vec![
            (-3760.4, f(&["accel_sensor"])),
            (29.7, f(&["accel_sensor"])),
        ];
        assert_eq!(
            fault_seen(&starved, "accel_sensor", -600.0),
            FaultSeen::AlreadySet(-3760.4)
        );
        assert!(
            accel_fault_bound_ms(Variant::AccelDead {
                before_contact_s: 0.6
            }) > 52.0
        );
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
