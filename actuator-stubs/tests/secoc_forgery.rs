//! A forged fire command cannot fire the airbag: the frame a `cansend` attacker can build —
//! a correct E2E CRC and counter (public algorithms), Armed + Fire — is logged but never acted
//! on without a genuine authenticator; a genuine command + authenticator pair fires, and a
//! recorded genuine pair replayed later does not.

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

fn feed(rx: &mut Receiver, modules: &mut Modules, f: &RawFrame, t_ns: u64) -> Option<Decoded> {
    let v = rx.on_frame(f, t_ns);
    if let Some(d) = &v.act {
        modules.apply(t_ns, d);
    }
    v.act
}

const MS: u64 = 1_000_000;

#[test]
fn forged_fire_commands_do_not_fire_and_are_counted() {
    let mut rx = Receiver::new(&keys());
    let mut modules = Modules::default();
    let mut attacker = E2eProtector::new();
    let mut t = 1_000 * MS;

    // 1. Command alone (no authenticator): passes E2E, is held, never acted on.
    let cmd = airbag_cmd(&mut attacker, true);
    let v = rx.on_frame(&cmd, t);
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
    let mut forger_tx = wrong.tx(1);
    let cmd = airbag_cmd(&mut attacker, true);
    let auth = forger_tx.authenticate(&cmd).expect("auth frame");
    assert!(feed(&mut rx, &mut modules, &cmd, t).is_none());
    let v = rx.on_frame(&auth, t + 100_000);
    assert_eq!(v.e2e, "n/a");
    assert_eq!(v.secoc.as_deref(), Some("mac_mismatch"));
    assert!(v.act.is_none());

    // 3. A bare authenticator with no command (injected; the forged command above was
    // dropped after the pairing timeout): rejected.
    t += 20 * MS;
    rx.expire(t);
    assert_eq!(rx.secoc_commands_dropped(), 2);
    let v = rx.on_frame(&auth, t);
    assert_eq!(v.secoc.as_deref(), Some("no_pending_command"));

    assert!(!modules.airbag_fired, "a forged frame fired the airbag");
    assert_eq!(rx.secoc_accepted(), 0);
    let rejected = rx.secoc_rejected();
    assert_eq!(rejected.get("mac_mismatch"), Some(&1));
    assert_eq!(rejected.get("no_pending_command"), Some(&1));
    assert_eq!(rejected.len(), 2, "{rejected:?}");
    // Authenticators are not E2E frames: no E2E rejection on this sequence.
    let e2e_rejected: u64 = bus::RejectReason::ALL
        .iter()
        .map(|r| rx.checker().stats().rejected_for(*r))
        .sum();
    assert_eq!(e2e_rejected, 0);
}

#[test]
fn genuine_pair_fires_and_its_replay_is_rejected() {
    let keys = keys();
    let mut ecu_e2e = E2eProtector::new();
    let mut ecu_tx = keys.tx(1);
    let mut t = 1_000 * MS;

    // Recorded by an eavesdropper: a genuine fire pair.
    let fire = airbag_cmd(&mut ecu_e2e, true);
    let fire_auth = ecu_tx.authenticate(&fire).expect("auth frame");

    // A receiver that sees it fires — only once the authenticator arrived.
    {
        let mut rx = Receiver::new(&keys);
        let mut modules = Modules::default();
        assert!(feed(&mut rx, &mut modules, &fire, t).is_none());
        assert!(
            !modules.airbag_fired,
            "must not act before the authenticator"
        );
        let act = feed(&mut rx, &mut modules, &fire_auth, t + 150_000).expect("authenticated");
        assert!(matches!(
            act,
            Decoded::Airbag {
                armed: true,
                fire: true,
                stage: 1,
                ..
            }
        ));
        assert!(modules.airbag_fired);
        assert_eq!(rx.secoc_accepted(), 1);
    }

    // Another receiver in normal driving, fed by an ECU with the same keys: it accepts a
    // genuine NoFire pair with the recorded pair's freshness and E2E counter, then 15 more
    // (so the recorded command's 4-bit E2E counter is the next expected one again); then the
    // attacker replays the recorded fire pair.
    let mut rx = Receiver::new(&keys);
    let mut modules = Modules::default();
    let mut rx_e2e = E2eProtector::new();
    let mut rx_tx = keys.tx(1);
    let first = airbag_cmd(&mut rx_e2e, false);
    let first_auth = rx_tx.authenticate(&first).expect("auth");
    assert!(feed(&mut rx, &mut modules, &first, t).is_none());
    assert!(feed(&mut rx, &mut modules, &first_auth, t + 100_000).is_some());
    for _ in 0..15 {
        t += 10 * MS;
        let c = airbag_cmd(&mut rx_e2e, false);
        let a = rx_tx.authenticate(&c).expect("auth");
        assert!(feed(&mut rx, &mut modules, &c, t).is_none());
        assert!(feed(&mut rx, &mut modules, &a, t + 100_000).is_some());
    }
    assert!(!modules.airbag_fired);
    t += 10 * MS;
    let v = rx.on_frame(&fire, t);
    assert_eq!(
        v.e2e, "ok",
        "the replayed command's E2E counter is in sequence"
    );
    let v = rx.on_frame(&fire_auth, t + 100_000);
    assert_eq!(v.secoc.as_deref(), Some("replay"));
    assert!(v.act.is_none());
    assert!(
        !modules.airbag_fired,
        "a replayed fire pair fired the airbag"
    );
    assert_eq!(rx.secoc_rejected().get("replay"), Some(&1));
}
