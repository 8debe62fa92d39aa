//! The transport carries the `signals` records and does not link the restraint core: the
//! feeds and the stubs, which use `ipc`, never compile the ECU's logic (issue 21 item 2).

use std::process::Command;

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
