//! The first shot into the patches against closed forms: an isotropic source's flux onto a
//! rectangle is I Ω (the rectangle's solid angle), a cosine source's I₀ h² ∫ dA / r⁴ (the
//! differential form factor's integral); a shadow edge along patch edges halves it exactly.

use super::*;
use crate::geom::Vec3;
use crate::lighting::direct_illuminance;
use crate::lighting::tests::{ies, isotropic, parse, steps};
use crate::mesh::MeshParams;
use crate::scene::{Material, Polygon, Scene};
use crate::Rgb;

/// The solid angle of the rectangle [0, a] × [0, b] in a plane, seen from height h above its
/// corner (0, 0): atan(a b / (h √(h² + a² + b²))), odd in a and in b.
fn corner_solid_angle(a: f64, b: f64, h: f64) -> f64 {
    (a * b / (h * (h * h + a * a + b * b).sqrt())).atan()
}

/// ∫∫ over [0, a] × [0, b] of h² / (h² + x² + y²)² (π times the form factor from a
/// differential area at height h above the corner, parallel to the rectangle), odd in a and
/// in b: ½ [A/√(1+A²) atan(B/√(1+A²)) + B/√(1+B²) atan(A/√(1+B²))], A = a/h, B = b/h.
fn corner_cosine_integral(a: f64, b: f64, h: f64) -> f64 {
    let (x, y) = (a / h, b / h);
    let (sx, sy) = ((1.0 + x * x).sqrt(), (1.0 + y * y).sqrt());
    0.5 * (x / sx * (y / sx).atan() + y / sy * (x / sy).atan())
}

/// `f` over the rectangle [x0, x1] × [y0, y1] seen from above (px, py): the signed sum of
/// its four corner terms.
fn over_rectangle(
    f: impl Fn(f64, f64) -> f64,
    [x0, x1, y0, y1]: [f64; 4],
    px: f64,
    py: f64,
) -> f64 {
    f(x1 - px, y1 - py) - f(x0 - px, y1 - py) - f(x1 - px, y0 - py) + f(x0 - px, y0 - py)
}

/// A horizontal rectangle at z = 0 facing up, meshed with at most `edge` a side.
fn rectangle([x0, x1, y0, y1]: [f64; 4], edge: f32) -> (Scene, Mesh) {
    let v = |x: f64, y: f64| Vec3::new(x as f32, y as f32, 0.0);
    let scene = Scene::of_polygons(
        "floor",
        Material::diffuse("floor", Rgb::splat(0.5)),
        vec![vec![v(x0, y0), v(x1, y0), v(x1, y1), v(x0, y1)]],
    );
    let mesh = Mesh::build(&scene, MeshParams::MaxEdge(edge)).unwrap();
    (scene, mesh)
}

/// The flux onto `mesh`'s patches of surface `surface` (unit = 1 m).
fn flux_on(mesh: &Mesh, e: &DirectResult, surface: u32) -> f64 {
    mesh.patches
        .iter()
        .zip(&e.total)
        .filter(|(p, _)| p.surface == surface)
        .map(|(p, e)| p.area as f64 * e)
        .sum()
}

fn at(photometry: std::sync::Arc<crate::photometry::Photometry>, x: [f64; 3]) -> Luminaire {
    Luminaire::new("l", photometry, x, [0.0, 0.0, -1.0], None, 1.0, "").unwrap()
}

/// A 2 × 1.5 m rectangle as one patch, an isotropic 1,000 cd source above its middle, above a
/// corner, and off to the side and low: the flux is I Ω to rounding (the rule's solid angle
/// is exact), where the patch's centre alone gives 1.9 times it under the middle.
#[test]
fn an_isotropic_source_sends_a_rectangle_its_solid_angle() {
    let rect = [0.0, 2.0, 0.0, 1.5];
    let (_, mesh) = rectangle(rect, 10.0);
    assert_eq!(mesh.len(), 1);
    let i0 = 1000.0;
    for x in [
        [1.0, 0.75, 0.8],
        [0.0, 0.0, 1.5],
        [3.0, -0.5, 0.4],
        [1.0, 0.75, 25.0],
    ] {
        let l = at(isotropic(i0), x);
        let e = patch_illuminance(&mesh, std::slice::from_ref(&l), None, 1.0).unwrap();
        let omega = over_rectangle(|a, b| corner_solid_angle(a, b, x[2]), rect, x[0], x[1]);
        let want = i0 * omega;
        let got = flux_on(&mesh, &e, 0);
        assert!(
            (got - want).abs() < 1e-9 * want,
            "{x:?}: {got} lm, I Ω = {want} lm"
        );
    }
    // The midpoint rule under the middle: I A / h² = 4,688 lm against I Ω = 2,254 lm.
    let l = at(isotropic(i0), [1.0, 0.75, 0.8]);
    let centre = crate::lighting::SensorPoint::new([1.0, 0.75, 0.0], [0.0, 0.0, 1.0]).unwrap();
    let midpoint = 3.0
        * direct_illuminance(&[centre], &[l], None, 1.0)
            .unwrap()
            .total[0];
    let omega = over_rectangle(|a, b| corner_solid_angle(a, b, 0.8), rect, 1.0, 0.75);
    assert!((midpoint - 4687.5).abs() < 1e-9 && (i0 * omega - 2254.0).abs() < 1.0);
}

/// A cosine source I₀ cos γ (tabulated every 0.5°: the linear interpolation errs by at most
/// (Δ²/8) I₀ = 10⁻⁵ I₀) over the same rectangle, one patch: the flux is I₀ h² ∫ dA / r⁴, in
/// closed form. The rule leaves only the centroid rule's error for I over cells of at most
/// [`SPLIT_RATIO`] radian: about ½ |I''| × the cells' second moment ≤ (0.1²/8) I, 1.25 × 10⁻³;
/// measured 0.7, 1.7 and 5.4 × 10⁻⁴. Cells half as large at least halve the error (measured
/// 3.6 to 4.8 times less, the rule being of second order).
#[test]
fn a_cosine_source_sends_a_rectangle_its_form_factor_integral() {
    let i0 = 1000.0;
    let table = ies(&[0.0], &steps(0.0, 180.0, 0.5), |_, g| {
        if g <= 90.0 {
            (i0 * g.to_radians().cos()).max(0.0)
        } else {
            0.0
        }
    });
    let cosine = parse(&table, "cosine.ies");
    let rect = [0.0, 2.0, 0.0, 1.5];
    let (_, mesh) = rectangle(rect, 10.0);
    for x in [[1.0, 0.75, 0.8], [0.0, 0.0, 1.3], [2.5, 2.0, 0.6]] {
        let l = at(cosine.clone(), x);
        let want = i0 * over_rectangle(|a, b| corner_cosine_integral(a, b, x[2]), rect, x[0], x[1]);
        let lums = std::slice::from_ref(&l);
        let got = flux_on(
            &mesh,
            &patch_illuminance(&mesh, lums, None, 1.0).unwrap(),
            0,
        );
        let err = (got - want).abs() / want;
        assert!(
            err < 1.25e-3,
            "{x:?}: {got} lm, closed form {want} lm ({err:e})"
        );
        let fine = patch_illuminance_with(&mesh, lums, None, 1.0, 0.05, 6).unwrap();
        let fine_err = (flux_on(&mesh, &fine, 0) - want).abs() / want;
        assert!(fine_err < 0.5 * err + 2e-5, "{x:?}: {err:e} → {fine_err:e}");
    }
}

/// An opaque board at half height whose edge lies right under an isotropic source shades
/// exactly the half x < 0 of a 2 × 2 m floor meshed along x = 0: the floor gets I Ω / 2.
#[test]
fn a_shadow_along_patch_edges_is_exact() {
    let (h, i0) = (1.0, 1000.0);
    let v = |x: f64, y: f64, z: f64| Vec3::new(x as f32, y as f32, z as f32);
    let floor = vec![
        v(-1., -1., 0.),
        v(1., -1., 0.),
        v(1., 1., 0.),
        v(-1., 1., 0.),
    ];
    let board = vec![
        v(-3., -3., h / 2.),
        v(-3., 3., h / 2.),
        v(0., 3., h / 2.),
        v(0., -3., h / 2.),
    ];
    let polygon = |vertices| Polygon {
        vertices,
        material: 0,
        line: 0,
        group: 0,
    };
    let scene = Scene {
        name: "shade".into(),
        materials: vec![Material::diffuse("grey", Rgb::splat(0.5))],
        polygons: vec![polygon(floor), polygon(board)],
        ..Default::default()
    };
    let mesh = Mesh::build(&scene, MeshParams::MaxEdge(1.0)).unwrap();
    let bvh = Bvh::build(&mesh);
    let l = at(isotropic(i0), [0.0, 0.0, h]);
    let e = patch_illuminance(&mesh, std::slice::from_ref(&l), Some(&bvh), 1.0).unwrap();
    let want = 0.5 * i0 * 4.0 * corner_solid_angle(1.0, 1.0, h);
    let got = flux_on(&mesh, &e, 0);
    assert!(
        (got - want).abs() < 1e-6 * want,
        "{got} lm, I Ω / 2 = {want} lm"
    );
}
