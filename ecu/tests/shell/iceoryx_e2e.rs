//! Real iceoryx2 round trip through the full ECU process body (`app::run_ecu`):
//! a feed publishes object states and accelerometer batches, the ECU receives them
//! (read in place from shared memory) and publishes diagnostics that a subscriber reads.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use crate::support;

use ecu::runtime::{app, EcuConfig};
use ipc::{
    AccelPublisher, CrashAccelSample, Degraded, DiagnosticsSubscriber, EcuDiagnostics, EcuMode,
    ObjectPublisher, ObjectState, ServiceNames, VALID,
};
use support::passthrough::PassthroughActivity;

/// Generous bound for "the ECU eventually reacts"; only a functional failure hits it.
const PATIENCE: Duration = Duration::from_secs(30);

fn wait_for(
    sub: &mut DiagnosticsSubscriber,
    what: &str,
    pred: impl Fn(&EcuDiagnostics) -> bool,
) -> EcuDiagnostics {
    let t0 = Instant::now();
    loop {
        if let Some(d) = sub.latest() {
            if pred(&d) {
                return d;
            }
        }
        assert!(t0.elapsed() < PATIENCE, "ECU never reached: {what}");
        std::thread::sleep(Duration::from_millis(1));
    }
}

#[test]
fn feed_to_ecu_to_diagnostics_subscriber() {
    let prefix = format!("ecu-e2e-{}", std::process::id());
    let mut cfg = EcuConfig {
        period_us: 500,
        ..EcuConfig::default()
    };
    cfg.can.enabled = false;
    cfg.ipc.service_prefix.clone_from(&prefix);
    cfg.ipc.node_name = format!("ecu-e2e-{}", std::process::id());
    cfg.rt.prefault_stack_kib = 0;

    let stop = Arc::new(AtomicBool::new(false));
    let ecu = {
        let stop = stop.clone();
        std::thread::spawn(move || {
            let mut activity = PassthroughActivity::new();
            app::run_ecu(&cfg, &mut activity, None, &stop, false, None).map(|o| o.json)
        })
    };

    let names = ServiceNames::with_prefix(&prefix);
    let (node, _) = ipc::create_node("ecu-e2e-feed", false).unwrap();
    let mut diag = DiagnosticsSubscriber::new(&node, &names).unwrap();
    let mut objects = ObjectPublisher::new(&node, &names).unwrap();
    let mut accel = AccelPublisher::new(&node, &names).unwrap();

    // The ECU is up (its subscribers exist) once it publishes.
    let first = wait_for(&mut diag, "first diagnostics", |d| d.cycle_count > 0);
    assert_eq!(first.mode, EcuMode::Monitoring as u8);
    assert_ne!(first.degraded_reasons & Degraded::CAN_DISABLED.bits(), 0);

    for seq in 1..=50u64 {
        objects
            .publish_with(ObjectState::INVALID, |o| {
                o.sequence = seq;
                o.distance_m = 30.0 - seq as f32 * 0.1;
                o.closing_speed_mps = 15.0;
                o.opponent_mass_kg = 1500.0;
                o.valid = VALID;
            })
            .unwrap();
        if seq <= 20 {
            accel
                .publish_with(CrashAccelSample::EMPTY, |a| {
                    a.sequence = seq;
                    a.count = 8;
                })
                .unwrap();
        }
        std::thread::sleep(Duration::from_millis(1));
    }

    let d = wait_for(&mut diag, "last object and accel sequence", |d| {
        d.last_object_sequence == 50 && d.last_accel_sequence == 20
    });
    assert!(
        d.object_samples_rx >= 1 && d.object_samples_rx <= 50,
        "{d:?}"
    );
    assert!(d.accel_batches_rx >= 1 && d.accel_batches_rx <= 20, "{d:?}");
    // Fresh object state → not stale.
    let fresh = wait_for(&mut diag, "object not stale", |d| {
        d.degraded_reasons & Degraded::OBJECT_STALE.bits() == 0
    });
    assert_eq!(fresh.last_object_sequence, 50);

    stop.store(true, Ordering::Relaxed);
    let json = ecu.join().unwrap().unwrap();
    let v: serde_json::Value = serde_json::from_str(&json).unwrap();
    assert_eq!(v["stop_reason"], "signal");
    assert_eq!(v["can"]["enabled"], false);
    let rx = v["ipc"]["object_rx"].as_u64().unwrap();
    assert!((1..=50).contains(&rx), "{v}");
    assert_eq!(v["counters"]["objects_rx"].as_u64(), Some(rx));
    assert_eq!(
        v["counters"]["accel_samples_rx"].as_u64(),
        Some(8 * v["ipc"]["accel_rx"].as_u64().unwrap())
    );
    assert!(v["ipc"]["diagnostics_tx"].as_u64().unwrap() >= 1);
    assert!(v["cycles"].as_u64().unwrap() >= 1);
}
