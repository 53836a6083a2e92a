//! A view-factor matrix for radiative heat transfer: mesh (the memory of the stored matrix
//! checked before meshing and after), every row of F by the chosen method, in this process or
//! split over ranks; per input face on request. What `radiosity form-factors` and the Python
//! `form_factors_csr` both run.

use crate::accel::Bvh;
use crate::comm::Ranks;
use crate::distributed::{rows, Report};
use crate::formfactor::{aggregate, Estimator, Params, Storage};
use crate::mesh::{Mesh, MeshParams};
use crate::observe::Observer;
use crate::scene::Scene;
use crate::system::SparseMatrix;
use crate::Error;
use std::time::Instant;

use super::{MemoryCheck, MemoryLimit};

/// What decides a view-factor matrix.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ViewFactorSettings {
    /// How surfaces are cut into patches ([`MeshParams::Faces`]: one patch a planar face).
    pub mesh: MeshParams,
    /// The form-factor method and its parameters.
    pub form_factors: Params,
    /// Dense or sparse accumulation of each row.
    pub storage: Storage,
    /// Refuse jobs whose stored matrix would exceed this.
    pub memory_limit: MemoryLimit,
}

impl Default for ViewFactorSettings {
    fn default() -> Self {
        Self {
            mesh: MeshParams::default(),
            form_factors: Params::default(),
            storage: Storage::Auto,
            memory_limit: MemoryLimit::Available,
        }
    }
}

/// A computed view-factor matrix.
#[derive(Debug)]
pub struct ViewFactors {
    /// The patches its rows and columns stand for.
    pub mesh: Mesh,
    /// F, one row a patch (`None` on the ranks other than 0 of a distributed run).
    pub matrix: Option<SparseMatrix>,
    /// The form-factor parameters used (Monte Carlo's rays a row may have been set from the
    /// patch count).
    pub params: Params,
    /// Wall-clock seconds: meshing, hierarchy and rows.
    pub seconds: f64,
}

impl ViewFactors {
    /// Every patch's area, in scene units squared.
    pub fn areas(&self) -> Vec<f64> {
        self.mesh.patches.iter().map(|p| p.area as f64).collect()
    }

    /// F between the input faces of `scene` (area-weighted rows, summed columns: reciprocity
    /// and row sums carry over) and the faces' areas; `None` where this rank holds no matrix.
    pub fn per_face(&self, scene: &Scene) -> Option<(SparseMatrix, Vec<f64>)> {
        let m = self.matrix.as_ref()?;
        let group: Vec<u32> = self.mesh.patches.iter().map(|p| p.surface).collect();
        Some(aggregate(m, &self.areas(), &group, scene.polygons.len()))
    }
}

/// Mesh `scene` and compute every row of F (Monte Carlo's rays a row set by `rays_for(patches)`
/// when given), the memory of the stored matrix checked before meshing and after; progress
/// goes to `observer`.
///
/// ```
/// use radiosity::pipeline::{view_factors, ViewFactorSettings};
/// use radiosity::{mesh::MeshParams, scene::builtin};
///
/// let settings = ViewFactorSettings { mesh: MeshParams::Faces, ..Default::default() };
/// let f = view_factors(&builtin::furnace(), &settings, None, &radiosity::observe::Silent).unwrap();
/// // A closed furnace: every face sees the others and nothing else, so each row sums to 1.
/// let m = f.matrix.unwrap();
/// let row: f32 = m.row_entries(0).iter().map(|e| e.1).sum();
/// assert!((row - 1.0).abs() < 0.01);
/// ```
pub fn view_factors(
    scene: &Scene,
    settings: &ViewFactorSettings,
    rays_for: Option<&dyn Fn(usize) -> u32>,
    observer: &dyn Observer,
) -> Result<ViewFactors, Error> {
    view_factors_over(scene, settings, rays_for, None, observer).map(|(v, _)| v)
}

/// [`view_factors`], over `ranks` when given: each rank computes the rows of its block
/// (balanced by estimated cost) and rank 0 gathers the matrix (`None` on the others), with the
/// run's [`Report`].
pub fn view_factors_over(
    scene: &Scene,
    settings: &ViewFactorSettings,
    rays_for: Option<&dyn Fn(usize) -> u32>,
    ranks: Option<&Ranks<'_>>,
    observer: &dyn Observer,
) -> Result<(ViewFactors, Option<Report>), Error> {
    // View factors need geometry, not light; one patch a face needs planar faces.
    scene.validate_geometry()?;
    settings.mesh.validate()?;
    if settings.mesh == MeshParams::Faces {
        crate::mesh::check_planar(scene)?;
    }
    let t = Instant::now();
    let start = ranks.map(Ranks::traffic);
    let limit = settings.memory_limit.bytes();
    let mut params = settings.form_factors;
    MemoryCheck::stored_matrix(&params, limit).before_meshing(scene, settings.mesh)?;
    let mesh = Mesh::build(scene, settings.mesh)?;
    if let Some(f) = rays_for {
        params.rays = f(mesh.len());
    }
    MemoryCheck::stored_matrix(&params, limit).check(mesh.len() as u64)?;
    let bvh = Bvh::build(&mesh);
    let estimator = Estimator::new(&mesh, &bvh, params)?;
    let (matrix, report) = match (ranks, start) {
        (Some(r), Some(start)) => {
            let mut report = Report {
                transport: r.communicator().describe(),
                ..Report::default()
            };
            let (block, busy) = rows::split(&estimator, r, observer, &mut report);
            let matrix = rows::gather_matrix(&block, mesh.len(), 0, r);
            report.finish(busy, &start, r);
            (matrix, Some(report))
        }
        _ => (
            Some(estimator.matrix(settings.storage, observer).into_sparse()),
            None,
        ),
    };
    drop(estimator);
    drop(bvh);
    Ok((
        ViewFactors {
            mesh,
            matrix,
            params,
            seconds: t.elapsed().as_secs_f64(),
        },
        report,
    ))
}
