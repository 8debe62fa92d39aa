//! Runs N lookups (N from argv, default 1_000_000) over a 4536-cell table so
//! that `valgrind --tool=callgrind` / `perf stat -e instructions` can give a
//! deterministic instructions-per-lookup figure: run with two N and divide
//! the difference (see README).

use std::hint::black_box;

use diagram::{AirbagThresholds, Axes, BuildInfo, Cell, Diagram, EgoVehicle, Header, Query};

fn main() {
    let n: usize = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(1_000_000);
    let header = Header {
        ego: EgoVehicle {
            mass_kg: 1785.0,
            class: 4,
            description: "icount".into(),
        },
        build: BuildInfo::default(),
        airbag_thresholds: AirbagThresholds::DEFAULT,
    };
    let axes = Axes::new(
        vec![40.0, 48.0, 56.0, 64.0, 72.0, 80.0, 90.0, 100.0, 108.0],
        (0..12).map(|i| 800.0 + 200.0 * i as f32).collect(),
        vec![30.0, 45.0, 60.0, 75.0, 90.0, 105.0, 125.0],
        vec![200.0, 250.0, 300.0, 350.0, 400.0, 450.0],
    );
    let d = Diagram::from_fn(header, axes, |p| Cell {
        a_max_g: p.query.closing_speed_kph / 3.0,
        belt_limiter_kn: 4.0,
        ..Cell::default()
    })
    .expect("valid table");
    let view = d.view();
    let mut sum = 0.0f32;
    for i in 0..n {
        let f = (i % 1000) as f32 / 1000.0;
        let q = Query {
            closing_speed_kph: 35.0 + 80.0 * f,
            opponent_mass_kg: 700.0 + 2400.0 * (1.0 - f),
            occupant_mass_kg: 25.0 + 105.0 * f,
            seat_distance_mm: 190.0 + 270.0 * f,
        };
        sum += view.lookup(black_box(&q)).values.a_max_g;
    }
    println!("{n} lookups, checksum {sum}");
}
