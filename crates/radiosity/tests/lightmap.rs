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
