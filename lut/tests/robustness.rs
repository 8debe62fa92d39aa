//! The Monte-Carlo robustness study on the committed default table, without a scheduler:
//! sharded runs equal the local run bit for bit, a perfect estimate reproduces what the table
//! itself predicts, and shards of another study are refused.

use diagram::{Diagram, Query};
use lut::progress::Progress;
use lut::robustness::{self, EstimateErrors, RobustnessJob, Situation};
use lut::verify;
use std::path::PathBuf;

fn table_path() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../data/default.lut")
}

fn job(errors: EstimateErrors, samples: u64, seed: u64) -> RobustnessJob {
    let d = Diagram::load(table_path()).unwrap();
    RobustnessJob {
        table: table_path(),
        table_crc32c: d.checksum(),
        // A grid point of data/default-grid.toml.
        situation: Situation {
            closing_speed_kph: 91.0,
            opponent_mass_kg: 1800.0,
            occupant_mass_kg: 75.0,
            seat_distance_mm: 300.0,
        },
        errors,
        samples,
        seed,
    }
}

const TYPICAL: EstimateErrors = EstimateErrors {
    mass_error_kg: 300.0,
    speed_sigma_kph: 2.0,
    distance_sigma_m: 0.1,
    measurement_ttc_ms: 100.0,
};

#[test]
fn sharded_study_equals_the_local_run() {
    let j = job(TYPICAL, 900, 5);
    let local = j.run_local(Some(2), true).unwrap();
    let id = j.identity().unwrap();
    let quiet = Progress::new(0, "", "samples", true);
    let mut shards: Vec<(String, Vec<u8>)> = (1..=4)
        .map(|k| {
            (
                format!("shard-{k}"),
                j.compute_shard(k, 4, Some(1), &quiet).unwrap(),
            )
        })
        .collect();
    shards.reverse();
    let dir = std::env::temp_dir().join(format!("lut-robustness-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("r.json");
    j.collect(&id, &shards, &out).unwrap();
    let merged = robustness::read_result(&out).unwrap();
    assert_eq!(merged, local);
    assert_eq!(
        serde_json::to_string(&merged).unwrap(),
        serde_json::to_string(&local).unwrap()
    );
    assert!(robustness::output_matches(&out, &id));
    assert!(local.a_mean_g.sd > 0.0 && local.a_max_g.p95 >= local.a_max_g.p05);

    // A shard of the same study with another seed is refused, naming it.
    let other = job(TYPICAL, 900, 6);
    shards[0] = (
        "seed6.bin".into(),
        other.compute_shard(4, 4, Some(1), &quiet).unwrap(),
    );
    let e = j.collect(&id, &shards, &out).unwrap_err().to_string();
    assert!(
        e.starts_with("seed6.bin: shard of another grid or configuration"),
        "{e}"
    );
    // A missing shard is named as a gap.
    let e = j.collect(&id, &shards[1..], &out).unwrap_err().to_string();
    assert!(e.contains("items 675..900 missing"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_perfect_estimate_reproduces_the_table_and_has_no_spread() {
    let zero = EstimateErrors {
        mass_error_kg: 0.0,
        speed_sigma_kph: 0.0,
        distance_sigma_m: 0.0,
        measurement_ttc_ms: 100.0,
    };
    let j = job(zero, 50, 1);
    let r = j.run_local(Some(2), true).unwrap();
    for s in [
        &r.a_max_g,
        &r.a_mean_g,
        &r.excursion_mm,
        &r.objective_increase_g,
    ] {
        // Identical samples (the mean of equal numbers may round in the last bit).
        assert_eq!(s.min, s.max);
        assert!(s.sd < 1e-12, "{s:?}");
    }
    assert_eq!(r.a_mean_g.min, r.exact_estimate.a_mean_g);
    assert_eq!(r.fallback_samples, 0);
    // The table's own prediction for this grid point (stored by the optimiser when the table
    // was built) is what the study's re-simulation of the looked-up setting gives, within the
    // tolerance of `lut verify`'s re-simulation (the stored setting is rounded to f32).
    let d = Diagram::load(table_path()).unwrap();
    let s = &j.situation;
    let l = d.lookup(&Query {
        closing_speed_kph: s.closing_speed_kph as f32,
        opponent_mass_kg: s.opponent_mass_kg as f32,
        occupant_mass_kg: s.occupant_mass_kg as f32,
        seat_distance_mm: s.seat_distance_mm as f32,
    });
    let stored = f64::from(l.values.a_max_g) + f64::from(l.values.a_mean_g);
    let ours = r.exact_estimate.a_max_g + r.exact_estimate.a_mean_g;
    assert!(
        (ours - stored).abs() <= verify::RESIM_TOL_ABS_G.max(verify::RESIM_TOL_REL * stored),
        "study {ours:.3} g vs table {stored:.3} g"
    );
    assert_eq!(r.exact_estimate.bottoming_out, l.bottoming_out);
}

#[test]
fn estimates_outside_the_table_fall_back_to_the_reference_restraint() {
    // 40 km/h is the table's lowest closing speed: about half the speed errors leave it.
    let mut j = job(
        EstimateErrors {
            mass_error_kg: 0.0,
            speed_sigma_kph: 2.0,
            distance_sigma_m: 0.0,
            measurement_ttc_ms: 100.0,
        },
        400,
        3,
    );
    j.situation.closing_speed_kph = 40.0;
    let r = j.run_local(Some(2), true).unwrap();
    let share = r.fallback_samples as f64 / 400.0;
    assert!((0.4..0.6).contains(&share), "{share}");
}
