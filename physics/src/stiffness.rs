//! Force-deflection curves: fixed-capacity piecewise-linear storage, the series combination of
//! two vehicles at equal force, and the mass classes of the paper.
//!
//! Convention: deflection (crush) is positive when the vehicle front is shortened; force is the
//! compressive contact force, positive. Beyond the last point a curve continues with its last
//! slope (a real front keeps stiffening; the compartment collapse beyond ~56 km/h per vehicle is
//! outside the model's validity, SPEC).

use crate::PhysicsError;

/// Fixed point capacity of a [`Curve`] and of a [`CombinedSpring`].
pub const CURVE_CAPACITY: usize = 32;

/// Piecewise-linear force-deflection characteristic of one vehicle front.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Curve {
    deflection_m: [f64; CURVE_CAPACITY],
    force_n: [f64; CURVE_CAPACITY],
    len: usize,
}

mod generated {
    use super::Curve;
    include!(concat!(env!("OUT_DIR"), "/stiffness_classes.rs"));
}
pub use generated::{CLASS_CURVES, CLASS_RANGES_KG, COMBINED_CURVE};

impl Curve {
    /// Used by the build-time generated consts (validated in build.rs). Not for user data:
    /// use [`Curve::from_points`], which validates.
    #[doc(hidden)]
    pub const fn from_padded(
        deflection_m: [f64; CURVE_CAPACITY],
        force_n: [f64; CURVE_CAPACITY],
        len: usize,
    ) -> Self {
        Curve {
            deflection_m,
            force_n,
            len,
        }
    }

    /// Build a curve from points (SI units). Requirements: 2..=32 points, all finite, first point
    /// (0, 0), deflection and force strictly increasing (the force must be invertible so that two
    /// curves can be combined in series).
    pub fn from_points(deflection_m: &[f64], force_n: &[f64]) -> Result<Self, PhysicsError> {
        if deflection_m.len() != force_n.len() {
            return Err(PhysicsError::InvalidCurve(
                "deflection and force differ in length",
            ));
        }
        let len = deflection_m.len();
        if len < 2 {
            return Err(PhysicsError::InvalidCurve(
                "a curve needs at least 2 points",
            ));
        }
        if len > CURVE_CAPACITY {
            return Err(PhysicsError::CurveTooLong);
        }
        let mut curve = Curve {
            deflection_m: [0.0; CURVE_CAPACITY],
            force_n: [0.0; CURVE_CAPACITY],
            len,
        };
        for (i, (&d, &f)) in deflection_m.iter().zip(force_n.iter()).enumerate() {
            if !d.is_finite() || !f.is_finite() {
                return Err(PhysicsError::InvalidCurve("non-finite value"));
            }
            if i == 0 && (d != 0.0 || f != 0.0) {
                return Err(PhysicsError::InvalidCurve("a curve must start at (0, 0)"));
            }
            if i > 0 && (d <= curve.deflection_m[i - 1] || f <= curve.force_n[i - 1]) {
                return Err(PhysicsError::InvalidCurve(
                    "deflection and force must be strictly increasing",
                ));
            }
            curve.deflection_m[i] = d;
            curve.force_n[i] = f;
        }
        Ok(curve)
    }

    /// A linear spring `force = stiffness · deflection` (closed-form oracles, `--linear-stiffness`).
    pub fn linear(stiffness_n_per_m: f64) -> Result<Self, PhysicsError> {
        if !(stiffness_n_per_m.is_finite() && stiffness_n_per_m > 0.0) {
            return Err(PhysicsError::InvalidInput(
                "linear stiffness must be finite and > 0",
            ));
        }
        Curve::from_points(&[0.0, 1.0], &[0.0, stiffness_n_per_m])
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Never true for a constructed curve (at least 2 points); present for API symmetry.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Deflection points [m].
    pub fn deflection_m(&self) -> &[f64] {
        &self.deflection_m[..self.len.min(CURVE_CAPACITY)]
    }

    /// Force points [N].
    pub fn force_n(&self) -> &[f64] {
        &self.force_n[..self.len.min(CURVE_CAPACITY)]
    }

    /// Contact force at a deflection [N]; 0 for deflection ≤ 0, last slope beyond the last point.
    pub fn force_at_n(&self, deflection_m: f64) -> f64 {
        if !(deflection_m > 0.0) {
            return 0.0;
        }
        interp_extrapolate(self.deflection_m(), self.force_n(), deflection_m)
    }

    /// Deflection at which the curve reaches a force [m] (inverse of [`Curve::force_at_n`]).
    pub fn deflection_at_force_m(&self, force_n: f64) -> f64 {
        if !(force_n > 0.0) {
            return 0.0;
        }
        interp_extrapolate(self.force_n(), self.deflection_m(), force_n)
    }

    /// Energy absorbed when loading to a deflection [J] (area under the curve).
    pub fn energy_to_deflection_j(&self, deflection_m: f64) -> f64 {
        if !(deflection_m > 0.0) {
            return 0.0;
        }
        let (d, f) = (self.deflection_m(), self.force_n());
        let mut energy_j = 0.0;
        for i in 1..d.len() {
            let (x0, x1) = (d[i - 1], d[i]);
            if deflection_m <= x0 {
                return energy_j;
            }
            let x_end = if i + 1 == d.len() {
                deflection_m
            } else {
                deflection_m.min(x1)
            };
            let f_end = self.force_at_n(x_end);
            energy_j += 0.5 * (f[i - 1] + f_end) * (x_end - x0);
        }
        energy_j
    }
}

/// Linear interpolation in a strictly increasing `xs`, extrapolating with the end segments.
fn interp_extrapolate(xs: &[f64], ys: &[f64], x: f64) -> f64 {
    let n = xs.len().min(ys.len());
    if n < 2 {
        return 0.0;
    }
    let mut seg = 0;
    while seg + 2 < n && x > xs[seg + 1] {
        seg += 1;
    }
    let slope = (ys[seg + 1] - ys[seg]) / (xs[seg + 1] - xs[seg]);
    ys[seg] + (x - xs[seg]) * slope
}

/// The one combined crush spring of the two-mass model: the series combination of the ego and
/// the opponent curve (at equal force the deflections add), with the ego's share of the
/// deflection stored per point so that each vehicle's own crush follows from the relative
/// deflection without a second lookup.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CombinedSpring {
    pub(crate) x_m: [f64; CURVE_CAPACITY],
    pub(crate) force_n: [f64; CURVE_CAPACITY],
    pub(crate) ego_m: [f64; CURVE_CAPACITY],
    /// Slope of force over relative deflection in segment i (last entry used beyond the end).
    pub(crate) stiffness_n_per_m: [f64; CURVE_CAPACITY],
    /// Slope of the ego deflection over relative deflection in segment i.
    pub(crate) ego_share: [f64; CURVE_CAPACITY],
    pub(crate) len: usize,
}

impl CombinedSpring {
    /// Series combination of two fronts. `opponent = None` means a rigid, non-deforming opponent
    /// (a barrier or a wall): the combined spring is the ego curve itself.
    ///
    /// The combined breakpoints are the union of both curves' force breakpoints; between them
    /// both inverse curves are linear in force, so the sum is exact (no resampling error).
    pub fn series(ego: &Curve, opponent: Option<&Curve>) -> Result<Self, PhysicsError> {
        let mut spring = CombinedSpring {
            x_m: [0.0; CURVE_CAPACITY],
            force_n: [0.0; CURVE_CAPACITY],
            ego_m: [0.0; CURVE_CAPACITY],
            stiffness_n_per_m: [0.0; CURVE_CAPACITY],
            ego_share: [0.0; CURVE_CAPACITY],
            len: 0,
        };
        let (fe, fo): (&[f64], &[f64]) = match opponent {
            Some(o) => (ego.force_n(), o.force_n()),
            None => (ego.force_n(), &[]),
        };
        if fe.len() < 2 {
            return Err(PhysicsError::InvalidCurve(
                "ego curve has fewer than 2 points",
            ));
        }
        // Merge the two sorted force lists (both start at 0), dropping near-duplicates.
        let (mut i, mut j, mut n) = (0usize, 0usize, 0usize);
        let mut last_f = f64::NEG_INFINITY;
        while i < fe.len() || j < fo.len() {
            let f = match (fe.get(i), fo.get(j)) {
                (Some(&a), Some(&b)) if a <= b => {
                    i += 1;
                    a
                }
                (Some(_), Some(&b)) => {
                    j += 1;
                    b
                }
                (Some(&a), None) => {
                    i += 1;
                    a
                }
                (None, Some(&b)) => {
                    j += 1;
                    b
                }
                (None, None) => break,
            };
            if f - last_f <= 1.0e-9 * f.abs().max(1.0) {
                continue;
            }
            if n >= CURVE_CAPACITY {
                return Err(PhysicsError::CurveTooLong);
            }
            let d_ego = ego.deflection_at_force_m(f);
            let d_opp = opponent.map_or(0.0, |o| o.deflection_at_force_m(f));
            spring.force_n[n] = f;
            spring.ego_m[n] = d_ego;
            spring.x_m[n] = d_ego + d_opp;
            last_f = f;
            n += 1;
        }
        spring.len = n;
        for k in 0..n.saturating_sub(1) {
            let dx = spring.x_m[k + 1] - spring.x_m[k];
            if !(dx > 0.0) {
                return Err(PhysicsError::InvalidCurve(
                    "combined curve not strictly increasing",
                ));
            }
            spring.stiffness_n_per_m[k] = (spring.force_n[k + 1] - spring.force_n[k]) / dx;
            spring.ego_share[k] = (spring.ego_m[k + 1] - spring.ego_m[k]) / dx;
        }
        Ok(spring)
    }

    /// Combined spring of a single linear stiffness (rigid opponent), for oracles and the CLI.
    pub fn linear(stiffness_n_per_m: f64) -> Result<Self, PhysicsError> {
        CombinedSpring::series(&Curve::linear(stiffness_n_per_m)?, None)
    }

    /// Segment index containing relative deflection `x_m` (≥ 0), starting the search at `seg`.
    #[inline(always)]
    pub(crate) fn segment_from(&self, mut seg: usize, x_m: f64) -> usize {
        let last = self.len.saturating_sub(2);
        while seg < last && x_m > self.x_m[seg + 1] {
            seg += 1;
        }
        seg
    }

    /// Force at relative deflection [N] (linear search; the integrator uses a cursor instead).
    pub fn force_at_n(&self, x_m: f64) -> f64 {
        if !(x_m > 0.0) {
            return 0.0;
        }
        let s = self.segment_from(0, x_m);
        self.force_n[s] + (x_m - self.x_m[s]) * self.stiffness_n_per_m[s]
    }

    /// Ego vehicle's own deflection at a relative deflection during loading [m].
    pub fn ego_deflection_m(&self, x_m: f64) -> f64 {
        if !(x_m > 0.0) {
            return 0.0;
        }
        let s = self.segment_from(0, x_m);
        self.ego_m[s] + (x_m - self.x_m[s]) * self.ego_share[s]
    }

    /// Relative deflection points [m].
    pub fn deflection_m(&self) -> &[f64] {
        &self.x_m[..self.len.min(CURVE_CAPACITY)]
    }

    /// Force points [N].
    pub fn force_n(&self) -> &[f64] {
        &self.force_n[..self.len.min(CURVE_CAPACITY)]
    }
}

/// One of the paper's six mass classes (1..=6).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct MassClass(u8);

impl MassClass {
    /// Class from its number 1..=6.
    pub fn new(number: u8) -> Result<Self, PhysicsError> {
        if (1..=6).contains(&number) {
            Ok(MassClass(number))
        } else {
            Err(PhysicsError::InvalidInput("mass class must be 1..=6"))
        }
    }
    /// Class number 1..=6.
    pub fn number(self) -> u8 {
        self.0
    }
    /// The class's calibrated force-deflection curve.
    pub fn curve(self) -> &'static Curve {
        let idx = usize::from(self.0.clamp(1, 6)) - 1;
        &CLASS_CURVES[idx]
    }
    /// Mass lookup range [kg] (lower inclusive, upper exclusive).
    pub fn range_kg(self) -> (f64, f64) {
        CLASS_RANGES_KG[usize::from(self.0.clamp(1, 6)) - 1]
    }
}

/// Class of a vehicle by its (estimated) mass: < 1200, 1200–1400, 1400–1750, 1750–2000,
/// 2000–2500, ≥ 2500 kg (ranges from the data file). The estimate only needs to be rough.
pub fn class_for_mass_kg(mass_kg: f64) -> Result<MassClass, PhysicsError> {
    if !(mass_kg.is_finite() && mass_kg > 0.0) {
        return Err(PhysicsError::InvalidInput(
            "vehicle mass must be finite and > 0",
        ));
    }
    for (i, &(_, upper)) in CLASS_RANGES_KG.iter().enumerate() {
        if mass_kg < upper {
            return Ok(MassClass(i as u8 + 1));
        }
    }
    Ok(MassClass(6))
}

#[cfg(feature = "std")]
pub use loader::{load_class_file, parse_class_file, ClassSet};

#[cfg(feature = "std")]
mod loader {
    //! Loader for user-supplied class files (same schema as the shipped data file).
    use super::{Curve, PhysicsError};
    use crate::stiffness::schema;
    use std::{path::Path, string::String, vec::Vec};

    /// Classes read from a file.
    #[derive(Clone, Debug)]
    pub struct ClassSet {
        /// (lower_kg, upper_kg, curve) per class, ascending.
        pub classes: Vec<(f64, f64, Curve)>,
        /// The combined curve.
        pub combined: Curve,
        /// Provenance text from the file.
        pub provenance: String,
    }

    fn curve_si(deflection_mm: &[f64], force_kn: &[f64]) -> Result<Curve, PhysicsError> {
        let d: Vec<f64> = deflection_mm.iter().map(|v| v * 1.0e-3).collect();
        let f: Vec<f64> = force_kn.iter().map(|v| v * 1.0e3).collect();
        Curve::from_points(&d, &f)
    }

    /// Parse and validate class-file text. Errors name the offending class and rule.
    pub fn parse_class_file(text: &str) -> Result<ClassSet, String> {
        let file: schema::ClassFile = toml::from_str(text).map_err(|e| e.to_string())?;
        schema::validate_file(&file)?;
        let mut classes = Vec::new();
        for c in &file.class {
            let curve = curve_si(&c.deflection_mm, &c.force_kn)
                .map_err(|e| format!("class {}: {e}", c.id))?;
            classes.push((c.lower_kg, c.upper_kg, curve));
        }
        let combined = curve_si(&file.combined.deflection_mm, &file.combined.force_kn)
            .map_err(|e| format!("combined: {e}"))?;
        Ok(ClassSet {
            classes,
            combined,
            provenance: file.meta.provenance,
        })
    }

    /// Read, parse and validate a class file.
    pub fn load_class_file(path: &Path) -> Result<ClassSet, String> {
        let text = std::fs::read_to_string(path)
            .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
        parse_class_file(&text).map_err(|e| format!("{}: {e}", path.display()))
    }
}

#[cfg(feature = "std")]
#[allow(missing_docs)]
pub mod schema {
    //! Serde schema of the class file (shared with build.rs).
    include!("schema.rs");
}
