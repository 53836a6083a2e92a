//! Adaptive view factors: each pair of patches to a requested accuracy, exact where the pair
//! sees itself whole, with the shadows cut out exactly where something stands between.
//!
//! For two patches `a` and `b` the method computes the exchange area
//! `A_a F_ab = A_b F_ba = (1/π) ∫_a ∫_b V cos θ_a cos θ_b / r² dA_b dA_a` (Szirmay-Kalos & Márton
//! 1995, eq. 6, times `A_a`) once, and both entries follow from it, so reciprocity holds to the
//! rounding of the stored `f32`. A pair is one of:
//!
//! - **Not facing**: each polygon is clipped to the other's front half-space; when either part
//!   is empty the factor is 0 and nothing more is done.
//! - **Seen whole** (no occluder meets the convex hull of the two polygons, found through
//!   [`shaft`](super::shaft)): far apart, a Gauss–Legendre product rule of the point kernel
//!   `cos θ_a cos θ_b / (π r²)` with m × m points on each patch, m = 1, 2, 3, 4, until two
//!   successive orders agree within the relative accuracy (the difference bounds the error of
//!   the lower order, and the higher one is kept); the rule converges geometrically, the faster
//!   the farther apart the pair is. Close (gap below twice the larger patch's radius),
//!   straddling the other's plane, or not converged by m = 4: Stokes' contour integral of
//!   [`analytic`](super::analytic::polygon_factor_tol), exact also for shared edges and corners.
//! - **Occluded** (candidate occluders meet the hull; each is clipped to the space between the
//!   two planes). The outer integral runs over the patch farther from the occluders (a shadow
//!   then moves slowly with the outer point, and the sharp features near an occluder standing
//!   on a patch fall in the exact inner integral). For each candidate S two exact questions come
//!   first. Does S hide all of the receiver from all of the outer patch? The umbra is convex,
//!   so its corners decide (every segment from a corner of one patch to a corner of the other
//!   crosses S): then the pair is 0, and this is asked before the pair's shaft is built, as
//!   such an S meets every segment. From where does S shadow the receiver at all?
//!   From the points on S's side of every plane that separates S from the receiver; those
//!   through an edge of one and a corner of the other, and S's own plane, bound that region
//!   (Nishita & Nakamae 1985; Teller 1992), and clipping the outer patch by them gives it. If
//!   no candidate shadows from anywhere, the pair is seen whole. Otherwise the integral runs
//!   over Ω, the hull of those regions: at each point each shadowing occluder's pyramid is cut
//!   out of the receiver (Sutherland–Hodgman against its side planes), and Lambert's contour
//!   formula (`F = (1/2π) Σ_edges γ_k n · ĝ_k`, [`point_polygon`]) gives the factor lost and the
//!   factor still seen, exactly, with no sampling. The exchange area is the unoccluded one less
//!   the integral of what is lost, or (when Ω is the whole outer patch and what is seen
//!   integrates to less) the integral of what is seen, so a pair hidden by several occluders
//!   together is exactly 0. The outer rule: cells of the parameter square (bilinear for a quad,
//!   collapsed for a triangle of Ω's fan) with 2 × 2 Gauss points; each region first whole and
//!   in four (20 points), then the cell whose quarters differ most from it split, until the
//!   differences add up to the tolerance (or [`MAX_CELLS`] cells). What is seen is continuous
//!   in the outer point and smooth between penumbra boundaries, so the error falls as the
//!   cells along a boundary shrink; the difference is the estimate because along such a kink
//!   it falls only fourfold a halving, and a comparison with the cell's centre misses
//!   integrands whose curvatures cancel.
//! - **Shadowed by more than [`MAX_ACTIVE`] occluders** (a large polygon seen past many
//!   others): cutting each shadow out at each point would cost their number times the pieces
//!   left, so the pair is sampled: the exact unoccluded exchange area times the visible
//!   fraction, weighted by the point kernel, of the 4 × 4 by 4 × 4 Gauss points, each point
//!   pair tested by a ray of the [`Bvh`].
//!
//! Why clipping rather than sampling visibility with rays: a ray sample's error on a partly
//! shadowed pair falls as n^(−1/2) (stratified, in four dimensions, n^(−5/8)), so a factor
//! to 10⁻⁵ of its value takes 10⁸ rays; subdividing the pair into sub-pairs with exact factors
//! times visibility fractions from rays keeps that sampling error along every shadow boundary.
//! Clipping makes the inner integral exact, and leaves a continuous, piecewise smooth function
//! of two variables whose error an embedded rule estimates and subdivision drives down. It is
//! View3D's approach (Walton 2002, "Calculation of Obstructed View Factors by Adaptive
//! Integration", NISTIR 6925). Its price is the shadow work per point and occluder, so coplanar
//! patches are first merged into few convex occluders ([`shaft`](super::shaft)).
//!
//! Accuracy `E` ([`Params::accuracy`](super::Params::accuracy)): a pair seen whole to a relative
//! `E` (its rules' errors share one sign, so a relative tolerance keeps a row of many small
//! entries within `E` of its sum); an occluded one to an absolute `E` on both its entries (`E`
//! times the smaller area on the exchange area), whose errors change sign with where the
//! shadows fall. The estimate can be fooled by a pair seen only through a gap narrower than the
//! first points' spacing; the row sums measured on closed scenes are in docs/heat-transfer.md.
//! The cost is a constant per facing pair plus the shadow work of the occluded ones:
//! near-linear in the number of pairs that see each other. Rows are computed in parallel, each
//! pair by a rule that depends only on the pair, so the matrix does not depend on the thread
//! count and a row computed alone equals the matrix's.

use super::analytic;
use super::shaft::{patch_polygon, Occluders, Shaft};
use super::{Estimator, Matrix, Storage};
use crate::accel::Bvh;
use crate::geom::Ray;
use crate::mesh::Mesh;
use crate::observe::{Event, Observer, Stage};
use crate::system::{Entry, SparseMatrix};
use glam::DVec3;
use rayon::prelude::*;
use std::f64::consts::PI;
use std::sync::atomic::{AtomicU64, Ordering::Relaxed};

/// Most cells of the outer integral of one occluded pair (each four visibility evaluations).
pub const MAX_CELLS: usize = 256;

/// Most occluders shadowing one occluded pair for exact clipping: the exact shadow of each is
/// cut from every visible piece of the receiver at every point, so that work grows as their
/// number times the pieces; beyond it the pair is sampled with visibility rays.
pub const MAX_ACTIVE: usize = 16;

/// Gauss orders of the unoccluded product rule.
const ORDERS: usize = 4;
/// Offsets of order m's points in a patch's rule table (1 + 4 + 9 + 16 = 30 points).
const RULE_START: [usize; ORDERS + 1] = [0, 1, 5, 14, 30];

/// A pair whose gap is below this many times the larger patch's radius goes to the contour
/// integral (the product rule would need high orders there).
const NEAR: f64 = 2.0;

/// Largest number of occluders for which the candidates of every pair of occluders are found
/// once, before the rows, and each pair of patches only filters its groups' list.
const GROUP_TABLE_MAX: usize = 2048;

/// What the method did, for benchmarks and tests.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Stats {
    /// Pairs (each unordered pair counted once) that face each other.
    pub facing: u64,
    /// Of those, pairs with no occluder in their hull done by the product rule.
    pub product_rule: u64,
    /// Pairs done by the exact contour integral (near, straddling, or not converged).
    pub contour: u64,
    /// Pairs with an occluder in their hull.
    pub occluded: u64,
    /// Occluded pairs on which no evaluated point saw a shadow (then done as unoccluded).
    pub occluded_clear: u64,
    /// Occluded pairs hidden at every evaluated point.
    pub occluded_hidden: u64,
    /// Visibility evaluations (points of the outer integral of occluded pairs).
    pub points: u64,
    /// Occluded pairs that stopped at [`MAX_CELLS`] before the tolerance.
    pub capped: u64,
    /// Occluded pairs shadowed by more than [`MAX_ACTIVE`] occluders, done by sampling.
    pub sampled: u64,
    /// Visibility rays cast for them.
    pub rays: u64,
}

#[derive(Debug, Default)]
struct Counters {
    facing: AtomicU64,
    product_rule: AtomicU64,
    contour: AtomicU64,
    occluded: AtomicU64,
    occluded_clear: AtomicU64,
    occluded_hidden: AtomicU64,
    points: AtomicU64,
    capped: AtomicU64,
    sampled: AtomicU64,
    rays: AtomicU64,
}

/// One patch in f64.
#[derive(Clone, Copy, Debug)]
struct Patch {
    v: [DVec3; 4],
    nv: usize,
    normal: DVec3,
    centre: DVec3,
    radius: f64,
    /// Area as the mesh holds it (the entries are divided by it, as the summaries multiply).
    area: f64,
}

impl Patch {
    fn corners(&self) -> &[DVec3] {
        &self.v[..self.nv]
    }
}

/// The candidate occluders of each pair of occluders (groups), found once: those that meet the
/// hull of the two and shadow one from somewhere on the other. Every patch lies in its group's
/// polygon, so an occluder that shadows nothing between two groups shadows nothing between any
/// of their patches, and one that hides all of one group from all of the other hides every
/// pair of their patches.
#[derive(Debug)]
struct GroupTable {
    groups: usize,
    /// `(start, len)` into `candidates` for `(g, h)`, `g ≤ h`, at `g · groups + h`;
    /// `len == NOT_FACING` when no part of one faces the other, `len == HIDDEN` when one
    /// occluder hides all of one from all of the other.
    ranges: Vec<(u32, u32)>,
    candidates: Vec<u32>,
}

const NOT_FACING: u32 = u32::MAX;
const HIDDEN: u32 = u32::MAX - 1;

/// What the method prepares once per mesh: the patches in f64, their Gauss points, the
/// occluders and their tree, and the candidates per pair of occluders.
#[derive(Debug)]
pub struct Prepared {
    patches: Vec<Patch>,
    rule: Vec<(DVec3, f64)>,
    /// The same points by coordinate (x, y, z, weight), for the product rule's inner loop.
    rule_soa: [Vec<f64>; 4],
    occluders: Occluders,
    table: Option<GroupTable>,
    accuracy: f64,
    counters: Counters,
}

/// Per-thread buffers: nothing is allocated per pair once they are warm.
#[derive(Debug, Default)]
pub struct Scratch {
    pa: Vec<DVec3>,
    pb: Vec<DVec3>,
    tmp: Vec<DVec3>,
    shaft: Shaft,
    stack: Vec<u32>,
    /// Candidates of the pair whose boxes meet its box, and those its shaft keeps.
    near: Vec<u32>,
    found: Vec<u32>,
    /// Occluders of the pair clipped to the space between the planes: corners and ranges.
    occ: Vec<DVec3>,
    occ_range: Vec<(u32, u32)>,
    occ_centre: Vec<DVec3>,
    occ_normal: Vec<DVec3>,
    /// Visible pieces of the receiver: corners and ranges, current and next.
    pieces: Vec<DVec3>,
    ranges: Vec<(u32, u32)>,
    next: Vec<DVec3>,
    next_ranges: Vec<(u32, u32)>,
    inside: Vec<DVec3>,
    outside: Vec<DVec3>,
    cone: Vec<(DVec3, f64)>,
    cells: Vec<Cell>,
    /// Occluders that shadow the receiver from part of the outer patch, the separating
    /// planes bounding each one's region, their corners (Ω's points) and Ω.
    active: Vec<u32>,
    planes: Vec<(DVec3, f64)>,
    plane_range: Vec<(u32, u32)>,
    omega: Vec<DVec3>,
    flat: Vec<(f64, f64, u32)>,
    hull: Vec<DVec3>,
    analytic: analytic::Scratch,
    /// Which of the lost and the seen parts the points of the current pair must measure.
    need: Need,
    /// Whether each occluder may hold a patch facing the current row's patch.
    facing: Vec<bool>,
    stats: Stats,
}

/// What the visibility at a point of the outer integral must measure: both parts while the
/// method chooses which to integrate, then only that one.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
enum Need {
    #[default]
    Both,
    Lost,
    Seen,
}

/// A cell of the outer integral: region (triangle or quad of the fan), its square
/// `[u0, u0 + h] × [v0, v0 + h]` in the region's parameters, its 2 × 2 Gauss values and their
/// errors.
#[derive(Clone, Copy, Debug)]
struct Cell {
    region: u8,
    u0: f64,
    v0: f64,
    h: f64,
    /// The factor lost to shadows, and the factor still seen, over the cell.
    value: [f64; 2],
    /// Their error estimates.
    err: [f64; 2],
}

impl Prepared {
    /// Prepare `mesh` for accuracy `accuracy`.
    pub fn new(mesh: &Mesh, accuracy: f64) -> Prepared {
        let n = mesh.len();
        let polys: Vec<Vec<DVec3>> = (0..n).map(|k| patch_polygon(mesh, k)).collect();
        let patches: Vec<Patch> = polys
            .iter()
            .zip(&mesh.patches)
            .map(|(p, mp)| {
                let mut v = [DVec3::ZERO; 4];
                v[..p.len()].copy_from_slice(p);
                let mut s = DVec3::ZERO;
                for k in 1..p.len() - 1 {
                    s += (p[k] - p[0]).cross(p[k + 1] - p[0]);
                }
                let normal = s.normalize_or_zero();
                let centre = p.iter().copied().sum::<DVec3>() / p.len() as f64;
                let radius = p.iter().map(|q| (*q - centre).length()).fold(0.0, f64::max);
                Patch {
                    v,
                    nv: p.len(),
                    normal,
                    centre,
                    radius,
                    area: mp.area as f64,
                }
            })
            .collect();
        let rule: Vec<(DVec3, f64)> = patches.iter().flat_map(gauss_points).collect();
        let rule_soa = [
            rule.iter().map(|r| r.0.x).collect(),
            rule.iter().map(|r| r.0.y).collect(),
            rule.iter().map(|r| r.0.z).collect(),
            rule.iter().map(|r| r.1).collect(),
        ];
        let scale = mesh
            .vertices
            .iter()
            .fold(0.0f64, |m, v| m.max(v.abs().max_element() as f64))
            .max(f64::MIN_POSITIVE);
        let normals: Vec<DVec3> = patches.iter().map(|p| p.normal).collect();
        let occluders = Occluders::build(&polys, &normals, scale);
        let table = (occluders.len() <= GROUP_TABLE_MAX && occluders.len() * 4 <= n.max(4))
            .then(|| group_table(&occluders));
        Prepared {
            patches,
            rule,
            rule_soa,
            occluders,
            table,
            accuracy,
            counters: Counters::default(),
        }
    }

    /// Number of merged occluders.
    pub fn occluders(&self) -> usize {
        self.occluders.len()
    }

    /// The counts so far.
    pub fn stats(&self) -> Stats {
        let c = &self.counters;
        Stats {
            facing: c.facing.load(Relaxed),
            product_rule: c.product_rule.load(Relaxed),
            contour: c.contour.load(Relaxed),
            occluded: c.occluded.load(Relaxed),
            occluded_clear: c.occluded_clear.load(Relaxed),
            occluded_hidden: c.occluded_hidden.load(Relaxed),
            points: c.points.load(Relaxed),
            capped: c.capped.load(Relaxed),
            sampled: c.sampled.load(Relaxed),
            rays: c.rays.load(Relaxed),
        }
    }

    fn flush(&self, s: &mut Stats) {
        let c = &self.counters;
        c.facing.fetch_add(s.facing, Relaxed);
        c.product_rule.fetch_add(s.product_rule, Relaxed);
        c.contour.fetch_add(s.contour, Relaxed);
        c.occluded.fetch_add(s.occluded, Relaxed);
        c.occluded_clear.fetch_add(s.occluded_clear, Relaxed);
        c.occluded_hidden.fetch_add(s.occluded_hidden, Relaxed);
        c.points.fetch_add(s.points, Relaxed);
        c.capped.fetch_add(s.capped, Relaxed);
        c.sampled.fetch_add(s.sampled, Relaxed);
        c.rays.fetch_add(s.rays, Relaxed);
        *s = Stats::default();
    }

    /// The exchange area `A_i F_ij = A_j F_ji` of patches `i` and `j`: the same value whichever
    /// is named first.
    pub fn exchange(&self, i: usize, j: usize, bvh: &Bvh, s: &mut Scratch) -> f64 {
        let (i, j) = (i.min(j), i.max(j));
        let (pi, pj) = (&self.patches[i], &self.patches[j]);
        // The outer integral over the smaller patch (the lower index on a tie).
        let (ia, ib) = if pj.area < pi.area { (j, i) } else { (i, j) };
        let (a, b) = (&self.patches[ia], &self.patches[ib]);
        let size = (a.centre - b.centre).length() + a.radius + b.radius;
        let eps = 1e-9 * size;
        let side = |p: &Patch, q: &Patch| {
            q.corners()
                .iter()
                .map(|v| p.normal.dot(*v - p.v[0]))
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), d| {
                    (lo.min(d), hi.max(d))
                })
        };
        let (amin, amax) = side(b, a);
        let (bmin, bmax) = side(a, b);
        if amax <= eps || bmax <= eps {
            return 0.0;
        }
        let straddle = amin < -eps || bmin < -eps;
        // Each in front of the other's plane (a polygon wholly in front is its own clip: the
        // sides are the ones `clip` computes).
        let front = |p: &Patch, q: &Patch, lo: f64, out: &mut Vec<DVec3>| {
            if lo >= 0.0 {
                out.clear();
                out.extend_from_slice(p.corners());
            } else {
                clip(p.corners(), q.v[0], q.normal, 0.0, out);
            }
        };
        front(a, b, amin, &mut s.pa);
        front(b, a, bmin, &mut s.pb);
        if s.pa.len() < 3 || s.pb.len() < 3 {
            return 0.0;
        }
        s.stats.facing += 1;
        // Candidate occluders: the groups' list filtered by this pair's hull, or the tree.
        let (ga, gb) = (self.occluders.group[ia], self.occluders.group[ib]);
        s.found.clear();
        match &self.table {
            Some(t) => {
                let (g, h) = (ga.min(gb) as usize, ga.max(gb) as usize);
                let (start, len) = t.ranges[g * t.groups + h];
                if len == HIDDEN {
                    s.stats.occluded += 1;
                    s.stats.occluded_hidden += 1;
                    return 0.0;
                }
                if len != NOT_FACING && len > 0 {
                    // The hull lies in the pair's bounding box: a candidate whose box is
                    // clear of it (by far more than the shaft's slack) cuts no segment, and
                    // the shaft is built only when some candidate's box meets it.
                    let (mut lo, mut hi) = (s.pa[0], s.pa[0]);
                    for p in s.pa.iter().chain(&s.pb) {
                        lo = lo.min(*p);
                        hi = hi.max(*p);
                    }
                    let margin = DVec3::splat(1e-6 * (hi - lo).length());
                    let (lo, hi) = (lo - margin, hi + margin);
                    let cands = &t.candidates[start as usize..(start + len) as usize];
                    // A candidate that hides all of one patch from all of the other meets
                    // every segment between them, so it is one the shaft keeps: asked first,
                    // it spares the shaft of a hidden pair.
                    s.near.clear();
                    for &k in cands {
                        let (bl, bh) = self.occluders.bounds(k);
                        if bh.cmplt(lo).any() || bl.cmpgt(hi).any() {
                            continue;
                        }
                        s.near.push(k);
                        let planes = [(a.normal, a.v[0]), (b.normal, b.v[0])];
                        if self.hides_pair(
                            k,
                            planes,
                            &s.pa,
                            &s.pb,
                            eps,
                            size,
                            &mut s.tmp,
                            &mut s.inside,
                        ) {
                            s.stats.occluded += 1;
                            s.stats.occluded_hidden += 1;
                            return 0.0;
                        }
                    }
                    if !s.near.is_empty() {
                        s.shaft.set(&s.pa, a.normal, &s.pb, b.normal);
                        for &k in &s.near {
                            if !s.shaft.excludes_polygon(self.occluders.polygon(k)) {
                                s.found.push(k);
                            }
                        }
                    }
                }
            }
            None => {
                s.shaft.set(&s.pa, a.normal, &s.pb, b.normal);
                self.occluders
                    .query(&s.shaft, [ga, gb], &mut s.stack, &mut s.found);
            }
        }
        // Each candidate clipped to the space in front of both planes.
        s.occ.clear();
        s.occ_range.clear();
        s.occ_centre.clear();
        s.occ_normal.clear();
        for idx in 0..s.found.len() {
            let k = s.found[idx];
            let poly = self.occluders.polygon(k);
            let flat = |n: DVec3, o: DVec3| poly.iter().all(|p| n.dot(*p - o).abs() <= eps);
            if flat(a.normal, a.v[0]) || flat(b.normal, b.v[0]) {
                // In the plane of either patch: no segment between them crosses it.
                continue;
            }
            clip_between(
                poly,
                [(a.v[0], a.normal), (b.v[0], b.normal)],
                &mut s.tmp,
                &mut s.inside,
            );
            if s.inside.len() < 3 || polygon_area(&s.inside) <= 1e-14 * size * size {
                continue;
            }
            let start = s.occ.len() as u32;
            s.occ.extend_from_slice(&s.inside);
            s.occ_range.push((start, s.inside.len() as u32));
            s.occ_centre
                .push(s.inside.iter().copied().sum::<DVec3>() / s.inside.len() as f64);
            s.occ_normal.push(self.occluders.normal(k));
        }
        if s.occ_range.is_empty() {
            return self.unoccluded(ia, ib, straddle, s);
        }
        s.stats.occluded += 1;
        self.occluded(ia, ib, straddle, size, bvh, s)
    }

    /// Whether occluder `k` alone hides all of `rec` (in the plane `(nb, ob)`: normal, point)
    /// from all of `outer` (in `(na, oa)`), by [`umbra_of`] on `k` clipped to the space between
    /// the two planes (as [`Prepared::occluded`] asks it). Two necessary conditions come first,
    /// on the whole occluder and with slacks wider than the umbra's, so that only an occluder
    /// that may hide is clipped: the two polygons on opposite sides of its plane, and the
    /// segment between their centres through it.
    #[allow(clippy::too_many_arguments)]
    fn hides_pair(
        &self,
        k: u32,
        [(na, oa), (nb, ob)]: [(DVec3, DVec3); 2],
        outer: &[DVec3],
        rec: &[DVec3],
        eps: f64,
        size: f64,
        tmp: &mut Vec<DVec3>,
        inside: &mut Vec<DVec3>,
    ) -> bool {
        let poly = self.occluders.polygon(k);
        let no = self.occluders.normal(k);
        let ho = no.dot(poly[0]);
        let slack = 2.0 * eps;
        let range = |p: &[DVec3]| {
            p.iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), x| {
                    let d = no.dot(*x) - ho;
                    (lo.min(d), hi.max(d))
                })
        };
        let (alo, ahi) = range(outer);
        let (blo, bhi) = range(rec);
        let apart = (blo >= -slack && ahi < slack) || (bhi <= slack && alo > -slack);
        if !apart {
            return false;
        }
        // The segment between the two centres crosses the occluder (well inside, as every
        // segment does for the umbra; the slack only keeps borderline ones).
        let ca = outer.iter().copied().sum::<DVec3>() / outer.len() as f64;
        let cb = rec.iter().copied().sum::<DVec3>() / rec.len() as f64;
        let (da, db) = (no.dot(ca) - ho, no.dot(cb) - ho);
        if da == db {
            return false;
        }
        let x = ca + (cb - ca) * (da / (da - db));
        let tol = 1e-6 * size;
        for (p, q) in edge_pairs(poly) {
            let e = q - p;
            // Distance of x outside the edge, in the occluder's plane (counter-clockwise
            // about `no`), times the edge's length.
            if e.cross(x - p).dot(no) < -tol * e.length() {
                return false;
            }
        }
        let flat = |n: DVec3, o: DVec3| poly.iter().all(|p| n.dot(*p - o).abs() <= eps);
        if flat(na, oa) || flat(nb, ob) {
            return false;
        }
        clip_between(poly, [(oa, na), (ob, nb)], tmp, inside);
        if inside.len() < 3 || polygon_area(inside) <= 1e-14 * size * size {
            return false;
        }
        umbra_of(inside, no, outer, rec, eps)
    }

    /// Whether occluder (group) `g` may hold a patch that faces patch `i`: not when it lies
    /// wholly behind `i`'s plane, nor when `i` lies wholly behind its plane. A patch lies in
    /// its group's polygon and plane, so such a pair has one polygon behind the other's plane
    /// (but for rounding: [`Prepared::exchange`] would give it 0, or a few roundings' worth
    /// where the two are coplanar in f32 corners). The pair `(i, j)`, `i < j`, is skipped by
    /// `group_faces(i, group(j))` whichever row asks, so a row alone equals the matrix's.
    fn group_faces(&self, i: usize, g: u32) -> bool {
        let p = &self.patches[i];
        let (poly, n) = (self.occluders.polygon(g), self.occluders.normal(g));
        let behind_i = poly.iter().all(|v| p.normal.dot(*v - p.v[0]) <= 0.0);
        let i_behind = p.corners().iter().all(|v| n.dot(*v - poly[0]) <= 0.0);
        !(behind_i || i_behind)
    }

    /// [`Prepared::group_faces`] of patch `i` and every group, into `out`.
    fn facing_groups(&self, i: usize, out: &mut Vec<bool>) {
        out.clear();
        out.extend((0..self.occluders.len() as u32).map(|g| self.group_faces(i, g)));
    }

    /// The exchange area of an unoccluded pair to the relative accuracy.
    fn unoccluded(&self, ia: usize, ib: usize, straddle: bool, s: &mut Scratch) -> f64 {
        let (a, b) = (&self.patches[ia], &self.patches[ib]);
        let gap = (a.centre - b.centre).length() - a.radius - b.radius;
        if !straddle && gap > NEAR * a.radius.max(b.radius) {
            let mut prev = self.product(ia, ib, 1);
            for m in 2..=ORDERS {
                let cur = self.product(ia, ib, m);
                if (cur - prev).abs() <= self.accuracy * cur.abs() {
                    s.stats.product_rule += 1;
                    return cur.max(0.0);
                }
                prev = cur;
            }
        }
        s.stats.contour += 1;
        analytic::polygon_factor_tol(
            a.corners(),
            a.normal,
            1.0,
            b.corners(),
            b.normal,
            0.01 * self.accuracy,
            &mut s.analytic,
        )
    }

    /// The m × m by m × m Gauss–Legendre product rule of the exchange area.
    fn product(&self, ia: usize, ib: usize, m: usize) -> f64 {
        let (na, nb) = (self.patches[ia].normal, self.patches[ib].normal);
        let ra = &self.rule[ia * RULE_START[ORDERS] + RULE_START[m - 1]..][..m * m];
        let at = ib * RULE_START[ORDERS] + RULE_START[m - 1];
        let [bx, by, bz, bw] = self.rule_soa.each_ref().map(|c| &c[at..at + m * m]);
        // The terms of one outer point in a fixed array (a loop the compiler vectorises),
        // then added in order.
        let mut terms = [0.0f64; 16];
        let mut sum = 0.0;
        for &(x, wx) in ra {
            for k in 0..m * m {
                let (rx, ry, rz) = (bx[k] - x.x, by[k] - x.y, bz[k] - x.z);
                let r2 = rx * rx + ry * ry + rz * rz;
                let ca = na.x * rx + na.y * ry + na.z * rz;
                let cb = nb.x * rx + nb.y * ry + nb.z * rz;
                terms[k] = bw[k] * ca * -cb / (r2 * r2);
            }
            let inner: f64 = terms[..m * m].iter().sum();
            sum += wx * inner;
        }
        sum / PI
    }

    /// The exchange area of a pair with candidate occluders in `s.occ`: the unoccluded
    /// exchange area less the integral, over the part Ω of the outer patch `s.pa` from which
    /// some occluder shadows the receiver `s.pb`, of the factor each point loses to the
    /// shadows. Ω and the umbra are exact (see [`Prepared::shadow_region`]), so a pair that no
    /// occluder shadows from anywhere is exactly unoccluded.
    fn occluded(
        &self,
        ia: usize,
        ib: usize,
        straddle: bool,
        size: f64,
        bvh: &Bvh,
        s: &mut Scratch,
    ) -> f64 {
        // The outer integral over the patch farther from the occluders: a shadow's edge on the
        // receiver then moves slowly with the outer point (the parallax is the ratio of the
        // occluder's distances to the two planes), and the sharp features near an occluder
        // that stands on or beside a patch fall in the exact inner integral.
        let (na, nb) = (self.patches[ia].normal, self.patches[ib].normal);
        let (oa, ob) = (self.patches[ia].v[0], self.patches[ib].v[0]);
        let (mut to_a, mut to_b) = (0.0, 0.0);
        for &c in &s.occ_centre {
            to_a += na.dot(c - oa);
            to_b += nb.dot(c - ob);
        }
        let (ia, ib) = if to_a < to_b {
            std::mem::swap(&mut s.pa, &mut s.pb);
            (ib, ia)
        } else {
            (ia, ib)
        };
        let (a, b) = (&self.patches[ia], &self.patches[ib]);
        let eps = 1e-9 * size;
        // Which occluders shadow the receiver from somewhere on the outer patch, and where.
        s.omega.clear();
        s.active.clear();
        s.planes.clear();
        s.plane_range.clear();
        for o in 0..s.occ_range.len() {
            if umbra(o, eps, s) {
                s.stats.occluded_hidden += 1;
                return 0.0;
            }
        }
        for o in 0..s.occ_range.len() {
            if Self::shadow_region(o, eps, s) {
                s.active.push(o as u32);
            }
        }
        if s.active.is_empty() {
            s.stats.occluded_clear += 1;
            return self.unoccluded(ia, ib, straddle, s);
        }
        if s.active.len() > MAX_ACTIVE {
            s.stats.sampled += 1;
            return self.sampled(ia, ib, straddle, bvh, s);
        }
        // Ω: the convex hull of the regions, in the outer patch's plane.
        convex_hull_in_plane(&s.omega, a.normal, &mut s.flat, &mut s.hull);
        if s.hull.len() < 3 {
            return self.unoccluded(ia, ib, straddle, s);
        }
        let tol = self.accuracy * a.area.min(b.area);
        let omega = std::mem::take(&mut s.hull);
        // When Ω is the whole outer patch the visible part may be integrated instead of the
        // lost one (and is, when it is the smaller: a pair hidden by several occluders
        // together is then exactly 0, not a difference of two nearly equal integrals).
        let whole_patch = polygon_area(&omega) >= (1.0 - 1e-9) * polygon_area(&s.pa);
        let regions = if omega.len() == 4 { 1 } else { omega.len() - 2 };
        // Only a whole patch may integrate what is seen; otherwise only the lost part counts.
        s.need = if whole_patch { Need::Both } else { Need::Lost };
        let mut cells = std::mem::take(&mut s.cells);
        cells.clear();
        // Each region once whole and once in four: the first estimates come from comparing
        // them (20 points a region), so a pair seen through a gap narrower than the region is
        // rarely missed by every point.
        for r in 0..regions {
            let whole = Cell {
                region: r as u8,
                u0: 0.0,
                v0: 0.0,
                h: 1.0,
                value: self.gauss(&omega, a.normal, size, r as u8, 0.0, 0.0, 1.0, s),
                err: [0.0; 2],
            };
            self.split_cell(&omega, a.normal, size, &whole, &mut cells, s);
        }
        let total = |cells: &[Cell], k: usize| cells.iter().map(|c| c.value[k]).sum::<f64>();
        // 0: the lost part (G = unoccluded − lost), 1: the visible part (G = visible).
        let k = usize::from(whole_patch && total(&cells, 1) < total(&cells, 0));
        s.need = if k == 1 { Need::Seen } else { Need::Lost };
        loop {
            let err: f64 = cells.iter().map(|c| c.err[k]).sum();
            if err <= tol {
                break;
            }
            if cells.len() + 3 > MAX_CELLS {
                s.stats.capped += 1;
                break;
            }
            let worst = cells
                .iter()
                .enumerate()
                .max_by(|x, y| x.1.err[k].total_cmp(&y.1.err[k]).then(y.0.cmp(&x.0)))
                .map(|(k, _)| k)
                .expect("cells");
            let parent = cells.swap_remove(worst);
            self.split_cell(&omega, a.normal, size, &parent, &mut cells, s);
        }
        let result = if k == 1 {
            total(&cells, 1)
        } else {
            self.unoccluded(ia, ib, straddle, s) - total(&cells, 0)
        };
        s.hull = omega;
        s.cells = cells;
        result.max(0.0)
    }

    /// A pair that more than [`MAX_ACTIVE`] occluders shadow (a large polygon seen past many
    /// others, where cutting every shadow out at every point costs their number times the
    /// pieces left): the exact unoccluded exchange area times the visible fraction, weighted by
    /// the point kernel, over the 4 × 4 by 4 × 4 Gauss–Legendre points of the two patches, each
    /// pair of points tested by a ray. Exact when the pair is wholly visible or wholly hidden;
    /// otherwise its error is that of the visible fraction on 256 point pairs.
    fn sampled(&self, ia: usize, ib: usize, straddle: bool, bvh: &Bvh, s: &mut Scratch) -> f64 {
        let (a, b) = (&self.patches[ia], &self.patches[ib]);
        let m = ORDERS;
        let ra = &self.rule[ia * RULE_START[ORDERS] + RULE_START[m - 1]..][..m * m];
        let rb = &self.rule[ib * RULE_START[ORDERS] + RULE_START[m - 1]..][..m * m];
        let off = bvh.ray_offset() as f64;
        let (mut all, mut seen) = (0.0, 0.0);
        for &(x, wx) in ra {
            for &(y, wy) in rb {
                let r = y - x;
                let (cx, cy) = (a.normal.dot(r), -b.normal.dot(r));
                if cx <= 0.0 || cy <= 0.0 {
                    continue;
                }
                let r2 = r.length_squared();
                let k = wx * wy * cx * cy / (r2 * r2);
                all += k;
                let from = x + a.normal * off;
                let to = y + b.normal * off;
                let d = to - from;
                let len = d.length();
                let ray = Ray::new(from.as_vec3(), (d / len).as_vec3());
                if !bvh.occluded(&ray, len as f32) {
                    seen += k;
                }
            }
        }
        s.stats.rays += (m * m * m * m) as u64;
        if seen == 0.0 {
            return 0.0;
        }
        self.unoccluded(ia, ib, straddle, s) * (seen / all)
    }

    /// Where occluder `o` of `s.occ` shadows the receiver `s.pb` from the outer patch `s.pa`
    /// (normal `na`). The points from which a convex occluder S hides part of a convex
    /// receiver B are those on S's side of every plane that separates S from B; the extreme
    /// ones touch both, through an edge of one and a corner of the other, or are S's own plane
    /// (the penumbra's boundary, Nishita & Nakamae 1985; Teller 1992); those found here are a
    /// subset, so the region they bound holds the true one. The region (the outer patch
    /// clipped by the separating planes) goes into `s.omega` and the planes into `s.planes`.
    fn shadow_region(o: usize, eps: f64, s: &mut Scratch) -> bool {
        let (start, len) = s.occ_range[o];
        let occ = &s.occ[start as usize..(start + len) as usize];
        let rec = &s.pb;
        let first_plane = s.planes.len();
        // Is the plane (m, h) (unnormalised, `slack` matching) separating? The occluder (S)
        // and the receiver (B) lie each wholly on one side, on opposite sides: then the plane,
        // normalised and facing S, bounds the region. Stops at the first corner that shows it
        // is not.
        let consider = |m: DVec3,
                        h: f64,
                        l: f64,
                        slack: f64,
                        [first, second]: [&[DVec3]; 2],
                        occ_first: bool,
                        planes: &mut Vec<(DVec3, f64)>| {
            // Side of a polygon: whether a corner lies above, and one below, by the slack.
            let side_of = |p: &[DVec3]| {
                let (mut above, mut below) = (false, false);
                for x in p {
                    let d = m.dot(*x) - h;
                    above |= d > slack;
                    below |= d < -slack;
                    if above && below {
                        return None;
                    }
                }
                Some((above, below))
            };
            let Some(f) = side_of(first) else {
                return;
            };
            let Some(g) = side_of(second) else {
                return;
            };
            let ((so_above, so_below), (sr_above, sr_below)) =
                if occ_first { (f, g) } else { (g, f) };
            let inv = 1.0 / l;
            if !so_above && !sr_below {
                // Occluder below (or on), receiver above (or on): the shadowing side is below.
                planes.push((-m * inv, -h * inv));
            } else if !so_below && !sr_above {
                planes.push((m * inv, h * inv));
            }
        };
        let tiny = 1e-24 * (eps * 1e9).powi(4);
        // The polygon of the plane's corner is asked first: the one of its edge lies on one
        // side (but for the slack), so it is the other that usually straddles.
        for (edges, corners, occ_corners) in
            [(occ, rec.as_slice(), false), (rec.as_slice(), occ, true)]
        {
            for (p, q) in edge_pairs(edges) {
                for &v in corners.iter() {
                    let m = (q - p).cross(v - p);
                    let l2 = m.length_squared();
                    if l2 > tiny {
                        let l = l2.sqrt();
                        consider(
                            m,
                            m.dot(p),
                            l,
                            eps * l,
                            [corners, edges],
                            occ_corners,
                            &mut s.planes,
                        );
                    }
                }
            }
        }
        // The occluder's own plane, when the receiver lies wholly on one side of it: the
        // points must be on the other side.
        let no = s.occ_normal[o];
        let ho = no.dot(occ[0]);
        let (sr, hr) = rec
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), x| {
                let d = no.dot(*x) - ho;
                (lo.min(d), hi.max(d))
            });
        let beyond = if sr >= -eps {
            Some((-no, -ho))
        } else if hr <= eps {
            Some((no, ho))
        } else {
            None
        };
        if let Some(p) = beyond {
            s.planes.push(p);
        }
        // The penumbra's region on the outer patch.
        s.inside.clear();
        s.inside.extend_from_slice(&s.pa);
        for k in first_plane..s.planes.len() {
            let (m, h) = s.planes[k];
            // Wholly on the plane's side: `clip` would give it back unchanged.
            let o = m * h;
            if s.inside.iter().all(|p| (*p - o).dot(m) + eps >= 0.0) {
                continue;
            }
            clip(&s.inside, o, m, eps, &mut s.tmp);
            std::mem::swap(&mut s.inside, &mut s.tmp);
            if s.inside.len() < 3 {
                s.planes.truncate(first_plane);
                return false;
            }
        }
        // A sliver a few slacks wide (an occluder that only touches the pair's hull, kept by
        // the clipping's slack) loses nothing measurable, but would stretch Ω over the whole
        // patch and thin the points where the real shadows are.
        let perimeter: f64 = edge_pairs(&s.pa).map(|(p, q)| (q - p).length()).sum();
        if polygon_area(&s.inside) <= 16.0 * eps * perimeter {
            s.planes.truncate(first_plane);
            return false;
        }
        s.omega.extend_from_slice(&s.inside);
        s.plane_range
            .push((first_plane as u32, (s.planes.len() - first_plane) as u32));
        true
    }

    /// Split `parent` into its four quarters, each with its 2 × 2 Gauss value of the factor lost
    /// to shadows, and each an equal share (a quarter) of the error estimate
    /// `|parent − Σ quarters|`: the whole difference, not a fraction of it, because along a
    /// penumbra's kink the composite rule's error falls only about fourfold a halving (16-fold
    /// where the integrand is smooth), so the difference bounds the quarters' error in either
    /// case.
    fn split_cell(
        &self,
        omega: &[DVec3],
        normal: DVec3,
        size: f64,
        parent: &Cell,
        cells: &mut Vec<Cell>,
        s: &mut Scratch,
    ) {
        let h = 0.5 * parent.h;
        let first = cells.len();
        let mut sum = [0.0; 2];
        for (du, dv) in [(0.0, 0.0), (h, 0.0), (0.0, h), (h, h)] {
            let (u0, v0) = (parent.u0 + du, parent.v0 + dv);
            let value = self.gauss(omega, normal, size, parent.region, u0, v0, h, s);
            sum[0] += value[0];
            sum[1] += value[1];
            cells.push(Cell {
                region: parent.region,
                u0,
                v0,
                h,
                value,
                err: [0.0; 2],
            });
        }
        let err = [0, 1].map(|k| (parent.value[k] - sum[k]).abs() / 4.0);
        for c in &mut cells[first..] {
            c.err = err;
        }
    }

    /// The 2 × 2 Gauss–Legendre values over the cell `[u0, u0 + h] × [v0, v0 + h]` of region
    /// `region` of Ω of the factor lost to shadows and of the factor still seen.
    #[allow(clippy::too_many_arguments)]
    fn gauss(
        &self,
        omega: &[DVec3],
        normal: DVec3,
        size: f64,
        region: u8,
        u0: f64,
        v0: f64,
        h: f64,
        s: &mut Scratch,
    ) -> [f64; 2] {
        const G: f64 = 0.211_324_865_405_187_1; // (1 − 1/√3) / 2
        let mut sum = [0.0; 2];
        for (pu, pv) in [(G, G), (1.0 - G, G), (G, 1.0 - G), (1.0 - G, 1.0 - G)] {
            let (x, jac) = map(omega, region, u0 + h * pu, v0 + h * pv);
            let (lost, seen) = self.blocked(x, normal, size, s);
            sum[0] += 0.25 * jac * lost;
            sum[1] += 0.25 * jac * seen;
        }
        s.stats.points += 4;
        [sum[0] * h * h, sum[1] * h * h]
    }

    /// The factor from the point `x` (normal `n`) to the part of the receiver `s.pb` that the
    /// active occluders hide: each occluder's pyramid from `x` cuts the visible pieces
    /// (Sutherland–Hodgman against its side planes), and what falls inside is measured by
    /// Lambert's formula; and the factor to the pieces left visible. Of the two only what
    /// `s.need` asks for is measured (the other is 0): when only the lost part counts, the last
    /// occluder's pyramid is cut from the pieces without keeping what lies outside it.
    fn blocked(&self, x: DVec3, n: DVec3, size: f64, s: &mut Scratch) -> (f64, f64) {
        let eps = 1e-11 * size;
        s.pieces.clear();
        s.ranges.clear();
        s.pieces.extend_from_slice(&s.pb);
        s.ranges.push((0, s.pb.len() as u32));
        let mut lost = 0.0;
        let (want_lost, want_seen) = match s.need {
            Need::Both => (true, true),
            Need::Lost => (true, false),
            Need::Seen => (false, true),
        };
        let last = s.active.len().saturating_sub(1);
        for idx in 0..s.active.len() {
            // Pieces outside this pyramid matter only to later occluders or to what is seen.
            let keep = want_seen || idx < last;
            let o = s.active[idx] as usize;
            // Only from its penumbra region does an occluder shadow the receiver.
            let (ps, pl) = s.plane_range[idx];
            if s.planes[ps as usize..(ps + pl) as usize]
                .iter()
                .any(|&(m, h)| m.dot(x) - h < -eps)
            {
                continue;
            }
            let (start, len) = s.occ_range[o];
            let w = s.occ_centre[o] - x;
            // x in the occluder's plane: its pyramid is flat and hides nothing.
            let dw = s.occ_normal[o].dot(w);
            if dw * dw <= 1e-24 * w.length_squared() {
                continue;
            }
            // The pyramid's side planes through x, normals pointing inwards, unnormalised,
            // each with the slack `eps` times its normal's length.
            s.cone.clear();
            let occ = &s.occ[start as usize..(start + len) as usize];
            let mut orient = 0.0;
            for (p, q) in edge_pairs(occ) {
                let m = (p - x).cross(q - x);
                let l = m.length();
                // All of one sign but for rounding (x is off the occluder's plane).
                orient += m.dot(w);
                s.cone.push((m, eps * l));
            }
            if orient < 0.0 {
                for m in &mut s.cone {
                    m.0 = -m.0;
                }
            }
            // Wholly outside one side plane (within the slack): `None`. Otherwise the side
            // planes the piece lies wholly inside, beyond the slack (bit k for plane k), which
            // cutting would give back unchanged: the piece is lost whole when that is all of
            // them, and the parts cut from it stay inside them too (but for rounding).
            let classify = |poly: &[DVec3], cone: &[(DVec3, f64)]| {
                let mut inside = 0u64;
                for (k, &(m, e)) in cone.iter().enumerate() {
                    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
                    for p in poly {
                        let d = m.dot(*p - x);
                        lo = lo.min(d);
                        hi = hi.max(d);
                    }
                    if hi <= e {
                        return None;
                    }
                    if lo > e && k < 64 {
                        inside |= 1 << k;
                    }
                }
                Some(inside)
            };
            // Subtract the pyramid from every piece; what lies inside it is lost.
            s.next.clear();
            s.next_ranges.clear();
            for r in 0..s.ranges.len() {
                let (ps, pl) = s.ranges[r];
                let piece = &s.pieces[ps as usize..(ps + pl) as usize];
                let all = if s.cone.len() >= 64 {
                    0
                } else {
                    (1u64 << s.cone.len()) - 1
                };
                let inside = classify(piece, &s.cone);
                match inside {
                    None => {
                        if keep {
                            let at = s.next.len() as u32;
                            s.next.extend_from_slice(piece);
                            s.next_ranges.push((at, pl));
                        }
                        continue;
                    }
                    Some(k) if k == all && all != 0 => {
                        if want_lost {
                            lost += point_polygon(x, n, piece);
                        }
                        continue;
                    }
                    Some(_) => {}
                }
                let inside = inside.unwrap_or(0);
                s.inside.clear();
                s.inside.extend_from_slice(piece);
                for k in 0..s.cone.len() {
                    if k < 64 && inside >> k & 1 == 1 {
                        continue;
                    }
                    let (m, e) = s.cone[k];
                    if keep {
                        split(&s.inside, m, x, e, &mut s.tmp, &mut s.outside);
                        if s.outside.len() >= 3 {
                            let at = s.next.len() as u32;
                            s.next.extend_from_slice(&s.outside);
                            s.next_ranges.push((at, s.outside.len() as u32));
                        }
                    } else {
                        keep_inside(&s.inside, m, x, e, &mut s.tmp);
                    }
                    std::mem::swap(&mut s.inside, &mut s.tmp);
                    if s.inside.len() < 3 {
                        break;
                    }
                }
                if want_lost && s.inside.len() >= 3 {
                    lost += point_polygon(x, n, &s.inside);
                }
            }
            std::mem::swap(&mut s.pieces, &mut s.next);
            std::mem::swap(&mut s.ranges, &mut s.next_ranges);
            if s.ranges.is_empty() {
                break;
            }
        }
        let mut seen = 0.0;
        if want_seen {
            for &(ps, pl) in &s.ranges {
                seen += point_polygon(x, n, &s.pieces[ps as usize..(ps + pl) as usize]);
            }
        }
        (lost, seen)
    }
}

/// Whether every segment from a corner of `outer` to a corner of `rec` (on opposite sides of
/// the plane of the convex occluder `occ`, unit normal `no`) crosses `occ` more than `eps`
/// inside each of its edges. The crossing of the segment `a b` is `(a d_b − b d_a) / (d_b −
/// d_a)` (`d` the signed distances to the plane), so each edge's test is a sign with no
/// division.
fn corners_cross(occ: &[DVec3], no: DVec3, outer: &[DVec3], rec: &[DVec3], eps: f64) -> bool {
    const MAX: usize = 16;
    if occ.len() > MAX {
        return outer.iter().all(|&x| hides(x, occ, rec, eps));
    }
    let ho = no.dot(occ[0]);
    // Each edge's inward normal in the plane, and its offset moved `eps` inwards.
    let turn: f64 = edge_pairs(occ).map(|(p, q)| p.cross(q).dot(no)).sum();
    let sign = if turn < 0.0 { -1.0 } else { 1.0 };
    let mut edges = [(DVec3::ZERO, 0.0); MAX];
    for (e, (p, q)) in edges.iter_mut().zip(edge_pairs(occ)) {
        let g = no.cross(q - p) * sign;
        *e = (g, g.dot(p) + eps * g.length());
    }
    let edges = &edges[..occ.len()];
    outer.iter().all(|&a| {
        let da = no.dot(a) - ho;
        rec.iter().all(|&b| {
            let db = no.dot(b) - ho;
            let (x, d) = if db > da {
                (a * db - b * da, db - da)
            } else {
                (b * da - a * db, da - db)
            };
            edges.iter().all(|&(g, c)| g.dot(x) - d * c > 0.0)
        })
    })
}

/// Whether the convex occluder `occ` hides every corner of the convex receiver `rec` from the
/// point `x`: each corner strictly inside the pyramid from `x` over `occ` (the occluder being
/// between `x` and the receiver, as the occluders of a pair are clipped to be).
fn hides(x: DVec3, occ: &[DVec3], rec: &[DVec3], eps: f64) -> bool {
    let c = occ.iter().copied().sum::<DVec3>() / occ.len() as f64;
    edge_pairs(occ).all(|(p, q)| {
        let m = (p - x).cross(q - x);
        let l = m.length();
        if l <= 0.0 {
            return false;
        }
        let m = if m.dot(c - x) < 0.0 { -m / l } else { m / l };
        rec.iter().all(|p| m.dot(*p - x) > eps)
    })
}

/// Whether occluder `o` of `s.occ` hides all of the receiver `s.pb` from all of the outer
/// patch `s.pa`. The umbra, the points from which a convex occluder hides all of a convex
/// receiver, is convex (the intersection over the receiver's points of the convex regions
/// behind the occluder seen from each), so it holds the outer patch when it holds its corners;
/// it holds a corner beyond the occluder's plane when the receiver's corners all lie inside
/// the pyramid over the occluder from it, that is when the segments from it to them all cross
/// the occluder ([`corners_cross`]).
fn umbra(o: usize, eps: f64, s: &Scratch) -> bool {
    let (start, len) = s.occ_range[o];
    let occ = &s.occ[start as usize..(start + len) as usize];
    umbra_of(occ, s.occ_normal[o], &s.pa, &s.pb, eps)
}

/// [`umbra`] of the occluder `occ` (unit normal `no`), the outer patch `outer` and the
/// receiver `rec`.
fn umbra_of(occ: &[DVec3], no: DVec3, outer: &[DVec3], rec: &[DVec3], eps: f64) -> bool {
    let ho = no.dot(occ[0]);
    // The receiver wholly on one side of the occluder's plane, every outer corner strictly on
    // the other (from a point in the plane the pyramid is flat).
    let side = |p: &DVec3| no.dot(*p) - ho;
    let receiver_above = rec.iter().all(|p| side(p) >= -eps);
    let receiver_below = rec.iter().all(|p| side(p) <= eps);
    let beyond = if receiver_above {
        outer.iter().all(|p| side(p) < -eps)
    } else if receiver_below {
        outer.iter().all(|p| side(p) > eps)
    } else {
        false
    };
    beyond && corners_cross(occ, no, outer, rec, eps)
}

/// The convex hull of `points` (lying in a plane with unit normal `n`), counter-clockwise
/// about `n`, into `out` (Andrew's monotone chain in the plane's coordinates; `flat` is its
/// buffer).
fn convex_hull_in_plane(
    points: &[DVec3],
    n: DVec3,
    flat: &mut Vec<(f64, f64, u32)>,
    out: &mut Vec<DVec3>,
) {
    out.clear();
    flat.clear();
    if points.len() < 3 {
        return;
    }
    let e1 = n.any_orthonormal_vector();
    let e2 = n.cross(e1);
    flat.extend(
        points
            .iter()
            .enumerate()
            .map(|(k, x)| (x.dot(e1), x.dot(e2), k as u32)),
    );
    flat.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    let m = flat.len();
    // The chain is built in place after the sorted points: lower hull, then upper.
    let cross = |o: (f64, f64, u32), a: (f64, f64, u32), b: (f64, f64, u32)| {
        (a.0 - o.0) * (b.1 - o.1) - (a.1 - o.1) * (b.0 - o.0)
    };
    for pass in 0..2 {
        let base = flat.len();
        for k in 0..m {
            let q = if pass == 0 { flat[k] } else { flat[m - 1 - k] };
            while flat.len() >= base + 2
                && cross(flat[flat.len() - 2], flat[flat.len() - 1], q) <= 0.0
            {
                flat.pop();
            }
            flat.push(q);
        }
        flat.pop();
    }
    out.extend(flat[m..].iter().map(|q| points[q.2 as usize]));
    // With e2 = n × e1 the chain runs counter-clockwise about n.
}

/// The 1, 2 × 2, 3 × 3 and 4 × 4 Gauss–Legendre points of a patch, weights summing to its
/// area: through the bilinear map of a quad, the collapsed map of a triangle.
fn gauss_points(p: &Patch) -> Vec<(DVec3, f64)> {
    let mut out = Vec::with_capacity(RULE_START[ORDERS]);
    let poly = p.corners();
    for m in 1..=ORDERS {
        let (x, w) = super::quadrature::gauss_legendre(m);
        let mut pts = Vec::with_capacity(m * m);
        for (u, wu) in x.iter().zip(&w) {
            for (v, wv) in x.iter().zip(&w) {
                let (q, jac) = map(poly, 0, *u, *v);
                pts.push((q, wu * wv * jac));
            }
        }
        // Weights sum to the area exactly (the maps are exact for planar polygons).
        let total: f64 = pts.iter().map(|q| q.1).sum();
        let area = polygon_area(poly);
        out.extend(pts.into_iter().map(|(q, w)| (q, w * area / total)));
    }
    out
}

/// Point `(u, v)` of region `region` of a convex polygon and the map's Jacobian: a quad through
/// its bilinear map; otherwise triangle `region` of the fan from corner 0, through the
/// collapsed map `p0 + u (p1 − p0) + u v (p2 − p1)`.
fn map(poly: &[DVec3], region: u8, u: f64, v: f64) -> (DVec3, f64) {
    if poly.len() == 4 {
        let [p0, p1, p2, p3] = [poly[0], poly[1], poly[2], poly[3]];
        let x = p0 * ((1.0 - u) * (1.0 - v))
            + p1 * (u * (1.0 - v))
            + p2 * (u * v)
            + p3 * ((1.0 - u) * v);
        let du = (p1 - p0) * (1.0 - v) + (p2 - p3) * v;
        let dv = (p3 - p0) * (1.0 - u) + (p2 - p1) * u;
        (x, du.cross(dv).length())
    } else {
        let r = region as usize;
        let (p0, p1, p2) = (poly[0], poly[r + 1], poly[r + 2]);
        let x = p0 + (p1 - p0) * u + (p2 - p1) * (u * v);
        (x, u * (p1 - p0).cross(p2 - p1).length())
    }
}

/// The edges `(p_k, p_{k+1})` of a polygon, `k = 0, …, n − 1`, the last closing it.
fn edge_pairs(p: &[DVec3]) -> impl Iterator<Item = (DVec3, DVec3)> + '_ {
    let n = p.len();
    (0..n).map(move |k| (p[k], p[if k + 1 == n { 0 } else { k + 1 }]))
}

/// Area of a planar polygon (Newell).
fn polygon_area(p: &[DVec3]) -> f64 {
    let mut s = DVec3::ZERO;
    for k in 1..p.len().saturating_sub(1) {
        s += (p[k] - p[0]).cross(p[k + 1] - p[0]);
    }
    0.5 * s.length()
}

/// Keep the part of `poly` where `(p − origin) · normal ≥ -slack`.
fn clip(poly: &[DVec3], origin: DVec3, normal: DVec3, slack: f64, out: &mut Vec<DVec3>) {
    out.clear();
    let n = poly.len();
    for k in 0..n {
        let (a, b) = (poly[k], poly[(k + 1) % n]);
        let (da, db) = (
            (a - origin).dot(normal) + slack,
            (b - origin).dot(normal) + slack,
        );
        if da >= 0.0 {
            out.push(a);
        }
        if (da > 0.0 && db < 0.0) || (da < 0.0 && db > 0.0) {
            out.push(a + (b - a) * (da / (da - db)));
        }
    }
}

/// `poly` clipped to the front of two planes (each an origin and a normal, no slack), into
/// `out` (`tmp` between), as [`clip`] twice; a plane that has `poly` wholly in front is
/// skipped (`clip` would give it back unchanged).
fn clip_between(
    poly: &[DVec3],
    [(oa, na), (ob, nb)]: [(DVec3, DVec3); 2],
    tmp: &mut Vec<DVec3>,
    out: &mut Vec<DVec3>,
) {
    let front = |p: &[DVec3], o: DVec3, n: DVec3| p.iter().all(|a| (*a - o).dot(n) + 0.0 >= 0.0);
    let src: &[DVec3] = if front(poly, oa, na) {
        poly
    } else {
        clip(poly, oa, na, 0.0, tmp);
        tmp
    };
    if front(src, ob, nb) {
        out.clear();
        out.extend_from_slice(src);
    } else {
        clip(src, ob, nb, 0.0, out);
    }
}

/// Split the convex `poly` by the plane through `x` with normal `m`: the part with
/// `m · (p − x) ≥ 0` into `inside`, the rest into `outside` (points with `|m · (p − x)| ≤ eps`,
/// within `eps / |m|` of the plane, go to both).
fn split(
    poly: &[DVec3],
    m: DVec3,
    x: DVec3,
    eps: f64,
    inside: &mut Vec<DVec3>,
    outside: &mut Vec<DVec3>,
) {
    cut(poly, m, x, eps, inside, Some(outside));
}

/// The part of the convex `poly` with `m · (p − x) ≥ 0` into `inside`, exactly as [`split`]
/// makes it, without the other part.
fn keep_inside(poly: &[DVec3], m: DVec3, x: DVec3, eps: f64, inside: &mut Vec<DVec3>) {
    cut(poly, m, x, eps, inside, None);
}

/// [`split`]'s one pass over the edges, the outside part kept only when asked for.
fn cut(
    poly: &[DVec3],
    m: DVec3,
    x: DVec3,
    eps: f64,
    inside: &mut Vec<DVec3>,
    mut outside: Option<&mut Vec<DVec3>>,
) {
    inside.clear();
    if let Some(o) = outside.as_deref_mut() {
        o.clear();
    }
    let side = |p: DVec3| {
        let d = m.dot(p - x);
        if d.abs() <= eps {
            0.0
        } else {
            d
        }
    };
    let n = poly.len();
    let mut d0 = side(poly[0]);
    for k in 0..n {
        let a = poly[k];
        let b = poly[(k + 1) % n];
        let da = d0;
        let db = side(b);
        if da >= 0.0 {
            inside.push(a);
        }
        if da <= 0.0 {
            if let Some(o) = outside.as_deref_mut() {
                o.push(a);
            }
        }
        if (da > 0.0 && db < 0.0) || (da < 0.0 && db > 0.0) {
            let p = a + (b - a) * (da / (da - db));
            inside.push(p);
            if let Some(o) = outside.as_deref_mut() {
                o.push(p);
            }
        }
        d0 = db;
    }
    if inside.len() < 3 {
        inside.clear();
    }
    if let Some(o) = outside {
        if o.len() < 3 {
            o.clear();
        }
    }
}

/// The exact factor from a point `x` with unit normal `n` to the convex polygon `p`
/// (counter-clockwise about its own normal, facing `x`, wholly in front of `x`): Lambert's
/// contour formula `F = (1/2π) Σ_k γ_k n · (r_k × r_{k+1}) / |r_k × r_{k+1}|`, `r_k = p_k − x`,
/// `γ_k` the angle between `r_k` and `r_{k+1}` (Howell's catalogue, B-0; Sillion & Puech 1994,
/// eq. 4.24). The receiver faces the point, so its corners run clockwise as seen from it and
/// the sum is negated.
pub fn point_polygon(x: DVec3, n: DVec3, p: &[DVec3]) -> f64 {
    let mut sum = 0.0;
    let mut r2 = p[0] - x;
    for (_, q) in edge_pairs(p) {
        let r1 = r2;
        r2 = q - x;
        let g = r1.cross(r2);
        // An edge whose plane through x contains the normal adds nothing (a wall's
        // vertical edge seen from the floor): no angle needed.
        let ng = n.dot(g);
        if ng == 0.0 {
            continue;
        }
        let gl = g.length();
        if gl <= 0.0 {
            continue;
        }
        // atan2(y, x) = atan(y / x) for x > 0 (the common case: an edge seen under less
        // than a right angle), which costs about half as much.
        let c = r1.dot(r2);
        let angle = if c > 0.0 {
            (gl / c).atan()
        } else {
            gl.atan2(c)
        };
        sum += angle * ng / gl;
    }
    -sum / (2.0 * PI)
}

/// Of the candidates `s.found` of two whole occluders (`s.pa`, normal `na`, and `s.pb`,
/// normal `nb`, each clipped to the other's front), keep those that shadow one from somewhere
/// on the other ([`Prepared::shadow_region`]); true when one of them hides all of `s.pb` from
/// all of `s.pa` ([`umbra`]). The slack is a thousandth of a pair's, so that what is dropped
/// is dropped at every pair of their patches too.
fn group_shadows(occ: &Occluders, na: DVec3, nb: DVec3, s: &mut Scratch) -> bool {
    let (mut lo, mut hi) = (s.pa[0], s.pa[0]);
    for p in s.pa.iter().chain(&s.pb) {
        lo = lo.min(*p);
        hi = hi.max(*p);
    }
    let size = (hi - lo).length();
    let eps = 1e-12 * size;
    let (oa, ob) = (s.pa[0], s.pb[0]);
    let mut kept = 0;
    for idx in 0..s.found.len() {
        let k = s.found[idx];
        let poly = occ.polygon(k);
        let flat = |n: DVec3, o: DVec3| poly.iter().all(|p| n.dot(*p - o).abs() <= eps);
        if flat(na, oa) || flat(nb, ob) {
            continue;
        }
        clip_between(poly, [(oa, na), (ob, nb)], &mut s.tmp, &mut s.inside);
        if s.inside.len() < 3 || polygon_area(&s.inside) <= 1e-14 * size * size {
            continue;
        }
        s.occ.clear();
        s.occ.extend_from_slice(&s.inside);
        s.occ_range.clear();
        s.occ_range.push((0, s.inside.len() as u32));
        s.occ_normal.clear();
        s.occ_normal.push(occ.normal(k));
        if umbra(0, eps, s) {
            return true;
        }
        s.planes.clear();
        s.plane_range.clear();
        s.omega.clear();
        if Prepared::shadow_region(0, eps, s) {
            s.found[kept] = k;
            kept += 1;
        }
    }
    s.found.truncate(kept);
    false
}

/// One occluder's candidate pairs and their members, as `group_table` gathers them.
type GroupRows = (Vec<(u32, u32)>, Vec<u32>);

/// The candidates of every pair of occluders that face each other.
fn group_table(occ: &Occluders) -> GroupTable {
    let g = occ.len();
    let per: Vec<GroupRows> = (0..g)
        .into_par_iter()
        .map_init(Scratch::default, |s, p| {
            let mut ranges = Vec::with_capacity(g - p);
            let mut cands = Vec::new();
            let (np, ppoly) = (occ.normal(p as u32), occ.polygon(p as u32));
            for q in p..g {
                let (nq, qpoly) = (occ.normal(q as u32), occ.polygon(q as u32));
                clip(ppoly, qpoly[0], nq, 0.0, &mut s.pa);
                clip(qpoly, ppoly[0], np, 0.0, &mut s.pb);
                let facing = q != p
                    && s.pa.len() >= 3
                    && s.pb.len() >= 3
                    && polygon_area(&s.pa) > 0.0
                    && polygon_area(&s.pb) > 0.0;
                if !facing {
                    ranges.push((0, NOT_FACING));
                    continue;
                }
                s.shaft.set(&s.pa, np, &s.pb, nq);
                occ.query(&s.shaft, [p as u32, q as u32], &mut s.stack, &mut s.found);
                if group_shadows(occ, np, nq, s) {
                    ranges.push((0, HIDDEN));
                    continue;
                }
                ranges.push((cands.len() as u32, s.found.len() as u32));
                cands.extend_from_slice(&s.found);
            }
            (ranges, cands)
        })
        .collect();
    let mut ranges = vec![(0u32, NOT_FACING); g * g];
    let mut candidates = Vec::new();
    for (p, (r, c)) in per.into_iter().enumerate() {
        let base = candidates.len() as u32;
        for (k, &(start, len)) in r.iter().enumerate() {
            ranges[p * g + p + k] = if len == NOT_FACING || len == HIDDEN {
                (0, len)
            } else {
                (base + start, len)
            };
        }
        candidates.extend(c);
    }
    GroupTable {
        groups: g,
        ranges,
        candidates,
    }
}

/// Row `i` of F: every pair's exchange area over `A_i`.
pub(super) fn row(est: &Estimator, i: usize, scratch: &mut super::Scratch) {
    let prep = est
        .adaptive
        .as_ref()
        .expect("prepared for the adaptive method");
    let ai = prep.patches[i].area;
    let mut facing = std::mem::take(&mut scratch.adaptive.facing);
    prep.facing_groups(i, &mut facing);
    let gi = prep.occluders.group[i];
    for j in 0..prep.patches.len() {
        // The pair's skip as the matrix decides it: from the lower index's side.
        let faces = match j.cmp(&i) {
            std::cmp::Ordering::Less => prep.group_faces(j, gi),
            std::cmp::Ordering::Equal => false,
            std::cmp::Ordering::Greater => facing[prep.occluders.group[j] as usize],
        };
        if !faces {
            continue;
        }
        // Rounded as the whole matrix rounds it, so the two give the same bits.
        let g = prep.exchange(i, j, est.bvh, &mut scratch.adaptive) as f32;
        if g > 0.0 {
            scratch.add(j as u32, g as f64 / ai);
        }
    }
    scratch.adaptive.facing = facing;
    prep.flush(&mut scratch.adaptive.stats);
}

/// Every row: each pair's exchange area once (rows in parallel, row `i` computing the pairs
/// `j > i`), both entries from it.
pub(super) fn matrix(est: &Estimator, storage: Storage, observer: &dyn Observer) -> Matrix {
    let prep = est
        .adaptive
        .as_ref()
        .expect("prepared for the adaptive method");
    let n = prep.patches.len();
    observer.event(Event::Stage(Stage::FormFactors));
    let done = AtomicU64::new(0);
    // Exchange areas in f32 (the entries are stored in f32 anyway): 8 bytes a pair.
    let upper: Vec<Vec<(u32, f32)>> = (0..n)
        .into_par_iter()
        .map_init(Scratch::default, |s, i| {
            let mut row = Vec::new();
            let mut facing = std::mem::take(&mut s.facing);
            prep.facing_groups(i, &mut facing);
            for j in i + 1..n {
                if !facing[prep.occluders.group[j] as usize] {
                    continue;
                }
                let g = prep.exchange(i, j, est.bvh, s);
                if g > 0.0 {
                    row.push((j as u32, g as f32));
                }
            }
            s.facing = facing;
            prep.flush(&mut s.stats);
            observer.event(Event::Progress {
                stage: Stage::FormFactors,
                done: done.fetch_add(1, Relaxed) + 1,
                total: n as u64,
            });
            row
        })
        .collect();
    // Both triangles straight into one compressed-row array: row r holds its lower part
    // (i < r, from the rows above, ascending) then its upper part, sorted by column, with no
    // per-row copies in between; each upper row is freed once spread.
    let mut row_ptr = vec![0usize; n + 1];
    for (i, r) in upper.iter().enumerate() {
        row_ptr[i + 1] += r.len();
        for &(j, _) in r {
            row_ptr[j as usize + 1] += 1;
        }
    }
    for k in 0..n {
        row_ptr[k + 1] += row_ptr[k];
    }
    let mut next = row_ptr[..n].to_vec();
    let mut flat: Vec<Entry> = vec![(0, 0.0); row_ptr[n]];
    for (i, r) in upper.into_iter().enumerate() {
        let ai = prep.patches[i].area;
        for (j, g) in r {
            let (g, aj) = (g as f64, prep.patches[j as usize].area);
            flat[next[j as usize]] = (i as u32, (g / aj) as f32);
            next[j as usize] += 1;
            flat[next[i]] = (j, (g / ai) as f32);
            next[i] += 1;
        }
    }
    let dense = match storage {
        Storage::Dense => true,
        Storage::Sparse => false,
        Storage::Auto => n <= super::DENSE_MAX,
    };
    if dense {
        let mut values = vec![0.0f32; n * n];
        for i in 0..n {
            for &(j, f) in &flat[row_ptr[i]..row_ptr[i + 1]] {
                values[i * n + j as usize] = f;
            }
        }
        Matrix::Dense { n, values }
    } else {
        Matrix::Sparse(SparseMatrix::from_csr(n, row_ptr, flat))
    }
}
