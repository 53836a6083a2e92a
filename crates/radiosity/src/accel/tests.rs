//! Tests of the hierarchy: its build, its layout and statistics, and the closest-hit
//! queries against brute force.

use super::build::PARALLEL_MIN;
use super::node::NO_TRIANGLE;
use super::simd::NATIVE_AVX;
use super::traverse::INTERLEAVE_FROM;
use super::*;
use crate::geom::Ray;
use crate::mesh::MeshParams;
use crate::scene::builtin;

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

/// Subtrees are built in parallel, and the hierarchy is the same, node for node, on any
/// number of threads (the mesh is large enough for the top levels to split their work).
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
                let o =
                    shift + Vec3::new(30.0 + 490.0 * u(), 30.0 + 490.0 * u(), 30.0 + 490.0 * u());
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
/// and from below which copy is covered gets answers that agree. (The mesher merges
/// coincident polygons, [`crate::mesh::Coincidence`]; the copy's patches are added by hand,
/// as a mesh made otherwise could hold them.)
#[test]
fn coincident_copies_resolve_the_same_way_from_both_sides() {
    let scene = builtin::cornell();
    let copy = scene.polygons.len() as u32;
    let mut mesh = Mesh::build(&scene, MeshParams::Patches(3000)).unwrap();
    // The floor meshed alone, appended with its grid.
    let mut alone = scene.clone();
    alone.polygons.truncate(1);
    let floor = Mesh::build(&alone, MeshParams::MaxEdge(mesh.max_edge)).unwrap();
    let (pv, pp) = (mesh.vertices.len() as u32, mesh.patches.len() as u32);
    mesh.vertices.extend_from_slice(&floor.vertices);
    for mut p in floor.patches {
        for v in p
            .vertices
            .iter_mut()
            .filter(|v| **v != crate::mesh::Patch::NONE)
        {
            *v += pv;
        }
        p.surface = copy;
        mesh.patches.push(p);
    }
    for mut g in floor.grids {
        g.first_patch += pp;
        g.first_vertex += pv;
        mesh.grids.push(g);
    }
    mesh.groups.push(0);
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
        let from_below = bvh.closest_hit(&Ray::new(point - p.normal * off, p.normal), 2.0 * off);
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
