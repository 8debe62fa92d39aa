//! Published numbers of the paper, typed from SPEC.md (Table 5). These are the calibration
//! targets; nothing here is computed by this crate.

/// One row of Table 5 (vehicle results of the symmetric 1785 kg vs 1785 kg, 108 km/h case).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Table5Row {
    /// "1".."6" or "1-6" (all classes combined).
    pub class: &'static str,
    /// Vehicle crush s_veh [mm].
    pub crush_mm: f64,
    /// Peak vehicle deceleration a_max,veh [g].
    pub a_max_g: f64,
    /// Mean vehicle deceleration a_mean,veh [g].
    pub a_mean_g: f64,
}

/// Mass of both vehicles in the Table 5 study [kg] (Ford Taurus).
pub const TABLE5_MASS_KG: f64 = 1785.0;
/// Closing speed of the Table 5 study [km/h] (54 km/h each).
pub const TABLE5_CLOSING_KPH: f64 = 108.0;
/// Occupant mass of the Table 5 study [kg].
pub const TABLE5_OCCUPANT_KG: f64 = 75.0;

/// Table 5, vehicle columns, as published. Index 0..=5 = class 1..=6, index 6 = combined.
pub const TABLE5: [Table5Row; 7] = [
    Table5Row {
        class: "1",
        crush_mm: 579.3,
        a_max_g: 40.06,
        a_mean_g: 21.59,
    },
    Table5Row {
        class: "2",
        crush_mm: 665.5,
        a_max_g: 33.64,
        a_mean_g: 19.88,
    },
    Table5Row {
        class: "3",
        crush_mm: 663.4,
        a_max_g: 34.50,
        a_mean_g: 19.85,
    },
    Table5Row {
        class: "4",
        crush_mm: 653.9,
        a_max_g: 39.24,
        a_mean_g: 20.00,
    },
    Table5Row {
        class: "5",
        crush_mm: 677.7,
        a_max_g: 38.25,
        a_mean_g: 19.56,
    },
    Table5Row {
        class: "6",
        crush_mm: 649.9,
        a_max_g: 44.74,
        a_mean_g: 20.22,
    },
    Table5Row {
        class: "1-6",
        crush_mm: 662.0,
        a_max_g: 37.64,
        a_mean_g: 19.89,
    },
];

/// Calibration tolerances the constructed curves must meet (relative): crush ±8 %, peak ±15 %, mean ±10 %.
pub const TOLERANCE_CRUSH: f64 = 0.08;
/// Peak deceleration tolerance (relative).
pub const TOLERANCE_A_MAX: f64 = 0.15;
/// Mean deceleration tolerance (relative).
pub const TOLERANCE_A_MEAN: f64 = 0.10;
