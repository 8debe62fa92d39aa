//! The second opponent-mass source (V2X `V2xOpponentMass`): which mass the plan is for.
//!
//! The standard approach of `scenarios.rs` (90 km/h closing, contact at C, the object list
//! reporting 1 500 kg, σ 100 kg) with a V2X station every 100 ms. The test LUT is linear in
//! the opponent mass, so the pre-crash belt level names the planning mass exactly
//! (`belt_kn(90 km/h, m)`): without a usable station the reported mass + 1 200 kg
//! (`mass_misreport_kg`), with one the heavier of the two sources + 300 kg
//! (`v2x_mass_margin_kg`).

use crate::cycle_support::*;
use bus::codec::{BeltLimiterCmdPretensionerCmd, V2xOpponentMassStationStatus};
use bus::V2xOpponentMass;

/// Contact of the approach.
const C: u64 = T0 + 1_000 * MS;
/// Closing speed, m/s (90 km/h).
const V: f32 = 25.0;
/// The object list's opponent mass, kg.
const REPORTED_KG: f64 = 1500.0;

/// What the V2X station sends in a run.
#[derive(Clone, Copy)]
struct Station {
    status: V2xOpponentMassStationStatus,
    mass_kg: f32,
    /// Added to the true range, m (another station at another place).
    range_offset_m: f32,
    /// Added to the true closing speed, m/s.
    closing_offset_mps: f32,
    /// Frames stop at this time (a receiver that went silent).
    until_ns: u64,
    /// Every frame's CRC byte is flipped (E2E rejects it).
    corrupt: bool,
}

impl Station {
    fn true_one(mass_kg: f32) -> Self {
        Self {
            status: V2xOpponentMassStationStatus::Valid,
            mass_kg,
            range_offset_m: 0.0,
            closing_offset_mps: 0.0,
            until_ns: u64::MAX,
            corrupt: false,
        }
    }
}

/// Runs the approach to just before contact with `station` (or none) and returns the belt
/// level of the first pretensioner command (the pre-crash plan), kN, and the number of lookups
/// planned with V2X.
fn preset_belt_kn(station: Option<Station>) -> (f32, u64) {
    let mut b = Bench::oracle(Some(test_lut()));
    while b.now < C - 5 * MS {
        let ms = (b.now - T0) / MS;
        if let Some(s) = station.filter(|s| ms.is_multiple_of(100) && b.now < s.until_ns) {
            let range_m = ((C - b.now) as f64 * 1e-9 * f64::from(V)) as f32 + s.range_offset_m;
            let m = V2xOpponentMass::encode(
                s.status,
                s.mass_kg,
                100.0,
                range_m.clamp(0.0, 400.0),
                V + s.closing_offset_mps,
            )
            .expect("in range");
            let mut f = b.tx.seal(m);
            if s.corrupt {
                f.data[0] ^= 0xFF;
            }
            b.io.push_can(f);
        }
        if ms.is_multiple_of(10) && b.now >= T0 + 200 * MS {
            b.push_approach(C, V, REPORTED_KG as f32, 100.0);
        }
        b.step();
    }
    let belts = b.belt_frames();
    let (_, f) = belts
        .iter()
        .find(|(_, f)| f.pretensioner_cmd() == BeltLimiterCmdPretensionerCmd::Fire)
        .expect("pretensioner fired before contact");
    (f.load_limiter_level(), b.counter("v2x_lookups"))
}

/// The belt level the test LUT gives at 90 km/h for `planning_kg`, as the DBC carries it.
fn level_for(planning_kg: f64) -> f32 {
    q(belt_kn(90.0, planning_kg), 0.05)
}

/// `with_v2x`: whether any lookup of the run used the station (`None`: not asked).
fn assert_plans_for(station: Option<Station>, planning_kg: f64, with_v2x: Option<bool>) {
    let (kn, v2x_lookups) = preset_belt_kn(station);
    assert!(
        (kn - level_for(planning_kg)).abs() < 1e-4,
        "belt {kn} kN, expected the plan for {planning_kg} kg ({} kN)",
        level_for(planning_kg)
    );
    if let Some(w) = with_v2x {
        assert_eq!(v2x_lookups > 0, w, "{v2x_lookups} lookups with V2X");
    }
}

#[test]
fn without_v2x_the_plan_holds_an_opponent_1200_kg_heavier() {
    assert_plans_for(None, REPORTED_KG + 1200.0, Some(false));
}

#[test]
fn an_agreeing_station_lowers_the_margin_to_300_kg() {
    assert_plans_for(
        Some(Station::true_one(1500.0)),
        REPORTED_KG + 300.0,
        Some(true),
    );
}

#[test]
fn a_heavier_station_wins_over_a_light_object_list() {
    // The object list reads 1 000 kg light (its single fault): the station's true 2 500 kg
    // holds the plan.
    assert_plans_for(Some(Station::true_one(2500.0)), 2500.0 + 300.0, Some(true));
}

#[test]
fn a_light_station_cannot_lower_the_plan_below_the_object_list() {
    // A forged or faulty station reporting 800 kg: the object list's 1 500 kg holds.
    assert_plans_for(
        Some(Station::true_one(800.0)),
        REPORTED_KG + 300.0,
        Some(true),
    );
}

#[test]
fn a_station_elsewhere_or_at_another_speed_is_not_the_tracked_object() {
    let far = Station {
        range_offset_m: 20.0,
        ..Station::true_one(1500.0)
    };
    assert_plans_for(Some(far), REPORTED_KG + 1200.0, Some(false));
    let faster = Station {
        closing_offset_mps: 5.0,
        ..Station::true_one(1500.0)
    };
    assert_plans_for(Some(faster), REPORTED_KG + 1200.0, Some(false));
    // Inside the gates (8 m, 3 m/s): the same object.
    let near = Station {
        range_offset_m: 5.0,
        closing_offset_mps: 2.0,
        ..Station::true_one(1500.0)
    };
    assert_plans_for(Some(near), REPORTED_KG + 300.0, Some(true));
}

#[test]
fn a_silent_corrupt_or_empty_station_leaves_the_1200_kg_margin() {
    // Frames stop 700 ms before contact: stale (300 ms) long before the plan is made.
    let silent = Station {
        until_ns: C - 700 * MS,
        ..Station::true_one(1500.0)
    };
    // (Its first frames planned the first lookups: the counter says so; the preset is later.)
    assert_plans_for(Some(silent), REPORTED_KG + 1200.0, Some(true));
    let corrupt = Station {
        corrupt: true,
        ..Station::true_one(1500.0)
    };
    assert_plans_for(Some(corrupt), REPORTED_KG + 1200.0, Some(false));
    let none = Station {
        status: V2xOpponentMassStationStatus::NoStation,
        ..Station::true_one(1500.0)
    };
    assert_plans_for(Some(none), REPORTED_KG + 1200.0, Some(false));
}
