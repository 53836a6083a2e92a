//! Python bindings of the radiosity engine: the native module `radiosity._native`, wrapped by
//! the pure-Python package `radiosity` (`python/radiosity/__init__.py`), which adds SciPy
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

use numpy::ndarray::{Array1, Array2, Array3};
use numpy::{IntoPyArray, PyArray1, PyArray2, PyArray3, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::exceptions::{PyMemoryError, PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use radiosity::color::Rgb;
use radiosity::formfactor::{FormFactorMethod, Params as FormFactorParams};
use radiosity::geom::Vec3;
use radiosity::mesh::{Mesh, MeshParams};
use radiosity::observe::{Event, Observer, Stage};
use radiosity::pipeline::{self, Settings};
use radiosity::scene::{Material, Polygon, Scene as RScene};
use radiosity::solve::{Solver, SolverParams};
use radiosity::system::{SparseMatrix, System};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Mutex;
use std::time::{Duration, Instant};

fn value_error(e: impl std::fmt::Display) -> PyErr {
    PyValueError::new_err(e.to_string())
}

/// A library error as the Python exception that fits it.
fn library_error(e: radiosity::Error) -> PyErr {
    match e {
        radiosity::Error::OutOfMemory { .. } => PyMemoryError::new_err(e.to_string()),
        radiosity::Error::Export(_) => PyRuntimeError::new_err(e.to_string()),
        e => PyValueError::new_err(e.to_string()),
    }
}

/// A scene: polygons with diffuse materials (and a camera, when the file has one).
#[pyclass(module = "radiosity._native", name = "Scene")]
#[derive(Clone)]
pub struct Scene {
    inner: RScene,
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
            let a: numpy::PyReadonlyArrayDyn<'_, f64> = arg
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
fn builtin(name: &str) -> PyResult<Scene> {
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
fn load(py: Python<'_>, path: &str, one_sided: bool) -> PyResult<Scene> {
    let inner = py
        .allow_threads(|| {
            radiosity::scene::load_with(path, &radiosity::scene::LoadOptions { one_sided })
        })
        .map_err(value_error)?;
    Ok(Scene { inner })
}

/// Forwards progress to a Python callable `(stage: str, done: int, total: int)`, at most every
/// 50 ms, taking the GIL only for the call; the first exception it raises stops the reports.
struct Progress {
    callback: Option<Py<PyAny>>,
    last: Mutex<(Instant, Option<PyErr>)>,
    /// Set with the first exception: solves stop at their next iteration.
    stop: AtomicBool,
}

impl Progress {
    fn new(callback: Option<Py<PyAny>>) -> Self {
        Self {
            callback,
            last: Mutex::new((Instant::now() - Duration::from_secs(1), None)),
            stop: AtomicBool::new(false),
        }
    }

    fn error(self) -> Option<PyErr> {
        self.last.into_inner().ok().and_then(|l| l.1)
    }
}

impl Observer for Progress {
    fn cancelled(&self) -> bool {
        self.stop.load(Ordering::Relaxed)
    }

    fn event(&self, e: Event<'_>) {
        let (stage, done, total) = match e {
            Event::Progress { stage, done, total } => (stage, done, total),
            Event::Stage(stage) => (stage, 0, 0),
            // A solve's iterations: reported as (solve, iterations, 0), and where Ctrl-C is
            // noticed during a long solve.
            Event::Solve(status, _) => (Stage::Solve, status.iterations.max(1), 0),
            _ => return,
        };
        let Ok(mut last) = self.last.lock() else {
            return;
        };
        if last.1.is_some()
            || (done != total && last.0.elapsed() < Duration::from_millis(50) && done != 0)
        {
            return;
        }
        last.0 = Instant::now();
        let Some(cb) = &self.callback else {
            // No callback: still notice Ctrl-C (the KeyboardInterrupt is raised when the
            // stage returns; the library has no way to stop a stage midway).
            Python::with_gil(|py| {
                if let Err(err) = py.check_signals() {
                    last.1 = Some(err);
                    self.stop.store(true, Ordering::Relaxed);
                }
            });
            return;
        };
        let name = match stage {
            Stage::Mesh => "mesh",
            Stage::Bvh => "bvh",
            Stage::FormFactors => "form-factors",
            Stage::Solve => "solve",
            Stage::Render => "render",
            Stage::Experiment => "experiment",
        };
        Python::with_gil(|py| {
            if let Err(err) = cb.call1(py, (name, done, total)) {
                last.1 = Some(err);
                self.stop.store(true, Ordering::Relaxed);
            }
        });
    }
}

fn rgb_array(py: Python<'_>, v: &[Rgb]) -> Py<PyArray2<f64>> {
    let mut a = Array2::<f64>::zeros((v.len(), 3));
    for (i, c) in v.iter().enumerate() {
        a[[i, 0]] = c.r;
        a[[i, 1]] = c.g;
        a[[i, 2]] = c.b;
    }
    a.into_pyarray(py).unbind()
}

fn vec3_array(py: Python<'_>, v: impl ExactSizeIterator<Item = Vec3>) -> Py<PyArray2<f64>> {
    let mut a = Array2::<f64>::zeros((v.len(), 3));
    for (i, p) in v.enumerate() {
        a[[i, 0]] = p.x as f64;
        a[[i, 1]] = p.y as f64;
        a[[i, 2]] = p.z as f64;
    }
    a.into_pyarray(py).unbind()
}

fn solver_by_name(name: &str) -> PyResult<Solver> {
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

fn method_by_name(name: &str) -> PyResult<FormFactorMethod> {
    FormFactorMethod::from_name(name).ok_or_else(|| {
        value_error(format!(
            "form-factor method '{name}' is not one of: {}",
            FormFactorMethod::ALL.map(|m| m.name()).join(", ")
        ))
    })
}

/// A solved scene: per-patch arrays, the solver's report, pictures and files.
#[pyclass(module = "radiosity._native", name = "Solution")]
pub struct Solution {
    scene: RScene,
    inner: pipeline::Solution,
}

#[pymethods]
impl Solution {
    /// Patch centres, (N, 3).
    #[getter]
    fn centres(&self, py: Python<'_>) -> Py<PyArray2<f64>> {
        vec3_array(py, self.inner.mesh.patches.iter().map(|p| p.centre))
    }

    /// Unit patch normals, (N, 3).
    #[getter]
    fn normals(&self, py: Python<'_>) -> Py<PyArray2<f64>> {
        vec3_array(py, self.inner.mesh.patches.iter().map(|p| p.normal))
    }

    /// Patch areas, (N,).
    #[getter]
    fn areas(&self, py: Python<'_>) -> Py<PyArray1<f64>> {
        Array1::from(self.inner.system.area.clone())
            .into_pyarray(py)
            .unbind()
    }

    /// Radiosity B per patch and channel, (N, 3) (without the display ambient term).
    #[getter]
    fn radiosity(&self, py: Python<'_>) -> Py<PyArray2<f64>> {
        rgb_array(py, &self.inner.radiosity)
    }

    /// Unshot radiosity per patch when a shooting method stopped, (N, 3).
    #[getter]
    fn unshot(&self, py: Python<'_>) -> Py<PyArray2<f64>> {
        rgb_array(py, &self.inner.unshot)
    }

    /// Reflectance per patch, (N, 3).
    #[getter]
    fn reflectance(&self, py: Python<'_>) -> Py<PyArray2<f64>> {
        rgb_array(py, &self.inner.system.reflectance)
    }

    /// Emission per patch, (N, 3).
    #[getter]
    fn emission(&self, py: Python<'_>) -> Py<PyArray2<f64>> {
        rgb_array(py, &self.inner.system.emission)
    }

    /// The input polygon of each patch, (N,).
    #[getter]
    fn surfaces(&self, py: Python<'_>) -> Py<PyArray1<u32>> {
        Array1::from_iter(self.inner.mesh.patches.iter().map(|p| p.surface))
            .into_pyarray(py)
            .unbind()
    }

    /// The solver's report: method, iterations, converged, unshot fraction, seconds per stage
    /// (`seconds_solve_rays`: the part of `seconds_solve` stochastic Jacobi spent casting its
    /// rays), rays, and the energy balance (emitted, absorbed, escaped, unshot; summed over channels).
    #[getter]
    fn info<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        let i = &self.inner.info;
        let t = &self.inner.timings;
        d.set_item("solver", self.inner.method.name())?;
        d.set_item("patches", self.inner.mesh.len())?;
        d.set_item("iterations", i.iterations)?;
        d.set_item("converged", i.converged)?;
        d.set_item("unshot_fraction", i.unshot_fraction)?;
        d.set_item("rays", self.inner.form_factors.rays)?;
        d.set_item("seconds_mesh", t.mesh)?;
        d.set_item("seconds_bvh", t.bvh)?;
        d.set_item("seconds_form_factors", t.form_factors)?;
        d.set_item("seconds_solve", t.solve)?;
        d.set_item("seconds_solve_rays", t.solve_rays)?;
        d.set_item("emitted", i.emitted.sum())?;
        d.set_item("absorbed", i.absorbed.sum())?;
        d.set_item("escaped", i.escaped.sum())?;
        d.set_item("unshot", i.unshot.sum())?;
        d.set_item("estimated_error", i.estimated_error)?;
        Ok(d)
    }

    /// The convergence trace (eq. 22 error and unshot energy per iteration) as a dict of
    /// arrays `iteration`, `seconds`, `error`, `unshot`, when the solve recorded one.
    #[getter]
    fn trace<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyDict>>> {
        self.inner
            .trace
            .as_ref()
            .map(|t| trace_dict(py, t.csv()))
            .transpose()
    }

    /// A picture, (height, width, 3) float32 linear radiance: `integrator` "radiosity" (the
    /// solution shown directly), "gather" (final gather) or "path" (path tracer).
    #[pyo3(signature = (width = 512, height = 512, spp = None, integrator = "radiosity", seed = 1, progress = None))]
    #[allow(clippy::too_many_arguments)]
    fn render(
        &self,
        py: Python<'_>,
        width: u32,
        height: u32,
        spp: Option<u32>,
        integrator: &str,
        seed: u64,
        progress: Option<Py<PyAny>>,
    ) -> PyResult<Py<PyArray3<f32>>> {
        if width == 0 || height == 0 || width > 32768 || height > 32768 {
            return Err(value_error(format!(
                "width {width}, height {height}: 1 to 32768 pixels a side"
            )));
        }
        let spp = spp.unwrap_or(match integrator {
            "gather" => 16,
            "path" => 256,
            _ => 4,
        });
        if spp == 0 {
            return Err(value_error("spp: at least one sample per pixel"));
        }
        let params = radiosity::render::RenderParams {
            width,
            height,
            samples_per_pixel: spp,
            seed,
        };
        let camera = self.inner.default_camera(&self.scene);
        let observer = Progress::new(progress);
        let image = py.allow_threads(|| match integrator {
            "radiosity" => Ok(self.inner.render(&camera, &params, &observer)),
            "gather" => Ok(self.inner.render_gather(
                &camera,
                &params,
                radiosity::render::gather::GatherParams::default(),
                &observer,
            )),
            "path" => pipeline::path_trace(&self.scene, &camera, &params, &observer)
                .map_err(|e| e.to_string()),
            other => Err(format!(
                "integrator '{other}' is not one of: radiosity, gather, path"
            )),
        });
        if let Some(e) = observer.error() {
            return Err(e);
        }
        let image = image.map_err(value_error)?;
        let mut a = Array3::<f32>::zeros((height as usize, width as usize, 3));
        for (k, p) in image.pixels.iter().enumerate() {
            let (y, x) = (k / width as usize, k % width as usize);
            for c in 0..3 {
                a[[y, x, c]] = p[c];
            }
        }
        Ok(a.into_pyarray(py).unbind())
    }

    /// Write the solution as the CLI's `solve --out` does: `.csv` (one row per patch) or a
    /// baked mesh (`.glb`, `.gltf`, `.ply`).
    fn save(&self, py: Python<'_>, path: &str) -> PyResult<()> {
        use radiosity::io::FileFormat;
        let p = std::path::Path::new(path);
        let format = FileFormat::from_path(p);
        py.allow_threads(|| -> Result<(), String> {
            if format == Some(FileFormat::Csv) {
                radiosity::export::write_patches_csv(
                    p,
                    &self.scene,
                    &self.inner.mesh,
                    &self.inner.radiosity,
                )
                .map_err(|e| e.to_string())
            } else if format.is_some_and(FileFormat::is_baked_mesh) {
                let vertex = self.inner.vertex_display_radiosity();
                let bake = radiosity::export::bake::Bake {
                    scene: &self.scene,
                    mesh: &self.inner.mesh,
                    vertex_radiosity: &vertex,
                    scale: self.inner.auto_exposure(),
                    camera: Some(self.inner.default_camera(&self.scene)),
                };
                radiosity::export::bake::write(p, &bake).map_err(|e| e.to_string())
            } else {
                Err(format!(
                    "{path}: unsupported output format (use .csv, .glb, .gltf or .ply)"
                ))
            }
        })
        .map_err(value_error)
    }

    fn __repr__(&self) -> String {
        format!(
            "Solution({} patches, {} iterations by {}, unshot {:.3}%)",
            self.inner.mesh.len(),
            self.inner.info.iterations,
            self.inner.method.name(),
            100.0 * self.inner.info.unshot_fraction
        )
    }
}

fn trace_dict<'py>(py: Python<'py>, csv: &str) -> PyResult<Bound<'py, PyDict>> {
    let mut cols: [Vec<f64>; 4] = Default::default();
    for line in csv.lines().skip(1) {
        for (k, v) in line.split(',').take(4).enumerate() {
            cols[k].push(v.parse().unwrap_or(f64::NAN));
        }
    }
    let d = PyDict::new(py);
    for (name, col) in ["iteration", "seconds", "error", "unshot"].iter().zip(cols) {
        d.set_item(*name, Array1::from(col).into_pyarray(py))?;
    }
    Ok(d)
}

/// Solve a scene (the CLI's `solve`): mesh, form factors, the solver.
#[pyfunction]
#[pyo3(signature = (scene, solver = "progressive", patches = 10000, tolerance = 0.01, seed = 1, threads = None, form_factor_method = "monte-carlo", rays = 256, max_iterations = None, trace = false, progress = None, omega = 1.1, photons = 1000, iteration_rays = 16, gather_rays = 0, resolution = 128, samples = 16, link_error = 2e-5))]
#[allow(clippy::too_many_arguments)]
fn solve(
    py: Python<'_>,
    scene: &Scene,
    solver: &str,
    patches: usize,
    tolerance: f64,
    seed: u64,
    threads: Option<usize>,
    form_factor_method: &str,
    rays: u32,
    max_iterations: Option<u64>,
    trace: bool,
    progress: Option<Py<PyAny>>,
    omega: f64,
    photons: u32,
    iteration_rays: u32,
    gather_rays: u32,
    resolution: u32,
    samples: u32,
    link_error: f64,
) -> PyResult<Solution> {
    if patches == 0 {
        return Err(value_error("patches: at least one patch is needed"));
    }
    if !(tolerance.is_finite() && tolerance > 0.0) {
        return Err(value_error(format!(
            "tolerance {tolerance}: must be a positive number"
        )));
    }
    // `hierarchical` is a method of scenes, not of linear systems: it has its own parameters.
    let hierarchical = (solver == "hierarchical").then(|| radiosity::hierarchical::Params {
        link_error,
        tolerance,
        seed,
        max_iterations: max_iterations
            .unwrap_or(radiosity::hierarchical::Params::default().max_iterations),
        ..Default::default()
    });
    if let Some(p) = &hierarchical {
        p.validate().map_err(value_error)?;
        if trace {
            return Err(value_error(
                "trace: the hierarchical solver has no stored matrix to trace against",
            ));
        }
    }
    let settings = Settings {
        hierarchical,
        mesh: MeshParams::Patches(patches),
        form_factors: FormFactorParams {
            method: method_by_name(form_factor_method)?,
            rays,
            resolution,
            samples,
            seed,
            ..FormFactorParams::shooting()
        },
        solver: if hierarchical.is_some() {
            Solver::Progressive
        } else {
            solver_by_name(solver)?
        },
        params: SolverParams {
            tolerance,
            max_iterations: max_iterations.unwrap_or(u64::MAX),
            seed,
            omega,
            photons,
            iteration_rays,
            gather_rays,
            ..SolverParams::default()
        },
        trace,
        ..Settings::default()
    };
    settings.form_factors.validate().map_err(value_error)?;
    let observer = Progress::new(progress);
    let run = |s: &RScene| pipeline::solve(s, &settings, &observer);
    let result = match threads {
        Some(0) => return Err(value_error("threads: at least one")),
        Some(t) => {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(t)
                .build()
                .map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
            py.allow_threads(|| pool.install(|| run(&scene.inner)))
        }
        // On a worker of the global pool, as with a pool of `threads`: a method of many short
        // parallel steps (progressive refinement) pays for each one started from outside it.
        None => py.allow_threads(|| rayon::scope(|_| run(&scene.inner))),
    };
    if let Some(e) = observer.error() {
        return Err(e);
    }
    let inner = result.map_err(library_error)?;
    Ok(Solution {
        scene: scene.inner.clone(),
        inner,
    })
}

/// View factors of a scene: (data, indices, indptr, shape, areas) of the CSR matrix F, rows
/// per patch (or per input face with `faces=True`).
#[pyfunction]
#[pyo3(signature = (scene, method = "monte-carlo", patches = None, faces = false, rays = 1_000_000, resolution = 128, samples = 16, seed = 1))]
#[allow(clippy::too_many_arguments, clippy::type_complexity)]
fn form_factors_csr(
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
        (false, Some(0)) => return Err(value_error("patches: at least one patch is needed")),
        (false, Some(n)) => MeshParams::Patches(n),
        (false, None) => MeshParams::default(),
    };
    let s = &scene.inner;
    let (matrix, area) = py
        .allow_threads(|| -> Result<(SparseMatrix, Vec<f64>), String> {
            s.validate_geometry().map_err(|e| e.to_string())?;
            let mesh = Mesh::build(s, mesh_params).map_err(|e| e.to_string())?;
            let bvh = radiosity::accel::Bvh::build(&mesh);
            let est = radiosity::formfactor::Estimator::new(&mesh, &bvh, params)
                .map_err(|e| e.to_string())?;
            let m = est.sparse_matrix();
            let area: Vec<f64> = mesh.patches.iter().map(|p| p.area as f64).collect();
            if faces {
                let group: Vec<u32> = mesh.patches.iter().map(|p| p.surface).collect();
                Ok(radiosity::formfactor::aggregate(
                    &m,
                    &area,
                    &group,
                    s.polygons.len(),
                ))
            } else {
                Ok((m, area))
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

fn rgb_rows(a: &Bound<'_, PyAny>, n: usize, what: &str) -> PyResult<Vec<Rgb>> {
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

/// Solve the system `B = E + diag(ρ) F B` given in CSR form (`data`, `indices`, `indptr`,
/// N rows) with areas, reflectances and emissions; returns B (N, 3) and the trace (a dict of
/// arrays, or None).
#[pyfunction]
#[pyo3(signature = (data, indices, indptr, area, reflectance, emission, solver = "gauss-seidel", tolerance = 1e-6, max_iterations = None, seed = 1, trace = true, progress = None))]
#[allow(clippy::too_many_arguments, clippy::type_complexity)]
fn solve_system_csr<'py>(
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
    if !(tolerance.is_finite() && tolerance > 0.0) {
        return Err(value_error(format!(
            "tolerance {tolerance}: must be a positive number"
        )));
    }
    let params = SolverParams {
        tolerance,
        max_iterations: max_iterations.unwrap_or_else(|| {
            radiosity::solve::default_iteration_cap(solver, n, &SolverParams::default())
        }),
        seed,
        ..SolverParams::default()
    };
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
        .map(|t| trace_dict(py, t.csv()))
        .transpose()?;
    Ok((rgb_array(py, &out.radiosity), t))
}

/// One boundary from Python: name, emissivity, temperature, flux (each optional).
type BoundaryItem = (String, Option<f64>, Option<f64>, Option<f64>);

/// Radiative heat transfer (the CLI's `thermal`): `boundaries` maps each surface name to
/// `(emissivity or None, temperature K or None, flux W/m² or None)`. Returns a dict with
/// per-surface results (`surfaces`: name → dict of area, emissivity, temperature, flux,
/// power), per-patch arrays (`patches`) and the balance (`info`).
#[pyfunction]
#[pyo3(signature = (scene, boundaries, unit = 1.0, environment = 0.0, enclosure = "auto", patches = None, max_edge = None, form_factor_method = "monte-carlo", rays = None, resolution = 256, samples = 16, seed = 1, linear_solver = "auto", progress = None))]
#[allow(clippy::too_many_arguments)]
fn thermal<'py>(
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
        (_, Some(l)) if !(l.is_finite() && l > 0.0) => {
            return Err(value_error(format!(
                "max_edge {l}: must be a positive length"
            )))
        }
        (_, Some(l)) => MeshParams::MaxEdge(l),
        (Some(0), _) => return Err(value_error("patches: at least one patch is needed")),
        (Some(n), _) => MeshParams::Patches(n),
        (None, None) => MeshParams::Faces,
    };
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
        memory_limit: 0,
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
    m.add_class::<Scene>()?;
    m.add_class::<Solution>()?;
    m.add_function(wrap_pyfunction!(builtin, m)?)?;
    m.add_function(wrap_pyfunction!(load, m)?)?;
    m.add_function(wrap_pyfunction!(solve, m)?)?;
    m.add_function(wrap_pyfunction!(form_factors_csr, m)?)?;
    m.add_function(wrap_pyfunction!(solve_system_csr, m)?)?;
    m.add_function(wrap_pyfunction!(methods, m)?)?;
    m.add_function(wrap_pyfunction!(thermal, m)?)?;
    Ok(())
}
