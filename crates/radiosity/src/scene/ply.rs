//! PLY polygon files (Stanford Triangle Format): `ascii 1.0`, `binary_little_endian 1.0` and
//! `binary_big_endian 1.0`, with any scalar types (`char`…`double`, or `int8`…`float64`).
//!
//! **Elements read.** `vertex` and `face`; other elements (edges, materials, …) are read past and
//! ignored. Each face is one [`Polygon`]; all faces of the file form one smoothing group
//! ([`Polygon::group`]), so radiosity is interpolated across shared vertices except at creases.
//!
//! | element | property | meaning |
//! |---|---|---|
//! | vertex | `x`, `y`, `z` | position (required) |
//! | face | `vertex_indices` (or `vertex_index`) | list of at least 3 vertex indices, counter-clockwise seen from the front (required) |
//! | face or vertex | `reflectance_red`, `reflectance_green`, `reflectance_blue` | diffuse reflectance ρ, linear, each in `[0, 1)` |
//! | face or vertex | `red`, `green`, `blue` (or `diffuse_red`, …) | colour taken as reflectance: integer types are sRGB-encoded display values (0–255 for `uchar`) decoded to linear; `float`/`double` are linear in `[0, 1]` |
//! | face or vertex | `emission_red`, `emission_green`, `emission_blue`, or `emission` (grey) | emitted exitance E, W/m² per channel (≥ 0) |
//!
//! A face takes its own properties first, else the mean of its vertices'. `reflectance_*` beats a
//! colour. A colour brighter than a reflectance of [`MAX_REFLECTANCE`] (white, 255) is scaled
//! down to it, with a warning; an explicit `reflectance_*` must already be in `[0, 1)`. A file
//! with no reflectance or colour gets ρ = 0.5 grey. PLY has no unit: lengths are taken as they
//! are. PLY has no camera either; +y is taken as up (the convention of the Stanford scans), so a
//! room is viewed from inside ([`crate::render::camera::default_camera`]).
//!
//! **Errors** name the file and, for ASCII data, the line: a malformed header, a missing
//! `x`/`y`/`z` or `vertex_indices`, a number that does not parse, an index out of range, a face
//! with fewer than three vertices, and a header whose element counts do not match the data (the
//! data ending early, or going on after the last element).

use super::mgf::MAX_REFLECTANCE;
use super::{Material, Polygon, Scene, SceneError};
use crate::color::Rgb;
use crate::geom::Vec3;
use std::collections::HashMap;
use std::path::Path;

/// A scalar type of the format.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Ty {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Ty {
    fn parse(s: &str) -> Option<Ty> {
        Some(match s {
            "char" | "int8" => Ty::I8,
            "uchar" | "uint8" => Ty::U8,
            "short" | "int16" => Ty::I16,
            "ushort" | "uint16" => Ty::U16,
            "int" | "int32" => Ty::I32,
            "uint" | "uint32" => Ty::U32,
            "float" | "float32" => Ty::F32,
            "double" | "float64" => Ty::F64,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            Ty::I8 | Ty::U8 => 1,
            Ty::I16 | Ty::U16 => 2,
            Ty::I32 | Ty::U32 | Ty::F32 => 4,
            Ty::F64 => 8,
        }
    }

    fn is_float(self) -> bool {
        matches!(self, Ty::F32 | Ty::F64)
    }

    /// Largest value of an unsigned type (for colour scaling), 1 for floats.
    fn full_scale(self) -> f64 {
        match self {
            Ty::U8 | Ty::I8 => 255.0,
            Ty::U16 | Ty::I16 => 65535.0,
            Ty::U32 | Ty::I32 => u32::MAX as f64,
            Ty::F32 | Ty::F64 => 1.0,
        }
    }
}

#[derive(Clone, Debug)]
struct Property {
    name: String,
    /// `Some(count type)` for a list.
    list: Option<Ty>,
    ty: Ty,
}

#[derive(Clone, Debug)]
struct Element {
    name: String,
    count: usize,
    props: Vec<Property>,
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum Format {
    Ascii,
    Le,
    Be,
}

/// The data of one element: scalar columns by property name, and the one list property we use.
#[derive(Default)]
struct Columns {
    scalars: HashMap<String, (Ty, Vec<f64>)>,
    /// Flattened list entries and, per element, the end of its run.
    list: Vec<u32>,
    list_end: Vec<usize>,
    /// Line of each element (ASCII only).
    lines: Vec<u32>,
}

/// Where the data is read from, with enough context for messages.
struct Cursor<'a> {
    path: &'a Path,
    format: Format,
    bytes: &'a [u8],
    pos: usize,
    line: usize,
    /// Tokens of the current ASCII line not yet used.
    /// Tokens of the current ASCII line, and the next one to use (the buffer is reused).
    tokens: Vec<&'a str>,
    next: usize,
}

impl<'a> Cursor<'a> {
    fn fail(&self, message: String) -> SceneError {
        let at = match self.format {
            Format::Ascii => crate::loc::FileLoc::line(self.path, self.line),
            _ => crate::loc::FileLoc::file(self.path).with_item(crate::loc::Item::Byte(self.pos)),
        };
        SceneError::Invalid {
            at,
            message: crate::loc::shorten(message),
        }
    }

    /// The next ASCII token, moving to further lines as needed; `None` at the end of the data.
    fn token(&mut self) -> Option<&'a str> {
        loop {
            if let Some(&t) = self.tokens.get(self.next) {
                self.next += 1;
                return Some(t);
            }
            if self.pos >= self.bytes.len() {
                return None;
            }
            let rest = &self.bytes[self.pos..];
            let end = rest.iter().position(|&b| b == b'\n').unwrap_or(rest.len());
            let text = std::str::from_utf8(&rest[..end]).unwrap_or("\u{fffd}");
            self.pos += (end + 1).min(rest.len());
            self.line += 1;
            self.tokens.clear();
            self.tokens.extend(text.split_whitespace());
            self.next = 0;
        }
    }

    /// The next value of type `ty`, `None` at the end of the data.
    fn value(&mut self, ty: Ty, what: &dyn Fn() -> String) -> Result<Option<f64>, SceneError> {
        match self.format {
            Format::Ascii => {
                let Some(t) = self.token() else {
                    return Ok(None);
                };
                let v: f64 = t
                    .parse()
                    .map_err(|_| self.fail(format!("malformed number '{t}' for {}", what())))?;
                if !v.is_finite() {
                    return Err(self.fail(format!("{} value '{t}' is not finite", what())));
                }
                if !ty.is_float() && v.fract() != 0.0 {
                    return Err(self.fail(format!(
                        "{} is an integer property, but the value is '{t}'",
                        what()
                    )));
                }
                Ok(Some(v))
            }
            Format::Le | Format::Be => {
                let n = ty.size();
                if self.pos + n > self.bytes.len() {
                    return Ok(None);
                }
                let mut b = [0u8; 8];
                b[..n].copy_from_slice(&self.bytes[self.pos..self.pos + n]);
                if self.format == Format::Be {
                    b[..n].reverse();
                }
                self.pos += n;
                let v = match ty {
                    Ty::I8 => b[0] as i8 as f64,
                    Ty::U8 => b[0] as f64,
                    Ty::I16 => i16::from_le_bytes([b[0], b[1]]) as f64,
                    Ty::U16 => u16::from_le_bytes([b[0], b[1]]) as f64,
                    Ty::I32 => i32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
                    Ty::U32 => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
                    Ty::F32 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
                    Ty::F64 => f64::from_le_bytes(b),
                };
                if !v.is_finite() {
                    return Err(self.fail(format!("{} value is not finite", what())));
                }
                Ok(Some(v))
            }
        }
    }
}

fn invalid(path: &Path, line: usize, message: impl Into<String>) -> SceneError {
    SceneError::Invalid {
        at: crate::loc::FileLoc::line(path, line),
        message: crate::loc::shorten(message.into()),
    }
}

/// Parse the header; returns the format, the elements, the byte offset of the data and the
/// number of header lines.
fn header(path: &Path, bytes: &[u8]) -> Result<(Format, Vec<Element>, usize, usize), SceneError> {
    let mut pos = 0;
    let mut line = 0;
    let mut format = None;
    let mut elements: Vec<Element> = Vec::new();
    loop {
        if pos >= bytes.len() {
            return Err(invalid(path, line, "the header has no end_header line"));
        }
        let rest = &bytes[pos..];
        let end = rest
            .iter()
            .position(|&b| b == b'\n')
            .ok_or_else(|| invalid(path, line + 1, "the header has no end_header line"))?;
        pos += end + 1;
        line += 1;
        let text = std::str::from_utf8(&rest[..end])
            .map_err(|_| invalid(path, line, "the header is not text"))?
            .trim_end_matches('\r');
        let t: Vec<&str> = text.split_whitespace().collect();
        if line == 1 {
            if t != ["ply"] {
                return Err(invalid(
                    path,
                    1,
                    "not a PLY file: the first line must be 'ply'",
                ));
            }
            continue;
        }
        match t.as_slice() {
            [] | ["comment", ..] | ["obj_info", ..] => {}
            ["format", f, version] => {
                if *version != "1.0" {
                    return Err(invalid(
                        path,
                        line,
                        format!("PLY version {version} is not supported (only 1.0)"),
                    ));
                }
                format = Some(match *f {
                    "ascii" => Format::Ascii,
                    "binary_little_endian" => Format::Le,
                    "binary_big_endian" => Format::Be,
                    _ => return Err(invalid(path, line, format!("unknown PLY format '{f}'"))),
                });
            }
            ["element", name, count] => {
                let count: usize = count.parse().map_err(|_| {
                    invalid(
                        path,
                        line,
                        format!("element count '{count}' is not a non-negative integer"),
                    )
                })?;
                elements.push(Element {
                    name: name.to_string(),
                    count,
                    props: Vec::new(),
                });
            }
            ["property", "list", count_ty, item_ty, name] => {
                let e = elements
                    .last_mut()
                    .ok_or_else(|| invalid(path, line, "property before any element"))?;
                let c = Ty::parse(count_ty)
                    .filter(|t| !t.is_float())
                    .ok_or_else(|| {
                        invalid(path, line, format!("bad list count type '{count_ty}'"))
                    })?;
                let ty = Ty::parse(item_ty)
                    .ok_or_else(|| invalid(path, line, format!("unknown type '{item_ty}'")))?;
                e.props.push(Property {
                    name: name.to_string(),
                    list: Some(c),
                    ty,
                });
            }
            ["property", ty, name] => {
                let e = elements
                    .last_mut()
                    .ok_or_else(|| invalid(path, line, "property before any element"))?;
                let ty = Ty::parse(ty)
                    .ok_or_else(|| invalid(path, line, format!("unknown type '{ty}'")))?;
                e.props.push(Property {
                    name: name.to_string(),
                    list: None,
                    ty,
                });
            }
            ["end_header"] => break,
            _ => {
                return Err(invalid(
                    path,
                    line,
                    format!("unrecognised header line '{text}'"),
                ))
            }
        }
    }
    let format = format.ok_or_else(|| invalid(path, line, "the header has no format line"))?;
    Ok((format, elements, pos, line))
}

/// Read the data of one element into columns (only the properties named in `keep`, and the
/// list named `list`, are stored).
fn read_element(
    c: &mut Cursor,
    e: &Element,
    counts: &str,
    keep: &[&str],
    list: Option<&str>,
) -> Result<Columns, SceneError> {
    let mut cols = Columns::default();
    for p in &e.props {
        if p.list.is_none() && keep.contains(&p.name.as_str()) {
            cols.scalars.insert(
                p.name.clone(),
                (p.ty, Vec::with_capacity(e.count.min(c.bytes.len()))),
            );
        }
    }
    let short = |c: &Cursor, i: usize| {
        c.fail(format!(
            "the data ends in {} {i}, but the header declares {} {} elements",
            e.name, e.count, e.name
        ))
    };
    for i in 0..e.count {
        if c.format == Format::Ascii {
            // Each element starts on its own line.
            c.next = c.tokens.len();
        }
        for (k, p) in e.props.iter().enumerate() {
            let what = || format!("property '{}' of {} {i}", p.name, e.name);
            if k == 1 && c.format == Format::Ascii {
                // The first value has been read: the element starts on the current line.
                cols.lines.push(c.line as u32);
            }
            match p.list {
                None => {
                    let v = c.value(p.ty, &what)?.ok_or_else(|| short(c, i))?;
                    if let Some((_, col)) = cols.scalars.get_mut(&p.name) {
                        col.push(v);
                    }
                }
                Some(count_ty) => {
                    let n = c.value(count_ty, &what)?.ok_or_else(|| short(c, i))?;
                    if n < 0.0 {
                        return Err(c.fail(format!("{} has a negative list length", what())));
                    }
                    let store = list == Some(p.name.as_str());
                    for _ in 0..n as usize {
                        let v = c.value(p.ty, &what)?.ok_or_else(|| short(c, i))?;
                        if store {
                            if v < 0.0 || v > u32::MAX as f64 || v.fract() != 0.0 {
                                return Err(
                                    c.fail(format!("{}: '{v}' is not a vertex index", what()))
                                );
                            }
                            cols.list.push(v as u32);
                        }
                    }
                    if store {
                        cols.list_end.push(cols.list.len());
                    }
                }
            }
        }
        if c.format == Format::Ascii {
            if e.props.len() < 2 {
                cols.lines.push(c.line as u32);
            }
            if let Some(&t) = c.tokens.get(c.next) {
                return Err(c.fail(format!(
                    "{} {i} has more values than its {} properties (extra '{t}'): do the header's element counts ({counts}) match the data?",
                    e.name,
                    e.props.len(),
                )));
            }
        }
    }
    Ok(cols)
}

/// An RGB triple from columns `names`, element `i`: `Some((value, ty))` if all three exist.
fn rgb_of(cols: &Columns, names: [&str; 3], i: usize) -> Option<(Rgb, Ty)> {
    let r = cols.scalars.get(names[0])?;
    let g = cols.scalars.get(names[1])?;
    let b = cols.scalars.get(names[2])?;
    Some((Rgb::new(r.1[i], g.1[i], b.1[i]), r.0))
}

const REFLECTANCE: [&str; 3] = ["reflectance_red", "reflectance_green", "reflectance_blue"];
const COLOUR: [&str; 3] = ["red", "green", "blue"];
const DIFFUSE: [&str; 3] = ["diffuse_red", "diffuse_green", "diffuse_blue"];
const EMISSION: [&str; 3] = ["emission_red", "emission_green", "emission_blue"];

/// What an element (face or vertex) says about its material.
#[derive(Clone, Copy, Default)]
struct Says {
    reflectance: Option<Rgb>,
    colour: Option<Rgb>,
    emission: Option<Rgb>,
}

fn says(cols: &Columns, i: usize) -> Says {
    let colour = rgb_of(cols, COLOUR, i)
        .or_else(|| rgb_of(cols, DIFFUSE, i))
        .map(|(c, ty)| {
            if ty.is_float() {
                c
            } else {
                (c / ty.full_scale()).map(|v| crate::color::srgb_to_linear(v.clamp(0.0, 1.0)))
            }
        });
    let emission = rgb_of(cols, EMISSION, i)
        .map(|(c, _)| c)
        .or_else(|| cols.scalars.get("emission").map(|(_, v)| Rgb::splat(v[i])));
    Says {
        reflectance: rgb_of(cols, REFLECTANCE, i).map(|(c, _)| c),
        colour,
        emission,
    }
}

/// Load a PLY file.
pub fn load(path: &Path) -> Result<Scene, SceneError> {
    let bytes = crate::io::read_input(path).map_err(|source| SceneError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let (format, elements, start, header_lines) = header(path, &bytes)?;
    let vertex_el = elements
        .iter()
        .find(|e| e.name == "vertex")
        .ok_or_else(|| {
            invalid(
                path,
                header_lines,
                "the header declares no 'vertex' element",
            )
        })?;
    let face_el = elements
        .iter()
        .find(|e| e.name == "face")
        .ok_or_else(|| invalid(path, header_lines, "the header declares no 'face' element"))?;
    for axis in ["x", "y", "z"] {
        if !vertex_el
            .props
            .iter()
            .any(|p| p.name == axis && p.list.is_none())
        {
            return Err(invalid(
                path,
                header_lines,
                format!("the vertex element has no '{axis}' property"),
            ));
        }
    }
    let index_list = face_el
        .props
        .iter()
        .find(|p| p.list.is_some() && (p.name == "vertex_indices" || p.name == "vertex_index"))
        .map(|p| p.name.clone())
        .ok_or_else(|| {
            invalid(
                path,
                header_lines,
                "the face element has no 'vertex_indices' list",
            )
        })?;

    let mut keep: Vec<&str> = vec!["x", "y", "z", "emission"];
    for set in [REFLECTANCE, COLOUR, DIFFUSE, EMISSION] {
        keep.extend(set);
    }
    let mut cursor = Cursor {
        path,
        format,
        bytes: &bytes,
        pos: start,
        line: header_lines,
        tokens: Vec::new(),
        next: 0,
    };
    let counts = elements
        .iter()
        .map(|e| format!("{} {}", e.count, e.name))
        .collect::<Vec<_>>()
        .join(", ");
    let (mut vcols, mut fcols) = (None, None);
    for e in &elements {
        let list = (e.name == "face").then_some(index_list.as_str());
        let cols = read_element(&mut cursor, e, &counts, &keep, list)?;
        match e.name.as_str() {
            "vertex" if vcols.is_none() => vcols = Some(cols),
            "face" if fcols.is_none() => fcols = Some(cols),
            _ => {}
        }
    }
    // Anything after the last element means the header undercounts.
    let trailing = match format {
        Format::Ascii => cursor.token().is_some(),
        _ => cursor.pos < bytes.len(),
    };
    if trailing {
        return Err(cursor.fail(format!(
            "the data goes on after the elements the header declares ({counts})"
        )));
    }
    let (v, f) = (vcols.unwrap_or_default(), fcols.unwrap_or_default());
    let xs = &v.scalars["x"].1;
    let ys = &v.scalars["y"].1;
    let zs = &v.scalars["z"].1;
    let positions: Vec<Vec3> = (0..xs.len())
        .map(|i| Vec3::new(xs[i] as f32, ys[i] as f32, zs[i] as f32))
        .collect();
    let vertex_says: Vec<Says> = (0..positions.len()).map(|i| says(&v, i)).collect();

    let mut materials: Vec<Material> = Vec::new();
    let mut material_of: HashMap<[u64; 6], usize> = HashMap::new();
    let mut polygons = Vec::with_capacity(f.list_end.len());
    let (mut clipped, mut uncoloured) = (0usize, 0usize);
    let mut start_idx = 0;
    for (i, &end) in f.list_end.iter().enumerate() {
        let idx = &f.list[start_idx..end];
        start_idx = end;
        let line = f.lines.get(i).copied().unwrap_or(0) as usize;
        let place = |m: String| match format {
            Format::Ascii => invalid(path, line, m),
            _ => SceneError::Invalid {
                at: crate::loc::FileLoc::file(path).with_item(crate::loc::Item::Face(i)),
                message: crate::loc::shorten(m),
            },
        };
        if idx.len() < 3 {
            return Err(place(format!(
                "face {i} has {} vertices; at least 3 needed",
                idx.len()
            )));
        }
        if let Some(&bad) = idx.iter().find(|&&k| k as usize >= positions.len()) {
            return Err(place(format!(
                "face {i}: vertex index {bad} is out of range (the file has {} vertices)",
                positions.len()
            )));
        }
        // The face's own properties, else the mean of its vertices'.
        let own = says(&f, i);
        let mean = |get: &dyn Fn(&Says) -> Option<Rgb>| -> Option<Rgb> {
            let vals: Option<Vec<Rgb>> =
                idx.iter().map(|&k| get(&vertex_says[k as usize])).collect();
            vals.map(|vs| vs.iter().copied().sum::<Rgb>() / vs.len() as f64)
        };
        let reflectance = own.reflectance.or_else(|| mean(&|s| s.reflectance));
        let rho = match reflectance {
            Some(r) => {
                if r.min_channel() < 0.0 || r.max_channel() >= 1.0 {
                    return Err(place(format!(
                        "face {i}: reflectance {r} must have every channel in [0, 1)"
                    )));
                }
                r
            }
            None => match own.colour.or_else(|| mean(&|s| s.colour)) {
                Some(c) if c.max_channel() > MAX_REFLECTANCE => {
                    clipped += 1;
                    c * (MAX_REFLECTANCE / c.max_channel())
                }
                Some(c) => c,
                None => {
                    uncoloured += 1;
                    Rgb::splat(super::obj::DEFAULT_REFLECTANCE)
                }
            },
        };
        let e = own
            .emission
            .or_else(|| mean(&|s| s.emission))
            .unwrap_or(Rgb::BLACK);
        if e.min_channel() < 0.0 {
            return Err(place(format!(
                "face {i}: emission {e} must be non-negative"
            )));
        }
        let key = [
            rho.r.to_bits(),
            rho.g.to_bits(),
            rho.b.to_bits(),
            e.r.to_bits(),
            e.g.to_bits(),
            e.b.to_bits(),
        ];
        let material = *material_of.entry(key).or_insert_with(|| {
            materials.push(Material::emitter(
                &format!("ply{}", materials.len()),
                rho,
                e,
            ));
            materials.len() - 1
        });
        polygons.push(Polygon {
            vertices: idx.iter().map(|&k| positions[k as usize]).collect(),
            material,
            line: line as u32,
            group: 1,
        });
    }
    let mut warnings = Vec::new();
    if clipped > 0 {
        warnings.push(format!(
            "{}: {clipped} faces had a colour brighter than a reflectance of {MAX_REFLECTANCE} and were scaled down to it",
            path.display()
        ));
    }
    if uncoloured > 0 && uncoloured < polygons.len() {
        warnings.push(format!(
            "{}: {uncoloured} faces have no colour and get reflectance {}",
            path.display(),
            super::obj::DEFAULT_REFLECTANCE
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
        up: Some(Vec3::Y),
    })
}
