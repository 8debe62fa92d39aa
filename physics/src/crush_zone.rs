//! What a crush-zone (upfront) satellite feels: the front structure between the fascia and the
//! sensor, from the ego's crush.
//!
//! **Where the sensor sits.** A production upfront sensor is bolted to the front end at the
//! rail tips or the radiator support, `depth` (default 0.2 m) behind the fascia: ahead of it
//! only the fascia, the energy-absorbing foam, the bumper beam and the crash boxes. The
//! compartment accelerometer sits on the body, behind the rails; the collision model's ego
//! pulse (`physics::simulate_collision`) is that body's, and the ego's crush `c(t)` is how much
//! the structure in front of it has shortened.
//!
//! **Model (a graded crush zone).** The structure crushes progressively from the front: the
//! part already folded moves with the obstacle's face (the face's speed is the body's less
//! the crush rate ċ), the part far behind the folds moves with the body. A sensor at depth `L`
//! is folded into the face once the crush has used the length ahead of it: folding compacts
//! a crash box to ≈ 30 % of its length ([`COMPACTED_STRAIN`] of it crushes), so that is at
//! `c = ε·L`. Between contact and that instant the sensor's speed is graded linearly between
//! the body's and the face's by how much of that length is used:
//!
//! `v_sensor = v_body − ċ · w(c)`,  `w(c) = clamp(c / (ε·L), 0, 1)`,
//!
//! so its acceleration is the body's plus `d/dt(−ċ·w(c))`. At contact `w = 0`: no step in the
//! sensor's speed however fast the crush starts; at a constant crush rate `v` (a rigid barrier
//! before the body has slowed) the sensor decelerates at `v²/(ε·L)` relative to the body for
//! `ε·L/v` — 177 g for 1.8 ms … 8.9 ms at 56 km/h: the satellite's Δv leads the body's by
//! metres per second within the first milliseconds, which is what upfront sensors are fitted
//! for; at 16 km/h the same is 14 g, and the lead is `v²·t/(ε·L)`: it grows with the square of
//! the closing speed. Nothing here feeds back on the body: the body pulse is the collision
//! model's, unchanged (the sensor's few kilograms of structure do not move it).
//!
//! **What it leaves out** (say so where it matters): the stress wave and the ringing of the
//! front end at contact (real satellites read short spikes of hundreds of g, which their
//! low-pass and the algorithm's Δv windows integrate away) and the sensor's destruction once the
//! folds reach it (here it moves with the face). The side-to-side difference of offset and
//! angular impacts is the caller's: it passes the crush at each rail tip (`world`'s truth,
//! `satellite_crush_m`).

/// *Default* depth of a satellite behind the fascia [m]: at the rail tips, ahead of it only the
/// fascia, the foam, the bumper beam and the crash boxes (Bosch, Continental and ZF upfront
/// sensors sit on the front-end carrier or the rail tips).
pub const DEFAULT_DEPTH_M: f64 = 0.2;

/// Fraction of a crash box's length that folding can use before the folds are packed
/// (stroke efficiency): square and octagonal steel and aluminium crash boxes reach 70–75 %
/// (Abramowicz & Jones, "Dynamic progressive buckling of circular and square tubes", 1986;
/// the usual design figure of 0.7 for a box's usable stroke).
pub const COMPACTED_STRAIN: f64 = 0.7;

/// The satellite's acceleration relative to the body [m/s²] at each sample of the ego's crush
/// `crush_m` (samples `step_s` apart from contact), for a sensor `depth_m` behind the fascia.
/// Central differences of `−ċ·w(c)` (one-sided at the ends); empty crush → empty.
pub fn relative_accel_mps2(crush_m: &[f64], step_s: f64, depth_m: f64) -> Vec<f64> {
    let n = crush_m.len();
    if n < 2 || !(step_s > 0.0) || !(depth_m > 0.0) {
        return vec![0.0; n];
    }
    let fold_m = COMPACTED_STRAIN * depth_m;
    let w = |c: f64| (c / fold_m).clamp(0.0, 1.0);
    // Crush rate by central differences; at contact the crush starts from 0 with the
    // closing speed's share, so the forward difference is the right one there.
    let rate = |k: usize| -> f64 {
        let (a, b) = (k.saturating_sub(1), (k + 1).min(n - 1));
        let span = (b - a) as f64 * step_s;
        (crush_m[b] - crush_m[a]) / span
    };
    let rel_v: Vec<f64> = (0..n).map(|k| -rate(k) * w(crush_m[k])).collect();
    (0..n)
        .map(|k| {
            let (a, b) = (k.saturating_sub(1), (k + 1).min(n - 1));
            (rel_v[b] - rel_v[a]) / ((b - a) as f64 * step_s)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A constant crush rate v (the body not yet slowed): the closed form is −v²/(ε·L) until
    /// the folds reach the sensor at t = ε·L/v, then 0; the velocity lead at time t is
    /// v²·t/(ε·L) until then and v (the face's speed) after.
    #[test]
    fn a_constant_crush_rate_decelerates_the_sensor_by_v_squared_over_the_fold_length() {
        let (v, step, depth) = (15.6, 1e-4, 0.2);
        let crush: Vec<f64> = (0..400).map(|k| v * k as f64 * step).collect();
        let rel = relative_accel_mps2(&crush, step, depth);
        let fold = COMPACTED_STRAIN * depth;
        let t_fold = fold / v;
        let expected = -v * v / fold;
        for (k, a) in rel.iter().enumerate().skip(2) {
            let t = k as f64 * step;
            if t < t_fold - 2.0 * step {
                assert!((a - expected).abs() < 1e-6 * expected.abs(), "t {t}: {a}");
            } else if t > t_fold + 2.0 * step {
                assert!(a.abs() < 1e-6 * expected.abs(), "t {t}: {a}");
            }
        }
        // Integrated: the sensor's speed lead over the body reaches the crush rate (it moves
        // with the face) once the folds are there.
        let lead: f64 = rel.iter().map(|a| a * step).sum();
        assert!((lead + v).abs() < 0.02 * v, "lead {lead}");
    }

    #[test]
    fn no_crush_no_difference_and_degenerate_inputs_give_zeros() {
        assert!(relative_accel_mps2(&[0.0; 50], 1e-4, 0.2)
            .iter()
            .all(|a| *a == 0.0));
        assert_eq!(relative_accel_mps2(&[], 1e-4, 0.2), Vec::<f64>::new());
        assert_eq!(relative_accel_mps2(&[0.0, 0.1], 0.0, 0.2), vec![0.0, 0.0]);
    }
}
