//! The one place that knows every stage, in order: validate the scene → mesh it into patches →
//! build the ray-casting hierarchy → solve (shooting methods with Monte Carlo form factors
//! computed on demand; the others, or any method when the whole matrix is asked for, with every
//! row estimated first and stored sparse) → (optionally) render.
//!
//! One file a pipeline: [`solve`](solve()) (a scene, uniform or hierarchical), [`solve_system`]
//! (a given system), [`thermal`](thermal()) (radiative heat transfer), [`view_factors`]
//! (a view-factor matrix), the references ([`path_trace`], surface means); [`MemoryCheck`] is the
//! one memory model every pipeline checks a job against. Each takes the ranks of a distributed
//! run where it can run over several ([`crate::comm::Ranks`]; `None` for one process).

mod daylight;
mod lighting;
mod memory;
mod panes;
mod radiant;
mod reference;
mod solve;
mod sun_cone;
mod system;
mod thermal;
mod thermal_matrix_free;
mod view_factors;

/// The bridge from a meshed scene to its linear system (it lives with the mesh).
pub use crate::mesh::patch_system;
pub use crate::observe::{Event, Observer, Stage};
pub use daylight::{
    daylight, daylight_coefficients, DaylightCoefficients, DaylightResult, DaylightSettings,
    DaylightSource, DirectSun,
};
pub use lighting::{
    lighting, lighting_solution, luminance, EnergyBooks, LightingResult, LightingSettings,
    LightingSolution, SurfaceLight, BLACK_ROW_RAYS, ESCAPE_BANDS, ESCAPE_SECTORS, SCENE_GROUP,
};
pub use memory::{available_memory, MemoryCheck, MemoryLimit, BYTES_PER_PATCH};
pub use radiant::{
    radiant_temperatures, RadiantParams, RadiantPoint, RadiantResult, MAX_RADIANT_RAYS,
};
pub use reference::{light_surface_means, path_surface_means, path_trace};
pub use solve::{solve, solve_over};
pub use system::{solve_system, trace_reference, SystemSolution, TRACE_EXACT_MAX};
pub use thermal::{
    thermal, thermal_boundaries, thermal_default_rays, thermal_enclosure, thermal_over,
    thermal_system, Enclosure, ThermalOutcome, ThermalSettings,
};
pub use view_factors::{view_factors, view_factors_over, ViewFactorSettings, ViewFactors};

use crate::accel::Bvh;
use crate::color::Rgb;
use crate::formfactor::{FormFactorMethod, FormFactorStats};
use crate::mesh::{Mesh, MeshParams};
use crate::render::{render, vertex_radiosity, Image, RenderParams};
use crate::scene::{Camera, Scene};
use crate::solve::trace::Trace;
use crate::solve::{ambient_term, Info, Solver, SolverParams};
use crate::system::System;

/// Whether every row of F is computed and stored before the solver starts, or computed when
/// the solver asks for it ([`crate::formfactor::OnDemandRows`], O(N) memory plus a bounded cache).
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

/// How a scene is solved: each method with the settings it reads, and nothing it would ignore.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Method {
    /// Cut every surface into patches, estimate form factors (stored or on demand) and run a
    /// linear-system solver.
    Uniform(Uniform),
    /// Hierarchical radiosity with clustering ([`crate::hierarchical`]): adaptive elements and
    /// links over the scene's pieces, solved by its own gather–push–pull iteration.
    Hierarchical(crate::hierarchical::Params),
}

/// A uniform solve: the mesh, the form factors and the linear-system solver.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Uniform {
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
    /// Record a convergence trace ([`Solution::trace`]); every row of F is then stored first,
    /// so that the error can be measured against the LU solution of the very matrix solved.
    pub trace: bool,
}

impl Default for Uniform {
    fn default() -> Self {
        Self {
            mesh: MeshParams::default(),
            form_factors: crate::formfactor::Params::shooting(),
            rows: Rows::Auto,
            solver: Solver::Progressive,
            params: SolverParams::default(),
            trace: false,
        }
    }
}

impl Uniform {
    /// Seed every random stream of a uniform solve: the form-factor rows' and the solver's.
    pub fn set_seed(&mut self, seed: u64) {
        self.form_factors.seed = seed;
        self.params.seed = seed;
    }

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

/// Everything that decides a solution: the method, and the memory it may use.
///
/// ```
/// use radiosity::pipeline::{Method, Settings, Uniform};
/// use radiosity::mesh::MeshParams;
///
/// let uniform = Settings::from(Uniform { mesh: MeshParams::Patches(500), ..Default::default() });
/// let hierarchical = Settings::from(radiosity::hierarchical::Params::default());
/// assert!(matches!(uniform.method, Method::Uniform(_)));
/// assert!(matches!(hierarchical.method, Method::Hierarchical(_)));
/// ```
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Settings {
    /// How the scene is solved.
    pub method: Method,
    /// Refuse jobs whose estimated memory exceeds this.
    pub memory_limit: MemoryLimit,
}

impl Default for Method {
    fn default() -> Self {
        Method::Uniform(Uniform::default())
    }
}

impl From<Uniform> for Settings {
    fn from(u: Uniform) -> Self {
        Settings {
            method: Method::Uniform(u),
            memory_limit: MemoryLimit::Available,
        }
    }
}

impl From<crate::hierarchical::Params> for Settings {
    fn from(p: crate::hierarchical::Params) -> Self {
        Settings {
            method: Method::Hierarchical(p),
            memory_limit: MemoryLimit::Available,
        }
    }
}

impl Settings {
    /// Seed every random stream the method draws from (form-factor rows, photons, visibility
    /// samples, cluster estimates): the one seed of a run. A solution depends on it and on
    /// nothing else random, not even the thread count.
    pub fn set_seed(&mut self, seed: u64) {
        match &mut self.method {
            Method::Uniform(u) => u.set_seed(seed),
            Method::Hierarchical(p) => p.seed = seed,
        }
    }

    /// The seed of the method's random streams ([`Settings::set_seed`]).
    pub fn seed(&self) -> u64 {
        match &self.method {
            Method::Uniform(u) => u.params.seed,
            Method::Hierarchical(p) => p.seed,
        }
    }

    /// The uniform method's settings, if that is the method.
    pub fn uniform(&self) -> Option<&Uniform> {
        match &self.method {
            Method::Uniform(u) => Some(u),
            Method::Hierarchical(_) => None,
        }
    }

    /// The fraction of the emitted energy left unshot (or unconverged) at which the method
    /// stops.
    pub fn tolerance(&self) -> f64 {
        match &self.method {
            Method::Uniform(u) => u.params.tolerance,
            Method::Hierarchical(p) => p.tolerance,
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
    /// The convergence trace, when [`Uniform::trace`] asked for one.
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
    /// [`crate::render::gather`]. The picture `radiosity render` makes by default.
    ///
    /// ```
    /// use radiosity::prelude::*;
    ///
    /// let scene = builtin::cornell();
    /// let settings = Settings::from(Uniform { mesh: MeshParams::Patches(500), ..Default::default() });
    /// let s = solve(&scene, &settings, &Silent).unwrap();
    /// let params = RenderParams { width: 24, height: 24, samples_per_pixel: 1, ..Default::default() };
    /// let gather = radiosity::render::gather::GatherParams { cache_samples: 64, ..Default::default() };
    /// let image = s.render_gather(&s.default_camera(&scene), &params, gather, &Silent);
    /// assert_eq!(image.pixels.len(), 24 * 24);
    /// // Light reaches the camera: the box is lit, and no pixel is negative or NaN.
    /// assert!(image.pixels.iter().all(|p| p.iter().all(|c| c.is_finite() && *c >= 0.0)));
    /// assert!(image.pixels.iter().any(|p| p[1] > 0.0));
    /// ```
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
    ///
    /// ```
    /// use radiosity::prelude::*;
    ///
    /// let scene = builtin::furnace();
    /// let s = solve(&scene, &Settings::from(Uniform { mesh: MeshParams::Patches(200), ..Default::default() }), &Silent).unwrap();
    /// let params = RenderParams { width: 16, height: 16, ..Default::default() };
    /// let image = s.render(&s.default_camera(&scene), &params, &Silent);
    /// // Inside the furnace every wall has B = E/(1 − ρ) = 2 (green), a radiance of 2/π.
    /// let want = 2.0 / std::f32::consts::PI;
    /// assert!(image.pixels.iter().all(|p| (p[1] - want).abs() < 0.1 * want), "{:?}", &image.pixels[..4]);
    /// ```
    pub fn render(&self, camera: &Camera, params: &RenderParams, observer: &dyn Observer) -> Image {
        let vertex = vertex_radiosity(&self.mesh, &self.display_radiosity());
        render(&self.mesh, &self.bvh, &vertex, camera, params, observer)
    }
}
