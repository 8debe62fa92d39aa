//! `sensor-feeds --check`: a file with `[[accel_event]]`s is validated like every other key
//! (the same `file:line: field …` error on stderr, exit status 1) and, when valid, its events
//! are announced after the true contact, on stdout, ending `FILE: valid`. No transport is opened.

use std::path::PathBuf;
use std::process::Command;

fn check(name: &str, text: &str) -> (bool, String) {
    let dir = std::env::temp_dir().join(format!("sensor-feeds-check-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let file: PathBuf = dir.join(name);
    std::fs::write(&file, text).expect("write");
    let out = Command::new(env!("CARGO_BIN_EXE_sensor-feeds"))
        .arg("--check")
        .arg("--scenario")
        .arg(&file)
        .output()
        .expect("run sensor-feeds");
    let _ = std::fs::remove_file(&file);
    // A valid file's verdict is on stdout; an error on stderr.
    let printed = if out.status.success() {
        &out.stdout
    } else {
        &out.stderr
    };
    (
        out.status.success(),
        String::from_utf8_lossy(printed).replace(&format!("{}/", dir.display()), ""),
    )
}

const BASE: &str = "name = \"c\"\nduration_s = 3\n[ego]\nmass_kg = 1785\nspeed_kph = 50\n\
[opponent]\nkind = \"vehicle\"\nmass_kg = 1785\nspeed_kph = 50\ninitial_distance_m = 50\nevade_s = 1.799\n\
[occupant]\nmass_kg = 75\n\n[[accel_event]]\nkind = \"half_sine\"\nstart_s = 1.80\npeak_g = 7.5\nduration_ms = 4.0\n";

#[test]
fn check_announces_valid_events() {
    let (ok, err) = check("c.toml", BASE);
    assert!(ok, "{err}");
    assert!(
        err.contains("scenario c: no contact within 3.00 s"),
        "{err}"
    );
    assert!(
        err.contains("\naccel_event[0]: half_sine 7.5 g × 4 ms from 1.8000 s on all\n"),
        "{err}"
    );
    assert!(err.ends_with("c.toml: valid\n"), "{err}");
}

#[test]
fn check_rejects_a_bad_event_with_its_line() {
    // The second [[accel_event]] header is line 21, its duration_ms line 25.
    let text = format!(
        "{BASE}\n[[accel_event]]\nkind = \"spike\"\nstart_s = 0.5\npeak_g = 40\nduration_ms = 2\n"
    );
    let (ok, err) = check("bad.toml", &text);
    assert!(!ok);
    assert_eq!(
        err.trim_end(),
        "sensor-feeds: error: bad.toml:25: field `accel_event[1].duration_ms`: not used by kind = \"spike\": remove this key",
    );
    let text = BASE.replace("kind = \"half_sine\"", "kind = \"bump\"");
    let (ok, err) = check("kind.toml", &text);
    assert!(!ok);
    assert!(
        err.starts_with("sensor-feeds: error: kind.toml:16:8: field `accel_event[0].kind`: unknown variant `bump`"),
        "{err}"
    );
}
