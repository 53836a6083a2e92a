//! Quadrature over a patch for the outer integral of eq. 6 of Szirmay-Kalos & Márton (1995):
//! Gauss–Legendre rules on [0, 1], and tensor rules over quads (through the bilinear map) and
//! triangles (through the collapsed, Duffy, map).

use crate::geom::Vec3;
use crate::mesh::Mesh;
use std::f64::consts::PI;

/// Quadrature points over patch `i` with weights summing to 1: an m × m Gauss–Legendre rule,
/// m = ⌈√samples⌉. On a quad it is a tensor rule through the bilinear map, weighted by its
/// Jacobian; on a triangle, a tensor rule through the collapsed (Duffy) map. The point-to-patch
/// factor is smooth over the patch, so this converges far faster than a grid of cell centres.
pub fn patch_points(mesh: &Mesh, i: usize, samples: u32, out: &mut Vec<(Vec3, f64)>) {
    out.clear();
    let p = &mesh.patches[i];
    let v = |k: usize| mesh.vertices[p.vertices[k] as usize];
    let m = (samples as f64).sqrt().ceil().max(1.0) as usize;
    let (nodes, weights) = gauss_legendre(m);
    if p.is_triangle() {
        let (a, b, c) = (v(0), v(1), v(2));
        for (x, wx) in nodes.iter().zip(&weights) {
            for (y, wy) in nodes.iter().zip(&weights) {
                let (s, t) = (*x, y * (1.0 - x));
                let q = a + (b - a) * s as f32 + (c - a) * t as f32;
                out.push((q, wx * wy * (1.0 - x)));
            }
        }
    } else {
        let (a, b, c, d) = (v(0), v(1), v(2), v(3));
        for (x, wx) in nodes.iter().zip(&weights) {
            for (y, wy) in nodes.iter().zip(&weights) {
                let (s, t) = (*x as f32, *y as f32);
                let q = a * ((1.0 - s) * (1.0 - t))
                    + b * (s * (1.0 - t))
                    + c * (s * t)
                    + d * ((1.0 - s) * t);
                let ds = (b - a) * (1.0 - t) + (c - d) * t;
                let dt = (d - a) * (1.0 - s) + (c - b) * s;
                out.push((q, wx * wy * ds.cross(dt).length() as f64));
            }
        }
    }
    let total: f64 = out.iter().map(|p| p.1).sum();
    out.iter_mut().for_each(|p| p.1 /= total);
}

/// Gauss–Legendre nodes and weights on [0, 1] with `m` points (Newton's iteration on the
/// Legendre polynomial from the Chebyshev guess, Golub–Welsch accuracy for the sizes used).
pub fn gauss_legendre(m: usize) -> (Vec<f64>, Vec<f64>) {
    let mut nodes = Vec::with_capacity(m);
    let mut weights = Vec::with_capacity(m);
    for k in 0..m {
        let mut x = (PI * (k as f64 + 0.75) / (m as f64 + 0.5)).cos();
        let mut dp = 1.0;
        for _ in 0..100 {
            // P_m(x) and its derivative by the three-term recurrence.
            let (mut p0, mut p1) = (1.0, x);
            for n in 2..=m {
                let p2 = ((2 * n - 1) as f64 * x * p1 - (n - 1) as f64 * p0) / n as f64;
                p0 = p1;
                p1 = p2;
            }
            let pm = if m == 0 {
                1.0
            } else if m == 1 {
                x
            } else {
                p1
            };
            let pm1 = if m == 1 { 1.0 } else { p0 };
            dp = m as f64 * (x * pm - pm1) / (x * x - 1.0);
            let dx = pm / dp;
            x -= dx;
            if dx.abs() < 1e-16 {
                break;
            }
        }
        nodes.push(0.5 * (1.0 - x));
        weights.push(1.0 / ((1.0 - x * x) * dp * dp));
    }
    (nodes, weights)
}

#[cfg(test)]
mod tests {
    #[test]
    fn gauss_legendre_integrates_polynomials_exactly() {
        for m in 1..12 {
            let (x, w) = super::gauss_legendre(m);
            assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-14);
            // Exact for degree 2m − 1: ∫₀¹ x^d dx = 1/(d + 1).
            for d in 0..2 * m {
                let q: f64 = x.iter().zip(&w).map(|(x, w)| w * x.powi(d as i32)).sum();
                assert!((q - 1.0 / (d + 1) as f64).abs() < 1e-13, "m={m} d={d}: {q}");
            }
        }
    }
}
