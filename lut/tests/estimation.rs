//! `lut study estimation` (lut::estimation) on cases with a known answer.

use lut::estimation::{self, raw_estimate, VARIATIONS};
use restraint::{ObjectState, VALID};
use world::Scenario;

fn scenario(extra_sensor: &str) -> Scenario {
    // Two 60 km/h cars, no braking: contact when the 40 m gap closes at 33.3 m/s.
    let text = format!(
        "name = \"t\"\nduration_s = 3\nseed = 1\n[ego]\nmass_kg = 1785\nclass = 4\nspeed_kph = 60\n\
         [opponent]\nkind = \"vehicle\"\nmass_kg = 1500\nspeed_kph = 60\ninitial_distance_m = 40\n\
         [sensor]\n{extra_sensor}\n[occupant]\nmass_kg = 75\nbelted = true\n"
    );
    Scenario::parse("t.toml", &text).expect("valid scenario")
}

#[test]
fn raw_estimate_is_the_closed_form_of_one_sample() {
    // 1 s after the epoch: 10 m at 20 m/s, no acceleration → contact 0.5 s later.
    let o = ObjectState {
        timestamp_ns: 2_000_000_000,
        distance_m: 10.0,
        closing_speed_mps: 20.0,
        opponent_mass_kg: 1500.0,
        opponent_mass_sigma_kg: 300.0,
        valid: VALID,
        ..ObjectState::INVALID
    };
    let h = raw_estimate(&o, 1.0).unwrap();
    assert!((h.contact_s - 1.5).abs() < 1e-9, "{h:?}");
    assert_eq!(h.closing_speed_mps, 20.0);
    assert_eq!((h.mass_kg, h.lookup_mass_kg), (1500.0, 1800.0));
    assert!(h.contact_sigma_s.is_nan());
}

#[test]
fn noise_free_constant_speeds_are_estimated_exactly_by_both() {
    // Without noise and acceleration both estimates are exact up to the f32 samples and the
    // ns time stamps (the sensor's latency is compensated by both).
    let s = scenario("distance_noise_m = 0\nspeed_noise_mps = 0\nlatency_ms = 35");
    let r = estimation::simulate(&s, &VARIATIONS[0], 1, 0, false).unwrap();
    let v_true = 2.0 * 60.0 / 3.6;
    assert!(
        (r.contact_s - 40.0 / v_true).abs() < 1e-5,
        "{}",
        r.contact_s
    );
    for h in [r.raw.unwrap(), r.filtered.unwrap()] {
        assert!((h.contact_s - r.contact_s).abs() < 1e-5, "{h:?}");
        assert!((h.closing_speed_mps - v_true).abs() < 1e-4, "{h:?}");
        assert!((h.mass_kg - 1500.0).abs() < 1e-9);
    }
    assert_eq!((r.outliers, r.starts), (0, 1));
}

#[test]
fn runs_are_reproducible_and_variations_do_what_they_say() {
    let s = scenario("");
    // Compared as text: the raw estimate's σ is NaN, which equals nothing.
    let run = |i| {
        format!(
            "{:?}",
            estimation::simulate(&s, &VARIATIONS[1], 7, i, true).unwrap()
        )
    };
    let (a, b, c) = (run(3), run(3), run(4));
    assert!(a == b, "same seed and index, different runs");
    assert!(a != c, "another index, the same run");
    // Noise ×3: the sensor's noise ×3 and a tracker's acceleration noise.
    let n = VARIATIONS[1].apply(&s);
    assert_eq!(n.sensor.distance_noise_m, 3.0 * s.sensor.distance_noise_m);
    assert_eq!(n.sensor.speed_noise_mps, 3.0 * s.sensor.speed_noise_mps);
    assert_eq!(
        n.sensor.relative_accel_noise_mps2,
        3.0 * estimation::TRACKER_ACCEL_NOISE_MPS2
    );
    // 30 % dropped: about 30 % fewer samples than the same run without drops.
    let full = estimation::simulate(&s, &VARIATIONS[0], 7, 3, false).unwrap();
    let dropped = estimation::simulate(&s, &VARIATIONS[4], 7, 3, false).unwrap();
    let share = dropped.samples as f64 / full.samples as f64;
    assert!(
        (0.5..0.9).contains(&share),
        "{} of {}",
        dropped.samples,
        full.samples
    );
}
