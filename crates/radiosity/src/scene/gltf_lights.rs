//! The lights a glTF 2.0 file places in its scene, for lighting design
//! ([`crate::lighting::gltf`] turns them into luminaires):
//!
//! - `KHR_lights_punctual` **point** and **spot** lights: `intensity` is luminous intensity in
//!   candela (the extension's unit for both), `color` a linear RGB tint; a spot's
//!   `innerConeAngle` and `outerConeAngle` (radians, 0 ≤ inner < outer ≤ π/2) bound its cone.
//!   **Directional** lights are noted and left out (sunlight is daylight, not a luminaire);
//!   `range` is noted and ignored (light falls off by the inverse square law without a cut-off).
//! - `EXT_lights_ies` profiles: the file's root `extensions.EXT_lights_ies.lights` lists IES
//!   LM-63 files (a relative `uri`, a `data:` URI, or a `bufferView` with the media type
//!   `application/x-ies-lm-63`); a node's `extensions.EXT_lights_ies` places one with an
//!   optional `multiplier` (≥ 0) and `color`.
//!
//! Every light takes its node's world transform: it sits at the node's origin and points along
//! the node's −Z; the X/Y plane is its horizontal photometric plane and X its C = 0 direction
//! (the `EXT_lights_ies` coordinate mapping). The node's scale does not change its intensity.
//! Lights of nodes outside the default scene (or the first, when none is marked default) are
//! not in the scene and are not returned.
//!
//! **Errors** name the file and the JSON path: a light index out of range, a cone that is not
//! 0 ≤ inner < outer ≤ π/2, a negative or non-finite intensity, multiplier or colour, a profile
//! with neither `uri` nor `bufferView`, a bufferView past its buffer, a wrong media type.

use super::gltf::{invalid, open, Opened, Reader};
use super::SceneError;
use crate::color::Rgb;
use glam::{DMat4, DVec3};
use serde_json::Value;
use std::collections::HashMap;
use std::path::Path;

/// What a scene light sends: the shape of its distribution.
#[derive(Clone, Debug, PartialEq)]
pub enum LightKind {
    /// The same intensity in every direction (`KHR_lights_punctual` point).
    Point,
    /// A cone about the light's −Z (`KHR_lights_punctual` spot): full intensity within
    /// `inner`, none past `outer`, radians.
    Spot {
        /// The inner cone's half-angle, radians.
        inner: f64,
        /// The outer cone's half-angle, radians.
        outer: f64,
    },
    /// A measured distribution (`EXT_lights_ies`).
    Ies {
        /// The IES LM-63 file's bytes.
        profile: Vec<u8>,
        /// Where they came from, for messages: the file the URI names, or the bufferView.
        source: String,
    },
}

/// One light of a glTF scene, in world coordinates (metres, +y up).
#[derive(Clone, Debug, PartialEq)]
pub struct SceneLight {
    /// The light's name (the light's, else the node's, else `light N`).
    pub name: String,
    /// Its distribution.
    pub kind: LightKind,
    /// The node's origin in the world.
    pub position: [f64; 3],
    /// The world direction of the node's −Z, unit length: where a spot or a profile's
    /// (0, 0) points.
    pub direction: [f64; 3],
    /// The world direction of the node's +X, unit length: a profile's C = 0 direction.
    pub x_axis: [f64; 3],
    /// For point and spot lights the luminous intensity, candela; for a profile its
    /// `multiplier` (1 by default).
    pub intensity: f64,
    /// The linear tint (`color`, white by default).
    pub colour: Rgb,
}

/// The lights of a glTF file, and remarks about what was left out.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SceneLights {
    /// The scene's lights, in depth-first node order.
    pub lights: Vec<SceneLight>,
    /// One line each: lights left out or properties ignored.
    pub warnings: Vec<String>,
}

/// Read the lights of the glTF file at `path` (see the module documentation).
pub fn load_lights(path: &Path) -> Result<SceneLights, SceneError> {
    let bytes = crate::io::read_input(path).map_err(|source| SceneError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let Opened { gltf, json, bin } = open(path, &bytes)?;
    let doc = &gltf.document;
    let root: Value = serde_json::from_slice(json)
        .map_err(|e| invalid(path, format!("invalid glTF JSON: {e}")))?;
    let profiles = root
        .pointer("/extensions/EXT_lights_ies/lights")
        .map(|v| {
            v.as_array()
                .cloned()
                .ok_or_else(|| invalid(path, "extensions.EXT_lights_ies.lights must be an array"))
        })
        .transpose()?
        .unwrap_or_default();
    let mut r = Reader {
        path,
        doc,
        buffers: Vec::new(),
        image_means: HashMap::new(),
    };
    let mut out = SceneLights::default();
    let Some(scene) = doc.default_scene().or_else(|| doc.scenes().next()) else {
        return Ok(out);
    };
    if !profiles.is_empty() {
        r.load_buffers(bin)?;
    }
    // Each profile's bytes, read once however many nodes place it.
    let mut profile_bytes: HashMap<usize, (Vec<u8>, String)> = HashMap::new();
    let (mut directional, mut ranged) = (0usize, 0usize);
    let node_count = doc.nodes().count();
    let mut stack: Vec<(::gltf::Node, DMat4, usize)> =
        scene.nodes().map(|n| (n, DMat4::IDENTITY, 0)).collect();
    stack.reverse();
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
        let at = format!("nodes[{}]", node.index());
        let frame = || frame(path, &at, &world);
        if let Some(light) = node.light() {
            let what = format!("{at}: KHR_lights_punctual.lights[{}]", light.index());
            use ::gltf::khr_lights_punctual::Kind;
            let kind = match light.kind() {
                Kind::Directional => {
                    directional += 1;
                    None
                }
                Kind::Point => Some(LightKind::Point),
                Kind::Spot {
                    inner_cone_angle,
                    outer_cone_angle,
                } => {
                    let (inner, outer) = (inner_cone_angle as f64, outer_cone_angle as f64);
                    if !(inner >= 0.0 && inner < outer && outer <= std::f64::consts::FRAC_PI_2) {
                        return Err(invalid(
                            path,
                            format!(
                                "{what}: the spot's cone angles must satisfy 0 <= inner < outer \
                                 <= pi/2 radians (inner {inner}, outer {outer})"
                            ),
                        ));
                    }
                    Some(LightKind::Spot { inner, outer })
                }
            };
            if let Some(kind) = kind {
                let intensity = light.intensity() as f64;
                if !(intensity.is_finite() && intensity >= 0.0) {
                    return Err(invalid(
                        path,
                        format!("{what}: intensity {intensity} must be a finite number >= 0"),
                    ));
                }
                if light.range().is_some() {
                    ranged += 1;
                }
                let c = light.color();
                let colour = colour_of(path, &what, [c[0] as f64, c[1] as f64, c[2] as f64])?;
                let (position, direction, x_axis) = frame()?;
                let name = light
                    .name()
                    .or(node.name())
                    .map(str::to_string)
                    .unwrap_or_else(|| format!("light {}", out.lights.len() + 1));
                out.lights.push(SceneLight {
                    name,
                    kind,
                    position,
                    direction,
                    x_axis,
                    intensity,
                    colour,
                });
            }
        }
        let Some(ies) = root.pointer(&format!(
            "/nodes/{}/extensions/EXT_lights_ies",
            node.index()
        )) else {
            continue;
        };
        let what = format!("{at}.extensions.EXT_lights_ies");
        let index = ies
            .get("light")
            .and_then(Value::as_u64)
            .ok_or_else(|| invalid(path, format!("{what}: 'light' must be an index")))?;
        let Some(profile) = usize::try_from(index).ok().and_then(|i| profiles.get(i)) else {
            return Err(invalid(
                path,
                format!(
                    "{what}: light {index} is not in extensions.EXT_lights_ies.lights ({} profiles)",
                    profiles.len()
                ),
            ));
        };
        let index = index as usize;
        let multiplier = match ies.get("multiplier") {
            None => 1.0,
            Some(v) => match v.as_f64() {
                Some(m) if m.is_finite() && m >= 0.0 => m,
                _ => {
                    return Err(invalid(
                        path,
                        format!("{what}: 'multiplier' must be a finite number >= 0"),
                    ))
                }
            },
        };
        let colour = match ies.get("color") {
            None => Rgb::new(1.0, 1.0, 1.0),
            Some(v) => {
                let c: Option<Vec<f64>> = v
                    .as_array()
                    .filter(|a| a.len() == 3)
                    .map(|a| a.iter().filter_map(Value::as_f64).collect());
                match c {
                    Some(c) if c.len() == 3 => colour_of(path, &what, [c[0], c[1], c[2]])?,
                    _ => {
                        return Err(invalid(
                            path,
                            format!("{what}: 'color' must be an array of 3 numbers"),
                        ))
                    }
                }
            }
        };
        if let std::collections::hash_map::Entry::Vacant(e) = profile_bytes.entry(index) {
            e.insert(read_profile(&r, profile, index)?);
        }
        let (bytes, source) = &profile_bytes[&index];
        let (position, direction, x_axis) = frame()?;
        let name = profile
            .get("name")
            .and_then(Value::as_str)
            .filter(|n| !n.is_empty())
            .or(node.name())
            .map(str::to_string)
            .unwrap_or_else(|| format!("light {}", out.lights.len() + 1));
        out.lights.push(SceneLight {
            name,
            kind: LightKind::Ies {
                profile: bytes.clone(),
                source: source.clone(),
            },
            position,
            direction,
            x_axis,
            intensity: multiplier,
            colour,
        });
    }
    if directional > 0 {
        out.warnings.push(format!(
            "{}: {directional} directional light(s) left out (a luminaire is a point source; \
             sunlight is daylight)",
            path.display()
        ));
    }
    if ranged > 0 {
        out.warnings.push(format!(
            "{}: the 'range' of {ranged} light(s) ignored (light falls off by the inverse square \
             law without a cut-off)",
            path.display()
        ));
    }
    Ok(out)
}

/// A light's linear tint, checked: finite and ≥ 0 per channel.
fn colour_of(path: &Path, what: &str, c: [f64; 3]) -> Result<Rgb, SceneError> {
    if c.iter().all(|v| v.is_finite() && *v >= 0.0) {
        Ok(Rgb::new(c[0], c[1], c[2]))
    } else {
        Err(invalid(
            path,
            format!(
                "{what}: color [{}, {}, {}] must be finite and >= 0",
                c[0], c[1], c[2]
            ),
        ))
    }
}

/// A light's position, direction (−Z) and C = 0 axis (+X) in the world.
type Frame = ([f64; 3], [f64; 3], [f64; 3]);

/// The node's origin, −Z and +X in the world (the directions unit length). A transform that
/// collapses either direction is refused.
fn frame(path: &Path, at: &str, world: &DMat4) -> Result<Frame, SceneError> {
    let position = world.transform_point3(DVec3::ZERO);
    let direction = world.transform_vector3(-DVec3::Z).normalize_or_zero();
    let x_axis = world.transform_vector3(DVec3::X).normalize_or_zero();
    if !position.is_finite()
        || direction == DVec3::ZERO
        || x_axis == DVec3::ZERO
        || direction.cross(x_axis).length() < 1e-6
    {
        return Err(invalid(
            path,
            format!("{at}: the node's transform gives its light no position or direction"),
        ));
    }
    Ok((position.to_array(), direction.to_array(), x_axis.to_array()))
}

/// The bytes of profile `index` of `EXT_lights_ies.lights`, and where they came from.
fn read_profile(
    r: &Reader<'_>,
    profile: &Value,
    index: usize,
) -> Result<(Vec<u8>, String), SceneError> {
    let what = format!("extensions.EXT_lights_ies.lights[{index}]");
    if let Some(uri) = profile.get("uri") {
        let uri = uri
            .as_str()
            .ok_or_else(|| invalid(r.path, format!("{what}: 'uri' must be a string")))?;
        return r.resolve(uri, &what);
    }
    let Some(view) = profile.get("bufferView") else {
        return Err(invalid(
            r.path,
            format!("{what}: a profile needs a 'uri' or a 'bufferView'"),
        ));
    };
    match profile.get("mimeType").and_then(Value::as_str) {
        Some("application/x-ies-lm-63") => {}
        _ => {
            return Err(invalid(
                r.path,
                format!(
                "{what}: a profile in a bufferView needs the mimeType 'application/x-ies-lm-63'"
            ),
            ))
        }
    }
    let view = view
        .as_u64()
        .and_then(|v| r.doc.views().nth(usize::try_from(v).ok()?))
        .ok_or_else(|| {
            invalid(
                r.path,
                format!("{what}: 'bufferView' is not an index of the file's bufferViews"),
            )
        })?;
    let buffer = &r.buffers[view.buffer().index()];
    let (start, len) = (view.offset(), view.length());
    let bytes = start
        .checked_add(len)
        .and_then(|end| buffer.get(start..end))
        .ok_or_else(|| {
            invalid(
                r.path,
                format!(
                    "{what}: bufferViews[{}] ({len} bytes at {start}) reaches past its buffer of {} bytes",
                    view.index(),
                    buffer.len()
                ),
            )
        })?;
    Ok((
        bytes.to_vec(),
        format!("{what} (bufferViews[{}])", view.index()),
    ))
}
