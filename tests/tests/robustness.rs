//! The fault-injection campaign (tests/src/faults/) end to end: real ecu, sensor-feeds,
//! actuator-stubs, candump, cansend, cangen and bus-inject on vcan — on the host if its kernel
//! has vcan, else inside the QEMU guest (one boot; where guests run in virtual time, one per host
//! CPU side by side, each on a share of the cases with its own baseline); with no route the tests
//! FAIL (never skipped). The campaign runs once (first test to get here) and writes
//! `target/robustness/campaign.json` (the guests' parts merged),
//! which `test.sh` prints as the robustness report together with the fuzzing figures.

use e2e_tests::faults::{cases, merge_campaigns, report_text, Campaign, Fault};
use e2e_tests::harness::{bin_dir, build_bench_bins, deal, parallel_guests, run_in_guests};
use e2e_tests::timeline::draw_timeline;
use std::ffi::OsString;
use std::path::PathBuf;
use std::process::Command;
use std::sync::{Mutex, OnceLock};

/// The campaign and the host timing runs take turns: run side by side they would measure each
/// other (2 vCPUs; the timed ECU runs at SCHED_FIFO, an emulated guest's timing follows the
/// host's load).
static SERIAL: Mutex<()> = Mutex::new(());

fn root() -> PathBuf {
    e2e_tests::repo_root()
}

/// Keeps an artefact in `target/robustness/`, where test.sh's robustness report reads it.
fn keep(name: &str, bytes: &[u8]) {
    let dir = root().join("target/robustness");
    std::fs::create_dir_all(&dir).expect("target/robustness");
    std::fs::write(dir.join(name), bytes).unwrap_or_else(|e| panic!("writing {name}: {e}"));
}

/// Runs the campaign once; returns it.
fn campaign() -> &'static Campaign {
    static RUN: OnceLock<Campaign> = OnceLock::new();
    RUN.get_or_init(|| {
        let _turn = SERIAL
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        build_bench_bins();
        e2e_tests::harness::vcan_route();
        let out = bin_dir().join("robustness");
        let _ = std::fs::remove_dir_all(&out);
        // The fault cases dealt over guests side by side where they run in virtual time
        // (harness::parallel_guests); every guest runs its own baseline first, which its cases
        // are judged against, and the parts are merged into one campaign.
        let faults: Vec<&str> = cases()
            .iter()
            .filter(|k| k.fault != Fault::None)
            .map(|k| k.name)
            .collect();
        let groups = deal(&faults, parallel_guests());
        let dirs: Vec<PathBuf> = (0..groups.len())
            .map(|k| out.join(format!("guest-{}", k + 1)))
            .collect();
        let runs = groups
            .iter()
            .zip(&dirs)
            .map(|(group, dir)| {
                let mut args: Vec<OsString> = vec![
                    bin_dir().join("fault-campaign").into(),
                    "run".into(),
                    "--out".into(),
                    dir.into(),
                    "--repo".into(),
                    root().into(),
                ];
                for name in group {
                    args.push("--case".into());
                    args.push(name.into());
                }
                args
            })
            .collect();
        let outputs = run_in_guests("fault-campaign", &out, runs);
        let mut parts = Vec::new();
        for (o, dir) in outputs.iter().zip(&dirs) {
            let path = dir.join("campaign.json");
            let text = std::fs::read_to_string(&path).unwrap_or_else(|e| {
                panic!("{}: {e} (fault-campaign exit {})", path.display(), o.status)
            });
            let part: Campaign =
                serde_json::from_str(&text).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            parts.push(part);
        }
        let merged = merge_campaigns(parts);
        let text = serde_json::to_string_pretty(&merged).expect("campaign json");
        std::fs::write(out.join("campaign.json"), &text).expect("campaign.json");
        draw_timeline(&merged, &out.join("campaign.png")).expect("campaign timeline");
        keep("campaign.json", text.as_bytes());
        merged
    })
}

#[test]
fn every_fault_case_ran_and_passed_its_checks() {
    let c = campaign();
    let names: Vec<&str> = c.cases.iter().map(|r| r.name.as_str()).collect();
    let want: Vec<&str> = cases().iter().map(|k| k.name).collect();
    assert_eq!(names, want, "every case of the campaign ran, in order");
    let failed: Vec<String> = c
        .cases
        .iter()
        .filter(|r| !r.pass)
        .map(|r| {
            let why: Vec<String> = r
                .checks
                .iter()
                .filter(|k| !k.ok)
                .map(|k| format!("{}: {}", k.what, k.detail))
                .collect();
            format!("{}: {}", r.name, why.join("; "))
        })
        .collect();
    assert!(failed.is_empty(), "failed cases:\n{}", failed.join("\n"));
}

#[test]
fn the_campaign_timeline_is_drawn() {
    campaign();
    let png = bin_dir().join("robustness/campaign.png");
    let bytes = std::fs::metadata(&png)
        .unwrap_or_else(|e| panic!("{}: {e}", png.display()))
        .len();
    assert!(bytes > 10_000, "{}: {bytes} bytes", png.display());
    keep(
        "campaign.png",
        &std::fs::read(&png).expect("read campaign.png"),
    );
}

#[test]
fn no_genuine_command_is_lost_and_nothing_forged_is_acted_on() {
    for r in &campaign().cases {
        assert!(
            r.commands_sent > 100,
            "{}: {} commands",
            r.name,
            r.commands_sent
        );
        assert!(
            r.commands_authenticated <= r.commands_sent,
            "{}: acted on {} commands, the ECU sent {}",
            r.name,
            r.commands_authenticated,
            r.commands_sent
        );
        assert_eq!(
            r.commands_lost - r.commands_denied_by_attack,
            0,
            "{}: genuine commands lost",
            r.name
        );
    }
}

#[test]
fn forged_and_replayed_fire_commands_never_fire_the_airbag() {
    let c = campaign();
    for name in ["forged-fire", "replayed-fire"] {
        let r = c.cases.iter().find(|r| r.name == name).expect(name);
        assert!(!r.airbag_fired, "{name}: the airbag fired");
        assert!(
            r.frames_injected >= 2,
            "{name}: {} frames sent with cansend",
            r.frames_injected
        );
        let secoc: u64 = r
            .frames_rejected
            .iter()
            .filter(|(k, _)| k.starts_with("stubs:secoc:"))
            .map(|(_, n)| n)
            .sum();
        assert!(
            secoc > 0,
            "{name}: SecOC rejected nothing: {:?}",
            r.frames_rejected
        );
    }
}

/// The error frames of the bus-fault case, as the field's readers see them: asammdf finds
/// them in run.mf4's CAN_ErrorFrame group, Foxglove's `mcap` on /can/error of run.mcap, each
/// against candump.log (record/check_mf4.py, record/check_mcap.py).
#[test]
fn the_error_frames_of_the_bus_fault_case_are_in_both_recordings() {
    let c = campaign();
    let r = c
        .cases
        .iter()
        .find(|r| r.name == "can-errors")
        .expect("can-errors");
    assert!(
        r.frames_injected > 10,
        "{} error frames sent",
        r.frames_injected
    );
    let dir = PathBuf::from(&r.dir);
    let s = record::write_run_mf4(&dir, &dir.join(record::RUN_MF4)).expect("run.mf4");
    assert_eq!(s.error_frames as u64, r.frames_injected);
    let text = e2e_tests::harness::check_mf4(&[&dir]).unwrap_or_else(|e| panic!("{e}"));
    let all = format!("all {} error frames", r.frames_injected);
    assert!(text.contains(&format!("CAN_ErrorFrame: {all}")), "{text}");
    let text = e2e_tests::harness::check_recording(&dir, false).unwrap_or_else(|e| panic!("{e}"));
    assert!(text.contains(&format!("/can/error: {all}")), "{text}");
}

#[test]
fn the_robustness_report_names_every_figure() {
    let c = campaign();
    let text = report_text(c, None);
    eprintln!("{text}");
    for figure in [
        "cases tried",
        "faults survived",
        "commands lost      0",
        "deadline misses",
        "frames rejected by reason",
        "inputs fuzzed",
    ] {
        assert!(text.contains(figure), "report lacks {figure:?}:\n{text}");
    }
    let faults = cases().iter().filter(|k| k.fault != Fault::None).count();
    assert!(
        text.contains(&format!("faults survived    {faults} of {faults}")),
        "{text}"
    );
}

/// The iceoryx2 faults on the host kernel (real timers; CAN side off, named in the output):
/// the runs happen and the ECU notices the object faults. Deadline figures are printed, never
/// asserted (a noisy 2-vCPU VM without PREEMPT_RT; the budgets are in benches/).
#[test]
fn host_timing_runs_the_ipc_faults_with_real_timers() {
    let _turn = SERIAL
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let out = bin_dir().join("host-timing");
    let o = Command::new(bin_dir().join("fault-campaign"))
        .arg("host-timing")
        .arg("--out")
        .arg(&out)
        .arg("--repo")
        .arg(root())
        .current_dir(root())
        .output()
        .expect("fault-campaign host-timing");
    let stdout = String::from_utf8_lossy(&o.stdout);
    eprintln!("{stdout}\n{}", String::from_utf8_lossy(&o.stderr));
    assert!(o.status.success(), "host-timing failed: {}", o.status);
    assert!(
        stdout.contains("--no-can"),
        "the report names the CAN side as off"
    );
    let text = std::fs::read_to_string(out.join("host-timing.json")).expect("host-timing.json");
    let h: e2e_tests::host_timing::HostTiming = serde_json::from_str(&text).expect("json");
    let run = |n: &str| {
        h.runs
            .iter()
            .find(|r| r.name == n)
            .unwrap_or_else(|| panic!("{n}"))
    };
    let base = run("baseline");
    for r in &h.runs {
        assert!(r.cycles > 2000, "{}: {} cycles", r.name, r.cycles);
    }
    for n in ["feeds-killed", "stale-objects"] {
        assert!(
            run(n).object_faults > base.object_faults + 50,
            "{n}: the ECU did not notice ({} object-fault cycles vs baseline {})",
            run(n).object_faults,
            base.object_faults
        );
    }
    keep("host-timing.json", text.as_bytes());
}
