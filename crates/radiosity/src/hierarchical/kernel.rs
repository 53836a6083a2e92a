//! The transfer coefficient of one link, evaluated at sixteen jittered points of its receiver.
//!
//! - From an element: the exact unoccluded factor from a point to a polygon (Lambert's contour
//!   formula, e.g. Baum, Rushmeier & Winget 1989, eq. 3) times the fraction of rays from the
//!   point to points on the source that arrive unoccluded, each ray weighted by the kernel at
//!   its end (so the fraction is the kernel's, not the area's), drawn on the part of the
//!   source in front of the point.
//! - From a cluster: a Monte Carlo estimate of the same point-to-area factor over the cluster's
//!   surfaces, points drawn by area (from its emitters and from its other surfaces
//!   separately), each weighted by both cosines (a surface facing away sends nothing) and its
//!   visibility; the pieces the samples saw, and their parts of the factor, are what the
//!   link gathers from.
//!
//! The coefficient `k` of the link is the mean over the receiver's points, and what the
//! refinement oracle needs is kept beside it (the largest and smallest point value, whether
//! any ray was blocked, and the largest value visibility aside).

use super::cluster::{Clusters, CLUSTER};
use super::element::{Element, POINTS};
use crate::accel::Bvh;
use crate::geom::{Ray, Vec3};
use crate::sampling::{stream, uniform, Rng64};
use glam::DVec3;
use std::f64::consts::PI;

/// The angle `atan2(y, x)` for `y ≥ 0` (in [0, π]), to within 10⁻⁹ relative: the angle an
/// edge subtends in Lambert's contour formula, a hot spot where `libm`'s `atan2` is slow
/// (`docs/notes/hierarchical.md`). Reduced to [0, 1] by symmetry, then to |t| ≤ tan(π/12) by
/// `atan u = π/6 + atan((u√3 − 1)/(u + √3))`, where the Taylor series to t¹³ errs by at most
/// t¹⁵/15 < 2·10⁻¹⁰.
#[inline]
fn angle(y: f64, x: f64) -> f64 {
    use std::f64::consts::{FRAC_PI_2, FRAC_PI_6};
    const SQRT3: f64 = 1.732_050_807_568_877_2;
    const TAN_PI_12: f64 = 0.267_949_192_431_122_7;
    let (ax, ay) = (x.abs(), y.abs());
    let (lo, hi) = if ay <= ax { (ay, ax) } else { (ax, ay) };
    if hi <= 0.0 {
        return 0.0;
    }
    let u = lo / hi;
    let (t, base) = if u > TAN_PI_12 {
        ((u * SQRT3 - 1.0) / (u + SQRT3), FRAC_PI_6)
    } else {
        (u, 0.0)
    };
    let t2 = t * t;
    let series = t
        * (1.0
            + t2 * (-1.0 / 3.0
                + t2 * (1.0 / 5.0
                    + t2 * (-1.0 / 7.0 + t2 * (1.0 / 9.0 + t2 * (-1.0 / 11.0 + t2 / 13.0))))));
    let mut a = base + series;
    if ay > ax {
        a = FRAC_PI_2 - a;
    }
    if x < 0.0 {
        a = std::f64::consts::PI - a;
    }
    a
}

/// The unoccluded form factor from a differential area at `x` (unit normal `n`) to the convex
/// polygon `poly` (counter-clockwise about its unit normal `ns`). One-sided both ways: zero when
/// `x` is behind the polygon, and only the polygon's part in front of `x`'s plane counts.
pub fn point_polygon(x: Vec3, n: Vec3, poly: &[Vec3], ns: Vec3) -> f64 {
    let (x, n) = (x.as_dvec3(), n.as_dvec3());
    if (x - poly[0].as_dvec3()).dot(ns.as_dvec3()) <= 0.0 {
        return 0.0;
    }
    // Clip to the half-space in front of x (Sutherland–Hodgman against one plane).
    let mut clipped = [DVec3::ZERO; 8];
    let mut m = 0;
    let k = poly.len();
    for i in 0..k {
        let (p, q) = (poly[i].as_dvec3() - x, poly[(i + 1) % k].as_dvec3() - x);
        let (dp, dq) = (p.dot(n), q.dot(n));
        if dp > 0.0 {
            clipped[m] = p;
            m += 1;
        }
        if (dp > 0.0) != (dq > 0.0) {
            let t = dp / (dp - dq);
            clipped[m] = p + (q - p) * t;
            m += 1;
        }
    }
    if m < 3 {
        return 0.0;
    }
    let mut sum = 0.0;
    for i in 0..m {
        let (p, q) = (clipped[i], clipped[(i + 1) % m]);
        let c = p.cross(q);
        let len = c.length();
        if len <= 0.0 {
            continue;
        }
        let gamma = angle(len, p.dot(q));
        sum += gamma * n.dot(c) / len;
    }
    (sum.abs() / (2.0 * PI)).min(1.0)
}

/// A link's coefficient and the oracle's view of it.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Estimate {
    /// The mean over the receiver's points: the fraction of the receiver's energy that would
    /// reach the source, `F_rs`.
    pub k: f32,
    /// The mean over the points in each of the receiver's four children (in child order):
    /// what each child's part of the receiver gathers.
    pub quarters: [f32; 4],
    /// The largest point value.
    pub hi: f32,
    /// The smallest point value.
    pub lo: f32,
    /// Rays cast.
    pub rays: u32,
    /// Some ray was blocked: the source is hidden from some points, wholly or in part, and
    /// the points cannot tell how much of the receiver is in shadow.
    pub blocked: bool,
    /// The largest point value with every ray counted as arriving: the kernel's bound when
    /// visibility is uncertain.
    pub unoccluded: f32,
    /// From an element: the share of `k` that comes from each of the source's four children
    /// (in child order, summing to 1): where on the source the receiver's view falls, so that
    /// the link can gather from the source's parts rather than from their mean. Even shares
    /// from a cluster.
    pub sources: [f32; 4],
    /// From a cluster, in a kept estimate: the root pieces that the samples seen from the
    /// receiver fell on, each with its share of `k` (summing to 1), so that the link gathers
    /// what the surfaces it sees send, not the mean of all the cluster's surfaces.
    pub seen: Vec<(u32, f32)>,
}

/// What link estimation reads.
pub struct Context<'a> {
    /// Every element.
    pub elements: &'a [Element],
    /// The clusters over the roots.
    pub clusters: &'a Clusters,
    /// The hierarchy over the input pieces, for visibility.
    pub bvh: &'a Bvh,
    /// Rays per receiver point.
    pub rays: u32,
    /// Seed of the visibility streams.
    pub seed: u64,
    /// Which input pieces emit.
    pub emits: &'a [bool],
    /// The first of each input piece's coincident twins (itself when it has none,
    /// [`super::element::Element::twins`]): a ray that meets a twin of its target has met
    /// the target, and only the first of a group sends (the light of all).
    pub twin_of: &'a [u32],
    /// What each element sends now (channel mean; [`super::Hierarchy::sent`]) times its
    /// area: the weights that visibility samples on a source are drawn by
    /// (`Context::power_point`). Empty: by area alone.
    pub power: &'a [f32],
}

/// How much of an element light can reach ([`cover`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cover {
    /// The fraction not inside a closed solid (the floor under a box standing on it): a
    /// covered point can neither receive nor send light, so the mean radiosity a source shows
    /// is taken over its exposed part, and a leaf's reflected light is what it gathered
    /// divided by this fraction (its covered points gathered nothing).
    pub exposed: f32,
    /// The fraction both exposed and open in front: not under another polygon lying flush
    /// against the surface (a panel on a wall, a cabinet's bottom on the floor), where
    /// gathering from points lifted off the surface would see through the cover. What arrives
    /// at the element is what it gathered × `free / exposed`.
    pub free: f32,
}

/// The cover of element `e` (id `id`) at its sixteen jittered receiver points
/// ([`Element::receiver_points`]). A point is *inside a solid* when two rays (along the
/// normal and one cosine-distributed) both first meet the back of a surface, and *under a
/// flush polygon* when a ray from just behind it through the surface meets another polygon
/// within a few ray offsets, front or back. The piece's own coincident twins (`coincident`,
/// as [`super::element::Element::twins`] groups them) do not cover it: they are the same
/// surface, and the ray goes on past them. Both tests at the same points, so that a solid's
/// face lying flush (inside the solid and under the face at once) is not counted twice; and
/// sixteen points rather than four, because a leaf across a box's edge sends in inverse
/// proportion to its exposed fraction.
pub fn cover(e: &Element, id: u32, bvh: &Bvh, coincident: &[u32], seed: u64) -> Cover {
    let mut rng = stream(seed, id as u64, 0, 0x4558_504f);
    let jitter: [f32; 2 * POINTS] = std::array::from_fn(|_| uniform(&mut rng));
    let off = bvh.ray_offset();
    let (t, b) = crate::geom::orthonormal_basis(e.normal);
    let group = coincident[e.root as usize];
    let (mut exposed, mut free) = (0, 0);
    for x in e.receiver_points(&jitter) {
        let d = crate::sampling::cosine_direction_in(
            e.normal,
            t,
            b,
            uniform(&mut rng),
            uniform(&mut rng),
        );
        let inside = [e.normal, d]
            .iter()
            .all(|&dir| first_hit_is_a_back(x + e.normal * off, dir, bvh, coincident, group));
        if inside {
            continue;
        }
        exposed += 1;
        if !under_flush(x, e.normal, bvh, coincident, group) {
            free += 1;
        }
    }
    Cover {
        exposed: exposed as f32 / POINTS as f32,
        free: free as f32 / POINTS as f32,
    }
}

/// Whether the first surface the ray from `from` along `d` meets, other than the piece's own
/// (its coincident group `group`), shows its back ([`cover`]). The piece's own triangles are
/// looked through: the points of a warped quad lie on its bilinear surface, up to millimetres
/// behind the triangles that the hierarchy holds, whose backs they would otherwise see.
fn first_hit_is_a_back(mut from: Vec3, d: Vec3, bvh: &Bvh, coincident: &[u32], group: u32) -> bool {
    let off = bvh.ray_offset();
    for _ in 0..8 {
        match bvh.closest_hit(&Ray::new(from, d), f32::INFINITY) {
            Some(h) if coincident[h.patch as usize] == group => from += d * (h.t + off),
            Some(h) => return !h.front,
            None => return false,
        }
    }
    false
}

/// Whether a polygon facing the same way as `x`'s surface (normal `n`), other than `group`'s
/// coincident twins, lies within a few ray offsets of `x`, in front or behind ([`cover`]).
/// Seen along `n`, such a polygon shows its back. One that shows its front faces the other
/// way: it is the far side of a wall of no thickness (two one-sided polygons back to back,
/// as MGF's two-sided surfaces become), which hides nothing in front of `x`, and the ray goes
/// on past it. (A solid's face lying face down on `x`, a cabinet's bottom on the floor, is
/// found by the inside-a-solid test before this one.)
fn under_flush(x: Vec3, n: Vec3, bvh: &Bvh, coincident: &[u32], group: u32) -> bool {
    let off = bvh.ray_offset();
    let mut from = x - n * (2.0 * off);
    let mut reach = 8.0 * off;
    // Past the piece's twins and back-to-back partners (a few at most), to what lies beyond.
    for _ in 0..8 {
        match bvh.closest_hit(&Ray::new(from, n), reach) {
            Some(h) if h.front || coincident[h.patch as usize] == group => {
                let step = h.t + 0.25 * off;
                from += n * step;
                reach -= step;
                if reach <= 0.0 {
                    return false;
                }
            }
            Some(_) => return true,
            None => return false,
        }
    }
    false
}

/// Where the ray from `x` along `d` meets the front of element `s`, if it does.
fn hit_polygon(x: Vec3, d: Vec3, s: &Element) -> Option<Vec3> {
    let denom = d.dot(s.normal);
    if denom >= 0.0 {
        return None;
    }
    let t = (s.corners[0] - x).dot(s.normal) / denom;
    if t.is_nan() || t <= 0.0 {
        return None;
    }
    let y = x + d * t;
    let poly = s.polygon();
    let k = poly.len();
    (0..k)
        .all(|i| {
            (poly[(i + 1) % k] - poly[i])
                .cross(y - poly[i])
                .dot(s.normal)
                >= 0.0
        })
        .then_some(y)
}

/// The four children of a source element, as polygons, for the share of a point's factor
/// that each receives ([`Estimate::sources`]).
struct Parts {
    corners: [[Vec3; 4]; 4],
    n: usize,
}

impl Parts {
    fn of(e: &Element) -> Self {
        Self {
            corners: e.child_corners(),
            n: if e.tri { 3 } else { 4 },
        }
    }

    /// The exact unoccluded factor from `x` (normal `n`) to each child.
    fn factors(&self, x: Vec3, n: Vec3, ns: Vec3) -> [f64; 4] {
        std::array::from_fn(|q| point_polygon(x, n, &self.corners[q][..self.n], ns))
    }

    /// The differential kernel from `x` (normal `n`) to each child's centre, times its area:
    /// the children's shares from a distant receiver, up to a common factor.
    fn far(&self, x: Vec3, n: Vec3, ns: Vec3) -> [f64; 4] {
        std::array::from_fn(|q| {
            let c = Element::new(self.corners[q], self.n == 3, 0, 0, 0);
            let d = c.centre - x;
            let d2 = d.length_squared() as f64;
            let w = (n.dot(d) as f64).max(0.0) * (-ns.dot(d) as f64).max(0.0) / (d2 * d2);
            if w.is_finite() {
                w * c.area as f64
            } else {
                0.0
            }
        })
    }
}

/// One receiver point in each quarter of an element ([`Element::receiver_points`]; the
/// quarters of [`quarter`]): for quads, on the 4 × 4 grid (i, j) = (0, 0), (2, 1), (1, 2),
/// (3, 3); for triangles, the first point of each child's four.
const ONE_PER_QUARTER: [usize; 4] = [0, 6, 9, 15];

/// The child of an element that holds its receiver point `p` ([`Element::receiver_points`]).
fn quarter(tri: bool, p: usize) -> usize {
    if tri {
        p / 4
    } else {
        // Points on a 4 × 4 grid, p = i + 4 j; children (0,0), (1,0), (1,1), (0,1).
        let (i, j) = ((p % 4) / 2, (p / 4) / 2);
        [[0, 3], [1, 2]][i][j]
    }
}

impl Context<'_> {
    /// Whether `y`, a point on input piece `piece`, is what `x` (on a surface of normal `nx`)
    /// sees first in its direction: the closest hit of the ray from `x` towards `y` must be
    /// the front of `piece`. Asking only whether the segment is free would see both of two
    /// coincident polygons and count their light twice; so of coincident reflectors only the
    /// one the hierarchy reports first is seen. Coincident *emitters* are all seen (a hit at
    /// the target's distance counts), as the shooting methods and the path tracer's next-event
    /// estimation count every emitter's power.
    fn visible(&self, x: Vec3, nx: Vec3, own: u32, y: Vec3, piece: u32) -> bool {
        let off = self.bvh.ray_offset();
        let from = x + nx * off;
        let d = y - from;
        let dist = d.length();
        if dist <= 4.0 * off {
            return true;
        }
        let dir = d / dist;
        // Anything else well before the target is in the way, whichever side it shows: the
        // any-hit query, cheaper than the closest hit, answers for all but the last stretch,
        // where the target, its twins, coincident emitters and polygons flush over it lie;
        // there the closest hit decides. The target's own group and the receiver's (`own`)
        // are looked through on the way: a point sampled on the bilinear surface of a warped
        // quad may lie millimetres behind its triangles, a receiver point as well as a target.
        let group = self.twin_of[piece as usize];
        let tolerance = 1e-4 * dist + 4.0 * off;
        let near = dist - 2.0 * tolerance;
        // (Only when that leaves the last stretch's start in front of `from`.)
        let end = dist * 1.001 + 4.0 * off;
        let mut start = if near > off {
            let skip = |p: u32| {
                let g = self.twin_of[p as usize];
                g == group || g == own
            };
            // One any-hit query over the whole ray first: most rays meet nothing but the
            // two groups (then the target is what they see: its piece faces `x`, as every
            // caller has checked) or an occluder well before the target. Only a hit on the
            // last stretch (a polygon flush over the target, a coincident emitter, the wall
            // at a corner) needs the closest hit; an occluder may then still lie before it,
            // which the traversal, not ordered by distance, need not have met first.
            match self.bvh.any_hit_except(&Ray::new(from, dir), end, skip) {
                None => return true,
                Some(t) if t < near => return false,
                Some(_) => {}
            }
            if self.bvh.occluded_except(&Ray::new(from, dir), near, skip) {
                return false;
            }
            near - off
        } else {
            0.0
        };
        // The receiver's own surface met on the last stretch is stepped past (a few times at
        // most: its two triangles, a twin's).
        for _ in 0..4 {
            match self
                .bvh
                .closest_hit(&Ray::new(from + dir * start, dir), end - start)
            {
                Some(h) if self.twin_of[h.patch as usize] == own && own != group => {
                    start += h.t + 0.25 * off;
                }
                Some(h) => {
                    return h.front
                        && (h.patch == piece
                            || self.twin_of[h.patch as usize] == group
                            || (self.emits[piece as usize]
                                && (h.t + start - dist).abs() <= tolerance));
                }
                // Rounding let the ray slip past the edge of its target: nothing was in the
                // way.
                None => return true,
            }
        }
        true
    }

    /// The coefficient of the link from receiver element `r` to `source` (an element id, or a
    /// cluster index tagged with [`CLUSTER`]).
    /// `round` keys the random stream: the estimate that decides a link and the one it keeps
    /// are independent, so that keeping a link because its points happened to agree (all in
    /// shadow, say) does not bias its coefficient. `shares`: also find the source children's
    /// shares ([`Estimate::sources`]; even shares otherwise), which only a kept link needs.
    pub fn estimate(&self, r: u32, source: u32, round: u64, shares: bool) -> Estimate {
        let re = &self.elements[r as usize];
        let mut rng = stream(self.seed, r as u64, source as u64, 0x4c49_4e4b_0000 + round);
        let mut out = Estimate {
            lo: f32::INFINITY,
            ..Default::default()
        };
        let m = self.rays.max(1);
        let mut sum = 0.0f64;
        let mut sources = [0.0f64; 4];
        // The source's four children, for the shares of `k` that each sends: in the near
        // field the exact factor to each from one point in each quarter of the receiver
        // (exact factors at every point are costly, `docs/notes/hierarchical.md`, and the
        // shares vary slowly over the receiver); in the far field (centres more
        // than twice the radii apart) the kernel from the receiver's centre to each child's,
        // which varies little over the receiver there.
        let mut parts = None;
        if shares && source & CLUSTER == 0 {
            let s = &self.elements[source as usize];
            let p = Parts::of(s);
            if (s.centre - re.centre).length() > 2.0 * (s.radius + re.radius) {
                sources = p.far(re.centre, re.normal, s.normal);
            } else {
                parts = Some(p);
            }
        }
        let jitter: [f32; 2 * POINTS] = std::array::from_fn(|_| uniform(&mut rng));
        // From a cluster, the receiver points share out the cluster's surfaces: point `p`
        // draws its pieces from stratum `strata[p]` of the area (a random permutation), so
        // that the sixteen points' samples spread over the whole cluster rather than fall
        // where independent draws happen to cluster. Each draw is still uniform by area, so
        // the estimate stays unbiased; only its variance falls.
        let mut strata: [u8; POINTS] = std::array::from_fn(|i| i as u8);
        if source & CLUSTER != 0 {
            for i in (1..POINTS).rev() {
                let j = ((uniform(&mut rng) * (i + 1) as f32) as usize).min(i);
                strata.swap(i, j);
            }
        }
        let own = self.twin_of[re.root as usize];
        for (p, x) in re.receiver_points(&jitter).into_iter().enumerate() {
            let mut vis = [0u32; 2];
            let (f, bound) = if source & CLUSTER == 0 {
                let s = &self.elements[source as usize];
                let (f, bound) =
                    self.element_factor(x, re.normal, own, source, s, m, &mut rng, &mut vis);
                if let (Some(parts), true) = (&parts, f > 0.0 && ONE_PER_QUARTER.contains(&p)) {
                    // The point's factor shared among the source's children by their exact
                    // unoccluded factors (visibility taken as the point's, over all of them).
                    let each = parts.factors(x, re.normal, s.normal);
                    let total: f64 = each.iter().sum();
                    if total > 0.0 {
                        for (acc, fq) in sources.iter_mut().zip(each) {
                            *acc += f * fq / total;
                        }
                    }
                }
                (f, bound)
            } else {
                let seen = if shares { Some(&mut out.seen) } else { None };
                self.cluster_factor(
                    x,
                    re.normal,
                    own,
                    source & !CLUSTER,
                    (m, strata[p] as u32),
                    &mut rng,
                    &mut vis,
                    seen,
                )
            };
            out.rays += vis[0] + vis[1];
            out.quarters[quarter(re.tri, p)] += f as f32 / (POINTS / 4) as f32;
            out.blocked |= vis[1] > 0;
            out.unoccluded = out.unoccluded.max(bound as f32);
            sum += f;
            out.hi = out.hi.max(f as f32);
            out.lo = out.lo.min(f as f32);
        }
        out.k = (sum / POINTS as f64) as f32;
        let total: f64 = sources.iter().sum();
        out.sources = if total > 0.0 {
            sources.map(|v| (v / total) as f32)
        } else {
            [0.25; 4]
        };
        if !out.seen.is_empty() {
            // One entry a piece (merged in place), shares summing to 1.
            out.seen.sort_unstable_by_key(|&(p, _)| p);
            out.seen.dedup_by(|next, kept| {
                let same = next.0 == kept.0;
                if same {
                    kept.1 += next.1;
                }
                same
            });
            let total: f32 = out.seen.iter().map(|x| x.1).sum();
            for x in &mut out.seen {
                x.1 /= total;
            }
        }
        out
    }

    /// A point on element `start` drawn by the power its leaves send, and the importance
    /// weight that keeps estimates unbiased: what the leaf drawn sends relative to what
    /// `start` sends, over the density the point was drawn with relative to the uniform one
    /// (1 but where `start` sends the mean over its exposed area, which differs from the
    /// mean over its whole area where part of it is covered): going down the quadtree
    /// from `start`, each child is taken in proportion to its power (to its area where its
    /// siblings send nothing), and the point is uniform over the leaf reached. One sample per
    /// receiver point (the default) then sees the source in proportion to what it sends.
    /// An element that sends nothing yet is drawn by area.
    fn power_point(&self, start: u32, rng: &mut Rng64) -> (Vec3, f64) {
        let mut e = start;
        let mut el = &self.elements[e as usize];
        // Children made after `power` was taken are not looked at: refinement decides a
        // round's candidates in slices, and the slices must not see each other's splits.
        let drawn_leaf = |el: &Element| el.is_leaf() || el.children as usize >= self.power.len();
        if self.power.is_empty() || drawn_leaf(el) || self.power[e as usize] <= 0.0 {
            return (el.sample(uniform(rng), uniform(rng), uniform(rng)), 1.0);
        }
        let mut ratio = 1.0f64;
        while !drawn_leaf(el) {
            let first = el.children as usize;
            let (mut area, mut power) = (0.0f64, 0.0f64);
            for c in first..first + 4 {
                area += self.elements[c].area as f64;
                power += self.power[c] as f64;
            }
            let share = |c: usize| {
                if power > 0.0 {
                    self.power[c] as f64 / power
                } else {
                    self.elements[c].area as f64 / area
                }
            };
            let u = uniform(rng) as f64;
            let (mut acc, mut pick) = (0.0, first + 3);
            for c in first..first + 4 {
                acc += share(c);
                if u < acc {
                    pick = c;
                    break;
                }
            }
            ratio *= share(pick) * area / self.elements[pick].area as f64;
            e = pick as u32;
            el = &self.elements[e as usize];
        }
        let y = el.sample(uniform(rng), uniform(rng), uniform(rng));
        let top = &self.elements[start as usize];
        let relative = (self.power[e as usize] as f64 / el.area.max(f32::MIN_POSITIVE) as f64)
            / (self.power[start as usize] as f64 / top.area as f64);
        (y, relative / ratio)
    }

    #[allow(clippy::too_many_arguments)]
    fn element_factor(
        &self,
        x: Vec3,
        n: Vec3,
        own: u32,
        s_id: u32,
        s: &Element,
        m: u32,
        rng: &mut Rng64,
        vis: &mut [u32; 2],
    ) -> (f64, f64) {
        let f = point_polygon(x, n, s.polygon(), s.normal);
        if f <= 0.0 {
            return (0.0, 0.0);
        }
        // Visibility over the part of the source in front of x (the part the analytic factor
        // counts), weighted by the kernel cos θ cos θ' / r², so that the fraction is the
        // kernel's, not the area's (they differ where the near part of a source is hidden and
        // the far part is not). A source that fills much of x's view (F ≥ 0.1) is sampled by
        // cosine-distributed directions that meet it, whose density is the kernel itself;
        // a smaller one by points drawn over its area by the power its leaves send
        // ([`Context::power_point`]), each ray weighted by the kernel times that power: the
        // fraction is then the one of the light the source sends towards x, which differs
        // from the area's where a bright spot on the source is what an occluder hides (the
        // spot a bare bulb throws on the wall behind it, which the bulb itself shadows from
        // the rest of the room).
        let (mut seen, mut total, mut valid) = (0.0f64, 0.0f64, 0u32);
        if f >= 0.1 {
            let (t, b) = crate::geom::orthonormal_basis(n);
            let tries = (m as f64 / f * 2.0).ceil() as u32 + 8;
            for _ in 0..tries {
                if valid == m {
                    break;
                }
                let d = crate::sampling::cosine_direction_in(n, t, b, uniform(rng), uniform(rng));
                let Some(y) = hit_polygon(x, d, s) else {
                    continue;
                };
                valid += 1;
                total += 1.0;
                if self.visible(x, n, own, y, s.root) {
                    seen += 1.0;
                    vis[0] += 1;
                } else {
                    vis[1] += 1;
                }
            }
        } else {
            for _ in 0..8 * m {
                if valid == m {
                    break;
                }
                let (y, b) = self.power_point(s_id, rng);
                let d = y - x;
                let d2 = d.length_squared() as f64;
                let w = b * n.dot(d) as f64 * -(s.normal.dot(d) as f64) / (d2 * d2);
                if w.is_nan() || w <= 0.0 {
                    continue;
                }
                valid += 1;
                total += w;
                if self.visible(x, n, own, y, s.root) {
                    seen += w;
                    vis[0] += 1;
                } else {
                    vis[1] += 1;
                }
            }
        }
        if valid == 0 {
            // A sliver in front: too thin to hit; its factor is tiny, take it as seen.
            return (f, f);
        }
        (f * seen / total, f)
    }

    /// The point-to-area factor from `x` to the surfaces of cluster `c` that it sees, by
    /// points drawn by area, `m` from its emitters and `m` from its other surfaces (the two
    /// strata, each weighted by its area): a lamp is a small part of a cluster's area but
    /// most of its light, and drawn with the rest it would be missed by most receivers and
    /// met with a large weight by a few. Within each, the draws come from `stratum` of
    /// `POINTS` equal parts of the area (the estimate's receiver points take one part each).
    /// `seen` (kept estimates): each sample seen, with its part of the factor, for the link
    /// to gather what those surfaces send.
    #[allow(clippy::too_many_arguments)]
    fn cluster_factor(
        &self,
        x: Vec3,
        n: Vec3,
        own: u32,
        c: u32,
        (m, stratum): (u32, u32),
        rng: &mut Rng64,
        vis: &mut [u32; 2],
        mut seen: Option<&mut Vec<(u32, f32)>>,
    ) -> (f64, f64) {
        let mut k = 0.0;
        let mut bound = 0.0;
        for emitters in [true, false] {
            let area = self.clusters.area_in(c, emitters);
            if area <= 0.0 {
                continue;
            }
            let scale = area / m as f64;
            for j in 0..m {
                // Stratum `stratum` of POINTS, sample j of its m sub-strata.
                let u =
                    ((stratum * m + j) as f64 + uniform(rng) as f64) / (POINTS as u32 * m) as f64;
                let piece = self
                    .clusters
                    .pick_in(c, emitters, u.min(1.0 - f64::EPSILON));
                let root = &self.elements[piece as usize];
                if self.twin_of[piece as usize] != piece {
                    // A twin's light is sent by its representative, drawn as often.
                    continue;
                }
                // Over the piece by the power its parts send (the link gathers the piece's
                // mean, and the weight is the drawn part's power over that mean).
                let (y, b) = self.power_point(piece, rng);
                let d = y - x;
                let d2 = d.length_squared();
                if d2 <= 0.0 {
                    continue;
                }
                let (cr, cs) = (n.dot(d), -root.normal.dot(d));
                if cr <= 0.0 || cs <= 0.0 {
                    continue;
                }
                let w = b * scale * (cr as f64 * cs as f64) / (PI * d2 as f64 * d2 as f64);
                bound += w;
                if self.visible(x, n, own, y, piece) {
                    k += w;
                    vis[0] += 1;
                    if let Some(seen) = seen.as_deref_mut() {
                        seen.push((piece, w as f32));
                    }
                } else {
                    vis[1] += 1;
                }
            }
        }
        (k, bound)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::formfactor::closed_form;

    /// The edge angle agrees with `atan2` over the half-plane y ≥ 0, to 10⁻⁹ relative.
    #[test]
    fn edge_angle_matches_atan2() {
        let mut worst = 0.0f64;
        for i in 0..=20_000 {
            let phi = std::f64::consts::PI * i as f64 / 20_000.0;
            for r in [1e-6, 0.3, 1.0, 7e4] {
                let (y, x) = (r * phi.sin().max(0.0), r * phi.cos());
                let exact = y.atan2(x);
                let got = angle(y, x);
                worst = worst.max((got - exact).abs() / exact.max(1e-300));
                assert!(
                    (got - exact).abs() <= 1e-9 * exact + 1e-15,
                    "{phi}: {got} vs {exact}"
                );
            }
        }
        assert!(worst < 1e-9, "{worst}");
        assert_eq!(angle(0.0, 0.0), 0.0);
        assert_eq!(angle(0.0, 2.0), 0.0);
    }

    #[test]
    fn point_to_polygon_matches_closed_forms() {
        // A point on the axis of a parallel square: four corner rectangles of Howell's B-3.
        let h = 0.7f32;
        let square = [
            Vec3::new(-1.0, h, -1.0),
            Vec3::new(-1.0, h, 1.0),
            Vec3::new(1.0, h, 1.0),
            Vec3::new(1.0, h, -1.0),
        ];
        let f = point_polygon(Vec3::ZERO, Vec3::Y, &square, -Vec3::Y);
        let quarter = closed_form::point_parallel_rectangle(1.0, 1.0, h as f64);
        assert!((f - 4.0 * quarter).abs() < 1e-6, "{f} vs {}", 4.0 * quarter);
        // Behind the source: nothing; a source half behind the receiver's plane: clipped.
        assert_eq!(
            point_polygon(Vec3::Y * 2.0, Vec3::Y, &square, -Vec3::Y),
            0.0
        );
        let tilted = [
            Vec3::new(1.0, -1.0, -1.0),
            Vec3::new(1.0, -1.0, 1.0),
            Vec3::new(1.0, 1.0, 1.0),
            Vec3::new(1.0, 1.0, -1.0),
        ];
        let half = point_polygon(Vec3::ZERO, Vec3::Y, &tilted, -Vec3::X);
        let upper = [
            Vec3::new(1.0, 0.0, -1.0),
            Vec3::new(1.0, 0.0, 1.0),
            Vec3::new(1.0, 1.0, 1.0),
            Vec3::new(1.0, 1.0, -1.0),
        ];
        let expect = point_polygon(Vec3::ZERO, Vec3::Y, &upper, -Vec3::X);
        assert!((half - expect).abs() < 1e-12 && half > 0.0);
        // The clipped half against a midpoint rule over it (400 × 400 cells).
        let n = 400;
        let mut quad = 0.0;
        for i in 0..n {
            for j in 0..n {
                let (y, z) = (
                    (i as f64 + 0.5) / n as f64,
                    -1.0 + 2.0 * (j as f64 + 0.5) / n as f64,
                );
                let r2 = 1.0 + y * y + z * z;
                quad += y * 1.0 / (PI * r2 * r2) * (2.0 / (n * n) as f64);
            }
        }
        assert!((half - quad).abs() < 1e-4, "{half} vs {quad}");
        // A closed cube around the point: the factors to the five faces in front sum to 1.
        let c = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
        let faces: [([Vec3; 4], Vec3); 5] = [
            (
                [
                    c(-1., 1., -1.),
                    c(-1., 1., 1.),
                    c(1., 1., 1.),
                    c(1., 1., -1.),
                ],
                -Vec3::Y,
            ),
            (
                [
                    c(1., -1., -1.),
                    c(1., -1., 1.),
                    c(1., 1., 1.),
                    c(1., 1., -1.),
                ],
                -Vec3::X,
            ),
            (
                [
                    c(-1., -1., -1.),
                    c(-1., 1., -1.),
                    c(-1., 1., 1.),
                    c(-1., -1., 1.),
                ],
                Vec3::X,
            ),
            (
                [
                    c(-1., -1., 1.),
                    c(-1., 1., 1.),
                    c(1., 1., 1.),
                    c(1., -1., 1.),
                ],
                -Vec3::Z,
            ),
            (
                [
                    c(-1., -1., -1.),
                    c(1., -1., -1.),
                    c(1., 1., -1.),
                    c(-1., 1., -1.),
                ],
                Vec3::Z,
            ),
        ];
        let x = Vec3::new(0.2, -0.3, 0.1);
        let total: f64 = faces
            .iter()
            .map(|(p, ns)| {
                // Orient counter-clockwise about the inward normal.
                let mut p = *p;
                if crate::geom::triangle_cross(p[0], p[1], p[2]).dot(*ns) < 0.0 {
                    p.reverse();
                }
                point_polygon(x, Vec3::Y, &p, *ns)
            })
            .sum();
        assert!((total - 1.0).abs() < 1e-9, "{total}");
    }
}
