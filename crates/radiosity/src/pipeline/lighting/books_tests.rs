//! The energy books against closed forms (a closed cube as an integrating sphere; a point
//! source over an open floor), and the arriving light of a black surface.

use super::tests::{cube, lamp};
use super::*;
use crate::scene::{Material, Polygon};
use std::f64::consts::PI;

/// An isotropic 1,000 cd source at the centre of a closed 4 m cube of ρ = 0.5, cut into
/// 20 × 20 patches a face: nothing escapes, so the flux emitted, 4π I, is absorbed, less what
/// is left unshot. The first shot integrates each patch's solid angle exactly, so the patches
/// book 4π I to rounding (the `f32` vertices: 10⁻⁶); the rays cast from the source all reach
/// a front face, and the interreflection's shots too, but for the rare ray that slips through
/// an edge of the cube in `f32` (a 10⁻³ allowance).
#[test]
fn a_closed_cube_absorbs_what_it_emits() {
    let (s, rho, i0) = (4.0, 0.5, 1000.0);
    let scene = cube(s as f32, rho);
    let lum = lamp("lamp", i0, [s / 2.0; 3], 1.0, "default");
    let settings = LightingSettings {
        mesh: MeshParams::MaxEdge(0.2),
        ..Default::default()
    };
    let r = lighting(
        &scene,
        std::slice::from_ref(&lum),
        &[],
        &settings,
        &crate::observe::Silent,
    )
    .unwrap();
    assert_eq!(r.patches, 2400);
    assert_eq!(r.books.len(), 1);
    let b = r.books[0];
    let phi = 4.0 * PI * i0;
    let bound = 1e-6 * phi;
    assert!((b.emitted - phi).abs() < 1e-9 * phi, "{b:?}");
    assert!(
        (b.direct_to_surfaces - phi).abs() < bound,
        "first shot {} lm, 4π I = {phi} lm ± {bound}",
        b.direct_to_surfaces
    );
    assert!(b.escaped_counted.abs() < 1e-3 * phi, "{b:?}");
    // The solver stops when the unshot flux is 10⁻³ of its first shot, ρ Φ.
    assert!(b.unshot >= 0.0 && b.unshot < 1.01e-3 * rho * phi, "{b:?}");
    assert!(
        (b.emitted - b.absorbed - b.unshot).abs() < bound + 1e-3 * phi,
        "{b:?} ± {bound}"
    );
    assert!((b.escaped - (b.emitted - b.absorbed - b.unshot)).abs() < 1e-9 * phi);
    assert!(
        b.balance_error().abs() < (bound + 1e-3 * phi) / phi,
        "{b:?}"
    );
    assert_eq!(EnergyBooks::total(&r.books), b);
}

/// An isotropic I = 1,000 cd source 2 m above the centre of a lone 4 × 4 m floor (ρ = 0.5):
/// the flux reaching the floor is I Ω, Ω = 4 asin(L² / (L² + 4h²)) the solid angle of an
/// L × L square seen from height h above its centre (= 2π/3 sr here); the floor absorbs
/// (1 − ρ) of it and sees nothing of itself, so the rest, 4π I − (1 − ρ) I Ω, escapes. The
/// patch sums (40 × 40 patches) are the closed form; the
/// escape counted by rays on the 64 × 128 grid of equal solid angle is the grid's count of
/// the square, replayed here against the square itself, and the balance error the difference
/// of the two estimates of the floor's flux. The patches' sum is I Ω to rounding (10⁻⁶).
#[test]
fn an_open_floor_lets_the_rest_escape() {
    let (l, h, rho, i0) = (4.0f64, 2.0f64, 0.5, 1000.0);
    let w = l / 2.0;
    let floor = vec![vec![
        Vec3::new(-w as f32, -w as f32, 0.0),
        Vec3::new(w as f32, -w as f32, 0.0),
        Vec3::new(w as f32, w as f32, 0.0),
        Vec3::new(-w as f32, w as f32, 0.0),
    ]];
    let scene = Scene::of_polygons("floor", Material::diffuse("floor", Rgb::splat(rho)), floor);
    let lum = lamp("lamp", i0, [0.0, 0.0, h], 1.0, "default");
    let settings = LightingSettings {
        mesh: MeshParams::MaxEdge(0.1),
        ..Default::default()
    };
    let r = lighting(
        &scene,
        std::slice::from_ref(&lum),
        &[],
        &settings,
        &crate::observe::Silent,
    )
    .unwrap();
    assert_eq!(r.patches, 1600);
    let b = r.books[0];
    let omega = 4.0 * (l * l / (l * l + 4.0 * h * h)).asin();
    assert!((omega - 2.0 * PI / 3.0).abs() < 1e-12);
    let phi = 4.0 * PI * i0;
    let on_floor = i0 * omega;
    let bound = 1e-6 * on_floor;
    assert!(
        (b.direct_to_surfaces - on_floor).abs() < bound,
        "first shot {} lm, I Ω = {on_floor} lm ± {bound}",
        b.direct_to_surfaces
    );
    assert!(
        (b.absorbed - (1.0 - rho) * on_floor).abs() < (1.0 - rho) * bound,
        "{b:?}"
    );
    assert!(
        b.unshot >= 0.0 && b.unshot < 1.01e-3 * rho * on_floor,
        "{b:?}"
    );
    let escape = phi - (1.0 - rho) * on_floor;
    assert!(
        (b.escaped - escape).abs() < (1.0 - rho) * bound + b.unshot,
        "escaped {} lm, closed form {escape} lm",
        b.escaped
    );
    // The grid's count, replayed: the cells whose centre's direction meets the square.
    let hits = |z: f64, phi: f64| {
        let r = (1.0 - z * z).max(0.0).sqrt();
        let (x, y) = (r * phi.cos(), r * phi.sin());
        z < 0.0 && (x / -z * h).abs() <= w && (y / -z * h).abs() <= w
    };
    let (nb, ns) = (ESCAPE_BANDS, ESCAPE_SECTORS);
    let mut reached = 0;
    for band in 0..nb {
        for sector in 0..ns {
            let z = -1.0 + 2.0 * (band as f64 + 0.5) / nb as f64;
            let p = 2.0 * PI * (sector as f64 + 0.5) / ns as f64;
            reached += usize::from(hits(z, p));
        }
    }
    let cell = phi / (nb * ns) as f64;
    let grid = reached as f64 * cell;
    // The grid's own error here: 0.4 % of the floor's flux.
    assert!(
        (grid - on_floor).abs() < 0.005 * on_floor,
        "{grid} {on_floor}"
    );
    // Counted: the source's flux that misses the floor, and the floor's reflection (all of
    // it escapes, less what is left unshot); two cells for rays that `f32` puts on the other
    // side of the square's edge.
    let counted = phi - grid + rho * on_floor;
    assert!(
        (b.escaped_counted - counted).abs() < 2.0 * cell + rho * bound + b.unshot,
        "counted escape {} lm, the grid's {counted} lm",
        b.escaped_counted
    );
    // The balance error is then the grid's flux on the floor less the patches'.
    assert!(
        (b.balance_error() * phi - (grid - on_floor)).abs() < bound + 2.0 * cell + 2.0 * b.unshot,
        "{b:?}"
    );
}

/// A box of white walls (ρ = 0.8) lit by an isotropic source, its floor black (ρ = 0) or a
/// grey so dark (ρ = 10⁻³) that it changes the walls' light by about 10⁻³: the floor's mean
/// illuminance in the surfaces table must be the same. The grey floor's arriving light is
/// read back from its exitance, (B − ρ E)/ρ, which the shots from every wall patch (≥ 256
/// rays a row, about a fifth of them reaching the floor, over 1,125 shooters: ≈ 60,000 rays
/// landing on it) put there to about 0.4 %; the black floor's is gathered along its 225
/// patches' rows of 1,024 rays (≈ 230,000 rays: 0.2 %). 2 % is more than four times their
/// combined noise and the 0.1 % that the grey floor's own reflection adds.
#[test]
fn a_black_floor_reports_its_interreflected_light() {
    let s = 3.0f32;
    let v = |x: f32, y: f32, z: f32| Vec3::new(x * s, y * s, z * s);
    let walls = [
        vec![v(0., 0., 1.), v(0., 1., 1.), v(1., 1., 1.), v(1., 0., 1.)],
        vec![v(0., 0., 0.), v(0., 0., 1.), v(1., 0., 1.), v(1., 0., 0.)],
        vec![v(0., 1., 0.), v(1., 1., 0.), v(1., 1., 1.), v(0., 1., 1.)],
        vec![v(0., 0., 0.), v(0., 1., 0.), v(0., 1., 1.), v(0., 0., 1.)],
        vec![v(1., 0., 0.), v(1., 0., 1.), v(1., 1., 1.), v(1., 1., 0.)],
    ];
    let floor = vec![v(0., 0., 0.), v(1., 0., 0.), v(1., 1., 0.), v(0., 1., 0.)];
    let scene_with = |floor_rho: f64| {
        let mut polygons: Vec<Polygon> = walls
            .iter()
            .map(|w| Polygon {
                vertices: w.clone(),
                material: 0,
                line: 0,
                group: 0,
            })
            .collect();
        polygons.push(Polygon {
            vertices: floor.clone(),
            material: 1,
            line: 0,
            group: 0,
        });
        Scene {
            name: "box".into(),
            materials: vec![
                Material::diffuse("wall", Rgb::splat(0.8)),
                Material::diffuse("floor", Rgb::splat(floor_rho)),
            ],
            polygons,
            ..Default::default()
        }
    };
    let lum = lamp("lamp", 1000.0, [1.5, 1.5, 2.0], 1.0, "default");
    let settings = LightingSettings {
        mesh: MeshParams::MaxEdge(0.2),
        ..Default::default()
    };
    let floor_row = |rho: f64| {
        let r = lighting(
            &scene_with(rho),
            std::slice::from_ref(&lum),
            &[],
            &settings,
            &crate::observe::Silent,
        )
        .unwrap();
        r.surfaces.into_iter().find(|s| s.name == "floor").unwrap()
    };
    let black = floor_row(0.0);
    let grey = floor_row(1e-3);
    assert_eq!(black.exitance, 0.0);
    assert!(
        (black.illuminance - grey.illuminance).abs() < 0.02 * grey.illuminance,
        "black floor {black:?}, grey floor {grey:?}"
    );
    // The direct part alone, I Ω / A for the 3 × 3 m floor 2 m below the source, is about a
    // quarter of it: a floor reporting its direct light only would fail.
    let direct = 1000.0 * 4.0 * (9.0f64 / (9.0 + 16.0)).asin() / 9.0;
    assert!(
        black.illuminance > 2.0 * direct,
        "{black:?}: direct {direct} lx"
    );
}
