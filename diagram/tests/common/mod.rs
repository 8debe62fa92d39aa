//! Shared helpers for the diagram integration tests.
#![allow(dead_code)]

use diagram::{AirbagThresholds, Axes, BuildInfo, Cell, Diagram, EgoVehicle, GridPoint, Header};

/// The documented default ego vehicle (1785 kg, class 4).
pub fn header() -> Header {
    Header {
        ego: EgoVehicle {
            mass_kg: 1785.0,
            class: 4,
            description: "test ego".into(),
        },
        build: BuildInfo {
            optimiser_seed: 42,
            restitution: 0.1,
            defaults_hash: "deadbeef".into(),
            extra: [("grid".to_string(), "test".to_string())]
                .into_iter()
                .collect(),
        },
        airbag_thresholds: AirbagThresholds::DEFAULT,
    }
}

/// A small, non-uniform grid over the paper's ranges.
pub fn small_axes() -> Axes {
    Axes::new(
        vec![40.0, 60.0, 80.0, 108.0],
        vec![800.0, 1200.0, 1785.0, 2400.0, 3000.0],
        vec![30.0, 75.0, 125.0],
        vec![200.0, 300.0, 450.0],
    )
}

/// Deterministic pseudo-random value in [0, 1) from a cell index and field
/// (SplitMix64 finaliser): arbitrary, unstructured cell contents.
pub fn hash01(index: usize, field: usize, seed: u64) -> f32 {
    let mut z = (index as u64)
        .wrapping_mul(0x9E37_79B9_7F4A_7C15)
        .wrapping_add((field as u64) << 32)
        .wrapping_add(seed);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    (z >> 40) as f32 / (1u64 << 24) as f32
}

/// Arbitrary but plausible cell contents for grid point `p`.
pub fn random_cell(p: GridPoint, seed: u64) -> Cell {
    let h = |f| hash01(p.index, f, seed);
    Cell {
        belt_limiter_kn: 1.0 + 11.0 * h(0),
        airbag_level_kn: 12.0 * h(1),
        pretensioner_time_ms: -100.0 + 120.0 * h(2),
        airbag_time_ms: 3.0 + 37.0 * h(3),
        a_max_g: 10.0 + 50.0 * h(4),
        a_mean_g: 5.0 + 20.0 * h(5),
        excursion_mm: 50.0 + 300.0 * h(6),
        bottoming_out: if h(7) > 0.8 { 1.0 } else { 0.0 },
        a_ideal_g: 3.0 + 15.0 * h(8),
    }
}

pub fn random_diagram(axes: Axes, seed: u64) -> Diagram {
    Diagram::from_fn(header(), axes, |p| random_cell(p, seed)).expect("valid test diagram")
}
