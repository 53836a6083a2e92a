//! Wavefront OBJ with MTL materials.
//!
//! Read: `v` (positions), `f` (polygons; `i`, `i/t`, `i//n`, `i/t/n` forms, negative indices
//! relative to the end), `usemtl`, `mtllib`. From MTL: `newmtl`, `Kd` (→ reflectance ρ) and `Ke`
//! (→ emission E, W/m²). Faces before any `usemtl`, and every face of an OBJ without `mtllib`,
//! get the default material: ρ = 0.5 grey, no emission. `vt`, `vn`, `o`, `g`, `s` are ignored
//! silently; other statements are counted and reported as one warning.
//!
//! Errors name the file and line: an unreadable file, a malformed number, a non-finite vertex, a
//! face index out of range, a face with fewer than three vertices, an unknown material, a `Kd`
//! outside `[0, 1)` or a negative `Ke`.

use super::{Material, Polygon, Scene, SceneError};
use crate::color::Rgb;
use crate::geom::Vec3;
use crate::loc::FileLoc;
use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};

/// Reflectance of the default material.
pub const DEFAULT_REFLECTANCE: f64 = 0.5;

fn invalid(path: &Path, line: usize, message: impl Into<String>) -> SceneError {
    SceneError::Invalid {
        at: FileLoc::line(path, line),
        message: crate::loc::shorten(message.into()),
    }
}

/// A text file, or an error naming it.
pub(super) fn read(path: &Path) -> Result<String, SceneError> {
    let bytes = crate::io::read_input(path).map_err(|source| SceneError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let text = String::from_utf8(bytes).map_err(|e| SceneError::Invalid {
        at: FileLoc::file(path),
        message: format!(
            "not UTF-8 text (invalid byte at offset {})",
            e.utf8_error().valid_up_to()
        ),
    })?;
    if let Some(line) = crate::io::overlong_line(&text) {
        return Err(invalid(
            path,
            line,
            format!("a line longer than {} MiB", crate::io::MAX_LINE_BYTES >> 20),
        ));
    }
    Ok(text)
}

/// A finite number, or an error naming the file, line and token.
pub(super) fn parse_f64(
    path: &Path,
    line: usize,
    tok: &str,
    what: &str,
) -> Result<f64, SceneError> {
    let v: f64 = tok
        .parse()
        .map_err(|_| invalid(path, line, format!("malformed number '{tok}' in {what}")))?;
    if !v.is_finite() {
        return Err(invalid(
            path,
            line,
            format!("{what} value '{tok}' is not finite"),
        ));
    }
    Ok(v)
}

/// Parse an RGB statement (`Kd r g b` or `Kd v`).
fn parse_rgb(path: &Path, line: usize, args: &[&str], what: &str) -> Result<Rgb, SceneError> {
    match args {
        [v] => Ok(Rgb::splat(parse_f64(path, line, v, what)?)),
        [r, g, b, ..] => Ok(Rgb::new(
            parse_f64(path, line, r, what)?,
            parse_f64(path, line, g, what)?,
            parse_f64(path, line, b, what)?,
        )),
        _ => Err(invalid(path, line, format!("{what} needs 1 or 3 numbers"))),
    }
}

/// Read an MTL file into `materials` (name → material).
fn load_mtl(
    path: &Path,
    out: &mut Vec<Material>,
    names: &mut HashMap<String, usize>,
) -> Result<(), SceneError> {
    let text = read(path)?;
    let mut current: Option<usize> = None;
    // Per material of this file: its transmission filter `Tf` and transparency (1 − `d`, or
    // `Tr`); its transmittance is their product (Y of the filter), set at the end.
    let mut see_through: HashMap<usize, (Rgb, f64)> = HashMap::new();
    for (k, raw) in text.lines().enumerate() {
        let line = k + 1;
        let s = raw.split('#').next().unwrap_or("").trim();
        let mut toks = s.split_whitespace();
        let Some(key) = toks.next() else { continue };
        let args: Vec<&str> = toks.collect();
        match key {
            "newmtl" => {
                let name = args.join(" ");
                if name.is_empty() {
                    return Err(invalid(path, line, "newmtl without a name"));
                }
                let idx = out.len();
                out.push(Material::diffuse(&name, Rgb::splat(DEFAULT_REFLECTANCE)));
                names.insert(name, idx);
                current = Some(idx);
            }
            "Kd" | "Ke" => {
                let Some(m) = current else {
                    return Err(invalid(path, line, format!("{key} before any newmtl")));
                };
                let c = parse_rgb(path, line, &args, key)?;
                if key == "Kd" {
                    if c.min_channel() < 0.0 || c.max_channel() >= 1.0 {
                        return Err(invalid(
                            path,
                            line,
                            format!(
                                "Kd {} {} {}: diffuse reflectance must be in [0, 1) (a surface cannot reflect all the light it receives)",
                                c.r, c.g, c.b
                            ),
                        ));
                    }
                    out[m].reflectance = c;
                } else {
                    if c.min_channel() < 0.0 {
                        return Err(invalid(
                            path,
                            line,
                            format!("Ke {} {} {}: emission must be non-negative", c.r, c.g, c.b),
                        ));
                    }
                    out[m].emission = c;
                }
            }
            "Tf" | "d" | "Tr" => {
                let Some(m) = current else {
                    return Err(invalid(path, line, format!("{key} before any newmtl")));
                };
                let e = see_through.entry(m).or_insert((Rgb::splat(1.0), 0.0));
                if key == "Tf" {
                    let c = parse_rgb(path, line, &args, key)?;
                    if c.min_channel() < 0.0 || c.max_channel() > 1.0 {
                        return Err(invalid(
                            path,
                            line,
                            format!(
                                "Tf {} {} {}: a transmission filter must be in [0, 1]",
                                c.r, c.g, c.b
                            ),
                        ));
                    }
                    e.0 = c;
                } else {
                    // `d -halo v`: the halo form is read as plain dissolve.
                    let v = args
                        .iter()
                        .rfind(|a| !a.starts_with('-'))
                        .ok_or_else(|| invalid(path, line, format!("{key} needs a number")))?;
                    let v = parse_f64(path, line, v, key)?;
                    if !(0.0..=1.0).contains(&v) {
                        return Err(invalid(path, line, format!("{key} {v}: must be in [0, 1]")));
                    }
                    e.1 = if key == "d" { 1.0 - v } else { v };
                }
            }
            _ => {}
        }
    }
    for (m, (tf, t)) in see_through {
        out[m].transmittance = t * (0.2126 * tf.r + 0.7152 * tf.g + 0.0722 * tf.b);
    }
    Ok(())
}

/// Resolve an OBJ vertex reference (1-based, negative = relative) against `count` vertices.
fn vertex_index(path: &Path, line: usize, tok: &str, count: usize) -> Result<usize, SceneError> {
    let first = tok.split('/').next().unwrap_or("");
    let i: i64 = first
        .parse()
        .map_err(|_| invalid(path, line, format!("malformed face vertex '{tok}'")))?;
    let resolved = if i > 0 { i - 1 } else { count as i64 + i };
    if i == 0 || resolved < 0 || resolved >= count as i64 {
        return Err(invalid(
            path,
            line,
            format!("face vertex index {i} out of range (1..={count} defined so far)"),
        ));
    }
    Ok(resolved as usize)
}

/// Load an OBJ file (and the MTL files it names, relative to its folder).
pub fn load(path: &Path) -> Result<Scene, SceneError> {
    let text = read(path)?;
    let dir = path
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_else(|| PathBuf::from("."));
    let mut positions: Vec<Vec3> = Vec::new();
    let mut materials: Vec<Material> = Vec::new();
    let mut names: HashMap<String, usize> = HashMap::new();
    let mut default_material: Option<usize> = None;
    let mut current: Option<usize> = None;
    let mut polygons = Vec::new();
    let mut ignored: BTreeMap<String, usize> = BTreeMap::new();
    let mut face = Vec::with_capacity(8);
    for (k, raw) in text.lines().enumerate() {
        let line = k + 1;
        let s = raw.split('#').next().unwrap_or("").trim();
        let mut toks = s.split_whitespace();
        let Some(key) = toks.next() else { continue };
        match key {
            "v" => {
                let args: Vec<&str> = toks.collect();
                if args.len() < 3 {
                    return Err(invalid(path, line, "vertex needs 3 coordinates"));
                }
                let mut c = [0f32; 3];
                for a in 0..3 {
                    let x = args[a].parse::<f32>().map_err(|_| {
                        invalid(
                            path,
                            line,
                            format!("malformed number '{}' in vertex", args[a]),
                        )
                    })?;
                    if !x.is_finite() {
                        return Err(invalid(
                            path,
                            line,
                            format!("vertex coordinate '{}' is not finite", args[a]),
                        ));
                    }
                    c[a] = x;
                }
                positions.push(Vec3::from_array(c));
            }
            "f" => {
                face.clear();
                for tok in toks {
                    face.push(positions[vertex_index(path, line, tok, positions.len())?]);
                }
                if face.len() < 3 {
                    return Err(invalid(
                        path,
                        line,
                        format!("face has {} vertices; at least 3 needed", face.len()),
                    ));
                }
                let material = match current {
                    Some(m) => m,
                    None => *default_material.get_or_insert_with(|| {
                        materials.push(Material::diffuse(
                            "default",
                            Rgb::splat(DEFAULT_REFLECTANCE),
                        ));
                        materials.len() - 1
                    }),
                };
                polygons.push(Polygon {
                    vertices: face.clone(),
                    material,
                    line: line as u32,
                    group: 0,
                });
            }
            "mtllib" => {
                let rest = s[key.len()..].trim();
                if rest.is_empty() {
                    return Err(invalid(path, line, "mtllib without a file name"));
                }
                let mtl = dir.join(rest);
                if !mtl.exists() {
                    return Err(invalid(
                        path,
                        line,
                        format!("material library '{}' not found", mtl.display()),
                    ));
                }
                load_mtl(&mtl, &mut materials, &mut names).map_err(|e| match e {
                    SceneError::Io { path: lib, source } => invalid(
                        path,
                        line,
                        format!("material library {}: {source}", lib.display()),
                    ),
                    other => other,
                })?;
            }
            "usemtl" => {
                let name = s[key.len()..].trim();
                current = Some(*names.get(name).ok_or_else(|| {
                    invalid(
                        path,
                        line,
                        format!("unknown material '{name}' (not defined by any mtllib)"),
                    )
                })?);
            }
            "vt" | "vn" | "o" | "g" | "s" => {}
            other => *ignored.entry(other.to_string()).or_default() += 1,
        }
    }
    let mut warnings = Vec::new();
    if !ignored.is_empty() {
        let list: Vec<String> = ignored.iter().map(|(k, n)| format!("{k} ×{n}")).collect();
        warnings.push(format!(
            "{}: ignored statements: {}",
            path.display(),
            list.join(", ")
        ));
    }
    if default_material.is_some() {
        warnings.push(format!(
            "{}: faces without a material got the default (reflectance {DEFAULT_REFLECTANCE}, no emission)",
            path.display()
        ));
    }
    Ok(Scene {
        name: super::name_of(path),
        source: Some(path.to_path_buf()),
        materials,
        polygons,
        camera: None,
        warnings,
        origins: vec![],
        up: None,
    })
}
