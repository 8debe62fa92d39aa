//! The crash modes in scenario files: their keys, validated with the file's line and field,
//! and what the truth and the satellites make of them.

use world::scenario::{FrontSide, OpponentKind};
use world::{Scenario, Truth};

/// A scenario at `kph` against `opponent` (its `[opponent]` lines after `kind`), the crash
/// 1.5 s in.
fn scenario(kph: f64, kind: &str, opponent: &str) -> String {
    let fixed = matches!(kind, "barrier" | "offset_barrier" | "pole");
    format!(
        "name = \"m\"\nduration_s = 2.0\n\n[ego]\nmass_kg = 1785\nclass = 4\nspeed_kph = {kph}\n\n\
         [opponent]\nkind = \"{kind}\"\ninitial_distance_m = {:.3}\n{opponent}\n\n[sensor]\n{}\n\
         [occupant]\nmass_kg = 75\n",
        kph / 3.6 * 1.5,
        if fixed {
            "mass_estimate_kg = 3000\n"
        } else {
            ""
        }
    )
}

fn parse(text: &str) -> Result<Scenario, world::scenario::ScenarioError> {
    Scenario::parse("m.toml", text)
}

#[test]
fn each_kind_parses_with_its_defaults() {
    use physics::crash_mode::CrashMode;
    let s = parse(&scenario(64.0, "offset_barrier", "")).unwrap();
    assert_eq!(s.opponent.kind, OpponentKind::OffsetBarrier);
    assert_eq!(s.crash_mode(), CrashMode::Offset { overlap: 0.4 });
    assert!(s.opponent_mass_kg().is_infinite());
    let s = parse(&scenario(
        32.0,
        "barrier",
        "angle_deg = 30\nstruck_side = \"right\"",
    ))
    .unwrap();
    assert!(
        matches!(s.crash_mode(), CrashMode::Angular { angle_rad } if (angle_rad - 30f64.to_radians()).abs() < 1e-12)
    );
    assert_eq!(s.opponent.struck_side, Some(FrontSide::Right));
    assert_eq!(
        parse(&scenario(32.0, "pole", "")).unwrap().crash_mode(),
        CrashMode::Pole
    );
    let s = parse(&scenario(40.0, "underride", "mass_kg = 12000")).unwrap();
    assert_eq!(s.crash_mode(), CrashMode::Underride);
    assert_eq!(s.opponent_mass_kg(), 12000.0);
    let s = parse(&scenario(
        50.0,
        "vehicle",
        "mass_kg = 1500\noverlap_percent = 50",
    ))
    .unwrap();
    assert_eq!(s.crash_mode(), CrashMode::Offset { overlap: 0.5 });
    assert!(s.opponent_class().is_some());
    // Today's files: the full frontal, unchanged.
    let s = parse(&scenario(50.0, "barrier", "")).unwrap();
    assert_eq!(s.crash_mode(), CrashMode::FullFrontal);
    assert_eq!(s.ego.width_m, physics::crash_mode::DEFAULT_WIDTH_M);
}

/// Every key a kind does not use, and every value out of its range: the field and its line.
#[test]
fn a_key_a_kind_does_not_use_or_a_value_out_of_range_names_its_field_and_line() {
    for (kind, line, field, says) in [
        (
            "pole",
            "mass_kg = 1000",
            "opponent.mass_kg",
            "not used by kind = \"pole\"",
        ),
        (
            "offset_barrier",
            "speed_kph = 10",
            "opponent.speed_kph",
            "fixed in place",
        ),
        (
            "offset_barrier",
            "overlap_percent = 5",
            "opponent.overlap_percent",
            "outside 10..=100",
        ),
        (
            "pole",
            "overlap_percent = 40",
            "opponent.overlap_percent",
            "centre of the front",
        ),
        (
            "underride",
            "mass_kg = 12000\nangle_deg = 10",
            "opponent.angle_deg",
            "rigid barrier's",
        ),
        (
            "underride",
            "mass_kg = 12000\nclass = 6",
            "opponent.class",
            "bed, not the truck's front",
        ),
        (
            "underride",
            "mass_kg = 1000",
            "opponent.mass_kg",
            "outside 3000..=40000",
        ),
        (
            "barrier",
            "angle_deg = 50",
            "opponent.angle_deg",
            "outside 0..=45",
        ),
        (
            "barrier",
            "overlap_percent = 40\nangle_deg = 20",
            "opponent.angle_deg",
            "corner first",
        ),
        (
            "barrier",
            "struck_side = \"left\"",
            "opponent.struck_side",
            "one side first",
        ),
        (
            "pole",
            "struck_side = \"left\"",
            "opponent.struck_side",
            "one side first",
        ),
    ] {
        let text = scenario(40.0, kind, line);
        let e = parse(&text).expect_err(line);
        assert_eq!(e.field.as_deref(), Some(field), "{kind} {line}: {e}");
        assert!(e.message.contains(says), "{kind} {line}: {e}");
        let key = field.trim_start_matches("opponent.");
        let opponent = text.lines().position(|l| l == "[opponent]").unwrap();
        let want = text
            .lines()
            .enumerate()
            .skip(opponent)
            .find(|(_, l)| l.starts_with(key))
            .map(|(i, _)| i + 1);
        assert_eq!(e.line, want, "{kind} {line}: {e}");
    }
    // A misspelt kind or side: toml's own message, with the line.
    let e = parse(&scenario(40.0, "offset-barrier", "")).unwrap_err();
    assert!(e.message.contains("offset_barrier"), "{e}");
    let e = parse(&scenario(
        40.0,
        "offset_barrier",
        "struck_side = \"middle\"",
    ))
    .unwrap_err();
    assert!(e.line.is_some(), "{e}");
    // A pole needs what the classifier reports, as a barrier does.
    let text = scenario(32.0, "pole", "").replace("mass_estimate_kg = 3000\n", "");
    let e = parse(&text).unwrap_err();
    assert_eq!(e.field.as_deref(), Some("sensor.mass_estimate_kg"), "{e}");
}

fn satellite_dv(t: &Truth, side: FrontSide, ms: f64) -> f64 {
    let tc = t.contact_s.unwrap();
    // Integrated minus the body's: the crush Δv the satellite leads the body by.
    (0..(ms * 10.0) as usize)
        .map(|k| {
            let s = tc + k as f64 * 1e-4;
            (t.ego_accel_mps2(s) - t.satellite_accel_mps2(side, s)) * 1e-4
        })
        .sum()
}

/// The struck side's satellite folds first: in a 40 % offset only the struck rail is loaded
/// (the other satellite moves with the body); at 30° the far rail's tip is reached only after
/// the wall has advanced (0.8 − 0.2)·width·tan 30° further; a full frontal loads both alike.
#[test]
fn the_struck_sides_satellite_folds_first() {
    let t =
        Truth::new(&parse(&scenario(64.0, "offset_barrier", "struck_side = \"right\"")).unwrap())
            .unwrap();
    assert!(satellite_dv(&t, FrontSide::Right, 10.0) > 2.0);
    assert!(satellite_dv(&t, FrontSide::Left, 100.0).abs() < 1e-9);
    let t = Truth::new(&parse(&scenario(32.0, "barrier", "angle_deg = 30")).unwrap()).unwrap();
    let (near, far) = (
        satellite_dv(&t, FrontSide::Left, 60.0),
        satellite_dv(&t, FrontSide::Right, 60.0),
    );
    assert!(near > 1.0 && far < 0.1 * near, "near {near}, far {far}");
    let t = Truth::new(&parse(&scenario(56.0, "barrier", "")).unwrap()).unwrap();
    for ms in [2.0, 5.0, 20.0] {
        assert_eq!(
            satellite_dv(&t, FrontSide::Left, ms),
            satellite_dv(&t, FrontSide::Right, ms)
        );
    }
    // Under the bed neither tip is reached; beside a pole not before the engine.
    let t = Truth::new(&parse(&scenario(40.0, "underride", "mass_kg = 12000")).unwrap()).unwrap();
    assert!(satellite_dv(&t, FrontSide::Left, 150.0).abs() < 1e-9);
    let t = Truth::new(&parse(&scenario(32.0, "pole", "")).unwrap()).unwrap();
    assert!(satellite_dv(&t, FrontSide::Left, 40.0).abs() < 1e-9);
}

/// A slow underride outlasts the pulse buffer: the body's pulse ends with it, it is not held.
#[test]
fn a_contact_longer_than_the_pulse_ends_with_it() {
    let t = Truth::new(&parse(&scenario(20.0, "underride", "mass_kg = 30000")).unwrap()).unwrap();
    let tc = t.contact_s.unwrap();
    let end = t.pulse.len() as f64 * t.pulse.step_s();
    assert!(
        t.ego_accel_mps2(tc + end - 2e-4) < 0.0,
        "still in contact at the buffer's end"
    );
    assert_eq!(t.ego_accel_mps2(tc + end + 1e-3), 0.0);
}
