//! Command-line syntax (clap).

use clap::{Args, Parser, Subcommand};
use std::path::PathBuf;

/// Diffuse global illumination by the radiosity method.
#[derive(Debug, Parser)]
#[command(name = "radiosity", version, about, long_about = None)]
pub struct Cli {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// The subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Solve a scene and render a picture (PNG, or linear HDR as .exr / .pfm).
    Render(RenderArgs),
    /// Solve a scene and write one CSV row per patch, or bake the radiosity into a mesh's vertex
    /// colours (.glb, .gltf, .ply).
    Solve(SolveCmdArgs),
    /// Show a baked glTF as a glTF viewer does (unlit, COLOR_0 as is), without solving.
    View(ViewArgs),
    /// Measure ray-casting speed and the time to converge the Cornell box.
    Bench(BenchArgs),
    /// Solve a given linear system: a form-factor matrix (Matrix Market) and a patches CSV.
    SolveSystem(SolveSystemArgs),
    /// Compute a view-factor (form-factor) matrix and write it as Matrix Market.
    FormFactors(FormFactorsArgs),
    /// Reproduce the papers' experiments: `convergence` (Gortler et al. section 6, figures 3–8) or
    /// `complexity` (Szirmay-Kalos & Márton's claims as N grows). Writes CSVs, plots (SVG and PNG) and a
    /// Markdown summary.
    Experiment(ExperimentArgs),
}

/// Which experiment.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum ExperimentKind {
    /// Eq. 22 error per iteration and per CPU second of every solver on the office, the dim
    /// and bright cube and random sparse systems.
    Convergence,
    /// Time, iterations and peak memory of the form-factor methods and solvers as N grows,
    /// with fitted exponents beside the paper's.
    Complexity,
}

/// `radiosity experiment`.
#[derive(Debug, Args)]
pub struct ExperimentArgs {
    /// The experiment.
    #[arg(value_enum)]
    pub kind: ExperimentKind,
    /// Folder for the results (created if missing).
    #[arg(long, value_name = "DIR", default_value = "experiments")]
    pub out: PathBuf,
    /// Small sizes that run in seconds.
    #[arg(long)]
    pub quick: bool,
    /// Worker threads (default: one per core).
    #[arg(long, value_name = "T")]
    pub threads: Option<usize>,
    /// Seed of the random systems, Monte Carlo and photons.
    #[arg(long, value_name = "S", default_value_t = 1)]
    pub seed: u64,
    /// convergence: iterations per method, in sweeps (multiples of N).
    #[arg(long, value_name = "K", default_value_t = 3.0)]
    pub sweeps: f64,
    /// complexity: patch counts (default 250,500,1000,2000,4000; with --quick 40,…,640).
    #[arg(long, value_name = "N,N,…", value_delimiter = ',', num_args = 1..)]
    pub sizes: Option<Vec<usize>>,
}

/// `radiosity form-factors`.
#[derive(Debug, Args)]
pub struct FormFactorsArgs {
    /// A built-in scene or an .obj or .mgf file.
    pub scene: String,
    /// Method: hemicube, hemisphere, tetrahedron, monte-carlo, analytic (unoccluded).
    #[arg(long, value_name = "M", default_value = "monte-carlo")]
    pub method: String,
    /// P: pixels along a hemicube/tetrahedron face, cells across the hemisphere's disc.
    #[arg(long, value_name = "P", default_value_t = 128)]
    pub resolution: u32,
    /// Points over each patch for the projection methods (rounded up to a square).
    #[arg(long, value_name = "K", default_value_t = 16)]
    pub samples: u32,
    /// Monte Carlo rays per row (standard deviation of each entry ≤ 1/(2√N)).
    #[arg(long, value_name = "N", default_value_t = 1_000_000)]
    pub rays: u32,
    /// Seed of Monte Carlo.
    #[arg(long, value_name = "S", default_value_t = 1)]
    pub seed: u64,
    /// One row per input face (no subdivision): face-to-face view factors.
    #[arg(long, conflicts_with_all = ["patches", "max_edge"])]
    pub faces: bool,
    /// Approximate number of patches.
    #[arg(long, value_name = "N", conflicts_with = "max_edge")]
    pub patches: Option<usize>,
    /// Largest patch edge, scene units.
    #[arg(long, value_name = "L")]
    pub max_edge: Option<f32>,
    /// Storage while computing: auto (dense up to 4,096 patches), dense or sparse.
    #[arg(long, value_name = "S", default_value = "auto")]
    pub storage: String,
    /// Drop negative entries (F ≥ 0).
    #[arg(long)]
    pub clamp: bool,
    /// Rescale every row to sum to 1 (closed enclosures only).
    #[arg(long)]
    pub normalize_rows: bool,
    /// Make A_i F_ij = A_j F_ji keeping row sums (symmetric matrix scaling, Knight 2008).
    #[arg(long)]
    pub symmetrize: bool,
    /// Output matrix (Matrix Market, coordinate real general, 1-based).
    #[arg(long, short, value_name = "F.mtx")]
    pub out: PathBuf,
    /// Also write the rows' patches (or faces) as CSV.
    #[arg(long, value_name = "patches.csv")]
    pub patches_out: Option<PathBuf>,
    /// Worker threads (default: one per core). Results do not depend on it.
    #[arg(long, value_name = "T")]
    pub threads: Option<usize>,
}

/// `radiosity solve-system`.
#[derive(Debug, Args)]
pub struct SolveSystemArgs {
    /// Form factors F_ij: Matrix Market, coordinate real general, 1-based indices.
    #[arg(long, value_name = "F.mtx")]
    pub form_factors: PathBuf,
    /// Patches: CSV with a header; columns `area` and either `reflectance`,`emission` or
    /// `reflectance_r`,`reflectance_g`,`reflectance_b`,`emission_r`,`emission_g`,`emission_b`.
    #[arg(long, value_name = "patches.csv")]
    pub patches: PathBuf,
    /// Solution method (see `radiosity solve --help`).
    #[arg(long, value_name = "M", default_value = "progressive")]
    pub solver: String,
    /// Output: one radiosity row per patch.
    #[arg(long, short, value_name = "B.csv")]
    pub out: PathBuf,
    /// Write the convergence trace (iteration,seconds,error,unshot) to this CSV.
    #[arg(long, value_name = "FILE")]
    pub trace: Option<PathBuf>,
    /// Stop after this many iterations at the latest.
    #[arg(long, value_name = "K")]
    pub max_iterations: Option<u64>,
    /// Stop when the unshot energy is at most this fraction of the emitted energy.
    #[arg(long, value_name = "T", default_value_t = 0.01)]
    pub tolerance: f64,
    /// Relaxation factor ω of `sor`.
    #[arg(long, value_name = "W", default_value_t = 1.1)]
    pub omega: f64,
    /// `stochastic`: each photon carries 1/N of the shooter's unshot power.
    #[arg(long, value_name = "N", default_value_t = 1000)]
    pub photons: u32,
    /// Seed of `stochastic`.
    #[arg(long, value_name = "S", default_value_t = 1)]
    pub seed: u64,
}

/// Options shared by every command that solves a scene.
#[derive(Debug, Args)]
pub struct SolveArgs {
    /// A built-in scene (cornell, cube-dim, cube-bright, furnace, office, …) or a path to an .obj
    /// or .mgf file.
    #[arg(default_value = "cornell")]
    pub scene: String,
    /// MGF and glTF scenes: keep every surface one-sided, ignoring MGF's `sides 2` (RenderPark's
    /// -force-onesided) and glTF's `doubleSided`. By default a two-sided surface is two polygons
    /// back to back.
    #[arg(long)]
    pub one_sided: bool,
    /// Approximate total number of patches.
    #[arg(long, value_name = "N", conflicts_with = "max_edge")]
    pub patches: Option<usize>,
    /// Largest patch edge, in scene units (instead of --patches).
    #[arg(long, value_name = "L")]
    pub max_edge: Option<f32>,
    /// Monte Carlo rays per form-factor row for a patch shooting an average share of the power
    /// (emitters get proportionally more).
    #[arg(long, value_name = "N", default_value_t = 256)]
    pub rays: u32,
    /// Seed of every random stream.
    #[arg(long, value_name = "S", default_value_t = 1)]
    pub seed: u64,
    /// Worker threads (default: one per core). Results do not depend on it.
    #[arg(long, value_name = "T")]
    pub threads: Option<usize>,
    /// Stop when the unshot energy is at most this fraction of the emitted energy.
    #[arg(long, value_name = "F", default_value_t = 0.01)]
    pub tolerance: f64,
    /// Stop after this many iterations (shots, rows, photons) at the latest.
    #[arg(long, value_name = "K")]
    pub max_iterations: Option<u64>,
    /// Solution method: gauss, jacobi, gauss-seidel-0, gauss-seidel, gauss-seidel-jacobi, sor,
    /// southwell, progressive, overshoot-ambient, overshoot, stochastic.
    #[arg(long, value_name = "M", default_value = "progressive")]
    pub solver: String,
    /// Relaxation factor ω of `sor`.
    #[arg(long, value_name = "W", default_value_t = 1.1)]
    pub omega: f64,
    /// `stochastic`: each photon carries 1/N of the shooter's unshot power.
    #[arg(long, value_name = "N", default_value_t = 1000)]
    pub photons: u32,
    /// Form-factor method: monte-carlo (rows on demand for shooting solvers), or hemicube,
    /// hemisphere, tetrahedron, analytic (unoccluded), whose full matrix is computed first.
    #[arg(long, value_name = "M", default_value = "monte-carlo")]
    pub form_factors: String,
    /// P for the hemicube, tetrahedron and hemisphere.
    #[arg(long, value_name = "P", default_value_t = 128)]
    pub resolution: u32,
    /// Points per patch for the hemicube, tetrahedron and hemisphere.
    #[arg(long, value_name = "K", default_value_t = 16)]
    pub samples: u32,
    /// Write the convergence trace (iteration,seconds,error,unshot) to this CSV. The form
    /// factors are then estimated and stored in full first, and the error is measured against
    /// their LU solution (N ≤ 5,000).
    #[arg(long, value_name = "FILE")]
    pub trace: Option<PathBuf>,
}

/// Camera overrides.
#[derive(Debug, Args)]
pub struct CameraArgs {
    /// Eye point x,y,z.
    #[arg(long, value_name = "X,Y,Z", allow_hyphen_values = true)]
    pub eye: Option<String>,
    /// Point looked at x,y,z.
    #[arg(long, value_name = "X,Y,Z", allow_hyphen_values = true)]
    pub target: Option<String>,
    /// Up direction x,y,z.
    #[arg(long, value_name = "X,Y,Z", allow_hyphen_values = true)]
    pub up: Option<String>,
    /// Vertical field of view, degrees.
    #[arg(long, value_name = "DEG")]
    pub fov: Option<f32>,
}

/// `radiosity render`.
#[derive(Debug, Args)]
pub struct RenderArgs {
    #[command(flatten)]
    pub solve: SolveArgs,
    #[command(flatten)]
    pub camera: CameraArgs,
    /// Output image: .png (tone-mapped sRGB), .exr or .pfm (linear radiance). Default SCENE.png.
    #[arg(long, short, value_name = "FILE")]
    pub out: Option<PathBuf>,
    #[command(flatten)]
    pub image: ImageArgs,
    /// Exposure adjustment in stops, relative to automatic exposure (PNG only).
    #[arg(
        long,
        value_name = "EV",
        default_value_t = 0.0,
        allow_hyphen_values = true
    )]
    pub exposure: f32,
}

/// `radiosity solve`.
#[derive(Debug, Args)]
pub struct SolveCmdArgs {
    #[command(flatten)]
    pub solve: SolveArgs,
    /// Output: .csv (one row per patch: geometry, material, radiosity), or a baked mesh with the
    /// radiosity at its vertices: .glb / .gltf (glTF 2.0: COLOR_0 display colours, unlit
    /// materials, _RADIOSITY linear values) or .ply (vertex colours plus float radiosity).
    #[arg(long, short, value_name = "FILE")]
    pub out: PathBuf,
    /// Baked meshes: exposure adjustment in stops, relative to automatic exposure (which maps
    /// the 97th percentile of patch luminance, by area, to 0.9). COLOR_0 = min(1, B · scale).
    #[arg(
        long,
        value_name = "EV",
        default_value_t = 0.0,
        allow_hyphen_values = true
    )]
    pub exposure: f32,
}

/// `radiosity bench`.
#[derive(Debug, Args)]
pub struct BenchArgs {
    /// Patches of the Cornell box.
    #[arg(long, value_name = "N", default_value_t = 10_000)]
    pub patches: usize,
    /// Rays per ray-casting measurement.
    #[arg(long, value_name = "N", default_value_t = 2_000_000)]
    pub rays: usize,
    /// Repetitions of each measurement (the median is reported).
    #[arg(long, value_name = "K", default_value_t = 5)]
    pub runs: usize,
    /// Worker threads (default: one per core).
    #[arg(long, value_name = "T")]
    pub threads: Option<usize>,
    /// Instead: time per iteration of every solver on the Cornell box's stored form factors
    /// at these patch counts.
    #[arg(long, value_name = "N,N,…", value_delimiter = ',', num_args = 1..)]
    pub solvers: Option<Vec<usize>>,
    /// Instead: every form-factor method's error against Howell's closed forms at three
    /// resolutions, and its time per row on the Cornell box at 1,000, 4,000 and 16,000 patches.
    #[arg(long)]
    pub form_factors: bool,
    /// Instead: the full face-to-face view-factor matrix of the built-in `city` (19,847 facets)
    /// by monte-carlo and by hemicube, with time and peak memory.
    #[arg(long)]
    pub city: bool,
}

/// `radiosity view`.
#[derive(Debug, Args)]
pub struct ViewArgs {
    /// A baked glTF (.glb or .gltf) whose primitives carry COLOR_0, e.g. from
    /// `radiosity solve SCENE --out baked.glb`.
    pub file: PathBuf,
    #[command(flatten)]
    pub camera: CameraArgs,
    /// Output image: .png (COLOR_0 sRGB-encoded), .exr or .pfm (COLOR_0 linear). Default
    /// FILE.png.
    #[arg(long, short, value_name = "FILE")]
    pub out: Option<PathBuf>,
    #[command(flatten)]
    pub image: ImageArgs,
}

/// Picture size and sampling, shared by `render` and `view`.
#[derive(Debug, Args)]
pub struct ImageArgs {
    /// Image width in pixels.
    #[arg(long, value_name = "W", default_value_t = 512)]
    pub width: u32,
    /// Image height in pixels.
    #[arg(long, value_name = "H", default_value_t = 512)]
    pub height: u32,
    /// Camera rays per pixel.
    #[arg(long, value_name = "N", default_value_t = 4)]
    pub spp: u32,
}
