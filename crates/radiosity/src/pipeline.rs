//! The one place that knows every stage, in order: validate the scene → mesh it into patches →
//! build the ray-casting hierarchy → solve by progressive refinement with Monte Carlo form
//! factors computed on demand → (optionally) render.

use crate::accel::Bvh;
use crate::color::Rgb;
use crate::formfactor::monte_carlo::{MonteCarloParams, MonteCarloRows};
use crate::formfactor::FormFactorStats;
use crate::mesh::{Mesh, MeshParams};
use crate::render::{render, vertex_radiosity, Image, RenderParams};
use crate::scene::{Camera, Scene};
use crate::solve::progressive::{Progressive, ProgressiveParams};
use crate::solve::{ambient_term, Info, Status, System};
use crate::Error;
use std::time::Instant;

/// Everything that decides a solution.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Settings {
    /// How to cut surfaces into patches.
    pub mesh: MeshParams,
    /// Monte Carlo form factors.
    pub monte_carlo: MonteCarloParams,
    /// Progressive refinement.
    pub progressive: ProgressiveParams,
    /// Refuse jobs whose estimated memory exceeds this many bytes (0: the machine's available
    /// memory).
    pub memory_limit: u64,
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
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Event {
    /// A stage begins.
    Stage(Stage),
    /// The solver's status before a shot.
    Solve(Status),
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
    /// Radiosity per patch (progressive refinement's output, without the ambient term).
    pub radiosity: Vec<Rgb>,
    /// Unshot radiosity per patch when the solver stopped.
    pub unshot: Vec<Rgb>,
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
    let needed = mesh.len() as u64 * BYTES_PER_PATCH;
    if needed > limit {
        return Err(Error::OutOfMemory {
            what: format!("{} patches", mesh.len()),
            needed,
            limit,
            alternative: "fewer patches (--patches N or a larger --max-edge)".into(),
        });
    }
    let mut monte_carlo = settings.monte_carlo;
    monte_carlo.cache_bytes = monte_carlo.cache_bytes.min(((limit - needed) / 2) as usize);

    observer(Event::Stage(Stage::Bvh));
    let t = Instant::now();
    let bvh = Bvh::build(&mesh);
    let bvh_s = t.elapsed().as_secs_f64();

    observer(Event::Stage(Stage::Solve));
    let area: Vec<f64> = mesh.patches.iter().map(|p| p.area as f64).collect();
    let reflectance: Vec<Rgb> = mesh
        .patches
        .iter()
        .map(|p| scene.materials[p.material as usize].reflectance)
        .collect();
    let emission: Vec<Rgb> = mesh
        .patches
        .iter()
        .map(|p| scene.materials[p.material as usize].emission)
        .collect();
    let system = System {
        area: &area,
        reflectance: &reflectance,
        emission: &emission,
    };
    system.validate()?;
    let mut rows = MonteCarloRows::new(&mesh, &bvh, monte_carlo);
    let mut pr = Progressive::new(system);
    let info = pr.run(&mut rows, &settings.progressive, &mut |s| {
        observer(Event::Solve(*s))
    });
    let form_factors = rows.stats();
    let radiosity = pr.radiosity().to_vec();
    let unshot = pr.unshot().to_vec();
    drop(pr);
    drop(rows);
    Ok(Solution {
        timings: Timings {
            mesh: mesh_s,
            bvh: bvh_s,
            form_factors: form_factors.seconds,
            solve: (info.seconds - form_factors.seconds).max(0.0),
        },
        mesh,
        bvh,
        area,
        reflectance,
        emission,
        radiosity,
        unshot,
        info,
        form_factors,
    })
}
