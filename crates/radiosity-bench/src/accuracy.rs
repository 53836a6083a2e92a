//! `radiosity bench --hierarchical SCENE`: the per-surface accuracy of hierarchical radiosity
//! (at each `--link-errors`) and of uniform meshes solved by progressive refinement (at each
//! `--sizes`), against path-traced surface means that know nothing of either
//! ([`radiosity::pipeline::path_surface_means`]). Emitters are left out of the errors (their
//! radiosity is mostly their own emission). Coincident twins (the same polygon twice, as when
//! a scene includes an object twice) are compared as one surface against the reference's group
//! mean, which lights every twin as the surface (the path tracer starts paths on each). A
//! shooting method lights whichever twin each ray meets first and leaves the other dark at
//! that spot, so the light of the place is the *sum* of the twins' radiosities; hierarchical
//! radiosity lights every twin as the surface, so it is any one of them (their largest).

use crate::args::{HierarchicalArgs, ReferenceTracer};
use anyhow::{bail, Context, Result};
use radiosity::hierarchical::Params as HierarchicalParams;
use radiosity::mesh::MeshParams;
use radiosity::pipeline::{self, Settings, Solution, Uniform};
use radiosity::Rgb;
use std::path::Path;
use std::time::Instant;

/// Surface means and their standard errors, from `path` or made and written there.
fn reference(
    a: &HierarchicalArgs,
    scene: &radiosity::scene::Scene,
    path: &Path,
) -> Result<Vec<(Rgb, Rgb)>> {
    if path.exists() {
        let text = std::fs::read_to_string(path)
            .with_context(|| format!("cannot read {}", path.display()))?;
        let mut out = Vec::new();
        for (k, line) in text.lines().enumerate().skip(1) {
            let v: Vec<f64> = line
                .split(',')
                .skip(1)
                .map(|t| t.trim().parse::<f64>())
                .collect::<Result<_, _>>()
                .with_context(|| format!("{}:{}: not a number", path.display(), k + 1))?;
            if v.len() != 6 {
                bail!(
                    "{}:{}: expected 7 columns (surface,b_r,b_g,b_b,se_r,se_g,se_b)",
                    path.display(),
                    k + 1
                );
            }
            out.push((Rgb::new(v[0], v[1], v[2]), Rgb::new(v[3], v[4], v[5])));
        }
        if out.len() != scene.polygons.len() {
            bail!(
                "{}: {} surfaces, but the scene has {}",
                path.display(),
                out.len(),
                scene.polygons.len()
            );
        }
        println!("reference   {} (read)", path.display());
        return Ok(out);
    }
    let t = Instant::now();
    let means = match a.reference_tracer {
        ReferenceTracer::Light => pipeline::light_surface_means(scene, a.reference_paths, 7)?,
        ReferenceTracer::Path => pipeline::path_surface_means(scene, a.reference_paths, 7)?,
    };
    let mut csv = String::from("surface,b_r,b_g,b_b,se_r,se_g,se_b\n");
    for (k, (b, se)) in means.iter().enumerate() {
        csv += &format!("{k},{},{},{},{},{},{}\n", b.r, b.g, b.b, se.r, se.g, se.b);
    }
    radiosity::export::write_text(path, &csv)?;
    println!(
        "reference   {} ({} {}, {:.1} s)",
        path.display(),
        a.reference_paths,
        match a.reference_tracer {
            ReferenceTracer::Light => "particles, light tracer",
            ReferenceTracer::Path => "paths, path tracer",
        },
        t.elapsed().as_secs_f64()
    );
    Ok(means)
}

/// The scene's polygons grouped by coincidence: each group the polygons with the same
/// vertices (as a set, to 10⁻⁶ of the scene's size) and the same side, in order.
fn twin_groups(scene: &radiosity::scene::Scene) -> Vec<Vec<usize>> {
    use radiosity::geom::{coincidence_key, coincidence_step, Vec3};
    use std::collections::HashMap;
    let step = coincidence_step(
        scene
            .polygons
            .iter()
            .flat_map(|p| p.vertices.iter().copied()),
    );
    let mut index: HashMap<Vec<i64>, usize> = HashMap::new();
    let mut groups: Vec<Vec<usize>> = Vec::new();
    for (k, p) in scene.polygons.iter().enumerate() {
        // Newell's normal: the side the polygon faces.
        let n = p
            .vertices
            .iter()
            .zip(p.vertices.iter().cycle().skip(1))
            .fold(Vec3::ZERO, |acc, (a, b)| acc + a.cross(*b))
            .normalize_or_zero();
        let key = coincidence_key(p.vertices.iter().copied(), n, step);
        let g = *index.entry(key).or_insert_with(|| {
            groups.push(Vec::new());
            groups.len() - 1
        });
        groups[g].push(k);
    }
    groups
}

/// Relative errors of a solution's surface means (channel sums), emitters and surfaces the
/// reference cannot resolve (standard error above 1 %) left out, twins as one surface: (mean,
/// worst, area-weighted L1, the reference's own noise floor of that L1).
fn errors(
    scene: &radiosity::scene::Scene,
    groups: &[Vec<usize>],
    s: &Solution,
    reference: &[(Rgb, Rgb)],
) -> (f64, f64, f64, f64) {
    let n = scene.polygons.len();
    let mut sum = vec![0.0f64; n];
    let mut area = vec![0.0f64; n];
    for (p, b) in s.mesh.patches.iter().zip(&s.radiosity) {
        sum[p.surface as usize] += b.sum() * p.area as f64;
        area[p.surface as usize] += p.area as f64;
    }
    let (mut total, mut worst, mut count) = (0.0, 0.0f64, 0usize);
    let (mut l1, mut floor, mut weight) = (0.0, 0.0, 0.0);
    for group in groups {
        let emits = group.iter().any(|&k| {
            scene.materials[scene.polygons[k].material]
                .emission
                .max_channel()
                > 0.0
        });
        let k = group[0];
        if emits || group.iter().any(|&j| area[j] <= 0.0) {
            continue;
        }
        let m = group.len() as f64;
        let b: f64 = group.iter().map(|&j| reference[j].0.sum()).sum::<f64>() / m;
        if b <= 0.0 {
            continue;
        }
        let se = (group
            .iter()
            .map(|&j| {
                let se = reference[j].1;
                se.r * se.r + se.g * se.g + se.b * se.b
            })
            .sum::<f64>()
            / (m * m))
            .sqrt();
        let means = group.iter().map(|&j| sum[j] / area[j]);
        let run = if s.hierarchy.is_some() {
            means.fold(f64::MIN, f64::max)
        } else {
            means.sum()
        };
        let rel = (run - b) / b;
        l1 += (run - b).abs() * area[k];
        floor += se * (2.0 / std::f64::consts::PI).sqrt() * area[k];
        weight += b * area[k];
        if se / b > 0.01 {
            continue;
        }
        total += rel.abs();
        worst = worst.max(rel.abs());
        count += 1;
    }
    (
        total / count.max(1) as f64,
        worst,
        l1 / weight.max(f64::MIN_POSITIVE),
        floor / weight.max(f64::MIN_POSITIVE),
    )
}

/// Run the accuracy benchmark.
pub fn run(a: &HierarchicalArgs) -> Result<()> {
    let name = &a.scene;
    let scene = radiosity_cli::load_scene(name, a.one_sided)?;
    let path = a
        .reference
        .clone()
        .unwrap_or_else(|| std::path::PathBuf::from(format!("{}-surfaces.csv", scene.name)));
    let reference = reference(a, &scene, &path)?;
    let groups = twin_groups(&scene);
    let twins = scene.polygons.len() - groups.len();
    if twins > 0 {
        println!("twins       {twins} polygons coincide with an earlier one: each group compared as one surface");
    }
    println!(
        "{:<28} {:>9} {:>9} {:>8} {:>8} {:>8} {:>8} {:>8}",
        "method", "elements", "links", "wall s", "mean %", "worst %", "L1 %", "floor %"
    );
    let row = |label: String, s: &Solution, links: usize, wall: f64| {
        let (mean, worst, l1, floor) = errors(&scene, &groups, s, &reference);
        println!(
            "{label:<28} {:>9} {:>9} {:>8.2} {:>8.3} {:>8.3} {:>8.3} {:>8.3}",
            s.mesh.len(),
            links,
            wall,
            100.0 * mean,
            100.0 * worst,
            100.0 * l1,
            100.0 * floor
        );
    };
    let tolerance = a.tolerance.min(1e-4);
    let seeds = &a.solve_seeds;
    let tag = |seed: u64| {
        if seeds.len() > 1 {
            format!(" s{seed}")
        } else {
            String::new()
        }
    };
    for &e in a.link_errors.as_deref().unwrap_or(&[1e-4, 3e-5, 1e-5]) {
        for &seed in seeds {
            let settings = Settings::from(HierarchicalParams {
                link_error: e,
                tolerance,
                max_passes: a.passes.unwrap_or(HierarchicalParams::default().max_passes),
                seed,
                ..Default::default()
            });
            let t = Instant::now();
            let s = pipeline::solve(&scene, &settings, &radiosity::observe::Silent)?;
            let wall = t.elapsed().as_secs_f64();
            let links = s.hierarchy.as_ref().map_or(0, |h| h.hierarchy.links.len());
            row(format!("hierarchical {e:e}{}", tag(seed)), &s, links, wall);
        }
    }
    for &n in a.sizes.as_deref().unwrap_or(&[]) {
        for &seed in seeds {
            let mut u = Uniform {
                mesh: MeshParams::Patches(n),
                ..Uniform::default()
            };
            u.form_factors.rays = a.uniform_rays;
            u.set_seed(seed);
            u.params.tolerance = tolerance;
            let settings = Settings::from(u);
            let t = Instant::now();
            let s = pipeline::solve(&scene, &settings, &radiosity::observe::Silent)?;
            let wall = t.elapsed().as_secs_f64();
            row(format!("uniform progressive {n}{}", tag(seed)), &s, 0, wall);
        }
    }
    Ok(())
}
