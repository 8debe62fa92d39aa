//! End-to-end tests of the real bench processes (see tests/tests/) and the bench orchestration
//! they share with the demo (`hil-bench`).
//!
//! One scenario run: `candump -L IF > candump.log`, `actuator-stubs`, `ecu --json`, then
//! `sensor-feeds` (which plays the scenario in real time); when the feeds finish the stubs see
//! the bench truth's `done` and judge; then the ECU and candump get SIGTERM. Everything a run
//! produced lands in `OUT/<scenario>/`. Every run uses its own iceoryx2 service prefix, so
//! leftovers of an earlier (killed) run can never be mistaken for this run's samples.

pub mod docs;
pub mod expect;
pub mod faults;
pub mod harness;
pub mod host_timing;
pub mod misuse;
pub mod offline;
pub mod offline_plot;
pub mod replay;
pub mod route;
mod run;
mod summary;
pub mod timeline;

pub use route::{Allowances, Route};
pub use run::*;
pub use summary::*;

use anyhow::{Context, Result};
use std::path::{Path, PathBuf};

/// How an EcuStatus fault flag showed for a failure that began at `from_ms`, given the ECU's
/// flag changes `(ms, set flags)` on the same time axis. A flag set long before — e.g. the
/// accelerometer reported faulty at start-up, before its first batch — is not a detection of
/// this failure: only a rise after it counts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FaultSeen {
    /// Raised at this time; the flag was clear when the failure began.
    Raised(f64),
    /// Already set when the failure began (by the change at this time): nothing to see.
    AlreadySet(f64),
    /// Not raised after the failure began.
    Never,
}

/// See [`FaultSeen`].
pub fn fault_seen(changes: &[(f64, Vec<String>)], flag: &str, from_ms: f64) -> FaultSeen {
    let has = |f: &[String]| f.iter().any(|n| n == flag);
    let at_failure = changes.iter().take_while(|(t, _)| *t <= from_ms).last();
    if let Some((t, _)) = at_failure.filter(|(_, f)| has(f)) {
        return FaultSeen::AlreadySet(*t);
    }
    changes
        .iter()
        .find(|(t, f)| *t > from_ms && has(f))
        .map_or(FaultSeen::Never, |(t, _)| FaultSeen::Raised(*t))
}

/// A scenario's `accel_fault_before_contact` as the ECU showed it: FaultAccelSensor rose after
/// the sensor failed (not the start-up report, see [`fault_seen`]) and before the contact.
/// `faults` are the EcuStatus flag changes in ms relative to the contact, which came at
/// `contact_s` scenario seconds (None: no contact, so nothing before it).
pub fn accel_fault_before_contact(
    scenario: &world::Scenario,
    faults: &[(f64, Vec<String>)],
    contact_s: Option<f64>,
) -> bool {
    let failed_ms = match (scenario.sensor.accel_fails_at_s(), contact_s) {
        (Some(f), Some(c)) => (f - c) * 1e3,
        _ => f64::NEG_INFINITY,
    };
    matches!(
        fault_seen(faults, "accel_sensor", failed_ms),
        FaultSeen::Raised(t) if t < 0.0
    )
}

/// The ECU's counter `name` in its JSON report (`ecu-report.json`, `counters`; `None`: no
/// report, or no such counter).
pub fn ecu_counter(ecu_report: Option<&serde_json::Value>, name: &str) -> Option<u64> {
    ecu_report?.get("counters")?.get(name)?.as_u64()
}

/// When the ECU fell back to the reference restraint after it had been Normal, given its
/// EcuStatus mode changes `(ms, mode)`. Every run starts in ReferenceFallback (no input is
/// fresh yet): that start is not a fallback, so "the ECU fell back" needs a Normal before it.
pub fn fell_back_after_normal(modes: &[(f64, String)]) -> Option<f64> {
    let normal = modes.iter().position(|(_, m)| m == "Normal")?;
    modes
        .iter()
        .skip(normal + 1)
        .find(|(_, m)| m == "ReferenceFallback")
        .map(|(t, _)| *t)
}

/// The repository a bench tool works on when `--repo` is not given: the checkout the user is
/// in (walking up from the current folder, then from the tool's own folder), never the folder
/// the tool was built in.
pub fn repo_or_default(given: Option<PathBuf>) -> Result<PathBuf> {
    match given {
        Some(r) => Ok(r),
        None => host::find_repo().context(
            "not inside the bench's repository (no bus/restraint.dbc above the current folder \
             or the tool's): run from the checkout or pass --repo DIR",
        ),
    }
}

/// The scenario library: every `*.toml` of the repository's `scenarios/`, sorted by name (the
/// offline bench's default and what the library tests run).
pub fn library_files(repo: &Path) -> Result<Vec<PathBuf>> {
    let dir = repo.join("scenarios");
    let mut files = Vec::new();
    for e in std::fs::read_dir(&dir).with_context(|| dir.display().to_string())? {
        let p = e?.path();
        if p.extension().is_some_and(|x| x == "toml") {
            files.push(p);
        }
    }
    files.sort();
    Ok(files)
}

/// The repository this crate was built in — for the tests, which cargo builds and runs inside
/// the checkout; the tools use [`repo_or_default`].
pub fn repo_root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_else(|| PathBuf::from("."))
}
