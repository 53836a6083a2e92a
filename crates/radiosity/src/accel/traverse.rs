//! The queries: closest hit, one ray at a time or several interleaved, and any hit. The
//! traversal is iterative; every child met is prefetched into the cache at once; the
//! children met are ordered nearest first by branch-free sorting networks (with fast paths
//! for one and two), pushed without branches, and skipped when they begin beyond the
//! closest hit.

use super::intersect::{lanes_hit, lanes_hit_front_slack, Ray4};
use super::node::{WideNode, LEAF, WIDTH};
#[cfg(all(target_arch = "x86_64", not(target_feature = "avx2")))]
use super::simd::dispatch;
use super::simd::NATIVE_AVX;
use super::stack::Stack;
use super::{Bvh, Hit};
use crate::geom::Ray;

/// Relative distance within which two hits count as one (a ray through a shared edge).
pub(super) const TIE: f32 = 1e-6;

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

/// Sorting networks for three and four keys: the fewest compare-exchanges (Knuth, TAOCP
/// vol. 3, §5.3.4).
const SORT3: [(usize, usize); 3] = [(0, 1), (1, 2), (0, 1)];
/// See [`SORT3`].
const SORT4: [(usize, usize); 5] = [(0, 1), (2, 3), (0, 2), (1, 3), (1, 2)];

/// The keys of the `K` children met (`mask` has exactly `K` bits), as [`sorted_keys`] makes
/// them, sorted nearest first by the network `net`. Most nodes a ray enters with more than
/// two children met have three or four, which the eight-key network costs five to six times
/// as many compare-exchanges (docs/notes/accel.md).
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
/// cache (measurements: docs/notes/accel.md).
pub const IN_FLIGHT: usize = 16;

/// Bytes of hierarchy from which [`Bvh::closest_hits`] interleaves its rays. Below, one ray at
/// a time is as fast or faster: the interleaving costs about what the overlap of memory waits
/// saves while most of the tree sits in the L2 cache (docs/notes/accel.md).
pub(super) const INTERLEAVE_FROM: usize = 12 << 20;

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
    pub(super) fn closest_hit_in<const AVX: bool>(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
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
    /// to BVH traversal): on a tree far larger than the cache, more than twice the rays per
    /// second on one thread. Where most of the tree fits the L2 cache it gains nothing, so
    /// smaller hierarchies cast one ray at a time. Rays that share an origin (a row of form
    /// factors) gain less, their common path being in the cache already (figures:
    /// docs/notes/accel.md).
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
    pub(super) fn closest_hits_in<const AVX: bool>(
        &self,
        rays: &[Ray],
        t_max: f32,
        out: &mut [Option<Hit>],
    ) {
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

    /// [`Bvh::closest_hits`] with [`IN_FLIGHT`] rays interleaved a visit at a time, whatever
    /// the hierarchy's size; `rays` and `out` have the same length.
    #[inline(always)]
    pub(super) fn interleaved<const AVX: bool>(
        &self,
        rays: &[Ray],
        t_max: f32,
        out: &mut [Option<Hit>],
    ) {
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
    /// met farthest first (in a closed scene the far ones hold the surface the ray ends on;
    /// docs/notes/accel.md), so it does less work than [`Bvh::closest_hit`] on the same ray.
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
    /// lies well before the target; docs/notes/accel.md).
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
    pub(super) fn any_hit_except_in<const AVX: bool, const FAR_FIRST: bool>(
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
}
