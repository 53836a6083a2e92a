//! Solving a scene: `solve` and the `Solution` class (per-patch arrays, the solver's report
//! and trace, pictures and files).

use crate::convert::{
    library_error, method_by_name, rgb_array, solver_by_name, trace_dict, value_error, vec3_array,
};
use crate::observer::Progress;
use crate::scene::Scene;
use numpy::ndarray::{Array1, Array3};
use numpy::{IntoPyArray, PyArray1, PyArray2, PyArray3};
use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use radiosity::formfactor::Params as FormFactorParams;
use radiosity::mesh::MeshParams;
use radiosity::pipeline::{self, Settings, Uniform};
use radiosity::scene::Scene as RScene;
use radiosity::solve::{Solver, SolverParams};

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
            .map(|t| trace_dict(py, t.rows()))
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

    /// Bake a lightmap of the scene (docs/baking.md) from this solution: a second UV set on
    /// the scene's faces and atlases of radiosity. `texel_size` (scene units) and/or `size`
    /// (atlas side, texels) as the CLI's `--texel-size` and `--lightmap-size` (neither:
    /// `size` 1024); `direct`, `indirect`, `spacing`, `denoise` (bool, or the filter's
    /// radius in texels) as the `--lightmap-*` flags. Returns a dict: `atlases`, a list of
    /// (H, W, 3) float32 arrays of linear radiosity B (one unless the charts did not fit one
    /// atlas); per atlas `surface` (H, W) int32, the input polygon each texel lies on (−1:
    /// padding), and `inside` (H, W) bool, whether the texel's centre is inside it (else a
    /// border texel), and `covered` (H, W) bool; the faces' mesh `positions` (V, 3) float64,
    /// `uv` (V, 2) float32 (`TEXCOORD_1`, in [0, 1]² of the vertex's atlas, (0, 0) the
    /// image's top-left corner), `vertex_atlas` (V,) uint32, `triangles` (T, 3) uint32 and
    /// `triangle_surface` (T,) uint32; and `texel_size`.
    #[pyo3(signature = (texel_size = None, size = None, direct = 16, indirect = 256, spacing = 4, denoise = None, seed = 1))]
    #[allow(clippy::too_many_arguments)]
    fn bake_lightmap<'py>(
        &self,
        py: Python<'py>,
        texel_size: Option<f32>,
        size: Option<u32>,
        direct: u32,
        indirect: u32,
        spacing: u32,
        denoise: Option<Bound<'py, PyAny>>,
        seed: u64,
    ) -> PyResult<Bound<'py, PyDict>> {
        use numpy::ndarray::Array2;
        use radiosity::bake::lightmap::{bake, Denoise, LightmapParams, Texel};
        use radiosity::bake::uv::Density;
        if spacing == 0 {
            return Err(value_error("spacing: at least 1 texel"));
        }
        let density = match (texel_size, size) {
            (Some(l), Some(n)) => Density::Both(l, n),
            (Some(l), None) => Density::TexelSize(l),
            (None, Some(n)) => Density::AtlasSize(n),
            (None, None) => LightmapParams::default().density,
        };
        let denoise = match denoise {
            None => None,
            Some(d) if d.is_instance_of::<pyo3::types::PyBool>() => {
                d.extract::<bool>()?.then(Denoise::default)
            }
            Some(d) => Some(Denoise::with_radius(d.extract::<f32>().map_err(|_| {
                value_error("denoise: a bool or the filter's radius in texels")
            })?)),
        };
        let params = LightmapParams {
            density,
            direct,
            indirect,
            spacing,
            seed,
            denoise,
            memory_limit: pipeline::MemoryLimit::Available.bytes(),
            ..Default::default()
        };
        let map = py
            .allow_threads(|| {
                let vertex =
                    radiosity::render::vertex_radiosity(&self.inner.mesh, &self.inner.radiosity);
                bake(&self.scene, self.inner.surfaces(), &vertex, &params)
            })
            .map_err(value_error)?;
        let (w, h) = (map.width() as usize, map.height() as usize);
        let u = &map.unwrap;
        let d = PyDict::new(py);
        let (mut atlases, mut surfaces, mut insides, mut covered) =
            (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        for a in 0..map.atlases() as usize {
            let base = a * w * h;
            let mut img = Array3::<f32>::zeros((h, w, 3));
            let mut surface = Array2::<i32>::from_elem((h, w), -1);
            let mut inside = Array2::<bool>::from_elem((h, w), false);
            let mut cov = Array2::<bool>::from_elem((h, w), false);
            for y in 0..h {
                for x in 0..w {
                    let k = base + y * w + x;
                    for c in 0..3 {
                        img[[y, x, c]] = map.texels[k][c];
                    }
                    if map.faces[k] != u32::MAX {
                        surface[[y, x]] = u.mesh.patches[map.faces[k] as usize].surface as i32;
                        inside[[y, x]] = map.inside[k];
                        cov[[y, x]] = map.kind[k] == Texel::Covered;
                    }
                }
            }
            atlases.push(img.into_pyarray(py));
            surfaces.push(surface.into_pyarray(py));
            insides.push(inside.into_pyarray(py));
            covered.push(cov.into_pyarray(py));
        }
        d.set_item("atlases", atlases)?;
        d.set_item("surface", surfaces)?;
        d.set_item("inside", insides)?;
        d.set_item("covered", covered)?;
        d.set_item("positions", vec3_array(py, u.mesh.vertices.iter().copied()))?;
        let mut uv = Array2::<f32>::zeros((u.uv.len(), 2));
        for (i, t) in u.uv.iter().enumerate() {
            uv[[i, 0]] = t[0];
            uv[[i, 1]] = t[1];
        }
        d.set_item("uv", uv.into_pyarray(py))?;
        let mut vertex_atlas = vec![0u32; u.mesh.vertices.len()];
        let (mut tris, mut tri_surface) = (Vec::new(), Vec::new());
        for (f, p) in u.mesh.patches.iter().enumerate() {
            let a = u.atlas_of(f as u32);
            for t in p.triangles() {
                for v in t {
                    vertex_atlas[v as usize] = a;
                }
                tris.push(t);
                tri_surface.push(p.surface);
            }
        }
        let mut t = Array2::<u32>::zeros((tris.len(), 3));
        for (i, tri) in tris.iter().enumerate() {
            for c in 0..3 {
                t[[i, c]] = tri[c];
            }
        }
        d.set_item("vertex_atlas", Array1::from(vertex_atlas).into_pyarray(py))?;
        d.set_item("triangles", t.into_pyarray(py))?;
        d.set_item(
            "triangle_surface",
            Array1::from(tri_surface).into_pyarray(py),
        )?;
        d.set_item("texel_size", u.texel)?;
        Ok(d)
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

/// Solve a scene (the CLI's `solve`): mesh, form factors, the solver.
#[pyfunction]
#[pyo3(signature = (scene, solver = "progressive", patches = 10000, tolerance = 0.01, seed = 1, threads = None, form_factor_method = "monte-carlo", rays = 256, max_iterations = None, trace = false, progress = None, omega = 1.1, photons = 1000, iteration_rays = 16, gather_rays = 0, resolution = 128, samples = 16, link_error = 2e-5))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn solve(
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
    MeshParams::Patches(patches)
        .validate()
        .map_err(value_error)?;
    // `hierarchical` is a method of scenes, not of linear systems: it has its own parameters.
    let hierarchical = (solver == "hierarchical").then(|| radiosity::hierarchical::Params {
        link_error,
        tolerance,
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
    let uniform = Uniform {
        mesh: MeshParams::Patches(patches),
        form_factors: FormFactorParams {
            method: method_by_name(form_factor_method)?,
            rays,
            resolution,
            samples,
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
            omega,
            photons,
            iteration_rays,
            gather_rays,
            ..SolverParams::default()
        },
        trace,
        ..Uniform::default()
    };
    // Every argument is checked, whichever method reads it.
    uniform.form_factors.validate().map_err(value_error)?;
    uniform.params.validate().map_err(value_error)?;
    let mut settings = match hierarchical {
        Some(p) => Settings::from(p),
        None => Settings::from(uniform),
    };
    settings.set_seed(seed);
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
