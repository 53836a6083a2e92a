//! What the hierarchical solver is given ([`Params`], with its defaults and the ranges
//! [`Params::validate`] checks), why it may refuse to run ([`HierarchicalError`]), and what it
//! reports ([`Info`]).

/// Smallest [`Params::link_error`]: the geometry is f32, whose relative precision is
/// 2⁻²⁴ ≈ 6 × 10⁻⁸, so every form factor between elements carries a relative error of about
/// 10⁻⁷ from the corners' rounding alone. A link error below that refines links to move power
/// the geometry cannot place, and the refinement (links grow as the error's inverse square)
/// runs on without bound; it is refused.
pub const MIN_LINK_ERROR: f64 = 1e-7;

/// What the hierarchical solver is given.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Params {
    /// A link is refined when the power it may misplace exceeds this fraction of the emitted
    /// power.
    pub link_error: f64,
    /// Elements are not split below this area (square scene units); 0: the scene's area × 1e-6.
    pub min_area: f64,
    /// Visibility rays from each of a link's sixteen receiver points.
    pub visibility_rays: u32,
    /// Refinement passes at most (each followed by a solve).
    pub max_passes: u32,
    /// Stop iterating when the last iteration changed at most this fraction of the emitted
    /// power.
    pub tolerance: f64,
    /// Iterations per solve at most.
    pub max_iterations: u64,
    /// Seed of the visibility streams.
    pub seed: u64,
    /// Refuse to grow beyond this many bytes of elements and links.
    pub memory_limit: u64,
}

impl Default for Params {
    fn default() -> Self {
        Self {
            link_error: 2e-5,
            min_area: 0.0,
            visibility_rays: 1,
            max_passes: 6,
            tolerance: 1e-4,
            max_iterations: 1000,
            seed: 1,
            memory_limit: 4 << 30,
        }
    }
}

/// A parameter, for errors (the program maps it to its option).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Parameter {
    /// [`Params::link_error`].
    LinkError,
    /// [`Params::min_area`].
    MinArea,
    /// [`Params::visibility_rays`].
    VisibilityRays,
    /// [`Params::tolerance`].
    Tolerance,
}

impl std::fmt::Display for Parameter {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Parameter::LinkError => "link error",
            Parameter::MinArea => "minimum element area",
            Parameter::VisibilityRays => "visibility rays per receiver point",
            Parameter::Tolerance => "tolerance",
        })
    }
}

/// Why the hierarchical solver could not run.
#[derive(Debug, thiserror::Error)]
pub enum HierarchicalError {
    /// A parameter is out of range.
    #[error("{parameter} = {value} is outside {range}")]
    Parameter {
        /// Which.
        parameter: Parameter,
        /// Its value.
        value: f64,
        /// The range it must lie in.
        range: &'static str,
    },
    /// Refinement would outgrow the memory allowed.
    #[error("hierarchical refinement reached {elements} elements and {links} links, about {} MiB, more than the {} MiB allowed; raise the link error or the minimum element area", needed >> 20, limit >> 20)]
    TooLarge {
        /// Elements so far.
        elements: usize,
        /// Links so far.
        links: usize,
        /// Bytes they need.
        needed: u64,
        /// Bytes allowed.
        limit: u64,
    },
}

impl Params {
    /// Check every parameter's range.
    pub fn validate(&self) -> Result<(), HierarchicalError> {
        let bad = |parameter, value: f64, range| {
            Err(HierarchicalError::Parameter {
                parameter,
                value,
                range,
            })
        };
        if !(self.link_error.is_finite() && self.link_error >= MIN_LINK_ERROR) {
            return bad(Parameter::LinkError, self.link_error, "[1e-7, ∞)");
        }
        if !(self.min_area.is_finite() && self.min_area >= 0.0) {
            return bad(Parameter::MinArea, self.min_area, "[0, ∞)");
        }
        if !(1..=1024).contains(&self.visibility_rays) {
            return bad(
                Parameter::VisibilityRays,
                self.visibility_rays as f64,
                "[1, 1024]",
            );
        }
        if !(self.tolerance.is_finite() && self.tolerance > 0.0) {
            return bad(Parameter::Tolerance, self.tolerance, "(0, ∞)");
        }
        Ok(())
    }
}

/// What the hierarchical solver did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Info {
    /// Elements in all the quadtrees (roots included).
    pub elements: usize,
    /// Leaf elements (the output).
    pub leaves: usize,
    /// Links.
    pub links: usize,
    /// Clusters.
    pub clusters: usize,
    /// Links replaced by finer ones.
    pub refinements: u64,
    /// Links dropped because every visibility sample was blocked (judged with solved
    /// radiosities, so that their error was below the tolerance even if partly visible).
    pub invisible: u64,
    /// Refinement passes.
    pub passes: u32,
    /// Gather–push–pull iterations, all passes.
    pub iterations: u64,
    /// Visibility rays.
    pub rays: u64,
    /// Bytes held by elements, clusters and links.
    pub bytes: u64,
    /// Seconds refining links (estimation included).
    pub refine_seconds: f64,
    /// Seconds iterating.
    pub solve_seconds: f64,
    /// Power the last iteration changed, over the emitted power.
    pub unshot_fraction: f64,
    /// True when the last solve reached the tolerance.
    pub converged: bool,
    /// The minimum element area used.
    pub min_area: f64,
    /// Roots that are coincident twins of another (solved as that one).
    pub twins: usize,
}
