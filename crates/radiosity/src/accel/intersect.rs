//! A ray prepared for the queries and its two tests: the slab test of a wide node's eight
//! child boxes (near and far planes chosen once per ray by the direction's signs, each
//! distance one fused multiply-add where AVX2 and FMA are there), and Möller–Trumbore on a
//! leaf's block of four triangles, with the masks of the lanes hit.

use super::node::{TriBlock, WideNode, WIDTH};
#[cfg(target_arch = "x86_64")]
use super::simd::avx;
use crate::geom::{Ray, Vec3};
use glam::Vec4;

/// Largest inverse direction component used by the box test (directions' components below
/// its inverse are rounded up to it): the box test's products of coordinates and inverse
/// directions stay finite for coordinates up to 10²⁰.
const INV_MAX: f32 = 1e18;

/// A ray prepared for the queries: broadcast to four SIMD lanes for the triangle blocks, and
/// its origin and safe inverse direction for the node boxes.
pub(super) struct Ray4 {
    o: [Vec4; 3],
    d: [Vec4; 3],
    origin: [f32; 3],
    pub(super) inv: [f32; 3],
    /// Per axis, `origin · inv` plus a few of its ulps: subtracted from `plane · inv` (one
    /// fused multiply-add, in [`avx::enter`]) it gives the distance to a near plane rounded
    /// down.
    #[cfg(target_arch = "x86_64")]
    pub(super) o_near: [f32; 3],
    /// `origin · inv` minus a few of its ulps, for the far planes (rounded up).
    #[cfg(target_arch = "x86_64")]
    pub(super) o_far: [f32; 3],
    /// Per axis, the plane of a child's box the ray enters by (the lower one where the
    /// direction is positive) and the one it leaves by: indices into [`WideNode::planes`].
    pub(super) near: [usize; 3],
    /// See `near`.
    pub(super) far: [usize; 3],
}

/// `max` and `min` as one instruction each (`maxps`/`minps`), without `f32::max`'s NaN
/// handling: no NaN arises in the box test (see [`Ray4::new`]).
#[inline(always)]
fn fmax(a: f32, b: f32) -> f32 {
    if a > b {
        a
    } else {
        b
    }
}

/// See [`fmax`].
#[inline(always)]
fn fmin(a: f32, b: f32) -> f32 {
    if a < b {
        a
    } else {
        b
    }
}

impl Ray4 {
    #[inline(always)]
    pub(super) fn new(ray: &Ray) -> Self {
        let (o, d) = (ray.origin, ray.direction);
        // 1/d with components too close to zero replaced by ±INV_MAX: (box − o)·inv then
        // never evaluates 0·∞ = NaN for a ray that lies in a box's face plane, and o·inv
        // stays finite.
        let safe_inv = |c: f32| {
            if c.abs() > 1.0 / INV_MAX {
                1.0 / c
            } else {
                INV_MAX.copysign(c)
            }
        };
        let s = |v: Vec3| [Vec4::splat(v.x), Vec4::splat(v.y), Vec4::splat(v.z)];
        let inv = [safe_inv(d.x), safe_inv(d.y), safe_inv(d.z)];
        let near = std::array::from_fn(|a| a + 3 * inv[a].is_sign_negative() as usize);
        // The fused box test computes `plane·inv − o·inv` with one rounding after that of
        // `o·inv`, whose error (an ulp of `o·inv`: large where the origin lies far from the
        // scene's origin, unlike the error of `(plane − o)·inv`) is taken up by moving near
        // planes four ulps closer and far ones four ulps farther: the test stays
        // conservative.
        #[cfg(target_arch = "x86_64")]
        let (o_near, o_far) = {
            let o_inv = [0, 1, 2].map(|a| o[a] * inv[a]);
            let pad = o_inv.map(|x| x.abs() * (4.0 * f32::EPSILON));
            (
                [0, 1, 2].map(|a| o_inv[a] + pad[a]),
                [0, 1, 2].map(|a| o_inv[a] - pad[a]),
            )
        };
        Self {
            o: s(o),
            d: s(d),
            origin: o.to_array(),
            inv,
            #[cfg(target_arch = "x86_64")]
            o_near,
            #[cfg(target_arch = "x86_64")]
            o_far,
            near,
            far: near.map(|k| (k + 3) % 6),
        }
    }

    /// Möller–Trumbore on a block's four triangles: `(t, u, v, det)` per lane (NaN lanes for
    /// det = 0, which fail every comparison).
    #[inline(always)]
    pub(super) fn intersect(&self, b: &TriBlock) -> (Vec4, Vec4, Vec4, Vec4) {
        let [dx, dy, dz] = self.d;
        let px = dy * b.e2[2] - dz * b.e2[1];
        let py = dz * b.e2[0] - dx * b.e2[2];
        let pz = dx * b.e2[1] - dy * b.e2[0];
        let det = b.e1[0] * px + b.e1[1] * py + b.e1[2] * pz;
        let inv_det = Vec4::ONE / det;
        let sx = self.o[0] - b.v0[0];
        let sy = self.o[1] - b.v0[1];
        let sz = self.o[2] - b.v0[2];
        let u = (sx * px + sy * py + sz * pz) * inv_det;
        let qx = sy * b.e1[2] - sz * b.e1[1];
        let qy = sz * b.e1[0] - sx * b.e1[2];
        let qz = sx * b.e1[1] - sy * b.e1[0];
        let v = (dx * qx + dy * qy + dz * qz) * inv_det;
        let t = (b.e2[0] * qx + b.e2[1] * qy + b.e2[2] * qz) * inv_det;
        (t, u, v, det)
    }

    /// Entry distances into a node's child boxes, and the mask of the children the ray
    /// meets with `0 ≤ t ≤ t_max`. With `AVX`, in AVX2 and FMA intrinsics
    /// ([`avx::enter`]): only where the CPU has them.
    #[inline(always)]
    pub(super) fn enter<const AVX: bool>(&self, n: &WideNode, t_max: f32) -> ([f32; WIDTH], u32) {
        #[cfg(target_arch = "x86_64")]
        if AVX {
            return avx::enter(self, n, fmin(t_max, f32::MAX));
        }
        self.enter_lanes(n, t_max)
    }

    /// [`Ray4::enter`] lane by lane, for the compiler to vectorise (CPUs without AVX2 and
    /// FMA): the two-step `(plane − o)·inv`.
    #[inline(always)]
    fn enter_lanes(&self, n: &WideNode, t_max: f32) -> ([f32; WIDTH], u32) {
        // Finite, so that no ray enters an empty lane's box, which lies at infinity.
        let t_max = fmin(t_max, f32::MAX);
        let [ox, oy, oz] = self.origin;
        let [ix, iy, iz] = self.inv;
        let mut near = [0.0f32; WIDTH];
        let mut far = [0.0f32; WIDTH];
        let (pn, pf) = (
            self.near.map(|k| &n.planes[k]),
            self.far.map(|k| &n.planes[k]),
        );
        for l in 0..WIDTH {
            // The slabs' near and far planes, chosen by the direction's signs: no min/max
            // between each slab's two distances. An empty lane's box (+∞ planes) gives a
            // near distance of +∞ or a far one of −∞ on every axis.
            let nx = (pn[0][l] - ox) * ix;
            let fx = (pf[0][l] - ox) * ix;
            let ny = (pn[1][l] - oy) * iy;
            let fy = (pf[1][l] - oy) * iy;
            let nz = (pn[2][l] - oz) * iz;
            let fz = (pf[2][l] - oz) * iz;
            // The clamps take the box's value second, which `fmax`/`fmin` return when it is
            // NaN (a ray with a NaN coordinate): then nothing is entered, not even an empty
            // lane.
            near[l] = fmax(fmax(0.0, nz), fmax(nx, ny));
            far[l] = fmin(fmin(t_max, fz), fmin(fx, fy));
        }
        // The comparison four lanes at a time: `cmpps` and `movmskps`.
        let mut mask = 0u32;
        for h in 0..WIDTH / 4 {
            let lane4 =
                |a: &[f32; WIDTH]| Vec4::new(a[4 * h], a[4 * h + 1], a[4 * h + 2], a[4 * h + 3]);
            mask |= lane4(&near).cmple(lane4(&far)).bitmask() << (4 * h);
        }
        (near, mask)
    }
}

/// The lanes whose triangle the ray crosses (inside the edges, up to the block's slack)
/// with `0 < t < t_below`.
#[inline(always)]
pub(super) fn lanes_hit(b: &TriBlock, t: Vec4, u: Vec4, v: Vec4, t_below: f32) -> u32 {
    lanes_within(t, u, v, b.slack0 + b.slack1 * t, t_below)
}

/// The lanes with `(u, v)` inside the triangle widened by `slack` and `0 < t < t_below`.
#[inline(always)]
fn lanes_within(t: Vec4, u: Vec4, v: Vec4, slack: Vec4, t_below: f32) -> u32 {
    (u.cmpge(-slack)
        & v.cmpge(-slack)
        & (u + v).cmple(Vec4::ONE + slack)
        & t.cmpgt(Vec4::ZERO)
        & t.cmplt(Vec4::splat(t_below)))
    .bitmask()
}

/// [`lanes_hit`] for closest-hit queries: the slack widens front sides only, back sides are
/// met strictly inside their edges. The slack closes the `f32` cracks between neighbouring
/// triangles, but at a convex edge it can let a ray that passes just outside the edge meet
/// the back of one face without the front of the other (whose slack, proportional to its own
/// size, may be smaller), and the tie rule that gives such an edge to the front side then
/// has no front to give it to: a ray lost at an object's silhouette. A back side met strictly
/// is always behind a front side met first or at the same distance on a closed object.
#[inline(always)]
pub(super) fn lanes_hit_front_slack(
    b: &TriBlock,
    t: Vec4,
    u: Vec4,
    v: Vec4,
    det: Vec4,
    t_below: f32,
) -> u32 {
    let slack = Vec4::select(det.cmpgt(Vec4::ZERO), b.slack0 + b.slack1 * t, Vec4::ZERO);
    lanes_within(t, u, v, slack, t_below)
}
