//! Lightmaps (issue 59): the Cornell box's texels against path-traced references, no light
//! leaking into a closed box, seams that agree, and the Khronos validator on every
//! lightmapped glTF written.

use radiosity::bake::lightmap::{bake, Denoise, Lightmap, LightmapParams, Texel};
use radiosity::bake::uv::Density;
use radiosity::color::Rgb;
use radiosity::export::bake::{write_lightmap_gltf, LightmapBake};
use radiosity::geom::Vec3;
use radiosity::prelude::*;
use radiosity::scene::{Material, Polygon, Scene};
use std::path::PathBuf;

fn solved(scene: &Scene, patches: usize) -> Solution {
    let mut settings = Settings::from(Uniform {
        mesh: MeshParams::Patches(patches),
        ..Default::default()
    });
    if let radiosity::pipeline::Method::Uniform(u) = &mut settings.method {
        u.params.tolerance = 1e-4;
    }
    solve(scene, &settings, &Silent).unwrap()
}

fn baked(scene: &Scene, s: &Solution, params: &LightmapParams) -> Lightmap {
    let vertex = radiosity::render::vertex_radiosity(&s.mesh, &s.radiosity);
    bake(scene, s.surfaces(), &vertex, params).unwrap()
}

/// Write `map` as `.glb` and run the Khronos validator over it: no errors and no warnings
/// (MOZ_lightmap, which it does not know, is reported as information only).
fn validate(scene: &Scene, map: &Lightmap, name: &str) {
    let path: PathBuf = std::env::temp_dir().join(format!(
        "radiosity-lightmap-{name}-{}.glb",
        std::process::id()
    ));
    write_lightmap_gltf(
        &path,
        &LightmapBake {
            scene,
            lightmap: map,
            scale: 1.0,
            camera: None,
        },
        true,
    )
    .unwrap();
    let report = crate::validator::validate_gltf_report(std::slice::from_ref(&path));
    assert!(report.contains(": 0 errors, 0 warnings"), "{report}");
    std::fs::remove_file(&path).unwrap();
}

fn sum(b: Rgb) -> f64 {
    b.r + b.g + b.b
}

/// The Cornell box at a texel size of 1 % of the box (5.56 units): the mean of each quad's
/// texels (those whose centre lies inside it: a midpoint rule for its area mean) within 2 % of
/// the path tracer's mean radiosity of that quad (plus two of the reference's standard errors), and 400 texels against a per-texel path-traced
/// radiosity at their points at a relative RMSE (over the reference's mean) within 3 %, the
/// reference's own variance taken off. The path tracer shares no code with the solution or the
/// gather but the ray caster and the emitter sampling.
#[test]
fn cornell_texels_match_path_traced_references() {
    let scene = builtin::cornell();
    let s = solved(&scene, 20_000);
    let map = baked(
        &scene,
        &s,
        &LightmapParams {
            density: Density::TexelSize(5.56),
            direct: 32,
            ..Default::default()
        },
    );
    validate(&scene, &map, "cornell");
    // Quads: polygons of the scene (the lamp excluded: it is its emission).
    let reference = radiosity::pipeline::path_surface_means(&scene, 4_000_000, 7).unwrap();
    let mesh = &map.unwrap.mesh;
    let mut per = vec![(Rgb::BLACK, 0usize); scene.polygons.len()];
    for k in 0..map.texels.len() {
        if let Some(p) = map.point(k).filter(|p| p.inside) {
            let s = mesh.patches[p.face as usize].surface as usize;
            per[s].0 += map.texel(k);
            per[s].1 += 1;
        }
    }
    for (k, ((b, n), (r, se))) in per.iter().zip(&reference).enumerate() {
        if scene.materials[scene.polygons[k].material]
            .emission
            .max_channel()
            > 0.0
        {
            continue;
        }
        let mean = sum(*b) / *n as f64;
        let (r, se) = (sum(*r), sum(*se));
        let rel = (mean - r).abs() / r;
        eprintln!(
            "quad {k}: lightmap {mean:.5} path {r:.5} ± {se:.5} ({:.2} %)",
            100.0 * rel
        );
        // 2 %, widened by two of the reference's own standard errors (its small quads get few
        // of the paths).
        assert!(rel <= 0.02 + 2.0 * se / r, "quad {k}: {mean} vs {r} ± {se}");
    }
    // Texels: 400 drawn evenly among the lit ones, each against 20,000 paths at its point.
    let mesh_bvh = radiosity::accel::Bvh::build(mesh);
    let system = radiosity::mesh::patch_system(&scene, mesh);
    let surfaces = radiosity::render::light::Surfaces {
        mesh,
        bvh: &mesh_bvh,
        reflectance: &system.reflectance,
        emission: &system.emission,
    };
    let lights = radiosity::render::light::Lights::new(mesh, &system.emission);
    let lit: Vec<usize> = (0..map.texels.len())
        .filter(|&k| map.kind[k] == Texel::Surface && map.inside[k])
        .collect();
    let step = lit.len() / 400;
    use rayon::prelude::*;
    let pairs: Vec<(f64, f64, f64)> = (0..400)
        .into_par_iter()
        .map(|i| {
            let k = lit[i * step];
            let p = map.point_on(k, &scene, &s.surfaces()).unwrap();
            let mut rng = radiosity::sampling::stream(11, 0, k as u64, 0);
            let (r, se) = radiosity::render::path::radiosity_at(
                &surfaces, &lights, p.x, p.n, p.face, 20_000, &mut rng,
            );
            (sum(map.texel(k)), sum(r), sum(se))
        })
        .collect();
    let mse = pairs.iter().map(|(a, r, _)| (a - r).powi(2)).sum::<f64>() / 400.0;
    let noise = pairs.iter().map(|(_, _, se)| se * se).sum::<f64>() / 400.0;
    let mean = pairs.iter().map(|(_, r, _)| r).sum::<f64>() / 400.0;
    let rmse = (mse - noise).max(0.0).sqrt() / mean;
    eprintln!(
        "texels: relative RMSE {:.2} % (raw {:.2} %, reference noise {:.2} %)",
        100.0 * rmse,
        100.0 * mse.sqrt() / mean,
        100.0 * noise.sqrt() / mean
    );
    assert!(rmse <= 0.03, "relative RMSE {rmse}");
}

/// 400 lit texels' radiosity at their points by the path tracer (20,000 paths each): the
/// texel index, the reference and its standard error (summed over channels).
fn texel_references(scene: &Scene, s: &Solution, map: &Lightmap) -> Vec<(usize, f64, f64)> {
    let mesh = &map.unwrap.mesh;
    let mesh_bvh = radiosity::accel::Bvh::build(mesh);
    let system = radiosity::mesh::patch_system(scene, mesh);
    let surfaces = radiosity::render::light::Surfaces {
        mesh,
        bvh: &mesh_bvh,
        reflectance: &system.reflectance,
        emission: &system.emission,
    };
    let lights = radiosity::render::light::Lights::new(mesh, &system.emission);
    let lit: Vec<usize> = (0..map.texels.len())
        .filter(|&k| map.kind[k] == Texel::Surface && map.inside[k])
        .collect();
    let step = lit.len() / 400;
    use rayon::prelude::*;
    (0..400)
        .into_par_iter()
        .map(|i| {
            let k = lit[i * step];
            let p = map.point_on(k, scene, &s.surfaces()).unwrap();
            let mut rng = radiosity::sampling::stream(11, 0, k as u64, 0);
            let (r, se) = radiosity::render::path::radiosity_at(
                &surfaces, &lights, p.x, p.n, p.face, 20_000, &mut rng,
            );
            (k, sum(r), sum(se))
        })
        .collect()
}

/// Relative RMSE of `map`'s texels against `refs` (over the references' mean), the
/// references' own variance taken off.
fn relative_rmse(map: &Lightmap, refs: &[(usize, f64, f64)]) -> f64 {
    let n = refs.len() as f64;
    let mse = refs
        .iter()
        .map(|&(k, r, _)| (sum(map.texel(k)) - r).powi(2))
        .sum::<f64>()
        / n;
    let noise = refs.iter().map(|(_, _, se)| se * se).sum::<f64>() / n;
    let mean = refs.iter().map(|(_, r, _)| r).sum::<f64>() / n;
    (mse - noise).max(0.0).sqrt() / mean
}

/// Denoising (issue 59): the Cornell box baked with few indirect samples (16 a record, noisy)
/// comes closer to the path-traced per-texel reference with the cross-bilateral filter than
/// without (measured 2.80 % → 1.60 % relative RMSE; 256 samples unfiltered give 1.07 %, the
/// floor set by the solution's mesh): at most 0.75 times, and within the 3 % target. The
/// direct light is not filtered, so a texel's value changes only by its indirect part; each
/// quad's texel mean stays within 2 % (plus two reference standard errors) of the path
/// tracer's surface mean, as without denoising (the edge between lit and covered texels is
/// kept by the leak test, run with the filter too).
#[test]
fn denoising_lowers_the_texels_error() {
    let scene = builtin::cornell();
    let s = solved(&scene, 5000);
    let bake_with = |denoise| {
        baked(
            &scene,
            &s,
            &LightmapParams {
                density: Density::TexelSize(5.56),
                direct: 32,
                indirect: 16,
                denoise,
                ..Default::default()
            },
        )
    };
    let (noisy, filtered) = (bake_with(None), bake_with(Some(Denoise::default())));
    let refs = texel_references(&scene, &s, &noisy);
    let (before, after) = (
        relative_rmse(&noisy, &refs),
        relative_rmse(&filtered, &refs),
    );
    eprintln!(
        "relative RMSE: {:.2} % without denoising, {:.2} % with",
        100.0 * before,
        100.0 * after
    );
    assert!(
        after <= 0.75 * before && after <= 0.03,
        "{before} → {after}"
    );
    // Quad means.
    let reference = radiosity::pipeline::path_surface_means(&scene, 1_000_000, 7).unwrap();
    let mesh = &filtered.unwrap.mesh;
    let mut per = vec![(Rgb::BLACK, 0usize); scene.polygons.len()];
    for k in 0..filtered.texels.len() {
        if let Some(p) = filtered.point(k).filter(|p| p.inside) {
            let q = mesh.patches[p.face as usize].surface as usize;
            per[q].0 += filtered.texel(k);
            per[q].1 += 1;
        }
    }
    for (k, ((b, n), (r, se))) in per.iter().zip(&reference).enumerate() {
        let m = &scene.materials[scene.polygons[k].material];
        if m.emission.max_channel() > 0.0 {
            continue;
        }
        let (mean, r, se) = (sum(*b) / *n as f64, sum(*r), sum(*se));
        assert!(
            (mean - r).abs() <= (0.02 + 2.0 * se / r) * r,
            "quad {k}: {mean} vs {r} ± {se}"
        );
    }
}

/// Several atlases (issue 59): the Cornell box at one texel size packed into 64 × 64 atlases
/// (several) holds, chart for chart, exactly the texels of the one atlas that texel size
/// alone gives (each texel's streams are keyed by chart and texel, not by its place in an
/// atlas), each face's UVs lie in its chart's rectangle of its atlas, and the glTF, a
/// material and a texture per atlas, passes the validator.
#[test]
fn several_atlases_hold_the_texels_of_one() {
    let scene = builtin::cornell();
    let s = solved(&scene, 300);
    let l = 12.0;
    let params = |density| LightmapParams {
        density,
        direct: 4,
        indirect: 16,
        ..Default::default()
    };
    let one = baked(&scene, &s, &params(Density::TexelSize(l)));
    let many = baked(&scene, &s, &params(Density::Both(l, 64)));
    assert_eq!(one.atlases(), 1);
    assert!(many.atlases() >= 2, "{} atlases", many.atlases());
    assert_eq!((many.width(), many.height()), (64, 64));
    validate(&scene, &many, "atlases");
    assert_eq!(one.unwrap.charts.len(), many.unwrap.charts.len());
    let per = |m: &Lightmap| m.width() as usize * m.height() as usize;
    let mut compared = 0;
    for (a, b) in one.unwrap.charts.iter().zip(&many.unwrap.charts) {
        assert_eq!((a.width, a.height, &a.faces), (b.width, b.height, &b.faces));
        for j in 0..a.height {
            for i in 0..a.width {
                let ka = ((a.y0 + j) * one.width() + a.x0 + i) as usize;
                let kb =
                    b.atlas as usize * per(&many) + ((b.y0 + j) * many.width() + b.x0 + i) as usize;
                assert_eq!(one.texels[ka], many.texels[kb], "chart texel ({i}, {j})");
                assert_eq!(one.kind[ka], many.kind[kb]);
                compared += 1;
            }
        }
    }
    assert_eq!(compared, one.surface_texels().max(compared));
    // Each face's UVs inside its chart's rectangle of its atlas.
    let u = &many.unwrap;
    for (f, p) in u.mesh.patches.iter().enumerate() {
        let c = &u.charts[u.chart_of[f] as usize];
        for &v in p.vertices.iter().take(if p.is_triangle() { 3 } else { 4 }) {
            let t = u.uv[v as usize];
            let (x, y) = (t[0] * u.width as f32, t[1] * u.height as f32);
            assert!(x >= c.x0 as f32 && x <= (c.x0 + c.width) as f32);
            assert!(y >= c.y0 as f32 && y <= (c.y0 + c.height) as f32);
        }
    }
}

fn quad(a: Vec3, b: Vec3, c: Vec3, d: Vec3, material: usize) -> Polygon {
    Polygon {
        vertices: vec![a, b, c, d],
        material,
        line: 0,
        group: 0,
    }
}

/// The six faces of the box `[lo, hi]`, facing out (`inward` false) or in.
fn box_faces(lo: Vec3, hi: Vec3, material: usize, inward: bool) -> Vec<Polygon> {
    let v = Vec3::new;
    let (x0, y0, z0, x1, y1, z1) = (lo.x, lo.y, lo.z, hi.x, hi.y, hi.z);
    let mut faces = vec![
        // −y, +y, −x, +x, −z, +z (counter-clockwise seen from outside)
        quad(
            v(x0, y0, z0),
            v(x1, y0, z0),
            v(x1, y0, z1),
            v(x0, y0, z1),
            material,
        ),
        quad(
            v(x0, y1, z0),
            v(x0, y1, z1),
            v(x1, y1, z1),
            v(x1, y1, z0),
            material,
        ),
        quad(
            v(x0, y0, z0),
            v(x0, y0, z1),
            v(x0, y1, z1),
            v(x0, y1, z0),
            material,
        ),
        quad(
            v(x1, y0, z0),
            v(x1, y1, z0),
            v(x1, y1, z1),
            v(x1, y0, z1),
            material,
        ),
        quad(
            v(x0, y0, z0),
            v(x0, y1, z0),
            v(x1, y1, z0),
            v(x1, y0, z0),
            material,
        ),
        quad(
            v(x0, y0, z1),
            v(x1, y0, z1),
            v(x1, y1, z1),
            v(x0, y1, z1),
            material,
        ),
    ];
    if inward {
        for f in &mut faces {
            f.vertices.reverse();
        }
    }
    faces
}

/// A closed dark box (walls 5 cm thick: six faces out, six in) resting on a lit floor under a
/// lamp: the floor's texels under the box and every texel inside the box read below 0.1 % of
/// the lit floor's mean.
#[test]
fn no_light_leaks_into_a_closed_box() {
    let v = Vec3::new;
    let f = 4.0;
    let mut polygons = vec![
        quad(
            v(-f, 0.0, -f),
            v(-f, 0.0, f),
            v(f, 0.0, f),
            v(f, 0.0, -f),
            0,
        ),
        quad(
            v(-0.5, 3.0, -0.5),
            v(0.5, 3.0, -0.5),
            v(0.5, 3.0, 0.5),
            v(-0.5, 3.0, 0.5),
            1,
        ),
    ];
    let (lo, hi) = (v(-0.3, 0.0, -0.6), v(0.7, 1.0, 0.4));
    let t = 0.05;
    polygons.extend(box_faces(lo, hi, 2, false));
    polygons.extend(box_faces(lo + Vec3::splat(t), hi - Vec3::splat(t), 2, true));
    let scene = Scene {
        name: "leak".into(),
        materials: vec![
            Material::diffuse("floor", Rgb::splat(0.6)),
            Material::emitter("lamp", Rgb::BLACK, Rgb::splat(50.0)),
            Material::diffuse("box", Rgb::splat(0.05)),
        ],
        polygons,
        ..Default::default()
    };
    let s = solved(&scene, 4000);
    for denoise in [None, Some(Denoise::default())] {
        let map = baked(
            &scene,
            &s,
            &LightmapParams {
                density: Density::TexelSize(0.02),
                denoise,
                ..Default::default()
            },
        );
        if denoise.is_none() {
            validate(&scene, &map, "leak");
        }
        check_no_leak(&map, lo, hi);
    }
}

/// The floor's texels under the box `[lo, hi]` and every texel inside it read below 0.1 % of
/// the lit floor's mean.
fn check_no_leak(map: &Lightmap, lo: Vec3, hi: Vec3) {
    let mesh = &map.unwrap.mesh;
    let (mut lit, mut n_lit) = (0.0, 0usize);
    let mut under = Vec::new();
    let mut inside = Vec::new();
    for k in 0..map.texels.len() {
        let Some(p) = map.point(k) else { continue };
        let surface = mesh.patches[p.face as usize].surface as usize;
        let b = sum(map.texel(k));
        if surface == 0 {
            let in_footprint = p.x.x > lo.x && p.x.x < hi.x && p.x.z > lo.z && p.x.z < hi.z;
            if in_footprint {
                under.push(b);
            } else if map.kind[k] == Texel::Surface {
                lit += b;
                n_lit += 1;
            }
        } else if surface >= 8 {
            inside.push(b);
        }
    }
    let lit = lit / n_lit as f64;
    let worst = |v: &[f64]| v.iter().copied().fold(0.0f64, f64::max);
    eprintln!(
        "lit floor {lit:.4}; under the box {} texels, worst {:.3e}; inside {} texels, worst {:.3e}",
        under.len(),
        worst(&under),
        inside.len(),
        worst(&inside)
    );
    assert!(under.len() > 1000 && inside.len() > 10_000);
    assert!(worst(&under) < 1e-3 * lit, "under the box");
    assert!(worst(&inside) < 1e-3 * lit, "inside the box");
}

/// A floor cut into four quads of different (equal) materials, so four charts, lit smoothly by
/// a high lamp: along each seam, the lightmap sampled bilinearly from either side differs by no
/// more, on average, than neighbouring texels inside a chart do.
#[test]
fn seams_agree() {
    let v = Vec3::new;
    let f = 2.0;
    let white = Material::diffuse("a", Rgb::splat(0.5));
    let mut materials = Vec::new();
    for k in 0..4 {
        materials.push(Material {
            name: format!("floor{k}"),
            ..white.clone()
        });
    }
    materials.push(Material::emitter("lamp", Rgb::BLACK, Rgb::splat(100.0)));
    let mut polygons = Vec::new();
    for (k, (x0, z0)) in [(-f, -f), (0.0, -f), (-f, 0.0), (0.0, 0.0)]
        .into_iter()
        .enumerate()
    {
        polygons.push(quad(
            v(x0, 0.0, z0),
            v(x0, 0.0, z0 + f),
            v(x0 + f, 0.0, z0 + f),
            v(x0 + f, 0.0, z0),
            k,
        ));
    }
    polygons.push(quad(
        v(-1.3, 4.0, -0.2),
        v(-0.8, 4.0, -0.2),
        v(-0.8, 4.0, 0.3),
        v(-1.3, 4.0, 0.3),
        4,
    ));
    let scene = Scene {
        name: "seams".into(),
        materials,
        polygons,
        ..Default::default()
    };
    let s = solved(&scene, 2000);
    let map = baked(
        &scene,
        &s,
        &LightmapParams {
            density: Density::AtlasSize(256),
            ..Default::default()
        },
    );
    validate(&scene, &map, "seams");
    let u = &map.unwrap;
    assert_eq!(u.charts.len(), 5);
    let chart_of_surface = |k: u32| {
        u.charts
            .iter()
            .position(|c| u.mesh.patches[c.faces[0] as usize].surface == k)
            .unwrap()
    };
    let at = |c: usize, p: Vec3| {
        let chart = &u.charts[c];
        let s = chart.texel_coords(p, u.texel);
        map.sample(
            0,
            [
                (chart.x0 as f32 + s[0]) / u.width as f32,
                (chart.y0 as f32 + s[1]) / u.height as f32,
            ],
        )
    };
    // Neighbouring texels inside each floor chart.
    let (mut var, mut n_var) = (0.0, 0usize);
    for k in 0..4 {
        let c = &u.charts[chart_of_surface(k)];
        for j in c.y0..c.y0 + c.height {
            for i in c.x0..c.x0 + c.width - 1 {
                let (a, b) = ((j * u.width + i) as usize, (j * u.width + i + 1) as usize);
                let inside = |q: usize| map.inside[q];
                if inside(a) && inside(b) {
                    var += (sum(map.texel(a)) - sum(map.texel(b))).abs();
                    n_var += 1;
                }
            }
        }
    }
    let var = var / n_var as f64;
    // Seams: x = 0 between surfaces (0, 1) and (2, 3); z = 0 between (0, 2) and (1, 3).
    let seams = [
        (0, 1, Vec3::X),
        (2, 3, Vec3::X),
        (0, 2, Vec3::Z),
        (1, 3, Vec3::Z),
    ];
    for (a, b, across) in seams {
        let along = if across == Vec3::X { Vec3::Z } else { Vec3::X };
        // The seam's segment: the shared edge, from −f (surface 0's edges) or from 0.
        let start = if a == 0 { -f } else { 0.0 };
        let (ca, cb) = (chart_of_surface(a), chart_of_surface(b));
        let mut jump = 0.0;
        let n = 200;
        for i in 0..n {
            let t = start + f * (i as f32 + 0.5) / n as f32;
            let p = along * t;
            jump += (sum(at(ca, p)) - sum(at(cb, p))).abs();
        }
        let jump = jump / n as f64;
        eprintln!("seam {a}|{b}: mean jump {jump:.5}, neighbouring texels {var:.5}");
        assert!(jump <= var, "seam {a}|{b}: {jump} > {var}");
    }
}

/// An atlas whose texels would need more than the memory limit is refused before any is
/// allocated, naming its size and what it needs; at the limit it bakes.
#[test]
fn an_atlas_past_the_memory_limit_is_refused() {
    use radiosity::bake::lightmap::{bytes_per_texel, LightmapError};
    let scene = radiosity::scene::builtin::cornell();
    let s = solved(&scene, 300);
    let vertex = radiosity::render::vertex_radiosity(&s.mesh, &s.radiosity);
    let params = |limit: u64| LightmapParams {
        density: Density::AtlasSize(64),
        direct: 1,
        indirect: 4,
        memory_limit: limit,
        ..Default::default()
    };
    let err = bake(&scene, s.surfaces(), &vertex, &params(1 << 10)).unwrap_err();
    let LightmapError::TooLarge {
        width,
        height,
        needed,
        ..
    } = err
    else {
        panic!("{err}")
    };
    assert_eq!(
        needed,
        width as u64 * height as u64 * bytes_per_texel(4, false)
    );
    // The slimmed bake (issue 59): 22 bytes a texel at the default spacing, 145 before.
    assert_eq!(bytes_per_texel(4, false), 22);
    assert!(err_text(&params(1 << 10), &scene, &s).contains("lightmap needs about"));
    assert!(err_text(&params(1 << 10), &scene, &s).contains("64 × 64"));
    assert!(bake(&scene, s.surfaces(), &vertex, &params(needed)).is_ok());
}

fn err_text(p: &LightmapParams, scene: &Scene, s: &Solution) -> String {
    let vertex = radiosity::render::vertex_radiosity(&s.mesh, &s.radiosity);
    bake(scene, s.surfaces(), &vertex, p)
        .unwrap_err()
        .to_string()
}

/// A glTF of one square (−1..1 in x and y, facing +z) whose `TEXCOORD_1` spans the unit
/// square (top-left corner (0, 0)), lit by a `MOZ_lightmap` of intensity `intensity` on the
/// PNG `png`, with a camera at (0, 0, 3) looking down −z seeing ±1.5.
fn gradient_glb(png: &[u8], intensity: f64) -> Vec<u8> {
    let mut bin: Vec<u8> = Vec::new();
    let pos: [[f32; 3]; 4] = [[-1., 1., 0.], [1., 1., 0.], [1., -1., 0.], [-1., -1., 0.]];
    let uv: [[f32; 2]; 4] = [[0., 0.], [1., 0.], [1., 1.], [0., 1.]];
    for p in pos.iter().flatten().chain(uv.iter().flatten()) {
        bin.extend_from_slice(&p.to_le_bytes());
    }
    for i in [0u32, 3, 2, 0, 2, 1] {
        bin.extend_from_slice(&i.to_le_bytes());
    }
    let png_at = bin.len();
    bin.extend_from_slice(png);
    while bin.len() % 4 != 0 {
        bin.push(0);
    }
    let json = serde_json::json!({
        "asset": {"version": "2.0"},
        "extensionsUsed": ["MOZ_lightmap"],
        "scene": 0,
        "scenes": [{"nodes": [0, 1]}],
        "nodes": [{"mesh": 0}, {"camera": 0, "translation": [0.0, 0.0, 3.0]}],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 2.0 * (0.5f64).atan(), "znear": 0.01}}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1, "TEXCOORD_1": 1},
            "indices": 2, "material": 0}]}],
        "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [1.0, 1.0, 1.0, 1.0], "metallicFactor": 0.0},
            "extensions": {"MOZ_lightmap": {"index": 0, "texCoord": 1, "intensity": intensity}}}],
        "textures": [{"source": 0, "sampler": 0}],
        "samplers": [{"magFilter": 9729, "minFilter": 9729, "wrapS": 33071, "wrapT": 33071}],
        "images": [{"bufferView": 3, "mimeType": "image/png"}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
             "min": [-1.0, -1.0, 0.0], "max": [1.0, 1.0, 0.0]},
            {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC2"},
            {"bufferView": 2, "componentType": 5125, "count": 6, "type": "SCALAR"}
        ],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 48},
            {"buffer": 0, "byteOffset": 48, "byteLength": 32},
            {"buffer": 0, "byteOffset": 80, "byteLength": 24},
            {"buffer": 0, "byteOffset": png_at, "byteLength": png.len()}
        ],
        "buffers": [{"byteLength": bin.len()}]
    });
    let mut text = serde_json::to_vec(&json).unwrap();
    while text.len() % 4 != 0 {
        text.push(b' ');
    }
    let mut out = b"glTF".to_vec();
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&((28 + text.len() + bin.len()) as u32).to_le_bytes());
    out.extend_from_slice(&(text.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&text);
    out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(&bin);
    out
}

/// An 8-bit RGB PNG of `w × h` pixels.
fn png_rgb(w: u32, h: u32, rgb: &[u8]) -> Vec<u8> {
    let mut png = Vec::new();
    image::ImageEncoder::write_image(
        image::codecs::png::PngEncoder::new(&mut png),
        rgb,
        w,
        h,
        image::ExtendedColorType::Rgb8,
    )
    .unwrap();
    png
}

/// IEC 61966-2-1's decoding, written out here (the test's own reference).
fn srgb_decode(e: f64) -> f64 {
    if e <= 0.04045 {
        e / 12.92
    } else {
        ((e + 0.055) / 1.055).powf(2.4)
    }
}

/// `view` of a square lit by a 2 × 2 lightmap: red 0 → 255 left to right, blue 0 → 255 top to
/// bottom, green 128 everywhere, intensity π/2. Bilinear filtering of the decoded texels with
/// clamped edges makes red `clamp(2u − ½, 0, 1)` and blue `clamp(2v − ½, 0, 1)`, green
/// `srgb⁻¹(128/255)`, all times intensity/π = ½: every pixel inside the square must show that
/// at its centre's (u, v). Tolerance 0.003: a pixel is the mean over its area (16 stratified
/// rays), which differs from the centre's value only at the clamp's kinks, by at most
/// slope × pixel / 8 = 1 × 0.0156 / 8 = 0.002, plus the stratified jitter's noise.
#[test]
fn view_renders_a_known_lightmap_gradient() {
    let rgb = [0, 128, 0, 255, 128, 0, 0, 128, 255, 255, 128, 255];
    let glb = gradient_glb(&png_rgb(2, 2, &rgb), std::f64::consts::PI / 2.0);
    let path =
        std::env::temp_dir().join(format!("radiosity-lm-gradient-{}.glb", std::process::id()));
    std::fs::write(&path, &glb).unwrap();
    let view = radiosity::render::baked::BakedView::load_lightmap(&path)
        .unwrap()
        .expect("a lightmapped file");
    let (w, h) = (96u32, 96u32);
    let image = view.render(
        &view.default_camera(),
        &radiosity::render::RenderParams {
            width: w,
            height: h,
            samples_per_pixel: 16,
            seed: 3,
        },
        &Silent,
    );
    let green = 0.5 * srgb_decode(128.0 / 255.0);
    let (mut checked, mut worst) = (0, 0.0f64);
    for py in 0..h {
        for px in 0..w {
            let x = ((px as f64 + 0.5) / w as f64 * 2.0 - 1.0) * 1.5;
            let y = (1.0 - (py as f64 + 0.5) / h as f64 * 2.0) * 1.5;
            if x.abs() > 0.95 || y.abs() > 0.95 {
                continue;
            }
            let (u, v) = ((x + 1.0) / 2.0, (1.0 - y) / 2.0);
            let want = [
                0.5 * (2.0 * u - 0.5).clamp(0.0, 1.0),
                green,
                0.5 * (2.0 * v - 0.5).clamp(0.0, 1.0),
            ];
            let got = image.at(px, py);
            for c in 0..3 {
                let d = (got[c] as f64 - want[c]).abs();
                worst = worst.max(d);
                assert!(
                    d <= 3e-3,
                    "pixel ({px}, {py}) channel {c}: {} vs {}",
                    got[c],
                    want[c]
                );
            }
            checked += 1;
        }
    }
    eprintln!("gradient: {checked} pixels, worst difference {worst:.5}");
    assert!(checked > 3000);
    std::fs::remove_file(&path).unwrap();
}

/// Hostile lightmap images are refused on one line naming the file and the place: an image
/// claiming more pixels than its bytes can hold, and a texture index past the list.
#[test]
fn hostile_lightmaps_are_refused() {
    let dir = std::env::temp_dir();
    // A PNG whose header claims 16384 × 16384 pixels, with 2×2 pixels of data.
    let mut png = png_rgb(2, 2, &[0; 12]);
    png[16..20].copy_from_slice(&16384u32.to_be_bytes());
    png[20..24].copy_from_slice(&16384u32.to_be_bytes());
    let path = dir.join(format!("radiosity-lm-huge-{}.glb", std::process::id()));
    std::fs::write(&path, gradient_glb(&png, 1.0)).unwrap();
    let err = radiosity::render::baked::BakedView::load_lightmap(&path)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("radiosity-lm-huge") && err.contains("images[0]"),
        "{err}"
    );
    assert!(!err.contains('\n'), "{err}");
    // A MOZ_lightmap naming texture 7 of 1.
    let glb = gradient_glb(&png_rgb(2, 2, &[0; 12]), 1.0);
    let mut b = glb.clone();
    let at = glb.windows(9).position(|w| w == b"\"index\":0").unwrap();
    b[at + 8] = b'7';
    let bad = dir.join(format!("radiosity-lm-index-{}.glb", std::process::id()));
    std::fs::write(&bad, &b).unwrap();
    let err = radiosity::render::baked::BakedView::load_lightmap(&bad)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("materials[0].extensions.MOZ_lightmap: no texture 7"),
        "{err}"
    );
    std::fs::remove_file(&bad).unwrap();
    std::fs::remove_file(&path).unwrap();
}

/// The display value of lightmap `map` at `uv` as the PNG holds it before quantisation:
/// `min(1, B · scale)` per texel, then bilinear with clamped edges (the test's own sampler).
fn display_sample(map: &Lightmap, atlas: u32, scale: f64, uv: [f32; 2]) -> [f64; 3] {
    let (w, h) = (map.width() as f64, map.height() as f64);
    let x = (uv[0] as f64 * w - 0.5).clamp(0.0, w - 1.0);
    let y = (uv[1] as f64 * h - 0.5).clamp(0.0, h - 1.0);
    let (x0, y0) = (x.floor(), y.floor());
    let (fx, fy) = (x - x0, y - y0);
    let at = |i: f64, j: f64| {
        let (i, j) = (i.min(w - 1.0) as usize, j.min(h - 1.0) as usize);
        let b = map.atlas_texels(atlas)[j * map.width() as usize + i];
        b.map(|c| (c as f64 * scale).clamp(0.0, 1.0))
    };
    let (a, b, c, d) = (
        at(x0, y0),
        at(x0 + 1.0, y0),
        at(x0, y0 + 1.0),
        at(x0 + 1.0, y0 + 1.0),
    );
    std::array::from_fn(|k| {
        a[k] * (1.0 - fx) * (1.0 - fy)
            + b[k] * fx * (1.0 - fy)
            + c[k] * (1.0 - fx) * fy
            + d[k] * fx * fy
    })
}

/// Points on each face of `map`'s unwrap (a 4 × 4 grid of barycentric points a triangle):
/// (face, point, normal, UV).
fn face_points(map: &Lightmap) -> Vec<(usize, Vec3, Vec3, [f32; 2])> {
    let u = &map.unwrap;
    let mut out = Vec::new();
    for (f, p) in u.mesh.patches.iter().enumerate() {
        for t in p.triangles() {
            for i in 0..4 {
                for j in 0..4 - i {
                    let (a, b) = ((i as f32 + 0.3) / 4.0, (j as f32 + 0.3) / 4.0);
                    let w = [1.0 - a - b, a, b];
                    let x: Vec3 = (0..3).map(|k| u.mesh.vertices[t[k] as usize] * w[k]).sum();
                    let uv = [0, 1].map(|c| (0..3).map(|k| u.uv[t[k] as usize][c] * w[k]).sum());
                    out.push((f, x, p.normal, uv));
                }
            }
        }
    }
    out
}

/// What a baked view shows at the surface point `x` (normal `n`): the front hit of a ray
/// arriving along −n.
fn shown_at(view: &radiosity::render::baked::BakedView, x: Vec3, n: Vec3, lift: f32) -> [f64; 3] {
    let ray = radiosity::geom::Ray::new(x + n * lift, -n);
    let hit = view
        .bvh
        .closest_hit(&ray, 2.0 * lift)
        .expect("the view's surface is there");
    let s = view.shown(&hit);
    [s.r, s.g, s.b]
}

/// The Cornell box baked with `--bake lightmap`, written and shown by `view`: at points on
/// every face, what the view shows equals the baked atlas's display value `min(1, B · scale)`
/// (bilinear at the point's UVs) within the PNG's quantisation, 0.5/255 of the sRGB code
/// times the decoding's largest slope (2.275 at 1): 0.00446. And each quad's mean matches the
/// vertex-colour bake of the same solution viewed the same way, within 4 % of the brightest
/// channel (or 0.01): the two differ by the method, the lightmap's exact direct light against
/// the patch mesh's interpolation (the block's shadow, the light's penumbra), not by the
/// file formats.
#[test]
fn cornell_lightmap_view_matches_its_atlas_and_the_vertex_bake() {
    let scene = radiosity::scene::builtin::cornell();
    let s = solved(&scene, 3000);
    let scale = s.auto_exposure() as f64;
    let params = LightmapParams {
        density: Density::AtlasSize(192),
        direct: 8,
        indirect: 64,
        ..Default::default()
    };
    let map = baked(&scene, &s, &params);
    let dir = std::env::temp_dir();
    let lm = dir.join(format!("radiosity-lm-view-{}.glb", std::process::id()));
    write_lightmap_gltf(
        &lm,
        &LightmapBake {
            scene: &scene,
            lightmap: &map,
            scale: scale as f32,
            camera: None,
        },
        true,
    )
    .unwrap();
    let vb = dir.join(format!("radiosity-lm-vertex-{}.glb", std::process::id()));
    let vertex = s.vertex_display_radiosity();
    radiosity::export::bake::write(
        &vb,
        &radiosity::export::bake::Bake {
            scene: &scene,
            mesh: &s.mesh,
            vertex_radiosity: &vertex,
            scale: scale as f32,
            camera: None,
        },
    )
    .unwrap();
    let view = radiosity::render::baked::BakedView::load_lightmap(&lm)
        .unwrap()
        .unwrap();
    let vview = radiosity::render::baked::BakedView::load(&vb).unwrap();
    let lift = 1e-3 * scene.bounds().diagonal();
    let quant = 2.2749 * 0.5 / 255.0 + 1e-5;
    let faces = map.unwrap.mesh.len();
    let mut sums = vec![([0.0f64; 3], [0.0f64; 3], 0usize); faces];
    let mut worst = 0.0f64;
    for (f, x, n, uv) in face_points(&map) {
        let got = shown_at(&view, x, n, lift);
        let want = display_sample(&map, 0, scale, uv);
        for c in 0..3 {
            let d = (got[c] - want[c]).abs();
            worst = worst.max(d);
            assert!(
                d <= quant,
                "face {f} at {x:?}: {got:?} vs the atlas's {want:?}"
            );
        }
        let v = shown_at(&vview, x, n, lift);
        let e = &mut sums[f];
        for c in 0..3 {
            e.0[c] += got[c];
            e.1[c] += v[c];
        }
        e.2 += 1;
    }
    eprintln!("view against the atlas: worst {worst:.5} (limit {quant:.5})");
    let mut worst_rel = 0.0f64;
    for (f, (a, b, n)) in sums.iter().enumerate() {
        let (a, b) = (a.map(|x| x / *n as f64), b.map(|x| x / *n as f64));
        let top = a.iter().chain(b.iter()).fold(0.0f64, |m, x| m.max(*x));
        for c in 0..3 {
            let d = (a[c] - b[c]).abs();
            worst_rel = worst_rel.max(d / top.max(0.25));
            assert!(
                d <= (0.04 * top).max(0.01),
                "face {f}: lightmap mean {a:?}, vertex bake {b:?}"
            );
        }
    }
    eprintln!("per-quad means, lightmap against vertex bake: worst {worst_rel:.4} of the brightest channel");
    std::fs::remove_file(&lm).unwrap();
    std::fs::remove_file(&vb).unwrap();
}

/// A lightmap in several atlases shown by `view`: each material's `MOZ_lightmap` names its
/// atlas's texture, so at points on every face what the view shows equals the display value
/// of the face's own atlas (bilinear at the point's UVs) within the PNG's quantisation, as in
/// the one-atlas test above; faces of every atlas are checked.
#[test]
fn view_shows_each_face_from_its_atlas() {
    let scene = radiosity::scene::builtin::cornell();
    let s = solved(&scene, 300);
    let scale = s.auto_exposure() as f64;
    let params = LightmapParams {
        density: Density::Both(12.0, 64),
        direct: 4,
        indirect: 16,
        ..Default::default()
    };
    let map = baked(&scene, &s, &params);
    assert!(map.atlases() >= 2, "{} atlases", map.atlases());
    let lm = std::env::temp_dir().join(format!("radiosity-lm-atlases-{}.glb", std::process::id()));
    write_lightmap_gltf(
        &lm,
        &LightmapBake {
            scene: &scene,
            lightmap: &map,
            scale: scale as f32,
            camera: None,
        },
        true,
    )
    .unwrap();
    let view = radiosity::render::baked::BakedView::load_lightmap(&lm)
        .unwrap()
        .unwrap();
    let lift = 1e-3 * scene.bounds().diagonal();
    let quant = 2.2749 * 0.5 / 255.0 + 1e-5;
    let mut per_atlas = vec![0usize; map.atlases() as usize];
    for (f, x, n, uv) in face_points(&map) {
        let a = map.unwrap.atlas_of(f as u32);
        let got = shown_at(&view, x, n, lift);
        let want = display_sample(&map, a, scale, uv);
        for c in 0..3 {
            assert!(
                (got[c] - want[c]).abs() <= quant,
                "face {f} (atlas {a}) at {x:?}: {got:?} vs the atlas's {want:?}"
            );
        }
        per_atlas[a as usize] += 1;
    }
    assert!(per_atlas.iter().all(|n| *n > 0), "{per_atlas:?}");
    std::fs::remove_file(&lm).unwrap();
}

/// A glTF that already has `TEXCOORD_1` (written by a first bake) baked again on its own UV
/// set: the output's `TEXCOORD_1` at every triangle corner equals the input's bit for bit, the
/// texels that lie on the surface are the same ones (the layout is the input's), and the
/// Khronos validator passes the file with no errors and no warnings.
#[test]
fn an_existing_texcoord_1_is_kept_bit_for_bit() {
    let scene = radiosity::scene::builtin::cornell();
    let s = solved(&scene, 1500);
    let params = LightmapParams {
        density: Density::AtlasSize(128),
        direct: 4,
        indirect: 32,
        ..Default::default()
    };
    let first = baked(&scene, &s, &params);
    let dir = std::env::temp_dir();
    let one = dir.join(format!("radiosity-lm-first-{}.glb", std::process::id()));
    let two = dir.join(format!("radiosity-lm-second-{}.glb", std::process::id()));
    let write = |path: &PathBuf, scene: &Scene, map: &Lightmap| {
        write_lightmap_gltf(
            path,
            &LightmapBake {
                scene,
                lightmap: map,
                scale: 1.0,
                camera: None,
            },
            true,
        )
        .unwrap()
    };
    write(&one, &scene, &first);
    let (input, set) = radiosity::scene::gltf::load_lightmap(&one, false, false).unwrap();
    let uv: Vec<[[f32; 2]; 3]> = set
        .uv
        .iter()
        .map(|u| u.expect("every triangle has TEXCOORD_1"))
        .collect();
    let s2 = solved(&input, 1500);
    let vertex = radiosity::render::vertex_radiosity(&s2.mesh, &s2.radiosity);
    let second =
        radiosity::bake::lightmap::bake_on(&input, s2.surfaces(), &vertex, &params, Some(&uv))
            .unwrap();
    assert_eq!((second.width(), second.height()), (128, 128));
    write(&two, &input, &second);
    let (output, set2) = radiosity::scene::gltf::load_lightmap(&two, false, false).unwrap();
    assert_eq!(output.polygons.len(), input.polygons.len());
    for (i, (p, q)) in input.polygons.iter().zip(&output.polygons).enumerate() {
        let (a, b) = (set.uv[i].unwrap(), set2.uv[i].unwrap());
        for (k, v) in q.vertices.iter().enumerate() {
            // The same corner, wherever it sits in the triangle's order.
            let j = (0..3)
                .min_by(|&x, &y| {
                    p.vertices[x]
                        .distance(*v)
                        .total_cmp(&p.vertices[y].distance(*v))
                })
                .unwrap();
            assert!(p.vertices[j].distance(*v) <= 1e-3, "polygon {i} moved");
            assert_eq!(
                b[k].map(f32::to_bits),
                a[j].map(f32::to_bits),
                "polygon {i} corner {k}"
            );
        }
    }
    // The same texels on the surface as the first bake's own layout.
    let differ = first
        .kind
        .iter()
        .zip(&second.kind)
        .filter(|(a, b)| (**a == Texel::Padding) != (**b == Texel::Padding))
        .count();
    eprintln!(
        "kept UV set: {} charts, {} surface texels (first bake {}), {differ} texels differ in being on the surface",
        second.unwrap.charts.len(),
        second.surface_texels(),
        first.surface_texels()
    );
    assert_eq!(second.unwrap.charts.len(), first.unwrap.charts.len());
    assert!(
        differ as f64 <= 1e-3 * first.surface_texels() as f64,
        "{differ}"
    );
    let report = crate::validator::validate_gltf_report(std::slice::from_ref(&two));
    assert!(report.contains(": 0 errors, 0 warnings"), "{report}");
    std::fs::remove_file(&one).unwrap();
    std::fs::remove_file(&two).unwrap();
}
