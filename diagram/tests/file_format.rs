//! File format: round trips, determinism, and one crafted corruption per validator.

mod common;

use common::{header, random_diagram, small_axes};
use diagram::{
    lut_id_of, AxisId, Diagram, DiagramData, FileProblem, LoadError, Problem, FORMAT_VERSION,
    MAGIC, PREAMBLE_LEN,
};

fn sample() -> Diagram {
    random_diagram(small_axes(), 11)
}

fn load(bytes: &[u8]) -> Result<Diagram, LoadError> {
    Diagram::from_bytes("default.lut", bytes)
}

fn problem(bytes: &[u8]) -> FileProblem {
    load(bytes).expect_err("corrupt file accepted").problem
}

/// Re-encode modified data with a freshly computed (valid) checksum, so
/// only the semantic validator can catch the defect.
fn crafted(edit: impl FnOnce(&mut DiagramData)) -> Vec<u8> {
    let mut data = sample().into_data();
    edit(&mut data);
    data.to_bytes_unvalidated()
}

fn tmp_path(name: &str) -> std::path::PathBuf {
    std::env::temp_dir().join(format!("diagram-test-{}-{name}", std::process::id()))
}

#[test]
fn binary_round_trip_is_identical() {
    let d = sample();
    let bytes = d.to_bytes();
    assert_eq!(&bytes[..8], &MAGIC);
    assert_eq!(u16::from_le_bytes([bytes[8], bytes[9]]), FORMAT_VERSION);
    let payload_len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    assert_eq!(bytes.len(), PREAMBLE_LEN + payload_len);
    let back = load(&bytes).unwrap();
    assert_eq!(back, d);
    assert_eq!(back.to_bytes(), bytes);
    assert_eq!(
        back.checksum(),
        u32::from_le_bytes(bytes[16..20].try_into().unwrap())
    );
}

#[test]
fn encoding_is_deterministic() {
    assert_eq!(sample().to_bytes(), sample().to_bytes());
    assert_ne!(
        sample().to_bytes(),
        random_diagram(small_axes(), 12).to_bytes()
    );
    assert_ne!(sample().lut_id(), random_diagram(small_axes(), 12).lut_id());
}

#[test]
fn lut_id_folds_the_checksum_halves() {
    assert_eq!(lut_id_of(0x1234_5678), 0x1234 ^ 0x5678);
    let d = sample();
    assert_eq!(
        d.lut_id(),
        ((d.checksum() >> 16) ^ (d.checksum() & 0xFFFF)) as u16
    );
}

#[test]
fn json_round_trip_and_file_io() {
    let d = sample();
    let json = d.to_json_string();
    assert!(json.contains("\"closing_speed_kph\""));
    assert!(json.contains("\"belt_limiter_kn\""));
    let back = Diagram::from_json_str("t.json", &json).unwrap();
    assert_eq!(back, d);
    assert_eq!(back.to_bytes(), d.to_bytes());

    let bin = tmp_path("rt.lut");
    let js = tmp_path("rt.json");
    d.save(&bin).unwrap();
    d.save_json(&js).unwrap();
    assert_eq!(Diagram::load(&bin).unwrap(), d);
    assert_eq!(Diagram::load_json(&js).unwrap(), d);
    assert_eq!(Diagram::load_any(&bin).unwrap(), d);
    assert_eq!(Diagram::load_any(&js).unwrap(), d);
    std::fs::remove_file(&bin).unwrap();
    std::fs::remove_file(&js).unwrap();
    let e = Diagram::load(&bin).unwrap_err();
    assert!(matches!(e.problem, FileProblem::Io(_)));
    assert!(e.to_string().starts_with(&bin.display().to_string()), "{e}");
}

#[test]
fn json_edits_are_checked() {
    let d = sample();
    let json = d.to_json_string();
    // Editing a value without removing the checksum is caught.
    let mut v: serde_json::Value = serde_json::from_str(&json).unwrap();
    v["cells"][0]["a_max_g"] = serde_json::json!(12.5);
    let e = Diagram::from_json_str("t.json", &v.to_string()).unwrap_err();
    assert!(
        matches!(e.problem, FileProblem::ChecksumMismatch { .. }),
        "{e}"
    );
    // A deliberate hand edit drops crc32c and lut_id.
    v.as_object_mut().unwrap().remove("crc32c");
    v.as_object_mut().unwrap().remove("lut_id");
    let edited = Diagram::from_json_str("t.json", &v.to_string()).unwrap();
    assert_eq!(edited.cells()[0].a_max_g, 12.5);
    // Wrong LUT id.
    let mut w: serde_json::Value = serde_json::from_str(&json).unwrap();
    w["lut_id"] = serde_json::json!(d.lut_id().wrapping_add(1));
    assert!(matches!(
        Diagram::from_json_str("t.json", &w.to_string())
            .unwrap_err()
            .problem,
        FileProblem::LutIdMismatch { .. }
    ));
    // Wrong version, wrong format, NaN (serialised as null), validation.
    let mut x: serde_json::Value = serde_json::from_str(&json).unwrap();
    x["format_version"] = serde_json::json!(2);
    assert!(matches!(
        Diagram::from_json_str("t.json", &x.to_string())
            .unwrap_err()
            .problem,
        FileProblem::UnsupportedVersion { found: 2, .. }
    ));
    let mut y: serde_json::Value = serde_json::from_str(&json).unwrap();
    y["format"] = serde_json::json!("something-else");
    assert!(matches!(
        Diagram::from_json_str("t.json", &y.to_string())
            .unwrap_err()
            .problem,
        FileProblem::JsonFormat { .. }
    ));
    let mut z: serde_json::Value = serde_json::from_str(&json).unwrap();
    z["cells"][3]["excursion_mm"] = serde_json::Value::Null;
    assert!(matches!(
        Diagram::from_json_str("t.json", &z.to_string())
            .unwrap_err()
            .problem,
        FileProblem::Json(_)
    ));
    let mut u: serde_json::Value = serde_json::from_str(&json).unwrap();
    u.as_object_mut().unwrap().remove("crc32c");
    u["axes"]["seat_distance_mm"] = serde_json::json!([200.0, 450.0, 300.0]);
    let e = Diagram::from_json_str("t.json", &u.to_string()).unwrap_err();
    assert!(
        matches!(
            e.problem,
            FileProblem::Invalid(Problem::AxisNotIncreasing {
                axis: AxisId::SeatDistance,
                index: 2,
                ..
            })
        ),
        "{e}"
    );
}

#[test]
fn flipped_payload_byte_is_a_checksum_mismatch() {
    let bytes = sample().to_bytes();
    for at in [
        PREAMBLE_LEN,
        PREAMBLE_LEN + 1,
        bytes.len() / 2,
        bytes.len() - 1,
    ] {
        let mut b = bytes.clone();
        b[at] ^= 0x01;
        let e = load(&b).unwrap_err();
        assert!(
            matches!(e.problem, FileProblem::ChecksumMismatch { .. }),
            "byte {at}: {e}"
        );
        let msg = e.to_string();
        assert!(
            msg.starts_with("default.lut: checksum mismatch (stored 0x"),
            "{msg}"
        );
        assert!(msg.contains(", computed 0x"), "{msg}");
    }
    // A flipped bit in the stored CRC itself.
    let mut b = bytes.clone();
    b[17] ^= 0x80;
    assert!(matches!(problem(&b), FileProblem::ChecksumMismatch { .. }));
    // The preamble's length field is covered by the CRC, too: a length that
    // still matches the file cannot be forged without fixing the CRC.
    let mut b = bytes.clone();
    b.push(0);
    b[12..16].copy_from_slice(&((bytes.len() - PREAMBLE_LEN + 1) as u32).to_le_bytes());
    assert!(matches!(problem(&b), FileProblem::ChecksumMismatch { .. }));
}

#[test]
fn truncation_and_trailing_bytes_are_named() {
    let bytes = sample().to_bytes();
    for len in [0, 7, PREAMBLE_LEN - 1] {
        let e = load(&bytes[..len]).unwrap_err();
        assert!(
            matches!(e.problem, FileProblem::TruncatedPreamble { len: l, .. } if l == len),
            "{e}"
        );
        assert!(e.to_string().starts_with("default.lut: truncated"), "{e}");
    }
    for len in [PREAMBLE_LEN, PREAMBLE_LEN + 10, bytes.len() - 1] {
        let e = load(&bytes[..len]).unwrap_err();
        assert!(
            matches!(e.problem, FileProblem::TruncatedPayload { actual, .. } if actual == len - PREAMBLE_LEN),
            "{e}"
        );
        assert!(
            e.to_string()
                .starts_with("default.lut: truncated: preamble declares"),
            "{e}"
        );
    }
    let mut long = bytes.clone();
    long.extend_from_slice(&[0, 0, 0]);
    assert!(matches!(
        problem(&long),
        FileProblem::TrailingBytes { extra: 3, .. }
    ));
}

#[test]
fn magic_version_and_reserved_are_checked() {
    let bytes = sample().to_bytes();
    let mut b = bytes.clone();
    b[1] = b'X';
    assert!(matches!(problem(&b), FileProblem::BadMagic { .. }));
    let v2 = sample().into_data().to_bytes_with_version(2);
    let e = load(&v2).unwrap_err();
    assert!(matches!(
        e.problem,
        FileProblem::UnsupportedVersion {
            found: 2,
            supported: 1
        }
    ));
    assert_eq!(
        e.to_string(),
        "default.lut: unsupported format version 2 (this build reads version 1)"
    );
    let mut b = bytes.clone();
    b[10] = 1;
    assert!(matches!(problem(&b), FileProblem::Reserved { found: 1 }));
    assert!(matches!(
        problem(b"{not binary at all, but long enough}"),
        FileProblem::BadMagic { .. }
    ));
}

#[test]
fn payload_that_passes_the_crc_but_does_not_decode() {
    // A valid envelope around garbage: only the decoder can object.
    let good = sample().to_bytes();
    let d = crafted(|_| {});
    assert_eq!(d, good);
    let garbage = [0xFFu8; 5];
    let mut b = good[..PREAMBLE_LEN].to_vec();
    b[12..16].copy_from_slice(&(garbage.len() as u32).to_le_bytes());
    b.extend_from_slice(&garbage);
    let crc = crc::Crc::<u32>::new(&crc::CRC_32_ISCSI);
    let mut dg = crc.digest();
    dg.update(&b[..16]);
    dg.update(&garbage);
    b[16..20].copy_from_slice(&dg.finalize().to_le_bytes());
    assert!(
        matches!(problem(&b), FileProblem::Decode(_)),
        "{:?}",
        problem(&b)
    );
}

fn invalid(bytes: &[u8]) -> Problem {
    match problem(bytes) {
        FileProblem::Invalid(p) => p,
        other => panic!("expected a validation error, got {other}"),
    }
}

#[test]
fn each_semantic_validator_fires() {
    // Non-monotonic axis.
    let p = invalid(&crafted(|d| {
        d.axes.opponent_mass_kg[2] = d.axes.opponent_mass_kg[1]
    }));
    assert!(
        matches!(
            p,
            Problem::AxisNotIncreasing {
                axis: AxisId::OpponentMass,
                index: 2,
                ..
            }
        ),
        "{p}"
    );
    // Too short.
    let p = invalid(&crafted(|d| {
        d.axes.seat_distance_mm.truncate(1);
        d.cells.truncate(d.cells.len() / 3);
    }));
    assert!(
        matches!(
            p,
            Problem::AxisTooShort {
                axis: AxisId::SeatDistance,
                len: 1
            }
        ),
        "{p}"
    );
    // Non-finite axis.
    let p = invalid(&crafted(|d| d.axes.closing_speed_kph[3] = f32::INFINITY));
    assert!(
        matches!(
            p,
            Problem::AxisNotFinite {
                axis: AxisId::ClosingSpeed,
                index: 3,
                ..
            }
        ),
        "{p}"
    );
    // Implausible axis (m/s typed as km/h would pass; mass in g would not).
    let p = invalid(&crafted(|d| {
        d.axes.occupant_mass_kg = vec![30_000.0, 75_000.0, 125_000.0]
    }));
    assert!(
        matches!(
            p,
            Problem::AxisImplausible {
                axis: AxisId::OccupantMass,
                ..
            }
        ),
        "{p}"
    );
    // Cell count.
    let p = invalid(&crafted(|d| {
        d.cells.pop();
    }));
    assert!(
        matches!(
            p,
            Problem::CellCount {
                expected: 180,
                found: 179
            }
        ),
        "{p}"
    );
    // NaN value in a cell.
    let p = invalid(&crafted(|d| d.cells[17].a_mean_g = f32::NAN));
    assert!(
        matches!(
            p,
            Problem::CellNotFinite {
                index: 17,
                field: "a_mean_g",
                ..
            }
        ),
        "{p}"
    );
    let msg = load(&crafted(|d| d.cells[17].a_mean_g = f32::NAN))
        .unwrap_err()
        .to_string();
    assert!(
        msg.starts_with("default.lut: cell 17 [0, 1, 2, 2]: a_mean_g is not finite"),
        "{msg}"
    );
    // Out of plausible range, and a non-0/1 bottoming flag.
    let p = invalid(&crafted(|d| d.cells[5].belt_limiter_kn = -1.0));
    assert!(
        matches!(
            p,
            Problem::CellImplausible {
                index: 5,
                field: "belt_limiter_kn",
                ..
            }
        ),
        "{p}"
    );
    let p = invalid(&crafted(|d| d.cells[5].bottoming_out = 0.5));
    assert!(
        matches!(
            p,
            Problem::CellImplausible {
                index: 5,
                field: "bottoming_out",
                ..
            }
        ),
        "{p}"
    );
    // NaN fallback outside the axis.
    let p = invalid(&crafted(|d| d.axes.nan_fallback.occupant_mass_kg = 200.0));
    assert!(
        matches!(
            p,
            Problem::FallbackOutsideAxis {
                axis: AxisId::OccupantMass,
                ..
            }
        ),
        "{p}"
    );
    // Thresholds out of order.
    let p = invalid(&crafted(|d| {
        d.header.airbag_thresholds.no_fire_below_kn = 7.0
    }));
    assert!(matches!(p, Problem::Thresholds { .. }), "{p}");
    // Ego vehicle.
    let p = invalid(&crafted(|d| d.header.ego.class = 9));
    assert!(matches!(p, Problem::EgoVehicle { class: 9, .. }), "{p}");
}

#[test]
fn shards_in_any_order_rebuild_the_same_table() {
    let d = sample();
    let n = d.cells().len();
    // Three contiguous shards delivered in reverse order.
    let mut pieces: Vec<(usize, diagram::Cell)> = Vec::new();
    for (lo, hi) in [(120, n), (60, 120), (0, 60)] {
        pieces.extend((lo..hi).map(|i| (i, d.cells()[i])));
    }
    let merged = Diagram::from_indexed_cells(header(), small_axes(), pieces.clone()).unwrap();
    assert_eq!(merged.to_bytes(), d.to_bytes());
    let concat = Diagram::from_cells(header(), small_axes(), d.cells().to_vec()).unwrap();
    assert_eq!(concat, d);
    // Missing and duplicate cells.
    let e = Diagram::from_indexed_cells(header(), small_axes(), pieces[1..].to_vec()).unwrap_err();
    assert!(matches!(e, Problem::CellMissing { index: 120, .. }), "{e}");
    let mut dup = pieces.clone();
    dup.push(pieces[0]);
    let e = Diagram::from_indexed_cells(header(), small_axes(), dup).unwrap_err();
    assert!(
        matches!(
            e,
            Problem::CellIndexInvalid {
                index: 120,
                count: 180
            }
        ),
        "{e}"
    );
}
