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

/// A polygon against a cone.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Meets {
    Miss,
    Cover,
    Partial,
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
        SunCones {
            polygons,
            nodes,
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
        for k in 0..BLOCKERS {
            let b = v.blockers[k];
            if b != NONE && self.meets(v, b, c) == Meets::Cover {
                return Cone::Blocked;
            }
        }
        let Some(root) = self.nodes.first() else {
            return Cone::Clear(1.0);
        };
        let o = v.o;
        // The cone's radius where it leaves the scene's box bounds its radius in every box.
        let far = (o - root.lo).abs().max((root.hi - o).abs()).length();
        let e = far * self.tan_a;
        let inv = DVec3::new(1.0 / c.x, 1.0 / c.y, 1.0 / c.z);
        if box_entry(root, e, o, c, inv).is_none() {
            return Cone::Clear(1.0);
        }
        // Nodes whose boxes the cone may meet; children pushed farther first, so that the
        // polygons near the point, which block most cones, are met first.
        let mut stack = [0u32; STACK];
        let mut top = 1;
        let mut partial = false;
        let mut tau = 1.0;
        while top > 0 {
            top -= 1;
            let node = &self.nodes[stack[top] as usize];
            if node.count == 0 {
                if top + 2 > STACK {
                    return Cone::Partial;
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
                match (self.meets(v, k, c), p.pane) {
                    (Meets::Miss, _) => {}
                    (Meets::Cover, None) => {
                        v.blockers.copy_within(0..BLOCKERS - 1, 1);
                        v.blockers[0] = k;
                        return Cone::Blocked;
                    }
                    (Meets::Cover, Some(g)) => tau *= g.transmittance(p.normal.dot(c)),
                    (Meets::Partial, _) => partial = true,
                }
            }
        }
        if partial {
            Cone::Partial
        } else {
            Cone::Clear(tau)
        }
    }

    /// Polygon `k` against the cone about `c` from the viewpoint (module documentation),
    /// its set-up taken from or put into the viewpoint's cache.
    #[inline]
    fn meets(&self, v: &mut Viewpoint, k: u32, c: DVec3) -> Meets {
        let slot = k as usize % WAYS;
        if v.keys[slot] != k {
            v.pre[slot] = Pre::of(&self.polygons[k as usize], v.o);
            v.keys[slot] = k;
        }
        let pre = &v.pre[slot];
        if pre.dead {
            return Meets::Partial;
        }
        // cos β: the centre against the normal that faces the plane from the point. Every
        // direction runs parallel to or away from the plane when cos(β − α) ≤ 0, that is
        // cos β ≤ −sin α; some do when cos(β + α) ≤ 0, cos β ≤ sin α.
        let cz = pre.toward.dot(c);
        if cz <= -self.sin_a {
            return Meets::Miss;
        }
        let mut partial = pre.partial || cz <= self.sin_a;
        for m in &pre.edges[..pre.count as usize] {
            // The angle from c to the edge's plane against α, on the polygon's side.
            let d = m.dot(c);
            if d <= -self.sin_a {
                return Meets::Miss;
            }
            if d < self.sin_a {
                partial = true;
            }
        }
        if partial {
            Meets::Partial
        } else {
            Meets::Cover
        }
    }
}

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
