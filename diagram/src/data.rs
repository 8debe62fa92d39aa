//! The diagram's plain data (feature `std`): header, axes and cells as a file stores them,
//! not yet validated. A leaf module: the file format (`file.rs`) and the validated
//! [`crate::Diagram`] (`owned.rs`) both build on it, and neither on the other's types.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::validate::check_axes;
use crate::{
    cell_coords, cell_count, cell_index, AirbagThresholds, Cell, Problem, Query, AXIS_COUNT,
};

/// The ego vehicle the table was optimised for (its crash pulse is part of
/// every cell, so a table is only valid for this vehicle).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EgoVehicle {
    /// Ego vehicle mass, kg (*default* 1785 kg).
    pub mass_kg: f32,
    /// Stiffness / mass class 1..=6 (*default* 4).
    pub class: u8,
    /// Free text, e.g. "default mid-size sedan (class 4)".
    pub description: String,
}

/// How the table was built, so a rebuild can be reproduced and a table can
/// be matched to the defaults it came from.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct BuildInfo {
    /// Optimiser RNG seed.
    pub optimiser_seed: u64,
    /// Coefficient of restitution of the crash model.
    pub restitution: f32,
    /// Hash of the defaults / data files the build used (free-form, e.g. hex).
    pub defaults_hash: String,
    /// Anything else (tool version, command line, grid file, ...). A
    /// `BTreeMap` so that the encoding is deterministic.
    pub extra: BTreeMap<String, String>,
}

/// File header (everything but the format envelope, axes and cells).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Header {
    /// The ego vehicle the table belongs to.
    pub ego: EgoVehicle,
    /// Build parameters.
    pub build: BuildInfo,
    /// Mapping of the interpolated airbag level to a stage.
    pub airbag_thresholds: AirbagThresholds,
}

/// Header key (`build.extra`) of the planning margin a table's cells hold: a setting planned
/// for opponent mass M does not bottom the occupant out where the reference restraint does not
/// (nor deeper where both do) at any opponent from M − this [kg] to M. Written by `lut build`
/// (`[robust]`), checked by `lut verify`, and the ECU refuses a configuration whose planning
/// margins need more.
pub const EXTRA_LIGHTER_OPPONENT_KG: &str = "robust.lighter_opponent_kg";

impl Header {
    /// The span the table states for its planning margin ([`EXTRA_LIGHTER_OPPONENT_KG`]),
    /// `None` when it states none.
    ///
    /// # Errors
    /// The key is there but not a finite mass ≥ 0 kg.
    pub fn lighter_opponent_span_kg(&self) -> Result<Option<f64>, String> {
        match self.build.extra.get(EXTRA_LIGHTER_OPPONENT_KG) {
            None => Ok(None),
            Some(v) => match v.parse::<f64>() {
                Ok(x) if x.is_finite() && x >= 0.0 => Ok(Some(x)),
                _ => Err(format!(
                    "table header: {EXTRA_LIGHTER_OPPONENT_KG} = {v:?} is not a mass ≥ 0 kg"
                )),
            },
        }
    }
}

/// The four axes (each strictly increasing) plus the NaN fallback point.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Axes {
    /// Car-to-car closing speed grid, km/h.
    pub closing_speed_kph: Vec<f32>,
    /// Opponent mass grid, kg.
    pub opponent_mass_kg: Vec<f32>,
    /// Occupant mass grid, kg.
    pub occupant_mass_kg: Vec<f32>,
    /// Seat distance (chest to wheel) grid, mm.
    pub seat_distance_mm: Vec<f32>,
    /// Point used for an axis whose lookup input is NaN. Must lie inside each axis.
    pub nan_fallback: Query,
}

/// *Default* NaN fallback of the occupant-mass axis, kg: the 50th-percentile
/// male of the FMVSS 208 reference load cases.
pub const NAN_FALLBACK_OCCUPANT_KG: f32 = 75.0;
/// *Default* NaN fallback of the seat-distance axis, mm (SPEC default D).
pub const NAN_FALLBACK_SEAT_MM: f32 = 300.0;

impl Axes {
    /// Axes with the *default* NaN fallback: the most severe end of the two
    /// crash axes (highest closing speed and opponent mass: fail towards
    /// firing / strong restraint) and the reference occupant (75 kg, 300 mm,
    /// clamped into the axes).
    pub fn new(
        closing_speed_kph: Vec<f32>,
        opponent_mass_kg: Vec<f32>,
        occupant_mass_kg: Vec<f32>,
        seat_distance_mm: Vec<f32>,
    ) -> Self {
        fn last(v: &[f32]) -> f32 {
            v.last().copied().unwrap_or(f32::NAN)
        }
        fn clamp_into(v: &[f32], x: f32) -> f32 {
            match (v.first(), v.last()) {
                (Some(&lo), Some(&hi)) if lo <= hi => x.clamp(lo, hi),
                _ => f32::NAN,
            }
        }
        let nan_fallback = Query {
            closing_speed_kph: last(&closing_speed_kph),
            opponent_mass_kg: last(&opponent_mass_kg),
            occupant_mass_kg: clamp_into(&occupant_mass_kg, NAN_FALLBACK_OCCUPANT_KG),
            seat_distance_mm: clamp_into(&seat_distance_mm, NAN_FALLBACK_SEAT_MM),
        };
        Axes {
            closing_speed_kph,
            opponent_mass_kg,
            occupant_mass_kg,
            seat_distance_mm,
            nan_fallback,
        }
    }

    /// Axis points in storage order.
    pub fn as_slices(&self) -> [&[f32]; AXIS_COUNT] {
        [
            &self.closing_speed_kph,
            &self.opponent_mass_kg,
            &self.occupant_mass_kg,
            &self.seat_distance_mm,
        ]
    }

    /// Axis lengths in storage order.
    pub fn lens(&self) -> [usize; AXIS_COUNT] {
        self.as_slices().map(|a| a.len())
    }

    /// Number of grid cells (product of the lengths, saturating on overflow).
    pub fn cell_count(&self) -> usize {
        cell_count(self.lens()).unwrap_or(usize::MAX)
    }

    /// Row-major index of grid coordinates `[i, j, k, l]`.
    pub fn cell_index(&self, idx: [usize; AXIS_COUNT]) -> Option<usize> {
        cell_index(self.lens(), idx)
    }

    /// Grid coordinates of row-major cell `index`.
    pub fn cell_coords(&self, index: usize) -> Option<[usize; AXIS_COUNT]> {
        cell_coords(self.lens(), index)
    }

    /// The grid point (coordinates and axis values) of cell `index`.
    pub fn point(&self, index: usize) -> Option<GridPoint> {
        let coords = self.cell_coords(index)?;
        let s = self.as_slices();
        let mut values = [0.0f32; AXIS_COUNT];
        for ((v, axis), &i) in values.iter_mut().zip(s.iter()).zip(coords.iter()) {
            *v = *axis.get(i)?;
        }
        Some(GridPoint {
            index,
            coords,
            query: Query::from_array(values),
        })
    }

    /// Validate the axes (see the README's validation rules).
    pub fn validate(&self) -> Result<(), Problem> {
        check_axes(self.as_slices(), &self.nan_fallback).map(|_| ())
    }
}

/// One grid point, as handed to the cell closure of [`crate::Diagram::from_fn`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GridPoint {
    /// Row-major cell index.
    pub index: usize,
    /// Grid coordinates `[i, j, k, l]` in axis storage order.
    pub coords: [usize; AXIS_COUNT],
    /// Axis values at this point.
    pub query: Query,
}

/// Plain, unvalidated diagram data: what the file stores. Turn it into a
/// [`crate::Diagram`] with [`crate::Diagram::new`] (validates).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DiagramData {
    /// Header.
    pub header: Header,
    /// Axes.
    pub axes: Axes,
    /// Cells, row-major over the axes (last axis fastest).
    pub cells: Vec<Cell>,
}
