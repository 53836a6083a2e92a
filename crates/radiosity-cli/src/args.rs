//! Command-line syntax (clap): the only place that knows the flags. Method names come from the
//! library's enums, so `--help` lists exactly what the library implements and a misspelt
//! method gets clap's "did you mean".

use clap::builder::PossibleValue;
use clap::{Args, Parser, Subcommand, ValueEnum};
use radiosity::formfactor::{FormFactorMethod, Storage};
use radiosity::pipeline::Rows;
use radiosity::solve::Solver;
use radiosity::solve::SolverParams;
use std::path::PathBuf;

/// A solver named on the command line (`--solver`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SolverArg(pub Solver);

const fn wrap_solvers<const N: usize>(all: [Solver; N]) -> [SolverArg; N] {
    let mut out = [SolverArg(Solver::Gauss); N];
    let mut i = 0;
    while i < N {
        out[i] = SolverArg(all[i]);
        i += 1;
    }
    out
}

static SOLVERS: [SolverArg; Solver::ALL.len()] = wrap_solvers(Solver::ALL);

impl ValueEnum for SolverArg {
    fn value_variants<'a>() -> &'a [Self] {
        &SOLVERS
    }

    fn to_possible_value(&self) -> Option<PossibleValue> {
        Some(PossibleValue::new(self.0.name()).help(self.0.summary()))
    }
}

/// A method that solves a scene (`solve`, `render`, `--solver`): every linear-system solver,
/// or `hierarchical` (None), which needs the scene's geometry.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SceneSolverArg(pub Option<Solver>);

const fn wrap_scene_solvers<const N: usize, const M: usize>(
    all: [Solver; N],
) -> [SceneSolverArg; M] {
    let mut out = [SceneSolverArg(None); M];
    let mut i = 0;
    while i < N {
        out[i] = SceneSolverArg(Some(all[i]));
        i += 1;
    }
    out
}

static SCENE_SOLVERS: [SceneSolverArg; Solver::ALL.len() + 1] = wrap_scene_solvers(Solver::ALL);

/// The name and summary of the hierarchical method.
pub const HIERARCHICAL: (&str, &str) = (
    "hierarchical",
    "hierarchical radiosity with clustering: adaptive elements and links (Hanrahan et al. 1991; Smits et al. 1994)",
);

impl ValueEnum for SceneSolverArg {
    fn value_variants<'a>() -> &'a [Self] {
        &SCENE_SOLVERS
    }

    fn to_possible_value(&self) -> Option<PossibleValue> {
        Some(match self.0 {
            Some(s) => PossibleValue::new(s.name()).help(s.summary()),
            None => PossibleValue::new(HIERARCHICAL.0).help(HIERARCHICAL.1),
        })
    }
}

/// A form-factor method named on the command line (`--form-factor-method`, `--method`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FormFactorArg(pub FormFactorMethod);

const fn wrap_methods<const N: usize>(all: [FormFactorMethod; N]) -> [FormFactorArg; N] {
    let mut out = [FormFactorArg(FormFactorMethod::MonteCarlo); N];
    let mut i = 0;
    while i < N {
        out[i] = FormFactorArg(all[i]);
        i += 1;
    }
    out
}

static METHODS: [FormFactorArg; FormFactorMethod::ALL.len()] = wrap_methods(FormFactorMethod::ALL);

impl ValueEnum for FormFactorArg {
    fn value_variants<'a>() -> &'a [Self] {
        &METHODS
    }

    fn to_possible_value(&self) -> Option<PossibleValue> {
        Some(PossibleValue::new(self.0.name()).help(self.0.summary()))
    }
}

/// Whether rows of F are stored or computed on demand (`--rows`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum RowsArg {
    /// On demand for shooting solvers with monte-carlo; stored otherwise.
    Auto,
    /// Every row computed and stored before the solver starts.
    Stored,
    /// Rows computed when the solver asks, for any method (O(N) memory plus a bounded cache).
    OnDemand,
}

impl From<RowsArg> for Rows {
    fn from(r: RowsArg) -> Self {
        match r {
            RowsArg::Auto => Rows::Auto,
            RowsArg::Stored => Rows::Stored,
            RowsArg::OnDemand => Rows::OnDemand,
        }
    }
}

/// Matrix storage while computing (`form-factors --storage`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum StorageArg {
    /// Dense up to 4,096 patches, sparse beyond.
    Auto,
    /// N × N values.
    Dense,
    /// Sparse rows: never N² zeros.
    Sparse,
}

impl From<StorageArg> for Storage {
    fn from(s: StorageArg) -> Self {
        match s {
            StorageArg::Auto => Storage::Auto,
            StorageArg::Dense => Storage::Dense,
            StorageArg::Sparse => Storage::Sparse,
        }
    }
}

const SCENE: &str = "Scene";
const MESHING: &str = "Meshing";
const FORM_FACTORS: &str = "Form factors";
const SOLVER: &str = "Solver";
const OUTPUT: &str = "Output";
const CAMERA: &str = "Camera";
const RUN: &str = "Run";
const PICTURE: &str = "Picture";
const LIGHTMAP: &str = "Lightmap";
const DAYLIGHT: &str = "Daylight";

/// Diffuse global illumination by the radiosity method: baked light, view factors and heat
/// transfer, and every classic solver side by side.
#[derive(Debug, Parser)]
#[command(name = "radiosity", version, about, long_about = None, after_help = EXAMPLES_TOP)]
pub struct Cli {
    /// Worker threads (default: one per core), for any command; the pool is started once.
    /// Results do not depend on it.
    #[arg(long, global = true, value_name = "T", help_heading = RUN)]
    pub threads: Option<usize>,
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

const EXAMPLES_TOP: &str = "Examples:
  radiosity render                                   the built-in Cornell box → cornell.png
  radiosity solve office.obj --out office.glb        bake light into vertex colours
  radiosity form-factors room.obj --faces -o F.mtx   view factors between faces
  radiosity experiment convergence --quick           the papers' solvers side by side";

const EXAMPLES_RENDER: &str = "Examples:
  radiosity render cornell --patches 4000 -o cornell.png
  radiosity render hosp.mgf --one-sided --solver overshoot-ambient --width 1024 --height 768
  radiosity render cornell --integrator radiosity -o preview.png   the solution itself, fastest
  radiosity render cornell --integrator path --spp 1024 -o reference.exr";

const EXAMPLES_SOLVE: &str = "Examples:
  radiosity solve cornell -o cornell.csv
  radiosity solve room.gltf --patches 20000 --out baked.glb --exposure 0.5";

const EXAMPLES_VIEW: &str = "Examples:
  radiosity view baked.glb
  radiosity view baked.glb --eye 0,1.6,3 --target 0,1,0 -o shot.png";

const EXAMPLES_SOLVE_SYSTEM: &str = "Examples:
  radiosity solve-system --matrix F.mtx --patches patches.csv -o B.csv
  radiosity solve-system --matrix F.mtx --patches patches.csv --solver southwell --trace t.csv -o B.csv";

const EXAMPLES_FORM_FACTORS: &str = "Examples:
  radiosity form-factors room.obj --faces --rays 1000000 -o F.mtx --patches-out faces.csv
  radiosity form-factors cube-dim --method hemicube --resolution 256 --symmetrize -o F.mtx
  radiosity form-factors room.vs3 --format view3d -o room.vf
  radiosity form-factors room.obj --faces --method adaptive --accuracy 1e-6 -o F.mtx";

const EXAMPLES_EXPERIMENT: &str = "Examples:
  radiosity experiment convergence --out docs/experiments
  radiosity experiment complexity --quick --sizes 100,200,400";

/// The subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Solve a scene and render a picture (PNG, or linear HDR as .exr / .pfm).
    #[command(after_help = EXAMPLES_RENDER)]
    Render(RenderArgs),
    /// Solve a scene and write one CSV row per patch, or bake the radiosity into a mesh's vertex
    /// colours (.glb, .gltf, .ply).
    #[command(after_help = EXAMPLES_SOLVE)]
    Solve(SolveCmdArgs),
    /// Show a baked glTF as a glTF viewer does (unlit, COLOR_0 as is, or lit by its
    /// MOZ_lightmap lightmaps), without solving.
    #[command(after_help = EXAMPLES_VIEW)]
    View(ViewArgs),
    /// Solve a given linear system: a form-factor matrix (Matrix Market) and a patches CSV.
    #[command(after_help = EXAMPLES_SOLVE_SYSTEM)]
    SolveSystem(SolveSystemArgs),
    /// Compute a view-factor (form-factor) matrix and write it as Matrix Market.
    #[command(visible_alias = "view-factors", after_help = EXAMPLES_FORM_FACTORS)]
    FormFactors(FormFactorsArgs),
    /// Reproduce the papers' experiments: `convergence` (Gortler, Cohen & Slusallek 1993,
    /// section 6, figures 3–8) or `complexity` (Szirmay-Kalos & Márton 1995, their claims as N
    /// grows). Writes CSVs, plots (SVG and PNG) and a Markdown summary.
    #[command(after_help = EXAMPLES_EXPERIMENT)]
    Experiment(ExperimentArgs),
    /// Lighting design: illuminance in lux at calculation points from luminaires with
    /// photometric files (IES, EULUMDAT) placed by a schedule, interreflection included.
    #[command(after_help = EXAMPLES_LIGHTING)]
    Lighting(LightingArgs),
    /// Radiative heat transfer between grey diffuse surfaces: temperatures, net heat flux and
    /// power per surface, from a boundary-condition table (net-radiation method).
    #[command(after_help = EXAMPLES_THERMAL)]
    Thermal(ThermalArgs),
    /// Validate the lighting engine against published test cases: `cie171`, the
    /// electric-lighting cases of CIE 171:2006 (5.2–5.8), each point against a reference
    /// computed independently. Fails when a case misses this project's target.
    #[command(after_help = EXAMPLES_VALIDATE)]
    Validate(ValidateArgs),
}

const EXAMPLES_VALIDATE: &str = "Examples:
  radiosity validate cie171                          every case, its table and verdicts
  radiosity validate cie171 --case 5.2 --csv 5.2.csv one case, its table as CSV";

/// The suites of `radiosity validate`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ValidateSuite {
    /// CIE 171:2006, "Test cases to assess the accuracy of lighting computer programs":
    /// the electric-lighting cases 5.2, 5.3, 5.4, 5.6, 5.7 and 5.8.
    Cie171,
}

/// `radiosity validate`.
#[derive(Debug, Args)]
pub struct ValidateArgs {
    /// The suite.
    #[arg(value_enum)]
    pub suite: ValidateSuite,
    /// Run one case only: 5.2, 5.3, 5.4, 5.6, 5.7 or 5.8.
    #[arg(long, value_name = "ID", help_heading = RUN)]
    pub case: Option<String>,
    /// Write the table: `case,point,x,y,z,reference,ours,deviation_percent` (lux, or lumens
    /// for case 5.4's surfaces; positions in metres).
    #[arg(long, value_name = "table.csv", help_heading = OUTPUT)]
    pub csv: Option<PathBuf>,
}

const EXAMPLES_THERMAL: &str = "Examples:
  radiosity thermal examples/hot-plate.obj --boundary examples/hot-plate-bc.csv --out surfaces.csv
  radiosity thermal room.vs3 --boundary bc.csv --out surfaces.csv --unit mm --environment 293.15";

/// How a run's summary is printed (`--report`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ReportFormat {
    /// Lines for people.
    Text,
    /// One JSON object on standard output, nothing else there.
    Json,
}

/// How a view-factor matrix is written (`form-factors --format`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum MatrixFormatArg {
    /// Matrix Market, coordinate real general.
    Mtx,
    /// NIST View3D's text output (areas, N rows of factors, emissivities).
    View3d,
}

/// A length unit (`thermal --unit`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum UnitArg {
    /// Metre.
    M,
    /// Centimetre.
    Cm,
    /// Millimetre.
    Mm,
    /// Inch (25.4 mm).
    In,
    /// Foot (0.3048 m).
    Ft,
}

impl UnitArg {
    /// Metres per unit.
    pub fn metres(self) -> f64 {
        match self {
            UnitArg::M => 1.0,
            UnitArg::Cm => 0.01,
            UnitArg::Mm => 0.001,
            UnitArg::In => 0.0254,
            UnitArg::Ft => 0.3048,
        }
    }
}

/// Whether the surfaces form a closed enclosure (`thermal --enclosure`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum EnclosureArg {
    /// Closed when a View3D file says `encl=1`, or when every row of F sums to at least 0.99
    /// (what is missing is then estimation error); open otherwise.
    Auto,
    /// Every row is rescaled to sum to 1: nothing escapes.
    Closed,
    /// What a row misses reaches the surroundings at --environment.
    Open,
}

/// Whether `thermal` stores the view factors (`thermal --solver`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ThermalSolverArg {
    /// Stored up to 20,000 patches when the matrix fits in memory, matrix-free beyond (under
    /// mpirun, stored).
    Auto,
    /// F computed by --form-factors and stored; the system solved by --linear-solver: exact
    /// to F's accuracy.
    Stored,
    /// No F: stochastic Jacobi sweeps of rays gathered from every patch, with each patch's
    /// Monte Carlo standard error reported (docs/heat-transfer.md).
    MatrixFree,
}

/// How the net-radiation system is solved (`thermal --linear-solver`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum LinearSolverArg {
    /// Dense LU up to 3,000 patches, BiCGSTAB beyond (under mpirun, BiCGSTAB).
    Auto,
    /// Dense LU (O(N²) memory, O(N³) time), exact to rounding.
    Direct,
    /// BiCGSTAB on the sparse F, to a relative residual of 1e-12; its products split over the
    /// ranks under mpirun.
    Iterative,
    /// Jacobi sweeps on the sparse F, to a relative residual of 1e-12, split over the ranks
    /// under mpirun; slow where most surfaces re-radiate (adiabatic).
    Jacobi,
}

const EXAMPLES_LIGHTING: &str = "Examples:
  radiosity lighting office.obj --luminaires schedule.csv --grid desk.pts --out grid.csv
  radiosity lighting room.glb --luminaires lights.csv --grid a.pts --grid b.pts \\
      --out grid.csv --summary summary.json
  radiosity lighting blender-export.glb --workplane Floor --out grid.csv    (the file's own lights)";

/// The scene's vertical (`lighting --up`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum UpArg {
    /// +z is up.
    Z,
    /// +y is up (glTF's convention).
    Y,
}

/// `radiosity lighting`.
#[derive(Debug, Args)]
#[command(group(clap::ArgGroup::new("daylight").args(["sky", "weather"]).multiple(true)))]
pub struct LightingArgs {
    /// The scene: an OBJ, MGF, glTF, PLY or View3D file, or a built-in name. Its emitting
    /// surfaces' emission is luminous exitance in lm/m²; its reflectances are the materials'.
    pub scene: String,
    /// The luminaire schedule: a CSV with the header
    /// `name,file,x,y,z,aim_x,aim_y,aim_z,c0_x,c0_y,c0_z,multiplier,group` (files relative to
    /// it). Leave it out when the scene's own emitting surfaces (or a glTF scene's
    /// `KHR_lights_punctual` / `EXT_lights_ies` lights, which are always used) are the light.
    #[arg(long, value_name = "schedule.csv", help_heading = SCENE)]
    pub luminaires: Option<PathBuf>,
    /// Calculation points in Radiance's points format (`x y z dx dy dz` a line, the direction
    /// the sensor's normal); give it more than once for several grids.
    #[arg(long, value_name = "points.pts", required_unless_present = "workplane", help_heading = SCENE)]
    pub grid: Vec<PathBuf>,
    /// A work-plane grid over the surfaces of MATERIAL (a floor), HEIGHT metres above them
    /// (default 0.8), facing up, spaced as EN 12464-1 asks: p = 0.2 × 5^log₁₀(d) (d the longer
    /// side of the area, p ≤ 10 m), a 0.5 m border band left out.
    #[arg(long, value_name = "MATERIAL[:HEIGHT]", help_heading = SCENE)]
    pub workplane: Option<String>,
    /// Write the work-plane grid in Radiance's points format (for `rtrace -I`).
    #[arg(long, value_name = "points.pts", requires = "workplane", help_heading = OUTPUT)]
    pub grid_out: Option<PathBuf>,
    /// Length unit of the scene, the schedule and the points.
    #[arg(long, value_enum, default_value = "m", help_heading = SCENE)]
    pub unit: UnitArg,
    /// The scene's vertical: what "down" means for a luminaire with no aim [default: z; y
    /// for glTF scenes, which are always y-up].
    #[arg(long, value_enum, help_heading = SCENE)]
    pub up: Option<UpArg>,
    /// Patches of the interreflection's mesh.
    #[arg(long, value_name = "N", default_value_t = 10_000, help_heading = MESHING)]
    pub patches: usize,
    /// Stop the interreflection when this fraction of the first-shot flux is left unshot.
    #[arg(long, value_name = "F", default_value_t = 1e-3, help_heading = SOLVER)]
    pub tolerance: f64,
    /// Gather: pairs of samples per point for the light arriving from the surfaces.
    #[arg(long, value_name = "N", default_value_t = 1024, help_heading = SOLVER)]
    pub indirect_samples: u32,
    /// Seed of every random stream.
    #[arg(long, value_name = "S", default_value_t = 1, help_heading = RUN)]
    pub seed: u64,
    /// One row per point: `x,y,z,nx,ny,nz,illuminance` (lux, direct and interreflected),
    /// then `illuminance_<group>` per light group when there is more than one.
    #[arg(long, short, value_name = "grid.csv", required_unless_present = "annual", help_heading = OUTPUT)]
    pub out: Option<PathBuf>,
    /// One row per material name: `name,area,reflectance,illuminance,exitance,luminance`
    /// (m², the luminance-weighted reflectance, mean illuminance in lux, mean luminous exitance
    /// in lm/m², mean luminance in cd/m²).
    #[arg(long, value_name = "surfaces.csv", help_heading = OUTPUT)]
    pub surfaces_out: Option<PathBuf>,
    /// The summary as JSON: per grid the point count, average, minimum and maximum
    /// illuminance and the uniformities U₀ = E_min/Ē and E_min/E_max; per luminaire its
    /// file's lumens and the flux integrated from its distribution.
    #[arg(long, value_name = "summary.json", help_heading = OUTPUT)]
    pub summary: Option<PathBuf>,
    /// Pictures of each grid in DIR (created if missing): `<stem>-illuminance.png`/`.svg`, a
    /// false-colour map (viridis bands, legend in lux, Ē, E_min, E_max and U₀ in the
    /// caption), and `<stem>-isolux.png`/`.svg`, labelled isolux lines over the grid's points;
    /// the stem is the --grid file's, or `workplane-MATERIAL`. Each grid must lie in one plane.
    /// With --sky also `<stem>-daylight-factor.png`/`.svg` (legend in %); in an annual run
    /// (--weather) only `<stem>-daylight-autonomy.png`/`.svg` (DA₃₀₀ in %).
    #[arg(long, value_name = "DIR", help_heading = OUTPUT)]
    pub pictures: Option<PathBuf>,
    /// Daylight: the sky outside, `cie-1` … `cie-15` (ISO 15469 / CIE S 011 general skies),
    /// `cie-overcast` (L = L_z (1 + 2 sin θ)/3) or `uniform`; adds the groups `sky` (and
    /// `sun`) and a `daylight_factor` column to the grid.
    #[arg(long, value_name = "SKY", value_parser = clap::builder::PossibleValuesParser::new(radiosity::lighting::sky::SkyModel::NAMES), help_heading = DAYLIGHT)]
    pub sky: Option<String>,
    /// The sun's position, degrees: altitude, azimuth clockwise from north (north is +y in a
    /// z-up scene, −z in a y-up one; see --north).
    #[arg(long, value_name = "ALTITUDE,AZIMUTH", requires = "sky", allow_hyphen_values = true, help_heading = DAYLIGHT)]
    pub sun: Option<String>,
    /// The sky's unobstructed horizontal illuminance, lux (the sun's disc not included).
    #[arg(long, value_name = "LX", default_value_t = 10_000.0, requires = "sky", help_heading = DAYLIGHT)]
    pub sky_illuminance: f64,
    /// The sun's direct normal illuminance, lux (0: no sun disc); needs --sun.
    #[arg(long, value_name = "LX", default_value_t = 0.0, requires = "sun", help_heading = DAYLIGHT)]
    pub sun_illuminance: f64,
    /// True north, degrees counter-clockwise (seen from above) from the scene's north (+y in a
    /// z-up scene, −z in a y-up one).
    #[arg(long, value_name = "DEG", default_value_t = 0.0, requires = "daylight", allow_hyphen_values = true, help_heading = DAYLIGHT)]
    pub north: f64,
    /// Reflectance of the ground plane outside, lit by the sky and the sun.
    #[arg(long, value_name = "R", default_value_t = 0.2, requires = "daylight", help_heading = DAYLIGHT)]
    pub ground_reflectance: f64,
    /// A material that is a clear pane of this normal transmittance (Fresnel at n = 1.52 with
    /// the pane's interreflections; at most 0.918); more than once for several. Materials
    /// with MTL `Tf`/`d` or glTF `KHR_materials_transmission` are glazing already.
    #[arg(long, value_name = "NAME=TRANSMITTANCE", help_heading = DAYLIGHT)]
    pub glazing: Vec<String>,
    /// Sky rays at each calculation point (stratified; the error at an opening's edge falls
    /// as N^(−3/4)).
    #[arg(long, value_name = "N", default_value_t = 16_384, requires = "daylight", help_heading = DAYLIGHT)]
    pub sky_rays: u32,
    /// Refinement F of the points' sky strata (1 … 16; 1: off): one ray per F × F strata
    /// first, then the full --sky-rays density only where a ray or its neighbour saw outside
    /// (an opening or a pane), so walls cost 1/F² of the rays.
    #[arg(long, value_name = "F", default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=16), requires = "daylight", help_heading = DAYLIGHT)]
    pub sky_refine: u32,
    /// Shadow rays to the sun's disc (0.533°, stratified) at each point and patch, for each
    /// sun: `--sun`'s, and every hour's in an annual run with the exact sun.
    #[arg(long, value_name = "N", default_value_t = 16, requires = "daylight", help_heading = DAYLIGHT)]
    pub sun_rays: u32,
    /// Annual daylight: the weather file (EnergyPlus EPW) whose hourly direct normal and
    /// diffuse horizontal irradiance give the year's skies (Perez all-weather model); needs
    /// --annual.
    #[arg(long, value_name = "FILE.epw", help_heading = DAYLIGHT)]
    pub weather: Option<PathBuf>,
    /// Annual daylight: per point `point,x,y,z,daylight_autonomy,sun_hours,udi_fell_short,
    /// udi_supplementary,udi_autonomous,udi_exceeded,in_sda,in_ase` over the occupied hours
    /// (8:00–18:00); replaces --out. Needs --weather.
    #[arg(long, value_name = "OUT.csv", help_heading = DAYLIGHT)]
    pub annual: Option<PathBuf>,
    /// Annual daylight: every hour's illuminance too (lx): `.csv` with rows
    /// `month,day,hour,p0,p1,…`, or `.npy`, a NumPy hours × points float32 matrix (hours in
    /// the weather file's order).
    #[arg(long, value_name = "hourly.csv|.npy", help_heading = DAYLIGHT)]
    pub hourly: Option<PathBuf>,
    /// Annual daylight: the sky's patches, Reinhart's MF:N (1 = Tregenza's 145, 2 = 577,
    /// 144 N² + 1; at most 16); one daylight coefficient a patch and point.
    #[arg(long, value_name = "N", default_value_t = 1, help_heading = DAYLIGHT)]
    pub sky_patches: usize,
    /// Annual daylight: the occupied hours of every day, local standard time, START-END
    /// (hours 0…24; an hour counts when its middle lies inside). Default 8-18 (IES LM-83-12).
    #[arg(long, value_name = "START-END", help_heading = DAYLIGHT)]
    pub occupancy: Option<String>,
    /// Annual daylight: the occupied hours from a file, one line an hour of the weather
    /// file's, its last comma-separated field 1 (occupied) or 0 (`1`, or DAYSIM's
    /// `month,day,hour,1`; `#` comments and a header line skipped); in place of --occupancy.
    #[arg(long, value_name = "FILE", help_heading = DAYLIGHT)]
    pub occupancy_schedule: Option<PathBuf>,
    /// Annual daylight: daylight autonomy's illuminance (lx) for sDA, and where UDI's
    /// autonomous bin starts. Default 300.
    #[arg(long, value_name = "LX", help_heading = DAYLIGHT)]
    pub sda_threshold: Option<f64>,
    /// Annual daylight: the share of occupied hours (0…1] a point must reach the sDA
    /// illuminance to count in sDA. Default 0.5.
    #[arg(long, value_name = "F", help_heading = DAYLIGHT)]
    pub sda_fraction: Option<f64>,
    /// Annual daylight: ASE's direct-sun illuminance, lx. Default 1000.
    #[arg(long, value_name = "LX", help_heading = DAYLIGHT)]
    pub ase_threshold: Option<f64>,
    /// Annual daylight: a point counts in ASE when more than these occupied hours reach the
    /// ASE illuminance. Default 250.
    #[arg(long, value_name = "H", help_heading = DAYLIGHT)]
    pub ase_hours: Option<u32>,
    /// Annual daylight: UDI's useful range LOW,HIGH in lx (fell short below LOW, exceeded
    /// above HIGH). Default 100,3000.
    #[arg(long, value_name = "LOW,HIGH", help_heading = DAYLIGHT)]
    pub udi_range: Option<String>,
    /// Annual daylight: where the sun goes. `exact` (default): its direct light at its true
    /// position every hour (shadow rays, what ASE counts), its interreflection from its patch
    /// (the 5-phase method). `patch`: into the sky patch holding it (2-phase).
    #[arg(long, value_enum, value_name = "METHOD", help_heading = DAYLIGHT)]
    pub sun_method: Option<SunMethod>,
}

/// `--sun-method`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum SunMethod {
    /// Into the sky patch that holds it.
    Patch,
    /// Direct sun at its true position, interreflection from its patch.
    Exact,
}

/// `radiosity thermal`.
#[derive(Debug, Args)]
pub struct ThermalArgs {
    /// A scene file (.obj, .mgf, .gltf, .glb, .ply, View3D's .vs3) or a built-in scene.
    pub scene: String,
    /// Boundary conditions: CSV with the header `name,emissivity,temperature,flux`, one row
    /// per surface name (material name, or View3D surface name). Emissivity in (0, 1] (empty:
    /// the scene's own); temperature in K or flux in W/m² (net, leaving), or neither for an
    /// adiabatic surface.
    #[arg(long, value_name = "bc.csv", help_heading = SCENE)]
    pub boundary: PathBuf,
    /// What a scene unit is.
    #[arg(long, value_enum, default_value = "m", help_heading = SCENE)]
    pub unit: UnitArg,
    /// Temperature of the surroundings seen through openings, K.
    #[arg(long, value_name = "K", default_value_t = 0.0, help_heading = SCENE)]
    pub environment: f64,
    /// Closed enclosure or open to the surroundings.
    #[arg(long, value_enum, default_value = "auto", help_heading = SCENE)]
    pub enclosure: EnclosureArg,
    /// MGF and glTF: treat two-sided surfaces as one-sided.
    #[arg(long, help_heading = SCENE)]
    pub one_sided: bool,
    /// One patch per input face (the default).
    #[arg(long, conflicts_with_all = ["patches", "max_edge"], help_heading = MESHING)]
    pub faces: bool,
    /// Approximate number of patches (subdivides the faces).
    #[arg(long, value_name = "N", conflicts_with = "max_edge", help_heading = MESHING)]
    pub patches: Option<usize>,
    /// Largest patch edge, scene units.
    #[arg(long, value_name = "L", help_heading = MESHING)]
    pub max_edge: Option<f32>,
    /// The form-factor method.
    #[arg(long = "form-factor-method", visible_alias = "form-factors", value_name = "M", value_enum, default_value = "adaptive", help_heading = FORM_FACTORS)]
    pub method: FormFactorArg,
    /// adaptive: the accuracy E of every entry of F (relative where a pair sees itself whole,
    /// absolute where an occluder stands between; see docs/heat-transfer.md).
    #[arg(long, value_name = "E", default_value_t = radiosity::formfactor::DEFAULT_ACCURACY, help_heading = FORM_FACTORS)]
    pub accuracy: f64,
    /// Monte Carlo rays per row (default: 10⁶ up to 100 patches, then 10⁸/N, at least 10⁴).
    #[arg(long, value_name = "N", help_heading = FORM_FACTORS)]
    pub rays: Option<u32>,
    /// P: pixels along a hemicube/tetrahedron face, cells across the hemisphere's disc.
    #[arg(long, value_name = "P", default_value_t = 256, help_heading = FORM_FACTORS)]
    pub resolution: u32,
    /// Points over each patch for the projection methods (rounded up to a square).
    #[arg(long, value_name = "K", default_value_t = 16, help_heading = FORM_FACTORS)]
    pub samples: u32,
    /// Seed of Monte Carlo.
    #[arg(long, value_name = "S", default_value_t = 1, help_heading = FORM_FACTORS)]
    pub seed: u64,
    /// Store F (exact to its accuracy) or not (matrix-free: Monte Carlo, each patch's error
    /// reported); auto stores it up to 20,000 patches when it fits in memory.
    #[arg(long, value_enum, default_value = "auto", help_heading = SOLVER)]
    pub solver: ThermalSolverArg,
    /// How the net-radiation system of a stored F is solved.
    #[arg(long, value_enum, default_value = "auto", help_heading = SOLVER)]
    pub linear_solver: LinearSolverArg,
    /// Matrix-free: rays each patch at a prescribed temperature (whose flux is computed)
    /// gathers in the last sweep of every batch (rounded up to a square; stratified over the
    /// patch and the hemisphere). The flux's standard error falls as about 1/√N or faster.
    #[arg(long, value_name = "N", default_value_t = radiosity::thermal::MatrixFreeParams::default().flux_rays, help_heading = SOLVER)]
    pub flux_rays: u32,
    /// Matrix-free: the same for every other patch (prescribed flux or adiabatic: its
    /// temperature is computed).
    #[arg(long, value_name = "N", default_value_t = radiosity::thermal::MatrixFreeParams::default().temperature_rays, help_heading = SOLVER)]
    pub temperature_rays: u32,
    /// Matrix-free: rays each patch gathers in the other sweeps (rounded up to a square).
    #[arg(long, value_name = "N", default_value_t = radiosity::thermal::MatrixFreeParams::default().sweep_rays, help_heading = SOLVER)]
    pub sweep_rays: u32,
    /// Matrix-free: rays each patch gathers in the next-to-last sweep of every batch (the
    /// radiosities the last sweep gathers from, whose noise the flux carries).
    #[arg(long, value_name = "N", default_value_t = radiosity::thermal::MatrixFreeParams::default().carry_rays, help_heading = SOLVER)]
    pub carry_rays: u32,
    /// Matrix-free: independent batches, whose spread gives the standard errors (2 to 4096).
    #[arg(long, value_name = "B", default_value_t = radiosity::thermal::MatrixFreeParams::default().batches, help_heading = SOLVER)]
    pub batches: u32,
    /// Matrix-free: the per-patch flux error wanted (one standard error), relative to the mean
    /// |flux| of the patches at a prescribed temperature; patches above it after the batches
    /// gather more rays within every batch (the adaptive stage). 0: no adaptive stage.
    #[arg(long, value_name = "E", default_value_t = radiosity::thermal::MatrixFreeParams::default().flux_error, help_heading = SOLVER)]
    pub flux_error: f64,
    /// Output: one row per boundary name, `name,area,emissivity,temperature,flux,power`
    /// (m², K, W/m², W).
    #[arg(long, short, value_name = "surfaces.csv", help_heading = OUTPUT)]
    pub out: PathBuf,
    /// Also one row per patch, with its centre (scene units):
    /// `patch,name,x,y,z,area,emissivity,temperature,flux,power`.
    #[arg(long, value_name = "patches.csv", help_heading = OUTPUT)]
    pub patches_out: Option<PathBuf>,
    /// Points for radiant temperatures, in Radiance's points format (`x y z dx dy dz` a line,
    /// scene units; the direction is the side the plane radiant temperature faces); give it
    /// more than once for several files. Needs `--mrt-out`.
    #[arg(long, value_name = "points.pts", requires = "mrt_out", help_heading = OUTPUT)]
    pub grid: Vec<PathBuf>,
    /// One row per point of the grids: `x,y,z,mean_radiant_temperature,
    /// plane_radiant_temperature,sky_view` (K, K, the share of the sphere that sees no
    /// surface), from the solved radiosities with exact visibility.
    #[arg(long, value_name = "mrt.csv", requires = "grid", help_heading = OUTPUT)]
    pub mrt_out: Option<PathBuf>,
    /// Rays per point over the sphere (and as many over the hemisphere), stratified.
    #[arg(long, value_name = "N", default_value_t = 2048, help_heading = OUTPUT)]
    pub mrt_rays: u32,
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
    #[arg(long, value_name = "DIR", default_value = "experiments", help_heading = OUTPUT)]
    pub out: PathBuf,
    /// Small sizes that run in seconds.
    #[arg(long, help_heading = RUN)]
    pub quick: bool,
    /// Seed of the random systems, Monte Carlo and photons.
    #[arg(long, value_name = "S", default_value_t = 1, help_heading = RUN)]
    pub seed: u64,
    /// convergence: iterations per method, in sweeps (multiples of N).
    #[arg(long, value_name = "K", default_value_t = 3.0, help_heading = SOLVER)]
    pub sweeps: f64,
    /// complexity: patch counts (default 250,500,1000,2000,4000; with --quick 40,…,640).
    #[arg(long, value_name = "N,N,…", value_delimiter = ',', num_args = 1.., help_heading = MESHING)]
    pub sizes: Option<Vec<usize>>,
}

/// `radiosity form-factors`.
#[derive(Debug, Args)]
pub struct FormFactorsArgs {
    /// A built-in scene or a scene file (.obj, .mgf, .gltf, .glb, .ply, .vs3).
    pub scene: String,
    /// The form-factor method [default: adaptive for a View3D .vs3 scene, monte-carlo
    /// otherwise].
    #[arg(long, value_name = "M", value_enum, help_heading = FORM_FACTORS)]
    pub method: Option<FormFactorArg>,
    /// adaptive: the accuracy E of every entry of F (relative where a pair sees itself whole,
    /// absolute where an occluder stands between; see docs/heat-transfer.md).
    #[arg(long, value_name = "E", default_value_t = radiosity::formfactor::DEFAULT_ACCURACY, help_heading = FORM_FACTORS)]
    pub accuracy: f64,
    /// P: pixels along a hemicube/tetrahedron face, cells across the hemisphere's disc.
    #[arg(long, value_name = "P", default_value_t = 128, help_heading = FORM_FACTORS)]
    pub resolution: u32,
    /// Points over each patch for the projection methods (rounded up to a square).
    #[arg(long, value_name = "K", default_value_t = 16, help_heading = FORM_FACTORS)]
    pub samples: u32,
    /// Monte Carlo rays per row (standard deviation of each entry ≤ 1/(2√N)).
    #[arg(long, value_name = "N", default_value_t = 1_000_000, help_heading = FORM_FACTORS)]
    pub rays: u32,
    /// Seed of Monte Carlo.
    #[arg(long, value_name = "S", default_value_t = 1, help_heading = FORM_FACTORS)]
    pub seed: u64,
    /// One row per input face (no subdivision): face-to-face view factors.
    #[arg(long, conflicts_with_all = ["patches", "max_edge"], help_heading = MESHING)]
    pub faces: bool,
    /// Approximate number of patches.
    #[arg(long, value_name = "N", conflicts_with = "max_edge", help_heading = MESHING)]
    pub patches: Option<usize>,
    /// Largest patch edge, scene units.
    #[arg(long, value_name = "L", help_heading = MESHING)]
    pub max_edge: Option<f32>,
    /// Storage while computing.
    #[arg(long, value_name = "S", value_enum, default_value = "auto", help_heading = FORM_FACTORS)]
    pub storage: StorageArg,
    /// Drop negative entries (F ≥ 0).
    #[arg(long, help_heading = FORM_FACTORS)]
    pub clamp: bool,
    /// Rescale every row to sum to 1 (closed enclosures only).
    #[arg(long, help_heading = FORM_FACTORS)]
    pub normalize_rows: bool,
    /// Make A_i F_ij = A_j F_ji keeping row sums (symmetric matrix scaling, Knight 2008).
    #[arg(long, help_heading = FORM_FACTORS)]
    pub symmetrize: bool,
    /// Drop the entries F_ij below T (a pair is kept when either of its factors reaches T),
    /// then restore reciprocity and each row's sum before the drop (1 in an enclosure; the
    /// sky factor of an open scene is kept) by symmetric scaling of A F; reports what was
    /// dropped and the worst row-sum error (docs/heat-transfer.md, "Truncated factors").
    #[arg(long, value_name = "T", help_heading = FORM_FACTORS)]
    pub threshold: Option<f64>,
    /// Output matrix (Matrix Market, coordinate real general, 1-based; or View3D's text format
    /// with --format view3d).
    #[arg(long, short, value_name = "F.mtx", help_heading = OUTPUT)]
    pub out: PathBuf,
    /// Output format (default: by the extension; .mtx is Matrix Market). `view3d`: NIST
    /// View3D's view-factor file, one row per View3D surface (combined surfaces merged,
    /// obstructions left out) or per input face, with areas and emissivities.
    #[arg(long, value_enum, help_heading = OUTPUT)]
    pub format: Option<MatrixFormatArg>,
    /// With --format view3d: write Hottel's total exchange factors (script-F, View3D's
    /// `emit=1`) instead of view factors (default: as the .vs3 file's `emit` says).
    #[arg(long, help_heading = OUTPUT)]
    pub script_f: bool,
    /// Also write the rows' patches (or faces) as CSV.
    #[arg(long, value_name = "patches.csv", help_heading = OUTPUT)]
    pub patches_out: Option<PathBuf>,
}

/// `radiosity solve-system`.
#[derive(Debug, Args)]
pub struct SolveSystemArgs {
    /// Form factors F_ij: Matrix Market, coordinate real general, 1-based indices.
    #[arg(long, visible_alias = "form-factors", value_name = "F.mtx", help_heading = SCENE)]
    pub matrix: PathBuf,
    /// Patches: CSV with a header; columns `area` and either `reflectance`,`emission` or
    /// `reflectance_r`,`reflectance_g`,`reflectance_b`,`emission_r`,`emission_g`,`emission_b`.
    #[arg(long, value_name = "patches.csv", help_heading = SCENE)]
    pub patches: PathBuf,
    /// The solution method.
    #[arg(long, value_name = "M", value_enum, default_value = "progressive", help_heading = SOLVER)]
    pub solver: SolverArg,
    /// Output: one radiosity row per patch.
    #[arg(long, short, value_name = "B.csv", help_heading = OUTPUT)]
    pub out: PathBuf,
    /// Write the convergence trace (iteration,seconds,error,unshot) to this CSV.
    #[arg(long, value_name = "FILE", help_heading = OUTPUT)]
    pub trace: Option<PathBuf>,
    /// The solver's options.
    #[command(flatten)]
    pub flags: SolverFlags,
    /// Seed of `stochastic`.
    #[arg(long, value_name = "S", default_value_t = 1, help_heading = SOLVER)]
    pub seed: u64,
}

/// Options shared by every command that solves a scene.
#[derive(Debug, Args)]
pub struct SolveArgs {
    /// A built-in scene (cornell, cube-dim, cube-bright, furnace, office, city) or a scene file
    /// (.obj, .mgf, .gltf, .glb, .ply, .vs3).
    #[arg(default_value = "cornell")]
    pub scene: String,
    /// MGF and glTF scenes: keep every surface one-sided, ignoring MGF's `sides 2` (RenderPark's
    /// -force-onesided) and glTF's `doubleSided`. By default a two-sided surface is two polygons
    /// back to back.
    #[arg(long, help_heading = SCENE)]
    pub one_sided: bool,
    /// Approximate total number of patches [default: 10000].
    #[arg(long, value_name = "N", conflicts_with = "max_edge", help_heading = MESHING)]
    pub patches: Option<usize>,
    /// Largest patch edge, in scene units (instead of --patches).
    #[arg(long, value_name = "L", help_heading = MESHING)]
    pub max_edge: Option<f32>,
    /// The form-factor method (`--form-factors` is the older name).
    #[arg(long = "form-factor-method", visible_alias = "form-factors", value_name = "M", value_enum, default_value = "monte-carlo", help_heading = FORM_FACTORS)]
    pub form_factors: FormFactorArg,
    /// Monte Carlo rays per form-factor row for a patch shooting an average share of the power
    /// (emitters get proportionally more).
    #[arg(long, value_name = "N", default_value_t = 256, help_heading = FORM_FACTORS)]
    pub rays: u32,
    /// P for the hemicube, tetrahedron and hemisphere.
    #[arg(long, value_name = "P", default_value_t = 128, help_heading = FORM_FACTORS)]
    pub resolution: u32,
    /// Points per patch for the hemicube, tetrahedron and hemisphere.
    #[arg(long, value_name = "K", default_value_t = 16, help_heading = FORM_FACTORS)]
    pub samples: u32,
    /// Rows of F stored before solving, or computed when the solver asks.
    #[arg(long, value_name = "R", value_enum, default_value = "auto", help_heading = FORM_FACTORS)]
    pub rows: RowsArg,
    /// The solution method.
    #[arg(long, value_name = "M", value_enum, default_value = "progressive", help_heading = SOLVER)]
    pub solver: SceneSolverArg,
    /// The solver's options.
    #[command(flatten)]
    pub flags: SolverFlags,
    /// Set by `render`: the solve is for a picture (its default tolerance is tighter).
    #[arg(skip)]
    pub picture: bool,
    /// `hierarchical`: refine a link when the power it may misplace exceeds this fraction of
    /// the emitted power.
    #[arg(long, value_name = "E", default_value_t = radiosity::hierarchical::Params::default().link_error, help_heading = SOLVER)]
    pub link_error: f64,
    /// `hierarchical`: do not split elements below this area, in square scene units (default:
    /// the scene's total area × 1e-6).
    #[arg(long, value_name = "A", help_heading = SOLVER)]
    pub min_area: Option<f64>,
    /// `hierarchical`: visibility rays from each of a link's sixteen receiver points.
    #[arg(long, value_name = "N", default_value_t = radiosity::hierarchical::Params::default().visibility_rays, help_heading = SOLVER)]
    pub visibility_rays: u32,
    /// `hierarchical`: refinement passes at most (each followed by a solve).
    #[arg(long, value_name = "N", default_value_t = radiosity::hierarchical::Params::default().max_passes, help_heading = SOLVER)]
    pub passes: u32,
    /// Seed of every random stream.
    #[arg(long, value_name = "S", default_value_t = 1, help_heading = RUN)]
    pub seed: u64,
    /// Write the convergence trace (iteration,seconds,error,unshot) to this CSV. The form
    /// factors are then estimated and stored in full first, and the error is measured against
    /// their LU solution (N ≤ 5,000).
    #[arg(long, value_name = "FILE", help_heading = OUTPUT)]
    pub trace: Option<PathBuf>,
    /// How the run's summary is printed on standard output: `text` (lines for people) or
    /// `json` (one JSON object and nothing else, for scripts and the workbench: patches,
    /// rays, iterations, energy, seconds per stage, memory, CPU time, outputs).
    #[arg(long, value_name = "FORMAT", value_enum, default_value = "text", help_heading = OUTPUT)]
    pub report: ReportFormat,
}

/// The linear-system solver's options, shared by `solve`, `render` and `solve-system`.
#[derive(Debug, Args)]
pub struct SolverFlags {
    /// Stop when the unshot energy is at most this fraction of the emitted energy (default
    /// 0.01; `render` 0.0003, where the display's ambient term changes no part of the Cornell
    /// box's picture by more than 1 %).
    #[arg(long, value_name = "F", help_heading = SOLVER)]
    pub tolerance: Option<f64>,
    /// Stop after this many iterations (shots, rows, photons) at the latest.
    #[arg(long, value_name = "K", help_heading = SOLVER)]
    pub max_iterations: Option<u64>,
    /// Relaxation factor ω of `sor`.
    #[arg(long, value_name = "W", default_value_t = SolverParams::default().omega, help_heading = SOLVER)]
    pub omega: f64,
    /// `stochastic`: each photon carries 1/N of the shooter's unshot power.
    #[arg(long, value_name = "N", default_value_t = SolverParams::default().photons, help_heading = SOLVER)]
    pub photons: u32,
    /// `stochastic-jacobi`: rays per patch in each iteration (all patches shoot N × this many
    /// rays, each patch's share in proportion to its unshot power).
    #[arg(long, value_name = "N", default_value_t = SolverParams::default().iteration_rays, help_heading = SOLVER)]
    pub iteration_rays: u32,
    /// `stochastic-jacobi`: rays per patch of a final regular gathering iteration (Bekaert's,
    /// with the constant control variate); 0, the default, for none: on RenderPark's hospital
    /// it made the result noisier per patch and per surface at any count tried. At most 2²⁰.
    #[arg(long, value_name = "N", default_value_t = SolverParams::default().gather_rays, help_heading = SOLVER)]
    pub gather_rays: u32,
}

/// Camera overrides.
#[derive(Debug, Args)]
pub struct CameraArgs {
    /// Eye point x,y,z.
    #[arg(long, value_name = "X,Y,Z", allow_hyphen_values = true, help_heading = CAMERA)]
    pub eye: Option<String>,
    /// Point looked at x,y,z.
    #[arg(long, value_name = "X,Y,Z", allow_hyphen_values = true, help_heading = CAMERA)]
    pub target: Option<String>,
    /// Up direction x,y,z.
    #[arg(long, value_name = "X,Y,Z", allow_hyphen_values = true, help_heading = CAMERA)]
    pub up: Option<String>,
    /// Vertical field of view, degrees.
    #[arg(long, value_name = "DEG", help_heading = CAMERA)]
    pub fov: Option<f32>,
}

/// `radiosity render`.
#[derive(Debug, Args)]
pub struct RenderArgs {
    /// The scene and how it is solved.
    #[command(flatten)]
    pub solve: SolveArgs,
    /// The camera.
    #[command(flatten)]
    pub camera: CameraArgs,
    /// Output image: .png (tone-mapped sRGB), .exr or .pfm (linear radiance). Default SCENE.png.
    #[arg(long, short, value_name = "FILE", help_heading = OUTPUT)]
    pub out: Option<PathBuf>,
    /// Picture size and sampling.
    #[command(flatten)]
    pub image: ImageArgs,
    /// Exposure adjustment in stops, relative to automatic exposure (PNG only).
    #[arg(
        long,
        value_name = "EV",
        default_value_t = 0.0,
        allow_hyphen_values = true,
        help_heading = OUTPUT
    )]
    pub exposure: f32,
    /// How pixels are computed: `gather` (the default) computes direct light per pixel with
    /// exact shadows and gathers the indirect from the solution (no ambient term, no mesh
    /// showing); `radiosity` shows the solution itself (Gouraud-interpolated, with the display
    /// ambient term: fastest, a preview); `path` path-traces the scene without solving (the
    /// reference).
    #[arg(long, value_enum, default_value = "gather", help_heading = PICTURE)]
    pub integrator: IntegratorArg,
    /// Same as --integrator gather (the default; kept for scripts that name it).
    #[arg(long, conflicts_with = "integrator", help_heading = PICTURE)]
    pub gather: bool,
    /// Gather: shadow rays to the emitters per camera sample.
    #[arg(long, value_name = "N", default_value_t = 4, help_heading = PICTURE)]
    pub direct_samples: u32,
    /// Gather: rays into the solution per camera sample, where the irradiance cache is off or
    /// has no record.
    #[arg(long, value_name = "N", default_value_t = 16, help_heading = PICTURE)]
    pub indirect_samples: u32,
    /// Gather: a gather ray hitting closer than this many patch sizes is followed one level
    /// deeper (direct light with a shadow ray, indirect from the solution); 0 turns it off.
    #[arg(long, value_name = "F", default_value_t = 1.0, help_heading = PICTURE)]
    pub gather_near: f32,
    /// Gather: sample pairs per irradiance-cache record (the indirect light is gathered at
    /// sparse points and interpolated; Ward et al. 1988); 0 gathers at every camera sample.
    #[arg(long, value_name = "N", default_value_t = 1024, help_heading = PICTURE)]
    pub cache_samples: u32,
    /// Gather: the irradiance cache's accuracy a (smaller: more records).
    #[arg(long, value_name = "A", default_value_t = 0.1, help_heading = PICTURE)]
    pub cache_accuracy: f32,
    /// A lighting schedule (as `lighting --luminaires`): the picture is then the lighting
    /// pipeline's, the luminaires' first shot into the patches and the interreflection
    /// solved, each camera sample's direct light from the luminaires computed exactly with
    /// shadow rays and the interreflected gathered. Luminaires light the scene but are not
    /// seen; the scene's emission is luminous exitance in lm/m².
    #[arg(long, value_name = "schedule.csv", help_heading = SCENE)]
    pub luminaires: Option<PathBuf>,
    /// With --luminaires: the length unit of the scene and the schedule (distances in metres
    /// make lux) [default: m].
    #[arg(long, value_enum, value_name = "UNIT", help_heading = SCENE)]
    pub unit: Option<UnitArg>,
    /// With --luminaires: the scene's vertical, what "down" means for a luminaire with no aim
    /// (`lighting --up`; here --up is the camera's) [default: z].
    #[arg(long, value_enum, value_name = "AXIS", help_heading = SCENE)]
    pub vertical: Option<UpArg>,
    /// Write luminance in cd/m² (.exr or .pfm only): each pixel's photometric Y (BT.709
    /// weights of the linear RGB radiance) in all three channels, unscaled. The scene's
    /// emission is read as luminous exitance in lm/m².
    #[arg(long, help_heading = OUTPUT)]
    pub luminance: bool,
    /// With --luminance: also the luminance picture in false colour (PNG), logarithmic bands
    /// 1–2–5 a decade with a legend in cd/m².
    #[arg(long = "false-colour", visible_alias = "false-color", value_name = "FILE.png", requires = "luminance", help_heading = OUTPUT)]
    pub false_colour: Option<PathBuf>,
}

/// How `render` computes pixels.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum IntegratorArg {
    /// The radiosity solution shown directly (Gouraud shading, display ambient term).
    Radiosity,
    /// Final gather over the solution: exact direct light, one gathered bounce.
    Gather,
    /// Brute-force path tracing with next-event estimation and Russian roulette (no solve).
    Path,
}

/// `radiosity solve`.
#[derive(Debug, Args)]
pub struct SolveCmdArgs {
    /// The scene and how it is solved.
    #[command(flatten)]
    pub solve: SolveArgs,
    /// Output: .csv (one row per patch: geometry, material, radiosity), or a baked mesh with the
    /// radiosity at its vertices: .glb / .gltf (glTF 2.0: COLOR_0 display colours, unlit
    /// materials, _RADIOSITY linear values) or .ply (vertex colours plus float radiosity).
    #[arg(long, short, value_name = "FILE", help_heading = OUTPUT)]
    pub out: PathBuf,
    /// Baked meshes: exposure adjustment in stops, relative to automatic exposure (which maps
    /// the 97th percentile of patch luminance, by area, to 0.9). COLOR_0 = min(1, B · scale).
    #[arg(
        long,
        value_name = "EV",
        default_value_t = 0.0,
        allow_hyphen_values = true,
        help_heading = OUTPUT
    )]
    pub exposure: f32,
    /// `hierarchical`: write every link as CSV (receiver, source, kind, form factor,
    /// uncertainty, transported power).
    #[arg(long, value_name = "links.csv", help_heading = OUTPUT)]
    pub links_out: Option<PathBuf>,
    /// `hierarchical`: write every element as CSV (id, parent, level, surface, leaf, area,
    /// centre, radiosity, exposed: the fraction not inside a closed solid).
    #[arg(long, value_name = "elements.csv", help_heading = OUTPUT)]
    pub elements_out: Option<PathBuf>,
    /// Baked glTF: light at the vertices (`vertex`: COLOR_0) or in a lightmap texture on a
    /// generated second UV set (`lightmap`: TEXCOORD_1, MOZ_lightmap, the atlas as PNG).
    #[arg(long, value_enum, default_value_t = BakeArg::Vertex, help_heading = LIGHTMAP)]
    pub bake: BakeArg,
    /// Lightmap: atlas side in texels (1 to 16384); alone, the texel size is the finest whose
    /// charts fit. Default 1024 when --texel-size is not given either.
    #[arg(long, value_name = "N", help_heading = LIGHTMAP)]
    pub lightmap_size: Option<u32>,
    /// Lightmap: texel size in scene units; alone, the atlas is as large as the charts need.
    #[arg(long, value_name = "L", help_heading = LIGHTMAP)]
    pub texel_size: Option<f32>,
    /// Lightmap: also write the atlas as OpenEXR, linear float radiosity B per channel.
    #[arg(long, value_name = "lightmap.exr", help_heading = LIGHTMAP)]
    pub lightmap_out: Option<PathBuf>,
    /// Lightmap: shadow rays to the emitters per texel.
    #[arg(long, value_name = "N", default_value_t = radiosity::bake::lightmap::LightmapParams::default().direct, help_heading = LIGHTMAP)]
    pub lightmap_direct: u32,
    /// Lightmap: indirect sample pairs per record (records every --lightmap-spacing texels).
    #[arg(long, value_name = "N", default_value_t = radiosity::bake::lightmap::LightmapParams::default().indirect, help_heading = LIGHTMAP)]
    pub lightmap_indirect: u32,
    /// Lightmap: texels between indirect records along each chart axis (1: every texel).
    #[arg(long, value_name = "N", default_value_t = radiosity::bake::lightmap::LightmapParams::default().spacing, help_heading = LIGHTMAP)]
    pub lightmap_spacing: u32,
    /// Lightmap: filter the indirect light's noise with an edge-preserving cross-bilateral
    /// filter guided by the texels' positions, normals and charts (docs/baking.md).
    #[arg(long, help_heading = LIGHTMAP)]
    pub lightmap_denoise: bool,
    /// Lightmap: the denoising window's radius in texels (the spatial sigma is half of it).
    #[arg(long, value_name = "R", help_heading = LIGHTMAP)]
    pub lightmap_denoise_radius: Option<f32>,
}

/// What `solve --bake` puts in a baked glTF.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum BakeArg {
    /// Radiosity at the patch mesh's vertices (COLOR_0).
    Vertex,
    /// A lightmap texture on a second UV set (TEXCOORD_1, MOZ_lightmap).
    Lightmap,
}

/// `radiosity view`.
#[derive(Debug, Args)]
pub struct ViewArgs {
    /// A baked glTF (.glb or .gltf) whose primitives carry COLOR_0, e.g. from
    /// `radiosity solve SCENE --out baked.glb`, or whose materials carry a lightmap
    /// (MOZ_lightmap on a UV set, e.g. from `--bake lightmap`), then shown lit by it.
    pub file: PathBuf,
    /// The camera.
    #[command(flatten)]
    pub camera: CameraArgs,
    /// Output image: .png (COLOR_0 sRGB-encoded), .exr or .pfm (COLOR_0 linear). Default
    /// FILE.png.
    #[arg(long, short, value_name = "FILE", help_heading = OUTPUT)]
    pub out: Option<PathBuf>,
    /// Picture size and sampling.
    #[command(flatten)]
    pub image: ImageArgs,
    /// Final gather over the baked `_RADIOSITY` (exact direct light, indirect gathered from
    /// the bake; reflectance and emission from the materials `solve` baked) instead of
    /// showing COLOR_0; automatic exposure as `render`.
    #[arg(long, help_heading = PICTURE)]
    pub gather: bool,
    /// Gather: shadow rays to the emitters per camera sample.
    #[arg(long, value_name = "N", default_value_t = 4, help_heading = PICTURE)]
    pub direct_samples: u32,
    /// Gather: sample pairs per irradiance-cache record.
    #[arg(long, value_name = "N", default_value_t = 1024, help_heading = PICTURE)]
    pub cache_samples: u32,
}

/// Picture size and sampling, shared by `render` and `view`.
#[derive(Debug, Args)]
pub struct ImageArgs {
    /// Image width in pixels.
    #[arg(long, value_name = "W", default_value_t = 512, help_heading = OUTPUT)]
    pub width: u32,
    /// Image height in pixels.
    #[arg(long, value_name = "H", default_value_t = 512, help_heading = OUTPUT)]
    pub height: u32,
    /// Camera rays per pixel, stratified when a square (default 16 for `render`'s gather, 4
    /// with --integrator radiosity and for `view`, 256 paths with --integrator path).
    #[arg(long, value_name = "N", help_heading = OUTPUT)]
    pub spp: Option<u32>,
}
