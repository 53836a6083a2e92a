//! The hemisphere, Nusselt's analog (Szirmay-Kalos & Márton (1995), "Geometric methods"): what is
//! visible from a point of patch i is projected onto the unit hemisphere and then orthographically
//! onto its base circle; the form factor of patch j is the share of the circle's area covered by
//! its double projection. The circle is discretised into a P × P grid of equal cells (those whose
//! centre lies inside it), each worth `cell area / π` (normalised to sum to 1), and the patch seen
//! through a cell is found by casting a ray towards the hemisphere point above the cell's centre.
//! O(P² log N) per point with the hierarchy.

use super::estimator::{Estimator, Scratch};
use super::quadrature::patch_points;
use crate::geom::{orthonormal_basis, Ray};

/// The disc cells of resolution `p`: `(x, y, weight)` with weights summing to 1.
pub fn cells(p: usize) -> Vec<(f32, f32, f32)> {
    let p = p.max(2);
    let h = 2.0 / p as f64;
    let mut out = Vec::with_capacity(p * p);
    for j in 0..p {
        for i in 0..p {
            let (x, y) = (-1.0 + (i as f64 + 0.5) * h, -1.0 + (j as f64 + 0.5) * h);
            if x * x + y * y < 1.0 {
                out.push((x as f32, y as f32, 0.0f32));
            }
        }
    }
    let w = 1.0 / out.len() as f32;
    out.iter_mut().for_each(|c| c.2 = w);
    out
}

/// Row `i` of F: at each quadrature point of patch i, one ray through every disc cell; the
/// front-facing patch it hits first receives the cell's weight.
pub(super) fn row(est: &Estimator, i: usize, scratch: &mut Scratch) {
    let mut points = std::mem::take(&mut scratch.points);
    patch_points(est.mesh, i, est.params.samples, &mut points);
    let n = est.mesh.patches[i].normal;
    let (t, b) = orthonormal_basis(n);
    for &(o, weight) in &points {
        let origin = o + n * est.offset;
        for &(x, y, w) in &est.cells {
            let z = (1.0 - x * x - y * y).max(0.0).sqrt();
            let d = t * x + b * y + n * z;
            if let Some(h) = est.bvh.closest_hit(&Ray::new(origin, d), f32::INFINITY) {
                if h.front && h.patch as usize != i {
                    scratch.add(h.patch, weight * w as f64);
                }
            }
        }
    }
    scratch.points = points;
}
