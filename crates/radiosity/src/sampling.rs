//! Random numbers and the two distributions of eq. 7's estimator (Szirmay-Kalos & Márton (1995),
//! "Randomized form factor calculation"): points uniform over a patch, directions cosine-distributed
//! about its normal.
//!
//! Determinism: every random stream is keyed by `(seed, a, b, c)` (for form factors: patch,
//! row version, chunk of rays), never by thread, so results do not depend on the thread count.

use crate::geom::{orthonormal_basis, Vec3};
use rand::{Rng, SeedableRng};

/// The generator used everywhere: PCG-64 (MCG variant), fast and statistically sound.
pub type Rng64 = rand_pcg::Pcg64Mcg;

/// SplitMix64's finaliser: a bijective 64-bit mix.
pub fn mix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// A generator for the stream identified by `(seed, a, b, c)`.
pub fn stream(seed: u64, a: u64, b: u64, c: u64) -> Rng64 {
    let k = mix64(mix64(mix64(mix64(seed) ^ a) ^ b) ^ c);
    Rng64::seed_from_u64(k)
}

/// A uniform `f32` in `[0, 1)`.
#[inline]
pub fn uniform(rng: &mut Rng64) -> f32 {
    // 24 random bits: exactly representable, never 1.0.
    (rng.random::<u32>() >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
}

/// A direction about the unit normal `n` with density `cos θ / π` (Malley's method: a uniform
/// point on the unit disc lifted onto the hemisphere).
#[inline]
pub fn cosine_direction(n: Vec3, u1: f32, u2: f32) -> Vec3 {
    let (t, b) = orthonormal_basis(n);
    cosine_direction_in(n, t, b, u1, u2)
}

/// [`cosine_direction`] in a precomputed orthonormal frame `(t, b, n)`; unit length to within
/// rounding.
#[inline]
pub fn cosine_direction_in(n: Vec3, t: Vec3, b: Vec3, u1: f32, u2: f32) -> Vec3 {
    let r = u1.sqrt();
    let phi = std::f32::consts::TAU * u2;
    let (s, c) = phi.sin_cos();
    let z = (1.0 - u1).max(0.0).sqrt();
    t * (r * c) + b * (r * s) + n * z
}

/// Barycentric weights `(1 − s − t, s, t)` of a point uniform over a triangle, from two uniforms.
#[inline]
pub fn uniform_triangle(u1: f32, u2: f32) -> (f32, f32) {
    let su = u1.sqrt();
    (su * (1.0 - u2), su * u2)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cosine_directions_have_the_right_moments() {
        // For the density cos θ/π: E[cos θ] = 2/3 and E[cos² θ] = 1/2.
        let n = Vec3::new(0.2, 0.9, -0.3).normalize();
        let mut rng = stream(7, 0, 0, 0);
        let m = 200_000;
        let (mut s1, mut s2) = (0.0f64, 0.0f64);
        for _ in 0..m {
            let d = cosine_direction(n, uniform(&mut rng), uniform(&mut rng));
            let c = d.dot(n) as f64;
            assert!(c >= -1e-6);
            s1 += c;
            s2 += c * c;
        }
        let (m1, m2) = (s1 / m as f64, s2 / m as f64);
        // Standard errors: sd(cos)=sqrt(1/2-4/9)≈0.236 → 0.236/√m ≈ 5.3e-4; 5σ tolerance.
        assert!(
            (m1 - 2.0 / 3.0).abs() < 5.0 * 0.236 / (m as f64).sqrt(),
            "{m1}"
        );
        assert!((m2 - 0.5).abs() < 5.0 * 0.29 / (m as f64).sqrt(), "{m2}");
    }

    #[test]
    fn streams_differ_and_repeat() {
        let a: Vec<f32> = (0..4).map(|_| uniform(&mut stream(1, 2, 3, 4))).collect();
        let mut r = stream(1, 2, 3, 4);
        let b: Vec<f32> = (0..4).map(|_| uniform(&mut r)).collect();
        assert_eq!(a[0], b[0]);
        let mut r2 = stream(1, 2, 3, 5);
        assert_ne!(uniform(&mut r2), b[0]);
    }
}
