//! Occluders and shafts for the [`adaptive`](super::adaptive) method: which polygons may cut
//! the segments between two patches.
//!
//! **Occluders.** Every patch blocks from both sides. Coplanar patches that share a whole edge
//! are merged, while their union stays convex (and has at most `MAX_OCCLUDER_VERTICES`
//! corners), into one convex *occluder*: a wall cut into a grid of facets (as a View3D file of
//! equal facets lists it) becomes a few rectangles, so a shaft meets a few occluders instead of
//! dozens of facets, and a shadow is cut out of a receiver in a few clips. The merge covers
//! exactly the union of its patches, so nothing is approximated. Every patch belongs to exactly
//! one occluder (its *group*).
//!
//! **Shafts** (Haines & Wallace 1991, "Shaft Culling for Efficient Ray-Traced Radiosity", with
//! the exact hull in place of their box shaft): the convex hull of two convex polygons A and B
//! is the union of the segments from A to B, so a convex occluder that cuts any such segment
//! meets the hull, and one that does not meet it cuts none. The hull is kept as its supporting
//! planes: A's and B's own planes and every plane through an edge of one and a corner of the
//! other that has all corners of both on one side. A box or a polygon entirely outside one of
//! them cannot meet the hull (the converse fails only near the hull's edges, which costs a
//! useless candidate, never a missed one).
//!
//! **The tree** is a binary bounding-volume hierarchy over the occluders' boxes (median split
//! of the centres along the longest axis), queried with a shaft: a node whose box lies outside
//! one of the shaft's planes is skipped with everything below it, so a query visits the
//! occluders near the shaft, never all of them. The ray-casting [`crate::accel::Bvh`] holds
//! triangles in SIMD blocks without the convex polygons or a plane-set query; this one is
//! built for the question asked here and is small (one node per occluder).

use crate::mesh::Mesh;
use glam::DVec3;
use std::collections::HashMap;

/// Most corners of a merged occluder (a merge that would exceed it is not made).
pub(super) const MAX_OCCLUDER_VERTICES: usize = 12;

/// Occluders per leaf of the tree.
const LEAF: usize = 2;

/// A node of the occluder tree: a box, and either two children (`count == 0`, children at
/// `first` and `first + 1`) or `count` occluders from `order[first..]`.
#[derive(Clone, Copy, Debug)]
struct Node {
    min: DVec3,
    max: DVec3,
    first: u32,
    count: u32,
}

/// The scene's occluders: convex polygons (merged coplanar patches), each patch's group, and
/// the tree over them.
#[derive(Debug)]
pub(super) struct Occluders {
    /// Corners of every occluder, counter-clockwise about its normal.
    vertices: Vec<DVec3>,
    /// Occluder `k` has the corners `vertices[start[k]..start[k + 1]]`.
    start: Vec<u32>,
    /// Unit normal of each occluder.
    normal: Vec<DVec3>,
    /// The occluder holding each patch.
    pub(super) group: Vec<u32>,
    /// Bounding box of each occluder.
    bounds: Vec<(DVec3, DVec3)>,
    nodes: Vec<Node>,
    order: Vec<u32>,
}

impl Occluders {
    /// Merge `polygons` (one per patch, convex, counter-clockwise about `normals`) into
    /// occluders and build their tree. `scale` is the scene's size, for the tolerances.
    pub(super) fn build(polygons: &[Vec<DVec3>], normals: &[DVec3], scale: f64) -> Occluders {
        let n = polygons.len();
        // Patches by plane: the normal and the offset, on a grid far finer than any gap
        // between distinct planes of a scene but coarse enough for f32 corners.
        let mut planes: HashMap<[i64; 4], Vec<u32>> = HashMap::new();
        for (k, (p, nrm)) in polygons.iter().zip(normals).enumerate() {
            let q = |x: f64| (x * 1e6).round() as i64;
            let d = nrm.dot(p[0]) / scale;
            planes
                .entry([q(nrm.x), q(nrm.y), q(nrm.z), q(d)])
                .or_default()
                .push(k as u32);
        }
        let mut keys: Vec<[i64; 4]> = planes.keys().copied().collect();
        keys.sort_unstable();
        let mut vertices = Vec::new();
        let mut start = vec![0u32];
        let mut normal = Vec::new();
        let mut group = vec![0u32; n];
        for key in keys {
            let members = &planes[&key];
            let nrm = normals[members[0] as usize];
            for (poly, patches) in merge_plane(polygons, members, nrm, scale) {
                for &p in &patches {
                    group[p as usize] = normal.len() as u32;
                }
                vertices.extend_from_slice(&poly);
                start.push(vertices.len() as u32);
                normal.push(nrm);
            }
        }
        let mut occ = Occluders {
            vertices,
            start,
            normal,
            group,
            bounds: Vec::new(),
            nodes: Vec::new(),
            order: Vec::new(),
        };
        occ.bounds = (0..occ.len() as u32)
            .map(|k| occ.polygon_bounds(k))
            .collect();
        occ.build_tree();
        occ
    }

    /// Number of occluders.
    pub(super) fn len(&self) -> usize {
        self.normal.len()
    }

    /// The corners of occluder `k`.
    pub(super) fn polygon(&self, k: u32) -> &[DVec3] {
        let k = k as usize;
        &self.vertices[self.start[k] as usize..self.start[k + 1] as usize]
    }

    /// The unit normal of occluder `k`.
    pub(super) fn normal(&self, k: u32) -> DVec3 {
        self.normal[k as usize]
    }

    /// The bounding box of occluder `k`.
    pub(super) fn bounds(&self, k: u32) -> (DVec3, DVec3) {
        self.bounds[k as usize]
    }

    fn polygon_bounds(&self, k: u32) -> (DVec3, DVec3) {
        let p = self.polygon(k);
        p.iter()
            .fold((p[0], p[0]), |(lo, hi), v| (lo.min(*v), hi.max(*v)))
    }

    fn build_tree(&mut self) {
        let m = self.len();
        let boxes: Vec<(DVec3, DVec3)> = (0..m as u32).map(|k| self.bounds(k)).collect();
        self.order = (0..m as u32).collect();
        self.nodes.clear();
        if m == 0 {
            return;
        }
        self.nodes.push(Node {
            min: DVec3::ZERO,
            max: DVec3::ZERO,
            first: 0,
            count: 0,
        });
        // (node, range) to fill.
        let mut todo = vec![(0usize, 0usize, m)];
        while let Some((node, lo, hi)) = todo.pop() {
            let (bmin, bmax) = self.order[lo..hi].iter().fold(
                (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
                |(a, b), &k| (a.min(boxes[k as usize].0), b.max(boxes[k as usize].1)),
            );
            self.nodes[node].min = bmin;
            self.nodes[node].max = bmax;
            if hi - lo <= LEAF {
                self.nodes[node].first = lo as u32;
                self.nodes[node].count = (hi - lo) as u32;
                continue;
            }
            let centre = |k: u32| boxes[k as usize].0 + boxes[k as usize].1;
            let (cmin, cmax) = self.order[lo..hi].iter().fold(
                (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
                |(a, b), &k| (a.min(centre(k)), b.max(centre(k))),
            );
            let ext = cmax - cmin;
            let axis = if ext.x >= ext.y && ext.x >= ext.z {
                0
            } else if ext.y >= ext.z {
                1
            } else {
                2
            };
            let mid = (lo + hi) / 2;
            self.order[lo..hi].select_nth_unstable_by(mid - lo, |&a, &b| {
                centre(a)[axis].total_cmp(&centre(b)[axis]).then(a.cmp(&b))
            });
            let first = self.nodes.len();
            for _ in 0..2 {
                self.nodes.push(Node {
                    min: DVec3::ZERO,
                    max: DVec3::ZERO,
                    first: 0,
                    count: 0,
                });
            }
            self.nodes[node].first = first as u32;
            self.nodes[node].count = 0;
            todo.push((first, lo, mid));
            todo.push((first + 1, mid, hi));
        }
    }

    /// The occluders that may meet `shaft`, except `skip_a` and `skip_b` (the groups of the
    /// pair: a patch's own plane never cuts a segment leaving it), into `out` in increasing
    /// order. `stack` is the traversal's buffer.
    pub(super) fn query(
        &self,
        shaft: &Shaft,
        skip: [u32; 2],
        stack: &mut Vec<u32>,
        out: &mut Vec<u32>,
    ) {
        out.clear();
        if self.nodes.is_empty() {
            return;
        }
        stack.clear();
        stack.push(0);
        while let Some(node) = stack.pop() {
            let nd = &self.nodes[node as usize];
            if shaft.excludes_box(nd.min, nd.max) {
                continue;
            }
            if nd.count == 0 {
                stack.push(nd.first);
                stack.push(nd.first + 1);
                continue;
            }
            for &k in &self.order[nd.first as usize..(nd.first + nd.count) as usize] {
                if k != skip[0] && k != skip[1] && !shaft.excludes_polygon(self.polygon(k)) {
                    out.push(k);
                }
            }
        }
        out.sort_unstable();
    }
}

/// Merge the coplanar patches `members` (normal `nrm`) into convex polygons, each with the
/// patches it holds. Passes over the polygons join pairs that share a whole edge (the same
/// two corners, met in opposite directions) while the union stays convex, until a pass joins
/// none.
fn merge_plane(
    polygons: &[Vec<DVec3>],
    members: &[u32],
    nrm: DVec3,
    scale: f64,
) -> Vec<(Vec<DVec3>, Vec<u32>)> {
    let mut polys: Vec<Option<(Vec<DVec3>, Vec<u32>)>> = members
        .iter()
        .map(|&k| Some((polygons[k as usize].clone(), vec![k])))
        .collect();
    if polys.len() == 1 {
        return polys.into_iter().flatten().collect();
    }
    let key = |p: DVec3| [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()];
    loop {
        let mut edges: HashMap<([u64; 3], [u64; 3]), usize> = HashMap::new();
        for (i, p) in polys.iter().enumerate() {
            if let Some((v, _)) = p {
                for k in 0..v.len() {
                    edges.insert((key(v[k]), key(v[(k + 1) % v.len()])), i);
                }
            }
        }
        let mut touched = vec![false; polys.len()];
        let mut merged = false;
        for i in 0..polys.len() {
            if touched[i] || polys[i].is_none() {
                continue;
            }
            let len = polys[i].as_ref().map_or(0, |p| p.0.len());
            for k in 0..len {
                let (u, w) = {
                    let v = &polys[i].as_ref().expect("live").0;
                    (v[k], v[(k + 1) % v.len()])
                };
                let Some(&j) = edges.get(&(key(w), key(u))) else {
                    continue;
                };
                if j == i || touched[j] || polys[j].is_none() {
                    continue;
                }
                let a = &polys[i].as_ref().expect("live").0;
                let b = &polys[j].as_ref().expect("live").0;
                if let Some(union) = join(a, k, b, u, w, nrm, scale) {
                    let (_, pb) = polys[j].take().expect("live");
                    let (_, pa) = polys[i]
                        .as_mut()
                        .map(|p| (&mut p.0, &mut p.1))
                        .expect("live");
                    pa.extend(pb);
                    polys[i].as_mut().expect("live").0 = union;
                    touched[i] = true;
                    touched[j] = true;
                    merged = true;
                    break;
                }
            }
        }
        if !merged {
            break;
        }
    }
    polys.into_iter().flatten().collect()
}

/// The union of convex polygons `a` (whose edge `k` runs from `u` to `w`) and `b` (which has
/// the edge from `w` to `u`), if it is convex with at most [`MAX_OCCLUDER_VERTICES`] corners
/// once collinear corners are dropped.
fn join(
    a: &[DVec3],
    k: usize,
    b: &[DVec3],
    u: DVec3,
    w: DVec3,
    nrm: DVec3,
    scale: f64,
) -> Option<Vec<DVec3>> {
    // a from w round to u, then b from u round to w (without repeating u and w).
    let mut loop_ = Vec::with_capacity(a.len() + b.len());
    for s in 0..a.len() {
        loop_.push(a[(k + 1 + s) % a.len()]);
    }
    let start = b.iter().position(|p| *p == u)?;
    for s in 1..b.len() - 1 {
        loop_.push(b[(start + s) % b.len()]);
    }
    debug_assert_eq!(loop_[0], w);
    // Drop collinear corners, refuse a reflex one.
    let eps = 1e-12 * scale * scale;
    let mut out: Vec<DVec3> = Vec::with_capacity(loop_.len());
    let m = loop_.len();
    for s in 0..m {
        let prev = loop_[(s + m - 1) % m];
        let cur = loop_[s];
        let next = loop_[(s + 1) % m];
        let turn = (cur - prev).cross(next - cur).dot(nrm);
        if turn < -eps {
            return None;
        }
        if turn > eps {
            out.push(cur);
        }
    }
    (out.len() >= 3 && out.len() <= MAX_OCCLUDER_VERTICES).then_some(out)
}

/// The convex hull of two convex polygons as its outward supporting planes: a point `p` is
/// outside when `normal · p > offset`.
#[derive(Clone, Debug, Default)]
pub(super) struct Shaft {
    planes: Vec<(DVec3, f64)>,
    /// Slack on each side of a plane (absolute, from the size of the two polygons).
    eps: f64,
}

impl Shaft {
    /// The hull of `a` (normal `na`) and `b` (normal `nb`), each in front of the other's plane.
    ///
    /// Every face of the hull of two convex polygons holds three of their corners, so it is
    /// one polygon's own plane or a plane through an edge of one and a corner of the other
    /// (two corners of one polygon on a face that is not its plane are the ends of an edge).
    /// Each edge `pq` of a polygon `E` lies on exactly one such face: the plane through `pq`
    /// turned about it from `E`'s inside, across the side `E` faces, to the last corner of the
    /// other polygon (whose corners all lie on that side, in the half-turn between `E`'s inside
    /// and its outside). That corner is found by comparing the corners' angles about the edge
    /// with one cross product each, so a shaft of two quads costs eight planes of four corners.
    pub(super) fn set(&mut self, a: &[DVec3], na: DVec3, b: &[DVec3], nb: DVec3) {
        self.planes.clear();
        let (lo, hi) = a
            .iter()
            .chain(b)
            .fold((a[0], a[0]), |(l, h), p| (l.min(*p), h.max(*p)));
        let size = (hi - lo).length().max(f64::MIN_POSITIVE);
        self.eps = 1e-9 * size;
        // The polygons' own planes: the other lies in front, so the hull is on the front side.
        self.planes.push((-na, -na.dot(a[0])));
        self.planes.push((-nb, -nb.dot(b[0])));
        let tiny = 1e-12 * size;
        for (edges, ne, corners) in [(a, na, b), (b, nb, a)] {
            let centre = edges.iter().copied().sum::<DVec3>() / edges.len() as f64;
            for k in 0..edges.len() {
                let (p, q) = (edges[k], edges[(k + 1) % edges.len()]);
                let d = q - p;
                let dl = d.length();
                if dl <= tiny {
                    // A degenerate edge: leaving its face out only widens the hull.
                    continue;
                }
                // In the plane across the edge: `o` points out of E, `ne` to the side it faces.
                let mut o = (d / dl).cross(ne);
                if o.dot(centre - p) > 0.0 {
                    o = -o;
                }
                // The corner of largest angle from E's inside (−o) towards ne, (u, v) its
                // coordinates along (o, ne): angle(c) > angle(best) ⇔ u_c v_b − u_b v_c > 0.
                let (mut ub, mut vb) = (f64::NAN, f64::NAN);
                for &c in corners {
                    let w = c - p;
                    let (u, v) = (o.dot(w), ne.dot(w));
                    if u.abs().max(v.abs()) <= tiny {
                        // A corner on the edge's line spans no plane with it.
                        continue;
                    }
                    if ub.is_nan() || u * vb - ub * v > 0.0 {
                        (ub, vb) = (u, v);
                    }
                }
                if ub.is_nan() {
                    continue;
                }
                // The outward normal, at a right angle past the corner's direction:
                // v_b o − u_b ne (perpendicular to the edge and to the corner's offset).
                let m = o * vb - ne * ub;
                let l = m.length();
                if l <= tiny {
                    continue;
                }
                let m = m / l;
                self.planes.push((m, m.dot(p)));
            }
        }
    }

    /// True when the box `[min, max]` lies wholly outside one supporting plane.
    pub(super) fn excludes_box(&self, min: DVec3, max: DVec3) -> bool {
        self.planes.iter().any(|&(m, h)| {
            // The corner with the least m · p.
            let c = DVec3::new(
                if m.x >= 0.0 { min.x } else { max.x },
                if m.y >= 0.0 { min.y } else { max.y },
                if m.z >= 0.0 { min.z } else { max.z },
            );
            m.dot(c) > h + self.eps
        })
    }

    /// True when the polygon lies wholly outside one supporting plane.
    pub(super) fn excludes_polygon(&self, p: &[DVec3]) -> bool {
        self.planes
            .iter()
            .any(|&(m, h)| p.iter().all(|x| m.dot(*x) > h + self.eps))
    }
}

/// The corners of patch `k` of `mesh` in f64, counter-clockwise about its normal.
pub(super) fn patch_polygon(mesh: &Mesh, k: usize) -> Vec<DVec3> {
    let p = &mesh.patches[k];
    let n = if p.is_triangle() { 3 } else { 4 };
    p.vertices[..n]
        .iter()
        .map(|&v| mesh.vertices[v as usize].as_dvec3())
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square(x0: f64, y0: f64, s: f64, z: f64) -> Vec<DVec3> {
        vec![
            DVec3::new(x0, y0, z),
            DVec3::new(x0 + s, y0, z),
            DVec3::new(x0 + s, y0 + s, z),
            DVec3::new(x0, y0 + s, z),
        ]
    }

    #[test]
    fn a_grid_of_facets_merges_into_few_rectangles() {
        // 6 × 6 unit facets of one plane.
        let mut polys = Vec::new();
        for i in 0..6 {
            for j in 0..6 {
                polys.push(square(i as f64, j as f64, 1.0, 0.0));
            }
        }
        let normals = vec![DVec3::Z; polys.len()];
        let occ = Occluders::build(&polys, &normals, 6.0);
        assert!(occ.len() <= 6, "{} occluders", occ.len());
        // The union is exact: areas add up to 36, and every facet lies in its group's polygon.
        let area: f64 = (0..occ.len() as u32)
            .map(|k| {
                let p = occ.polygon(k);
                (1..p.len() - 1)
                    .map(|i| 0.5 * (p[i] - p[0]).cross(p[i + 1] - p[0]).z)
                    .sum::<f64>()
            })
            .sum();
        assert!((area - 36.0).abs() < 1e-12, "{area}");
        for (f, poly) in polys.iter().enumerate() {
            let g = occ.polygon(occ.group[f]);
            let c = poly.iter().copied().sum::<DVec3>() / 4.0;
            let lo = g.iter().fold(g[0], |a, b| a.min(*b));
            let hi = g.iter().fold(g[0], |a, b| a.max(*b));
            assert!(c.cmpge(lo).all() && c.cmple(hi).all());
        }
    }

    #[test]
    fn a_shaft_finds_what_lies_between_and_only_that() {
        // Two facing unit squares at z = 0 and z = 2; a blocker square at z = 1 over them, one
        // beside them, one behind the upper one.
        let a = square(0.0, 0.0, 1.0, 0.0);
        let mut b = square(0.0, 0.0, 1.0, 2.0);
        b.reverse();
        let polys = vec![
            a.clone(),
            b.clone(),
            square(0.25, 0.25, 0.5, 1.0),
            square(3.0, 0.0, 1.0, 1.0),
            square(0.0, 0.0, 1.0, 3.0),
        ];
        let normals = vec![DVec3::Z, -DVec3::Z, DVec3::Z, DVec3::Z, DVec3::Z];
        let occ = Occluders::build(&polys, &normals, 4.0);
        let mut shaft = Shaft::default();
        shaft.set(&a, DVec3::Z, &b, -DVec3::Z);
        let (mut stack, mut out) = (Vec::new(), Vec::new());
        occ.query(&shaft, [occ.group[0], occ.group[1]], &mut stack, &mut out);
        assert_eq!(out, vec![occ.group[2]]);
        // A blocker outside the hull but inside its bounding box (the hull of a square and a
        // square shifted sideways is slanted).
        let b2: Vec<DVec3> = b.iter().map(|p| *p + DVec3::new(2.0, 0.0, 0.0)).collect();
        shaft.set(&a, DVec3::Z, &b2, -DVec3::Z);
        assert!(shaft.excludes_polygon(&square(2.2, 0.2, 0.3, 0.2)));
        assert!(!shaft.excludes_polygon(&square(0.2, 0.2, 0.3, 0.2)));
    }
}
