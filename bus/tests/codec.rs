//! Codec and E2E tests. Oracles are independent of the code under test: a bitwise CRC-8 SAE
//! J1850 (checked against its published check value) and a bit-by-bit Intel-layout extractor
//! driven by the DBC's start bits and sizes.

use bus::codec::{
    AirbagStageCmdArm, AirbagStageCmdCmdSource, AirbagStageCmdFire, AirbagStageCmdStage,
    BeltLimiterCmdCmdSource, BeltLimiterCmdPretensionerCmd, EgoVehicleStateBrakeState,
    OccupantClassificationBeltBuckle, OccupantClassificationOccupantClass,
};
use bus::{
    decode, encode_values, signal_values, signals_of, AirbagStageCmd, BeltLimiterCmd, E2eChecker,
    E2eMessage, E2eProtector, EgoVehicleState, EncodeErrorKind, Messages, OccupantClassification,
    RawFrame, RejectReason, RxError, SignalInfo, MESSAGES,
};
use proptest::prelude::*;

fn crc8_j1850_bitwise(bytes: &[u8]) -> u8 {
    let mut crc = 0xFFu8;
    for b in bytes {
        crc ^= b;
        for _ in 0..8 {
            crc = if crc & 0x80 != 0 {
                (crc << 1) ^ 0x1D
            } else {
                crc << 1
            };
        }
    }
    crc ^ 0xFF
}

/// Independent CRC over data id + payload without the CRC byte.
fn oracle_crc(data_id: u16, crc_byte: usize, payload: &[u8]) -> u8 {
    let mut v = data_id.to_le_bytes().to_vec();
    v.extend(
        payload
            .iter()
            .enumerate()
            .filter(|(i, _)| *i != crc_byte)
            .map(|(_, b)| *b),
    );
    crc8_j1850_bitwise(&v)
}

/// Intel (little-endian) signal extraction, bit by bit.
fn extract_raw(data: &[u8], s: &SignalInfo) -> i64 {
    let mut v: u64 = 0;
    for i in 0..s.size {
        let bit = s.start_bit + i;
        let b = (data[(bit / 8) as usize] >> (bit % 8)) & 1;
        v |= u64::from(b) << i;
    }
    if s.signed && s.size < 64 && v & (1 << (s.size - 1)) != 0 {
        (v as i64) - (1i64 << s.size)
    } else {
        v as i64
    }
}

fn idx(sigs: &[SignalInfo], name: &str) -> usize {
    sigs.iter().position(|s| s.name == name).unwrap()
}

#[test]
fn bitwise_crc_oracle_matches_published_check_value() {
    assert_eq!(crc8_j1850_bitwise(b"123456789"), 0x4B);
}

/// Raw values for every signal of a message, anywhere in its valid range.
fn raw_vectors(id: u32) -> impl Strategy<Value = Vec<i64>> {
    let sigs = signals_of(id).unwrap();
    sigs.iter()
        .map(|s| s.raw_min..=s.raw_max)
        .collect::<Vec<_>>()
}

fn frame_for(id: u32, raws: &[i64]) -> (RawFrame, Vec<f64>) {
    let sigs = signals_of(id).unwrap();
    let info = bus::message_info(id).unwrap();
    let mut phys: Vec<f64> = sigs
        .iter()
        .zip(raws)
        .map(|(s, r)| *r as f64 * s.factor + s.offset)
        .collect();
    let mut frame = encode_values(id, &phys).unwrap();
    if let Some(did) = info.e2e_data_id {
        let ci = idx(sigs, "Crc");
        let crc_byte = (sigs[ci].start_bit / 8) as usize;
        phys[ci] = f64::from(oracle_crc(did, crc_byte, frame.payload()));
        frame = encode_values(id, &phys).unwrap();
    }
    (frame, phys)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    /// Every message, every signal over its whole DBC range (E2E fields included): the bits land
    /// where the DBC says, the frame passes the receive checks, and decodes to the same values.
    #[test]
    fn every_message_round_trips(
        (which, raws) in (0..MESSAGES.len()).prop_flat_map(|w| (Just(w), raw_vectors(MESSAGES[w].id)))
    ) {
        let id = MESSAGES[which].id;
        let (frame, phys) = frame_for(id, &raws);
        let sigs = signals_of(id).unwrap();
        prop_assert_eq!(frame.payload().len(), MESSAGES[which].size);
        for (s, (r, p)) in sigs.iter().zip(raws.iter().zip(&phys)) {
            let got = extract_raw(frame.payload(), s);
            let want = if s.name == "Crc" && MESSAGES[which].e2e_data_id.is_some() { *p as i64 } else { *r };
            prop_assert_eq!(got, want, "{}.{} bit layout", MESSAGES[which].name, s.name);
        }
        let msg = E2eChecker::new().check(id, frame.payload()).map_err(|e| TestCaseError::fail(format!("{e}")))?;
        let mut out = [0f64; 16];
        let n = signal_values(&msg, &mut out).unwrap();
        prop_assert_eq!(n, sigs.len());
        for (s, (got, want)) in sigs.iter().zip(out.iter().zip(&phys)) {
            let tol = s.factor * 1e-3 + want.abs() * 1e-6;
            prop_assert!((got - want).abs() <= tol, "{}.{}: {} vs {}", MESSAGES[which].name, s.name, got, want);
        }
    }

    /// Typed command path the ECU uses: physical values (any float in range, not only steps)
    /// encode to the nearest step, E2E-protect, pass the checker, and read back.
    #[test]
    fn airbag_command_typed_round_trip(
        force_kn in 0.0f32..=12.0, fire_ms in -200.0f32..=200.0, arm: bool, fire: bool,
        stage in 0u8..4, reference: bool, n_frames in 1usize..40,
    ) {
        let mut tx = E2eProtector::new();
        let mut rx = E2eChecker::new();
        for k in 0..n_frames {
            let m = AirbagStageCmd::encode(
                if arm { AirbagStageCmdArm::Armed } else { AirbagStageCmdArm::Disarmed },
                if fire { AirbagStageCmdFire::Fire } else { AirbagStageCmdFire::NoFire },
                if reference { AirbagStageCmdCmdSource::Reference } else { AirbagStageCmdCmdSource::Adaptive },
                match stage { 0 => AirbagStageCmdStage::NoStage, 1 => AirbagStageCmdStage::Stage1,
                              2 => AirbagStageCmdStage::Stage2, _ => AirbagStageCmdStage::BothStages },
                force_kn, fire_ms).unwrap();
            let f = tx.seal(m);
            prop_assert_eq!(f.id, 0x30);
            let Messages::AirbagStageCmd(d) = rx.check_frame(&f).unwrap() else { panic!("wrong type") };
            prop_assert_eq!(d.alive_counter() as usize, k % 16);
            // nearest step: error at most half a step (plus f32 noise)
            prop_assert!((d.force_level() - force_kn).abs() <= 0.025 + 1e-4);
            prop_assert!((d.fire_time() - fire_ms).abs() <= 0.05 + 1e-3);
            prop_assert_eq!(d.arm() == AirbagStageCmdArm::Armed, arm);
            prop_assert_eq!(d.fire() == AirbagStageCmdFire::Fire, fire);
            prop_assert_eq!(u8::from(d.stage()), stage);
        }
        prop_assert_eq!(rx.stats().accepted, n_frames as u64);
    }

    #[test]
    fn belt_command_and_inputs_typed_round_trip(
        level_kn in 0.0f32..=12.0, pret_ms in -200.0f32..=200.0, pret in 0u8..3,
        speed_mps in 0.0f32..=100.0, accel in -150.0f32..=150.0, brake in 0u8..5,
        mass_kg in 0.0f32..=250.0, d_mm in 0u16..=1000, seat_mm in 0u16..=400, conf in 0u8..=100,
        buckle in 0u8..4, class in 0u8..5,
    ) {
        let mut tx = E2eProtector::new();
        let mut rx = E2eChecker::new();
        let pret_cmd = [BeltLimiterCmdPretensionerCmd::Idle, BeltLimiterCmdPretensionerCmd::Fire,
                        BeltLimiterCmdPretensionerCmd::Release][pret as usize];
        let f = tx.seal(BeltLimiterCmd::encode(pret_cmd, BeltLimiterCmdCmdSource::Adaptive, level_kn, pret_ms).unwrap());
        let Messages::BeltLimiterCmd(d) = rx.check_frame(&f).unwrap() else { panic!() };
        prop_assert_eq!(d.pretensioner_cmd(), pret_cmd);
        prop_assert!((d.load_limiter_level() - level_kn).abs() <= 0.025 + 1e-4);
        prop_assert!((d.pretensioner_fire_time() - pret_ms).abs() <= 0.05 + 1e-3);

        let f = tx.seal(EgoVehicleState::encode([EgoVehicleStateBrakeState::Released, EgoVehicleStateBrakeState::DriverBraking,
             EgoVehicleStateBrakeState::AbsActive, EgoVehicleStateBrakeState::EmergencyBrakeAssist,
             EgoVehicleStateBrakeState::AutonomousEmergencyBraking][brake as usize], speed_mps, accel).unwrap());
        let Messages::EgoVehicleState(d) = rx.check_frame(&f).unwrap() else { panic!() };
        prop_assert!((d.ego_speed() - speed_mps).abs() <= 0.005 + 1e-4);
        prop_assert!((d.ego_long_accel() - accel).abs() <= 0.005 + 1e-4);
        prop_assert_eq!(u8::from(d.brake_state()), brake);

        let f = tx.seal(OccupantClassification::encode(
            [OccupantClassificationBeltBuckle::Unbuckled, OccupantClassificationBeltBuckle::Buckled,
             OccupantClassificationBeltBuckle::SwitchFault, OccupantClassificationBeltBuckle::NotAvailable][buckle as usize],
            [OccupantClassificationOccupantClass::Empty, OccupantClassificationOccupantClass::ChildSeat,
             OccupantClassificationOccupantClass::SmallAdult, OccupantClassificationOccupantClass::MidAdult,
             OccupantClassificationOccupantClass::LargeAdult][class as usize], conf, mass_kg, d_mm, seat_mm).unwrap());
        let Messages::OccupantClassification(d) = rx.check_frame(&f).unwrap() else { panic!() };
        prop_assert!((d.occupant_mass() - mass_kg).abs() <= 0.05 + 1e-3);
        prop_assert_eq!(d.chest_to_wheel(), d_mm);
        prop_assert_eq!(d.seat_track_position(), seat_mm);
        prop_assert_eq!(d.class_confidence(), conf);
        prop_assert_eq!(u8::from(d.belt_buckle()), buckle);
        prop_assert_eq!(u8::from(d.occupant_class()), class);
    }

    /// Any single bit flipped anywhere in a protected frame is caught by the CRC.
    #[test]
    fn corrupted_frames_are_rejected_as_crc_mismatch(which in 0..MESSAGES.len(), bit in 0usize..64, seed in any::<u64>()) {
        let info = MESSAGES[which];
        prop_assume!(info.e2e_data_id.is_some());
        let sigs = signals_of(info.id).unwrap();
        let raws: Vec<i64> = sigs.iter().enumerate()
            .map(|(i, s)| s.raw_min + ((seed >> (i % 8 * 8)) as i64 & 0x7FFF_FFFF) % (s.raw_max - s.raw_min + 1))
            .collect();
        let (frame, _) = frame_for(info.id, &raws);
        let mut bytes = frame.payload().to_vec();
        bytes[bit / 8] ^= 1 << (bit % 8);
        let r = E2eChecker::new().check(info.id, &bytes);
        let is_crc = matches!(r, Err(RxError::CrcMismatch { .. }));
        prop_assert!(is_crc, "{:?}", r);
        let is_crc = matches!(decode(info.id, &bytes), Err(RxError::CrcMismatch { .. }));
        prop_assert!(is_crc);
    }

    /// Arbitrary ids and bytes never panic; unknown ids and wrong lengths get their reason.
    #[test]
    fn arbitrary_input_never_panics(id in any::<u32>(), bytes in proptest::collection::vec(any::<u8>(), 0..12)) {
        let mut rx = E2eChecker::new();
        let r = rx.check(id, &bytes);
        match bus::message_info(id) {
            None => prop_assert_eq!(r.unwrap_err(), RxError::UnknownId(id)),
            Some(i) if i.size != bytes.len() =>
                prop_assert_eq!(r.unwrap_err(), RxError::WrongDlc { expected: i.size, got: bytes.len() }),
            Some(_) => {}
        }
        let _ = decode(id, &bytes);
    }
}

fn belt(level_kn: f32) -> BeltLimiterCmd {
    BeltLimiterCmd::encode(
        BeltLimiterCmdPretensionerCmd::Fire,
        BeltLimiterCmdCmdSource::Reference,
        level_kn,
        -20.0,
    )
    .unwrap()
}

#[test]
fn protector_crc_matches_independent_oracle() {
    let mut tx = E2eProtector::new();
    let f = tx.seal(belt(4.0));
    assert_eq!(
        f.data[BeltLimiterCmd::CRC_BYTE],
        oracle_crc(BeltLimiterCmd::DATA_ID, 0, &f.data)
    );
    // The data id matters: the same payload with another message's id fails its CRC.
    let wrong = oracle_crc(AirbagStageCmd::DATA_ID, 0, &f.data);
    assert_ne!(wrong, f.data[0]);
}

#[test]
fn repeated_counter_is_rejected() {
    let mut tx = E2eProtector::new();
    let mut rx = E2eChecker::new();
    let f = tx.seal(belt(4.0));
    assert!(rx.check_frame(&f).is_ok());
    assert_eq!(
        rx.check_frame(&f).unwrap_err(),
        RxError::CounterRepeated { counter: 0 }
    );
    assert_eq!(rx.stats().rejected_for(RejectReason::CounterRepeated), 1);
    // the stream continues normally after a replay
    assert!(rx.check_frame(&tx.seal(belt(4.0))).is_ok());
}

#[test]
fn skipped_counter_reports_lost_frames_and_resyncs() {
    for lost in 1u8..=14 {
        let mut tx = E2eProtector::new();
        let mut strict = E2eChecker::new();
        let mut tolerant = E2eChecker::with_max_lost(lost);
        let first = tx.seal(belt(1.0));
        strict.check_frame(&first).unwrap();
        tolerant.check_frame(&first).unwrap();
        for _ in 0..lost {
            let _dropped = tx.seal(belt(1.0));
        }
        let after_gap = tx.seal(belt(1.0));
        assert_eq!(
            strict.check_frame(&after_gap).unwrap_err(),
            RxError::CounterSkipped { lost }
        );
        assert!(tolerant.check_frame(&after_gap).is_ok());
        assert_eq!(tolerant.stats().lost_frames, u64::from(lost));
        // resynchronised: the next frame is fine for both
        let next = tx.seal(belt(1.0));
        assert!(strict.check_frame(&next).is_ok());
        assert!(tolerant.check_frame(&next).is_ok());
    }
}

#[test]
fn counters_are_per_message() {
    let mut tx = E2eProtector::new();
    let mut rx = E2eChecker::new();
    for _ in 0..3 {
        rx.check_frame(&tx.seal(belt(2.0))).unwrap();
    }
    // a different message starts its own sequence at 0 and is not "skipped"
    let ego = EgoVehicleState::encode(EgoVehicleStateBrakeState::Released, 13.9, 0.0).unwrap();
    let f = tx.seal(ego);
    assert_eq!(f.data[1] & 0x0F, 0);
    rx.check_frame(&f).unwrap();
    assert_eq!(tx.next_counter::<BeltLimiterCmd>(), 3);
}

#[test]
fn wrong_dlc_and_unknown_ids_are_rejected() {
    let f = E2eProtector::new().seal(belt(3.0));
    let mut rx = E2eChecker::new();
    for len in 0..8 {
        assert_eq!(
            rx.check(f.id, &f.data[..len]).unwrap_err(),
            RxError::WrongDlc {
                expected: 8,
                got: len
            }
        );
    }
    let known: Vec<u32> = MESSAGES.iter().map(|m| m.id).collect();
    for id in (0..0x800u32).filter(|i| !known.contains(i)) {
        assert_eq!(rx.check(id, &f.data).unwrap_err(), RxError::UnknownId(id));
    }
    // 29-bit frame with the same low bits as ours
    let ext = f.id | bus::CAN_EFF_FLAG;
    assert_eq!(rx.check(ext, &f.data).unwrap_err(), RxError::UnknownId(ext));
    assert_eq!(rx.stats().rejected_for(RejectReason::WrongDlc), 8);
}

#[test]
fn out_of_range_raw_values_are_rejected_by_name() {
    // ForceLevel raw 241..=255 is representable in 8 bits but above the DBC's 12 kN.
    let sigs = AirbagStageCmd::SIGNALS;
    for raw in 241..=255u8 {
        let mut v: Vec<f64> = sigs.iter().map(|_| 0.0).collect();
        let mut f = encode_values(0x30, &v).unwrap();
        f.data[3] = raw; // ForceLevel byte per the DBC (start bit 24), checked by the oracle:
        assert_eq!(
            extract_raw(&f.data, &sigs[idx(sigs, "ForceLevel")]),
            i64::from(raw)
        );
        v[idx(sigs, "Crc")] = f64::from(oracle_crc(AirbagStageCmd::DATA_ID, 0, &f.data));
        f.data[0] = v[idx(sigs, "Crc")] as u8;
        assert_eq!(
            E2eChecker::new().check_frame(&f).unwrap_err(),
            RxError::OutOfRange("ForceLevel")
        );
    }
    // PretensionerCmd raw 3 has no meaning
    let mut f = E2eProtector::new().seal(belt(1.0));
    f.data[1] |= 0b0011_0000;
    f.data[0] = oracle_crc(BeltLimiterCmd::DATA_ID, 0, &f.data);
    assert_eq!(
        decode(f.id, &f.data).unwrap_err(),
        RxError::OutOfRange("PretensionerCmd")
    );
}

#[test]
fn encoder_rejects_nan_and_out_of_range_by_name() {
    let e = BeltLimiterCmd::encode(
        BeltLimiterCmdPretensionerCmd::Idle,
        BeltLimiterCmdCmdSource::Adaptive,
        f32::NAN,
        0.0,
    )
    .unwrap_err();
    assert_eq!(
        (e.signal, e.kind),
        ("LoadLimiterLevel", EncodeErrorKind::NotFinite)
    );
    let e = BeltLimiterCmd::encode(
        BeltLimiterCmdPretensionerCmd::Idle,
        BeltLimiterCmdCmdSource::Adaptive,
        12.5,
        0.0,
    )
    .unwrap_err();
    assert_eq!(
        (e.signal, e.kind),
        ("LoadLimiterLevel", EncodeErrorKind::OutOfRange)
    );
    let e = EgoVehicleState::encode(EgoVehicleStateBrakeState::Released, -1.0, 0.0).unwrap_err();
    assert_eq!(e.signal, "EgoSpeed");
    // Rounding, not truncation: 6.5 kN is exactly raw 130 (dbc-codegen's own setter would give
    // 129 = 6.45 kN because 6.5/0.05 = 129.99999 in f32).
    let m = belt(6.5);
    assert_eq!(m.load_limiter_level_raw_val(), 130);
}

#[test]
fn cycle_times_and_ids_come_from_the_dbc() {
    let dbc = bus::DBC_TEXT;
    for m in MESSAGES {
        assert!(
            dbc.contains(&format!("BO_ {} {}:", m.id, m.name)),
            "{}",
            m.name
        );
        if let Some(c) = m.cycle_time_ms {
            assert!(dbc.contains(&format!("BA_ \"GenMsgCycleTime\" BO_ {} {c};", m.id)));
        }
    }
    assert_eq!(bus::message_info(0xC0).unwrap().cycle_time_ms, Some(100));
    assert_eq!(EgoVehicleState::MESSAGE_CYCLE_TIME_MS, 10);
}
