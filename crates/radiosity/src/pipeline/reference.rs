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
    Ok(trace(&surfaces, &lights))
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
