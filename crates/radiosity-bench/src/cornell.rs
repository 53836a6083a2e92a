//! `radiosity-bench cornell`, `solvers`, `form-factors` and `city`: ray-casting speed on incoherent form-factor rays, and the time to
//! converge the Cornell box (meshing, hierarchy, form factors and solve) to 1 % unshot energy.
//! Each figure is the median of `--runs` repetitions.

use crate::args::{CornellArgs, SolversArgs};
use crate::median;
use anyhow::{bail, Result};
use radiosity::accel::Bvh;
use radiosity::formfactor::monte_carlo::photon_ray;
use radiosity::formfactor::{
    closed_form, Estimator, FormFactorMethod, Params as FfParams, Storage,
};
use radiosity::geom::Ray;
use radiosity::geom::Vec3;
use radiosity::mesh::{Mesh, MeshParams};
use radiosity::pipeline::{self, Settings, Uniform};
use radiosity::sampling::stream;
use radiosity::scene::builtin;
use radiosity::solve::{Solver, SolverParams};
use rand::Rng;
use rayon::prelude::*;
use std::time::Instant;

/// Time per iteration of every solver on stored Monte Carlo form factors of the Cornell box.
pub fn solvers(a: &SolversArgs) -> Result<()> {
    let (sizes, runs) = (&a.sizes, a.runs);
    crate::positive(&[("--runs", runs)])?;
    if sizes.contains(&0) {
        bail!("patch counts must be positive");
    }
    let scene = builtin::cornell();
    println!("solver time per iteration, Cornell box, stored sparse F (256 rays per row), median of {runs}:");
    println!(
        "{:>7} {:>9} {:<20} {:>10} {:>12} {:>14}",
        "patches", "nnz", "method", "iterations", "seconds", "µs/iteration"
    );
    for &n in sizes {
        let mesh = Mesh::build(&scene, MeshParams::Patches(n))?;
        let bvh = Bvh::build(&mesh);
        let mut f = radiosity::formfactor::Estimator::new(
            &mesh,
            &bvh,
            radiosity::formfactor::Params::monte_carlo(256, 1),
        )
        .expect("valid parameters")
        .sparse_matrix();
        let data = radiosity::mesh::patch_system(&scene, &mesh);
        let system = &data;
        for method in Solver::ALL {
            let iterations = match method {
                Solver::Gauss => 1,
                Solver::Stochastic => 200_000,
                Solver::StochasticJacobi => 4,
                _ => mesh.len() as u64,
            };
            let params = SolverParams {
                tolerance: 0.0,
                max_iterations: iterations,
                memory_limit: 8 << 30,
                ..Default::default()
            };
            let mut times = Vec::new();
            let mut done = 0;
            for _ in 0..runs {
                let t = Instant::now();
                let mut s = radiosity::solve::start(method, system, &mut f, &params)?;
                let info = radiosity::solve::run(&mut *s, &mut f, &params, false, &mut |_, _| true);
                times.push(t.elapsed().as_secs_f64());
                done = info.iterations;
            }
            let t = median(times);
            println!(
                "{:>7} {:>9} {:<20} {:>10} {:>12.4} {:>14.2}",
                mesh.len(),
                f.nnz(),
                method.name(),
                done,
                t,
                1e6 * t / done.max(1) as f64
            );
        }
    }
    Ok(())
}

/// Ray casting and convergence on the Cornell box.
pub fn run(a: &CornellArgs) -> Result<()> {
    crate::positive(&[
        ("--runs", a.runs),
        ("--rays", a.rays),
        ("--patches", a.patches),
    ])?;
    let count = a.rays;
    let scene = builtin::cornell();
    let mesh = Mesh::build(&scene, MeshParams::Patches(a.patches))?;
    let t = Instant::now();
    let bvh = Bvh::build(&mesh);
    let build = t.elapsed().as_secs_f64();
    let info = bvh.info();
    println!(
        "cornell: {} patches, {} triangles, hierarchy {} nodes, depth {}, built in {:.3} s; {} threads",
        mesh.len(),
        info.triangles,
        info.nodes,
        info.depth,
        build,
        rayon::current_num_threads()
    );
    // Warm-up, then timed runs.
    trace_random_rays(&mesh, &bvh, count / 10, 0);
    let mut rates = Vec::new();
    for r in 0..a.runs {
        let t = Instant::now();
        let hits = trace_random_rays(&mesh, &bvh, count, r as u64 + 1);
        let s = t.elapsed().as_secs_f64();
        rates.push(count as f64 / s);
        if hits == 0 {
            bail!("no ray hit anything: the benchmark scene is broken");
        }
    }
    println!(
        "ray casting: {:.2} M rays/s (median of {}; {} incoherent closest-hit rays each)",
        median(rates) / 1e6,
        a.runs,
        count
    );
    let settings = Settings::from(Uniform {
        mesh: MeshParams::Patches(a.patches),
        ..Uniform::default()
    });
    let mut times = Vec::new();
    let mut last = None;
    for _ in 0..a.runs {
        let t = Instant::now();
        let s = pipeline::solve(&scene, &settings, &radiosity::observe::Silent)?;
        times.push(t.elapsed().as_secs_f64());
        last = Some(s);
    }
    let s = last.expect("at least one run");
    println!(
        "converge to {:.0}% unshot: {:.3} s (median of {}; {} patches, {} shots, {} rays, form factors {:.3} s)",
        100.0 * settings.tolerance(),
        median(times),
        a.runs,
        s.mesh.len(),
        s.info.iterations,
        s.form_factors.rays,
        s.timings.form_factors
    );
    Ok(())
}

fn ff_estimate(scene: &radiosity::scene::Scene, params: FfParams) -> Result<f64> {
    let mesh = Mesh::build(scene, MeshParams::Faces)?;
    let bvh = Bvh::build(&mesh);
    let m = Estimator::new(&mesh, &bvh, params)?
        .matrix(Storage::Sparse, &radiosity::observe::Silent)
        .into_sparse();
    Ok(m.row_entries(0)
        .iter()
        .find(|e| e.0 == 1)
        .map_or(0.0, |e| e.1 as f64))
}

fn unit_squares() -> Vec<(&'static str, radiosity::scene::Scene, f64)> {
    use radiosity::scene::{Material, Scene};
    let v = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
    let scene = |polys: Vec<Vec<Vec3>>| {
        Scene::of_polygons(
            "squares",
            Material::diffuse("m", radiosity::Rgb::splat(0.5)),
            polys,
        )
    };
    vec![
        (
            "parallel",
            scene(vec![
                vec![v(0., 0., 0.), v(1., 0., 0.), v(1., 1., 0.), v(0., 1., 0.)],
                vec![v(0., 0., 1.), v(0., 1., 1.), v(1., 1., 1.), v(1., 0., 1.)],
            ]),
            closed_form::parallel_rectangles(1.0, 1.0, 1.0),
        ),
        (
            "perpendicular",
            scene(vec![
                vec![v(0., 0., 0.), v(0., 0., 1.), v(1., 0., 1.), v(1., 0., 0.)],
                vec![v(0., 0., 0.), v(1., 0., 0.), v(1., 1., 0.), v(0., 1., 0.)],
            ]),
            closed_form::perpendicular_rectangles(1.0, 1.0, 1.0),
        ),
    ]
}

/// Errors against closed forms, and time per row as N grows.
pub fn form_factor_table(runs: usize) -> Result<()> {
    crate::positive(&[("--runs", runs)])?;
    println!("relative error against Howell's closed forms (unit squares, one patch per face; K = 16 points):");
    println!("| method | setting | parallel (F = 0.19982) | perpendicular (F = 0.20004) |");
    println!("|---|---|---|---|");
    let cases = unit_squares();
    let row = |method: FormFactorMethod, label: String, params: FfParams| -> Result<()> {
        let mut cells = Vec::new();
        for (_, scene, exact) in &cases {
            let f = ff_estimate(scene, params)?;
            cells.push(format!("{:+.2e}", (f - exact) / exact));
        }
        println!("| {method} | {label} | {} | {} |", cells[0], cells[1]);
        Ok(())
    };
    for method in [
        FormFactorMethod::Hemicube,
        FormFactorMethod::Hemisphere,
        FormFactorMethod::Tetrahedron,
    ] {
        for p in [32u32, 128, 512] {
            row(
                method,
                format!("P = {p}"),
                FfParams {
                    method,
                    resolution: p,
                    ..Default::default()
                },
            )?;
        }
    }
    for n in [10_000u32, 100_000, 1_000_000] {
        row(
            FormFactorMethod::MonteCarlo,
            format!("n = {n}"),
            FfParams {
                method: FormFactorMethod::MonteCarlo,
                rays: n,
                ..Default::default()
            },
        )?;
    }
    row(
        FormFactorMethod::Analytic,
        "exact quadrature".into(),
        FfParams {
            method: FormFactorMethod::Analytic,
            ..Default::default()
        },
    )?;

    println!();
    println!("time per row on the Cornell box (default settings: P = 128, K = 16, n = 1,000,000 rays; median over rows spread through the mesh, {} threads):", rayon::current_num_threads());
    println!("| method | N = 1,000 | N = 4,000 | N = 16,000 | fitted exponent |");
    println!("|---|---|---|---|---|");
    let scene = builtin::cornell();
    let sizes = [1000usize, 4000, 16_000];
    let meshes: Vec<Mesh> = sizes
        .iter()
        .map(|&n| Mesh::build(&scene, MeshParams::Patches(n)))
        .collect::<Result<_, _>>()?;
    let bvhs: Vec<Bvh> = meshes.iter().map(Bvh::build).collect();
    for method in FormFactorMethod::ALL {
        let mut times = Vec::new();
        for (mesh, bvh) in meshes.iter().zip(&bvhs) {
            let est = Estimator::new(
                mesh,
                bvh,
                FfParams {
                    method,
                    ..Default::default()
                },
            )?;
            let mut scratch = radiosity::formfactor::Scratch::default();
            let mut out = Vec::new();
            let rows = (4 * runs).clamp(4, 24);
            let mut t_rows = Vec::new();
            for k in 0..rows {
                let i = (k * mesh.len()) / rows;
                let t = Instant::now();
                est.row(i, &mut scratch, &mut out);
                t_rows.push(t.elapsed().as_secs_f64());
            }
            times.push(median(t_rows));
        }
        let slope = (times[2] / times[0]).ln() / (sizes[2] as f64 / sizes[0] as f64).ln();
        println!(
            "| {method} | {:.2} ms | {:.2} ms | {:.2} ms | {slope:.2} |",
            1e3 * times[0],
            1e3 * times[1],
            1e3 * times[2]
        );
    }
    Ok(())
}

/// Peak resident memory (VmHWM) in bytes, from /proc/self/status.
fn peak_memory() -> Option<u64> {
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    let l = s.lines().find(|l| l.starts_with("VmHWM:"))?;
    Some(l.split_whitespace().nth(1)?.parse::<u64>().ok()? * 1024)
}

/// Reset the peak-memory counter (Linux: writing 5 to /proc/self/clear_refs).
fn reset_peak() {
    let _ = std::fs::write("/proc/self/clear_refs", "5");
}

/// The full face-to-face matrix of the city by Monte Carlo and by hemicube.
pub fn city() -> Result<()> {
    let scene = builtin::city(63);
    let mesh = Mesh::build(&scene, MeshParams::Faces)?;
    let bvh = Bvh::build(&mesh);
    println!(
        "city: {} facets, {} patches, {} threads",
        scene.polygons.len(),
        mesh.len(),
        rayon::current_num_threads()
    );
    for (label, params) in [
        (
            "monte-carlo, 10,000 rays per row",
            FfParams {
                method: FormFactorMethod::MonteCarlo,
                rays: 10_000,
                ..Default::default()
            },
        ),
        (
            "hemicube, P = 64, K = 1",
            FfParams {
                method: FormFactorMethod::Hemicube,
                resolution: 64,
                samples: 1,
                ..Default::default()
            },
        ),
    ] {
        reset_peak();
        let t = Instant::now();
        let m = Estimator::new(&mesh, &bvh, params)?
            .matrix(Storage::Sparse, &radiosity::observe::Silent)
            .into_sparse();
        let s = t.elapsed().as_secs_f64();
        let area: Vec<f64> = mesh.patches.iter().map(|p| p.area as f64).collect();
        let sum = radiosity::formfactor::summary(&m, &area);
        println!(
            "{label}: {s:.1} s, peak memory {} MiB, {} entries (fill {:.3}%), row sums {:.4} … {:.4}",
            peak_memory().map_or("?".to_string(), |b| (b >> 20).to_string()),
            m.nnz(),
            100.0 * sum.fill,
            sum.min_row_sum,
            sum.max_row_sum
        );
    }
    Ok(())
}

/// Trace `count` rays from random patches (uniform over patch indices), from uniform points in
/// cosine-distributed directions: the incoherent rays of form-factor estimation, without the
/// coherence of tracing one patch's row at a time. Returns how many hit a front side. For
/// measuring ray-casting speed.
pub fn trace_random_rays(mesh: &Mesh, bvh: &Bvh, count: usize, seed: u64) -> u64 {
    let offset = bvh.ray_offset();
    let n = mesh.len() as u64;
    let chunks = count.div_ceil(1024);
    (0..chunks)
        .into_par_iter()
        .map(|c| {
            let mut rng = stream(seed, u64::MAX, 0, c as u64);
            let todo = (count - c * 1024).min(1024);
            let mut rays = [Ray::new(glam::Vec3::ZERO, glam::Vec3::Z); 1024];
            for ray in &mut rays[..todo] {
                let i = ((rng.random::<u32>() as u64 * n) >> 32) as usize;
                *ray = photon_ray(mesh, i, offset, &mut rng);
            }
            let mut hits = [None; 1024];
            bvh.closest_hits(&rays[..todo], f32::INFINITY, &mut hits[..todo]);
            hits.iter().flatten().filter(|h| h.front).count() as u64
        })
        .sum()
}
