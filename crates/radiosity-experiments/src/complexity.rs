//! The complexity claims of Szirmay-Kalos & Márton (1995), measured as N grows on the Cornell box
//! (`--patches N`, at least four sizes spanning a factor of 16):
//!
//! | case | claim (paper) |
//! |---|---|
//! | `hemicube-matrix`: every row by the hemicube, P² pixels | O(N²·P²) time, O(N²) space |
//! | `monte-carlo-matrix`: every row by n random rays (eq. 7) | O(N·n) time and space (sparse) |
//! | `gauss`: Gauss elimination (dense LU) | O(N³) time, O(N²) space |
//! | `jacobi`, `gauss-seidel`: iteration on the stored F | iterations independent of N, O(N²) time |
//! | `progressive`: one hemicube per shot, nothing stored | iterations ∝ N (eq. 28), O(N²) time, O(N) space |
//! | `stochastic`: photon shooting, nothing stored | iterations ∝ N·n, O(n·N²) time, O(N) space |
//!
//! The iterative solvers run to a fixed tolerance on the unshot energy. Jacobi's and
//! Gauss-Seidel's iterations are reported in sweeps (relaxations / N), the shooting methods' in
//! shots or photons. Memory is the peak of the heap above what was allocated before the case
//! (so the stored F that Jacobi and Gauss-Seidel read is not theirs; it is the matrix cases').

use super::{fit_exponent, measure, CaseProgress, ExperimentError, MemoryProbe};
use radiosity::accel::Bvh;
use radiosity::formfactor::OnDemandRows;
use radiosity::formfactor::{Estimator, FormFactorMethod, Params as FfParams, Storage};
use radiosity::mesh::patch_system;
use radiosity::mesh::{Mesh, MeshParams};
use radiosity::observe::Observer;
use radiosity::scene::builtin;
use radiosity::solve::gauss::dense_solve;
use radiosity::solve::{run, start, Solver, SolverParams};
use radiosity::system::SparseMatrix;
use radiosity::system::{Operator, System};

/// How the experiment runs.
#[derive(Clone, Debug, PartialEq)]
pub struct Params {
    /// Target patch counts.
    pub sizes: Vec<usize>,
    /// Hemicube resolution P (pixels along the top face).
    pub resolution: u32,
    /// Rays per row n of the Monte Carlo matrix.
    pub rays: u32,
    /// Photons per unit of shot power of `stochastic` (its n).
    pub photons: u32,
    /// Unshot-energy tolerance of the deterministic iterative solvers.
    pub tolerance: f64,
    /// Unshot-energy tolerance of `stochastic`.
    pub stochastic_tolerance: f64,
    /// Seed of every random stream.
    pub seed: u64,
}

impl Params {
    /// The full experiment: N = 250 … 4,000.
    pub fn full() -> Self {
        Self {
            sizes: vec![250, 500, 1000, 2000, 4000],
            resolution: 64,
            rays: 100,
            photons: 100,
            tolerance: 1e-3,
            stochastic_tolerance: 1e-2,
            seed: 1,
        }
    }

    /// Small sizes (N = 40 … 640) that run in seconds.
    pub fn quick() -> Self {
        Self {
            sizes: vec![40, 80, 160, 320, 640],
            resolution: 32,
            rays: 20,
            photons: 50,
            ..Self::full()
        }
    }
}

/// What is measured.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Quantity {
    /// Wall-clock seconds.
    Seconds,
    /// Iterations (sweeps, shots or photons) to the tolerance.
    Iterations,
    /// Peak heap bytes.
    Memory,
}

impl Quantity {
    /// Column name.
    pub fn name(self) -> &'static str {
        match self {
            Quantity::Seconds => "seconds",
            Quantity::Iterations => "iterations",
            Quantity::Memory => "peak_bytes",
        }
    }
}

/// One claim of the paper: `case`'s `quantity` grows as N^exponent.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Claim {
    /// The case.
    pub case: &'static str,
    /// What grows.
    pub quantity: Quantity,
    /// The paper's exponent of N.
    pub exponent: f64,
    /// The paper's statement.
    pub text: &'static str,
}

/// The cases in the order they run.
pub const CASES: [&str; 7] = [
    "hemicube-matrix",
    "monte-carlo-matrix",
    "gauss",
    "jacobi",
    "gauss-seidel",
    "progressive",
    "stochastic",
];

/// Every claim checked.
pub const CLAIMS: [Claim; 16] = [
    Claim {
        case: "hemicube-matrix",
        quantity: Quantity::Seconds,
        exponent: 2.0,
        text: "O(N²·P²)",
    },
    Claim {
        case: "hemicube-matrix",
        quantity: Quantity::Memory,
        exponent: 2.0,
        text: "O(N²)",
    },
    Claim {
        case: "monte-carlo-matrix",
        quantity: Quantity::Seconds,
        exponent: 1.0,
        text: "O(N·n)",
    },
    Claim {
        case: "monte-carlo-matrix",
        quantity: Quantity::Memory,
        exponent: 1.0,
        text: "O(N·n), sparse",
    },
    Claim {
        case: "gauss",
        quantity: Quantity::Seconds,
        exponent: 3.0,
        text: "O(N³)",
    },
    Claim {
        case: "gauss",
        quantity: Quantity::Memory,
        exponent: 2.0,
        text: "O(N²)",
    },
    Claim {
        case: "jacobi",
        quantity: Quantity::Iterations,
        exponent: 0.0,
        text: "independent of N",
    },
    Claim {
        case: "jacobi",
        quantity: Quantity::Seconds,
        exponent: 2.0,
        text: "O(N²)",
    },
    Claim {
        case: "gauss-seidel",
        quantity: Quantity::Iterations,
        exponent: 0.0,
        text: "independent of N",
    },
    Claim {
        case: "gauss-seidel",
        quantity: Quantity::Seconds,
        exponent: 2.0,
        text: "O(N²)",
    },
    Claim {
        case: "progressive",
        quantity: Quantity::Iterations,
        exponent: 1.0,
        text: "∝ N (eq. 28)",
    },
    Claim {
        case: "progressive",
        quantity: Quantity::Seconds,
        exponent: 2.0,
        text: "O(N²)",
    },
    Claim {
        case: "progressive",
        quantity: Quantity::Memory,
        exponent: 1.0,
        text: "O(N)",
    },
    Claim {
        case: "stochastic",
        quantity: Quantity::Iterations,
        exponent: 1.0,
        text: "∝ N·n",
    },
    Claim {
        case: "stochastic",
        quantity: Quantity::Seconds,
        exponent: 2.0,
        text: "O(n·N²)",
    },
    Claim {
        case: "stochastic",
        quantity: Quantity::Memory,
        exponent: 1.0,
        text: "O(N)",
    },
];

/// One measurement: a case at one size.
#[derive(Clone, Debug, PartialEq)]
pub struct Measurement {
    /// The case (one of [`CASES`]).
    pub case: &'static str,
    /// Patches N.
    pub patches: usize,
    /// Wall-clock seconds.
    pub seconds: f64,
    /// Iterations to the tolerance, for the iterative solvers.
    pub iterations: Option<f64>,
    /// Peak heap bytes above the case's start, when a probe is given.
    pub peak_bytes: Option<u64>,
    /// Non-zeros of the matrix (the two matrix cases only).
    pub nnz: Option<u64>,
    /// Whether an iterative solver reached its tolerance.
    pub converged: Option<bool>,
}

impl Measurement {
    /// The value of `q`, if measured.
    pub fn value(&self, q: Quantity) -> Option<f64> {
        match q {
            Quantity::Seconds => Some(self.seconds),
            Quantity::Iterations => self.iterations,
            Quantity::Memory => self.peak_bytes.map(|b| b as f64),
        }
    }
}

/// A claim with the exponent fitted to the measurements.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fit {
    /// The claim.
    pub claim: Claim,
    /// Least-squares slope of log(quantity) against log(N); `None` if not measurable.
    pub fitted: Option<f64>,
}

/// Fit every claim to `measurements`.
pub fn fits(measurements: &[Measurement]) -> Vec<Fit> {
    CLAIMS
        .iter()
        .map(|&claim| {
            let pts: Vec<(f64, f64)> = measurements
                .iter()
                .filter(|m| m.case == claim.case)
                .filter_map(|m| Some((m.patches as f64, m.value(claim.quantity)?)))
                .collect();
            Fit {
                claim,
                fitted: fit_exponent(&pts),
            }
        })
        .collect()
}

fn solve_to_tolerance(
    method: Solver,
    system: &System,
    source: &mut dyn Operator,
    params: &SolverParams,
) -> Result<radiosity::solve::Info, ExperimentError> {
    let mut solver = start(method, system, source, params)?;
    Ok(run(&mut *solver, source, params, false, &mut |_, _| true))
}

struct Size {
    mesh: Mesh,
    bvh: Bvh,
    data: System,
    f: Option<SparseMatrix>,
}

/// Run every case at every size. `progress` gets one bar per case, one step per size.
pub fn run_all(
    params: &Params,
    probe: Option<&dyn MemoryProbe>,
    progress: &dyn Observer,
) -> Result<Vec<Measurement>, ExperimentError> {
    if params.sizes.len() < 2 || params.sizes.contains(&0) {
        return Err(ExperimentError::Invalid(
            "complexity: at least two positive sizes are needed".into(),
        ));
    }
    let scene = builtin::cornell();
    let mut sizes = Vec::new();
    for &n in &params.sizes {
        let mesh = Mesh::build(&scene, MeshParams::Patches(n))?;
        let bvh = Bvh::build(&mesh);
        let data = patch_system(&scene, &mesh);
        sizes.push(Size {
            mesh,
            bvh,
            data,
            f: None,
        });
    }
    let hemicube = FfParams {
        method: FormFactorMethod::Hemicube,
        resolution: params.resolution,
        samples: 1,
        seed: params.seed,
        // One hemicube per shot, as the paper runs it: nothing kept between shots.
        cache_bytes: 0,
        ..Default::default()
    };
    let mut out = Vec::new();
    for case in CASES {
        let case_progress = CaseProgress::begin(progress, case, sizes.len() as u64);
        for (k, s) in sizes.iter_mut().enumerate() {
            let n = s.mesh.len();
            let mut m = Measurement {
                case,
                patches: n,
                seconds: 0.0,
                iterations: None,
                peak_bytes: None,
                nnz: None,
                converged: None,
            };
            let system = &s.data;
            let solver_params = SolverParams {
                tolerance: params.tolerance,
                photons: params.photons,
                seed: params.seed,
                memory_limit: 1 << 36,
                ..Default::default()
            };
            match case {
                "hemicube-matrix" | "monte-carlo-matrix" => {
                    let ff = if case == "hemicube-matrix" {
                        hemicube
                    } else {
                        FfParams {
                            method: FormFactorMethod::MonteCarlo,
                            rays: params.rays,
                            seed: params.seed,
                            ..Default::default()
                        }
                    };
                    let est = Estimator::new(&s.mesh, &s.bvh, ff)?;
                    let (f, seconds, peak) = measure(probe, || {
                        est.matrix(Storage::Sparse, &radiosity::observe::Silent)
                            .into_sparse()
                    });
                    m.seconds = seconds;
                    m.peak_bytes = peak;
                    m.nnz = Some(f.nnz() as u64);
                    if case == "hemicube-matrix" {
                        s.f = Some(f);
                    }
                }
                "gauss" => {
                    let f = s.f.as_mut().expect("hemicube matrix first");
                    // Once unmeasured: the linear-algebra kernels allocate their per-thread
                    // packing buffers on first use at each blocking size.
                    dense_solve(system, f, 1 << 36)?;
                    let (b, seconds, peak) = measure(probe, || dense_solve(system, f, 1 << 36));
                    b?;
                    m.seconds = seconds;
                    m.peak_bytes = peak;
                }
                "jacobi" | "gauss-seidel" => {
                    let method = Solver::from_name(case).expect("a solver name");
                    let f = s.f.as_mut().expect("hemicube matrix first");
                    let (info, seconds, peak) = measure(probe, || {
                        solve_to_tolerance(method, system, f, &solver_params)
                    });
                    let info = info?;
                    m.seconds = seconds;
                    m.peak_bytes = peak;
                    m.iterations = Some(info.iterations as f64 / n as f64);
                    m.converged = Some(info.converged);
                }
                "progressive" | "stochastic" => {
                    let (result, seconds, peak) = measure(probe, || {
                        if case == "progressive" {
                            let est = Estimator::new(&s.mesh, &s.bvh, hemicube)?;
                            let mut source = OnDemandRows::new(est);
                            solve_to_tolerance(
                                Solver::Progressive,
                                system,
                                &mut source,
                                &solver_params,
                            )
                        } else {
                            let mc = FfParams {
                                cache_bytes: 0,
                                ..FfParams::monte_carlo(params.rays, params.seed)
                            };
                            let mut source =
                                OnDemandRows::new(Estimator::new(&s.mesh, &s.bvh, mc)?);
                            let sp = SolverParams {
                                tolerance: params.stochastic_tolerance,
                                ..solver_params
                            };
                            solve_to_tolerance(Solver::Stochastic, system, &mut source, &sp)
                        }
                    });
                    let info = result?;
                    m.seconds = seconds;
                    m.peak_bytes = peak;
                    m.iterations = Some(info.iterations as f64);
                    m.converged = Some(info.converged);
                }
                _ => unreachable!(),
            }
            out.push(m);
            case_progress.advance(k as u64 + 1);
        }
        case_progress.end(case);
    }
    Ok(out)
}
