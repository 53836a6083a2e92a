//! Conversions between the library's values and Python's: per-patch colours and points as
//! NumPy arrays, the convergence trace as a dict of arrays, solver and form-factor method
//! names, and library errors as Python exceptions.

use numpy::ndarray::{Array1, Array2};
use numpy::{IntoPyArray, PyArray2};
use pyo3::exceptions::{PyMemoryError, PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use radiosity::color::Rgb;
use radiosity::formfactor::FormFactorMethod;
use radiosity::geom::Vec3;
use radiosity::solve::trace::TraceRow;
use radiosity::solve::Solver;

/// A `ValueError` with the message.
pub(crate) fn value_error(e: impl std::fmt::Display) -> PyErr {
    PyValueError::new_err(e.to_string())
}

/// A library error as the Python exception that fits it.
pub(crate) fn library_error(e: radiosity::Error) -> PyErr {
    match e {
        radiosity::Error::OutOfMemory { .. } => PyMemoryError::new_err(e.to_string()),
        radiosity::Error::Export(_) => PyRuntimeError::new_err(e.to_string()),
        e => PyValueError::new_err(e.to_string()),
    }
}

/// Colours as an (N, 3) float64 array.
pub(crate) fn rgb_array(py: Python<'_>, v: &[Rgb]) -> Py<PyArray2<f64>> {
    let mut a = Array2::<f64>::zeros((v.len(), 3));
    for (i, c) in v.iter().enumerate() {
        a[[i, 0]] = c.r;
        a[[i, 1]] = c.g;
        a[[i, 2]] = c.b;
    }
    a.into_pyarray(py).unbind()
}

/// Points (or vectors) as an (N, 3) float64 array.
pub(crate) fn vec3_array(
    py: Python<'_>,
    v: impl ExactSizeIterator<Item = Vec3>,
) -> Py<PyArray2<f64>> {
    let mut a = Array2::<f64>::zeros((v.len(), 3));
    for (i, p) in v.enumerate() {
        a[[i, 0]] = p.x as f64;
        a[[i, 1]] = p.y as f64;
        a[[i, 2]] = p.z as f64;
    }
    a.into_pyarray(py).unbind()
}

/// Colours from Python: an (n,) (grey) or (n, 3) float array; `what` names the argument.
pub(crate) fn rgb_rows(a: &Bound<'_, PyAny>, n: usize, what: &str) -> PyResult<Vec<Rgb>> {
    let arr: numpy::PyReadonlyArrayDyn<'_, f64> = a
        .extract()
        .map_err(|_| value_error(format!("{what}: expected a float array")))?;
    let arr = arr.as_array();
    match arr.shape() {
        [m] if *m == n => Ok(arr.iter().map(|&x| Rgb::splat(x)).collect()),
        [m, 3] if *m == n => Ok((0..n)
            .map(|i| Rgb::new(arr[[i, 0]], arr[[i, 1]], arr[[i, 2]]))
            .collect()),
        s => Err(value_error(format!(
            "{what}: shape {s:?}; expected ({n},) or ({n}, 3)"
        ))),
    }
}

pub(crate) fn solver_by_name(name: &str) -> PyResult<Solver> {
    Solver::ALL
        .into_iter()
        .find(|s| s.name() == name)
        .ok_or_else(|| {
            value_error(format!(
                "solver '{name}' is not one of: {}",
                Solver::ALL.map(|s| s.name()).join(", ")
            ))
        })
}

pub(crate) fn method_by_name(name: &str) -> PyResult<FormFactorMethod> {
    FormFactorMethod::from_name(name).ok_or_else(|| {
        value_error(format!(
            "form-factor method '{name}' is not one of: {}",
            FormFactorMethod::ALL.map(|m| m.name()).join(", ")
        ))
    })
}

/// A convergence trace as a dict of arrays `iteration`, `seconds`, `error` (NaN where the solve
/// had no exact solution to measure against) and `unshot`. All four are float64, `iteration`
/// included: so they were when the dict was parsed back from the trace's CSV text.
pub(crate) fn trace_dict<'py>(py: Python<'py>, rows: &[TraceRow]) -> PyResult<Bound<'py, PyDict>> {
    let column = |f: fn(&TraceRow) -> f64| Array1::from_iter(rows.iter().map(f)).into_pyarray(py);
    let d = PyDict::new(py);
    d.set_item("iteration", column(|r| r.iteration as f64))?;
    d.set_item("seconds", column(|r| r.seconds))?;
    d.set_item("error", column(|r| r.error.unwrap_or(f64::NAN)))?;
    d.set_item("unshot", column(|r| r.unshot))?;
    Ok(d)
}
