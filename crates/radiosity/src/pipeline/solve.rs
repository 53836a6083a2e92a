//! A scene solved: validate → mesh → hierarchy → form factors (stored or on demand) → the
//! chosen solver; or hierarchical radiosity over the scene's pieces.

use super::*;
use crate::accel::Bvh;
use crate::color::Rgb;
use crate::comm::Ranks;
use crate::distributed::rows::{self, RowBlock};
use crate::distributed::{not_distributed, Report, DISTRIBUTED_SOLVERS};
use crate::formfactor::{Estimator, FormFactorMethod, FormFactorStats, OnDemandRows, Storage};
use crate::mesh::{patch_system, Mesh, MeshParams};
use crate::observe::{Event, Observer, Stage};
use crate::scene::Scene;
use crate::solve::trace::Trace;
use crate::solve::SolveError;
use crate::solve::{Info, Solver};
use crate::system::{Operator, System};
use crate::Error;
use std::time::Instant;

/// Validate, mesh and solve `scene`, over `ranks` when given: a distributed method
/// ([`DISTRIBUTED_SOLVERS`], uniform meshing) or any method over more than one rank runs the
/// distributed pipeline (every rank returns the same solution, with the run's [`Report`]; a
/// method that cannot run over ranks is refused), everything else runs here alone.
pub fn solve_over(
    scene: &Scene,
    settings: &Settings,
    ranks: Option<&Ranks<'_>>,
    observer: &dyn Observer,
) -> Result<(Solution, Option<Report>), Error> {
    match ranks {
        Some(r)
            if r.size() > 1
                || settings
                    .uniform()
                    .is_some_and(|u| DISTRIBUTED_SOLVERS.contains(&u.solver)) =>
        {
            solve_distributed(scene, settings, r, observer).map(|(s, report)| (s, Some(report)))
        }
        _ => solve(scene, settings, observer).map(|s| (s, None)),
    }
}

/// Validate, mesh and solve `scene` in this process.
pub fn solve(
    scene: &Scene,
    settings: &Settings,
    observer: &dyn Observer,
) -> Result<Solution, Error> {
    scene.validate()?;
    let limit = settings.memory_limit.bytes();
    let u = match &settings.method {
        Method::Hierarchical(params) => return solve_hierarchical(scene, params, limit, observer),
        Method::Uniform(u) => u,
    };
    u.mesh.validate()?;
    let store = u.stores_rows();
    let memory = MemoryCheck {
        limit,
        stored_rows: store,
        rays: u.form_factors.rays,
    };
    let check = |patches: u64| memory.check(patches);
    memory.before_meshing(scene, u.mesh)?;
    observer.event(Event::Stage(Stage::Mesh));
    let t = Instant::now();
    let mesh = Mesh::build(scene, u.mesh)?;
    let mesh_s = t.elapsed().as_secs_f64();
    let needed = check(mesh.len() as u64)?;
    // Gauss' dense matrix is refused before any form factor is computed.
    if u.solver == Solver::Gauss {
        let dense = crate::solve::gauss::bytes_needed(mesh.len());
        let allowed = u.params.memory_limit.min(limit - needed);
        if dense > allowed {
            return Err(crate::solve::SolveError::TooLarge {
                solver: Solver::Gauss,
                n: mesh.len(),
                needed: dense,
                limit: allowed,
                alternative: "an iterative solver (progressive, gauss-seidel or overshoot) needs no dense matrix",
            }
            .into());
        }
    }
    let mut ff = u.form_factors;
    ff.cache_bytes = ff.cache_bytes.min(((limit - needed) / 2) as usize);
    // Parameters are checked before any work.
    ff.validate()?;
    let mut params = u.params;
    params.memory_limit = params.memory_limit.min(limit - needed);

    observer.event(Event::Stage(Stage::Bvh));
    let t = Instant::now();
    let bvh = Bvh::build(&mesh);
    let bvh_s = t.elapsed().as_secs_f64();

    let system = patch_system(scene, &mesh);
    system.validate().map_err(|e| located(e, scene, &mesh))?;

    let estimator = Estimator::new(&mesh, &bvh, ff)?;
    let mut stored;
    let mut trace = None;
    let mut form_factors = FormFactorStats::default();
    let mut on_demand = None;
    let source: &mut dyn Operator = if store {
        let t = Instant::now();
        stored = estimator.matrix(Storage::Sparse, observer).into_sparse();
        if ff.method == FormFactorMethod::MonteCarlo {
            form_factors.rays = mesh.len() as u64 * ff.rays as u64;
        }
        form_factors.rows = mesh.len() as u64;
        form_factors.seconds = t.elapsed().as_secs_f64();
        observer.event(Event::Matrix(&stored, &system));
        if u.trace {
            trace = Some(Trace::new(
                trace_reference(&system, &stored, observer),
                &system.emission,
            ));
        }
        &mut stored
    } else {
        on_demand.insert(OnDemandRows::new(estimator))
    };
    observer.event(Event::Stage(Stage::Solve));
    let mut solver = crate::solve::start(u.solver, &system, source, &params)?;
    let info = crate::solve::run(&mut *solver, source, &params, false, &mut |s, sv| {
        if let Some(t) = trace.as_mut() {
            t.record(s, sv);
        }
        observer.event(Event::Solve(s, sv));
        !observer.cancelled()
    });
    let mut radiosity = Vec::new();
    solver.radiosity(&mut radiosity);
    let unshot = solver.unshot().map_or_else(
        || vec![Rgb::BLACK; system.len()],
        std::borrow::Cow::into_owned,
    );
    drop(solver);
    if let Some(rows) = &on_demand {
        form_factors = rows.stats();
    }
    let solve_s = (info.seconds - if store { 0.0 } else { form_factors.seconds }).max(0.0);
    Ok(Solution {
        timings: Timings {
            mesh: mesh_s,
            bvh: bvh_s,
            form_factors: form_factors.seconds,
            solve: solve_s,
            solve_rays: info.ray_seconds.min(solve_s),
        },
        mesh,
        bvh,
        system,
        radiosity,
        unshot,
        method: u.solver,
        info,
        form_factors,
        trace,
        hierarchy: None,
    })
}

/// Hierarchical radiosity over the scene's pieces ([`crate::hierarchical`]); the solution's
/// patches are the leaf elements, and its hierarchy is built over them for pictures.
fn solve_hierarchical(
    scene: &Scene,
    params: &crate::hierarchical::Params,
    limit: u64,
    observer: &dyn Observer,
) -> Result<Solution, Error> {
    params.validate()?;
    observer.event(Event::Stage(Stage::Mesh));
    let t = Instant::now();
    let roots = Mesh::build(scene, MeshParams::Faces)?;
    let root_system = patch_system(scene, &roots);
    root_system
        .validate()
        .map_err(|e| located(e, scene, &roots))?;
    let mesh_s = t.elapsed().as_secs_f64();
    observer.event(Event::Stage(Stage::Bvh));
    let t = Instant::now();
    let root_bvh = Bvh::build(&roots);
    let mut bvh_s = t.elapsed().as_secs_f64();
    let params = crate::hierarchical::Params {
        memory_limit: params.memory_limit.min(limit / 2),
        ..*params
    };
    let h = crate::hierarchical::solve(&roots, &root_system, &root_bvh, &params, observer)?;
    let t = Instant::now();
    let leaves = h.leaves();
    let mesh = crate::hierarchical::output::leaf_mesh(&h, &roots, &leaves);
    let root_of = |k: usize| h.elements.items[leaves[k] as usize].root as usize;
    let system = System {
        area: mesh.patches.iter().map(|p| p.area as f64).collect(),
        reflectance: (0..leaves.len())
            .map(|k| root_system.reflectance[root_of(k)])
            .collect(),
        emission: (0..leaves.len())
            .map(|k| root_system.emission[root_of(k)])
            .collect(),
    };
    let radiosity: Vec<Rgb> = leaves.iter().map(|&e| h.radiosity[e as usize]).collect();
    let unshot: Vec<Rgb> = leaves.iter().map(|&e| h.unshot[e as usize]).collect();
    let bvh = Bvh::build(&mesh);
    bvh_s += t.elapsed().as_secs_f64();
    let hi = h.info;
    // Energy: emitted by every leaf; what arrived (Σ A H) against what left (Σ A B) over the
    // leaves that are not a coincident twin's copy (the same surface, counted once).
    let counted: Vec<bool> = (0..leaves.len())
        .map(|k| h.twin_of[root_of(k)] as usize == root_of(k))
        .collect();
    let sum = |f: &dyn Fn(usize) -> Rgb| -> Rgb {
        (0..leaves.len()).filter(|&k| counted[k]).map(f).sum()
    };
    let emitted: Rgb = (0..leaves.len())
        .map(|k| system.emission[k] * system.area[k])
        .sum();
    // What arrived at each leaf, H A: through its own links and every ancestor's.
    let incident = |k: usize| {
        let e = leaves[k] as usize;
        h.incident[e] * h.elements.items[e].area as f64
    };
    let arrived = sum(&incident);
    // A twin's emission leaves through the first of its group.
    let left = sum(&|k| radiosity[k] * system.area[k])
        + (0..leaves.len())
            .filter(|&k| !counted[k])
            .map(|k| system.emission[k] * system.area[k])
            .sum::<Rgb>();
    let absorbed = sum(&|k| incident(k) * (Rgb::splat(1.0) - system.reflectance[k]));
    let unshot_power = sum(&|k| unshot[k] * system.area[k]);
    let info = Info {
        iterations: hi.iterations,
        converged: hi.converged,
        unshot_fraction: hi.unshot_fraction,
        seconds: hi.refine_seconds + hi.solve_seconds,
        emitted,
        absorbed,
        escaped: left - arrived,
        unshot: unshot_power,
        estimated_error: 0.0,
        ray_seconds: 0.0,
    };
    Ok(Solution {
        timings: Timings {
            mesh: mesh_s,
            bvh: bvh_s,
            form_factors: hi.refine_seconds,
            solve: hi.solve_seconds,
            solve_rays: 0.0,
        },
        mesh,
        bvh,
        system,
        radiosity,
        unshot,
        method: Solver::Jacobi,
        info,
        form_factors: FormFactorStats {
            rows: hi.links as u64,
            rays: hi.rays,
            seconds: hi.refine_seconds,
            ..Default::default()
        },
        trace: None,
        hierarchy: Some(HierarchicalSolution {
            hierarchy: h,
            leaves,
            root_surfaces: roots.patches.iter().map(|p| p.surface).collect(),
        }),
    })
}

/// A system error about a patch, as an error at the place of the polygon it was cut from.
pub(crate) fn located(e: crate::system::SystemError, scene: &Scene, mesh: &Mesh) -> Error {
    use crate::system::SystemError as E;
    match &e {
        E::Area { patch, .. } | E::Reflectance { patch, .. } | E::Emission { patch, .. } => {
            let surface = mesh.patches[*patch].surface as usize;
            Error::Scene(crate::scene::SceneError::Invalid {
                at: scene.place_of(surface),
                message: format!("{e} (a patch cut from this polygon)"),
            })
        }
        _ => Error::Solve(e.into()),
    }
}

/// The scene pipeline over ranks: mesh and BVH on every rank, then the distributed methods —
/// Jacobi on each rank's rows of F ([`crate::distributed::jacobi`]) or stochastic Jacobi with
/// each iteration's rays shared ([`crate::solve::stochastic_jacobi`]) — with the same
/// [`Solution`] on every rank and a [`Report`] of where the time and the bytes went.
fn solve_distributed(
    scene: &Scene,
    settings: &Settings,
    ranks: &Ranks<'_>,
    observer: &dyn Observer,
) -> Result<(Solution, Report), Error> {
    let u = match &settings.method {
        Method::Hierarchical(_) => {
            return Err(not_distributed(
                "hierarchical radiosity",
                "its links are refined and solved on one machine",
            ))
        }
        Method::Uniform(u) => u,
    };
    u.mesh.validate()?;
    if !DISTRIBUTED_SOLVERS.contains(&u.solver) {
        return Err(not_distributed(
            &format!("--solver {}", u.solver),
            "it relaxes one row, or shoots one patch, after another",
        ));
    }
    if u.trace {
        return Err(not_distributed(
            "a convergence trace",
            "it needs the LU solution of the whole matrix",
        ));
    }
    scene.validate()?;
    let start = ranks.traffic();
    let limit = settings.memory_limit.bytes();
    let jacobi = u.solver == Solver::Jacobi;
    // Rows are split over the ranks: each stores about 1/size of them.
    let memory = MemoryCheck {
        limit: limit.saturating_mul(ranks.size() as u64),
        stored_rows: jacobi,
        rays: u.form_factors.rays,
    };
    memory.before_meshing(scene, u.mesh)?;
    observer.event(Event::Stage(Stage::Mesh));
    let t = Instant::now();
    let mesh = Mesh::build(scene, u.mesh)?;
    let mesh_s = t.elapsed().as_secs_f64();
    let needed = memory.check(mesh.len() as u64)?;
    let mut ff = u.form_factors;
    let per_rank = needed / ranks.size() as u64;
    ff.cache_bytes = ff
        .cache_bytes
        .min((limit.saturating_sub(per_rank) / 2) as usize);
    ff.validate()?;
    let params = u.params;
    observer.event(Event::Stage(Stage::Bvh));
    let t = Instant::now();
    let bvh = Bvh::build(&mesh);
    let bvh_s = t.elapsed().as_secs_f64();
    let system = patch_system(scene, &mesh);
    system.validate().map_err(|e| located(e, scene, &mesh))?;
    let estimator = Estimator::new(&mesh, &bvh, ff)?;
    let mut report = Report {
        transport: ranks.communicator().describe(),
        ..Report::default()
    };
    let mut form_factors = FormFactorStats::default();
    let mut busy = 0.0;
    let (radiosity, unshot, info, solve_s);
    if jacobi {
        let t = Instant::now();
        let (block, rows_s): (RowBlock, f64) =
            rows::split(&estimator, ranks, observer, &mut report);
        busy += rows_s;
        form_factors.rows = mesh.len() as u64;
        if ff.method == crate::formfactor::FormFactorMethod::MonteCarlo {
            form_factors.rays = mesh.len() as u64 * ff.rays as u64;
        }
        // Wait for the slowest rank, so that the stage's time is the run's.
        ranks.barrier();
        form_factors.seconds = t.elapsed().as_secs_f64();
        observer.event(Event::Stage(Stage::Solve));
        let (b, i, sweeps) =
            crate::distributed::jacobi::solve(&system, &block, &params, ranks, &mut |s, _| {
                observer.event(Event::Progress {
                    stage: Stage::Solve,
                    done: (s.unshot_fraction.max(1e-30).log10() * -1000.0).max(0.0) as u64,
                    total: (params.tolerance.max(1e-30).log10() * -1000.0).max(1.0) as u64,
                });
                true
            });
        busy += sweeps
            .iter()
            .map(|s| s.seconds - s.communication)
            .sum::<f64>();
        solve_s = i.seconds;
        report.sweeps = sweeps;
        radiosity = b;
        unshot = vec![Rgb::BLACK; system.len()];
        info = i;
    } else {
        let n = mesh.len();
        report.blocks = crate::comm::balance(&vec![1.0; n], ranks.size());
        report.stored_entries = vec![0; ranks.size()];
        observer.event(Event::Stage(Stage::Solve));
        let mut source = OnDemandRows::new(estimator);
        let mut solver = crate::solve::stochastic_jacobi::StochasticJacobi::new(&system, &params)?
            .distributed(ranks);
        use crate::solve::SolverState;
        if crate::system::Operator::photons(&source).is_none() {
            return Err(SolveError::NoPhotons {
                solver: Solver::StochasticJacobi,
            }
            .into());
        }
        let before = ranks.traffic().seconds;
        let i = crate::solve::run(&mut solver, &mut source, &params, false, &mut |s, sv| {
            observer.event(Event::Solve(s, sv));
            true
        });
        busy += i.seconds - (ranks.traffic().seconds - before);
        report.shooting = Some(solver.timing());
        let mut b = Vec::new();
        solver.radiosity(&mut b);
        unshot = solver
            .unshot()
            .map_or_else(|| vec![Rgb::BLACK; n], std::borrow::Cow::into_owned);
        radiosity = b;
        solve_s = i.seconds;
        info = i;
        drop(solver);
        form_factors = source.stats();
    }
    report.finish(busy, &start, ranks);
    Ok((
        Solution {
            timings: Timings {
                mesh: mesh_s,
                bvh: bvh_s,
                form_factors: form_factors.seconds,
                solve: solve_s,
                solve_rays: info.ray_seconds.min(solve_s),
            },
            mesh,
            bvh,
            system,
            radiosity,
            unshot,
            method: u.solver,
            info,
            form_factors,
            trace: None,
            hierarchy: None,
        },
        report,
    ))
}
