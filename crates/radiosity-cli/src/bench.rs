//! `radiosity bench`: ray-casting speed on incoherent form-factor rays, and the time to
//! converge the Cornell box (meshing, hierarchy, form factors and solve) to 1 % unshot energy.
//! Each figure is the median of `--runs` repetitions.

use crate::args::BenchArgs;
use anyhow::{bail, Result};
use radiosity::accel::Bvh;
use radiosity::formfactor::monte_carlo::{estimate_all_rows, trace_random_rays};
use radiosity::mesh::{Mesh, MeshParams};
use radiosity::pipeline::{self, Settings};
use radiosity::scene::builtin;
use radiosity::solve::{Method, SolverParams, System};
use std::time::Instant;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// Time per iteration of every solver on stored Monte Carlo form factors of the Cornell box.
fn solvers(sizes: &[usize], runs: usize) -> Result<()> {
    let scene = builtin::cornell();
    println!("solver time per iteration, Cornell box, stored sparse F (256 rays per row), median of {runs}:");
    println!(
        "{:>7} {:>9} {:<20} {:>10} {:>12} {:>14}",
        "patches", "nnz", "method", "iterations", "seconds", "µs/iteration"
    );
    for &n in sizes {
        let mesh = Mesh::build(&scene, MeshParams::Patches(n))?;
        let bvh = Bvh::build(&mesh);
        let mut f = estimate_all_rows(&mesh, &bvh, 256, 1);
        let area: Vec<f64> = mesh.patches.iter().map(|p| p.area as f64).collect();
        let refl: Vec<_> = mesh
            .patches
            .iter()
            .map(|p| scene.materials[p.material as usize].reflectance)
            .collect();
        let emis: Vec<_> = mesh
            .patches
            .iter()
            .map(|p| scene.materials[p.material as usize].emission)
            .collect();
        let system = System {
            area: &area,
            reflectance: &refl,
            emission: &emis,
        };
        for method in Method::ALL {
            let iterations = match method {
                Method::Gauss => 1,
                Method::Stochastic => 200_000,
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
                let info = radiosity::solve::run(&mut *s, &mut f, &params, false, &mut |_, _| {});
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

/// Run the benchmark and print its table.
pub fn run(a: BenchArgs) -> Result<()> {
    if a.runs == 0 || a.rays == 0 || a.patches == 0 {
        bail!("--runs, --rays and --patches must be positive");
    }
    crate::settings::threads(a.threads)?;
    if let Some(sizes) = &a.solvers {
        if sizes.contains(&0) {
            bail!("--solvers: patch counts must be positive");
        }
        return solvers(sizes, a.runs);
    }
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
    trace_random_rays(&mesh, &bvh, a.rays / 10, 0);
    let mut rates = Vec::new();
    for r in 0..a.runs {
        let t = Instant::now();
        let hits = trace_random_rays(&mesh, &bvh, a.rays, r as u64 + 1);
        let s = t.elapsed().as_secs_f64();
        rates.push(a.rays as f64 / s);
        if hits == 0 {
            bail!("no ray hit anything: the benchmark scene is broken");
        }
    }
    println!(
        "ray casting: {:.2} M rays/s (median of {}; {} incoherent closest-hit rays each)",
        median(rates) / 1e6,
        a.runs,
        a.rays
    );
    let settings = Settings {
        mesh: MeshParams::Patches(a.patches),
        ..Default::default()
    };
    let mut times = Vec::new();
    let mut last = None;
    for _ in 0..a.runs {
        let t = Instant::now();
        let s = pipeline::solve(&scene, &settings, &mut |_| {})?;
        times.push(t.elapsed().as_secs_f64());
        last = Some(s);
    }
    let s = last.expect("at least one run");
    println!(
        "converge to {:.0}% unshot: {:.3} s (median of {}; {} patches, {} shots, {} rays, form factors {:.3} s)",
        100.0 * settings.params.tolerance,
        median(times),
        a.runs,
        s.mesh.len(),
        s.info.iterations,
        s.form_factors.rays,
        s.timings.form_factors
    );
    Ok(())
}
