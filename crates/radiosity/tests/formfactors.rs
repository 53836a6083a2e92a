//! Every form-factor method against closed forms from Howell's catalogue of configuration
//! factors, and row sums in closed scenes.

use radiosity::accel::Bvh;
use radiosity::color::Rgb;
use radiosity::formfactor::{aggregate, Estimator, FormFactorMethod, Params, Storage};
use radiosity::geom::Vec3;
use radiosity::mesh::{Mesh, MeshParams};
use radiosity::scene::{builtin, Material, Scene};
use std::f64::consts::PI;

pub use radiosity::formfactor::closed_form::{
    coaxial_discs, parallel_rectangles, perpendicular_rectangles,
};

fn scene_of(polys: Vec<Vec<Vec3>>) -> Scene {
    Scene::of_polygons(
        "pair",
        Material::emitter("m", Rgb::splat(0.5), Rgb::splat(1.0)),
        polys,
    )
}

fn v(x: f32, y: f32, z: f32) -> Vec3 {
    Vec3::new(x, y, z)
}

/// The two unit-square cases: parallel at distance 1 and perpendicular with a common edge.
pub fn unit_square_cases() -> Vec<(&'static str, Scene, f64)> {
    vec![
        (
            "parallel unit squares",
            scene_of(vec![
                vec![v(0., 0., 0.), v(1., 0., 0.), v(1., 1., 0.), v(0., 1., 0.)],
                vec![v(0., 0., 1.), v(0., 1., 1.), v(1., 1., 1.), v(1., 0., 1.)],
            ]),
            parallel_rectangles(1.0, 1.0, 1.0),
        ),
        (
            "perpendicular unit squares",
            scene_of(vec![
                vec![v(0., 0., 0.), v(0., 0., 1.), v(1., 0., 1.), v(1., 0., 0.)],
                vec![v(0., 0., 0.), v(1., 0., 0.), v(1., 1., 0.), v(0., 1., 0.)],
            ]),
            perpendicular_rectangles(1.0, 1.0, 1.0),
        ),
    ]
}

/// F from face 0 to face 1 of `scene` meshed with one patch per face piece, grouped by face.
pub fn face_factor(scene: &Scene, params: Params) -> f64 {
    let mesh = Mesh::build(scene, MeshParams::Faces).unwrap();
    let bvh = Bvh::build(&mesh);
    let est = Estimator::new(&mesh, &bvh, params).unwrap();
    let m = est
        .matrix(Storage::Sparse, &radiosity::observe::Silent)
        .into_sparse();
    let area: Vec<f64> = mesh.patches.iter().map(|p| p.area as f64).collect();
    let group: Vec<u32> = mesh.patches.iter().map(|p| p.surface).collect();
    let (g, _) = aggregate(&m, &area, &group, scene.polygons.len());
    g.row_entries(0)
        .iter()
        .find(|e| e.0 == 1)
        .map_or(0.0, |e| e.1 as f64)
}

#[test]
fn closed_forms_are_howells_values() {
    assert!((parallel_rectangles(1.0, 1.0, 1.0) - 0.19982).abs() < 5e-6);
    assert!((perpendicular_rectangles(1.0, 1.0, 1.0) - 0.20004).abs() < 5e-6);
    assert!((coaxial_discs(1.0, 1.0, 1.0) - 0.381966).abs() < 1e-6);
}

/// With default settings every method is within 1 % of the closed form on the two unit-square
/// cases; the analytic method within 1e-6.
#[test]
fn every_method_matches_howell_with_defaults() {
    for (name, scene, exact) in unit_square_cases() {
        for method in FormFactorMethod::ALL {
            let f = face_factor(
                &scene,
                Params {
                    method,
                    ..Default::default()
                },
            );
            let tol = if method == FormFactorMethod::Analytic {
                1e-6
            } else {
                0.01 * exact
            };
            assert!(
                (f - exact).abs() < tol,
                "{name}, {method}: F = {f}, exact {exact}"
            );
        }
    }
}

/// The projection methods' error is pixel aliasing at the edges of the projected patch, O(1/P):
/// on the smooth (parallel) case, going from P ∈ {16, 32} to P ∈ {128, 256} (8×) cuts the mean
/// error by at least 4.
#[test]
fn projection_error_shrinks_with_resolution() {
    let (_, scene, exact) = unit_square_cases().remove(0);
    for method in [
        FormFactorMethod::Hemicube,
        FormFactorMethod::Hemisphere,
        FormFactorMethod::Tetrahedron,
    ] {
        let err = |p: u32| {
            (face_factor(
                &scene,
                Params {
                    method,
                    resolution: p,
                    ..Default::default()
                },
            ) - exact)
                .abs()
                / exact
        };
        let coarse = 0.5 * (err(16) + err(32));
        let fine = 0.5 * (err(128) + err(256));
        assert!(
            fine * 4.0 < coarse,
            "{method}: mean error {coarse:.2e} at P = 16, 32 but {fine:.2e} at P = 128, 256"
        );
        assert!(fine < 0.005, "{method}: {fine}");
    }
}

/// Eq. 6's one-point approximation does not shrink with P; spreading points over patch i does.
#[test]
fn one_point_error_is_removed_by_samples() {
    let (_, scene, exact) = unit_square_cases().remove(0);
    let one = face_factor(
        &scene,
        Params {
            method: FormFactorMethod::Hemicube,
            samples: 1,
            resolution: 256,
            ..Default::default()
        },
    );
    // From the centre the opposed square subtends 0.2395, 20 % above the area average.
    assert!((one - exact) / exact > 0.15, "{one}");
    let many = face_factor(
        &scene,
        Params {
            method: FormFactorMethod::Hemicube,
            samples: 16,
            resolution: 256,
            ..Default::default()
        },
    );
    assert!((many - exact).abs() / exact < 0.005, "{many}");
}

/// Monte Carlo within 4σ of eq. 7 (σ² = F(1 − F)/n) at every n.
#[test]
fn monte_carlo_error_follows_one_over_root_n() {
    for (name, scene, exact) in unit_square_cases() {
        for rays in [10_000u32, 100_000, 1_000_000] {
            let f = face_factor(
                &scene,
                Params {
                    method: FormFactorMethod::MonteCarlo,
                    rays,
                    seed: 5,
                    ..Default::default()
                },
            );
            let sigma = (exact * (1.0 - exact) / rays as f64).sqrt();
            assert!(
                (f - exact).abs() < 4.0 * sigma,
                "{name}, n = {rays}: F = {f}, exact {exact}, σ {sigma}"
            );
        }
    }
}

fn disc(r: f32, z: f32, up: bool, sides: usize) -> Vec<Vec3> {
    let mut pts: Vec<Vec3> = (0..sides)
        .map(|k| {
            let a = k as f32 * std::f32::consts::TAU / sides as f32;
            v(r * a.cos(), r * a.sin(), z)
        })
        .collect();
    if !up {
        pts.reverse();
    }
    pts
}

/// Parallel coaxial discs (Howell C-41), as 48-gons: the analytic factor is within the
/// polygons' own approximation error of the discs' value, and every method within 1 % of the
/// analytic factor of the same polygons.
#[test]
fn coaxial_discs_as_polygons() {
    let sides = 48;
    let scene = scene_of(vec![
        disc(1.0, 0.0, true, sides),
        disc(1.0, 1.0, false, sides),
    ]);
    let exact_disc = coaxial_discs(1.0, 1.0, 1.0);
    let analytic = face_factor(
        &scene,
        Params {
            method: FormFactorMethod::Analytic,
            ..Default::default()
        },
    );
    // An inscribed n-gon misses a share ≈ (2π/n)²/6 of the disc's area.
    let deficit = (2.0 * PI / sides as f64).powi(2) / 6.0;
    assert!(
        (analytic - exact_disc).abs() < 2.0 * deficit * exact_disc,
        "analytic {analytic} vs disc {exact_disc}"
    );
    for method in [
        FormFactorMethod::Hemicube,
        FormFactorMethod::Hemisphere,
        FormFactorMethod::Tetrahedron,
        FormFactorMethod::MonteCarlo,
    ] {
        let params = Params {
            method,
            samples: 4,
            rays: 200_000,
            ..Default::default()
        };
        let f = face_factor(&scene, params);
        assert!(
            (f - analytic).abs() < 0.01 * analytic,
            "{method}: {f} vs {analytic}"
        );
    }
}

/// In a closed enclosure every row sums to 1: exactly for Monte Carlo and the hemisphere (every
/// ray hits a front side), to a pixel for the z-buffer methods (deltas normalised), and to the
/// quadrature's accuracy for the analytic method in a convex room without occlusion.
#[test]
fn rows_sum_to_one_in_closed_scenes() {
    let check = |scene: &Scene, patches: usize, method: FormFactorMethod, tol: f64| {
        let mesh = Mesh::build(scene, MeshParams::Patches(patches)).unwrap();
        let bvh = Bvh::build(&mesh);
        let params = Params {
            method,
            rays: 20_000,
            samples: 4,
            resolution: 64,
            ..Default::default()
        };
        let m = Estimator::new(&mesh, &bvh, params)
            .unwrap()
            .matrix(Storage::Auto, &radiosity::observe::Silent)
            .into_sparse();
        let worst = (0..m.n())
            .map(|i| (m.row_sum(i) - 1.0).abs())
            .fold(0.0, f64::max);
        assert!(
            worst < tol,
            "{} {method}: worst |row sum − 1| = {worst}",
            scene.name
        );
    };
    let furnace = builtin::furnace();
    for method in [FormFactorMethod::Hemisphere, FormFactorMethod::MonteCarlo] {
        check(&furnace, 150, method, 1e-4);
    }
    // A point-sampled z-buffer may lose or double a pixel where faces meet: the projection
    // methods' rows sum to 1 within two pixels' worth of the largest delta form factor.
    for (method, solid) in [
        (
            FormFactorMethod::Hemicube,
            radiosity::formfactor::projection::Solid::hemicube(64),
        ),
        (
            FormFactorMethod::Tetrahedron,
            radiosity::formfactor::projection::Solid::tetrahedron(64),
        ),
    ] {
        let max_delta = solid
            .faces
            .iter()
            .flat_map(|f| f.delta.iter())
            .fold(0.0f32, |m, d| m.max(*d)) as f64;
        check(&furnace, 150, method, 2.0 * max_delta);
    }
    check(
        &builtin::cube(builtin::CubeVariant::Bright),
        100,
        FormFactorMethod::Analytic,
        1e-6,
    );
}

/// The hemicube and the hemisphere agree with Monte Carlo on a scene with occlusion, entry by
/// entry, within Monte Carlo's 4σ plus the projections' aliasing.
#[test]
fn methods_agree_on_an_occluded_scene() {
    let scene = builtin::furnace();
    let mesh = Mesh::build(&scene, MeshParams::Patches(60)).unwrap();
    let bvh = Bvh::build(&mesh);
    let rays = 400_000u32;
    let reference = Estimator::new(
        &mesh,
        &bvh,
        Params {
            method: FormFactorMethod::MonteCarlo,
            rays,
            ..Default::default()
        },
    )
    .unwrap()
    .matrix(Storage::Dense, &radiosity::observe::Silent)
    .into_sparse();
    for method in [
        FormFactorMethod::Hemisphere,
        FormFactorMethod::Tetrahedron,
        FormFactorMethod::Hemicube,
    ] {
        let m = Estimator::new(
            &mesh,
            &bvh,
            Params {
                method,
                ..Default::default()
            },
        )
        .unwrap()
        .matrix(Storage::Sparse, &radiosity::observe::Silent)
        .into_sparse();
        let mut worst: f64 = 0.0;
        for i in 0..mesh.len() {
            let (a, b) = (m.row_entries(i), reference.row_entries(i));
            for j in 0..mesh.len() as u32 {
                let fa = a.iter().find(|e| e.0 == j).map_or(0.0, |e| e.1 as f64);
                let fb = b.iter().find(|e| e.0 == j).map_or(0.0, |e| e.1 as f64);
                let sigma = (fb * (1.0 - fb) / rays as f64).sqrt();
                worst = worst.max((fa - fb).abs() - 4.0 * sigma - 0.01 * fb.max(fa));
            }
        }
        assert!(worst < 2e-3, "{method}: worst excess difference {worst}");
    }
}
