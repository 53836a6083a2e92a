//! The regular grids [`Mesh::build`](super::Mesh::build) cuts pieces into, and the way back from
//! a point of a piece to the patch there ([`Locator`]): a ray caster can then meet a piece as one
//! or two triangles, however many patches it was cut into, and still report the patch hit.

use super::{Mesh, Patch};
use crate::geom::Vec3;

/// A piece that [`Mesh::build`] cut into a regular grid of patches, whose patches and vertices
/// are consecutive from `first_patch` and `first_vertex`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Grid {
    /// The grid's first patch.
    pub first_patch: u32,
    /// The grid's first vertex.
    pub first_vertex: u32,
    /// How it is divided.
    pub shape: GridShape,
}

/// How a [`Grid`] divides its piece.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GridShape {
    /// A convex quad `q0 q1 q2 q3` cut into `nu × nv` quads. Vertex `(i, j)` (`i ≤ nu`,
    /// `j ≤ nv`) is the bilinear point at `(s, t) = (i / nu, j / nv)` (`s` runs from `q0`
    /// to `q1`, `t` from `q0` to `q3`) and is vertex `first_vertex + j (nu + 1) + i`; patch
    /// `(i, j)` (`i < nu`, `j < nv`) is patch `first_patch + j nu + i`, with the vertices
    /// `(i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)`.
    Quad {
        /// Divisions from `q0` to `q1`.
        nu: u32,
        /// Divisions from `q0` to `q3`.
        nv: u32,
    },
    /// A triangle `t0 t1 t2` cut into `n²` triangles. Vertex `(i, j)` (`i + j ≤ n`) is
    /// `t0 + (t1 − t0) i / n + (t2 − t0) j / n`, rows of constant `j` one after another (row
    /// `j` holds `n + 1 − j` vertices). The patches go row by row, and in row `j`, for each
    /// `i < n − j`, the upright triangle `(i, j), (i + 1, j), (i, j + 1)` and then, where
    /// `i + j + 1 < n`, the inverted one `(i + 1, j), (i + 1, j + 1), (i, j + 1)`.
    Tri {
        /// Divisions of each edge.
        n: u32,
    },
}

impl Grid {
    /// How many patches the grid holds.
    pub fn patches(&self) -> usize {
        match self.shape {
            GridShape::Quad { nu, nv } => (nu as usize).saturating_mul(nv as usize),
            GridShape::Tri { n } => (n as usize).saturating_mul(n as usize),
        }
    }

    /// How many vertices the grid holds.
    pub fn vertices(&self) -> usize {
        match self.shape {
            GridShape::Quad { nu, nv } => (nu as usize + 1).saturating_mul(nv as usize + 1),
            GridShape::Tri { n } => (n as usize + 1).saturating_mul(n as usize + 2) / 2,
        }
    }
}

/// Vertex `(i, j)` of quad `q` cut into `nu × nv` ([`GridShape::Quad`]).
#[inline]
pub fn quad_point(q: &[Vec3; 4], nu: u32, nv: u32, i: u32, j: u32) -> Vec3 {
    let (s, t) = (i as f32 / nu as f32, j as f32 / nv as f32);
    q[0] * ((1.0 - s) * (1.0 - t))
        + q[1] * (s * (1.0 - t))
        + q[2] * (s * t)
        + q[3] * ((1.0 - s) * t)
}

/// Vertex `(i, j)` of triangle `t` cut into `n²` ([`GridShape::Tri`]).
#[inline]
pub fn tri_point(t: &[Vec3; 3], n: u32, i: u32, j: u32) -> Vec3 {
    let (s, r) = (i as f32 / n as f32, j as f32 / n as f32);
    t[0] + (t[1] - t[0]) * s + (t[2] - t[0]) * r
}

/// The way from a point of a [`Grid`]'s piece, given as where a ray met one of the piece's
/// triangles ([`Locator::new`] lists them), to the patch there and where in that patch:
/// the inverse of the grid's vertex formula.
///
/// A quad piece `q0 q1 q2 q3` is met as the triangles `(q0, q1, q2)` and `(q0, q2, q3)`. In
/// the affine coordinates `(a, b)` of its plane with `q0` at the origin, `q1` at `(1, 0)` and
/// `q3` at `(0, 1)`, the fourth corner `q2` is `(1 + α, 1 + β)` (α = β = 0 for a
/// parallelogram), and the bilinear point of parameters `(s, t)` is
/// `(s (1 + α t), t (1 + β s))`. A point met on a piece triangle with barycentric coordinates
/// `(u, v)` is turned into `(a, b)` (affine maps keep barycentric coordinates), and `(s, t)`
/// found from `α t² + (1 + β a − α b) t − b = 0` (the root in `[0, 1]`, in the form that does
/// not cancel) and `s = a / (1 + α t)`. The patch is `(⌊s nu⌋, ⌊t nv⌋)`; the point's
/// barycentric coordinates in that patch's triangle are again computed in `(a, b)`.
///
/// A triangle piece is met as itself; its barycentric coordinates scaled by `n` give the row,
/// the column and whether the point lies in the upright or the inverted small triangle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Locator {
    first: u32,
    /// Quad: divisions from `q0` to `q1`; triangle: `n`.
    nu: u32,
    /// Quad: divisions from `q0` to `q3`; triangle: 0.
    nv: u32,
    /// `1 / nu` and `1 / nv` (quad).
    inv_nu: f32,
    inv_nv: f32,
    /// 0 and 0 for a parallelogram, to within the tolerance it was built with.
    alpha: f32,
    beta: f32,
}

/// The smallest `1 + α`, `1 + β` and `1 + α + β` a quad may have: how far from degenerate
/// (a corner's angle near 180°) its bilinear parameters are still well conditioned.
const CONVEX_MARGIN: f64 = 1e-3;

impl Locator {
    /// The locator of grid `g` of `mesh`, with the triangles of its piece (ccw seen from the
    /// front, as the patches') and how many there are (2 for a quad, 1 for a triangle), if the
    /// mesh holds what `g` says: its patches and vertices in range and numbered as the grid
    /// numbers them, every vertex within `tol` (each coordinate) of the grid's point, and a
    /// quad within `tol` of planar and convex. `None` otherwise: then the caller meets the
    /// grid's patches one by one.
    pub fn new(mesh: &Mesh, g: &Grid, tol: f32) -> Option<(Locator, [[Vec3; 3]; 2], usize)> {
        let (p0, v0) = (g.first_patch as usize, g.first_vertex as usize);
        if p0.checked_add(g.patches())? > mesh.patches.len()
            || v0.checked_add(g.vertices())? > mesh.vertices.len()
            || g.patches() == 0
        {
            return None;
        }
        let near = |a: Vec3, b: Vec3| (a - b).abs().max_element() <= tol;
        match g.shape {
            GridShape::Quad { nu, nv } => {
                let at = |i: u32, j: u32| (v0 + j as usize * (nu as usize + 1) + i as usize) as u32;
                let vx = |i, j| mesh.vertices[at(i, j) as usize];
                let q = [vx(0, 0), vx(nu, 0), vx(nu, nv), vx(0, nv)];
                for j in 0..nv {
                    for i in 0..nu {
                        let p = &mesh.patches[p0 + (j * nu + i) as usize];
                        if p.vertices != [at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)] {
                            return None;
                        }
                    }
                }
                for j in 0..=nv {
                    for i in 0..=nu {
                        if !near(vx(i, j), quad_point(&q, nu, nv, i, j)) {
                            return None;
                        }
                    }
                }
                // q2 − q0 = x e + y f by least squares over the edges e and f, in f64.
                let d64 = |a: Vec3, b: Vec3| (a - b).as_dvec3();
                let (e, f, d) = (d64(q[1], q[0]), d64(q[3], q[0]), d64(q[2], q[0]));
                let (ee, ff, ef) = (e.dot(e), f.dot(f), e.dot(f));
                let det = ee * ff - ef * ef;
                if det.is_nan() || det <= 1e-9 * ee * ff {
                    return None;
                }
                let (de, df) = (d.dot(e), d.dot(f));
                let x = (de * ff - df * ef) / det;
                let y = (df * ee - de * ef) / det;
                let twist = (d - e * x - f * y).length();
                let (mut alpha, mut beta) = (x - 1.0, y - 1.0);
                if twist.is_nan()
                    || twist > tol as f64
                    || 1.0 + alpha < CONVEX_MARGIN
                    || 1.0 + beta < CONVEX_MARGIN
                    || 1.0 + alpha + beta < CONVEX_MARGIN
                {
                    return None;
                }
                // A parallelogram where the corners' rounding allows: the bilinear term
                // `s t (α e + β f)` then moves no point by more than `tol`, and the patch is
                // found without a square root or a division.
                if (e * alpha + f * beta).length() <= tol as f64 {
                    (alpha, beta) = (0.0, 0.0);
                }
                let locator = Locator {
                    first: g.first_patch,
                    nu,
                    nv,
                    inv_nu: 1.0 / nu as f32,
                    inv_nv: 1.0 / nv as f32,
                    alpha: alpha as f32,
                    beta: beta as f32,
                };
                Some((locator, [[q[0], q[1], q[2]], [q[0], q[2], q[3]]], 2))
            }
            GridShape::Tri { n } => {
                // Row j starts after the rows before it, of n + 1, n, … vertices.
                let row = |j: u32| v0 + (j as usize * (2 * n as usize + 3 - j as usize)) / 2;
                let at = |i: u32, j: u32| (row(j) + i as usize) as u32;
                let vx = |i, j| mesh.vertices[at(i, j) as usize];
                let t = [vx(0, 0), vx(n, 0), vx(0, n)];
                let mut k = p0;
                for j in 0..n {
                    for i in 0..n - j {
                        let up = [at(i, j), at(i + 1, j), at(i, j + 1), Patch::NONE];
                        if mesh.patches[k].vertices != up {
                            return None;
                        }
                        k += 1;
                        if i + j + 1 < n {
                            let down = [at(i + 1, j), at(i + 1, j + 1), at(i, j + 1), Patch::NONE];
                            if mesh.patches[k].vertices != down {
                                return None;
                            }
                            k += 1;
                        }
                    }
                }
                for j in 0..=n {
                    for i in 0..=n - j {
                        if !near(vx(i, j), tri_point(&t, n, i, j)) {
                            return None;
                        }
                    }
                }
                let area = (t[1] - t[0]).cross(t[2] - t[0]).length();
                if area.is_nan() || area <= 0.0 {
                    return None;
                }
                let locator = Locator {
                    first: g.first_patch,
                    nu: n,
                    nv: 0,
                    inv_nu: 1.0 / n as f32,
                    inv_nv: 0.0,
                    alpha: 0.0,
                    beta: 0.0,
                };
                Some((locator, [t, t], 1))
            }
        }
    }

    /// The patch at the point with barycentric coordinates `(u, v)` in the piece's triangle
    /// `sub` (0 or 1, as [`Locator::new`] listed them), and the point's triangle of that patch
    /// (0: `(v0, v1, v2)`, 1: `(v0, v2, v3)`) and barycentric coordinates in it, as
    /// [`crate::accel::Hit`] gives them. Points a little outside the piece (within a ray
    /// caster's slack) go to the nearest patch.
    #[inline(always)]
    pub fn locate(&self, sub: u32, u: f32, v: f32) -> (u32, u8, f32, f32) {
        if self.nv == 0 {
            return self.locate_in_triangle(u, v);
        }
        let (al, be) = (self.alpha, self.beta);
        let (nu, nv) = (self.nu as f32, self.nv as f32);
        if al == 0.0 && be == 0.0 {
            // A parallelogram: (a, b) are the bilinear parameters, and the patches'
            // triangles are halves of the cells of the grid they scale to.
            let (a, b) = if sub == 0 { (u + v, v) } else { (u, u + v) };
            let (x, y) = (a * nu, b * nv);
            // `as` saturates: negative and NaN give 0.
            let i = (x as u32).min(self.nu - 1);
            let j = (y as u32).min(self.nv - 1);
            let (x, y) = (x - i as f32, y - j as f32);
            let patch = self.first + j * self.nu + i;
            return if x >= y {
                (patch, 0, x - y, y)
            } else {
                (patch, 1, x, y - x)
            };
        }
        self.locate_in_quad(sub, u, v)
    }

    /// [`Locator::locate`] on a quad that is not a parallelogram.
    #[inline(never)]
    fn locate_in_quad(&self, sub: u32, u: f32, v: f32) -> (u32, u8, f32, f32) {
        let (al, be) = (self.alpha, self.beta);
        // The point in the plane's coordinates with q0, q1, q3 at (0, 0), (1, 0), (0, 1).
        let (a, b) = if sub == 0 {
            (u + v * (1.0 + al), v * (1.0 + be))
        } else {
            (u * (1.0 + al), u * (1.0 + be) + v)
        };
        let q = 1.0 + be * a - al * b;
        let root = q + (q * q + 4.0 * al * b).max(0.0).sqrt();
        let t = if root > 0.0 { 2.0 * b / root } else { b };
        let s = a / (1.0 + al * t.clamp(0.0, 1.0));
        let (nu, nv) = (self.nu, self.nv);
        // `as` saturates: negative and NaN give 0.
        let i = ((s * nu as f32) as u32).min(nu - 1);
        let j = ((t * nv as f32) as u32).min(nv - 1);
        let patch = self.first + j * nu + i;
        // The patch's corners in the same coordinates.
        let c = |i: u32, j: u32| {
            let (s, t) = (i as f32 * self.inv_nu, j as f32 * self.inv_nv);
            (s * (1.0 + al * t), t * (1.0 + be * s))
        };
        let (c0, c1, c2, c3) = (c(i, j), c(i + 1, j), c(i + 1, j + 1), c(i, j + 1));
        let w = (a - c0.0, b - c0.1);
        let d2 = (c2.0 - c0.0, c2.1 - c0.1);
        // v1 lies right of the diagonal v0 → v2 (the corners run counter-clockwise).
        let (sub, e1, e2) = if d2.0 * w.1 - d2.1 * w.0 <= 0.0 {
            (0, (c1.0 - c0.0, c1.1 - c0.1), d2)
        } else {
            (1, d2, (c3.0 - c0.0, c3.1 - c0.1))
        };
        let inv = 1.0 / (e1.0 * e2.1 - e1.1 * e2.0);
        let pu = (w.0 * e2.1 - w.1 * e2.0) * inv;
        let pv = (e1.0 * w.1 - e1.1 * w.0) * inv;
        (patch, sub, pu, pv)
    }

    /// How many patches the grid holds.
    pub fn patches(&self) -> usize {
        if self.nv == 0 {
            self.nu as usize * self.nu as usize
        } else {
            self.nu as usize * self.nv as usize
        }
    }

    /// [`Locator::locate`] on a triangle grid.
    #[inline(always)]
    fn locate_in_triangle(&self, u: f32, v: f32) -> (u32, u8, f32, f32) {
        let n = self.nu;
        let (x, y) = (u * n as f32, v * n as f32);
        let j = (y as u32).min(n - 1);
        let i = (x as u32).min(n - 1 - j);
        let (fx, fy) = (x - i as f32, y - j as f32);
        let down = fx + fy > 1.0 && i + j + 1 < n;
        // Rows before j hold 2 (n − j') − 1 patches each: 2 n j − j² in all.
        let (n64, j64) = (n as u64, j as u64);
        let patch = self.first + (2 * n64 * j64 - j64 * j64) as u32 + 2 * i + down as u32;
        if down {
            (patch, 0, fx + fy - 1.0, 1.0 - fx)
        } else {
            (patch, 0, fx, fy)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::MeshParams;

    /// Barycentric coordinates of `p` in triangle `t` (in its plane).
    fn barycentric(t: &[Vec3; 3], p: Vec3) -> (f32, f32) {
        let (e1, e2, w) = (t[1] - t[0], t[2] - t[0], p - t[0]);
        let n = e1.cross(e2);
        let inv = 1.0 / n.length_squared();
        (w.cross(e2).dot(n) * inv, e1.cross(w).dot(n) * inv)
    }

    /// Each patch of a grid is found again at points inside each of its triangles (near every
    /// corner and at the centre), from the piece triangle that holds the point, with the
    /// patch's triangle and coordinates of that point; on quads whose fourth corner lies off
    /// the parallelogram of the other three by various amounts, and on a triangle.
    #[test]
    fn each_patch_is_found_at_its_own_points() {
        let quads = [
            [[0.0, 0.0], [2.0, 0.0], [2.0, 1.0], [0.0, 1.0]],
            [[0.0, 0.0], [2.0, 0.5], [3.0, 2.0], [1.0, 1.5]],
            [[0.0, 0.0], [3.0, 0.0], [2.0, 1.0], [1.0, 1.0]],
            [[0.0, 0.0], [1.0, 0.2], [1.4, 1.9], [-0.3, 0.8]],
            [[0.0, 0.0], [4.0, 0.0], [4.0, 0.3], [0.0, 3.0]],
        ];
        let mut polygons: Vec<Vec<Vec3>> = quads
            .iter()
            .enumerate()
            .map(|(k, q)| {
                q.iter()
                    .map(|&[x, y]| Vec3::new(x + 5.0 * k as f32, y, 0.5 * x - 3.0))
                    .collect()
            })
            .collect();
        polygons.push(vec![
            Vec3::new(0.0, 5.0, 1.0),
            Vec3::new(3.0, 6.0, 1.0),
            Vec3::new(1.0, 8.0, 2.0),
        ]);
        let scene = crate::scene::Scene::of_polygons(
            "grids",
            crate::scene::Material::diffuse("grey", crate::color::Rgb::splat(0.5)),
            polygons,
        );
        let mesh = Mesh::build(&scene, MeshParams::MaxEdge(0.23)).unwrap();
        assert_eq!(mesh.grids.len(), 6);
        let mut checked = 0;
        for g in &mesh.grids {
            let (locator, tris, count) = Locator::new(&mesh, g, 1e-5).expect("a grid");
            assert_eq!(locator.patches(), g.patches());
            assert!(g.patches() > 20);
            for k in 0..g.patches() {
                let patch = g.first_patch + k as u32;
                let p = &mesh.patches[patch as usize];
                for (sub, t) in p.triangles().enumerate() {
                    let t = t.map(|v| mesh.vertices[v as usize]);
                    let centre = (t[0] + t[1] + t[2]) / 3.0;
                    for point in [centre, t[0], t[1], t[2]].map(|c| c + (centre - c) * 0.1) {
                        // The piece triangle that holds the point.
                        let (piece, (u, v)) = (0..count)
                            .map(|s| (s, barycentric(&tris[s], point)))
                            .find(|(_, (u, v))| *u >= -1e-6 && *v >= -1e-6 && u + v <= 1.0 + 1e-6)
                            .expect("inside the piece");
                        let (found, s, pu, pv) = locator.locate(piece as u32, u, v);
                        assert_eq!(found, patch, "grid {g:?}, patch {k}");
                        assert_eq!(s as usize, sub, "grid {g:?}, patch {k}");
                        let (eu, ev) = barycentric(&t, point);
                        assert!(
                            (pu - eu).abs() < 1e-3 && (pv - ev).abs() < 1e-3,
                            "({pu}, {pv}) against ({eu}, {ev})"
                        );
                        checked += 1;
                    }
                }
            }
        }
        assert!(checked > 1000, "{checked}");
    }

    /// A grid whose mesh no longer holds what it says is refused: a vertex moved, patches
    /// renumbered, or a quad bent out of its plane.
    #[test]
    fn a_grid_the_mesh_contradicts_is_refused() {
        let scene = crate::scene::Scene::of_polygons(
            "grids",
            crate::scene::Material::diffuse("grey", crate::color::Rgb::splat(0.5)),
            vec![vec![
                Vec3::new(0.0, 0.0, 0.0),
                Vec3::new(1.0, 0.0, 0.0),
                Vec3::new(1.0, 1.0, 0.0),
                Vec3::new(0.0, 1.0, 0.0),
            ]],
        );
        let mesh = Mesh::build(&scene, MeshParams::Patches(16)).unwrap();
        let g = mesh.grids[0];
        assert!(Locator::new(&mesh, &g, 1e-6).is_some());
        let mut moved = mesh.clone();
        moved.vertices[6].x += 1e-3;
        assert!(Locator::new(&moved, &g, 1e-6).is_none());
        let mut swapped = mesh.clone();
        swapped.patches.swap(1, 2);
        assert!(Locator::new(&swapped, &g, 1e-6).is_none());
        let mut bent = mesh.clone();
        let last = bent.vertices.len() - 1;
        bent.vertices[last].z += 1e-3;
        assert!(Locator::new(&bent, &g, 1e-6).is_none());
        let mut short = mesh.clone();
        short.patches.pop();
        assert!(Locator::new(&short, &g, 1e-6).is_none());
        // Counts far beyond the mesh: refused without overflow.
        for shape in [
            GridShape::Quad {
                nu: u32::MAX,
                nv: u32::MAX,
            },
            GridShape::Quad { nu: 0, nv: 5 },
            GridShape::Tri { n: u32::MAX },
        ] {
            assert!(Locator::new(&mesh, &Grid { shape, ..g }, 1e-6).is_none());
        }
    }
}
