//! `record` (run.mcap) on run folders that need no bus: the committed sample candump log, and
//! the same log with a command log whose clock is shifted by a known offset. Every file is read
//! back by record/check_mcap.py (Foxglove's `mcap` package and cantools), not by our code.

use e2e_tests::harness::{check_mf4, check_recording};
use record::latency::From;
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
        scenario: None,
        simulated_start_ns: None,
    }
}

/// One line of the stubs' commands.jsonl for `f`, received at `mono` (CLOCK_MONOTONIC ns),
/// E2E accepted — written as the stubs write it.
fn command_line(mono: u64, f: &bus::RawFrame, message: &str) -> String {
    let rec = actuator_stubs::commands::CommandRecord {
        rx_mono_ns: mono,
        id: f.id,
        message: message.to_owned(),
        data_hex: bus::candump::data_hex(f.payload()),
        e2e: "ok".to_owned(),
        secoc: None,
        decoded: None,
    };
    format!("{}\n", serde_json::to_string(&rec).unwrap())
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
/// shifted by a known offset, the file's log times are UTC, as the run's MF4 is: every frame at
/// candump's own stamp, every command record at its monotonic time plus exactly that offset.
#[test]
fn log_times_are_utc_with_the_offset_the_stubs_measured() {
    const OFFSET_NS: i64 = 1_733_000_000_123_456_789;
    let dir = sample_dir("clock");
    let log = bus::candump::CandumpLog::read(&dir.join("candump.log")).unwrap();
    let mut lines = String::new();
    for f in &log.frames {
        let Some(m) = bus::message_info(f.frame.id) else {
            continue;
        };
        if m.transmitter != bus::ECU_NODE {
            continue;
        }
        let mono = (f.t_us * 1_000) as i64 - OFFSET_NS;
        lines += &command_line(mono as u64, &f.frame, m.name);
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
    assert!(
        text.contains("log times in UTC: every frame at candump's stamp"),
        "{text}"
    );
    assert!(text.contains("/stubs/commands: all"), "{text}");
    // Read back here too: the first command's log time is its monotonic time + the offset.
    let bytes = std::fs::read(dir.join("run.mcap")).unwrap();
    let first = mcap::MessageStream::new(&bytes)
        .unwrap()
        .map(Result::unwrap)
        .find(|m| m.channel.topic == "/stubs/commands")
        .expect("a command");
    let v: serde_json::Value = serde_json::from_slice(&first.data).unwrap();
    let mono = v["rx_mono_ns"].as_u64().unwrap();
    assert_eq!(first.log_time, mono.saturating_add_signed(OFFSET_NS));
}

#[test]
fn a_damaged_log_is_recorded_as_far_as_it_goes_and_a_missing_one_is_a_clear_error() {
    let dir = sample_dir("damaged");
    let mut text = std::fs::read_to_string(dir.join("candump.log")).unwrap();
    text.insert_str(0, "garbage\n(12.5) vcan0 ZZZ#00\n");
    std::fs::write(dir.join("candump.log"), &text).unwrap();
    // A damaged scenario file (as the campaign plays some): its truth is left out, the rest
    // recorded.
    std::fs::write(dir.join("bad.toml"), "[ego\nspeed_kph = ").unwrap();
    let with_bad_scenario = record::RunMeta {
        scenario: Some(dir.join("bad.toml")),
        ..meta()
    };
    let s = record::write_run(&dir, &dir.join("run.mcap"), &with_bad_scenario).unwrap();
    assert!(!s.messages.contains_key("/truth/world"));
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

/// `record latency` against a run built to known figures: 200 cycles 1 ms apart (cycle 50's
/// diagnostics record never published), an AirbagStageCmd 20 + (k mod 7) µs after each cycle's
/// start (Fire from cycle 150 on), an EcuStatus 40 µs after every tenth; candump's stamps on
/// CLOCK_REALTIME, the stubs' on CLOCK_MONOTONIC. The report must give exactly those
/// latencies' percentiles (nearest rank), computed here from the construction.
#[test]
fn latency_is_measured_from_the_cycle_that_sent_each_frame() {
    let dir = std::env::temp_dir().join(format!("record-latency-{}", std::process::id()));
    let Known {
        mut cmd_lat,
        mut status_lat,
        mut fire_lat,
        mut cmd_sample_lat,
        mut status_sample_lat,
        mut fire_sample_lat,
    } = known_run(&dir);
    let s = record::write_run(&dir, &dir.join("run.mcap"), &meta()).unwrap();
    assert_eq!(s.realtime_minus_monotonic_ns, Some(KNOWN_OFFSET_NS));
    python_check(&dir, false);
    let l = record::latency::latency(&dir.join("run.mcap")).unwrap();
    let nearest = |v: &mut Vec<f64>, p: f64| {
        v.sort_by(f64::total_cmp);
        v[((p / 100.0 * v.len() as f64).ceil() as usize).max(1) - 1]
    };
    let row = |from: From, what: &str| {
        l.row(from, what)
            .unwrap_or_else(|| panic!("no row {from:?} {what}: {}", l.table()))
            .clone()
    };
    for (from, what, v) in [
        (
            From::CycleStart,
            "AirbagStageCmd (every frame)",
            &mut cmd_lat,
        ),
        (From::CycleStart, "EcuStatus (every frame)", &mut status_lat),
        (From::CycleStart, "airbag fire (every frame)", &mut fire_lat),
        (
            From::CrashSample,
            "AirbagStageCmd (every frame)",
            &mut cmd_sample_lat,
        ),
        (
            From::CrashSample,
            "EcuStatus (every frame)",
            &mut status_sample_lat,
        ),
        (
            From::CrashSample,
            "airbag fire (every frame)",
            &mut fire_sample_lat,
        ),
    ] {
        let r = row(from, what);
        assert_eq!(r.n, v.len(), "{what}");
        for (got, want) in [
            (r.p50_us, nearest(v, 50.0)),
            (r.p99_us, nearest(v, 99.0)),
            (r.max_us, nearest(v, 100.0)),
        ] {
            assert!(
                (got - want).abs() < 1e-6,
                "{what}: {got} vs {want}\n{}",
                l.table()
            );
        }
    }
    // The first fire frame: cycle 150's, 20 + 150 mod 7 = 23 µs after its start, and its
    // newest crash sample 25 + 10 · (150 mod 3) = 25 µs before that start.
    assert!((row(From::CycleStart, "airbag fire (first frame)").p50_us - 23.0).abs() < 1e-6);
    assert!((row(From::CrashSample, "airbag fire (first frame)").p50_us - 48.0).abs() < 1e-6);
    // Cycle 50 published no record: its two frames have no sample figure, and say so.
    assert_eq!(l.no_sample, 2, "{}", l.table());
}

/// The realtime − monotonic offset of [`known_run`].
const KNOWN_OFFSET_NS: i64 = 1_700_000_000_000_000_000;

/// The latencies [`known_run`] built in, µs: from the cycle's start, and from the newest crash
/// sample the cycle had (only cycles whose diagnostics record was published).
struct Known {
    cmd_lat: Vec<f64>,
    status_lat: Vec<f64>,
    fire_lat: Vec<f64>,
    cmd_sample_lat: Vec<f64>,
    status_sample_lat: Vec<f64>,
    fire_sample_lat: Vec<f64>,
}

/// A run folder built to known figures (see the latency test).
fn known_run(dir: &Path) -> Known {
    const OFFSET_NS: i64 = KNOWN_OFFSET_NS;
    const T0: u64 = 5_000_000_000;
    let _ = std::fs::remove_dir_all(dir);
    std::fs::create_dir_all(dir).unwrap();
    let (mut candump, mut commands, mut diag) = (String::new(), String::new(), Vec::new());
    let (mut cmd_lat, mut status_lat, mut fire_lat) = (Vec::new(), Vec::new(), Vec::new());
    let (mut cmd_sample_lat, mut status_sample_lat, mut fire_sample_lat) =
        (Vec::new(), Vec::new(), Vec::new());
    let mut feeds = Vec::new();
    let mut frame = |mono: u64, f: &bus::RawFrame, name: &str| {
        let rt_us = (mono as i64 + OFFSET_NS) as u64 / 1_000;
        candump += &bus::candump::log_line(rt_us, "vcan0", f);
        candump.push('\n');
        commands += &command_line(mono, f, name);
    };
    let bag = bus::message_info(bus::AirbagStageCmd::RAW_ID).unwrap();
    let status = bus::message_info(bus::EcuStatus::RAW_ID).unwrap();
    for k in 1..=200u64 {
        let start = T0 + k * 1_000_000;
        // Crash batch k: 8 samples 125 µs apart, the newest 25 + 10 · (k mod 3) µs before cycle
        // k starts, published 5 µs after it; cycle k read it.
        let age_us = 25 + 10 * (k % 3);
        let mut b = signals::CrashAccelSample::EMPTY;
        b.sequence = k;
        b.count = 8;
        b.sample_period_ns = 125_000;
        b.first_timestamp_ns = start - age_us * 1_000 - 7 * 125_000;
        let published_ns = start - age_us * 1_000 + 5_000;
        feeds.extend(
            postcard::to_stdvec(&signals::FeedLogRecord {
                published_ns,
                item: signals::FeedItem::CrashAccel(b),
            })
            .unwrap(),
        );
        let published = k != 50;
        if published {
            let mut d = signals::EcuDiagnostics::ZERO;
            d.timestamp_ns = start;
            d.cycle_count = k;
            d.last_accel_sequence = k;
            diag.extend(postcard::to_stdvec(&d).unwrap());
        }
        // Whole µs: candump's stamps have µs resolution.
        let lat_us = 20 + k % 7;
        let sigs = bus::signals_of(bag.id).unwrap();
        let vals: Vec<f64> = sigs
            .iter()
            .map(|s| match s.name {
                "Fire" | "Arm" => f64::from(u8::from(k >= 150)),
                // Unique payloads: the clock offset pairs frames by their bytes.
                "FireTime" => k as f64 * 0.1,
                _ => 0.0,
            })
            .collect();
        let f = bus::encode_values(bag.id, &vals).unwrap();
        frame(start + lat_us * 1_000, &f, bag.name);
        cmd_lat.push(lat_us as f64);
        let sample_us = (lat_us + age_us) as f64;
        if published {
            cmd_sample_lat.push(sample_us);
        }
        if k >= 150 {
            fire_lat.push(lat_us as f64);
            fire_sample_lat.push(sample_us);
        }
        if k % 10 == 0 {
            let sigs = bus::signals_of(status.id).unwrap();
            let f = bus::encode_values(status.id, &vec![0.0; sigs.len()]).unwrap();
            frame(start + 40_000, &f, status.name);
            status_lat.push(40.0);
            if published {
                status_sample_lat.push((40 + age_us) as f64);
            }
        }
    }
    std::fs::write(dir.join("candump.log"), candump).unwrap();
    std::fs::write(dir.join("commands.jsonl"), commands).unwrap();
    std::fs::write(dir.join(actuator_stubs::DIAGNOSTICS_LOG), diag).unwrap();
    std::fs::write(dir.join(record::FEEDS_LOG), feeds).unwrap();
    Known {
        cmd_lat,
        status_lat,
        fire_lat,
        cmd_sample_lat,
        status_sample_lat,
        fire_sample_lat,
    }
}

/// run.mf4 (ASAM MDF 4.1 bus logging) read by asammdf: every frame with its bytes and time,
/// asammdf's own DBC decode equal to cantools', every diagnostics record equal to the MCAP's on
/// the same instant. A frame changed after the file was written, or a stamp 2 µs off, fails
/// the check (it is no check that cannot fail).
#[test]
fn the_recording_reads_the_diagnostics_log_under_the_name_the_stubs_write() {
    // `record` reads run folders without linking the stubs; the name is the contract.
    assert_eq!(record::DIAGNOSTICS_LOG, actuator_stubs::DIAGNOSTICS_LOG);
}

#[test]
fn run_mf4_is_the_bus_logging_asammdf_decodes_with_the_dbc() {
    let dir = std::env::temp_dir().join(format!("record-mf4-{}", std::process::id()));
    known_run(&dir);
    record::write_run(&dir, &dir.join("run.mcap"), &meta()).unwrap();
    let s = record::write_run_mf4(&dir, &dir.join(record::RUN_MF4)).unwrap();
    assert_eq!(
        s.diagnostics, 199,
        "200 cycles, cycle 50's record never published"
    );
    assert_eq!(s.diagnostics_left_out, None);
    let text = check_mf4(&[&dir]).unwrap_or_else(|e| panic!("{e}"));
    for want in [
        "CAN_DataFrame: all",
        "2 DBC messages",
        "EcuDiagnostics: all 199 records",
        "restraint.dbc attached",
    ] {
        assert!(text.contains(want), "{want}: {text}");
    }
    let log = std::fs::read_to_string(dir.join("candump.log")).unwrap();
    let line = log.lines().nth(100).unwrap().to_owned();
    // One data byte changed.
    let (head, data) = line.rsplit_once('#').unwrap();
    let flipped = format!(
        "{head}#{}{}",
        if data.starts_with('0') { '1' } else { '0' },
        &data[1..]
    );
    std::fs::write(dir.join("candump.log"), log.replacen(&line, &flipped, 1)).unwrap();
    let e = check_mf4(&[&dir]).unwrap_err();
    assert!(e.contains("frame 100"), "{e}");
    // One stamp 2 µs late.
    let (stamp, rest) = line.split_once(')').unwrap();
    let us: u64 = stamp[stamp.len() - 6..].parse().unwrap();
    let late = format!("{}{:06}){rest}", &stamp[..stamp.len() - 6], us + 2);
    std::fs::write(dir.join("candump.log"), log.replacen(&line, &late, 1)).unwrap();
    let e = check_mf4(&[&dir]).unwrap_err();
    assert!(e.contains("frame 100: time"), "{e}");
}

/// Error frames (a controller's reports; candump logs them with its error filter) are in the
/// MCAP on /can/error and in run.mf4's CAN_ErrorFrame group, as Python's readers see them: the
/// classes and bytes linux/can/error.h gives, the time, a CRC-sequence violation typed as
/// ASAM's CRC error; one changed class byte fails both checks.
#[test]
fn error_frames_are_recorded_in_both_files() {
    let dir = std::env::temp_dir().join(format!("record-errors-{}", std::process::id()));
    known_run(&dir);
    let log = std::fs::read_to_string(dir.join("candump.log")).unwrap();
    // After frames 10, 20, 30: CAN_ERR_PROT | BUSERROR | CNT, bit error in the CRC sequence,
    // rx error counter 1, 2, 3 — as `bus-inject mirror --mode errors` sends them.
    let mut lines: Vec<String> = log.lines().map(str::to_owned).collect();
    for (k, at) in [(3u8, 30usize), (2, 20), (1, 10)] {
        let stamp = lines[at].split_once(')').unwrap().0.to_owned();
        lines.insert(
            at + 1,
            format!("{stamp}) vcan0 20000288#00000108000000{k:02X}"),
        );
    }
    std::fs::write(dir.join("candump.log"), lines.join("\n") + "\n").unwrap();
    let s = record::write_run(&dir, &dir.join("run.mcap"), &meta()).unwrap();
    assert_eq!(s.messages.get("/can/error"), Some(&3));
    let m = record::write_run_mf4(&dir, &dir.join(record::RUN_MF4)).unwrap();
    assert_eq!(m.error_frames, 3);
    let text = python_check(&dir, false);
    assert!(text.contains("/can/error: all 3 error frames"), "{text}");
    let text = check_mf4(&[&dir]).unwrap_or_else(|e| panic!("{e}"));
    assert!(
        text.contains("CAN_ErrorFrame: all 3 error frames"),
        "{text}"
    );
    assert!(text.contains("CRC Error"), "{text}");
    // The recordings are kept; the log changes under them.
    let changed =
        lines
            .join("\n")
            .replacen("20000288#0000010800000002", "20000288#0000010800000009", 1);
    std::fs::write(dir.join("candump.log"), changed + "\n").unwrap();
    let e = check_mf4(&[&dir]).unwrap_err();
    assert!(e.contains("error frame 1"), "{e}");
    let e = check_recording(&dir, false).unwrap_err();
    assert!(e.contains("error frame 1"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Diagnostics whose clock cannot be placed (no command frame seen by both candump and the
/// stubs) are left out and said so; the bus is still written and decodes.
#[test]
fn run_mf4_without_a_clock_pairing_leaves_the_diagnostics_out_and_says_so() {
    let dir = sample_dir("mf4-unpaired");
    let mut d = signals::EcuDiagnostics::ZERO;
    d.cycle_count = 1;
    std::fs::write(
        dir.join(actuator_stubs::DIAGNOSTICS_LOG),
        postcard::to_stdvec(&d).unwrap(),
    )
    .unwrap();
    let s = record::write_run_mf4(&dir, &dir.join(record::RUN_MF4)).unwrap();
    assert_eq!(s.diagnostics, 0);
    assert!(s
        .diagnostics_left_out
        .unwrap()
        .contains("candump and the stubs"));
    let text = check_mf4(&[&dir]).unwrap_or_else(|e| panic!("{e}"));
    assert!(text.contains("no run.mcap"), "{text}");
    assert!(text.contains("extract_bus_logging"), "{text}");
}

/// `RECORD_ON_HOST`: a run leaves a note; `record pending` (record::pending::write_pending) writes
/// the recording and the asked-for MF4 afterwards, appends their lines to the run's summary and
/// removes the note. A damaged note fails that folder alone, says which, and keeps its note.
#[test]
fn pending_recordings_are_written_after_the_run_and_a_bad_note_fails_alone() {
    let root = std::env::temp_dir().join(format!("record-pending-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&root);
    let good = root.join("good");
    known_run(&good);
    std::fs::write(good.join("summary.txt"), "the run's summary\n").unwrap();
    record::pending::defer(&good, &meta()).unwrap();
    assert!(record::pending::defer_mf4(&good).unwrap());
    let bad = root.join("bad");
    std::fs::create_dir_all(&bad).unwrap();
    std::fs::write(bad.join(record::pending::PENDING), "{ not json").unwrap();
    let plain = root.join("plain");
    std::fs::create_dir_all(&plain).unwrap();
    assert!(
        !record::pending::defer_mf4(&plain).unwrap(),
        "no note: the caller writes the MF4 itself"
    );

    // The stubs' picture left to the host (`--plot-later`): a rising deceleration and
    // excursion, drawn to outcome.png by the stubs' own pass after the recordings.
    let judged = |a: f64| {
        format!(
            r#"{{"load_limiter_kn": 6.0, "airbag_level_kn": 5.0, "pretensioner_ms": -30.0,
                "airbag_ms": 12.0, "a_max_g": {a}, "a_mean_g": 15.0, "excursion_mm": 180.0,
                "available_mm": 240.0, "bottomed_out": false}}"#
        )
    };
    let trace = r#"{"t_ms": [0.0, 50.0, 100.0], "decel_g": [0.0, 20.0, 5.0], "excursion_mm": [0.0, 150.0, 180.0]}"#;
    std::fs::write(
        good.join(actuator_stubs::plot::PLOT_LATER),
        format!(
            r#"{{"title": "known", "adaptive": {}, "adaptive_trace": {trace}, "reference": {},
                "reference_trace": {trace}, "pulse_g": [0.0, 10.0, 20.0, 0.0], "pulse_step_ms": 30.0}}"#,
            judged(20.0),
            judged(24.0)
        ),
    )
    .unwrap();
    let written = record::pending::write_pending(&root).unwrap();
    assert_eq!(written.len(), 2, "{written:?}");
    let by = |d: &Path| written.iter().find(|w| w.dir == d).unwrap();
    let lines = by(&good).result.as_ref().unwrap();
    assert!(lines[0].starts_with("recording: ") && lines[0].contains("written on the host"));
    assert!(lines[1].starts_with("recording (MDF 4.1): "));
    assert_eq!(lines.len(), 2, "{lines:?}");
    let drawn = actuator_stubs::plot::draw_pending(&root).unwrap();
    assert_eq!(drawn.len(), 1, "{drawn:?}");
    assert_eq!(drawn[0].dir, good);
    let line = drawn[0].result.as_ref().unwrap();
    assert!(line.starts_with("outcome picture: "), "{line}");
    let png = std::fs::read(good.join("outcome.png")).unwrap();
    assert_eq!(&png[1..4], b"PNG");
    assert!(!good.join(actuator_stubs::plot::PLOT_LATER).exists());
    assert!(!good.join(record::pending::PENDING).exists());
    let summary = std::fs::read_to_string(good.join("summary.txt")).unwrap();
    assert!(
        summary.starts_with("the run's summary\nrecording: ")
            && summary
                .trim_end()
                .ends_with("(drawn on the host after the run)"),
        "{summary}"
    );
    python_check(&good, false);
    check_mf4(&[&good]).unwrap_or_else(|e| panic!("{e}"));
    let e = by(&bad).result.as_ref().unwrap_err();
    assert!(e.contains("record.pending.json"), "{e}");
    assert!(bad.join(record::pending::PENDING).exists());
    // Written once: a second pass finds only the bad note.
    assert_eq!(record::pending::write_pending(&root).unwrap().len(), 1);
}
