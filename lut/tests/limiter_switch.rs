//! Two-level load limiter study (lut::limiter_switch): the evidence is measured as physics says,
//! the rule keeps the high level where the truth is more severe, and the plan's guarantee holds
//! at every point of the set — judged by re-simulating each point here, not by the optimiser's
//! cost.

use lut::limiter_switch::{speed_lost_by_mps, SwitchRule};
use lut::robust_cells::{set_points, Situation, UncertainSet, Uncertainty};
use lut::scenario::{Ego, Opponent, Pulse};
use lut::table::Grid;
use physics::reference::ReferenceRestraint;
use physics::{
    mps2_to_g, simulate_occupant, simulate_occupant_switched, CompartmentPulse, OccupantInput,
    OccupantOutcome, RestraintHardware,
};
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
    let cfg = Grid::load(repo("data/default-grid.toml"))
        .unwrap()
        .optimiser;
    let ego = Ego::default();
    for (v, m) in [(96.0, 1785.0), (104.0, 1785.0), (96.0, 1300.0)] {
        let s = Situation {
            closing_kph: v,
            opponent_kg: m,
            occupant: occupant(),
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

fn objective_g(o: &OccupantOutcome) -> f64 {
    mps2_to_g(o.max_decel_mps2) + mps2_to_g(o.mean_decel_mps2)
}

/// At every point of the set the two-level plan (with the switch the rule gives on that
/// point's true pulse, the measurement read low as configured) is no worse than the reference
/// restraint and does not bottom out where it does not.
#[test]
fn a_two_level_plan_keeps_its_guarantee_over_the_whole_set() {
    let reference = ReferenceRestraint::load(repo("data/reference-restraint.toml"))
        .unwrap()
        .settings();
    let cfg = Grid::load(repo("data/default-grid.toml"))
        .unwrap()
        .optimiser;
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
            occupant: occupant(),
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
            let r = simulate_occupant(&pulse, &occupant(), &reference, &hw).unwrap();
            let lost = speed_lost_by_mps(&pulse, rule.decide_s) * (1.0 - err);
            let o = if lost < rule.threshold_mps {
                simulate_occupant_switched(&pulse, &occupant(), &plan.settings, &plan.switch, &hw)
            } else {
                simulate_occupant(&pulse, &occupant(), &plan.settings, &hw)
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
