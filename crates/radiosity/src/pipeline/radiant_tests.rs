//! Radiant temperatures against closed forms: solid angles of polygons (Van Oosterom &
//! Strackee 1983) and point-to-polygon view factors (Lambert's contour formula), computed here
//! independently of the ray casting under test.

use super::*;
use crate::color::Rgb;
use crate::mesh::MeshParams;
use crate::scene::{Material, Polygon, Scene};
use glam::DVec3;

/// A closed box `sx × sy × sz` seen from inside, one material per face.
fn closed_box(s: [f32; 3]) -> Scene {
    let faces = [
        [[0., 0., 0.], [0., 0., 1.], [1., 0., 1.], [1., 0., 0.]],
        [[0., 1., 0.], [1., 1., 0.], [1., 1., 1.], [0., 1., 1.]],
        [[0., 0., 0.], [1., 0., 0.], [1., 1., 0.], [0., 1., 0.]],
        [[0., 0., 1.], [0., 1., 1.], [1., 1., 1.], [1., 0., 1.]],
        [[0., 0., 0.], [0., 1., 0.], [0., 1., 1.], [0., 0., 1.]],
        [[1., 0., 0.], [1., 0., 1.], [1., 1., 1.], [1., 1., 0.]],
    ];
    Scene {
        name: "box".into(),
        materials: (0..6)
            .map(|k| Material::diffuse(&format!("face{k}"), Rgb::new(0.0, 0.0, 0.0)))
            .collect(),
        polygons: (0..6)
            .map(|k| Polygon {
                vertices: faces[k]
                    .iter()
                    .map(|p| Vec3::new(p[0] * s[0], p[1] * s[1], p[2] * s[2]))
                    .collect(),
                material: k,
                line: 0,
                group: 0,
            })
            .collect(),
        ..Scene::default()
    }
}

fn corners(p: &Polygon) -> Vec<DVec3> {
    p.vertices.iter().map(|v| v.as_dvec3()).collect()
}

/// The solid angle of a convex polygon seen from `x`, by fanning it into triangles, each by
/// Van Oosterom & Strackee's formula tan(Ω/2) = |a·(b×c)| / (abc + (a·b)c + (a·c)b + (b·c)a).
fn solid_angle(x: DVec3, poly: &[DVec3]) -> f64 {
    let mut omega = 0.0;
    for k in 1..poly.len() - 1 {
        let (a, b, c) = (poly[0] - x, poly[k] - x, poly[k + 1] - x);
        let (la, lb, lc) = (a.length(), b.length(), c.length());
        let num = a.dot(b.cross(c)).abs();
        let den = la * lb * lc + a.dot(b) * lc + a.dot(c) * lb + b.dot(c) * la;
        omega += 2.0 * num.atan2(den);
    }
    omega
}

/// The view factor from a differential area at `x` with unit normal `n` to a polygon wholly
/// in front of it (Lambert): F = (1/2π) Σ_edges γ_k n · (r_k × r_k+1)/|r_k × r_k+1|.
fn point_factor(x: DVec3, n: DVec3, poly: &[DVec3]) -> f64 {
    let mut f = 0.0;
    for k in 0..poly.len() {
        let (a, b) = (poly[k] - x, poly[(k + 1) % poly.len()] - x);
        let c = a.cross(b);
        let gamma = a.angle_between(b);
        f += gamma * n.dot(c.normalize());
    }
    (f / (2.0 * std::f64::consts::PI)).abs()
}

/// Black walls: J = σT⁴, and T_mr⁴ = Σ (Ω_i/4π) T_i⁴, T_pr⁴ = Σ F_i T_i⁴, nothing open. The
/// stratified estimate errs only in the cells an edge of the box crosses: about 3·√n of the n
/// cells for a box's 12 edges, each misattributing at most the whole spread of T⁴ with a
/// random sign, so the error's standard deviation is below √(3√n)/n of the spread (0.12 % at
/// 4,096 rays); the bound is 4 of those.
#[test]
fn black_box_mean_and_plane_radiant_temperatures_match_solid_angles() {
    let scene = closed_box([4.0, 3.0, 2.5]);
    let mesh = crate::mesh::Mesh::build(&scene, MeshParams::Faces).unwrap();
    let bvh = Bvh::build(&mesh);
    let temps = [290.0, 300.0, 320.0, 340.0, 360.0, 400.0];
    let t4 = |k: usize| f64::powi(temps[k], 4);
    let j: Vec<f64> = mesh
        .patches
        .iter()
        .map(|p| STEFAN_BOLTZMANN * t4(p.material as usize))
        .collect();
    let points = [
        ([2.0, 1.5, 1.25], [0.0, 0.0, 1.0]),
        ([0.5, 0.4, 1.1], [1.0, 0.0, 0.0]),
        ([3.6, 2.7, 0.3], [0.0, -0.6, 0.8]),
        ([1.0, 2.0, 2.2], [0.0, 0.0, -1.0]),
    ];
    let sensors: Vec<SensorPoint> = points
        .iter()
        .map(|&(position, normal)| SensorPoint { position, normal })
        .collect();
    let params = RadiantParams {
        rays: 4096,
        seed: 3,
    };
    let r = radiant_temperatures(&mesh, &bvh, &j, 0.0, &sensors, params).unwrap();
    let spread = t4(5) - t4(0);
    let bound = 4.0 * (3.0 * 64.0f64).sqrt() / 4096.0 * spread;
    for (s, got) in sensors.iter().zip(&r.points) {
        let x = DVec3::from_array(s.position);
        let n = DVec3::from_array(s.normal).normalize();
        let (mut mean, mut plane, mut omega) = (0.0, 0.0, 0.0);
        for (k, poly) in scene.polygons.iter().enumerate() {
            let c = corners(poly);
            let o = solid_angle(x, &c);
            omega += o;
            mean += o / (4.0 * std::f64::consts::PI) * t4(k);
            // The part of a face behind the sensor's plane does not count: clip it.
            plane += clipped_factor(x, n, &c) * t4(k);
        }
        assert!(
            (omega - 4.0 * std::f64::consts::PI).abs() < 1e-9,
            "closed: {omega}"
        );
        let got_mean = got.mean_radiant_temperature.powi(4);
        let got_plane = got.plane_radiant_temperature.powi(4);
        assert!(
            (got_mean - mean).abs() < bound,
            "T_mr⁴ {got_mean:.6e} vs {mean:.6e} (bound {bound:.2e})"
        );
        assert!(
            (got_plane - plane).abs() < bound,
            "T_pr⁴ {got_plane:.6e} vs {plane:.6e} (bound {bound:.2e})"
        );
        assert_eq!(got.sky_view, 0.0);
    }
    assert_eq!(r.back_hits, 0);
}

/// [`point_factor`] of the part of a convex polygon in front of the plane through `x` with
/// normal `n` (Sutherland–Hodgman against that one plane).
fn clipped_factor(x: DVec3, n: DVec3, poly: &[DVec3]) -> f64 {
    let side = |p: DVec3| (p - x).dot(n);
    let mut out = Vec::new();
    for k in 0..poly.len() {
        let (a, b) = (poly[k], poly[(k + 1) % poly.len()]);
        let (da, db) = (side(a), side(b));
        if da >= 0.0 {
            out.push(a);
        }
        if (da >= 0.0) != (db >= 0.0) {
            out.push(a + (b - a) * (da / (da - db)));
        }
    }
    if out.len() < 3 {
        0.0
    } else {
        point_factor(x, n, &out)
    }
}

/// A point on open ground sees the sky over its upper half and the ground below: sky view
/// one half, and the surroundings' temperature fills the sky.
#[test]
fn open_ground_sees_half_sky() {
    let g = 1000.0;
    let scene = Scene {
        name: "ground".into(),
        materials: vec![Material::diffuse("ground", Rgb::new(0.0, 0.0, 0.0))],
        polygons: vec![Polygon {
            vertices: vec![
                Vec3::new(-g, -g, 0.0),
                Vec3::new(g, -g, 0.0),
                Vec3::new(g, g, 0.0),
                Vec3::new(-g, g, 0.0),
            ],
            material: 0,
            line: 0,
            group: 0,
        }],
        ..Scene::default()
    };
    let mesh = crate::mesh::Mesh::build(&scene, MeshParams::Faces).unwrap();
    let bvh = Bvh::build(&mesh);
    let (tg, te) = (310.0f64, 250.0f64);
    let j = vec![STEFAN_BOLTZMANN * tg.powi(4); mesh.len()];
    let sensors = [
        SensorPoint {
            position: [3.0, -2.0, 0.0],
            normal: [0.0, 0.0, 1.0],
        },
        SensorPoint {
            position: [0.0, 0.0, 1.5],
            normal: [1.0, 0.0, 0.0],
        },
    ];
    let r = radiant_temperatures(&mesh, &bvh, &j, te, &sensors, RadiantParams::default()).unwrap();
    // On the ground (the sphere's cells meet at the horizon: exact), and 1.5 m above a
    // ground of half-width 1000 m (it misses a band below the horizon of solid angle
    // 2π·1.5/1000 at most: 1.5e-3 of the sphere... halved by symmetry of the estimate).
    for (p, tol) in r.points.iter().zip([1e-12, 1.5e-3]) {
        assert!((p.sky_view - 0.5).abs() <= tol, "sky view {}", p.sky_view);
        let want = (0.5 * (tg.powi(4) + te.powi(4))).powf(0.25);
        assert!(
            (p.mean_radiant_temperature - want).abs() < 0.01 * (tg - te),
            "{} vs {want}",
            p.mean_radiant_temperature
        );
    }
    // The ground point's sensor faces the sky alone; the standing one faces a vertical
    // plane: half sky, half ground, as its T_pr⁴ says.
    assert!((r.points[0].plane_radiant_temperature - te).abs() < 1e-9);
    let half = (0.5 * (tg.powi(4) + te.powi(4))).powf(0.25);
    assert!((r.points[1].plane_radiant_temperature - half).abs() < 0.02 * (tg - te));
}

#[test]
fn bad_requests_are_refused() {
    let scene = closed_box([1.0, 1.0, 1.0]);
    let mesh = crate::mesh::Mesh::build(&scene, MeshParams::Faces).unwrap();
    let bvh = Bvh::build(&mesh);
    let j = vec![1.0; mesh.len()];
    let p = [SensorPoint {
        position: [0.5, 0.5, 0.5],
        normal: [0.0, 0.0, 1.0],
    }];
    let run = |j: &[f64], env: f64, rays: u32| {
        radiant_temperatures(&mesh, &bvh, j, env, &p, RadiantParams { rays, seed: 1 })
    };
    assert!(run(&j, 0.0, 0).is_err());
    assert!(run(&j, 0.0, MAX_RADIANT_RAYS + 1).is_err());
    assert!(run(&j[1..], 0.0, 64).is_err());
    assert!(run(&j, f64::NAN, 64).is_err());
    assert!(run(&vec![f64::INFINITY; mesh.len()], 0.0, 64).is_err());
    // A point inside the box looking out of it: every ray meets a wall's back.
    let outside = [SensorPoint {
        position: [2.0, 0.5, 0.5],
        normal: [0.0, 0.0, 1.0],
    }];
    let r = radiant_temperatures(&mesh, &bvh, &j, 0.0, &outside, RadiantParams::default()).unwrap();
    assert!(r.back_hits > 0);
    // Thread count: the same bits from one worker.
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let one = pool.install(|| run(&j, 0.0, 256).unwrap());
    assert_eq!(one, run(&j, 0.0, 256).unwrap());
}
