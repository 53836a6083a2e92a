//! Panes in the interreflection against independent computations: a large pane between two
//! parallel walls passes τ_d and returns ρ_d of a wall's diffuse light (the Gauss–Legendre
//! averages of the Fresnel model) with the books closed, and a box split by a pane, lit on
//! one side, against its radiosity equations solved with form factors by quadrature.

use super::*;
use crate::color::Rgb;
use crate::lighting::glazing::GLASS_INDEX;
use crate::lighting::sky::{gauss_legendre, Sky, SkyModel, SunPosition};
use crate::lighting::SensorPoint;
use crate::observe::Silent;
use crate::pipeline::{daylight, DaylightSettings, LightingSettings};
use crate::scene::{Material, Polygon};
use glam::DVec3;
use std::f64::consts::PI;

/// A scene of `(vertices, material)` polygons over `materials`.
fn scene_of(materials: Vec<Material>, polys: Vec<(Vec<Vec3>, usize)>) -> Scene {
    Scene {
        name: "panes".into(),
        materials,
        polygons: polys
            .into_iter()
            .map(|(vertices, material)| Polygon {
                vertices,
                material,
                line: 0,
                group: 0,
            })
            .collect(),
        ..Scene::default()
    }
}

fn glass(t: f64) -> Material {
    let mut g = Material::diffuse("glass", Rgb::BLACK);
    g.transmittance = t;
    g
}

/// An axis-aligned rectangle on the plane `axis = at`, spanning `[a0, a1] × [b0, b1]` in the
/// other two axes (in order y, z for x; x, z for y; x, y for z), facing `+axis` when `up`.
fn rect(axis: usize, at: f32, [a0, a1, b0, b1]: [f32; 4], up: bool) -> Vec<Vec3> {
    let p = |a: f32, b: f32| match axis {
        0 => Vec3::new(at, a, b),
        1 => Vec3::new(a, at, b),
        _ => Vec3::new(a, b, at),
    };
    // (a, b) counter-clockwise: normal +axis for x and z, −y for y (y's pair is x, z).
    let mut v = vec![p(a0, b0), p(a1, b0), p(a1, b1), p(a0, b1)];
    if up != (axis != 1) {
        v.reverse();
    }
    v
}

/// The opaque scene's mesh (one patch a polygon), its hierarchy, and the panes.
fn split(scene: &Scene) -> (Scene, Mesh, Bvh, Panes) {
    let glazing: Vec<Option<Glazing>> = scene
        .materials
        .iter()
        .map(|m| {
            (m.transmittance > 0.0).then(|| Glazing::new(m.transmittance, GLASS_INDEX).unwrap())
        })
        .collect();
    let mut opaque = scene.clone();
    opaque.polygons.retain(|p| glazing[p.material].is_none());
    let panes = Panes::new(scene, glazing).unwrap().unwrap();
    let mesh = Mesh::build(&opaque, MeshParams::Faces).unwrap();
    let bvh = Bvh::build(&mesh);
    (opaque, mesh, bvh, panes)
}

/// A closed slab 0.1 thick and 10 × 10 wide, a pane across its middle (x = 0.05): of the
/// light leaving the centre of one wall, the other side receives τ_d, its own side ρ_d
/// (mirrored, itself included) and the pane absorbs 1 − τ_d − ρ_d, within 4σ of the rows'
/// Monte Carlo (σ ≤ √(F(1 − F)/n) for weights in [0, 1]) plus 1e-4 for the rays that reach
/// the slab's rim (θ > 89.4°, cosine share sin² 0.6°); every row's books close,
/// Σ_j F_ij + absorbed_i = 1.
#[test]
fn a_pane_passes_tau_d_and_returns_rho_d_of_diffuse_light() {
    let tau_n = 0.8;
    let wall = Material::diffuse("wall", Rgb::splat(0.5));
    let mut polys = Vec::new();
    for (x, up) in [(0.0f32, true), (0.1, false)] {
        polys.push((rect(0, x, [4.5, 5.5, 4.5, 5.5], up), 0));
        for r in [
            [0.0, 4.5, 0.0, 10.0],
            [5.5, 10.0, 0.0, 10.0],
            [4.5, 5.5, 0.0, 4.5],
            [4.5, 5.5, 5.5, 10.0],
        ] {
            polys.push((rect(0, x, r, up), 0));
        }
    }
    for half in [[0.0f32, 0.05], [0.05, 0.1]] {
        for (axis, at, up) in [
            (1, 0.0f32, true),
            (1, 10.0, false),
            (2, 0.0, true),
            (2, 10.0, false),
        ] {
            polys.push((rect(axis, at, [half[0], half[1], 0.0, 10.0], up), 0));
        }
    }
    polys.push((rect(0, 0.05, [0.0, 10.0, 0.0, 10.0], true), 1));
    let scene = scene_of(vec![wall, glass(tau_n)], polys);
    let (_, mesh, bvh, panes) = split(&scene);
    let n = 400_000u32;
    let memory = MemoryCheck {
        limit: u64::MAX,
        stored_rows: true,
        rays: n,
    };
    let (f, absorbed) = panes.rows(&mesh, &bvh, n, 7, &memory, &Silent).unwrap();
    let g = Glazing::new(tau_n, GLASS_INDEX).unwrap();
    let (td, rd) = (g.diffuse(), g.diffuse_reflectance());
    for i in 0..mesh.len() {
        let sum: f64 = f.row_entries(i).iter().map(|&(_, v)| v as f64).sum();
        assert!(
            (sum + absorbed[i] - 1.0).abs() < 1e-4,
            "row {i}: {sum} + {}",
            absorbed[i]
        );
    }
    // The centre of the x = 0 wall is patch 0; the far side's patches have centres x > 0.05.
    let (mut far, mut near) = (0.0, 0.0);
    for &(j, v) in f.row_entries(0) {
        if mesh.patches[j as usize].centre.x > 0.05 {
            far += v as f64;
        } else {
            near += v as f64;
        }
    }
    let sigma = |p: f64| (p * (1.0 - p) / n as f64).sqrt();
    assert!(
        (far - td).abs() < 4.0 * sigma(td) + 1e-4,
        "τ: {far} against τ_d {td}"
    );
    assert!(
        (near - rd).abs() < 4.0 * sigma(rd) + 1e-4,
        "ρ: {near} against ρ_d {rd}"
    );
    let a = 1.0 - td - rd;
    assert!(
        (absorbed[0] - a).abs() < 4.0 * sigma(a) + 2e-4,
        "{} against {a}",
        absorbed[0]
    );
    assert!(a > 0.05, "a pane of τ_n 0.8 absorbs: {a}");
}

/// A rectangle for quadrature: a corner, two edges, its unit normal.
#[derive(Clone, Copy)]
struct Quad {
    o: DVec3,
    u: DVec3,
    v: DVec3,
    n: DVec3,
}

impl Quad {
    /// Mirrored in the plane x = `x`.
    fn mirror(self, x: f64) -> Quad {
        let m = |p: DVec3| DVec3::new(2.0 * x - p.x, p.y, p.z);
        let d = |p: DVec3| DVec3::new(-p.x, p.y, p.z);
        Quad {
            o: m(self.o),
            u: d(self.u),
            v: d(self.v),
            n: d(self.n),
        }
    }
}

/// (1/π) ∫_q w(d) cos θ cos θ' / r² dA from `x` facing `n`: the illuminance at x per unit
/// radiosity of q along paths weighted by `w` (Gauss–Legendre, 24 × 24).
fn cf(x: DVec3, n: DVec3, q: Quad, w: &dyn Fn(DVec3) -> f64) -> f64 {
    let gl = gauss_legendre(24);
    let area = q.u.cross(q.v).length();
    let mut s = 0.0;
    for &(a, wa) in &gl {
        for &(b, wb) in &gl {
            let y = q.o + q.u * (0.5 * (a + 1.0)) + q.v * (0.5 * (b + 1.0));
            let r = y - x;
            let d2 = r.length_squared();
            let d = r / d2.sqrt();
            let c = n.dot(d).max(0.0) * (-q.n.dot(d)).max(0.0);
            s += 0.25 * wa * wb * c / d2 * w(d);
        }
    }
    s * area / PI
}

/// F from `a` to `b` along weighted paths: `cf` averaged over a (Gauss–Legendre, 12 × 12).
fn ff(a: Quad, b: Quad, w: &dyn Fn(DVec3) -> f64) -> f64 {
    let gl = gauss_legendre(12);
    let mut s = 0.0;
    for &(p, wp) in &gl {
        for &(q, wq) in &gl {
            let x = a.o + a.u * (0.5 * (p + 1.0)) + a.v * (0.5 * (q + 1.0));
            s += 0.25 * wp * wq * cf(x, a.n, b, w);
        }
    }
    s
}

/// A 1.5 × 1 × 1 box split by a pane at x = 1. The sun at the zenith comes through a hole in
/// the left half's roof onto a grey square of the floor below it; the right half's far wall
/// (x = 1.5) is grey, all else black. The square's radiosity crosses the pane to the wall
/// (F through the pane), and at two sensors of the right half the illuminance is the square
/// through the pane, the wall, and the wall mirrored in the pane. The reference solves
/// B_f = ρ_f (E_n + F_fw B_w), B_w = ρ_w (F_wf B_f + F_ww B_w) with every F and sensor term a
/// Gauss–Legendre quadrature of the pane-weighted kernel (τ(θ) across, R(θ) mirrored, θ
/// from the pane's normal x). Tolerance: 4σ of the wall row's Monte Carlo F_wf carried into
/// the wall's term, plus 1e-3 for the sensors' stratified gather (2²⁰ rays; measured
/// agreement 1.6e-4 and 2.9e-4).
#[test]
fn light_crosses_a_pane_both_ways_in_the_interreflection() {
    let (rho_f, rho_w, tau_n, en) = (0.6, 0.6, 0.8, 1000.0);
    let sq = [0.2f32, 0.8, 0.2, 0.8];
    let mut polys = vec![
        (rect(2, 0.0, sq, true), 1),
        (rect(2, 0.0, [0.0, 0.2, 0.0, 1.0], true), 0),
        (rect(2, 0.0, [0.8, 1.5, 0.0, 1.0], true), 0),
        (rect(2, 0.0, [0.2, 0.8, 0.0, 0.2], true), 0),
        (rect(2, 0.0, [0.2, 0.8, 0.8, 1.0], true), 0),
        // The ceiling round the hole, and over the right half.
        (rect(2, 1.0, [0.0, 0.2, 0.0, 1.0], false), 0),
        (rect(2, 1.0, [0.8, 1.5, 0.0, 1.0], false), 0),
        (rect(2, 1.0, [0.2, 0.8, 0.0, 0.2], false), 0),
        (rect(2, 1.0, [0.2, 0.8, 0.8, 1.0], false), 0),
        (rect(0, 0.0, [0.0, 1.0, 0.0, 1.0], true), 0),
        (rect(0, 1.5, [0.0, 1.0, 0.0, 1.0], false), 2),
        (rect(0, 1.0, [0.0, 1.0, 0.0, 1.0], true), 3),
    ];
    for half in [[0.0f32, 1.0], [1.0, 1.5]] {
        polys.push((rect(1, 0.0, [half[0], half[1], 0.0, 1.0], true), 0));
        polys.push((rect(1, 1.0, [half[0], half[1], 0.0, 1.0], false), 0));
    }
    let scene = scene_of(
        vec![
            Material::diffuse("black", Rgb::BLACK),
            Material::diffuse("floor", Rgb::splat(rho_f)),
            Material::diffuse("wall", Rgb::splat(rho_w)),
            glass(tau_n),
        ],
        polys,
    );
    let rays = 400_000u32;
    let mut ls = LightingSettings {
        mesh: MeshParams::Faces,
        ..LightingSettings::default()
    };
    ls.form_factors.rays = rays;
    ls.params.tolerance = 1e-10;
    let settings = DaylightSettings {
        lighting: ls,
        point_rays: 1 << 20,
        ground_reflectance: 0.0,
        ..DaylightSettings::default()
    };
    let sensors = [
        (DVec3::new(1.49, 0.5, 0.5), DVec3::new(-1.0, 0.0, 0.0)),
        (DVec3::new(1.25, 0.5, 0.99), DVec3::new(0.0, 0.0, -1.0)),
    ];
    let points: Vec<SensorPoint> = sensors
        .iter()
        .map(|(p, n)| SensorPoint::new(p.to_array(), n.to_array()).unwrap())
        .collect();
    let dark = Sky::new(SkyModel::Uniform, None, 0.0).unwrap();
    let sun = SunPosition::new(90.0, 0.0).unwrap();
    let r = daylight(&scene, &points, &dark, Some((sun, en)), &settings, &Silent).unwrap();
    assert!(r.converged);

    // The reference.
    let g = Glazing::new(tau_n, GLASS_INDEX).unwrap();
    let tau = |d: DVec3| g.transmittance(d.x.abs());
    let refl = |d: DVec3| g.reflectance(d.x.abs());
    let one = |_: DVec3| 1.0;
    let x = DVec3::X;
    let floor = Quad {
        o: DVec3::new(0.2, 0.2, 0.0),
        u: DVec3::new(0.6, 0.0, 0.0),
        v: DVec3::new(0.0, 0.6, 0.0),
        n: DVec3::Z,
    };
    let wall = Quad {
        o: DVec3::new(1.5, 0.0, 0.0),
        u: DVec3::new(0.0, 1.0, 0.0),
        v: DVec3::new(0.0, 0.0, 1.0),
        n: -x,
    };
    let image = wall.mirror(1.0);
    let f_fw = ff(floor, wall, &tau);
    let f_wf = ff(wall, floor, &tau);
    let f_ww = ff(wall, image, &refl);
    // Reciprocity of the pane-weighted kernel, a check of the quadrature itself.
    assert!((0.36 * f_fw - f_wf).abs() < 1e-9 * f_wf, "{f_fw} {f_wf}");
    // B_f = ρ_f (E_n + F_fw B_w), B_w = ρ_w F_wf B_f / (1 − ρ_w F_ww).
    let k = rho_w * f_wf / (1.0 - rho_w * f_ww);
    let b_f = rho_f * en / (1.0 - rho_f * f_fw * k);
    let b_w = k * b_f;
    let sigma_rel = ((1.0 - f_wf) / (f_wf * rays as f64)).sqrt();
    for (i, &(p, n)) in sensors.iter().enumerate() {
        let from_floor = b_f * cf(p, n, floor, &tau);
        let from_wall = b_w * (cf(p, n, wall, &one) + cf(p, n, image, &refl));
        let want = from_floor + from_wall;
        let got = r.total[i];
        let tol = 4.0 * sigma_rel * from_wall + 1e-3 * want;
        assert!(
            (got - want).abs() < tol,
            "sensor {i}: {got} against {want} (floor {from_floor}, wall {from_wall}; tolerance {tol})"
        );
        // The wall's light is more than the tolerance's Monte Carlo part: the test sees F.
        assert!(
            from_wall > 1e-3 * want,
            "sensor {i} sees the wall's light: {from_wall}"
        );
    }
}

/// One hierarchy over the walls and the panes ([`Panes::join`]) follows every ray as the two
/// apart do: 20,000 rays from random points in random directions in a closed box holding two
/// free panes (none touching a wall, so no hit ties between a pane and a wall), every branch's
/// end and weight the same, bit for bit, and the absorbed weight too.
#[test]
fn a_joined_hierarchy_follows_every_branch_as_the_two_apart() {
    let mut polys = vec![
        (rect(0, 0.0, [0.0, 1.0, 0.0, 1.0], true), 0),
        (rect(0, 1.5, [0.0, 1.0, 0.0, 1.0], false), 0),
        (rect(1, 0.0, [0.0, 1.5, 0.0, 1.0], true), 0),
        (rect(1, 1.0, [0.0, 1.5, 0.0, 1.0], false), 0),
        (rect(2, 0.0, [0.0, 1.5, 0.0, 1.0], true), 0),
        (rect(2, 1.0, [0.0, 1.5, 0.0, 1.0], false), 0),
        (rect(0, 0.75, [0.2, 0.8, 0.2, 0.8], true), 1),
    ];
    let tilted = vec![
        Vec3::new(0.3, 0.1, 0.3),
        Vec3::new(0.5, 0.1, 0.7),
        Vec3::new(0.5, 0.9, 0.7),
        Vec3::new(0.3, 0.9, 0.3),
    ];
    polys.push((tilted, 2));
    let scene = scene_of(
        vec![
            Material::diffuse("wall", Rgb::splat(0.5)),
            glass(0.8),
            glass(0.6),
        ],
        polys,
    );
    let (_, mesh, bvh, apart) = split(&scene);
    let (_, _, _, mut joined) = split(&scene);
    joined.join(&mesh);
    let mut rng = crate::sampling::stream(21, 0, 0, 0);
    let mut u = || crate::sampling::uniform(&mut rng);
    let (mut branches, mut crossed) = (0usize, 0usize);
    for _ in 0..20_000 {
        let o = Vec3::new(0.05 + 1.4 * u(), 0.05 + 0.9 * u(), 0.05 + 0.9 * u());
        let d = Vec3::new(u() - 0.5, u() - 0.5, u() - 0.5).normalize_or_zero();
        if d == Vec3::ZERO {
            continue;
        }
        let mut a = Vec::new();
        let mut b = Vec::new();
        let lost_a = apart.follow(&bvh, o, d, &mut |e, w| a.push((e, w)));
        let lost_b = joined.follow(&bvh, o, d, &mut |e, w| b.push((e, w)));
        assert_eq!(a, b, "from {o} along {d}");
        assert_eq!(lost_a, lost_b);
        branches += a.len();
        crossed += (a.len() > 1) as usize;
    }
    // Many rays meet a pane and branch.
    assert!(crossed > 2_000 && branches > 22_000, "{crossed} {branches}");
}
