//! The world's one noise primitive, shared by the sensor models and the misuse events.

use rand::Rng;
use rand_chacha::ChaCha8Rng;

/// A standard normal draw (Box–Muller; two uniforms per draw keeps every seeded stream the
/// same draw for draw — scenario noise, the matrix's variants and the offline bench's table
/// depend on it).
pub(crate) fn gauss(rng: &mut ChaCha8Rng) -> f64 {
    let u1: f64 = rng.gen_range(f64::MIN_POSITIVE..1.0);
    let u2: f64 = rng.gen::<f64>();
    (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
}
