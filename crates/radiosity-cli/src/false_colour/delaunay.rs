//! The Delaunay triangulation of scattered grid points, for linear interpolation between
//! them: the Bowyer–Watson algorithm (Bowyer 1981; Watson 1981) inserting the points in
//! order of x and retiring a triangle once its circumcircle lies wholly left of the next
//! point (Bourke's sweep, "Triangulate", 1989), which keeps the working set near √n
//! triangles for evenly spread points. The triangles cover the points' convex hull.
//!
//! Floating point only: four co-circular points (a rotated lattice) may be triangulated
//! either way, both Delaunay. [`triangulate`] checks its result (every triangle counter-
//! clockwise, the areas summing to the hull's, no overlap and at most slivers of 1e-4 of the
//! hull's area missing at its edge) and says so when rounding broke it.

/// A triangulation: triangles as counter-clockwise vertex indices into the input points.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Triangulation {
    /// Triangles, counter-clockwise.
    pub triangles: Vec<[usize; 3]>,
}

#[derive(Clone, Copy)]
struct Tri {
    v: [usize; 3],
    centre: [f64; 2],
    r2: f64,
}

fn orient(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}

/// The triangle (a, b, c) made counter-clockwise, with its circumcircle.
fn triangle(pts: &[[f64; 2]], mut v: [usize; 3]) -> Tri {
    if orient(pts[v[0]], pts[v[1]], pts[v[2]]) < 0.0 {
        v.swap(1, 2);
    }
    let (a, b, c) = (pts[v[0]], pts[v[1]], pts[v[2]]);
    let (bx, by, cx, cy) = (b[0] - a[0], b[1] - a[1], c[0] - a[0], c[1] - a[1]);
    let d = 2.0 * (bx * cy - by * cx);
    let (b2, c2) = (bx * bx + by * by, cx * cx + cy * cy);
    let ux = (cy * b2 - by * c2) / d;
    let uy = (bx * c2 - cx * b2) / d;
    Tri {
        v,
        centre: [a[0] + ux, a[1] + uy],
        r2: ux * ux + uy * uy,
    }
}

/// Area of the convex hull of `pts` (Andrew's monotone chain).
pub fn hull_area(pts: &[[f64; 2]]) -> f64 {
    let mut p: Vec<[f64; 2]> = pts.to_vec();
    p.sort_by(|a, b| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])));
    if p.len() < 3 {
        return 0.0;
    }
    let mut hull: Vec<[f64; 2]> = Vec::with_capacity(2 * p.len());
    for pass in 0..2 {
        let start = hull.len();
        let iter: Box<dyn Iterator<Item = &[f64; 2]>> = if pass == 0 {
            Box::new(p.iter())
        } else {
            Box::new(p.iter().rev())
        };
        for &q in iter {
            while hull.len() >= start + 2
                && orient(hull[hull.len() - 2], hull[hull.len() - 1], q) <= 0.0
            {
                hull.pop();
            }
            hull.push(q);
        }
        hull.pop();
    }
    let n = hull.len();
    (0..n)
        .map(|i| {
            let (a, b) = (hull[i], hull[(i + 1) % n]);
            a[0] * b[1] - a[1] * b[0]
        })
        .sum::<f64>()
        / 2.0
}

/// The Delaunay triangulation of `pts` (distinct points, not all on a line). The error says
/// the result failed its check (rounding on nearly degenerate input).
pub fn triangulate(pts: &[[f64; 2]]) -> Result<Triangulation, String> {
    let n = pts.len();
    if n < 3 {
        return Err("fewer than three points".into());
    }
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in pts {
        for k in 0..2 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let size = (hi[0] - lo[0]).max(hi[1] - lo[1]);
    let mid = [0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1])];
    // The super-triangle, far away: a hull edge is lost only when every triangle on it is
    // flatter than its circumcircle reaches (a sliver of relative area below 1e-5).
    let mut all = pts.to_vec();
    let far = 1e4 * size;
    all.push([mid[0] - far, mid[1] - far]);
    all.push([mid[0] + far, mid[1] - far]);
    all.push([mid[0], mid[1] + far]);
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| {
        pts[a][0]
            .total_cmp(&pts[b][0])
            .then(pts[a][1].total_cmp(&pts[b][1]))
    });
    let mut active = vec![triangle(&all, [n, n + 1, n + 2])];
    let mut done: Vec<Tri> = Vec::new();
    let mut edges: Vec<[usize; 2]> = Vec::new();
    let mut kept: Vec<Tri> = Vec::new();
    for &i in &order {
        let p = all[i];
        edges.clear();
        kept.clear();
        for t in active.drain(..) {
            let dx = p[0] - t.centre[0];
            let dy = p[1] - t.centre[1];
            if dx > 0.0 && dx * dx > t.r2 {
                // Every later point is at least as far right: this triangle is final.
                done.push(t);
            } else if dx * dx + dy * dy < t.r2 {
                for k in 0..3 {
                    let (a, b) = (t.v[k], t.v[(k + 1) % 3]);
                    edges.push([a.min(b), a.max(b)]);
                }
            } else {
                kept.push(t);
            }
        }
        // The cavity's boundary: the edges of exactly one removed triangle.
        edges.sort_unstable();
        let mut k = 0;
        while k < edges.len() {
            if k + 1 < edges.len() && edges[k + 1] == edges[k] {
                let e = edges[k];
                while k < edges.len() && edges[k] == e {
                    k += 1;
                }
                continue;
            }
            kept.push(triangle(&all, [edges[k][0], edges[k][1], i]));
            k += 1;
        }
        std::mem::swap(&mut active, &mut kept);
    }
    done.extend(active);
    let triangles: Vec<[usize; 3]> = done
        .into_iter()
        .filter(|t| t.v.iter().all(|&v| v < n))
        .map(|t| t.v)
        .collect();
    // The check: counter-clockwise triangles tiling the hull, no overlap, no gap.
    let mut area = 0.0;
    for t in &triangles {
        let a = orient(pts[t[0]], pts[t[1]], pts[t[2]]) / 2.0;
        if a < 0.0 {
            return Err("rounding left a triangle turned over".into());
        }
        area += a;
    }
    let hull = hull_area(pts);
    if area > hull * (1.0 + 1e-9) || area < hull * (1.0 - 1e-4) {
        return Err(format!(
            "the triangles cover {area} of the hull's {hull} (rounding on nearly degenerate points)"
        ));
    }
    Ok(Triangulation { triangles })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A deterministic scatter in the unit square (a linear congruential stream).
    fn scatter(n: usize, seed: u64) -> Vec<[f64; 2]> {
        let mut s = seed;
        let mut next = || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64
        };
        (0..n).map(|_| [next(), next()]).collect()
    }

    /// Hull vertices of points in general position (Andrew's chain, collinear ones left out).
    fn hull_count(pts: &[[f64; 2]]) -> usize {
        let mut p = pts.to_vec();
        p.sort_by(|a, b| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])));
        let mut count = 0;
        for pass in 0..2 {
            let mut hull: Vec<[f64; 2]> = Vec::new();
            if pass == 1 {
                p.reverse();
            }
            for &q in &p {
                while hull.len() >= 2
                    && orient(hull[hull.len() - 2], hull[hull.len() - 1], q) <= 0.0
                {
                    hull.pop();
                }
                hull.push(q);
            }
            count += hull.len() - 1;
        }
        count
    }

    /// The empty-circle property (no point strictly inside any triangle's circumcircle, to
    /// rounding) and the tiling of the hull (checked inside), on random points and on a
    /// rotated 12 × 9 lattice (co-circular everywhere); the count of triangles is Euler's,
    /// 2n − 2 − h for h points on the hull (2 × 11 × 8 = 176 for the lattice).
    #[test]
    fn triangulations_are_delaunay() {
        let rotated: Vec<[f64; 2]> = (0..12)
            .flat_map(|i| (0..9).map(move |j| (i as f64 * 0.3, j as f64 * 0.3)))
            .map(|(x, y)| {
                let (s, c) = 0.5f64.sin_cos();
                [c * x - s * y, s * x + c * y]
            })
            .collect();
        for (pts, count) in [
            (scatter(400, 7), None),
            (scatter(50, 3), None),
            (rotated, Some(176)),
        ] {
            let t = triangulate(&pts).unwrap();
            for tri in &t.triangles {
                let c = triangle(&pts, *tri);
                for (k, p) in pts.iter().enumerate() {
                    if tri.contains(&k) {
                        continue;
                    }
                    let d2 = (p[0] - c.centre[0]).powi(2) + (p[1] - c.centre[1]).powi(2);
                    assert!(d2 >= c.r2 * (1.0 - 1e-9), "point {k} inside {tri:?}");
                }
            }
            let want = count.unwrap_or_else(|| 2 * pts.len() - 2 - hull_count(&pts));
            assert_eq!(t.triangles.len(), want);
        }
        let square = [[0.0, 0.0], [2.0, 0.0], [2.0, 1.0], [0.0, 1.0], [1.0, 0.5]];
        assert!((hull_area(&square) - 2.0).abs() < 1e-12);
    }
}
