//! Property tests of the multilinear interpolation against independent oracles.

mod common;

use common::{header, random_cell, random_diagram, small_axes};
use diagram::{AirbagStage, Axes, AxisId, Cell, Diagram, Query, AXIS_COUNT, CELL_FIELDS};
use proptest::prelude::*;

/// Strictly increasing axis: start + cumulative positive steps.
fn axis(start: (f32, f32), step: (f32, f32)) -> impl Strategy<Value = Vec<f32>> {
    (
        start.0..start.1,
        prop::collection::vec(step.0..step.1, 1..5),
    )
        .prop_map(|(s, steps)| {
            let mut v = vec![s];
            for d in steps {
                let next = v[v.len() - 1] + d;
                v.push(next);
            }
            v
        })
}

fn axes_strategy() -> impl Strategy<Value = Axes> {
    (
        axis((0.0, 50.0), (1.0, 40.0)),
        axis((500.0, 1500.0), (50.0, 600.0)),
        axis((20.0, 60.0), (5.0, 30.0)),
        axis((100.0, 250.0), (10.0, 80.0)),
    )
        .prop_map(|(a, b, c, d)| Axes::new(a, b, c, d))
}

/// A point inside the axes from fractions in [0, 1].
fn inside(axes: &Axes, frac: [f64; AXIS_COUNT]) -> Query {
    let s = axes.as_slices();
    let mut q = [0.0f32; AXIS_COUNT];
    for a in 0..AXIS_COUNT {
        let lo = s[a][0] as f64;
        let hi = *s[a].last().unwrap() as f64;
        q[a] = ((lo + frac[a] * (hi - lo)) as f32).clamp(lo as f32, hi as f32);
    }
    Query::from_array(q)
}

/// Normalised coordinate, affine in x, so multilinear functions of it stay multilinear.
fn unit(axes: &Axes, q: &Query) -> [f64; AXIS_COUNT] {
    let s = axes.as_slices();
    let x = q.to_array();
    let mut u = [0.0; AXIS_COUNT];
    for a in 0..AXIS_COUNT {
        let lo = s[a][0] as f64;
        let hi = *s[a].last().unwrap() as f64;
        u[a] = (x[a] as f64 - lo) / (hi - lo);
    }
    u
}

/// A multilinear function (degree ≤ 1 in each coordinate): multilinear
/// interpolation must reproduce it everywhere, not only at grid points.
fn multilinear(u: [f64; AXIS_COUNT]) -> f64 {
    u[0] * u[1] + 0.5 * u[2] * (1.0 - u[3]) + u[0] * u[1] * u[2] * u[3] + 0.3 * u[3]
}

fn oracle_cell(g: f64) -> [f64; CELL_FIELDS] {
    [
        1.0 + 3.0 * g,
        3.0 * g,
        -50.0 + 20.0 * g,
        5.0 + 10.0 * g,
        10.0 + 10.0 * g,
        5.0 + 5.0 * g,
        100.0 + 50.0 * g,
        0.0,
        2.0 + 3.0 * g,
    ]
}

fn to_cell(v: [f64; CELL_FIELDS]) -> Cell {
    Cell::from_array(v.map(|x| x as f32))
}

/// Index of the grid interval containing x (independent linear scan).
fn enclosing(axis: &[f32], x: f32) -> usize {
    let mut i = 0;
    while i + 2 < axis.len() && axis[i + 1] <= x {
        i += 1;
    }
    i
}

fn all_finite(c: &Cell) -> bool {
    c.to_array().iter().all(|v| v.is_finite())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn reproduces_multilinear_functions(axes in axes_strategy(),
                                        frac in prop::array::uniform4(0.0f64..=1.0)) {
        let ax = axes.clone();
        let d = Diagram::from_fn(header(), axes, |p| to_cell(oracle_cell(multilinear(unit(&ax, &p.query))))).unwrap();
        let q = inside(d.axes(), frac);
        let got = d.view().lookup(&q);
        let want = oracle_cell(multilinear(unit(d.axes(), &q)));
        for (f, (g, w)) in got.values.to_array().iter().zip(want.iter()).enumerate() {
            let tol = 1e-4 * (1.0 + w.abs());
            prop_assert!((*g as f64 - w).abs() <= tol, "field {} got {} want {}", Cell::FIELD_NAMES[f], g, w);
        }
        prop_assert!(!got.out_of_range.any());
    }

    #[test]
    fn exact_at_grid_points(axes in axes_strategy(), seed in any::<u64>()) {
        let d = random_diagram(axes, seed);
        let v = d.view();
        for index in 0..d.axes().cell_count() {
            let p = d.axes().point(index).unwrap();
            let got = v.lookup(&p.query);
            // Bitwise equality with the stored cell.
            prop_assert_eq!(got.values.to_array().map(f32::to_bits), d.cells()[index].to_array().map(f32::to_bits));
            prop_assert_eq!(got.bottoming_out, d.cells()[index].bottoming_out == 1.0);
            prop_assert!(!got.out_of_range.any());
        }
    }

    #[test]
    fn bounded_by_the_surrounding_corners(axes in axes_strategy(), seed in any::<u64>(),
                                          frac in prop::array::uniform4(0.0f64..=1.0)) {
        let d = random_diagram(axes, seed);
        let q = inside(d.axes(), frac);
        let got = d.view().lookup(&q).values.to_array();
        let s = d.axes().as_slices();
        let x = q.to_array();
        let lower: Vec<usize> = (0..AXIS_COUNT).map(|a| enclosing(s[a], x[a])).collect();
        let mut lo = [f32::INFINITY; CELL_FIELDS];
        let mut hi = [f32::NEG_INFINITY; CELL_FIELDS];
        for corner in 0..16 {
            let idx = [0, 1, 2, 3].map(|a| lower[a] + ((corner >> (3 - a)) & 1));
            let c = d.cells()[d.axes().cell_index(idx).unwrap()].to_array();
            for f in 0..CELL_FIELDS {
                lo[f] = lo[f].min(c[f]);
                hi[f] = hi[f].max(c[f]);
            }
        }
        for f in 0..CELL_FIELDS {
            let tol = 1e-5 * (1.0 + lo[f].abs().max(hi[f].abs()));
            prop_assert!(got[f] >= lo[f] - tol && got[f] <= hi[f] + tol,
                "{} = {} outside corners {}..{}", Cell::FIELD_NAMES[f], got[f], lo[f], hi[f]);
        }
    }

    #[test]
    fn continuous(axes in axes_strategy(), seed in any::<u64>(),
                  frac in prop::array::uniform4(0.0f64..=1.0), axis_i in 0usize..4, step in -1e-3f64..1e-3) {
        let d = random_diagram(axes, seed);
        let v = d.view();
        let q0 = inside(d.axes(), frac);
        let mut f1 = frac;
        f1[axis_i] = (f1[axis_i] + step).clamp(0.0, 1.0);
        let q1 = inside(d.axes(), f1);
        let a = v.lookup(&q0).values.to_array();
        let b = v.lookup(&q1).values.to_array();
        let s = d.axes().as_slices()[axis_i];
        let min_spacing = s.windows(2).map(|w| w[1] - w[0]).fold(f32::INFINITY, f32::min) as f64;
        let dx = (q1.to_array()[axis_i] - q0.to_array()[axis_i]).abs() as f64;
        for f in 0..CELL_FIELDS {
            let col: Vec<f32> = d.cells().iter().map(|c| c.to_array()[f]).collect();
            let range = col.iter().cloned().fold(f32::NEG_INFINITY, f32::max) as f64
                - col.iter().cloned().fold(f32::INFINITY, f32::min) as f64;
            // Lipschitz bound of a multilinear interpolant along one axis.
            let bound = range * dx / min_spacing + 1e-4 * (1.0 + range);
            prop_assert!(((a[f] - b[f]) as f64).abs() <= bound,
                "{}: jump {} over dx {} (bound {})", Cell::FIELD_NAMES[f], a[f] - b[f], dx, bound);
        }
    }

    #[test]
    fn clamps_and_flags_out_of_range(seed in any::<u64>(), frac in prop::array::uniform4(0.0f64..=1.0),
                                      side in prop::array::uniform4(0u8..3), excess in 0.001f32..1000.0) {
        let d = random_diagram(small_axes(), seed);
        let v = d.view();
        let inner = inside(d.axes(), frac).to_array();
        let s = d.axes().as_slices();
        let mut q = inner;
        let mut clamped = inner;
        for a in 0..AXIS_COUNT {
            let lo = s[a][0];
            let hi = *s[a].last().unwrap();
            match side[a] {
                1 => { q[a] = lo - excess; clamped[a] = lo; }
                2 => { q[a] = hi + excess; clamped[a] = hi; }
                _ => {}
            }
        }
        let got = v.lookup(&Query::from_array(q));
        let want = v.lookup(&Query::from_array(clamped));
        prop_assert_eq!(got.values, want.values);
        prop_assert_eq!(got.out_of_range.0, side.map(|s| s != 0));
        prop_assert!(!got.nan_input.any());
        prop_assert_eq!(got.used.to_array(), clamped);
    }

    #[test]
    fn nan_and_inf_never_panic_nor_leak(seed in any::<u64>(), kind in prop::array::uniform4(0u8..6),
                                         frac in prop::array::uniform4(0.0f64..=1.0)) {
        let d = random_diagram(small_axes(), seed);
        let v = d.view();
        let inner = inside(d.axes(), frac).to_array();
        let fb = d.axes().nan_fallback.to_array();
        let mut q = inner;
        let mut expect_used = inner;
        let s = d.axes().as_slices();
        for a in 0..AXIS_COUNT {
            match kind[a] {
                0 => { q[a] = f32::NAN; expect_used[a] = fb[a]; }
                1 => { q[a] = f32::INFINITY; expect_used[a] = *s[a].last().unwrap(); }
                2 => { q[a] = f32::NEG_INFINITY; expect_used[a] = s[a][0]; }
                3 => { q[a] = f32::MAX; expect_used[a] = *s[a].last().unwrap(); }
                4 => { q[a] = -f32::MAX; expect_used[a] = s[a][0]; }
                _ => {}
            }
        }
        let got = v.lookup(&Query::from_array(q));
        prop_assert!(all_finite(&got.values));
        prop_assert_eq!(got.nan_input.0, kind.map(|k| k == 0));
        prop_assert_eq!(got.out_of_range.0, kind.map(|k| k < 5));
        prop_assert_eq!(got.used.to_array(), expect_used);
        prop_assert_eq!(got.values, v.lookup(&Query::from_array(expect_used)).values);
    }
}

#[test]
fn default_nan_fallback_is_most_severe_crash_and_reference_occupant() {
    let axes = small_axes();
    let fb = axes.nan_fallback;
    assert_eq!(fb.closing_speed_kph, 108.0);
    assert_eq!(fb.opponent_mass_kg, 3000.0);
    assert_eq!(fb.occupant_mass_kg, 75.0);
    assert_eq!(fb.seat_distance_mm, 300.0);
    // Clamped into axes that do not contain the reference values.
    let narrow = Axes::new(
        vec![20.0, 30.0],
        vec![900.0, 1000.0],
        vec![90.0, 100.0],
        vec![350.0, 400.0],
    );
    assert_eq!(narrow.nan_fallback.occupant_mass_kg, 90.0);
    assert_eq!(narrow.nan_fallback.seat_distance_mm, 350.0);
}

/// Closed form on a 2×2×2×2 grid: the value at a point is the product of the
/// per-axis linear weights times the corner values.
#[test]
fn hand_computed_midpoint() {
    let axes = Axes::new(
        vec![20.0, 60.0],
        vec![1000.0, 2000.0],
        vec![50.0, 100.0],
        vec![200.0, 400.0],
    );
    // Only corner (1,1,1,1) has a_max 16 g, the rest 0.
    let d = Diagram::from_fn(header(), axes, |p| Cell {
        a_max_g: if p.coords == [1, 1, 1, 1] { 16.0 } else { 0.0 },
        ..Cell::default()
    })
    .unwrap();
    let q = Query {
        closing_speed_kph: 30.0,
        opponent_mass_kg: 1500.0,
        occupant_mass_kg: 75.0,
        seat_distance_mm: 350.0,
    };
    // weights 0.25 * 0.5 * 0.5 * 0.75 = 0.046875 → 0.75 g
    let got = d.lookup(&q).values.a_max_g;
    assert!((got - 0.75).abs() < 1e-6, "{got}");
}

#[test]
fn bottoming_out_reported_if_any_weighted_corner_has_it() {
    let axes = Axes::new(
        vec![20.0, 60.0, 100.0],
        vec![1000.0, 2000.0],
        vec![50.0, 100.0],
        vec![200.0, 400.0],
    );
    // Bottoming out only at the top speed 100 km/h.
    let d = Diagram::from_fn(header(), axes, |p| Cell {
        bottoming_out: if p.coords[0] == 2 { 1.0 } else { 0.0 },
        ..Cell::default()
    })
    .unwrap();
    let v = d.view();
    let at = |speed| {
        v.lookup(&Query {
            closing_speed_kph: speed,
            opponent_mass_kg: 1500.0,
            occupant_mass_kg: 75.0,
            seat_distance_mm: 300.0,
        })
    };
    assert!(!at(20.0).bottoming_out);
    assert!(!at(59.0).bottoming_out);
    // Exactly at 60 km/h the upper corner's weight is 0: feasible.
    assert!(!at(60.0).bottoming_out);
    let r = at(60.5);
    assert!(r.bottoming_out);
    assert!((r.values.bottoming_out - 0.0125).abs() < 1e-6);
    assert!(at(100.0).bottoming_out);
    assert!(at(500.0).bottoming_out);
}

#[test]
fn airbag_stage_is_derived_after_interpolation() {
    // Airbag level 0 kN at 20 km/h, 12 kN at 68 km/h: level = (v - 20) / 4 kN.
    let axes = Axes::new(
        vec![20.0, 68.0],
        vec![1000.0, 2000.0],
        vec![50.0, 100.0],
        vec![200.0, 400.0],
    );
    let d = Diagram::from_fn(header(), axes, |p| Cell {
        airbag_level_kn: if p.coords[0] == 1 { 12.0 } else { 0.0 },
        ..Cell::default()
    })
    .unwrap();
    let at = |speed: f32| {
        d.lookup(&Query {
            closing_speed_kph: speed,
            opponent_mass_kg: 1500.0,
            occupant_mass_kg: 75.0,
            seat_distance_mm: 300.0,
        })
    };
    // Default thresholds: no fire below 1 kN, stage 2 from 6 kN.
    assert_eq!(at(23.0).airbag_stage, AirbagStage::NoFire); // 0.75 kN
    assert_eq!(at(23.0).airbag_command_kn(), 0.0);
    assert_eq!(at(25.0).airbag_stage, AirbagStage::Stage1); // 1.25 kN
    assert!((at(25.0).airbag_command_kn() - 1.25).abs() < 1e-6);
    assert_eq!(at(43.0).airbag_stage, AirbagStage::Stage1); // 5.75 kN
    assert_eq!(at(45.0).airbag_stage, AirbagStage::Stage2); // 6.25 kN
    assert!(at(45.0).airbag_fires());
}

#[test]
fn view_and_owned_lookup_agree_and_cells_are_addressable() {
    let d = random_diagram(small_axes(), 7);
    let v = d.view();
    assert_eq!(v.lens(), [4, 5, 3, 3]);
    let idx = [2, 3, 1, 0];
    let i = d.axes().cell_index(idx).unwrap();
    assert_eq!(i, ((2 * 5 + 3) * 3 + 1) * 3);
    assert_eq!(v.cell_at(idx), Some(&d.cells()[i]));
    assert_eq!(d.axes().cell_coords(i), Some(idx));
    let p = d.axes().point(i).unwrap();
    assert_eq!(
        p.query,
        Query {
            closing_speed_kph: 80.0,
            opponent_mass_kg: 2400.0,
            occupant_mass_kg: 75.0,
            seat_distance_mm: 200.0
        }
    );
    assert_eq!(random_cell(p, 7), d.cells()[i]);
    let q = Query {
        closing_speed_kph: 55.0,
        opponent_mass_kg: 1300.0,
        occupant_mass_kg: 80.0,
        seat_distance_mm: 310.0,
    };
    assert_eq!(d.lookup(&q), v.lookup(&q));
    assert_eq!(
        AxisId::ALL.map(|a| d.lookup(&q).out_of_range.get(a)),
        [false; 4]
    );
}
