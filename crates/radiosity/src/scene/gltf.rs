//! glTF 2.0 scenes: `.gltf` (JSON with `.bin` buffers and images beside it, or embedded as
//! `data:` URIs) and `.glb` (binary container).
//!
//! **Geometry.** Every mesh instance of the default scene (or of the first scene when none is
//! marked default), each in its node's world transform. Primitive modes `TRIANGLES`,
//! `TRIANGLE_STRIP` and `TRIANGLE_FAN` become triangles; points and lines are refused (radiosity
//! needs surfaces). Each triangle is one [`Polygon`]; the triangles of one primitive instance
//! share a smoothing group ([`Polygon::group`]), so a wall made of two triangles is shaded as one
//! wall. A node whose world transform mirrors (negative determinant) has its triangles reversed,
//! as the glTF specification asks, so they keep facing the same way. Zero-area triangles (used by
//! strips to restart) are skipped and counted in a warning. Units are metres, as glTF defines;
//! +y is up.
//!
//! **Materials.** Reflectance ρ = `baseColorFactor` (rgb) × the mean of `baseColorTexture` over
//! its texels (decoded from sRGB to linear first), scaled down to a largest channel of
//! [`MAX_REFLECTANCE`] when it is brighter (glTF's default white is 1.0, which no real surface
//! reaches; reported in a warning). Emission E (W/m²) = `emissiveFactor` ×
//! `KHR_materials_emissive_strength` × the mean of `emissiveTexture`. A primitive without a
//! material gets glTF's default material (white, scaled as above). A `doubleSided` material
//! gives two polygons back to back, as a two-sided MGF surface does, unless
//! [`super::LoadOptions::one_sided`]. Metallic, roughness, transparency and `COLOR_0` are
//! ignored (with a warning): the engine is diffuse, and reflectance is per material.
//!
//! **Baked files.** A material whose `extras` hold `{"radiosity": {"reflectance": [r, g, b],
//! "emission": [r, g, b]}}` takes ρ and E from there. The baked files this engine writes
//! ([`crate::export::bake`]) carry them, because their visible material is unlit white (the light
//! is in the vertex colours): so a baked file can be read back and solved again.
//!
//! **Camera.** The first node of the scene (depth first, in document order) that carries a
//! perspective camera gives the default view: eye at the node's origin, looking down its −z, up
//! along its +y, `yfov` as the vertical field of view.
//!
//! **Errors** name the file and the glTF object: a truncated `.glb`, a missing or short buffer
//! file, an accessor reaching past its buffer view, an index out of range, a point or line mode,
//! a required extension the engine does not implement (Draco, meshopt compression), a cycle in
//! the node hierarchy.

use super::mgf::MAX_REFLECTANCE;
use super::{Camera, Material, Polygon, Scene, SceneError};
use crate::color::Rgb;
use crate::geom::Vec3;
use ::gltf::accessor::{DataType, Dimensions};
use ::gltf::mesh::Mode;
use base64::Engine as _;
use glam::{DMat4, DVec3};
use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};

/// Extensions whose presence in `extensionsRequired` we can honour: those we read (the lights
/// by [`super::gltf_lights`], for `lighting`), and those that only change what we ignore anyway.
const SUPPORTED_REQUIRED: &[&str] = &[
    "KHR_materials_emissive_strength",
    "KHR_materials_unlit",
    "KHR_texture_transform",
    "KHR_materials_ior",
    "KHR_materials_transmission",
    "KHR_materials_specular",
    "KHR_mesh_quantization",
    "KHR_lights_punctual",
    "EXT_lights_ies",
];

pub(super) fn invalid(path: &Path, message: impl Into<String>) -> SceneError {
    SceneError::Invalid {
        at: crate::loc::FileLoc::file(path),
        message: crate::loc::shorten(message.into()),
    }
}

/// Split a `.glb` into its JSON chunk and optional BIN chunk, checking every length first.
fn split_glb<'a>(path: &Path, bytes: &'a [u8]) -> Result<(&'a [u8], Option<&'a [u8]>), SceneError> {
    let u32_at = |b: &[u8], at: usize| u32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]]);
    if bytes.len() < 12 {
        return Err(invalid(
            path,
            format!(
                "truncated GLB: {} bytes, shorter than the 12-byte header",
                bytes.len()
            ),
        ));
    }
    let version = u32_at(bytes, 4);
    if version != 2 {
        return Err(invalid(
            path,
            format!("GLB version {version} is not supported (only 2)"),
        ));
    }
    let length = u32_at(bytes, 8) as usize;
    if length > bytes.len() {
        return Err(invalid(
            path,
            format!(
                "truncated GLB: the header says {length} bytes but the file has {}",
                bytes.len()
            ),
        ));
    }
    let data = &bytes[..length];
    let (mut json, mut bin) = (None, None);
    let mut pos = 12;
    while pos < data.len() {
        if pos + 8 > data.len() {
            return Err(invalid(
                path,
                format!("truncated GLB: chunk header at byte {pos} is cut off"),
            ));
        }
        let len = u32_at(data, pos) as usize;
        let kind = u32_at(data, pos + 4);
        let start = pos + 8;
        if len > data.len() - start {
            return Err(invalid(
                path,
                format!(
                    "truncated GLB: the chunk at byte {pos} says {len} bytes but {} remain",
                    data.len() - start
                ),
            ));
        }
        let chunk = &data[start..start + len];
        match kind {
            0x4E4F_534A if json.is_none() && pos == 12 => json = Some(chunk),
            0x004E_4942 if json.is_some() && bin.is_none() => bin = Some(chunk),
            _ if pos == 12 => {
                return Err(invalid(path, "GLB: the first chunk is not JSON"));
            }
            _ => {} // unknown chunks are skipped, as the specification allows
        }
        pos = start + len;
    }
    let json = json.ok_or_else(|| invalid(path, "GLB has no JSON chunk"))?;
    Ok((json, bin))
}

/// Decode `%XX` escapes of a relative URI.
fn percent_decode(uri: &str) -> String {
    let b = uri.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        let hex = |c: u8| (c as char).to_digit(16);
        if b[i] == b'%' && i + 2 < b.len() {
            if let (Some(h), Some(l)) = (hex(b[i + 1]), hex(b[i + 2])) {
                out.push((h * 16 + l) as u8);
                i += 3;
                continue;
            }
        }
        out.push(b[i]);
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}

pub(super) struct Reader<'a> {
    pub(super) path: &'a Path,
    pub(super) doc: &'a ::gltf::Document,
    pub(super) buffers: Vec<Vec<u8>>,
    /// Mean linear colour of each image already decoded.
    pub(super) image_means: HashMap<usize, Rgb>,
}

impl<'a> Reader<'a> {
    /// The bytes a URI names: a `data:` URI, or a file relative to the glTF file.
    pub(super) fn resolve(&self, uri: &str, what: &str) -> Result<(Vec<u8>, String), SceneError> {
        if let Some(rest) = uri.strip_prefix("data:") {
            let (_, payload) = rest.split_once(";base64,").ok_or_else(|| {
                invalid(
                    self.path,
                    format!("{what}: only base64 data URIs are supported"),
                )
            })?;
            let bytes = base64::engine::general_purpose::STANDARD
                .decode(payload.trim())
                .map_err(|e| invalid(self.path, format!("{what}: bad base64 data URI ({e})")))?;
            return Ok((bytes, format!("{what} (data URI)")));
        }
        if uri.contains("://") {
            return Err(invalid(
                self.path,
                format!("{what}: URI '{uri}' is not a relative file path (nothing is downloaded)"),
            ));
        }
        let file: PathBuf = self
            .path
            .parent()
            .unwrap_or(Path::new("."))
            .join(percent_decode(uri));
        let bytes = crate::io::read_input(&file).map_err(|e| {
            invalid(
                self.path,
                format!("{what}: cannot read '{}': {e}", file.display()),
            )
        })?;
        Ok((bytes, file.display().to_string()))
    }

    pub(super) fn load_buffers(&mut self, bin: Option<&[u8]>) -> Result<(), SceneError> {
        for b in self.doc.buffers() {
            let what = format!("buffers[{}]", b.index());
            let (data, from) = match b.source() {
                ::gltf::buffer::Source::Bin => match bin {
                    Some(bin) => (bin.to_vec(), format!("{what} (GLB binary chunk)")),
                    None => {
                        return Err(invalid(
                            self.path,
                            format!("{what} has no URI and there is no GLB binary chunk"),
                        ))
                    }
                },
                ::gltf::buffer::Source::Uri(uri) => self.resolve(uri, &what)?,
            };
            if data.len() < b.length() {
                return Err(invalid(
                    self.path,
                    format!(
                        "{from}: {} bytes, but the glTF says the buffer has {}",
                        data.len(),
                        b.length()
                    ),
                ));
            }
            self.buffers.push(data);
        }
        Ok(())
    }

    /// The components of every element of an accessor, as f64 (normalised integers mapped to
    /// [0, 1] or [−1, 1] as the specification defines), checked against its view and buffer.
    fn read(&self, acc: &::gltf::Accessor, what: &str) -> Result<(Vec<f64>, usize), SceneError> {
        let err = |m: String| {
            invalid(
                self.path,
                format!("accessors[{}] ({what}): {m}", acc.index()),
            )
        };
        if acc.sparse().is_some() {
            return Err(err("sparse accessors are not supported".into()));
        }
        let dims = match acc.dimensions() {
            Dimensions::Scalar => 1,
            Dimensions::Vec2 => 2,
            Dimensions::Vec3 => 3,
            Dimensions::Vec4 => 4,
            d => return Err(err(format!("{d:?} elements are not expected here"))),
        };
        let ty = acc.data_type();
        let size = ty.size();
        let count = acc.count();
        let Some(view) = acc.view() else {
            // No view: all zeros (only meaningful with sparse data, which we refuse).
            return Err(err("the accessor has no buffer view".into()));
        };
        let buffer = &self.buffers[view.buffer().index()];
        let view_end = view.offset().checked_add(view.length());
        if view_end.is_none_or(|end| end > buffer.len()) {
            return Err(err(format!(
                "bufferViews[{}] (offset {}, length {}) reaches past its {}-byte buffer",
                view.index(),
                view.offset(),
                view.length(),
                buffer.len()
            )));
        }
        let data = &buffer[view.offset()..view.offset() + view.length()];
        let elem = size * dims;
        let stride = view.stride().unwrap_or(elem);
        // Checked: counts and offsets come from the file and may be absurd.
        let last_end = stride
            .checked_mul(count.saturating_sub(1))
            .and_then(|x| x.checked_add(acc.offset()))
            .and_then(|x| x.checked_add(elem));
        if count > 0 && last_end.is_none_or(|end| end > data.len()) {
            return Err(err(format!(
                "{count} elements from byte {} do not fit in bufferViews[{}] ({} bytes)",
                acc.offset(),
                view.index(),
                data.len()
            )));
        }
        let norm = acc.normalized();
        let mut out = Vec::with_capacity(count * dims);
        for i in 0..count {
            let at = acc.offset() + i * stride;
            for c in 0..dims {
                let b = &data[at + c * size..at + (c + 1) * size];
                let v = match ty {
                    DataType::I8 => {
                        let x = b[0] as i8 as f64;
                        if norm {
                            (x / 127.0).max(-1.0)
                        } else {
                            x
                        }
                    }
                    DataType::U8 => {
                        let x = b[0] as f64;
                        if norm {
                            x / 255.0
                        } else {
                            x
                        }
                    }
                    DataType::I16 => {
                        let x = i16::from_le_bytes([b[0], b[1]]) as f64;
                        if norm {
                            (x / 32767.0).max(-1.0)
                        } else {
                            x
                        }
                    }
                    DataType::U16 => {
                        let x = u16::from_le_bytes([b[0], b[1]]) as f64;
                        if norm {
                            x / 65535.0
                        } else {
                            x
                        }
                    }
                    DataType::U32 => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
                    DataType::F32 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
                };
                out.push(v);
            }
        }
        Ok((out, dims))
    }

    /// Mean linear colour (rgb) of a texture's image.
    fn texture_mean(&mut self, tex: ::gltf::Texture, what: &str) -> Result<Rgb, SceneError> {
        let image = tex.source();
        if let Some(m) = self.image_means.get(&image.index()) {
            return Ok(*m);
        }
        let what = format!("{what}: images[{}]", image.index());
        let (bytes, from) = match image.source() {
            ::gltf::image::Source::View { view, .. } => {
                let buffer = &self.buffers[view.buffer().index()];
                let end = view.offset() + view.length();
                if end > buffer.len() {
                    return Err(invalid(
                        self.path,
                        format!("{what}: its buffer view reaches past the buffer"),
                    ));
                }
                (buffer[view.offset()..end].to_vec(), what.clone())
            }
            ::gltf::image::Source::Uri { uri, .. } => self.resolve(uri, &what)?,
        };
        let img = image::load_from_memory(&bytes)
            .map_err(|e| invalid(self.path, format!("{from}: cannot decode the image ({e})")))?
            .to_rgba8();
        let lut: Vec<f64> = (0..256)
            .map(|v| crate::color::srgb_to_linear(v as f64 / 255.0))
            .collect();
        let mut sum = [0.0f64; 3];
        for p in img.pixels() {
            for c in 0..3 {
                sum[c] += lut[p.0[c] as usize];
            }
        }
        let n = (img.width() as f64 * img.height() as f64).max(1.0);
        let mean = Rgb::new(sum[0] / n, sum[1] / n, sum[2] / n);
        self.image_means.insert(image.index(), mean);
        Ok(mean)
    }

    /// The engine's material for a glTF material (None: the default material), and whether it
    /// is double-sided.
    fn material(
        &mut self,
        m: &::gltf::Material,
        clipped: &mut usize,
    ) -> Result<(Material, bool), SceneError> {
        let what = match m.index() {
            Some(i) => format!("materials[{i}]"),
            None => "default material".to_string(),
        };
        let name = m.name().map(str::to_string).unwrap_or_else(|| what.clone());
        if let Some(baked) = baked_material(m) {
            let (rho, e) = baked
                .map_err(|msg| invalid(self.path, format!("{what}: extras.radiosity: {msg}")))?;
            return Ok((Material::emitter(&name, rho, e), m.double_sided()));
        }
        let pbr = m.pbr_metallic_roughness();
        let f = pbr.base_color_factor();
        let mut rho = Rgb::new(f[0] as f64, f[1] as f64, f[2] as f64);
        if let Some(t) = pbr.base_color_texture() {
            rho = rho * self.texture_mean(t.texture(), &format!("{what}.baseColorTexture"))?;
        }
        if rho.max_channel() > MAX_REFLECTANCE {
            rho = rho * (MAX_REFLECTANCE / rho.max_channel());
            *clipped += 1;
        }
        let ef = m.emissive_factor();
        let strength = m.emissive_strength().unwrap_or(1.0) as f64;
        let mut e = Rgb::new(ef[0] as f64, ef[1] as f64, ef[2] as f64) * strength;
        if let Some(t) = m.emissive_texture() {
            if e.max_channel() > 0.0 {
                e = e * self.texture_mean(t.texture(), &format!("{what}.emissiveTexture"))?;
            }
        }
        let mut material = Material::emitter(&name, rho, e);
        // KHR_materials_transmission: a clear pane passing transmissionFactor × the base
        // colour's luminance of what a non-absorbing pane of its IOR (KHR_materials_ior,
        // default 1.5) passes at normal incidence, (1 − r₀)/(1 + r₀).
        if let Some(t) = m.transmission() {
            let factor = t.transmission_factor() as f64;
            if factor > 0.0 {
                let n = m.ior().map(f64::from).filter(|n| *n > 1.0).unwrap_or(1.5);
                let r0 = ((n - 1.0) / (n + 1.0)).powi(2);
                let tint = 0.2126 * f[0] as f64 + 0.7152 * f[1] as f64 + 0.0722 * f[2] as f64;
                material.transmittance = factor * tint.clamp(0.0, 1.0) * (1.0 - r0) / (1.0 + r0);
                material.ior = Some(n);
            }
        }
        Ok((material, m.double_sided()))
    }
}

/// `extras.radiosity` of a material, if present: `Ok((ρ, E))` or what is wrong with it.
fn baked_material(m: &::gltf::Material) -> Option<Result<(Rgb, Rgb), String>> {
    let raw = m.extras().as_ref()?;
    let v: serde_json::Value = serde_json::from_str(raw.get()).ok()?;
    let r = v.get("radiosity")?;
    let rgb = |key: &str| -> Result<Rgb, String> {
        let a = r
            .get(key)
            .and_then(|x| x.as_array())
            .filter(|a| a.len() == 3)
            .ok_or_else(|| format!("'{key}' must be an array of 3 numbers"))?;
        let c: Vec<f64> = a
            .iter()
            .map(|x| {
                x.as_f64()
                    .ok_or_else(|| format!("'{key}' must be an array of 3 numbers"))
            })
            .collect::<Result<_, _>>()?;
        Ok(Rgb::new(c[0], c[1], c[2]))
    };
    Some(rgb("reflectance").and_then(|rho| Ok((rho, rgb("emission")?))))
}

/// Load a glTF 2.0 scene (`.gltf` or `.glb`); `one_sided` drops the back copies of
/// double-sided materials.
pub fn load_with(path: &Path, one_sided: bool) -> Result<Scene, SceneError> {
    read_scene(path, one_sided, None, None)
}

/// A baked file as a viewer shows it: the scene, and for each polygon (triangle) the linear
/// `COLOR_0` of its three corners, in the polygon's vertex order. Every primitive must have
/// `COLOR_0` (VEC3 or VEC4; alpha is ignored).
pub fn load_vertex_colours(path: &Path) -> Result<(Scene, Vec<[Rgb; 3]>), SceneError> {
    load_vertex_values(path, VertexValues::Colour)
}

/// Which per-vertex values of a baked file to read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VertexValues {
    /// `COLOR_0`: the display colour.
    Colour,
    /// `_RADIOSITY`: the linear radiosity B that `radiosity solve` bakes beside it.
    Radiosity,
}

impl VertexValues {
    fn name(self) -> &'static str {
        match self {
            VertexValues::Colour => "COLOR_0",
            VertexValues::Radiosity => "_RADIOSITY",
        }
    }

    fn semantic(self) -> ::gltf::Semantic {
        match self {
            VertexValues::Colour => ::gltf::Semantic::Colors(0),
            VertexValues::Radiosity => ::gltf::Semantic::Extras("RADIOSITY".into()),
        }
    }
}

/// The scene of a baked file and, for each of its triangles (polygons), the values at its
/// three corners.
pub fn load_vertex_values(
    path: &Path,
    which: VertexValues,
) -> Result<(Scene, Vec<[Rgb; 3]>), SceneError> {
    let mut values = Vec::new();
    let scene = read_scene(path, false, Some((&mut values, which)), None)?;
    Ok((scene, values))
}

/// Largest lightmap image side read, texels (as [`crate::bake::uv::MAX_ATLAS`]).
pub const MAX_LIGHTMAP_SIDE: u32 = 16_384;

/// Deflate's largest compression ratio (RFC 1951: a 258-byte match in 2 bits, about 1032:1),
/// which bounds how many pixels an image of a given file size can honestly hold.
const MAX_DEFLATE_RATIO: u64 = 1032;

/// How a lightmap texture is sampled outside `[0, 1]` (glTF sampler `wrapS`/`wrapT`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Wrap {
    /// `CLAMP_TO_EDGE` (what `radiosity solve --bake lightmap` writes).
    Clamp,
    /// `REPEAT` (glTF's default).
    Repeat,
    /// `MIRRORED_REPEAT`.
    Mirror,
}

impl Wrap {
    fn index(self, i: i64, n: u32) -> usize {
        let n = n as i64;
        (match self {
            Wrap::Clamp => i.clamp(0, n - 1),
            Wrap::Repeat => i.rem_euclid(n),
            Wrap::Mirror => {
                let m = i.rem_euclid(2 * n);
                if m >= n {
                    2 * n - 1 - m
                } else {
                    m
                }
            }
        }) as usize
    }
}

/// A decoded lightmap image: 8-bit sRGB RGB texels, rows top to bottom (glTF's UV `(0, 0)` is
/// the top-left corner).
#[derive(Clone, Debug)]
pub struct LightmapImage {
    /// Width, texels.
    pub width: u32,
    /// Height, texels.
    pub height: u32,
    /// `width × height × 3` bytes.
    pub srgb: Vec<u8>,
}

/// A material's `MOZ_lightmap` (Mozilla Hubs' extension, which three.js applies as its
/// `lightMap`): the image, the UV set, the intensity, and how it lights the surface.
#[derive(Clone, Debug, PartialEq)]
pub struct LightmapMaterial {
    /// Index into [`LightmapSet::images`].
    pub image: u32,
    /// The UV set it reads (`texCoord`: `TEXCOORD_n`).
    pub tex_coord: u32,
    /// `intensity` (default 1).
    pub intensity: f64,
    /// The material's diffuse colour: `baseColorFactor` (rgb) × (1 − `metallicFactor`), as
    /// three.js's standard material multiplies the lightmap by it.
    pub diffuse: Rgb,
    /// The sampler's wrap modes along u and v.
    pub wrap: [Wrap; 2],
    /// Whether the sampler magnifies by the nearest texel (`magFilter` 9728) instead of
    /// bilinearly.
    pub nearest: bool,
}

/// The lightmap side of a glTF file: for each polygon of the scene (in the order the scene
/// has them), the UV set's values at its three corners and its material's lightmap.
#[derive(Clone, Debug, Default)]
pub struct LightmapSet {
    /// Per polygon: the UV set at its corners (`None`: the primitive has none).
    pub uv: Vec<Option<[[f32; 2]; 3]>>,
    /// Per polygon: index into [`LightmapSet::materials`] (`None`: no lightmap).
    pub material: Vec<Option<u32>>,
    /// Per polygon: the glTF texture its material's `MOZ_lightmap` names (`None`: none), also
    /// when the images are not decoded; polygons of different lightmap textures lie in
    /// different atlases, whose UV sets overlap.
    pub texture: Vec<Option<u32>>,
    /// The lightmapped materials.
    pub materials: Vec<LightmapMaterial>,
    /// The decoded images.
    pub images: Vec<LightmapImage>,
    /// Image indices (glTF) already decoded, to their slot.
    image_slot: HashMap<usize, u32>,
}

impl LightmapSet {
    /// The linear value of lightmap `material` at `uv`, sampled as a GPU samples an sRGB
    /// texture: each texel decoded to linear (IEC 61966-2-1), then filtered bilinearly (or by
    /// the nearest texel) with the sampler's wrap modes.
    pub fn sample(&self, material: u32, uv: [f32; 2]) -> Rgb {
        let m = &self.materials[material as usize];
        let img = &self.images[m.image as usize];
        let (w, h) = (img.width, img.height);
        let texel = |x: i64, y: i64| {
            let at = (m.wrap[1].index(y, h) * w as usize + m.wrap[0].index(x, w)) * 3;
            let c = &img.srgb[at..at + 3];
            Rgb::new(srgb8(c[0]), srgb8(c[1]), srgb8(c[2]))
        };
        // Texel coordinates; saturating casts keep absurd UVs finite.
        let (x, y) = (uv[0] as f64 * w as f64, uv[1] as f64 * h as f64);
        if m.nearest {
            return texel(x.floor() as i64, y.floor() as i64);
        }
        let (x, y) = (x - 0.5, y - 0.5);
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let (x0, y0) = (x0 as i64, y0 as i64);
        texel(x0, y0) * ((1.0 - fx) * (1.0 - fy))
            + texel(x0.saturating_add(1), y0) * (fx * (1.0 - fy))
            + texel(x0, y0.saturating_add(1)) * ((1.0 - fx) * fy)
            + texel(x0.saturating_add(1), y0.saturating_add(1)) * (fx * fy)
    }

    /// The radiance a white-lit viewer shows for lightmap `material` at `uv`: three.js's
    /// standard material takes the lightmap texel times `intensity` as irradiance and reflects
    /// it by the Lambert BRDF, `L = diffuse · texel · intensity / π`.
    pub fn radiance(&self, material: u32, uv: [f32; 2]) -> Rgb {
        let m = &self.materials[material as usize];
        self.sample(material, uv) * m.diffuse * (m.intensity * std::f64::consts::FRAC_1_PI)
    }
}

/// The linear value of an 8-bit sRGB code.
fn srgb8(c: u8) -> f64 {
    static LUT: std::sync::OnceLock<[f64; 256]> = std::sync::OnceLock::new();
    LUT.get_or_init(|| std::array::from_fn(|v| crate::color::srgb_to_linear(v as f64 / 255.0)))
        [c as usize]
}

/// A material's `MOZ_lightmap` as written in the JSON.
#[derive(Clone, Copy, Debug)]
struct Moz {
    index: usize,
    tex_coord: u32,
    intensity: f64,
}

/// `extensions.MOZ_lightmap` of every material (`None` where absent), checked.
fn moz_lightmaps(path: &Path, json: &[u8], count: usize) -> Result<Vec<Option<Moz>>, SceneError> {
    use serde_json::Value;
    let root: Value = serde_json::from_str(&String::from_utf8_lossy(json))
        .map_err(|e| invalid(path, format!("invalid glTF JSON: {e}")))?;
    let mut out = vec![None; count];
    let materials = root.get("materials").and_then(Value::as_array);
    for (i, m) in materials.into_iter().flatten().enumerate().take(count) {
        let Some(z) = m.get("extensions").and_then(|e| e.get("MOZ_lightmap")) else {
            continue;
        };
        let what = format!("materials[{i}].extensions.MOZ_lightmap");
        let index = z
            .get("index")
            .and_then(Value::as_u64)
            .ok_or_else(|| invalid(path, format!("{what}: 'index' must be a texture index")))?;
        let tex_coord = match z.get("texCoord") {
            None => 0,
            Some(v) => v
                .as_u64()
                .filter(|k| *k < 64)
                .ok_or_else(|| invalid(path, format!("{what}: 'texCoord' must be a set index")))?,
        };
        let intensity = match z.get("intensity") {
            None => 1.0,
            Some(v) => v
                .as_f64()
                .filter(|x| x.is_finite() && *x >= 0.0)
                .ok_or_else(|| {
                    invalid(
                        path,
                        format!("{what}: 'intensity' must be a finite number ≥ 0"),
                    )
                })?,
        };
        out[i] = Some(Moz {
            index: index.min(usize::MAX as u64) as usize,
            tex_coord: tex_coord as u32,
            intensity,
        });
    }
    Ok(out)
}

impl Reader<'_> {
    /// Decode a material's lightmap (its image once per file) into `set`; its slot.
    fn lightmap_material(
        &mut self,
        set: &mut LightmapSet,
        material: &::gltf::Material,
        m: usize,
        z: Moz,
    ) -> Result<u32, SceneError> {
        use ::gltf::texture::{MagFilter, WrappingMode};
        let what = format!("materials[{m}].extensions.MOZ_lightmap");
        let tex = self.doc.textures().nth(z.index).ok_or_else(|| {
            invalid(
                self.path,
                format!(
                    "{what}: no texture {} (the file has {})",
                    z.index,
                    self.doc.textures().count()
                ),
            )
        })?;
        let image = tex.source();
        let slot = match set.image_slot.get(&image.index()) {
            Some(s) => *s,
            None => {
                let img = self.lightmap_image(image, &format!("{what}: textures[{}]", z.index))?;
                set.images.push(img);
                let s = (set.images.len() - 1) as u32;
                set.image_slot.insert(tex.source().index(), s);
                s
            }
        };
        let sampler = tex.sampler();
        let wrap = |w: WrappingMode| match w {
            WrappingMode::ClampToEdge => Wrap::Clamp,
            WrappingMode::MirroredRepeat => Wrap::Mirror,
            WrappingMode::Repeat => Wrap::Repeat,
        };
        let pbr = material.pbr_metallic_roughness();
        let f = pbr.base_color_factor();
        let metal = (1.0 - pbr.metallic_factor() as f64).clamp(0.0, 1.0);
        set.materials.push(LightmapMaterial {
            image: slot,
            tex_coord: z.tex_coord,
            intensity: z.intensity,
            diffuse: Rgb::new(f[0] as f64, f[1] as f64, f[2] as f64) * metal,
            wrap: [wrap(sampler.wrap_s()), wrap(sampler.wrap_t())],
            nearest: sampler.mag_filter() == Some(MagFilter::Nearest),
        });
        Ok((set.materials.len() - 1) as u32)
    }

    /// Decode a lightmap image to 8-bit sRGB RGB. Its size is checked before any pixel is
    /// allocated: at most [`MAX_LIGHTMAP_SIDE`] a side, and no more pixels than its bytes can
    /// hold (a row of one-bit pixels compressed at deflate's best ratio).
    fn lightmap_image(
        &self,
        image: ::gltf::Image,
        what: &str,
    ) -> Result<LightmapImage, SceneError> {
        let what = format!("{what}: images[{}]", image.index());
        let (bytes, from) = match image.source() {
            ::gltf::image::Source::View { view, .. } => {
                let buffer = &self.buffers[view.buffer().index()];
                let end = view.offset().checked_add(view.length());
                let Some(end) = end.filter(|e| *e <= buffer.len()) else {
                    return Err(invalid(
                        self.path,
                        format!("{what}: its buffer view reaches past the buffer"),
                    ));
                };
                (buffer[view.offset()..end].to_vec(), what.clone())
            }
            ::gltf::image::Source::Uri { uri, .. } => self.resolve(uri, &what)?,
        };
        let fail = |e: &dyn std::fmt::Display| {
            invalid(self.path, format!("{from}: cannot decode the image ({e})"))
        };
        let decoder = image::ImageReader::new(std::io::Cursor::new(&bytes))
            .with_guessed_format()
            .map_err(|e| fail(&e))?
            .into_decoder()
            .map_err(|e| fail(&e))?;
        use image::ImageDecoder as _;
        let (w, h) = decoder.dimensions();
        if w == 0 || h == 0 || w > MAX_LIGHTMAP_SIDE || h > MAX_LIGHTMAP_SIDE {
            return Err(invalid(
                self.path,
                format!("{from}: a {w} × {h} image; a lightmap must be 1 to {MAX_LIGHTMAP_SIDE} texels a side"),
            ));
        }
        let least = h as u64 * (1 + (w as u64).div_ceil(8));
        if least > MAX_DEFLATE_RATIO * bytes.len() as u64 + 1024 {
            return Err(invalid(
                self.path,
                format!(
                    "{from}: a {w} × {h} image cannot be held in {} bytes: the file is damaged",
                    bytes.len()
                ),
            ));
        }
        let mut decoder = decoder;
        let mut limits = image::Limits::default();
        limits.max_image_width = Some(w);
        limits.max_image_height = Some(h);
        limits.max_alloc = Some(w as u64 * h as u64 * 8 + (1 << 20));
        decoder.set_limits(limits).map_err(|e| fail(&e))?;
        let img = image::DynamicImage::from_decoder(decoder)
            .map_err(|e| fail(&e))?
            .into_rgb8();
        Ok(LightmapImage {
            width: w,
            height: h,
            srgb: img.into_raw(),
        })
    }
}

/// A lightmapped glTF: the scene and, per polygon, its lightmap UVs. With `textures`, each
/// primitive whose material has `MOZ_lightmap` gets that extension's UV set (`texCoord`) and
/// its decoded image ([`LightmapSet::radiance`] lights it); without, every primitive's
/// `TEXCOORD_1`, when it has one, is read (what a lightmap bake keeps) and no image is decoded.
pub fn load_lightmap(
    path: &Path,
    one_sided: bool,
    textures: bool,
) -> Result<(Scene, LightmapSet), SceneError> {
    let mut set = LightmapSet::default();
    let scene = read_scene(path, one_sided, None, Some((&mut set, textures)))?;
    Ok((scene, set))
}

/// What the `gltf` crate's validation lets through and its accessors then unwrap (a panic on a
/// hostile file): a primitive attribute naming an accessor that is not there, a camera whose
/// `type` names an absent object, an image with neither `uri` nor `bufferView`. Checked on the
/// JSON first, each refused with its JSON path.
fn check_references(path: &Path, json: &[u8]) -> Result<(), SceneError> {
    use serde_json::Value;
    // Invalid UTF-8 inside a string that the typed parser skips would fail a `Value` parse:
    // read the text lossily, so that the structure is checked all the same. JSON that does not
    // parse at all is left to the glTF parser, whose message is better.
    let Ok(root) = serde_json::from_str::<Value>(&String::from_utf8_lossy(json)) else {
        return Ok(());
    };
    let count = |key: &str| root.get(key).and_then(Value::as_array).map_or(0, Vec::len);
    let accessors = count("accessors");
    let list = |key: &str| {
        root.get(key)
            .and_then(Value::as_array)
            .cloned()
            .unwrap_or_default()
    };
    for (m, mesh) in list("meshes").iter().enumerate() {
        let prims = mesh.get("primitives").and_then(Value::as_array);
        for (p, prim) in prims.into_iter().flatten().enumerate() {
            let attrs = prim.get("attributes").and_then(Value::as_object);
            for (name, index) in attrs.into_iter().flatten() {
                match index.as_u64() {
                    Some(i) if (i as usize) < accessors => {}
                    _ => {
                        return Err(invalid(
                            path,
                            format!(
                                "invalid glTF: meshes[{m}].primitives[{p}].attributes.{}: no accessor {index}",
                                crate::loc::shorten(name.clone())
                            ),
                        ))
                    }
                }
            }
            let targets = prim.get("targets").and_then(Value::as_array);
            for (t, target) in targets.into_iter().flatten().enumerate() {
                for (name, index) in target.as_object().into_iter().flatten() {
                    if index.as_u64().is_none_or(|i| (i as usize) >= accessors) {
                        return Err(invalid(
                            path,
                            format!(
                                "invalid glTF: meshes[{m}].primitives[{p}].targets[{t}].{}: no accessor {index}",
                                crate::loc::shorten(name.clone())
                            ),
                        ));
                    }
                }
            }
        }
    }
    for (c, camera) in list("cameras").iter().enumerate() {
        let kind = camera.get("type").and_then(Value::as_str).unwrap_or("");
        if matches!(kind, "perspective" | "orthographic") && camera.get(kind).is_none() {
            return Err(invalid(
                path,
                format!("invalid glTF: cameras[{c}]: type '{kind}' but no '{kind}' object"),
            ));
        }
    }
    for (i, image) in list("images").iter().enumerate() {
        if image.get("uri").is_none() && image.get("bufferView").is_none() {
            return Err(invalid(
                path,
                format!("invalid glTF: images[{i}]: neither 'uri' nor 'bufferView'"),
            ));
        }
    }
    Ok(())
}

/// A glTF file's bytes parsed: the document, its JSON text and (GLB) its binary chunk; the
/// references the `gltf` crate would unwrap are checked first, and a required extension the
/// engine does not implement is refused.
pub(super) fn open<'b>(path: &Path, bytes: &'b [u8]) -> Result<Opened<'b>, SceneError> {
    let (json, bin) = if bytes.starts_with(b"glTF") {
        split_glb(path, bytes)?
    } else {
        (bytes, None)
    };
    check_references(path, json)?;
    let gltf = ::gltf::Gltf::from_slice(json).map_err(|e| match e {
        ::gltf::Error::Validation(list) => {
            let (p, err) = &list[0];
            let more = match list.len() {
                1 => String::new(),
                n => format!(" (and {} more problems)", n - 1),
            };
            invalid(path, format!("invalid glTF: {p}: {err}{more}"))
        }
        e => invalid(path, format!("invalid glTF: {e}")),
    })?;
    for ext in gltf.document.extensions_required() {
        if !SUPPORTED_REQUIRED.contains(&ext) {
            return Err(invalid(
                path,
                format!("the file requires extension {ext}, which this engine does not implement"),
            ));
        }
    }
    Ok(Opened { gltf, json, bin })
}

/// A glTF file parsed by [`open`].
pub(super) struct Opened<'b> {
    pub(super) gltf: ::gltf::Gltf,
    /// The JSON text.
    pub(super) json: &'b [u8],
    /// The GLB binary chunk, if any.
    pub(super) bin: Option<&'b [u8]>,
}

fn read_scene(
    path: &Path,
    one_sided: bool,
    colours: Option<(&mut Vec<[Rgb; 3]>, VertexValues)>,
    mut lightmap: Option<(&mut LightmapSet, bool)>,
) -> Result<Scene, SceneError> {
    let (mut colours, which) = match colours {
        Some((c, w)) => (Some(c), w),
        None => (None, VertexValues::Colour),
    };
    let bytes = crate::io::read_input(path).map_err(|source| SceneError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let Opened { gltf, bin, json } = open(path, &bytes)?;
    let doc = &gltf.document;
    let mut r = Reader {
        path,
        doc,
        buffers: Vec::new(),
        image_means: HashMap::new(),
    };
    r.load_buffers(bin)?;
    // MOZ_lightmap of each material (parsed only when the lightmaps or their UVs are asked
    // for: the UVs' reader needs each polygon's lightmap texture).
    let moz = match &lightmap {
        Some(_) => moz_lightmaps(path, json, doc.materials().count())?,
        None => Vec::new(),
    };
    // glTF material index → the lightmap set's material slot.
    let mut lightmap_slot: HashMap<usize, u32> = HashMap::new();

    let scene = doc
        .default_scene()
        .or_else(|| doc.scenes().next())
        .ok_or_else(|| invalid(path, "the file has no scene"))?;

    // Depth-first over the node tree, with world transforms.
    let mut stack: Vec<(::gltf::Node, DMat4, usize)> =
        scene.nodes().map(|n| (n, DMat4::IDENTITY, 0)).collect();
    stack.reverse();
    let node_count = doc.nodes().count();
    let mut materials: Vec<Material> = Vec::new();
    let mut material_of: HashMap<Option<usize>, (usize, bool)> = HashMap::new();
    let mut polygons: Vec<Polygon> = Vec::new();
    let mut camera: Option<Camera> = None;
    let (mut degenerate, mut clipped, mut group) = (0usize, 0usize, 0u32);
    let mut ignored: BTreeMap<&'static str, usize> = BTreeMap::new();
    while let Some((node, parent, depth)) = stack.pop() {
        if depth > node_count {
            return Err(invalid(
                path,
                format!("nodes[{}]: the node hierarchy has a cycle", node.index()),
            ));
        }
        let local =
            DMat4::from_cols_array_2d(&node.transform().matrix().map(|c| c.map(|x| x as f64)));
        let world = parent * local;
        for child in node.children().collect::<Vec<_>>().into_iter().rev() {
            stack.push((child, world, depth + 1));
        }
        if let (None, Some(cam)) = (camera, node.camera()) {
            match cam.projection() {
                ::gltf::camera::Projection::Perspective(p) => {
                    let eye = world.transform_point3(DVec3::ZERO);
                    let forward = world.transform_vector3(-DVec3::Z).normalize_or_zero();
                    let up = world.transform_vector3(DVec3::Y).normalize_or_zero();
                    let c = Camera {
                        eye: eye.as_vec3(),
                        target: (eye + forward).as_vec3(),
                        up: up.as_vec3(),
                        fov_y_deg: p.yfov().to_degrees(),
                    };
                    c.validate().map_err(|m| {
                        invalid(
                            path,
                            format!("cameras[{}] on nodes[{}]: {m}", cam.index(), node.index()),
                        )
                    })?;
                    camera = Some(c);
                }
                ::gltf::camera::Projection::Orthographic(_) => {
                    *ignored.entry("orthographic cameras").or_default() += 1;
                }
            }
        }
        if node.light().is_some() {
            *ignored
                .entry("punctual lights (only `lighting` reads them; here only emissive surfaces emit)")
                .or_default() += 1;
        }
        let Some(mesh) = node.mesh() else { continue };
        let mirrored = world.determinant() < 0.0;
        for prim in mesh.primitives() {
            let what = format!("meshes[{}].primitives[{}]", mesh.index(), prim.index());
            let mode = prim.mode();
            if !matches!(
                mode,
                Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
            ) {
                return Err(invalid(
                    path,
                    format!(
                        "{what}: mode {} ({}) is not supported: radiosity needs surfaces (TRIANGLES, TRIANGLE_STRIP or TRIANGLE_FAN)",
                        match mode {
                            Mode::Points => "POINTS",
                            Mode::Lines => "LINES",
                            Mode::LineLoop => "LINE_LOOP",
                            _ => "LINE_STRIP",
                        },
                        mode.as_gl_enum()
                    ),
                ));
            }
            let pos_acc = prim
                .get(&::gltf::Semantic::Positions)
                .ok_or_else(|| invalid(path, format!("{what} has no POSITION attribute")))?;
            let (pos, dims) = r.read(&pos_acc, &format!("{what}.POSITION"))?;
            if dims != 3 {
                return Err(invalid(path, format!("{what}: POSITION must be VEC3")));
            }
            let nverts = pos.len() / 3;
            let indices: Vec<u32> = match prim.indices() {
                Some(acc) => {
                    if !matches!(
                        acc.data_type(),
                        DataType::U8 | DataType::U16 | DataType::U32
                    ) || acc.dimensions() != Dimensions::Scalar
                    {
                        return Err(invalid(
                            path,
                            format!("{what}: indices must be unsigned integer scalars"),
                        ));
                    }
                    let (idx, _) = r.read(&acc, &format!("{what}.indices"))?;
                    let mut out = Vec::with_capacity(idx.len());
                    for (k, &i) in idx.iter().enumerate() {
                        if i as usize >= nverts {
                            return Err(invalid(
                                path,
                                format!("{what}: index {i} (entry {k} of accessors[{}]) is out of range: the primitive has {nverts} vertices", acc.index()),
                            ));
                        }
                        out.push(i as u32);
                    }
                    out
                }
                None => (0..nverts as u32).collect(),
            };
            let tris: Vec<[u32; 3]> = match mode {
                Mode::Triangles => {
                    if indices.len() % 3 != 0 {
                        return Err(invalid(
                            path,
                            format!(
                                "{what}: {} indices is not a multiple of 3 for TRIANGLES",
                                indices.len()
                            ),
                        ));
                    }
                    indices
                        .chunks_exact(3)
                        .map(|t| [t[0], t[1], t[2]])
                        .collect()
                }
                Mode::TriangleStrip => (0..indices.len().saturating_sub(2))
                    .map(|i| {
                        let (a, b, c) = (indices[i], indices[i + 1], indices[i + 2]);
                        if i % 2 == 0 {
                            [a, b, c]
                        } else {
                            [b, a, c]
                        }
                    })
                    .collect(),
                _ => (1..indices.len().saturating_sub(1))
                    .map(|i| [indices[0], indices[i], indices[i + 1]])
                    .collect(),
            };
            let corner_colours: Option<Vec<Rgb>> = match (&colours, prim.get(&which.semantic())) {
                (None, _) => None,
                (Some(_), None) => {
                    return Err(invalid(
                        path,
                        format!("{what} has no {} vertex values to show", which.name()),
                    ))
                }
                (Some(_), Some(acc)) => {
                    let (c, dims) = r.read(&acc, &format!("{what}.{}", which.name()))?;
                    if c.len() / dims.max(1) != nverts || dims < 3 {
                        return Err(invalid(
                            path,
                            format!(
                                "{what}: {} must be VEC3 or VEC4 with one value per vertex",
                                which.name()
                            ),
                        ));
                    }
                    Some(
                        c.chunks_exact(dims)
                            .map(|c| Rgb::new(c[0], c[1], c[2]))
                            .collect(),
                    )
                }
            };
            // The lightmap's UV set (and its material slot) when asked for.
            let mut texture: Option<u32> = None;
            let (corner_uvs, slot): (Option<Vec<[f32; 2]>>, Option<u32>) = match &mut lightmap {
                None => (None, None),
                Some((set, textures)) => {
                    let moz_of = prim
                        .material()
                        .index()
                        .and_then(|m| moz.get(m).copied().flatten().map(|z| (m, z)));
                    texture = moz_of.map(|(_, z)| z.index.min(u32::MAX as usize) as u32);
                    let (set_index, slot) = match (*textures, moz_of) {
                        (false, _) => (Some(1), None),
                        (true, None) => (None, None),
                        (true, Some((m, z))) => {
                            let slot = match lightmap_slot.get(&m) {
                                Some(s) => *s,
                                None => {
                                    let s = r.lightmap_material(set, &prim.material(), m, z)?;
                                    lightmap_slot.insert(m, s);
                                    s
                                }
                            };
                            (Some(z.tex_coord), Some(slot))
                        }
                    };
                    match set_index {
                        None => (None, None),
                        Some(k) => match prim.get(&::gltf::Semantic::TexCoords(k)) {
                            None if slot.is_some() => {
                                return Err(invalid(
                                    path,
                                    format!("{what}: its material's MOZ_lightmap reads TEXCOORD_{k}, which the primitive does not have"),
                                ))
                            }
                            None => (None, None),
                            Some(acc) => {
                                let name = format!("{what}.TEXCOORD_{k}");
                                let (c, dims) = r.read(&acc, &name)?;
                                if dims != 2 || c.len() / 2 != nverts {
                                    return Err(invalid(
                                        path,
                                        format!("{name}: must be VEC2 with one value per vertex"),
                                    ));
                                }
                                if let Some(i) = c.iter().position(|x| !x.is_finite()) {
                                    return Err(invalid(
                                        path,
                                        format!("{name}: element {} is not finite", i / 2),
                                    ));
                                }
                                (
                                    Some(
                                        c.chunks_exact(2)
                                            .map(|c| [c[0] as f32, c[1] as f32])
                                            .collect(),
                                    ),
                                    slot,
                                )
                            }
                        },
                    }
                }
            };
            // A baked or unlit material's COLOR_0 is light, not reflectance: expected, not lost.
            let baked = prim.material().unlit() || baked_material(&prim.material()).is_some();
            if colours.is_none() && !baked && prim.get(&::gltf::Semantic::Colors(0)).is_some() {
                *ignored
                    .entry("COLOR_0 vertex colours (reflectance is per material)")
                    .or_default() += 1;
            }
            let gm = prim.material();
            let (mat, double) = match material_of.get(&gm.index()) {
                Some(v) => *v,
                None => {
                    let (m, double) = r.material(&gm, &mut clipped)?;
                    let pbr = gm.pbr_metallic_roughness();
                    if pbr.metallic_factor() > 0.0
                        && gm.index().is_some()
                        && !gm.unlit()
                        && baked_material(&gm).is_none()
                    {
                        *ignored
                            .entry("metallic factors (surfaces are diffuse)")
                            .or_default() += 1;
                    }
                    materials.push(m);
                    let v = (materials.len() - 1, double);
                    material_of.insert(gm.index(), v);
                    v
                }
            };
            let world_pos: Vec<Vec3> = pos
                .chunks_exact(3)
                .map(|p| {
                    world
                        .transform_point3(DVec3::new(p[0], p[1], p[2]))
                        .as_vec3()
                })
                .collect();
            group += 1;
            let front = group;
            let back = if double && !one_sided {
                group += 1;
                Some(group)
            } else {
                None
            };
            for t in tris {
                let mut v = vec![
                    world_pos[t[0] as usize],
                    world_pos[t[1] as usize],
                    world_pos[t[2] as usize],
                ];
                if !v.iter().all(|p| p.is_finite()) {
                    return Err(invalid(
                        path,
                        format!("{what}: a vertex position is not finite"),
                    ));
                }
                if super::vector_area(&v).length() <= 0.0
                    || t[0] == t[1]
                    || t[1] == t[2]
                    || t[0] == t[2]
                {
                    degenerate += 1;
                    continue;
                }
                let mut corner = corner_colours
                    .as_ref()
                    .map(|c| [c[t[0] as usize], c[t[1] as usize], c[t[2] as usize]]);
                if mirrored {
                    v.reverse();
                    if let Some(c) = &mut corner {
                        c.reverse();
                    }
                }
                if let (Some(out), Some(c)) = (colours.as_deref_mut(), corner) {
                    out.push(c);
                    if back.is_some() {
                        out.push([c[2], c[1], c[0]]);
                    }
                }
                if let Some((set, _)) = &mut lightmap {
                    let mut uv = corner_uvs
                        .as_ref()
                        .map(|c| [c[t[0] as usize], c[t[1] as usize], c[t[2] as usize]]);
                    if mirrored {
                        if let Some(u) = &mut uv {
                            u.reverse();
                        }
                    }
                    set.uv.push(uv);
                    set.material.push(slot);
                    set.texture.push(texture);
                    if back.is_some() {
                        set.uv.push(uv.map(|u| [u[2], u[1], u[0]]));
                        set.material.push(slot);
                        set.texture.push(texture);
                    }
                }
                let reversed = back.map(|b| (v.iter().rev().copied().collect(), b));
                polygons.push(Polygon {
                    vertices: v,
                    material: mat,
                    line: 0,
                    group: front,
                });
                if let Some((vertices, b)) = reversed {
                    polygons.push(Polygon {
                        vertices,
                        material: mat,
                        line: 0,
                        group: b,
                    });
                }
            }
        }
    }
    // Slivers too thin for f32 relative to the scene (the threshold of Scene::validate) count
    // as degenerate too.
    let size = crate::geom::Aabb::from_points(polygons.iter().flat_map(|p| p.vertices.iter()))
        .diagonal() as f64;
    let before = polygons.len();
    let keep: Vec<bool> = polygons
        .iter()
        .map(|p| super::polygon_area(&p.vertices) > (1e-7 * size).powi(2))
        .collect();
    let mut k = 0;
    polygons.retain(|_| {
        k += 1;
        keep[k - 1]
    });
    if let Some(out) = colours {
        let mut k = 0;
        out.retain(|_| {
            k += 1;
            keep[k - 1]
        });
    }
    if let Some((set, _)) = lightmap {
        let mut k = 0;
        set.uv.retain(|_| {
            k += 1;
            keep[k - 1]
        });
        let mut k = 0;
        set.material.retain(|_| {
            k += 1;
            keep[k - 1]
        });
    }
    degenerate += before - polygons.len();
    let mut warnings = Vec::new();
    if degenerate > 0 {
        warnings.push(format!(
            "{}: skipped {degenerate} zero-area triangles",
            path.display()
        ));
    }
    if clipped > 0 {
        warnings.push(format!(
            "{}: {clipped} materials had a base colour brighter than a reflectance of {MAX_REFLECTANCE} and were scaled down to it",
            path.display()
        ));
    }
    if !ignored.is_empty() {
        let list: Vec<String> = ignored.iter().map(|(k, n)| format!("{k} ×{n}")).collect();
        warnings.push(format!("{}: ignored: {}", path.display(), list.join(", ")));
    }
    if polygons.is_empty() {
        return Err(invalid(path, "the scene has no triangles"));
    }
    Ok(Scene {
        name: super::name_of(path),
        source: Some(path.to_path_buf()),
        materials,
        polygons,
        camera,
        warnings,
        origins: vec![],
        up: Some(Vec3::Y),
    })
}

#[cfg(test)]
mod tests {
    /// Found by the fuzzer: invalid UTF-8 inside a string the typed parser skips, and a
    /// POSITION naming an accessor that is not there, made the `gltf` crate's validation
    /// index out of bounds. The reference check must see through the bad byte.
    #[test]
    fn invalid_utf8_does_not_hide_a_missing_accessor() {
        let dir = std::env::temp_dir().join(format!("radiosity-gltf-utf8-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let mut json = br#"{"asset":{"version":"2.0","generator":"x"#.to_vec();
        json.push(0xf5);
        json.extend_from_slice(br#""},"meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}]}"#);
        let path = dir.join("bad.gltf");
        std::fs::write(&path, &json).unwrap();
        let err = super::load_with(&path, false).unwrap_err().to_string();
        assert!(err.contains("no accessor 0"), "{err}");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
