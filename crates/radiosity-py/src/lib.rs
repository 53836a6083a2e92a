//! Python bindings of the radiosity engine: the native module `radiosity._native`, wrapped by
//! the pure-Python package `radiosity` (`python/radiosity/`), which adds SciPy
//! conversions and the documented signatures.
//!
//! Arrays go to NumPy with one copy (from the library's `Vec<Rgb>` into a fresh array); the
//! GIL is released during meshing, form factors, solves and rendering; a progress callback,
//! when given, is called with the GIL taken back, at most every 50 ms, and an exception it
//! raises (KeyboardInterrupt included) stops a solve at its next iteration and is raised by the
//! call; without one, Ctrl-C is noticed at the same points and does the same. (Meshing, form
//! factors computed up front and rendering run to their end first.) Library errors become `ValueError`
//! (bad input), `MemoryError` (too large) or `RuntimeError`, with the library's one-line
//! message.
//!
//! Modules: `scene` (the `Scene` class, built-in scenes, files), `solve` (`solve` and the
//! `Solution` class), `view_factors` (the form-factor matrix), `system` (solving a matrix
//! brought from Python), `thermal` (radiative heat transfer), `observer` (progress and Ctrl-C)
//! and `convert` (arrays, names and errors between the library and Python); this file registers
//! them as the module `_native`, with `methods`.

mod convert;
mod lighting;
mod observer;
mod scene;
mod solve;
mod system;
mod thermal;
mod view_factors;

use pyo3::prelude::*;
use pyo3::types::PyDict;
use radiosity::formfactor::FormFactorMethod;
use radiosity::solve::Solver;

/// Names of the solvers and form-factor methods.
#[pyfunction]
fn methods(py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
    let d = PyDict::new(py);
    d.set_item(
        "solvers",
        Solver::ALL.iter().map(|s| s.name()).collect::<Vec<_>>(),
    )?;
    d.set_item(
        "scene_solvers",
        Solver::ALL
            .iter()
            .map(|s| s.name())
            .chain(["hierarchical"])
            .collect::<Vec<_>>(),
    )?;
    d.set_item(
        "form_factors",
        FormFactorMethod::ALL
            .iter()
            .map(|m| m.name())
            .collect::<Vec<_>>(),
    )?;
    Ok(d)
}

/// The native module.
#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<scene::Scene>()?;
    m.add_class::<solve::Solution>()?;
    m.add_function(wrap_pyfunction!(scene::builtin, m)?)?;
    m.add_function(wrap_pyfunction!(scene::load, m)?)?;
    m.add_function(wrap_pyfunction!(solve::solve, m)?)?;
    m.add_function(wrap_pyfunction!(view_factors::form_factors_csr, m)?)?;
    m.add_function(wrap_pyfunction!(system::solve_system_csr, m)?)?;
    m.add_function(wrap_pyfunction!(methods, m)?)?;
    m.add_function(wrap_pyfunction!(thermal::thermal, m)?)?;
    m.add_function(wrap_pyfunction!(lighting::lighting, m)?)?;
    m.add_function(wrap_pyfunction!(lighting::read_photometry, m)?)?;
    Ok(())
}
