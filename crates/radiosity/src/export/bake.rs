//! Baked light: the patch mesh with the radiosity at its vertices, for other tools (game engines,
//! Blender, web viewers) to show as is. Written as glTF 2.0 ([`write_gltf`], `.glb` or `.gltf`)
//! or PLY ([`write_ply`]).
//!
//! **Values.** Each vertex carries two things:
//! - the *linear radiosity* B (W/m² per channel, the display radiosity of
//!   [`crate::pipeline::Solution::display_radiosity`]) interpolated as
//!   [`crate::render::vertex_radiosity`] does: smooth within a surface, hard between surfaces;
//! - a *display colour*, what our PNG pictures show: `c = min(1, B · scale)` per channel, with
//!   `scale` the exposure. A PNG stores `srgb(c)` in 8 bits; glTF's `COLOR_0` is linear, so it
//!   holds `c` itself (sRGB-encoded display value decoded back to linear, which is the identity
//!   on `[0, 1]`), and a viewer that encodes its output to sRGB shows the same colours as our
//!   pictures. PLY's `red`/`green`/`blue` are 8-bit and hold `srgb(c)`, as images do.
//!
//! **glTF layout.** One mesh with one primitive per scene material, each with its own vertices:
//! `POSITION`, `COLOR_0` (display colour, float VEC3) and `_RADIOSITY` (linear B, float VEC3; an
//! application-specific attribute, as glTF allows for names starting with `_`), and u32
//! triangle indices (quad patches are split along their first diagonal). Materials are unlit
//! (`KHR_materials_unlit`) and white, so a viewer shows `COLOR_0` unchanged; the physical
//! material goes in the material's `extras` as `{"radiosity": {"reflectance": [r, g, b],
//! "emission": [r, g, b]}}`, which [`crate::scene::gltf`] reads back, so a baked file can be
//! solved again. The scene's camera, when given, becomes a perspective camera node. `.glb` holds
//! the binary buffer in its BIN chunk; `.gltf` embeds it as a base64 `data:` URI, so either is a
//! single self-contained file.
//!
//! **PLY layout** (binary little-endian): vertex `x y z` (float), `red green blue` (uchar,
//! display colour, sRGB), `radiosity_red radiosity_green radiosity_blue` (float, linear B); face
//! `vertex_indices` (list uchar uint, 3 or 4: quad patches stay quads), `reflectance_red …` and
//! `emission_red …` (float), the names [`crate::scene::ply`] reads.

use super::{write_atomic, ExportError, OutputError};
use crate::color::Rgb;
use crate::mesh::{Mesh, Patch};
use crate::render::srgb_encode;
use crate::scene::{Camera, Scene};
use base64::Engine as _;
use std::io::Write;
use std::path::Path;

/// What a baked file is made of.
#[derive(Clone, Copy, Debug)]
pub struct Bake<'a> {
    /// The scene (for materials and names).
    pub scene: &'a Scene,
    /// The patch mesh.
    pub mesh: &'a Mesh,
    /// Linear radiosity at each mesh vertex (e.g. [`crate::render::vertex_radiosity`]).
    pub vertex_radiosity: &'a [Rgb],
    /// Exposure: display colour = min(1, B · scale).
    pub scale: f32,
    /// A camera to include, if any.
    pub camera: Option<Camera>,
}

impl Bake<'_> {
    fn display(&self, b: Rgb) -> [f32; 3] {
        [b.r, b.g, b.b].map(|c| ((c as f32) * self.scale).clamp(0.0, 1.0))
    }
}

/// Baked-output formats, chosen by file extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BakeFormat {
    /// Binary glTF.
    Glb,
    /// glTF JSON with the buffer embedded.
    Gltf,
    /// Binary little-endian PLY.
    Ply,
}

impl BakeFormat {
    /// The format `path`'s extension names, if it is one.
    pub fn from_path(path: &Path) -> Option<Self> {
        match crate::io::FileFormat::from_path(path)? {
            crate::io::FileFormat::Glb => Some(Self::Glb),
            crate::io::FileFormat::Gltf => Some(Self::Gltf),
            crate::io::FileFormat::Ply => Some(Self::Ply),
            _ => None,
        }
    }
}

/// Write `bake` to `path` in the format its extension names (`.glb`, `.gltf`, `.ply`).
///
/// ```
/// use radiosity::export::bake::{write, Bake};
/// use radiosity::prelude::*;
///
/// let scene = builtin::cornell();
/// let s = solve(&scene, &Settings::from(Uniform { mesh: MeshParams::Patches(300), ..Default::default() }), &Silent).unwrap();
/// let vertex = s.vertex_display_radiosity();
/// let path = std::env::temp_dir().join(format!("radiosity-doc-{}.glb", std::process::id()));
/// let bake = Bake {
///     scene: &scene,
///     mesh: &s.mesh,
///     vertex_radiosity: &vertex,
///     scale: s.auto_exposure(),
///     camera: Some(s.default_camera(&scene)),
/// };
/// write(&path, &bake).unwrap();
/// // A binary glTF: its magic, then version 2.
/// let bytes = std::fs::read(&path).unwrap();
/// assert_eq!(&bytes[..4], b"glTF");
/// assert_eq!(u32::from_le_bytes(bytes[4..8].try_into().unwrap()), 2);
/// std::fs::remove_file(&path).unwrap();
/// ```
pub fn write(path: &Path, bake: &Bake) -> Result<(), ExportError> {
    match BakeFormat::from_path(path) {
        Some(BakeFormat::Ply) => write_ply(path, bake),
        Some(f) => write_gltf(path, bake, f == BakeFormat::Glb),
        None => Err(ExportError::Format {
            path: path.to_path_buf(),
            what: "baked mesh",
            supported: ".glb, .gltf or .ply",
        }),
    }
}

/// The vertex count of a patch.
fn corners(p: &Patch) -> usize {
    if p.is_triangle() {
        3
    } else {
        4
    }
}

/// Per material (per material and atlas for a lightmap): the patches, and their vertices
/// renumbered from 0.
struct Group {
    /// The group's key: the material, or `material · atlases + atlas`.
    key: usize,
    vertices: Vec<u32>,
    triangles: Vec<[u32; 3]>,
}

/// The patches of `mesh` grouped by `key` (below `keys`), groups in key order.
fn groups(mesh: &Mesh, keys: usize, key: impl Fn(usize) -> usize) -> Vec<Group> {
    let mut by_key: Vec<Vec<usize>> = vec![Vec::new(); keys];
    for i in 0..mesh.patches.len() {
        by_key[key(i)].push(i);
    }
    let mut local = vec![u32::MAX; mesh.vertices.len()];
    let mut out = Vec::new();
    for (key, patches) in by_key.into_iter().enumerate() {
        if patches.is_empty() {
            continue;
        }
        let mut g = Group {
            key,
            vertices: Vec::new(),
            triangles: Vec::with_capacity(patches.len() * 2),
        };
        for &pi in &patches {
            let p = &mesh.patches[pi];
            for &v in &p.vertices[..corners(p)] {
                if local[v as usize] == u32::MAX {
                    local[v as usize] = g.vertices.len() as u32;
                    g.vertices.push(v);
                }
            }
            for t in p.triangles() {
                g.triangles.push(t.map(|v| local[v as usize]));
            }
        }
        for &v in &g.vertices {
            local[v as usize] = u32::MAX;
        }
        out.push(g);
    }
    out
}

fn push_f32s(buf: &mut Vec<u8>, v: &[f32]) {
    for x in v {
        buf.extend_from_slice(&x.to_le_bytes());
    }
}

/// A rotation quaternion `[x, y, z, w]` turning glTF's camera frame (looking down −z, up +y) to
/// look along `forward` with `up` up.
fn look_rotation(forward: glam::Vec3, up: glam::Vec3) -> [f32; 4] {
    let f = forward.normalize();
    let r = f.cross(up).normalize();
    let u = r.cross(f);
    let m = glam::Mat3::from_cols(r, u, -f);
    glam::Quat::from_mat3(&m).normalize().to_array()
}

/// Write a baked glTF: binary (`.glb`) when `binary`, else JSON with an embedded buffer.
pub fn write_gltf(path: &Path, bake: &Bake, binary: bool) -> Result<(), ExportError> {
    use serde_json::json;
    let mesh = bake.mesh;
    let groups = groups(mesh, bake.scene.materials.len(), |i| {
        mesh.patches[i].material as usize
    });
    let total: usize = groups.iter().map(|g| g.vertices.len()).sum();
    let tri_total: usize = groups.iter().map(|g| g.triangles.len()).sum();
    // Buffer: positions, colours, radiosities (each all groups in order), then indices.
    let vec3_bytes = total * 12;
    let mut buf: Vec<u8> = Vec::with_capacity(3 * vec3_bytes + tri_total * 12);
    for g in &groups {
        for &v in &g.vertices {
            push_f32s(&mut buf, &mesh.vertices[v as usize].to_array());
        }
    }
    for g in &groups {
        for &v in &g.vertices {
            push_f32s(&mut buf, &bake.display(bake.vertex_radiosity[v as usize]));
        }
    }
    for g in &groups {
        for &v in &g.vertices {
            let b = bake.vertex_radiosity[v as usize];
            push_f32s(&mut buf, &[b.r as f32, b.g as f32, b.b as f32]);
        }
    }
    for g in &groups {
        for t in &g.triangles {
            for i in t {
                buf.extend_from_slice(&i.to_le_bytes());
            }
        }
    }
    let index_bytes = tri_total * 12;

    let mut accessors = Vec::new();
    let mut primitives = Vec::new();
    let mut materials = Vec::new();
    let (mut voff, mut ioff) = (0usize, 0usize);
    for g in &groups {
        let n = g.vertices.len();
        let (lo, hi) = position_bounds(mesh, &g.vertices);
        let base = accessors.len();
        accessors.push(
            json!({"bufferView": 0, "byteOffset": voff * 12, "componentType": 5126,
            "count": n, "type": "VEC3", "min": lo, "max": hi}),
        );
        accessors.push(
            json!({"bufferView": 1, "byteOffset": voff * 12, "componentType": 5126,
            "count": n, "type": "VEC3"}),
        );
        accessors.push(
            json!({"bufferView": 2, "byteOffset": voff * 12, "componentType": 5126,
            "count": n, "type": "VEC3"}),
        );
        accessors.push(
            json!({"bufferView": 3, "byteOffset": ioff * 12, "componentType": 5125,
            "count": g.triangles.len() * 3, "type": "SCALAR"}),
        );
        voff += n;
        ioff += g.triangles.len();
        let m = &bake.scene.materials[g.key];
        primitives.push(json!({
            "attributes": {"POSITION": base, "COLOR_0": base + 1, "_RADIOSITY": base + 2},
            "indices": base + 3,
            "material": materials.len(),
            "mode": 4
        }));
        materials.push(json!({
            "name": m.name,
            "pbrMetallicRoughness": {"baseColorFactor": [1.0, 1.0, 1.0, 1.0],
                "metallicFactor": 0.0, "roughnessFactor": 1.0},
            "extensions": {"KHR_materials_unlit": {}},
            "extras": {"radiosity": {"reflectance": m.reflectance.to_array(),
                "emission": m.emission.to_array()}}
        }));
    }
    let mut nodes = vec![json!({"name": bake.scene.name, "mesh": 0})];
    let mut cameras = Vec::new();
    if let Some(c) = bake.camera {
        let diag = crate::geom::Aabb::from_points(mesh.vertices.iter()).diagonal();
        cameras.push(json!({"type": "perspective", "perspective": {
            "yfov": c.fov_y_deg.to_radians(), "znear": (diag * 1e-3).max(1e-6)}}));
        nodes.push(
            json!({"name": "camera", "camera": 0, "translation": c.eye.to_array(),
            "rotation": look_rotation(c.target - c.eye, c.up)}),
        );
    }
    let mut root = json!({
        "asset": {"version": "2.0", "generator": concat!("radiosity ", env!("CARGO_PKG_VERSION"))},
        "extensionsUsed": ["KHR_materials_unlit"],
        "scene": 0,
        "scenes": [{"name": bake.scene.name, "nodes": (0..nodes.len()).collect::<Vec<_>>()}],
        "nodes": nodes,
        "meshes": [{"name": bake.scene.name, "primitives": primitives}],
        "materials": materials,
        "accessors": accessors,
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": vec3_bytes, "byteStride": 12, "target": 34962},
            {"buffer": 0, "byteOffset": vec3_bytes, "byteLength": vec3_bytes, "byteStride": 12, "target": 34962},
            {"buffer": 0, "byteOffset": 2 * vec3_bytes, "byteLength": vec3_bytes, "byteStride": 12, "target": 34962},
            {"buffer": 0, "byteOffset": 3 * vec3_bytes, "byteLength": index_bytes, "target": 34963}
        ],
    });
    if !cameras.is_empty() {
        root["cameras"] = json!(cameras);
    }
    write_gltf_file(path, root, buf, binary)
}

/// Finish a glTF: the one buffer (embedded as a base64 `data:` URI unless `binary`), then the
/// file, `.glb` framing when `binary`, written atomically.
fn write_gltf_file(
    path: &Path,
    mut root: serde_json::Value,
    mut buf: Vec<u8>,
    binary: bool,
) -> Result<(), ExportError> {
    use serde_json::json;
    let buffer_length = buf.len();
    let mut buffer = json!({"byteLength": buffer_length});
    if !binary {
        buffer["uri"] = json!(format!(
            "data:application/octet-stream;base64,{}",
            base64::engine::general_purpose::STANDARD.encode(&buf)
        ));
    }
    root["buffers"] = json!([buffer]);
    let text = serde_json::to_string(&root).map_err(|e| OutputError {
        path: path.to_path_buf(),
        source: std::io::Error::other(e),
    })?;
    write_atomic(path, |out| {
        if !binary {
            return out.write_all(text.as_bytes());
        }
        // GLB: header, JSON chunk padded with spaces, BIN chunk padded with zeros (4-byte
        // alignment for both, as the specification requires).
        let mut json_bytes = text.into_bytes();
        while json_bytes.len() % 4 != 0 {
            json_bytes.push(b' ');
        }
        while buf.len() % 4 != 0 {
            buf.push(0);
        }
        let total = 12 + 8 + json_bytes.len() + 8 + buf.len();
        out.write_all(b"glTF")?;
        out.write_all(&2u32.to_le_bytes())?;
        out.write_all(&(total as u32).to_le_bytes())?;
        out.write_all(&(json_bytes.len() as u32).to_le_bytes())?;
        out.write_all(&0x4E4F_534Au32.to_le_bytes())?;
        out.write_all(&json_bytes)?;
        out.write_all(&(buf.len() as u32).to_le_bytes())?;
        out.write_all(&0x004E_4942u32.to_le_bytes())?;
        out.write_all(&buf)
    })
}

/// Write a baked binary little-endian PLY.
pub fn write_ply(path: &Path, bake: &Bake) -> Result<(), ExportError> {
    let mesh = bake.mesh;
    write_atomic(path, |out| {
        write!(
            out,
            "ply\nformat binary_little_endian 1.0\n\
             comment radiosity {}: baked radiosity of scene '{}'\n\
             comment red green blue: display colour, sRGB, after exposure scale {}\n\
             comment radiosity_*: linear radiosity, W/m2 (scene units)\n\
             element vertex {}\n\
             property float x\nproperty float y\nproperty float z\n\
             property uchar red\nproperty uchar green\nproperty uchar blue\n\
             property float radiosity_red\nproperty float radiosity_green\nproperty float radiosity_blue\n\
             element face {}\n\
             property list uchar uint vertex_indices\n\
             property float reflectance_red\nproperty float reflectance_green\nproperty float reflectance_blue\n\
             property float emission_red\nproperty float emission_green\nproperty float emission_blue\n\
             end_header\n",
            env!("CARGO_PKG_VERSION"),
            bake.scene.name.replace('\n', " "),
            bake.scale,
            mesh.vertices.len(),
            mesh.patches.len()
        )?;
        let mut rec = Vec::with_capacity(64);
        for (p, b) in mesh.vertices.iter().zip(bake.vertex_radiosity) {
            rec.clear();
            push_f32s(&mut rec, &p.to_array());
            for c in bake.display(*b) {
                rec.push((srgb_encode(c) * 255.0 + 0.5) as u8);
            }
            push_f32s(&mut rec, &[b.r as f32, b.g as f32, b.b as f32]);
            out.write_all(&rec)?;
        }
        for p in &mesh.patches {
            rec.clear();
            let n = corners(p);
            rec.push(n as u8);
            for &v in &p.vertices[..n] {
                rec.extend_from_slice(&v.to_le_bytes());
            }
            let m = &bake.scene.materials[p.material as usize];
            let (r, e) = (m.reflectance, m.emission);
            push_f32s(&mut rec, &[r.r, r.g, r.b, e.r, e.g, e.b].map(|x| x as f32));
            out.write_all(&rec)?;
        }
        Ok(())
    })
}

/// A lightmapped glTF: the scene's faces with their second UV set and the atlas.
#[derive(Clone, Copy, Debug)]
pub struct LightmapBake<'a> {
    /// The scene (materials, names).
    pub scene: &'a Scene,
    /// The baked lightmap: faces, UVs, atlas of B.
    pub lightmap: &'a crate::bake::lightmap::Lightmap,
    /// Exposure: the PNG's texel holds `srgb(min(1, B · scale))`.
    pub scale: f32,
    /// A camera to include, if any.
    pub camera: Option<Camera>,
}

/// `MOZ_lightmap`'s intensity: three.js (and Hubs, which defined the extension) light a white
/// matte material by a lightmap texel `t` as `t · intensity / π` (the Lambert BRDF of the
/// texel taken as irradiance), so π shows the texel's display colour itself, as `COLOR_0` is
/// shown in a vertex-colour bake.
pub const LIGHTMAP_INTENSITY: f64 = std::f64::consts::PI;

/// Atlas `atlas` as 8-bit sRGB RGB bytes, rows top to bottom: `srgb(min(1, B · scale))`, the
/// display colour of our PNG pictures.
pub fn lightmap_srgb8(map: &crate::bake::lightmap::Lightmap, atlas: u32, scale: f32) -> Vec<u8> {
    let texels = map.atlas_texels(atlas);
    let mut out = Vec::with_capacity(texels.len() * 3);
    for b in texels {
        for c in *b {
            let c = (c * scale).clamp(0.0, 1.0);
            out.push((srgb_encode(c) * 255.0 + 0.5) as u8);
        }
    }
    out
}

/// Write a lightmapped glTF (binary `.glb` when `binary`, else `.gltf` with everything
/// embedded).
///
/// Layout: one mesh, one primitive per material and atlas, each with its own vertices:
/// `POSITION`, `TEXCOORD_1` (float VEC2, the lightmap's UV set; [`crate::bake::uv`]; the same
/// accessor is also `TEXCOORD_0`, since glTF's texture-coordinate sets must start at 0) and
/// u32 triangle indices (quads split along their first diagonal). Every material is white,
/// matte (metallic 0, roughness 1; not `KHR_materials_unlit`, which the Khronos validator
/// warns may not combine with another extension), carries `extras.radiosity` as a vertex bake
/// does, and `MOZ_lightmap: {"index": a, "texCoord": 1, "intensity": π}`
/// ([`LIGHTMAP_INTENSITY`]): texture `a` is atlas `a`, an 8-bit sRGB PNG embedded in the
/// buffer, sampled linearly and clamped. `MOZ_lightmap` belongs to a material, so with several
/// atlases a scene material whose charts lie in several of them becomes one glTF material per
/// atlas (the same name and `extras`, plus `extras.radiosity.lightmap_atlas`), each with the
/// primitive of its faces in that atlas. The PNG holds the display colour `min(1, B · scale)`
/// and the exposure `scale` rides in `extras.radiosity.lightmap_scale` of the material, so
/// `B = texel / scale` below clipping; the unclipped linear `B` is what
/// [`write_lightmap_exr`] writes.
pub fn write_lightmap_gltf(
    path: &Path,
    bake: &LightmapBake,
    binary: bool,
) -> Result<(), ExportError> {
    use serde_json::json;
    let map = bake.lightmap;
    let u = &map.unwrap;
    let mesh = &u.mesh;
    let atlases = u.atlases as usize;
    let groups = groups(mesh, bake.scene.materials.len() * atlases, |i| {
        mesh.patches[i].material as usize * atlases + u.atlas_of(i as u32) as usize
    });
    let fail = |e: std::io::Error| OutputError {
        path: path.to_path_buf(),
        source: e,
    };
    let mut pngs = Vec::with_capacity(atlases);
    for a in 0..u.atlases {
        let mut png = Vec::new();
        let enc = image::codecs::png::PngEncoder::new(&mut png);
        image::ImageEncoder::write_image(
            enc,
            &lightmap_srgb8(map, a, bake.scale),
            map.width(),
            map.height(),
            image::ExtendedColorType::Rgb8,
        )
        .map_err(|e| fail(std::io::Error::other(e)))?;
        pngs.push(png);
    }
    let total: usize = groups.iter().map(|g| g.vertices.len()).sum();
    let tri_total: usize = groups.iter().map(|g| g.triangles.len()).sum();
    let (pos_bytes, uv_bytes, index_bytes) = (total * 12, total * 8, tri_total * 12);
    let png_bytes: usize = pngs.iter().map(|p| p.len() + 4).sum();
    let mut buf: Vec<u8> = Vec::with_capacity(pos_bytes + uv_bytes + index_bytes + png_bytes);
    for g in &groups {
        for &v in &g.vertices {
            push_f32s(&mut buf, &mesh.vertices[v as usize].to_array());
        }
    }
    for g in &groups {
        for &v in &g.vertices {
            push_f32s(&mut buf, &u.uv[v as usize]);
        }
    }
    for g in &groups {
        for t in &g.triangles {
            for i in t {
                buf.extend_from_slice(&i.to_le_bytes());
            }
        }
    }
    let mut buffer_views = vec![
        json!({"buffer": 0, "byteOffset": 0, "byteLength": pos_bytes, "byteStride": 12, "target": 34962}),
        json!({"buffer": 0, "byteOffset": pos_bytes, "byteLength": uv_bytes, "byteStride": 8, "target": 34962}),
        json!({"buffer": 0, "byteOffset": pos_bytes + uv_bytes, "byteLength": index_bytes, "target": 34963}),
    ];
    let (mut images, mut textures) = (Vec::new(), Vec::new());
    for (a, png) in pngs.iter().enumerate() {
        // Each image 4-byte aligned in the buffer.
        while buf.len() % 4 != 0 {
            buf.push(0);
        }
        let name = if atlases == 1 {
            "lightmap".to_string()
        } else {
            format!("lightmap-{a}")
        };
        images
            .push(json!({"name": name, "bufferView": buffer_views.len(), "mimeType": "image/png"}));
        textures.push(json!({"name": name, "source": a, "sampler": 0}));
        buffer_views.push(json!({"buffer": 0, "byteOffset": buf.len(), "byteLength": png.len()}));
        buf.extend_from_slice(png);
    }
    let mut accessors = Vec::new();
    let mut primitives = Vec::new();
    let mut materials = Vec::new();
    let (mut voff, mut ioff) = (0usize, 0usize);
    for g in &groups {
        let n = g.vertices.len();
        let (lo, hi) = position_bounds(mesh, &g.vertices);
        let base = accessors.len();
        accessors.push(
            json!({"bufferView": 0, "byteOffset": voff * 12, "componentType": 5126,
            "count": n, "type": "VEC3", "min": lo, "max": hi}),
        );
        accessors.push(
            json!({"bufferView": 1, "byteOffset": voff * 8, "componentType": 5126,
            "count": n, "type": "VEC2"}),
        );
        accessors.push(
            json!({"bufferView": 2, "byteOffset": ioff * 12, "componentType": 5125,
            "count": g.triangles.len() * 3, "type": "SCALAR"}),
        );
        voff += n;
        ioff += g.triangles.len();
        let (material, atlas) = (g.key / atlases, g.key % atlases);
        let m = &bake.scene.materials[material];
        primitives.push(json!({
            "attributes": {"POSITION": base, "TEXCOORD_0": base + 1, "TEXCOORD_1": base + 1},
            "indices": base + 2,
            "material": materials.len(),
            "mode": 4
        }));
        let mut extras = json!({"reflectance": m.reflectance.to_array(),
            "emission": m.emission.to_array(), "lightmap_scale": bake.scale});
        if atlases > 1 {
            extras["lightmap_atlas"] = json!(atlas);
        }
        materials.push(json!({
            "name": m.name,
            "pbrMetallicRoughness": {"baseColorFactor": [1.0, 1.0, 1.0, 1.0],
                "metallicFactor": 0.0, "roughnessFactor": 1.0},
            "extensions": {
                "MOZ_lightmap": {"index": atlas, "texCoord": 1, "intensity": LIGHTMAP_INTENSITY}
            },
            "extras": {"radiosity": extras}
        }));
    }
    let mut nodes = vec![json!({"name": bake.scene.name, "mesh": 0})];
    let mut cameras = Vec::new();
    if let Some(c) = bake.camera {
        let diag = crate::geom::Aabb::from_points(mesh.vertices.iter()).diagonal();
        cameras.push(json!({"type": "perspective", "perspective": {
            "yfov": c.fov_y_deg.to_radians(), "znear": (diag * 1e-3).max(1e-6)}}));
        nodes.push(
            json!({"name": "camera", "camera": 0, "translation": c.eye.to_array(),
            "rotation": look_rotation(c.target - c.eye, c.up)}),
        );
    }
    let mut root = json!({
        "asset": {"version": "2.0", "generator": concat!("radiosity ", env!("CARGO_PKG_VERSION"))},
        "extensionsUsed": ["MOZ_lightmap"],
        "scene": 0,
        "scenes": [{"name": bake.scene.name, "nodes": (0..nodes.len()).collect::<Vec<_>>()}],
        "nodes": nodes,
        "meshes": [{"name": bake.scene.name, "primitives": primitives}],
        "materials": materials,
        "accessors": accessors,
        "images": images,
        "samplers": [{"magFilter": 9729, "minFilter": 9729, "wrapS": 33071, "wrapT": 33071}],
        "textures": textures,
        "bufferViews": buffer_views,
    });
    if !cameras.is_empty() {
        root["cameras"] = json!(cameras);
    }
    write_gltf_file(path, root, buf, binary)
}

/// The files [`write_lightmap_exr`] writes for `atlases` atlases at `path`: `path` itself for
/// one; for several, `-0`, `-1`, … inserted before the extension (`x.exr` → `x-0.exr`,
/// `x-1.exr`, …; the number is the `MOZ_lightmap` texture index of the glTF).
pub fn lightmap_exr_paths(path: &Path, atlases: u32) -> Vec<std::path::PathBuf> {
    if atlases == 1 {
        return vec![path.to_path_buf()];
    }
    let stem = path.file_stem().unwrap_or_default().to_string_lossy();
    let ext = path.extension().map(|e| e.to_string_lossy().into_owned());
    (0..atlases)
        .map(|a| {
            let name = match &ext {
                Some(e) => format!("{stem}-{a}.{e}"),
                None => format!("{stem}-{a}"),
            };
            path.with_file_name(name)
        })
        .collect()
}

/// Write the atlases as OpenEXR, linear 32-bit float RGB holding the radiosity B (W/m² per
/// channel, scene units), rows top to bottom as in the glTF's textures, layer `radiosity`,
/// one file per atlas named by [`lightmap_exr_paths`]; the files written.
pub fn write_lightmap_exr(
    path: &Path,
    map: &crate::bake::lightmap::Lightmap,
) -> Result<Vec<std::path::PathBuf>, ExportError> {
    use exr::prelude::*;
    let (w, h) = (map.width() as usize, map.height() as usize);
    let paths = lightmap_exr_paths(path, map.atlases());
    for (a, p) in paths.iter().enumerate() {
        let texels = map.atlas_texels(a as u32);
        write_atomic::<ExportError>(p, |out| {
            let channels = SpecificChannels::rgb(|pos: Vec2<usize>| {
                let [r, g, b] = texels[pos.y() * w + pos.x()];
                (r, g, b)
            });
            let layer = Layer::new(
                (w, h),
                LayerAttributes::named("radiosity"),
                Encoding::FAST_LOSSLESS,
                channels,
            );
            exr::image::Image::from_layer(layer)
                .write()
                .to_buffered(out)
                .map_err(std::io::Error::other)
        })?;
    }
    Ok(paths)
}

/// The bounds of `vertices` of `mesh`, as glTF's POSITION accessor must state them.
fn position_bounds(mesh: &Mesh, vertices: &[u32]) -> ([f32; 3], [f32; 3]) {
    let (mut lo, mut hi) = ([f32::MAX; 3], [f32::MIN; 3]);
    for &v in vertices {
        let p = mesh.vertices[v as usize].to_array();
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    (lo, hi)
}
