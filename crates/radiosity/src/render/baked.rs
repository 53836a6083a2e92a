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
use crate::scene::gltf::VertexValues;
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
        Self::load_values(path, VertexValues::Colour)
    }

    /// Read a baked file's `COLOR_0` (shown as is) or its `_RADIOSITY` (for the final
    /// gather: [`BakedView::render_gather`]).
    pub fn load_values(path: &Path, which: VertexValues) -> Result<Self, Error> {
        let (scene, colours) = crate::scene::gltf::load_vertex_values(path, which)?;
        // Shown as is, COLOR_0 is a radiance times π; the radiosity is used as it is.
        let scale = match which {
            VertexValues::Colour => std::f64::consts::PI,
            VertexValues::Radiosity => 1.0,
        };
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
                values[v as usize] = colours[p.surface as usize][j] * scale;
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

    /// Final gather over the baked radiosity (a file read with [`VertexValues::Radiosity`]):
    /// reflectance and emission from the materials `solve` baked, the indirect light from the
    /// baked `_RADIOSITY` ([`crate::render::gather`]).
    pub fn render_gather(
        &self,
        camera: &Camera,
        params: &RenderParams,
        gather: super::gather::GatherParams,
        observer: &dyn Observer,
    ) -> Image {
        let system = crate::mesh::patch_system(&self.scene, &self.mesh);
        let surfaces = super::light::Surfaces {
            mesh: &self.mesh,
            bvh: &self.bvh,
            reflectance: &system.reflectance,
            emission: &system.emission,
        };
        super::gather::Gather::new(surfaces, &self.vertex_values, gather)
            .render(camera, params, observer)
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
