//! Robust cells (lut::robust_cells): the guarantee they are optimised for holds at every point
//! of their set, they cannot beat the unconstrained optimum on the nominal case, and the set is
//! what it says. The two-level load limiter study built on them (lut::limiter_switch): the
//! evidence is measured as physics says, the rule keeps the high level where the truth is more
//! severe, and the plan's guarantee holds at every point of the set — judged by re-simulating
//! each point here, not by the optimiser's cost.

use lut::limiter_switch::{speed_lost_by_mps, SwitchRule};
use lut::optimise::OptimiserConfig;
use lut::robust_cells::{
    objective_g, point_optimum, set_points, Situation, UncertainSet, Uncertainty, LIBRARY_OCCUPANT,
};
use lut::scenario::{Ego, Opponent, Pulse};
use lut::table::Grid;
use physics::reference::ReferenceRestraint;
use physics::{
    simulate_occupant, simulate_occupant_switched, CompartmentPulse, RestraintHardware,
    RestraintSettings,
};
use std::path::PathBuf;

fn repo(p: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..").join(p)
}

/// The shipped reference restraint's settings.
fn reference() -> RestraintSettings {
    ReferenceRestraint::load(repo("data/reference-restraint.toml"))
        .unwrap()
        .settings()
}

/// The default grid's optimiser settings.
fn optimiser() -> OptimiserConfig {
    Grid::load(repo("data/default-grid.toml"))
        .unwrap()
        .optimiser
}

#[test]
fn the_set_is_the_nominal_point_and_one_error_at_a_time_or_both() {
    let s = Situation {
        closing_kph: 96.0,
        opponent_kg: 1000.0,
        occupant: LIBRARY_OCCUPANT,
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
    let reference = reference();
    let cfg = optimiser();
    let ego = Ego::default();
    for (v, m) in [(96.0, 1785.0), (96.0, 1000.0), (62.0, 1785.0)] {
        let s = Situation {
            closing_kph: v,
            opponent_kg: m,
            occupant: LIBRARY_OCCUPANT,
        };
        let u = Uncertainty::MISREPORT;
        let set = UncertainSet::new(&ego, &s, &u, &reference, cfg.reserve_m).unwrap();
        let robust = set.robust_optimum(&cfg).unwrap();
        let j = set.judge(&robust).unwrap();
        assert_eq!(j.bottoms_out_alone, 0, "{v} km/h, {m} kg: {j:?}");
        assert_eq!(j.worse_than_reference, 0, "{v} km/h, {m} kg: {j:?}");
        let free = point_optimum(&ego, &LIBRARY_OCCUPANT, v, m, &cfg).unwrap();
        let jf = set.judge(&free).unwrap();
        assert!(
            j.nominal_change_pct >= jf.nominal_change_pct - 0.5,
            "{v} km/h, {m} kg: robust {j:?} beat the nominal optimum {jf:?}"
        );
    }
}

#[test]
fn the_speed_lost_by_a_time_is_the_pulse_integrated_to_it() {
    // 20 g from contact for 50 ms: a·t until then, a·50 ms after (and the trapezoid's half step
    // down to zero: 0.1 % of it).
    let a = 20.0 * 9.80665;
    let mut s = vec![0.0; 1000];
    s[..501].iter_mut().for_each(|v| *v = -a);
    let p = CompartmentPulse {
        step_s: 1e-4,
        accel_mps2: &s,
    };
    assert!((speed_lost_by_mps(&p, 0.030) / (a * 0.030) - 1.0).abs() < 1e-9);
    assert!((speed_lost_by_mps(&p, 0.080) / (a * 0.050) - 1.0).abs() < 1.1e-3);
    assert_eq!(speed_lost_by_mps(&p, 0.0), 0.0);
    assert_eq!(speed_lost_by_mps(&p, -1.0), 0.0);
    // Beyond the pulse's end: all of it.
    assert!((speed_lost_by_mps(&p, 10.0) / (a * 0.050) - 1.0).abs() < 1.1e-3);
}

/// The heavier opponent and the faster closing both lose more speed by the decision than the
/// threshold allows: the rule keeps the robust high level for them; the estimate itself switches.
#[test]
fn the_rule_keeps_the_high_level_where_the_truth_is_heavier_or_faster() {
    let cfg = optimiser();
    let ego = Ego::default();
    for (v, m) in [(96.0, 1785.0), (104.0, 1785.0), (96.0, 1300.0)] {
        let s = Situation {
            closing_kph: v,
            opponent_kg: m,
            occupant: LIBRARY_OCCUPANT,
        };
        let rule = SwitchRule::new(&ego, &s, 1200.0, 0.040, 0.0, &cfg).unwrap();
        let pulse = |v: f64, m: f64| Pulse::predict(&ego, Opponent::Car { mass_kg: m }, v).unwrap();
        assert!(
            rule.switches(&pulse(v, m).ego()),
            "{v} km/h {m} kg: {rule:?}"
        );
        assert!(
            !rule.switches(&pulse(v, m + 1200.0).ego()),
            "{v} {m}: {rule:?}"
        );
        assert!(
            !rule.switches(&pulse(v + 18.0, m).ego()),
            "{v} {m}: {rule:?}"
        );
        // How little the mass shows by then: the two predictions are within 5 % of each other.
        let (a, b) = rule.predicted_mps;
        assert!(b > a && (b - a) / a < 0.05, "{v} {m}: {rule:?}");
    }
}

/// At every point of the set the two-level plan (with the switch the rule gives on that
/// point's true pulse, the measurement read low as configured) is no worse than the reference
/// restraint and does not bottom out where it does not.
#[test]
fn a_two_level_plan_keeps_its_guarantee_over_the_whole_set() {
    let reference = reference();
    let cfg = optimiser();
    let (ego, hw, u) = (
        Ego::default(),
        RestraintHardware::default(),
        Uncertainty::MISREPORT,
    );
    for (v, m, err) in [
        (96.0, 1785.0, 0.0),
        (62.0, 1785.0, 0.0),
        (96.0, 1300.0, 0.02),
    ] {
        let s = Situation {
            closing_kph: v,
            opponent_kg: m,
            occupant: LIBRARY_OCCUPANT,
        };
        let set = UncertainSet::new(&ego, &s, &u, &reference, cfg.reserve_m).unwrap();
        let rule = SwitchRule::new(&ego, &s, u.mass_kg, 0.040, err, &cfg).unwrap();
        let plan = set.two_level_optimum(&rule, &cfg).unwrap();
        assert!(
            plan.switch.level_n <= plan.settings.load_limiter_n,
            "{plan:?}"
        );
        for (pv, pm) in set_points(&s, &u) {
            let p = Pulse::predict(&ego, Opponent::Car { mass_kg: pm }, pv).unwrap();
            let pulse = p.ego();
            let r = simulate_occupant(&pulse, &LIBRARY_OCCUPANT, &reference, &hw).unwrap();
            let lost = speed_lost_by_mps(&pulse, rule.decide_s) * (1.0 - err);
            let o = if lost < rule.threshold_mps {
                simulate_occupant_switched(
                    &pulse,
                    &LIBRARY_OCCUPANT,
                    &plan.settings,
                    &plan.switch,
                    &hw,
                )
            } else {
                simulate_occupant(&pulse, &LIBRARY_OCCUPANT, &plan.settings, &hw)
            }
            .unwrap();
            assert!(
                !o.bottomed_out || r.bottomed_out,
                "{v}/{m}: point {pv} km/h {pm} kg bottoms out alone: {o:?}"
            );
            assert!(
                objective_g(&o) <= objective_g(&r),
                "{v}/{m}: point {pv} km/h {pm} kg worse than the reference: {} > {} g",
                objective_g(&o),
                objective_g(&r)
            );
        }
    }
}
