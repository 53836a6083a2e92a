//! Diffuse global illumination by the radiosity method.
//!
//! The pipeline: a [`scene::Scene`] of planar polygons with diffuse materials is cut into
//! patches ([`mesh`]), a bounding-volume hierarchy makes them ray-castable ([`accel`]), form
//! factors are estimated ([`formfactor`]) and the radiosity system is solved ([`solve`]); the
//! result is rendered ([`render`]) or written out ([`export`]). [`pipeline`] runs the stages in
//! order, one entry point a use:
//!
//! | to | call |
//! |---|---|
//! | solve a scene | [`pipeline::solve`] (over MPI ranks: [`pipeline::solve_over`]) |
//! | make a picture | [`pipeline::Solution::render_gather`], [`pipeline::Solution::render`] |
//! | bake light into a mesh | [`export::bake::write`] |
//! | bake a lightmap (texture on a second UV set) | [`bake::lightmap::bake`], [`export::bake::write_lightmap_gltf`] |
//! | view factors | [`pipeline::view_factors`] |
//! | radiative heat transfer | [`pipeline::thermal`] |
//! | solve a given system | [`pipeline::solve_system`] |
//!
//! `use radiosity::prelude::*;` brings the types these take.
//!
//! ```
//! use radiosity::prelude::*;
//!
//! let scene = builtin::furnace();
//! let settings = Settings::from(Uniform { mesh: MeshParams::Patches(200), ..Default::default() });
//! let solution = solve(&scene, &settings, &Silent).unwrap();
//! // Closed furnace: every patch's radiosity is near E/(1 − ρ) = 2 in the green channel.
//! let mean: f64 = solution.radiosity.iter().map(|b| b.g).sum::<f64>() / solution.radiosity.len() as f64;
//! assert!((mean - 2.0).abs() < 0.1);
//! ```

// Unsafe code is refused everywhere but in three small audited modules: two of the ray caster
// (`accel`), the run-time dispatch to its AVX2 build, called only on a CPU that has AVX2, and
// the box test in AVX2/FMA intrinsics, run only by builds that assume those features and by
// that AVX2 build; and `hint`, the cache prefetch hint.
#![deny(unsafe_code)]

pub mod accel;
pub mod bake;
pub mod color;
pub mod comm;
pub mod daylight;
pub mod distributed;
pub mod export;
pub mod formfactor;
pub mod geom;
pub mod hierarchical;
mod hint;
pub mod io;
pub mod lighting;
pub mod loc;
pub mod mesh;
pub mod observe;
pub mod photometry;
pub mod pipeline;
pub mod render;
pub mod sampling;
pub mod scene;
pub mod solve;
pub mod system;
pub mod thermal;

pub use color::Rgb;

/// The types a program solving, rendering, baking or computing view factors and heat transfer
/// starts from.
pub mod prelude {
    pub use crate::color::Rgb;
    pub use crate::formfactor::{FormFactorMethod, Params as FormFactorParams};
    pub use crate::mesh::MeshParams;
    pub use crate::observe::{Observer, Silent};
    pub use crate::pipeline::{
        solve, solve_system, thermal, view_factors, Method, Settings, Solution, ThermalSettings,
        Uniform, ViewFactorSettings,
    };
    pub use crate::render::RenderParams;
    pub use crate::scene::{builtin, Camera, Scene};
    pub use crate::solve::{Solver, SolverParams};
    pub use crate::Error;
}

/// Any failure of the library's stages.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The scene could not be read or is not fit to solve.
    #[error(transparent)]
    Scene(#[from] scene::SceneError),
    /// The linear system is malformed, or a solver refused it.
    #[error(transparent)]
    Solve(#[from] solve::SolveError),
    /// Form-factor parameters are out of range.
    #[error(transparent)]
    FormFactors(#[from] formfactor::FormFactorError),
    /// Meshing parameters are out of range.
    #[error(transparent)]
    Mesh(#[from] mesh::MeshParamError),
    /// An output could not be written.
    #[error(transparent)]
    Export(#[from] export::ExportError),
    /// An input file is malformed.
    #[error(transparent)]
    Input(#[from] io::InputError),
    /// Hierarchical radiosity could not run.
    #[error(transparent)]
    Hierarchical(#[from] hierarchical::HierarchicalError),
    /// A lighting input is malformed, or a lighting computation could not run.
    #[error(transparent)]
    Lighting(#[from] lighting::LightingError),
    /// A heat-transfer problem could not be solved.
    #[error(transparent)]
    Thermal(#[from] thermal::ThermalError),
    /// What was asked for does not run over several ranks.
    #[error("{0}")]
    NotDistributed(String),
    /// The job would not fit in memory.
    #[error(
        "{what} would need about {} MiB but only {} MiB are available; use {}",
        needed >> 20,
        limit >> 20,
        if *stored_rows {
            "a shooting solver (progressive computes rows on demand), fewer patches or fewer rays per row"
        } else {
            "fewer patches (or a larger patch edge)"
        }
    )]
    OutOfMemory {
        /// What was asked for.
        what: String,
        /// Estimated bytes.
        needed: u64,
        /// Bytes available.
        limit: u64,
        /// True when the estimate includes every form-factor row stored.
        stored_rows: bool,
    },
}
