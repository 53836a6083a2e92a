//! Lighting design: photometric files read into arrays, and illuminance at points
//! (`radiosity lighting`'s pipeline).

use crate::convert::{library_error, value_error};
use crate::observer::Progress;
use crate::scene::Scene;
use numpy::ndarray::{Array1, Array2};
use numpy::{IntoPyArray, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use radiosity::lighting::{read_points, read_schedule, SensorPoint, Up};
use radiosity::mesh::MeshParams;
use radiosity::pipeline::{lighting as run_lighting, LightingSettings};
use std::path::PathBuf;

/// A photometric file (IES LM-63 or EULUMDAT) as a dict: `kind` ("C", "B" or "A", the
/// photometric type), `c_angles` (degrees: type C's C-planes over the full 0–360; for types B
/// and A the horizontal angles H), `gamma_angles` (degrees: type C's γ; for B and A the
/// vertical angles V), `candela` (planes × angles, absolute candela), `lumens` (the file's
/// rated lumens, or None for absolute photometry), `rated_flux`, `flux` (lumens integrated
/// from the distribution), `source` and `warnings`.
#[pyfunction]
pub(crate) fn read_photometry<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Bound<'py, PyDict>> {
    let p = radiosity::photometry::read(&path).map_err(value_error)?;
    let (nc, ng) = (p.c_angles.len(), p.gamma_angles.len());
    let candela = Array2::from_shape_vec((nc, ng), p.candela.clone()).map_err(value_error)?;
    let d = PyDict::new(py);
    d.set_item("kind", p.kind.to_string())?;
    d.set_item(
        "c_angles",
        Array1::from(p.c_angles.clone()).into_pyarray(py),
    )?;
    d.set_item(
        "gamma_angles",
        Array1::from(p.gamma_angles.clone()).into_pyarray(py),
    )?;
    d.set_item("candela", candela.into_pyarray(py))?;
    d.set_item("lumens", p.lumens)?;
    d.set_item("rated_flux", p.rated_flux)?;
    d.set_item("flux", p.flux())?;
    d.set_item("source", p.source.clone())?;
    d.set_item("warnings", p.warnings.clone())?;
    Ok(d)
}

/// Illuminance at points from the luminaires of a schedule (and the scene's emitting
/// surfaces), interreflection included: `points` an (N, 6) array of `x y z dx dy dz` rows or
/// a list of `.pts` files. Returns a dict: `groups`, `illuminance` (N,), `by_group` (N, G),
/// `direct` (N,), `patches`, `flux` (G,).
#[pyfunction]
#[pyo3(signature = (scene, luminaires = None, points = None, grids = Vec::new(), unit = 1.0, up = "z", patches = 10000, tolerance = 1e-3, indirect_samples = 256, seed = 1, progress = None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn lighting<'py>(
    py: Python<'py>,
    scene: &Scene,
    luminaires: Option<PathBuf>,
    points: Option<PyReadonlyArray2<'py, f64>>,
    grids: Vec<PathBuf>,
    unit: f64,
    up: &str,
    patches: usize,
    tolerance: f64,
    indirect_samples: u32,
    seed: u64,
    progress: Option<Py<PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let up = match up {
        "z" => Up::Z,
        "y" => Up::Y,
        other => return Err(value_error(format!("up '{other}': z or y"))),
    };
    let lums = match &luminaires {
        Some(p) => read_schedule(p, up).map_err(value_error)?,
        None => Vec::new(),
    };
    let mut sensors = Vec::new();
    if let Some(a) = &points {
        let a = a.as_array();
        if a.ncols() != 6 {
            return Err(value_error(format!(
                "points: an (N, 6) array of x y z dx dy dz rows, not (N, {})",
                a.ncols()
            )));
        }
        for (i, r) in a.rows().into_iter().enumerate() {
            sensors.push(
                SensorPoint::new([r[0], r[1], r[2]], [r[3], r[4], r[5]]).ok_or_else(|| {
                    value_error(format!("points row {i}: not finite, or a zero direction"))
                })?,
            );
        }
    }
    for g in &grids {
        sensors.extend(read_points(g).map_err(value_error)?);
    }
    if sensors.is_empty() {
        return Err(value_error("no points: give points= or grids="));
    }
    let mut settings = LightingSettings {
        mesh: MeshParams::Patches(patches),
        unit_metres: unit,
        ..LightingSettings::default()
    };
    settings.params.tolerance = tolerance;
    settings.params.seed = seed;
    settings.form_factors.seed = seed;
    settings.gather.indirect = indirect_samples;
    let observer = Progress::new(progress);
    let s = &scene.inner;
    let result = py.allow_threads(|| run_lighting(s, &lums, &sensors, &settings, &observer));
    if let Some(e) = observer.error() {
        return Err(e);
    }
    let r = result.map_err(library_error)?;
    let (n, ng) = (sensors.len(), r.groups.len());
    let d = PyDict::new(py);
    d.set_item("groups", r.groups.clone())?;
    d.set_item("illuminance", Array1::from(r.total).into_pyarray(py))?;
    d.set_item(
        "by_group",
        Array2::from_shape_vec((n, ng), r.by_group)
            .map_err(value_error)?
            .into_pyarray(py),
    )?;
    d.set_item("direct", Array1::from(r.direct).into_pyarray(py))?;
    d.set_item("patches", r.patches)?;
    d.set_item("flux", Array1::from(r.flux).into_pyarray(py))?;
    Ok(d)
}
