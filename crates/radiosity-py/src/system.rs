//! Solving a linear system brought from Python: `B = E + diag(ρ) F B` with F as CSR arrays.

use crate::convert::{library_error, rgb_array, rgb_rows, solver_by_name, trace_dict, value_error};
use crate::observer::Progress;
use numpy::{PyArray2, PyReadonlyArray1};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use radiosity::pipeline;
use radiosity::solve::SolverParams;
use radiosity::system::{SparseMatrix, System};

/// Solve the system `B = E + diag(ρ) F B` given in CSR form (`data`, `indices`, `indptr`,
/// N rows) with areas, reflectances and emissions; returns B (N, 3) and the trace (a dict of
/// arrays, or None).
#[pyfunction]
#[pyo3(signature = (data, indices, indptr, area, reflectance, emission, solver = "gauss-seidel", tolerance = 1e-6, max_iterations = None, seed = 1, trace = true, progress = None))]
#[allow(clippy::too_many_arguments, clippy::type_complexity)]
pub(crate) fn solve_system_csr<'py>(
    py: Python<'py>,
    data: PyReadonlyArray1<'py, f64>,
    indices: PyReadonlyArray1<'py, i64>,
    indptr: PyReadonlyArray1<'py, i64>,
    area: PyReadonlyArray1<'py, f64>,
    reflectance: &Bound<'py, PyAny>,
    emission: &Bound<'py, PyAny>,
    solver: &str,
    tolerance: f64,
    max_iterations: Option<u64>,
    seed: u64,
    trace: bool,
    progress: Option<Py<PyAny>>,
) -> PyResult<(Py<PyArray2<f64>>, Option<Bound<'py, PyDict>>)> {
    let area = area.as_array().to_vec();
    let n = area.len();
    let (data, indices, indptr) = (data.as_array(), indices.as_array(), indptr.as_array());
    if indptr.len() != n + 1 {
        return Err(value_error(format!(
            "F: {} rows, but {n} areas",
            indptr.len().saturating_sub(1)
        )));
    }
    if data.len() != indices.len() {
        return Err(value_error("F: data and indices differ in length"));
    }
    let mut rows = Vec::with_capacity(n);
    for i in 0..n {
        let (a, b) = (indptr[i], indptr[i + 1]);
        if a < 0 || b < a || b as usize > data.len() {
            return Err(value_error(format!("F: row {i} has a bad extent {a}..{b}")));
        }
        let mut row: Vec<(u32, f32)> = Vec::with_capacity((b - a) as usize);
        for k in a as usize..b as usize {
            let j = indices[k];
            if j < 0 || j as usize >= n {
                return Err(value_error(format!("F: row {i}: column {j} out of range")));
            }
            if !data[k].is_finite() {
                return Err(value_error(format!("F[{i}, {j}] is not finite")));
            }
            if data[k] != 0.0 {
                row.push((j as u32, data[k] as f32));
            }
        }
        row.sort_by_key(|e| e.0);
        row.dedup_by(|b, a| {
            if a.0 == b.0 {
                a.1 += b.1;
                true
            } else {
                false
            }
        });
        rows.push(row);
    }
    let system = System {
        area,
        reflectance: rgb_rows(reflectance, n, "reflectance")?,
        emission: rgb_rows(emission, n, "emission")?,
    };
    let mut f = SparseMatrix::from_rows(rows);
    let solver = solver_by_name(solver)?;
    let params = SolverParams {
        tolerance,
        max_iterations: max_iterations.unwrap_or_else(|| {
            radiosity::solve::default_iteration_cap(solver, n, &SolverParams::default())
        }),
        seed,
        ..SolverParams::default()
    };
    params.validate().map_err(value_error)?;
    let observer = Progress::new(progress);
    let out = py.allow_threads(|| {
        pipeline::solve_system(&system, &mut f, solver, &params, trace, &observer)
    });
    if let Some(e) = observer.error() {
        return Err(e);
    }
    let out = out.map_err(library_error)?;
    let t = out
        .trace
        .as_ref()
        .map(|t| trace_dict(py, t.rows()))
        .transpose()?;
    Ok((rgb_array(py, &out.radiosity), t))
}
