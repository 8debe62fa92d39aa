//! Robust cells (lut::robust_cells): the guarantee they are optimised for holds at every point
//! of their set, they cannot beat the unconstrained optimum on the nominal case, and the set is
//! what it says.

use lut::robust_cells::{point_optimum, set_points, Situation, UncertainSet, Uncertainty};
use lut::scenario::Ego;
use lut::table::Grid;
use physics::reference::ReferenceRestraint;
use physics::OccupantInput;
use std::path::PathBuf;

fn repo(p: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..").join(p)
}

fn occupant() -> OccupantInput {
    OccupantInput {
        mass_kg: 75.0,
        chest_to_wheel_m: 0.300,
        belted: true,
    }
}

#[test]
fn the_set_is_the_nominal_point_and_one_error_at_a_time_or_both() {
    let s = Situation {
        closing_kph: 96.0,
        opponent_kg: 1000.0,
        occupant: occupant(),
    };
    let cross = set_points(&s, &Uncertainty::MISREPORT);
    assert_eq!(cross.len(), 5);
    assert_eq!(cross[0], (96.0, 1000.0));
    // 1000 − 1200 kg is clamped to the axis' lightest opponent.
    assert!(cross.contains(&(96.0, 800.0)) && cross.contains(&(96.0, 2200.0)));
    assert!(cross.contains(&(78.0, 1000.0)) && cross.contains(&(114.0, 1000.0)));
    let boxed = set_points(
        &s,
        &Uncertainty {
            corners: true,
            ..Uncertainty::MISREPORT
        },
    );
    assert_eq!(boxed.len(), 9);
    assert!(boxed.contains(&(114.0, 2200.0)) && boxed.contains(&(78.0, 800.0)));
}

/// At every point of the set the robust cell is no worse than the reference restraint and
/// does not bottom out where the reference does not — judged by re-simulating the true pulse
/// at each point (not by the optimiser's own cost) — and on the nominal case it cannot beat
/// the optimum planned for the nominal case alone.
#[test]
fn a_robust_cell_keeps_its_guarantee_over_the_whole_set() {
    let reference = ReferenceRestraint::load(repo("data/reference-restraint.toml"))
        .unwrap()
        .settings();
    let cfg = Grid::load(repo("data/default-grid.toml"))
        .unwrap()
        .optimiser;
    let ego = Ego::default();
    for (v, m) in [(96.0, 1785.0), (96.0, 1000.0), (62.0, 1785.0)] {
        let s = Situation {
            closing_kph: v,
            opponent_kg: m,
            occupant: occupant(),
        };
        let u = Uncertainty::MISREPORT;
        let set = UncertainSet::new(&ego, &s, &u, &reference, cfg.reserve_m).unwrap();
        let robust = set.robust_optimum(&cfg).unwrap();
        let j = set.judge(&robust).unwrap();
        assert_eq!(j.bottoms_out_alone, 0, "{v} km/h, {m} kg: {j:?}");
        assert_eq!(j.worse_than_reference, 0, "{v} km/h, {m} kg: {j:?}");
        let free = point_optimum(&ego, &occupant(), v, m, &cfg).unwrap();
        let jf = set.judge(&free).unwrap();
        assert!(
            j.nominal_change_pct >= jf.nominal_change_pct - 0.5,
            "{v} km/h, {m} kg: robust {j:?} beat the nominal optimum {jf:?}"
        );
    }
}
