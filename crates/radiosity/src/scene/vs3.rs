//! NIST View3D's input format, `.vs3` (G. Walton, *View3D 3.2 User's Manual*, NISTIR 6925, 2002;
//! View3D 4.0's `doc/view3d-manual.tex`), both geometry forms:
//!
//! - `F 3`: vertices `V n x y z`, then surfaces `S n v1 v2 v3 v4 base cmb emit name` (v4 = 0 for
//!   a triangle; vertices counter-clockwise seen from the active side);
//! - `F 3a`: `S n shape base cmb emit name` followed by `x y z azimuth tilt` and the shape's
//!   plane coordinates (`R` width height, `Q` four x y pairs, `T` three), placed as View3D's
//!   `GetVS3Da` places them (azimuth clockwise from +y, tilt 0 facing up, 90 vertical).
//!
//! Also read: `T` title, `C` control (`encl`, `emit`, `eps`, `maxU`, `maxO`, `minO`, `row`,
//! `col`, `out`, `list`), `O` obstruction surfaces (non-radiating: they block views and are left
//! out of View3D-format output), combined surfaces (`cmb`: several convex pieces reported as
//! one surface), comments (`!` anywhere, `/` at the start of a line) and `E`/`*` end of data.
//! Subsurfaces (base ≠ 0), masks `M` and null surfaces `N` are refused with a located error.
//!
//! Each reported surface becomes one material named as the surface, grey with reflectance
//! 1 − ε and no emission; a combined surface's pieces share the material of the surface they
//! combine into; an obstruction gets a material `obstruction-<n>` of reflectance 0.

use super::{Material, Polygon, Scene, SceneError};
use crate::color::Rgb;
use crate::geom::Vec3;
use crate::loc::FileLoc;
use std::path::Path;

/// What kind of surface a `.vs3` surface is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SurfaceKind {
    /// `S`: a radiating surface.
    Radiating,
    /// `O`: blocks views, has no view factors of its own.
    Obstruction,
}

/// One input surface of a `.vs3` file (polygon `k` of the scene is surface `k + 1`).
#[derive(Clone, Debug, PartialEq)]
pub struct Surface {
    /// Its name (obstructions: `obstruction-<n>`).
    pub name: String,
    /// Radiating or obstruction.
    pub kind: SurfaceKind,
    /// Emissivity (0 for obstructions).
    pub emissivity: f64,
    /// The surface (0-based) it is combined into, if any.
    pub combined_into: Option<usize>,
    /// Line of the file.
    pub line: usize,
}

/// The `C` line's parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct Control {
    /// `encl=1`: the surfaces form a closed enclosure (rows are normalised to sum to 1).
    pub enclosure: bool,
    /// `emit=1`: report Hottel's total exchange factors (script-F) instead of view factors.
    pub emit: bool,
    /// `eps`: View3D's integration convergence criterion (default 1e-4).
    pub eps: f64,
    /// Parameters of View3D's own integrator and output that have no counterpart here
    /// (`maxU`, `maxO`, `minO`, `out`, `row`, `col`), as written (`list`, its log detail, is
    /// dropped).
    pub unmapped: Vec<String>,
}

impl Default for Control {
    fn default() -> Self {
        Self {
            enclosure: false,
            emit: false,
            eps: 1e-4,
            unmapped: Vec::new(),
        }
    }
}

/// A `.vs3` file read: the scene and what View3D knows of its surfaces.
#[derive(Clone, Debug)]
pub struct Vs3 {
    /// The geometry, one polygon per input surface, in order.
    pub scene: Scene,
    /// The input surfaces.
    pub surfaces: Vec<Surface>,
    /// The reported surfaces in View3D's order (radiating surfaces not combined into another),
    /// as material indices of the scene.
    pub reported: Vec<usize>,
    /// The control line.
    pub control: Control,
    /// The last title line.
    pub title: String,
}

/// Most surfaces or vertices of one file: far past View3D's own examples and real models, and
/// a bound on what a hostile count can make us allocate before reading the data itself.
pub const MAX_ITEMS: usize = 10_000_000;

fn invalid(path: &Path, line: usize, message: impl Into<String>) -> SceneError {
    SceneError::Invalid {
        at: FileLoc::line(path, line),
        message: crate::loc::shorten(message.into()),
    }
}

/// The words of every line, comments removed, with their line numbers.
fn words(text: &str) -> Vec<(usize, Vec<&str>)> {
    text.lines()
        .enumerate()
        .map(|(k, l)| {
            let l = l.split('!').next().unwrap_or("");
            let t = l.trim_start();
            let w = if t.starts_with('/') {
                Vec::new()
            } else {
                t.split_whitespace().collect()
            };
            (k + 1, w)
        })
        .collect()
}

/// A cursor over the words of the lines from one element on: an element's numbers may run
/// onto the following lines (View3D reads words, not lines).
struct Cursor<'a, 'p> {
    lines: &'a [(usize, Vec<&'a str>)],
    at: usize,
    word: usize,
    path: &'p Path,
}

impl<'a> Cursor<'a, '_> {
    fn line(&self) -> usize {
        self.lines
            .get(self.at)
            .map_or_else(|| self.lines.last().map_or(0, |l| l.0), |l| l.0)
    }

    fn next(&mut self, what: &str) -> Result<&'a str, SceneError> {
        while let Some((_, w)) = self.lines.get(self.at) {
            if let Some(s) = w.get(self.word) {
                self.word += 1;
                return Ok(s);
            }
            self.at += 1;
            self.word = 0;
        }
        Err(invalid(
            self.path,
            self.line(),
            format!("the file ends where {what} was expected"),
        ))
    }

    fn number(&mut self, what: &str) -> Result<f64, SceneError> {
        let line = self.line();
        let w = self.next(what)?;
        match w.parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(v),
            _ => Err(invalid(
                self.path,
                self.line().max(line),
                format!("{what}: '{w}' is not a finite number"),
            )),
        }
    }

    fn integer(&mut self, what: &str) -> Result<i64, SceneError> {
        let w = self.next(what)?;
        w.parse::<i64>().map_err(|_| {
            invalid(
                self.path,
                self.line(),
                format!("{what}: '{w}' is not an integer"),
            )
        })
    }
}

/// Read a `.vs3` file.
pub fn load(path: &Path) -> Result<Vs3, SceneError> {
    let text = super::obj::read(path)?;
    parse(path, &text)
}

/// [`load`] on text already read.
pub fn parse(path: &Path, text: &str) -> Result<Vs3, SceneError> {
    let lines = words(text);
    let raw: Vec<&str> = text.lines().collect();
    let mut format: Option<bool> = None; // Some(true) = 3a
    let mut control = Control::default();
    let mut title = String::new();
    let mut vertices: Vec<Vec3> = Vec::new();
    let mut surfaces: Vec<Surface> = Vec::new();
    let mut polygons: Vec<Vec<Vec3>> = Vec::new();
    let mut warnings = Vec::new();
    let mut k = 0;
    while k < lines.len() {
        let (line, ref w) = lines[k];
        let Some(first) = w.first() else {
            k += 1;
            continue;
        };
        let key = first.chars().next().unwrap_or(' ').to_ascii_uppercase();
        let mut cursor = Cursor {
            lines: &lines,
            at: k,
            word: 1,
            path,
        };
        match key {
            'T' => {
                title = raw[line - 1]
                    .trim_start()
                    .get(1..)
                    .unwrap_or("")
                    .trim()
                    .to_string();
            }
            '*' | 'E' => break,
            'C' => {
                // name=value pairs, separated by blanks, '=' or ','.
                let rest: Vec<&str> = w[1..]
                    .iter()
                    .flat_map(|s| s.split(['=', ',']))
                    .filter(|s| !s.is_empty())
                    .collect();
                let mut i = 0;
                while i < rest.len() {
                    let name = rest[i].to_ascii_lowercase();
                    let Some(value) = rest.get(i + 1) else {
                        return Err(invalid(
                            path,
                            line,
                            format!("control parameter '{}' has no value", rest[i]),
                        ));
                    };
                    let int = || {
                        value.parse::<i64>().map_err(|_| {
                            invalid(
                                path,
                                line,
                                format!("control {}={value}: not an integer", rest[i]),
                            )
                        })
                    };
                    match name.as_str() {
                        "encl" => control.enclosure = int()? != 0,
                        "emit" => control.emit = int()? != 0,
                        "eps" => {
                            control.eps = match value.parse::<f64>() {
                                Ok(v) if v.is_finite() && v > 0.0 => v,
                                _ => {
                                    return Err(invalid(
                                        path,
                                        line,
                                        format!("control eps={value}: not a positive number"),
                                    ))
                                }
                            }
                        }
                        // Log detail: nothing to map.
                        "list" => {
                            int()?;
                        }
                        "maxu" | "maxo" | "mino" | "row" | "col" | "out" | "prjreb" => {
                            int()?;
                            control.unmapped.push(format!("{}={value}", rest[i]));
                        }
                        _ => {
                            return Err(invalid(
                                path,
                                line,
                                format!(
                                    "unknown control parameter '{}' (View3D's are eps, maxU, maxO, minO, row, col, encl, emit, out, list)",
                                    rest[i]
                                ),
                            ))
                        }
                    }
                    i += 2;
                }
            }
            'F' => {
                let g = cursor.next("the geometry format")?;
                format = Some(match g.to_ascii_lowercase().as_str() {
                    "3" => false,
                    "3a" => true,
                    _ => {
                        return Err(invalid(
                            path,
                            line,
                            format!("geometry format 'F {g}' is not supported (F 3 and F 3a are)"),
                        ))
                    }
                });
            }
            'X' => warnings.push(format!(
                "{}:{line}: coordinate transformation lines are ignored (as View3D does)",
                path.display()
            )),
            'V' => {
                if format != Some(false) {
                    return Err(invalid(
                        path,
                        line,
                        "a vertex line needs 'F 3' before it (F 3a surfaces carry their own vertices)",
                    ));
                }
                let n = cursor.integer("the vertex number")?;
                if n != vertices.len() as i64 + 1 {
                    return Err(invalid(
                        path,
                        line,
                        format!(
                            "vertex {n} out of sequence (expected {})",
                            vertices.len() + 1
                        ),
                    ));
                }
                if vertices.len() >= MAX_ITEMS {
                    return Err(invalid(
                        path,
                        line,
                        format!("more than {MAX_ITEMS} vertices"),
                    ));
                }
                let x = cursor.number("x")?;
                let y = cursor.number("y")?;
                let z = cursor.number("z")?;
                vertices.push(Vec3::new(x as f32, y as f32, z as f32));
            }
            'S' | 'O' | 'M' | 'N' => {
                let Some(three_a) = format else {
                    return Err(invalid(
                        path,
                        line,
                        "a surface line needs the geometry format ('F 3' or 'F 3a') before it",
                    ));
                };
                if key == 'M' || key == 'N' {
                    return Err(invalid(
                        path,
                        line,
                        format!(
                            "{} surfaces are not supported; describe the visible part of the base as separate surfaces combined with 'cmb'",
                            if key == 'M' { "masking (M)" } else { "null (N)" }
                        ),
                    ));
                }
                let n = cursor.integer("the surface number")?;
                if n != surfaces.len() as i64 + 1 {
                    return Err(invalid(
                        path,
                        line,
                        format!(
                            "surface {n} out of sequence (expected {})",
                            surfaces.len() + 1
                        ),
                    ));
                }
                if surfaces.len() >= MAX_ITEMS {
                    return Err(invalid(
                        path,
                        line,
                        format!("more than {MAX_ITEMS} surfaces"),
                    ));
                }
                let ns = surfaces.len();
                let (vs, data) = if three_a {
                    let shape = cursor.next("the shape (R, Q or T)")?.to_ascii_uppercase();
                    let data = if key == 'O' {
                        None
                    } else {
                        Some(surface_data(&mut cursor, &surfaces, ns, line)?)
                    };
                    let o = Vec3::new(
                        cursor.number("the plane's origin x")? as f32,
                        cursor.number("the plane's origin y")? as f32,
                        cursor.number("the plane's origin z")? as f32,
                    );
                    let azimuth = cursor.number("the azimuth")?.to_radians();
                    let tilt = cursor.number("the tilt")?.to_radians();
                    let local: Vec<(f64, f64)> = match shape.as_str() {
                        "R" => {
                            let w = cursor.number("the width")?;
                            let h = cursor.number("the height")?;
                            vec![(0.0, h), (0.0, 0.0), (w, 0.0), (w, h)]
                        }
                        "Q" | "T" => {
                            let m = if shape == "Q" { 4 } else { 3 };
                            let mut v = Vec::with_capacity(m);
                            for _ in 0..m {
                                v.push((cursor.number("x")?, cursor.number("y")?));
                            }
                            v
                        }
                        _ => {
                            return Err(invalid(
                                path,
                                line,
                                format!("surface {n}: shape '{shape}' is not R, Q or T"),
                            ))
                        }
                    };
                    // View3D's GetVS3Da.
                    let (ca, sa) = (-azimuth.cos(), azimuth.sin());
                    let (ct, st) = (tilt.cos(), tilt.sin());
                    let vs = local
                        .iter()
                        .map(|&(x, y)| {
                            Vec3::new(
                                (o.x as f64 + x * ca - y * ct * sa) as f32,
                                (o.y as f64 + x * sa + y * ct * ca) as f32,
                                (o.z as f64 + y * st) as f32,
                            )
                        })
                        .collect::<Vec<_>>();
                    (vs, data)
                } else {
                    let mut vs = Vec::with_capacity(4);
                    for (m, what) in ["first", "second", "third", "fourth"].iter().enumerate() {
                        let v = cursor.integer(&format!("the {what} vertex"))?;
                        if m == 3 && v == 0 {
                            break;
                        }
                        if v < 1 || v as usize > vertices.len() {
                            return Err(invalid(
                                path,
                                line,
                                format!(
                                    "surface {n}: {what} vertex {v} is not a vertex defined before it (1…{})",
                                    vertices.len()
                                ),
                            ));
                        }
                        vs.push(vertices[v as usize - 1]);
                    }
                    let data = if key == 'O' {
                        None
                    } else {
                        Some(surface_data(&mut cursor, &surfaces, ns, line)?)
                    };
                    (vs, data)
                };
                let surface = match data {
                    Some((name, emissivity, combined_into)) => Surface {
                        name,
                        kind: SurfaceKind::Radiating,
                        emissivity,
                        combined_into,
                        line,
                    },
                    None => Surface {
                        name: format!("obstruction-{n}"),
                        kind: SurfaceKind::Obstruction,
                        emissivity: 0.0,
                        combined_into: None,
                        line,
                    },
                };
                let vs = collapse_repeated(vs, path, line, n, &mut warnings)?;
                surfaces.push(surface);
                polygons.push(vs);
                // Continue after the words this element used.
                k = cursor.at.max(k);
            }
            _ => {
                return Err(invalid(
                    path,
                    line,
                    format!("'{first}' is not a View3D input element (T, C, F, V, S, O, E)"),
                ))
            }
        }
        k += 1;
    }
    if surfaces.is_empty() {
        return Err(invalid(
            path,
            lines.len().max(1),
            "no surfaces (S lines) before the end of data",
        ));
    }
    // Materials: one per reported surface; combined pieces share theirs.
    let mut materials: Vec<Material> = Vec::new();
    let mut material_of = vec![usize::MAX; surfaces.len()];
    let mut reported = Vec::new();
    // Name → its first line: a repeated name is found in O(1). View3D identifies surfaces by
    // number and reads files whose names repeat; so do we, with a warning: each surface keeps
    // its own material (its own row of factors), and a boundary condition given for the name
    // applies to every surface of that name.
    let mut named: std::collections::HashMap<&str, usize> = std::collections::HashMap::new();
    let mut repeats: Vec<(usize, usize, &str)> = Vec::new();
    for (k, s) in surfaces.iter().enumerate() {
        let new_name = !matches!((s.kind, s.combined_into), (SurfaceKind::Radiating, Some(_)));
        if new_name {
            if let Some(&first) = named.get(s.name.as_str()) {
                repeats.push((s.line, first, &s.name));
            } else {
                named.insert(&s.name, s.line);
            }
        }
        material_of[k] = match (s.kind, s.combined_into) {
            (SurfaceKind::Radiating, Some(t)) => material_of[t],
            (SurfaceKind::Radiating, None) => {
                reported.push(materials.len());
                materials.push(Material::diffuse(&s.name, Rgb::splat(1.0 - s.emissivity)));
                materials.len() - 1
            }
            (SurfaceKind::Obstruction, _) => {
                materials.push(Material::diffuse(&s.name, Rgb::BLACK));
                materials.len() - 1
            }
        };
    }
    if !repeats.is_empty() {
        let shown: Vec<String> = repeats
            .iter()
            .take(3)
            .map(|(line, first, name)| {
                format!(
                    "'{}' on line {line} (first on line {first})",
                    crate::loc::shorten(name.to_string())
                )
            })
            .collect();
        let more = match repeats.len() {
            n if n > 3 => format!(" and {} more", n - 3),
            _ => String::new(),
        };
        warnings.push(format!(
            "{}: {} surface name(s) repeat: {}{more}; each surface keeps its own row, and a boundary condition for a repeated name applies to all of its surfaces",
            path.display(),
            repeats.len(),
            shown.join(", ")
        ));
    }
    let name = super::name_of(path);
    let scene = Scene {
        name,
        source: Some(path.to_path_buf()),
        materials,
        polygons: polygons
            .into_iter()
            .zip(&surfaces)
            .enumerate()
            .map(|(k, (vertices, s))| Polygon {
                vertices,
                material: material_of[k],
                line: s.line as u32,
                group: 0,
            })
            .collect(),
        camera: None,
        warnings,
        origins: Vec::new(),
        up: None,
    };
    let scene = scene.with_coincidence_noted();
    Ok(Vs3 {
        scene,
        surfaces,
        reported,
        control,
        title,
    })
}

/// A surface's corners with repeated corners dropped: a triangle given as a quad (`1 2 3 3`, or
/// an `F 3a` `Q` with two equal points), which View3D reads as the triangle it is (its
/// polygon routines drop a side of zero length), is read so here too, with a warning naming the
/// line, so that every command meshes the same triangle. Corners are compared as read (after
/// the conversion to f32), cyclically, so `1 1 2 3` and `1 2 3 1` are triangles as well. Fewer
/// than three distinct corners is no surface, and an error.
fn collapse_repeated(
    vs: Vec<Vec3>,
    path: &Path,
    line: usize,
    n: i64,
    warnings: &mut Vec<String>,
) -> Result<Vec<Vec3>, SceneError> {
    let m = vs.len();
    let repeated = |k: usize| vs[k] == vs[(k + 1) % m];
    if !(0..m).any(repeated) {
        return Ok(vs);
    }
    let kept: Vec<Vec3> = (0..m).filter(|&k| !repeated(k)).map(|k| vs[k]).collect();
    if kept.len() < 3 {
        return Err(invalid(
            path,
            line,
            format!(
                "surface {n}: only {} distinct corner(s) of {m}; a surface needs three",
                kept.len()
            ),
        ));
    }
    warnings.push(format!(
        "{}:{line}: surface {n} repeats a corner; read as the {} it is (as View3D does)",
        path.display(),
        if kept.len() == 3 {
            "triangle"
        } else {
            "polygon"
        }
    ));
    Ok(kept)
}

/// `base cmb emit name` of a radiating surface.
fn surface_data(
    cursor: &mut Cursor<'_, '_>,
    surfaces: &[Surface],
    ns: usize,
    line: usize,
) -> Result<(String, f64, Option<usize>), SceneError> {
    let path = cursor.path;
    let n = ns + 1;
    let base = cursor.integer("the base surface")?;
    if base != 0 {
        return Err(invalid(
            path,
            line,
            format!("surface {n}: subsurfaces (base {base}) are not supported; describe the base around it as separate surfaces combined with 'cmb'"),
        ));
    }
    let cmb = cursor.integer("the combine surface")?;
    let combined_into = match cmb {
        0 => None,
        c if c < 0 || c as usize >= n => {
            return Err(invalid(
                path,
                line,
                format!("surface {n}: combine surface {c} must be a surface before it"),
            ))
        }
        c => {
            let t = c as usize - 1;
            match (surfaces[t].kind, surfaces[t].combined_into) {
                (SurfaceKind::Obstruction, _) => {
                    return Err(invalid(
                        path,
                        line,
                        format!("surface {n}: cannot combine with obstruction surface {c}"),
                    ))
                }
                (_, Some(_)) => {
                    return Err(invalid(
                        path,
                        line,
                        format!("surface {n}: surface {c} is itself combined into another; combine with that one (View3D does not chain combinations)"),
                    ))
                }
                _ => Some(t),
            }
        }
    };
    let emissivity = cursor.number("the emissivity")?;
    if !(emissivity > 0.0 && emissivity <= 1.0) {
        return Err(invalid(
            path,
            line,
            format!("surface {n}: emissivity {emissivity} is outside (0, 1]"),
        ));
    }
    let name = cursor.next("the surface name")?.to_string();
    Ok((name, emissivity, combined_into))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scenes() -> std::path::PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/scenes/view3d")
    }

    #[test]
    #[ignore = "needs View3D's examples in ../shared/scenes/view3d (run with --include-ignored, as .ci/run does)"]
    fn both_forms_of_pinney_bean_give_the_same_surfaces() {
        let a = load(&scenes().join("pinney-bean-test-4.vs3")).unwrap();
        let b = load(&scenes().join("pinney-bean-test-4-f3a.vs3")).unwrap();
        assert_eq!(a.surfaces.len(), 12);
        assert_eq!(a.reported.len(), 8);
        assert!(a.control.enclosure && a.control.emit);
        assert!(b.control.enclosure && !b.control.emit);
        assert_eq!(a.surfaces[8].combined_into, Some(6));
        for (p, q) in a.scene.polygons.iter().zip(&b.scene.polygons) {
            // Same corners (maybe from another starting vertex), same orientation.
            let (na, nb) = (
                super::super::vector_area(&p.vertices),
                super::super::vector_area(&q.vertices),
            );
            assert!((na - nb).length() < 1e-5, "{na} vs {nb}");
            for v in &p.vertices {
                assert!(q.vertices.iter().any(|w| (*v - *w).length() < 1e-5));
            }
            assert_eq!(p.material, q.material);
        }
        let names: Vec<&str> = a
            .reported
            .iter()
            .map(|&m| a.scene.materials[m].name.as_str())
            .collect();
        assert_eq!(
            names,
            ["srf-1", "srf-2", "srf-3", "srf-4", "srf-5", "srf-6", "srf-7", "srf-8"]
        );
    }

    /// View3D reads files whose surface names repeat (it numbers surfaces); so do we, with
    /// one warning naming the first few: each surface keeps its own material (its own row).
    #[test]
    fn repeated_names_are_read_with_a_warning() {
        let mut text = String::from("F 3\nV 1 0 0 0\nV 2 1 0 0\nV 3 1 1 0\nV 4 0 1 0\n");
        for k in 1..=6 {
            text += &format!("S {k} 1 2 3 4 0 0 0.5 wall\n");
        }
        let v = parse(Path::new("x.vs3"), &text).unwrap();
        assert_eq!(v.reported.len(), 6);
        assert_eq!(v.scene.materials.len(), 6);
        assert!(v.scene.materials.iter().all(|m| m.name == "wall"));
        let w: Vec<&String> = v
            .scene
            .warnings
            .iter()
            .filter(|w| w.contains("repeat"))
            .collect();
        assert_eq!(w.len(), 1, "{:?}", v.scene.warnings);
        assert!(w[0].contains("5 surface name(s) repeat"), "{}", w[0]);
        assert!(w[0].contains("line 7 (first on line 6)") && w[0].contains("and 2 more"));
    }

    #[test]
    fn bad_files_are_located() {
        let p = Path::new("x.vs3");
        for (text, needle) in [
            ("F 3\nV 2 0 0 0\n", "x.vs3:2: vertex 2 out of sequence"),
            (
                "F 3\nV 1 0 0 0\nS 1 1 2 0 0 0 0 0.5 a\n",
                "x.vs3:3: surface 1: second vertex 2",
            ),
            (
                "F 3\nV 1 0 0 0\nV 2 1 0 0\nV 3 0 1 0\nS 1 1 2 3 0 0 0 1.5 a\n",
                "emissivity 1.5",
            ),
            (
                "F 3\nV 1 0 0 0\nV 2 1 0 0\nV 3 0 1 0\nS 1 1 2 3 0 1 0 0.5 a\n",
                "subsurfaces",
            ),
            (
                "F 3\nV 1 0 0 0\nV 2 1 0 0\nV 3 0 1 0\nS 1 1 2 3 0 0 1 0.5 a\n",
                "combine surface 1",
            ),
            (
                "F 3\nV 1 0 0 0\nV 2 1 0 0\nV 3 0 1 0\nM 1 1 2 3 0 0 0 0.5 a\n",
                "masking",
            ),
            ("F 3\nV 1 0 0 0\nV 2 1 0 0\n", "no surfaces"),
            ("F 2\n", "'F 2' is not supported"),
            ("C foo=1\n", "unknown control parameter 'foo'"),
            ("C eps=x\n", "eps=x"),
            ("V 1 0 0 0\n", "needs 'F 3'"),
            (
                "F 3a\nS 1 R 0 0 0.5 a\n 0 0 0 0 90 1\n",
                "the file ends where the height",
            ),
            ("F 3a\nS 1 K 0 0 0.5 a\n 0 0 0 0 90 1 1\n", "shape 'K'"),
            ("Z\n", "'Z' is not a View3D input element"),
            ("F 3\nV 1 0 0 nan\n", "not a finite number"),
            (
                "F 3\nV 1 0 0 0\nV 2 1 0 0\nS 1 1 2 2 1 0 0 0.5 a\n",
                "x.vs3:4: surface 1: only 2 distinct corner(s) of 4",
            ),
        ] {
            let e = parse(p, text).unwrap_err().to_string();
            assert!(e.contains(needle), "{text:?}: {e}");
        }
    }

    /// A triangle given as a quad with a repeated corner (View3D reads it) is read as that
    /// triangle, wherever the repeat sits and in either geometry format, with a warning naming
    /// the file and line; its area is the triangle's, 1/2.
    #[test]
    fn a_quad_with_a_repeated_corner_is_its_triangle() {
        let p = Path::new("tri.vs3");
        for (text, line) in [
            (
                "F 3\nV 1 0 0 0\nV 2 1 0 0\nV 3 0 1 0\nS 1 1 2 3 3 0 0 0.5 a\n",
                5,
            ),
            (
                "F 3\nV 1 0 0 0\nV 2 1 0 0\nV 3 0 1 0\nS 1 1 1 2 3 0 0 0.5 a\n",
                5,
            ),
            (
                "F 3\nV 1 0 0 0\nV 2 1 0 0\nV 3 0 1 0\nS 1 1 2 3 1 0 0 0.5 a\n",
                5,
            ),
            ("F 3a\nS 1 Q 0 0 0.5 a\n 0 0 0 0 0 0 0 1 0 0 1 0 1\n", 2),
        ] {
            let v = parse(p, text).unwrap();
            let poly = &v.scene.polygons[0];
            assert_eq!(poly.vertices.len(), 3, "{text:?}");
            let area = super::super::vector_area(&poly.vertices).length();
            assert!((area - 0.5).abs() < 1e-6, "{text:?}: area {area}");
            let w = &v.scene.warnings;
            assert_eq!(w.len(), 1, "{w:?}");
            assert!(
                w[0].starts_with(&format!("tri.vs3:{line}: surface 1 repeats a corner")),
                "{}",
                w[0]
            );
        }
        // A proper quad is left alone, without a warning.
        let v = parse(
            p,
            "F 3\nV 1 0 0 0\nV 2 1 0 0\nV 3 1 1 0\nV 4 0 1 0\nS 1 1 2 3 4 0 0 0.5 a\n",
        )
        .unwrap();
        assert_eq!(v.scene.polygons[0].vertices.len(), 4);
        assert!(v.scene.warnings.is_empty());
    }
}
