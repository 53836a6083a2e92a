//! `radiosity bench --ranks SCENE`: the distributed methods over the ranks of this run.

use crate::args::RanksArgs;
use crate::median;
use anyhow::{Context, Result};
use radiosity::distributed::{Ranks, Report, Serial};
use radiosity::formfactor::Params;
use radiosity::mesh::MeshParams;
use radiosity::observe::Silent;
use radiosity::pipeline::{Settings, Uniform};
use radiosity::solve::{Solver, SolverParams};
use std::time::Instant;

/// One timed run: wall seconds, the solution's stage times and report.
struct Run {
    wall: f64,
    form_factors: f64,
    solve: f64,
    iterations: u64,
    sweeps: usize,
    report: Report,
    patches: usize,
    unshot: f64,
}

fn once(scene: &radiosity::scene::Scene, settings: &Settings, ranks: &Ranks<'_>) -> Result<Run> {
    ranks.barrier();
    let t = Instant::now();
    let (sol, report) = radiosity::pipeline::solve_over(scene, settings, Some(ranks), &Silent)?;
    let report = report.context("the method did not run over the ranks")?;
    ranks.barrier();
    Ok(Run {
        wall: t.elapsed().as_secs_f64(),
        form_factors: sol.timings.form_factors,
        solve: sol.timings.solve,
        iterations: sol.info.iterations,
        sweeps: report.sweeps.len(),
        report,
        patches: sol.mesh.len(),
        unshot: sol.info.unshot_fraction,
    })
}

/// Run the benchmark.
pub fn run(a: &RanksArgs) -> Result<()> {
    crate::positive(&[("--runs", a.runs), ("--patches", a.patches)])?;
    let scene_name = a.scene.as_str();
    let scene = radiosity_cli::load_scene(scene_name, a.solve.one_sided)?;
    let serial = Ranks::new(&Serial);
    let world = radiosity_cli::ranks::current().unwrap_or(&serial);
    let k = world.size();
    let threads = rayon::current_num_threads();
    println!(
        "radiosity-bench ranks {}: {} patches asked, {k} rank{} × {threads} thread{} ({})",
        scene.place(),
        a.patches,
        if k == 1 { "" } else { "s" },
        if threads == 1 { "" } else { "s" },
        world.communicator().describe()
    );
    println!("medians of {} runs; efficiency = T(1 rank) / (K × T(K ranks)), one rank measured first on rank 0 alone with the same threads", a.runs);
    println!(
        "{:<18} {:>7} {:>8} {:>8} {:>8} {:>9} {:>10} {:>9} {:>8} {:>8} {:>7} {:>7}",
        "method",
        "patches",
        "wall s",
        "ff s",
        "solve s",
        "iter",
        "s/iter",
        "MiB sent",
        "comm s",
        "balance",
        "1-rank",
        "effic."
    );
    for solver in [Solver::Jacobi, Solver::StochasticJacobi] {
        let params = SolverParams {
            tolerance: a.solve.tolerance,
            iteration_rays: a.solve.iteration_rays,
            gather_rays: a.solve.gather_rays,
            ..SolverParams::default()
        };
        params.validate()?;
        let settings = Settings::from(Uniform {
            mesh: MeshParams::Patches(a.patches),
            form_factors: Params::shooting(),
            solver,
            params,
            ..Uniform::default()
        });
        // One rank: rank 0 alone, the others waiting.
        let baseline = if k > 1 {
            let mut t = 0.0;
            if world.is_root() {
                let runs: Result<Vec<f64>> = (0..a.runs)
                    .map(|_| once(&scene, &settings, &serial).map(|r| r.wall))
                    .collect();
                t = median(runs?);
            }
            Some(world.agree(t))
        } else {
            None
        };
        let mut runs = Vec::with_capacity(a.runs);
        for _ in 0..a.runs {
            runs.push(once(&scene, &settings, world)?);
        }
        let wall = median(runs.iter().map(|r| r.wall).collect());
        let ff = median(runs.iter().map(|r| r.form_factors).collect());
        let solve = median(runs.iter().map(|r| r.solve).collect());
        let last = runs.last().expect("--runs is positive");
        let per_iteration = match solver {
            Solver::Jacobi => median(last.report.sweeps.iter().map(|s| s.seconds).collect()),
            _ => solve / last.iterations.max(1) as f64,
        };
        let iterations = match solver {
            Solver::Jacobi => format!("{} sw", last.sweeps),
            _ => format!("{}", last.iterations),
        };
        let comm = median(
            runs.iter()
                .map(|r| {
                    r.report
                        .traffic
                        .iter()
                        .map(|t| t.seconds)
                        .fold(0.0, f64::max)
                })
                .collect(),
        );
        println!(
            "{:<18} {:>7} {:>8.3} {:>8.3} {:>8.3} {:>9} {:>10.5} {:>9.2} {:>8.3} {:>8.2} {:>7} {:>7}",
            solver.name(),
            last.patches,
            wall,
            ff,
            solve,
            iterations,
            per_iteration,
            last.report.bytes_sent() as f64 / (1 << 20) as f64,
            comm,
            last.report.balance(),
            baseline.map_or("—".into(), |b| format!("{b:.3}")),
            baseline.map_or("—".into(), |b| format!("{:.2}", b / (k as f64 * wall))),
        );
        let _ = last.unshot;
        // The parts of an iteration, for the model of larger runs (rank 0's view).
        let n = last.patches as f64;
        match (&last.report.shooting, solver) {
            (Some(t), _) => {
                let it = last.iterations.max(1) as f64;
                println!(
                    "{:<18} per iteration: {:.0} rays ({:.1} a patch), trace {:.4} s, exchange {:.4} s ({:.2} MiB of hits a rank), reduce {:.4} s (serial, {:.1} ns a ray)",
                    "",
                    t.rays as f64 / it,
                    t.rays as f64 / it / n,
                    t.trace / it,
                    t.exchange / it,
                    4.0 * t.rays as f64 / it / (1 << 20) as f64,
                    t.reduce / it,
                    1e9 * t.reduce / t.rays.max(1) as f64
                );
            }
            (None, Solver::Jacobi) => {
                let sweeps = &last.report.sweeps;
                let s = sweeps.len().max(1) as f64;
                let compute = sweeps
                    .iter()
                    .map(|w| w.seconds - w.communication)
                    .sum::<f64>()
                    / s;
                let exchange = sweeps.iter().map(|w| w.communication).sum::<f64>() / s;
                let nnz: u64 = last.report.stored_entries.iter().sum();
                println!(
                    "{:<18} per sweep: {} entries of F ({:.1} a row), rows {:.4} s ({:.2} ns an entry a rank), exchange {:.4} s ({:.2} MiB of B and H a rank)",
                    "",
                    nnz,
                    nnz as f64 / n,
                    compute,
                    1e9 * compute * k as f64 / nnz.max(1) as f64,
                    exchange,
                    48.0 * n / (1 << 20) as f64
                );
            }
            _ => {}
        }
    }
    println!("ff: form factors (Jacobi's rows; stochastic Jacobi casts its rays in the solve); sw: sweeps; comm s: the most any rank spent in collectives (waiting included); balance: mean / busiest rank's work");
    Ok(())
}
