//! The one memory model: what a job needs (per patch, and per stored form-factor entry) against
//! what this process may use.

use crate::mesh::MeshParams;
use crate::scene::Scene;
use crate::Error;

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
    /// The check of a job that stores every row of F computed by `p`: the entries a row can
    /// hold at most are one per ray (Monte Carlo), one per pixel (or disc cell) of each sample
    /// point (the projection methods), or every other patch (analytic). Used by view factors
    /// and heat transfer, whose matrix is stored whatever the method.
    pub fn stored_matrix(p: &crate::formfactor::Params, limit: u64) -> MemoryCheck {
        use crate::formfactor::FormFactorMethod as M;
        MemoryCheck {
            limit,
            stored_rows: true,
            rays: match p.method {
                M::MonteCarlo => p.rays,
                M::Hemicube | M::Tetrahedron | M::Hemisphere => {
                    ((p.resolution as u64).pow(2) * 3 * p.samples as u64).min(u32::MAX as u64)
                        as u32
                }
                M::Analytic | M::Adaptive => u32::MAX,
            },
        }
    }

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

/// How much memory a job may use: the one setting every pipeline reads ([`super::Settings`],
/// [`super::ThermalSettings`], [`super::ViewFactorSettings`]); each pipeline hands its stages
/// (a solver, the thermal solve, hierarchical refinement) their budgets in bytes from it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum MemoryLimit {
    /// What this process may still use when the job starts ([`available_memory`]; no limit
    /// where that is unknown).
    #[default]
    Available,
    /// At most this many bytes.
    Bytes(u64),
}

impl MemoryLimit {
    /// The limit in bytes, now.
    pub fn bytes(self) -> u64 {
        match self {
            MemoryLimit::Available => available_memory().unwrap_or(u64::MAX),
            MemoryLimit::Bytes(b) => b,
        }
    }
}
