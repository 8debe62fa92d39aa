//! The worst-case search's operators over [`CycleCase`]s (`worst-cycle search`): a random case,
//! uniform in every range of the space, and a mutation of one. Running and measuring a case is
//! [`crate::worst_case`]'s.

use crate::worst_case::{CanKind, CycleCase, ObjectKind};
use rand::Rng;
use rand_chacha::ChaCha8Rng;

/// A random case (uniform in every range).
pub fn random_case(rng: &mut ChaCha8Rng) -> CycleCase {
    let objects = (0..rng.gen_range(0..=2))
        .map(|_| object_kind(rng))
        .collect();
    let can = (0..rng.gen_range(0..=4)).map(|_| can_kind(rng)).collect();
    let case = CycleCase {
        closing_speed_mps: rng.gen_range(5.0..45.0),
        closing_accel_mps2: rng.gen_range(-12.0..2.0),
        opponent_mass_kg: rng.gen_range(500.0..4000.0),
        mass_sigma_kg: rng.gen_range(0.0..1000.0),
        contact_in_ms: rng.gen_range(-40.0..700.0),
        tracked_ms: rng.gen_range(10.0..1000.0),
        object_period_ms: rng.gen_range(5..=40),
        latency_ms: rng.gen_range(0..=60),
        noise: rng.gen_range(0.0..1.0),
        noise_seed: rng.gen(),
        confidence: rng.gen_range(0.0..1.0),
        ego_speed_mps: rng.gen_range(0.0..60.0),
        occupant_mass_kg: rng.gen_range(30.0..150.0),
        chest_mm: rng.gen_range(150.0..500.0),
        buckled: rng.gen(),
        adult: rng.gen(),
        crash_decel_g: rng.gen_range(0.0..60.0),
        accel_rate_hz: rng.gen_range(1000.0..8000.0),
        secoc: rng.gen(),
        lut: rng.gen_bool(0.8),
        v2x: rng.gen(),
        objects,
        can,
        accel_batches: rng.gen_range(0..=2),
        late_us: rng.gen_range(0..=900),
        overruns: rng.gen_range(0..=3),
    };
    case.clamped()
}

fn object_kind(rng: &mut ChaCha8Rng) -> ObjectKind {
    ObjectKind::ALL[rng.gen_range(0..ObjectKind::ALL.len())]
}

fn can_kind(rng: &mut ChaCha8Rng) -> CanKind {
    CanKind::ALL[rng.gen_range(0..CanKind::ALL.len())]
}

/// One edit of a measured cycle's input list (at most `max` long): an element added, removed
/// or replaced by `new`.
fn edit<T>(list: &mut Vec<T>, max: usize, rng: &mut ChaCha8Rng, new: fn(&mut ChaCha8Rng) -> T) {
    match rng.gen_range(0..3) {
        0 if list.len() < max => list.push(new(rng)),
        1 if !list.is_empty() => {
            let i = rng.gen_range(0..list.len());
            list.remove(i);
        }
        _ if !list.is_empty() => {
            let i = rng.gen_range(0..list.len());
            list[i] = new(rng);
        }
        _ => list.push(new(rng)),
    }
}

/// A mutation of `c`: each field changes with probability `p` (numbers by a normal step of a
/// fifth of their range, flags flipped, lists edited).
pub fn mutate(c: &CycleCase, p: f64, rng: &mut ChaCha8Rng) -> CycleCase {
    let mut m = c.clone();
    let num = |v: &mut f64, lo: f64, hi: f64, rng: &mut ChaCha8Rng| {
        if rng.gen_bool(p) {
            let u1: f64 = rng.gen_range(f64::MIN_POSITIVE..1.0);
            let u2: f64 = rng.gen();
            let g = (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos();
            *v = (*v + 0.2 * (hi - lo) * g).clamp(lo, hi);
        }
    };
    num(&mut m.closing_speed_mps, 5.0, 45.0, rng);
    num(&mut m.closing_accel_mps2, -12.0, 2.0, rng);
    num(&mut m.opponent_mass_kg, 500.0, 4000.0, rng);
    num(&mut m.mass_sigma_kg, 0.0, 1000.0, rng);
    num(&mut m.contact_in_ms, -40.0, 700.0, rng);
    num(&mut m.tracked_ms, 10.0, 1000.0, rng);
    num(&mut m.noise, 0.0, 1.0, rng);
    num(&mut m.confidence, 0.0, 1.0, rng);
    num(&mut m.ego_speed_mps, 0.0, 60.0, rng);
    num(&mut m.occupant_mass_kg, 30.0, 150.0, rng);
    num(&mut m.chest_mm, 150.0, 500.0, rng);
    num(&mut m.crash_decel_g, 0.0, 60.0, rng);
    num(&mut m.accel_rate_hz, 1000.0, 8000.0, rng);
    if rng.gen_bool(p) {
        m.object_period_ms = rng.gen_range(5..=40);
    }
    if rng.gen_bool(p) {
        m.latency_ms = rng.gen_range(0..=60);
    }
    if rng.gen_bool(p) {
        m.noise_seed = rng.gen();
    }
    for flag in [
        &mut m.buckled,
        &mut m.adult,
        &mut m.secoc,
        &mut m.lut,
        &mut m.v2x,
    ] {
        if rng.gen_bool(p * 0.5) {
            *flag = !*flag;
        }
    }
    if rng.gen_bool(p) {
        edit(&mut m.objects, 2, rng, object_kind);
    }
    if rng.gen_bool(p) {
        edit(&mut m.can, 4, rng, can_kind);
    }
    if rng.gen_bool(p) {
        m.accel_batches = rng.gen_range(0..=2);
    }
    if rng.gen_bool(p) {
        m.late_us = rng.gen_range(0..=900);
    }
    if rng.gen_bool(p) {
        m.overruns = rng.gen_range(0..=3);
    }
    m.clamped()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::worst_case::run;
    use rand::SeedableRng;

    #[test]
    fn random_and_mutated_cases_are_in_range_and_reproducible() {
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        for _ in 0..50 {
            let c = random_case(&mut rng);
            assert_eq!(c.clone().clamped(), c);
            let m = mutate(&c, 0.5, &mut rng);
            assert_eq!(m.clone().clamped(), m);
        }
        let c = random_case(&mut ChaCha8Rng::seed_from_u64(9));
        assert_eq!(run(&c).unwrap(), run(&c).unwrap());
        let text = serde_json::to_string(&c).unwrap();
        let back: CycleCase = serde_json::from_str(&text).unwrap();
        assert_eq!(back, c);
    }
}
