//! Ray casting over the patches: a bounding-volume hierarchy of the patches' triangles, where
//! a piece of the input that the mesh cut into a regular grid of patches is one or two
//! triangles, however many patches it holds, and the patch a ray meets on it is found from
//! where it met it ([`Locator`], [`Bvh::build`]). The hierarchy is then the size of the
//! input scene, not of its mesh: the one-sided hospital cut into 996,217 patches makes a tree
//! of 42,324 triangles and 2.8 MB instead of 1,189,437 and 75 MB, which the cache holds.
//!
//! Build: a binary tree by the binned surface-area heuristic (32 bins per axis, Wald 2007 "On
//! fast Construction of SAH-based Bounding Volume Hierarchies"; the cost counts blocks of
//! [`MAX_LEAF`] triangles, which one SIMD test takes), leaves of at most [`MAX_LEAF`]
//! triangles. Where a node's best split by objects leaves its halves overlapping (by more
//! than 10⁻⁴ of the scene's surface area), a spatial split is tried too (Stich, Friedrich &
//! Dietrich 2009, "Spatial Splits in Bounding Volume Hierarchies"): a plane along the node's
//! longest axis that cuts the triangles it crosses, each side keeping the box of its part,
//! chosen when its SAH cost is lower, within a budget of 30 % more triangle references; a
//! triangle may then sit in several leaves. The binary tree is then collapsed into an 8-wide
//! tree by the SAH-optimal dynamic programme of Ylitie, Karras & Laine 2017 ("Efficient
//! Incoherent Ray Traversal on GPUs Through Compressed Wide BVHs", §3.1). A node holds its
//! eight children's boxes in structure-of-arrays form, so one AVX pass tests all eight (the layout of Embree's BVH8): each slab's near and far
//! planes are chosen once per ray by the direction's signs, and each distance is one fused
//! multiply-add. Traversal: iterative; every child met is prefetched into the cache at once
//! (the latency of a tree larger than the cache then overlaps with the work on its
//! siblings); the children met are ordered nearest first by a branch-free sorting network
//! (with fast paths for one and two), pushed without branches, and skipped when they begin
//! beyond the closest hit; the stack is a small fixed array that spills to the heap only for
//! a pathologically deep tree. Triangle test: Möller–Trumbore on blocks of four, edges
//! precomputed, which also tells which side was hit; each triangle's edges are widened by a
//! few epsilons of the distance along the ray over its smallest height, which closes `f32`
//! cracks between neighbours without fattening triangles near the ray's origin (front sides
//! only, in closest-hit queries: `lanes_hit_front_slack`).
//!
//! Ties (two faces at the same distance, within a relative 10⁻⁶ or the ray offset): the front side
//! wins, and between faces of the same side the lower triangle id (patch order, the grids met
//! whole after the patches met one by one), so coincident copies of a surface resolve the same
//! way whichever side a ray comes from and whatever order the traversal meets them in.
//!
//! Portable builds (without `-C target-cpu=native`, which `.cargo/config.toml` sets) compile
//! the queries a second time for AVX2, FMA and BMI and choose that copy at run time where the
//! CPU has them (module `dispatch`). With `unsafe` also: the box test in AVX2 intrinsics
//! (module `avx`, run by builds that assume AVX2 and FMA and by that run-time copy), the
//! prefetch hint (`hint`) and the traversal stack's uninitialised array (`Stack`).
//!
//! Self-intersection: callers start rays a small distance off the surface (see
//! [`Bvh::ray_offset`]) along its normal; since patches are planar, a piece is met whole only
//! if it is planar to within a quarter of that offset, and rays leave into the front
//! hemisphere, a ray cannot hit its own patch or the rest of its piece.

use crate::geom::{Aabb, Ray, Vec3};
use crate::mesh::{Locator, Mesh};
use glam::Vec4;
use rayon::prelude::*;
use std::mem::MaybeUninit;

/// [`Bvh::ray_offset`] of a scene within `bounds`.
fn offset_of(bounds: &Aabb) -> f32 {
    let m = bounds.min.abs().max(bounds.max.abs()).max_element();
    let d = bounds.diagonal();
    (m * 4e-6).max(d * 1e-6).max(f32::MIN_POSITIVE)
}

/// Most triangles in a leaf.
pub const MAX_LEAF: usize = 4;
const BINS: usize = 32;
/// The child reference of an empty lane of a wide node: block 0, which holds no triangle,
/// so a lane entered by mistake (a box test gone NaN on absurd coordinates) costs a wasted
/// test, never a wrong index.
const EMPTY_LANE: u32 = LEAF;
/// The id of an unused lane of a [`TriBlock`].
const NO_TRIANGLE: u32 = u32::MAX;
/// Largest inverse direction component used by the box test (directions' components below
/// its inverse are rounded up to it): the box test's products of coordinates and inverse
/// directions stay finite for coordinates up to 10²⁰.
const INV_MAX: f32 = 1e18;
/// Least barycentric slack that keeps shared edges watertight under rounding (see
/// [`TriBlock::slack0`] for the slack each triangle gets).
const EDGE_EPS: f32 = 1e-6;
/// Machine epsilons of the distance that a triangle's edges are widened by (see
/// [`TriBlock::slack0`]).
const SLACK_ULPS: f32 = 4.0;
/// Relative distance within which two hits count as one (a ray through a shared edge).
const TIE: f32 = 1e-6;

#[derive(Clone, Copy, Debug)]
#[repr(C)]
struct Node {
    min: [f32; 3],
    /// Interior: index of the left child (right is `first + 1`). Leaf: first triangle.
    first: u32,
    max: [f32; 3],
    /// Number of triangles for a leaf, 0 for an interior node.
    count: u32,
}

/// Children per node of the wide tree.
pub const WIDTH: usize = 8;

/// A wide node: the boxes of up to [`WIDTH`] children in structure-of-arrays form, one SIMD
/// lane each. An empty lane's box is +∞ in every coordinate, which no ray enters.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
struct WideNode {
    /// The children's bounding planes: lower x, y, z, then upper x, y, z (`planes[a]` and
    /// `planes[3 + a]` bound axis `a`), each for every child.
    planes: [[f32; WIDTH]; 6],
    /// Child references: a node index, or [`LEAF`] | block index; [`EMPTY_LANE`] for none.
    child: [u32; WIDTH],
}

impl WideNode {
    const EMPTY: WideNode = WideNode {
        planes: [[f32::INFINITY; WIDTH]; 6],
        child: [EMPTY_LANE; WIDTH],
    };
}

/// Whether the build assumes AVX2 and FMA, so that the queries test boxes with
/// [`avx::enter`] without asking the CPU.
const NATIVE_AVX: bool = cfg!(all(
    target_arch = "x86_64",
    target_feature = "avx2",
    target_feature = "fma"
));

/// Marks a child reference as a leaf.
const LEAF: u32 = 1 << 31;

/// The sorting network for eight keys: 19 compare-exchanges, the fewest possible (Knuth,
/// TAOCP vol. 3, §5.3.4).
const SORT8: [(usize, usize); 19] = [
    (0, 2),
    (1, 3),
    (4, 6),
    (5, 7),
    (0, 4),
    (1, 5),
    (2, 6),
    (3, 7),
    (0, 1),
    (2, 3),
    (4, 5),
    (6, 7),
    (2, 4),
    (3, 5),
    (1, 4),
    (3, 6),
    (1, 2),
    (3, 4),
    (5, 6),
];

/// Entries of a traversal stack's fixed part (see [`Stack`]).
const STACK: usize = 56;

/// Deepest level of the binary tree, which bounds the builder's recursion.
const MAX_DEPTH: usize = 64;

/// From this level of the binary tree down, splits halve the triangles by count: fewer than
/// 2³¹ triangles then reach leaves of [`MAX_LEAF`] within [`MAX_DEPTH`] levels.
const HALVING_DEPTH: usize = MAX_DEPTH - 31;

/// A traversal stack: a fixed array on the machine stack, small enough that setting it up
/// costs little per ray, whose bottom half moves to the heap when a deep tree would overflow
/// it; so nothing is allocated in the common case and no tree is too deep.
///
/// Aligned to a cache line. Unaligned, its speed depended on where the thread's machine stack
/// happened to put it: with the command on a worker of the pool, two threads on the Cornell
/// box (9,992 patches) cast 9.6–9.8 M rays/s with 2 MiB worker stacks, 11.1–11.7 with 64 MiB
/// ones and 11.6–12.2 from the main thread; aligned, 11.7–12.4 in every case (hospital, two
/// threads: 4.8–5.0 → 5.4).
///
/// The array is left uninitialised: zeroing its 448 bytes for every ray took fourteen stores
/// (Cornell box, 1,000 patches, one thread: 7.37 → 7.57 M rays/s without them, medians of
/// five back-to-back pairs; within the noise on larger trees). Every slot below `sp` has been
/// written since the last [`Stack::clear`]: pushes write at `sp` before counting, a spill
/// moves written slots down, and a refill writes the slots it counts.
#[repr(align(64))]
struct Stack<T: Copy> {
    top: [MaybeUninit<T>; STACK],
    sp: usize,
    spill: Vec<T>,
}

#[allow(unsafe_code)]
impl<T: Copy> Stack<T> {
    #[inline(always)]
    fn new() -> Self {
        Stack {
            // SAFETY: an array of `MaybeUninit` needs no initialisation. (The array
            // expression `[MaybeUninit::uninit(); STACK]` was compiled to zeroing stores.)
            top: unsafe { MaybeUninit::<[MaybeUninit<T>; STACK]>::uninit().assume_init() },
            sp: 0,
            spill: Vec::new(),
        }
    }

    /// Empty it.
    #[inline(always)]
    fn clear(&mut self) {
        self.sp = 0;
        self.spill.clear();
    }

    /// Make room for [`WIDTH`] pushes.
    #[inline(always)]
    fn reserve(&mut self) {
        if self.sp + WIDTH > STACK {
            self.spill_half();
        }
    }

    #[cold]
    #[inline(never)]
    fn spill_half(&mut self) {
        // Called with `sp > STACK − WIDTH ≥ STACK / 2`: the bottom half is written.
        // SAFETY: slots below `sp` are initialised (the type's invariant).
        let bottom = self.top[..STACK / 2]
            .iter()
            .map(|v| unsafe { v.assume_init() });
        self.spill.extend(bottom);
        self.top.copy_within(STACK / 2..self.sp, 0);
        self.sp -= STACK / 2;
    }

    #[inline(always)]
    fn push(&mut self, v: T) {
        self.top[self.sp] = MaybeUninit::new(v);
        self.sp += 1;
    }

    /// Write `v` on top, but count it pushed only if `keep`: a push without a branch.
    #[inline(always)]
    fn push_if(&mut self, v: T, keep: bool) {
        self.top[self.sp] = MaybeUninit::new(v);
        self.sp += keep as usize;
    }

    #[inline(always)]
    fn pop(&mut self) -> Option<T> {
        if self.sp == 0 && !self.refill() {
            return None;
        }
        self.sp -= 1;
        // SAFETY: `sp` was above this slot, so it is initialised (the type's invariant).
        Some(unsafe { self.top[self.sp].assume_init() })
    }

    /// Bring back the top of what was spilled; false if nothing was.
    #[cold]
    #[inline(never)]
    fn refill(&mut self) -> bool {
        let k = self.spill.len().min(STACK / 2);
        let from = self.spill.len() - k;
        for (slot, &v) in self.top[..k].iter_mut().zip(&self.spill[from..]) {
            *slot = MaybeUninit::new(v);
        }
        self.spill.truncate(from);
        self.sp = k;
        k > 0
    }
}

#[derive(Clone, Copy, Debug)]
struct Tri {
    v0: Vec3,
    e1: Vec3,
    e2: Vec3,
    /// `patch << 1 | sub`, `sub` = which triangle of the patch; for a grid met whole
    /// ([`Bvh::build`]), `(patches + grid) << 1 | sub`, `sub` = which triangle of its piece.
    id: u32,
}

/// The (up to) four triangles of a leaf in structure-of-arrays form, tested in one SIMD pass.
/// Unused lanes hold a degenerate triangle (zero edges), which no ray hits. Aligned to cache
/// lines, so that one spans exactly three.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
struct TriBlock {
    v0: [Vec4; 3],
    e1: [Vec4; 3],
    e2: [Vec4; 3],
    /// Barycentric slack of each triangle at distance `t` along the ray: `slack0 + slack1·t`.
    /// Möller–Trumbore's `f32` rounding is a few machine epsilons of `|o − v0|` (at most `t`
    /// plus the triangle's longest edge) in world units, which is that over the triangle's
    /// smallest height in barycentric units. Without it, a ray through the edge two small
    /// triangles share, far from its origin, can slip between them (a crack: 3 in 2 × 10⁶
    /// form-factor rays in the 40,000-patch Cornell box); a slack that ignores the distance
    /// (a few epsilons of the largest coordinate) fattens triangles near the ray's origin
    /// beyond what rounding needs, and rays leaving a corner then graze the next wall.
    slack0: Vec4,
    /// See `slack0`.
    slack1: Vec4,
    id: [u32; 4],
}

impl TriBlock {
    /// Four unused lanes: zero edges, which no ray hits (Möller–Trumbore's determinant is 0
    /// and every comparison of its NaN results fails).
    const EMPTY: TriBlock = TriBlock {
        v0: [Vec4::ZERO; 3],
        e1: [Vec4::ZERO; 3],
        e2: [Vec4::ZERO; 3],
        slack0: Vec4::ZERO,
        slack1: Vec4::ZERO,
        id: [NO_TRIANGLE; 4],
    };
}

/// A ray-patch intersection.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Distance along the ray (in units of the ray direction's length).
    pub t: f32,
    /// The patch hit.
    pub patch: u32,
    /// Which triangle of the patch: 0 = `(v0, v1, v2)`, 1 = `(v0, v2, v3)`.
    pub sub: u8,
    /// Barycentric coordinates of the hit point in that triangle: `p = (1−u−v)·a + u·b + v·c`.
    pub u: f32,
    /// See `u`.
    pub v: f32,
    /// True when the ray hit the front (emitting, reflecting) side.
    pub front: bool,
}

/// A ray prepared for the queries: broadcast to four SIMD lanes for the triangle blocks, and
/// its origin and safe inverse direction for the node boxes.
struct Ray4 {
    o: [Vec4; 3],
    d: [Vec4; 3],
    origin: [f32; 3],
    inv: [f32; 3],
    /// Per axis, `origin · inv` plus a few of its ulps: subtracted from `plane · inv` (one
    /// fused multiply-add, in [`avx::enter`]) it gives the distance to a near plane rounded
    /// down.
    #[cfg(target_arch = "x86_64")]
    o_near: [f32; 3],
    /// `origin · inv` minus a few of its ulps, for the far planes (rounded up).
    #[cfg(target_arch = "x86_64")]
    o_far: [f32; 3],
    /// Per axis, the plane of a child's box the ray enters by (the lower one where the
    /// direction is positive) and the one it leaves by: indices into [`WideNode::planes`].
    near: [usize; 3],
    /// See `near`.
    far: [usize; 3],
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
    fn new(ray: &Ray) -> Self {
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
    fn intersect(&self, b: &TriBlock) -> (Vec4, Vec4, Vec4, Vec4) {
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
    fn enter<const AVX: bool>(&self, n: &WideNode, t_max: f32) -> ([f32; WIDTH], u32) {
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
fn lanes_hit(b: &TriBlock, t: Vec4, u: Vec4, v: Vec4, t_below: f32) -> u32 {
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
fn lanes_hit_front_slack(b: &TriBlock, t: Vec4, u: Vec4, v: Vec4, det: Vec4, t_below: f32) -> u32 {
    let slack = Vec4::select(det.cmpgt(Vec4::ZERO), b.slack0 + b.slack1 * t, Vec4::ZERO);
    lanes_within(t, u, v, slack, t_below)
}

/// Sorting networks for three and four keys: the fewest compare-exchanges (Knuth, TAOCP
/// vol. 3, §5.3.4).
const SORT3: [(usize, usize); 3] = [(0, 1), (1, 2), (0, 1)];
/// See [`SORT3`].
const SORT4: [(usize, usize); 5] = [(0, 1), (2, 3), (0, 2), (1, 3), (1, 2)];

/// The keys of the `K` children met (`mask` has exactly `K` bits), as [`sorted_keys`] makes
/// them, sorted nearest first by the network `net`. Most nodes a ray enters with more than
/// two children met have three or four (hospital, 25,051 patches: 0.74 and 0.24 per ray
/// against 0.16 with five or more); the eight-key network costs them five to six times as
/// many compare-exchanges (closest hit 2.8 → 3.05 M rays/s there, one thread).
#[inline(always)]
fn sorted_met<const K: usize>(
    dist: &[f32; WIDTH],
    mut mask: u32,
    net: &[(usize, usize)],
) -> [u32; K] {
    let mut k = [0u32; K];
    for slot in &mut k {
        let l = mask.trailing_zeros() as usize % WIDTH;
        *slot = (dist[l].to_bits() & !7) | l as u32;
        mask &= mask.wrapping_sub(1);
    }
    for &(a, b) in net {
        let (x, y) = (k[a], k[b]);
        k[a] = x.min(y);
        k[b] = x.max(y);
    }
    k
}

/// The children met (`mask`), sorted by entry distance without branches: each lane's key is
/// its distance's bits (non-negative floats order as their bits) with the lane in the three
/// low bits, `u32::MAX` for a lane missed; a sorting network of 19 compare-exchanges (Knuth,
/// TAOCP 5.3.4) orders the eight keys, nearest first, missed lanes last.
#[inline(always)]
fn sorted_keys(dist: &[f32; WIDTH], mask: u32) -> [u32; WIDTH] {
    let mut k = [0u32; WIDTH];
    for l in 0..WIDTH {
        k[l] = if mask >> l & 1 != 0 {
            (dist[l].to_bits() & !7) | l as u32
        } else {
            u32::MAX
        };
    }
    for (a, b) in SORT8 {
        let (x, y) = (k[a], k[b]);
        k[a] = x.min(y);
        k[b] = x.max(y);
    }
    k
}

/// One visit of a closest-hit traversal, shared by [`Bvh::closest_hit`] (a loop over one ray,
/// its state in locals) and [`Bvh::closest_hits`] (several rays' states, each advanced a visit
/// at a time): test the node or leaf `$cur`, then choose the next one, the nearest child met,
/// else the nearest entry on the stack still worth visiting, and go on with `$next` (which
/// continues the caller's loop or returns). Falls through when nothing is left to visit.
macro_rules! closest_visit {
    ($bvh:expr, $avx:ident, $r:expr, $tie_abs:expr, $best_t:expr, $far:expr, $best:expr,
     $bu:expr, $bv:expr, $bdet:expr, $stack:expr, $cur:expr, $next:expr) => {{
        let tie_abs = $tie_abs;
        if $cur & LEAF != 0 {
            let b = &$bvh.blocks[($cur & !LEAF) as usize];
            let (t, u, v, det) = $r.intersect(b);
            // Hits up to TIE beyond the best are kept for the tie rule below. Back sides
            // get no slack: see `lanes_hit_front_slack`.
            let mut mask = lanes_hit_front_slack(b, t, u, v, det, $far);
            if mask != 0 {
                let (ta, ua, va, da) = (t.to_array(), u.to_array(), v.to_array(), det.to_array());
                while mask != 0 {
                    let l = mask.trailing_zeros() as usize;
                    mask &= mask - 1;
                    // Closer, or a tie (a ray through the edge where two faces meet) won by the
                    // front side: at a convex edge the front-facing surface is the visible one.
                    let closer = ta[l] < $best_t * (1.0 - TIE) - tie_abs;
                    let tie = !closer && ta[l] <= $far;
                    if closer
                        || (tie && da[l] > 0.0 && ($best == u32::MAX || $bdet <= 0.0))
                        || (tie
                            && (da[l] > 0.0) == ($bdet > 0.0)
                            && (ta[l] < $best_t || (ta[l] == $best_t && b.id[l] < $best)))
                    {
                        $best_t = ta[l];
                        $far = $best_t * (1.0 + TIE) + tie_abs;
                        $best = b.id[l];
                        $bu = ua[l];
                        $bv = va[l];
                        $bdet = da[l];
                    }
                }
            }
        } else {
            let n = &$bvh.nodes[$cur as usize];
            // Boxes up to the tie distance beyond the best are entered: a tie it holds
            // (a front face meeting the back face hit so far at an edge) must be seen.
            let (dist, mask) = $r.enter::<$avx>(n, $far);
            if mask != 0 {
                // The first and last children met are asked for without a loop (the
                // same one when only one is met), the others below: a loop's exit
                // would be a branch on how many were met, which no predictor knows.
                let a = mask.trailing_zeros() as usize % WIDTH;
                let b = (31 - mask.leading_zeros()) as usize % WIDTH;
                $bvh.prefetch(n.child[a]);
                $bvh.prefetch(n.child[b]);
                if a == b {
                    $cur = n.child[a];
                    $next
                }
                $stack.reserve();
                let middle = mask & !(1 << a | 1 << b);
                if middle == 0 {
                    let (near, away) = if dist[a] <= dist[b] { (a, b) } else { (b, a) };
                    $stack.push((n.child[away], dist[away]));
                    $cur = n.child[near];
                    $next
                }
                $bvh.prefetch_met(n, middle);
            }
            let count = mask.count_ones() as usize;
            // Push the farther ones (farthest deepest); go on with the nearest.
            let entry = |key: u32| (n.child[(key & 7) as usize], f32::from_bits(key & !7));
            if count == 3 {
                let k = sorted_met::<3>(&dist, mask, &SORT3);
                $stack.push(entry(k[2]));
                $stack.push(entry(k[1]));
                $cur = n.child[(k[0] & 7) as usize];
                $next
            }
            if count == 4 {
                let k = sorted_met::<4>(&dist, mask, &SORT4);
                $stack.push(entry(k[3]));
                $stack.push(entry(k[2]));
                $stack.push(entry(k[1]));
                $cur = n.child[(k[0] & 7) as usize];
                $next
            }
            if count > 4 {
                let k = sorted_keys(&dist, mask);
                // Each write kept only when its lane was met.
                for i in (1..WIDTH).rev() {
                    $stack.push_if(entry(k[i]), count > i);
                }
                $cur = n.child[(k[0] & 7) as usize];
                $next
            }
        }
        // Pop the next node still worth visiting.
        while let Some((c, dist)) = $stack.pop() {
            if dist <= $far {
                $cur = c;
                $next
            }
        }
    }};
}

/// Rays a thread traces at once in [`Bvh::closest_hits`]: enough that one ray's visit
/// overlaps the memory wait of the others', few enough that their states stay in the L1
/// cache. Hospital, 10⁶ patches, one thread, `bench --rays` (M rays/s): on the 2-core AMD
/// EPYC of 2026-11-27, 8 in flight 6.52, 16 7.77–7.97, 32 7.92–8.03, one at a time 2.9–3.9
/// (two threads: 12.9–13.5, 16.1–16.2, 16.3); on the machine before, 4 in flight 3.2–3.6, 8
/// 4.9, 16 4.1–4.3, one at a time 2.6–2.8.
pub const IN_FLIGHT: usize = 16;

/// Bytes of hierarchy from which [`Bvh::closest_hits`] interleaves its rays. Below, one ray at
/// a time is as fast or faster: the interleaving costs about what the overlap of memory waits
/// saves while most of the tree sits in the L2 cache (2 MiB a core on the machine measured).
/// Hospital, one thread, `bench --rays`, one at a time against interleaved (M rays/s): 3 MB
/// (28,735 patches) 2.90 / 2.84, 5.4 MB 3.78 / 3.81, 8.4 MB 3.75 / 3.58, 15.7 MB 3.90 / 4.52,
/// 74 MB (10⁶ patches) 3.2 / 5.0.
const INTERLEAVE_FROM: usize = 12 << 20;

/// One ray's closest-hit traversal, advanced a visit at a time by [`Bvh::closest_step`]: the
/// state [`Bvh::closest_hit`] keeps in locals.
struct Closest {
    r: Ray4,
    t_max: f32,
    /// The closest hit so far: its distance (`t_max` while none), the reach of the queries
    /// beyond it (see [`Bvh::closest_hit_in`]), its triangle id (`u32::MAX` while none),
    /// barycentric coordinates and determinant (positive: the front side).
    best_t: f32,
    far: f32,
    best: u32,
    bu: f32,
    bv: f32,
    bdet: f32,
    /// The node or leaf to visit next.
    cur: u32,
    stack: Stack<(u32, f32)>,
}

impl Closest {
    #[inline(always)]
    fn new(ray: &Ray, t_max: f32, tie_abs: f32) -> Self {
        Closest {
            r: Ray4::new(ray),
            t_max,
            best_t: t_max,
            far: t_max * (1.0 + TIE) + tie_abs,
            best: u32::MAX,
            bu: 0.0,
            bv: 0.0,
            bdet: 0.0,
            cur: 0,
            stack: Stack::new(),
        }
    }

    /// Start over with another ray, keeping the stack's spill allocation.
    #[inline(always)]
    fn restart(&mut self, ray: &Ray, t_max: f32, tie_abs: f32) {
        self.r = Ray4::new(ray);
        self.t_max = t_max;
        self.best_t = t_max;
        self.far = t_max * (1.0 + TIE) + tie_abs;
        self.best = u32::MAX;
        self.bu = 0.0;
        self.bv = 0.0;
        self.bdet = 0.0;
        self.cur = 0;
        self.stack.clear();
    }

    /// The traversal's answer, once it is over.
    #[inline(always)]
    fn hit(&self, bvh: &Bvh) -> Option<Hit> {
        bvh.answer(
            self.best,
            self.best_t,
            self.t_max,
            self.bu,
            self.bv,
            self.bdet,
        )
    }
}

impl Bvh {
    /// The hit a traversal that ended with this state found.
    #[inline(always)]
    fn answer(&self, best: u32, best_t: f32, t_max: f32, u: f32, v: f32, det: f32) -> Option<Hit> {
        (best != u32::MAX && best_t < t_max).then(|| self.hit_of(best, best_t, u, v, det))
    }
}

/// The hierarchy over all patches of a mesh.
#[derive(Clone, Debug)]
pub struct Bvh {
    nodes: Vec<WideNode>,
    /// One block per leaf.
    blocks: Vec<TriBlock>,
    /// Every triangle once, in the mesh's order (kept for validation and statistics).
    tris: Vec<Tri>,
    /// Triangle references in the leaves: the triangles, and the copies spatial splits made.
    references: usize,
    bounds: Aabb,
    /// Absolute distance within which two hits also count as one: [`Bvh::ray_offset`]. Two
    /// coplanar triangles (a two-sided surface's back-to-back copies, meshed differently) give
    /// distances that differ by the rounding of the coordinates, amplified at grazing angles, far
    /// beyond the relative [`TIE`]; surfaces closer than the ray offset are not told apart
    /// anyway.
    tie: f32,
    /// Patches of the mesh: triangle ids `k << 1 | sub` with `k` below it are a patch's,
    /// from it on a grid's.
    patches: u32,
    /// The grids met whole, which find the patch a ray met: grid `k` has the ids
    /// `(patches + k) << 1 | sub`.
    grids: Vec<Locator>,
}

/// Statistics of a built hierarchy.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BvhInfo {
    /// Number of nodes.
    pub nodes: usize,
    /// Number of triangles.
    pub triangles: usize,
    /// Triangle references in the leaves: the triangles and the extra copies of those that
    /// spatial splits cut.
    pub references: usize,
    /// Depth of the deepest leaf.
    pub depth: usize,
    /// Number of leaves (blocks of at most [`MAX_LEAF`] triangles).
    pub leaves: usize,
    /// Bytes held.
    pub bytes: usize,
    /// Of which the nodes'.
    pub node_bytes: usize,
    /// The surface-area-heuristic cost of visiting the nodes: the sum of their boxes' areas
    /// over the root's (the expected number of nodes a random line through the scene's box
    /// visits), as Embree's `verbose=2` statistics count it.
    pub sah_nodes: f64,
    /// The same for the leaves (one block of triangles each).
    pub sah_leaves: f64,
    /// Pieces of the mesh met as a whole (their one or two triangles in the hierarchy in place
    /// of their patches'), the patch hit found from where ([`Bvh::build`]).
    pub whole_pieces: usize,
    /// Patches in those pieces.
    pub patches_in_whole_pieces: usize,
}

#[derive(Clone, Copy)]
struct Prim {
    bounds: Aabb,
    centroid: Vec3,
    tri: Tri,
}

impl Bvh {
    /// Build over the triangles of `mesh`'s patches, except that a piece cut into a regular
    /// grid of two or more patches ([`Mesh::grids`]) is put in as its own one or two triangles,
    /// and a ray that meets it is told the patch at the point met ([`Locator`]): the same
    /// answers (up to the rounding at the patches' edges) from a hierarchy whose size does not
    /// grow with the patch count. On the one-sided hospital (22,271 polygons) cut into 996,217
    /// patches, the tree shrinks from 1,189,437 triangles and 75 MB to 42,324 and 2.8 MB, and
    /// each ray visits the nodes of the coarse scene only: `bench --rays`, two threads, 19.6 M
    /// rays/s against 16.9 for the tree over every patch (sixteen rays in flight) and 7.7 for
    /// Embree's stream over the same patches. A grid is met whole only if the mesh still holds what it says (its patches'
    /// vertices numbered as the grid numbers them and lying where its formula puts them, to a
    /// quarter of [`Bvh::ray_offset`]) and its piece is planar and convex to that tolerance,
    /// so that a ray leaving one of its patches a ray offset off cannot meet the piece
    /// itself; else its patches go in one by one.
    pub fn build(mesh: &Mesh) -> Bvh {
        let n = mesh.len();
        let tol = 0.25 * offset_of(&bounds_of(&mesh.vertices, |v| Aabb::from_points(&[*v])));
        // Grids in patch order, disjoint, and few enough for their ids.
        let usable = mesh
            .grids
            .windows(2)
            .all(|w| w[0].first_patch as usize + w[0].patches() <= w[1].first_patch as usize)
            && n + mesh.grids.len() < (1 << 31);
        let found: Vec<_> = if usable {
            mesh.grids
                .par_iter()
                .map(|g| {
                    (g.patches() >= 2)
                        .then(|| Locator::new(mesh, g, tol))
                        .flatten()
                })
                .collect()
        } else {
            Vec::new()
        };
        let mut covered = vec![false; n];
        let mut grids = Vec::new();
        let mut pieces = Vec::new();
        for (g, f) in mesh.grids.iter().zip(found) {
            if let Some((locator, tris, count)) = f {
                let first = g.first_patch as usize;
                covered[first..first + g.patches()].fill(true);
                pieces.push((((n + grids.len()) as u32) << 1, tris, count));
                grids.push(locator);
            }
        }
        let prim = |a: Vec3, b: Vec3, c: Vec3, id: u32| {
            let bounds = Aabb::from_points(&[a, b, c]);
            Prim {
                bounds,
                centroid: bounds.centre(),
                tri: Tri {
                    v0: a,
                    e1: b - a,
                    e2: c - a,
                    id,
                },
            }
        };
        let mut prims: Vec<Prim> = mesh
            .patches
            .par_iter()
            .enumerate()
            .filter(|(k, _)| !covered[*k])
            .flat_map_iter(|(k, p)| {
                p.triangles().enumerate().map(move |(sub, t)| {
                    let [a, b, c] = t.map(|i| mesh.vertices[i as usize]);
                    prim(a, b, c, (k as u32) << 1 | sub as u32)
                })
            })
            .collect();
        for (id, tris, count) in pieces {
            for (sub, [a, b, c]) in tris.into_iter().take(count).enumerate() {
                prims.push(prim(a, b, c, id | sub as u32));
            }
        }
        let mut bvh = Self::from_prims(prims);
        bvh.patches = n as u32;
        bvh.grids = grids;
        bvh
    }

    fn from_prims(prims: Vec<Prim>) -> Bvh {
        let n = prims.len();
        let bounds = bounds_of(&prims, |p| p.bounds);
        let unique: Vec<Tri> = prims.iter().map(|p| p.tri).collect();
        // The binary tree, subtrees built in parallel (each owns its references, and every
        // choice depends only on them and on its share of the split budget, so the tree is
        // the same for any number of threads), then laid out depth first, left first, each
        // node's two children side by side.
        let split = Splits {
            min_overlap: SPLIT_OVERLAP * bounds.surface_area(),
        };
        let budget = (n as f64 * SPLIT_BUDGET) as usize;
        let mut prims = prims;
        let tree = build_tree(&mut prims, 0, budget, &split);
        drop(prims);
        let mut nodes = Vec::with_capacity((2 * n / MAX_LEAF.max(1)).max(1) * 2);
        nodes.push(Node {
            min: [0.0; 3],
            first: 0,
            max: [0.0; 3],
            count: 0,
        });
        let mut tris = Vec::with_capacity(n + n / 4);
        lay_out(&tree, 0, &mut nodes, &mut tris);
        drop(tree);
        if n == 0 {
            nodes[0].min = [f32::INFINITY; 3];
            nodes[0].max = [f32::NEG_INFINITY; 3];
        }
        let mut wide = Vec::with_capacity(nodes.len() / 2 + 1);
        let mut blocks = Vec::with_capacity(nodes.len() / 2 + 2);
        blocks.push(TriBlock::EMPTY); // what empty lanes refer to
        if n > 0 {
            let plan = plan_collapse(&nodes);
            collapse(&nodes, &plan, 0, &tris, &mut wide, &mut blocks);
        } else {
            wide.push(WideNode::EMPTY);
        }
        let mut bvh = Bvh {
            nodes: wide,
            blocks,
            references: tris.len(),
            tris: unique,
            bounds,
            tie: 0.0,
            patches: 0,
            grids: Vec::new(),
        };
        bvh.tie = bvh.ray_offset();
        bvh
    }

    /// Bounds of the whole scene.
    pub fn bounds(&self) -> Aabb {
        self.bounds
    }

    /// How far off a surface rays should start: large enough to clear `f32` rounding of the
    /// scene's coordinates (the largest coordinate times 2⁻¹⁸), small against any patch.
    pub fn ray_offset(&self) -> f32 {
        offset_of(&self.bounds)
    }

    /// The hit of the triangle `id` at distance `t`, barycentric coordinates `(u, v)` and
    /// determinant `det`: on a grid met whole, the patch there.
    #[inline(always)]
    fn hit_of(&self, id: u32, t: f32, u: f32, v: f32, det: f32) -> Hit {
        let k = id >> 1;
        let (patch, sub, u, v) = match self.grids.get(k.wrapping_sub(self.patches) as usize) {
            Some(g) => g.locate(id & 1, u, v),
            None => (k, (id & 1) as u8, u, v),
        };
        Hit {
            t,
            patch,
            sub,
            u,
            v,
            front: det > 0.0,
        }
    }

    /// The patch of triangle `id` at barycentric coordinates `(u, v)`.
    #[inline(always)]
    fn patch_of(&self, id: u32, u: f32, v: f32) -> u32 {
        let k = id >> 1;
        match self.grids.get(k.wrapping_sub(self.patches) as usize) {
            Some(g) => g.locate(id & 1, u, v).0,
            None => k,
        }
    }

    /// Sizes and depth.
    pub fn info(&self) -> BvhInfo {
        let mut depth = 0;
        let root = f64::from(self.bounds.surface_area());
        let (mut sah_nodes, mut sah_leaves) = (0.0, 0.0);
        let mut stack = vec![(0usize, 1usize)];
        while let Some((i, d)) = stack.pop() {
            depth = depth.max(d);
            let n = &self.nodes[i];
            for (lane, &c) in n.child.iter().enumerate() {
                if c == EMPTY_LANE {
                    continue;
                }
                let area = f64::from(
                    Aabb {
                        min: Vec3::from_array([0, 1, 2].map(|a| n.planes[a][lane])),
                        max: Vec3::from_array([3, 4, 5].map(|a| n.planes[a][lane])),
                    }
                    .surface_area(),
                ) / root;
                if c & LEAF == 0 {
                    sah_nodes += area;
                    stack.push((c as usize, d + 1));
                } else {
                    sah_leaves += area;
                }
            }
        }
        if !self.tris.is_empty() {
            sah_nodes += 1.0; // the root
        }
        let node_bytes = self.nodes.len() * std::mem::size_of::<WideNode>();
        BvhInfo {
            nodes: self.nodes.len(),
            triangles: self.tris.len(),
            references: self.references,
            depth,
            // The first block is the one empty lanes refer to.
            leaves: self.blocks.len() - 1,
            bytes: self.bytes(),
            node_bytes,
            sah_nodes,
            sah_leaves,
            whole_pieces: self.grids.len(),
            patches_in_whole_pieces: self.grids.iter().map(Locator::patches).sum(),
        }
    }

    /// The closest hit of `ray` with `0 < t < t_max`, front or back side.
    #[inline]
    pub fn closest_hit(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
        #[cfg(all(target_arch = "x86_64", not(target_feature = "avx2")))]
        if dispatch::avx2() {
            return dispatch::closest_hit(self, ray, t_max);
        }
        self.closest_hit_in::<NATIVE_AVX>(ray, t_max)
    }

    /// Start bringing child `c` (a node or a leaf's block) into the cache: the traversal
    /// asks for every child it will visit as soon as it knows it, so the memory latency of
    /// a tree larger than the cache overlaps with the work in between. Without a branch
    /// (whether a child is a leaf is as good as random): the address is selected, and four
    /// lines are asked for either way, a node's four or a block's three and the line after.
    #[inline(always)]
    fn prefetch(&self, c: u32) {
        // Both are aligned to cache lines of 64 bytes: a block spans 3 lines, a node 4.
        const LINES: usize = std::mem::size_of::<WideNode>().div_ceil(64);
        let leaf = c & LEAF != 0;
        let i = (c & !LEAF) as usize;
        let node = self.nodes.as_ptr().wrapping_add(i) as *const u8;
        let block = self.blocks.as_ptr().wrapping_add(i) as *const u8;
        crate::hint::prefetch(if leaf { block } else { node }, LINES);
    }

    /// [`Bvh::prefetch`] every child of `n` in `mask`.
    #[inline(always)]
    fn prefetch_met(&self, n: &WideNode, mut mask: u32) {
        while mask != 0 {
            self.prefetch(n.child[mask.trailing_zeros() as usize % WIDTH]);
            mask &= mask - 1;
        }
    }

    /// [`Bvh::closest_hit`], compiled for whatever instruction set its caller is.
    #[inline(always)]
    fn closest_hit_in<const AVX: bool>(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
        if self.tris.is_empty() {
            return None;
        }
        let r = Ray4::new(ray);
        let tie_abs = self.tie;
        let mut best_t = t_max;
        // How far a hit or a box may begin and still matter: up to the tie distance beyond
        // the best hit (a tie there, a front face meeting the back face hit so far at an
        // edge, must be seen); kept with `best_t`.
        let mut far = best_t * (1.0 + TIE) + tie_abs;
        let mut best = u32::MAX; // triangle id of the closest hit
        let (mut bu, mut bv, mut bdet) = (0.0f32, 0.0f32, 0.0f32);
        let mut stack = Stack::<(u32, f32)>::new();
        let mut cur = 0u32;
        'outer: loop {
            closest_visit!(
                self,
                AVX,
                r,
                tie_abs,
                best_t,
                far,
                best,
                bu,
                bv,
                bdet,
                stack,
                cur,
                continue 'outer
            );
            return self.answer(best, best_t, t_max, bu, bv, bdet);
        }
    }

    /// The closest hit of each ray of `rays` with `0 < t < t_max`, into the same place of
    /// `out`: exactly what [`Bvh::closest_hit`] finds for it, but on a hierarchy of
    /// 12 MiB or more (`INTERLEAVE_FROM`) [`IN_FLIGHT`] rays at a time on each thread. A ray's
    /// traversal is a chain of dependent loads, each waiting on the memory once the tree is
    /// larger than the cache; here each visit of one ray asks for the next node it needs and
    /// the other rays' visits run while it comes, so that their waits overlap (the
    /// interleaving of Kocberber et al. 2015, "Asynchronous Memory Access Chaining", applied
    /// to BVH traversal). Incoherent rays on the hospital at 10⁶ patches (a tree of 74 MB):
    /// 2.9–3.9 → 7.8–8.0 M rays/s on one thread. Where most of the tree fits the L2 cache
    /// it gains nothing, so smaller hierarchies cast one ray at a time. Rays that share an
    /// origin (a row of form factors) gain less, their common path being in the cache
    /// already: progressive refinement's rows at 10⁶ patches 11 % with 8 in flight.
    ///
    /// # Panics
    /// If `out` and `rays` differ in length.
    pub fn closest_hits(&self, rays: &[Ray], t_max: f32, out: &mut [Option<Hit>]) {
        assert_eq!(rays.len(), out.len(), "closest_hits: one answer per ray");
        #[cfg(all(target_arch = "x86_64", not(target_feature = "avx2")))]
        if dispatch::avx2() {
            return dispatch::closest_hits(self, rays, t_max, out);
        }
        self.closest_hits_in::<NATIVE_AVX>(rays, t_max, out)
    }

    /// [`Bvh::closest_hits`], compiled for whatever instruction set its caller is: one ray at
    /// a time on a hierarchy smaller than [`INTERLEAVE_FROM`], else [`Bvh::interleaved`].
    #[inline(always)]
    fn closest_hits_in<const AVX: bool>(&self, rays: &[Ray], t_max: f32, out: &mut [Option<Hit>]) {
        if self.tris.is_empty() || rays.len() < 2 || !self.interleaves() {
            for (ray, o) in rays.iter().zip(out.iter_mut()) {
                *o = self.closest_hit_in::<AVX>(ray, t_max);
            }
            return;
        }
        self.interleaved::<AVX>(rays, t_max, out);
    }

    /// Whether [`Bvh::closest_hits`] interleaves its rays on this hierarchy (12 MiB or more
    /// of nodes and leaves) rather than casting one at a time.
    pub fn interleaves(&self) -> bool {
        self.bytes() >= INTERLEAVE_FROM
    }

    /// Bytes of the nodes and leaf blocks, which a traversal reads.
    fn bytes(&self) -> usize {
        self.nodes.len() * std::mem::size_of::<WideNode>()
            + self.blocks.len() * std::mem::size_of::<TriBlock>()
    }

    /// [`Bvh::closest_hits`] with [`IN_FLIGHT`] rays interleaved a visit at a time, whatever
    /// the hierarchy's size; `rays` and `out` have the same length.
    #[inline(always)]
    fn interleaved<const AVX: bool>(&self, rays: &[Ray], t_max: f32, out: &mut [Option<Hit>]) {
        if self.tris.is_empty() || rays.is_empty() {
            out.fill(None);
            return;
        }
        // The rays in flight: lane `k` traces ray `which[k]`; lanes from `live` on are idle.
        let live0 = IN_FLIGHT.min(rays.len());
        let mut lanes: [Closest; IN_FLIGHT] =
            std::array::from_fn(|k| Closest::new(&rays[k.min(live0 - 1)], t_max, self.tie));
        let mut which: [usize; IN_FLIGHT] = std::array::from_fn(|k| k);
        let (mut live, mut next, mut k) = (live0, live0, 0);
        loop {
            let q = &mut lanes[k];
            if self.closest_step::<AVX>(q) {
                k += 1;
            } else {
                out[which[k]] = q.hit(self);
                if next < rays.len() {
                    q.restart(&rays[next], t_max, self.tie);
                    which[k] = next;
                    next += 1;
                    k += 1;
                } else {
                    // No ray left to start: the last lane in flight takes this one's place.
                    live -= 1;
                    if live == 0 {
                        return;
                    }
                    lanes.swap(k, live);
                    which[k] = which[live];
                }
            }
            if k >= live {
                k = 0;
            }
        }
    }

    /// One visit of `q`'s traversal ([`closest_visit`]); false when nothing is left to visit,
    /// and `q.hit()` is then the answer.
    #[inline(always)]
    fn closest_step<const AVX: bool>(&self, q: &mut Closest) -> bool {
        closest_visit!(
            self,
            AVX,
            q.r,
            self.tie,
            q.best_t,
            q.far,
            q.best,
            q.bu,
            q.bv,
            q.bdet,
            q.stack,
            q.cur,
            return true
        );
        false
    }

    /// Whether anything (front or back side) lies on `ray` with `0 < t < t_max`: the any-hit
    /// query of shadow rays. It stops at the first intersection found and visits the children
    /// met farthest first (in a closed scene the far ones hold the surface the ray ends on:
    /// 1.65× the rate of the stored order on the hospital's form-factor rays, 1.1× on the
    /// Cornell box's), so it does less work than [`Bvh::closest_hit`] on the same ray.
    #[inline]
    pub fn occluded(&self, ray: &Ray, t_max: f32) -> bool {
        self.occluded_except(ray, t_max, |_| false)
    }

    /// Whether anything other than the patches `skip` names lies on `ray` with
    /// `0 < t < t_max`: [`Bvh::occluded`] that looks through some patches (a visibility
    /// ray's own target, which a point sampled on a slightly warped quad may lie behind).
    #[inline]
    pub fn occluded_except(&self, ray: &Ray, t_max: f32, skip: impl Fn(u32) -> bool) -> bool {
        #[cfg(all(target_arch = "x86_64", not(target_feature = "avx2")))]
        if dispatch::avx2() {
            return dispatch::any_hit_except::<true>(self, ray, t_max, skip).is_some();
        }
        self.any_hit_except_in::<NATIVE_AVX, true>(ray, t_max, skip)
            .is_some()
    }

    /// The distance of some intersection (the first the traversal meets, not the closest) of
    /// `ray` with `0 < t < t_max` other than the patches `skip` names, if there is one: the
    /// any-hit query of [`Bvh::occluded_except`] telling also where it stopped. It visits the
    /// children in their stored order, which meets hits on the near part of a segment sooner
    /// than the farthest-first order (hierarchical visibility asks whether the first hit
    /// lies well before the target: 4 % faster on the hospital than farthest first).
    #[inline]
    pub fn any_hit_except(&self, ray: &Ray, t_max: f32, skip: impl Fn(u32) -> bool) -> Option<f32> {
        #[cfg(all(target_arch = "x86_64", not(target_feature = "avx2")))]
        if dispatch::avx2() {
            return dispatch::any_hit_except::<false>(self, ray, t_max, skip);
        }
        self.any_hit_except_in::<NATIVE_AVX, false>(ray, t_max, skip)
    }

    /// [`Bvh::any_hit_except`], compiled for whatever instruction set its caller is.
    #[inline(always)]
    /// `FAR_FIRST`: children met are visited farthest first, else in their stored order.
    fn any_hit_except_in<const AVX: bool, const FAR_FIRST: bool>(
        &self,
        ray: &Ray,
        t_max: f32,
        skip: impl Fn(u32) -> bool,
    ) -> Option<f32> {
        if self.tris.is_empty() {
            return None;
        }
        let r = Ray4::new(ray);
        let mut stack = Stack::<u32>::new();
        let mut cur = 0u32;
        loop {
            if cur & LEAF != 0 {
                let b = &self.blocks[(cur & !LEAF) as usize];
                let (t, u, v, _) = r.intersect(b);
                let mut mask = lanes_hit(b, t, u, v, t_max);
                while mask != 0 {
                    let l = mask.trailing_zeros() as usize;
                    mask &= mask - 1;
                    if !skip(self.patch_of(b.id[l], u.to_array()[l], v.to_array()[l])) {
                        return Some(t.to_array()[l]);
                    }
                }
            } else {
                let n = &self.nodes[cur as usize];
                // (An empty lane's box is never entered.)
                let (dist, mut mask) = r.enter::<AVX>(n, t_max);
                let count = mask.count_ones() as usize;
                self.prefetch_met(n, mask);
                if count == 1 {
                    cur = n.child[mask.trailing_zeros() as usize % WIDTH];
                    continue;
                }
                stack.reserve();
                if !FAR_FIRST {
                    while mask != 0 {
                        stack.push(n.child[mask.trailing_zeros() as usize % WIDTH]);
                        mask &= mask - 1;
                    }
                } else if count == 2 {
                    let a = mask.trailing_zeros() as usize % WIDTH;
                    let b = (mask & (mask - 1)).trailing_zeros() as usize % WIDTH;
                    let (near, far) = if dist[a] <= dist[b] { (a, b) } else { (b, a) };
                    stack.push(n.child[near]);
                    cur = n.child[far];
                    continue;
                } else if count == 3 {
                    let k = sorted_met::<3>(&dist, mask, &SORT3);
                    stack.push(n.child[(k[0] & 7) as usize]);
                    stack.push(n.child[(k[1] & 7) as usize]);
                    cur = n.child[(k[2] & 7) as usize];
                    continue;
                } else if count == 4 {
                    let k = sorted_met::<4>(&dist, mask, &SORT4);
                    for &key in &k[..3] {
                        stack.push(n.child[(key & 7) as usize]);
                    }
                    cur = n.child[(k[3] & 7) as usize];
                    continue;
                } else if count > 4 {
                    let k = sorted_keys(&dist, mask);
                    // Farthest first: in a closed scene the far children hold the surface
                    // the ray ends on.
                    for i in 0..count - 1 {
                        stack.push(n.child[(k[i] & 7) as usize]);
                    }
                    cur = n.child[(k[count - 1] & 7) as usize];
                    continue;
                }
            }
            cur = stack.pop()?;
        }
    }

    /// Check the hierarchy's invariants: children inside parents, every triangle in at least
    /// one leaf (more than one where a spatial split cut it), meeting each box it is in, and
    /// every point of it (a grid of 15 barycentric points) inside the box of one of its
    /// leaves. Tests call it.
    pub fn validate(&self) -> Result<(), String> {
        // Triangle ids (patch << 1 | sub) are unique: where each is in `tris`.
        let index: std::collections::HashMap<u32, usize> = self
            .tris
            .iter()
            .enumerate()
            .map(|(k, t)| (t.id, k))
            .collect();
        if index.len() != self.tris.len() {
            return Err("two triangles share an id".into());
        }
        let mut boxes: Vec<Vec<Aabb>> = vec![Vec::new(); self.tris.len()];
        let lane_box = |n: &WideNode, l: usize| Aabb {
            min: Vec3::new(n.planes[0][l], n.planes[1][l], n.planes[2][l]),
            max: Vec3::new(n.planes[3][l], n.planes[4][l], n.planes[5][l]),
        };
        let tol = |a: f32| 1e-4 * a.abs().max(1.0);
        let inside = |p: Vec3, b: &Aabb| {
            (0..3).all(|k| p[k] >= b.min[k] - tol(p[k]) && p[k] <= b.max[k] + tol(p[k]))
        };
        // (node, box of the node as its parent stores it)
        let mut stack = vec![(
            0usize,
            Aabb {
                min: Vec3::splat(f32::NEG_INFINITY),
                max: Vec3::splat(f32::INFINITY),
            },
        )];
        let mut references = 0;
        while let Some((i, parent)) = stack.pop() {
            let n = &self.nodes[i];
            for l in 0..WIDTH {
                let c = n.child[l];
                if c == EMPTY_LANE {
                    continue;
                }
                let b = lane_box(n, l);
                if !inside(b.min, &parent) || !inside(b.max, &parent) {
                    return Err(format!("a child of node {i} sticks out of it"));
                }
                if c & LEAF == 0 {
                    stack.push((c as usize, b));
                    continue;
                }
                let blk = &self.blocks[(c & !LEAF) as usize];
                for lane in 0..4 {
                    if blk.id[lane] == NO_TRIANGLE {
                        continue;
                    }
                    references += 1;
                    let get = |a: &[Vec4; 3]| Vec3::new(a[0][lane], a[1][lane], a[2][lane]);
                    let (v0, e1, e2) = (get(&blk.v0), get(&blk.e1), get(&blk.e2));
                    let Some(&k) = index.get(&blk.id[lane]).filter(|&&k| {
                        let t = &self.tris[k];
                        (t.v0, t.e1, t.e2) == (v0, e1, e2)
                    }) else {
                        return Err(format!(
                            "leaf lane holds an unknown triangle {}",
                            blk.id[lane]
                        ));
                    };
                    let tb = Aabb::from_points(&[v0, v0 + e1, v0 + e2]);
                    let meets = (0..3).all(|a| {
                        tb.min[a] <= b.max[a] + tol(tb.min[a])
                            && tb.max[a] >= b.min[a] - tol(tb.max[a])
                    });
                    if !meets {
                        return Err(format!("triangle {k} does not meet its leaf's box"));
                    }
                    boxes[k].push(b);
                }
            }
        }
        if references != self.references {
            return Err(format!(
                "{references} triangle references in the leaves, {} counted",
                self.references
            ));
        }
        for (k, (t, bs)) in self.tris.iter().zip(&boxes).enumerate() {
            if bs.is_empty() {
                return Err(format!("triangle {k} in no leaf"));
            }
            // A point's rounding is relative to the vertices' coordinates, not its own.
            let m = [t.v0, t.v0 + t.e1, t.v0 + t.e2]
                .iter()
                .fold(1f32, |m, v| m.max(v.abs().max_element()));
            let near = |p: Vec3, b: &Aabb| {
                (0..3).all(|k| p[k] >= b.min[k] - tol(m) && p[k] <= b.max[k] + tol(m))
            };
            for i in 0..=4 {
                for j in 0..=4 - i {
                    let p = t.v0 + t.e1 * (i as f32 / 4.0) + t.e2 * (j as f32 / 4.0);
                    if !bs.iter().any(|b| near(p, b)) {
                        return Err(format!(
                            "a point of triangle {k} lies in none of its leaves' boxes"
                        ));
                    }
                }
            }
        }
        Ok(())
    }
}

/// [`Ray4::enter`] in AVX2 and FMA intrinsics, used by builds that assume them (the default,
/// `-C target-cpu=native` on such a CPU) and by the run-time AVX2 copy of a portable build
/// ([`NATIVE_AVX`], module `dispatch`): the compiler's own vectorisation of
/// [`Ray4::enter_lanes`] splits the far distances into two halves and keeps the ray's
/// constants on the stack.
#[cfg(target_arch = "x86_64")]
#[allow(unsafe_code)]
mod avx {
    use super::{Ray4, WideNode, WIDTH};
    use std::arch::x86_64::*;

    /// Entry distances and the mask of the children met with `0 ≤ t ≤ t_max` (finite), as
    /// [`Ray4::enter_lanes`] computes them but with each slab distance one fused
    /// multiply-add (`plane·inv − o·inv`, the ray's constants padded so that the test stays
    /// conservative).
    ///
    /// The maxima, minima and the comparison are taken on the distances' bits as signed
    /// integers (`vpmaxsd`, `vpminsd`, `vpcmpgtd`: one cycle each against `maxps`'s four, on
    /// the chain from a node's load to the next: hospital, 28,735 patches, one thread,
    /// 2.72 → 2.86 M rays/s; Cornell, 9,992, 5.8 → 6.4). As integers, non-negative floats
    /// keep their order and every negative one lies below them, so the entry distance, a
    /// maximum with 0, is the float maximum; an exit distance that comes out negative, as an
    /// integer or not, lies below every entry and the child is not met, as with floats. A
    /// NaN origin coordinate makes both of its slab's distances carry its NaN (propagated
    /// through `o·inv`, the padding and the fused multiply-add), which as an integer lies
    /// above every exit (positive sign) or below every entry (negative), so such a ray still
    /// enters nothing (and `nan_rays_meet_nothing` holds NaN rays to no hit). Only an exit of
    /// exactly −0.0 differs from the float test, which would meet that box at t = 0, where
    /// no hit counts.
    #[inline(always)]
    pub(super) fn enter(r: &Ray4, n: &WideNode, t_max: f32) -> ([f32; WIDTH], u32) {
        // SAFETY: `Ray4::enter::<true>`, the only caller, is instantiated only where the CPU
        // has AVX2 and FMA: in builds whose target features include both (`NATIVE_AVX`),
        // and in `dispatch`'s copies, which run after `is_x86_feature_detected!`. The loads
        // and the store touch whole `[f32; 8]` arrays through references to them.
        unsafe {
            let plane = |k: usize| _mm256_loadu_ps(n.planes[k].as_ptr());
            let dist = |k: usize, a: usize, o: f32| {
                _mm256_fmsub_ps(plane(k), _mm256_set1_ps(r.inv[a]), _mm256_set1_ps(o))
            };
            let nx = dist(r.near[0], 0, r.o_near[0]);
            let ny = dist(r.near[1], 1, r.o_near[1]);
            let nz = dist(r.near[2], 2, r.o_near[2]);
            let fx = dist(r.far[0], 0, r.o_far[0]);
            let fy = dist(r.far[1], 1, r.o_far[1]);
            let fz = dist(r.far[2], 2, r.o_far[2]);
            let i = _mm256_castps_si256;
            let near = _mm256_max_epi32(
                _mm256_max_epi32(_mm256_setzero_si256(), i(nz)),
                _mm256_max_epi32(i(nx), i(ny)),
            );
            let far = _mm256_min_epi32(
                _mm256_min_epi32(i(_mm256_set1_ps(t_max)), i(fz)),
                _mm256_min_epi32(i(fx), i(fy)),
            );
            let beyond = _mm256_cmpgt_epi32(near, far);
            let mask = !(_mm256_movemask_ps(_mm256_castsi256_ps(beyond)) as u32) & 0xff;
            let mut out = [0.0f32; WIDTH];
            _mm256_storeu_ps(out.as_mut_ptr(), _mm256_castsi256_ps(near));
            (out, mask)
        }
    }
}

/// Run-time choice of instruction set, for builds that do not assume AVX2 (no
/// `-C target-cpu=native`): the queries are compiled a second time with AVX2, FMA, BMI and
/// POPCNT enabled (8-wide box tests in one instruction, `tzcnt`, `popcnt`), and that copy runs
/// wherever the CPU has them. A build for a CPU with AVX2 uses its one copy directly.
#[cfg(all(target_arch = "x86_64", not(target_feature = "avx2")))]
#[allow(unsafe_code)]
mod dispatch {
    use super::{Bvh, Hit};
    use crate::geom::Ray;
    use std::sync::OnceLock;

    /// Whether this CPU has every feature the AVX2 copy is compiled with (asked once).
    #[inline(always)]
    pub(super) fn avx2() -> bool {
        static HAS: OnceLock<bool> = OnceLock::new();
        *HAS.get_or_init(|| {
            is_x86_feature_detected!("avx2")
                && is_x86_feature_detected!("fma")
                && is_x86_feature_detected!("bmi1")
                && is_x86_feature_detected!("bmi2")
                && is_x86_feature_detected!("lzcnt")
                && is_x86_feature_detected!("popcnt")
        })
    }

    #[target_feature(enable = "avx2,fma,bmi1,bmi2,lzcnt,popcnt")]
    fn closest_hit_avx2(bvh: &Bvh, ray: &Ray, t_max: f32) -> Option<Hit> {
        bvh.closest_hit_in::<true>(ray, t_max)
    }

    #[target_feature(enable = "avx2,fma,bmi1,bmi2,lzcnt,popcnt")]
    fn closest_hits_avx2(bvh: &Bvh, rays: &[Ray], t_max: f32, out: &mut [Option<Hit>]) {
        bvh.closest_hits_in::<true>(rays, t_max, out)
    }

    #[target_feature(enable = "avx2,fma,bmi1,bmi2,lzcnt,popcnt")]
    fn any_hit_except_avx2<const FAR_FIRST: bool>(
        bvh: &Bvh,
        ray: &Ray,
        t_max: f32,
        skip: impl Fn(u32) -> bool,
    ) -> Option<f32> {
        bvh.any_hit_except_in::<true, FAR_FIRST>(ray, t_max, skip)
    }

    /// The AVX2 copy of [`Bvh::closest_hit`]; call only where [`avx2`] is true.
    #[inline]
    pub(super) fn closest_hit(bvh: &Bvh, ray: &Ray, t_max: f32) -> Option<Hit> {
        debug_assert!(avx2());
        // SAFETY: the caller checked with `avx2()` that the CPU has every feature enabled.
        unsafe { closest_hit_avx2(bvh, ray, t_max) }
    }

    /// The AVX2 copy of [`Bvh::closest_hits`]; call only where [`avx2`] is true.
    #[inline]
    pub(super) fn closest_hits(bvh: &Bvh, rays: &[Ray], t_max: f32, out: &mut [Option<Hit>]) {
        debug_assert!(avx2());
        // SAFETY: the caller checked with `avx2()` that the CPU has every feature enabled.
        unsafe { closest_hits_avx2(bvh, rays, t_max, out) }
    }

    /// The AVX2 copy of [`Bvh::any_hit_except`]; call only where [`avx2`] is true.
    #[inline]
    pub(super) fn any_hit_except<const FAR_FIRST: bool>(
        bvh: &Bvh,
        ray: &Ray,
        t_max: f32,
        skip: impl Fn(u32) -> bool,
    ) -> Option<f32> {
        debug_assert!(avx2());
        // SAFETY: as above.
        unsafe { any_hit_except_avx2::<FAR_FIRST>(bvh, ray, t_max, skip) }
    }
}

/// SAH cost of testing a wide node's child boxes, per unit of the node's surface area.
const COST_NODE: f32 = 1.0;
/// SAH cost of testing a leaf's block of triangles, per unit of the leaf's surface area.
const COST_BLOCK: f32 = 1.0;

/// How to cut the binary tree into wide nodes with the least SAH cost, by dynamic programming
/// over the subtrees (the collapse of Ylitie, Karras & Laine 2017, "Efficient Incoherent Ray
/// Traversal on GPUs Through Compressed Wide BVHs", §3.1), instead of greedily opening the
/// largest child, which leaves many nodes with two or three children.
///
/// For binary node `n` and `i ≥ 2`, `plan[n][i − 1]` tells how its subtree best fills at most
/// `i` child slots of a wide node: 0 as with `i − 1` slots (with one slot, `n` itself is the
/// child), `k > 0` by giving `k` slots to its left subtree and `i − k` to its right.
/// `plan[n][0]` tells how an interior `n` made a wide node shares out its [`WIDTH`] slots.
fn plan_collapse(bin: &[Node]) -> Vec<[u8; WIDTH]> {
    let mut cost = vec![[0f32; WIDTH]; bin.len()];
    let mut plan = vec![[0u8; WIDTH]; bin.len()];
    // Children come after their parent in `bin`: backwards is bottom up.
    for n in (0..bin.len()).rev() {
        let a = node_area(&bin[n]);
        if bin[n].count > 0 {
            cost[n] = [a * COST_BLOCK; WIDTH];
            continue;
        }
        let (l, r) = (bin[n].first as usize, bin[n].first as usize + 1);
        // split[i − 1]: the best cost of `i` slots shared between the two subtrees (one
        // slot to the left where every cost overflows to ∞, so the plan stays valid).
        let mut split = [(f32::INFINITY, 1u8); WIDTH];
        for i in 2..=WIDTH {
            for k in 1..i {
                let c = cost[l][k - 1] + cost[r][i - k - 1];
                if c < split[i - 1].0 {
                    split[i - 1] = (c, k as u8);
                }
            }
        }
        cost[n][0] = a * COST_NODE + split[WIDTH - 1].0;
        plan[n][0] = split[WIDTH - 1].1;
        for i in 2..=WIDTH {
            if split[i - 1].0 < cost[n][i - 2] {
                cost[n][i - 1] = split[i - 1].0;
                plan[n][i - 1] = split[i - 1].1;
            } else {
                cost[n][i - 1] = cost[n][i - 2];
            }
        }
    }
    plan
}

fn node_area(n: &Node) -> f32 {
    Aabb {
        min: Vec3::from_array(n.min),
        max: Vec3::from_array(n.max),
    }
    .surface_area()
}

/// The wide-node children that binary subtree `n` becomes when given at most `slots` slots.
fn gather(bin: &[Node], plan: &[[u8; WIDTH]], n: usize, slots: usize, kids: &mut Vec<usize>) {
    let mut i = slots;
    while i > 1 && plan[n][i - 1] == 0 {
        i -= 1;
    }
    if i == 1 {
        kids.push(n);
        return;
    }
    let k = plan[n][i - 1] as usize;
    let l = bin[n].first as usize;
    gather(bin, plan, l, k, kids);
    gather(bin, plan, l + 1, i - k, kids);
}

/// Collapse the binary tree under `b` into wide nodes appended to `out` as `plan` says;
/// returns the index of the node made for `b` (which must be interior, or the root).
fn collapse(
    bin: &[Node],
    plan: &[[u8; WIDTH]],
    b: usize,
    tris: &[Tri],
    out: &mut Vec<WideNode>,
    blocks: &mut Vec<TriBlock>,
) -> u32 {
    let mut kids = Vec::with_capacity(WIDTH);
    if bin[b].count > 0 {
        kids.push(b); // a root that is a leaf
    } else {
        let k = plan[b][0] as usize;
        let l = bin[b].first as usize;
        gather(bin, plan, l, k, &mut kids);
        gather(bin, plan, l + 1, WIDTH - k, &mut kids);
    }
    debug_assert!(kids.len() <= WIDTH);
    let me = out.len();
    out.push(WideNode::EMPTY);
    for (lane, &k) in kids.iter().enumerate() {
        let n = bin[k];
        let r = if n.count > 0 {
            assert!(n.count as usize <= 4, "leaf of more than four triangles");
            let mut blk = TriBlock::EMPTY;
            for (lane, t) in tris[n.first as usize..(n.first + n.count) as usize]
                .iter()
                .enumerate()
            {
                for a in 0..3 {
                    blk.v0[a][lane] = t.v0[a];
                    blk.e1[a][lane] = t.e1[a];
                    blk.e2[a][lane] = t.e2[a];
                }
                blk.id[lane] = t.id;
                // Rounding of a few ulps of the distance from the ray's origin to the
                // triangle's first vertex, in world units, over the triangle's smallest height
                // (twice its area over its longest edge).
                let longest = t.e1.length().max(t.e2.length()).max((t.e2 - t.e1).length());
                let height = t.e1.cross(t.e2).length() / longest;
                let per_length = SLACK_ULPS * f32::EPSILON / height;
                if per_length.is_finite() {
                    blk.slack0[lane] = (per_length * longest).max(EDGE_EPS);
                    blk.slack1[lane] = per_length;
                } else {
                    blk.slack0[lane] = EDGE_EPS;
                }
            }
            blocks.push(blk);
            LEAF | (blocks.len() - 1) as u32
        } else {
            collapse(bin, plan, k, tris, out, blocks)
        };
        let node = &mut out[me];
        for a in 0..3 {
            node.planes[a][lane] = n.min[a];
            node.planes[3 + a][lane] = n.max[a];
        }
        node.child[lane] = r;
    }
    me as u32
}

/// Slices at least this long are split over threads (bounds, bins).
const PARALLEL_MIN: usize = 16 * 1024;

/// Nodes of at least this many references build their two subtrees on two threads.
const JOIN_MIN: usize = 1024;

/// A node of the binary tree while it is built.
enum Built {
    Leaf { bounds: Aabb, tris: Vec<Tri> },
    Inner { bounds: Aabb, kids: Box<[Built; 2]> },
}

/// The union of `f(p)` over `prims`, in parallel for long slices: min and max are exact, so
/// the result does not depend on how the work is split.
fn bounds_of<T: Sync>(prims: &[T], f: impl Fn(&T) -> Aabb + Sync) -> Aabb {
    if prims.len() < PARALLEL_MIN {
        return prims.iter().fold(Aabb::EMPTY, |b, p| b.union(f(p)));
    }
    prims
        .par_chunks(PARALLEL_MIN / 4)
        .map(|c| c.iter().fold(Aabb::EMPTY, |b, p| b.union(f(p))))
        .reduce(|| Aabb::EMPTY, Aabb::union)
}

/// References that spatial splits may add, as a fraction of the triangles (the hospital at
/// 28,735 patches takes 6 %, at a million 1.7 %).
const SPLIT_BUDGET: f64 = 0.3;
/// A node whose best object split leaves children overlapping by more than this fraction of
/// the scene's surface area also tries a spatial split (Stich, Friedrich & Dietrich 2009, α;
/// they use 10⁻⁵, which builds the hospital's tree a third slower for no faster rays).
const SPLIT_OVERLAP: f32 = 1e-4;
/// Bins of a spatial split, at most.
const SPATIAL_BINS: usize = 32;
const _: () = assert!(SPATIAL_BINS <= BINS, "sweep's arrays hold BINS");

/// Bins of a spatial split of `n` references: fewer for small nodes, whose triangles span
/// many of a fine grid's bins, each to be clipped.
fn spatial_bins(n: usize) -> usize {
    if n >= 64 {
        32
    } else if n >= 16 {
        16
    } else {
        4
    }
}

/// What the spatial splits of a build share.
struct Splits {
    /// The overlap, in units of surface area, from which a spatial split is tried.
    min_overlap: f32,
}

/// How a node is split.
enum Cut {
    /// A leaf.
    Leaf,
    /// The first `mid` references (reordered in place) and the rest.
    At(usize),
    /// A spatial split: the first `n` references (rewritten in place) and a new list.
    Spatial(usize, Vec<Prim>),
}

/// Build the binary tree over the references `prims` (reordered in place), which may grow by
/// `budget` more references through spatial splits.
fn build_tree(prims: &mut [Prim], depth: usize, budget: usize, split: &Splits) -> Built {
    let count = prims.len();
    let bounds = bounds_of(prims, |p| p.bounds);
    let cut = if count <= MAX_LEAF {
        Cut::Leaf
    } else if depth >= HALVING_DEPTH {
        // Deep enough that only halving by count keeps the tree within MAX_DEPTH levels
        // (which the traversal stacks are sized for); a pathological input gets here.
        Cut::At(count / 2)
    } else {
        choose_split(prims, bounds, budget, split)
    };
    let kids = |l: &mut [Prim], r: &mut [Prim]| {
        // The budget left, shared in proportion to the references on each side.
        let (nl, nr) = (l.len(), r.len());
        let left = budget.saturating_sub(nl + nr - count);
        let lb = (left as u128 * nl as u128 / (nl + nr) as u128) as usize;
        let rb = left - lb;
        let (a, b) = if count >= JOIN_MIN {
            rayon::join(
                || build_tree(l, depth + 1, lb, split),
                || build_tree(r, depth + 1, rb, split),
            )
        } else {
            (
                build_tree(l, depth + 1, lb, split),
                build_tree(r, depth + 1, rb, split),
            )
        };
        Built::Inner {
            bounds,
            kids: Box::new([a, b]),
        }
    };
    match cut {
        Cut::At(mid) => {
            let (l, r) = prims.split_at_mut(mid);
            kids(l, r)
        }
        Cut::Spatial(nl, mut r) => kids(&mut prims[..nl], &mut r),
        Cut::Leaf => Built::Leaf {
            bounds,
            tris: prims.iter().map(|p| p.tri).collect(),
        },
    }
}

/// Write `t` into `nodes[at]`, its children after the end of `nodes`, depth first, and its
/// leaves' triangles at the end of `tris`.
fn lay_out(t: &Built, at: usize, nodes: &mut Vec<Node>, tris: &mut Vec<Tri>) {
    let (b, first, count) = match t {
        Built::Leaf { bounds, tris: mine } => {
            let first = tris.len() as u32;
            tris.extend_from_slice(mine);
            (*bounds, first, mine.len() as u32)
        }
        Built::Inner { bounds, .. } => (*bounds, nodes.len() as u32, 0),
    };
    nodes[at] = Node {
        min: b.min.to_array(),
        first,
        max: b.max.to_array(),
        count,
    };
    if let Built::Inner { kids, .. } = t {
        let left = nodes.len();
        for _ in 0..2 {
            nodes.push(Node {
                min: [0.0; 3],
                first: 0,
                max: [0.0; 3],
                count: 0,
            });
        }
        lay_out(&kids[0], left, nodes, tris);
        lay_out(&kids[1], left + 1, nodes, tris);
    }
}

/// The box of the part of triangle `t` with `lo ≤ x[axis] ≤ hi`, within `within`, grown by a
/// few units in the last place so that rounding in the clipping never leaves a point of the
/// triangle outside every box made for it. Empty if the part is.
fn clip(t: &Tri, axis: usize, lo: f32, hi: f32, within: &Aabb) -> Aabb {
    let v = [t.v0, t.v0 + t.e1, t.v0 + t.e2];
    let mut b = Aabb::EMPTY;
    for k in 0..3 {
        let (p, q) = (v[k], v[(k + 1) % 3]);
        if p[axis] >= lo && p[axis] <= hi {
            b = b.grow(p);
        }
        for c in [lo, hi] {
            if (p[axis] < c && q[axis] > c) || (p[axis] > c && q[axis] < c) {
                let mut x = p + (q - p) * ((c - p[axis]) / (q[axis] - p[axis]));
                x[axis] = c;
                b = b.grow(x);
            }
        }
    }
    if b.is_empty() {
        return b;
    }
    let m = v.iter().fold(0f32, |m, p| m.max(p.abs().max_element()));
    let pad = Vec3::splat(m * 8.0 * f32::EPSILON);
    let b = Aabb {
        min: (b.min - pad).max(within.min),
        max: (b.max + pad).min(within.max),
    };
    if b.is_empty() {
        Aabb::EMPTY
    } else {
        b
    }
}

/// Add to `bins[b0..=b1]` the boxes of the parts of triangle `t` in each bin of a spatial
/// split along `axis` (bin `b` from `lo + b·width`; the first and last open-ended), within
/// `within`: each vertex goes to its bin, each point where an edge crosses a bin's boundary
/// to the bins on both sides. For the split's cost only: the partition clips exactly.
#[allow(clippy::too_many_arguments)]
fn chop(
    t: &Tri,
    axis: usize,
    lo: f32,
    width: f32,
    scale: f32,
    b0: usize,
    b1: usize,
    within: &Aabb,
    bins: &mut [(Aabb, usize, usize); SPATIAL_BINS],
) {
    let v = [t.v0, t.v0 + t.e1, t.v0 + t.e2];
    let vb = v.map(|p| spatial_bin(p[axis], lo, scale, SPATIAL_BINS).clamp(b0, b1));
    // The points where the edges cross the boundary below the current bin.
    let mut below = Aabb::EMPTY;
    for b in b0..=b1 {
        let mut part = below;
        for k in 0..3 {
            if vb[k] == b {
                part = part.grow(v[k]);
            }
        }
        below = Aabb::EMPTY;
        if b < b1 {
            let c = lo + (b + 1) as f32 * width;
            for k in 0..3 {
                let (p, q) = (v[k], v[(k + 1) % 3]);
                if (p[axis] < c && q[axis] > c) || (p[axis] > c && q[axis] < c) {
                    let mut x = p + (q - p) * ((c - p[axis]) / (q[axis] - p[axis]));
                    x[axis] = c;
                    below = below.grow(x);
                }
            }
            part = part.union(below);
        }
        let clipped = Aabb {
            min: part.min.max(within.min),
            max: part.max.min(within.max),
        };
        if !clipped.is_empty() {
            bins[b].0 = bins[b].0.union(clipped);
        }
    }
}

/// The bin of coordinate `x` of a spatial split from `lo` with bins `1 / scale` wide.
fn spatial_bin(x: f32, lo: f32, scale: f32, nb: usize) -> usize {
    (((x - lo) * scale).max(0.0) as usize).min(nb - 1)
}

/// The best spatial split of `prims` inside `bounds` along its longest axis (Stich,
/// Friedrich & Dietrich 2009, §4.2: bins of equal width, each reference chopped into the
/// bins it spans): its SAH cost, counting blocks of [`MAX_LEAF`] as the object split does,
/// its bin boundary, and the references it cuts in two. Only the longest axis is tried: a
/// third of the cost of all three, and as fast a tree on the hospital at 28,735 patches.
fn spatial_split(prims: &[Prim], bounds: &Aabb) -> Option<(f32, usize, usize, usize)> {
    let ext = bounds.extent();
    let axis = ext.max_position();
    if ext[axis] <= 0.0 {
        return None;
    }
    let nb = spatial_bins(prims.len());
    let lo = bounds.min[axis];
    let scale = nb as f32 / ext[axis];
    let width = ext[axis] / nb as f32;
    // Per bin: the box of the parts in it, the references that begin in it, and those
    // that end in it.
    let fill = |c: &[Prim]| {
        let mut bins = [(Aabb::EMPTY, 0usize, 0usize); SPATIAL_BINS];
        for p in c {
            let b0 = spatial_bin(p.bounds.min[axis], lo, scale, nb);
            let b1 = spatial_bin(p.bounds.max[axis], lo, scale, nb);
            bins[b0].1 += 1;
            bins[b1].2 += 1;
            if b0 == b1 {
                bins[b0].0 = bins[b0].0.union(p.bounds);
            } else {
                chop(&p.tri, axis, lo, width, scale, b0, b1, &p.bounds, &mut bins);
            }
        }
        bins
    };
    let bins = if prims.len() < PARALLEL_MIN {
        fill(prims)
    } else {
        prims.par_chunks(PARALLEL_MIN / 4).map(fill).reduce(
            || [(Aabb::EMPTY, 0usize, 0usize); SPATIAL_BINS],
            |mut a, b| {
                for (x, y) in a.iter_mut().zip(b) {
                    x.0 = x.0.union(y.0);
                    x.1 += y.1;
                    x.2 += y.2;
                }
                a
            },
        )
    };
    let best = sweep(&bins[..nb])?;
    Some((best.cost, axis, best.bin, best.nl + best.nr - prims.len()))
}

/// The cheapest boundary of a binned sweep: its SAH cost (counting blocks of [`MAX_LEAF`]),
/// the first bin above it, and each side's box and references.
struct Sweep {
    cost: f32,
    bin: usize,
    left: Aabb,
    right: Aabb,
    nl: usize,
    nr: usize,
}

/// The cheapest boundary between `bins` (at most [`BINS`]), each holding a box, the references
/// that begin in it and those that end in it (the same count for an object split, whose
/// references each fall in one bin); `None` when every boundary leaves a side empty.
fn sweep(bins: &[(Aabb, usize, usize)]) -> Option<Sweep> {
    // From the right: the boxes and counts above each boundary.
    let mut right = [(Aabb::EMPTY, 0usize); BINS];
    let (mut rb, mut rc) = (Aabb::EMPTY, 0);
    for b in (1..bins.len()).rev() {
        rb = rb.union(bins[b].0);
        rc += bins[b].2;
        right[b] = (rb, rc);
    }
    let mut best: Option<Sweep> = None;
    let (mut lb, mut lc) = (Aabb::EMPTY, 0);
    for b in 1..bins.len() {
        lb = lb.union(bins[b - 1].0);
        lc += bins[b - 1].1;
        let (rbox, rcount) = right[b];
        if lc == 0 || rcount == 0 {
            continue;
        }
        let cost = lb.surface_area() * lc.div_ceil(MAX_LEAF) as f32
            + rbox.surface_area() * rcount.div_ceil(MAX_LEAF) as f32;
        if best.as_ref().is_none_or(|s| cost < s.cost) {
            best = Some(Sweep {
                cost,
                bin: b,
                left: lb,
                right: rbox,
                nl: lc,
                nr: rcount,
            });
        }
    }
    best
}

/// Split `prims` (more than [`MAX_LEAF`]) by the binned SAH, by objects or, where the objects'
/// halves would overlap and the budget allows, by a plane that cuts the triangles it crosses
/// into a part for each side (a spatial split); or a leaf.
fn choose_split(prims: &mut [Prim], bounds: Aabb, budget: usize, split: &Splits) -> Cut {
    let object = object_split(prims);
    if budget > 0 {
        if let Some(o) = &object {
            let overlap = Aabb {
                min: o.left.min.max(o.right.min),
                max: o.left.max.min(o.right.max),
            };
            if overlap.surface_area() > split.min_overlap {
                if let Some((cost, axis, b, cut)) = spatial_split(prims, &bounds) {
                    if cost < o.cost && cut <= budget {
                        if let Some((nl, r)) = spatial_partition(prims, &bounds, axis, b) {
                            return Cut::Spatial(nl, r);
                        }
                    }
                }
            }
        }
    }
    match object {
        Some(o) => {
            partition(prims, o.axis, o.bin, o.lo, o.scale);
            Cut::At(o.mid)
        }
        // All centroids coincide: split by count.
        None if prims.len() > MAX_LEAF => Cut::At(prims.len() / 2),
        None => Cut::Leaf,
    }
}

/// Cut `prims` at bin boundary `b` of the spatial split along `axis`: a reference wholly on
/// one side goes there; one that straddles the plane goes to both, each with the box of its
/// part on that side. The left side is written over the front of `prims` (it is shorter, and
/// each reference gives it at most one), the right side into a new list, so that a split
/// copies only half its node. `None`, with `prims` untouched, when a side would be empty or
/// hold every reference.
fn spatial_partition(
    prims: &mut [Prim],
    bounds: &Aabb,
    axis: usize,
    b: usize,
) -> Option<(usize, Vec<Prim>)> {
    let ext = bounds.extent()[axis];
    let nb = spatial_bins(prims.len());
    let scale = nb as f32 / ext;
    let lo = bounds.min[axis];
    let plane = lo + b as f32 * (ext / nb as f32);
    let part = |p: &Prim, lo: f32, hi: f32| {
        let bx = clip(&p.tri, axis, lo, hi, &p.bounds);
        (!bx.is_empty()).then_some(Prim {
            bounds: bx,
            centroid: bx.centre(),
            tri: p.tri,
        })
    };
    // Which side each reference goes to: wholly left, wholly right, or cut.
    let side = |p: &Prim| {
        let b0 = spatial_bin(p.bounds.min[axis], lo, scale, nb);
        let b1 = spatial_bin(p.bounds.max[axis], lo, scale, nb);
        (b0 >= b, b1 < b)
    };
    let n = prims.len();
    let (mut left, mut right) = (0, Vec::new());
    for p in prims.iter() {
        match side(p) {
            (false, true) => left += 1,
            (true, false) => right.push(*p),
            _ => {
                left += part(p, f32::NEG_INFINITY, plane).is_some() as usize;
                right.extend(part(p, plane, f32::INFINITY));
            }
        }
    }
    if left == 0 || right.is_empty() || left == n || right.len() == n {
        return None;
    }
    let mut w = 0;
    for k in 0..n {
        let p = prims[k];
        let keep = match side(&p) {
            (false, true) => Some(p),
            (true, false) => None,
            _ => part(&p, f32::NEG_INFINITY, plane),
        };
        if let Some(q) = keep {
            prims[w] = q;
            w += 1;
        }
    }
    debug_assert_eq!(w, left);
    Some((left, right))
}

/// The binned SAH's bins of `prims` along `axis`: each bin's bounds and count, in parallel for
/// long slices (exact, whatever the split).
fn bins_of(prims: &[Prim], axis: usize, lo: f32, scale: f32) -> [(Aabb, usize); BINS] {
    let fill = |c: &[Prim]| {
        let mut bins = [(Aabb::EMPTY, 0usize); BINS];
        for p in c {
            let b = (((p.centroid[axis] - lo) * scale) as usize).min(BINS - 1);
            bins[b].0 = bins[b].0.union(p.bounds);
            bins[b].1 += 1;
        }
        bins
    };
    if prims.len() < PARALLEL_MIN {
        return fill(prims);
    }
    prims.par_chunks(PARALLEL_MIN / 4).map(fill).reduce(
        || [(Aabb::EMPTY, 0usize); BINS],
        |mut a, b| {
            for (x, y) in a.iter_mut().zip(b) {
                x.0 = x.0.union(y.0);
                x.1 += y.1;
            }
            a
        },
    )
}

/// The best object split of the binned SAH: its cost, where it cuts, and the two sides' boxes.
struct ObjectSplit {
    cost: f32,
    axis: usize,
    bin: usize,
    lo: f32,
    scale: f32,
    /// How many references go left.
    mid: usize,
    left: Aabb,
    right: Aabb,
}

/// Choose an object split of `prims` by the binned SAH; `None` when their centroids coincide.
fn object_split(prims: &[Prim]) -> Option<ObjectSplit> {
    let cb = bounds_of(prims, |p| Aabb {
        min: p.centroid,
        max: p.centroid,
    });
    let ext = cb.extent();
    let mut best: Option<ObjectSplit> = None;
    for axis in 0..3 {
        if ext[axis] <= 0.0 {
            continue;
        }
        let scale = BINS as f32 / ext[axis];
        let bins = bins_of(prims, axis, cb.min[axis], scale).map(|(b, n)| (b, n, n));
        let Some(s) = sweep(&bins) else {
            continue;
        };
        if best.as_ref().is_none_or(|o| s.cost < o.cost) {
            best = Some(ObjectSplit {
                cost: s.cost,
                axis,
                bin: s.bin,
                lo: cb.min[axis],
                scale,
                mid: s.nl,
                left: s.left,
                right: s.right,
            });
        }
    }
    best
}

/// Put the references whose centroid falls below bin `b` first.
fn partition(prims: &mut [Prim], axis: usize, b: usize, lo: f32, scale: f32) {
    let (mut i, mut j) = (0, prims.len());
    while i < j {
        let bin = (((prims[i].centroid[axis] - lo) * scale) as usize).min(BINS - 1);
        if bin < b {
            i += 1;
        } else {
            j -= 1;
            prims.swap(i, j);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::MeshParams;
    use crate::scene::builtin;

    /// Subtrees are built in parallel, and the hierarchy is the same, node for node, on any
    /// number of threads (the mesh is large enough for the top levels to split their work).
    #[test]
    fn stack_spills_and_refills_in_order() {
        // Pushes in node-sized batches far beyond the fixed part, interleaved with pops: the
        // stack gives back exactly what a Vec would.
        let mut stack = Stack::<u32>::new();
        let mut model = Vec::new();
        let mut next = 0u32;
        for round in 0..200 {
            stack.reserve();
            for _ in 0..WIDTH {
                stack.push(next);
                model.push(next);
                next += 1;
            }
            if round % 3 == 0 {
                assert_eq!(stack.pop(), model.pop());
            }
        }
        assert!(!stack.spill.is_empty());
        while let Some(v) = model.pop() {
            assert_eq!(stack.pop(), Some(v));
        }
        assert_eq!(stack.pop(), None);
    }

    /// A hierarchy that meets grids whole answers what one over every patch's triangles
    /// answers: on quads (a square, a parallelogram, a trapezoid and a kite-like convex quad, so
    /// that the bilinear inversion is exercised with α and β both zero and not) and a triangle,
    /// tilted and far from the origin, the same patch for every ray but those that pass within
    /// rounding of a patch's edge, the same distance and side, and barycentric coordinates that
    /// put the point where the ray met it, in the patch's own triangle.
    #[test]
    fn grids_met_whole_find_the_patch_met() {
        let at = |p: [f32; 3]| Vec3::from_array(p) + Vec3::new(40.0, -25.0, 60.0);
        let polygon = |v: Vec<[f32; 3]>| v.into_iter().map(at).collect::<Vec<_>>();
        let scene = crate::scene::Scene::of_polygons(
            "grids",
            crate::scene::Material::diffuse("grey", crate::color::Rgb::splat(0.5)),
            vec![
                // Floor square, facing up.
                polygon(vec![
                    [0.0, 0.0, 0.0],
                    [0.0, 0.0, 4.0],
                    [4.0, 0.0, 4.0],
                    [4.0, 0.0, 0.0],
                ]),
                // Parallelogram on a tilted plane.
                polygon(vec![
                    [0.0, 3.0, 0.0],
                    [3.0, 4.0, 0.5],
                    [4.0, 4.5, 3.0],
                    [1.0, 3.5, 2.5],
                ]),
                // Trapezoid wall, facing +x.
                polygon(vec![
                    [-1.0, 0.0, 0.0],
                    [-1.0, 3.0, 1.0],
                    [-1.0, 3.0, 2.5],
                    [-1.0, 0.0, 4.0],
                ]),
                // A convex quad with no parallel sides, facing −x.
                polygon(vec![
                    [5.0, 0.2, 0.0],
                    [5.0, 0.0, 4.0],
                    [5.0, 3.5, 3.0],
                    [5.0, 2.5, 0.4],
                ]),
                // A triangle, facing down.
                polygon(vec![[0.5, 5.0, 0.5], [3.5, 5.0, 1.0], [1.0, 5.0, 3.5]]),
            ],
        );
        let mesh = Mesh::build(&scene, MeshParams::Patches(3000)).unwrap();
        let whole = Bvh::build(&mesh);
        let info = whole.info();
        assert_eq!(info.whole_pieces, 5, "{info:?}");
        assert_eq!(info.patches_in_whole_pieces, mesh.len());
        assert!(info.triangles <= 9);
        whole.validate().unwrap();
        // Grids that overlap are not trusted, none of them.
        let mut twice = mesh.clone();
        twice.grids.push(twice.grids[0]);
        assert_eq!(Bvh::build(&twice).info().whole_pieces, 0);
        let mut plain = mesh.clone();
        plain.grids.clear();
        let each = Bvh::build(&plain);
        assert_eq!(each.info().whole_pieces, 0);
        assert_eq!(
            each.info().triangles,
            plain
                .patches
                .iter()
                .map(|p| p.triangles().count())
                .sum::<usize>()
        );
        let mut rng = crate::sampling::stream(3, 0, 0, 0);
        let centre = at([2.0, 2.5, 2.0]);
        let (mut hits, mut differ) = (0, 0);
        for _ in 0..200_000 {
            // From a random point of a box around the scene, towards a random point inside it.
            let mut r = || crate::sampling::uniform(&mut rng);
            let o = centre + Vec3::new(r() - 0.5, r() - 0.5, r() - 0.5) * 14.0;
            let target = centre + Vec3::new(r() - 0.5, r() - 0.5, r() - 0.5) * 6.0;
            let ray = Ray::new(o, (target - o).normalize());
            let (a, b) = (
                whole.closest_hit(&ray, f32::INFINITY),
                each.closest_hit(&ray, f32::INFINITY),
            );
            let (Some(a), Some(b)) = (a, b) else {
                assert_eq!(a, b, "{ray:?}");
                continue;
            };
            // A grazing ray's distance, and where it meets the plane, move by the rounding of
            // the coordinates over the cosine: left out.
            if ray
                .direction
                .dot(mesh.patches[b.patch as usize].normal)
                .abs()
                < 0.05
            {
                continue;
            }
            hits += 1;
            assert_eq!(a.front, b.front);
            // The same to the rounding of the coordinates (directions are unit vectors).
            let off = whole.ray_offset();
            assert!((a.t - b.t).abs() <= off, "{a:?} {b:?}");
            // Where the patch's triangle and coordinates put the point.
            let p = &mesh.patches[a.patch as usize];
            let [v0, v1, v2, v3] = p.vertices;
            let (v1, v2) = if a.sub == 0 { (v1, v2) } else { (v2, v3) };
            let [p0, p1, p2] = [v0, v1, v2].map(|v| mesh.vertices[v as usize]);
            let point = p0 + (p1 - p0) * a.u + (p2 - p0) * a.v;
            let met = ray.origin + ray.direction * a.t;
            assert!((point - met).length() < off, "{a:?}: {point} against {met}");
            let slack = 1e-3;
            assert!(
                a.u >= -slack && a.v >= -slack && a.u + a.v <= 1.0 + slack,
                "{a:?}"
            );
            if a.patch != b.patch {
                differ += 1;
                // Only at an edge: the point within rounding of the other's patch too.
                let q = &mesh.patches[b.patch as usize];
                let inside = q.triangles().any(|t| {
                    let [q0, q1, q2] = t.map(|v| mesh.vertices[v as usize]);
                    let n = (q1 - q0).cross(q2 - q0);
                    [(q0, q1), (q1, q2), (q2, q0)]
                        .iter()
                        .all(|&(x, y)| (y - x).cross(met - x).dot(n) >= -1e-4 * n.length())
                });
                assert!(inside, "{a:?} against {b:?}");
            } else if a.sub == b.sub {
                assert!(
                    (a.u - b.u).abs() < 1e-3 && (a.v - b.v).abs() < 1e-3,
                    "{a:?} {b:?}"
                );
            }
        }
        assert!(hits > 50_000, "{hits}");
        // The band within the rounding of an edge (a ray offset, 2.6 × 10⁻⁴ here) is about
        // 2 × 10⁻³ of a patch's width (0.13): only a small part of the rays can fall in it.
        assert!(differ * 1_000 < hits, "{differ} of {hits}");
        // Looking through a patch finds the next surface behind it, whichever way it is met.
        let down = Ray::new(at([2.03, 6.0, 1.97]), -Vec3::Y);
        let top = whole.closest_hit(&down, f32::INFINITY).unwrap();
        let floor = whole
            .closest_hit(&Ray::new(at([2.03, 1.0, 1.97]), -Vec3::Y), f32::INFINITY)
            .unwrap();
        assert!(whole.occluded_except(&down, 10.0, |_| false));
        assert!(whole.occluded_except(&down, 10.0, |k| k == top.patch));
        assert!(!whole.occluded_except(&down, 10.0, |k| k == top.patch
            || k == floor.patch
            || mesh.patches[k as usize].surface == 1));
    }

    #[test]
    fn build_is_the_same_on_any_number_of_threads() {
        // Every patch's triangles, not the pieces': enough of them to build in parallel.
        let mut mesh = Mesh::build(&builtin::cornell(), MeshParams::Patches(20_000)).unwrap();
        mesh.grids.clear();
        assert!(Bvh::build(&mesh).info().triangles > 2 * PARALLEL_MIN);
        let build = |threads| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            format!("{:?}", pool.install(|| Bvh::build(&mesh)))
        };
        let one = build(1);
        assert_eq!(one, build(2));
        assert_eq!(one, build(5));
    }

    pub(super) fn brute(mesh: &Mesh, ray: &Ray) -> Option<(f32, u32)> {
        let mut best: Option<(f32, u32)> = None;
        for (k, p) in mesh.patches.iter().enumerate() {
            for t in p.triangles() {
                let [a, b, c] = t.map(|i| mesh.vertices[i as usize]);
                let (e1, e2) = (b - a, c - a);
                let pv = ray.direction.cross(e2);
                let det = e1.dot(pv);
                if det.abs() < 1e-12 {
                    continue;
                }
                let s = ray.origin - a;
                let u = s.dot(pv) / det;
                let q = s.cross(e1);
                let v = ray.direction.dot(q) / det;
                let tt = e2.dot(q) / det;
                if u >= 0.0
                    && v >= 0.0
                    && u + v <= 1.0
                    && tt > 0.0
                    && best.is_none_or(|(bt, _)| tt < bt)
                {
                    best = Some((tt, k as u32));
                }
            }
        }
        best
    }

    #[test]
    fn agrees_with_brute_force() {
        let scene = builtin::cornell();
        let mesh = Mesh::build(&scene, MeshParams::Patches(800)).unwrap();
        let bvh = Bvh::build(&mesh);
        bvh.validate().unwrap();
        let mut rng = crate::sampling::stream(3, 0, 0, 0);
        let mut u = || crate::sampling::uniform(&mut rng);
        let mut agree = 0;
        let trials = 3000;
        for _ in 0..trials {
            let o = Vec3::new(20.0 + 500.0 * u(), 10.0 + 500.0 * u(), 10.0 + 500.0 * u());
            let d = Vec3::new(u() - 0.5, u() - 0.5, u() - 0.5).normalize();
            let ray = Ray::new(o, d);
            let a = bvh.closest_hit(&ray, f32::INFINITY).map(|h| (h.t, h.patch));
            let b = brute(&mesh, &ray);
            match (a, b) {
                (Some((ta, pa)), Some((tb, pb))) => {
                    assert!((ta - tb).abs() <= 1e-3 * tb.max(1.0), "{ta} vs {tb}");
                    if pa == pb {
                        agree += 1;
                    }
                }
                (None, None) => agree += 1,
                // Rays through shared edges may be caught by the slack on one side only.
                (Some((ta, _)), None) => assert!(ta > 0.0),
                (None, Some(_)) => panic!("BVH missed a hit"),
            }
        }
        // Disagreement on the patch is only possible for rays exactly through shared edges.
        assert!(agree as f64 >= 0.999 * trials as f64, "{agree}");
    }

    /// Spatial splits cut large triangles into parts (the Cornell box turned off the axes and
    /// lightly meshed, so that its triangles' boxes are loose), and the tree still finds every hit that a
    /// brute-force loop over the triangles finds, at the same distance, and the any-hit query
    /// agrees.
    #[test]
    fn spatial_splits_cut_triangles_and_lose_no_hit() {
        let turn = glam::Quat::from_axis_angle(Vec3::new(1.0, 2.0, 3.0).normalize(), 0.7);
        let centre = Vec3::splat(278.0);
        for params in [MeshParams::Patches(200), MeshParams::Patches(1000)] {
            let mut mesh = Mesh::build(&builtin::cornell(), params).unwrap();
            for v in &mut mesh.vertices {
                *v = centre + turn * (*v - centre);
            }
            let bvh = Bvh::build(&mesh);
            bvh.validate().unwrap();
            let info = bvh.info();
            assert!(info.references > info.triangles, "{info:?}");
            assert!(
                info.references as f64 <= info.triangles as f64 * (1.0 + SPLIT_BUDGET) + 1.0,
                "{info:?}"
            );
            let mut rng = crate::sampling::stream(8, 0, 0, 0);
            let mut u = || crate::sampling::uniform(&mut rng);
            let trials = 4000;
            let mut agree = 0;
            for _ in 0..trials {
                let o = Vec3::new(20.0 + 500.0 * u(), 10.0 + 500.0 * u(), 10.0 + 500.0 * u());
                let d = Vec3::new(u() - 0.5, u() - 0.5, u() - 0.5).normalize();
                let ray = Ray::new(o, d);
                let a = bvh.closest_hit(&ray, f32::INFINITY).map(|h| (h.t, h.patch));
                match (a, brute(&mesh, &ray)) {
                    (Some((ta, pa)), Some((tb, pb))) => {
                        assert!((ta - tb).abs() <= 1e-3 * tb.max(1.0), "{ta} vs {tb}");
                        agree += (pa == pb) as usize;
                        assert!(bvh.occluded(&ray, ta * 1.01));
                        assert!(!bvh.occluded(&ray, ta * 0.99));
                    }
                    (None, None) => agree += 1,
                    (Some((ta, _)), None) => assert!(ta > 0.0),
                    (None, Some(_)) => panic!("BVH missed a hit"),
                }
            }
            assert!(agree as f64 >= 0.999 * trials as f64, "{agree}");
        }
    }

    /// The statistics count what the hierarchy holds: every triangle in a leaf of at most
    /// MAX_LEAF (some in two or more, cut by spatial splits), the bytes those leaves and the
    /// nodes take.
    #[test]
    fn info_counts_what_it_holds() {
        let mut mesh = Mesh::build(&builtin::cornell(), MeshParams::Patches(3000)).unwrap();
        mesh.grids.clear();
        let bvh = Bvh::build(&mesh);
        let info = bvh.info();
        let tris: usize = mesh.patches.iter().map(|p| p.triangles().count()).sum();
        assert_eq!(info.triangles, tris);
        assert!(info.references >= tris, "{info:?}");
        assert!(
            info.leaves * MAX_LEAF >= info.references && info.leaves <= info.references,
            "{info:?}"
        );
        let used: usize = bvh.blocks[1..]
            .iter()
            .map(|b| b.id.iter().filter(|&&id| id != NO_TRIANGLE).count())
            .sum();
        assert_eq!(used, info.references);
        assert_eq!(info.node_bytes, info.nodes * 256);
        assert_eq!(info.bytes, info.node_bytes + (info.leaves + 1) * 192);
        // The SAH costs are expected counts of boxes that a uniformly random line through
        // the root's box crosses (Crofton: a convex body inside another is crossed with
        // probability the ratio of their surface areas). Such lines: a uniform point on the
        // root box's surface, a cosine-distributed direction into it. Counted by brute force
        // over every child box, they must agree within a few standard errors.
        let root = bvh.bounds;
        let ext = root.extent();
        let faces = [ext.y * ext.z, ext.x * ext.z, ext.x * ext.y];
        let mut rng = crate::sampling::stream(9, 0, 0, 0);
        let mut u = || crate::sampling::uniform(&mut rng);
        let lines = 20_000;
        // The root counts once per line.
        let (mut nodes, mut leaves) = (lines as f64, 0.0f64);
        let (mut sq_nodes, mut sq_leaves) = (0.0f64, 0.0f64);
        for _ in 0..lines {
            // A face (area-weighted), which side, a point on it, the inward normal.
            let pick = u() * (faces[0] + faces[1] + faces[2]);
            let axis = if pick < faces[0] {
                0
            } else if pick < faces[0] + faces[1] {
                1
            } else {
                2
            };
            let upper = u() < 0.5;
            let mut p = root.min + ext * Vec3::new(u(), u(), u());
            p[axis] = if upper {
                root.max[axis]
            } else {
                root.min[axis]
            };
            let mut n = Vec3::ZERO;
            n[axis] = if upper { -1.0 } else { 1.0 };
            let (t, b) = crate::geom::orthonormal_basis(n);
            let d = crate::sampling::cosine_direction_in(n, t, b, u(), u());
            let crosses = |lo: Vec3, hi: Vec3| {
                let (mut t0, mut t1) = (f64::NEG_INFINITY, f64::INFINITY);
                for a in 0..3 {
                    let (o, d) = (p[a] as f64, d[a] as f64);
                    let (l, h) = (lo[a] as f64, hi[a] as f64);
                    if d == 0.0 {
                        if o < l || o > h {
                            return false;
                        }
                    } else {
                        let (x, y) = ((l - o) / d, (h - o) / d);
                        t0 = t0.max(x.min(y));
                        t1 = t1.min(x.max(y));
                    }
                }
                t0 <= t1
            };
            let (mut my_nodes, mut my_leaves) = (1.0, 0.0);
            for node in &bvh.nodes {
                for (lane, &c) in node.child.iter().enumerate() {
                    if c == EMPTY_LANE {
                        continue;
                    }
                    let lo = Vec3::from_array([0, 1, 2].map(|a| node.planes[a][lane]));
                    let hi = Vec3::from_array([3, 4, 5].map(|a| node.planes[a][lane]));
                    if crosses(lo, hi) {
                        if c & LEAF == 0 {
                            my_nodes += 1.0;
                        } else {
                            my_leaves += 1.0;
                        }
                    }
                }
            }
            nodes += my_nodes - 1.0;
            leaves += my_leaves;
            sq_nodes += my_nodes * my_nodes;
            sq_leaves += my_leaves * my_leaves;
        }
        let m = lines as f64;
        let (nodes, leaves) = (nodes / m, leaves / m);
        let sigma = |mean: f64, sq: f64| ((sq / m - mean * mean) / m).sqrt();
        let (sn, sl) = (sigma(nodes, sq_nodes), sigma(leaves, sq_leaves));
        assert!(
            (nodes - info.sah_nodes).abs() < 4.0 * sn,
            "{nodes} ± {sn}: {info:?}"
        );
        assert!(
            (leaves - info.sah_leaves).abs() < 4.0 * sl,
            "{leaves} ± {sl}: {info:?}"
        );
    }

    /// The two box tests (lane by lane, for CPUs without AVX2, and the fused AVX2 one the
    /// queries use where the CPU has it) lead to the same hits: the lane-by-lane one is
    /// otherwise exercised only on such CPUs.
    #[test]
    fn both_box_tests_find_the_same_hits() {
        let mesh = Mesh::build(&builtin::cornell(), MeshParams::Patches(3000)).unwrap();
        let bvh = Bvh::build(&mesh);
        let mut rng = crate::sampling::stream(5, 0, 0, 0);
        let mut u = || crate::sampling::uniform(&mut rng);
        for _ in 0..20_000 {
            let o = Vec3::new(20.0 + 500.0 * u(), 10.0 + 500.0 * u(), 10.0 + 500.0 * u());
            let d = Vec3::new(u() - 0.5, u() - 0.5, u() - 0.5).normalize();
            let ray = Ray::new(o, d);
            let a = bvh.closest_hit_in::<false>(&ray, f32::INFINITY);
            assert_eq!(a, bvh.closest_hit(&ray, f32::INFINITY), "{ray:?}");
            let blocked = bvh.any_hit_except_in::<false, true>(&ray, 300.0, |_| false);
            assert_eq!(blocked.is_some(), bvh.occluded(&ray, 300.0), "{ray:?}");
        }
    }

    /// Rays aimed just inside the corners of triangles (which lie on their leaves' box
    /// faces) of a Cornell box moved far from the origin, where the fused box test's
    /// `o·inv` is large and its rounding would otherwise cut the boxes short: the BVH
    /// misses nothing that brute force finds. A third of the rays run almost along an axis
    /// (tiny direction components, huge inverses).
    #[test]
    fn box_test_is_conservative_far_from_the_origin() {
        // The patches' own triangles, which the brute force below tests.
        let mut mesh = Mesh::build(&builtin::cornell(), MeshParams::Patches(2000)).unwrap();
        mesh.grids.clear();
        let shift = Vec3::new(3.0e4, -2.0e4, 1.0e4);
        for v in &mut mesh.vertices {
            *v += shift;
        }
        let bvh = Bvh::build(&mesh);
        bvh.validate().unwrap();
        let mut rng = crate::sampling::stream(11, 0, 0, 0);
        let mut u = || crate::sampling::uniform(&mut rng);
        let mut trials = 0;
        for (k, p) in mesh.patches.iter().enumerate() {
            for [a, b, c] in p.triangles() {
                let [a, b, c] = [a, b, c].map(|i| mesh.vertices[i as usize]);
                for corner in [[a, b, c], [b, c, a], [c, a, b]] {
                    let target = corner[0] * 0.998 + corner[1] * 0.001 + corner[2] * 0.001;
                    let o = shift
                        + Vec3::new(30.0 + 490.0 * u(), 30.0 + 490.0 * u(), 30.0 + 490.0 * u());
                    let mut d = target - o;
                    if trials % 3 == 0 {
                        // Nearly along the axis the target is farthest on.
                        let m = d.abs().max_element();
                        d = Vec3::select(d.abs().cmpeq(Vec3::splat(m)), d, d * 1e-7);
                    }
                    let dist = d.length();
                    let ray = Ray::new(o, d / dist);
                    trials += 1;
                    let hit = bvh.closest_hit(&ray, f32::INFINITY);
                    let brute_hit = brute(&mesh, &ray);
                    match (hit, brute_hit) {
                        (Some(h), Some((tb, _))) => {
                            assert!((h.t - tb).abs() <= 1e-3 * tb.max(1.0), "{} vs {tb}", h.t)
                        }
                        (None, Some((tb, _))) => panic!("patch {k}: BVH missed a hit at {tb}"),
                        _ => {}
                    }
                }
            }
        }
        assert!(trials > 10_000, "{trials}");
    }

    /// Rays aimed at the midpoints of the edges that small patches share, far from the
    /// origin (the 40,000-patch Cornell box: coordinates up to 560, patches of 3), from
    /// points inside the closed part of the box: every one hits something. With a fixed
    /// barycentric slack of 1e-6, `f32` rounding let 192 of these 12,481 rays slip through
    /// (and 3 in 2 × 10⁶ random form-factor rays).
    #[test]
    fn shared_edges_leave_no_crack() {
        let mesh = Mesh::build(&builtin::cornell(), MeshParams::Patches(40_000)).unwrap();
        let bvh = Bvh::build(&mesh);
        let mut rng = crate::sampling::stream(5, 0, 0, 0);
        let mut u = || crate::sampling::uniform(&mut rng);
        // The floor's edges, by their end points; those met twice are shared.
        let mut edges = std::collections::BTreeMap::new();
        for p in mesh.patches.iter().filter(|p| p.surface == 0) {
            let k = if p.vertices[3] == crate::mesh::Patch::NONE {
                3
            } else {
                4
            };
            for e in 0..k {
                let a = mesh.vertices[p.vertices[e] as usize];
                let b = mesh.vertices[p.vertices[(e + 1) % k] as usize];
                let key = |v: Vec3| v.to_array().map(f32::to_bits);
                let (ka, kb) = (key(a), key(b));
                edges
                    .entry(if ka < kb { (ka, kb) } else { (kb, ka) })
                    .or_insert((0, a, b))
                    .0 += 1;
            }
        }
        let (mut rays, mut slipped) = (0, Vec::new());
        for &(_, a, b) in edges.values().filter(|e| e.0 == 2) {
            {
                let target = 0.5 * (a + b);
                // Inside the box, above the floor, away from the open front.
                let o = Vec3::new(50.0 + 450.0 * u(), 100.0 + 400.0 * u(), 300.0 + 200.0 * u());
                let ray = Ray::new(o, (target - o).normalize());
                if bvh.closest_hit(&ray, f32::INFINITY).is_none() {
                    slipped.push(target);
                }
                rays += 1;
            }
        }
        assert!(rays > 10_000, "{rays}");
        assert!(
            slipped.is_empty(),
            "{} of {rays} rays slipped through edges at {slipped:?}",
            slipped.len()
        );
    }

    /// Two coincident copies of a surface: every ray meets both at the same distance, and
    /// the copy with the lower patch number wins from either side, whatever order the
    /// traversal meets them in; so a solver that asks from above which copy receives light
    /// and from below which copy is covered gets answers that agree.
    #[test]
    fn coincident_copies_resolve_the_same_way_from_both_sides() {
        let mut scene = builtin::cornell();
        scene.polygons.push(scene.polygons[0].clone());
        let copy = scene.polygons.len() as u32 - 1;
        let mesh = Mesh::build(&scene, MeshParams::Patches(3000)).unwrap();
        let bvh = Bvh::build(&mesh);
        let off = bvh.ray_offset();
        let first_copy = mesh.patches.iter().position(|p| p.surface == copy).unwrap() as u32;
        let mut rng = crate::sampling::stream(6, 0, 0, 0);
        let mut u = || crate::sampling::uniform(&mut rng);
        let mut checked = 0;
        for (i, p) in mesh.patches.iter().enumerate() {
            if p.surface != 0 {
                continue;
            }
            assert!((i as u32) < first_copy);
            let point = mesh.sample_point(i, u(), u(), u());
            let o = Vec3::new(50.0 + 450.0 * u(), 100.0 + 400.0 * u(), 300.0 + 200.0 * u());
            let from_above = bvh.closest_hit(&Ray::new(o, (point - o).normalize()), f32::INFINITY);
            let from_below =
                bvh.closest_hit(&Ray::new(point - p.normal * off, p.normal), 2.0 * off);
            for h in [from_above, from_below] {
                let h = h.expect("the floor is hit");
                if mesh.patches[h.patch as usize].surface == 0 || h.patch >= first_copy {
                    assert!(h.patch < first_copy, "the copy won a tie");
                }
            }
            checked += 1;
        }
        assert!(checked > 100);
    }

    /// A ray with a NaN in its origin or direction meets nothing, and no query panics.
    #[test]
    fn nan_rays_meet_nothing() {
        let mesh = Mesh::build(&builtin::cornell(), MeshParams::Patches(800)).unwrap();
        let bvh = Bvh::build(&mesh);
        let o = Vec3::new(278.0, 274.0, 280.0);
        for ray in [
            Ray::new(Vec3::new(f32::NAN, 274.0, 280.0), Vec3::Y),
            Ray::new(o, Vec3::new(0.0, f32::NAN, 1.0)),
            Ray::new(Vec3::splat(f32::NAN), Vec3::splat(f32::NAN)),
        ] {
            assert_eq!(bvh.closest_hit(&ray, f32::INFINITY), None);
            assert!(!bvh.occluded(&ray, f32::INFINITY));
            assert_eq!(bvh.any_hit_except(&ray, 1e3, |_| false), None);
        }
        // And a finite ray still hits.
        assert!(bvh
            .closest_hit(&Ray::new(o, Vec3::Y), f32::INFINITY)
            .is_some());
    }

    /// Several rays in flight find exactly what one ray at a time finds, in every batch size
    /// (fewer rays than lanes, a lane refilled, lanes drained), with finite and infinite
    /// reach, NaN rays among them, and on an empty hierarchy.
    #[test]
    fn closest_hits_agree_with_closest_hit() {
        let mesh = Mesh::build(&builtin::cornell(), MeshParams::Patches(3000)).unwrap();
        let bvh = Bvh::build(&mesh);
        let mut rng = crate::sampling::stream(11, 0, 0, 0);
        let mut u = || crate::sampling::uniform(&mut rng);
        let mut rays: Vec<Ray> = (0..600)
            .map(|_| {
                let o = Vec3::new(556.0 * u(), 548.0 * u(), 559.0 * u());
                let d = Vec3::new(u() - 0.5, u() - 0.5, u() - 0.5);
                Ray::new(o, d.normalize_or(Vec3::Y))
            })
            .collect();
        rays[5] = Ray::new(Vec3::splat(f32::NAN), Vec3::Y);
        rays[17] = Ray::new(
            Vec3::new(278.0, 274.0, 280.0),
            Vec3::new(0.0, f32::NAN, 1.0),
        );
        for t_max in [f32::INFINITY, 150.0] {
            let one: Vec<_> = rays.iter().map(|r| bvh.closest_hit(r, t_max)).collect();
            // Inside the closed box every finite ray hits a wall, unless the reach stops it.
            let hits = one.iter().filter(|h| h.is_some()).count();
            assert!(hits > 100 && hits < 600, "{hits} hits within {t_max}");
            for len in [0, 1, 2, 7, IN_FLIGHT, IN_FLIGHT + 1, 33, 600] {
                let mut out = vec![None; len];
                bvh.closest_hits(&rays[..len], t_max, &mut out);
                assert_eq!(out, one[..len], "{len} rays, reach {t_max}");
                // The interleaved traversal itself: this tree is below the size from which
                // `closest_hits` chooses it.
                assert!(bvh.bytes() < INTERLEAVE_FROM);
                let mut out = vec![None; len];
                bvh.interleaved::<NATIVE_AVX>(&rays[..len], t_max, &mut out);
                assert_eq!(out, one[..len], "{len} rays interleaved, reach {t_max}");
            }
        }
        let empty = Bvh::build(&Mesh::default());
        let mut out = vec![
            Some(Hit {
                t: 1.0,
                patch: 0,
                sub: 0,
                u: 0.0,
                v: 0.0,
                front: true,
            });
            3
        ];
        empty.closest_hits(&rays[..3], f32::INFINITY, &mut out);
        assert_eq!(out, vec![None; 3]);
        out[1] = Some(Hit {
            t: 2.0,
            patch: 1,
            sub: 1,
            u: 0.5,
            v: 0.5,
            front: false,
        });
        empty.interleaved::<NATIVE_AVX>(&rays[..3], f32::INFINITY, &mut out);
        assert_eq!(out, vec![None; 3]);
    }

    /// Coordinates so large that every box's surface area overflows to ∞ still give a valid
    /// hierarchy (the collapse's costs are all ∞ and it must still share out the slots).
    #[test]
    fn huge_coordinates_build_a_valid_tree() {
        let mesh = Mesh::build(&builtin::cornell(), MeshParams::Patches(300)).unwrap();
        let mut huge = mesh.clone();
        for v in &mut huge.vertices {
            *v *= 1e34;
        }
        let bvh = Bvh::build(&huge);
        bvh.validate().unwrap();
        // (Möller–Trumbore's products overflow at this scale: rays need not hit, but must
        // not panic either.)
        let o = Vec3::new(278.0, 274.0, 280.0) * 1e34;
        let _ = bvh.closest_hit(&Ray::new(o, Vec3::Y), f32::INFINITY);
        let _ = bvh.occluded(&Ray::new(o, Vec3::Y), f32::INFINITY);
    }

    #[test]
    fn hit_side_is_reported() {
        let scene = builtin::cornell();
        let mesh = Mesh::build(&scene, MeshParams::Faces).unwrap();
        let bvh = Bvh::build(&mesh);
        // From inside the box straight down: the floor's front side.
        let h = bvh
            .closest_hit(
                &Ray::new(Vec3::new(100.0, 400.0, 500.0), -Vec3::Y),
                f32::INFINITY,
            )
            .unwrap();
        assert!(h.front);
        assert!((h.t - 400.0).abs() < 1e-3);
        // From below the floor going up: its back side.
        let h = bvh
            .closest_hit(
                &Ray::new(Vec3::new(100.0, -10.0, 500.0), Vec3::Y),
                f32::INFINITY,
            )
            .unwrap();
        assert!(!h.front);
    }
}

#[cfg(test)]
mod occlusion_tests {
    use super::*;
    use crate::mesh::{Mesh, MeshParams};
    use crate::sampling::{stream, uniform};

    /// The any-hit query agrees with the closest hit on random rays and bounds: something lies
    /// on the ray before t_max exactly when the closest hit does.
    #[test]
    fn occluded_agrees_with_closest_hit() {
        let scene = crate::scene::builtin::by_name("cornell").unwrap();
        let mesh = Mesh::build(&scene, MeshParams::Patches(2000)).unwrap();
        let bvh = Bvh::build(&mesh);
        let mut rng = stream(3, 1, 4, 1);
        let c = bvh.bounds().centre();
        let size = bvh.bounds().diagonal();
        let mut disagree = 0;
        for _ in 0..4_000 {
            let o = c + Vec3::new(
                uniform(&mut rng) - 0.5,
                uniform(&mut rng) - 0.5,
                uniform(&mut rng) - 0.5,
            ) * size
                * 0.4;
            let d = Vec3::new(
                uniform(&mut rng) - 0.5,
                uniform(&mut rng) - 0.5,
                uniform(&mut rng) - 0.5,
            )
            .normalize();
            let t_max = uniform(&mut rng) * size;
            let ray = Ray::new(o, d);
            let closest = bvh
                .closest_hit(&ray, f32::INFINITY)
                .map_or(f32::INFINITY, |h| h.t);
            // Away from the bound (where rounding may decide), the two must agree.
            if (closest - t_max).abs() > 1e-4 * size
                && bvh.occluded(&ray, t_max) != (closest < t_max)
            {
                disagree += 1;
            }
            // Looking through nothing is `occluded`; looking through the first patch met
            // leaves whatever lies beyond it (the closest hit of the rest, by brute force).
            if bvh.occluded_except(&ray, t_max, |_| false) != bvh.occluded(&ray, t_max) {
                disagree += 1;
            }
            // Where the any-hit query stops is a real intersection in range: at or beyond the
            // closest one (by brute force), and itself a hit of the ray.
            if let Some(t) = bvh.any_hit_except(&ray, t_max, |_| false) {
                let at = super::tests::brute(&mesh, &Ray::new(o + d * (t - 1e-3 * size), d));
                if t >= t_max
                    || t < closest - 1e-5 * size
                    || at.is_none_or(|(s, _)| s > 2e-3 * size)
                {
                    disagree += 1;
                }
            }
            if let Some(first) = bvh.closest_hit(&ray, f32::INFINITY) {
                let mut rest = mesh.clone();
                rest.patches.remove(first.patch as usize);
                let beyond = super::tests::brute(&rest, &ray).map_or(f32::INFINITY, |(t, _)| t);
                if (beyond - t_max).abs() > 1e-4 * size
                    && bvh.occluded_except(&ray, t_max, |p| p == first.patch) != (beyond < t_max)
                {
                    disagree += 1;
                }
            }
        }
        assert_eq!(disagree, 0);
    }
}
