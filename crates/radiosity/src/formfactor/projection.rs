//! The z-buffer projection shared by the hemicube and the cubic tetrahedron
//! (Szirmay-Kalos & Márton (1995), "Geometric methods", and its pseudo-code): the scene is projected
//! from a point of patch i onto the faces of a projection solid around it, an item buffer records
//! the nearest patch in each pixel, and each pixel adds its precomputed delta form factor to the
//! patch it shows.
//!
//! A face is a grid of pixels on the plane at unit distance along its axis `D` in the point's
//! local frame (x, y along the patch, z along its normal n), spanned by axes `U`, `V`. A pixel
//! centred at `p = D + u·U + v·V` subtends the delta form factor
//!
//! ```text
//! ΔF = cos θ_i · cos θ_face / (π |p|²) · ΔA = (p·n) / (π |p|⁴) · ΔA
//! ```
//!
//! (eq. 6's integrand with the pixel as dA_j), and pixels below the patch's plane (p·n ≤ 0) are
//! masked. The hemicube (Cohen & Greenberg 1985) has a top face and four half side faces; the
//! cubic tetrahedron (Beran-Koehn & Pavicic 1991) has three faces of a cube whose diagonal is the
//! normal, each a right triangle. The deltas of a solid are normalised to sum to exactly 1 (their
//! raw sum differs from 1 by the midpoint rule's O(1/P²) error); [`Solid::raw_sum`] keeps it.
//!
//! Triangles are clipped against a near plane, projected, and rasterised at pixel centres with
//! edge functions; depth is compared as 1/depth, which is affine in screen space. A pixel whose
//! nearest surface shows its back transfers nothing (one-sided surfaces). This is a potential
//! source of hemicube aliasing, as rad.c says: a patch smaller than a pixel may be missed or
//! counted whole.

use super::estimator::{Estimator, Scratch};
use super::quadrature::patch_points;
use crate::geom::{orthonormal_basis, Vec3};

const EDGE_SLACK: f32 = 1e-3;

/// Item-buffer value of an empty pixel.
pub const EMPTY: u32 = u32::MAX;
/// Flag on an item-buffer value: the nearest surface shows its back.
pub const BACK: u32 = 1 << 31;

/// One face of a projection solid.
#[derive(Clone, Debug)]
pub struct Face {
    /// Axis through the face's centre (unit, local frame).
    pub d: Vec3,
    /// Screen axis u (unit, orthogonal to `d` and `v`).
    pub u: Vec3,
    /// Screen axis v.
    pub v: Vec3,
    /// Range of u covered by the pixels.
    pub u_range: (f32, f32),
    /// Range of v covered by the pixels.
    pub v_range: (f32, f32),
    /// Pixels along u.
    pub nu: usize,
    /// Pixels along v.
    pub nv: usize,
    /// Delta form factor per pixel (row-major, v-major), 0 where masked.
    pub delta: Vec<f32>,
}

impl Face {
    fn new(
        d: Vec3,
        u: Vec3,
        v: Vec3,
        u_range: (f32, f32),
        v_range: (f32, f32),
        nu: usize,
        nv: usize,
        keep: impl Fn(f32, f32) -> bool,
    ) -> Self {
        let (du, dv) = (
            (u_range.1 - u_range.0) / nu as f32,
            (v_range.1 - v_range.0) / nv as f32,
        );
        let n = Vec3::Z;
        let mut delta = vec![0.0f32; nu * nv];
        for y in 0..nv {
            for x in 0..nu {
                let (a, b) = (
                    u_range.0 + (x as f32 + 0.5) * du,
                    v_range.0 + (y as f32 + 0.5) * dv,
                );
                let p = d + u * a + v * b;
                let pn = p.dot(n) as f64;
                if pn > 0.0 && keep(a, b) {
                    let r2 = p.length_squared() as f64;
                    delta[y * nu + x] =
                        (pn / (std::f64::consts::PI * r2 * r2) * (du * dv) as f64) as f32;
                }
            }
        }
        Self {
            d,
            u,
            v,
            u_range,
            v_range,
            nu,
            nv,
            delta,
        }
    }
}

/// A projection solid: its faces with their delta form factors.
#[derive(Clone, Debug)]
pub struct Solid {
    /// The faces.
    pub faces: Vec<Face>,
    raw_sum: f64,
}

impl Solid {
    fn normalised(faces: Vec<Face>) -> Self {
        let raw_sum: f64 = faces
            .iter()
            .flat_map(|f| f.delta.iter())
            .map(|&d| d as f64)
            .sum();
        let mut faces = faces;
        for f in &mut faces {
            f.delta
                .iter_mut()
                .for_each(|d| *d = (*d as f64 / raw_sum) as f32);
        }
        Self { faces, raw_sum }
    }

    /// The hemicube of resolution P: a P × P top face and four P × P/2 half side faces.
    pub fn hemicube(p: usize) -> Self {
        let p = p.max(2);
        let half = p.div_ceil(2);
        let (x, y, z) = (Vec3::X, Vec3::Y, Vec3::Z);
        let all = |_: f32, _: f32| true;
        Self::normalised(vec![
            Face::new(z, x, y, (-1.0, 1.0), (-1.0, 1.0), p, p, all),
            Face::new(x, y, z, (-1.0, 1.0), (0.0, 1.0), p, half, all),
            Face::new(-x, y, z, (-1.0, 1.0), (0.0, 1.0), p, half, all),
            Face::new(y, x, z, (-1.0, 1.0), (0.0, 1.0), p, half, all),
            Face::new(-y, x, z, (-1.0, 1.0), (0.0, 1.0), p, half, all),
        ])
    }

    /// The cubic tetrahedron of resolution P: three faces of the cube [−2, 1]³ (eye at the
    /// origin) meeting at (1, 1, 1) on the normal; each face is the right triangle of its P × P
    /// grid above the patch's plane.
    pub fn tetrahedron(p: usize) -> Self {
        let p = p.max(2);
        let s = (2.0f32 / 3.0).sqrt();
        let c: Vec<Vec3> = (0..3)
            .map(|k| {
                let phi = k as f32 * std::f32::consts::TAU / 3.0;
                Vec3::new(s * phi.cos(), s * phi.sin(), 1.0 / 3.0f32.sqrt())
            })
            .collect();
        let faces = (0..3)
            .map(|k| {
                // On face k the other two cube coordinates a, b lie in [−2, 1] with a + b ≥ −1.
                Face::new(
                    c[k],
                    c[(k + 1) % 3],
                    c[(k + 2) % 3],
                    (-2.0, 1.0),
                    (-2.0, 1.0),
                    p,
                    p,
                    |a, b| a + b >= -1.0,
                )
            })
            .collect();
        Self::normalised(faces)
    }

    /// Sum of the deltas before normalisation (1 minus the discretisation error).
    pub fn raw_sum(&self) -> f64 {
        self.raw_sum
    }

    /// Total number of pixels.
    pub fn pixels(&self) -> usize {
        self.faces.iter().map(|f| f.nu * f.nv).sum()
    }
}

/// Item and depth buffers for one solid, reused for every sample point.
#[derive(Clone, Debug, Default)]
pub struct Buffers {
    /// Per face: nearest item per pixel.
    pub item: Vec<Vec<u32>>,
    /// Per face: 1/depth of the nearest item per pixel (0 = empty).
    pub inv_depth: Vec<Vec<f32>>,
    clipped: Vec<(Vec3, f32)>,
    scratch: Vec<(Vec3, f32)>,
    projected: Vec<(Vec3, f32)>,
}

impl Buffers {
    /// Buffers sized for `solid`, cleared.
    pub fn clear(&mut self, solid: &Solid) {
        if self.item.len() != solid.faces.len() {
            self.item = solid
                .faces
                .iter()
                .map(|f| vec![EMPTY; f.nu * f.nv])
                .collect();
            self.inv_depth = solid.faces.iter().map(|f| vec![0.0; f.nu * f.nv]).collect();
        } else {
            for k in 0..self.item.len() {
                self.item[k].fill(EMPTY);
                self.inv_depth[k].fill(0.0);
            }
        }
    }
}

/// Rasterise the triangle `tri` (local frame) carrying item `id` into every face of `solid`.
pub fn rasterise(solid: &Solid, buffers: &mut Buffers, tri: &[Vec3; 3], id: u32, near: f32) {
    for (k, face) in solid.faces.iter().enumerate() {
        let depth = [tri[0].dot(face.d), tri[1].dot(face.d), tri[2].dot(face.d)];
        if depth.iter().all(|&d| d <= near) {
            continue;
        }
        // Clip against depth ≥ near and against the face's frustum, widened by a pixel (a guard
        // band), so that projected coordinates stay near the face and keep f32 precision.
        let (du, dv) = (
            (face.u_range.1 - face.u_range.0) / face.nu as f32,
            (face.v_range.1 - face.v_range.0) / face.nv as f32,
        );
        let (u0, u1) = (face.u_range.0 - du, face.u_range.1 + du);
        let (v0, v1) = (face.v_range.0 - dv, face.v_range.1 + dv);
        let clipped = &mut buffers.clipped;
        clipped.clear();
        clipped.extend(tri.iter().zip(depth).map(|(q, d)| (*q, d)));
        let planes: [&dyn Fn(Vec3, f32) -> f32; 5] = [
            &|_, d| d - near,
            &|q, d| q.dot(face.u) - u0 * d,
            &|q, d| u1 * d - q.dot(face.u),
            &|q, d| q.dot(face.v) - v0 * d,
            &|q, d| v1 * d - q.dot(face.v),
        ];
        for plane in planes {
            let input = std::mem::take(clipped);
            let scratch = &mut buffers.scratch;
            scratch.clear();
            let n = input.len();
            for e in 0..n {
                let (a, b) = (input[e], input[(e + 1) % n]);
                let (sa, sb) = (plane(a.0, a.1), plane(b.0, b.1));
                if sa >= 0.0 {
                    scratch.push(a);
                }
                if (sa >= 0.0) != (sb >= 0.0) {
                    let t = sa / (sa - sb);
                    scratch.push((a.0 + (b.0 - a.0) * t, a.1 + (b.1 - a.1) * t));
                }
            }
            *clipped = input;
            std::mem::swap(clipped, scratch);
            if clipped.len() < 3 {
                break;
            }
        }
        let clipped = &buffers.clipped;
        if clipped.len() < 3 {
            continue;
        }
        // Project to pixel coordinates, with 1/depth.
        let (su, sv) = (
            face.nu as f32 / (face.u_range.1 - face.u_range.0),
            face.nv as f32 / (face.v_range.1 - face.v_range.0),
        );
        let proj = &mut buffers.projected;
        proj.clear();
        let (mut x0, mut x1, mut y0, mut y1) = (
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::INFINITY,
            f32::NEG_INFINITY,
        );
        for &(q, d) in clipped.iter() {
            let w = 1.0 / d;
            let px = (q.dot(face.u) * w - face.u_range.0) * su;
            let py = (q.dot(face.v) * w - face.v_range.0) * sv;
            x0 = x0.min(px);
            x1 = x1.max(px);
            y0 = y0.min(py);
            y1 = y1.max(py);
            proj.push((Vec3::new(px, py, 0.0), w));
        }
        if x1 < 0.0 || y1 < 0.0 || x0 > face.nu as f32 || y0 > face.nv as f32 {
            continue;
        }
        let (items, depths) = (&mut buffers.item[k], &mut buffers.inv_depth[k]);
        // Fan of the convex clipped polygon.
        for t in 1..proj.len() - 1 {
            raster_triangle(face, items, depths, proj[0], proj[t], proj[t + 1], id);
        }
    }
}

#[inline]
fn raster_triangle(
    face: &Face,
    items: &mut [u32],
    depths: &mut [f32],
    a: (Vec3, f32),
    b: (Vec3, f32),
    c: (Vec3, f32),
    id: u32,
) {
    let (pa, pb, pc) = (a.0, b.0, c.0);
    let area = (pb.x - pa.x) * (pc.y - pa.y) - (pb.y - pa.y) * (pc.x - pa.x);
    if area == 0.0 || !area.is_finite() {
        return;
    }
    let inv_area = 1.0 / area;
    // Slack per edge, as edge-function values: EDGE_SLACK pixels times the edge's length, with
    // the sign of the area so that the test reads "inside or within the slack".
    let slack = |p: Vec3, q: Vec3| -EDGE_SLACK * (q - p).length() * area.signum();
    let xs = (pa.x.min(pb.x).min(pc.x).floor().max(0.0)) as usize;
    let xe = (pa.x.max(pb.x).max(pc.x).ceil().min(face.nu as f32)) as usize;
    let ys = (pa.y.min(pb.y).min(pc.y).floor().max(0.0)) as usize;
    let ye = (pa.y.max(pb.y).max(pc.y).ceil().min(face.nv as f32)) as usize;
    let (s0, s1, s2) = (slack(pb, pc), slack(pc, pa), slack(pa, pb));
    for y in ys..ye {
        let py = y as f32 + 0.5;
        for x in xs..xe {
            let px = x as f32 + 0.5;
            // Edge functions (twice the signed areas of the sub-triangles), then barycentric weights.
            let e0 = (pb.x - px) * (pc.y - py) - (pb.y - py) * (pc.x - px);
            let e1 = (pc.x - px) * (pa.y - py) - (pc.y - py) * (pa.x - px);
            let e2 = (pa.x - px) * (pb.y - py) - (pa.y - py) * (pb.x - px);
            // A pixel centre within EDGE_SLACK pixels of an edge counts as inside, so that centres
            // on a shared edge are not lost to rounding by both triangles (a pixel covered twice
            // is settled by the depth test).
            if (e0 - s0) * area.signum() < 0.0
                || (e1 - s1) * area.signum() < 0.0
                || (e2 - s2) * area.signum() < 0.0
            {
                continue;
            }
            let (w0, w1) = (e0 * inv_area, e1 * inv_area);
            let w2 = 1.0 - w0 - w1;
            let w = w0 * a.1 + w1 * b.1 + w2 * c.1;
            let k = y * face.nu + x;
            // Nearer wins; on a tie (a pixel on the edge where two faces meet) the front side
            // wins, as at a convex edge the front-facing surface is the visible one.
            let tie = (w - depths[k]).abs() <= 1e-5 * w;
            if (w > depths[k] && !tie)
                || (tie && id & BACK == 0 && items[k] & BACK != 0)
                || depths[k] == 0.0
            {
                depths[k] = w;
                items[k] = id;
            }
        }
    }
}

/// Row `i` through the projection solid `solid`: at each quadrature point of patch i every
/// other patch's triangles are projected onto the solid's faces, and each pixel adds its delta
/// form factor to the patch it shows (if it shows its front). The shared row algorithm of the
/// hemicube and the cubic tetrahedron.
pub(super) fn row(est: &Estimator, solid: &Solid, i: usize, scratch: &mut Scratch) {
    let mut points = std::mem::take(&mut scratch.points);
    patch_points(est.mesh, i, est.params.samples, &mut points);
    let normal = est.mesh.patches[i].normal;
    let (t, b) = orthonormal_basis(normal);
    for &(o, weight) in &points {
        scratch.buffers.clear(solid);
        let local = |p: Vec3| {
            let d = p - o;
            Vec3::new(d.dot(t), d.dot(b), d.dot(normal))
        };
        for (j, pj) in est.mesh.patches.iter().enumerate() {
            if j == i {
                continue;
            }
            let front = pj.normal.dot(o - pj.centre) > 0.0;
            let id = j as u32 | if front { 0 } else { BACK };
            for tri in pj.triangles() {
                let q = tri.map(|k| local(est.mesh.vertices[k as usize]));
                if q.iter().all(|p| p.z <= 0.0) {
                    continue;
                }
                rasterise(solid, &mut scratch.buffers, &q, id, est.near);
            }
        }
        for (k, face) in solid.faces.iter().enumerate() {
            for px in 0..face.delta.len() {
                let item = scratch.buffers.item[k][px];
                if item != EMPTY && item & BACK == 0 {
                    scratch.add(item, weight * face.delta[px] as f64);
                }
            }
        }
    }
    scratch.points = points;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn deltas_sum_to_one_and_raw_sums_converge() {
        for p in [16usize, 64, 256] {
            for (name, s) in [
                ("hemicube", Solid::hemicube(p)),
                ("tetrahedron", Solid::tetrahedron(p)),
            ] {
                let sum: f64 = s
                    .faces
                    .iter()
                    .flat_map(|f| f.delta.iter())
                    .map(|&d| d as f64)
                    .sum();
                assert!(
                    (sum - 1.0).abs() < 1e-5,
                    "{name} P={p}: normalised sum {sum}"
                );
                // Midpoint rule: the raw sum approaches 1 as O(1/P²).
                let err = (s.raw_sum() - 1.0).abs();
                assert!(
                    err < 2.0 / (p * p) as f64 + 2e-6,
                    "{name} P={p}: raw sum {}",
                    s.raw_sum()
                );
            }
        }
    }
}
