//! `record` (run.mcap) on run folders that need no bus: the committed sample candump log, and
//! the same log with a command log whose clock is shifted by a known offset. Every file is read
//! back by record/check_mcap.py (Foxglove's `mcap` package and cantools), not by our code.

use e2e_tests::harness::check_recording;
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    e2e_tests::repo_root()
}

fn sample_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("record-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::copy(
        root().join("docs/sample/candump-taurus-48-48-abs.log"),
        dir.join("candump.log"),
    )
    .unwrap();
    dir
}

fn meta() -> record::RunMeta {
    record::RunMeta {
        route: "test".into(),
        timing_emulated: None,
    }
}

fn python_check(dir: &Path, full: bool) -> String {
    check_recording(dir, full).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn a_candump_log_is_recorded_frame_for_frame_and_decoded_as_cantools_decodes_it() {
    let dir = sample_dir("plain");
    let s = record::write_run(&dir, &dir.join("run.mcap"), &meta()).unwrap();
    let frames = bus::candump::CandumpLog::read(&dir.join("candump.log")).unwrap();
    assert_eq!(s.messages["/can/raw"], frames.frames.len() as u64);
    assert_eq!(
        s.realtime_minus_monotonic_ns, None,
        "no stubs: no clock pairing"
    );
    let text = python_check(&dir, false);
    assert!(
        text.contains("every signal equals cantools' decode"),
        "{text}"
    );
    // Without the stubs' files it is no whole run.
    let o = std::process::Command::new(e2e_tests::harness::python3())
        .arg(root().join("record/check_mcap.py"))
        .arg(&dir)
        .arg(root().join("bus/restraint.dbc"))
        .arg("--full")
        .output()
        .unwrap();
    assert!(
        !o.status.success(),
        "--full must refuse a folder without the stubs' files"
    );
}

/// The stubs log command frames on CLOCK_MONOTONIC; candump on CLOCK_REALTIME. With a command log
/// shifted by a known offset, the file's log times are candump's stamps minus exactly that
/// offset, and every command record sits at its own monotonic time.
#[test]
fn log_times_are_on_the_monotonic_clock_the_stubs_measured() {
    const OFFSET_NS: i64 = 1_733_000_000_123_456_789;
    let dir = sample_dir("clock");
    let log = bus::candump::CandumpLog::read(&dir.join("candump.log")).unwrap();
    let mut lines = String::new();
    for f in &log.frames {
        let Some(m) = bus::message_info(f.frame.id) else {
            continue;
        };
        if m.transmitter != "RestraintEcu" {
            continue;
        }
        let hex: String = f
            .frame
            .payload()
            .iter()
            .map(|b| format!("{b:02x}"))
            .collect();
        let mono = (f.t_us * 1_000) as i64 - OFFSET_NS;
        lines += &format!(
            "{{\"rx_mono_ns\":{mono},\"id\":{},\"message\":\"{}\",\"data_hex\":\"{hex}\",\"e2e\":\"ok\"}}\n",
            f.frame.id, m.name
        );
    }
    assert!(lines.lines().count() > 100);
    // A stubs process killed mid-line leaves a partial last line: recorded up to it.
    std::fs::write(
        dir.join("commands.jsonl"),
        format!("{lines}{{\"rx_mono_ns\":12"),
    )
    .unwrap();
    let s = record::write_run(&dir, &dir.join("run.mcap"), &meta()).unwrap();
    assert_eq!(s.realtime_minus_monotonic_ns, Some(OFFSET_NS));
    assert_eq!(s.messages["/stubs/commands"], lines.lines().count() as u64);
    let text = python_check(&dir, false);
    assert!(text.contains(&format!("offset {OFFSET_NS} ns")), "{text}");
    assert!(text.contains("/stubs/commands: all"), "{text}");
}

#[test]
fn a_damaged_log_is_recorded_as_far_as_it_goes_and_a_missing_one_is_a_clear_error() {
    let dir = sample_dir("damaged");
    let mut text = std::fs::read_to_string(dir.join("candump.log")).unwrap();
    text.insert_str(0, "garbage\n(12.5) vcan0 ZZZ#00\n");
    std::fs::write(dir.join("candump.log"), &text).unwrap();
    let s = record::write_run(&dir, &dir.join("run.mcap"), &meta()).unwrap();
    assert_eq!(
        s.messages["/can/raw"],
        bus::candump::CandumpLog::parse(&text).frames.len() as u64
    );
    python_check(&dir, false);
    let empty = std::env::temp_dir().join(format!("record-none-{}", std::process::id()));
    std::fs::create_dir_all(&empty).unwrap();
    let e = record::write_run(&empty, &empty.join("run.mcap"), &meta()).unwrap_err();
    assert!(format!("{e:#}").contains("candump.log"), "{e:#}");
}
