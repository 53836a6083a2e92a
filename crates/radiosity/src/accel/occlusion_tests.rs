//! Tests of the any-hit queries against the closest hit and brute force.

use super::*;
use crate::geom::Ray;
use crate::mesh::{Mesh, MeshParams};
use crate::sampling::{stream, uniform};

/// The any-hit query agrees with the closest hit on random rays and bounds: something lies
/// on the ray before t_max exactly when the closest hit does.
#[test]
fn occluded_agrees_with_closest_hit() {
    let scene = crate::scene::builtin::by_name("cornell").unwrap();
    let mesh = Mesh::build(&scene, MeshParams::Patches(2000)).unwrap();
    let bvh = Bvh::build(&mesh);
    let mut rng = stream(3, 1, 4, 1);
    let c = bvh.bounds().centre();
    let size = bvh.bounds().diagonal();
    let mut disagree = 0;
    for _ in 0..4_000 {
        let o = c + Vec3::new(
            uniform(&mut rng) - 0.5,
            uniform(&mut rng) - 0.5,
            uniform(&mut rng) - 0.5,
        ) * size
            * 0.4;
        let d = Vec3::new(
            uniform(&mut rng) - 0.5,
            uniform(&mut rng) - 0.5,
            uniform(&mut rng) - 0.5,
        )
        .normalize();
        let t_max = uniform(&mut rng) * size;
        let ray = Ray::new(o, d);
        let closest = bvh
            .closest_hit(&ray, f32::INFINITY)
            .map_or(f32::INFINITY, |h| h.t);
        // Away from the bound (where rounding may decide), the two must agree.
        if (closest - t_max).abs() > 1e-4 * size && bvh.occluded(&ray, t_max) != (closest < t_max) {
            disagree += 1;
        }
        // Looking through nothing is `occluded`; looking through the first patch met
        // leaves whatever lies beyond it (the closest hit of the rest, by brute force).
        if bvh.occluded_except(&ray, t_max, |_| false) != bvh.occluded(&ray, t_max) {
            disagree += 1;
        }
        // Where the any-hit query stops is a real intersection in range: at or beyond the
        // closest one (by brute force), and itself a hit of the ray.
        if let Some(t) = bvh.any_hit_except(&ray, t_max, |_| false) {
            let at = super::tests::brute(&mesh, &Ray::new(o + d * (t - 1e-3 * size), d));
            if t >= t_max || t < closest - 1e-5 * size || at.is_none_or(|(s, _)| s > 2e-3 * size) {
                disagree += 1;
            }
        }
        if let Some(first) = bvh.closest_hit(&ray, f32::INFINITY) {
            let mut rest = mesh.clone();
            rest.patches.remove(first.patch as usize);
            let beyond = super::tests::brute(&rest, &ray).map_or(f32::INFINITY, |(t, _)| t);
            if (beyond - t_max).abs() > 1e-4 * size
                && bvh.occluded_except(&ray, t_max, |p| p == first.patch) != (beyond < t_max)
            {
                disagree += 1;
            }
        }
    }
    assert_eq!(disagree, 0);
}
