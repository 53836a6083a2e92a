//! Whole-disc sun visibility: whether every direction from a point to the sun's disc meets the
//! same surfaces, decided exactly for the cone of those directions, so that a point wholly in
//! the sun or wholly in shadow needs one ray instead of a disc's worth.
//!
//! The sun's disc seen from a point `o` is the cone of directions within the half-angle α
//! (0.2665°) of its centre `c`. A convex planar polygon and the cone meet in one of three
//! ways, each decided from the polygon's corners alone:
//!
//! - **Miss**: no direction of the cone reaches the polygon. Either the plane through `o` and
//!   one edge separates the cone from the polygon (the angle from `c` to that plane is at least
//!   α, on the far side from the polygon's centre: the wedge `m · (x − o) ≥ 0` of the edge's
//!   plane holds the whole polygon, and a direction `d` with `m · d < 0` never enters it), or
//!   every direction of the cone runs parallel to or away from the polygon's plane (the angle
//!   β between `c` and the normal facing the plane satisfies β − α ≥ 90°).
//! - **Cover**: every direction of the cone reaches the polygon, in front of `o`: each
//!   direction meets the plane at t > 0 (β + α < 90°) and lies inside every edge's wedge (the
//!   angle from `c` to each edge's plane is at least α on the polygon's side); the wedges'
//!   intersection cut by the plane is the polygon.
//! - **Partial**: anything else (an edge's plane passes within α of `c`, or the cone grazes
//!   the plane).
//!
//! A cone that no polygon meets partly is then **Clear** (every direction passes the same
//! panes, whole, as the centre does) unless an opaque polygon covers it (**Blocked**); the
//! sun's light at `o` is then cos θ_c τ(c) or 0 exactly as every disc sample finds it, and
//! only a **Partial** cone, a point in a penumbra, is sampled. The decision is the cone
//! against each polygon, found by a binary hierarchy over the polygons' boxes whose slabs are
//! widened by the cone's radius where it leaves the scene's box (conservative). Polygons are the mesh
//! patches, a planar convex quad whole, any other patch as its two triangles (the ray
//! caster's split), so a seam between two polygons is Partial along its shadow: sampled, not
//! wrong.
//!
//! Two refinements keep the sampling for true penumbrae:
//!
//! - **Seams.** A cone cut by one edge of each of two opaque polygons, and otherwise inside
//!   both, is covered by the two together when the two edges' planes through the point are
//!   one plane and the polygons lie on its opposite sides: every direction on one side meets
//!   that side's polygon. Walls in pieces around a window (T-junctions included), and two
//!   walls at a corner, then block the disc over their seam without sampling ([`SunCones`]'s
//!   `seam_covers`). A seam between panes is still sampled.
//! - **Groups of suns.** The same tests hold for a wider cone: the disc about every direction
//!   within a spread s of an axis lies in the cone of half-angle α + s about it, and a
//!   polygon that this cone misses or covers is missed or covered by each disc inside it. An
//!   annual run's suns at one hour of the day over a week lie within about 1.5° of each other,
//!   so [`SunGroups`] gathers the suns into a tree by direction and a point decides a group
//!   at once ([`SunCones::classify_wide`]), splitting it only where it is partial. A Clear
//!   group lists its panes, and each sun's τ comes from a table by pane class and sun (the
//!   same arithmetic as the sun alone, so every value is bit for bit the single sun's).
//!
//! The same idea, classifying a pencil of rays against polygons by separating planes through
//! the apex and edges, is the shadow-volume test of Nishita & Nakamae (1985) and the
//! umbra/penumbra split of Teller (1992), applied here to the sun's narrow cone.

use super::panes::Panes;
use crate::lighting::glazing::Glazing;
use crate::mesh::Mesh;
use glam::DVec3;

/// What the cone of directions from a point to the sun's disc meets.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Cone {
    /// No opaque polygon meets the cone and every pane it meets covers it whole: every
    /// direction of the disc fares as its centre, which crosses panes of this product of
    /// transmittances τ(θ) (1 when none).
    Clear(f64),
    /// An opaque polygon covers the whole cone in front of the point.
    Blocked,
    /// Some polygon meets part of the cone: the disc must be sampled.
    Partial,
}

/// What a wide cone about a group of suns' directions meets ([`SunCones::classify_wide`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Wide {
    /// An opaque polygon covers the whole cone: every sun of the group is blocked.
    Blocked,
    /// No opaque polygon meets the cone and these panes (`panes[..count]`) each cover it.
    Clear {
        panes: [u32; WIDE_PANES],
        count: usize,
    },
    /// Some polygon meets part of the cone, or it crosses more than [`WIDE_PANES`] panes.
    Partial,
}

/// The widest spread (degrees) of a group of suns decided at once: a week's suns at one hour
/// of the day lie within about 1.5° of their mean, and suns an hour apart 15° apart, so
/// groups wider than this are rarely decided whole and are split instead.
pub(crate) const WIDEST: f64 = 5.0;

/// Most panes a wide cone's Clear answer lists.
pub(crate) const WIDE_PANES: usize = 4;

/// A cone's half-angle, as its sine (the planes' test) and tangent (the boxes' widening).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Aperture {
    sin_a: f64,
    tan_a: f64,
}

/// A cone against every polygon.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Outcome {
    Clear,
    Blocked,
    Partial,
}

/// A polygon against a cone.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Meets {
    Miss,
    Cover,
    /// Partly: the bits of the edges whose planes cut the cone, every other edge's wedge
    /// and the plane's front side holding it whole; 0 when the cone grazes the plane or the
    /// point lies on an edge's line or in the plane (nothing more to say).
    Partial(u8),
}

/// A convex planar polygon of three or four corners.
#[derive(Clone, Copy, Debug)]
struct Convex {
    corners: [DVec3; 4],
    count: usize,
    normal: DVec3,
    centre: DVec3,
    /// The pane it is, None for an opaque polygon.
    pane: Option<Glazing>,
}

impl Convex {
    /// The transmittance τ(θ) along the unit direction `c` (1 for an opaque polygon, which
    /// no caller asks).
    #[inline]
    fn transmittance(&self, c: DVec3) -> f64 {
        self.pane
            .map_or(1.0, |g| g.transmittance(self.normal.dot(c)))
    }
}

/// A node of the hierarchy: its box, and either two children (`count == 0`, the first at
/// `first`, the second at `first + 1`) or `count` polygons from `first`.
#[derive(Clone, Copy, Debug)]
struct Node {
    lo: DVec3,
    hi: DVec3,
    first: u32,
    count: u32,
}

/// Most polygons in a leaf.
const LEAF: usize = 2;
/// Depth of the traversal stack; a deeper hierarchy's query answers Partial (sampled).
const STACK: usize = 64;
/// Widening of the cone (radians) so that the single-precision rays of the disc samples, which
/// decide a hit within about 10⁻⁶ of an edge, agree with a decision made in double precision.
const MARGIN: f64 = 2e-5;

/// The opaque polygons and panes of a scene, ready for cone queries.
pub(crate) struct SunCones {
    polygons: Vec<Convex>,
    nodes: Vec<Node>,
    /// Each pane's class (panes of one glazing and one normal up to sign pass the same
    /// τ(θ) in every direction), [`NONE`] for opaque polygons and past [`CLASSES`] classes.
    class: Vec<u32>,
    /// Each class's pane (its first).
    classes: Vec<u32>,
    /// The sun's half-angle, widened by [`MARGIN`].
    half_angle: f64,
    sin_a: f64,
    tan_a: f64,
}

impl SunCones {
    /// The patches of `opaque` (opaque) and `panes` (seen through) for cones of half-angle
    /// `half_angle` radians (widened by [`MARGIN`]). Degenerate patches (no area) are left
    /// out: rays do not meet them.
    pub(crate) fn new(opaque: &Mesh, panes: Option<&Panes>, half_angle: f64) -> SunCones {
        let mut polygons = Vec::new();
        add_mesh(opaque, &|_| None, &mut polygons);
        if let Some(p) = panes {
            add_mesh(p.mesh(), &|m| Some(p.glazing(m)), &mut polygons);
        }
        SunCones::of(polygons, half_angle)
    }

    /// The hierarchy over `polygons`.
    fn of(mut polygons: Vec<Convex>, half_angle: f64) -> SunCones {
        let half_angle = half_angle + MARGIN;
        let mut nodes = Vec::with_capacity(2 * polygons.len() / LEAF + 1);
        if !polygons.is_empty() {
            let n = polygons.len();
            nodes.push(Node {
                lo: DVec3::ZERO,
                hi: DVec3::ZERO,
                first: 0,
                count: 0,
            });
            build(&mut polygons, 0, n, 0, &mut nodes);
        }
        let (class, classes) = pane_classes(&polygons);
        SunCones {
            polygons,
            nodes,
            class,
            classes,
            half_angle,
            sin_a: half_angle.sin(),
            tan_a: half_angle.tan(),
        }
    }

    /// The sine of the (widened) half-angle: a receiver whose normal `n` has `n · c` above
    /// it sees the whole cone above its horizon.
    pub(crate) fn horizon_margin(&self) -> f32 {
        self.sin_a as f32
    }

    /// What the cone from `o` about the direction `c` (normalised here) meets. No allocation.
    #[cfg(test)]
    pub(crate) fn classify(&self, o: DVec3, c: DVec3) -> Cone {
        self.classify_from(&mut Viewpoint::new(o), c)
    }

    /// What the cone from the viewpoint's point about the direction `c` (normalised here)
    /// meets, trying first the opaque polygons that blocked the point's latest cones (a
    /// shadow cache, Haines & Greenberg 1986) and taking each polygon's set-up from the
    /// viewpoint. The answer is the same whatever the viewpoint holds: a cone is Blocked as
    /// soon as any opaque polygon covers it, and each polygon is decided by the same
    /// arithmetic. No allocation.
    pub(crate) fn classify_from(&self, v: &mut Viewpoint, c: DVec3) -> Cone {
        let c = c.normalize_or_zero();
        if c == DVec3::ZERO {
            return Cone::Partial;
        }
        let mut tau = 1.0;
        let narrow = Aperture {
            sin_a: self.sin_a,
            tan_a: self.tan_a,
        };
        match self.decide(v, c, narrow, &mut |_, p| {
            tau *= p.transmittance(c);
            true
        }) {
            Outcome::Clear => Cone::Clear(tau),
            Outcome::Blocked => Cone::Blocked,
            Outcome::Partial => Cone::Partial,
        }
    }

    /// The aperture of a cone that holds the disc about every direction within `spread`
    /// radians of an axis (the sun's half-angle, widened, plus `spread`); None when it is too
    /// wide to be worth deciding (`spread` over [`WIDEST`] degrees), or not a finite angle.
    pub(crate) fn aperture(&self, spread: f64) -> Option<Aperture> {
        // The margin covers the rounding of the spread and of the axis.
        let a = self.half_angle + spread + 1e-9;
        (spread.is_finite() && spread >= 0.0 && spread <= WIDEST.to_radians()).then(|| Aperture {
            sin_a: a.sin(),
            tan_a: a.tan(),
        })
    }

    /// What the cone of aperture `ap` about the unit direction `axis` meets (a group of suns,
    /// [`SunCones::aperture`]). Blocked and Clear hold for the disc about every direction in
    /// the cone: a polygon that misses the wide cone misses each narrow one inside it, one
    /// that covers it covers each, so [`SunCones::classify_from`] answers the same for each
    /// sun, a Clear one crossing exactly the panes listed here. No allocation.
    pub(crate) fn classify_wide(&self, v: &mut Viewpoint, axis: DVec3, ap: Aperture) -> Wide {
        let mut panes = [NONE; WIDE_PANES];
        let mut count = 0;
        match self.decide(v, axis, ap, &mut |k, _| {
            if count == WIDE_PANES {
                return false;
            }
            panes[count] = k;
            count += 1;
            true
        }) {
            Outcome::Blocked => Wide::Blocked,
            Outcome::Partial => Wide::Partial,
            Outcome::Clear => Wide::Clear { panes, count },
        }
    }

    /// The number of pane classes (see [`SunCones::pane_class`]).
    pub(crate) fn pane_classes(&self) -> usize {
        self.classes.len()
    }

    /// Pane `k`'s class: every pane of a class passes the same τ(θ) in a given direction, so
    /// a table of [`SunCones::class_transmittance`] by class and direction gives the value
    /// [`SunCones::transmittance`] computes, bit for bit. None for a pane past the classes
    /// kept.
    pub(crate) fn pane_class(&self, k: u32) -> Option<usize> {
        let c = self.class[k as usize];
        (c != NONE).then_some(c as usize)
    }

    /// The transmittance of class `class`'s panes along the unit direction `c`.
    pub(crate) fn class_transmittance(&self, class: usize, c: DVec3) -> f64 {
        self.polygons[self.classes[class] as usize].transmittance(c)
    }

    /// The product of the transmittances τ(θ) of `panes` (indices from
    /// [`SunCones::classify_wide`]) for the unit direction `c`.
    pub(crate) fn transmittance(&self, panes: &[u32], c: DVec3) -> f64 {
        let mut tau = 1.0;
        for &k in panes {
            tau *= self.polygons[k as usize].transmittance(c);
        }
        tau
    }

    /// The cone of aperture `ap` about the unit direction `c` against every polygon:
    /// Blocked at the first opaque cover, Partial if any polygon meets part of it (or
    /// `pane` refuses a pane), else Clear, every pane that covers it handed to `pane` in the
    /// order met.
    fn decide(
        &self,
        v: &mut Viewpoint,
        c: DVec3,
        ap: Aperture,
        pane: &mut impl FnMut(u32, &Convex) -> bool,
    ) -> Outcome {
        for k in 0..BLOCKERS {
            let b = v.blockers[k];
            if b != NONE && self.meets(v, b, c, ap.sin_a) == Meets::Cover {
                return Outcome::Blocked;
            }
        }
        let Some(root) = self.nodes.first() else {
            return Outcome::Clear;
        };
        let o = v.o;
        // The cone's radius where it leaves the scene's box bounds its radius in every box.
        let far = (o - root.lo).abs().max((root.hi - o).abs()).length();
        let e = far * ap.tan_a;
        let inv = DVec3::new(1.0 / c.x, 1.0 / c.y, 1.0 / c.z);
        if box_entry(root, e, o, c, inv).is_none() {
            return Outcome::Clear;
        }
        // Nodes whose boxes the cone may meet; children pushed farther first, so that the
        // polygons near the point, which block most cones, are met first.
        let mut stack = [0u32; STACK];
        let mut top = 1;
        let mut partial = false;
        // Opaque polygons met partly, each cut by one edge's plane only (a seam's two sides),
        // and whether anything else was met partly.
        let mut seams = [(NONE, 0u8); SEAMS];
        let mut count = 0;
        let mut other = false;
        while top > 0 {
            top -= 1;
            let node = &self.nodes[stack[top] as usize];
            if node.count == 0 {
                if top + 2 > STACK {
                    return Outcome::Partial;
                }
                let (a, b) = (node.first, node.first + 1);
                let ta = box_entry(&self.nodes[a as usize], e, o, c, inv);
                let tb = box_entry(&self.nodes[b as usize], e, o, c, inv);
                match (ta, tb) {
                    (Some(x), Some(y)) => {
                        let (near, far) = if x <= y { (a, b) } else { (b, a) };
                        stack[top] = far;
                        stack[top + 1] = near;
                        top += 2;
                    }
                    (Some(_), None) => {
                        stack[top] = a;
                        top += 1;
                    }
                    (None, Some(_)) => {
                        stack[top] = b;
                        top += 1;
                    }
                    (None, None) => {}
                }
                continue;
            }
            for k in node.first..node.first + node.count {
                let p = &self.polygons[k as usize];
                match (self.meets(v, k, c, ap.sin_a), p.pane) {
                    (Meets::Miss, _) => {}
                    (Meets::Cover, None) => {
                        v.blockers.copy_within(0..BLOCKERS - 1, 1);
                        v.blockers[0] = k;
                        return Outcome::Blocked;
                    }
                    (Meets::Cover, Some(_)) => {
                        if !pane(k, p) {
                            partial = true;
                            other = true;
                        }
                    }
                    (Meets::Partial(cut), None) if cut.is_power_of_two() && count < SEAMS => {
                        partial = true;
                        seams[count] = (k, cut);
                        count += 1;
                    }
                    (Meets::Partial(_), _) => {
                        partial = true;
                        other = true;
                    }
                }
            }
        }
        if !partial {
            return Outcome::Clear;
        }
        if !other && self.seam_covers(v, &seams[..count]) {
            return Outcome::Blocked;
        }
        Outcome::Partial
    }

    /// Whether two of the opaque polygons `seams` (each met partly, cut by the plane of one
    /// edge only) are cut by the same plane through the point, one on each side: the cone's
    /// directions on each side of the plane then meet that side's polygon (they lie inside
    /// its other edges' planes, in front), so the two cover it together. The two edges need
    /// not be one: a wall in pieces, two walls at a corner and a T-junction (a piece's edge
    /// along part of another's) all block the disc over their seam without its being
    /// sampled. The planes count as one when their unit normals are opposite within
    /// [`SEAM_PLANE`] (an angle under 4.5·10⁻⁷ rad, far below the single-precision rays'
    /// resolution that [`MARGIN`] covers); an edge shared by two polygons gives exactly
    /// opposite normals.
    fn seam_covers(&self, v: &Viewpoint, seams: &[(u32, u8)]) -> bool {
        for (i, &(a, cut_a)) in seams.iter().enumerate() {
            let pa = self.pre(v, a);
            let ma = pa.edges[cut_a.trailing_zeros() as usize];
            for &(b, cut_b) in &seams[i + 1..] {
                let pb = self.pre(v, b);
                let mb = pb.edges[cut_b.trailing_zeros() as usize];
                if ma.dot(mb) <= -(1.0 - SEAM_PLANE) {
                    return true;
                }
            }
        }
        false
    }

    /// Polygon `k`'s set-up from the viewpoint: the cached one, or computed afresh.
    fn pre(&self, v: &Viewpoint, k: u32) -> Pre {
        let slot = k as usize % WAYS;
        if v.keys[slot] == k {
            v.pre[slot]
        } else {
            Pre::of(&self.polygons[k as usize], v.o)
        }
    }

    /// Polygon `k` against the cone about `c` from the viewpoint (module documentation),
    /// its set-up taken from or put into the viewpoint's cache.
    #[inline]
    fn meets(&self, v: &mut Viewpoint, k: u32, c: DVec3, sin_a: f64) -> Meets {
        let slot = k as usize % WAYS;
        if v.keys[slot] != k {
            v.pre[slot] = Pre::of(&self.polygons[k as usize], v.o);
            v.keys[slot] = k;
        }
        let pre = &v.pre[slot];
        if pre.dead {
            return Meets::Partial(0);
        }
        // cos β: the centre against the normal that faces the plane from the point. Every
        // direction runs parallel to or away from the plane when cos(β − α) ≤ 0, that is
        // cos β ≤ −sin α; some do when cos(β + α) ≤ 0, cos β ≤ sin α.
        let cz = pre.toward.dot(c);
        if cz <= -sin_a {
            return Meets::Miss;
        }
        let grazes = pre.partial || cz <= sin_a;
        let mut cut = 0u8;
        for (e, m) in pre.edges[..pre.count as usize].iter().enumerate() {
            // The angle from c to the edge's plane against α, on the polygon's side.
            let d = m.dot(c);
            if d <= -sin_a {
                return Meets::Miss;
            }
            if d < sin_a {
                cut |= 1 << e;
            }
        }
        if grazes {
            Meets::Partial(0)
        } else if cut != 0 {
            Meets::Partial(cut)
        } else {
            Meets::Cover
        }
    }
}

/// How far from −1 the dot product of two edges' plane normals may be for the planes to be
/// one ([`SunCones`]'s `seam_covers`).
const SEAM_PLANE: f64 = 1e-13;
/// Most polygons a cone's seam test holds.
const SEAMS: usize = 4;
/// Entries of a viewpoint's cache of polygon set-ups (direct-mapped by polygon index).
const WAYS: usize = 32;
/// Latest blockers a viewpoint tries first.
const BLOCKERS: usize = 4;
/// No polygon.
const NONE: u32 = u32::MAX;

/// A polygon seen from a point: the normal facing its plane from the point, and its edges'
/// planes through the point as unit normals pointing into the polygon's wedge.
#[derive(Clone, Copy, Debug, Default)]
struct Pre {
    toward: DVec3,
    edges: [DVec3; 4],
    count: u8,
    /// An edge's plane holds the polygon's centre (the point is on the edge's line): no
    /// cone is covered.
    partial: bool,
    /// The point lies in the polygon's plane: every cone not missed otherwise is Partial.
    dead: bool,
}

impl Pre {
    fn of(p: &Convex, o: DVec3) -> Pre {
        let mut pre = Pre {
            count: p.count as u8,
            ..Pre::default()
        };
        let s0 = p.normal.dot(o - p.corners[0]);
        if s0 == 0.0 {
            pre.dead = true;
            return pre;
        }
        pre.toward = if s0 > 0.0 { -p.normal } else { p.normal };
        let g = p.centre - o;
        for k in 0..p.count {
            let a = p.corners[k] - o;
            let b = p.corners[(k + 1) % p.count] - o;
            let m = a.cross(b);
            let side = m.dot(g);
            let len = m.length();
            if side == 0.0 || len <= 0.0 || !len.is_finite() {
                pre.partial = true;
                pre.edges[k] = DVec3::ZERO;
                continue;
            }
            pre.edges[k] = m * (side.signum() / len);
        }
        pre
    }
}

/// The cones from one point: its polygons' set-ups and its latest blockers (see
/// [`SunCones::classify_from`]). About 4 KiB; make one a point and reuse it for all its cones.
pub(crate) struct Viewpoint {
    o: DVec3,
    keys: [u32; WAYS],
    pre: [Pre; WAYS],
    blockers: [u32; BLOCKERS],
}

impl Viewpoint {
    /// The cones from `o`.
    pub(crate) fn new(o: DVec3) -> Viewpoint {
        Viewpoint {
            o,
            keys: [NONE; WAYS],
            pre: [Pre::default(); WAYS],
            blockers: [NONE; BLOCKERS],
        }
    }
}

/// Suns of nearby directions gathered into a binary tree of cones, so that a point decides a
/// whole group with one [`SunCones::classify_wide`] (a week's suns at one hour of the day lie
/// within a few degrees). Each node holds the members `order[first..first + count]`, the
/// unit axis of their mean direction and the aperture of the cone that holds the disc about
/// every member (None when it is too wide to try); an inner node's children are at `child`
/// and `child + 1`.
pub(crate) struct SunGroups {
    /// Member indices (into the directions given), grouped by node.
    pub(crate) order: Vec<usize>,
    pub(crate) nodes: Vec<SunGroup>,
}

/// A node of [`SunGroups`].
#[derive(Clone, Copy, Debug)]
pub(crate) struct SunGroup {
    pub(crate) axis: DVec3,
    pub(crate) aperture: Option<Aperture>,
    pub(crate) first: u32,
    pub(crate) count: u32,
    /// The first child (the second follows it); [`NONE`] for a single sun.
    pub(crate) child: u32,
}

impl SunGroups {
    /// The tree over the unit directions `dirs` (index, direction), split at the median of
    /// the longest axis of their extent until one sun is left, each node's aperture from
    /// `cones`. Empty for no directions.
    pub(crate) fn new(cones: &SunCones, dirs: &[(usize, DVec3)]) -> SunGroups {
        let mut items = dirs.to_vec();
        let mut nodes = Vec::with_capacity(2 * items.len());
        if !items.is_empty() {
            let n = items.len();
            nodes.push(SunGroup {
                axis: DVec3::Z,
                aperture: None,
                first: 0,
                count: 0,
                child: NONE,
            });
            group(cones, &mut items, 0, n, 0, &mut nodes);
        }
        SunGroups {
            order: items.into_iter().map(|(i, _)| i).collect(),
            nodes,
        }
    }

    /// The members of node `k`.
    pub(crate) fn members(&self, k: usize) -> &[usize] {
        let g = &self.nodes[k];
        &self.order[g.first as usize..(g.first + g.count) as usize]
    }
}

/// Fill node `at` with `items[first..end]`.
fn group(
    cones: &SunCones,
    items: &mut [(usize, DVec3)],
    first: usize,
    end: usize,
    at: usize,
    nodes: &mut Vec<SunGroup>,
) {
    let part = &items[first..end];
    let sum: DVec3 = part.iter().map(|p| p.1).sum();
    let axis = sum.normalize_or_zero();
    // The largest angle from the axis to a member (rounding is covered by the aperture's
    // margin).
    let spread = part
        .iter()
        .map(|p| p.1.dot(axis).clamp(-1.0, 1.0).acos())
        .fold(0.0, f64::max);
    let n = end - first;
    nodes[at] = SunGroup {
        axis,
        aperture: if axis == DVec3::ZERO || n < 2 {
            None
        } else {
            cones.aperture(spread)
        },
        first: first as u32,
        count: n as u32,
        child: NONE,
    };
    if n < 2 {
        return;
    }
    let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    for p in part {
        lo = lo.min(p.1);
        hi = hi.max(p.1);
    }
    let extent = hi - lo;
    let axis = if extent.x >= extent.y && extent.x >= extent.z {
        0
    } else if extent.y >= extent.z {
        1
    } else {
        2
    };
    items[first..end].select_nth_unstable_by(n / 2, |a, b| a.1[axis].total_cmp(&b.1[axis]));
    let child = nodes.len();
    let blank = nodes[at];
    nodes.push(blank);
    nodes.push(blank);
    nodes[at].child = child as u32;
    group(cones, items, first, first + n / 2, child, nodes);
    group(cones, items, first + n / 2, end, child + 1, nodes);
}

/// Where the centre ray enters the node's box widened by `e`, the cone's radius at the
/// farthest point of the scene's box (a cone direction inside the box at distance t lies
/// within t tan α ≤ `e` of the centre ray's point at t); None when it does not, and then no
/// direction of the cone meets the box.
#[inline]
fn box_entry(node: &Node, e: f64, o: DVec3, c: DVec3, inv: DVec3) -> Option<f64> {
    let (lo, hi) = (node.lo - e, node.hi + e);
    let (mut t0, mut t1) = (0.0f64, f64::INFINITY);
    for k in 0..3 {
        if c[k] == 0.0 {
            if o[k] < lo[k] || o[k] > hi[k] {
                return None;
            }
            continue;
        }
        let (a, b) = ((lo[k] - o[k]) * inv[k], (hi[k] - o[k]) * inv[k]);
        let (a, b) = if a < b { (a, b) } else { (b, a) };
        t0 = t0.max(a);
        t1 = t1.min(b);
        if t0 > t1 {
            return None;
        }
    }
    Some(t0)
}

/// The convex polygon of `corners` (3 or 4, counter-clockwise about `normal`'s side), or None
/// when it has no area or is not planar and convex.
fn convex(corners: &[DVec3], pane: Option<Glazing>) -> Option<Convex> {
    let count = corners.len();
    // Newell's normal.
    let mut n = DVec3::ZERO;
    for k in 0..count {
        let (a, b) = (corners[k], corners[(k + 1) % count]);
        n += DVec3::new(
            (a.y - b.y) * (a.z + b.z),
            (a.z - b.z) * (a.x + b.x),
            (a.x - b.x) * (a.y + b.y),
        );
    }
    let len = n.length();
    if len.is_nan() || len <= 0.0 {
        return None;
    }
    let normal = n / len;
    let size = corners
        .iter()
        .map(|&v| (v - corners[0]).length())
        .fold(0.0, f64::max);
    let planar = corners
        .iter()
        .all(|&v| normal.dot(v - corners[0]).abs() <= 1e-9 * size.max(1e-300));
    let turns = (0..count).all(|k| {
        let (a, b, c) = (
            corners[k],
            corners[(k + 1) % count],
            corners[(k + 2) % count],
        );
        (b - a).cross(c - b).dot(normal) > 0.0
    });
    if !(planar && turns) {
        return None;
    }
    let mut out = [DVec3::ZERO; 4];
    out[..count].copy_from_slice(corners);
    Some(Convex {
        corners: out,
        count,
        normal,
        centre: corners.iter().copied().sum::<DVec3>() / count as f64,
        pane,
    })
}

/// The mesh's patches as convex polygons, each with the pane `pane(material)` gives,
/// appended to `out`.
fn add_mesh(mesh: &Mesh, pane: &dyn Fn(u32) -> Option<Glazing>, out: &mut Vec<Convex>) {
    let v = |i: u32| mesh.vertices[i as usize].as_dvec3();
    for p in &mesh.patches {
        let g = pane(p.material);
        if !p.is_triangle() {
            let q = p.vertices.map(v);
            if let Some(c) = convex(&q, g) {
                out.push(c);
                continue;
            }
        }
        for t in p.triangles() {
            if let Some(c) = convex(&t.map(v), g) {
                out.push(c);
            }
        }
    }
}

/// Most pane classes kept (a building's glazing has a few orientations and glasses).
const CLASSES: usize = 64;

/// The panes' classes (see [`SunCones`]): the same glazing, and normals equal or opposite
/// bit for bit, so that |n · c| and τ are the same for every pane of a class.
fn pane_classes(polygons: &[Convex]) -> (Vec<u32>, Vec<u32>) {
    let mut class = vec![NONE; polygons.len()];
    let mut classes: Vec<u32> = Vec::new();
    for (k, p) in polygons.iter().enumerate() {
        let Some(g) = p.pane else { continue };
        let found = classes.iter().position(|&q| {
            let q = &polygons[q as usize];
            q.pane == Some(g) && (q.normal == p.normal || q.normal == -p.normal)
        });
        match found {
            Some(c) => class[k] = c as u32,
            None if classes.len() < CLASSES => {
                class[k] = classes.len() as u32;
                classes.push(k as u32);
            }
            None => {}
        }
    }
    (class, classes)
}

/// Fill node `at` with the polygons `first..end`, splitting at the median of the centres along
/// the box's longest axis until a leaf holds at most [`LEAF`].
fn build(polygons: &mut [Convex], first: usize, end: usize, at: usize, nodes: &mut Vec<Node>) {
    let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    let (mut clo, mut chi) = (lo, hi);
    for p in &polygons[first..end] {
        for &v in &p.corners[..p.count] {
            lo = lo.min(v);
            hi = hi.max(v);
        }
        clo = clo.min(p.centre);
        chi = chi.max(p.centre);
    }
    nodes[at].lo = lo;
    nodes[at].hi = hi;
    let n = end - first;
    let extent = chi - clo;
    if n <= LEAF || extent.max_element() <= 0.0 {
        nodes[at].first = first as u32;
        nodes[at].count = n as u32;
        return;
    }
    let axis = if extent.x >= extent.y && extent.x >= extent.z {
        0
    } else if extent.y >= extent.z {
        1
    } else {
        2
    };
    let mid = first + n / 2;
    polygons[first..end]
        .select_nth_unstable_by(n / 2, |a, b| a.centre[axis].total_cmp(&b.centre[axis]));
    let child = nodes.len();
    let blank = Node {
        lo,
        hi,
        first: 0,
        count: 0,
    };
    nodes.push(blank);
    nodes.push(blank);
    nodes[at].first = child as u32;
    nodes[at].count = 0;
    build(polygons, first, mid, child, nodes);
    build(polygons, mid, end, child + 1, nodes);
}

#[cfg(test)]
#[path = "sun_cone_tests.rs"]
mod tests;
