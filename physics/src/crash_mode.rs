//! Crash modes: which part of the ego's front a collision engages, and when.
//!
//! The paper's classes are full-width force-deflection curves (`stiffness`): the whole front —
//! both longitudinal rails, the bumper beam and sub-frame, later the engine and the firewall —
//! loaded at once by a flat, full-width face. A production crash-sensing calibration is judged
//! on more: a 40 % offset deformable barrier, an angled wall, a centre pole, a truck's rear
//! bed. Each engages a *part* of the same structure, some of it only after a gap; this module
//! builds the curve the collision model runs for each from the vehicle's own class curve, so
//! the two-mass model, the occupant model and the sensors stay as they are.
//!
//! **The front as load paths** (*defaults*, [`FrontLayout`]): two rails, each
//! [`RAIL_SHARE`] of the curve's force, whose tips sit [`RAIL_INBOARD_FRACTION`] of the width in
//! from each side, and the rest ([`DISTRIBUTED_SHARE`]: bumper beam, sub-frame, wheels, engine)
//! spread over the width. A mode's curve is the sum of the paths it engages, each the class
//! curve scaled by its share and shifted by the deflection before it is reached:
//!
//! `F_mode(x) = F_soft(x) + Σ share_i · F_class(x − gap_i)`   (`F(x < 0) = 0`)
//!
//! | mode | engaged | gap | source of the figures |
//! |---|---|---|---|
//! | full frontal | everything | 0 | the paper's curves, unchanged |
//! | offset (overlap p) | the rails inside the overlap, p of the rest | 0 | geometry; a deformable barrier's face in series ([`odb_face_curve`], UN R94 Annex 9 honeycomb) |
//! | angular (wall at θ) | the struck rail once the wall reaches it, the rest as the contact widens | `y·tan θ` to a path at `y` from the struck corner | geometry; the car slides along the wall: only the normal speed is arrested, x share `cos² θ (1 + e) v` |
//! | centre pole | bumper beam bending ([`POLE_BEAM_FORCE_N`]), then engine and sub-frame | [`POLE_GAP_M`] (bumper to engine) | IIHS pole study: the hard stage after the bumper-to-engine gap, delay ≈ d / v |
//! | underride | hood and fenders ([`UNDERRIDE_SOFT_FORCE_N`]), then the A-pillars | [`UNDERRIDE_GAP_M`] (the hood's length under the bed) | bumper and rails pass under the bed (NASS EDR: underride needs a higher Δv to deploy) |
//!
//! What it leaves out (say so where it matters): the yaw of offset and angular impacts (all the
//! energy goes into the x-y translation here), the lateral pulse (the sensors are x axis), the
//! compartment's intrusion beyond the class curves' stiffening, and a pole or a bed that gives.

use crate::{Curve, PhysicsError};

/// Share of the front's force each longitudinal rail carries (*default*, two rails: 70 % of the
/// full-width force, the rest spread). Load-path studies of full frontal tests put 50–70 % of
/// the crush energy into the rails.
pub const RAIL_SHARE: f64 = 0.35;

/// Share of the front's force spread over its width: bumper beam, sub-frame, wheels, engine.
pub const DISTRIBUTED_SHARE: f64 = 1.0 - 2.0 * RAIL_SHARE;

/// Where a rail's tip sits, as a fraction of the vehicle's width in from its side (*default*:
/// 0.36 m on a 1.8 m car).
pub const RAIL_INBOARD_FRACTION: f64 = 0.2;

/// The vehicle's front width [m] (*default*: the paper's mid-size cars, 1.8 m).
pub const DEFAULT_WIDTH_M: f64 = 1.8;

/// A centre pole's soft stage: the bumper beam bending about the pole (three-point bending of
/// production bumper beams peaks at 30–80 kN; *default* 50 kN), reached over the first
/// [`POLE_BEAM_RISE_M`].
pub const POLE_BEAM_FORCE_N: f64 = 80.0e3;

/// Deflection over which the bumper beam's bending force builds up [m].
pub const POLE_BEAM_RISE_M: f64 = 0.05;

/// A centre pole's gap between the bumper beam and the engine / cross member [m] (crash-sensing
/// references: d ≈ 0.45 m, the hard stage ≈ d / v after contact — 51 ms at 32 km/h).
pub const POLE_GAP_M: f64 = 0.45;

/// Share of the class curve that engages behind a pole's gap: the engine, the sub-frame and the
/// rails loaded through the wrapped beam (*default*: the distributed paths and half the rails).
pub const POLE_HARD_SHARE: f64 = DISTRIBUTED_SHARE + RAIL_SHARE;

/// An underride's soft stage: hood, fenders and the radiator support's top crushed by the bed's
/// edge (*default* 25 kN).
pub const UNDERRIDE_SOFT_FORCE_N: f64 = 25.0e3;

/// Deflection over which the soft stage's force builds up [m].
pub const UNDERRIDE_SOFT_RISE_M: f64 = 0.1;

/// How far the car runs under the bed before its A-pillars and the windscreen's base meet it
/// [m] (*default*: a mid-size car's hood, 0.9 m).
pub const UNDERRIDE_GAP_M: f64 = 0.9;

/// Share of the class curve the A-pillars and roof rails carry once they meet the bed.
pub const UNDERRIDE_HARD_SHARE: f64 = 0.5;

/// UN R94 Annex 9 offset deformable barrier: the main honeycomb block's crush strength [Pa],
/// its height [m] and depth [m], and the barrier's width [m].
pub const ODB_MAIN_CRUSH_PA: f64 = 0.342e6;
/// The main block's height [m].
pub const ODB_MAIN_HEIGHT_M: f64 = 0.65;
/// The main block's depth [m] plus the bumper element's 90 mm: the face's stroke.
pub const ODB_STROKE_M: f64 = 0.45 + 0.09;
/// The barrier's width [m].
pub const ODB_WIDTH_M: f64 = 1.0;
/// Stiffness of the face once its honeycomb is packed [N/m] (the rigid block behind it).
pub const ODB_PACKED_STIFFNESS_N_PER_M: f64 = 50.0e6;

/// How the ego meets what it hits.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CrashMode {
    /// A flat face over the whole width (a wall, or an aligned car): the class curve itself.
    FullFrontal,
    /// A flat face over `overlap` (0 < overlap ≤ 1) of the width from one side.
    Offset {
        /// Overlapped fraction of the ego's width.
        overlap: f64,
    },
    /// A flat rigid wall at `angle_rad` (0 ≤ angle < 60°) to the ego's front.
    Angular {
        /// Angle between the wall and the ego's front [rad].
        angle_rad: f64,
    },
    /// A narrow rigid pole on the centre line, between the rails.
    Pole,
    /// The rear of a truck's bed above the ego's bumper and rails.
    Underride,
}

/// The curve a mode's collision runs, and how its motion maps onto the ego's x axis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Engaged {
    /// Force against deflection along the collision's normal.
    pub curve: Curve,
    /// cos of the angle between the collision's normal and the ego's x axis: the ego's x
    /// acceleration and velocity change are the normal ones times this, its crush along x the
    /// normal deflection divided by it (1 but for an angular impact).
    pub axis_cos: f64,
}

/// Points at which a mode's curve is sampled between the class curve's own breakpoints, where
/// a path's share grows with the deflection (the angular contact widening).
const RAMP_SAMPLES: usize = 4;

impl CrashMode {
    /// The mode's curve from the ego's class curve `class` for a front `width_m` wide.
    ///
    /// # Errors
    /// An overlap outside (0, 1], an angle outside [0°, 60°), a width that is not positive and
    /// finite, or a curve with more points than [`crate::stiffness::CURVE_CAPACITY`].
    pub fn engage(self, class: &Curve, width_m: f64) -> Result<Engaged, PhysicsError> {
        if !(width_m > 0.0 && width_m.is_finite()) {
            return Err(PhysicsError::InvalidInput("vehicle width must be > 0"));
        }
        let full = |curve| {
            Ok(Engaged {
                curve,
                axis_cos: 1.0,
            })
        };
        match self {
            CrashMode::FullFrontal => full(*class),
            CrashMode::Offset { overlap } => {
                if !(overlap > 0.0 && overlap <= 1.0) {
                    return Err(PhysicsError::InvalidInput("overlap must be in (0, 1]"));
                }
                let rails = [RAIL_INBOARD_FRACTION, 1.0 - RAIL_INBOARD_FRACTION]
                    .iter()
                    .filter(|y| overlap >= **y)
                    .count() as f64;
                let share = DISTRIBUTED_SHARE * overlap + RAIL_SHARE * rails;
                full(scaled(class, share)?)
            }
            CrashMode::Angular { angle_rad } => {
                if !(0.0..core::f64::consts::FRAC_PI_3).contains(&angle_rad) {
                    return Err(PhysicsError::InvalidInput("angle must be in [0°, 60°)"));
                }
                angular(class, width_m, angle_rad)
            }
            CrashMode::Pole => full(staged(
                class,
                POLE_BEAM_FORCE_N,
                POLE_BEAM_RISE_M,
                POLE_GAP_M,
                POLE_HARD_SHARE,
            )?),
            CrashMode::Underride => full(staged(
                class,
                UNDERRIDE_SOFT_FORCE_N,
                UNDERRIDE_SOFT_RISE_M,
                UNDERRIDE_GAP_M,
                UNDERRIDE_HARD_SHARE,
            )?),
        }
    }
}

/// The class curve with every force times `share`.
fn scaled(class: &Curve, share: f64) -> Result<Curve, PhysicsError> {
    let mut f = [0.0; crate::stiffness::CURVE_CAPACITY];
    let d = class.deflection_m();
    for (o, v) in f.iter_mut().zip(class.force_n()) {
        *o = v * share;
    }
    Curve::from_points(d, &f[..d.len()])
}

/// A soft stage rising to `soft_n` over `rise_m` and held (with a small slope, so the curve
/// stays invertible) until `gap_m`, then `hard_share` of the class curve on top of it.
fn staged(
    class: &Curve,
    soft_n: f64,
    rise_m: f64,
    gap_m: f64,
    hard_share: f64,
) -> Result<Curve, PhysicsError> {
    // The held soft force creeps up 2 % over the gap: a folding sheet still stiffens.
    let soft = |x: f64| {
        if x <= rise_m {
            soft_n * x / rise_m
        } else {
            soft_n * (1.0 + 0.02 * (x - rise_m) / (gap_m - rise_m).max(1e-9))
        }
    };
    let force = |x: f64| soft(x) + hard_share * class.force_at_n(x - gap_m);
    let mut xs = points::Points::new();
    xs.push(0.0);
    xs.push(rise_m);
    for d in class.deflection_m() {
        xs.push(gap_m + d);
    }
    xs.finish(force)
}

/// An angled wall: the struck corner first, each path engaged once the wall has advanced
/// `y·tan θ` along x to it, the spread paths with the contact's width; along the wall's normal.
fn angular(class: &Curve, width_m: f64, angle_rad: f64) -> Result<Engaged, PhysicsError> {
    let (sin, cos) = (libm::sin(angle_rad), libm::cos(angle_rad));
    if angle_rad == 0.0 {
        return Ok(Engaged {
            curve: *class,
            axis_cos: 1.0,
        });
    }
    let tan = sin / cos;
    // Along the car's axis: the deflection at which the wall reaches lateral position y.
    let reach = |y: f64| y * width_m * tan;
    let rail_gaps = [
        reach(RAIL_INBOARD_FRACTION),
        reach(1.0 - RAIL_INBOARD_FRACTION),
    ];
    let full_width = reach(1.0);
    let axial = |xa: f64| {
        let spread = DISTRIBUTED_SHARE * (xa / full_width).clamp(0.0, 1.0) * class.force_at_n(xa);
        let rails: f64 = rail_gaps
            .iter()
            .map(|g| RAIL_SHARE * class.force_at_n(xa - g))
            .sum();
        spread + rails
    };
    // Along the normal: x_n = x_a·cos θ, and the normal force does the axial force's work,
    // N·dx_n = F_a·dx_a, so N(x_n) = F_a(x_n / cos θ) / cos θ.
    let normal = |xn: f64| axial(xn / cos) / cos;
    let mut xs = points::Points::new();
    xs.push(0.0);
    for k in 1..=RAMP_SAMPLES {
        xs.push(rail_gaps[0] * cos * k as f64 / RAMP_SAMPLES as f64);
    }
    for g in [0.0, rail_gaps[0], rail_gaps[1]] {
        for d in class.deflection_m().iter().skip(1) {
            xs.push((g + d) * cos);
        }
    }
    xs.push(full_width * cos);
    Ok(Engaged {
        curve: xs.finish(normal)?,
        axis_cos: cos,
    })
}

/// A fixed-capacity set of deflection points, sorted and made into a curve.
mod points {
    use crate::stiffness::CURVE_CAPACITY;
    use crate::{Curve, PhysicsError};

    /// Up to twice a curve's capacity of candidate points (duplicates and crowded points are
    /// dropped before the curve is built).
    pub struct Points {
        x: [f64; 2 * CURVE_CAPACITY],
        len: usize,
    }

    impl Points {
        pub fn new() -> Self {
            Self {
                x: [0.0; 2 * CURVE_CAPACITY],
                len: 0,
            }
        }

        /// Adds `x` (ignored once full; [`Points::finish`] then reports it).
        pub fn push(&mut self, x: f64) {
            if self.len < self.x.len() && x.is_finite() && x >= 0.0 {
                self.x[self.len] = x;
            }
            self.len += 1;
        }

        /// The curve through `force` at the points, sorted, without points closer than 0.1 mm.
        pub fn finish(mut self, force: impl Fn(f64) -> f64) -> Result<Curve, PhysicsError> {
            if self.len > self.x.len() {
                return Err(PhysicsError::CurveTooLong);
            }
            let xs = &mut self.x[..self.len];
            xs.sort_unstable_by(f64::total_cmp);
            let mut d = [0.0; CURVE_CAPACITY];
            let mut f = [0.0; CURVE_CAPACITY];
            let mut n = 0;
            for &x in xs.iter() {
                if n > 0 && x - d[n - 1] < 1e-4 {
                    continue;
                }
                if n == CURVE_CAPACITY {
                    return Err(PhysicsError::CurveTooLong);
                }
                d[n] = x;
                f[n] = if x == 0.0 { 0.0 } else { force(x) };
                n += 1;
            }
            Curve::from_points(&d[..n], &f[..n])
        }
    }
}

/// The face of a UN R94 offset deformable barrier where `loaded_width_m` of it is struck: the
/// main block's honeycomb crushing at its strength over the loaded area for the face's stroke,
/// then the rigid block behind it.
///
/// # Errors
/// A loaded width that is not positive and finite.
pub fn odb_face_curve(loaded_width_m: f64) -> Result<Curve, PhysicsError> {
    if !(loaded_width_m > 0.0 && loaded_width_m.is_finite()) {
        return Err(PhysicsError::InvalidInput("loaded width must be > 0"));
    }
    let w = loaded_width_m.min(ODB_WIDTH_M);
    let plateau = ODB_MAIN_CRUSH_PA * w * ODB_MAIN_HEIGHT_M;
    // Honeycomb reaches its crush strength within a few mm and holds it (2 % rise over the
    // stroke keeps the curve invertible); packed, the rigid block.
    Curve::from_points(
        &[0.0, 0.005, ODB_STROKE_M, ODB_STROKE_M + 0.1],
        &[
            0.0,
            plateau,
            plateau * 1.02,
            plateau * 1.02 + ODB_PACKED_STIFFNESS_N_PER_M * 0.1,
        ],
    )
}
