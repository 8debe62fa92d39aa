//! The world stays free of I/O: its normal dependency tree holds no transport (iceoryx2,
//! SocketCAN), no process plumbing (the bench's `host` clock and signals, `ipc`) and no
//! command-line or application error crate — what plays it in real time is `sensor-feeds`.

use std::process::Command;

/// Crates of the bench's I/O side.
const IO: &[&str] = &[
    "iceoryx2",
    "socketcan",
    "nix",
    "ipc",
    "host",
    "sensor-feeds",
    "clap",
    "anyhow",
    "triple_buffer",
];

#[test]
fn the_world_depends_on_no_io_crate() {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let out = Command::new(cargo)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .args([
            "tree",
            "-p",
            env!("CARGO_PKG_NAME"),
            "-e",
            "normal",
            "--prefix",
            "none",
            "-f",
            "{p}",
        ])
        .output()
        .expect("run cargo tree");
    assert!(
        out.status.success(),
        "cargo tree failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout).expect("utf-8");
    let names: Vec<&str> = text
        .lines()
        .filter_map(|l| l.split_whitespace().next())
        .collect();
    assert!(
        names.contains(&"physics") && names.contains(&"toml_edit"),
        "tree parse failed: {names:?}"
    );
    let bad: Vec<&str> = names.iter().copied().filter(|n| IO.contains(n)).collect();
    assert!(bad.is_empty(), "I/O crates in the world's tree: {bad:?}");
}

/// The transport carries the `signals` records and does not link the restraint core: the
/// feeds and the stubs, which use `ipc`, never compile the ECU's logic.
/// (Here, not in `ipc`'s own tests: a test binary of `ipc` would link iceoryx2 for a
/// `cargo tree` call.)
#[test]
fn the_transport_does_not_link_the_core() {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    for package in ["ipc", "sensor-feeds", "actuator-stubs", "world"] {
        let out = Command::new(&cargo)
            .current_dir(env!("CARGO_MANIFEST_DIR"))
            .args(["tree", "-p", package, "-e", "normal", "--prefix", "none"])
            .output()
            .expect("run cargo tree");
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let tree = String::from_utf8_lossy(&out.stdout);
        let names: Vec<&str> = tree
            .lines()
            .filter_map(|l| l.split_whitespace().next())
            .collect();
        assert!(names.contains(&"signals"), "{package}: {tree}");
        assert!(
            !names.contains(&"restraint"),
            "{package} links the core:\n{tree}"
        );
    }
}
