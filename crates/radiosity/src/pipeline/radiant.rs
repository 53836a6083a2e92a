//! Radiant temperature at points, from a solved thermal problem: what a person (or a
//! globe thermometer, or a small plane sensor) at a point exchanges with the surfaces it sees.
//!
//! With every surface grey and diffuse, a surface of radiosity J sends radiance J/π in every
//! direction, and the surroundings seen through openings send σT_e⁴/π. So, at a point x:
//!
//! ```text
//! σ T_mr⁴ = (1/4π) ∫_sphere J(x, ω) dω           mean radiant temperature (ISO 7726, a small sphere)
//! σ T_pr⁴ = (1/π) ∫_{n·ω > 0} J(x, ω) (n·ω) dω     plane radiant temperature of the side facing n
//! sky_view = (1/4π) ∫_sphere [ω reaches no surface] dω
//! ```
//!
//! J(x, ω) being the radiosity of the patch the ray from x along ω hits first (exact
//! visibility, by the BVH), or σT_e⁴ where it hits nothing. For black surfaces J = σT⁴ and the
//! first integral is Σ_i (Ω_i/4π) σT_i⁴, the classical angle-factor form (Fanger 1970).
//!
//! **Estimators.** Both integrals are sampled with stratified jittered directions: the sphere
//! in `k × 2k` cells equal in solid angle (z = cos θ uniform in [−1, 1] times φ uniform), the
//! hemisphere in `m × m` cells of Malley's cosine-weighted map; each cell holds one ray. A
//! piecewise constant J is then estimated with an error that comes only from the cells a
//! surface's outline crosses: of order n^(−3/4) for n rays, against n^(−1/2) for independent
//! rays. A ray that meets the back of a one-sided surface (a point inside a solid) counts as
//! seeing the surroundings and is reported in [`RadiantResult::back_hits`].
//!
//! The streams are keyed by (seed, point): results do not depend on the thread count.

use crate::accel::Bvh;
use crate::geom::{orthonormal_basis, Ray, Vec3};
use crate::lighting::SensorPoint;
use crate::mesh::Mesh;
use crate::sampling::{cosine_direction_in, stream, uniform};
use crate::thermal::STEFAN_BOLTZMANN;
use rayon::prelude::*;

/// How radiant temperatures are sampled.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RadiantParams {
    /// Rays over the sphere per point (rounded to `2k²`, k even, so that the sensor's plane is
    /// a boundary of the cells); as many again over the hemisphere for the plane radiant
    /// temperature (rounded to `m²`).
    pub rays: u32,
    /// Seed of the jitter.
    pub seed: u64,
}

impl Default for RadiantParams {
    fn default() -> Self {
        Self {
            rays: 2048,
            seed: 1,
        }
    }
}

/// Most rays per point.
pub const MAX_RADIANT_RAYS: u32 = 1 << 22;

/// The radiant environment of one point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RadiantPoint {
    /// Mean radiant temperature, K.
    pub mean_radiant_temperature: f64,
    /// Plane radiant temperature of the half-space the point's direction faces, K.
    pub plane_radiant_temperature: f64,
    /// Share of the sphere that reaches no surface (0–1).
    pub sky_view: f64,
}

/// Radiant temperatures at points.
#[derive(Clone, Debug, PartialEq)]
pub struct RadiantResult {
    /// One per point, in order.
    pub points: Vec<RadiantPoint>,
    /// Rays that met the back of a surface (counted as surroundings), over all points.
    pub back_hits: u64,
    /// Rays cast in all.
    pub rays: u64,
}

/// The radiant temperatures at `points` of a scene whose patches (`mesh`, with `bvh` built on
/// it) have radiosities `radiosity` (W/m²), the surroundings being at `environment` K. Errors:
/// a ray count of 0 or past [`MAX_RADIANT_RAYS`], a radiosity array of the wrong length, a
/// negative or non-finite radiosity or environment.
pub fn radiant_temperatures(
    mesh: &Mesh,
    bvh: &Bvh,
    radiosity: &[f64],
    environment: f64,
    points: &[SensorPoint],
    params: RadiantParams,
) -> Result<RadiantResult, String> {
    if params.rays == 0 || params.rays > MAX_RADIANT_RAYS {
        return Err(format!(
            "{} rays per point: give 1 to {MAX_RADIANT_RAYS}",
            params.rays
        ));
    }
    if radiosity.len() != mesh.len() {
        return Err(format!(
            "{} radiosities for {} patches",
            radiosity.len(),
            mesh.len()
        ));
    }
    if !(environment.is_finite() && environment >= 0.0) {
        return Err(format!("environment temperature {environment} K"));
    }
    if let Some(j) = radiosity.iter().find(|j| !(j.is_finite() && **j >= 0.0)) {
        return Err(format!("a patch radiosity of {j} W/m²"));
    }
    // k even: the sensor's plane (z = 0) is a cell boundary.
    let k = 2 * ((params.rays as f64 / 8.0).sqrt().round() as usize).max(1);
    let m = ((params.rays as f64).sqrt().round() as usize).max(1);
    let surroundings = STEFAN_BOLTZMANN * environment.powi(4);
    let offset = bvh.ray_offset();
    let results: Vec<(RadiantPoint, u64)> = points
        .par_iter()
        .enumerate()
        .map(|(i, p)| {
            let mut rng = stream(params.seed, 0x4d52_5400, i as u64, 0);
            let n = Vec3::new(p.normal[0] as f32, p.normal[1] as f32, p.normal[2] as f32)
                .normalize_or_zero();
            let n = if n == Vec3::ZERO { Vec3::Z } else { n };
            let origin = Vec3::new(
                p.position[0] as f32,
                p.position[1] as f32,
                p.position[2] as f32,
            ) + n * offset;
            let (t, b) = orthonormal_basis(n);
            let mut back = 0u64;
            // What a ray along `d` sees: (J, reached a surface).
            let mut look = |d: Vec3| -> (f64, bool) {
                match bvh.closest_hit(&Ray::new(origin, d), f32::INFINITY) {
                    Some(h) if h.front => (radiosity[h.patch as usize], true),
                    Some(_) => {
                        back += 1;
                        (surroundings, true)
                    }
                    None => (surroundings, false),
                }
            };
            // The sphere, k × 2k cells of equal solid angle.
            let (mut sphere, mut open) = (0.0f64, 0usize);
            for a in 0..k {
                for c in 0..2 * k {
                    let z = -1.0 + 2.0 * (a as f32 + uniform(&mut rng)) / k as f32;
                    let phi = std::f32::consts::PI * (c as f32 + uniform(&mut rng)) / k as f32;
                    let r = (1.0 - z * z).max(0.0).sqrt();
                    let (s, co) = phi.sin_cos();
                    let d = t * (r * co) + b * (r * s) + n * z;
                    let (j, hit) = look(d);
                    sphere += j;
                    open += usize::from(!hit);
                }
            }
            let cells = (2 * k * k) as f64;
            // The hemisphere facing n, m × m cells of Malley's map.
            let mut plane = 0.0f64;
            for a in 0..m {
                for c in 0..m {
                    let u1 = (a as f32 + uniform(&mut rng)) / m as f32;
                    let u2 = (c as f32 + uniform(&mut rng)) / m as f32;
                    plane += look(cosine_direction_in(n, t, b, u1, u2)).0;
                }
            }
            let temperature = |j: f64| (j / STEFAN_BOLTZMANN).max(0.0).powf(0.25);
            (
                RadiantPoint {
                    mean_radiant_temperature: temperature(sphere / cells),
                    plane_radiant_temperature: temperature(plane / (m * m) as f64),
                    sky_view: open as f64 / cells,
                },
                back,
            )
        })
        .collect();
    let rays = points.len() as u64 * (2 * k * k + m * m) as u64;
    Ok(RadiantResult {
        back_hits: results.iter().map(|r| r.1).sum(),
        points: results.into_iter().map(|r| r.0).collect(),
        rays,
    })
}

#[cfg(test)]
#[path = "radiant_tests.rs"]
mod tests;
