//! Radiative heat transfer without a stored F: the meshed scene's BVH, the enclosure decided
//! from rays, the matrix-free solve ([`crate::thermal::matrix_free`]).

use super::thermal::{thermal_system, Enclosure, ThermalOutcome, ThermalSettings};
use crate::accel::Bvh;
use crate::mesh::Mesh;
use crate::observe::{Event, Observer, Stage};
use crate::thermal::{open_share, solve_matrix_free, ThermalSolver};
use crate::Error;

/// The share of the view reaching no surface below which `Enclosure::Auto` takes a scene as
/// closed, when no input says: a closed scene loses rays only through cracks of rounding.
pub const CLOSED_OPEN_SHARE: f64 = 1e-3;

/// [`super::thermal`] on `mesh` without F: `params` are the form-factor parameters reported
/// back (none are used).
pub(super) fn thermal_matrix_free(
    mesh: Mesh,
    boundary_of: &[Option<u32>],
    boundaries: &[crate::thermal::Boundary],
    settings: &ThermalSettings,
    params: crate::formfactor::Params,
    observer: &dyn Observer,
) -> Result<ThermalOutcome, Error> {
    let mf = settings.matrix_free;
    mf.validate()
        .map_err(|m| Error::Thermal(crate::thermal::ThermalError::Malformed(m)))?;
    observer.event(Event::Stage(Stage::Bvh));
    let bvh = Bvh::build(&mesh);
    let closed = match settings.enclosure {
        Enclosure::Closed => true,
        Enclosure::Open => false,
        Enclosure::Auto => match settings.enclosure_hint {
            Some(c) => c,
            None => open_share(&mesh, &bvh, mf.sweep_rays, mf.seed) < CLOSED_OPEN_SHARE,
        },
    };
    let area: Vec<f64> = mesh.patches.iter().map(|p| p.area as f64).collect();
    let system = thermal_system(&mesh, &area, boundary_of, boundaries, settings, closed);
    observer.event(Event::Stage(Stage::Solve));
    let progress = |done: u64, total: u64| {
        observer.event(Event::Progress {
            stage: Stage::Solve,
            done,
            total,
        })
    };
    let solution = solve_matrix_free(&system, &mesh, &bvh, &mf, &progress)?;
    let per_boundary = solution.per_boundary(&system);
    let no_matrix = crate::formfactor::Summary {
        min_row_sum: 0.0,
        max_row_sum: 0.0,
        worst_reciprocity: 0.0,
        fill: 0.0,
        min_entry: 0.0,
    };
    Ok(ThermalOutcome {
        mesh,
        system,
        solution,
        per_boundary,
        form_factors: params,
        form_factor_seconds: 0.0,
        before: no_matrix,
        after: no_matrix,
        adaptive: None,
        solver: ThermalSolver::MatrixFree,
        closed,
    })
}
