//! Surfaces to patches.
//!
//! Every input polygon is first cut into *pieces*: a planar convex quad stays one piece, a
//! triangle is one piece, anything else is triangulated (ear clipping in the polygon's plane; a
//! non-planar quad is split along its shorter diagonal). A polygon with more than four vertices
//! that is not planar is refused. Each piece is then subdivided into a regular grid of patches
//! whose edges are no longer than the target length: quads into `nu × nv` quads (bilinear
//! interpolation of the corners), triangles into `n²` triangles. Vertices are shared inside a
//! piece, so that radiosity can be interpolated smoothly across it (Gouraud); pieces do not share
//! vertices with each other, which keeps edges between surfaces hard.
//!
//! A patch is planar to within the planarity tolerance of its piece; its normal is that of its
//! vector area, and its area the length of that vector.

mod coincident;
mod grid;

pub use coincident::Coincidence;
pub use grid::{quad_point, tri_point, Grid, GridShape, Locator};

use crate::geom::Vec3;
use crate::scene::{vector_area, Scene, SceneError};

/// Relative deviation from planarity (distance from the best plane over the polygon's diameter)
/// below which a polygon is treated as planar.
pub const PLANARITY_TOLERANCE: f32 = 1e-2;

/// How finely to subdivide.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum MeshParams {
    /// Patch edges no longer than this (scene units).
    MaxEdge(f32),
    /// About this many patches in total (the edge length is searched for).
    Patches(usize),
    /// One patch per piece: no subdivision (view factors between input faces).
    Faces,
}

impl Default for MeshParams {
    fn default() -> Self {
        MeshParams::Patches(10_000)
    }
}

/// A meshing parameter out of its range ([`MeshParams::validate`]).
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
pub enum MeshParamError {
    /// `Patches(0)`.
    #[error("0 patches: at least one patch is needed")]
    NoPatches,
    /// A largest edge that is not a finite positive length.
    #[error("largest patch edge {0}: must be a positive length")]
    MaxEdge(f32),
}

impl MeshParams {
    /// Check the parameters before any work: at least one patch, a finite positive largest
    /// edge. The one check the command line, the Python bindings and the workbench share.
    pub fn validate(&self) -> Result<(), MeshParamError> {
        match *self {
            MeshParams::Patches(0) => Err(MeshParamError::NoPatches),
            MeshParams::MaxEdge(l) if !(l.is_finite() && l > 0.0) => {
                Err(MeshParamError::MaxEdge(l))
            }
            _ => Ok(()),
        }
    }
}

/// A patch: a planar triangle or convex quad, part of one input polygon.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Patch {
    /// Indices into [`Mesh::vertices`], counter-clockwise seen from the front; the fourth is
    /// [`Patch::NONE`] for a triangle.
    pub vertices: [u32; 4],
    /// Index of the input polygon (the *surface*) the patch belongs to.
    pub surface: u32,
    /// Index of the scene material.
    pub material: u32,
    /// Area (square scene units).
    pub area: f32,
    /// Unit normal of the front side.
    pub normal: Vec3,
    /// Centroid.
    pub centre: Vec3,
    /// Fraction of the area in the first triangle `(v0, v1, v2)` (1 for a triangle); the rest is
    /// in `(v0, v2, v3)`. Used to sample points uniformly.
    pub split: f32,
}

impl Patch {
    /// Marker for the absent fourth vertex of a triangle.
    pub const NONE: u32 = u32::MAX;

    /// True for a triangular patch.
    pub fn is_triangle(&self) -> bool {
        self.vertices[3] == Self::NONE
    }

    /// The one or two triangles of the patch, as vertex-index triples.
    pub fn triangles(&self) -> impl Iterator<Item = [u32; 3]> {
        let [a, b, c, d] = self.vertices;
        std::iter::once([a, b, c]).chain((d != Self::NONE).then_some([a, c, d]))
    }
}

/// The patches of a scene and their vertices.
#[derive(Clone, Debug, Default)]
pub struct Mesh {
    /// Vertex positions, shared by the patches of one piece.
    pub vertices: Vec<Vec3>,
    /// The patches, grouped by piece, pieces in input-polygon order.
    pub patches: Vec<Patch>,
    /// The edge length the mesh was built with (0 for [`MeshParams::Faces`]).
    pub max_edge: f32,
    /// Smoothing group of each surface (input polygon), from [`crate::scene::Polygon::group`].
    pub groups: Vec<u32>,
    /// T-vertices `[v, a, b]`: vertex `v` lies on the edge `(a, b)` of a larger patch that
    /// does not have it as a corner, so its interpolated value must be the mean of `a`'s and
    /// `b`'s for colours to stay continuous. Ordered so that a constraint's `a` and `b` are
    /// final before it (longest edges first). Empty for uniform meshes; filled by adaptive
    /// meshes (hierarchical radiosity's leaves).
    pub hanging: Vec<[u32; 3]>,
    /// The regular grids [`Mesh::build`] cut its pieces into, in patch order: which patches and
    /// vertices each holds and how it is divided. A ray caster may then meet a piece as a whole
    /// and find the patch from where it met it ([`crate::accel::Bvh`], which checks that the
    /// patches and vertices still are the grid's before it relies on one). Empty for meshes
    /// made otherwise (hierarchical radiosity's leaves); a grid may be dropped at no cost but
    /// speed.
    pub grids: Vec<Grid>,
    /// Coincident polygons ([`Coincidence`]): the copies have no patches, and each stands for
    /// its representative's surface.
    pub coincident: Coincidence,
}

/// A piece of an input polygon: a triangle or a convex quad.
#[derive(Clone, Debug)]
enum Piece {
    Tri([Vec3; 3]),
    Quad([Vec3; 4]),
}

fn plane_deviation(v: &[Vec3]) -> (f32, f32) {
    let n = vector_area(v).normalize_or_zero();
    let c = v.iter().copied().sum::<Vec3>() / v.len() as f32;
    let dev = v.iter().map(|p| (*p - c).dot(n).abs()).fold(0.0, f32::max);
    let mut diam = 0.0f32;
    for a in v {
        for b in v {
            diam = diam.max((*a - *b).length());
        }
    }
    (dev, diam)
}

fn is_convex(v: &[Vec3], n: Vec3) -> bool {
    let k = v.len();
    (0..k).all(|i| {
        let (a, b, c) = (v[i], v[(i + 1) % k], v[(i + 2) % k]);
        (b - a).cross(c - b).dot(n) > 0.0
    })
}

/// Ear-clipping triangulation of a planar simple polygon; `None` if it is not simple.
fn ear_clip(v: &[Vec3], n: Vec3) -> Option<Vec<[Vec3; 3]>> {
    let mut idx: Vec<usize> = (0..v.len()).collect();
    let mut out = Vec::with_capacity(v.len() - 2);
    let inside = |p: Vec3, a: Vec3, b: Vec3, c: Vec3| {
        (b - a).cross(p - a).dot(n) >= 0.0
            && (c - b).cross(p - b).dot(n) >= 0.0
            && (a - c).cross(p - c).dot(n) >= 0.0
    };
    let mut guard = 0;
    while idx.len() > 3 {
        let k = idx.len();
        let mut clipped = false;
        for i in 0..k {
            let (ia, ib, ic) = (idx[(i + k - 1) % k], idx[i], idx[(i + 1) % k]);
            let (a, b, c) = (v[ia], v[ib], v[ic]);
            if (b - a).cross(c - b).dot(n) <= 0.0 {
                continue; // reflex or degenerate corner
            }
            // Only a reflex (or flat) corner inside the ear can make it invalid: a convex one
            // cannot lie inside without a reflex one there too (the test of Mapbox's earcut,
            // which also lets keyhole polygons, whose seams repeat vertices, be cut). Copies of
            // the ear's own corners do not block it.
            let blocked = (0..k).any(|m| {
                let j = idx[m];
                let p = v[j];
                if j == ia || j == ib || j == ic || p == a || p == b || p == c {
                    return false;
                }
                let (prev, next) = (v[idx[(m + k - 1) % k]], v[idx[(m + 1) % k]]);
                (p - prev).cross(next - p).dot(n) <= 0.0 && inside(p, a, b, c)
            });
            if !blocked {
                out.push([a, b, c]);
                idx.remove(i);
                clipped = true;
                break;
            }
        }
        guard += 1;
        if !clipped || guard > 4 * v.len() {
            return None;
        }
    }
    out.push([v[idx[0]], v[idx[1]], v[idx[2]]]);
    Some(out)
}

/// Cut polygon `i` of `scene` into pieces, or say why it cannot be.
fn pieces(scene: &Scene, i: usize) -> Result<Vec<Piece>, SceneError> {
    let v = &scene.polygons[i].vertices;
    let bad = |message: String| SceneError::Invalid {
        at: scene.place_of(i),
        message,
    };
    if v.len() == 3 {
        return Ok(vec![Piece::Tri([v[0], v[1], v[2]])]);
    }
    let n = vector_area(v).normalize_or_zero();
    let (dev, diam) = plane_deviation(v);
    let planar = dev <= PLANARITY_TOLERANCE * diam;
    if v.len() == 4 {
        let q = [v[0], v[1], v[2], v[3]];
        if planar && is_convex(v, n) {
            return Ok(vec![Piece::Quad(q)]);
        }
        if !planar {
            // Split along the shorter diagonal: both halves are planar.
            return Ok(if (q[2] - q[0]).length() <= (q[3] - q[1]).length() {
                vec![
                    Piece::Tri([q[0], q[1], q[2]]),
                    Piece::Tri([q[0], q[2], q[3]]),
                ]
            } else {
                vec![
                    Piece::Tri([q[0], q[1], q[3]]),
                    Piece::Tri([q[1], q[2], q[3]]),
                ]
            });
        }
    }
    if !planar {
        return Err(bad(format!(
            "polygon with {} vertices is not planar (a vertex lies {} of the polygon's size off its plane); split it into triangles",
            v.len(),
            crate::loc::percent(dev as f64, diam as f64, 3)
        )));
    }
    let tris = ear_clip(v, n).ok_or_else(|| {
        bad(format!(
            "polygon with {} vertices is not simple (its edges cross or it is degenerate) and cannot be triangulated",
            v.len()
        ))
    })?;
    Ok(tris.into_iter().map(Piece::Tri).collect())
}

/// Refuse polygons that are not planar (for one patch per face: a view factor needs a plane).
pub fn check_planar(scene: &Scene) -> Result<(), SceneError> {
    for (i, p) in scene.polygons.iter().enumerate() {
        if p.vertices.len() > 3 {
            let (dev, diam) = plane_deviation(&p.vertices);
            if dev > PLANARITY_TOLERANCE * diam {
                return Err(SceneError::Invalid {
                    at: scene.place_of(i),
                    message: format!(
                        "face is not planar (a vertex lies {} of its size off its plane); one patch per face needs planar faces: split it into triangles",
                        crate::loc::percent(dev as f64, diam as f64, 3)
                    ),
                });
            }
        }
    }
    Ok(())
}

fn divisions(len: f32, max_edge: f32) -> u32 {
    if max_edge <= 0.0 {
        return 1;
    }
    ((len / max_edge).ceil() as u32).max(1)
}

fn quad_divisions(q: &[Vec3; 4], l: f32) -> (u32, u32) {
    let nu = divisions((q[1] - q[0]).length().max((q[2] - q[3]).length()), l);
    let nv = divisions((q[3] - q[0]).length().max((q[2] - q[1]).length()), l);
    (nu, nv)
}

fn tri_divisions(t: &[Vec3; 3], l: f32) -> u32 {
    let e = (t[1] - t[0])
        .length()
        .max((t[2] - t[1]).length())
        .max((t[0] - t[2]).length());
    divisions(e, l)
}

fn count(all: &[(usize, Vec<Piece>)], l: f32) -> u64 {
    let mut n = 0u64;
    for (_, ps) in all {
        for p in ps {
            n += match p {
                Piece::Quad(q) => {
                    let (a, b) = quad_divisions(q, l);
                    a as u64 * b as u64
                }
                Piece::Tri(t) => (tri_divisions(t, l) as u64).pow(2),
            };
        }
    }
    n
}

fn make_patch(mesh: &Mesh, vertices: [u32; 4], surface: u32, material: u32) -> Patch {
    let p = |k: usize| mesh.vertices[vertices[k] as usize];
    let (a0, a1, area_vec, centre) = if vertices[3] == Patch::NONE {
        let a = (p(1) - p(0)).cross(p(2) - p(0)) * 0.5;
        (a.length(), 0.0, a, (p(0) + p(1) + p(2)) / 3.0)
    } else {
        let t0 = (p(1) - p(0)).cross(p(2) - p(0)) * 0.5;
        let t1 = (p(2) - p(0)).cross(p(3) - p(0)) * 0.5;
        let c0 = (p(0) + p(1) + p(2)) / 3.0;
        let c1 = (p(0) + p(2) + p(3)) / 3.0;
        let (l0, l1) = (t0.length(), t1.length());
        let c = if l0 + l1 > 0.0 {
            (c0 * l0 + c1 * l1) / (l0 + l1)
        } else {
            c0
        };
        (l0, l1, t0 + t1, c)
    };
    let total = a0 + a1;
    Patch {
        vertices,
        surface,
        material,
        area: total,
        normal: area_vec.normalize_or_zero(),
        centre,
        split: if total > 0.0 { a0 / total } else { 1.0 },
    }
}

impl Mesh {
    /// Mesh `scene` (which should have passed [`Scene::validate`]).
    pub fn build(scene: &Scene, params: MeshParams) -> Result<Mesh, SceneError> {
        let coincident = Coincidence::find(scene);
        // Every polygon is checked; the copies of a coincident group are then left out.
        let mut all: Vec<(usize, Vec<Piece>)> = (0..scene.polygons.len())
            .map(|i| pieces(scene, i).map(|p| (i, p)))
            .collect::<Result<_, _>>()?;
        if coincident.merged > 0 {
            all.retain(|(i, _)| !coincident.is_copy(*i));
        }
        let max_edge = match params {
            MeshParams::Faces => 0.0,
            MeshParams::MaxEdge(l) => l,
            MeshParams::Patches(target) => {
                let target = target.max(1) as f64;
                let area: f64 = all
                    .iter()
                    .map(|(i, _)| crate::scene::polygon_area(&scene.polygons[*i].vertices))
                    .sum();
                let mut l = (area / target).sqrt() as f32;
                let mut best = (f64::INFINITY, l);
                for _ in 0..8 {
                    let c = count(&all, l) as f64;
                    let err = (c / target).ln().abs();
                    if err < best.0 {
                        best = (err, l);
                    }
                    if err < 0.01 {
                        break;
                    }
                    l *= (c / target).sqrt() as f32;
                }
                best.1
            }
        };
        let mut mesh = Mesh {
            max_edge,
            groups: scene.polygons.iter().map(|p| p.group).collect(),
            coincident,
            ..Default::default()
        };
        let expected = count(&all, max_edge) as usize;
        mesh.patches.reserve(expected);
        mesh.vertices.reserve(expected + expected / 4);
        for (poly, ps) in &all {
            let material = scene.polygons[*poly].material as u32;
            for piece in ps {
                mesh.add_piece(piece, max_edge, *poly as u32, material);
            }
        }
        Ok(mesh)
    }

    fn add_piece(&mut self, piece: &Piece, l: f32, surface: u32, material: u32) {
        let base = self.vertices.len() as u32;
        let first_patch = self.patches.len() as u32;
        match piece {
            Piece::Quad(q) => {
                let (nu, nv) = quad_divisions(q, l);
                self.grids.push(Grid {
                    first_patch,
                    first_vertex: base,
                    shape: GridShape::Quad { nu, nv },
                });
                for j in 0..=nv {
                    for i in 0..=nu {
                        self.vertices.push(quad_point(q, nu, nv, i, j));
                    }
                }
                let at = |i: u32, j: u32| base + j * (nu + 1) + i;
                for j in 0..nv {
                    for i in 0..nu {
                        let vs = [at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)];
                        let p = make_patch(self, vs, surface, material);
                        self.patches.push(p);
                    }
                }
            }
            Piece::Tri(t) => {
                let n = tri_divisions(t, l);
                self.grids.push(Grid {
                    first_patch,
                    first_vertex: base,
                    shape: GridShape::Tri { n },
                });
                // Row j holds n + 1 − j vertices; index of (i, j).
                let mut row_start = Vec::with_capacity(n as usize + 1);
                for j in 0..=n {
                    row_start.push(self.vertices.len() as u32);
                    for i in 0..=(n - j) {
                        self.vertices.push(tri_point(t, n, i, j));
                    }
                }
                let at = |i: u32, j: u32| row_start[j as usize] + i;
                for j in 0..n {
                    for i in 0..(n - j) {
                        let up = [at(i, j), at(i + 1, j), at(i, j + 1), Patch::NONE];
                        let p = make_patch(self, up, surface, material);
                        self.patches.push(p);
                        if i + j + 1 < n {
                            let down = [at(i + 1, j), at(i + 1, j + 1), at(i, j + 1), Patch::NONE];
                            let p = make_patch(self, down, surface, material);
                            self.patches.push(p);
                        }
                    }
                }
            }
        }
    }

    /// The area-weighted mean of `values` (one per patch) over each of the `surfaces` input
    /// polygons; a coincident copy ([`Coincidence`]) reports its group's surface, and a
    /// surface with no patch (none of zero area) black.
    pub fn surface_means(
        &self,
        values: &[crate::color::Rgb],
        surfaces: usize,
    ) -> Vec<crate::color::Rgb> {
        use crate::color::Rgb;
        let mut sum = vec![Rgb::BLACK; surfaces];
        let mut area = vec![0.0f64; surfaces];
        for (p, v) in self.patches.iter().zip(values) {
            if let Some(s) = sum.get_mut(p.surface as usize) {
                *s += *v * p.area as f64;
                area[p.surface as usize] += p.area as f64;
            }
        }
        let mut out: Vec<Rgb> = sum
            .iter()
            .zip(&area)
            .map(|(&s, &a)| if a > 0.0 { s * (1.0 / a) } else { Rgb::BLACK })
            .collect();
        for i in 0..surfaces {
            let r = self.coincident.representative(i);
            if r != i && r < surfaces {
                out[i] = out[r];
            }
        }
        out
    }

    /// Number of patches.
    pub fn len(&self) -> usize {
        self.patches.len()
    }

    /// True when there are no patches.
    pub fn is_empty(&self) -> bool {
        self.patches.is_empty()
    }

    /// Total patch area.
    pub fn total_area(&self) -> f64 {
        self.patches.iter().map(|p| p.area as f64).sum()
    }

    /// A point of patch `i` from two uniforms in `[0, 1)`; uniform over the patch's area.
    #[inline]
    pub fn sample_point(&self, i: usize, u1: f32, u2: f32, u3: f32) -> Vec3 {
        let p = &self.patches[i];
        let [a, b, c, d] = p.vertices;
        let (b, c) = if u3 < p.split || d == Patch::NONE {
            (b, c)
        } else {
            (c, d)
        };
        let (s, t) = crate::sampling::uniform_triangle(u1, u2);
        let (a, b, c) = (
            self.vertices[a as usize],
            self.vertices[b as usize],
            self.vertices[c as usize],
        );
        a + (b - a) * s + (c - a) * t
    }

    /// Check the mesh's invariants: indices in range, positive areas, unit normals that agree
    /// with each triangle's own orientation. Tests call it.
    pub fn validate(&self) -> Result<(), String> {
        for (k, p) in self.patches.iter().enumerate() {
            for t in p.triangles() {
                if t.iter().any(|&v| v as usize >= self.vertices.len()) {
                    return Err(format!("patch {k}: vertex index out of range"));
                }
                let tn = crate::geom::triangle_cross(
                    self.vertices[t[0] as usize],
                    self.vertices[t[1] as usize],
                    self.vertices[t[2] as usize],
                );
                if tn.dot(p.normal) < 0.0 {
                    return Err(format!(
                        "patch {k}: a triangle faces against the patch normal"
                    ));
                }
            }
            if p.area.is_nan() || p.area <= 0.0 {
                return Err(format!("patch {k}: area {} is not positive", p.area));
            }
            if (p.normal.length() - 1.0).abs() > 1e-4 {
                return Err(format!("patch {k}: normal is not unit length"));
            }
        }
        Ok(())
    }
}

/// The linear system of `mesh`'s patches in `scene`: areas, and reflectances and emissions
/// from their materials. The one bridge from geometry to the solvers.
pub fn patch_system(scene: &Scene, mesh: &Mesh) -> crate::system::System {
    let material = |p: &Patch| &scene.materials[p.material as usize];
    crate::system::System {
        area: mesh.patches.iter().map(|p| p.area as f64).collect(),
        reflectance: mesh
            .patches
            .iter()
            .map(|p| material(p).reflectance)
            .collect(),
        emission: mesh.patches.iter().map(|p| material(p).emission).collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::color::Rgb;
    use crate::scene::{builtin, polygon_area, Material, Polygon};

    fn one_polygon(vertices: Vec<Vec3>) -> Scene {
        Scene {
            name: "t".into(),
            materials: vec![Material::emitter("m", Rgb::splat(0.5), Rgb::splat(1.0))],
            polygons: vec![Polygon {
                vertices,
                material: 0,
                line: 0,
                group: 0,
            }],
            ..Default::default()
        }
    }

    #[test]
    fn area_is_preserved_and_edges_bounded() {
        let s = builtin::cornell();
        for l in [200.0, 50.0, 17.0] {
            let m = Mesh::build(&s, MeshParams::MaxEdge(l)).unwrap();
            m.validate().unwrap();
            let rel = (m.total_area() - s.total_area()).abs() / s.total_area();
            assert!(rel < 1e-5, "{rel}");
            for p in &m.patches {
                for t in p.triangles() {
                    for k in 0..3 {
                        let e = m.vertices[t[k] as usize] - m.vertices[t[(k + 1) % 3] as usize];
                        // Quad diagonals are up to √2·l; a quad side at most l (plus rounding).
                        assert!(e.length() <= l * 1.4143 + 1e-2);
                    }
                }
            }
        }
    }

    #[test]
    fn patch_count_target_is_met_approximately() {
        let s = builtin::cornell();
        for target in [500, 4000, 10_000] {
            let m = Mesh::build(&s, MeshParams::Patches(target)).unwrap();
            let ratio = m.len() as f64 / target as f64;
            assert!((0.85..1.15).contains(&ratio), "{target}: {}", m.len());
        }
    }

    #[test]
    fn triangle_subdivision_shares_vertices() {
        let s = one_polygon(vec![Vec3::ZERO, Vec3::X, Vec3::Y]);
        // The hypotenuse √2 sets n = ceil(√2 / 0.36) = 4.
        let m = Mesh::build(&s, MeshParams::MaxEdge(0.36)).unwrap();
        assert_eq!(m.len(), 16);
        assert_eq!(m.vertices.len(), 15); // (n+1)(n+2)/2 for n = 4
        assert!((m.total_area() - 0.5).abs() < 1e-6);
        m.validate().unwrap();
    }

    #[test]
    fn nonconvex_polygon_is_triangulated_exactly() {
        // An L shape of area 3.
        let l = vec![
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(2.0, 0.0, 0.0),
            Vec3::new(2.0, 1.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(1.0, 2.0, 0.0),
            Vec3::new(0.0, 2.0, 0.0),
        ];
        let s = one_polygon(l.clone());
        assert!((polygon_area(&l) - 3.0).abs() < 1e-6);
        let m = Mesh::build(&s, MeshParams::Faces).unwrap();
        assert_eq!(m.len(), 4);
        assert!((m.total_area() - 3.0).abs() < 1e-6);
        m.validate().unwrap();
    }

    #[test]
    fn nonplanar_hexagon_is_refused() {
        let mut v: Vec<Vec3> = (0..6)
            .map(|k| {
                let a = k as f32 * std::f32::consts::TAU / 6.0;
                Vec3::new(a.cos(), a.sin(), 0.0)
            })
            .collect();
        v[2].z = 0.5;
        let err = Mesh::build(&one_polygon(v), MeshParams::Faces).unwrap_err();
        assert!(err.to_string().contains("not planar"), "{err}");
    }

    #[test]
    fn nonplanar_quad_is_split() {
        let q = vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.3), Vec3::Y];
        let m = Mesh::build(&one_polygon(q), MeshParams::Faces).unwrap();
        assert_eq!(m.len(), 2);
        assert!(m.patches.iter().all(|p| p.is_triangle()));
    }
}
