//! The `ecu` binary as a real process: CLI, config errors, `--cycles`, SIGTERM, JSON
//! report and `ecu monitor` against a running ECU. No assertion depends on wall-clock
//! timing (only generous "eventually" bounds for functional failures).

use std::path::PathBuf;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use ipc::{DiagnosticsSubscriber, ObjectPublisher, ObjectState, ServiceNames, VALID};
use nix::sys::signal::{kill, Signal};
use nix::unistd::Pid;

const ECU: &str = env!("CARGO_BIN_EXE_ecu");
const PATIENCE: Duration = Duration::from_secs(30);

fn tmpdir(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("ecu-proc-{}-{tag}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn prefix(tag: &str) -> String {
    format!("ecu-proc-{}-{tag}", std::process::id())
}

#[test]
fn help_lists_the_flags() {
    let out = Command::new(ECU).arg("--help").output().unwrap();
    assert!(out.status.success());
    let s = String::from_utf8_lossy(&out.stdout);
    for flag in [
        "--config",
        "--period-us",
        "--cycles",
        "--json",
        "--sched-fifo",
        "--mlockall",
        "--cpu",
        "--pm-qos",
        "--no-can",
        "monitor",
    ] {
        assert!(s.contains(flag), "{flag} missing in --help:\n{s}");
    }
}

#[test]
fn bad_config_exits_with_file_and_line() {
    let dir = tmpdir("badcfg");
    let path = dir.join("bad.toml");
    std::fs::write(&path, "period_us = 1000\n[rt]\nmlockall = maybe\n").unwrap();
    let out = Command::new(ECU)
        .arg("--config")
        .arg(&path)
        .arg("--no-can")
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains(&format!("{}:3:", path.display())), "{err}");
}

/// `ecu --show-config` with `env` set on the child only (no test changes its own environment).
fn show_config(args: &[&str], env: &[(&str, &str)]) -> (bool, String, String) {
    let out = Command::new(ECU)
        .arg("--show-config")
        .args(args)
        .env_remove("VCAN")
        .envs(env.iter().copied())
        .output()
        .unwrap();
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn environment_overrides_the_file_and_flags_override_the_environment() {
    let dir = tmpdir("layers");
    let path = dir.join("ecu.toml");
    std::fs::write(&path, "period_us = 2000\n[rt]\ncpu = 1\nmlockall = true\n").unwrap();
    let env = [("ECU_PERIOD_US", "800"), ("ECU_RT__CPU", "0")];
    let (ok, out, err) = show_config(
        &["--config", path.to_str().unwrap(), "--period-us", "500"],
        &env,
    );
    assert!(ok, "{err}");
    let has = |line: &str| out.lines().any(|l| l == line);
    assert!(has("period_us = 500  # command line"), "{out}");
    assert!(has("cpu = 0  # environment variable ECU_RT__CPU"), "{out}");
    assert!(
        has(&format!("mlockall = true  # {}:4", path.display())),
        "{out}"
    );
    assert!(has("interface = \"vcan0\"  # defaults"), "{out}");
    // optional settings that are not set are listed as comments, not left out (TOML has no
    // null); a set one is not
    assert!(has("# cycles = (not set)"), "{out}");
    assert!(has("# sched_fifo_priority = (not set)"), "{out}");
    assert!(!out.contains("# cpu = (not set)"), "{out}");
}

#[test]
fn vcan_names_the_interface_below_ecu_variables_and_flags() {
    let line = |args: &[&str], env: &[(&str, &str)]| {
        let (ok, out, err) = show_config(args, env);
        assert!(ok, "{err}");
        out.lines()
            .find(|l| l.starts_with("interface = "))
            .unwrap_or_default()
            .to_owned()
    };
    assert_eq!(
        line(&[], &[("VCAN", "vcan7")]),
        "interface = \"vcan7\"  # environment variable VCAN"
    );
    assert_eq!(
        line(&[], &[("VCAN", "")]),
        "interface = \"vcan0\"  # defaults"
    );
    assert_eq!(
        line(&[], &[("VCAN", "vcan7"), ("ECU_CAN__INTERFACE", "vcan8")]),
        "interface = \"vcan8\"  # environment variable ECU_CAN__INTERFACE"
    );
    assert_eq!(
        line(&["--can", "vcan9"], &[("VCAN", "vcan7")]),
        "interface = \"vcan9\"  # command line"
    );
}

#[test]
fn a_bad_environment_variable_is_named_in_the_error() {
    for (var, value, expect) in [
        ("ECU_PERIOD_US", "fast", "invalid type"),
        ("ECU_PERIOD_US", "5", "outside 50..=1000000"),
        ("ECU_RT__MLOCK", "true", "unknown field"),
        ("ECU_CYCLE__CONFIRM_DECEL_G", "0.1", "outside 1.5..=100"),
    ] {
        let (ok, _, err) = show_config(&[], &[(var, value)]);
        assert!(!ok, "{var}={value} accepted");
        assert!(
            err.contains(&format!("environment variable {var}: invalid")) && err.contains(expect),
            "{var}={value}: {err}"
        );
    }
}

#[test]
fn missing_can_interface_is_an_error_unless_no_can() {
    let out = Command::new(ECU)
        .args(["--cycles", "1", "--can", "nocan-test0"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("nocan-test0") && err.contains("--no-can"),
        "{err}"
    );
}

#[test]
fn cycles_run_writes_json_report_and_monitor_shows_it() {
    let dir = tmpdir("cycles");
    let report = dir.join("report.json");
    let pfx = prefix("cycles");
    let mut ecu = Command::new(ECU)
        .args([
            "--cycles",
            "4000",
            "--period-us",
            "500",
            "--no-can",
            "--quiet",
        ])
        .args([
            "--service-prefix",
            &pfx,
            "--node-name",
            &format!("{pfx}-ecu"),
        ])
        .arg("--json")
        .arg(&report)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();

    // Wait for the ECU's diagnostics, then feed a few object states.
    let names = ServiceNames::with_prefix(&pfx);
    let (node, _) = ipc::create_node("ecu-proc-feed", false).unwrap();
    let mut diag = DiagnosticsSubscriber::new(&node, &names).unwrap();
    let mut objects = ObjectPublisher::new(&node, &names).unwrap();
    let t0 = Instant::now();
    while diag.latest().is_none() {
        assert!(
            t0.elapsed() < PATIENCE,
            "no diagnostics from the ecu process"
        );
        std::thread::sleep(Duration::from_millis(2));
    }
    let monitor = Command::new(ECU)
        .args([
            "monitor",
            "--count",
            "3",
            "--lines",
            "--rate-hz",
            "50",
            "--service-prefix",
            &pfx,
        ])
        .output()
        .unwrap();
    for seq in 1..=10u64 {
        objects
            .publish_with(ObjectState::INVALID, |o| {
                o.sequence = seq;
                o.valid = VALID;
            })
            .unwrap();
        std::thread::sleep(Duration::from_millis(2));
    }

    let status = ecu.wait().unwrap();
    let mut stdout = String::new();
    std::io::Read::read_to_string(ecu.stdout.as_mut().unwrap(), &mut stdout).unwrap();
    assert!(status.success(), "ecu failed: {stdout}");
    assert!(stdout.contains("cycles 4000"), "{stdout}");
    assert!(stdout.contains("stopped by cycles"), "{stdout}");

    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
    assert_eq!(v["cycles"], 4000);
    assert!(v["overruns"].is_u64());
    for h in ["wake_latency_us", "exec_us"] {
        for k in ["p50", "p99", "p999", "max"] {
            let x = v[h][k].as_f64().unwrap_or(-1.0);
            assert!(x >= 0.0, "{h}.{k} = {x}");
        }
        assert!(v[h]["p50"].as_f64() <= v[h]["max"].as_f64());
    }
    assert_eq!(v["can"]["enabled"], false);
    assert!(v["can"]["reason"].as_str().unwrap().contains("--no-can"));
    for s in ["sched", "mlockall", "cpu_affinity", "pm_qos"] {
        assert_eq!(v["rt"][s]["requested"], false, "{s}");
    }
    assert!(v["ipc"]["object_rx"].as_u64().unwrap() >= 1, "{v}");

    assert!(monitor.status.success());
    let mon = String::from_utf8_lossy(&monitor.stdout);
    assert_eq!(mon.lines().count(), 3, "{mon}");
    // The restraint cycle without CAN (no occupant data) runs DEGRADED on the reference.
    assert!(mon.contains("mode ReferenceFallback (degraded)"), "{mon}");
    assert!(mon.contains("can-off"), "{mon}");
}

#[test]
fn sigterm_stops_cleanly_with_report() {
    let pfx = prefix("sigterm");
    let ecu = Command::new(ECU)
        .args(["--no-can", "--quiet", "--period-us", "1000"])
        .args([
            "--service-prefix",
            &pfx,
            "--node-name",
            &format!("{pfx}-ecu"),
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let names = ServiceNames::with_prefix(&pfx);
    let (node, _) = ipc::create_node("ecu-proc-sigterm", false).unwrap();
    let mut diag = DiagnosticsSubscriber::new(&node, &names).unwrap();
    let t0 = Instant::now();
    while diag.latest().is_none_or(|d| d.cycle_count < 10) {
        assert!(
            t0.elapsed() < PATIENCE,
            "no diagnostics from the ecu process"
        );
        std::thread::sleep(Duration::from_millis(2));
    }
    kill(Pid::from_raw(ecu.id() as i32), Signal::SIGTERM).unwrap();
    let out = ecu.wait_with_output().unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(stdout.contains("stopped by signal"), "{stdout}");
    assert!(stdout.contains("p99.9"), "{stdout}");
}

/// `ecu --no-can --cycles 3` with `args`, run in `cwd`: (success, stderr).
fn short_run(cwd: &std::path::Path, tag: &str, args: &[&str]) -> (bool, String) {
    let pfx = prefix(tag);
    let out = Command::new(ECU)
        .current_dir(cwd)
        .args(["--no-can", "--cycles", "3", "--quiet"])
        .args([
            "--service-prefix",
            &pfx,
            "--node-name",
            &format!("{pfx}-ecu"),
        ])
        .args(args)
        .output()
        .unwrap();
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn started_from_another_folder_the_ecu_finds_its_table_and_keys() {
    // From any folder but the repository's root it ran DEGRADED and sent its
    // commands without authenticators, exit 0. The defaults now resolve against the
    // repository, found by walking up from the executable.
    let (ok, err) = short_run(&tmpdir("elsewhere"), "elsewhere", &[]);
    assert!(ok, "{err}");
    assert!(!err.contains("error"), "{err}");
    let repo = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..");
    let lut = repo.join("data/default.lut").canonicalize().unwrap();
    let keys = repo
        .join("data/secoc-keys.example.toml")
        .canonicalize()
        .unwrap();
    let named = |p: &std::path::Path| {
        err.lines().any(|l| {
            l.split_whitespace()
                .any(|w| PathBuf::from(w).canonicalize().ok().as_deref() == Some(p))
        })
    };
    assert!(named(&lut), "{err}");
    assert!(named(&keys), "{err}");
}

#[test]
fn missing_keys_or_table_stop_the_ecu_unless_it_is_asked_to_run_without_them() {
    // Fail closed: one clear line naming the file and the flag; exit != 0.
    let here = tmpdir("failclosed");
    let (ok, err) = short_run(&here, "nokeys", &["--secoc-keys", "/nonexistent/keys.toml"]);
    assert!(!ok, "started without keys: {err}");
    assert!(
        err.contains("/nonexistent/keys.toml") && err.contains("--no-secoc"),
        "{err}"
    );
    let (ok, err) = short_run(&here, "nolut", &["--lut", "missing.lut"]);
    assert!(!ok, "started without its table: {err}");
    assert!(
        err.contains("missing.lut") && err.contains("--no-lut"),
        "{err}"
    );
    // Asked for explicitly: it runs, and says so.
    let (ok, err) = short_run(&here, "asked", &["--no-secoc", "--no-lut"]);
    assert!(ok, "{err}");
    assert!(
        err.contains("--no-secoc") && err.contains("--no-lut"),
        "{err}"
    );
    // A table that is there but corrupt leaves the ECU DEGRADED on the reference restraint
    // (never no protection; the fault campaign's lut-corrupt case runs it on the bench).
    let corrupt = here.join("corrupt.lut");
    std::fs::write(&corrupt, b"not a table").unwrap();
    let (ok, err) = short_run(&here, "corrupt", &["--lut", corrupt.to_str().unwrap()]);
    assert!(ok, "{err}");
    assert!(err.contains("DEGRADED"), "{err}");
}

#[test]
fn an_output_path_is_checked_before_the_run_and_config_paths_follow_their_file() {
    let here = tmpdir("paths");
    let (ok, err) = short_run(
        &here,
        "badout",
        // A folder nobody can make (its missing folders are made otherwise, as every tool's).
        &["--json", "/proc/no-such-dir/r.json"],
    );
    assert!(!ok, "{err}");
    assert!(err.contains("/proc/no-such-dir/r.json"), "{err}");
    assert!(!err.contains("cycles run"), "it ran first: {err}");
    // `secoc_keys = "keys.toml"` in a config file means the file beside it, from any folder.
    let repo = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..");
    let conf_dir = tmpdir("conf");
    std::fs::copy(
        repo.join("data/secoc-keys.example.toml"),
        conf_dir.join("keys.toml"),
    )
    .unwrap();
    std::fs::write(
        conf_dir.join("ecu.toml"),
        "[cycle]\nsecoc_keys = \"keys.toml\"\n",
    )
    .unwrap();
    let conf = conf_dir.join("ecu.toml");
    let (ok, err) = short_run(&here, "conf", &["--config", conf.to_str().unwrap()]);
    assert!(ok, "{err}");
    assert!(
        err.contains(&conf_dir.join("keys.toml").display().to_string()),
        "{err}"
    );
}

#[test]
fn config_errors_are_one_line_naming_the_field_and_the_os_error_once() {
    // `mlockall = "yes"` gave line and column but not the field; a missing
    // file repeated its OS error.
    let dir = tmpdir("errstyle");
    let path = dir.join("typed.toml");
    std::fs::write(&path, "[rt]\nmlockall = \"yes\"\n").unwrap();
    let (ok, err) = short_run(&dir, "typed", &["--config", path.to_str().unwrap()]);
    assert!(!ok);
    assert!(
        err.contains(&format!("{}:2:", path.display())) && err.contains("field `rt.mlockall`"),
        "{err}"
    );
    let (ok, err) = short_run(&dir, "nofile", &["--config", "/nonexistent/ecu.toml"]);
    assert!(!ok);
    assert_eq!(err.matches("No such file").count(), 1, "{err}");
    assert_eq!(err.trim().lines().count(), 1, "{err}");
}
