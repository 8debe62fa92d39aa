//! Shared by the real-bus integration tests (`bus/tests/real_bus.rs`, `ecu/tests/cycle_vcan.rs`,
//! each includes this file with `#[path]`): run a test's worker on a usable host vcan, else
//! re-run it inside a user-mode Linux guest through `vcan-setup.sh --run`. A file rather than
//! a crate because it is ~40 lines of std-only test glue that only test binaries compile.
//!
//! Never a silent skip: with neither a host vcan nor a working UML guest the test FAILS.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use bus::socket::interface_usable;

/// The CAN interface under test: `$VCAN` (vcan-setup.sh sets it inside the guest), else `vcan0`.
pub fn iface() -> String {
    std::env::var("VCAN").unwrap_or_else(|_| "vcan0".into())
}

/// The workspace root (the including package sits one level below it).
pub fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .unwrap()
        .to_path_buf()
}

/// Runs `worker` here when [`iface`] is usable; otherwise re-runs the `#[ignore]`d test
/// `worker_test` (which must call the same worker) of this very test binary inside UML, and
/// asserts that it ran and passed there. Inside the guest (`VCAN_IN_UML` set) an unusable
/// interface is a failure, not a reason to recurse.
pub fn run_here_or_in_uml(worker_test: &str, worker: impl FnOnce()) {
    if interface_usable(&iface()) {
        worker();
        return;
    }
    assert!(
        std::env::var_os("VCAN_IN_UML").is_none(),
        "inside the UML guest but {} is not usable",
        iface()
    );
    eprintln!(
        "host has no usable {}; re-running {worker_test} inside user-mode Linux",
        iface()
    );
    let out = Command::new(repo_root().join("vcan-setup.sh"))
        .args(["--iface", &iface(), "--run", "--"])
        .arg(std::env::current_exe().unwrap())
        .args([
            "--exact",
            worker_test,
            "--ignored",
            "--nocapture",
            "--test-threads=1",
        ])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .stdin(Stdio::null())
        .output()
        .expect("run vcan-setup.sh");
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    eprintln!("--- guest stdout ---\n{stdout}\n--- vcan-setup stderr ---\n{stderr}");
    assert!(
        out.status.success(),
        "{worker_test} failed (neither host vcan nor a working UML guest?): {:?}",
        out.status
    );
    assert!(
        stdout.contains("1 passed"),
        "{worker_test} did not run inside the guest: {stdout}"
    );
}
