//! A baked glTF shown as an unlit glTF viewer shows it: each triangle Gouraud-shaded with its
//! corners' `COLOR_0`, no solving. PNG pixels are then the sRGB encoding of `COLOR_0` (at
//! exposure scale 1), which is how `radiosity view` checks what a baked file looks like
//! elsewhere.

use super::{render, Image, RenderParams};
use crate::accel::Bvh;
use crate::color::Rgb;
use crate::geom::Vec3;
use crate::mesh::{Mesh, MeshParams};
use crate::observe::Observer;
use crate::scene::{Camera, Scene};
use crate::Error;
use std::path::Path;

/// A baked file, ready to show.
#[derive(Debug)]
pub struct BakedView {
    /// The file's scene (one polygon per triangle).
    pub scene: Scene,
    /// One patch per triangle.
    pub mesh: Mesh,
    /// The hierarchy over them.
    pub bvh: Bvh,
    /// The value at each mesh vertex that the renderer shows as radiance (π × COLOR_0).
    pub vertex_values: Vec<Rgb>,
}

impl BakedView {
    /// Read a baked `.glb` or `.gltf` whose primitives all carry `COLOR_0`.
    pub fn load(path: &Path) -> Result<Self, Error> {
        let (scene, colours) = crate::scene::gltf::load_vertex_colours(path)?;
        scene.validate_geometry()?;
        let mesh = Mesh::build(&scene, MeshParams::Faces)?;
        // Each triangle is one patch; give its vertices the colours of the polygon's corners.
        let mut values = vec![Rgb::BLACK; mesh.vertices.len()];
        for p in &mesh.patches {
            let poly = &scene.polygons[p.surface as usize];
            for &v in &p.vertices[..3] {
                let at = mesh.vertices[v as usize];
                let j = poly.vertices.iter().position(|q| *q == at).unwrap_or(0);
                // The renderer shows radiance B/π; scale by π so that pixels are COLOR_0.
                values[v as usize] = colours[p.surface as usize][j] * std::f64::consts::PI;
            }
        }
        let bvh = Bvh::build(&mesh);
        Ok(Self {
            scene,
            mesh,
            bvh,
            vertex_values: values,
        })
    }

    /// The file's own camera, else a view from inside (glTF's +y is up).
    pub fn default_camera(&self) -> Camera {
        self.scene
            .camera
            .unwrap_or_else(|| super::camera::default_camera(&self.bvh, Vec3::Y))
    }

    /// Render the vertex colours from `camera`.
    pub fn render(&self, camera: &Camera, params: &RenderParams, observer: &dyn Observer) -> Image {
        render(
            &self.mesh,
            &self.bvh,
            &self.vertex_values,
            camera,
            params,
            observer,
        )
    }
}
