//! A baked glTF shown as an unlit glTF viewer shows it: each triangle Gouraud-shaded with its
//! corners' `COLOR_0`, no solving. PNG pixels are then the sRGB encoding of `COLOR_0` (at
//! exposure scale 1), which is how `radiosity view` checks what a baked file looks like
//! elsewhere.
//!
//! A **lightmapped** file (materials with `MOZ_lightmap`, [`BakedView::load_lightmap`]) is
//! shown as three.js shows it lit by its lightmap alone: at a point of a triangle, its UVs
//! (the extension's `texCoord` set, usually `TEXCOORD_1`) interpolated from the corners, the
//! texture sampled there (texels decoded from sRGB to linear, then bilinear, with the sampler's
//! wrap modes), and the radiance `L = diffuse · texel · intensity / π`
//! ([`crate::scene::gltf::LightmapSet::radiance`]). `radiosity solve --bake lightmap` writes
//! white matte materials with intensity π and texels `srgb(min(1, B · scale))`, so a pixel
//! shows `min(1, B · scale)`, the same display colour as `COLOR_0` of a vertex bake.

use super::{render, Image, RenderParams};
use crate::accel::Bvh;
use crate::accel::Hit;
use crate::color::Rgb;
use crate::geom::Vec3;
use crate::mesh::{Mesh, MeshParams};
use crate::observe::Observer;
use crate::scene::gltf::{LightmapSet, VertexValues};
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
    /// The value at each mesh vertex that the renderer shows as radiance (π × COLOR_0; black
    /// in a lightmapped view).
    pub vertex_values: Vec<Rgb>,
    /// The lightmaps, for a file read by [`BakedView::load_lightmap`].
    pub lightmap: Option<LightmapView>,
}

/// The lightmaps of a view, per patch.
#[derive(Debug)]
pub struct LightmapView {
    /// The file's lightmaps.
    pub set: LightmapSet,
    /// Per patch (triangle): the lightmap UVs at its three mesh vertices.
    pub uv: Vec<[[f32; 2]; 3]>,
    /// Per patch: its lightmap material (`None`: not lightmapped, shown black).
    pub material: Vec<Option<u32>>,
}

/// The corner of `corners` nearest to `p`.
fn nearest_corner(corners: &[Vec3], p: Vec3) -> usize {
    let mut best = (0, f32::INFINITY);
    for (j, q) in corners.iter().enumerate() {
        let d = q.distance_squared(p);
        if d < best.1 {
            best = (j, d);
        }
    }
    best.0
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
            lightmap: None,
        })
    }

    /// Read a lightmapped `.glb` or `.gltf` (materials with `MOZ_lightmap`, their images
    /// decoded); `None` when no material has one.
    pub fn load_lightmap(path: &Path) -> Result<Option<Self>, Error> {
        let (scene, set) = crate::scene::gltf::load_lightmap(path, false, true)?;
        if set.materials.is_empty() {
            return Ok(None);
        }
        scene.validate_geometry()?;
        let mesh = Mesh::build(&scene, MeshParams::Faces)?;
        let mut uv = Vec::with_capacity(mesh.len());
        let mut material = Vec::with_capacity(mesh.len());
        for p in &mesh.patches {
            let s = p.surface as usize;
            let poly = &scene.polygons[s];
            match (set.uv[s], set.material[s]) {
                (Some(corners), Some(m)) => {
                    uv.push(std::array::from_fn(|k| {
                        corners
                            [nearest_corner(&poly.vertices, mesh.vertices[p.vertices[k] as usize])]
                    }));
                    material.push(Some(m));
                }
                _ => {
                    uv.push([[0.0; 2]; 3]);
                    material.push(None);
                }
            }
        }
        let bvh = Bvh::build(&mesh);
        Ok(Some(Self {
            vertex_values: vec![Rgb::BLACK; mesh.vertices.len()],
            scene,
            mesh,
            bvh,
            lightmap: Some(LightmapView { set, uv, material }),
        }))
    }

    /// The radiance shown at a hit (front or back): the lightmap's for a lightmapped view,
    /// else `COLOR_0` interpolated (at exposure 1, a PNG pixel encodes this value).
    pub fn shown(&self, hit: &Hit) -> Rgb {
        match &self.lightmap {
            Some(l) => match l.material[hit.patch as usize] {
                Some(m) => {
                    let [a, b, c] = l.uv[hit.patch as usize];
                    let (u, v) = (hit.u, hit.v);
                    let w = 1.0 - u - v;
                    let uv = [
                        a[0] * w + b[0] * u + c[0] * v,
                        a[1] * w + b[1] * u + c[1] * v,
                    ];
                    l.set.radiance(m, uv)
                }
                None => Rgb::BLACK,
            },
            None => {
                super::gouraud(&self.mesh, &self.vertex_values, hit) * std::f64::consts::FRAC_1_PI
            }
        }
    }

    /// Triangles with a lightmap (all of them for a file whose every material has one).
    pub fn lightmapped_triangles(&self) -> usize {
        self.lightmap
            .as_ref()
            .map_or(0, |l| l.material.iter().filter(|m| m.is_some()).count())
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

    /// Render the vertex colours (or the lightmaps) from `camera`.
    pub fn render(&self, camera: &Camera, params: &RenderParams, observer: &dyn Observer) -> Image {
        if self.lightmap.is_some() {
            return super::render_with(
                &self.bvh,
                camera,
                params,
                observer,
                1.0,
                |_, hit, _, _, _| self.shown(hit),
            );
        }
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
