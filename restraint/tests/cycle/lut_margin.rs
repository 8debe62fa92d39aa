//! The planning margin a table states (`robust.lighter_opponent_kg`, `lut::margin`) against the
//! configured margins: a table verified for less than the configuration's plans need is
//! rejected at start-up like a table of another car — the ECU runs DEGRADED on the reference
//! restraint and says why — and a table that states nothing is taken as before.

use crate::cycle_support::*;
use diagram::{Diagram, EXTRA_LIGHTER_OPPONENT_KG};
use restraint::{CycleConfig, LutMismatch, RestraintCycle};

fn stating(span: &str) -> Diagram {
    let mut data = test_lut().into_data();
    data.header
        .build
        .extra
        .insert(EXTRA_LIGHTER_OPPONENT_KG.into(), span.into());
    Diagram::new(data).unwrap()
}

fn notes(cfg: CycleConfig, d: &Diagram) -> Option<LutMismatch> {
    RestraintCycle::new(cfg, Some(lut_of(d)), &REFERENCE)
        .expect("valid config")
        .1
        .lut_rejected
}

fn margins(misreport_kg: f64, v2x_kg: f64) -> CycleConfig {
    CycleConfig {
        mass_misreport_kg: misreport_kg,
        v2x_mass_margin_kg: v2x_kg,
        ..ideal_sensor_config()
    }
}

#[test]
fn a_table_verified_for_the_configured_margins_is_taken() {
    // Default margins: 2 × 1 200 = 2 400 and 1 200 + 300 = 1 500 → 2 400 needed.
    assert_eq!(notes(ideal_sensor_config(), &stating("2400")), None);
    assert_eq!(notes(margins(600.0, 300.0), &stating("1200")), None);
    // A table that states nothing makes no claim and is taken with any margins.
    assert_eq!(notes(margins(5000.0, 300.0), &test_lut()), None);
}

#[test]
fn a_table_verified_for_less_than_the_margins_need_is_rejected_and_says_why() {
    for (cfg, span, needed) in [
        (margins(1500.0, 300.0), "2400", 3000.0),
        // The V2X rule needs more than twice the misreport bound here.
        (margins(600.0, 1300.0), "1500", 1900.0),
        (ideal_sensor_config(), "2000", 2400.0),
    ] {
        let m = notes(cfg, &stating(span)).expect("rejected");
        let LutMismatch::Margin {
            lighter_opponent_kg,
            needed_kg,
        } = m
        else {
            panic!("{m:?}")
        };
        assert_eq!(f64::from(lighter_opponent_kg), span.parse::<f64>().unwrap());
        assert_eq!(needed_kg, needed);
        let text = m.to_string();
        assert!(
            text.contains("robust.lighter_opponent_kg") && text.contains("DEGRADED"),
            "{text}"
        );
    }
    // A span the shell could not read covers nothing.
    let d = stating("2400");
    let mut l = lut_of(&d);
    l.lighter_opponent_kg = Some(f32::NAN);
    let (_, n) = RestraintCycle::new(ideal_sensor_config(), Some(l), &REFERENCE).unwrap();
    assert!(matches!(n.lut_rejected, Some(LutMismatch::Margin { .. })));
    let bad = stating("heavy");
    assert!(lut_of(&bad).lighter_opponent_kg.is_some_and(f32::is_nan));
}

#[test]
fn a_rejected_table_runs_degraded_on_the_reference_restraint() {
    let mut b = Bench::with_config(margins(1500.0, 300.0), Some(stating("2400")));
    idle_until(&mut b, T0 + 200 * MS);
    let d = b.diagnostics.last().expect("diagnostics");
    assert_eq!(d.mode, restraint::EcuMode::Degraded as u8);
    assert_ne!(
        d.degraded_reasons & restraint::Degraded::LUT_INVALID.bits(),
        0
    );
    assert!(b
        .status_frames()
        .iter()
        .all(|(_, s)| s.fault_lut() && s.lut_id() == 0));
    // The same table with the default margins is taken.
    let mut ok = Bench::with_config(ideal_sensor_config(), Some(stating("2400")));
    idle_until(&mut ok, T0 + 200 * MS);
    let d = ok.diagnostics.last().expect("diagnostics");
    assert_eq!(
        d.degraded_reasons & restraint::Degraded::LUT_INVALID.bits(),
        0
    );
}
