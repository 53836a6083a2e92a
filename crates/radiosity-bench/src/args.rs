//! The harness's command line: one subcommand per measurement, each with its own flags.

use clap::{Args, Parser, Subcommand, ValueEnum};
use radiosity::solve::SolverParams;
use radiosity_cli::args::SolverArg;
use std::path::PathBuf;

/// The workbench that measures the `radiosity` engine: ray casting, solvers, form factors,
/// scale, pictures, hierarchical accuracy and distributed runs. Each figure is the median of
/// `--runs` repetitions where a measurement repeats.
#[derive(Debug, Parser)]
#[command(name = "radiosity-bench", version, about, long_about = None, after_help = EXAMPLES)]
pub struct BenchCli {
    /// Worker threads (default: one per core); the pool is started once for the whole run,
    /// and `scale` passes it to each child `radiosity solve`.
    #[arg(long, global = true, value_name = "T")]
    pub threads: Option<usize>,
    /// What to measure.
    #[command(subcommand)]
    pub mode: Mode,
}

const EXAMPLES: &str = "Examples:
  radiosity-bench cornell --patches 10000 --runs 5
  radiosity-bench rays hosp.mgf --one-sided --rays 2000000
  radiosity-bench scale hosp.mgf --one-sided --sizes 25000,100000 --solver stochastic-jacobi
  radiosity-bench pictures cornell --out pictures
  radiosity-bench canyon --sizes 500,2000,8000 --closed
  radiosity-bench view3d --source View3D --sizes 484,1936,7744,20449
  radiosity-bench daylight-floor --rooms 20 --points-per-room 500 --run
  mpirun -np 2 radiosity-bench ranks hosp.mgf --one-sided --patches 100000";

/// The measurements.
#[derive(Debug, Subcommand)]
pub enum Mode {
    /// Ray-casting speed on incoherent form-factor rays, and the time to converge the Cornell
    /// box (meshing, hierarchy, form factors and solve) to 1 % unshot energy (the old plain
    /// `radiosity bench`).
    Cornell(CornellArgs),
    /// Ray casting on one scene alone, by every backend this binary has (`radiosity bench
    /// --rays SCENE`).
    Rays(RaysArgs),
    /// Time per iteration of every solver on the Cornell box's stored form factors at these
    /// patch counts (`radiosity bench --solvers`).
    Solvers(SolversArgs),
    /// Every form-factor method's error against Howell's closed forms at three resolutions,
    /// and its time per row on the Cornell box at 1,000, 4,000 and 16,000 patches
    /// (`radiosity bench --form-factor-accuracy`).
    #[command(visible_alias = "form-factor-accuracy")]
    FormFactors(RunsArgs),
    /// The full face-to-face view-factor matrix of the built-in `city` (19,847 facets) by
    /// monte-carlo and by hemicube, with time and peak memory (`radiosity bench --city`).
    City,
    /// The adaptive view factors against Monte Carlo on urban canyons written as View3D files
    /// (3 × 3 box buildings on a ground plane, facets of about equal size): time, CPU time,
    /// row sums (exact closure with `--closed`), what the method did.
    Canyon(CanyonArgs),
    /// Side by side with NIST View3D, built here from its source with `cc -O2`: open urban
    /// canyons of 121 k² facets, `radiosity form-factors --method adaptive` and View3D each
    /// timed as a child (CPU, wall, peak memory), and their agreement (mean and worst |ΔF|
    /// and |Δ row sum|, sky view per facet).
    View3d(View3dArgs),
    /// The distributed methods (Jacobi on stored rows, stochastic Jacobi) on SCENE over the
    /// ranks of this run (run it under `mpirun -np K`; alone it is one rank): time per stage,
    /// per iteration, bytes exchanged, load balance and parallel efficiency against one rank
    /// (`radiosity bench --ranks`).
    Ranks(RanksArgs),
    /// Solve SCENE at each of `--sizes`, each in a fresh `radiosity solve` process (read back
    /// through its `--report json`), and print rays, wall and CPU time, each stage's time,
    /// peak resident memory, the bookkeeping's share of the wall time (`solve %`), the round
    /// trip of a value between two cores before and after the solve (`xcore0 ns`, `xcore1
    /// ns`), and the fitted exponents against N (`radiosity bench --scale`).
    Scale(ScaleArgs),
    /// Time against error of the three ways to make a picture (radiosity shown directly, the
    /// final gather, the path tracer) on SCENE, against a path-traced reference; writes
    /// pictures.csv, pictures.svg/.png and the images to --out (`radiosity bench --pictures`).
    Pictures(PicturesArgs),
    /// Per-surface accuracy of hierarchical radiosity (at each --link-errors) and of uniform
    /// meshes (at each --sizes, progressive) on SCENE, against path-traced surface means
    /// (`radiosity bench --hierarchical`).
    Hierarchical(HierarchicalArgs),
    /// Issue 58's annual benchmark: writes an office floor of side-lit rooms (two rows along a
    /// corridor, glazed windows), a work-plane grid at 0.8 m and a synthetic EPW year, and with
    /// `--run` times `radiosity lighting FLOOR --weather --grid --annual` on them (CPU, wall,
    /// peak memory, the metrics).
    DaylightFloor(FloorArgs),
}

/// Repetitions of a measurement.
#[derive(Debug, Args)]
pub struct RunsArgs {
    /// Repetitions of each measurement (the median is reported).
    #[arg(long, value_name = "K", default_value_t = 5)]
    pub runs: usize,
}

/// `canyon`.
#[derive(Debug, Args)]
pub struct CanyonArgs {
    /// About how many facets each canyon has.
    #[arg(long, value_name = "N,N,…", value_delimiter = ',', num_args = 1.., default_value = "500,2000,8000")]
    pub sizes: Vec<usize>,
    /// Close the canyon with a faceted lid and sides (every row of F then sums to 1).
    #[arg(long)]
    pub closed: bool,
    /// Monte Carlo rays per row.
    #[arg(long, value_name = "N", default_value_t = 10_000)]
    pub rays: u32,
    /// The adaptive method's accuracy.
    #[arg(long, value_name = "E", default_value_t = radiosity::formfactor::DEFAULT_ACCURACY)]
    pub accuracy: f64,
    /// Folder for the View3D files (created if missing).
    #[arg(long, value_name = "DIR", default_value = "canyon")]
    pub out: std::path::PathBuf,
}

/// `daylight-floor`.
#[derive(Debug, Args)]
pub struct FloorArgs {
    /// Rooms (even: two rows).
    #[arg(long, value_name = "N", default_value_t = 20)]
    pub rooms: usize,
    /// Work-plane points in each room.
    #[arg(long, value_name = "N", default_value_t = 500)]
    pub points_per_room: usize,
    /// Seed of the synthetic year's clear and overcast days.
    #[arg(long, value_name = "S", default_value_t = 58)]
    pub seed: u64,
    /// Folder for floor.obj, floor.mtl, floor.pts, year.epw and the run's outputs (created if
    /// missing).
    #[arg(long, value_name = "DIR", default_value = "daylight-floor")]
    pub out: std::path::PathBuf,
    /// Also run and time the annual command on the files.
    #[arg(long)]
    pub run: bool,
    /// More arguments for `radiosity lighting` (after `--`), e.g. `-- --sky-rays 4096`.
    #[arg(last = true, value_name = "ARGS")]
    pub extra: Vec<String>,
}

/// `view3d`.
#[derive(Debug, Args)]
pub struct View3dArgs {
    /// View3D's source folder (a checkout of jasondegraw/View3D, or its `src`): built with
    /// `$CC` (default `cc`) at `-O2` from the files its CMakeLists.txt lists.
    #[arg(long, value_name = "DIR")]
    pub source: std::path::PathBuf,
    /// About how many facets each canyon has (121 k² exactly: 484, 1936, 7744, 20449, …).
    #[arg(long, value_name = "N,N,…", value_delimiter = ',', num_args = 1.., default_value = "484,1936,7744")]
    pub sizes: Vec<usize>,
    /// Canyons with more facets than this run ours alone (View3D's time grows as N^2.3 and
    /// beyond).
    #[arg(long, value_name = "N", default_value_t = 10_000)]
    pub view3d_up_to: usize,
    /// Runs of each tool at each size (the medians are reported).
    #[arg(long, value_name = "K", default_value_t = 1)]
    pub runs: usize,
    /// The adaptive method's accuracy.
    #[arg(long, value_name = "E", default_value_t = radiosity::formfactor::DEFAULT_ACCURACY)]
    pub accuracy: f64,
    /// Folder for View3D's build, the scenes, the logs and `skyview-N.csv` (created if missing).
    #[arg(long, value_name = "DIR", default_value = "view3d-bench")]
    pub out: std::path::PathBuf,
    /// Keep both view-factor files (N² numbers each: 540 MB at 7,744 facets).
    #[arg(long)]
    pub keep: bool,
}

/// `cornell`.
#[derive(Debug, Args)]
pub struct CornellArgs {
    /// Patches of the Cornell box.
    #[arg(long, value_name = "N", default_value_t = 10_000)]
    pub patches: usize,
    /// Rays per ray-casting measurement.
    #[arg(long, value_name = "N", default_value_t = 2_000_000)]
    pub rays: usize,
    /// Repetitions of each measurement (the median is reported).
    #[arg(long, value_name = "K", default_value_t = 5)]
    pub runs: usize,
}

/// `rays`.
#[derive(Debug, Args)]
pub struct RaysArgs {
    /// The scene: a built-in name or a file.
    pub scene: String,
    /// Rays per measurement.
    #[arg(long, value_name = "N", default_value_t = 2_000_000)]
    pub rays: usize,
    /// Patches the scene is meshed into.
    #[arg(long, value_name = "N", default_value_t = 10_000)]
    pub patches: usize,
    /// Repetitions of each measurement (the median is reported).
    #[arg(long, value_name = "K", default_value_t = 5)]
    pub runs: usize,
    /// Keep every surface one-sided (see `radiosity solve --help`).
    #[arg(long)]
    pub one_sided: bool,
    /// Which ray casters to time (`embree` needs a build with `--features embree`).
    #[arg(long, value_enum, default_value = "all")]
    pub backend: BackendArg,
}

/// `solvers`.
#[derive(Debug, Args)]
pub struct SolversArgs {
    /// The patch counts.
    #[arg(value_name = "N,N,…", value_delimiter = ',', num_args = 1.., required = true)]
    pub sizes: Vec<usize>,
    /// Repetitions of each measurement (the median is reported).
    #[arg(long, value_name = "K", default_value_t = 5)]
    pub runs: usize,
}

/// The solver flags `ranks` and `scale` pass on.
#[derive(Debug, Args)]
pub struct SolveFlags {
    /// Keep every surface one-sided (see `radiosity solve --help`).
    #[arg(long)]
    pub one_sided: bool,
    /// The solution method.
    #[arg(long, value_name = "M", value_enum, default_value = "progressive")]
    pub solver: SolverArg,
    /// Stop at this fraction of the emitted energy unshot.
    #[arg(long, value_name = "F", default_value_t = SolverParams::default().tolerance)]
    pub tolerance: f64,
    /// `stochastic-jacobi`: rays per patch and iteration.
    #[arg(long, value_name = "N", default_value_t = SolverParams::default().iteration_rays)]
    pub iteration_rays: u32,
    /// `stochastic-jacobi`: rays per patch of the final gathering iteration (0: none).
    #[arg(long, value_name = "N", default_value_t = SolverParams::default().gather_rays)]
    pub gather_rays: u32,
}

/// `ranks`.
#[derive(Debug, Args)]
pub struct RanksArgs {
    /// The scene: a built-in name or a file.
    pub scene: String,
    /// Patches the scene is meshed into.
    #[arg(long, value_name = "N", default_value_t = 10_000)]
    pub patches: usize,
    /// Repetitions of each measurement (the median is reported).
    #[arg(long, value_name = "K", default_value_t = 5)]
    pub runs: usize,
    /// The solver flags.
    #[command(flatten)]
    pub solve: SolveFlags,
}

/// `scale`.
#[derive(Debug, Args)]
pub struct ScaleArgs {
    /// The scene: a built-in name or a file.
    pub scene: String,
    /// The patch counts.
    #[arg(long, value_name = "N,N,…", value_delimiter = ',', num_args = 1.., required = true)]
    pub sizes: Vec<usize>,
    /// Time the method's bookkeeping alone, in this process: solve each size once to fill the
    /// row cache, then `--runs` more times on the cached rows (no rays), and print the shots,
    /// the receivers updated and the median time of those solves.
    #[arg(long)]
    pub bookkeeping: bool,
    /// `--bookkeeping`: repetitions (the median is reported).
    #[arg(long, value_name = "K", default_value_t = 5)]
    pub runs: usize,
    /// The solver flags.
    #[command(flatten)]
    pub solve: SolveFlags,
}

/// `pictures`.
#[derive(Debug, Args)]
pub struct PicturesArgs {
    /// The scene: a built-in name or a file.
    pub scene: String,
    /// The reference image (.pfm) to compare against; without it one is path traced with
    /// --reference-spp paths a pixel.
    #[arg(long, value_name = "REF.pfm")]
    pub reference: Option<PathBuf>,
    /// A second, independent reference (another `--seed`): the references' own noise is then
    /// measured from their difference rather than fitted, and the pictures are compared with
    /// their average.
    #[arg(long = "reference-b", value_name = "REF2.pfm", requires = "reference")]
    pub reference_b: Option<PathBuf>,
    /// Paths per pixel of the reference when it is made.
    #[arg(long, value_name = "N", default_value_t = 16384)]
    pub reference_spp: u32,
    /// Image size (square).
    #[arg(long, value_name = "PX", default_value_t = 256)]
    pub size: u32,
    /// Folder for the results.
    #[arg(long, value_name = "DIR", default_value = "pictures")]
    pub out: PathBuf,
}

/// `hierarchical`.
#[derive(Debug, Args)]
pub struct HierarchicalArgs {
    /// The scene: a built-in name or a file.
    pub scene: String,
    /// Keep every surface one-sided (see `radiosity solve --help`).
    #[arg(long)]
    pub one_sided: bool,
    /// The link errors to try.
    #[arg(long, value_name = "E,E,…", value_delimiter = ',', num_args = 1..)]
    pub link_errors: Option<Vec<f64>>,
    /// Patch counts of the uniform meshes (progressive).
    #[arg(long, value_name = "N,N,…", value_delimiter = ',', num_args = 1..)]
    pub sizes: Option<Vec<usize>>,
    /// Refinement passes of the hierarchical solves (default: the solver's).
    #[arg(long, value_name = "N")]
    pub passes: Option<u32>,
    /// Seeds of the solves' random streams (visibility samples, Monte Carlo rows); each method
    /// runs once a seed, a row each, to show how much the errors owe to the draw.
    #[arg(long = "solve-seeds", value_name = "S,S,…", value_delimiter = ',', num_args = 1.., default_value = "1")]
    pub solve_seeds: Vec<u64>,
    /// The uniform solves stop at this fraction of the emitted energy unshot.
    #[arg(long, value_name = "F", default_value_t = SolverParams::default().tolerance)]
    pub tolerance: f64,
    /// The reference surface means (surfaces.csv); made when absent.
    #[arg(long, value_name = "surfaces.csv")]
    pub reference: Option<PathBuf>,
    /// Paths (`--reference-tracer path`, shared by area) or particles (`light`) of the
    /// reference in all.
    #[arg(long, value_name = "N", default_value_t = 20_000_000)]
    pub reference_paths: u64,
    /// How the reference is made when the --reference file is absent: a light tracer or a
    /// path tracer (both independent of every radiosity method).
    #[arg(
        long = "reference-tracer",
        value_enum,
        value_name = "T",
        default_value = "light"
    )]
    pub reference_tracer: ReferenceTracer,
    /// Monte Carlo rays a form-factor row of the uniform solves.
    #[arg(long = "uniform-rays", value_name = "N", default_value_t = 1024)]
    pub uniform_rays: u32,
}

/// Ray-casting backends (`rays --backend`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum BackendArg {
    /// Every backend this binary has.
    All,
    /// The engine's own BVH (and, where it meets pieces whole, its tree over every patch's
    /// triangles beside it).
    Bvh,
    /// Intel Embree 3 (builds with `--features embree`).
    Embree,
}

/// How `hierarchical` makes its reference surface means (`--reference-tracer`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ReferenceTracer {
    /// Particles shot from the emitters, each crediting the surfaces it reaches: rays go where
    /// the light goes (best where lamps throw small bright spots).
    Light,
    /// Paths from points spread over each surface by area, with next-event estimation.
    Path,
}
