//! The references' mathematics, written here and nowhere else: nothing of the engine under
//! test is used.
//!
//! - The solid angle of a rectangle from a point (the isotropic source's flux onto a wall):
//!   for a rectangle of sides a, b at distance h whose corner is the foot of the perpendicular,
//!   Ω = atan(a b / (h √(a² + b² + h²))) (e.g. Gardner & Carnes; it is the sum of two
//!   Van Oosterom & Strackee (1983) triangle angles), any other placement by superposition.
//! - Configuration factors from a differential planar element to a rectangle, from Howell's
//!   catalogue ("A Catalog of Radiation Heat Transfer Configuration Factors"):
//!   - the rectangle parallel to the element, the element's normal through a corner
//!     (X = a/c, Y = b/c):
//!     F = 1/(2π) [X/√(1+X²) atan(Y/√(1+X²)) + Y/√(1+Y²) atan(X/√(1+Y²))];
//!   - the rectangle in a perpendicular plane, one of its edges on the line where that plane
//!     meets the element's plane, the element below one end of that edge at distance h from
//!     the line, the rectangle a along the line and c away from it:
//!     F = 1/(2π) [atan(a/h) − h/√(h² + c²) atan(a/√(h² + c²))];
//!
//!   any other rectangle in those two planes by superposition (signed corners). The
//!   illuminance from a Lambertian luminous rectangle of luminance L is E = π L F, and the
//!   flux a Lambertian point source of nadir intensity I₀ sends into a rectangle is π I₀ F
//!   (its projected solid angle).
//! - Lambert's contour formula for any polygon, F = 1/(2π) Σ_edges β_k (n · ĉ_k), β_k the angle
//!   an edge subtends and ĉ_k the unit normal of the plane through the point and the edge: the
//!   independent check of the two catalogue cases in the tests.
//! - Gauss–Legendre quadrature (nodes by Newton's iteration on the Legendre polynomial),
//!   composite over equal panels, for the reflection references.

use std::f64::consts::PI;

/// A 3-vector in metres.
pub type V3 = [f64; 3];

pub(crate) fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

pub(crate) fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

pub(crate) fn cross(a: V3, b: V3) -> V3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

pub(crate) fn norm(a: V3) -> f64 {
    dot(a, a).sqrt()
}

/// An axis-aligned rectangle: the plane `axis = at`, spanning `lo..hi` on the other two axes
/// (in increasing axis order: for `axis` 2, `lo[0]..hi[0]` is x and `lo[1]..hi[1]` is y).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rect {
    /// The axis the rectangle is perpendicular to: 0, 1 or 2.
    pub axis: usize,
    /// Its coordinate on that axis, metres.
    pub at: f64,
    /// The lower corner on the other two axes.
    pub lo: [f64; 2],
    /// The upper corner on the other two axes.
    pub hi: [f64; 2],
}

impl Rect {
    /// The two axes the rectangle spans, in increasing order.
    pub fn span_axes(&self) -> [usize; 2] {
        match self.axis {
            0 => [1, 2],
            1 => [0, 2],
            _ => [0, 1],
        }
    }

    /// The point at (u, v) on the spanned axes.
    pub fn point(&self, u: f64, v: f64) -> V3 {
        let [a, b] = self.span_axes();
        let mut p = [0.0; 3];
        p[self.axis] = self.at;
        p[a] = u;
        p[b] = v;
        p
    }

    /// Its area, m².
    pub fn area(&self) -> f64 {
        (self.hi[0] - self.lo[0]) * (self.hi[1] - self.lo[1])
    }

    /// Its four corners, counter-clockwise seen from the +axis side.
    pub fn corners(&self) -> [V3; 4] {
        [
            self.point(self.lo[0], self.lo[1]),
            self.point(self.hi[0], self.lo[1]),
            self.point(self.hi[0], self.hi[1]),
            self.point(self.lo[0], self.hi[1]),
        ]
    }
}

/// Solid angle, steradians, of the rectangle `[0, a] × [0, b]` seen from a point at distance
/// `h` above its corner (0 when any side is 0).
pub fn solid_angle_corner(a: f64, b: f64, h: f64) -> f64 {
    if a <= 0.0 || b <= 0.0 || h <= 0.0 {
        return 0.0;
    }
    (a * b / (h * (a * a + b * b + h * h).sqrt())).atan()
}

/// Solid angle, steradians, of `rect` seen from `p` (not in its plane).
pub fn solid_angle(p: V3, rect: &Rect) -> f64 {
    let h = (rect.at - p[rect.axis]).abs();
    let [a, b] = rect.span_axes();
    let corner = |u: f64, v: f64| u.signum() * v.signum() * solid_angle_corner(u.abs(), v.abs(), h);
    superpose(rect, [p[a], p[b]], corner)
}

/// Σ over the four corners of `rect` (relative to `foot` on its spanned axes) of ±g(u, v): the
/// superposition of corner-anchored rectangles for a function g odd in u and in v.
fn superpose(rect: &Rect, foot: [f64; 2], g: impl Fn(f64, f64) -> f64) -> f64 {
    let (u0, u1) = (rect.lo[0] - foot[0], rect.hi[0] - foot[0]);
    let (v0, v1) = (rect.lo[1] - foot[1], rect.hi[1] - foot[1]);
    g(u1, v1) - g(u0, v1) - g(u1, v0) + g(u0, v0)
}

/// Howell's parallel case: the configuration factor from a differential element to the
/// parallel rectangle `[0, a] × [0, b]` at distance `c`, the element's normal through a
/// corner.
pub fn factor_parallel_corner(a: f64, b: f64, c: f64) -> f64 {
    if a <= 0.0 || b <= 0.0 || c <= 0.0 {
        return 0.0;
    }
    let (x, y) = (a / c, b / c);
    let (sx, sy) = ((1.0 + x * x).sqrt(), (1.0 + y * y).sqrt());
    (x / sx * (y / sx).atan() + y / sy * (x / sy).atan()) / (2.0 * PI)
}

/// Howell's perpendicular case: the configuration factor from a differential element to the
/// rectangle `a` along the line where its plane meets the element's plane and `c` away from
/// that line, the element at distance `h` from the line below one end of the rectangle's
/// edge on it.
pub fn factor_perpendicular_corner(a: f64, c: f64, h: f64) -> f64 {
    if a <= 0.0 || c <= 0.0 || h <= 0.0 {
        return 0.0;
    }
    let s = (h * h + c * c).sqrt();
    ((a / h).atan() - h / s * (a / s).atan()) / (2.0 * PI)
}

/// The configuration factor from a differential element at `p` facing along axis `normal_axis`
/// (`normal_sign` ±1) to the axis-aligned `rect`: Howell's parallel or perpendicular case by
/// superposition; what lies behind the element's plane is not seen.
pub fn factor(p: V3, normal_axis: usize, normal_sign: f64, rect: &Rect) -> f64 {
    let [a, b] = rect.span_axes();
    if normal_axis == rect.axis {
        let c = (rect.at - p[rect.axis]) * normal_sign;
        if c <= 0.0 {
            return 0.0;
        }
        let corner =
            |u: f64, v: f64| u.signum() * v.signum() * factor_parallel_corner(u.abs(), v.abs(), c);
        return superpose(rect, [p[a], p[b]], corner);
    }
    // Perpendicular: the rectangle's plane is `h` from the element along `rect.axis`; along
    // the element's normal it extends over [y0, y1] in front of the element (clipped at its
    // plane); along the third axis over [x0, x1].
    let h = (rect.at - p[rect.axis]).abs();
    if h <= 0.0 {
        return 0.0;
    }
    let (k_normal, k_line) = if a == normal_axis { (0, 1) } else { (1, 0) };
    let line_axis = if k_line == 0 { a } else { b };
    let y = |v: f64| ((v - p[normal_axis]) * normal_sign).max(0.0);
    let (y0, y1) = {
        let (s, t) = (y(rect.lo[k_normal]), y(rect.hi[k_normal]));
        (s.min(t), s.max(t))
    };
    let (x0, x1) = (
        rect.lo[k_line] - p[line_axis],
        rect.hi[k_line] - p[line_axis],
    );
    let strip = |x: f64, c: f64| x.signum() * factor_perpendicular_corner(x.abs(), c, h);
    (strip(x1, y1) - strip(x0, y1)) - (strip(x1, y0) - strip(x0, y0))
}

/// Lambert's contour formula: the configuration factor from a differential element at `p`
/// with unit normal `n` to the planar polygon `vertices` (wholly in front of the element).
pub fn factor_polygon(p: V3, n: V3, vertices: &[V3]) -> f64 {
    let mut sum = 0.0;
    for k in 0..vertices.len() {
        let a = sub(vertices[k], p);
        let b = sub(vertices[(k + 1) % vertices.len()], p);
        let c = cross(a, b);
        let len = norm(c);
        if len == 0.0 {
            continue;
        }
        let beta = len.atan2(dot(a, b));
        sum += beta * dot(n, c) / len;
    }
    sum.abs() / (2.0 * PI)
}

/// Gauss–Legendre nodes and weights on [−1, 1], `n` points (exact for polynomials of degree
/// 2n − 1). Newton's iteration on P_n from Chebyshev guesses, to machine precision.
pub fn gauss_legendre(n: usize) -> (Vec<f64>, Vec<f64>) {
    let mut x = vec![0.0; n];
    let mut w = vec![0.0; n];
    for i in 0..n.div_ceil(2) {
        let mut z = (PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        let mut dp = 1.0;
        for _ in 0..100 {
            // P_n(z) (in p1) and P_{n−1}(z) (in p0) by the three-term recurrence, then
            // P_n'(z) = n (z P_n − P_{n−1}) / (z² − 1).
            let (mut p0, mut p1) = (0.0, 1.0);
            for k in 1..=n {
                let p2 = ((2 * k - 1) as f64 * z * p1 - (k - 1) as f64 * p0) / k as f64;
                p0 = p1;
                p1 = p2;
            }
            dp = n as f64 * (z * p1 - p0) / (z * z - 1.0);
            let dz = p1 / dp;
            z -= dz;
            if dz.abs() < 1e-15 {
                break;
            }
        }
        x[i] = -z;
        x[n - 1 - i] = z;
        let wi = 2.0 / ((1.0 - z * z) * dp * dp);
        w[i] = wi;
        w[n - 1 - i] = wi;
    }
    (x, w)
}

/// A composite Gauss–Legendre rule on `[a, b]`: `panels` equal panels of `points` nodes each.
pub fn composite(a: f64, b: f64, panels: usize, points: usize) -> Vec<(f64, f64)> {
    let (x, w) = gauss_legendre(points);
    let h = (b - a) / panels as f64;
    let mut out = Vec::with_capacity(panels * points);
    for p in 0..panels {
        let mid = a + (p as f64 + 0.5) * h;
        for (xi, wi) in x.iter().zip(&w) {
            out.push((mid + 0.5 * h * xi, 0.5 * h * wi));
        }
    }
    out
}

/// The nodes (positions on the rectangle) and area weights of a product composite
/// Gauss–Legendre rule over `rect`.
pub fn rect_rule(rect: &Rect, panels: usize, points: usize) -> Vec<(V3, f64)> {
    let us = composite(rect.lo[0], rect.hi[0], panels, points);
    let vs = composite(rect.lo[1], rect.hi[1], panels, points);
    let mut out = Vec::with_capacity(us.len() * vs.len());
    for &(u, wu) in &us {
        for &(v, wv) in &vs {
            out.push((rect.point(u, v), wu * wv));
        }
    }
    out
}

/// The differential configuration-factor kernel cos θ_p cos θ_y / (π r²) between a point `p`
/// with unit normal `np` and a point `y` with unit normal `ny` (0 when either faces away).
pub fn kernel(p: V3, np: V3, y: V3, ny: V3) -> f64 {
    let d = sub(y, p);
    let r2 = dot(d, d);
    if r2 == 0.0 {
        return 0.0;
    }
    let cp = dot(np, d);
    let cy = -dot(ny, d);
    if cp <= 0.0 || cy <= 0.0 {
        return 0.0;
    }
    cp * cy / (PI * r2 * r2)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64, rel: f64) -> bool {
        (a - b).abs() <= rel * b.abs().max(1e-300)
    }

    /// Gauss–Legendre integrates polynomials of degree 2n − 1 exactly and its weights sum to 2.
    #[test]
    fn gauss_legendre_is_exact_for_its_degree() {
        for n in [1, 2, 3, 4, 7, 8, 16] {
            let (x, w) = gauss_legendre(n);
            assert!(close(w.iter().sum::<f64>(), 2.0, 1e-14), "n {n}");
            for k in 0..(2 * n) {
                let got: f64 = x.iter().zip(&w).map(|(x, w)| w * x.powi(k as i32)).sum();
                let want = if k % 2 == 1 {
                    0.0
                } else {
                    2.0 / (k as f64 + 1.0)
                };
                assert!(
                    (got - want).abs() < 1e-13,
                    "n {n} degree {k}: {got} vs {want}"
                );
            }
        }
    }

    /// The two catalogue cases against Lambert's contour formula, on rectangles placed every
    /// way around the element (superposition with corners on either side of the foot), and
    /// the solid angle against the same superposition of its corner formula summed as four
    /// triangles' Van Oosterom–Strackee angles.
    #[test]
    fn catalogue_cases_match_the_contour_formula() {
        let rects = [
            Rect {
                axis: 2,
                at: 3.0,
                lo: [1.5, 1.5],
                hi: [2.5, 2.5],
            },
            Rect {
                axis: 2,
                at: 3.0,
                lo: [-1.0, 0.5],
                hi: [2.0, 4.0],
            },
            Rect {
                axis: 2,
                at: 3.0,
                lo: [0.2, 0.3],
                hi: [0.9, 1.7],
            },
            Rect {
                axis: 2,
                at: 2.0,
                lo: [-3.0, -2.0],
                hi: [-0.5, 0.25],
            },
        ];
        let points: [(V3, usize, f64); 5] = [
            ([0.0, 0.0, 0.0], 2, 1.0),
            ([2.0, 2.25, 0.0], 2, 1.0),
            ([2.0, 0.0, 0.75], 1, 1.0),
            ([0.0, 0.1, 1.5], 0, 1.0),
            ([1.0, 4.0, 2.75], 1, -1.0),
        ];
        for rect in &rects {
            for &(p, axis, sign) in &points {
                if (rect.at - p[rect.axis]).abs() < 1e-12 {
                    continue;
                }
                let mut n = [0.0; 3];
                n[axis] = sign;
                // Lambert's formula sees only what is in front: clip by hand for the
                // perpendicular case (the part behind contributes nothing).
                let mut clipped = *rect;
                if axis != rect.axis {
                    let [a, _] = rect.span_axes();
                    let k = if a == axis { 0 } else { 1 };
                    if sign > 0.0 {
                        clipped.lo[k] = clipped.lo[k].max(p[axis]);
                    } else {
                        clipped.hi[k] = clipped.hi[k].min(p[axis]);
                    }
                    if clipped.lo[k] >= clipped.hi[k] {
                        assert_eq!(factor(p, axis, sign, rect), 0.0);
                        continue;
                    }
                } else if (rect.at - p[axis]) * sign <= 0.0 {
                    assert_eq!(factor(p, axis, sign, rect), 0.0);
                    continue;
                }
                let want = factor_polygon(p, n, &clipped.corners());
                let got = factor(p, axis, sign, rect);
                assert!(close(got, want, 1e-12), "{rect:?} {p:?}: {got} vs {want}");
            }
            // Solid angle: four triangles from the foot of the perpendicular's corners.
            let p = [0.7, 1.1, 0.0];
            let c = rect.corners();
            let tri = |a: V3, b: V3, c: V3| {
                let (a, b, c) = (sub(a, p), sub(b, p), sub(c, p));
                let (la, lb, lc) = (norm(a), norm(b), norm(c));
                let num = dot(a, cross(b, c));
                let den = la * lb * lc + dot(a, b) * lc + dot(a, c) * lb + dot(b, c) * la;
                2.0 * num.atan2(den)
            };
            let want = (tri(c[0], c[1], c[2]) + tri(c[0], c[2], c[3])).abs();
            assert!(close(solid_angle(p, rect), want, 1e-12));
        }
        // A whole half-space: an infinite plane facing the element fills its hemisphere.
        let big = Rect {
            axis: 2,
            at: 1.0,
            lo: [-1e7, -1e7],
            hi: [1e7, 1e7],
        };
        assert!(close(factor([0.0; 3], 2, 1.0, &big), 1.0, 1e-6));
        assert!(close(solid_angle([0.0; 3], &big), 2.0 * PI, 1e-6));
    }

    /// The product Gauss–Legendre rule with a constant integrand reproduces the closed-form
    /// configuration factor.
    #[test]
    fn quadrature_of_the_kernel_is_the_configuration_factor() {
        let rect = Rect {
            axis: 2,
            at: 0.0,
            lo: [0.0, 0.0],
            hi: [4.0, 4.0],
        };
        let up = [0.0, 0.0, 1.0];
        for (p, n) in [
            ([2.0, 0.0, 0.75], [0.0, 1.0, 0.0]),
            ([2.0, 0.25, 3.0], [0.0, 0.0, -1.0]),
            ([1.0, 3.0, 2.0], [0.0, 0.0, -1.0]),
        ] {
            let q: f64 = rect_rule(&rect, 16, 8)
                .iter()
                .map(|&(y, w)| w * kernel(p, n, y, up))
                .sum();
            let axis = n.iter().position(|v| *v != 0.0).unwrap();
            let f = factor(p, axis, n[axis], &rect);
            assert!(close(q, f, 1e-10), "{p:?}: {q} vs {f}");
        }
    }
}
