//! Characteristic diagram (restraint LUT): file format and allocation-free
//! multilinear interpolation.
//!
//! The paper's method optimises the adaptive restraint offline for every
//! pre-crash situation and stores the optima in a 4-D table; the ECU only
//! interpolates it in real time. This crate is that table:
//!
//! * [`Cell`] — what one grid point stores (optimal settings + predicted outcome).
//! * [`DiagramView`] — a borrowed, validated, `no_std` view with the
//!   allocation-free [`DiagramView::lookup`] used on the ECU cycle.
//! * `Diagram` (feature `std`) — the owned table, its constructors for the
//!   optimiser (`from_fn`, `from_cells`, `from_indexed_cells`) and the
//!   versioned, checksummed binary file format plus a JSON export/import.
//!
//! Axis order (row-major, the last axis varies fastest) is fixed:
//! closing speed, opponent mass, occupant mass, seat distance — see [`AxisId`].
#![cfg_attr(not(feature = "std"), no_std)]
#![forbid(unsafe_code)]
#![warn(missing_docs)]

use serde::{Deserialize, Serialize};

mod validate;
mod view;

#[cfg(feature = "std")]
mod data;
#[cfg(feature = "std")]
mod file;
#[cfg(feature = "std")]
mod owned;

pub use validate::{limits, Problem};
pub use view::{DiagramView, Lookup};

#[cfg(feature = "std")]
pub use data::{
    Axes, BuildInfo, DiagramData, EgoVehicle, GridPoint, Header, EXTRA_LIGHTER_OPPONENT_KG,
    NAN_FALLBACK_OCCUPANT_KG, NAN_FALLBACK_SEAT_MM,
};
#[cfg(feature = "std")]
pub use file::{
    frame, unframe, write_atomically, FileProblem, LoadError, FORMAT_VERSION, JSON_FORMAT_NAME,
    MAGIC, PREAMBLE_LEN,
};
#[cfg(feature = "std")]
pub use owned::{lut_id_of, Diagram};

/// Number of axes of the characteristic diagram.
pub const AXIS_COUNT: usize = 4;

/// Number of stored values per cell (the fields of [`Cell`]).
pub const CELL_FIELDS: usize = 9;

/// The four axes, in storage order (row-major: the last one varies fastest).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum AxisId {
    /// Car-to-car relative closing speed, km/h.
    ClosingSpeed = 0,
    /// Opponent vehicle mass, kg.
    OpponentMass = 1,
    /// Occupant mass, kg.
    OccupantMass = 2,
    /// Distance chest to steering wheel / airbag module, mm.
    SeatDistance = 3,
}

impl AxisId {
    /// All axes in storage order.
    pub const ALL: [AxisId; AXIS_COUNT] = [
        AxisId::ClosingSpeed,
        AxisId::OpponentMass,
        AxisId::OccupantMass,
        AxisId::SeatDistance,
    ];

    /// Field-style name with unit, used in error messages and JSON.
    pub const fn name(self) -> &'static str {
        match self {
            AxisId::ClosingSpeed => "closing_speed_kph",
            AxisId::OpponentMass => "opponent_mass_kg",
            AxisId::OccupantMass => "occupant_mass_kg",
            AxisId::SeatDistance => "seat_distance_mm",
        }
    }

    /// Position of this axis in storage order (0..4).
    pub const fn index(self) -> usize {
        self as usize
    }
}

impl core::fmt::Display for AxisId {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(self.name())
    }
}

/// One point of the 4-D input space (a lookup query, or a grid point).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Query {
    /// Car-to-car relative closing speed, km/h (both vehicles' speeds added).
    pub closing_speed_kph: f32,
    /// Opponent vehicle mass, kg.
    pub opponent_mass_kg: f32,
    /// Occupant mass, kg.
    pub occupant_mass_kg: f32,
    /// Distance chest to steering wheel / airbag module, mm.
    pub seat_distance_mm: f32,
}

impl Query {
    /// The query as an array in axis storage order.
    pub const fn to_array(self) -> [f32; AXIS_COUNT] {
        [
            self.closing_speed_kph,
            self.opponent_mass_kg,
            self.occupant_mass_kg,
            self.seat_distance_mm,
        ]
    }

    /// Build from an array in axis storage order.
    pub const fn from_array(a: [f32; AXIS_COUNT]) -> Self {
        Query {
            closing_speed_kph: a[0],
            opponent_mass_kg: a[1],
            occupant_mass_kg: a[2],
            seat_distance_mm: a[3],
        }
    }
}

/// What one grid point of the diagram stores: the optimal restraint settings
/// for that situation and the occupant outcome the optimiser predicted.
///
/// All fields are `f32`: ample for values known to a few per cent, and it
/// halves the table's cache footprint on the ECU.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Cell {
    /// Belt load-limiter level, kN (lumped shoulder + lap).
    pub belt_limiter_kn: f32,
    /// Airbag / steering-column force level, kN; 0 = do not fire.
    pub airbag_level_kn: f32,
    /// Pretensioner trigger time relative to contact, ms; negative = pre-crash.
    pub pretensioner_time_ms: f32,
    /// Airbag trigger time after contact, ms. Also meaningful for no-fire
    /// cells: the builder should store a plausible time there (e.g. the
    /// reference 10 ms) so that interpolation near a fire/no-fire border
    /// stays sensible.
    pub airbag_time_ms: f32,
    /// Predicted occupant peak acceleration, g.
    pub a_max_g: f32,
    /// Predicted occupant mean acceleration, g (definition: see physics crate).
    pub a_mean_g: f32,
    /// Predicted occupant forward excursion, mm.
    pub excursion_mm: f32,
    /// 1.0 if the optimum still bottoms out (no feasible solution), else 0.0.
    /// Stored as a float so the cell is a plain vector for interpolation; see
    /// [`Lookup::bottoming_out`] for how it is reported after interpolation.
    pub bottoming_out: f32,
    /// Ideal constant-force restraint lower bound a*, g.
    pub a_ideal_g: f32,
}

impl Cell {
    /// Field names with units, in [`Cell::to_array`] order.
    pub const FIELD_NAMES: [&'static str; CELL_FIELDS] = [
        "belt_limiter_kn",
        "airbag_level_kn",
        "pretensioner_time_ms",
        "airbag_time_ms",
        "a_max_g",
        "a_mean_g",
        "excursion_mm",
        "bottoming_out",
        "a_ideal_g",
    ];

    /// The cell as a plain vector (field order of [`Cell::FIELD_NAMES`]).
    pub const fn to_array(&self) -> [f32; CELL_FIELDS] {
        [
            self.belt_limiter_kn,
            self.airbag_level_kn,
            self.pretensioner_time_ms,
            self.airbag_time_ms,
            self.a_max_g,
            self.a_mean_g,
            self.excursion_mm,
            self.bottoming_out,
            self.a_ideal_g,
        ]
    }

    /// Inverse of [`Cell::to_array`].
    pub const fn from_array(a: [f32; CELL_FIELDS]) -> Self {
        Cell {
            belt_limiter_kn: a[0],
            airbag_level_kn: a[1],
            pretensioner_time_ms: a[2],
            airbag_time_ms: a[3],
            a_max_g: a[4],
            a_mean_g: a[5],
            excursion_mm: a[6],
            bottoming_out: a[7],
            a_ideal_g: a[8],
        }
    }

    /// `true` if this (grid) cell is flagged as bottoming out.
    pub fn is_bottoming_out(&self) -> bool {
        self.bottoming_out > 0.5
    }
}

/// One flag per axis, in storage order.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct AxisFlags(pub [bool; AXIS_COUNT]);

impl AxisFlags {
    /// `true` if any axis is flagged.
    pub fn any(&self) -> bool {
        self.0.iter().any(|&b| b)
    }

    /// The flag of one axis.
    pub fn get(&self, axis: AxisId) -> bool {
        // AxisId::index() < AXIS_COUNT by construction, `get` keeps it panic-free anyway.
        self.0.get(axis.index()).copied().unwrap_or(false)
    }
}

/// Discrete airbag decision, derived from the *interpolated* force level.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum AirbagStage {
    /// Do not fire (interpolated level below [`AirbagThresholds::no_fire_below_kn`]).
    NoFire,
    /// Fire the first inflator stage only.
    Stage1,
    /// Fire both stages (level ≥ [`AirbagThresholds::stage2_from_kn`]).
    Stage2,
}

/// Thresholds that turn the interpolated airbag force level into a discrete
/// stage. Stored in the file header so a table and its stage mapping travel
/// together.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct AirbagThresholds {
    /// Below this interpolated level, kN, the airbag is not fired. Non-zero
    /// because interpolating between a no-fire cell (0 kN) and a firing cell
    /// smears small levels that would make a useless, possibly harmful, deployment.
    pub no_fire_below_kn: f32,
    /// From this level on, kN, both inflator stages fire.
    pub stage2_from_kn: f32,
}

impl AirbagThresholds {
    /// *Default* thresholds: no fire below 1 kN (under ~10 % of the 12 kN
    /// range the bag adds little restraint), stage 2 from 6 kN (half range,
    /// a two-stage inflator split evenly).
    pub const DEFAULT: AirbagThresholds = AirbagThresholds {
        no_fire_below_kn: 1.0,
        stage2_from_kn: 6.0,
    };

    /// Map an interpolated airbag level, kN, to a stage. NaN → `Stage2`
    /// (cannot happen for validated tables; fail towards protection).
    pub fn stage(&self, level_kn: f32) -> AirbagStage {
        if level_kn < self.no_fire_below_kn {
            AirbagStage::NoFire
        } else if level_kn < self.stage2_from_kn {
            AirbagStage::Stage1
        } else {
            AirbagStage::Stage2
        }
    }
}

impl Default for AirbagThresholds {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// Row-major cell index of grid coordinates `idx` for axis lengths `lens`
/// (last axis fastest). `None` if a coordinate is out of range or the
/// product overflows.
pub fn cell_index(lens: [usize; AXIS_COUNT], idx: [usize; AXIS_COUNT]) -> Option<usize> {
    let mut flat = 0usize;
    for (&n, &i) in lens.iter().zip(idx.iter()) {
        if i >= n {
            return None;
        }
        flat = flat.checked_mul(n)?.checked_add(i)?;
    }
    Some(flat)
}

/// Inverse of [`cell_index`]: grid coordinates of row-major cell `index`.
/// `None` if `index` ≥ the product of `lens`.
pub fn cell_coords(lens: [usize; AXIS_COUNT], index: usize) -> Option<[usize; AXIS_COUNT]> {
    if index >= cell_count(lens)? {
        return None;
    }
    let mut rest = index;
    let mut out = [0usize; AXIS_COUNT];
    for (o, &n) in out.iter_mut().zip(lens.iter()).rev() {
        // n > 0 here: a zero length makes cell_count 0 and returns above.
        *o = rest.checked_rem(n)?;
        rest = rest.checked_div(n)?;
    }
    Some(out)
}

/// Product of the axis lengths; `None` on overflow.
pub fn cell_count(lens: [usize; AXIS_COUNT]) -> Option<usize> {
    lens.iter().try_fold(1usize, |acc, &n| acc.checked_mul(n))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn index_roundtrip_small_grid() {
        let lens = [3, 4, 2, 5];
        let mut expected = 0;
        for i in 0..3 {
            for j in 0..4 {
                for k in 0..2 {
                    for l in 0..5 {
                        assert_eq!(cell_index(lens, [i, j, k, l]), Some(expected));
                        assert_eq!(cell_coords(lens, expected), Some([i, j, k, l]));
                        expected += 1;
                    }
                }
            }
        }
        assert_eq!(cell_coords(lens, expected), None);
        assert_eq!(cell_index(lens, [3, 0, 0, 0]), None);
        assert_eq!(cell_index(lens, [0, 0, 0, 5]), None);
    }

    #[test]
    fn stage_thresholds() {
        let t = AirbagThresholds::DEFAULT;
        assert_eq!(t.stage(0.0), AirbagStage::NoFire);
        assert_eq!(t.stage(0.999), AirbagStage::NoFire);
        assert_eq!(t.stage(1.0), AirbagStage::Stage1);
        assert_eq!(t.stage(5.99), AirbagStage::Stage1);
        assert_eq!(t.stage(6.0), AirbagStage::Stage2);
        assert_eq!(t.stage(f32::NAN), AirbagStage::Stage2);
    }
}
