//! A light tracer: particles shot from the emitters and followed through the scene, each
//! crediting its power to every surface it reaches (the collision estimator of particle
//! tracing, as in Pattanaik & Mudur's particle model of light transport). The power reaching
//! a surface is its irradiance times its area, `H A`, so a surface's mean radiosity is
//! `E + ρ H`. Independent of any radiosity solution and of the path tracer
//! ([`super::path::surface_means`]), which starts from points of the surfaces: a second,
//! differently built reference for surface means.
//!
//! Where the path tracer spends its paths by area, the particles go where the light goes:
//! a bright spot a few centimetres wide on a large wall, which a path tracer finds only with
//! the few paths that start in it, is where most of the wall's particles land. The error of a
//! surface's mean falls as 1/√(particles reaching it), so the area-weighted L1 error over all
//! surfaces is small for the same count of rays.
//!
//! One particle: an emitting patch drawn in proportion to its power ([`Lights`]), a point
//! uniform on it and a cosine-distributed direction; its power is `E A / (p N)` per channel
//! for `N` particles. At the closest surface hit from the front, the power is credited to the
//! surface (and to every coincident twin of the patch hit, which the path tracer lights as
//! the same place); the particle then survives with probability `q = max ρ` (Russian
//! roulette), its power multiplied by `ρ / q`, and leaves in a cosine-distributed direction.
//! A back side absorbs, as one-sided surfaces do in the radiosity system and in the path
//! tracer. No power ever grows, so every credit fits a fixed-point integer: credits are summed
//! as integers (2⁻²⁴ of a particle's starting power), whose sums do not depend on the order
//! of addition, and the result is the same on any number of threads for a fixed seed.
//!
//! Standard errors come from 32 batches of the particles: the spread of the batch totals.

use super::light::{Lights, Surfaces};
use crate::color::Rgb;
use crate::geom::{orthonormal_basis, Ray};
use crate::sampling::{cosine_direction_in, stream, uniform};
use rayon::prelude::*;
use std::sync::atomic::{AtomicU64, Ordering};

/// Batches the particles are split into, for the standard errors.
pub const BATCHES: u64 = 32;

/// Particles a job traces with one random stream.
const CHUNK: u64 = 4096;

/// Fixed-point steps in a particle's largest starting power.
const STEPS: f64 = (1u64 << 24) as f64;

/// Coincident patches (the same corners, to 10⁻⁶ of the scene's size, facing the same way):
/// for each patch, the others of its group.
fn twins(s: &Surfaces<'_>) -> Vec<Vec<u32>> {
    use std::collections::HashMap;
    let mesh = s.mesh;
    let step = crate::geom::coincidence_step(mesh.vertices.iter().copied());
    let mut groups: HashMap<Vec<i64>, Vec<u32>> = HashMap::new();
    for (i, p) in mesh.patches.iter().enumerate() {
        let corners = p
            .vertices
            .iter()
            .filter(|&&v| v != crate::mesh::Patch::NONE)
            .map(|&v| mesh.vertices[v as usize]);
        let key = crate::geom::coincidence_key(corners, p.normal, step);
        groups.entry(key).or_default().push(i as u32);
    }
    let mut out = vec![Vec::new(); mesh.patches.len()];
    for group in groups.values().filter(|g| g.len() > 1) {
        for &p in group {
            out[p as usize] = group.iter().copied().filter(|&o| o != p).collect();
        }
    }
    out
}

/// The mean radiosity of each of `surfaces` surfaces (input polygons; the patches' `surface`
/// indices) and its standard error, from `particles` particles (rounded up to a whole number
/// per batch). Streams are keyed by `(seed, batch, chunk)`.
pub fn surface_means(
    s: &Surfaces<'_>,
    lights: &Lights,
    surfaces: usize,
    particles: u64,
    seed: u64,
) -> Vec<(Rgb, Rgb)> {
    let mesh = s.mesh;
    let mut area = vec![0.0f64; surfaces];
    let mut first = vec![u32::MAX; surfaces];
    for (i, p) in mesh.patches.iter().enumerate() {
        if let Some(a) = area.get_mut(p.surface as usize) {
            *a += p.area as f64;
            let f = &mut first[p.surface as usize];
            if *f == u32::MAX {
                *f = i as u32;
            }
        }
    }
    let per_batch = particles.div_ceil(BATCHES).max(1);
    let n = (per_batch * BATCHES) as f64;
    // The largest power a particle starts with, per channel: the fixed-point scale.
    let start = |j: u32, pdf: f64| {
        s.emission[j as usize] * (mesh.patches[j as usize].area as f64 / (pdf * n))
    };
    let largest = lights
        .emitters()
        .map(|(j, pdf)| start(j, pdf).max_channel())
        .fold(0.0f64, f64::max);
    let mut sum = vec![Rgb::BLACK; surfaces];
    let mut sq = vec![Rgb::BLACK; surfaces];
    if largest <= 0.0 || surfaces == 0 {
        return finish(s, &first, &area, &sum, &sq);
    }
    let unit = largest / STEPS;
    let twins = twins(s);
    let credits: Vec<[AtomicU64; 3]> = (0..surfaces)
        .map(|_| [AtomicU64::new(0), AtomicU64::new(0), AtomicU64::new(0)])
        .collect();
    let credit = |patch: u32, power: Rgb| {
        let v = [power.r, power.g, power.b].map(|c| (c / unit).round() as u64);
        let one = |p: u32| {
            let surface = mesh.patches[p as usize].surface as usize;
            if let Some(c) = credits.get(surface) {
                for (slot, v) in c.iter().zip(v) {
                    if v > 0 {
                        slot.fetch_add(v, Ordering::Relaxed);
                    }
                }
            }
        };
        one(patch);
        for &t in &twins[patch as usize] {
            one(t);
        }
    };
    let offset = s.bvh.ray_offset();
    let chunks = per_batch.div_ceil(CHUNK);
    for batch in 0..BATCHES {
        (0..chunks).into_par_iter().for_each(|chunk| {
            let mut rng = stream(seed, batch, chunk, 0x4c49_4748_5400);
            let count = CHUNK.min(per_batch - chunk * CHUNK);
            for _ in 0..count {
                let Some((mut patch, pdf)) = lights.pick(uniform(&mut rng) as f64) else {
                    return;
                };
                let (u1, u2, u3) = (uniform(&mut rng), uniform(&mut rng), uniform(&mut rng));
                let mut x = mesh.sample_point(patch as usize, u1, u2, u3);
                let mut power = start(patch, pdf);
                loop {
                    let n = mesh.patches[patch as usize].normal;
                    let (t, b) = orthonormal_basis(n);
                    let d = cosine_direction_in(n, t, b, uniform(&mut rng), uniform(&mut rng));
                    let ray = Ray::new(x + n * offset, d);
                    let hit = match s.bvh.closest_hit(&ray, f32::INFINITY) {
                        Some(h) if h.front && h.patch != patch => h,
                        _ => break,
                    };
                    credit(hit.patch, power);
                    let rho = s.reflectance[hit.patch as usize];
                    let q = rho.max_channel().min(1.0);
                    if q <= 0.0 || uniform(&mut rng) as f64 >= q {
                        break;
                    }
                    power = power * rho / q;
                    patch = hit.patch;
                    x = ray.at(hit.t);
                }
            }
        });
        for ((c, s1), s2) in credits.iter().zip(&mut sum).zip(&mut sq) {
            let v = c
                .each_ref()
                .map(|a| a.swap(0, Ordering::Relaxed) as f64 * unit);
            let v = Rgb::new(v[0], v[1], v[2]);
            *s1 += v;
            *s2 += v * v;
        }
    }
    finish(s, &first, &area, &sum, &sq)
}

/// Surface means `E + ρ H` and their standard errors from the batch totals of the power
/// arriving (`sum`, and the sum of squares `sq`, over [`BATCHES`] batches).
fn finish(
    s: &Surfaces<'_>,
    first: &[u32],
    area: &[f64],
    sum: &[Rgb],
    sq: &[Rgb],
) -> Vec<(Rgb, Rgb)> {
    let b = BATCHES as f64;
    (0..first.len())
        .map(|k| {
            if first[k] == u32::MAX || area[k] <= 0.0 {
                return (Rgb::BLACK, Rgb::BLACK);
            }
            let p = first[k] as usize;
            let (e, rho) = (s.emission[p], s.reflectance[p]);
            // The total is the sum of the batches; its variance B times a batch's.
            let var = (sq[k] - sum[k] * sum[k] / b) * (b / (b - 1.0));
            let se = var.map(|v| v.max(0.0).sqrt());
            (e + rho * sum[k] / area[k], rho * se / area[k])
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::light::tests::Fixture;
    use crate::scene::builtin;

    fn means(scene: &crate::scene::Scene, particles: u64, seed: u64) -> Vec<(Rgb, Rgb)> {
        let f = Fixture::new(scene, 1);
        let surfaces = scene.polygons.len();
        surface_means(&f.surfaces(), &f.lights(), surfaces, particles, seed)
    }

    /// The furnace (a closed box whose every surface emits E and reflects ρ, with a floating
    /// block inside): B = E/(1 − ρ) on every surface, within 4 standard errors (+ 0.1 % for
    /// the rays that slip through edges), and the standard errors themselves of the size
    /// 1/√n predicts.
    #[test]
    fn furnace_is_uniform() {
        let scene = builtin::furnace();
        let out = means(&scene, 400_000, 1);
        let m = &scene.materials[scene.polygons[0].material];
        let exact = m.emission.g / (1.0 - m.reflectance.g);
        for (k, (b, se)) in out.iter().enumerate() {
            assert!(
                se.g > 0.0 && se.g < 0.02 * exact,
                "surface {k}: se {}",
                se.g
            );
            assert!(
                (b.g - exact).abs() < 4.0 * se.g + 1e-3 * exact,
                "surface {k}: {} ± {} against {exact}",
                b.g,
                se.g
            );
        }
    }

    /// A unit square lamp (ρ = 0) facing a grey square of the same size 0.8 away, and
    /// nothing else: the grey square's mean radiosity is ρ E F with F Howell's C-11 for
    /// directly opposed parallel squares, within 4 standard errors.
    #[test]
    fn opposed_squares_match_howell() {
        let (e, rho, c) = (10.0, 0.5, 0.8f32);
        let v = crate::geom::Vec3::new;
        let square = |y: f32, up: bool, material: usize| {
            let mut vertices = vec![
                v(0.0, y, 0.0),
                v(1.0, y, 0.0),
                v(1.0, y, 1.0),
                v(0.0, y, 1.0),
            ];
            if !up {
                vertices.reverse();
            }
            crate::scene::Polygon {
                vertices,
                material,
                line: 0,
                group: 0,
            }
        };
        let scene = crate::scene::Scene {
            name: "two squares".into(),
            materials: vec![
                crate::scene::Material::emitter("lamp", Rgb::BLACK, Rgb::splat(e)),
                crate::scene::Material::diffuse("grey", Rgb::splat(rho)),
            ],
            polygons: vec![square(c, true, 0), square(0.0, false, 1)],
            ..Default::default()
        };
        let out = means(&scene, 400_000, 3);
        let exact =
            rho * e * crate::formfactor::closed_form::parallel_rectangles(1.0, 1.0, c as f64);
        let (b, se) = out[1];
        assert!(se.g > 0.0 && se.g < 0.01 * exact, "se {}", se.g);
        assert!(
            (b.g - exact).abs() < 4.0 * se.g,
            "{} ± {} against {exact}",
            b.g,
            se.g
        );
        assert_eq!(out[0].0, Rgb::splat(e), "the lamp reflects nothing");
    }

    /// The same seed gives the same means on one thread as on several.
    #[test]
    fn results_do_not_depend_on_the_thread_count() {
        let scene = builtin::cornell();
        let run = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| means(&scene, 100_000, 9))
        };
        assert_eq!(run(1), run(3));
    }
}
