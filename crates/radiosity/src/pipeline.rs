//! The one place that knows every stage, in order: validate the scene → mesh it into patches →
//! build the ray-casting hierarchy → solve (shooting methods with Monte Carlo form factors
//! computed on demand; the others, or any method when the whole matrix is asked for, with every
//! row estimated first and stored sparse) → (optionally) render.

use crate::accel::Bvh;
use crate::color::Rgb;
use crate::formfactor::monte_carlo::{estimate_all_rows, MonteCarloParams, MonteCarloRows};
use crate::formfactor::FormFactorStats;
use crate::mesh::{Mesh, MeshParams};
use crate::render::{render, vertex_radiosity, Image, RenderParams};
use crate::scene::{Camera, Scene};
use crate::solve::matrix::SparseMatrix;
use crate::solve::{ambient_term, Info, Method, RowSource, Solver, SolverParams, Status, System};
use crate::Error;
use std::time::Instant;

/// Everything that decides a solution.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Settings {
    /// How to cut surfaces into patches.
    pub mesh: MeshParams,
    /// Monte Carlo form factors.
    pub monte_carlo: MonteCarloParams,
    /// Another form-factor method (hemicube, hemisphere, tetrahedron, analytic) whose full
    /// matrix is computed first; `None` for Monte Carlo.
    pub geometric: Option<crate::formfactor::Params>,
    /// The solution method.
    pub solver: Method,
    /// Its parameters (tolerance, iterations, ω, photons, seed, memory).
    pub params: SolverParams,
    /// Estimate and store every row of F first, whatever the method (a trace's reference
    /// solution needs the very matrix the method used).
    pub store_matrix: bool,
    /// Refuse jobs whose estimated memory exceeds this many bytes (0: the machine's available
    /// memory).
    pub memory_limit: u64,
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            mesh: MeshParams::default(),
            monte_carlo: MonteCarloParams::default(),
            geometric: None,
            solver: Method::Progressive,
            params: SolverParams::default(),
            store_matrix: false,
            memory_limit: 0,
        }
    }
}

/// The stages, as reported to observers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stage {
    /// Cutting surfaces into patches.
    Mesh,
    /// Building the hierarchy.
    Bvh,
    /// Form factors and progressive refinement.
    Solve,
    /// Rendering the picture.
    Render,
}

/// Progress reports.
#[derive(Clone, Copy)]
pub enum Event<'a> {
    /// A stage begins.
    Stage(Stage),
    /// Every row of F has been estimated and stored: the system to be solved.
    Matrix(&'a SparseMatrix, &'a System<'a>),
    /// The solver's status before each iteration, and the solver (whose current B can be read).
    Solve(&'a Status, &'a dyn Solver),
}

/// Wall-clock seconds per stage.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Timings {
    /// Meshing.
    pub mesh: f64,
    /// Building the hierarchy.
    pub bvh: f64,
    /// Estimating form-factor rows (part of the solve).
    pub form_factors: f64,
    /// Solving, form factors excluded.
    pub solve: f64,
}

/// A solved scene.
#[derive(Debug)]
pub struct Solution {
    /// The patches.
    pub mesh: Mesh,
    /// The hierarchy over them.
    pub bvh: Bvh,
    /// Patch areas (f64).
    pub area: Vec<f64>,
    /// Patch reflectances.
    pub reflectance: Vec<Rgb>,
    /// Patch emissions.
    pub emission: Vec<Rgb>,
    /// Radiosity per patch (the method's output, without the ambient term).
    pub radiosity: Vec<Rgb>,
    /// Unshot radiosity per patch when a shooting method stopped (zero for the others).
    pub unshot: Vec<Rgb>,
    /// The method used.
    pub method: Method,
    /// The solver's report.
    pub info: Info,
    /// Form-factor work.
    pub form_factors: FormFactorStats,
    /// Time per stage.
    pub timings: Timings,
}

impl Solution {
    /// The linear system that was solved.
    pub fn system(&self) -> System<'_> {
        System {
            area: &self.area,
            reflectance: &self.reflectance,
            emission: &self.emission,
        }
    }

    /// Radiosity for display: `B_i + ρ_i · ambient` (the ambient term of Cohen et al. 1988, see
    /// [`ambient_term`]), which stands in for the light not yet shot.
    pub fn display_radiosity(&self) -> Vec<Rgb> {
        let ambient = ambient_term(&self.system(), &self.unshot);
        self.radiosity
            .iter()
            .zip(&self.reflectance)
            .map(|(b, r)| *b + *r * ambient)
            .collect()
    }

    /// The view for `scene`: its own camera, else one inside it when its vertical is known and it
    /// is an interior ([`crate::render::camera::default_camera`]), else one framing it.
    pub fn default_camera(&self, scene: &Scene) -> Camera {
        match (scene.camera, scene.up) {
            (Some(c), _) => c,
            (None, Some(up)) => crate::render::camera::default_camera(&self.bvh, up),
            (None, None) => scene.camera_or_default(),
        }
    }

    /// The display radiosity at each mesh vertex, interpolated within surfaces
    /// ([`vertex_radiosity`]): what pictures and baked files show.
    pub fn vertex_display_radiosity(&self) -> Vec<Rgb> {
        vertex_radiosity(&self.mesh, &self.display_radiosity())
    }

    /// Automatic exposure for baked colours ([`crate::render::auto_exposure_patches`]).
    pub fn auto_exposure(&self) -> f32 {
        crate::render::auto_exposure_patches(&self.display_radiosity(), &self.area)
    }

    /// Render the display radiosity, Gouraud-interpolated within surfaces.
    pub fn render(
        &self,
        camera: &Camera,
        params: &RenderParams,
        progress: &(dyn Fn(u32) + Sync),
    ) -> Image {
        let vertex = vertex_radiosity(&self.mesh, &self.display_radiosity());
        render(&self.mesh, &self.bvh, &vertex, camera, params, progress)
    }
}

/// The per-patch data of the radiosity system of a meshed scene, owned.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PatchData {
    /// Patch areas.
    pub area: Vec<f64>,
    /// Patch reflectances (from their materials).
    pub reflectance: Vec<Rgb>,
    /// Patch emissions (from their materials).
    pub emission: Vec<Rgb>,
}

impl PatchData {
    /// The areas, reflectances and emissions of `mesh`'s patches in `scene`.
    pub fn new(scene: &Scene, mesh: &Mesh) -> Self {
        let material = |p: &crate::mesh::Patch| &scene.materials[p.material as usize];
        Self {
            area: mesh.patches.iter().map(|p| p.area as f64).collect(),
            reflectance: mesh
                .patches
                .iter()
                .map(|p| material(p).reflectance)
                .collect(),
            emission: mesh.patches.iter().map(|p| material(p).emission).collect(),
        }
    }

    /// The system view the solvers take.
    pub fn system(&self) -> System<'_> {
        System {
            area: &self.area,
            reflectance: &self.reflectance,
            emission: &self.emission,
        }
    }
}

/// Bytes of memory per patch the pipeline needs besides the form-factor cache (patch record,
/// vertices, two triangles and their hierarchy nodes, the system and solver vectors).
pub const BYTES_PER_PATCH: u64 = 420;

/// Memory the machine has available, from `/proc/meminfo` (`None` where unknown).
pub fn available_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// Validate, mesh and solve `scene`.
pub fn solve(
    scene: &Scene,
    settings: &Settings,
    observer: &mut dyn FnMut(Event),
) -> Result<Solution, Error> {
    scene.validate()?;
    observer(Event::Stage(Stage::Mesh));
    let t = Instant::now();
    let mesh = Mesh::build(scene, settings.mesh)?;
    let mesh_s = t.elapsed().as_secs_f64();

    let limit = match settings.memory_limit {
        0 => available_memory().unwrap_or(u64::MAX),
        l => l,
    };
    let store =
        settings.store_matrix || settings.solver.needs_all_rows() || settings.geometric.is_some();
    // A stored matrix holds at most min(N, rays) entries a row, 20 bytes each (rows, columns,
    // sampling sums).
    let per_patch = BYTES_PER_PATCH
        + if store {
            20 * (mesh.len() as u64).min(settings.monte_carlo.rays as u64)
        } else {
            0
        };
    let needed = mesh.len() as u64 * per_patch;
    if needed > limit {
        return Err(Error::OutOfMemory {
            what: format!(
                "{} patches{}",
                mesh.len(),
                if store {
                    " with every form-factor row stored"
                } else {
                    ""
                }
            ),
            needed,
            limit,
            alternative: if store {
                "a shooting method (--solver progressive, which computes rows on demand), fewer patches or fewer --rays".into()
            } else {
                "fewer patches (--patches N or a larger --max-edge)".into()
            },
        });
    }
    let mut monte_carlo = settings.monte_carlo;
    monte_carlo.cache_bytes = monte_carlo.cache_bytes.min(((limit - needed) / 2) as usize);
    let mut params = settings.params;
    params.memory_limit = params.memory_limit.min(limit - needed);

    observer(Event::Stage(Stage::Bvh));
    let t = Instant::now();
    let bvh = Bvh::build(&mesh);
    let bvh_s = t.elapsed().as_secs_f64();

    observer(Event::Stage(Stage::Solve));
    let PatchData {
        area,
        reflectance,
        emission,
    } = PatchData::new(scene, &mesh);
    let system = System {
        area: &area,
        reflectance: &reflectance,
        emission: &emission,
    };
    system.validate()?;

    let mut stored;
    let mut on_demand = MonteCarloRows::new(&mesh, &bvh, monte_carlo);
    let mut form_factors = FormFactorStats::default();
    let source: &mut dyn RowSource = if store {
        let t = Instant::now();
        stored = match settings.geometric {
            Some(p) => crate::formfactor::Estimator::new(&mesh, &bvh, p)
                .map_err(|e| Error::Solve(crate::solve::SolveError::Invalid(e.to_string())))?
                .matrix(crate::formfactor::Storage::Sparse, &|_| {})
                .into_sparse(),
            None => {
                form_factors.rays = mesh.len() as u64 * monte_carlo.rays as u64;
                estimate_all_rows(&mesh, &bvh, monte_carlo.rays, monte_carlo.seed)
            }
        };
        form_factors.rows = mesh.len() as u64;
        form_factors.seconds = t.elapsed().as_secs_f64();
        observer(Event::Matrix(&stored, &system));
        &mut stored
    } else {
        &mut on_demand
    };
    let mut solver = crate::solve::start(settings.solver, system, source, &params)?;
    let info = crate::solve::run(&mut *solver, source, &params, false, &mut |s, sv| {
        observer(Event::Solve(s, sv))
    });
    let mut radiosity = Vec::new();
    solver.radiosity(&mut radiosity);
    let unshot = solver
        .unshot()
        .map_or_else(|| vec![Rgb::BLACK; area.len()], <[Rgb]>::to_vec);
    drop(solver);
    if !store {
        form_factors = on_demand.stats();
    }
    let solve_s = (info.seconds - if store { 0.0 } else { form_factors.seconds }).max(0.0);
    Ok(Solution {
        timings: Timings {
            mesh: mesh_s,
            bvh: bvh_s,
            form_factors: form_factors.seconds,
            solve: solve_s,
        },
        mesh,
        bvh,
        area,
        reflectance,
        emission,
        radiosity,
        unshot,
        method: settings.solver,
        info,
        form_factors,
    })
}
