//! Section 6 of Gortler, Cohen & Slusallek (1993): the error of its eq. 22,
//!
//! ```text
//! Error(k) = Σ_i (B*_i − B_i(k)) / Σ_i (B*_i − E_i),
//! ```
//!
//! the share of the reflected radiosity not yet accounted for, after every iteration of every
//! solver, where B* is the direct (LU) solution of the same system. The paper's six algorithms
//! are `gauss-seidel-0`, `gauss-seidel-jacobi` (Gauss-Seidel+Jacobi), `southwell`, `progressive`
//! (Southwell+Jacobi), `gauss-seidel` (Gauss-Seidel-E) and `overshoot`; the others run too.
//! One iteration is one row or column of F (a relaxation or a shot); for `stochastic` it is
//! `photons` photons, the work that shoots one patch's unshot power once; `gauss` is one
//! iteration, shown against CPU time only.
//!
//! The cases are the paper's: an office of about 270 patches (the built-in `office`), the
//! inside of a cube with emitters on its ceiling (384 patches, reflectances around 0.3 and
//! around 0.8), with F from the hemicube as the paper's were; and random sparse 390 × 390
//! row-diagonally-dominant systems, dim and bright, with few and with all patches emitting.

use super::random::section6;
use super::{CaseProgress, ExperimentError, StoredSystem};
use radiosity::accel::Bvh;
use radiosity::formfactor::{Estimator, FormFactorMethod, Params as FfParams, Storage};
use radiosity::mesh::patch_system;
use radiosity::mesh::{Mesh, MeshParams};
use radiosity::observe::Observer;
use radiosity::scene::builtin;
use radiosity::solve::gauss::dense_solve;
use radiosity::solve::{relative_error, start, Solver, SolverParams};
use std::time::Instant;

/// How the experiment runs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Params {
    /// Small cases (about 100 patches, coarse hemicubes) that run in seconds.
    pub quick: bool,
    /// Iterations per method, in sweeps (multiples of N).
    pub sweeps: f64,
    /// Photons per unit of shot power for `stochastic` (see [`SolverParams::photons`]).
    pub photons: u32,
    /// Seed of the random systems and of `stochastic`.
    pub seed: u64,
    /// Relaxation factor of `sor`.
    pub omega: f64,
}

impl Default for Params {
    fn default() -> Self {
        Self {
            quick: false,
            sweeps: 3.0,
            photons: 1000,
            seed: 1,
            omega: 1.1,
        }
    }
}

/// The methods in the order they are reported: the paper's six first.
pub const METHODS: [Solver; 11] = [
    Solver::GaussSeidel0,
    Solver::GaussSeidelJacobi,
    Solver::Southwell,
    Solver::Progressive,
    Solver::GaussSeidel,
    Solver::Overshoot,
    Solver::Jacobi,
    Solver::Sor,
    Solver::OvershootAmbient,
    Solver::Stochastic,
    Solver::Gauss,
];

/// The paper's name for a method, where it has one.
pub fn paper_name(m: Solver) -> Option<&'static str> {
    Some(match m {
        Solver::GaussSeidel0 => "Gauss-Seidel-0",
        Solver::GaussSeidelJacobi => "Gauss-Seidel+Jacobi",
        Solver::Southwell => "Southwell",
        Solver::Progressive => "Southwell+Jacobi",
        Solver::GaussSeidel => "Gauss-Seidel-E",
        Solver::Overshoot => "Overshooting",
        _ => return None,
    })
}

/// One test case: a stored system and what it is.
#[derive(Clone, Debug)]
pub struct Case {
    /// File-name-safe name (`office`, `cube-dim`, …).
    pub name: String,
    /// Title of its plots.
    pub title: String,
    /// The paper's figure for this case, if it has one.
    pub figure: Option<u32>,
    /// The system.
    pub system: StoredSystem,
    /// Seconds spent computing its form factors (0 for random systems).
    pub form_factor_seconds: f64,
}

/// One point of a convergence curve.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Point {
    /// Iterations done (for `stochastic`: photons / `photons`).
    pub iteration: f64,
    /// CPU seconds spent in the method's steps so far (error evaluation excluded).
    pub seconds: f64,
    /// Eq. 22 error of the method's output.
    pub error: f64,
}

/// The convergence of one method on one case.
#[derive(Clone, Debug)]
pub struct Curve {
    /// The method.
    pub method: Solver,
    /// Its points, in order of iterations.
    pub points: Vec<Point>,
}

impl Curve {
    /// The error after `iteration` iterations (the last point at or before it).
    pub fn error_at(&self, iteration: f64) -> Option<f64> {
        self.points
            .iter()
            .take_while(|p| p.iteration <= iteration + 1e-9)
            .last()
            .map(|p| p.error)
    }

    /// The first point from which |error| stays at most `level` to the end of the run
    /// (overshooting methods can cross zero on their way, which does not count).
    pub fn settled_below(&self, level: f64) -> Option<Point> {
        let last_above = self.points.iter().rposition(|p| p.error.abs() > level);
        match last_above {
            None => self.points.first().copied(),
            Some(k) => self.points.get(k + 1).copied(),
        }
    }
}

fn scene_system(
    scene: &radiosity::scene::Scene,
    mesh: &Mesh,
    f: radiosity::system::SparseMatrix,
) -> StoredSystem {
    StoredSystem {
        system: patch_system(scene, mesh),
        f,
    }
}

fn hemicube_matrix(
    mesh: &Mesh,
    params: FfParams,
    progress: &dyn Observer,
    label: &str,
) -> Result<(radiosity::system::SparseMatrix, f64), ExperimentError> {
    let bvh = Bvh::build(mesh);
    let case_progress = CaseProgress::begin(progress, label, mesh.len() as u64);
    let t = Instant::now();
    let f = Estimator::new(mesh, &bvh, params)?
        .matrix(Storage::Sparse, &radiosity::observe::Silent)
        .into_sparse();
    let s = t.elapsed().as_secs_f64();
    case_progress.advance(mesh.len() as u64);
    case_progress.end(&format!("{} rows in {s:.1} s", mesh.len()));
    Ok((f, s))
}

/// Build the cases: office, dim and bright cube, four random systems.
pub fn cases(params: &Params, progress: &dyn Observer) -> Result<Vec<Case>, ExperimentError> {
    let ff = FfParams {
        method: FormFactorMethod::Hemicube,
        resolution: if params.quick { 32 } else { 128 },
        samples: if params.quick { 4 } else { 16 },
        ..Default::default()
    };
    let mut out = Vec::new();
    let office = builtin::office();
    let mesh = Mesh::build(
        &office,
        MeshParams::Patches(if params.quick { 80 } else { 270 }),
    )?;
    let (f, s) = hemicube_matrix(&mesh, ff, progress, "office: hemicube form factors")?;
    out.push(Case {
        name: "office".into(),
        title: format!("office, {} patches", mesh.len()),
        figure: Some(3),
        system: scene_system(&office, &mesh, f),
        form_factor_seconds: s,
    });
    let dim = builtin::cube(builtin::CubeVariant::Dim);
    let bright = builtin::cube(builtin::CubeVariant::Bright);
    let mesh = Mesh::build(
        &dim,
        MeshParams::MaxEdge(if params.quick { 0.25 } else { 0.125 }),
    )?;
    let (f, s) = hemicube_matrix(&mesh, ff, progress, "cube: hemicube form factors")?;
    // Same geometry, so the same F for both variants.
    out.push(Case {
        name: "cube-dim".into(),
        title: format!("dim cube (ρ ≈ 0.3), {} patches", mesh.len()),
        figure: Some(4),
        system: scene_system(&dim, &mesh, f.clone()),
        form_factor_seconds: s,
    });
    out.push(Case {
        name: "cube-bright".into(),
        title: format!("bright cube (ρ ≈ 0.8), {} patches", mesh.len()),
        figure: Some(5),
        system: scene_system(&bright, &mesh, f),
        form_factor_seconds: s,
    });
    let n = if params.quick { 100 } else { 390 };
    let few = (n / 80).max(3);
    for (name, rho, emitters, figure) in [
        ("random-dim-few", 0.3, few, Some(6)),
        ("random-bright-few", 0.8, few, Some(7)),
        ("random-dim-many", 0.3, n, Some(8)),
        ("random-bright-many", 0.8, n, None),
    ] {
        let brightness = if rho < 0.5 { "dim" } else { "bright" };
        let who = if emitters == n {
            "all emitting".to_string()
        } else {
            format!("{emitters} emitters")
        };
        out.push(Case {
            name: name.into(),
            title: format!("random {brightness} {n}×{n} matrix, {who}"),
            figure,
            system: section6(
                n,
                0.1,
                rho,
                emitters,
                params.seed.wrapping_add(figure.unwrap_or(9) as u64),
            ),
            form_factor_seconds: 0.0,
        });
    }
    Ok(out)
}

/// Run every method of [`METHODS`] on `case` for `params.sweeps · N` iterations (or until its
/// error is below 1e-9), recording the eq. 22 error after each iteration.
pub fn run_case(
    case: &mut Case,
    params: &Params,
    progress: &dyn Observer,
) -> Result<Vec<Curve>, ExperimentError> {
    let n = case.system.len();
    let (sys, f) = case.system.parts();
    let exact = dense_solve(sys, f, 1 << 34)?;
    let max_iterations = (params.sweeps * n as f64).ceil().max(1.0) as u64;
    let case_progress = CaseProgress::begin(
        progress,
        &format!("{}: {} methods", case.name, METHODS.len()),
        METHODS.len() as u64 * max_iterations,
    );
    let mut curves = Vec::new();
    let mut b = Vec::new();
    for (k, &method) in METHODS.iter().enumerate() {
        let sp = SolverParams {
            tolerance: 0.0,
            omega: params.omega,
            photons: params.photons,
            seed: params.seed,
            memory_limit: 1 << 34,
            ..Default::default()
        };
        // Photons per reported iteration for stochastic, 1 otherwise.
        let unit = if method == Solver::Stochastic {
            params.photons as u64
        } else {
            1
        };
        let mut solver = start(method, sys, f, &sp)?;
        let mut points = Vec::new();
        let mut seconds = 0.0;
        if method != Solver::Gauss {
            solver.radiosity(&mut b);
            points.push(Point {
                iteration: 0.0,
                seconds: 0.0,
                error: relative_error(&exact, &sys.emission, &b),
            });
        }
        let budget = max_iterations * unit;
        loop {
            let t = Instant::now();
            let more = solver.step(f);
            seconds += t.elapsed().as_secs_f64();
            let done = solver.iterations();
            if done % unit == 0 || !more || done >= budget {
                solver.radiosity(&mut b);
                let error = relative_error(&exact, &sys.emission, &b);
                points.push(Point {
                    iteration: done as f64 / unit as f64,
                    seconds,
                    error,
                });
                case_progress.advance(k as u64 * max_iterations + done / unit);
                if !more || done >= budget || error.abs() < 1e-9 {
                    break;
                }
            }
        }
        curves.push(Curve { method, points });
    }
    let last = |m: Solver| {
        curves
            .iter()
            .find(|c| c.method == m)
            .and_then(|c| c.error_at(n as f64 / 2.0))
            .unwrap_or(f64::NAN)
    };
    case_progress.end(&format!(
        "after N/2 iterations: overshoot {:.2e}, progressive {:.2e}, gauss-seidel-0 {:.2e}",
        last(Solver::Overshoot),
        last(Solver::Progressive),
        last(Solver::GaussSeidel0)
    ));
    Ok(curves)
}
