//! Scenes: the `Scene` class (from arrays), the built-in scenes and scene files.

use crate::convert::value_error;
use numpy::{PyReadonlyArray2, PyReadonlyArrayDyn};
use pyo3::prelude::*;
use radiosity::color::Rgb;
use radiosity::geom::Vec3;
use radiosity::scene::{Material, Polygon, Scene as RScene};

/// A scene: polygons with diffuse materials (and a camera, when the file has one).
#[pyclass(module = "radiosity._native", name = "Scene")]
#[derive(Clone)]
pub struct Scene {
    pub(crate) inner: RScene,
}

#[pymethods]
impl Scene {
    /// A scene from arrays: `vertices` (V, 3) floats; `faces` (F, K) vertex indices, K ≥ 3
    /// (counter-clockwise seen from the front); `reflectance` and `emission` per face, (F, 3)
    /// or (F,) (grey). Reflectance in [0, 1), emission ≥ 0.
    #[staticmethod]
    #[pyo3(signature = (vertices, faces, reflectance, emission, name = "arrays"))]
    fn from_arrays(
        vertices: PyReadonlyArray2<'_, f64>,
        faces: PyReadonlyArray2<'_, i64>,
        reflectance: &Bound<'_, PyAny>,
        emission: &Bound<'_, PyAny>,
        name: &str,
    ) -> PyResult<Self> {
        let v = vertices.as_array();
        let f = faces.as_array();
        if v.ncols() != 3 {
            return Err(value_error(format!(
                "vertices: shape ({}, {}); expected (V, 3)",
                v.nrows(),
                v.ncols()
            )));
        }
        if f.ncols() < 3 {
            return Err(value_error(format!(
                "faces: shape ({}, {}); expected (F, K) with K ≥ 3",
                f.nrows(),
                f.ncols()
            )));
        }
        let nf = f.nrows();
        let per_face = |arg: &Bound<'_, PyAny>, what: &str| -> PyResult<Vec<Rgb>> {
            let a: PyReadonlyArrayDyn<'_, f64> = arg
                .extract()
                .map_err(|_| value_error(format!("{what}: expected a float array")))?;
            let a = a.as_array();
            match a.shape() {
                [n] if *n == nf => Ok(a.iter().map(|&x| Rgb::splat(x)).collect()),
                [n, 3] if *n == nf => Ok((0..nf)
                    .map(|i| Rgb::new(a[[i, 0]], a[[i, 1]], a[[i, 2]]))
                    .collect()),
                s => Err(value_error(format!(
                    "{what}: shape {s:?}; expected ({nf},) or ({nf}, 3), one per face"
                ))),
            }
        };
        let rho = per_face(reflectance, "reflectance")?;
        let e = per_face(emission, "emission")?;
        for (i, r) in rho.iter().enumerate() {
            if !(r.is_finite() && r.min_channel() >= 0.0 && r.max_channel() < 1.0) {
                return Err(value_error(format!(
                    "reflectance[{i}] = {r}: every channel must be in [0, 1)"
                )));
            }
        }
        for (i, x) in e.iter().enumerate() {
            if !(x.is_finite() && x.min_channel() >= 0.0) {
                return Err(value_error(format!(
                    "emission[{i}] = {x}: must be finite and non-negative"
                )));
            }
        }
        let nv = v.nrows() as i64;
        let mut polygons = Vec::with_capacity(nf);
        let mut materials = Vec::with_capacity(nf);
        for i in 0..nf {
            let mut vs = Vec::with_capacity(f.ncols());
            for &k in f.row(i) {
                if k < 0 {
                    break; // -1 pads a shorter face
                }
                if k >= nv {
                    return Err(value_error(format!(
                        "faces[{i}]: vertex {k} out of range (there are {nv})"
                    )));
                }
                let k = k as usize;
                vs.push(Vec3::new(
                    v[[k, 0]] as f32,
                    v[[k, 1]] as f32,
                    v[[k, 2]] as f32,
                ));
            }
            materials.push(Material::emitter(&format!("face{i}"), rho[i], e[i]));
            polygons.push(Polygon {
                vertices: vs,
                material: i,
                line: 0,
                group: 0,
            });
        }
        let scene = RScene {
            name: name.to_string(),
            materials,
            polygons,
            ..RScene::default()
        };
        scene.validate_geometry().map_err(value_error)?;
        Ok(Self { inner: scene })
    }

    /// The scene's name.
    #[getter]
    fn name(&self) -> String {
        self.inner.name.clone()
    }

    /// Number of input polygons.
    #[getter]
    fn polygons(&self) -> usize {
        self.inner.polygons.len()
    }

    /// Material names, in order.
    #[getter]
    fn materials(&self) -> Vec<String> {
        self.inner
            .materials
            .iter()
            .map(|m| m.name.clone())
            .collect()
    }

    fn __repr__(&self) -> String {
        format!(
            "Scene('{}', {} polygons, {} materials)",
            self.inner.name,
            self.inner.polygons.len(),
            self.inner.materials.len()
        )
    }
}

/// A built-in scene by name (cornell, office, cube-dim, cube-bright, furnace, city).
#[pyfunction]
pub(crate) fn builtin(name: &str) -> PyResult<Scene> {
    radiosity::scene::builtin::by_name(name)
        .map(|inner| Scene { inner })
        .ok_or_else(|| {
            value_error(format!(
                "'{name}' is not a built-in scene ({})",
                radiosity::scene::builtin::NAMES.join(", ")
            ))
        })
}

/// Load a scene file (.obj, .mgf, .gltf, .glb, .ply, .vs3); `one_sided` as the CLI's flag.
#[pyfunction]
#[pyo3(signature = (path, one_sided = false))]
pub(crate) fn load(py: Python<'_>, path: &str, one_sided: bool) -> PyResult<Scene> {
    let inner = py
        .allow_threads(|| {
            radiosity::scene::load_with(path, &radiosity::scene::LoadOptions { one_sided })
        })
        .map_err(value_error)?;
    Ok(Scene { inner })
}
