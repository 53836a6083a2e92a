//! Solvers of the radiosity system (000_59d10e371b5f300d.txt eq. 3; 003_6556f2e3d50166bb.txt
//! eq. 1)
//!
//! ```text
//! B_i = E_i + ρ_i Σ_j F_ij B_j        for every patch i, in each colour channel,
//! ```
//!
//! i.e. `M B = E` with `M = I − diag(ρ) F`. The solvers know only the linear system: areas,
//! reflectances, emissions ([`System`]) and rows, columns and samples of F from a
//! [`RowSource`] (a stored [`matrix::SparseMatrix`] or an estimator run on demand), never
//! geometry. Every iterative method steps one relaxation at a time — one row or one column of F
//! is one iteration, as in section 6 of 003_… — and can report its current B after any step
//! ([`Solver`]). One file per method; [`relaxation`] holds what the relaxation methods share.
//! [`run`] drives any of them to a tolerance on the unshot (residual) energy.

pub mod gauss;
pub mod gauss_seidel;
pub mod jacobi;
pub mod matrix;
pub mod overshoot;
pub mod overshoot_ambient;
pub mod progressive;
pub mod relaxation;
pub mod sor;
pub mod southwell;
pub mod stochastic;

use crate::color::Rgb;
use crate::formfactor::Entry;
use crate::sampling::Rng64;
use std::time::Instant;

/// The data of the radiosity system besides F: per patch, area `A_i`, reflectance `ρ_i` and
/// emission `E_i` (all three channels at once).
#[derive(Clone, Copy, Debug)]
pub struct System<'a> {
    /// Patch areas (> 0).
    pub area: &'a [f64],
    /// Reflectances, each channel in `[0, 1)`.
    pub reflectance: &'a [Rgb],
    /// Emissions (radiant exitance, ≥ 0).
    pub emission: &'a [Rgb],
}

impl System<'_> {
    /// Number of unknowns (patches).
    pub fn len(&self) -> usize {
        self.area.len()
    }

    /// True for the empty system.
    pub fn is_empty(&self) -> bool {
        self.area.is_empty()
    }

    /// Total emitted power Σ E_i A_i per channel.
    pub fn emitted_power(&self) -> Rgb {
        self.emission
            .iter()
            .zip(self.area)
            .map(|(e, a)| *e * *a)
            .sum()
    }

    /// Check sizes and physical ranges.
    pub fn validate(&self) -> Result<(), SolveError> {
        let n = self.len();
        if self.reflectance.len() != n || self.emission.len() != n {
            return Err(SolveError::Invalid(format!(
                "{} areas, {} reflectances, {} emissions: lengths differ",
                n,
                self.reflectance.len(),
                self.emission.len()
            )));
        }
        for i in 0..n {
            let (a, r, e) = (self.area[i], self.reflectance[i], self.emission[i]);
            if !(a.is_finite() && a > 0.0) {
                return Err(SolveError::Invalid(format!(
                    "patch {i}: area {a} is not positive"
                )));
            }
            if !r.is_finite() || r.min_channel() < 0.0 || r.max_channel() >= 1.0 {
                return Err(SolveError::Invalid(format!(
                    "patch {i}: reflectance {r} outside [0, 1)"
                )));
            }
            if !e.is_finite() || e.min_channel() < 0.0 {
                return Err(SolveError::Invalid(format!(
                    "patch {i}: emission {e} is negative or not finite"
                )));
            }
        }
        if self.emitted_power().max_channel() <= 0.0 {
            return Err(SolveError::Invalid(
                "no patch emits: the solution is zero".into(),
            ));
        }
        Ok(())
    }
}

/// Where a solver gets rows of F: a stored matrix or an estimator run on demand.
pub trait RowSource {
    /// Number of patches (rows).
    fn len(&self) -> usize;

    /// True when there are no rows.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Row `i` of F: `(j, F_ij)` for the non-zero entries, sorted by `j`. `share` is the
    /// fraction of the scene's emitted power the caller is about to shoot from `i`; estimators
    /// may use it to choose their effort, stored matrices ignore it.
    fn row(&mut self, i: usize, share: f64) -> &[Entry];

    /// Column `i` of F: `(j, F_ji)` for the non-zero entries, sorted by `j`: where the energy
    /// shot from `i` lands, as fractions of each receiver's own exitance (shooting needs it,
    /// 000_… eq. 23–24). `share` as for [`RowSource::row`].
    fn column(&mut self, i: usize, share: f64) -> &[Entry];

    /// Where a photon leaving patch `i` first arrives: patch `j` with probability `F_ij`, `None`
    /// (lost) with probability `1 − Σ_j F_ij`.
    fn sample(&mut self, i: usize, rng: &mut Rng64) -> Option<u32>;
}

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
}

/// Why a solver could not run.
#[derive(Debug, thiserror::Error)]
pub enum SolveError {
    /// The system is malformed or unphysical.
    #[error("invalid radiosity system: {0}")]
    Invalid(String),
    /// The method would need more memory than allowed.
    #[error("{method} on {n} patches would need about {} MiB, more than the {} MiB allowed; use {alternative}", needed >> 20, limit >> 20)]
    TooLarge {
        /// The method.
        method: &'static str,
        /// Unknowns.
        n: usize,
        /// Bytes it would need.
        needed: u64,
        /// Bytes allowed.
        limit: u64,
        /// What to use instead.
        alternative: &'static str,
    },
    /// The method cannot handle this system.
    #[error("{method}: {message}")]
    Unsupported {
        /// The method.
        method: &'static str,
        /// Why.
        message: String,
    },
}

/// The solution methods, named as on the command line (`--solver`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Method {
    /// Gauss elimination: dense LU with partial pivoting ([`gauss`]).
    Gauss,
    /// Jacobi iteration from B = E (000_… eq. 8), one row per iteration ([`jacobi`]).
    Jacobi,
    /// Gauss-Seidel from B = 0 ([`gauss_seidel`]).
    GaussSeidel0,
    /// Gauss-Seidel from B = E: gathering ([`gauss_seidel`]).
    GaussSeidel,
    /// Gauss-Seidel from 0 whose output is the unknowns plus their residuals ([`gauss_seidel`]).
    GaussSeidelJacobi,
    /// Successive over-relaxation from B = E, factor ω (000_… eq. 21) ([`sor`]).
    Sor,
    /// Southwell relaxation: largest residual first, output the unknowns ([`southwell`]).
    Southwell,
    /// Progressive refinement: Southwell on the energy system plus the free Jacobi sweep
    /// ([`progressive`]).
    Progressive,
    /// Feda's overshooting with the ambient term (003_… section 2.2.1) ([`overshoot_ambient`]).
    OvershootAmbient,
    /// SuperShootGather overshooting (003_… section 2.2.2, appendix C) ([`overshoot`]).
    Overshoot,
    /// Probabilistic progressive refinement: photon shooting (000_…) ([`stochastic`]).
    Stochastic,
}

impl Method {
    /// Every method, in the order of the docs.
    pub const ALL: [Method; 11] = [
        Method::Gauss,
        Method::Jacobi,
        Method::GaussSeidel0,
        Method::GaussSeidel,
        Method::GaussSeidelJacobi,
        Method::Sor,
        Method::Southwell,
        Method::Progressive,
        Method::OvershootAmbient,
        Method::Overshoot,
        Method::Stochastic,
    ];

    /// The command-line name.
    pub fn name(self) -> &'static str {
        match self {
            Method::Gauss => "gauss",
            Method::Jacobi => "jacobi",
            Method::GaussSeidel0 => "gauss-seidel-0",
            Method::GaussSeidel => "gauss-seidel",
            Method::GaussSeidelJacobi => "gauss-seidel-jacobi",
            Method::Sor => "sor",
            Method::Southwell => "southwell",
            Method::Progressive => "progressive",
            Method::OvershootAmbient => "overshoot-ambient",
            Method::Overshoot => "overshoot",
            Method::Stochastic => "stochastic",
        }
    }

    /// The method called `name`, if any.
    pub fn from_name(name: &str) -> Option<Method> {
        Method::ALL.into_iter().find(|m| m.name() == name)
    }

    /// True for the methods that need every row of F before they start (gathering and
    /// direct methods); the others (shooting) take rows or photons on demand.
    pub fn needs_all_rows(self) -> bool {
        !matches!(
            self,
            Method::Progressive | Method::OvershootAmbient | Method::Stochastic
        )
    }
}

impl std::fmt::Display for Method {
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
    /// Seed of `stochastic`'s random stream.
    pub seed: u64,
    /// Memory the solver may use, bytes (`gauss`' dense matrix, `overshoot`'s shot matrix).
    pub memory_limit: u64,
}

impl Default for SolverParams {
    fn default() -> Self {
        Self {
            tolerance: 0.01,
            max_iterations: u64::MAX,
            omega: 1.1,
            photons: 1000,
            seed: 1,
            memory_limit: 4 << 30,
        }
    }
}

/// A solution method in progress, advanced one iteration at a time.
pub trait Solver {
    /// The method.
    fn method(&self) -> Method;
    /// One iteration (one row or column of F, or one photon). Returns false when there is
    /// nothing left to do (the residual is exactly zero, or a direct method has finished).
    fn step(&mut self, source: &mut dyn RowSource) -> bool;
    /// The method's current estimate of B, written into `out` (resized to N).
    fn radiosity(&self, out: &mut Vec<Rgb>);
    /// For shooting methods whose output already includes it, the unshot radiosity per patch
    /// (non-negative): what the display-only ambient term stands in for.
    fn unshot(&self) -> Option<&[Rgb]> {
        None
    }
    /// Unshot energy Σ |r_i| A_i over the emitted energy. Methods that keep the residual give
    /// it exactly; others may return a value computed a few iterations ago unless `exact`.
    fn unshot_fraction(&mut self, source: &mut dyn RowSource, exact: bool) -> f64;
    /// Iterations done.
    fn iterations(&self) -> u64;
    /// The energy bookkeeping of the current state.
    fn info(&mut self, source: &mut dyn RowSource) -> Info;
}

/// Start `method` on `system` (whose rows of F `source` provides).
pub fn start<'s>(
    method: Method,
    system: System<'s>,
    source: &mut dyn RowSource,
    params: &SolverParams,
) -> Result<Box<dyn Solver + 's>, SolveError> {
    system.validate()?;
    if source.len() != system.len() {
        return Err(SolveError::Invalid(format!(
            "the form-factor matrix has {} rows but the system {} patches",
            source.len(),
            system.len()
        )));
    }
    Ok(match method {
        Method::Gauss => Box::new(gauss::Gauss::new(system, params)?),
        Method::Jacobi => Box::new(jacobi::Jacobi::new(system, source)),
        Method::GaussSeidel0 => Box::new(gauss_seidel::GaussSeidel::new(
            system,
            source,
            gauss_seidel::Variant::Zero,
        )),
        Method::GaussSeidel => Box::new(gauss_seidel::GaussSeidel::new(
            system,
            source,
            gauss_seidel::Variant::Emission,
        )),
        Method::GaussSeidelJacobi => Box::new(gauss_seidel::GaussSeidel::new(
            system,
            source,
            gauss_seidel::Variant::ZeroPlusResidual,
        )),
        Method::Sor => Box::new(sor::Sor::new(system, source, params.omega)?),
        Method::Southwell => Box::new(southwell::Southwell::new(system)),
        Method::Progressive => Box::new(progressive::Progressive::new(system)),
        Method::OvershootAmbient => Box::new(overshoot_ambient::OvershootAmbient::new(system)),
        Method::Overshoot => Box::new(overshoot::Overshoot::new(system, source, params)?),
        Method::Stochastic => Box::new(stochastic::Stochastic::new(system, params)?),
    })
}

/// Drive `solver` until the unshot energy is at most `params.tolerance` of the emitted energy,
/// or `params.max_iterations`. `observer` sees the status and the solver before the first
/// iteration and after each; with `exact_status` every status is exact (see
/// [`Solver::unshot_fraction`]), which costs `overshoot` a pass over F per iteration.
pub fn run(
    solver: &mut dyn Solver,
    source: &mut dyn RowSource,
    params: &SolverParams,
    exact_status: bool,
    observer: &mut dyn FnMut(&Status, &dyn Solver),
) -> Info {
    let mut seconds = 0.0;
    loop {
        let status = Status {
            iterations: solver.iterations(),
            unshot_fraction: solver.unshot_fraction(source, exact_status),
            seconds,
        };
        observer(&status, &*solver);
        let done = status.unshot_fraction <= params.tolerance;
        if done || solver.iterations() >= params.max_iterations {
            let converged = done || solver.unshot_fraction(source, true) <= params.tolerance;
            let mut info = solver.info(source);
            info.converged = converged;
            info.seconds = seconds;
            return info;
        }
        let t = Instant::now();
        let more = solver.step(source);
        seconds += t.elapsed().as_secs_f64();
        if !more {
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

/// Solve `system` by `method` to `params`; returns B and the report.
pub fn solve(
    method: Method,
    system: System,
    source: &mut dyn RowSource,
    params: &SolverParams,
) -> Result<(Vec<Rgb>, Info), SolveError> {
    let mut solver = start(method, system, source, params)?;
    let info = run(&mut *solver, source, params, false, &mut |_, _| {});
    let mut b = Vec::new();
    solver.radiosity(&mut b);
    Ok((b, info))
}

/// The error of eq. 22 of 003_6556f2e3d50166bb.txt: Σ_i (B*_i − B_i) / Σ_i (B*_i − E_i), the
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
/// 003_6556f2e3d50166bb.txt: the area-weighted mean unshot radiosity times the geometric series
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
