//! Solvers of the radiosity system `M B = E`, `M = I − diag(ρ) F` (Szirmay-Kalos & Márton
//! 1995, eq. 3; Gortler, Cohen & Slusallek 1993, eq. 1).
//!
//! The solvers know only the linear system ([`crate::system`]): the per-patch [`System`] and F
//! as an [`Operator`] (a stored [`crate::system::SparseMatrix`] or an estimator run on demand),
//! never geometry. Every iterative method steps one relaxation at a time — one row or one
//! column of F is one iteration, as in section 6 of Gortler et al. — and can report its current
//! B after any step ([`SolverState`]). The choice of method is [`Solver`]; one file per method;
//! [`relaxation`] holds what the relaxation methods share. [`run`] drives any of them to a
//! tolerance on the unshot (residual) energy.

mod awake;
pub mod gauss;
pub mod gauss_seidel;
pub mod jacobi;
pub mod overshoot;
pub mod overshoot_ambient;
pub mod progressive;
pub mod relaxation;
// Three of its methods serve only its tests.
#[cfg_attr(not(test), allow(dead_code))]
pub(crate) mod select;
pub mod sor;
pub mod southwell;
pub mod stochastic;
pub mod stochastic_jacobi;
pub mod trace;

pub use crate::system::{Operator, System, SystemError};

use crate::color::Rgb;
use std::time::Instant;

/// What a solver reports after each iteration.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Status {
    /// Iterations (shots, or relaxations) done.
    pub iterations: u64,
    /// Unshot (residual) energy Σ |r_i| A_i as a fraction of the emitted energy (channels
    /// summed), where r = E + ρ F B − B is the residual of the method's unknowns.
    pub unshot_fraction: f64,
    /// Seconds spent in the solver's steps so far.
    pub seconds: f64,
}

/// What a solver did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Info {
    /// Iterations done (shots for shooting methods).
    pub iterations: u64,
    /// True when the tolerance was reached.
    pub converged: bool,
    /// Unshot energy left, as a fraction of the emitted energy (channels summed).
    pub unshot_fraction: f64,
    /// Wall-clock seconds, form factors computed on demand included.
    pub seconds: f64,
    /// Emitted power Σ E_i A_i.
    pub emitted: Rgb,
    /// Power absorbed by the patches, Σ (1 − ρ_j) × (power arriving at j).
    pub absorbed: Rgb,
    /// Power shot that reached no patch (left an open scene or hit a back side).
    pub escaped: Rgb,
    /// Power not yet shot, Σ ΔB_i A_i.
    pub unshot: Rgb,
    /// Monte Carlo methods that estimate it: the standard error of B relative to B
    /// (area-weighted RMS over patches); 0 where not estimated.
    pub estimated_error: f64,
    /// Wall-clock seconds of [`Info::seconds`] that stochastic Jacobi spent in its parallel
    /// ray casting (drawing and casting its photons and its final gathering's rays). 0 for
    /// the other solvers: the shooting and sweeping methods' rays are the operator's rows,
    /// timed as form factors, and the photon method's single photons are not timed apart.
    pub ray_seconds: f64,
}

/// A solver parameter, for errors (the program maps it to its own option name).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Parameter {
    /// [`SolverParams::tolerance`].
    Tolerance,
    /// [`SolverParams::omega`].
    Omega,
    /// [`SolverParams::photons`].
    Photons,
    /// [`SolverParams::iteration_rays`].
    IterationRays,
    /// [`SolverParams::gather_rays`].
    GatherRays,
}

impl std::fmt::Display for Parameter {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Parameter::Tolerance => "tolerance",
            Parameter::Omega => "relaxation factor ω",
            Parameter::Photons => "photons per shot",
            Parameter::IterationRays => "rays per patch and iteration",
            Parameter::GatherRays => "gathering rays per patch",
        })
    }
}

/// Why a solver could not run.
#[derive(Debug, thiserror::Error)]
pub enum SolveError {
    /// The system is malformed or unphysical.
    #[error("invalid radiosity system: {0}")]
    System(#[from] SystemError),
    /// A parameter is out of its range.
    #[error("{parameter} = {value} is outside {range}")]
    Parameter {
        /// Which.
        parameter: Parameter,
        /// Its value.
        value: f64,
        /// The range it must lie in.
        range: &'static str,
    },
    /// The method would need more memory than allowed.
    #[error("{solver} on {n} patches would need about {} MiB, more than the {} MiB allowed; {alternative}", needed >> 20, limit >> 20)]
    TooLarge {
        /// The method.
        solver: Solver,
        /// Unknowns.
        n: usize,
        /// Bytes it would need.
        needed: u64,
        /// Bytes allowed.
        limit: u64,
        /// What to use instead.
        alternative: &'static str,
    },
    /// SuperShootGather needs `F_ii = 0`.
    #[error("{solver}: patch {patch} sees itself (F_ii = {value}); SuperShootGather needs F_ii = 0; progressive has no such need")]
    SelfFactor {
        /// The method.
        solver: Solver,
        /// The patch.
        patch: usize,
        /// Its F_ii.
        value: f32,
    },
    /// The photon method was given an operator that cannot draw photons.
    #[error("{solver}: this form-factor operator cannot draw photons")]
    NoPhotons {
        /// The method.
        solver: Solver,
    },
    /// `I − diag(ρ) F` is singular.
    #[error("the matrix I − diag(ρ) F is singular")]
    Singular,
}

/// The solution methods, named as on the command line (`--solver`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Solver {
    /// Gauss elimination: dense LU with partial pivoting ([`gauss`]).
    Gauss,
    /// Jacobi iteration from B = E (Szirmay-Kalos & Márton eq. 8), one row per iteration ([`jacobi`]).
    Jacobi,
    /// Gauss-Seidel from B = 0 ([`gauss_seidel`]).
    GaussSeidel0,
    /// Gauss-Seidel from B = E: gathering ([`gauss_seidel`]).
    GaussSeidel,
    /// Gauss-Seidel from 0 whose output is the unknowns plus their residuals ([`gauss_seidel`]).
    GaussSeidelJacobi,
    /// Successive over-relaxation from B = E, factor ω (Szirmay-Kalos & Márton eq. 21) ([`sor`]).
    Sor,
    /// Southwell relaxation: largest residual first, output the unknowns ([`southwell`]).
    Southwell,
    /// Progressive refinement: Southwell on the energy system plus the free Jacobi sweep
    /// ([`progressive`]).
    Progressive,
    /// Feda's overshooting with the ambient term (Gortler et al. section 2.2.1) ([`overshoot_ambient`]).
    OvershootAmbient,
    /// SuperShootGather overshooting (Gortler et al. section 2.2.2, appendix C) ([`overshoot`]).
    Overshoot,
    /// Probabilistic progressive refinement: photon shooting (Szirmay-Kalos & Márton) ([`stochastic`]).
    Stochastic,
    /// Stochastic Jacobi: all patches shoot at once, rays in parallel (Neumann et al. 1994,
    /// Bekaert 1999) ([`stochastic_jacobi`]).
    StochasticJacobi,
}

impl Solver {
    /// Every method, in the order of the docs.
    pub const ALL: [Solver; 12] = [
        Solver::Gauss,
        Solver::Jacobi,
        Solver::GaussSeidel0,
        Solver::GaussSeidel,
        Solver::GaussSeidelJacobi,
        Solver::Sor,
        Solver::Southwell,
        Solver::Progressive,
        Solver::OvershootAmbient,
        Solver::Overshoot,
        Solver::Stochastic,
        Solver::StochasticJacobi,
    ];

    /// The command-line name.
    pub fn name(self) -> &'static str {
        match self {
            Solver::Gauss => "gauss",
            Solver::Jacobi => "jacobi",
            Solver::GaussSeidel0 => "gauss-seidel-0",
            Solver::GaussSeidel => "gauss-seidel",
            Solver::GaussSeidelJacobi => "gauss-seidel-jacobi",
            Solver::Sor => "sor",
            Solver::Southwell => "southwell",
            Solver::Progressive => "progressive",
            Solver::OvershootAmbient => "overshoot-ambient",
            Solver::Overshoot => "overshoot",
            Solver::Stochastic => "stochastic",
            Solver::StochasticJacobi => "stochastic-jacobi",
        }
    }

    /// One line on what the method is, with its source.
    pub fn summary(self) -> &'static str {
        match self {
            Solver::Gauss => "Gauss elimination, dense LU (Szirmay-Kalos & Márton 1995)",
            Solver::Jacobi => "Jacobi iteration from B = E (Szirmay-Kalos & Márton eq. 8)",
            Solver::GaussSeidel0 => "Gauss-Seidel from B = 0 (Gortler et al. 1993 §6)",
            Solver::GaussSeidel => "Gauss-Seidel from B = E: gathering (Gortler et al. §2.1)",
            Solver::GaussSeidelJacobi => {
                "Gauss-Seidel from 0, output plus residuals (Gortler et al. §6)"
            }
            Solver::Sor => "successive over-relaxation, factor ω (Szirmay-Kalos & Márton eq. 21)",
            Solver::Southwell => {
                "Southwell relaxation, largest residual first (Gortler et al. §3.1)"
            }
            Solver::Progressive => {
                "progressive refinement: Southwell plus a Jacobi sweep (Gortler et al. §2.1)"
            }
            Solver::OvershootAmbient => {
                "overshooting with the ambient term (Feda; Gortler et al. §2.2.1)"
            }
            Solver::Overshoot => "SuperShootGather overshooting (Gortler et al. §2.2.2, app. C)",
            Solver::Stochastic => {
                "photon shooting, probabilistic progressive refinement (Szirmay-Kalos & Márton)"
            }
            Solver::StochasticJacobi => {
                "stochastic Jacobi: all patches shoot at once, rays in parallel (Neumann 1994, Bekaert 1999)"
            }
        }
    }

    /// The method called `name`, if any.
    pub fn from_name(name: &str) -> Option<Solver> {
        Solver::ALL.into_iter().find(|m| m.name() == name)
    }

    /// True for the methods that need every row of F before they start (gathering and
    /// direct methods); the others (shooting) take rows or photons on demand.
    pub fn needs_all_rows(self) -> bool {
        !matches!(
            self,
            Solver::Progressive
                | Solver::OvershootAmbient
                | Solver::Stochastic
                | Solver::StochasticJacobi
        )
    }
}

impl std::fmt::Display for Solver {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Parameters shared by the solvers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SolverParams {
    /// Stop when the unshot energy is at most this fraction of the emitted energy.
    pub tolerance: f64,
    /// Stop after this many iterations at the latest.
    pub max_iterations: u64,
    /// Relaxation factor of `sor`.
    pub omega: f64,
    /// Photons per unit of a shooter's unshot power for `stochastic` (each carries 1/n).
    pub photons: u32,
    /// Seed of `stochastic`'s and `stochastic-jacobi`'s random streams.
    pub seed: u64,
    /// `stochastic-jacobi`: rays per patch in each iteration (R = this × N).
    pub iteration_rays: u32,
    /// `stochastic-jacobi`: rays per patch of the final regular gathering iteration, 0 for
    /// none (the default: on RenderPark's hospital it made every result noisier,
    /// [`stochastic_jacobi`]).
    pub gather_rays: u32,
    /// Memory the solver may use, bytes (`gauss`' dense matrix, `overshoot`'s shot matrix).
    pub memory_limit: u64,
}

impl SolverParams {
    /// The tolerance of a solve made for a picture (`radiosity render`): on the Cornell box the
    /// display ambient term's bias is then below 1 % of a 16 × 16-pixel block, for little more
    /// CPU time than at the default 0.01 (docs/notes/solvers.md).
    pub const PICTURE_TOLERANCE: f64 = 3e-4;

    /// Check every parameter against its range, before any work: the tolerance in [0, 1),
    /// ω in (0, 2), at least one photon a shot and one ray a patch and iteration, at most
    /// [`stochastic_jacobi::MAX_GATHER_RAYS`] gathering rays a patch. The one validation the
    /// command line, the Python bindings and the workbench share.
    pub fn validate(&self) -> Result<(), SolveError> {
        let bad = |parameter, value: f64, range| {
            Err(SolveError::Parameter {
                parameter,
                value,
                range,
            })
        };
        if !(0.0..1.0).contains(&self.tolerance) {
            return bad(Parameter::Tolerance, self.tolerance, "[0, 1)");
        }
        if !(self.omega > 0.0 && self.omega < 2.0) {
            return bad(Parameter::Omega, self.omega, "(0, 2)");
        }
        if self.photons == 0 {
            return bad(Parameter::Photons, 0.0, "[1, 2³²)");
        }
        if self.iteration_rays == 0 {
            return bad(Parameter::IterationRays, 0.0, "[1, 2³²)");
        }
        if self.gather_rays > stochastic_jacobi::MAX_GATHER_RAYS {
            return bad(Parameter::GatherRays, self.gather_rays as f64, "[0, 2²⁰]");
        }
        Ok(())
    }
}

impl Default for SolverParams {
    fn default() -> Self {
        Self {
            tolerance: 0.01,
            max_iterations: u64::MAX,
            omega: 1.1,
            photons: 1000,
            seed: 1,
            iteration_rays: 16,
            gather_rays: 0,
            memory_limit: 4 << 30,
        }
    }
}

/// A solution method in progress, advanced one iteration at a time.
pub trait SolverState {
    /// The method.
    fn method(&self) -> Solver;
    /// One iteration (one row or column of F, or one photon). Returns false when there is
    /// nothing left to do (the residual is exactly zero, or a direct method has finished).
    fn step(&mut self, source: &mut dyn Operator) -> bool;
    /// The method's current estimate of B, written into `out` (resized to N).
    fn radiosity(&self, out: &mut Vec<Rgb>);
    /// For shooting methods whose output already includes it, the unshot radiosity per patch
    /// (non-negative): what the display-only ambient term stands in for.
    fn unshot(&self) -> Option<std::borrow::Cow<'_, [Rgb]>> {
        None
    }
    /// Unshot energy Σ |r_i| A_i over the emitted energy. Methods that keep the residual give
    /// it exactly; others may return a value computed a few iterations ago unless `exact`.
    fn unshot_fraction(&mut self, source: &mut dyn Operator, exact: bool) -> f64;
    /// Iterations done.
    fn iterations(&self) -> u64;
    /// Called once when the driver stops (tolerance or iteration cap): a method may finish its
    /// estimate here (stochastic Jacobi's final gathering iteration). Returns true when it
    /// changed the estimate. Nothing by default.
    fn finish(&mut self, _source: &mut dyn Operator) -> bool {
        false
    }
    /// The energy bookkeeping of the current state.
    fn info(&mut self, source: &mut dyn Operator) -> Info;
}

/// Start `method` on `system` (whose rows of F `source` provides).
pub fn start<'s>(
    method: Solver,
    system: &'s System,
    source: &mut dyn Operator,
    params: &SolverParams,
) -> Result<Box<dyn SolverState + 's>, SolveError> {
    system.validate()?;
    system.check_operator(source)?;
    Ok(match method {
        Solver::Gauss => Box::new(gauss::Gauss::new(system, params)?),
        Solver::Jacobi => Box::new(jacobi::Jacobi::new(system, source)),
        Solver::GaussSeidel0 => Box::new(gauss_seidel::GaussSeidel::new(
            system,
            source,
            gauss_seidel::Variant::Zero,
        )),
        Solver::GaussSeidel => Box::new(gauss_seidel::GaussSeidel::new(
            system,
            source,
            gauss_seidel::Variant::Emission,
        )),
        Solver::GaussSeidelJacobi => Box::new(gauss_seidel::GaussSeidel::new(
            system,
            source,
            gauss_seidel::Variant::ZeroPlusResidual,
        )),
        Solver::Sor => Box::new(sor::Sor::new(system, source, params.omega)?),
        Solver::Southwell => Box::new(southwell::Southwell::new(system)),
        Solver::Progressive => Box::new(progressive::Progressive::new(system)),
        Solver::OvershootAmbient => Box::new(overshoot_ambient::OvershootAmbient::new(system)),
        Solver::Overshoot => Box::new(overshoot::Overshoot::new(system, source, params)?),
        Solver::Stochastic => {
            if source.photons().is_none() {
                return Err(SolveError::NoPhotons { solver: method });
            }
            Box::new(stochastic::Stochastic::new(system, params)?)
        }
        Solver::StochasticJacobi => {
            if source.photons().is_none() {
                return Err(SolveError::NoPhotons { solver: method });
            }
            Box::new(stochastic_jacobi::StochasticJacobi::new(system, params)?)
        }
    })
}

/// Drive `solver` until the unshot energy is at most `params.tolerance` of the emitted energy,
/// or `params.max_iterations`. `observer` sees the status and the solver before the first
/// iteration and after each, and returns false to stop there (the result so far, reported as
/// not converged unless it is); with `exact_status` every status is exact (see
/// [`SolverState::unshot_fraction`]), which costs `overshoot` a pass over F per iteration.
///
/// Call it from a worker of a rayon pool (`ThreadPool::install`, or `rayon::scope` for the
/// global pool) when the method takes many short steps: each parallel step started from
/// outside the pool wakes a worker and puts the caller to sleep until it is done, a cost that
/// shows at tens of thousands of shots (docs/notes/solvers.md); the results are the same
/// either way.
pub fn run(
    solver: &mut dyn SolverState,
    source: &mut dyn Operator,
    params: &SolverParams,
    exact_status: bool,
    observer: &mut dyn FnMut(&Status, &dyn SolverState) -> bool,
) -> Info {
    // Not for the methods whose steps are long parallel sweeps, where a spinning worker would
    // only add CPU time to their short serial parts.
    let _awake = (!matches!(solver.method(), Solver::StochasticJacobi | Solver::Gauss))
        .then(awake::KeepAwake::new);
    let mut seconds = 0.0;
    let cap =
        params
            .max_iterations
            .min(default_iteration_cap(solver.method(), source.len(), params));
    loop {
        let status = Status {
            iterations: solver.iterations(),
            unshot_fraction: solver.unshot_fraction(source, exact_status),
            seconds,
        };
        let go_on = observer(&status, &*solver);
        let done = status.unshot_fraction <= params.tolerance;
        if done || solver.iterations() >= cap || !go_on {
            let converged = done || solver.unshot_fraction(source, true) <= params.tolerance;
            let t = Instant::now();
            if solver.finish(source) {
                seconds += t.elapsed().as_secs_f64();
                observer(
                    &Status {
                        iterations: solver.iterations(),
                        unshot_fraction: status.unshot_fraction,
                        seconds,
                    },
                    &*solver,
                );
            }
            let mut info = solver.info(source);
            info.converged = converged;
            info.seconds = seconds;
            return info;
        }
        let t = Instant::now();
        let more = solver.step(source);
        seconds += t.elapsed().as_secs_f64();
        if !more {
            let t = Instant::now();
            solver.finish(source);
            seconds += t.elapsed().as_secs_f64();
            let mut info = solver.info(source);
            info.converged = true;
            info.seconds = seconds;
            observer(
                &Status {
                    iterations: solver.iterations(),
                    unshot_fraction: info.unshot_fraction,
                    seconds,
                },
                &*solver,
            );
            return info;
        }
    }
}

/// The most iterations [`run`] lets a method take on N patches, whatever
/// [`SolverParams::max_iterations`] says, so that every solve stops (a system with ρ → 1
/// converges arbitrarily slowly): 10⁴ sweeps of N relaxations; 10⁴ × N shots of `photons`
/// photons for photon shooting; 10⁴ iterations for stochastic Jacobi; one LU. A run that meets
/// it reports `converged: false` with the unshot energy it reached.
pub fn default_iteration_cap(solver: Solver, n: usize, params: &SolverParams) -> u64 {
    const SWEEPS: u64 = 10_000;
    let n = n.max(1) as u64;
    match solver {
        Solver::Gauss => 1,
        Solver::StochasticJacobi => SWEEPS,
        Solver::Stochastic => SWEEPS
            .saturating_mul(n)
            .saturating_mul(params.photons.max(1) as u64),
        _ => SWEEPS.saturating_mul(n),
    }
}

/// Solve `system` by `method` to `params`; returns B and the report.
pub fn solve(
    method: Solver,
    system: &System,
    source: &mut dyn Operator,
    params: &SolverParams,
) -> Result<(Vec<Rgb>, Info), SolveError> {
    let mut solver = start(method, system, source, params)?;
    let info = run(&mut *solver, source, params, false, &mut |_, _| true);
    let mut b = Vec::new();
    solver.radiosity(&mut b);
    Ok((b, info))
}

/// The error of eq. 22 of Gortler, Cohen & Slusallek (1993): Σ_i (B*_i − B_i) / Σ_i (B*_i − E_i), the
/// share of the reflected radiosity not yet accounted for (channels summed).
pub fn relative_error(exact: &[Rgb], emission: &[Rgb], b: &[Rgb]) -> f64 {
    let mut num = 0.0;
    let mut den = 0.0;
    for i in 0..exact.len() {
        num += (exact[i] - b[i]).sum();
        den += (exact[i] - emission[i]).sum();
    }
    num / den
}

/// The ambient term of Cohen, Chen, Wallace and Greenberg (1988), quoted as eq. 2 of
/// Gortler, Cohen & Slusallek (1993): the area-weighted mean unshot radiosity times the geometric series
/// of the area-weighted mean reflectance, `ΔB̄ / (1 − ρ̄)`. Added as `ρ_i · ambient` to each patch
/// for display only, it stands for the light not yet shot.
pub fn ambient_term(system: &System, unshot: &[Rgb]) -> Rgb {
    let total_area: f64 = system.area.iter().sum();
    let mut mean_unshot = Rgb::BLACK;
    let mut mean_rho = Rgb::BLACK;
    for i in 0..system.len() {
        mean_unshot += unshot[i] * system.area[i];
        mean_rho += system.reflectance[i] * system.area[i];
    }
    let (u, r) = (mean_unshot / total_area, mean_rho / total_area);
    Rgb::new(u.r / (1.0 - r.r), u.g / (1.0 - r.g), u.b / (1.0 - r.b))
}
