//! Radiative heat transfer: the CLI's `thermal` on a scene with boundary conditions per surface.

use crate::convert::{library_error, method_by_name, value_error, vec3_array};
use crate::observer::Progress;
use crate::scene::Scene;
use numpy::ndarray::Array1;
use numpy::IntoPyArray;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use radiosity::formfactor::Params as FormFactorParams;
use radiosity::mesh::MeshParams;

/// One boundary from Python: name, emissivity, temperature, flux (each optional).
type BoundaryItem = (String, Option<f64>, Option<f64>, Option<f64>);

/// Radiative heat transfer (the CLI's `thermal`): `boundaries` maps each surface name to
/// `(emissivity or None, temperature K or None, flux W/m² or None)`. Returns a dict with
/// per-surface results (`surfaces`: name → dict of area, emissivity, temperature, flux,
/// power), per-patch arrays (`patches`) and the balance (`info`).
#[pyfunction]
#[pyo3(signature = (scene, boundaries, unit = 1.0, environment = 0.0, enclosure = "auto", patches = None, max_edge = None, form_factor_method = "monte-carlo", rays = None, resolution = 256, samples = 16, seed = 1, linear_solver = "auto", progress = None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn thermal<'py>(
    py: Python<'py>,
    scene: &Scene,
    boundaries: Vec<BoundaryItem>,
    unit: f64,
    environment: f64,
    enclosure: &str,
    patches: Option<usize>,
    max_edge: Option<f32>,
    form_factor_method: &str,
    rays: Option<u32>,
    resolution: u32,
    samples: u32,
    seed: u64,
    linear_solver: &str,
    progress: Option<Py<PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    use radiosity::pipeline::{Enclosure, ThermalSettings};
    use radiosity::thermal::{Boundary, Condition, LinearSolver};
    let s = &scene.inner;
    let mut named = Vec::with_capacity(boundaries.len());
    for (name, eps, t, q) in &boundaries {
        let emissivity = eps.unwrap_or_else(|| {
            s.materials
                .iter()
                .find(|m| &m.name == name)
                .map_or(1.0, |m| {
                    1.0 - (m.reflectance.r + m.reflectance.g + m.reflectance.b) / 3.0
                })
        });
        if !(emissivity > 0.0 && emissivity <= 1.0) {
            return Err(value_error(format!(
                "boundaries['{name}']: emissivity {emissivity} outside (0, 1]"
            )));
        }
        let condition = match (t, q) {
            (Some(_), Some(_)) => {
                return Err(value_error(format!(
                    "boundaries['{name}']: give a temperature or a flux, not both"
                )))
            }
            (Some(t), None) if !(t.is_finite() && *t >= 0.0) => {
                return Err(value_error(format!(
                    "boundaries['{name}']: temperature {t} K must be finite and ≥ 0"
                )))
            }
            (Some(t), None) => Condition::Temperature(*t),
            (None, Some(q)) if !q.is_finite() => {
                return Err(value_error(format!(
                    "boundaries['{name}']: flux {q} is not finite"
                )))
            }
            (None, Some(q)) => Condition::Flux(*q),
            (None, None) => Condition::Adiabatic,
        };
        named.push((
            name.clone(),
            Boundary {
                emissivity,
                condition,
            },
        ));
    }
    let boundary_of = radiosity::pipeline::thermal_boundaries(s, &named, &|_| None).map_err(
        |(k, m)| match k {
            Some(k) => value_error(format!("boundaries['{}']: {m}", named[k].0)),
            None => value_error(format!("boundaries: {m}")),
        },
    )?;
    let mesh = match (patches, max_edge) {
        (_, Some(l)) => MeshParams::MaxEdge(l),
        (Some(n), _) => MeshParams::Patches(n),
        (None, None) => MeshParams::Faces,
    };
    mesh.validate().map_err(value_error)?;
    if !(unit.is_finite() && unit > 0.0) {
        return Err(value_error(format!(
            "unit {unit}: metres per scene unit, > 0"
        )));
    }
    if !(environment.is_finite() && environment >= 0.0) {
        return Err(value_error(format!(
            "environment {environment}: a temperature in kelvin, ≥ 0"
        )));
    }
    let settings = ThermalSettings {
        mesh,
        form_factors: FormFactorParams {
            method: method_by_name(form_factor_method)?,
            resolution,
            samples,
            seed,
            rays: rays.unwrap_or(10_000),
            ..FormFactorParams::default()
        },
        default_rays: rays.is_none(),
        unit_metres: unit,
        environment,
        enclosure: match enclosure {
            "auto" => Enclosure::Auto,
            "closed" => Enclosure::Closed,
            "open" => Enclosure::Open,
            e => {
                return Err(value_error(format!(
                    "enclosure '{e}': auto, closed or open"
                )))
            }
        },
        enclosure_hint: None,
        linear: match linear_solver {
            "auto" => LinearSolver::Auto,
            "direct" => LinearSolver::Direct,
            "iterative" => LinearSolver::Iterative,
            "jacobi" => LinearSolver::Jacobi,
            e => {
                return Err(value_error(format!(
                    "linear_solver '{e}': auto, direct, iterative or jacobi"
                )))
            }
        },
        memory_limit: radiosity::pipeline::MemoryLimit::Available,
        // The stored solve, as before the matrix-free one existed.
        solver: radiosity::thermal::ThermalSolver::Stored,
        matrix_free: radiosity::thermal::MatrixFreeParams::default(),
    };
    settings.form_factors.validate().map_err(value_error)?;
    let ts: Vec<Boundary> = named.iter().map(|n| n.1).collect();
    let observer = Progress::new(progress);
    let out = py
        .allow_threads(|| radiosity::pipeline::thermal(s, &boundary_of, &ts, &settings, &observer));
    if let Some(e) = observer.error() {
        return Err(e);
    }
    let out = out.map_err(library_error)?;
    let surfaces = PyDict::new(py);
    for (k, (name, b)) in named.iter().enumerate() {
        let (area, power, t) = out.per_boundary[k];
        let d = PyDict::new(py);
        d.set_item("area", area)?;
        d.set_item("emissivity", b.emissivity)?;
        d.set_item("temperature", t)?;
        d.set_item("flux", if area > 0.0 { power / area } else { 0.0 })?;
        d.set_item("power", power)?;
        surfaces.set_item(name, d)?;
    }
    let sol = &out.solution;
    let pd = PyDict::new(py);
    pd.set_item(
        "centre",
        vec3_array(py, out.mesh.patches.iter().map(|p| p.centre)),
    )?;
    pd.set_item(
        "area",
        Array1::from(out.system.area.clone()).into_pyarray(py),
    )?;
    pd.set_item(
        "surface",
        Array1::from(out.system.group.clone()).into_pyarray(py),
    )?;
    pd.set_item(
        "temperature",
        Array1::from(sol.temperature.clone()).into_pyarray(py),
    )?;
    pd.set_item("flux", Array1::from(sol.flux.clone()).into_pyarray(py))?;
    pd.set_item(
        "radiosity",
        Array1::from(sol.radiosity.clone()).into_pyarray(py),
    )?;
    pd.set_item(
        "irradiation",
        Array1::from(sol.irradiation.clone()).into_pyarray(py),
    )?;
    let info = PyDict::new(py);
    info.set_item("method", sol.info.method)?;
    info.set_item("iterations", sol.info.iterations)?;
    info.set_item("residual", sol.info.residual)?;
    info.set_item("total_power", sol.info.total_power)?;
    info.set_item("environment_loss", sol.info.environment_loss)?;
    info.set_item("balance_error", sol.info.balance_error)?;
    info.set_item("opening", sol.info.opening)?;
    info.set_item("closed", out.closed)?;
    info.set_item("rays", out.form_factors.rays)?;
    info.set_item("form_factor_seconds", out.form_factor_seconds)?;
    let d = PyDict::new(py);
    d.set_item("surfaces", surfaces)?;
    d.set_item("patches", pd)?;
    d.set_item("info", info)?;
    Ok(d)
}
