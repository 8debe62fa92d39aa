//! A scenario's `[pulse]` file drives the ego's crash: the shipped ISO-MME file of a 25 g ×
//! 100 ms half-sine is the oracle (its closed form: Δv = 2AT/π, the peak A at T/2), read back
//! through the accelerometer's own model; errors in the table or the file name the field.

use std::path::PathBuf;
use world::{Scenario, SensorModelSim, Truth};

const G: f64 = 9.806_65;
const PEAK_G: f64 = 25.0;
const T_S: f64 = 0.1;

fn scenarios() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../scenarios")
}

fn half_sine_g(t_s: f64) -> f64 {
    if (0.0..=T_S).contains(&t_s) {
        PEAK_G * (std::f64::consts::PI * t_s / T_S).sin()
    } else {
        0.0
    }
}

/// The file holds the closed form (to its 6 decimals), and the truth made of it carries the
/// closed form's Δv and peak.
#[test]
fn the_shipped_iso_mme_file_is_the_closed_form_half_sine() {
    let text = std::fs::read_to_string(scenarios().join("pulses/half-sine-25g-100ms.001"))
        .expect("pulse file");
    let trace = physics::trace::parse(&text).expect("ISO-MME");
    assert_eq!((trace.start_s, trace.step_s), (-0.01, 1e-4));
    for (k, a) in trace.accel_mps2.iter().enumerate() {
        let t = trace.start_s + k as f64 * trace.step_s;
        assert!((a / G + half_sine_g(t)).abs() < 1e-5, "{t} s: {a}");
    }
    let s = Scenario::load(scenarios().join("measured-pulse-half-sine-56.toml")).expect("load");
    let truth = Truth::new(&s).expect("truth");
    let c = truth.collision.expect("a crash");
    let dv = 2.0 * PEAK_G * G * T_S / std::f64::consts::PI;
    assert!((c.vehicle.delta_v_mps - dv).abs() < 1e-3 * dv, "{c:?}");
    assert!((c.vehicle.a_max_mps2 / G - PEAK_G).abs() < 1e-3, "{c:?}");
    // Against the barrier at the barrier's speed, the half-sine stops the car at T: its crush
    // is A·T²/π.
    let crush = PEAK_G * G * T_S * T_S / std::f64::consts::PI;
    let closing = truth.closing_speed_at_contact_mps();
    assert!((closing - 56.0 / 3.6).abs() < 1e-6);
    assert!(
        (c.vehicle.crush_m - crush).abs() < 0.01 * crush,
        "{c:?} vs {crush}"
    );
}

/// What the crash accelerometer publishes (its anti-alias low-pass, noise and range) carries
/// the file's Δv within 1 % and its peak within 2 %: a 10 Hz-wide pulse passes a 400 Hz
/// filter unchanged but for its delay.
#[test]
fn the_accelerometer_reads_the_files_velocity_change_and_peak() {
    let s = Scenario::load(scenarios().join("measured-pulse-half-sine-56.toml")).expect("load");
    let truth = Truth::new(&s).expect("truth");
    let tc = truth.contact_s.expect("contact");
    let mut sim = SensorModelSim::new(truth);
    let dt = 1e-4;
    let (mut dv, mut peak) = (0.0, 0.0f64);
    for k in 0..((T_S + 0.02) / dt) as usize {
        let a = sim.accel_mps2(tc + k as f64 * dt);
        dv += -a * dt;
        peak = peak.max(-a);
    }
    let dv_closed = 2.0 * PEAK_G * G * T_S / std::f64::consts::PI;
    assert!(
        (dv - dv_closed).abs() < 0.01 * dv_closed,
        "{dv} vs {dv_closed}"
    );
    assert!((peak / G - PEAK_G).abs() < 0.02 * PEAK_G, "{} g", peak / G);
}

fn with_pulse(dir: &std::path::Path, file_text: &str, table: &str) -> world::ScenarioError {
    let pulse = dir.join("p.csv");
    std::fs::write(&pulse, file_text).expect("write");
    let base = std::fs::read_to_string(scenarios().join("measured-pulse-half-sine-56.toml"))
        .expect("scenario");
    let text = base.replace("file = \"pulses/half-sine-25g-100ms.001\"", table);
    let path = dir.join("s.toml");
    std::fs::write(&path, text).expect("write");
    Scenario::load(&path).expect_err("refused")
}

/// Every way a pulse file can be wrong is an error naming the scenario file, the line of
/// `pulse.file`, the field and the pulse file's own line where it has one.
#[test]
fn a_bad_pulse_file_is_an_error_at_pulse_file() {
    let dir = std::env::temp_dir().join(format!("measured-pulse-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("dir");
    let csv = |rows: &dyn Fn(usize) -> String| {
        let mut s = String::from("time_ms,accel_g\n");
        for k in 0..40 {
            s += &rows(k);
        }
        s
    };
    let good = csv(&|k| format!("{},{}\n", k as f64 * 0.1 - 1.0, -10.0));
    for (file_text, table, says) in [
        (good.clone(), "file = \"missing.csv\"", "cannot read"),
        (
            good.replace("-10\n", "x\n"),
            "file = \"p.csv\"",
            "line 2: not a number",
        ),
        (
            csv(&|k| format!("{},{}\n", k as f64 * 0.1 + 1.0, -10.0)),
            "file = \"p.csv\"",
            "beginning is missing",
        ),
        (
            csv(&|k| format!("{},{}\n", k as f64 * 2.0, -10.0)),
            "file = \"p.csv\"",
            "coarser than 1 ms",
        ),
        (
            csv(&|k| format!("{},{}\n", k as f64 * 0.1, 10.0)),
            "file = \"p.csv\"",
            "does not slow the car",
        ),
        (
            good.clone(),
            "file = \"p.csv\"\nchannel = 3",
            "unknown field",
        ),
    ] {
        let e = with_pulse(&dir, &file_text, table);
        let line = e.to_string();
        assert!(line.contains(says), "{line}");
        assert!(line.contains("s.toml:"), "{line}");
        if !says.starts_with("unknown") {
            assert_eq!(e.field.as_deref(), Some("pulse.file"), "{line}");
            assert!(e.line.is_some(), "{line}");
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}
