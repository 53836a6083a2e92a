//! View factors: the form-factor matrix of a scene as CSR arrays (SciPy's `csr_matrix` is
//! made of them on the Python side).

use crate::convert::{method_by_name, value_error};
use crate::scene::Scene;
use numpy::ndarray::Array1;
use numpy::{IntoPyArray, PyArray1};
use pyo3::prelude::*;
use radiosity::formfactor::Params as FormFactorParams;
use radiosity::formfactor::Storage;
use radiosity::mesh::MeshParams;
use radiosity::observe::Silent;
use radiosity::pipeline::{view_factors, ViewFactorSettings};
use radiosity::system::SparseMatrix;

/// View factors of a scene: (data, indices, indptr, shape, areas) of the CSR matrix F, rows
/// per patch (or per input face with `faces=True`).
#[pyfunction]
#[pyo3(signature = (scene, method = "monte-carlo", patches = None, faces = false, rays = 1_000_000, resolution = 128, samples = 16, seed = 1))]
#[allow(clippy::too_many_arguments, clippy::type_complexity)]
pub(crate) fn form_factors_csr(
    py: Python<'_>,
    scene: &Scene,
    method: &str,
    patches: Option<usize>,
    faces: bool,
    rays: u32,
    resolution: u32,
    samples: u32,
    seed: u64,
) -> PyResult<(
    Py<PyArray1<f32>>,
    Py<PyArray1<u32>>,
    Py<PyArray1<u64>>,
    (usize, usize),
    Py<PyArray1<f64>>,
)> {
    let params = FormFactorParams {
        method: method_by_name(method)?,
        resolution,
        samples,
        rays,
        seed,
        ..FormFactorParams::default()
    };
    params.validate().map_err(value_error)?;
    let mesh_params = match (faces, patches) {
        (true, _) => MeshParams::Faces,
        (false, Some(n)) => MeshParams::Patches(n),
        (false, None) => MeshParams::default(),
    };
    mesh_params.validate().map_err(value_error)?;
    let s = &scene.inner;
    let settings = ViewFactorSettings {
        mesh: mesh_params,
        form_factors: params,
        storage: Storage::Sparse,
        memory_limit: radiosity::pipeline::MemoryLimit::Available,
    };
    let (matrix, area) = py
        .allow_threads(|| -> Result<(SparseMatrix, Vec<f64>), String> {
            let vf = view_factors(s, &settings, None, &Silent).map_err(|e| e.to_string())?;
            if faces {
                Ok(vf.per_face(s).expect("computed in this process"))
            } else {
                let area = vf.areas();
                Ok((vf.matrix.expect("computed in this process"), area))
            }
        })
        .map_err(value_error)?;
    let n = matrix.n();
    let mut data = Vec::with_capacity(matrix.nnz());
    let mut indices = Vec::with_capacity(matrix.nnz());
    let mut indptr = Vec::with_capacity(n + 1);
    indptr.push(0u64);
    for i in 0..n {
        for &(j, f) in matrix.row_entries(i) {
            indices.push(j);
            data.push(f);
        }
        indptr.push(indices.len() as u64);
    }
    Ok((
        Array1::from(data).into_pyarray(py).unbind(),
        Array1::from(indices).into_pyarray(py).unbind(),
        Array1::from(indptr).into_pyarray(py).unbind(),
        (n, n),
        Array1::from(area).into_pyarray(py).unbind(),
    ))
}
