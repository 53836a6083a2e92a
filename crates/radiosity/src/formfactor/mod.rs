//! Form factors: `F_ij`, the fraction of the energy leaving patch `i` that arrives directly at
//! patch `j` (Szirmay-Kalos & Márton 1995, eq. 6). Rows are sparse: a row holds only the patches
//! a method found, sorted by patch index, so that no N × N array is ever allocated.
//!
//! Methods, one file each, each owning its row algorithm, selected by [`FormFactorMethod`]:
//! - [`hemicube`] and [`tetrahedron`]: z-buffer projections through the shared [`projection`];
//! - [`hemisphere`]: Nusselt's analog by casting rays through a disc of cells;
//! - [`monte_carlo`]: eq. 7, ray shooting;
//! - [`analytic`]: the exact unoccluded polygon-to-polygon factor;
//! - [`adaptive`]: each pair to a requested accuracy, exact when unoccluded, shadows clipped
//!   exactly where occluders stand between (occluders and shafts in [`shaft`]).
//!
//! One [`Params`] serves them all. [`Estimator`] computes rows with any of them, and whole
//! matrices in parallel, dense or sparse; [`OnDemandRows`] hands rows to the solvers when they
//! ask (an [`crate::system::Operator`]), cached under a budget. Whether rows are stored or
//! computed on demand is decided in one place, the pipeline. [`enforce()`] optionally makes a
//! matrix physical, [`truncate()`] drops small entries and restores reciprocity and closure,
//! [`summary()`] describes one, [`quadrature`] spreads points over a patch.
//! This module produces linear systems and knows nothing of the solvers.

pub mod adaptive;
pub mod analytic;
pub mod closed_form;
pub mod enforce;
pub mod estimator;
pub mod hemicube;
pub mod hemisphere;
pub mod monte_carlo;
pub mod on_demand;
pub mod projection;
pub mod quadrature;
pub mod shaft;
pub mod summary;
pub mod tetrahedron;
pub mod truncate;

pub use crate::system::Entry;
pub use enforce::{aggregate, enforce, Enforce};
pub use estimator::{Effort, Estimator, Scratch};
pub use on_demand::OnDemandRows;
pub use quadrature::gauss_legendre;
pub use summary::{summary, Summary};
pub use truncate::{truncate, FactorRows, TruncateError, TruncateInfo};

use crate::system::SparseMatrix;

/// Statistics of form-factor work.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FormFactorStats {
    /// Rows estimated (including re-estimates).
    pub rows: u64,
    /// Rays cast.
    pub rays: u64,
    /// Wall-clock seconds spent estimating rows and keeping them (a row on demand is stored
    /// in the cache as part of its estimate).
    pub seconds: f64,
    /// Rows currently held in the cache.
    pub cached_rows: u64,
    /// Bytes held by cached rows.
    pub cached_bytes: u64,
}

/// The form-factor methods, named as on the command line (`--method`, `--form-factors`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum FormFactorMethod {
    /// Hemicube z-buffer ([`hemicube`]).
    Hemicube,
    /// Nusselt's hemisphere ([`hemisphere`]).
    Hemisphere,
    /// Cubic tetrahedron z-buffer ([`tetrahedron`]).
    Tetrahedron,
    /// Monte Carlo ray shooting ([`monte_carlo`]).
    MonteCarlo,
    /// Exact unoccluded contour integral ([`analytic`]).
    Analytic,
    /// Every pair to a requested accuracy, occlusion by exact clipping ([`adaptive`]).
    Adaptive,
}

impl FormFactorMethod {
    /// Every method.
    pub const ALL: [FormFactorMethod; 6] = [
        FormFactorMethod::Hemicube,
        FormFactorMethod::Hemisphere,
        FormFactorMethod::Tetrahedron,
        FormFactorMethod::MonteCarlo,
        FormFactorMethod::Analytic,
        FormFactorMethod::Adaptive,
    ];

    /// The command-line name.
    pub fn name(self) -> &'static str {
        match self {
            FormFactorMethod::Hemicube => "hemicube",
            FormFactorMethod::Hemisphere => "hemisphere",
            FormFactorMethod::Tetrahedron => "tetrahedron",
            FormFactorMethod::MonteCarlo => "monte-carlo",
            FormFactorMethod::Analytic => "analytic",
            FormFactorMethod::Adaptive => "adaptive",
        }
    }

    /// One line on what the method is, with its source.
    pub fn summary(self) -> &'static str {
        match self {
            FormFactorMethod::Hemicube => "hemicube z-buffer (Cohen & Greenberg 1985)",
            FormFactorMethod::Hemisphere => "Nusselt's hemisphere, one ray per disc cell",
            FormFactorMethod::Tetrahedron => {
                "cubic tetrahedron z-buffer (Beran-Koehn & Pavicic 1991)"
            }
            FormFactorMethod::MonteCarlo => {
                "ray shooting (Szirmay-Kalos & Márton 1995, eq. 7); rows on demand for shooting"
            }
            FormFactorMethod::Analytic => "exact contour integral, ignoring occlusion",
            FormFactorMethod::Adaptive => {
                "each pair to --accuracy: exact contour integrals, shadows clipped exactly (View3D's approach)"
            }
        }
    }

    /// The method called `name`.
    pub fn from_name(name: &str) -> Option<FormFactorMethod> {
        FormFactorMethod::ALL.into_iter().find(|m| m.name() == name)
    }
}

impl std::fmt::Display for FormFactorMethod {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Parameters of every form-factor method (each reads the fields it uses), with named presets.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Params {
    /// The method.
    pub method: FormFactorMethod,
    /// P: pixels along a hemicube or tetrahedron face, cells along the hemisphere's disc.
    pub resolution: u32,
    /// Points spread over patch i for the projection methods (rounded up to a square).
    pub samples: u32,
    /// Monte Carlo: rays per row (eq. 7's `n`). Rows computed on demand for a shooter take
    /// more in proportion to the power it shoots ([`Params::rays_for`]), never fewer.
    pub rays: u32,
    /// Monte Carlo: upper bound on the rays of one row computed on demand.
    pub max_rays: u32,
    /// Seed of Monte Carlo's random streams.
    pub seed: u64,
    /// Rows computed on demand ([`OnDemandRows`]): memory budget of their cache, bytes. Rows
    /// beyond it are recomputed when needed; 0 keeps only the last row (O(N) memory).
    pub cache_bytes: usize,
    /// Adaptive: the accuracy E of each entry (relative for pairs that see each other whole,
    /// absolute for occluded ones; see [`adaptive`]).
    pub accuracy: f64,
}

impl Default for Params {
    /// View factors: Monte Carlo with a million rays per row (each entry's standard deviation
    /// at most 1/(2·1000)).
    fn default() -> Self {
        Self {
            method: FormFactorMethod::MonteCarlo,
            resolution: 128,
            samples: 16,
            rays: 1_000_000,
            max_rays: 1 << 24,
            seed: 1,
            cache_bytes: 2 << 30,
            accuracy: DEFAULT_ACCURACY,
        }
    }
}

/// The adaptive method's default accuracy ([`Params::accuracy`]).
pub const DEFAULT_ACCURACY: f64 = 1e-5;

/// The range of [`Params::accuracy`]: below 1e-10 the f32 geometry and the stored f32 entries
/// cannot follow; above 0.1 it is no longer an accuracy.
pub const ACCURACY_RANGE: (f64, f64) = (1e-10, 0.1);

impl Params {
    /// The preset for shooting solvers on a scene: Monte Carlo rows on demand with 256 rays for
    /// a patch that shoots an average share of the power, proportionally more for the others.
    pub fn shooting() -> Self {
        Self {
            rays: 256,
            ..Self::default()
        }
    }

    /// `method` at resolution `resolution` with `samples` points per patch (projection and
    /// hemisphere methods).
    pub fn geometric(method: FormFactorMethod, resolution: u32, samples: u32) -> Self {
        Self {
            method,
            resolution,
            samples,
            ..Self::default()
        }
    }

    /// Monte Carlo with `rays` rays per row and seed `seed`.
    pub fn monte_carlo(rays: u32, seed: u64) -> Self {
        Self {
            rays,
            seed,
            ..Self::default()
        }
    }

    /// Monte Carlo rays for a row of a patch about to shoot the fraction `share` of the scene's
    /// emitted power, in a mesh of `patches` patches: `max(rays, ⌈rays · patches · share⌉)`, at
    /// most `max_rays`. So every ray carries at most the power that a ray of an average patch
    /// carries.
    pub fn rays_for(&self, share: f64, patches: usize) -> u32 {
        let want = (self.rays as f64 * patches as f64 * share).ceil();
        (want.min(self.max_rays as f64) as u32)
            .max(self.rays)
            .max(1)
    }

    /// Check every parameter against its range, whichever the method reads (an impossible
    /// value is refused even where the method would ignore it): the resolution in [2, 8192],
    /// at least one sample point and one ray a row, the accuracy in [`ACCURACY_RANGE`]. The one check the command line, the
    /// Python bindings and the pipelines share.
    pub fn validate(&self) -> Result<(), FormFactorError> {
        let range = |parameter, value: u32, min: u32, max: u32| {
            if value < min || value > max {
                Err(FormFactorError::Parameter {
                    method: self.method,
                    parameter,
                    value,
                    min,
                    max,
                })
            } else {
                Ok(())
            }
        };
        range(Parameter::Resolution, self.resolution, 2, MAX_RESOLUTION)?;
        range(Parameter::Samples, self.samples, 1, u32::MAX)?;
        range(Parameter::Rays, self.rays, 1, u32::MAX)?;
        let (lo, hi) = ACCURACY_RANGE;
        if !(self.accuracy >= lo && self.accuracy <= hi) {
            return Err(FormFactorError::Accuracy {
                value: self.accuracy,
                min: lo,
                max: hi,
            });
        }
        Ok(())
    }
}

/// Largest resolution P of the projection and hemisphere methods.
pub const MAX_RESOLUTION: u32 = 8192;

/// A form-factor parameter, for errors (the program maps it to its own option name).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Parameter {
    /// [`Params::resolution`].
    Resolution,
    /// [`Params::samples`].
    Samples,
    /// [`Params::rays`].
    Rays,
}

impl std::fmt::Display for Parameter {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Parameter::Resolution => "resolution",
            Parameter::Samples => "points per patch",
            Parameter::Rays => "rays per row",
        })
    }
}

/// Bad form-factor parameters.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum FormFactorError {
    /// A parameter is out of its range.
    #[error("{method}: {parameter} {value} is outside [{min}, {max}]")]
    Parameter {
        /// The method.
        method: FormFactorMethod,
        /// Which parameter.
        parameter: Parameter,
        /// Its value.
        value: u32,
        /// Smallest allowed.
        min: u32,
        /// Largest allowed.
        max: u32,
    },
    /// The adaptive method's accuracy is out of its range (or not a number).
    #[error("accuracy {value} is outside [{min:e}, {max}]")]
    Accuracy {
        /// Its value.
        value: f64,
        /// Smallest allowed.
        min: f64,
        /// Largest allowed.
        max: f64,
    },
}

/// Matrix storage.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Storage {
    /// Dense up to [`DENSE_MAX`] patches, sparse beyond.
    Auto,
    /// N × N values.
    Dense,
    /// Sparse rows: never N² zeros.
    Sparse,
}

/// Largest N stored densely by [`Storage::Auto`] (64 MiB of f32).
pub const DENSE_MAX: usize = 4096;

/// A computed form-factor matrix.
#[derive(Clone, Debug)]
pub enum Matrix {
    /// Row-major N × N.
    Dense {
        /// N.
        n: usize,
        /// The values.
        values: Vec<f32>,
    },
    /// Sparse rows and columns.
    Sparse(SparseMatrix),
}

impl Matrix {
    /// As a sparse matrix (the dense one's zeros dropped).
    pub fn into_sparse(self) -> SparseMatrix {
        match self {
            Matrix::Sparse(m) => m,
            Matrix::Dense { n, values } => SparseMatrix::from_rows(
                values
                    .chunks(n)
                    .map(|r| {
                        r.iter()
                            .enumerate()
                            .filter(|(_, v)| **v != 0.0)
                            .map(|(j, v)| (j as u32, *v))
                            .collect()
                    })
                    .collect(),
            ),
        }
    }
}
