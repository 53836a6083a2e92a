//! The transfer coefficient of one link, evaluated at four points of its receiver.
//!
//! - From an element: the exact unoccluded factor from a point to a polygon (Lambert's contour
//!   formula, e.g. Baum, Rushmeier & Winget 1989, eq. 3) times the fraction of rays from the
//!   point to points on the source that arrive unoccluded.
//! - From a cluster: a Monte Carlo estimate of the same point-to-area factor over the cluster's
//!   surfaces, points drawn by area, each weighted by both cosines (a surface facing away sends
//!   nothing) and its visibility.
//!
//! The coefficient `k` of the link is the mean over the receiver's points, and what the
//! refinement oracle needs is kept beside it (the largest and smallest point value).

use super::cluster::{Clusters, CLUSTER};
use super::element::Element;
use crate::accel::Bvh;
use crate::geom::{Ray, Vec3};
use crate::sampling::{stream, uniform, Rng64};
use glam::DVec3;
use std::f64::consts::PI;

/// The unoccluded form factor from a differential area at `x` (unit normal `n`) to the convex
/// polygon `poly` (counter-clockwise about its unit normal `ns`). One-sided both ways: zero when
/// `x` is behind the polygon, and only the polygon's part in front of `x`'s plane counts.
pub fn point_polygon(x: Vec3, n: Vec3, poly: &[Vec3], ns: Vec3) -> f64 {
    let (x, n) = (x.as_dvec3(), n.as_dvec3());
    if (x - poly[0].as_dvec3()).dot(ns.as_dvec3()) <= 0.0 {
        return 0.0;
    }
    // Clip to the half-space in front of x (Sutherland–Hodgman against one plane).
    let mut clipped = [DVec3::ZERO; 8];
    let mut m = 0;
    let k = poly.len();
    for i in 0..k {
        let (p, q) = (poly[i].as_dvec3() - x, poly[(i + 1) % k].as_dvec3() - x);
        let (dp, dq) = (p.dot(n), q.dot(n));
        if dp > 0.0 {
            clipped[m] = p;
            m += 1;
        }
        if (dp > 0.0) != (dq > 0.0) {
            let t = dp / (dp - dq);
            clipped[m] = p + (q - p) * t;
            m += 1;
        }
    }
    if m < 3 {
        return 0.0;
    }
    let mut sum = 0.0;
    for i in 0..m {
        let (p, q) = (clipped[i], clipped[(i + 1) % m]);
        let c = p.cross(q);
        let len = c.length();
        if len <= 0.0 {
            continue;
        }
        let gamma = len.atan2(p.dot(q));
        sum += gamma * n.dot(c) / len;
    }
    (sum.abs() / (2.0 * PI)).min(1.0)
}

/// A link's coefficient and the oracle's view of it.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Estimate {
    /// The mean over the receiver's points: the fraction of the receiver's energy that would
    /// reach the source, `F_rs`.
    pub k: f32,
    /// The largest point value.
    pub hi: f32,
    /// The smallest point value.
    pub lo: f32,
    /// Rays cast.
    pub rays: u32,
    /// Some rays arrived and some were blocked: the source is partly hidden, so the part
    /// seen may be brighter or darker than the source's mean radiosity.
    pub partial: bool,
}

/// What link estimation reads.
pub struct Context<'a> {
    /// Every element.
    pub elements: &'a [Element],
    /// The clusters over the roots.
    pub clusters: &'a Clusters,
    /// The hierarchy over the input pieces, for visibility.
    pub bvh: &'a Bvh,
    /// Rays per receiver point.
    pub rays: u32,
    /// Seed of the visibility streams.
    pub seed: u64,
}

impl Context<'_> {
    /// Whether the segment from `x` (on a surface of normal `nx`) to `y` (on a surface of
    /// normal `ny`) is free, both ends lifted off their surfaces.
    fn visible(&self, x: Vec3, nx: Vec3, y: Vec3, ny: Vec3) -> bool {
        let off = self.bvh.ray_offset();
        let (from, to) = (x + nx * off, y + ny * off);
        let d = to - from;
        let dist = d.length();
        if dist <= 4.0 * off {
            return true;
        }
        !self
            .bvh
            .occluded(&Ray::new(from, d / dist), dist - 2.0 * off)
    }

    /// The coefficient of the link from receiver element `r` to `source` (an element id, or a
    /// cluster index tagged with [`CLUSTER`]).
    /// `round` keys the random stream: the estimate that decides a link and the one it keeps
    /// are independent, so that keeping a link because its points happened to agree (all in
    /// shadow, say) does not bias its coefficient.
    pub fn estimate(&self, r: u32, source: u32, round: u64) -> Estimate {
        let re = &self.elements[r as usize];
        let mut rng = stream(self.seed, r as u64, source as u64, 0x4c49_4e4b_0000 + round);
        let mut out = Estimate {
            lo: f32::INFINITY,
            ..Default::default()
        };
        let m = self.rays.max(1);
        let mut sum = 0.0f64;
        let (mut blocked, mut free) = (false, false);
        let jitter: [f32; 8] = std::array::from_fn(|_| uniform(&mut rng));
        for x in re.receiver_points(jitter) {
            let mut vis = [0u32; 2];
            let f = if source & CLUSTER == 0 {
                self.from_element(x, re.normal, &self.elements[source as usize], m, &mut rng, &mut vis)
            } else {
                self.from_cluster(x, re.normal, source & !CLUSTER, m, &mut rng, &mut vis)
            };
            out.rays += vis[0] + vis[1];
            blocked |= vis[1] > 0;
            free |= vis[0] > 0;
            sum += f;
            out.hi = out.hi.max(f as f32);
            out.lo = out.lo.min(f as f32);
        }
        out.k = (sum / 4.0) as f32;
        out.partial = blocked && free;
        out
    }

    fn from_element(
        &self,
        x: Vec3,
        n: Vec3,
        s: &Element,
        m: u32,
        rng: &mut Rng64,
        vis: &mut [u32; 2],
    ) -> f64 {
        let f = point_polygon(x, n, s.polygon(), s.normal);
        if f <= 0.0 {
            return 0.0;
        }
        // Visibility over the part of the source in front of x (the part the analytic factor
        // counts), each ray weighted by the kernel cos θ cos θ' / r² at its end point, so that
        // the fraction seen is the kernel's, not the area's (the two differ where the near
        // part of a source is hidden and the far part is not). Points behind x's plane are
        // drawn again, up to 8 m draws.
        let (mut seen, mut total, mut valid) = (0.0f64, 0.0f64, 0u32);
        for _ in 0..8 * m {
            if valid == m {
                break;
            }
            let y = s.sample(uniform(rng), uniform(rng), uniform(rng));
            let d = y - x;
            let d2 = d.length_squared() as f64;
            let w = n.dot(d) as f64 * -(s.normal.dot(d) as f64) / (d2 * d2);
            if !(w > 0.0) {
                continue;
            }
            valid += 1;
            total += w;
            if self.visible(x, n, y, s.normal) {
                seen += w;
                vis[0] += 1;
            } else {
                vis[1] += 1;
            }
        }
        if valid == 0 {
            // A sliver in front: too thin to hit; its factor is tiny, take it as seen.
            return f;
        }
        f * seen / total
    }

    fn from_cluster(
        &self,
        x: Vec3,
        n: Vec3,
        c: u32,
        m: u32,
        rng: &mut Rng64,
        vis: &mut [u32; 2],
    ) -> f64 {
        let area = self.clusters.nodes[c as usize].area;
        let mut sum = 0.0;
        for _ in 0..m {
            let root = &self.elements[self.clusters.pick(c, uniform(rng) as f64) as usize];
            let y = root.sample(uniform(rng), uniform(rng), uniform(rng));
            let d = y - x;
            let d2 = d.length_squared();
            if d2 <= 0.0 {
                continue;
            }
            let (cr, cs) = (n.dot(d), -root.normal.dot(d));
            if cr <= 0.0 || cs <= 0.0 {
                continue;
            }
            if self.visible(x, n, y, root.normal) {
                sum += (cr as f64 * cs as f64) / (PI * d2 as f64 * d2 as f64);
                vis[0] += 1;
            } else {
                vis[1] += 1;
            }
        }
        area * sum / m as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::formfactor::closed_form;

    #[test]
    fn point_to_polygon_matches_closed_forms() {
        // A point on the axis of a parallel square: four corner rectangles of Howell's B-3.
        let h = 0.7f32;
        let square = [
            Vec3::new(-1.0, h, -1.0),
            Vec3::new(-1.0, h, 1.0),
            Vec3::new(1.0, h, 1.0),
            Vec3::new(1.0, h, -1.0),
        ];
        let f = point_polygon(Vec3::ZERO, Vec3::Y, &square, -Vec3::Y);
        let quarter = closed_form::point_parallel_rectangle(1.0, 1.0, h as f64);
        assert!((f - 4.0 * quarter).abs() < 1e-6, "{f} vs {}", 4.0 * quarter);
        // Behind the source: nothing; a source half behind the receiver's plane: clipped.
        assert_eq!(point_polygon(Vec3::Y * 2.0, Vec3::Y, &square, -Vec3::Y), 0.0);
        let tilted = [
            Vec3::new(1.0, -1.0, -1.0),
            Vec3::new(1.0, -1.0, 1.0),
            Vec3::new(1.0, 1.0, 1.0),
            Vec3::new(1.0, 1.0, -1.0),
        ];
        let half = point_polygon(Vec3::ZERO, Vec3::Y, &tilted, -Vec3::X);
        let upper = [
            Vec3::new(1.0, 0.0, -1.0),
            Vec3::new(1.0, 0.0, 1.0),
            Vec3::new(1.0, 1.0, 1.0),
            Vec3::new(1.0, 1.0, -1.0),
        ];
        let expect = point_polygon(Vec3::ZERO, Vec3::Y, &upper, -Vec3::X);
        assert!((half - expect).abs() < 1e-12 && half > 0.0);
        // The clipped half against a midpoint rule over it (400 × 400 cells).
        let n = 400;
        let mut quad = 0.0;
        for i in 0..n {
            for j in 0..n {
                let (y, z) = ((i as f64 + 0.5) / n as f64, -1.0 + 2.0 * (j as f64 + 0.5) / n as f64);
                let r2 = 1.0 + y * y + z * z;
                quad += y * 1.0 / (PI * r2 * r2) * (2.0 / (n * n) as f64);
            }
        }
        assert!((half - quad).abs() < 1e-4, "{half} vs {quad}");
        // A closed cube around the point: the factors to the five faces in front sum to 1.
        let c = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
        let faces: [([Vec3; 4], Vec3); 5] = [
            ([c(-1., 1., -1.), c(-1., 1., 1.), c(1., 1., 1.), c(1., 1., -1.)], -Vec3::Y),
            ([c(1., -1., -1.), c(1., -1., 1.), c(1., 1., 1.), c(1., 1., -1.)], -Vec3::X),
            ([c(-1., -1., -1.), c(-1., 1., -1.), c(-1., 1., 1.), c(-1., -1., 1.)], Vec3::X),
            ([c(-1., -1., 1.), c(-1., 1., 1.), c(1., 1., 1.), c(1., -1., 1.)], -Vec3::Z),
            ([c(-1., -1., -1.), c(1., -1., -1.), c(1., 1., -1.), c(-1., 1., -1.)], Vec3::Z),
        ];
        let x = Vec3::new(0.2, -0.3, 0.1);
        let total: f64 = faces
            .iter()
            .map(|(p, ns)| {
                // Orient counter-clockwise about the inward normal.
                let mut p = *p;
                if crate::geom::triangle_cross(p[0], p[1], p[2]).dot(*ns) < 0.0 {
                    p.reverse();
                }
                point_polygon(x, Vec3::Y, &p, *ns)
            })
            .sum();
        assert!((total - 1.0).abs() < 1e-9, "{total}");
    }
}
