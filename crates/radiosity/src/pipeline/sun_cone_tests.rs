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
