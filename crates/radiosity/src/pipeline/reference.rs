//! The independent references: a path-traced picture and traced surface means, made without
//! any radiosity solution.

use crate::accel::Bvh;
use crate::color::Rgb;
use crate::mesh::{patch_system, Mesh, MeshParams};
use crate::observe::Observer;
use crate::render::{Image, RenderParams};
use crate::scene::{Camera, Scene};
use crate::Error;

/// Path-traced mean radiosity of every surface (input polygon) of `scene`, with its standard
/// error ([`crate::render::path::surface_means`]): `samples` paths in all, shared among the
/// surfaces in proportion to their area (at least 64 each). The independent reference that
/// solutions' surface means are measured against.
pub fn path_surface_means(
    scene: &Scene,
    samples: u64,
    seed: u64,
) -> Result<Vec<(Rgb, Rgb)>, Error> {
    traced_means(scene, |surfaces, lights| {
        let mut area = vec![0.0f64; scene.polygons.len()];
        for p in &surfaces.mesh.patches {
            area[p.surface as usize] += p.area as f64;
        }
        let total: f64 = area.iter().sum();
        let counts: Vec<u64> = area
            .iter()
            .map(|a| ((samples as f64 * a / total).round() as u64).max(64))
            .collect();
        crate::render::path::surface_means(surfaces, lights, &counts, seed)
    })
}

/// Light-traced mean radiosity of every surface (input polygon) of `scene`, with its standard
/// error ([`crate::render::particle::surface_means`]): `particles` particles shot from the
/// emitters. The second independent reference beside [`path_surface_means`]; it spends its
/// rays where the light goes, which suits scenes whose lamps throw small bright spots.
pub fn light_surface_means(
    scene: &Scene,
    particles: u64,
    seed: u64,
) -> Result<Vec<(Rgb, Rgb)>, Error> {
    traced_means(scene, |surfaces, lights| {
        crate::render::particle::surface_means(
            surfaces,
            lights,
            scene.polygons.len(),
            particles,
            seed,
        )
    })
}

/// `scene` validated, meshed one patch a face with its hierarchy and materials, handed to a
/// tracer of surface means.
fn traced_means(
    scene: &Scene,
    trace: impl FnOnce(
        &crate::render::light::Surfaces<'_>,
        &crate::render::light::Lights,
    ) -> Vec<(Rgb, Rgb)>,
) -> Result<Vec<(Rgb, Rgb)>, Error> {
    scene.validate()?;
    let mesh = Mesh::build(scene, MeshParams::Faces)?;
    let bvh = Bvh::build(&mesh);
    let system = patch_system(scene, &mesh);
    let surfaces = crate::render::light::Surfaces {
        mesh: &mesh,
        bvh: &bvh,
        reflectance: &system.reflectance,
        emission: &system.emission,
    };
    let lights = crate::render::light::Lights::new(&mesh, &system.emission);
    let mut means = trace(&surfaces, &lights);
    // A coincident copy is its group's surface ([`crate::mesh::Coincidence`]).
    for i in 0..means.len() {
        let r = mesh.coincident.representative(i);
        if r != i && r < means.len() {
            means[i] = means[r];
        }
    }
    Ok(means)
}

/// Path-trace `scene` ([`crate::render::path`]): no radiosity solution, one patch per planar
/// piece of each face (the finest geometry the scene has; shading does not depend on it).
pub fn path_trace(
    scene: &Scene,
    camera: &Camera,
    params: &RenderParams,
    observer: &dyn Observer,
) -> Result<Image, Error> {
    scene.validate()?;
    let mesh = Mesh::build(scene, crate::mesh::MeshParams::Faces)?;
    let bvh = Bvh::build(&mesh);
    let system = patch_system(scene, &mesh);
    let surfaces = crate::render::light::Surfaces {
        mesh: &mesh,
        bvh: &bvh,
        reflectance: &system.reflectance,
        emission: &system.emission,
    };
    Ok(crate::render::path::render(
        &surfaces, camera, params, observer,
    ))
}

/// The references against the solutions the pipeline makes, and against each other.
#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::Vec3;
    use crate::pipeline::{solve, Settings, Uniform};
    use crate::render::light::Lights;
    use crate::render::path::*;
    use crate::sampling::stream;
    use crate::scene::builtin;

    /// Surface means see covers and twins as the radiosity methods do: a panel lying flush on
    /// half of the floor under a lamp (2.5 ray offsets above it) leaves the floor half its
    /// light (the lamp is black, so nothing the panel reflects comes back, and the lamp lights
    /// both halves alike); a coincident copy of the floor does not cover it, and both copies
    /// get the floor's light. Each within four standard errors.
    #[test]
    fn covered_points_receive_nothing_and_twins_do_not_cover() {
        use crate::render::light::tests::lamp_over_floor;
        use crate::scene::Polygon;
        let paths = 400_000;
        let plain = lamp_over_floor(1.0, 0.8, 10.0, 0.5);
        let base = crate::pipeline::path_surface_means(&plain, paths, 3).unwrap()[1];
        let v = Vec3::new;
        let f = 20.0;
        let mut panel = plain.clone();
        panel.polygons.push(Polygon {
            vertices: vec![
                v(-f, 2e-4, -f),
                v(-f, 2e-4, f),
                v(0.0, 2e-4, f),
                v(0.0, 2e-4, -f),
            ],
            material: 1,
            line: 0,
            group: 0,
        });
        let half = crate::pipeline::path_surface_means(&panel, paths, 4).unwrap()[1];
        let se = (base.1.g * base.1.g * 0.25 + half.1.g * half.1.g).sqrt();
        assert!(
            (half.0.g - 0.5 * base.0.g).abs() < 4.0 * se,
            "half covered {} vs {} ± {se}",
            half.0.g,
            0.5 * base.0.g
        );
        let mut twins = plain.clone();
        twins.polygons.push(plain.polygons[1].clone());
        let means = crate::pipeline::path_surface_means(&twins, paths, 5).unwrap();
        for (k, m) in [(1, means[1]), (2, means[2])] {
            let se = (base.1.g * base.1.g + m.1.g * m.1.g).sqrt();
            assert!(
                (m.0.g - base.0.g).abs() < 4.0 * se,
                "twin {k}: {} vs {} ± {se}",
                m.0.g,
                base.0.g
            );
        }
    }

    /// The path tracer against a radiosity solution of the bright cube (ρ ≈ 0.8, emitters on
    /// the ceiling): the area-weighted mean radiosity of each input polygon. The path tracer's
    /// mean over 3,000 uniform points of the polygon (16 paths each) has its standard error
    /// from the sample; the solution (10,000 patches, solved to 1e-4 unshot) carries mesh and
    /// Monte Carlo error of its own: its polygon means move by up to 2.2 % between 2,500 and
    /// 10,000 patches (0.02–0.3 % on the large faces). Tolerance: 4 standard errors plus 3 %.
    #[test]
    fn path_tracer_matches_the_solution_per_surface() {
        let scene = crate::scene::builtin::by_name("cube-bright").unwrap();
        let mut u = Uniform::default();
        u.params.tolerance = 1e-4;
        let settings = Settings::from(u);
        let sol = solve(&scene, &settings, &crate::observe::Silent).unwrap();
        let s = sol.surfaces();
        let lights = Lights::new(&sol.mesh, &sol.system.emission);
        let mut rng = stream(9, 0, 0, 0);
        for (k, poly) in scene.polygons.iter().enumerate() {
            if scene.materials[poly.material].emission.max_channel() > 0.0 {
                continue;
            }
            let patches: Vec<usize> = (0..sol.mesh.len())
                .filter(|&i| sol.mesh.patches[i].surface == k as u32)
                .collect();
            let area: f64 = patches
                .iter()
                .map(|&i| sol.mesh.patches[i].area as f64)
                .sum();
            let solved: f64 = patches
                .iter()
                .map(|&i| sol.radiosity[i].g * sol.mesh.patches[i].area as f64)
                .sum::<f64>()
                / area;
            // Uniform points over the polygon: a patch by area, then a point on it.
            let cdf: Vec<f64> = patches
                .iter()
                .scan(0.0, |acc, &i| {
                    *acc += sol.mesh.patches[i].area as f64 / area;
                    Some(*acc)
                })
                .collect();
            let (mut s1, mut s2) = (0.0, 0.0);
            let m = 3000;
            for _ in 0..m {
                let u = crate::sampling::uniform(&mut rng) as f64;
                let i = patches[cdf.partition_point(|&c| c <= u).min(patches.len() - 1)];
                let (u1, u2, u3) = (
                    crate::sampling::uniform(&mut rng),
                    crate::sampling::uniform(&mut rng),
                    crate::sampling::uniform(&mut rng),
                );
                let x = sol.mesh.sample_point(i, u1, u2, u3);
                let n = sol.mesh.patches[i].normal;
                let (b, _) = radiosity_at(&s, &lights, x, n, i as u32, 16, &mut rng);
                s1 += b.g;
                s2 += b.g * b.g;
            }
            let mean = s1 / m as f64;
            let se = ((s2 / m as f64 - mean * mean).max(0.0) / m as f64).sqrt();
            assert!(
                (mean - solved).abs() < 4.0 * se + 0.03 * solved,
                "polygon {k}: path {mean:.5} ± {se:.5}, radiosity {solved:.5}"
            );
        }
    }

    /// Two independent tracers agree: on the Cornell box every surface's mean from the light
    /// tracer (1M particles) and from the path tracer (4M paths, spread by area) within 4
    /// standard errors of their difference + 0.3 %.
    #[test]
    fn light_and_path_tracers_agree_on_the_cornell_box() {
        let scene = builtin::cornell();
        let light = light_surface_means(&scene, 1_000_000, 4).unwrap();
        let path = path_surface_means(&scene, 4_000_000, 5).unwrap();
        for (k, ((bl, sl), (bp, sp))) in light.iter().zip(&path).enumerate() {
            let sigma = (sl.g * sl.g + sp.g * sp.g).sqrt();
            assert!(
                (bl.g - bp.g).abs() < 4.0 * sigma + 3e-3 * bp.g,
                "surface {k}: light {} ± {}, path {} ± {}",
                bl.g,
                sl.g,
                bp.g,
                sp.g
            );
        }
    }
}
