//! A default view for scenes that bring no camera: from inside, when the scene is an interior.
//!
//! Candidate eye points lie on a 12 × 12 grid across the scene's horizontal extent at eye height
//! (1.6 units above the lowest point, or 45 % of the height if that is less). From each, 32
//! horizontal rays (pitched 5° down) and 8 steep ones (4 up, 4 down) are cast. A candidate is
//! *inside* when at least 90 % of them hit a front face (an eye in the open, or inside a solid
//! object, sees background or back faces) and nothing is nearer than 2 % of the scene's width.
//! The inside candidate with the deepest view wins, looking along the 60° sector whose rays travel
//! furthest. Scenes with no inside candidate (single objects) are framed from outside.
//! Deterministic: no random numbers.

use crate::accel::Bvh;
use crate::geom::{Aabb, Ray, Vec3};
use crate::scene::Camera;

const GRID: usize = 12;
const AZIMUTHS: usize = 32;
/// Sector of azimuths (each 360°/32) whose depth is summed to choose the view direction.
const SECTOR: usize = 5;

/// Frame the bounds `b` from outside, looking down on them, with `up` as the vertical.
pub fn framing(b: &Aabb, up: Vec3) -> Camera {
    let up = up.normalize();
    let (e1, e2) = crate::geom::orthonormal_basis(up);
    let centre = b.centre();
    let radius = (b.diagonal() * 0.5).max(1e-3);
    let fov = 45.0f32;
    let dir = (e1 * 0.6 + e2 * 0.8 + up * 0.45).normalize();
    let dist = radius / (fov.to_radians() * 0.5).sin() * 1.05;
    Camera {
        eye: centre + dir * dist,
        target: centre,
        up,
        fov_y_deg: fov,
    }
}

/// A camera inside the scene if it is an interior (see the module docs), else [`framing`].
pub fn default_camera(bvh: &Bvh, up: Vec3) -> Camera {
    let b = bvh.bounds();
    interior(bvh, &b, up.normalize()).unwrap_or_else(|| framing(&b, up))
}

fn interior(bvh: &Bvh, b: &Aabb, up: Vec3) -> Option<Camera> {
    let (e1, e2) = crate::geom::orthonormal_basis(up);
    let corners = (0..8).map(|k| {
        Vec3::new(
            if k & 1 == 0 { b.min.x } else { b.max.x },
            if k & 2 == 0 { b.min.y } else { b.max.y },
            if k & 4 == 0 { b.min.z } else { b.max.z },
        )
    });
    let (mut lo, mut hi) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
    for c in corners {
        let p = Vec3::new(c.dot(e1), c.dot(e2), c.dot(up));
        lo = lo.min(p);
        hi = hi.max(p);
    }
    let ext = hi - lo;
    let width = ext.x.max(ext.y);
    if width <= 0.0 || ext.z <= 0.0 {
        return None;
    }
    let height = lo.z + 1.6f32.min(0.45 * ext.z);
    let near = 0.02 * width;
    let far = 4.0 * b.diagonal();
    let pitch = (-5.0f32).to_radians();
    let dirs: Vec<Vec3> = (0..AZIMUTHS)
        .map(|k| {
            let a = std::f32::consts::TAU * k as f32 / AZIMUTHS as f32;
            (e1 * a.cos() + e2 * a.sin()) * pitch.cos() + up * pitch.sin()
        })
        .collect();
    let steep: Vec<Vec3> = (0..8)
        .map(|k| {
            let a = std::f32::consts::TAU * k as f32 / 4.0;
            let s = if k < 4 { 1.0 } else { -1.0 };
            ((e1 * a.cos() + e2 * a.sin()) * 0.3 + up * s).normalize()
        })
        .collect();
    let mut best: Option<(f32, Vec3, usize)> = None;
    let mut depth = [0f32; AZIMUTHS];
    for i in 0..GRID {
        for j in 0..GRID {
            let u = lo.x + ext.x * (i as f32 + 0.5) / GRID as f32;
            let v = lo.y + ext.y * (j as f32 + 0.5) / GRID as f32;
            let eye = e1 * u + e2 * v + up * height;
            let (mut front, mut total) = (0, 0);
            let mut blocked = false;
            for (k, d) in dirs.iter().chain(&steep).enumerate() {
                total += 1;
                match bvh.closest_hit(&Ray::new(eye, *d), far) {
                    Some(h) if h.front => {
                        front += 1;
                        blocked |= h.t < near;
                        if k < AZIMUTHS {
                            depth[k] = h.t;
                        }
                    }
                    _ => {
                        if k < AZIMUTHS {
                            depth[k] = 0.0;
                        }
                    }
                }
            }
            if blocked || (front as f32) < 0.9 * total as f32 {
                continue;
            }
            // The sector with the deepest view, and its depth.
            let (k, score) = (0..AZIMUTHS)
                .map(|k| {
                    let s: f32 = (0..SECTOR)
                        .map(|m| depth[(k + m + AZIMUTHS - SECTOR / 2) % AZIMUTHS])
                        .sum();
                    (k, s)
                })
                .fold((0, f32::MIN), |a, c| if c.1 > a.1 { c } else { a });
            if best.is_none_or(|(s, _, _)| score > s) {
                best = Some((score, eye, k));
            }
        }
    }
    let (score, eye, k) = best?;
    let look = dirs[k] * (score / SECTOR as f32 * 0.5).max(near);
    Some(Camera {
        eye,
        target: eye + look - up * (0.1 * look.length()),
        up,
        fov_y_deg: 60.0,
    })
}
