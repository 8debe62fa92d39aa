//! What became of the commands the ECU sent, and the frames a disturbance put beside them.

use super::*;

/// Flood frames on the bus: everything candump saw minus what the ECU sent and the vehicle
/// and occupant frames of the feeds (a random frame with one of those two ids is counted as
/// the feeds'; 2 of 2048 ids).
pub(super) fn flood_frames(run: &RunResult) -> u64 {
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
pub(super) fn flood_frames_on_command_ids(frames: &BTreeMap<String, u64>, sent: u64) -> u64 {
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
pub(super) fn disturbance_summary(run: &RunResult) -> Option<serde_json::Value> {
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
pub(super) fn injected(run: &RunResult, summary: Option<&serde_json::Value>) -> u64 {
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

/// What became of the commands the ECU sent.
pub(super) struct Commands {
    pub(super) sent: u64,
    pub(super) authenticated: u64,
    pub(super) lost: u64,
    pub(super) denied: u64,
    pub(super) late: u64,
}

/// Whether the commands lost beyond the `allowed` ones are all accounted for by `late` ones.
/// Commands lost only because they came after the freshness window are a time limit: a
/// failure with real timers, run again where the route's timing is emulated (the emulator
/// stalled the ECU or the stubs); a command lost any other way is a function failure on every
/// route.
pub(super) fn lost_only_late(lost: u64, allowed: u64, late: u64) -> bool {
    lost > allowed && lost - allowed <= late
}

/// Checks that every genuine command was acted on and nothing else.
pub(super) fn judge_commands(
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
}
