//! A brute-force path tracer for the same diffuse scenes: the reference every picture and test
//! can be compared against, computed without any radiosity solution.
//!
//! The radiance leaving a Lambertian point x is `L(x) = E(x)/π + ρ(x)/π ∫ L_in cos θ dω`
//! (the rendering equation for diffuse surfaces, whose patch-averaged form is the radiosity
//! equation of Szirmay-Kalos & Márton 1995, eq. 1). Each path starts at the camera and at
//! every vertex adds the direct light by next-event estimation (a point on an emitter and a
//! shadow ray, [`super::light`]); it continues in a cosine-distributed direction, so the
//! throughput is multiplied by ρ alone; emission met by a continuation ray is not counted again
//! (next-event estimation already has it). From the third bounce Russian roulette ends a path
//! with probability 1 − min(max ρ-throughput, 0.95) and reweights the survivors: unbiased, with
//! no depth limit. Back sides absorb, as one-sided surfaces do in the radiosity system.

use super::light::{Lights, Surfaces};
use super::{render_with, Image, RenderParams};
use crate::accel::Hit;
use crate::color::Rgb;
use crate::geom::{orthonormal_basis, Ray, Vec3};
use crate::observe::Observer;
use crate::sampling::{cosine_direction_in, uniform, Rng64};
use crate::scene::Camera;

/// Bounces after which Russian roulette starts.
pub const ROULETTE_AFTER: u32 = 3;

/// Radiance leaving the hit point `hit` of `ray` towards the ray's origin, one path.
pub fn radiance(s: &Surfaces<'_>, lights: &Lights, ray: &Ray, hit: &Hit, rng: &mut Rng64) -> Rgb {
    let inv_pi = std::f64::consts::FRAC_1_PI;
    let mut patch = hit.patch;
    let mut x = ray.at(hit.t);
    let mut l = s.emission[patch as usize] * inv_pi;
    let mut beta = Rgb::splat(1.0);
    let offset = s.bvh.ray_offset();
    let mut bounce = 0;
    loop {
        let rho = s.reflectance[patch as usize];
        if rho.max_channel() <= 0.0 {
            break;
        }
        let n = s.mesh.patches[patch as usize].normal;
        l += beta * rho * lights.irradiance(s, x, n, patch, rng) * inv_pi;
        beta = beta * rho;
        bounce += 1;
        if bounce >= ROULETTE_AFTER {
            let q = beta.max_channel().min(0.95);
            if (uniform(rng) as f64) >= q {
                break;
            }
            beta = beta / q;
        }
        let (t, b) = orthonormal_basis(n);
        let d = cosine_direction_in(n, t, b, uniform(rng), uniform(rng));
        let next = Ray::new(x + n * offset, d);
        match s.bvh.closest_hit(&next, f32::INFINITY) {
            Some(h) if h.front && h.patch != patch => {
                patch = h.patch;
                x = next.at(h.t);
            }
            _ => break,
        }
    }
    l
}

/// Render by path tracing, `params.samples_per_pixel` paths a pixel.
pub fn render(
    s: &Surfaces<'_>,
    camera: &Camera,
    params: &RenderParams,
    observer: &dyn Observer,
) -> Image {
    let lights = Lights::new(s.mesh, s.emission);
    render_with(
        s.bvh,
        camera,
        params,
        observer,
        1.0,
        |ray, hit, _, _, rng| radiance(s, &lights, ray, hit, rng),
    )
}

/// Radiosity at point `x` (normal `n`, on `patch`) estimated with `paths` paths: the emission
/// plus π times the reflected radiance, with its standard error per channel. For comparing
/// a radiosity solution's surface means against paths that know nothing of it.
pub fn radiosity_at(
    s: &Surfaces<'_>,
    lights: &Lights,
    x: Vec3,
    n: Vec3,
    patch: u32,
    paths: u32,
    rng: &mut Rng64,
) -> (Rgb, Rgb) {
    let (ray, hit) = super::arriving(x, n, patch);
    let (mut sum, mut sq) = (Rgb::BLACK, Rgb::BLACK);
    for _ in 0..paths {
        let v = radiance(s, lights, &ray, &hit, rng) * std::f64::consts::PI;
        sum += v;
        sq += v * v;
    }
    let k = paths.max(1) as f64;
    let mean = sum / k;
    let var = (sq / k - mean * mean) / (k - 1.0).max(1.0);
    let se = Rgb::new(
        var.r.max(0.0).sqrt(),
        var.g.max(0.0).sqrt(),
        var.b.max(0.0).sqrt(),
    );
    (mean, se)
}

/// The area-weighted mean radiosity of each surface (input polygon) and its standard error,
/// by one path from each of `samples[k]` points drawn uniformly over surface `k`. Independent
/// of any radiosity solution: the reference that solutions' surface means are measured
/// against. A point that another surface covers (one lies within eight ray offsets in front of
/// it: a panel flush on a wall, the floor under a box) receives nothing, and its radiosity is
/// its emission: a path started a ray offset above it would pass the cover and see the room.
/// A coincident twin (in the point's own plane) does not cover it. Points come in chunks of
/// 4,096 with streams keyed by `(seed, surface, chunk)`, so the result does not depend on the
/// thread count.
pub fn surface_means(
    s: &Surfaces<'_>,
    lights: &Lights,
    samples: &[u64],
    seed: u64,
) -> Vec<(Rgb, Rgb)> {
    use rayon::prelude::*;
    let surfaces = samples.len();
    // The patches of each surface with their cumulative areas.
    let mut patches: Vec<Vec<usize>> = vec![Vec::new(); surfaces];
    for (i, p) in s.mesh.patches.iter().enumerate() {
        if let Some(v) = patches.get_mut(p.surface as usize) {
            v.push(i);
        }
    }
    const CHUNK: u64 = 4096;
    let jobs: Vec<(usize, u64)> = (0..surfaces)
        .flat_map(|k| (0..samples[k].div_ceil(CHUNK)).map(move |c| (k, c)))
        .collect();
    let sums: Vec<(usize, Rgb, Rgb, u64)> = jobs
        .par_iter()
        .map(|&(k, c)| {
            let list = &patches[k];
            let mut rng = crate::sampling::stream(seed, k as u64, c, 0x5355_5246);
            let (mut s1, mut s2) = (Rgb::BLACK, Rgb::BLACK);
            let n = CHUNK.min(samples[k] - c * CHUNK);
            if list.is_empty() {
                return (k, s1, s2, 0);
            }
            let total: f64 = list.iter().map(|&i| s.mesh.patches[i].area as f64).sum();
            for _ in 0..n {
                let mut u = uniform(&mut rng) as f64 * total;
                let mut i = list[list.len() - 1];
                for &j in list {
                    let a = s.mesh.patches[j].area as f64;
                    if u < a {
                        i = j;
                        break;
                    }
                    u -= a;
                }
                let (u1, u2, u3) = (uniform(&mut rng), uniform(&mut rng), uniform(&mut rng));
                let x = s.mesh.sample_point(i, u1, u2, u3);
                let nrm = s.mesh.patches[i].normal;
                let off = s.bvh.ray_offset();
                let probe = Ray::new(x + nrm * (0.25 * off), nrm);
                let b = if s.bvh.closest_hit(&probe, 8.0 * off).is_some() {
                    s.emission[i]
                } else {
                    radiosity_at(s, lights, x, nrm, i as u32, 1, &mut rng).0
                };
                s1 += b;
                s2 += b * b;
            }
            (k, s1, s2, n)
        })
        .collect();
    let mut acc = vec![(Rgb::BLACK, Rgb::BLACK, 0u64); surfaces];
    for (k, s1, s2, n) in sums {
        acc[k].0 += s1;
        acc[k].1 += s2;
        acc[k].2 += n;
    }
    acc.into_iter()
        .map(|(s1, s2, n)| {
            if n == 0 {
                return (Rgb::BLACK, Rgb::BLACK);
            }
            let m = n as f64;
            let mean = s1 / m;
            let var = (s2 / m - mean * mean) / (m - 1.0).max(1.0);
            (mean, var.map(|v| v.max(0.0).sqrt()))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::light::tests::{corner_factor, lamp_over_floor, Fixture};
    use crate::sampling::stream;

    /// The furnace (every surface emits E and reflects ρ, closed): B = E/(1 − ρ) everywhere.
    /// The path tracer's estimate at points of the box and the block is within 4 standard
    /// errors of it (each from 4,000 paths).
    #[test]
    fn path_tracer_matches_the_furnace() {
        let f = Fixture::new(&crate::scene::builtin::furnace(), 600);
        let (s, lights) = (f.surfaces(), f.lights());
        let rho = crate::scene::builtin::FURNACE_REFLECTANCE;
        let e = crate::scene::builtin::FURNACE_EMISSION;
        let exact = e.g / (1.0 - rho.g);
        let mut rng = stream(5, 0, 0, 0);
        for i in (0..f.mesh.len()).step_by(97) {
            let p = &f.mesh.patches[i];
            let (b, se) = radiosity_at(&s, &lights, p.centre, p.normal, i as u32, 4000, &mut rng);
            assert!(
                (b.g - exact).abs() < 4.0 * se.g + 1e-9,
                "patch {i}: {} vs {exact} ± {}",
                b.g,
                se.g
            );
        }
    }

    /// A lamp over an open floor: the floor's radiance under the lamp is ρ/π · E · F exactly
    /// (its light escapes or meets the black lamp).
    #[test]
    fn path_tracer_matches_the_lamp_closed_form() {
        let f = Fixture::new(&lamp_over_floor(1.0, 0.8, 10.0, 0.5), 400);
        let (s, lights) = (f.surfaces(), f.lights());
        let exact = 0.5 * 10.0 * 4.0 * corner_factor(0.5, 0.5, 0.8);
        let mut rng = stream(6, 0, 0, 0);
        let (b, se) = radiosity_at(
            &s,
            &lights,
            Vec3::ZERO,
            Vec3::Y,
            f.floor(),
            100_000,
            &mut rng,
        );
        assert!(
            (b.g - exact).abs() < 4.0 * se.g,
            "{} vs {exact} ± {}",
            b.g,
            se.g
        );
    }
}
