//! The scene pipeline over ranks: mesh and BVH on every rank, then the distributed methods —
//! Jacobi on each rank's rows of F ([`super::jacobi`]) or stochastic Jacobi with each
//! iteration's rays shared ([`crate::solve::stochastic_jacobi`]) — with the same [`Solution`]
//! on every rank and a [`Report`] of where the time and the bytes went.

use super::rows::{self, RowBlock};
use super::{Ranks, Traffic};
use crate::accel::Bvh;
use crate::color::Rgb;
use crate::formfactor::{Estimator, FormFactorStats, OnDemandRows};
use crate::mesh::Mesh;
use crate::observe::{Event, Observer, Stage};
use crate::pipeline::{patch_system, MemoryCheck, Settings, Solution, Timings};
use crate::scene::Scene;
use crate::solve::{SolveError, Solver};
use crate::Error;
use std::ops::Range;
use std::time::Instant;

/// The methods that run over several ranks.
pub const DISTRIBUTED_SOLVERS: [Solver; 2] = [Solver::Jacobi, Solver::StochasticJacobi];

/// What a distributed run did, the same on every rank.
#[derive(Clone, Debug, Default)]
pub struct Report {
    /// The transport ([`super::Communicator::describe`]).
    pub transport: String,
    /// Each rank's block of patches (rows of F, or the patches whose rays it gathers).
    pub blocks: Vec<Range<usize>>,
    /// Seconds estimating row costs (Jacobi's pilot).
    pub pilot_seconds: f64,
    /// Per rank: seconds of its own work (rows of F, sweeps, rays), without waiting.
    pub busy: Vec<f64>,
    /// Per rank: its traffic.
    pub traffic: Vec<Traffic>,
    /// Per rank: entries of F it stores.
    pub stored_entries: Vec<u64>,
    /// Jacobi: every sweep.
    pub sweeps: Vec<super::jacobi::Sweep>,
    /// Stochastic Jacobi: where its shooting iterations' time went (this rank's view).
    pub shooting: Option<crate::solve::stochastic_jacobi::Timing>,
}

impl Report {
    /// Bytes all ranks sent, in all.
    pub fn bytes_sent(&self) -> u64 {
        self.traffic.iter().map(|t| t.bytes_sent).sum()
    }

    /// Gather every rank's busy time and its traffic since `start` (this one's `busy`
    /// seconds).
    pub fn finish(&mut self, busy: f64, start: &Traffic, ranks: &Ranks<'_>) {
        let traffic = ranks.traffic().since(start);
        let per_rank = ranks.all_gather(&[
            busy,
            traffic.calls as f64,
            traffic.bytes_sent as f64,
            traffic.bytes_received as f64,
            traffic.seconds,
        ]);
        for r in per_rank.chunks_exact(5) {
            self.busy.push(r[0]);
            self.traffic.push(Traffic {
                calls: r[1] as u64,
                bytes_sent: r[2] as u64,
                bytes_received: r[3] as u64,
                seconds: r[4],
            });
        }
    }

    /// Load balance: the mean rank's busy time over the busiest's (1 when even).
    pub fn balance(&self) -> f64 {
        let max = self.busy.iter().copied().fold(0.0, f64::max);
        if max > 0.0 {
            self.busy.iter().sum::<f64>() / self.busy.len() as f64 / max
        } else {
            1.0
        }
    }
}

/// The message for a method that does not run over several ranks, and why.
pub fn not_distributed(what: &str, why: &str) -> Error {
    Error::NotDistributed(format!(
        "{what} does not run over several ranks ({why}); the distributed methods are solve --solver jacobi or stochastic-jacobi, form-factors and thermal"
    ))
}

/// Validate, mesh and solve `scene` over `ranks` by a distributed method
/// ([`DISTRIBUTED_SOLVERS`]); every rank returns the same solution.
pub fn solve(
    scene: &Scene,
    settings: &Settings,
    ranks: &Ranks<'_>,
    observer: &dyn Observer,
) -> Result<(Solution, Report), Error> {
    if settings.hierarchical.is_some() {
        return Err(not_distributed(
            "hierarchical radiosity",
            "its links are refined and solved on one machine",
        ));
    }
    if !DISTRIBUTED_SOLVERS.contains(&settings.solver) {
        return Err(not_distributed(
            &format!("--solver {}", settings.solver),
            "it relaxes one row, or shoots one patch, after another",
        ));
    }
    if settings.trace {
        return Err(not_distributed(
            "a convergence trace",
            "it needs the LU solution of the whole matrix",
        ));
    }
    scene.validate()?;
    let start = ranks.traffic();
    let limit = match settings.memory_limit {
        0 => crate::pipeline::available_memory().unwrap_or(u64::MAX),
        l => l,
    };
    let jacobi = settings.solver == Solver::Jacobi;
    // Rows are split over the ranks: each stores about 1/size of them.
    let memory = MemoryCheck {
        limit: limit.saturating_mul(ranks.size() as u64),
        stored_rows: jacobi,
        rays: settings.form_factors.rays,
    };
    memory.before_meshing(scene, settings.mesh)?;
    observer.event(Event::Stage(Stage::Mesh));
    let t = Instant::now();
    let mesh = Mesh::build(scene, settings.mesh)?;
    let mesh_s = t.elapsed().as_secs_f64();
    let needed = memory.check(mesh.len() as u64)?;
    let mut ff = settings.form_factors;
    let per_rank = needed / ranks.size() as u64;
    ff.cache_bytes = ff
        .cache_bytes
        .min((limit.saturating_sub(per_rank) / 2) as usize);
    ff.validate()?;
    let params = settings.params;
    observer.event(Event::Stage(Stage::Bvh));
    let t = Instant::now();
    let bvh = Bvh::build(&mesh);
    let bvh_s = t.elapsed().as_secs_f64();
    let system = patch_system(scene, &mesh);
    system
        .validate()
        .map_err(|e| crate::pipeline::located(e, scene, &mesh))?;
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
        let (b, i, sweeps) = super::jacobi::solve(&system, &block, &params, ranks, &mut |s, _| {
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
        report.blocks = super::balance(&vec![1.0; n], ranks.size());
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
            method: settings.solver,
            info,
            form_factors,
            trace: None,
            hierarchy: None,
        },
        report,
    ))
}
