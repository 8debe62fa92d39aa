//! `bus-inject encode`: the frames it prints are what the ECU's own E2E checker accepts, and
//! byte for byte what cantools encodes from the DBC with an independently written CRC
//! (`bus/tests/cantools_check.py`).

fn encode(args: &[&str]) -> (i32, String, String) {
    let args: Vec<&str> = std::iter::once("encode")
        .chain(args.iter().copied())
        .collect();
    crate::run_tool(env!("CARGO_BIN_EXE_bus-inject"), &args)
}

/// `ID#HEX` → (id, bytes).
fn frame(line: &str) -> (u32, Vec<u8>) {
    let (id, hex) = line.trim().split_once('#').expect("ID#HEX");
    let bytes = (0..hex.len())
        .step_by(2)
        .map(|i| u8::from_str_radix(&hex[i..i + 2], 16).unwrap())
        .collect();
    (u32::from_str_radix(id, 16).unwrap(), bytes)
}

#[test]
fn a_stream_of_encoded_frames_passes_the_ecus_e2e_check_with_the_values_given() {
    let (code, out, err) = encode(&[
        "EgoVehicleState",
        "BrakeState=AbsActive",
        "EgoSpeed=13.9",
        "EgoLongAccel=-4.5",
        "--counter",
        "14",
        "--count",
        "4",
    ]);
    assert_eq!(code, 0, "{err}");
    let lines: Vec<&str> = out.lines().collect();
    assert_eq!(lines.len(), 4);
    let mut checker = bus::E2eChecker::new();
    for (k, line) in lines.iter().enumerate() {
        let (id, data) = frame(line);
        assert_eq!(id, bus::EgoVehicleState::RAW_ID);
        let m = checker
            .check(id, &data)
            .unwrap_or_else(|e| panic!("frame {k} ({line}) rejected: {e:?}"));
        let bus::Messages::EgoVehicleState(m) = m else {
            panic!("{m:?}")
        };
        assert_eq!(
            m.alive_counter(),
            ((14 + k) % 16) as u8,
            "counters 14, 15, 0, 1"
        );
        assert_eq!(
            m.brake_state(),
            bus::codec::EgoVehicleStateBrakeState::AbsActive
        );
        assert!((m.ego_speed() - 13.9).abs() < 0.006);
        assert!((m.ego_long_accel() + 4.5).abs() < 0.006);
    }
    assert_eq!(checker.stats().accepted, 4);
}

#[test]
fn cantools_encodes_the_same_bytes_from_the_dbc() {
    let (code, out, err) = encode(&[
        "OccupantClassification",
        "BeltBuckle=Buckled",
        "OccupantClass=MidAdult",
        "ClassConfidence=90",
        "OccupantMass=75",
        "ChestToWheel=300",
        "SeatTrackPosition=120",
        "--counter",
        "9",
    ]);
    assert_eq!(code, 0, "{err}");
    let dir = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("bus-encode");
    std::fs::create_dir_all(&dir).unwrap();
    let req = dir.join("occupant.json");
    std::fs::write(
        &req,
        r#"[{"name": "OccupantClassification", "signals": {"AliveCounter": 9, "BeltBuckle": "Buckled",
            "OccupantClass": "MidAdult", "ClassConfidence": 90, "OccupantMass": 75,
            "ChestToWheel": 300, "SeatTrackPosition": 120, "Crc": 0}}]"#,
    )
    .unwrap();
    let root = e2e_tests::repo_root();
    let path = |p: std::path::PathBuf| p.to_string_lossy().into_owned();
    let (script, dbc, req) = (
        path(root.join("bus/tests/cantools_check.py")),
        path(root.join("bus/restraint.dbc")),
        path(req),
    );
    let python = path(e2e_tests::harness::python3());
    let (code, cantools, err) = crate::run_tool(&python, &[&script, "encode", &dbc, &req]);
    assert_eq!(code, 0, "cantools: {err}");
    assert_eq!(out.trim(), cantools.trim());
}

#[test]
fn candump_lines_carry_the_dbc_cycle_time_and_bad_input_names_what_is_wrong() {
    let (code, out, _) = encode(&[
        "0x0A0",
        "BrakeState=0",
        "EgoSpeed=0",
        "EgoLongAccel=0",
        "--count",
        "3",
        "--candump",
        "--can",
        "vcan1",
    ]);
    assert_eq!(code, 0);
    let stamps: Vec<&str> = out.lines().map(|l| l.split(' ').next().unwrap()).collect();
    // EgoVehicleState's GenMsgCycleTime is 10 ms.
    assert_eq!(stamps, ["(0.000000)", "(0.010000)", "(0.020000)"]);
    assert!(out.lines().all(|l| l.contains(" vcan1 0A0#")));
    for (args, says) in [
        (
            &["EgoVehicleState", "EgoSpeed=1"][..],
            "needs a value for BrakeState, EgoLongAccel",
        ),
        (
            &["EgoVehicleState", "Speed=1"][..],
            "has no signal \"Speed\"",
        ),
        (
            &[
                "EgoVehicleState",
                "BrakeState=Parked",
                "EgoSpeed=1",
                "EgoLongAccel=0",
            ][..],
            "is not one of Released",
        ),
        (
            &[
                "EgoVehicleState",
                "BrakeState=0",
                "EgoSpeed=101",
                "EgoLongAccel=0",
            ][..],
            "EgoVehicleState.EgoSpeed is outside the DBC's 0 … 100 m/s",
        ),
        (&["EgoVehicleState", "AliveCounter=3"][..], "--counter"),
    ] {
        let (code, out, err) = encode(args);
        assert_ne!(code, 0, "{args:?}");
        assert!(out.is_empty(), "{args:?}: {out}");
        assert!(err.contains(says), "{args:?}: {err}");
        assert_eq!(err.lines().count(), 1, "{args:?}: one line: {err}");
    }
    // An unknown message is an argument error: clap's usage message names the DBC's messages.
    let (code, _, err) = encode(&["NoSuchMessage"]);
    assert_eq!(code, 2);
    assert!(
        err.contains("neither a DBC message (AirbagStageCmd"),
        "{err}"
    );
}
