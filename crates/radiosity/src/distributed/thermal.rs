//! Radiative heat transfer over ranks: the rows of F split over the ranks by cost
//! ([`super::rows`]), all-gathered so that every rank can enforce reciprocity and closure on the
//! whole matrix (both couple row i with column i), then the net-radiation system solved by
//! Jacobi sweeps split over the ranks ([`crate::thermal::solve_ranks`]); the direct and
//! BiCGSTAB solves run on every rank alike. The same bytes on every rank and for any number of
//! ranks.

use super::rows;
use super::Ranks;
use crate::accel::Bvh;
use crate::formfactor::Estimator;
use crate::mesh::Mesh;
use crate::observe::{Event, Observer, Stage};
use crate::pipeline::{thermal_default_rays, thermal_enclosure, ThermalOutcome, ThermalSettings};
use crate::scene::Scene;
use crate::Error;
use std::time::Instant;

/// [`crate::pipeline::thermal`] over `ranks`.
pub fn thermal(
    scene: &Scene,
    boundary_of: &[Option<u32>],
    boundaries: &[crate::thermal::Boundary],
    settings: &ThermalSettings,
    ranks: &Ranks<'_>,
    observer: &dyn Observer,
) -> Result<(ThermalOutcome, super::solve::Report), Error> {
    scene.validate_geometry()?;
    let start = ranks.traffic();
    let limit = match settings.memory_limit {
        0 => crate::pipeline::available_memory().unwrap_or(u64::MAX),
        l => l,
    };
    let mut params = settings.form_factors;
    let check = |p: &crate::formfactor::Params| crate::pipeline::thermal_memory(p, limit);
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
    let estimator = Estimator::new(&mesh, &bvh, params)?;
    let mut report = super::solve::Report {
        transport: ranks.communicator().describe(),
        ..Default::default()
    };
    let (block, busy) = rows::split(&estimator, ranks, observer, &mut report);
    let matrix = rows::all_gather_matrix(&block, mesh.len(), ranks);
    drop(block);
    let form_factor_seconds = t.elapsed().as_secs_f64();
    drop(estimator);
    drop(bvh);
    let area: Vec<f64> = mesh.patches.iter().map(|p| p.area as f64).collect();
    let (matrix, before, after, closed) = thermal_enclosure(matrix, &area, settings);
    let system =
        crate::pipeline::thermal_system(&mesh, &area, boundary_of, boundaries, settings, closed);
    observer.event(Event::Stage(Stage::Solve));
    let before_solve = ranks.traffic().seconds;
    let t_solve = Instant::now();
    let solution = crate::thermal::solve_ranks(
        &system,
        &matrix,
        crate::thermal::ThermalParams {
            linear: settings.linear,
            memory_limit: limit,
            ..Default::default()
        },
        ranks,
    )?;
    let busy = busy + t_solve.elapsed().as_secs_f64() - (ranks.traffic().seconds - before_solve);
    let per_boundary = solution.per_boundary(&system);
    report.finish(busy, &start, ranks);
    Ok((
        ThermalOutcome {
            mesh,
            system,
            solution,
            per_boundary,
            form_factors: params,
            form_factor_seconds,
            before,
            after,
            closed,
        },
        report,
    ))
}
