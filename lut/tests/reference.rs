//! The shipped reference restraint (data/reference-restraint.toml) against its two FMVSS 208
//! load cases, re-simulated with the physics crate.

use lut::reference::{ReferenceRestraint, FMVSS208_CASES};
use lut::scenario::{Ego, Opponent, Pulse};
use physics::{simulate_occupant, OccupantInput, RestraintHardware};

#[test]
fn shipped_reference_fires_at_10_ms_and_holds_the_belted_fmvss_case() {
    let r = ReferenceRestraint::load(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../data/reference-restraint.toml"
    ))
    .unwrap();
    assert_eq!(r, ReferenceRestraint::builtin().unwrap());
    assert_eq!(
        r.restraint.airbag_time_ms, 10.0,
        "SPEC: reference fire time 10 ms"
    );
    let hw = RestraintHardware::default();
    for (case, stored) in FMVSS208_CASES.iter().zip(&r.case) {
        assert_eq!(case.name, stored.name);
        let p = Pulse::predict(&Ego::default(), Opponent::Barrier, case.barrier_kph).unwrap();
        let occ = OccupantInput {
            mass_kg: case.occupant_kg,
            chest_to_wheel_m: stored.seat_distance_mm * 1e-3,
            belted: case.belted,
        };
        let o = simulate_occupant(&p.ego(), &occ, &r.settings(), &hw).unwrap();
        // The file reports what the physics gives (nothing hidden) ...
        assert_eq!(o.bottomed_out, stored.bottoming_out, "{}", case.name);
        // ... and the belted 56 km/h case is held without bottoming out.
        if case.belted {
            assert!(!o.bottomed_out, "{}: reference bottoms out", case.name);
        }
    }
}
