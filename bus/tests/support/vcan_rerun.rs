//! Shared by the real-bus integration tests (`bus/tests/real_bus.rs`, `ecu/tests/shell/cycle_vcan.rs`,
//! each includes this file with `#[path]`): run a test's worker on a usable host vcan, else
//! re-run it inside the QEMU guest of `vcan-setup.sh --run`. A file rather than a crate because
//! it is ~50 lines of std-only test glue that only test binaries compile.
//!
//! Never a silent skip: with no route to a vcan (host or guest) the test FAILS.

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
/// `worker_test` (which must call the same worker) of this very test binary inside the guest,
/// and asserts that it ran and passed there. Inside the guest (`VCAN_GUEST` set) an unusable
/// interface is a failure, not a reason to recurse.
pub fn run_here_or_in_guest(worker_test: &str, worker: impl FnOnce()) {
    if interface_usable(&iface()) {
        worker();
        return;
    }
    assert!(
        std::env::var_os("VCAN_GUEST").is_none(),
        "inside the QEMU guest but {} is not usable",
        iface()
    );
    eprintln!(
        "host has no usable {}; re-running {worker_test} inside the QEMU guest (vcan-setup.sh --run)",
        iface()
    );
    let out = Command::new(repo_root().join("vcan-setup.sh"))
        .args(["--can", &iface(), "--run", "--"])
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
    eprintln!("--- guest stdout ---\n{stdout}\n--- guest and vcan-setup stderr ---\n{stderr}");
    assert!(
        out.status.success(),
        "{worker_test} failed (no route to a vcan?): {:?}",
        out.status
    );
    assert!(
        stdout.contains("1 passed"),
        "{worker_test} did not run inside the guest: {stdout}"
    );
    assert!(
        stderr.contains("route=qemu-"),
        "vcan-setup.sh did not name the guest route: {stderr}"
    );
}
