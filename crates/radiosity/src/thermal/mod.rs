//! Radiative heat transfer between grey diffuse surfaces: the net-radiation method on the
//! engine's view factors.
//!
//! The radiosity system of Szirmay-Kalos & Márton (1995, eq. 1) and of Gortler, Cohen &
//! Slusallek (1993, eq. 1) is, for a grey diffuse opaque surface of emissivity ε at temperature
//! T, the engineer's net-radiation equation (Hottel & Sarofim 1967; Modest, *Radiative Heat
//! Transfer*, ch. 5; Incropera & DeWitt ch. 13), with ρ = 1 − ε and E = εσT⁴:
//!
//! ```text
//! J_i = ε_i σ T_i⁴ + (1 − ε_i) G_i          prescribed temperature
//! q_i = J_i − G_i                             net flux leaving i (W/m²)
//! G_i = (1/A_i) Σ_j A_j F_ji J_j + F_ie σ T_e⁴ irradiation
//! ```
//!
//! where `F_ie = 1 − Σ_j F_ij` is the part of patch i's view that reaches no surface (openings,
//! seen as black surroundings at `T_e`). A surface with prescribed flux has `J_i − G_i = q_i`
//! (an adiabatic, re-radiating one has q = 0), and its temperature follows from
//! `ε σT⁴ = J − (1 − ε) G`.
//!
//! **Energy balance by construction.** Irradiation is gathered through Fᵀ — the power that
//! leaves j and lands on i, `A_j J_j F_ji` — not through `Σ_j F_ij J_j`, which equals it only
//! where reciprocity holds exactly. So `Σ_i A_i q_i = Σ_i A_i F_ie (J_i − σT_e⁴)`, the net power
//! lost through the openings, holds to rounding for any view-factor matrix, and the fluxes of a
//! closed enclosure sum to zero to rounding.
//!
//! **Solvers.** The unknown is J; the system `J − D K J = b`, with `K J = A⁻¹ Fᵀ (A J)` and
//! `D = 1 − ε` on temperature surfaces, 1 on flux surfaces, is solved by dense LU (faer, partial
//! pivoting) when it is small, else by BiCGSTAB (van der Vorst 1992) with matrix–vector products
//! in parallel over the stored columns of F. The iterative solve stops at a relative residual of
//! 1e-12. A closed enclosure with no prescribed temperature is refused: its temperatures are
//! undetermined.
//!
//! **Without F.** [`matrix_free`] solves the same equations by stochastic Jacobi sweeps of
//! rays gathered from every patch, for scenes whose F would not fit (10⁶ patches), with each
//! patch's Monte Carlo standard error; [`ThermalSolver`] chooses.

pub mod boundary;
pub mod matrix_free;
#[cfg(test)]
mod matrix_free_tests;

use crate::comm::{Ranks, Serial};
use crate::system::SparseMatrix;
use faer::linalg::solvers::Solve;
use rayon::prelude::*;

pub use boundary::{read_boundary_csv, BoundaryRow};
pub use matrix_free::{open_share, solve_matrix_free, MatrixFreeInfo, MatrixFreeParams};

/// Stefan–Boltzmann constant σ, W m⁻² K⁻⁴ (CODATA 2018, exact in the SI since 2019).
pub const STEFAN_BOLTZMANN: f64 = 5.670_374_419e-8;

/// Highest temperature accepted, K (a boundary's or the surroundings'): σT⁴ = 5.7 × 10¹⁶ W/m².
///
/// σT⁴ itself overflows f64 only past 7.5 × 10⁷⁸ K, but the solve multiplies it by areas and
/// sums it over patches, and its residual norms square those sums. With T ≤ 10⁶ K, the largest
/// area f32 coordinates can span (≈ 10⁷⁷ m²) and 10⁹ patches, a power sum stays below 10¹⁰³
/// and its square below 10²⁰⁶, far from f64's 1.8 × 10³⁰⁸; and 10⁶ K is beyond any grey-body
/// surface (the Sun's photosphere is 5,772 K).
pub const MAX_TEMPERATURE: f64 = 1e6;

/// Largest prescribed net flux, W/m² (either sign): just above σ·[`MAX_TEMPERATURE`]⁴, so a
/// flux can ask for any state the temperature range reaches and no more.
pub const MAX_FLUX: f64 = 1e17;

/// What is known at a surface besides its emissivity.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Condition {
    /// Temperature, K (≥ 0).
    Temperature(f64),
    /// Net radiative flux leaving the surface, W/m² (positive: it loses heat by radiation).
    Flux(f64),
    /// No net radiative flux: a re-radiating (insulated) surface.
    Adiabatic,
}

/// A boundary condition: a grey diffuse surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Boundary {
    /// Hemispherical emissivity ε in (0, 1] (absorptivity, by Kirchhoff's law).
    pub emissivity: f64,
    /// What is prescribed.
    pub condition: Condition,
}

/// The thermal problem over patches: their areas, which boundary each belongs to, and the
/// temperature of the surroundings.
#[derive(Clone, Debug, Default)]
pub struct ThermalSystem {
    /// Area of each patch, m².
    pub area: Vec<f64>,
    /// Boundary of each patch, an index into `boundaries`.
    pub group: Vec<u32>,
    /// The boundary conditions.
    pub boundaries: Vec<Boundary>,
    /// Temperature of the surroundings seen through openings, K.
    pub environment: f64,
    /// A closed enclosure: every non-empty row of F is rescaled (in f64) to sum to exactly 1,
    /// so nothing reaches the surroundings, not even the rounding of F's f32 entries.
    pub closed: bool,
}

/// How the linear system is solved.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum LinearSolver {
    /// Dense LU up to [`DIRECT_MAX`] patches (and within the memory limit), else iterative.
    #[default]
    Auto,
    /// Dense LU with partial pivoting: O(N³) time, O(N²) memory, exact to rounding.
    Direct,
    /// BiCGSTAB on the stored sparse F: O(nnz) per iteration.
    Iterative,
    /// Jacobi sweeps `J ← b + D K J` on the stored F, O(nnz) a sweep; converges for every
    /// solvable problem (the spectral radius of D K is below 1 when some surface has a
    /// prescribed temperature or sees an opening), at a rate set by the reflectances: slowly
    /// where most surfaces re-radiate. Over ranks ([`crate::comm`]) each sweeps its block
    /// of patches and the blocks are all-gathered, as BiCGSTAB's products are.
    Jacobi,
}

impl LinearSolver {
    /// Every choice.
    pub const ALL: [LinearSolver; 4] = [
        LinearSolver::Auto,
        LinearSolver::Direct,
        LinearSolver::Iterative,
        LinearSolver::Jacobi,
    ];

    /// The command-line name.
    pub fn name(self) -> &'static str {
        match self {
            LinearSolver::Auto => "auto",
            LinearSolver::Direct => "direct",
            LinearSolver::Iterative => "iterative",
            LinearSolver::Jacobi => "jacobi",
        }
    }
}

/// Whether the view factors are stored.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ThermalSolver {
    /// Stored up to [`STORED_MAX`] patches when the matrix fits in memory, else matrix-free.
    #[default]
    Auto,
    /// F computed and stored, the system solved by a [`LinearSolver`]: exact to F's accuracy.
    Stored,
    /// No F: stochastic Jacobi sweeps of gathering rays ([`matrix_free`]), with each patch's
    /// Monte Carlo error.
    MatrixFree,
}

impl ThermalSolver {
    /// Every choice.
    pub const ALL: [ThermalSolver; 3] = [
        ThermalSolver::Auto,
        ThermalSolver::Stored,
        ThermalSolver::MatrixFree,
    ];

    /// The command-line name.
    pub fn name(self) -> &'static str {
        match self {
            ThermalSolver::Auto => "auto",
            ThermalSolver::Stored => "stored",
            ThermalSolver::MatrixFree => "matrix-free",
        }
    }
}

/// Most patches [`ThermalSolver::Auto`] stores F for: the adaptive factors of 20,265 facets
/// take about a minute and 2.5 GB (docs/heat-transfer.md); beyond, their N² pairs grow past
/// what the matrix-free solve needs for the same per-patch accuracy.
pub const STORED_MAX: usize = 20_000;

/// Largest system [`LinearSolver::Auto`] solves by dense LU.
pub const DIRECT_MAX: usize = 3000;

/// Parameters of the thermal solve.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ThermalParams {
    /// Direct or iterative.
    pub linear: LinearSolver,
    /// Relative residual ‖b − M J‖ / ‖b‖ at which the iterative solve stops.
    pub tolerance: f64,
    /// Most BiCGSTAB iterations.
    pub max_iterations: usize,
    /// Bytes the dense solve may use.
    pub memory_limit: u64,
}

impl Default for ThermalParams {
    fn default() -> Self {
        Self {
            linear: LinearSolver::Auto,
            tolerance: 1e-12,
            max_iterations: 10_000,
            memory_limit: u64::MAX,
        }
    }
}

/// Why a thermal solve failed.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum ThermalError {
    /// Arrays of different lengths, a group out of range, a non-physical value.
    #[error("malformed thermal system: {0}")]
    Malformed(String),
    /// Nothing fixes the temperature level.
    #[error("no surface has a prescribed temperature and the enclosure is closed (nothing escapes to the surroundings): its temperatures are undetermined; prescribe the temperature of at least one surface")]
    Undetermined,
    /// A prescribed flux that no non-negative temperature can give.
    #[error("boundary {group}: the prescribed fluxes need a negative σT⁴ ({value:.4e} W/m²) on part of it: more heat is taken out than the rest of the enclosure can supply")]
    Unphysical {
        /// Index of the boundary.
        group: usize,
        /// The most negative εσT⁴ found, W/m².
        value: f64,
    },
    /// The dense solve would not fit.
    #[error("the direct solve of {n} patches would need {} MiB but only {} MiB are available; use the iterative solver", needed >> 20, limit >> 20)]
    TooLarge {
        /// Unknowns.
        n: usize,
        /// Bytes needed.
        needed: u64,
        /// Bytes available.
        limit: u64,
    },
    /// The iterative solve did not reach the tolerance.
    #[error("the iterative solve stopped after {iterations} iterations at a relative residual of {residual:.2e}")]
    NotConverged {
        /// Iterations done.
        iterations: usize,
        /// Relative residual reached.
        residual: f64,
    },
}

/// What the solve did and the energy balance of its result.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ThermalInfo {
    /// "direct" or "iterative".
    pub method: &'static str,
    /// BiCGSTAB iterations (0 for the direct solve).
    pub iterations: usize,
    /// Relative residual of the boundary equations, ‖b − M J‖ / ‖b‖.
    pub residual: f64,
    /// Σ A_i q_i, W: the net power leaving all surfaces.
    pub total_power: f64,
    /// Net power lost through the openings, Σ A_i F_ie (J_i − σ T_e⁴), W.
    pub environment_loss: f64,
    /// |total − environment| / Σ |A_i q_i| (0 when nothing flows).
    pub balance_error: f64,
    /// Σ A_i F_ie / Σ A_i: the area-weighted part of the view that reaches no surface.
    pub opening: f64,
    /// Seconds in the linear solve.
    pub seconds: f64,
    /// The matrix-free solve's schedule and errors ([`matrix_free`]); `None` for the solves
    /// of a stored F.
    pub matrix_free: Option<MatrixFreeInfo>,
}

/// The solved state of every patch.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ThermalSolution {
    /// Radiosity J, W/m².
    pub radiosity: Vec<f64>,
    /// Irradiation G, W/m².
    pub irradiation: Vec<f64>,
    /// Temperature, K.
    pub temperature: Vec<f64>,
    /// Net radiative flux leaving, W/m².
    pub flux: Vec<f64>,
    /// Monte Carlo standard error of each patch's flux, W/m² (0 where the flux is
    /// prescribed): the matrix-free solve's; empty for the solves of a stored F.
    pub flux_std_error: Vec<f64>,
    /// Standard error of each patch's temperature, K (0 where prescribed); empty as above.
    pub temperature_std_error: Vec<f64>,
    /// Standard error of each boundary's net power, W; empty as above.
    pub boundary_power_std_error: Vec<f64>,
    /// The solve and its balance.
    pub info: ThermalInfo,
}

impl ThermalSolution {
    /// Per boundary: (area m², net power W, mean temperature K) — the temperature of a
    /// prescribed-temperature boundary is its own; elsewhere the radiative mean
    /// `(Σ A T⁴ / Σ A)^¼`, the uniform temperature that would emit as much.
    pub fn per_boundary(&self, system: &ThermalSystem) -> Vec<(f64, f64, f64)> {
        let k = system.boundaries.len();
        let mut acc = vec![(0.0, 0.0, 0.0); k];
        for (i, &g) in system.group.iter().enumerate() {
            let a = system.area[i];
            let e = &mut acc[g as usize];
            e.0 += a;
            e.1 += a * self.flux[i];
            e.2 += a * self.temperature[i].powi(4);
        }
        acc.iter()
            .zip(&system.boundaries)
            .map(|(&(a, p, t4), b)| match b.condition {
                Condition::Temperature(t) => (a, p, t),
                _ if a > 0.0 => (a, p, (t4 / a).powf(0.25)),
                _ => (a, p, 0.0),
            })
            .collect()
    }
}

impl ThermalSystem {
    /// Check lengths, indices and physical ranges.
    pub fn validate(&self, f: &SparseMatrix) -> Result<(), ThermalError> {
        let n = self.area.len();
        if f.n() != n {
            return Err(ThermalError::Malformed(format!(
                "{} areas, a {}×{} matrix",
                n,
                f.n(),
                f.n()
            )));
        }
        self.validate_patches(n)
    }

    /// [`Self::validate`] without a matrix: `n` patches.
    pub fn validate_patches(&self, n: usize) -> Result<(), ThermalError> {
        let bad = |m: String| Err(ThermalError::Malformed(m));
        if self.group.len() != n || self.area.len() != n {
            return bad(format!(
                "{} areas, {} groups, {} patches",
                self.area.len(),
                self.group.len(),
                n
            ));
        }
        if let Some(i) = (0..n).find(|&i| !(self.area[i].is_finite() && self.area[i] > 0.0)) {
            return bad(format!("patch {i} has area {}", self.area[i]));
        }
        if let Some(i) = (0..n).find(|&i| self.group[i] as usize >= self.boundaries.len()) {
            return bad(format!("patch {i} has no boundary"));
        }
        for (k, b) in self.boundaries.iter().enumerate() {
            if !(b.emissivity > 0.0 && b.emissivity <= 1.0) {
                return bad(format!(
                    "boundary {k}: emissivity {} outside (0, 1]",
                    b.emissivity
                ));
            }
            match b.condition {
                Condition::Temperature(t)
                    if !(t.is_finite() && (0.0..=MAX_TEMPERATURE).contains(&t)) =>
                {
                    return bad(format!(
                        "boundary {k}: temperature {t} K (give 0 to {MAX_TEMPERATURE:e} K)"
                    ))
                }
                Condition::Flux(q) if !(q.is_finite() && q.abs() <= MAX_FLUX) => {
                    return bad(format!(
                        "boundary {k}: flux {q} W/m² (give −{MAX_FLUX:e} to {MAX_FLUX:e} W/m²)"
                    ))
                }
                _ => {}
            }
        }
        if !(self.environment.is_finite() && (0.0..=MAX_TEMPERATURE).contains(&self.environment)) {
            return bad(format!(
                "environment temperature {} K (give 0 to {MAX_TEMPERATURE:e} K)",
                self.environment
            ));
        }
        Ok(())
    }
}

/// The system's pieces per patch: the coupling `d_i` (1 − ε or 1) and the right-hand side.
struct Assembled {
    d: Vec<f64>,
    b: Vec<f64>,
    /// F_ie, the part of each row reaching no surface (rows over 1 count as 1).
    open: Vec<f64>,
    /// 1 / max(row sum, 1): rows that sum past 1 (an estimate's error) are scaled to 1.
    scale: Vec<f64>,
}

fn assemble(system: &ThermalSystem, f: &SparseMatrix) -> Assembled {
    let n = system.area.len();
    let sigma_te4 = STEFAN_BOLTZMANN * system.environment.powi(4);
    let mut d = vec![0.0; n];
    let mut b = vec![0.0; n];
    let mut open = vec![0.0; n];
    let mut scale = vec![1.0; n];
    for i in 0..n {
        let s = f.row_sum(i);
        if system.closed && s > 0.0 {
            scale[i] = 1.0 / s;
            open[i] = 0.0;
        } else {
            scale[i] = 1.0 / s.max(1.0);
            open[i] = (1.0 - s).max(0.0);
        }
        let bd = system.boundaries[system.group[i] as usize];
        let ge = open[i] * sigma_te4;
        match bd.condition {
            Condition::Temperature(t) => {
                let eps = bd.emissivity;
                d[i] = 1.0 - eps;
                b[i] = eps * STEFAN_BOLTZMANN * t.powi(4) + (1.0 - eps) * ge;
            }
            Condition::Flux(q) => {
                d[i] = 1.0;
                b[i] = q + ge;
            }
            Condition::Adiabatic => {
                d[i] = 1.0;
                b[i] = ge;
            }
        }
    }
    Assembled { d, b, open, scale }
}

/// `y_i = (1/A_i) Σ_j A_j F'_ji x_j`, F' the row-capped F: the irradiation that radiosities
/// `x` produce, gathered in parallel over the stored columns.
fn gather(f: &SparseMatrix, area: &[f64], scale: &[f64], x: &[f64], y: &mut [f64]) {
    y.par_iter_mut()
        .enumerate()
        .for_each(|(i, yi)| *yi = column_gather(f, area, scale, x, i));
}

/// `y = M x = x − D K x`.
fn apply(f: &SparseMatrix, system: &ThermalSystem, a: &Assembled, x: &[f64], y: &mut [f64]) {
    gather(f, &system.area, &a.scale, x, y);
    y.par_iter_mut()
        .zip(x.par_iter())
        .zip(a.d.par_iter())
        .for_each(|((yi, &xi), &di)| *yi = xi - di * *yi);
}

/// `(1/A_i) Σ_j A_j F'_ji x_j`, summed in the column's stored order.
fn column_gather(f: &SparseMatrix, area: &[f64], scale: &[f64], x: &[f64], i: usize) -> f64 {
    let s: f64 = f
        .column_entries(i)
        .iter()
        .map(|&(j, v)| {
            let j = j as usize;
            area[j] * scale[j] * v as f64 * x[j]
        })
        .sum();
    s / area[i]
}

/// This rank's block of rows of M, balanced by the stored entries of their columns.
fn blocks(f: &SparseMatrix, n: usize, ranks: &Ranks<'_>) -> std::ops::Range<usize> {
    let costs: Vec<f64> = (0..n)
        .map(|i| 1.0 + f.column_entries(i).len() as f64)
        .collect();
    crate::comm::balance(&costs, ranks.size())[ranks.rank()].clone()
}

/// `g(i)` for every patch: this rank's block `mine` in parallel, then every rank's block
/// all-gathered, so that every rank holds the whole vector.
fn over_ranks(
    mine: &std::ops::Range<usize>,
    ranks: &Ranks<'_>,
    g: impl Fn(usize) -> f64 + Sync + Send,
) -> Vec<f64> {
    let block: Vec<f64> = mine.clone().into_par_iter().map(g).collect();
    ranks.all_gather(&block)
}

/// Σ a_i b_i in index order: the same bits for any number of threads or ranks (a parallel
/// sum's association follows the work splitting). O(N), small beside a product with F.
fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

fn norm(a: &[f64]) -> f64 {
    dot(a, a).sqrt()
}

/// Solve the net-radiation system for every patch's radiosity, then flux and temperature.
pub fn solve(
    system: &ThermalSystem,
    f: &SparseMatrix,
    params: ThermalParams,
) -> Result<ThermalSolution, ThermalError> {
    solve_ranks(system, f, params, &Ranks::new(&Serial))
}

/// [`solve`] over `ranks`, every one of which holds the whole F: the products with M of the
/// Jacobi sweeps and of BiCGSTAB are split over them by rows and all-gathered, and every other
/// vector operation runs on the whole vectors on every rank in index order, so the result is
/// the same bytes for any number of ranks. The dense LU runs on every rank alike.
pub fn solve_ranks(
    system: &ThermalSystem,
    f: &SparseMatrix,
    params: ThermalParams,
    ranks: &Ranks<'_>,
) -> Result<ThermalSolution, ThermalError> {
    system.validate(f)?;
    let start = std::time::Instant::now();
    let n = system.area.len();
    let a = assemble(system, f);
    let total_area: f64 = system.area.iter().sum();
    let opening = (0..n).map(|i| system.area[i] * a.open[i]).sum::<f64>() / total_area;
    let any_temperature = system
        .boundaries
        .iter()
        .any(|b| matches!(b.condition, Condition::Temperature(_)));
    if !any_temperature && opening < 1e-9 {
        return Err(ThermalError::Undetermined);
    }
    let direct = match params.linear {
        LinearSolver::Direct => true,
        LinearSolver::Iterative | LinearSolver::Jacobi => false,
        LinearSolver::Auto => n <= DIRECT_MAX && direct_bytes(n) <= params.memory_limit,
    };
    let (j, iterations) = if direct {
        let needed = direct_bytes(n);
        if needed > params.memory_limit {
            return Err(ThermalError::TooLarge {
                n,
                needed,
                limit: params.memory_limit,
            });
        }
        (solve_direct(system, f, &a), 0)
    } else if params.linear == LinearSolver::Jacobi {
        solve_jacobi(system, f, &a, params, ranks)?
    } else {
        solve_iterative(system, f, &a, params, ranks)?
    };
    // Residual of the boundary equations.
    let mut mj = vec![0.0; n];
    apply(f, system, &a, &j, &mut mj);
    let r: Vec<f64> = (0..n).map(|i| a.b[i] - mj[i]).collect();
    let bn = norm(&a.b);
    let residual = if bn > 0.0 { norm(&r) / bn } else { norm(&r) };
    if !direct && residual > params.tolerance * 10.0 {
        return Err(ThermalError::NotConverged {
            iterations,
            residual,
        });
    }

    // Irradiation, flux, temperature.
    let sigma_te4 = STEFAN_BOLTZMANN * system.environment.powi(4);
    let mut g = vec![0.0; n];
    gather(f, &system.area, &a.scale, &j, &mut g);
    for i in 0..n {
        g[i] += a.open[i] * sigma_te4;
    }
    let flux: Vec<f64> = (0..n).map(|i| j[i] - g[i]).collect();
    let mut temperature = vec![0.0; n];
    let mut worst: Vec<Option<f64>> = vec![None; system.boundaries.len()];
    let j_max = j.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    for i in 0..n {
        let k = system.group[i] as usize;
        let bd = system.boundaries[k];
        temperature[i] = match bd.condition {
            Condition::Temperature(t) => t,
            _ => {
                let e = bd.emissivity;
                let eb = (j[i] - (1.0 - e) * g[i]) / e;
                // Rounding can leave a black-body power of −1e-12 × the scale at a surface
                // at 0 K (the scale being the problem's where the surface sees only the cold
                // surroundings and its own J and G are rounding), and an iterative solve,
                // stopped at a relative residual of `tolerance`, leaves J uncertain by more:
                // up to 1e-10 of the largest J was seen on hidden faces of the hospital at
                // 1e-12 (their J and G both a small negative number). More than that is a
                // prescription no temperature meets.
                let scale = j[i].abs().max(g[i].abs()).max(1e-6 * j_max).max(1e-300);
                let solver = if direct {
                    0.0
                } else {
                    1e4 * params.tolerance * j_max
                };
                if eb < -(1e-8 * scale).max(solver) {
                    let w = worst[k].get_or_insert(eb);
                    *w = w.min(eb);
                }
                (eb.max(0.0) / STEFAN_BOLTZMANN).powf(0.25)
            }
        };
    }
    if let Some((group, value)) = worst
        .iter()
        .enumerate()
        .find_map(|(k, w)| w.map(|v| (k, v)))
    {
        return Err(ThermalError::Unphysical { group, value });
    }
    let total_power: f64 = (0..n).map(|i| system.area[i] * flux[i]).sum();
    let environment_loss: f64 = (0..n)
        .map(|i| system.area[i] * a.open[i] * (j[i] - sigma_te4))
        .sum();
    let scale: f64 = (0..n).map(|i| (system.area[i] * flux[i]).abs()).sum();
    let balance_error = if scale > 0.0 {
        (total_power - environment_loss).abs() / scale
    } else {
        0.0
    };
    Ok(ThermalSolution {
        radiosity: j,
        irradiation: g,
        temperature,
        flux,
        flux_std_error: Vec::new(),
        temperature_std_error: Vec::new(),
        boundary_power_std_error: Vec::new(),
        info: ThermalInfo {
            method: if direct {
                "direct"
            } else if params.linear == LinearSolver::Jacobi {
                "jacobi"
            } else {
                "iterative"
            },
            iterations,
            residual,
            total_power,
            environment_loss,
            balance_error,
            opening,
            seconds: start.elapsed().as_secs_f64(),
            matrix_free: None,
        },
    })
}

/// Bytes of the dense solve: the matrix and its factors.
pub fn direct_bytes(n: usize) -> u64 {
    2 * 8 * (n as u64) * (n as u64)
}

fn solve_direct(system: &ThermalSystem, f: &SparseMatrix, a: &Assembled) -> Vec<f64> {
    let n = system.area.len();
    let mut m = faer::Mat::<f64>::identity(n, n);
    // M_ij = δ_ij − d_i A_j F'_ji / A_i.
    for (row, j, v) in f.triplets() {
        let i = j as usize;
        m[(i, row)] -= a.d[i] * system.area[row] * a.scale[row] * v as f64 / system.area[i];
    }
    let rhs = faer::Mat::<f64>::from_fn(n, 1, |i, _| a.b[i]);
    let x = m.partial_piv_lu().solve(&rhs);
    (0..n).map(|i| x[(i, 0)]).collect()
}

/// Jacobi sweeps `J ← b + D K J` from J = b, each rank relaxing its block of patches (blocks
/// balanced by the stored entries of their columns) and the blocks all-gathered. The residual
/// of the sweep's start, `b − M J = J_new − J`, comes free; its norm is summed over the
/// gathered vector in patch order, so every rank stops after the same sweep.
fn solve_jacobi(
    system: &ThermalSystem,
    f: &SparseMatrix,
    a: &Assembled,
    params: ThermalParams,
    ranks: &Ranks<'_>,
) -> Result<(Vec<f64>, usize), ThermalError> {
    let n = system.area.len();
    let mine = blocks(f, n, ranks);
    let bn = norm(&a.b).max(f64::MIN_POSITIVE);
    let mut x = a.b.clone();
    let mut k = 0;
    loop {
        let new = over_ranks(&mine, ranks, |i| {
            a.b[i] + a.d[i] * column_gather(f, &system.area, &a.scale, &x, i)
        });
        let res = new
            .iter()
            .zip(&x)
            .map(|(y, x)| (y - x) * (y - x))
            .sum::<f64>()
            .sqrt()
            / bn;
        x = new;
        k += 1;
        if res <= params.tolerance {
            return Ok((x, k));
        }
        if k >= params.max_iterations {
            return Err(ThermalError::NotConverged {
                iterations: k,
                residual: res,
            });
        }
    }
}

/// BiCGSTAB (van der Vorst 1992), unpreconditioned: M's diagonal is 1 (a planar patch does not
/// see itself) and its off-diagonal rows sum to at most d_i ≤ 1.
fn solve_iterative(
    system: &ThermalSystem,
    f: &SparseMatrix,
    a: &Assembled,
    params: ThermalParams,
    ranks: &Ranks<'_>,
) -> Result<(Vec<f64>, usize), ThermalError> {
    let n = system.area.len();
    // M x: each rank its block of rows, all-gathered (every rank holds the whole vector).
    let mine = blocks(f, n, ranks);
    let apply =
        |f: &SparseMatrix, system: &ThermalSystem, a: &Assembled, x: &[f64], y: &mut Vec<f64>| {
            *y = over_ranks(&mine, ranks, |i| {
                x[i] - a.d[i] * column_gather(f, &system.area, &a.scale, x, i)
            });
        };
    // Start from each surface's own black-body exitance where it is known, else the b scale.
    let mean_b = a.b.iter().sum::<f64>() / n as f64;
    let mut x: Vec<f64> = (0..n)
        .map(
            |i| match system.boundaries[system.group[i] as usize].condition {
                Condition::Temperature(t) => STEFAN_BOLTZMANN * t.powi(4),
                _ => mean_b.abs(),
            },
        )
        .collect();
    let bn = norm(&a.b).max(f64::MIN_POSITIVE);
    let mut r = vec![0.0; n];
    apply(f, system, a, &x, &mut r);
    r.iter_mut().zip(&a.b).for_each(|(ri, bi)| *ri = bi - *ri);
    let r0 = r.clone();
    let (mut rho, mut alpha, mut omega) = (1.0f64, 1.0f64, 1.0f64);
    let mut v = vec![0.0; n];
    let mut p = vec![0.0; n];
    let mut s = vec![0.0; n];
    let mut t = vec![0.0; n];
    let mut res = norm(&r) / bn;
    let mut k = 0;
    while res > params.tolerance && k < params.max_iterations {
        k += 1;
        let rho_new = dot(&r0, &r);
        if rho_new == 0.0 || omega == 0.0 {
            break;
        }
        let beta = (rho_new / rho) * (alpha / omega);
        rho = rho_new;
        p.par_iter_mut()
            .zip(r.par_iter().zip(v.par_iter()))
            .for_each(|(pi, (&ri, &vi))| *pi = ri + beta * (*pi - omega * vi));
        apply(f, system, a, &p, &mut v);
        let r0v = dot(&r0, &v);
        if r0v == 0.0 {
            break;
        }
        alpha = rho / r0v;
        s.par_iter_mut()
            .zip(r.par_iter().zip(v.par_iter()))
            .for_each(|(si, (&ri, &vi))| *si = ri - alpha * vi);
        if norm(&s) / bn <= params.tolerance {
            x.iter_mut().zip(&p).for_each(|(xi, pi)| *xi += alpha * pi);
            res = norm(&s) / bn;
            break;
        }
        apply(f, system, a, &s, &mut t);
        let tt = dot(&t, &t);
        omega = if tt > 0.0 { dot(&t, &s) / tt } else { 0.0 };
        x.par_iter_mut()
            .zip(p.par_iter().zip(s.par_iter()))
            .for_each(|(xi, (&pi, &si))| *xi += alpha * pi + omega * si);
        r.par_iter_mut()
            .zip(s.par_iter().zip(t.par_iter()))
            .for_each(|(ri, (&si, &ti))| *ri = si - omega * ti);
        res = norm(&r) / bn;
    }
    if res > params.tolerance {
        // One more check on the true residual before giving up (the recursive one drifts).
        let mut mx = vec![0.0; n];
        apply(f, system, a, &x, &mut mx);
        let true_res = (0..n).map(|i| (a.b[i] - mx[i]).powi(2)).sum::<f64>().sqrt() / bn;
        if true_res > params.tolerance {
            return Err(ThermalError::NotConverged {
                iterations: k,
                residual: true_res,
            });
        }
    }
    Ok((x, k))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sigma_t4(t: f64) -> f64 {
        STEFAN_BOLTZMANN * t.powi(4)
    }

    fn dense(rows: &[&[f64]]) -> SparseMatrix {
        SparseMatrix::from_rows(
            rows.iter()
                .map(|r| {
                    r.iter()
                        .enumerate()
                        .filter(|(_, v)| **v != 0.0)
                        .map(|(j, &v)| (j as u32, v as f32))
                        .collect()
                })
                .collect(),
        )
    }

    /// Every linear solver's solution (Jacobi included).
    fn both(system: &ThermalSystem, f: &SparseMatrix) -> [ThermalSolution; 3] {
        [
            LinearSolver::Direct,
            LinearSolver::Iterative,
            LinearSolver::Jacobi,
        ]
        .map(|linear| {
            solve(
                system,
                f,
                ThermalParams {
                    linear,
                    ..Default::default()
                },
            )
            .unwrap()
        })
    }

    /// Incropera & DeWitt, *Fundamentals of Heat and Mass Transfer*, ch. 13, the paint-baking
    /// oven: a long duct whose cross-section is an equilateral triangle of 1 m sides (every
    /// F_ij = 0.5); heater at 1200 K with ε = 0.8, panels at 500 K with ε = 0.4, the third side
    /// insulated (ε = 0.8). The book's answer: 37 kW per metre of duct to the heater, and the
    /// insulated side at 1102 K. The three-surface network with a re-radiating surface gives
    /// q₁ = (E_b1 − E_b2) / [(1−ε₁)/ε₁A₁ + (A₁F₁₂ + (1/A₁F₁R + 1/A₂F₂R)⁻¹)⁻¹ + (1−ε₂)/ε₂A₂].
    #[test]
    fn three_surface_enclosure_with_a_reradiating_wall() {
        let f = dense(&[&[0.0, 0.5, 0.5], &[0.5, 0.0, 0.5], &[0.5, 0.5, 0.0]]);
        let system = ThermalSystem {
            area: vec![1.0; 3],
            group: vec![0, 1, 2],
            boundaries: vec![
                Boundary {
                    emissivity: 0.8,
                    condition: Condition::Temperature(1200.0),
                },
                Boundary {
                    emissivity: 0.4,
                    condition: Condition::Temperature(500.0),
                },
                Boundary {
                    emissivity: 0.8,
                    condition: Condition::Adiabatic,
                },
            ],
            environment: 0.0,
            closed: false,
        };
        let network = (sigma_t4(1200.0) - sigma_t4(500.0))
            / (0.2 / 0.8 + 1.0 / (0.5 + 1.0 / (2.0 + 2.0)) + 0.6 / 0.4);
        for s in both(&system, &f) {
            assert!(
                (s.flux[0] - network).abs() < 1e-9 * network,
                "{}",
                s.flux[0]
            );
            assert!((s.flux[1] + network).abs() < 1e-9 * network);
            assert!(s.flux[2].abs() < 1e-9 * network);
            // The book's rounded figures.
            assert!((s.flux[0] / 1000.0 - 37.0).abs() < 0.05, "{}", s.flux[0]);
            assert!(
                (s.temperature[2] - 1102.0).abs() < 0.5,
                "{}",
                s.temperature[2]
            );
            assert!(s.info.balance_error < 1e-12);
            assert!(s.info.total_power.abs() < 1e-9 * network);
        }
    }

    /// A black enclosure: Q_i = A_i Σ_j F_ij σ (T_i⁴ − T_j⁴), exactly.
    #[test]
    fn black_enclosure_exchange() {
        // A unit cube: opposite faces 0.1998248957, adjacent 0.2000437761 (Howell C-11, C-14).
        let (p, a) = (0.199_824_895_7, 0.200_043_776_1);
        let opposite = [3, 4, 5, 0, 1, 2];
        let rows: Vec<Vec<f64>> = (0..6)
            .map(|i| {
                (0..6)
                    .map(|j| {
                        if i == j {
                            0.0
                        } else if opposite[i] == j {
                            p
                        } else {
                            a
                        }
                    })
                    .collect()
            })
            .collect();
        let f = dense(&rows.iter().map(|r| r.as_slice()).collect::<Vec<_>>());
        let t = [300.0, 400.0, 500.0, 600.0, 700.0, 800.0];
        let system = ThermalSystem {
            area: vec![1.0; 6],
            group: (0..6).collect(),
            boundaries: t
                .iter()
                .map(|&t| Boundary {
                    emissivity: 1.0,
                    condition: Condition::Temperature(t),
                })
                .collect(),
            environment: 0.0,
            closed: false,
        };
        for s in both(&system, &f) {
            for i in 0..6 {
                let q: f64 = (0..6)
                    .map(|j| rows[i][j] * (sigma_t4(t[i]) - sigma_t4(t[j])))
                    .sum();
                // F is stored in f32 (relative rounding 6e-8 an entry).
                assert!((s.flux[i] - q).abs() < 1e-7 * sigma_t4(800.0), "{i}");
            }
            assert!(s.info.balance_error < 1e-12);
        }
    }

    /// A prescribed flux is met, and gives back the temperature that would produce it.
    #[test]
    fn prescribed_flux_round_trip() {
        let f = dense(&[&[0.0, 0.5, 0.5], &[0.5, 0.0, 0.5], &[0.5, 0.5, 0.0]]);
        let mut system = ThermalSystem {
            area: vec![1.0, 2.0, 1.0],
            group: vec![0, 1, 2],
            boundaries: vec![
                Boundary {
                    emissivity: 0.7,
                    condition: Condition::Temperature(900.0),
                },
                Boundary {
                    emissivity: 0.5,
                    condition: Condition::Temperature(400.0),
                },
                Boundary {
                    emissivity: 0.3,
                    condition: Condition::Temperature(650.0),
                },
            ],
            environment: 0.0,
            closed: false,
        };
        // Not reciprocal (areas differ): the balance must hold anyway.
        let first = solve(&system, &f, ThermalParams::default()).unwrap();
        assert!(first.info.balance_error < 1e-12);
        system.boundaries[2].condition = Condition::Flux(first.flux[2]);
        for s in both(&system, &f) {
            assert!(
                (s.temperature[2] - 650.0).abs() < 1e-8,
                "{}",
                s.temperature[2]
            );
            assert!((s.flux[0] - first.flux[0]).abs() < 1e-8 * first.flux[0].abs());
        }
    }

    /// One plate facing the surroundings alone: it loses εσ(T⁴ − T_e⁴).
    #[test]
    fn open_plate_loses_to_the_environment() {
        let f = SparseMatrix::from_rows(vec![vec![]]);
        let system = ThermalSystem {
            area: vec![2.0],
            group: vec![0],
            boundaries: vec![Boundary {
                emissivity: 0.6,
                condition: Condition::Temperature(500.0),
            }],
            environment: 300.0,
            closed: false,
        };
        for s in both(&system, &f) {
            let q = 0.6 * (sigma_t4(500.0) - sigma_t4(300.0));
            assert!((s.flux[0] - q).abs() < 1e-10 * q);
            assert!((s.info.environment_loss - 2.0 * q).abs() < 1e-9 * q);
        }
    }

    #[test]
    fn closed_without_temperature_is_refused() {
        let f = dense(&[&[0.0, 1.0], &[1.0, 0.0]]);
        let system = ThermalSystem {
            area: vec![1.0; 2],
            group: vec![0, 1],
            boundaries: vec![
                Boundary {
                    emissivity: 0.5,
                    condition: Condition::Flux(10.0),
                },
                Boundary {
                    emissivity: 0.5,
                    condition: Condition::Adiabatic,
                },
            ],
            environment: 0.0,
            closed: false,
        };
        assert_eq!(
            solve(&system, &f, ThermalParams::default()),
            Err(ThermalError::Undetermined)
        );
    }

    #[test]
    fn impossible_flux_is_refused() {
        // A plate that must lose 1 MW/m² in a 300 K enclosure it sees entirely.
        let f = dense(&[&[0.0, 1.0], &[0.5, 0.0]]);
        let system = ThermalSystem {
            area: vec![1.0, 2.0],
            group: vec![0, 1],
            boundaries: vec![
                Boundary {
                    emissivity: 0.5,
                    condition: Condition::Flux(-1e6),
                },
                Boundary {
                    emissivity: 0.5,
                    condition: Condition::Temperature(300.0),
                },
            ],
            environment: 0.0,
            closed: false,
        };
        assert!(matches!(
            solve(&system, &f, ThermalParams::default()),
            Err(ThermalError::Unphysical { group: 0, .. })
        ));
    }
}
