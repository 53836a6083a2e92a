//! The one place that knows every stage, in order: validate the scene → mesh it into patches →
//! build the ray-casting hierarchy → solve (shooting methods with Monte Carlo form factors
//! computed on demand; the others, or any method when the whole matrix is asked for, with every
//! row estimated first and stored sparse) → (optionally) render.

use crate::accel::Bvh;
use crate::color::Rgb;
use crate::formfactor::{Estimator, FormFactorMethod, FormFactorStats, OnDemandRows, Storage};
use crate::mesh::{Mesh, MeshParams};
pub use crate::observe::{Event, Observer, Stage};
use crate::render::{render, vertex_radiosity, Image, RenderParams};
use crate::scene::{Camera, Scene};
use crate::solve::trace::Trace;
use crate::solve::{ambient_term, Info, Solver, SolverParams};
use crate::system::{Operator, SparseMatrix, System};
use crate::Error;
use std::time::Instant;

/// Whether every row of F is computed and stored before the solver starts, or computed when
/// the solver asks for it ([`OnDemandRows`], O(N) memory plus a bounded cache).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Rows {
    /// On demand for the shooting solvers with Monte Carlo form factors; stored otherwise.
    #[default]
    Auto,
    /// Every row stored first (a trace's reference solution needs the very matrix the solver
    /// used).
    Stored,
    /// Rows on demand for any method; solvers that need every row before they start still get
    /// them computed up front.
    OnDemand,
}

/// Everything that decides a solution.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Settings {
    /// How to cut surfaces into patches.
    pub mesh: MeshParams,
    /// Form factors: the method and its parameters.
    pub form_factors: crate::formfactor::Params,
    /// Stored or on-demand rows.
    pub rows: Rows,
    /// The solution method.
    pub solver: Solver,
    /// Its parameters (tolerance, iterations, ω, photons, seed, memory).
    pub params: SolverParams,
    /// Refuse jobs whose estimated memory exceeds this many bytes (0: the machine's available
    /// memory).
    pub memory_limit: u64,
    /// Record a convergence trace ([`Solution::trace`]); every row of F is then stored first,
    /// so that the error can be measured against the LU solution of the very matrix solved.
    pub trace: bool,
    /// Solve by hierarchical radiosity with these parameters instead of meshing uniformly and
    /// running `solver` ([`crate::hierarchical`]): `mesh`, `form_factors`, `rows` and `solver`
    /// are then unused.
    pub hierarchical: Option<crate::hierarchical::Params>,
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            mesh: MeshParams::default(),
            form_factors: crate::formfactor::Params::shooting(),
            rows: Rows::Auto,
            solver: Solver::Progressive,
            params: SolverParams::default(),
            memory_limit: 0,
            trace: false,
            hierarchical: None,
        }
    }
}

impl Settings {
    /// True when every row of F is computed and stored before the solver starts.
    pub fn stores_rows(&self) -> bool {
        self.trace
            || self.solver.needs_all_rows()
            || match self.rows {
                Rows::Auto => self.form_factors.method != FormFactorMethod::MonteCarlo,
                Rows::Stored => true,
                Rows::OnDemand => false,
            }
    }
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
    /// The part of `solve` spent casting the solver's own rays in parallel (stochastic
    /// Jacobi's photons and gathering rays, [`crate::solve::Info::ray_seconds`]); 0 for the
    /// other solvers.
    pub solve_rays: f64,
}

/// A solved scene.
#[derive(Debug)]
pub struct Solution {
    /// The patches.
    pub mesh: Mesh,
    /// The hierarchy over them.
    pub bvh: Bvh,
    /// The linear system that was solved (areas, reflectances, emissions).
    pub system: System,
    /// Radiosity per patch (the method's output, without the ambient term).
    pub radiosity: Vec<Rgb>,
    /// Unshot radiosity per patch when a shooting method stopped (zero for the others).
    pub unshot: Vec<Rgb>,
    /// The method used.
    pub method: Solver,
    /// The solver's report.
    pub info: Info,
    /// Form-factor work.
    pub form_factors: FormFactorStats,
    /// Time per stage.
    pub timings: Timings,
    /// The convergence trace, when [`Settings::trace`] asked for one.
    pub trace: Option<Trace>,
    /// The element hierarchy and its links, when solved by hierarchical radiosity (the
    /// patches are then its leaves: patch `k` is element `leaves[k]`).
    pub hierarchy: Option<HierarchicalSolution>,
}

/// What hierarchical radiosity leaves beside the leaf patches.
#[derive(Debug)]
pub struct HierarchicalSolution {
    /// Every element, cluster and link, with radiosities.
    pub hierarchy: crate::hierarchical::Hierarchy,
    /// The element of each patch.
    pub leaves: Vec<u32>,
    /// The input polygon (surface) of each root element.
    pub root_surfaces: Vec<u32>,
}

impl Solution {
    /// The method's name: the solver's, or `hierarchical`.
    pub fn method_name(&self) -> &'static str {
        if self.hierarchy.is_some() {
            "hierarchical"
        } else {
            self.method.name()
        }
    }
}

impl Solution {
    /// Radiosity for display: `B_i + ρ_i · ambient` (the ambient term of Cohen et al. 1988, see
    /// [`ambient_term`]), which stands in for the light not yet shot.
    pub fn display_radiosity(&self) -> Vec<Rgb> {
        let ambient = ambient_term(&self.system, &self.unshot);
        self.radiosity
            .iter()
            .zip(&self.system.reflectance)
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
        crate::render::auto_exposure_patches(&self.display_radiosity(), &self.system.area)
    }

    /// Render by final gather over the solution's radiosity (no ambient term):
    /// [`crate::render::gather`].
    pub fn render_gather(
        &self,
        camera: &Camera,
        params: &RenderParams,
        gather: crate::render::gather::GatherParams,
        observer: &dyn Observer,
    ) -> Image {
        let vertex = vertex_radiosity(&self.mesh, &self.radiosity);
        let g = crate::render::gather::Gather::new(self.surfaces(), &vertex, gather);
        g.render(camera, params, observer)
    }

    /// The solution's surfaces for the ray-traced integrators.
    pub fn surfaces(&self) -> crate::render::light::Surfaces<'_> {
        crate::render::light::Surfaces {
            mesh: &self.mesh,
            bvh: &self.bvh,
            reflectance: &self.system.reflectance,
            emission: &self.system.emission,
        }
    }

    /// Render the display radiosity, Gouraud-interpolated within surfaces.
    pub fn render(&self, camera: &Camera, params: &RenderParams, observer: &dyn Observer) -> Image {
        let vertex = vertex_radiosity(&self.mesh, &self.display_radiosity());
        render(&self.mesh, &self.bvh, &vertex, camera, params, observer)
    }
}

/// The linear system of `mesh`'s patches in `scene`: areas, and reflectances and emissions
/// from their materials. The one bridge from geometry to the solvers.
pub fn patch_system(scene: &Scene, mesh: &Mesh) -> System {
    let material = |p: &crate::mesh::Patch| &scene.materials[p.material as usize];
    System {
        area: mesh.patches.iter().map(|p| p.area as f64).collect(),
        reflectance: mesh
            .patches
            .iter()
            .map(|p| material(p).reflectance)
            .collect(),
        emission: mesh.patches.iter().map(|p| material(p).emission).collect(),
    }
}

/// Bytes of memory per patch the pipeline needs besides the form-factor cache (patch record,
/// vertices, two triangles and their hierarchy nodes, the system and solver vectors).
pub const BYTES_PER_PATCH: u64 = 420;

/// The memory a job needs against what it may use: per patch [`BYTES_PER_PATCH`], plus, when
/// every row of F is stored, at most min(N, rays) entries a row of 20 bytes (rows, columns,
/// sampling sums).
#[derive(Clone, Copy, Debug)]
pub struct MemoryCheck {
    /// Bytes the job may use.
    pub limit: u64,
    /// Every row of F is stored.
    pub stored_rows: bool,
    /// Monte Carlo rays a row (bounds a stored row's entries).
    pub rays: u32,
}

impl MemoryCheck {
    /// The bytes `patches` patches need, or the refusal.
    pub fn check(&self, patches: u64) -> Result<u64, Error> {
        let per_patch = BYTES_PER_PATCH
            + if self.stored_rows {
                20 * patches.min(self.rays as u64)
            } else {
                0
            };
        let needed = patches.saturating_mul(per_patch);
        if needed > self.limit {
            return Err(Error::OutOfMemory {
                what: format!(
                    "{patches} patches{}",
                    if self.stored_rows {
                        " with every form-factor row stored"
                    } else {
                        ""
                    }
                ),
                needed,
                limit: self.limit,
                stored_rows: self.stored_rows,
            });
        }
        Ok(needed)
    }

    /// Checked before meshing from what the meshing parameters imply: the patch count asked
    /// for (the mesher comes within a few per cent of it), or, for a largest edge l, the
    /// scene's area / l² (a patch no longer than l a side covers at most l²).
    pub fn before_meshing(&self, scene: &Scene, mesh: MeshParams) -> Result<(), Error> {
        match mesh {
            MeshParams::Patches(n) => self.check(n as u64).map(|_| ()),
            MeshParams::MaxEdge(l) => {
                let at_least = scene.total_area() / (l as f64 * l as f64);
                self.check(if at_least.is_finite() {
                    at_least as u64
                } else {
                    u64::MAX
                })
                .map(|_| ())
            }
            MeshParams::Faces => Ok(()),
        }
    }
}

/// Memory this process may still use: the smallest of the machine's available memory
/// (`/proc/meminfo`), the room left under its cgroup's limit (`memory.max` − `memory.current`,
/// cgroup v2) and its address-space limit (`ulimit -v`, `/proc/self/limits`). `None` where none
/// is known.
pub fn available_memory() -> Option<u64> {
    let read = |p: &str| std::fs::read_to_string(p).ok();
    let meminfo = read("/proc/meminfo").and_then(|t| {
        let line = t
            .lines()
            .find(|l| l.starts_with("MemAvailable:"))?
            .to_string();
        let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
        Some(kib * 1024)
    });
    let cgroup = (|| {
        let max: u64 = read("/sys/fs/cgroup/memory.max")?.trim().parse().ok()?;
        let current: u64 = read("/sys/fs/cgroup/memory.current")?.trim().parse().ok()?;
        Some(max.saturating_sub(current))
    })();
    let address_space = read("/proc/self/limits").and_then(|t| {
        let line = t
            .lines()
            .find(|l| l.starts_with("Max address space"))?
            .to_string();
        line.split_whitespace().nth(3)?.parse::<u64>().ok()
    });
    [meminfo, cgroup, address_space].into_iter().flatten().min()
}

/// Validate, mesh and solve `scene`.
pub fn solve(
    scene: &Scene,
    settings: &Settings,
    observer: &dyn Observer,
) -> Result<Solution, Error> {
    scene.validate()?;
    let limit = match settings.memory_limit {
        0 => available_memory().unwrap_or(u64::MAX),
        l => l,
    };
    if let Some(params) = &settings.hierarchical {
        return solve_hierarchical(scene, params, limit, observer);
    }
    let store = settings.stores_rows();
    let memory = MemoryCheck {
        limit,
        stored_rows: store,
        rays: settings.form_factors.rays,
    };
    let check = |patches: u64| memory.check(patches);
    memory.before_meshing(scene, settings.mesh)?;
    observer.event(Event::Stage(Stage::Mesh));
    let t = Instant::now();
    let mesh = Mesh::build(scene, settings.mesh)?;
    let mesh_s = t.elapsed().as_secs_f64();
    let needed = check(mesh.len() as u64)?;
    // Gauss' dense matrix is refused before any form factor is computed.
    if settings.solver == Solver::Gauss {
        let dense = crate::solve::gauss::bytes_needed(mesh.len());
        let allowed = settings.params.memory_limit.min(limit - needed);
        if dense > allowed {
            return Err(crate::solve::SolveError::TooLarge {
                solver: Solver::Gauss,
                n: mesh.len(),
                needed: dense,
                limit: allowed,
                alternative: "an iterative solver (progressive, gauss-seidel or overshoot) needs no dense matrix",
            }
            .into());
        }
    }
    let mut ff = settings.form_factors;
    ff.cache_bytes = ff.cache_bytes.min(((limit - needed) / 2) as usize);
    // Parameters are checked before any work.
    ff.validate()?;
    let mut params = settings.params;
    params.memory_limit = params.memory_limit.min(limit - needed);

    observer.event(Event::Stage(Stage::Bvh));
    let t = Instant::now();
    let bvh = Bvh::build(&mesh);
    let bvh_s = t.elapsed().as_secs_f64();

    let system = patch_system(scene, &mesh);
    system.validate().map_err(|e| located(e, scene, &mesh))?;

    let estimator = Estimator::new(&mesh, &bvh, ff)?;
    let mut stored;
    let mut trace = None;
    let mut form_factors = FormFactorStats::default();
    let mut on_demand = None;
    let source: &mut dyn Operator = if store {
        let t = Instant::now();
        stored = estimator.matrix(Storage::Sparse, observer).into_sparse();
        if ff.method == FormFactorMethod::MonteCarlo {
            form_factors.rays = mesh.len() as u64 * ff.rays as u64;
        }
        form_factors.rows = mesh.len() as u64;
        form_factors.seconds = t.elapsed().as_secs_f64();
        observer.event(Event::Matrix(&stored, &system));
        if settings.trace {
            trace = Some(Trace::new(
                trace_reference(&system, &stored, observer),
                &system.emission,
            ));
        }
        &mut stored
    } else {
        on_demand.insert(OnDemandRows::new(estimator))
    };
    observer.event(Event::Stage(Stage::Solve));
    let mut solver = crate::solve::start(settings.solver, &system, source, &params)?;
    let info = crate::solve::run(&mut *solver, source, &params, false, &mut |s, sv| {
        if let Some(t) = trace.as_mut() {
            t.record(s, sv);
        }
        observer.event(Event::Solve(s, sv));
        !observer.cancelled()
    });
    let mut radiosity = Vec::new();
    solver.radiosity(&mut radiosity);
    let unshot = solver.unshot().map_or_else(
        || vec![Rgb::BLACK; system.len()],
        std::borrow::Cow::into_owned,
    );
    drop(solver);
    if let Some(rows) = &on_demand {
        form_factors = rows.stats();
    }
    let solve_s = (info.seconds - if store { 0.0 } else { form_factors.seconds }).max(0.0);
    Ok(Solution {
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
        trace,
        hierarchy: None,
    })
}

/// Hierarchical radiosity over the scene's pieces ([`crate::hierarchical`]); the solution's
/// patches are the leaf elements, and its hierarchy is built over them for pictures.
fn solve_hierarchical(
    scene: &Scene,
    params: &crate::hierarchical::Params,
    limit: u64,
    observer: &dyn Observer,
) -> Result<Solution, Error> {
    params.validate()?;
    observer.event(Event::Stage(Stage::Mesh));
    let t = Instant::now();
    let roots = Mesh::build(scene, MeshParams::Faces)?;
    let root_system = patch_system(scene, &roots);
    root_system
        .validate()
        .map_err(|e| located(e, scene, &roots))?;
    let mesh_s = t.elapsed().as_secs_f64();
    observer.event(Event::Stage(Stage::Bvh));
    let t = Instant::now();
    let root_bvh = Bvh::build(&roots);
    let mut bvh_s = t.elapsed().as_secs_f64();
    let params = crate::hierarchical::Params {
        memory_limit: params.memory_limit.min(limit / 2),
        ..*params
    };
    let h = crate::hierarchical::solve(&roots, &root_system, &root_bvh, &params, observer)?;
    let t = Instant::now();
    let leaves = h.leaves();
    let mesh = crate::hierarchical::output::leaf_mesh(&h, &roots, &leaves);
    let root_of = |k: usize| h.elements.items[leaves[k] as usize].root as usize;
    let system = System {
        area: mesh.patches.iter().map(|p| p.area as f64).collect(),
        reflectance: (0..leaves.len())
            .map(|k| root_system.reflectance[root_of(k)])
            .collect(),
        emission: (0..leaves.len())
            .map(|k| root_system.emission[root_of(k)])
            .collect(),
    };
    let radiosity: Vec<Rgb> = leaves.iter().map(|&e| h.radiosity[e as usize]).collect();
    let unshot: Vec<Rgb> = leaves.iter().map(|&e| h.unshot[e as usize]).collect();
    let bvh = Bvh::build(&mesh);
    bvh_s += t.elapsed().as_secs_f64();
    let hi = h.info;
    // Energy: emitted by every leaf; what arrived (Σ A H) against what left (Σ A B) over the
    // leaves that are not a coincident twin's copy (the same surface, counted once).
    let counted: Vec<bool> = (0..leaves.len())
        .map(|k| h.twin_of[root_of(k)] as usize == root_of(k))
        .collect();
    let sum = |f: &dyn Fn(usize) -> Rgb| -> Rgb {
        (0..leaves.len()).filter(|&k| counted[k]).map(f).sum()
    };
    let emitted: Rgb = (0..leaves.len())
        .map(|k| system.emission[k] * system.area[k])
        .sum();
    // What arrived at each leaf, H A: through its own links and every ancestor's.
    let incident = |k: usize| {
        let e = leaves[k] as usize;
        h.incident[e] * h.elements.items[e].area as f64
    };
    let arrived = sum(&incident);
    // A twin's emission leaves through the first of its group.
    let left = sum(&|k| radiosity[k] * system.area[k])
        + (0..leaves.len())
            .filter(|&k| !counted[k])
            .map(|k| system.emission[k] * system.area[k])
            .sum::<Rgb>();
    let absorbed = sum(&|k| incident(k) * (Rgb::splat(1.0) - system.reflectance[k]));
    let unshot_power = sum(&|k| unshot[k] * system.area[k]);
    let info = Info {
        iterations: hi.iterations,
        converged: hi.converged,
        unshot_fraction: hi.unshot_fraction,
        seconds: hi.refine_seconds + hi.solve_seconds,
        emitted,
        absorbed,
        escaped: left - arrived,
        unshot: unshot_power,
        estimated_error: 0.0,
        ray_seconds: 0.0,
    };
    Ok(Solution {
        timings: Timings {
            mesh: mesh_s,
            bvh: bvh_s,
            form_factors: hi.refine_seconds,
            solve: hi.solve_seconds,
            solve_rays: 0.0,
        },
        mesh,
        bvh,
        system,
        radiosity,
        unshot,
        method: Solver::Jacobi,
        info,
        form_factors: FormFactorStats {
            rows: hi.links as u64,
            rays: hi.rays,
            seconds: hi.refine_seconds,
            ..Default::default()
        },
        trace: None,
        hierarchy: Some(HierarchicalSolution {
            hierarchy: h,
            leaves,
            root_surfaces: roots.patches.iter().map(|p| p.surface).collect(),
        }),
    })
}

/// Path-traced mean radiosity of every surface (input polygon) of `scene`, with its standard
/// error ([`crate::render::path::surface_means`]): `samples` paths in all, shared among the
/// surfaces in proportion to their area (at least 64 each). The independent reference that
/// solutions' surface means are measured against.
pub fn path_surface_means(
    scene: &Scene,
    samples: u64,
    seed: u64,
) -> Result<Vec<(Rgb, Rgb)>, Error> {
    traced_means(scene, |surfaces, lights| {
        let mut area = vec![0.0f64; scene.polygons.len()];
        for p in &surfaces.mesh.patches {
            area[p.surface as usize] += p.area as f64;
        }
        let total: f64 = area.iter().sum();
        let counts: Vec<u64> = area
            .iter()
            .map(|a| ((samples as f64 * a / total).round() as u64).max(64))
            .collect();
        crate::render::path::surface_means(surfaces, lights, &counts, seed)
    })
}

/// Light-traced mean radiosity of every surface (input polygon) of `scene`, with its standard
/// error ([`crate::render::particle::surface_means`]): `particles` particles shot from the
/// emitters. The second independent reference beside [`path_surface_means`]; it spends its
/// rays where the light goes, which suits scenes whose lamps throw small bright spots.
pub fn light_surface_means(
    scene: &Scene,
    particles: u64,
    seed: u64,
) -> Result<Vec<(Rgb, Rgb)>, Error> {
    traced_means(scene, |surfaces, lights| {
        crate::render::particle::surface_means(
            surfaces,
            lights,
            scene.polygons.len(),
            particles,
            seed,
        )
    })
}

/// `scene` validated, meshed one patch a face with its hierarchy and materials, handed to a
/// tracer of surface means.
fn traced_means(
    scene: &Scene,
    trace: impl FnOnce(
        &crate::render::light::Surfaces<'_>,
        &crate::render::light::Lights,
    ) -> Vec<(Rgb, Rgb)>,
) -> Result<Vec<(Rgb, Rgb)>, Error> {
    scene.validate()?;
    let mesh = Mesh::build(scene, MeshParams::Faces)?;
    let bvh = Bvh::build(&mesh);
    let system = patch_system(scene, &mesh);
    let surfaces = crate::render::light::Surfaces {
        mesh: &mesh,
        bvh: &bvh,
        reflectance: &system.reflectance,
        emission: &system.emission,
    };
    let lights = crate::render::light::Lights::new(&mesh, &system.emission);
    Ok(trace(&surfaces, &lights))
}

/// A system error about a patch, as an error at the place of the polygon it was cut from.
pub(crate) fn located(e: crate::system::SystemError, scene: &Scene, mesh: &Mesh) -> Error {
    use crate::system::SystemError as E;
    match &e {
        E::Area { patch, .. } | E::Reflectance { patch, .. } | E::Emission { patch, .. } => {
            let surface = mesh.patches[*patch].surface as usize;
            Error::Scene(crate::scene::SceneError::Invalid {
                at: scene.place_of(surface),
                message: format!("{e} (a patch cut from this polygon)"),
            })
        }
        _ => Error::Solve(e.into()),
    }
}

/// Largest system whose trace measures the error against an LU solution.
pub const TRACE_EXACT_MAX: usize = 5000;

/// The exact solution a trace's error column is measured against: the LU solution of the
/// stored matrix `f`, when the system has at most [`TRACE_EXACT_MAX`] patches and the dense
/// matrix fits in half the available memory; otherwise `None`, with a warning to `observer`.
pub fn trace_reference(
    system: &System,
    f: &SparseMatrix,
    observer: &dyn Observer,
) -> Option<Vec<Rgb>> {
    let n = system.len();
    let limit = available_memory().unwrap_or(u64::MAX) / 2;
    if n > TRACE_EXACT_MAX || crate::solve::gauss::bytes_needed(n) > limit {
        observer.event(Event::Warning(&format!(
            "{n} patches: the trace's error column is left empty (LU reference only up to {TRACE_EXACT_MAX} patches)"
        )));
        return None;
    }
    match crate::solve::gauss::dense_solve_matrix(system, f, limit) {
        Ok(b) => Some(b),
        Err(e) => {
            observer.event(Event::Warning(&format!(
                "no reference solution for the trace: {e}"
            )));
            None
        }
    }
}

/// A given linear system, solved.
#[derive(Debug)]
pub struct SystemSolution {
    /// Radiosity per patch.
    pub radiosity: Vec<Rgb>,
    /// The solver's report.
    pub info: Info,
    /// The convergence trace, when asked for.
    pub trace: Option<Trace>,
}

/// Solve a given system (areas, reflectances, emissions and a stored F, e.g. read from files)
/// by `solver`; with `trace`, record the convergence of every iteration, each status exact
/// ([`crate::solve::run`]). The solver may use half the available memory.
pub fn solve_system(
    system: &System,
    f: &mut SparseMatrix,
    solver: Solver,
    params: &SolverParams,
    trace: bool,
    observer: &dyn Observer,
) -> Result<SystemSolution, Error> {
    let mut params = *params;
    params.memory_limit = available_memory().unwrap_or(u64::MAX) / 2;
    system.validate().map_err(crate::solve::SolveError::from)?;
    system
        .check_operator(f)
        .map_err(crate::solve::SolveError::from)?;
    let mut trace =
        trace.then(|| Trace::new(trace_reference(system, f, observer), &system.emission));
    observer.event(Event::Stage(Stage::Solve));
    let mut state = crate::solve::start(solver, system, f, &params)?;
    let info = crate::solve::run(&mut *state, f, &params, trace.is_some(), &mut |s, sv| {
        if let Some(t) = trace.as_mut() {
            t.record(s, sv);
        }
        observer.event(Event::Solve(s, sv));
        !observer.cancelled()
    });
    let mut radiosity = Vec::new();
    state.radiosity(&mut radiosity);
    Ok(SystemSolution {
        radiosity,
        info,
        trace,
    })
}

/// Path-trace `scene` ([`crate::render::path`]): no radiosity solution, one patch per planar
/// piece of each face (the finest geometry the scene has; shading does not depend on it).
pub fn path_trace(
    scene: &Scene,
    camera: &Camera,
    params: &RenderParams,
    observer: &dyn Observer,
) -> Result<Image, Error> {
    scene.validate()?;
    let mesh = Mesh::build(scene, crate::mesh::MeshParams::Faces)?;
    let bvh = Bvh::build(&mesh);
    let system = patch_system(scene, &mesh);
    let surfaces = crate::render::light::Surfaces {
        mesh: &mesh,
        bvh: &bvh,
        reflectance: &system.reflectance,
        emission: &system.emission,
    };
    Ok(crate::render::path::render(
        &surfaces, camera, params, observer,
    ))
}

/// Whether a thermal problem's surfaces close an enclosure.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Enclosure {
    /// Closed when `hint` says so (a View3D file's `encl`), else when every row of F sums to
    /// at least 0.99 (what is missing is then estimation error).
    #[default]
    Auto,
    /// Every row is rescaled to sum to 1.
    Closed,
    /// What a row misses reaches the surroundings.
    Open,
}

/// How a thermal problem is meshed and its view factors computed.
#[derive(Clone, Copy, Debug)]
pub struct ThermalSettings {
    /// Patches (the engineer's default: one per face).
    pub mesh: MeshParams,
    /// View factors; `rays` is replaced by [`thermal_default_rays`] when `default_rays`.
    pub form_factors: crate::formfactor::Params,
    /// Use [`thermal_default_rays`] for Monte Carlo.
    pub default_rays: bool,
    /// Metres per scene unit.
    pub unit_metres: f64,
    /// Temperature of the surroundings, K.
    pub environment: f64,
    /// Closed or open.
    pub enclosure: Enclosure,
    /// What `Enclosure::Auto` takes from the input (a View3D file's `encl`), if anything.
    pub enclosure_hint: Option<bool>,
    /// Dense or iterative.
    pub linear: crate::thermal::LinearSolver,
    /// Bytes the job may use (0: the machine's available memory).
    pub memory_limit: u64,
}

impl Default for ThermalSettings {
    fn default() -> Self {
        Self {
            mesh: MeshParams::Faces,
            form_factors: crate::formfactor::Params::default(),
            default_rays: true,
            unit_metres: 1.0,
            environment: 0.0,
            enclosure: Enclosure::Auto,
            enclosure_hint: None,
            linear: crate::thermal::LinearSolver::Auto,
            memory_limit: 0,
        }
    }
}

/// Default Monte Carlo rays per row of a thermal solve on `n` patches: 10⁶ up to 100
/// patches, then a total of 10⁸ rays shared out, but at least 10⁴ a row (each patch's
/// irradiation then has a relative standard error of at most 1 % of the spread of the
/// radiosities it sees).
pub fn thermal_default_rays(n: usize) -> u32 {
    (1e8 / n.max(1) as f64).clamp(1e4, 1e6) as u32
}

/// A thermal problem solved: the patches, the system, the solution and what was done.
#[derive(Debug)]
pub struct ThermalOutcome {
    /// The patches.
    pub mesh: Mesh,
    /// Areas (m²), boundaries, surroundings.
    pub system: crate::thermal::ThermalSystem,
    /// Radiosity, irradiation, temperature and flux per patch.
    pub solution: crate::thermal::ThermalSolution,
    /// Per boundary: area m², net power W, temperature K ([`crate::thermal::ThermalSolution::per_boundary`]).
    pub per_boundary: Vec<(f64, f64, f64)>,
    /// The form-factor parameters used.
    pub form_factors: crate::formfactor::Params,
    /// Seconds computing F.
    pub form_factor_seconds: f64,
    /// F's row sums and reciprocity before and after enforcement.
    pub before: crate::formfactor::Summary,
    /// See `before`.
    pub after: crate::formfactor::Summary,
    /// Whether the enclosure was treated as closed.
    pub closed: bool,
}

/// The boundary of each material of `scene` that has polygons, from `(name, boundary)` pairs;
/// `Err` with a message naming the unknown name (and what the scene has) or the surfaces
/// without a boundary. `combined` maps a name that a View3D file combines into another to
/// that other's name, for the message.
#[allow(clippy::type_complexity)]
pub fn thermal_boundaries(
    scene: &Scene,
    names: &[(String, crate::thermal::Boundary)],
    combined: &dyn Fn(&str) -> Option<String>,
) -> Result<Vec<Option<u32>>, (Option<usize>, String)> {
    let mut used = vec![false; scene.materials.len()];
    for p in &scene.polygons {
        used[p.material] = true;
    }
    let by_name: std::collections::HashMap<&str, usize> = scene
        .materials
        .iter()
        .enumerate()
        .filter(|(m, _)| used[*m])
        .map(|(m, mat)| (mat.name.as_str(), m))
        .collect();
    let mut boundary_of = vec![None; scene.materials.len()];
    for (k, (name, _)) in names.iter().enumerate() {
        let Some(&m) = by_name.get(name.as_str()) else {
            let hint = match combined(name) {
                Some(t) => format!("it is combined into '{t}' (cmb); name that surface"),
                None => {
                    let mut all: Vec<&str> = by_name.keys().copied().collect();
                    all.sort_unstable();
                    let shown = all.len().min(20);
                    format!(
                        "the scene's surfaces are: {}{}",
                        all[..shown].join(", "),
                        if all.len() > shown {
                            format!(" and {} more", all.len() - shown)
                        } else {
                            String::new()
                        }
                    )
                }
            };
            return Err((Some(k), format!("unknown surface '{name}'; {hint}")));
        };
        boundary_of[m] = Some(k as u32);
    }
    let mut missing: Vec<&str> = (0..scene.materials.len())
        .filter(|&m| used[m] && boundary_of[m].is_none())
        .map(|m| scene.materials[m].name.as_str())
        .collect();
    if !missing.is_empty() {
        missing.sort_unstable();
        return Err((
            None,
            format!(
                "no boundary condition for {} surface{}: {} (add a row for each; leave temperature and flux empty for an adiabatic surface)",
                missing.len(),
                if missing.len() == 1 { "" } else { "s" },
                missing.join(", ")
            ),
        ));
    }
    Ok(boundary_of)
}

/// The memory check of a thermal problem's stored F.
pub fn thermal_memory(p: &crate::formfactor::Params, limit: u64) -> MemoryCheck {
    use crate::formfactor::FormFactorMethod as M;
    MemoryCheck {
        limit,
        stored_rows: true,
        rays: match p.method {
            M::MonteCarlo => p.rays,
            M::Hemicube | M::Tetrahedron | M::Hemisphere => {
                ((p.resolution as u64).pow(2) * 3 * p.samples as u64).min(u32::MAX as u64) as u32
            }
            M::Analytic => u32::MAX,
        },
    }
}

/// A thermal problem's F made physical: closed or open as `settings` say (open or closed by its
/// row sums when automatic), reciprocity enforced, rows rescaled to 1 when closed. Returns it,
/// its summaries before and after, and whether it was treated as closed.
pub fn thermal_enclosure(
    matrix: crate::system::SparseMatrix,
    area: &[f64],
    settings: &ThermalSettings,
) -> (
    crate::system::SparseMatrix,
    crate::formfactor::Summary,
    crate::formfactor::Summary,
    bool,
) {
    use crate::formfactor::{enforce, summary, Enforce};
    let before = summary(&matrix, area);
    let closed = match settings.enclosure {
        Enclosure::Closed => true,
        Enclosure::Open => false,
        Enclosure::Auto => settings
            .enclosure_hint
            .unwrap_or(before.min_row_sum >= 0.99),
    };
    let matrix = enforce(
        matrix,
        area,
        Enforce {
            clamp: false,
            normalize_rows: closed,
            symmetrize: true,
        },
    );
    let after = summary(&matrix, area);
    (matrix, before, after, closed)
}

/// The thermal system of `mesh`'s patches: areas in m², each patch's boundary.
pub fn thermal_system(
    mesh: &Mesh,
    area: &[f64],
    boundary_of: &[Option<u32>],
    boundaries: &[crate::thermal::Boundary],
    settings: &ThermalSettings,
    closed: bool,
) -> crate::thermal::ThermalSystem {
    let unit2 = settings.unit_metres * settings.unit_metres;
    crate::thermal::ThermalSystem {
        area: area.iter().map(|a| a * unit2).collect(),
        group: mesh
            .patches
            .iter()
            .map(|p| boundary_of[p.material as usize].unwrap_or(u32::MAX))
            .collect(),
        boundaries: boundaries.to_vec(),
        environment: settings.environment,
        closed,
    }
}

/// Solve a radiative heat-transfer problem on `scene`: `boundary_of` (from
/// [`thermal_boundaries`]) gives each material's boundary in `boundaries`. Meshes, computes
/// F (memory checked first), enforces reciprocity (and closure when closed), solves.
pub fn thermal(
    scene: &Scene,
    boundary_of: &[Option<u32>],
    boundaries: &[crate::thermal::Boundary],
    settings: &ThermalSettings,
    observer: &dyn Observer,
) -> Result<ThermalOutcome, Error> {
    use crate::formfactor::Estimator;
    scene.validate_geometry()?;
    let limit = match settings.memory_limit {
        0 => available_memory().unwrap_or(u64::MAX),
        l => l,
    };
    let mut params = settings.form_factors;
    let check = |p: &crate::formfactor::Params| thermal_memory(p, limit);
    if settings.default_rays {
        params.rays = 10_000;
    }
    check(&params).before_meshing(scene, settings.mesh)?;
    observer.event(Event::Stage(Stage::Mesh));
    let mesh = Mesh::build(scene, settings.mesh)?;
    if settings.default_rays {
        params.rays = thermal_default_rays(mesh.len());
    }
    check(&params).check(mesh.len() as u64)?;
    let t = Instant::now();
    observer.event(Event::Stage(Stage::Bvh));
    let bvh = Bvh::build(&mesh);
    let matrix = Estimator::new(&mesh, &bvh, params)?
        .matrix(crate::formfactor::Storage::Sparse, observer)
        .into_sparse();
    let form_factor_seconds = t.elapsed().as_secs_f64();
    drop(bvh);
    let area: Vec<f64> = mesh.patches.iter().map(|p| p.area as f64).collect();
    let (matrix, before, after, closed) = thermal_enclosure(matrix, &area, settings);
    let system = thermal_system(&mesh, &area, boundary_of, boundaries, settings, closed);
    observer.event(Event::Stage(Stage::Solve));
    let solution = crate::thermal::solve(
        &system,
        &matrix,
        crate::thermal::ThermalParams {
            linear: settings.linear,
            memory_limit: limit,
            ..Default::default()
        },
    )?;
    let per_boundary = solution.per_boundary(&system);
    Ok(ThermalOutcome {
        mesh,
        system,
        solution,
        per_boundary,
        form_factors: params,
        form_factor_seconds,
        before,
        after,
        closed,
    })
}
