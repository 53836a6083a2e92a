//! Radiative heat transfer: boundary names → materials, mesh, F (memory checked first),
//! reciprocity and closure enforced, the net-radiation solve.

use super::*;
use crate::accel::Bvh;
use crate::comm::Ranks;
use crate::distributed::{rows, Report};
use crate::formfactor::Estimator;
use crate::mesh::{Mesh, MeshParams};
use crate::observe::{Event, Observer, Stage};
use crate::scene::Scene;
use crate::Error;
use std::time::Instant;

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
    /// Refuse jobs whose estimated memory exceeds this.
    pub memory_limit: MemoryLimit,
    /// Stored F or matrix-free ([`crate::thermal::matrix_free`]).
    pub solver: crate::thermal::ThermalSolver,
    /// The matrix-free solve's rays, batches and seed.
    pub matrix_free: crate::thermal::MatrixFreeParams,
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
            memory_limit: MemoryLimit::Available,
            solver: crate::thermal::ThermalSolver::Auto,
            matrix_free: crate::thermal::MatrixFreeParams::default(),
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
    /// F's row sums and reciprocity before and after enforcement (the default, all zero,
    /// for the matrix-free solve, which has no F).
    pub before: crate::formfactor::Summary,
    /// See `before`.
    pub after: crate::formfactor::Summary,
    /// What the adaptive method did (pairs by kind, points, rays), when it computed F (over
    /// ranks: this rank's rows).
    pub adaptive: Option<crate::formfactor::adaptive::Stats>,
    /// Which solve ran: [`crate::thermal::ThermalSolver::Stored`] or `MatrixFree`.
    pub solver: crate::thermal::ThermalSolver,
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
    // A name may be shared by several materials (View3D files may repeat surface names):
    // the row applies to all of them.
    let mut by_name: std::collections::HashMap<&str, Vec<usize>> = std::collections::HashMap::new();
    for (m, mat) in scene.materials.iter().enumerate() {
        if used[m] {
            by_name.entry(mat.name.as_str()).or_default().push(m);
        }
    }
    let mut boundary_of = vec![None; scene.materials.len()];
    for (k, (name, _)) in names.iter().enumerate() {
        let Some(ms) = by_name.get(name.as_str()) else {
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
            return Err((
                Some(k),
                crate::loc::shorten(format!("unknown surface '{name}'; {hint}")),
            ));
        };
        for &m in ms {
            boundary_of[m] = Some(k as u32);
        }
    }
    let mut missing: Vec<&str> = (0..scene.materials.len())
        .filter(|&m| used[m] && boundary_of[m].is_none())
        .map(|m| scene.materials[m].name.as_str())
        .collect();
    if !missing.is_empty() {
        missing.sort_unstable();
        missing.dedup();
        let shown: Vec<String> = missing
            .iter()
            .take(10)
            .map(|n| crate::loc::shorten(format!("'{n}'")))
            .collect();
        let more = if missing.len() > 10 {
            format!(" and {} more", missing.len() - 10)
        } else {
            String::new()
        };
        return Err((
            None,
            format!(
                "no boundary condition for {} surface name{}: {}{more} (add a row for each; leave temperature and flux empty for an adiabatic surface)",
                missing.len(),
                if missing.len() == 1 { "" } else { "s" },
                shown.join(", ")
            ),
        ));
    }
    Ok(boundary_of)
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
///
/// ```
/// use radiosity::prelude::*;
/// use radiosity::thermal::{Boundary, Condition};
///
/// // The furnace is a closed box (with a box inside): held at one temperature, every
/// // surface emits what it absorbs, so no net power flows.
/// let scene = builtin::furnace();
/// let boundaries = [Boundary { emissivity: 0.8, condition: Condition::Temperature(500.0) }];
/// let boundary_of = vec![Some(0); scene.materials.len()];
/// let mut settings = ThermalSettings { default_rays: false, ..Default::default() };
/// settings.form_factors.rays = 20_000;
/// let out = thermal(&scene, &boundary_of, &boundaries, &settings, &Silent).unwrap();
/// let (area, power, _) = out.per_boundary[0];
/// let emitted = area * 0.8 * 5.670374419e-8 * 500f64.powi(4);
/// assert!(power.abs() < 1e-6 * emitted);
/// ```
pub fn thermal(
    scene: &Scene,
    boundary_of: &[Option<u32>],
    boundaries: &[crate::thermal::Boundary],
    settings: &ThermalSettings,
    observer: &dyn Observer,
) -> Result<ThermalOutcome, Error> {
    thermal_over(scene, boundary_of, boundaries, settings, None, observer).map(|(o, _)| o)
}

/// [`thermal`], over `ranks` when given: the rows of F split over the ranks by cost
/// ([`crate::distributed::rows`]), all-gathered so that every rank can enforce reciprocity
/// and closure on the whole matrix (both couple row i with column i), then the net-radiation
/// system solved by Jacobi sweeps split over the ranks ([`crate::thermal::solve_ranks`]); the
/// direct and BiCGSTAB solves run on every rank alike. The same bytes on every rank and for
/// any number of ranks, with the run's [`Report`].
pub fn thermal_over(
    scene: &Scene,
    boundary_of: &[Option<u32>],
    boundaries: &[crate::thermal::Boundary],
    settings: &ThermalSettings,
    ranks: Option<&Ranks<'_>>,
    observer: &dyn Observer,
) -> Result<(ThermalOutcome, Option<Report>), Error> {
    scene.validate_geometry()?;
    settings.mesh.validate()?;
    use crate::thermal::ThermalSolver;
    let start = ranks.map(Ranks::traffic);
    let limit = settings.memory_limit.bytes();
    let mut params = settings.form_factors;
    let check = |p: &crate::formfactor::Params| MemoryCheck::stored_matrix(p, limit);
    let unstored = MemoryCheck {
        limit,
        stored_rows: false,
        rays: 0,
    };
    if settings.default_rays {
        params.rays = 10_000;
    }
    // Over ranks only the stored solve splits.
    let solver = match (settings.solver, ranks) {
        (ThermalSolver::MatrixFree, Some(_)) => {
            return Err(Error::Thermal(crate::thermal::ThermalError::Malformed(
                "the matrix-free solve does not run over ranks".into(),
            )))
        }
        (ThermalSolver::Auto, Some(_)) => ThermalSolver::Stored,
        (s, _) => s,
    };
    match solver {
        ThermalSolver::Stored => check(&params).before_meshing(scene, settings.mesh)?,
        _ => unstored.before_meshing(scene, settings.mesh)?,
    }
    observer.event(Event::Stage(Stage::Mesh));
    let mesh = Mesh::build(scene, settings.mesh)?;
    if settings.default_rays {
        params.rays = thermal_default_rays(mesh.len());
    }
    let solver = match solver {
        ThermalSolver::Auto
            if mesh.len() <= crate::thermal::STORED_MAX
                && check(&params).check(mesh.len() as u64).is_ok() =>
        {
            ThermalSolver::Stored
        }
        ThermalSolver::Auto => ThermalSolver::MatrixFree,
        s => s,
    };
    if solver == ThermalSolver::MatrixFree {
        unstored.check(mesh.len() as u64)?;
        return super::thermal_matrix_free::thermal_matrix_free(
            mesh,
            boundary_of,
            boundaries,
            settings,
            params,
            observer,
        )
        .map(|o| (o, None));
    }
    check(&params).check(mesh.len() as u64)?;
    let t = Instant::now();
    observer.event(Event::Stage(Stage::Bvh));
    let bvh = Bvh::build(&mesh);
    let estimator = Estimator::new(&mesh, &bvh, params)?;
    let mut report = ranks.map(|r| Report {
        transport: r.communicator().describe(),
        ..Default::default()
    });
    let (matrix, mut busy) = match (ranks, report.as_mut()) {
        (Some(r), Some(report)) => {
            let (block, busy) = rows::split(&estimator, r, observer, report);
            (rows::all_gather_matrix(&block, mesh.len(), r), busy)
        }
        _ => (
            estimator
                .matrix(crate::formfactor::Storage::Sparse, observer)
                .into_sparse(),
            0.0,
        ),
    };
    let form_factor_seconds = t.elapsed().as_secs_f64();
    let adaptive = estimator.adaptive().map(|p| p.stats());
    drop(estimator);
    drop(bvh);
    let area: Vec<f64> = mesh.patches.iter().map(|p| p.area as f64).collect();
    let (matrix, before, after, closed) = thermal_enclosure(matrix, &area, settings);
    let system = thermal_system(&mesh, &area, boundary_of, boundaries, settings, closed);
    observer.event(Event::Stage(Stage::Solve));
    let params_solve = crate::thermal::ThermalParams {
        linear: settings.linear,
        memory_limit: limit,
        ..Default::default()
    };
    let solution = match ranks {
        Some(r) => {
            let before_solve = r.traffic().seconds;
            let t_solve = Instant::now();
            let s = crate::thermal::solve_ranks(&system, &matrix, params_solve, r)?;
            busy += t_solve.elapsed().as_secs_f64() - (r.traffic().seconds - before_solve);
            s
        }
        None => crate::thermal::solve(&system, &matrix, params_solve)?,
    };
    let per_boundary = solution.per_boundary(&system);
    if let (Some(report), Some(r), Some(start)) = (report.as_mut(), ranks, &start) {
        report.finish(busy, start, r);
    }
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
            adaptive,
            solver: ThermalSolver::Stored,
            closed,
        },
        report,
    ))
}
