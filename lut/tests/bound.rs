//! `lut study bound` (lut::bound) on the shipped table: the ideal constant-force deceleration
//! a* is a lower bound of every restraint's peak (so a_max / a* ≥ 1 in every cell), the
//! `as built` re-optimisation is the build's own optimum, and lifting every limitation of the
//! restraint model brings the optima closer to the bound.

use diagram::Diagram;
use lut::bound::{levers, table_ratios, LEVERS};
use std::path::PathBuf;

fn table() -> Diagram {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../data/default.lut");
    Diagram::load_any(&p).expect("shipped table")
}

#[test]
fn no_cell_beats_the_constant_force_bound() {
    let t = table_ratios(&table()).unwrap();
    assert!(t.cells > 3000, "{} cells counted", t.cells);
    // f32 storage of a_max and a*: a hair of rounding, no more.
    assert!(
        t.best.ratio >= 0.999,
        "a cell below its bound: {:?}",
        t.best
    );
    assert!(t.p50 <= t.p90 && t.p90 <= t.worst.ratio);
    assert_eq!(
        t.by_closing_speed.len(),
        9,
        "one row per closing speed of the grid"
    );
}

#[test]
fn lifting_the_model_s_limitations_moves_the_optima_towards_the_bound() {
    let d = table();
    let rows = levers(&d, 12, 7).unwrap();
    assert_eq!(rows.len(), LEVERS.len());
    let by = |name: &str| rows.iter().find(|r| r.lever.name == name).unwrap();
    let (built, all) = (by("as built"), by("all of them"));
    assert!(built.feasible >= 10, "{built:?}");
    assert!(
        all.p50 < built.p50 && all.worst < built.worst,
        "as built {built:?}, all lifted {all:?}"
    );
    for r in &rows {
        assert!(r.p50 >= 0.999, "{r:?} below the bound");
    }
}

/// The `as built` lever is the build itself: the same optimiser, configuration and per-cell
/// seed give the stored cell's optimum, so its a_max / a* is the table's (to the f32 the
/// table stores).
#[test]
fn as_built_is_the_build_s_own_optimum() {
    let d = table();
    let grid = lut::table::Grid::from_table(&d).unwrap();
    let mut compared = 0;
    for i in (0..d.cells().len()).step_by(401) {
        let c = &d.cells()[i];
        let (ratio, objective_g, bottomed) =
            lut::bound::optimise_with(&grid, i, &LEVERS[0]).unwrap();
        assert_eq!(bottomed, c.is_bottoming_out(), "cell {i}");
        let stored = f64::from(c.a_max_g) + f64::from(c.a_mean_g);
        assert!(
            (objective_g - stored).abs() < 1e-3 * stored,
            "cell {i}: {objective_g} vs {stored}"
        );
        if !bottomed && c.a_ideal_g > 0.0 {
            let want = f64::from(c.a_max_g) / f64::from(c.a_ideal_g);
            assert!(
                (ratio - want).abs() < 1e-3 * want,
                "cell {i}: {ratio} vs {want}"
            );
            compared += 1;
        }
    }
    assert!(compared >= 4, "{compared} cells compared");
}
