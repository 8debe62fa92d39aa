//! Shared by the integration tests in `tests/tests/` (bench.rs, robustness.rs): where the
//! built binaries are, building them once, and how vcan is reached.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

/// The Python of the independent checks: `target/pyenv` (tests/setup-host.sh installs cantools
/// and mcap there), else `python3` from PATH (then the check says what is missing).
pub fn python3() -> PathBuf {
    let venv = crate::repo_root().join("target/pyenv/bin/python3");
    if venv.exists() {
        venv
    } else {
        "python3".into()
    }
}

/// Runs `record/check_mcap.py` (Foxglove's `mcap` reader and cantools, no project code) on a
/// run folder — with `full`, the folder of a whole bench run (the stubs' files there, log times
/// in UTC with a measured realtime − monotonic offset, every path of `record/foxglove-layout.json` in the file); its report, or
/// what failed.
pub fn check_recording(run_dir: &Path, full: bool) -> Result<String, String> {
    let root = crate::repo_root();
    let mut args = vec![run_dir.into(), root.join("bus/restraint.dbc").into()];
    if full {
        args.extend([
            "--full".into(),
            "--layout".into(),
            root.join("record/foxglove-layout.json").into(),
        ]);
    }
    python_check("record/check_mcap.py", &args)
}

/// Runs `record/check_mf4.py` (asammdf, cantools and Foxglove's `mcap`, no project code) on run
/// folders holding `run.mf4` (and `run.mcap`, whose diagnostics it compares), in one Python
/// process; its report, or what failed.
pub fn check_mf4<P: AsRef<Path>>(run_dirs: &[P]) -> Result<String, String> {
    let mut args = vec![crate::repo_root().join("bus/restraint.dbc").into()];
    args.extend(run_dirs.iter().map(|d| d.as_ref().into()));
    python_check("record/check_mf4.py", &args)
}

/// One of the repository's independent Python checks with `args`: its output, `Err` when it
/// failed (or could not start).
fn python_check(script: &str, args: &[std::ffi::OsString]) -> Result<String, String> {
    let o = Command::new(python3())
        .arg(crate::repo_root().join(script))
        .args(args)
        .output()
        .map_err(|e| format!("python3 {script}: {e} (tests/setup-host.sh installs its venv)"))?;
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    if o.status.success() {
        Ok(text)
    } else {
        Err(text)
    }
}

/// target/<profile>/ of the running test binary (it lives in target/<profile>/deps/).
pub fn bin_dir() -> PathBuf {
    let exe = std::env::current_exe().expect("current exe");
    exe.parent()
        .and_then(Path::parent)
        .expect("target/<profile>")
        .to_path_buf()
}

/// Builds the bench binaries once per test process with test.sh's build command, so under
/// test.sh (and after any `cargo test --workspace`, which resolves features the same way)
/// it is a no-op. A `-p` subset, or leaving out the tests, would resolve the shared crates'
/// features differently and rebuild them (≈ 1 min on 2 cores for a `-p` subset, measured).
pub fn build_bench_bins() {
    static BUILT: OnceLock<()> = OnceLock::new();
    BUILT.get_or_init(|| {
        let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
        let st = Command::new(cargo)
            .args([
                "build",
                "--release",
                "--workspace",
                "--features",
                "bus/socket",
            ])
            .args(["--bins", "--tests", "--examples"])
            .current_dir(crate::repo_root())
            .status()
            .expect("cargo build");
        assert!(st.success(), "building the bench binaries failed");
    });
}

/// The route these tests reach vcan by and whether its guest keeps virtual time, as
/// `vcan-setup.sh --check` prints them ("qemu-tcg virtual"), checked once. With no route the
/// test PANICS with the script's reason: these tests are never skipped.
fn vcan_check() -> (crate::Route, bool) {
    static CHECK: OnceLock<(crate::Route, bool)> = OnceLock::new();
    *CHECK.get_or_init(|| {
        let o = Command::new(crate::repo_root().join("vcan-setup.sh"))
            .arg("--check")
            .stderr(std::process::Stdio::piped())
            .output()
            .expect("vcan-setup.sh --check");
        let printed = String::from_utf8_lossy(&o.stdout);
        let mut words = printed.split_whitespace();
        let route = words.next().and_then(crate::Route::parse);
        let virtual_time = words.next() == Some("virtual");
        match (o.status.code(), route) {
            (Some(0 | 3), Some(r)) => {
                eprintln!("e2e: vcan route {}: {}", r.name(), r.describe());
                (r, virtual_time)
            }
            (code, _) => panic!(
                "no vcan route (vcan-setup.sh --check → {code:?}, printed {printed:?}):\n{}\n\
                 these tests are never skipped",
                String::from_utf8_lossy(&o.stderr)
            ),
        }
    })
}

/// The route these tests reach vcan by (the host kernel, or a QEMU guest under KVM or TCG).
pub fn vcan_route() -> crate::Route {
    vcan_check().0
}

/// How many guests may run side by side: where the guests keep virtual time (TCG's icount,
/// `vcan-setup.sh` decides and `--check` says so) one per host CPU (at most 4), because a
/// guest's clock counts its own instructions and another guest beside it slows the run, not
/// the guest's timing. Everywhere else 1: real timers on the host or under KVM would measure
/// each other, and a TCG guest on host time is starved by anything beside it.
pub fn parallel_guests() -> usize {
    if !vcan_check().1 {
        return 1;
    }
    std::thread::available_parallelism().map_or(1, |n| n.get().clamp(1, 4))
}

/// `items` dealt round-robin into `n` non-empty groups (fewer when there are fewer items).
pub fn deal<T: Clone>(items: &[T], n: usize) -> Vec<Vec<T>> {
    let n = n.clamp(1, items.len().max(1));
    let mut groups = vec![Vec::new(); n];
    for (i, x) in items.iter().enumerate() {
        groups[i % n].push(x.clone());
    }
    groups.retain(|g| !g.is_empty());
    groups
}

/// Runs `vcan-setup.sh --run -- ARGS…` once per argument list, all at once (one guest each),
/// in the repository root; prints each guest's stdout and stderr under a `--- WHAT, guest k
/// of n ---` header and returns their outputs in the same order. `out` is the folder the
/// runs write under, made here and shared into the guest read-write (`VCAN_GUEST_RW`), as a
/// user's `--out` anywhere is.
pub fn run_in_guests(
    what: &str,
    out: &Path,
    runs: Vec<Vec<std::ffi::OsString>>,
) -> Vec<std::process::Output> {
    let script = crate::repo_root().join("vcan-setup.sh");
    std::fs::create_dir_all(out).expect("output folder");
    let rw = match std::env::var("VCAN_GUEST_RW") {
        Ok(more) if !more.is_empty() => format!("{}:{more}", out.display()),
        _ => out.display().to_string(),
    };
    let handles: Vec<_> = runs
        .into_iter()
        .map(|args| {
            let script = script.clone();
            let rw = rw.clone();
            std::thread::spawn(move || {
                Command::new(&script)
                    .args(["--run", "--"])
                    .args(&args)
                    .env("VCAN_GUEST_RW", rw)
                    // Recordings are written here, on the host, when the guests have ended
                    // (record::pending: in the emulated guest they cost ≈ 15× as much).
                    .env(record::pending::RECORD_ON_HOST, "1")
                    .current_dir(crate::repo_root())
                    .output()
                    .expect("vcan-setup.sh --run")
            })
        })
        .collect();
    let outputs: Vec<std::process::Output> = handles
        .into_iter()
        .map(|h| h.join().expect("guest thread"))
        .collect();
    for (k, o) in outputs.iter().enumerate() {
        eprintln!(
            "--- {what}, guest {} of {} ---\n{}\n--- stderr ---\n{}",
            k + 1,
            outputs.len(),
            String::from_utf8_lossy(&o.stdout),
            String::from_utf8_lossy(&o.stderr)
        );
    }
    let started = std::time::Instant::now();
    let written = record::pending::write_pending(out).expect("the runs' output folder");
    let failed: Vec<String> = written
        .iter()
        .filter_map(|w| {
            w.result
                .as_ref()
                .err()
                .map(|e| format!("{}: {e}", w.dir.display()))
        })
        .collect();
    // The stubs' outcome pictures go the same way (`--plot-later`).
    let drawn = actuator_stubs::plot::draw_pending(out).expect("the runs' output folder");
    let failed: Vec<String> = failed
        .into_iter()
        .chain(drawn.iter().filter_map(|d| {
            d.result
                .as_ref()
                .err()
                .map(|e| format!("{}: {e}", d.dir.display()))
        }))
        .collect();
    // Reported, not asserted: the tests that read the recordings fail on a missing one, and a
    // fault case may damage what its recording is written from.
    eprintln!(
        "{what}: {} recordings and {} pictures written on the host in {:.1} s{}",
        written.len() - written.iter().filter(|w| w.result.is_err()).count(),
        drawn.iter().filter(|d| d.result.is_ok()).count(),
        started.elapsed().as_secs_f64(),
        if failed.is_empty() {
            String::new()
        } else {
            format!("; not written:\n{}", failed.join("\n"))
        }
    );
    outputs
}
