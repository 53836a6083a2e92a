//! MGF, the Materials and Geometry Format of Greg Ward (LBL, version 1.1, 1996), in which
//! RenderPark and Radiance's `mgf2rad` read their scenes.
//!
//! **Read.** Comments (`#`) and continued lines (`\` at the end); objects `o` (structure only);
//! transforms `xf` with `-t -rx -ry -rz -s -mx -my -mz`, iteration `-i N` and arrays `-a N`
//! (an array re-reads the entities up to the matching `xf` once per element, as the format
//! prescribes); includes `i file [transform]`, relative to the including file's folder, with the
//! include's own transform and arrays; colours `c` with `cxy`, `cspec`, `cct` and `cmix`;
//! materials `m` with `rd` and `ed` (and `sides`, `ir`, `rs`, `ts`, `td`, see below); vertices
//! `v` with `p` and `n`; faces `f` (any simple polygon, triangulated by the mesher when not
//! convex) and `fh` (faces with holes); and the primitives `sph`, `cyl`, `cone`, `ring`, `prism`
//! and `torus`, tessellated as described below. Vertex positions are transformed by the transform
//! in force where the vertex is *used*, as the format specifies; a transform with a mirror
//! reverses the vertex order so that faces keep facing the same way.
//!
//! **Colour.** An MGF colour is a chromaticity; the quantity (`rd`, `ed`) that uses it gives the
//! luminance `Y`. `(x, y, Y)` becomes CIE XYZ and then white-balanced linear sRGB
//! ([`spectrum::xyz_to_rgb`]): sRGB primaries with the equal-energy white, so MGF's default
//! colour, `x = y = ⅓`, is grey. `cspec` spectra and `cct` black bodies (Planck's law) are
//! integrated against the CIE 1931 observer to a chromaticity; `cmix` adds its colours' XYZ
//! weighted by the given (luminance) weights. Negative channels of colours outside the gamut are
//! clamped to zero; a reflectance whose largest channel reaches 1 is scaled down to
//! [`MAX_REFLECTANCE`] (reported in a warning).
//!
//! **Emission.** `ed` is a diffuse emittance in lumens per square metre, a luminous exitance.
//! It becomes radiant exitance `E = ed / 179 lm/W` (the luminous efficacy of equal-energy white
//! light under the CIE 1931 observer, the constant of Radiance's `mgf2rad`; RenderPark uses
//! 183.07 from the 1988 observer, 2 % less light) times the colour's balanced RGB. Lengths are
//! metres, as MGF defines.
//!
//! **Dropped.** The engine is diffuse: specular reflection `rs`, specular transmission `ts` and
//! diffuse transmission `td` are dropped, with one warning that says how much of the light
//! falling on the surfaces that use them was ignored. The engine's surfaces are one-sided, their
//! front the side from which the vertices run counter-clockwise; a two-sided MGF surface (`sides
//! 2`, the format's default) becomes two polygons back to back, both reflecting and emitting, as
//! RenderPark reads it. The option `one_sided` ([`load_with`], the CLI's `--one-sided`) keeps
//! only the front, as RenderPark's `-force-onesided` does. `ies` luminaires and `ir` are skipped, and faces whose area is
//! zero after transformation are dropped: both are listed in one summary warning.
//!
//! **Tessellation.** A full circle is cut into `4·`[`SEGMENTS_PER_QUARTER`] = 16 segments (the
//! chord's sagitta is at most 1.9 % of the radius, the cosine error of a facet's normal at most
//! 1.9 %); a sphere into 8 bands of latitude, triangles at the poles; a torus into 16 × 16
//! quads. Cylinders and cones are open-ended; rings are flat annuli (or discs) facing along their
//! centre vertex's normal. A negative radius (or prism length) turns the surface inside out.
//!
//! **Errors** name the file and line: an undefined vertex, colour or material, a malformed
//! number, a missing include, an include loop, a face with fewer than three vertices, an
//! unmatched `xf`, an argument out of range.

use super::{spectrum, Material, Polygon, Scene, SceneError};
use crate::color::Rgb;
use crate::geom::Vec3;
use glam::{DAffine3, DVec3};
use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};
use std::rc::Rc;

/// Segments per quarter circle when tessellating curved primitives (RenderPark's default).
pub const SEGMENTS_PER_QUARTER: usize = 4;
/// Luminous efficacy of equal-energy white light, lm/W: `ed` is divided by it.
pub const WHITE_EFFICACY: f64 = 179.0;
/// Largest reflectance channel kept: out-of-gamut colours are scaled down to it.
pub const MAX_REFLECTANCE: f64 = 0.99;

/// A chromaticity (CIE 1931 x, y).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Chroma {
    x: f64,
    y: f64,
}

impl Chroma {
    const WHITE: Chroma = Chroma {
        x: 1.0 / 3.0,
        y: 1.0 / 3.0,
    };

    fn from_xyz(xyz: [f64; 3]) -> Option<Chroma> {
        let s = xyz[0] + xyz[1] + xyz[2];
        (s > 0.0 && xyz[1] > 0.0).then(|| Chroma {
            x: xyz[0] / s,
            y: xyz[1] / s,
        })
    }

    /// XYZ with luminance `lum`.
    fn xyz(self, lum: f64) -> [f64; 3] {
        [
            self.x / self.y * lum,
            lum,
            (1.0 - self.x - self.y) / self.y * lum,
        ]
    }

    /// Balanced linear RGB of luminance `lum`, negative channels clamped (black for `y = 0`).
    fn rgb(self, lum: f64) -> Rgb {
        if self.y <= 0.0 {
            return Rgb::BLACK;
        }
        spectrum::xyz_to_rgb(self.xyz(lum)).map(|c| c.max(0.0))
    }
}

/// A material context.
#[derive(Clone, Debug)]
struct MatCtx {
    rd: f64,
    rd_c: Chroma,
    ed: f64,
    ed_c: Chroma,
    td: f64,
    rs: f64,
    ts: f64,
    /// 1 or 2 (MGF's default).
    sides: u8,
    /// Changes whenever the context does, so converted materials are cached per version.
    version: u64,
}

impl Default for MatCtx {
    fn default() -> Self {
        Self {
            rd: 0.0,
            rd_c: Chroma::WHITE,
            ed: 0.0,
            ed_c: Chroma::WHITE,
            td: 0.0,
            rs: 0.0,
            ts: 0.0,
            sides: 2,
            version: 0,
        }
    }
}

/// A vertex context: position and (optional, zero when absent) normal, untransformed.
#[derive(Clone, Copy, Debug, Default)]
struct Vertex {
    p: DVec3,
    n: DVec3,
}

/// One transform argument list, split at `-i` and `-a`.
#[derive(Clone, Debug)]
struct XfSpec {
    /// `(kind, transform)` per run of arguments: before any `-i`/`-a`, then one per `-i N` or `-a N`.
    parts: Vec<(Part, DAffine3)>,
}

#[derive(Clone, Copy, Debug)]
enum Part {
    Once,
    Iterate(u32),
    Array(u32),
}

impl XfSpec {
    /// Number of array elements (product of the `-a` counts).
    fn elements(&self) -> usize {
        self.parts
            .iter()
            .map(|(k, _)| match k {
                Part::Array(n) => *n as usize,
                _ => 1,
            })
            .fold(1usize, usize::saturating_mul)
    }

    /// The transform of array element `e` (mixed radix over the `-a` parts, first fastest).
    fn matrix(&self, mut e: usize) -> DAffine3 {
        let mut m = DAffine3::IDENTITY;
        for (kind, t) in &self.parts {
            let times = match kind {
                Part::Once => 1,
                Part::Iterate(n) => *n as usize,
                Part::Array(n) => {
                    let k = e % *n as usize;
                    e /= *n as usize;
                    k
                }
            };
            for _ in 0..times {
                m = *t * m;
            }
        }
        m
    }
}

/// A transform in force, with what geometry needs from it.
#[derive(Clone, Copy, Debug)]
struct Xf {
    m: DAffine3,
    /// A mirror: reverse vertex order.
    reverse: bool,
}

impl Xf {
    fn new(m: DAffine3) -> Self {
        Self {
            m,
            reverse: m.matrix3.determinant() < 0.0,
        }
    }
}

/// An open `xf` block of the file being read.
struct Frame {
    /// Index (into the file's lines) of the `xf` that opened it.
    begin: usize,
    spec: XfSpec,
    element: usize,
    parent: Xf,
}

/// A file's logical lines: `(line number, text)`, continuations joined.
type Lines = Rc<Vec<(usize, String)>>;

struct Reader {
    /// Files being read, outermost first (for include loops).
    open: Vec<PathBuf>,
    /// The canonical paths of `open`, for the include-loop check.
    open_canonical: Vec<PathBuf>,
    /// Statements read so far, array repetitions and includes counted: bounded by
    /// [`MAX_STATEMENTS`], so that nested arrays cannot make a small file endless.
    statements: u64,
    /// Copies made by arrays so far (`xf -a`, `i … -a`), nested arrays multiplied: bounded by
    /// [`MAX_ARRAY_INSTANCES`] before each array is expanded.
    instances: u64,
    /// Text of files already read (includes are often repeated).
    cache: HashMap<PathBuf, Lines>,
    colours: HashMap<String, Chroma>,
    colour: Chroma,
    colour_name: Option<String>,
    mats: HashMap<String, MatCtx>,
    mat: MatCtx,
    mat_name: Option<String>,
    clock: u64,
    vertices: HashMap<String, Vertex>,
    vertex_name: Option<String>,
    /// Converted materials: `(name, version)` → index.
    converted: HashMap<(String, u64), usize>,
    materials: Vec<Material>,
    /// Per converted material: fraction of incident light dropped (rs + ts + td).
    dropped: Vec<f64>,
    polygons: Vec<Polygon>,
    /// `(first polygon, file)` runs.
    origins: Vec<(usize, PathBuf)>,
    skipped: BTreeMap<String, usize>,
    degenerate: usize,
    clipped: usize,
    /// Ignore `sides 2`.
    one_sided: bool,
    /// Two-sided polygons doubled.
    doubled: usize,
    /// Scratch polygon.
    scratch: Vec<Vec3>,
}

fn invalid(path: &Path, line: usize, message: impl Into<String>) -> SceneError {
    SceneError::Invalid {
        at: crate::loc::FileLoc::line(path, line),
        message: crate::loc::shorten(message.into()),
    }
}

/// Read a file into logical lines.
fn read_lines(path: &Path) -> Result<Vec<(usize, String)>, SceneError> {
    let text = super::obj::read(path)?;
    let mut out = Vec::new();
    let mut pending: Option<(usize, String)> = None;
    for (k, raw) in text.lines().enumerate() {
        let raw = raw.strip_suffix('\r').unwrap_or(raw);
        let (body, continued) = match raw.strip_suffix('\\') {
            Some(b) => (b, true),
            None => (raw, false),
        };
        match &mut pending {
            Some((_, s)) => {
                s.push(' ');
                s.push_str(body);
            }
            None => pending = Some((k + 1, body.to_string())),
        }
        if !continued {
            out.extend(pending.take());
        }
    }
    out.extend(pending.take());
    Ok(out)
}

use super::obj::parse_f64 as number;

fn count(path: &Path, line: usize, tok: &str, what: &str) -> Result<u32, SceneError> {
    tok.parse::<u32>().ok().filter(|n| *n >= 1).ok_or_else(|| {
        invalid(
            path,
            line,
            format!("{what} needs a positive count, not '{tok}'"),
        )
    })
}

/// Deepest chain of includes.
pub const MAX_INCLUDE_DEPTH: usize = 64;
/// Most elements of one transform array (the product of its `-a` counts), and of the arrays
/// open around a statement together.
pub const MAX_ARRAY_ELEMENTS: usize = 1 << 20;
/// Most statements read, array repetitions and includes counted.
pub const MAX_STATEMENTS: u64 = 4_000_000;

/// Most copies made by all the arrays of a scene together (nested arrays multiplied).
///
/// Every copy is at least one polygon, meshed, lit and solved; an array of 10⁴ copies is
/// already a scene of its own (a floor of 100 × 100 tiles), and the radiosity of 10⁵ copies of
/// one triangle is a run of hours for one polygon's worth of information. Larger repetition
/// belongs in a mesh format.
pub const MAX_ARRAY_INSTANCES: u64 = 10_000;

fn check_elements(path: &Path, line: usize, spec: &XfSpec) -> Result<(), SceneError> {
    if spec.elements() > MAX_ARRAY_ELEMENTS {
        return Err(invalid(
            path,
            line,
            format!("a transform array of more than {MAX_ARRAY_ELEMENTS} elements"),
        ));
    }
    Ok(())
}

/// Parse transform arguments (`args` excludes the keyword).
fn parse_xf(path: &Path, line: usize, args: &[&str]) -> Result<XfSpec, SceneError> {
    let mut parts = vec![(Part::Once, DAffine3::IDENTITY)];
    let mut k = 0;
    let nums = |k: usize, n: usize, opt: &str| -> Result<Vec<f64>, SceneError> {
        if args.len() < k + 1 + n {
            return Err(invalid(
                path,
                line,
                format!("transform option {opt} needs {n} number(s)"),
            ));
        }
        args[k + 1..k + 1 + n]
            .iter()
            .map(|t| number(path, line, t, opt))
            .collect()
    };
    while k < args.len() {
        let opt = args[k];
        let (t, used) = match opt {
            "-t" => {
                let v = nums(k, 3, opt)?;
                (DAffine3::from_translation(DVec3::new(v[0], v[1], v[2])), 4)
            }
            "-rx" => (DAffine3::from_rotation_x(nums(k, 1, opt)?[0].to_radians()), 2),
            "-ry" => (DAffine3::from_rotation_y(nums(k, 1, opt)?[0].to_radians()), 2),
            "-rz" => (DAffine3::from_rotation_z(nums(k, 1, opt)?[0].to_radians()), 2),
            "-s" => {
                let s = nums(k, 1, opt)?[0];
                if s == 0.0 {
                    return Err(invalid(path, line, "transform scale -s 0 collapses the geometry"));
                }
                (DAffine3::from_scale(DVec3::splat(s)), 2)
            }
            "-mx" => (DAffine3::from_scale(DVec3::new(-1.0, 1.0, 1.0)), 1),
            "-my" => (DAffine3::from_scale(DVec3::new(1.0, -1.0, 1.0)), 1),
            "-mz" => (DAffine3::from_scale(DVec3::new(1.0, 1.0, -1.0)), 1),
            "-i" | "-a" => {
                let Some(tok) = args.get(k + 1) else {
                    return Err(invalid(path, line, format!("transform option {opt} needs a count")));
                };
                let n = count(path, line, tok, opt)?;
                parts.push((
                    if opt == "-i" { Part::Iterate(n) } else { Part::Array(n) },
                    DAffine3::IDENTITY,
                ));
                k += 2;
                continue;
            }
            other => {
                return Err(invalid(
                    path,
                    line,
                    format!("unknown transform option '{other}' (expected -t, -rx, -ry, -rz, -s, -mx, -my, -mz, -i or -a)"),
                ))
            }
        };
        let last = parts.last_mut().expect("parts starts non-empty");
        last.1 = t * last.1;
        k += used;
    }
    Ok(XfSpec { parts })
}

/// Points `c + h·a + r·(cos θ u + sin θ w)` on `4·SEGMENTS_PER_QUARTER` angles.
fn circle(c: DVec3, a: DVec3, u: DVec3, w: DVec3, h: f64, r: f64) -> Vec<DVec3> {
    let n = 4 * SEGMENTS_PER_QUARTER;
    (0..n)
        .map(|k| {
            let t = std::f64::consts::TAU * k as f64 / n as f64;
            c + a * h + (u * t.cos() + w * t.sin()) * r
        })
        .collect()
}

/// A unit vector `a` and two more completing a right-handed orthonormal basis `u × w = a`.
fn basis(a: DVec3) -> (DVec3, DVec3) {
    let u = a.any_orthonormal_vector();
    (u, a.cross(u))
}

impl Reader {
    /// Count `copies` more array copies, refusing past [`MAX_ARRAY_INSTANCES`] at `line`.
    fn count_instances(
        &mut self,
        path: &Path,
        line: usize,
        copies: usize,
    ) -> Result<(), SceneError> {
        if copies <= 1 {
            return Ok(());
        }
        self.instances = self.instances.saturating_add(copies as u64);
        if self.instances > MAX_ARRAY_INSTANCES {
            return Err(invalid(
                path,
                line,
                format!(
                    "transform arrays would make {} copies in all, more than {MAX_ARRAY_INSTANCES}; use fewer copies or a mesh format",
                    self.instances
                ),
            ));
        }
        Ok(())
    }

    fn new() -> Self {
        Self {
            open: Vec::new(),
            open_canonical: Vec::new(),
            statements: 0,
            instances: 0,
            cache: HashMap::new(),
            colours: HashMap::new(),
            colour: Chroma::WHITE,
            colour_name: None,
            mats: HashMap::new(),
            mat: MatCtx::default(),
            mat_name: None,
            clock: 0,
            vertices: HashMap::new(),
            vertex_name: None,
            converted: HashMap::new(),
            materials: Vec::new(),
            dropped: Vec::new(),
            polygons: Vec::new(),
            origins: Vec::new(),
            skipped: BTreeMap::new(),
            degenerate: 0,
            clipped: 0,
            one_sided: false,
            doubled: 0,
            scratch: Vec::new(),
        }
    }

    fn set_colour(&mut self, c: Chroma) {
        self.colour = c;
        if let Some(n) = &self.colour_name {
            self.colours.insert(n.clone(), c);
        }
    }

    /// Apply `f` to the current material context and record the change.
    fn change_mat(&mut self, f: impl FnOnce(&mut MatCtx, Chroma)) {
        self.clock += 1;
        let colour = self.colour;
        f(&mut self.mat, colour);
        self.mat.version = self.clock;
        if let Some(n) = &self.mat_name {
            self.mats.insert(n.clone(), self.mat.clone());
        }
    }

    /// Index of the engine material for the current context.
    fn material(&mut self) -> usize {
        let name = self.mat_name.clone().unwrap_or_default();
        let key = (name, self.mat.version);
        if let Some(&i) = self.converted.get(&key) {
            return i;
        }
        let m = &self.mat;
        let mut reflectance = m.rd_c.rgb(m.rd);
        if reflectance.max_channel() > MAX_REFLECTANCE {
            reflectance = reflectance * (MAX_REFLECTANCE / reflectance.max_channel());
            self.clipped += 1;
        }
        let emission = m.ed_c.rgb(m.ed / WHITE_EFFICACY);
        let label = if key.0.is_empty() {
            "(unnamed)".to_string()
        } else {
            key.0.clone()
        };
        self.materials
            .push(Material::emitter(&label, reflectance, emission));
        self.dropped.push(m.rs + m.ts + m.td);
        let i = self.materials.len() - 1;
        self.converted.insert(key, i);
        i
    }

    fn vertex(&self, path: &Path, line: usize, name: &str) -> Result<Vertex, SceneError> {
        self.vertices
            .get(name)
            .copied()
            .ok_or_else(|| invalid(path, line, format!("undefined vertex '{name}'")))
    }

    /// Emit a polygon given in local coordinates.
    fn emit(&mut self, local: &[DVec3], xf: &Xf, line: usize) {
        let material = self.material();
        let mut v = std::mem::take(&mut self.scratch);
        v.clear();
        for p in local {
            let q = xf.m.transform_point3(*p).as_vec3();
            if v.last() != Some(&q) {
                v.push(q);
            }
        }
        while v.len() > 1 && v.first() == v.last() {
            v.pop();
        }
        if xf.reverse {
            v.reverse();
        }
        let size = v
            .iter()
            .map(|p| (*p - v[0]).length())
            .fold(0.0f32, f32::max);
        if v.len() < 3 || super::polygon_area(&v) <= (1e-6 * size as f64).powi(2) {
            self.degenerate += 1;
        } else {
            self.polygons.push(Polygon {
                vertices: v.clone(),
                material,
                line: line as u32,
                group: 0,
            });
            if self.mat.sides == 2 && !self.one_sided {
                // The back side: the same polygon reversed. Where the two coincide the ray caster
                // reports the one facing the ray.
                self.doubled += 1;
                self.polygons.push(Polygon {
                    vertices: v.iter().rev().copied().collect(),
                    material,
                    line: line as u32,
                    group: 0,
                });
            }
        }
        self.scratch = v;
    }

    /// Emit the quads between two rings of points (closed loops of equal length), oriented so
    /// that their normals agree with `outward(centroid)`; `inward` flips them all.
    fn band(
        &mut self,
        a: &[DVec3],
        b: &[DVec3],
        outward: &dyn Fn(DVec3) -> DVec3,
        inward: bool,
        xf: &Xf,
        line: usize,
    ) {
        let n = a.len();
        for k in 0..n {
            let j = (k + 1) % n;
            let mut q = vec![a[k], a[j], b[j], b[k]];
            q.dedup();
            if q.len() > 1 && q.first() == q.last() {
                q.pop();
            }
            orient(&mut q, outward, inward);
            self.emit(&q, xf, line);
        }
    }

    fn parse_file(&mut self, path: &Path, base: Xf) -> Result<(), SceneError> {
        let lines = match self.cache.get(path) {
            Some(l) => l.clone(),
            None => {
                let l: Lines = Rc::new(read_lines(path)?);
                self.cache.insert(path.to_path_buf(), l.clone());
                l
            }
        };
        if self.open.len() >= MAX_INCLUDE_DEPTH {
            return Err(invalid(
                path,
                0,
                format!("includes nest deeper than {MAX_INCLUDE_DEPTH} files"),
            ));
        }
        self.open.push(path.to_path_buf());
        self.open_canonical
            .push(path.canonicalize().unwrap_or_else(|_| path.to_path_buf()));
        let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
        let mut frames: Vec<Frame> = Vec::new();
        let mut xf = base;
        let mut i = 0;
        while i < lines.len() {
            let (line, text) = (&lines[i].0, &lines[i].1);
            let line = *line;
            let toks: Vec<&str> = text.split_whitespace().collect();
            let Some(&key) = toks.first() else {
                i += 1;
                continue;
            };
            if key.starts_with('#') {
                i += 1;
                continue;
            }
            let args = &toks[1..];
            self.statements += 1;
            if self.statements > MAX_STATEMENTS {
                return Err(invalid(
                    path,
                    line,
                    format!(
                        "the scene expands to more than {MAX_STATEMENTS} statements through its arrays and includes"
                    ),
                ));
            }
            self.note_origin(path);
            match key {
                "xf" => {
                    if args.is_empty() {
                        let Some(f) = frames.last_mut() else {
                            return Err(invalid(path, line, "xf end without a matching xf"));
                        };
                        if f.element + 1 < f.spec.elements() {
                            f.element += 1;
                            xf = Xf::new(f.parent.m * f.spec.matrix(f.element));
                            i = f.begin + 1;
                            continue;
                        }
                        xf = f.parent;
                        frames.pop();
                    } else {
                        let spec = parse_xf(path, line, args)?;
                        check_elements(path, line, &spec)?;
                        // Nested arrays multiply: bound the product of the open blocks' counts.
                        let nested = frames
                            .iter()
                            .map(|f| f.spec.elements())
                            .fold(spec.elements(), usize::saturating_mul);
                        if nested > MAX_ARRAY_ELEMENTS {
                            return Err(invalid(
                                path,
                                line,
                                format!(
                                    "nested transform arrays of more than {MAX_ARRAY_ELEMENTS} elements in all"
                                ),
                            ));
                        }
                        // The block's copies, the enclosing arrays' included, counted once, on
                        // the enclosing arrays' first pass, before any is made.
                        if spec.elements() > 1 && frames.iter().all(|f| f.element == 0) {
                            self.count_instances(path, line, nested)?;
                        }
                        let m = spec.matrix(0);
                        frames.push(Frame {
                            begin: i,
                            spec,
                            element: 0,
                            parent: xf,
                        });
                        xf = Xf::new(xf.m * m);
                    }
                }
                "i" => {
                    let Some(name) = args.first() else {
                        return Err(invalid(path, line, "i needs a file name"));
                    };
                    let target = dir.join(name);
                    if !target.is_file() {
                        return Err(invalid(
                            path,
                            line,
                            if target.exists() {
                                format!(
                                    "included file '{}' is not a regular file (a folder or a device)",
                                    target.display()
                                )
                            } else {
                                format!("included file '{}' not found", target.display())
                            },
                        ));
                    }
                    let canon = target.canonicalize().unwrap_or(target.clone());
                    if self.open_canonical.contains(&canon) {
                        let chain: Vec<String> = self
                            .open
                            .iter()
                            .map(|p| p.display().to_string())
                            .chain([target.display().to_string()])
                            .collect();
                        return Err(invalid(
                            path,
                            line,
                            format!("include loop: {}", chain.join(" → ")),
                        ));
                    }
                    let spec = parse_xf(path, line, &args[1..])?;
                    check_elements(path, line, &spec)?;
                    self.count_instances(path, line, spec.elements())?;
                    // Read here, so that a file that cannot be read (a device, a folder, no
                    // permission) is reported at the include that names it.
                    if !self.cache.contains_key(&target) {
                        let lines = read_lines(&target).map_err(|e| {
                            invalid(
                                path,
                                line,
                                format!("cannot include '{}': {e}", target.display()),
                            )
                        })?;
                        self.cache.insert(target.clone(), Rc::new(lines));
                    }
                    for e in 0..spec.elements() {
                        self.parse_file(&target, Xf::new(xf.m * spec.matrix(e)))?;
                    }
                    self.note_origin(path);
                }
                "o" => {}
                "c" => self.colour_context(path, line, args)?,
                "cxy" => {
                    let [x, y] = args else {
                        return Err(invalid(path, line, "cxy needs 2 numbers"));
                    };
                    let (x, y) = (number(path, line, x, "cxy")?, number(path, line, y, "cxy")?);
                    if !(0.0..=1.0).contains(&x) || !(0.0..=1.0).contains(&y) || x + y > 1.0 + 1e-9
                    {
                        return Err(invalid(
                            path,
                            line,
                            format!("cxy {x} {y} is not a chromaticity (x, y ≥ 0, x + y ≤ 1)"),
                        ));
                    }
                    if y == 0.0 {
                        // No luminance at any intensity: black, as RenderPark reads it.
                        *self
                            .skipped
                            .entry("cxy with y = 0 (black)".into())
                            .or_default() += 1;
                    }
                    self.set_colour(Chroma { x, y });
                }
                "cspec" => {
                    if args.len() < 4 {
                        return Err(invalid(
                            path,
                            line,
                            "cspec needs λmin λmax and at least 2 values",
                        ));
                    }
                    let lo = number(path, line, args[0], "cspec")?;
                    let hi = number(path, line, args[1], "cspec")?;
                    if !(lo > 0.0 && hi > lo) {
                        return Err(invalid(
                            path,
                            line,
                            format!("cspec range {lo}–{hi} nm is empty"),
                        ));
                    }
                    let values: Vec<f64> = args[2..]
                        .iter()
                        .map(|t| number(path, line, t, "cspec"))
                        .collect::<Result<_, _>>()?;
                    let n = values.len();
                    let nm: Vec<f64> = (0..n)
                        .map(|k| lo + (hi - lo) * k as f64 / (n - 1) as f64)
                        .collect();
                    let c = Chroma::from_xyz(spectrum::spectrum_xyz(&nm, &values))
                        .ok_or_else(|| invalid(path, line, "cspec spectrum is black"))?;
                    self.set_colour(c);
                }
                "cct" => {
                    let [t] = args else {
                        return Err(invalid(path, line, "cct needs a temperature"));
                    };
                    let t = number(path, line, t, "cct")?;
                    if t < 100.0 {
                        return Err(invalid(path, line, format!("cct {t} K is below 100 K")));
                    }
                    let nm: Vec<f64> = (0..=80).map(|k| 380.0 + 5.0 * k as f64).collect();
                    let v: Vec<f64> = nm.iter().map(|l| spectrum::planck(*l, t)).collect();
                    let c = Chroma::from_xyz(spectrum::spectrum_xyz(&nm, &v))
                        .ok_or_else(|| invalid(path, line, "cct spectrum is black"))?;
                    self.set_colour(c);
                }
                "cmix" => {
                    if args.is_empty() || args.len() % 2 != 0 {
                        return Err(invalid(path, line, "cmix needs weight-colour pairs"));
                    }
                    let mut xyz = [0.0; 3];
                    for pair in args.chunks(2) {
                        let w = number(path, line, pair[0], "cmix")?;
                        let c = *self.colours.get(pair[1]).ok_or_else(|| {
                            invalid(path, line, format!("undefined colour '{}'", pair[1]))
                        })?;
                        let cx = c.xyz(w);
                        for a in 0..3 {
                            xyz[a] += cx[a];
                        }
                    }
                    let c = Chroma::from_xyz(xyz)
                        .ok_or_else(|| invalid(path, line, "cmix weights give no colour"))?;
                    self.set_colour(c);
                }
                "m" => self.material_context(path, line, args)?,
                "rd" | "td" | "ed" => {
                    let [v] = args else {
                        return Err(invalid(path, line, format!("{key} needs 1 number")));
                    };
                    let v = number(path, line, v, key)?;
                    if v < 0.0 || (key != "ed" && v > 1.0) {
                        return Err(invalid(
                            path,
                            line,
                            format!(
                                "{key} {v} is out of range ({})",
                                if key == "ed" { "≥ 0" } else { "0 to 1" }
                            ),
                        ));
                    }
                    match key {
                        "rd" => self.change_mat(|m, c| {
                            m.rd = v;
                            m.rd_c = c;
                        }),
                        "td" => self.change_mat(|m, _| m.td = v),
                        _ => self.change_mat(|m, c| {
                            m.ed = v;
                            m.ed_c = c;
                        }),
                    }
                }
                "rs" | "ts" => {
                    let [v, _rough] = args else {
                        return Err(invalid(path, line, format!("{key} needs 2 numbers")));
                    };
                    let v = number(path, line, v, key)?;
                    number(path, line, _rough, key)?;
                    if !(0.0..=1.0).contains(&v) {
                        return Err(invalid(
                            path,
                            line,
                            format!("{key} {v} is out of range (0 to 1)"),
                        ));
                    }
                    if key == "rs" {
                        self.change_mat(|m, _| m.rs = v);
                    } else {
                        self.change_mat(|m, _| m.ts = v);
                    }
                }
                "sides" => {
                    let sides = match args {
                        ["1"] => 1,
                        ["2"] => 2,
                        _ => return Err(invalid(path, line, "sides takes 1 or 2")),
                    };
                    self.change_mat(|m, _| m.sides = sides);
                }
                "ir" | "ies" => *self.skipped.entry(key.to_string()).or_default() += 1,
                "v" => self.vertex_context(path, line, args)?,
                "p" | "n" => {
                    let [x, y, z] = args else {
                        return Err(invalid(path, line, format!("{key} needs 3 numbers")));
                    };
                    let v = DVec3::new(
                        number(path, line, x, key)?,
                        number(path, line, y, key)?,
                        number(path, line, z, key)?,
                    );
                    let Some(name) = &self.vertex_name else {
                        return Err(invalid(
                            path,
                            line,
                            format!("{key} outside a named vertex context (v name =)"),
                        ));
                    };
                    let vx = self.vertices.get_mut(name).expect("current vertex exists");
                    if key == "p" {
                        vx.p = v;
                    } else {
                        vx.n = v;
                    }
                }
                "f" => {
                    if args.len() < 3 {
                        return Err(invalid(
                            path,
                            line,
                            format!("face has {} vertices; at least 3 needed", args.len()),
                        ));
                    }
                    let pts: Vec<DVec3> = args
                        .iter()
                        .map(|n| self.vertex(path, line, n).map(|v| v.p))
                        .collect::<Result<_, _>>()?;
                    self.emit(&pts, &xf, line);
                }
                "fh" => {
                    let pts = self.face_with_holes(path, line, args)?;
                    self.emit(&pts, &xf, line);
                }
                "sph" | "cyl" | "cone" | "ring" | "torus" | "prism" => {
                    self.primitive(path, line, key, args, &xf)?
                }
                other => {
                    *self
                        .skipped
                        .entry(format!("unknown '{other}'"))
                        .or_default() += 1
                }
            }
            i += 1;
        }
        if let Some(f) = frames.last() {
            return Err(invalid(
                path,
                lines[f.begin].0,
                "xf is never closed (no matching xf before the end of the file)",
            ));
        }
        self.open.pop();
        self.open_canonical.pop();
        Ok(())
    }

    /// Start a new origin run if the last polygon came from another file.
    fn note_origin(&mut self, path: &Path) {
        match self.origins.last() {
            Some((_, p)) if p == path => {}
            _ => {
                if let Some((start, _)) = self.origins.last() {
                    if *start == self.polygons.len() {
                        self.origins.pop();
                    }
                }
                self.origins.push((self.polygons.len(), path.to_path_buf()));
            }
        }
    }

    fn colour_context(
        &mut self,
        path: &Path,
        line: usize,
        args: &[&str],
    ) -> Result<(), SceneError> {
        match args {
            [] => {
                self.colour = Chroma::WHITE;
                self.colour_name = None;
            }
            [name] => {
                self.colour = *self
                    .colours
                    .get(*name)
                    .ok_or_else(|| invalid(path, line, format!("undefined colour '{name}'")))?;
                self.colour_name = Some(name.to_string());
            }
            [name, "="] => {
                self.colours.insert(name.to_string(), Chroma::WHITE);
                self.colour = Chroma::WHITE;
                self.colour_name = Some(name.to_string());
            }
            [name, "=", template] => {
                let c = *self
                    .colours
                    .get(*template)
                    .ok_or_else(|| invalid(path, line, format!("undefined colour '{template}'")))?;
                self.colours.insert(name.to_string(), c);
                self.colour = c;
                self.colour_name = Some(name.to_string());
            }
            _ => return Err(invalid(path, line, "c takes [name [= [template]]]")),
        }
        Ok(())
    }

    fn material_context(
        &mut self,
        path: &Path,
        line: usize,
        args: &[&str],
    ) -> Result<(), SceneError> {
        self.clock += 1;
        match args {
            [] => {
                self.mat = MatCtx {
                    version: self.clock,
                    ..MatCtx::default()
                };
                self.mat_name = None;
            }
            [name] => {
                self.mat =
                    self.mats.get(*name).cloned().ok_or_else(|| {
                        invalid(path, line, format!("undefined material '{name}'"))
                    })?;
                self.mat_name = Some(name.to_string());
            }
            [name, "=", rest @ ..] if rest.len() <= 1 => {
                let mut m = match rest {
                    [template] => self.mats.get(*template).cloned().ok_or_else(|| {
                        invalid(path, line, format!("undefined material '{template}'"))
                    })?,
                    _ => MatCtx::default(),
                };
                m.version = self.clock;
                self.mats.insert(name.to_string(), m.clone());
                self.mat = m;
                self.mat_name = Some(name.to_string());
            }
            _ => return Err(invalid(path, line, "m takes [name [= [template]]]")),
        }
        Ok(())
    }

    fn vertex_context(
        &mut self,
        path: &Path,
        line: usize,
        args: &[&str],
    ) -> Result<(), SceneError> {
        match args {
            [] => self.vertex_name = None,
            [name] => {
                if !self.vertices.contains_key(*name) {
                    return Err(invalid(path, line, format!("undefined vertex '{name}'")));
                }
                self.vertex_name = Some(name.to_string());
            }
            [name, "=", rest @ ..] if rest.len() <= 1 => {
                let v = match rest {
                    [template] => self.vertex(path, line, template)?,
                    _ => Vertex::default(),
                };
                self.vertices.insert(name.to_string(), v);
                self.vertex_name = Some(name.to_string());
            }
            _ => return Err(invalid(path, line, "v takes [name [= [template]]]")),
        }
        Ok(())
    }

    /// `fh outer… - hole… - hole…`: each hole is joined to the outer contour by a seam between
    /// its nearest pair of vertices, giving one polygon the mesher triangulates.
    fn face_with_holes(
        &self,
        path: &Path,
        line: usize,
        args: &[&str],
    ) -> Result<Vec<DVec3>, SceneError> {
        let mut contours: Vec<Vec<DVec3>> = vec![Vec::new()];
        for a in args {
            if *a == "-" {
                contours.push(Vec::new());
            } else {
                contours
                    .last_mut()
                    .unwrap()
                    .push(self.vertex(path, line, a)?.p);
            }
        }
        if let Some(c) = contours.iter().find(|c| c.len() < 3) {
            return Err(invalid(
                path,
                line,
                format!("fh contour has {} vertices; at least 3 needed", c.len()),
            ));
        }
        let mut outer = contours.remove(0);
        for hole in contours {
            let (mut bi, mut bj, mut best) = (0, 0, f64::INFINITY);
            for (i, p) in outer.iter().enumerate() {
                for (j, q) in hole.iter().enumerate() {
                    let d = p.distance_squared(*q);
                    if d < best {
                        (bi, bj, best) = (i, j, d);
                    }
                }
            }
            let mut joined = outer[..=bi].to_vec();
            joined.extend(hole[bj..].iter().chain(&hole[..=bj]));
            joined.extend(&outer[bi..]);
            outer = joined;
        }
        Ok(outer)
    }

    fn primitive(
        &mut self,
        path: &Path,
        line: usize,
        key: &str,
        args: &[&str],
        xf: &Xf,
    ) -> Result<(), SceneError> {
        let vtx = |k: usize| -> Result<Vertex, SceneError> {
            let name = args
                .get(k)
                .ok_or_else(|| invalid(path, line, format!("{key}: missing argument {}", k + 1)))?;
            self.vertex(path, line, name)
        };
        let num = |k: usize| -> Result<f64, SceneError> {
            let t = args
                .get(k)
                .ok_or_else(|| invalid(path, line, format!("{key}: missing argument {}", k + 1)))?;
            number(path, line, t, key)
        };
        let arity = |n: usize| -> Result<(), SceneError> {
            if args.len() == n {
                Ok(())
            } else {
                Err(invalid(
                    path,
                    line,
                    format!("{key} takes {n} arguments, not {}", args.len()),
                ))
            }
        };
        let axis_of = |v: &Vertex| -> Result<DVec3, SceneError> {
            v.n.try_normalize().ok_or_else(|| {
                invalid(
                    path,
                    line,
                    format!("{key}: its centre vertex has no normal (n) to orient it"),
                )
            })
        };
        match key {
            "sph" => {
                arity(2)?;
                let (c, r) = (vtx(0)?.p, num(1)?);
                if r == 0.0 {
                    return Err(invalid(path, line, "sph radius is 0"));
                }
                let bands = 2 * SEGMENTS_PER_QUARTER;
                let (u, w) = (DVec3::X, DVec3::Y);
                let rings: Vec<Vec<DVec3>> = (0..=bands)
                    .map(|j| {
                        let phi = std::f64::consts::PI * j as f64 / bands as f64;
                        circle(c, DVec3::Z, u, w, r.abs() * phi.cos(), r.abs() * phi.sin())
                    })
                    .collect();
                for j in 0..bands {
                    self.band(&rings[j], &rings[j + 1], &|p| p - c, r < 0.0, xf, line);
                }
            }
            "cyl" | "cone" => {
                let (v1, r1, v2, r2) = if key == "cyl" {
                    arity(3)?;
                    (vtx(0)?.p, num(1)?, vtx(2)?.p, num(1)?)
                } else {
                    arity(4)?;
                    (vtx(0)?.p, num(1)?, vtx(2)?.p, num(3)?)
                };
                if r1 * r2 < 0.0 || (r1 == 0.0 && r2 == 0.0) {
                    return Err(invalid(
                        path,
                        line,
                        format!("{key} radii {r1} and {r2} must share a sign and not both be 0"),
                    ));
                }
                let a = (v2 - v1).try_normalize().ok_or_else(|| {
                    invalid(path, line, format!("{key}: its two end vertices coincide"))
                })?;
                let (u, w) = basis(a);
                let ring1 = circle(v1, a, u, w, 0.0, r1.abs());
                let ring2 = circle(v2, a, u, w, 0.0, r2.abs());
                let out = move |p: DVec3| {
                    let d = p - v1;
                    // Away from the axis, tilted along it by the slope.
                    let radial = (d - a * d.dot(a)).normalize_or_zero();
                    radial * (v2 - v1).length() + a * (r1.abs() - r2.abs())
                };
                self.band(&ring1, &ring2, &out, r1 < 0.0 || r2 < 0.0, xf, line);
            }
            "ring" => {
                arity(3)?;
                let cv = vtx(0)?;
                let a = axis_of(&cv)?;
                let (r0, r1) = (num(1)?, num(2)?);
                if r0 < 0.0 || r1 < 0.0 || r0 == r1 {
                    return Err(invalid(
                        path,
                        line,
                        format!("ring radii {r0} and {r1} must be non-negative and differ"),
                    ));
                }
                let (u, w) = basis(a);
                let inner = circle(cv.p, a, u, w, 0.0, r0.min(r1));
                let outer = circle(cv.p, a, u, w, 0.0, r0.max(r1));
                self.band(&inner, &outer, &move |_| a, false, xf, line);
            }
            "torus" => {
                arity(3)?;
                let cv = vtx(0)?;
                let a = axis_of(&cv)?;
                let (r0, r1) = (num(1)?, num(2)?);
                if r0 * r1 < 0.0 || r0.abs() >= r1.abs() {
                    return Err(invalid(path, line, format!("torus radii {r0} and {r1}: the inner must be smaller than the outer, with the same sign")));
                }
                let (major, minor) = ((r0.abs() + r1.abs()) / 2.0, (r1.abs() - r0.abs()) / 2.0);
                let (u, w) = basis(a);
                let n = 4 * SEGMENTS_PER_QUARTER;
                let c = cv.p;
                let rings: Vec<Vec<DVec3>> = (0..=n)
                    .map(|j| {
                        let phi = std::f64::consts::TAU * j as f64 / n as f64;
                        circle(c, a, u, w, minor * phi.sin(), major + minor * phi.cos())
                    })
                    .collect();
                let out = move |p: DVec3| {
                    let d = p - c;
                    let radial = (d - a * d.dot(a)).normalize_or_zero();
                    p - (c + radial * major)
                };
                for j in 0..n {
                    self.band(&rings[j], &rings[j + 1], &out, r0 < 0.0, xf, line);
                }
            }
            _ => {
                // prism v1 … vk length
                if args.len() < 4 {
                    return Err(invalid(
                        path,
                        line,
                        format!(
                            "prism needs at least 3 vertices and a length; got {} arguments",
                            args.len()
                        ),
                    ));
                }
                let len = num(args.len() - 1)?;
                let base: Vec<DVec3> = (0..args.len() - 1)
                    .map(|k| vtx(k).map(|v| v.p))
                    .collect::<Result<_, _>>()?;
                let mut area = DVec3::ZERO;
                for k in 1..base.len() - 1 {
                    area += (base[k] - base[0]).cross(base[k + 1] - base[0]);
                }
                let nrm = area
                    .try_normalize()
                    .ok_or_else(|| invalid(path, line, "prism base polygon has zero area"))?;
                if len == 0.0 {
                    return Err(invalid(path, line, "prism length is 0"));
                }
                let top: Vec<DVec3> = base.iter().map(|p| *p - nrm * len).collect();
                self.emit(&base, xf, line);
                let rev: Vec<DVec3> = top.iter().rev().copied().collect();
                self.emit(&rev, xf, line);
                let k = base.len();
                for i in 0..k {
                    let j = (i + 1) % k;
                    self.emit(&[base[i], top[i], top[j], base[j]], xf, line);
                }
            }
        }
        Ok(())
    }
}

/// Orient polygon `q` so its normal agrees with `outward` at its centroid (reversed if `inward`).
fn orient(q: &mut [DVec3], outward: &dyn Fn(DVec3) -> DVec3, inward: bool) {
    if q.len() < 3 {
        return;
    }
    let mut area = DVec3::ZERO;
    for k in 1..q.len() - 1 {
        area += (q[k] - q[0]).cross(q[k + 1] - q[0]);
    }
    let centroid = q.iter().copied().sum::<DVec3>() / q.len() as f64;
    if (area.dot(outward(centroid)) < 0.0) != inward {
        q.reverse();
    }
}

/// Load an MGF file and everything it includes (two-sided surfaces doubled).
pub fn load(path: &Path) -> Result<Scene, SceneError> {
    load_with(path, false)
}

/// Load an MGF file; `one_sided` ignores `sides 2` and keeps every surface one-sided.
pub fn load_with(path: &Path, one_sided: bool) -> Result<Scene, SceneError> {
    let mut r = Reader::new();
    r.one_sided = one_sided;
    r.parse_file(path, Xf::new(DAffine3::IDENTITY))?;
    let mut warnings = Vec::new();
    let area_of = |p: &Polygon| super::polygon_area(&p.vertices);
    let (mut lost, mut total) = (0.0, 0.0);
    let mut lossy = vec![false; r.materials.len()];
    for p in &r.polygons {
        let a = area_of(p);
        total += a;
        lost += a * r.dropped[p.material];
        lossy[p.material] |= r.dropped[p.material] > 0.0;
    }
    let nlossy = lossy.iter().filter(|l| **l).count();
    if nlossy > 0 {
        let worst = r.dropped.iter().copied().fold(0.0, f64::max);
        warnings.push(format!(
            "{}: specular and transmission components (rs, ts, td) dropped from {nlossy} of {} materials: up to {} of the light falling on a surface, {} averaged over the scene's area",
            path.display(),
            r.materials.len(),
            crate::loc::percent(worst, 1.0, 0),
            crate::loc::percent(lost, total, 1)
        ));
    }
    let mut skipped: Vec<String> = r.skipped.iter().map(|(k, n)| format!("{k} ×{n}")).collect();
    if r.degenerate > 0 {
        skipped.push(format!("zero-area faces ×{}", r.degenerate));
    }
    if !skipped.is_empty() {
        warnings.push(format!(
            "{}: skipped: {}",
            path.display(),
            skipped.join(", ")
        ));
    }
    if r.clipped > 0 {
        warnings.push(format!(
            "{}: {} material colours lay outside the RGB gamut at their reflectance and were scaled to a largest channel of {MAX_REFLECTANCE}",
            path.display(),
            r.clipped
        ));
    }
    let origins = std::mem::take(&mut r.origins);
    let scene = Scene {
        name: super::name_of(path),
        source: Some(path.to_path_buf()),
        materials: r.materials,
        polygons: r.polygons,
        camera: None,
        warnings,
        origins,
        up: Some(Vec3::Z),
    };
    Ok(scene)
}

#[cfg(test)]
mod tests;
