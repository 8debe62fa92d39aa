//! Deadline misses attributable to faults, measured where timers are real: the iceoryx2 faults
//! of the campaign (feeds killed and restarted, stale object data, a stale service left by a
//! killed process) run on the HOST kernel with the ECU at SCHED_FIFO 80, mlockall, pinned to
//! one CPU. The project's CI hosts have no SocketCAN and no KVM that runs a stock kernel, so
//! **the ECU's and the feeds' CAN side is switched off (`--no-can`)** — the report says so; the
//! bus faults are covered functionally by the vcan campaign (in the QEMU TCG guest there, where
//! timing is emulated; on a host with vcan or KVM that campaign has real timers itself).
//!
//! A fault "costs" deadlines when its run has more overruns (or a worse wake-up tail) than the
//! clean runs around it. The VM is noisy: the baseline runs first and last, and the report puts
//! every run side by side; nothing here fails on wall-clock figures (the caller decides; the
//! test only checks that the runs happened and the ECU reacted).

use crate::faults::{frozen_scenario, CaseDisturbance, Fault, CRASH_SCENARIO};
use crate::{read_epoch, Disturbance, RunConfig, RunCtx};
use anyhow::{bail, Context, Result};
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;
use std::path::PathBuf;
use std::process::{Command, Stdio};
use std::time::Duration;

/// One timed run.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct TimedRun {
    /// Case name.
    pub name: String,
    /// ECU cycles.
    pub cycles: u64,
    /// Deadline misses (overruns).
    pub overruns: u64,
    /// Cycles with stale object data after the first object arrived (`object_lost_cycles`: the
    /// start-up wait for the feeds, which a loaded host stretches by hundreds of cycles, is not
    /// the fault) plus object samples rejected as invalid (too old): the ECU noticed the fault. (Degraded cycles say nothing here: without CAN there is no
    /// occupant classification, so the ECU runs on the reference restraint throughout.)
    pub object_faults: u64,
    /// Wake-up latency p50 / p99 / p99.9 / max [µs].
    pub wake_us: [f64; 4],
    /// Execution time p50 / p99 / p99.9 / max [µs].
    pub exec_us: [f64; 4],
    /// Real-time settings the ECU got (e.g. "SCHED_FIFO priority 80").
    pub sched: String,
}

/// All timed runs.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct HostTiming {
    /// Why the CAN side is off.
    pub can: String,
    /// Runs in order (baseline first and last).
    pub runs: Vec<TimedRun>,
    /// Where the other bench processes ran, e.g. "CPU 1 to the ECU alone; feeds on CPUs 0".
    #[serde(default)]
    pub cpus: String,
}

impl HostTiming {
    /// `schema_version` of `host-timing.json` (docs/using.md, "JSON results").
    pub const SCHEMA_VERSION: u32 = 1;
}

/// Where the runs happen.
#[derive(Clone, Debug)]
pub struct HostTimingConfig {
    /// Output root.
    pub out: PathBuf,
    /// Bench binaries.
    pub bin_dir: PathBuf,
    /// Repository root.
    pub repo: PathBuf,
    /// CPU the ECU is pinned to.
    pub cpu: u32,
}

/// The runs: baseline, the three iceoryx2 faults, baseline again.
pub fn host_cases() -> Vec<(&'static str, Fault)> {
    vec![
        ("baseline", Fault::None),
        (
            "feeds-killed",
            Fault::FeedsKilled {
                kill_s: 0.4,
                restart_s: 0.7, // the host starts a process in milliseconds
            },
        ),
        (
            "stale-objects",
            Fault::StaleObjects {
                from_s: 0.4,
                to_s: 0.7,
            },
        ),
        ("stale-service", Fault::StaleService),
        ("baseline-again", Fault::None),
    ]
}

fn pcts(e: &serde_json::Value, key: &str) -> [f64; 4] {
    let p = |q: &str| {
        e.get(key)
            .and_then(|v| v.get(q))
            .and_then(serde_json::Value::as_f64)
            .unwrap_or(f64::NAN)
    };
    [p("p50"), p("p99"), p("p999"), p("max")]
}

/// Runs every host case once.
pub fn run_host_timing(cfg: &HostTimingConfig) -> Result<HostTiming> {
    let mut out = HostTiming {
        can: "off (--no-can): this host kernel has no SocketCAN".into(),
        runs: Vec::new(),
        cpus: keep_off_cpu(cfg.cpu),
    };
    for (i, (name, fault)) in host_cases().into_iter().enumerate() {
        eprintln!("host-timing: {name}");
        let dir = cfg.out.join(name);
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir)?;
        let mut scenario = cfg
            .repo
            .join("scenarios")
            .join(format!("{CRASH_SCENARIO}.toml"));
        if let Fault::StaleObjects { from_s, to_s } = fault {
            scenario = frozen_scenario(&scenario, &dir.join("scenario"), from_s, to_s)?;
        }
        let run = RunConfig {
            scenario,
            out: dir.clone(),
            can: String::new(),
            bin_dir: cfg.bin_dir.clone(),
            service_prefix: format!("host-timing-{}-{i}", std::process::id()),
            ecu_args: Vec::new(),
            ecu_cwd: cfg.repo.clone(),
            stubs_args: Vec::new(),
            replay: None,
        };
        let mut dist = CaseDisturbance {
            fault: &fault,
            frames: Vec::new(),
        };
        dist.prepare(&run, &dir)?;
        let report = dir.join("ecu-report.json");
        let mut ecu = Command::new(cfg.bin_dir.join("ecu"))
            .args(["--no-can", "--quiet", "--sched-fifo", "80", "--mlockall"])
            .arg("--cpu")
            .arg(cfg.cpu.to_string())
            .args(["--service-prefix", &run.service_prefix])
            .arg("--node-name")
            .arg(format!("ecu-timing-{}", std::process::id()))
            .arg("--json")
            .arg(&report)
            .current_dir(&cfg.repo)
            .stdout(Stdio::null())
            .spawn()
            .context("starting the ECU")?;
        std::thread::sleep(Duration::from_millis(300));
        let scenario = world::Scenario::load(&run.scenario)?;
        let mut feeds = crate::feeds_command(&run, None, None)
            .stdout(Stdio::piped())
            .spawn()
            .context("starting sensor-feeds")?;
        let epoch_ns = read_epoch(&mut feeds)?;
        let ctx = RunCtx {
            cfg: &run,
            scenario: &scenario,
            dir: dir.clone(),
            epoch_ns,
        };
        let st = dist.feeds_running(&ctx, &mut feeds)?;
        if !st.success() {
            bail!("{name}: sensor-feeds {st}");
        }
        let st = crate::terminate(&mut ecu, "ecu", Duration::from_secs(5))?;
        if !st.success() {
            bail!("{name}: ecu {st}");
        }
        let text = std::fs::read_to_string(&report)
            .with_context(|| format!("reading {}", report.display()))?;
        let e: serde_json::Value = serde_json::from_str(&text)?;
        let num = |p: &str| {
            e.pointer(p)
                .and_then(serde_json::Value::as_u64)
                .unwrap_or(0)
        };
        out.runs.push(TimedRun {
            name: name.to_owned(),
            cycles: num("/cycles"),
            overruns: num("/overruns"),
            object_faults: num("/counters/object_lost_cycles") + num("/counters/objects_invalid"),
            wake_us: pcts(&e, "wake_latency_us"),
            exec_us: pcts(&e, "exec_us"),
            sched: e
                .pointer("/rt/sched/detail")
                .and_then(serde_json::Value::as_str)
                .unwrap_or("?")
                .to_owned(),
        });
    }
    Ok(out)
}

/// Moves this process (and so every process it starts: the feeds, a restarted feed, the stale
/// service's victims) off the ECU's CPU, as a bench isolates the CPU of the device under test:
/// a fault then reaches the ECU only through what it shares with the feeds (IPC, the kernel),
/// not through a process start or exit on its CPU. The ECU pins itself back (`--cpu`).
/// Returns the arrangement in words.
fn keep_off_cpu(ecu_cpu: u32) -> String {
    use nix::sched::{sched_getaffinity, sched_setaffinity, CpuSet};
    use nix::unistd::Pid;
    let Ok(mine) = sched_getaffinity(Pid::from_raw(0)) else {
        return "not isolated (affinity unreadable)".into();
    };
    let mut others = CpuSet::new();
    let mut names = Vec::new();
    for c in 0..CpuSet::count() {
        if c != ecu_cpu as usize && mine.is_set(c).unwrap_or(false) {
            let _ = others.set(c);
            names.push(c.to_string());
        }
    }
    if names.is_empty() {
        return format!("CPU {ecu_cpu} shared with the feeds (no other CPU)");
    }
    match sched_setaffinity(Pid::from_raw(0), &others) {
        Ok(()) => format!(
            "CPU {ecu_cpu} to the ECU alone; feeds and bench on CPU {}",
            names.join(",")
        ),
        Err(e) => format!("CPU {ecu_cpu} shared with the feeds (affinity: {e})"),
    }
}

/// The table of the runs.
pub fn host_timing_text(h: &HostTiming) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "deadline misses on the host kernel (1 kHz, ECU CAN side {}; {}):",
        h.can,
        if h.cpus.is_empty() {
            "CPUs not recorded"
        } else {
            &h.cpus
        }
    );
    let _ = writeln!(
        s,
        "  {:<15} {:>6} {:>8} {:>9}   {:>28}   {:>26}  sched",
        "run",
        "cycles",
        "overrun",
        "obj fault",
        "wake p50/p99/p99.9/max µs",
        "exec p50/p99/p99.9/max µs"
    );
    for r in &h.runs {
        let f = |v: &[f64; 4]| format!("{:.0}/{:.0}/{:.0}/{:.0}", v[0], v[1], v[2], v[3]);
        let g = |v: &[f64; 4]| format!("{:.1}/{:.1}/{:.1}/{:.0}", v[0], v[1], v[2], v[3]);
        let _ = writeln!(
            s,
            "  {:<15} {:>6} {:>8} {:>9}   {:>28}   {:>26}  {}",
            r.name,
            r.cycles,
            r.overruns,
            r.object_faults,
            f(&r.wake_us),
            g(&r.exec_us),
            r.sched
        );
    }
    let base: Vec<&TimedRun> = h
        .runs
        .iter()
        .filter(|r| r.name.starts_with("baseline"))
        .collect();
    let worst_base = base.iter().map(|r| r.overruns).max().unwrap_or(0);
    let extra: u64 = h
        .runs
        .iter()
        .filter(|r| !r.name.starts_with("baseline"))
        .map(|r| r.overruns.saturating_sub(worst_base))
        .sum();
    let _ = writeln!(
        s,
        "  deadline misses beyond the clean runs' worst ({worst_base}): {extra}"
    );
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_bench_leaves_the_ecus_cpu_to_the_ecu() {
        use nix::sched::sched_getaffinity;
        use nix::unistd::Pid;
        // Affinity is per thread: a thread of its own keeps the test runner as it was.
        std::thread::spawn(|| {
            let before = sched_getaffinity(Pid::from_raw(0)).expect("affinity");
            let n = (0..nix::sched::CpuSet::count())
                .filter(|c| before.is_set(*c).unwrap_or(false))
                .count();
            let said = keep_off_cpu(0);
            let after = sched_getaffinity(Pid::from_raw(0)).expect("affinity");
            if n > 1 && before.is_set(0).unwrap_or(false) {
                assert!(!after.is_set(0).unwrap(), "{said}");
                assert!(said.starts_with("CPU 0 to the ECU alone"), "{said}");
            } else {
                assert!(
                    said.contains("shared") || !before.is_set(0).unwrap(),
                    "{said}"
                );
            }
        })
        .join()
        .expect("thread");
    }
}
