//! Plain scene data: planar polygons with a diffuse material, an optional camera, and the
//! loaders and built-in scenes that produce them.
//!
//! **Units.** Lengths are in the scene's own unit (the Cornell box is in millimetres, the built-in
//! cubes in metres, OBJ files in whatever their author used); nothing in the engine depends on it
//! except the absolute size of areas in the output. Emission `E` is radiant exitance, power per
//! unit area leaving a surface by emission, in W/m² (or W per square scene unit: radiosity is
//! linear in `E`, so only ratios matter for pictures). Radiosity `B` has the same unit as `E`; the
//! radiance of a Lambertian surface is `B/π`. Reflectance `ρ` is the diffuse albedo, in `[0, 1)`.

pub mod builtin;
pub mod gltf;
pub mod gltf_lights;
pub mod mgf;
pub mod obj;
pub mod ply;
pub mod spectrum;
pub mod vs3;

use crate::color::Rgb;
use crate::geom::{Aabb, Vec3};
use crate::io::FileFormat;
use crate::loc::{FileLoc, Item};
use std::path::{Path, PathBuf};

/// A diffuse material: reflectance and emission per colour channel.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    /// Name (from the MTL file or the built-in scene).
    pub name: String,
    /// Diffuse reflectance ρ per channel, each in `[0, 1)`.
    pub reflectance: Rgb,
    /// Emitted radiant exitance E per channel, W/m² (≥ 0).
    pub emission: Rgb,
    /// Glazing: the normal transmittance of a clear pane (MTL `Tf`/`d`, glTF
    /// `KHR_materials_transmission`); 0 for an opaque surface. Daylight
    /// ([`crate::lighting::glazing`]) lets light through such a surface with the pane's angular
    /// dependence; the other calculations treat it as opaque.
    pub transmittance: f64,
    /// The pane's refractive index where the file gives one (glTF `KHR_materials_ior`);
    /// `None`: soda-lime glass, 1.52.
    pub ior: Option<f64>,
}

impl Material {
    /// A material that reflects but does not emit.
    pub fn diffuse(name: &str, reflectance: Rgb) -> Self {
        Self {
            name: name.to_string(),
            reflectance,
            emission: Rgb::BLACK,
            transmittance: 0.0,
            ior: None,
        }
    }

    /// A material that emits `emission` and reflects `reflectance`.
    pub fn emitter(name: &str, reflectance: Rgb, emission: Rgb) -> Self {
        Self {
            name: name.to_string(),
            reflectance,
            emission,
            transmittance: 0.0,
            ior: None,
        }
    }
}

/// A planar polygon. Its front side, the side that reflects and emits, is the one from which the
/// vertices are seen counter-clockwise (right-hand rule: normal = (v1 − v0) × (v2 − v0) for a
/// triangle).
#[derive(Clone, Debug, PartialEq)]
pub struct Polygon {
    /// Vertices in order (at least three).
    pub vertices: Vec<Vec3>,
    /// Index into [`Scene::materials`].
    pub material: usize,
    /// Line of the scene file that defined it (0 for built-in scenes), for error messages.
    pub line: u32,
    /// Smoothing group. Polygons with the same non-zero group form one smooth surface: where
    /// they meet at a shared vertex with normals less than [`CREASE_ANGLE_DEG`] apart, radiosity
    /// is interpolated across the edge. Group 0 means the polygon is a surface of its own, with
    /// hard edges all round. Triangle-mesh formats (glTF, PLY) give each mesh its own group, so
    /// that the triangles of a wall shade as one wall.
    pub group: u32,
}

/// Largest angle between the normals of two polygons of one smoothing group at which radiosity
/// is still interpolated across their common edge (Blender's default auto-smooth angle).
pub const CREASE_ANGLE_DEG: f32 = 30.0;

/// A pinhole camera.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Eye point.
    pub eye: Vec3,
    /// Point looked at.
    pub target: Vec3,
    /// Up direction (need not be orthogonal to the view direction).
    pub up: Vec3,
    /// Vertical field of view in degrees, in `(0, 180)`.
    pub fov_y_deg: f32,
}

impl Camera {
    /// A camera that frames the bounds `b` from the front (+z side), slightly above, looking at
    /// the centre, with a 45° vertical field of view.
    pub fn framing(b: &Aabb) -> Self {
        let centre = b.centre();
        let radius = (b.diagonal() * 0.5).max(1e-3);
        let fov = 45.0f32;
        let dir = Vec3::new(0.25, 0.35, 1.0).normalize();
        let dist = radius / (fov.to_radians() * 0.5).sin() * 1.05;
        Self {
            eye: centre + dir * dist,
            target: centre,
            up: Vec3::Y,
            fov_y_deg: fov,
        }
    }

    /// Check the camera is usable: finite, eye ≠ target, up not parallel to the view, fov in range.
    pub fn validate(&self) -> Result<(), String> {
        let finite = self.eye.is_finite() && self.target.is_finite() && self.up.is_finite();
        if !finite {
            return Err("camera has a non-finite coordinate".into());
        }
        let view = self.target - self.eye;
        if view.length() <= 0.0 {
            return Err("camera eye and target coincide".into());
        }
        if view.normalize().cross(self.up).length() < 1e-6 {
            return Err("camera up vector is parallel to the view direction".into());
        }
        if !(self.fov_y_deg > 0.0 && self.fov_y_deg < 180.0) {
            return Err(format!(
                "camera field of view {}° is outside (0, 180)",
                self.fov_y_deg
            ));
        }
        Ok(())
    }
}

/// A scene: polygons, their materials, and optionally a camera.
#[derive(Clone, Debug, Default)]
pub struct Scene {
    /// Name shown in reports (built-in name or file stem).
    pub name: String,
    /// File the scene was read from, if any (for error messages).
    pub source: Option<PathBuf>,
    /// Materials referenced by the polygons.
    pub materials: Vec<Material>,
    /// The geometry.
    pub polygons: Vec<Polygon>,
    /// The scene's own camera, if it defines one.
    pub camera: Option<Camera>,
    /// Non-fatal remarks from loading (ignored statements, defaults applied).
    pub warnings: Vec<String>,
    /// For scenes read from several files (MGF includes): `(first polygon, file)` runs, in
    /// polygon order; polygon `i` came from the file of the last run starting at or before `i`.
    /// Empty when every polygon came from [`Scene::source`].
    pub origins: Vec<(usize, PathBuf)>,
    /// The scene's vertical direction when its format defines one (MGF: +z); a scene without a
    /// camera is then viewed from inside when it is an interior
    /// ([`crate::render::camera::default_camera`]).
    pub up: Option<Vec3>,
}

/// Most vertices of one polygon: triangulating a non-convex polygon costs O(n²), so a polygon
/// past this is refused rather than left to run for hours.
pub const MAX_POLYGON_VERTICES: usize = 4096;

/// Why a scene could not be loaded or is not fit to solve.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// A file could not be read (the operating system's reason is the error's source).
    #[error("cannot read {}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating system's reason.
        source: std::io::Error,
    },
    /// A problem at a known place (`file:line`, or a polygon of a built-in scene).
    #[error("{at}: {message}")]
    Invalid {
        /// Where.
        at: FileLoc,
        /// What is wrong.
        message: String,
    },
    /// A scene name that is neither a built-in scene nor an existing file.
    #[error("'{0}' is neither a built-in scene ({list}) nor a readable file", list = builtin::NAMES.join(", "))]
    Unknown(String),
}

impl Scene {
    /// A scene named `name` of `polygons` (vertex lists, counter-clockwise seen from the
    /// front), all of `material`: for tests, benchmarks and programs that build geometry.
    pub fn of_polygons(name: &str, material: Material, polygons: Vec<Vec<Vec3>>) -> Scene {
        Scene {
            name: name.into(),
            materials: vec![material],
            polygons: polygons
                .into_iter()
                .map(|vertices| Polygon {
                    vertices,
                    material: 0,
                    line: 0,
                    group: 0,
                })
                .collect(),
            ..Scene::default()
        }
    }

    /// Where polygon `i` came from, for messages: `file:line` or `scene 'name' polygon i`.
    pub fn place_of(&self, i: usize) -> FileLoc {
        let run = self.origins.partition_point(|(start, _)| *start <= i);
        let source = match run {
            0 => self.source.as_ref(),
            r => Some(&self.origins[r - 1].1),
        };
        match (source, self.polygons.get(i)) {
            (Some(path), Some(p)) if p.line > 0 => FileLoc::line(path, p.line as usize),
            (Some(path), _) => FileLoc::file(path).with_item(Item::Polygon(i)),
            (None, _) => FileLoc::scene(&self.name).with_item(Item::Polygon(i)),
        }
    }

    /// Where the scene as a whole came from.
    pub fn place(&self) -> FileLoc {
        match &self.source {
            Some(p) => FileLoc::file(p),
            None => FileLoc::scene(&self.name),
        }
    }

    /// `self` with a warning when it has coincident polygons ([`crate::mesh::Coincidence`]):
    /// the mesher merges them, and the user is told how many.
    pub fn with_coincidence_noted(mut self) -> Scene {
        if let Some(w) = crate::mesh::Coincidence::find(&self).warning() {
            self.warnings.push(format!("{}: {w}", self.place()));
        }
        self
    }

    /// Bounds of all vertices.
    pub fn bounds(&self) -> Aabb {
        Aabb::from_points(self.polygons.iter().flat_map(|p| p.vertices.iter()))
    }

    /// Total area of the polygons (each as a fan of triangles; exact for planar polygons).
    pub fn total_area(&self) -> f64 {
        self.polygons
            .iter()
            .map(|p| polygon_area(&p.vertices))
            .sum()
    }

    /// Total emitted power Σ E·A per channel.
    pub fn emitted_power(&self) -> Rgb {
        self.polygons
            .iter()
            .map(|p| self.materials[p.material].emission * polygon_area(&p.vertices))
            .sum()
    }

    /// The camera to use: the scene's own, or one that frames its bounds.
    pub fn camera_or_default(&self) -> Camera {
        self.camera
            .unwrap_or_else(|| Camera::framing(&self.bounds()))
    }

    /// Check what every stage relies on: materials physical (ρ in `[0, 1)`, E ≥ 0, all
    /// finite), polygons with at least three finite vertices and non-zero area, valid material
    /// indices, a valid camera. Enough for view factors; solving also needs a light
    /// ([`Scene::validate`]).
    pub fn validate_geometry(&self) -> Result<(), SceneError> {
        let bad = |at: FileLoc, message: String| SceneError::Invalid { at, message };
        for m in &self.materials {
            let place = || self.place().with_item(Item::Material(m.name.clone()));
            let rho = m.reflectance;
            if !rho.is_finite() || rho.min_channel() < 0.0 || rho.max_channel() >= 1.0 {
                return Err(bad(
                    place(),
                    format!("reflectance {rho} must have every channel in [0, 1)"),
                ));
            }
            if !m.emission.is_finite() || m.emission.min_channel() < 0.0 {
                return Err(bad(
                    place(),
                    format!("emission {} must be finite and non-negative", m.emission),
                ));
            }
        }
        if self.polygons.is_empty() {
            return Err(bad(self.place(), "the scene has no polygons".into()));
        }
        let size = self.bounds().diagonal().max(f32::MIN_POSITIVE) as f64;
        for (i, p) in self.polygons.iter().enumerate() {
            if p.vertices.len() < 3 {
                return Err(bad(
                    self.place_of(i),
                    format!(
                        "polygon has {} vertices; at least 3 needed",
                        p.vertices.len()
                    ),
                ));
            }
            if p.vertices.len() > MAX_POLYGON_VERTICES {
                return Err(bad(
                    self.place_of(i),
                    format!(
                        "polygon has {} vertices; at most {MAX_POLYGON_VERTICES} are accepted (split it)",
                        p.vertices.len()
                    ),
                ));
            }
            if let Some(v) = p.vertices.iter().find(|v| !v.is_finite()) {
                return Err(bad(
                    self.place_of(i),
                    format!("vertex ({}, {}, {}) is not finite", v.x, v.y, v.z),
                ));
            }
            if p.material >= self.materials.len() {
                return Err(bad(
                    self.place_of(i),
                    format!("material index {} out of range", p.material),
                ));
            }
            // Zero area relative to the scene: below (1e-7 · size)², the patch would be
            // numerically empty in f32.
            if polygon_area(&p.vertices) <= (1e-7 * size).powi(2) {
                return Err(bad(
                    self.place_of(i),
                    "polygon has zero area (degenerate face)".into(),
                ));
            }
        }
        if let Some(c) = &self.camera {
            c.validate().map_err(|m| bad(self.place(), m))?;
        }
        Ok(())
    }

    /// [`Scene::validate_geometry`] plus: at least one light.
    pub fn validate(&self) -> Result<(), SceneError> {
        self.validate_geometry()?;
        if self.emitted_power().max_channel() <= 0.0 {
            return Err(SceneError::Invalid {
                at: self.place(),
                message:
                    "the scene has no light source: no polygon has a material with emission > 0"
                        .into(),
            });
        }
        Ok(())
    }
}

/// Area of a polygon as the length of its vector area (exact for planar polygons, the area of
/// the projection onto the best plane otherwise).
pub fn polygon_area(v: &[Vec3]) -> f64 {
    vector_area(v).length() as f64
}

/// The vector area ½ Σ vᵢ × vᵢ₊₁ (Newell's method): normal direction times area.
pub fn vector_area(v: &[Vec3]) -> Vec3 {
    if v.len() < 3 {
        return Vec3::ZERO;
    }
    // Relative to v[0] for precision.
    let o = v[0];
    let mut s = Vec3::ZERO;
    for k in 1..v.len() - 1 {
        s += (v[k] - o).cross(v[k + 1] - o);
    }
    s * 0.5
}

/// A scene's name from its file: the file stem.
fn name_of(path: &Path) -> String {
    path.file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("scene")
        .to_string()
}

/// Choices made while reading a scene file.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LoadOptions {
    /// MGF: treat every surface as one-sided, ignoring `sides 2` (RenderPark's
    /// `-force-onesided`). By default a two-sided MGF surface becomes two polygons back to back.
    pub one_sided: bool,
}

/// Load a scene by built-in name or from a file (`.obj`, `.mgf`, `.gltf`, `.glb`, `.ply`, View3D's
/// `.vs3`).
pub fn load(name_or_path: &str) -> Result<Scene, SceneError> {
    load_with(name_or_path, &LoadOptions::default())
}

/// [`load`] with options.
pub fn load_with(name_or_path: &str, options: &LoadOptions) -> Result<Scene, SceneError> {
    if let Some(s) = builtin::by_name(name_or_path) {
        return Ok(s);
    }
    let path = Path::new(name_or_path);
    let noted = |s: Result<Scene, SceneError>| s.map(Scene::with_coincidence_noted);
    match FileFormat::from_path(path) {
        Some(FileFormat::Obj) => noted(obj::load(path)),
        Some(FileFormat::Mgf) => noted(mgf::load_with(path, options.one_sided)),
        Some(FileFormat::Gltf | FileFormat::Glb) => noted(gltf::load_with(path, options.one_sided)),
        Some(FileFormat::Ply) => noted(ply::load(path)),
        Some(FileFormat::Vs3) => vs3::load(path).map(|v| v.scene),
        _ if !path.exists() => Err(SceneError::Unknown(name_or_path.to_string())),
        _ => Err(SceneError::Invalid {
            at: FileLoc::file(path),
            message:
                "unsupported scene format (supported: .obj with .mtl, .mgf, .gltf, .glb, .ply, .vs3)"
                    .into(),
        }),
    }
}
