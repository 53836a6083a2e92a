//! Pictures of the lit scene in luminance against closed forms: a point source over a lone
//! Lambertian floor, and a wall of a closed box against the surfaces table.

use super::tests::{cube, lamp};
use super::*;
use crate::render::CameraRays;
use crate::scene::Material;
use std::f64::consts::PI;

/// Where the ray through image point (px, py) meets the plane `axis` = `at` (f64).
fn on_plane(
    rays: &CameraRays,
    camera: &Camera,
    px: f32,
    py: f32,
    axis: usize,
    at: f64,
) -> [f64; 3] {
    let d = rays.ray(px, py).direction.as_dvec3().to_array();
    let e = camera.eye.as_dvec3().to_array();
    let t = (at - e[axis]) / d[axis];
    [e[0] + t * d[0], e[1] + t * d[1], e[2] + t * d[2]]
}

/// An isotropic I = 1,000 cd source 2 m above a lone 4 × 4 m floor of ρ = 0.5, seen from
/// above: nothing else reflects, so a floor point x shows L = ρ I cos³θ / (π h²), the
/// inverse-square cosine law times ρ/π, with nothing gathered (the floor's reflection leaves
/// it for good). With one camera sample at each pixel's centre the picture's luminance is
/// that at the centre's floor point, to `f32` rounding (10⁻⁴); with four jittered samples a
/// pixel is the mean of L over points of its footprint, so it lies within the largest
/// deviation of L over the footprint (sampled on a 5 × 5 grid) from its centre value.
#[test]
fn a_floor_under_a_point_source_shows_the_cosine_cubed_law() {
    let (w, h, rho, i0) = (2.0f64, 2.0f64, 0.5, 1000.0);
    let floor = vec![vec![
        Vec3::new(-w as f32, -w as f32, 0.0),
        Vec3::new(w as f32, -w as f32, 0.0),
        Vec3::new(w as f32, w as f32, 0.0),
        Vec3::new(-w as f32, w as f32, 0.0),
    ]];
    let scene = Scene::of_polygons("floor", Material::diffuse("floor", Rgb::splat(rho)), floor);
    let lum = lamp("lamp", i0, [0.0, 0.0, h], 1.0, "default");
    let settings = LightingSettings {
        mesh: MeshParams::MaxEdge(0.25),
        ..Default::default()
    };
    let (_, solution) = lighting_solution(
        &scene,
        std::slice::from_ref(&lum),
        &[],
        &settings,
        &crate::observe::Silent,
    )
    .unwrap();
    let camera = Camera {
        eye: Vec3::new(0.3, 0.2, 6.0),
        target: Vec3::ZERO,
        up: Vec3::Y,
        fov_y_deg: 50.0,
    };
    let size = 32;
    let law = |p: [f64; 3]| {
        let d2 = p[0] * p[0] + p[1] * p[1] + h * h;
        let cos = h / d2.sqrt();
        rho * i0 * cos.powi(3) / (PI * h * h)
    };
    let inside = |p: [f64; 3]| p[0].abs() < w - 1e-3 && p[1].abs() < w - 1e-3;
    let rays = CameraRays::new(&camera, size, size);
    let gather = GatherParams {
        cache_samples: 0,
        ..Default::default()
    };
    for spp in [1, 4] {
        let params = RenderParams {
            width: size,
            height: size,
            samples_per_pixel: spp,
            seed: 3,
        };
        let image = solution
            .render(&camera, &params, gather, &crate::observe::Silent)
            .unwrap();
        let y = image.luminance();
        let mut checked = 0;
        for py in 0..size {
            for px in 0..size {
                // The footprint on a 5 × 5 grid (its corners included).
                let grid: Vec<[f64; 3]> = (0..25)
                    .map(|k| {
                        let (u, v) = ((k % 5) as f32 / 4.0, (k / 5) as f32 / 4.0);
                        on_plane(&rays, &camera, px as f32 + u, py as f32 + v, 2, 0.0)
                    })
                    .collect();
                if !grid.iter().all(|&p| inside(p)) {
                    continue;
                }
                let centre = law(on_plane(
                    &rays,
                    &camera,
                    px as f32 + 0.5,
                    py as f32 + 0.5,
                    2,
                    0.0,
                ));
                let got = y[(py * size + px) as usize] as f64;
                let spread = if spp == 1 {
                    0.0
                } else {
                    grid.iter()
                        .map(|&p| (law(p) - centre).abs())
                        .fold(0.0, f64::max)
                };
                assert!(
                    (got - centre).abs() <= spread + 1e-4 * centre,
                    "spp {spp}, pixel ({px}, {py}): {got} cd/m², law {centre} ± {spread}"
                );
                checked += 1;
            }
        }
        assert!(checked > 300, "{checked} pixels on the floor");
    }
}

/// A closed 4 m cube of ρ = 0.5 lit by an isotropic source off its centre, one wall seen
/// square-on so that it fills the picture exactly: the image plane is parallel to the wall,
/// so the pixel centres are a uniform midpoint grid on it, and the picture's mean luminance is
/// the wall's mean. It must match the surfaces table's luminance for that wall. The two
/// differ by (1) the direct light's two midpoint rules (pixel centres, patch centres),
/// computed here exactly and taken off; (2) the gather's Monte Carlo noise, whose standard
/// error is estimated from the pixels' reflected part (the picture less ρ E_direct/π, which
/// still varies over the wall, so the estimate is an upper one); and (3) the solution's own
/// error, the patches' Monte Carlo rows (≥ 256 rays each over 2,400 patches) and the
/// interpolation of their exitance, allowed 1 % of the reflected part (the wall averages of
/// the integrating-sphere test are within 0.5 % of the closed form). Four standard errors and
/// that.
#[test]
fn a_wall_in_the_picture_matches_the_surfaces_table() {
    let (s, rho, i0) = (4.0f64, 0.5, 1000.0);
    let mut scene = cube(s as f32, rho);
    scene
        .materials
        .push(Material::diffuse("wall", Rgb::splat(rho)));
    // The x = s face (its normal −x) is the wall.
    scene.polygons[5].material = 1;
    let at = [1.5, 2.0, 2.5];
    let lum = lamp("lamp", i0, at, 1.0, "default");
    let settings = LightingSettings {
        mesh: MeshParams::MaxEdge(0.2),
        ..Default::default()
    };
    let (result, solution) = lighting_solution(
        &scene,
        std::slice::from_ref(&lum),
        &[],
        &settings,
        &crate::observe::Silent,
    )
    .unwrap();
    let table = result.surfaces.iter().find(|r| r.name == "wall").unwrap();
    assert!((table.area - s * s).abs() < 1e-3, "{table:?}");
    let eye_x = 0.01f64;
    let camera = Camera {
        eye: Vec3::new(eye_x as f32, 2.0, 2.0),
        target: Vec3::new(4.0, 2.0, 2.0),
        up: Vec3::Z,
        fov_y_deg: (2.0 * (2.0 / (s - eye_x)).atan()).to_degrees() as f32,
    };
    let size = 48;
    let params = RenderParams {
        width: size,
        height: size,
        samples_per_pixel: 1,
        seed: 5,
    };
    let gather = GatherParams {
        indirect: 64,
        cache_samples: 0,
        ..Default::default()
    };
    let image = solution
        .render(&camera, &params, gather, &crate::observe::Silent)
        .unwrap();
    let y = image.luminance();
    // The direct illuminance on the wall (normal −x): I cos θ / d².
    let direct = |p: [f64; 3]| {
        let d = [at[0] - p[0], at[1] - p[1], at[2] - p[2]];
        let d2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        i0 * (-d[0]).abs() / d2.sqrt() / d2
    };
    let rays = CameraRays::new(&camera, size, size);
    let n = (size * size) as f64;
    let (mut mean_direct_pixels, mut mean, mut reflected) = (0.0, 0.0, Vec::new());
    for py in 0..size {
        for px in 0..size {
            let p = on_plane(&rays, &camera, px as f32 + 0.5, py as f32 + 0.5, 0, s);
            assert!(p[1] > 0.0 && p[1] < s && p[2] > 0.0 && p[2] < s, "{p:?}");
            let e = direct(p);
            let l = y[(py * size + px) as usize] as f64;
            mean_direct_pixels += e / n;
            mean += l / n;
            reflected.push(l - rho * e / PI);
        }
    }
    let m = reflected.iter().sum::<f64>() / n;
    let var = reflected.iter().map(|r| (r - m).powi(2)).sum::<f64>() / (n - 1.0);
    let se = (var / n).sqrt();
    let (mut area, mut sum) = (0.0, 0.0);
    for p in solution.mesh.patches.iter().filter(|p| p.material == 1) {
        let c = p.centre.as_dvec3().to_array();
        area += p.area as f64;
        sum += p.area as f64 * direct(c);
    }
    let mean_direct_patches = sum / area;
    let midpoint = rho / PI * (mean_direct_pixels - mean_direct_patches);
    let table_reflected = table.luminance - rho / PI * mean_direct_patches;
    assert!(table_reflected > 0.2 * table.luminance, "{table:?}");
    let tolerance = 4.0 * se + 0.01 * table_reflected;
    assert!(
        (mean - midpoint - table.luminance).abs() < tolerance,
        "picture {mean} cd/m² (midpoint rules {midpoint}), table {} cd/m², tolerance {tolerance} (standard error {se})",
        table.luminance
    );
}
