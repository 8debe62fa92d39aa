//! A forged fire command cannot fire the airbag: the frame a `cansend` attacker can build —
//! a correct E2E CRC and counter (public algorithms), Armed + Fire — is logged but never acted
//! on without a genuine authenticator; a genuine command + authenticator pair fires, and a
//! recorded genuine pair replayed later — in the same session or in a later one, after the ECU
//! and the actuators restarted — does not.

use actuator_stubs::commands::{Decoded, Modules};
use actuator_stubs::rx::Receiver;
use bus::codec::{
    AirbagStageCmdArm, AirbagStageCmdCmdSource, AirbagStageCmdFire, AirbagStageCmdStage,
};
use bus::secoc::{SecOcKey, SecOcKeys};
use bus::{AirbagStageCmd, E2eProtector, RawFrame};

fn keys() -> SecOcKeys {
    let p =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../data/secoc-keys.example.toml");
    SecOcKeys::load(&p).expect("example keys")
}

/// An AirbagStageCmd, E2E-sealed by `protector` (as a forger with the DBC would).
fn airbag_cmd(protector: &mut E2eProtector, fire: bool) -> RawFrame {
    let m = AirbagStageCmd::encode(
        AirbagStageCmdArm::Armed,
        if fire {
            AirbagStageCmdFire::Fire
        } else {
            AirbagStageCmdFire::NoFire
        },
        AirbagStageCmdCmdSource::Adaptive,
        AirbagStageCmdStage::Stage1,
        6.0,
        0.0,
    )
    .expect("encodable");
    protector.seal(m)
}

/// Synchronized time (µs since the UNIX epoch) at monotonic `t_ns` of the first session: the
/// bench's CLOCK_REALTIME, here a fixed 2025 date so the test is reproducible.
fn sync(t_ns: u64) -> u64 {
    1_750_000_000_000_000 + t_ns / 1_000
}

fn feed(rx: &mut Receiver, modules: &mut Modules, f: &RawFrame, t_ns: u64) -> Option<Decoded> {
    let v = rx.on_frame(f, t_ns, sync(t_ns));
    if let Some(d) = &v.act {
        modules.apply(t_ns, d);
    }
    v.act
}

const MS: u64 = 1_000_000;
const S: u64 = 1_000 * MS;

#[test]
fn forged_fire_commands_do_not_fire_and_are_counted() {
    let mut rx = Receiver::new(&keys());
    let mut modules = Modules::default();
    let mut attacker = E2eProtector::new();
    let mut t = 1_000 * MS;

    // 1. Command alone (no authenticator): passes E2E, is held, never acted on.
    let cmd = airbag_cmd(&mut attacker, true);
    let v = rx.on_frame(&cmd, t, sync(t));
    assert_eq!(v.e2e, "ok", "the forgery has a valid E2E protection");
    assert_eq!(v.secoc.as_deref(), Some("held"));
    assert!(v.act.is_none());
    t += 20 * MS;
    rx.expire(t);
    assert_eq!(rx.secoc_commands_dropped(), 1);

    // 2. Command + authenticator computed with a guessed key.
    let wrong = SecOcKeys::new(
        SecOcKey::from_bytes([0x5a; 16]),
        SecOcKey::from_bytes([0xa5; 16]),
    );
    let mut forger_tx = wrong.tx();
    let cmd = airbag_cmd(&mut attacker, true);
    let auth = forger_tx.authenticate(&cmd, sync(t)).expect("auth frame");
    assert!(feed(&mut rx, &mut modules, &cmd, t).is_none());
    let v = rx.on_frame(&auth, t + 100_000, sync(t + 100_000));
    assert_eq!(v.e2e, "n/a");
    assert_eq!(v.secoc.as_deref(), Some("mac_mismatch"));
    assert!(v.act.is_none());

    // 3. A bare authenticator with no command (injected; the forged command above was
    // dropped after the pairing timeout): rejected.
    t += 20 * MS;
    rx.expire(t);
    assert_eq!(rx.secoc_commands_dropped(), 2);
    let v = rx.on_frame(&auth, t, sync(t));
    assert_eq!(v.secoc.as_deref(), Some("no_pending_command"));

    assert!(!modules.airbag_fired, "a forged frame fired the airbag");
    assert_eq!(rx.secoc_accepted(), 0);
    let rejected = rx.secoc_rejected();
    assert_eq!(rejected.get("mac_mismatch"), Some(&1));
    assert_eq!(rejected.get("no_pending_command"), Some(&1));
    assert_eq!(rejected.len(), 2, "{rejected:?}");
    // Authenticators are not E2E frames: no E2E rejection on this sequence.
    let e2e_rejected: u64 = <bus::RejectReason as bus::VariantArray>::VARIANTS
        .iter()
        .map(|r| rx.checker().stats().rejected_for(*r))
        .sum();
    assert_eq!(e2e_rejected, 0);
}

fn assert_fire(act: &Decoded) {
    assert!(
        matches!(
            act,
            Decoded::Airbag {
                armed: true,
                fire: true,
                stage: 1,
                ..
            }
        ),
        "{act:?}"
    );
}

#[test]
fn genuine_pair_fires_and_its_replay_in_the_session_is_rejected() {
    let keys = keys();
    let mut ecu_e2e = E2eProtector::new();
    let mut ecu_tx = keys.tx();
    let t = 1_000 * MS;

    let fire = airbag_cmd(&mut ecu_e2e, true);
    let fire_auth = ecu_tx.authenticate(&fire, sync(t)).expect("auth frame");

    // The receiver fires — only once the authenticator arrived.
    let mut rx = Receiver::new(&keys);
    let mut modules = Modules::default();
    assert!(feed(&mut rx, &mut modules, &fire, t).is_none());
    assert!(
        !modules.airbag_fired,
        "must not act before the authenticator"
    );
    let act = feed(&mut rx, &mut modules, &fire_auth, t + 150_000).expect("authenticated");
    assert_fire(&act);
    assert!(modules.airbag_fired);
    assert_eq!(rx.secoc_accepted(), 1);

    // 15 more genuine NoFire pairs 1 ms apart (so that the recorded command's 4-bit E2E
    // counter is the next expected one again), then the recorded pair sent again 20 ms after
    // the original — inside the freshness window, but its freshness value is used: a replay.
    let mut modules = Modules::default();
    let mut t2 = t;
    for _ in 0..15 {
        t2 += MS;
        let c = airbag_cmd(&mut ecu_e2e, false);
        let a = ecu_tx.authenticate(&c, sync(t2)).expect("auth");
        assert!(feed(&mut rx, &mut modules, &c, t2).is_none());
        assert!(feed(&mut rx, &mut modules, &a, t2 + 100_000).is_some());
    }
    let t2 = t + 20 * MS;
    let v = rx.on_frame(&fire, t2, sync(t2));
    assert_eq!(v.secoc.as_deref(), Some("held"), "passes E2E: {v:?}");
    let v = rx.on_frame(&fire_auth, t2 + 100_000, sync(t2 + 100_000));
    assert_eq!(v.secoc.as_deref(), Some("replay"));
    assert!(v.act.is_none());
    assert!(!modules.airbag_fired);
    assert_eq!(rx.secoc_rejected().get("replay"), Some(&1));
}

/// The replay hole: a genuine Armed + Fire pair recorded in one session (candump during a crash
/// test) and replayed with cansend in a *later* session, after ECU and actuators restarted.
/// With a freshness counter restarting at 1 it was ahead of the new session's counter and
/// fired the airbag; with time-stamp freshness it is rejected — `freshness_stale` when the
/// recording is up to ~25 s old, `mac_mismatch` beyond (the frame carries only 24 bits of its
/// time stamp, so an old recording looks like any forgery) — while the new session's genuine
/// commands, a genuine fire included, are accepted.
#[test]
fn pair_recorded_in_an_earlier_session_does_not_fire_later() {
    let keys = keys();
    // Session 1: the recording.
    let t1 = 1_000 * MS;
    let mut ecu1_e2e = E2eProtector::new();
    let mut ecu1_tx = keys.tx();
    let fire = airbag_cmd(&mut ecu1_e2e, true);
    let fire_auth = ecu1_tx.authenticate(&fire, sync(t1)).expect("auth frame");

    for (later, reason) in [(60 * S, "mac_mismatch"), (5 * S, "freshness_stale")] {
        // Session 2: new ECU (new E2E protector, new SecOC sender), new actuator receiver,
        // normal driving: genuine NoFire pairs every 10 ms, all accepted. 16 of them, so that
        // the recorded command's 4-bit E2E counter is the next expected one again.
        let mut t = t1 + later;
        let mut rx = Receiver::new(&keys);
        let mut modules = Modules::default();
        let mut ecu2_e2e = E2eProtector::new();
        let mut ecu2_tx = keys.tx();
        for _ in 0..16 {
            let c = airbag_cmd(&mut ecu2_e2e, false);
            let a = ecu2_tx.authenticate(&c, sync(t)).expect("auth");
            assert!(feed(&mut rx, &mut modules, &c, t).is_none());
            assert!(feed(&mut rx, &mut modules, &a, t + 100_000).is_some());
            t += 10 * MS;
        }
        assert_eq!(rx.secoc_accepted(), 16);
        // The attacker replays the recorded pair.
        let v = rx.on_frame(&fire, t, sync(t));
        assert_eq!(
            v.e2e, "ok",
            "the replayed command passes E2E (its counter is in sequence)"
        );
        assert_eq!(v.secoc.as_deref(), Some("held"));
        let v = rx.on_frame(&fire_auth, t + 100_000, sync(t + 100_000));
        assert_eq!(
            v.secoc.as_deref(),
            Some(reason),
            "recorded {} s earlier",
            later / S
        );
        assert!(v.act.is_none());
        assert!(
            !modules.airbag_fired,
            "a pair recorded in an earlier session fired the airbag"
        );
        assert_eq!(rx.secoc_rejected().get(reason), Some(&1));
        assert_eq!(rx.secoc_rejected().len(), 1);
        // Session 2's own genuine fire command still works. (The replay took the E2E counter
        // value of the ECU's next frame, which E2E would reject as a repetition; skip it.)
        t += 10 * MS;
        let _repeated_counter = airbag_cmd(&mut ecu2_e2e, false);
        let c = airbag_cmd(&mut ecu2_e2e, true);
        let a = ecu2_tx.authenticate(&c, sync(t)).expect("auth");
        assert!(feed(&mut rx, &mut modules, &c, t).is_none());
        let act = feed(&mut rx, &mut modules, &a, t + 100_000).expect("genuine fire accepted");
        assert_fire(&act);
        assert!(modules.airbag_fired);
        assert_eq!(rx.secoc_accepted(), 17);
        assert_eq!(rx.secoc_rejected().len(), 1);
    }
}
