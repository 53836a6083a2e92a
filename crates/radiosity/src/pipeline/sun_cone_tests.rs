//! The cone decisions against brute force: directions sampled over the cone (its centre, rings
//! out to its rim) and intersected with the polygon by Möller–Trumbore in double precision.

use super::*;
use crate::sampling::{stream, uniform};

/// Whether the ray `o + t d`, t > 0, meets the convex polygon (fan triangles).
fn hits(poly: &[DVec3], o: DVec3, d: DVec3) -> bool {
    (1..poly.len() - 1).any(|k| {
        let (a, b, c) = (poly[0], poly[k], poly[k + 1]);
        let (e1, e2) = (b - a, c - a);
        let p = d.cross(e2);
        let det = e1.dot(p);
        if det.abs() < 1e-300 {
            return false;
        }
        let s = o - a;
        let u = s.dot(p) / det;
        let q = s.cross(e1);
        let v = d.dot(q) / det;
        let t = e2.dot(q) / det;
        t > 0.0 && u >= 0.0 && v >= 0.0 && u + v <= 1.0
    })
}

/// Directions within `alpha` of `c`: the centre and 24 rings of 64, the last at the rim.
fn cone(c: DVec3, alpha: f64) -> Vec<DVec3> {
    let t = c.any_orthonormal_vector();
    let b = c.cross(t);
    let mut out = vec![c];
    for ring in 1..=24 {
        let r = alpha.tan() * ring as f64 / 24.0;
        for k in 0..64 {
            let phi = std::f64::consts::TAU * (k as f64 + 0.5 * (ring % 2) as f64) / 64.0;
            out.push((c + t * (r * phi.cos()) + b * (r * phi.sin())).normalize());
        }
    }
    out
}

fn random_point(rng: &mut crate::sampling::Rng64, scale: f64) -> DVec3 {
    DVec3::new(
        uniform(rng) as f64 - 0.5,
        uniform(rng) as f64 - 0.5,
        uniform(rng) as f64 - 0.5,
    ) * scale
}

/// A random planar convex polygon: a triangle or a parallelogram about a random centre.
fn random_polygon(rng: &mut crate::sampling::Rng64) -> Vec<DVec3> {
    let centre = random_point(rng, 2.0);
    let (u, v) = (random_point(rng, 1.5), random_point(rng, 1.5));
    if uniform(rng) < 0.5 {
        vec![centre, centre + u, centre + v]
    } else {
        vec![
            centre - u - v,
            centre + u - v,
            centre + u + v,
            centre - u + v,
        ]
    }
}

/// 20,000 random polygons and cones (the sun's 0.27°, 2° and 10° half-angles, the centre aimed
/// at random or at a point of the polygon): Blocked only when every sampled direction meets
/// the polygon, Clear only when none does; each outcome occurs, and a cone whose samples are
/// unanimous far from every edge is decided.
#[test]
fn decisions_agree_with_sampled_directions() {
    let mut rng = stream(7, 1, 2, 3);
    let mut counts = [0usize; 3];
    let mut decided_unanimous = 0;
    let mut unanimous = 0;
    for trial in 0..20_000 {
        let mut poly = random_polygon(&mut rng);
        let o = random_point(&mut rng, 4.0);
        let alpha = [0.5 * 0.533f64, 2.0, 10.0][trial % 3].to_radians();
        let aim = if trial % 2 == 0 {
            let w = [uniform(&mut rng) as f64, uniform(&mut rng) as f64];
            poly[0] + (poly[1] - poly[0]) * w[0] + (poly[2] - poly[1]) * w[0] * w[1]
        } else {
            o + random_point(&mut rng, 2.0)
        };
        let c = (aim - o).normalize_or_zero();
        if c == DVec3::ZERO {
            continue;
        }
        // Either winding: the decision must not depend on it.
        if trial % 4 < 2 {
            poly.reverse();
        }
        let Some(p) = convex(&poly, None) else {
            // Only a degenerate draw is refused.
            let area = (poly[1] - poly[0]).cross(poly[2] - poly[0]).length();
            assert!(area < 1e-9, "a convex polygon refused: {poly:?}");
            continue;
        };
        let cones = SunCones::of(vec![p], alpha - MARGIN);
        let dirs = cone(c, alpha);
        let met = dirs.iter().filter(|&&d| hits(&poly, o, d)).count();
        match cones.classify(o, c) {
            Cone::Blocked => {
                counts[0] += 1;
                assert_eq!(met, dirs.len(), "Blocked but a direction misses: {trial}");
            }
            Cone::Clear(_) => {
                counts[1] += 1;
                assert_eq!(met, 0, "Clear but a direction meets it: {trial}");
            }
            Cone::Partial => counts[2] += 1,
        }
        // Decisive away from the edges: a cone twice as wide all one way is decided.
        let wide = cone(c, 2.0 * alpha);
        let wide_met = wide.iter().filter(|&&d| hits(&poly, o, d)).count();
        let corner_far = poly.iter().all(|&v| {
            let a = (v - o).normalize();
            a.dot(c) < (3.0 * alpha).cos()
        });
        if corner_far && (wide_met == 0 || wide_met == wide.len()) {
            unanimous += 1;
            if cones.classify(o, c) != Cone::Partial {
                decided_unanimous += 1;
            }
        }
    }
    assert!(counts.iter().all(|&k| k > 500), "{counts:?}");
    // Partial away from corners only where an edge's plane (not its segment) passes near c.
    assert!(
        decided_unanimous as f64 > 0.9 * unanimous as f64,
        "{decided_unanimous} of {unanimous}"
    );
}

/// Several polygons: a pane covering the cone with an opaque polygon behind it is Blocked; the
/// pane alone is Clear; two panes sharing an edge through the cone are Partial (a seam is
/// sampled, not guessed); a cone near the hierarchy's boxes' edges is decided as each
/// polygon alone.
#[test]
fn panes_seams_and_the_hierarchy() {
    let v = |x: f64, y: f64, z: f64| DVec3::new(x, y, z);
    let square = |z: f64, x0: f64, x1: f64| {
        vec![v(x0, -1.0, z), v(x1, -1.0, z), v(x1, 1.0, z), v(x0, 1.0, z)]
    };
    let alpha = (0.5 * 0.533f64).to_radians();
    let o = v(0.3, 0.0, 0.0);
    let up = v(0.0, 0.0, 1.0);
    let glass = Glazing::new(0.8, crate::lighting::glazing::GLASS_INDEX).unwrap();
    let pane = convex(&square(1.0, -1.0, 1.0), Some(glass)).unwrap();
    let roof = convex(&square(2.0, -1.0, 1.0), None).unwrap();
    let clear = |c: Cone| match c {
        Cone::Clear(t) => t,
        other => panic!("{other:?}"),
    };
    assert!((clear(SunCones::of(vec![pane], alpha).classify(o, up)) - 0.8).abs() < 1e-12);
    let tilted = (up + DVec3::new(0.3, 0.0, 0.0)).normalize();
    assert_eq!(
        SunCones::of(vec![pane, pane], alpha).classify(o, tilted),
        Cone::Clear(glass.transmittance(tilted.z).powi(2))
    );
    assert_eq!(
        SunCones::of(vec![pane, roof], alpha).classify(o, up),
        Cone::Blocked
    );
    let halves = vec![
        convex(&square(1.0, -1.0, 0.3), Some(glass)).unwrap(),
        convex(&square(1.0, 0.3, 1.0), Some(glass)).unwrap(),
    ];
    assert_eq!(
        SunCones::of(halves.clone(), alpha).classify(o, up),
        Cone::Partial
    );
    let t = clear(SunCones::of(halves, alpha).classify(v(0.0, 0.0, 0.0), up));
    assert!((t - 0.8).abs() < 1e-12);
    // 400 small opaque tiles on a grid: the hierarchy's answer equals the brute answer of
    // each tile alone, for cones from many places.
    let mut tiles = Vec::new();
    for i in 0..20 {
        for j in 0..20 {
            let (x, y) = (i as f64 * 0.3, j as f64 * 0.3);
            tiles.push(
                convex(
                    &[
                        v(x, y, 3.0),
                        v(x + 0.2, y, 3.0),
                        v(x + 0.2, y + 0.2, 3.0),
                        v(x, y + 0.2, 3.0),
                    ],
                    None,
                )
                .unwrap(),
            );
        }
    }
    let all = SunCones::of(tiles.clone(), alpha);
    let mut rng = stream(3, 3, 3, 3);
    let mut seen = [0usize; 3];

    for _ in 0..5_000 {
        let o = v(
            uniform(&mut rng) as f64 * 6.0,
            uniform(&mut rng) as f64 * 6.0,
            0.0,
        );
        let c = (v(
            uniform(&mut rng) as f64 - 0.5,
            uniform(&mut rng) as f64 - 0.5,
            1.0,
        ))
        .normalize();
        let mut brute = Cone::Clear(1.0);
        for t in &tiles {
            match SunCones::of(vec![*t], alpha).classify(o, c) {
                Cone::Blocked => {
                    brute = Cone::Blocked;
                    break;
                }
                Cone::Partial => brute = Cone::Partial,
                Cone::Clear(_) => {}
            }
        }
        let got = all.classify(o, c);
        assert_eq!(got, brute);
        seen[match got {
            Cone::Blocked => 0,
            Cone::Clear(_) => 1,
            Cone::Partial => 2,
        }] += 1;
    }
    assert!(seen.iter().all(|&k| k > 50), "{seen:?}");
}

/// Two opaque polygons sharing an edge or part of one (a T-junction), in one plane (a wall in
/// pieces) or folded along it at random (two walls at a corner, seen from either side), and
/// cones aimed across the seam:
/// Blocked only when every sampled direction meets one of the two, and the cones that the two
/// cover only together (neither alone) are mostly decided Blocked rather than sampled.
#[test]
fn seams_block_what_their_two_sides_cover() {
    let mut rng = stream(11, 4, 2, 9);
    let alpha = (0.5 * 0.533f64).to_radians();
    let (mut blocked, mut covered, mut covered_blocked) = (0usize, 0usize, 0usize);
    for trial in 0..6_000 {
        let centre = random_point(&mut rng, 1.0);
        let (u, v) = (random_point(&mut rng, 1.5), random_point(&mut rng, 1.5));
        let a = vec![
            centre - u - v,
            centre + u - v,
            centre + u + v,
            centre - u + v,
        ];
        // B across A's edge 1–2: in A's plane, or turned about the edge by up to ±170°.
        let (p, q) = (a[1], a[2]);
        let axis = (q - p).normalize();
        let out = (p - a[0]) - axis * axis.dot(p - a[0]);
        let turn = if trial % 3 == 0 {
            0.0
        } else {
            (uniform(&mut rng) as f64 * 2.0 - 1.0) * 170f64.to_radians()
        };
        let w = glam::DQuat::from_axis_angle(axis, turn) * out * (0.3 + uniform(&mut rng) as f64);
        // B's edge along A's: the same edge, or (every other trial) a T-junction, B's edge
        // running from inside A's past one of its ends.
        let (s0, s1) = if trial % 2 == 0 {
            (0.0, 1.0)
        } else {
            (
                0.5 * uniform(&mut rng) as f64,
                1.0 + 0.5 * uniform(&mut rng) as f64,
            )
        };
        let (bp, bq) = (p + (q - p) * s0, p + (q - p) * s1);
        let b = vec![bq, bp, bp + w, bq + w];
        let (Some(pa), Some(pb)) = (convex(&a, None), convex(&b, None)) else {
            continue;
        };
        let o = centre + random_point(&mut rng, 6.0);
        // Near the seam, not on it (a direction exactly along the seam's plane is met by
        // neither polygon in the brute force's rounding, by both in exact arithmetic).
        let s = uniform(&mut rng) as f64;
        let aim = p + (q - p) * s + (p - a[0]) * (0.02 * (uniform(&mut rng) as f64 - 0.5));
        let c = (aim - o).normalize_or_zero();
        if c == DVec3::ZERO {
            continue;
        }
        let cones = SunCones::of(vec![pa, pb], alpha - MARGIN);
        let dirs = cone(c, alpha);
        let met = dirs
            .iter()
            .filter(|&&d| hits(&a, o, d) || hits(&b, o, d))
            .count();
        let got = cones.classify(o, c);
        if got == Cone::Blocked {
            blocked += 1;
            assert_eq!(met, dirs.len(), "Blocked but a direction passes: {trial}");
        }
        // Covered by the two together, with room to spare, and cut by the seam.
        let wide = cone(c, 2.0 * alpha);
        let wide_met = wide
            .iter()
            .filter(|&&d| hits(&a, o, d) || hits(&b, o, d))
            .count();
        let far_corners = [a[0], a[3], b[2], b[3], p, q, bp, bq]
            .iter()
            .all(|&x| (x - o).normalize().dot(c) < (3.0 * alpha).cos());
        // Neither alone covers it: only the seam rule can decide it.
        let straddles =
            wide.iter().any(|&d| !hits(&a, o, d)) && wide.iter().any(|&d| !hits(&b, o, d));
        if wide_met == wide.len() && far_corners && straddles {
            covered += 1;
            covered_blocked += (got == Cone::Blocked) as usize;
        }
    }
    assert!(blocked > 300, "{blocked}");
    assert!(
        covered > 300 && covered_blocked as f64 > 0.9 * covered as f64,
        "{covered_blocked} of {covered}"
    );
}

/// A wide cone about a group of suns against random polygons, opaque and glazed: Blocked only
/// when every sun inside it is Blocked alone, and Clear only when every sun inside it is Clear
/// alone with the product of the listed panes' τ, bit for bit; the three answers each occur.
#[test]
fn a_wide_cone_decides_every_sun_inside_it() {
    let mut rng = stream(13, 2, 7, 1);
    let glass = Glazing::new(0.8, crate::lighting::glazing::GLASS_INDEX).unwrap();
    let alpha = (0.5 * 0.533f64).to_radians();
    let mut seen = [0usize; 3];
    for trial in 0..4_000 {
        let polygons: Vec<Convex> = (0..4)
            .filter_map(|k| {
                let pane = (k % 2 == 1).then_some(glass);
                convex(&random_polygon(&mut rng), pane)
            })
            .collect();
        let cones = SunCones::of(polygons, alpha);
        let o = random_point(&mut rng, 4.0);
        let target = cones.polygons[trial % cones.polygons.len()].centre;
        let axis = (target - o + random_point(&mut rng, 0.5)).normalize_or_zero();
        if axis == DVec3::ZERO {
            continue;
        }
        let spread = uniform(&mut rng) as f64 * WIDEST.to_radians();
        let ap = cones.aperture(spread).unwrap();
        let (t, b) = (
            axis.any_orthonormal_vector(),
            axis.cross(axis.any_orthonormal_vector()),
        );
        let suns: Vec<DVec3> = (0..8)
            .map(|k| {
                let r = spread * if k == 0 { 0.0 } else { (k as f64 / 7.0).sqrt() };
                let phi = std::f64::consts::TAU * uniform(&mut rng) as f64;
                (axis * r.cos() + (t * phi.cos() + b * phi.sin()) * r.sin()).normalize()
            })
            .collect();
        let mut view = Viewpoint::new(o);
        match cones.classify_wide(&mut view, axis, ap) {
            Wide::Blocked => {
                seen[0] += 1;
                for &c in &suns {
                    assert_eq!(cones.classify(o, c), Cone::Blocked, "{trial}");
                }
            }
            Wide::Clear { panes, count } => {
                seen[1] += 1;
                for &c in &suns {
                    // As the single sun's test takes it (normalised again).
                    let tau = cones.transmittance(&panes[..count], c.normalize_or_zero());
                    match cones.classify(o, c) {
                        Cone::Clear(t) if count <= 1 => assert_eq!(t, tau, "{trial}"),
                        Cone::Clear(t) => assert!((t - tau).abs() <= 1e-15, "{trial}"),
                        other => panic!("{trial}: {other:?}"),
                    }
                }
            }
            Wide::Partial => seen[2] += 1,
        }
    }
    assert!(seen.iter().all(|&k| k > 200), "{seen:?}");
}

/// Two opaque squares side by side in the plane z = 1 and the sun's cone from the origin
/// aimed across their seam: touching (one edge, or a T-junction where the second square's
/// edge is longer) they block it; 0.002 apart, a gap of 0.002 rad that the cone straddles,
/// the cone is Partial (sampled), not Blocked.
#[test]
fn a_seam_blocks_and_a_gap_does_not() {
    let v = |x: f64, y: f64| DVec3::new(x, y, 1.0);
    let alpha = (0.5 * 0.533f64).to_radians();
    let left = convex(
        &[v(-1.0, -1.0), v(0.0, -1.0), v(0.0, 1.0), v(-1.0, 1.0)],
        None,
    )
    .unwrap();
    let right = |x0: f64, y0: f64, y1: f64| {
        convex(&[v(x0, y0), v(1.0, y0), v(1.0, y1), v(x0, y1)], None).unwrap()
    };
    let c = DVec3::new(0.001, 0.0, 1.0).normalize();
    let o = DVec3::ZERO;
    for (r, want) in [
        (right(0.0, -1.0, 1.0), Cone::Blocked),
        (right(0.0, -1.5, 2.0), Cone::Blocked),
        (right(0.002, -1.0, 1.0), Cone::Partial),
    ] {
        assert_eq!(SunCones::of(vec![left, r], alpha).classify(o, c), want);
    }
}
