//! `radiosity`: the command-line front end. Parses arguments, runs the library, reports.

mod alloc;
mod args;
mod bench;
mod experiment;
mod report;
mod settings;
mod view_factors;

use anyhow::{Context, Result};
use args::{Cli, Command, RenderArgs, SolveArgs, SolveCmdArgs, SolveSystemArgs, ViewArgs};
use clap::Parser;
use radiosity::export::bake::{self, Bake, BakeFormat};
use radiosity::export::{write_image, write_patches_csv, write_radiosity_csv, ImageFormat, Trace};
use radiosity::pipeline::{self, Event, Solution};
use radiosity::render::auto_exposure;
use radiosity::scene::{self, Scene};
use radiosity::solve::gauss::{bytes_needed, dense_solve_matrix};
use radiosity::solve::System;
use radiosity::system::SparseMatrix;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Render(a) => render(a),
        Command::Solve(a) => solve(a),
        Command::View(a) => view(a),
        Command::Bench(a) => bench::run(a),
        Command::SolveSystem(a) => solve_system(a),
        Command::FormFactors(a) => view_factors::run(a),
        Command::Experiment(a) => experiment::run(a),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("radiosity: error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

/// Load the scene named on the command line and print its warnings.
pub(crate) fn load_scene(name: &str, one_sided: bool) -> Result<Scene> {
    let scene = scene::load_with(name, &scene::LoadOptions { one_sided })?;
    for w in &scene.warnings {
        eprintln!("radiosity: warning: {w}");
    }
    Ok(scene)
}

/// Largest system whose trace measures the error against an LU solution.
const TRACE_EXACT_MAX: usize = 5000;

/// The exact solution for a trace's error column, when the system is small enough.
fn trace_reference(system: &System, m: &SparseMatrix) -> Option<Vec<radiosity::Rgb>> {
    let n = system.len();
    let limit = pipeline::available_memory().unwrap_or(u64::MAX) / 2;
    if n > TRACE_EXACT_MAX || bytes_needed(n) > limit {
        eprintln!("radiosity: warning: {n} patches: the trace's error column is left empty (LU reference only up to {TRACE_EXACT_MAX} patches)");
        return None;
    }
    match dense_solve_matrix(system, m, limit) {
        Ok(b) => Some(b),
        Err(e) => {
            eprintln!("radiosity: warning: no reference solution for the trace: {e}");
            None
        }
    }
}

/// Load and solve, with a progress bar (and the trace, if asked).
fn solve_scene(a: &SolveArgs) -> Result<(Scene, Solution)> {
    let settings = settings::settings(a)?;
    let scene = load_scene(&a.scene, a.one_sided)?;
    let mut progress = report::Progress::new(settings.params.tolerance);
    let mut trace: Option<Trace> = None;
    let tracing = a.trace.is_some();
    let solution = pipeline::solve(&scene, &settings, &mut |e| {
        match e {
            Event::Matrix(m, system) if tracing => {
                trace = Some(Trace::new(trace_reference(system, m), &system.emission));
            }
            Event::Solve(status, solver) => {
                if let Some(t) = trace.as_mut() {
                    t.record(status, solver);
                }
            }
            _ => {}
        }
        progress.event(e)
    })?;
    progress.finish();
    if let (Some(path), Some(t)) = (&a.trace, &trace) {
        t.write(path).context("writing the trace")?;
        println!("trace       {} ({} rows)", path.display(), t.len());
    }
    Ok((scene, solution))
}

fn solve_system(a: SolveSystemArgs) -> Result<()> {
    let method = settings::method(&a.solver)?;
    let params =
        settings::solver_params(a.tolerance, a.max_iterations, a.omega, a.photons, a.seed)?;
    let ext = a
        .out
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase());
    if ext.as_deref() != Some("csv") {
        anyhow::bail!("{}: unsupported output format (use .csv)", a.out.display());
    }
    settings::check_output(&a.out)?;
    if let Some(t) = &a.trace {
        settings::check_output(t)?;
    }
    let patches = radiosity::io::patches_csv::read(&a.patches)?;
    let mut matrix = radiosity::io::matrix_market::read(&a.form_factors)?;
    if matrix.n() != patches.area.len() {
        anyhow::bail!(
            "{}: {} patches, but {} is {} × {}",
            a.patches.display(),
            patches.area.len(),
            a.form_factors.display(),
            matrix.n(),
            matrix.n()
        );
    }
    let system = System {
        area: patches.area.to_vec(),
        reflectance: patches.reflectance.to_vec(),
        emission: patches.emission.to_vec(),
    };
    let mut params = params;
    params.memory_limit = pipeline::available_memory().unwrap_or(u64::MAX) / 2;
    let mut trace = a
        .trace
        .as_ref()
        .map(|_| Trace::new(trace_reference(&system, &matrix), &system.emission));
    let mut progress = report::Progress::new(params.tolerance);
    let mut solver = radiosity::solve::start(method, &system, &mut matrix, &params)?;
    let info = radiosity::solve::run(
        &mut *solver,
        &mut matrix,
        &params,
        trace.is_some(),
        &mut |status, sv| {
            if let Some(t) = trace.as_mut() {
                t.record(status, sv);
            }
            progress.event(Event::Solve(status, sv));
        },
    );
    progress.finish();
    let mut b = Vec::new();
    solver.radiosity(&mut b);
    write_radiosity_csv(&a.out, &b, patches.single_channel)?;
    if let (Some(path), Some(t)) = (&a.trace, &trace) {
        t.write(path).context("writing the trace")?;
        println!("trace       {} ({} rows)", path.display(), t.len());
    }
    let e = info.emitted.sum();
    println!(
        "system      {} patches, {} form factors",
        matrix.n(),
        matrix.nnz()
    );
    println!(
        "iterations  {} by {} ({}; unshot energy left {:.3e} of emitted) in {:.3} s",
        info.iterations,
        method,
        if info.converged {
            "converged"
        } else {
            "stopped at --max-iterations"
        },
        info.unshot_fraction,
        info.seconds
    );
    println!(
        "energy      emitted {:.6e}: absorbed {:.2}%, escaped {:.2}%, unshot {:.2}%",
        e,
        100.0 * info.absorbed.sum() / e,
        100.0 * info.escaped.sum() / e,
        100.0 * info.unshot.sum() / e
    );
    println!("wrote       {}", a.out.display());
    Ok(())
}

fn render(a: RenderArgs) -> Result<()> {
    let out = a
        .out
        .clone()
        .unwrap_or_else(|| default_output(&a.solve.scene, "png"));
    ImageFormat::from_path(&out)?;
    settings::check_output(&out)?;
    if let Some(t) = &a.solve.trace {
        settings::check_output(t)?;
    }
    settings::settings(&a.solve)?;
    let params = settings::image(&a.image, a.solve.seed)?;
    if !a.exposure.is_finite() {
        anyhow::bail!(
            "--exposure {}: must be a finite number of stops",
            a.exposure
        );
    }
    settings::threads(a.solve.threads)?;
    let (scene, solution) = solve_scene(&a.solve)?;
    let camera = settings::camera(solution.default_camera(&scene), &a.camera)?;
    let t = Instant::now();
    let bar = report::rows_bar(params.height);
    let image = solution.render(&camera, &params, &|rows| bar.set_position(rows as u64));
    bar.finish_and_clear();
    let render_s = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let scale = auto_exposure(&image) * 2f32.powf(a.exposure);
    write_image(&out, &image, scale).context("writing the image")?;
    let write_s = t.elapsed().as_secs_f64();
    report::summary(&scene, &solution, Some((render_s, write_s)));
    println!(
        "wrote       {} ({}×{}, {} samples per pixel)",
        out.display(),
        params.width,
        params.height,
        params.samples_per_pixel
    );
    Ok(())
}

fn solve(a: SolveCmdArgs) -> Result<()> {
    let ext = a
        .out
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase());
    let baked = BakeFormat::from_path(&a.out).is_some();
    if ext.as_deref() != Some("csv") && !baked {
        anyhow::bail!(
            "{}: unsupported output format (use .csv, .glb, .gltf or .ply)",
            a.out.display()
        );
    }
    if !a.exposure.is_finite() {
        anyhow::bail!(
            "--exposure {}: must be a finite number of stops",
            a.exposure
        );
    }
    settings::check_output(&a.out)?;
    if let Some(t) = &a.solve.trace {
        settings::check_output(t)?;
    }
    settings::settings(&a.solve)?;
    settings::threads(a.solve.threads)?;
    let (scene, solution) = solve_scene(&a.solve)?;
    let t = Instant::now();
    if baked {
        let vertex = solution.vertex_display_radiosity();
        let bake = Bake {
            scene: &scene,
            mesh: &solution.mesh,
            vertex_radiosity: &vertex,
            scale: solution.auto_exposure() * 2f32.powf(a.exposure),
            camera: Some(solution.default_camera(&scene)),
        };
        bake::write(&a.out, &bake)?;
    } else {
        write_patches_csv(&a.out, &scene, &solution.mesh, &solution.radiosity)?;
    }
    let write_s = t.elapsed().as_secs_f64();
    report::summary(&scene, &solution, None);
    println!(
        "wrote       {} ({} patches) in {write_s:.3} s",
        a.out.display(),
        solution.mesh.len()
    );
    Ok(())
}

/// Show a baked glTF's vertex colours from its camera (or `--eye`/`--target`), as an unlit
/// glTF viewer would: no solving, PNG pixels are the sRGB encoding of COLOR_0.
fn view(a: ViewArgs) -> Result<()> {
    use radiosity::mesh::{Mesh, MeshParams};
    let out = a
        .out
        .clone()
        .unwrap_or_else(|| default_output(&a.file.to_string_lossy(), "png"));
    ImageFormat::from_path(&out)?;
    settings::check_output(&out)?;
    let params = settings::image(&a.image, 1)?;
    let ext = a
        .file
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase());
    if !matches!(ext.as_deref(), Some("glb" | "gltf")) {
        anyhow::bail!(
            "{}: view shows baked glTF files (.glb or .gltf)",
            a.file.display()
        );
    }
    let (scene, colours) = scene::gltf::load_vertex_colours(&a.file)?;
    for w in &scene.warnings {
        eprintln!("radiosity: warning: {w}");
    }
    scene.validate_geometry()?;
    let mesh = Mesh::build(&scene, MeshParams::Faces)?;
    // Each triangle is one patch; give its vertices the colours of the polygon's corners.
    let mut values = vec![radiosity::Rgb::BLACK; mesh.vertices.len()];
    for p in &mesh.patches {
        let poly = &scene.polygons[p.surface as usize];
        for &v in &p.vertices[..3] {
            let at = mesh.vertices[v as usize];
            let j = poly.vertices.iter().position(|q| *q == at).unwrap_or(0);
            // The renderer shows radiance B/π; scale by π so that pixels are COLOR_0.
            values[v as usize] = colours[p.surface as usize][j] * std::f64::consts::PI;
        }
    }
    let bvh = radiosity::accel::Bvh::build(&mesh);
    let own = scene.camera.unwrap_or_else(|| {
        radiosity::render::camera::default_camera(&bvh, radiosity::geom::Vec3::Y)
    });
    let camera = settings::camera(own, &a.camera)?;
    let image = radiosity::render::render(&mesh, &bvh, &values, &camera, &params, &|_| {});
    write_image(&out, &image, 1.0).context("writing the image")?;
    println!(
        "wrote       {} ({}×{}, {} triangles shown with their COLOR_0)",
        out.display(),
        params.width,
        params.height,
        mesh.patches.len()
    );
    Ok(())
}

/// `SCENE.EXT` for a built-in scene, `STEM.EXT` (in the current folder) for a file.
fn default_output(scene: &str, ext: &str) -> PathBuf {
    let stem = std::path::Path::new(scene)
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("scene");
    PathBuf::from(format!("{stem}.{ext}"))
}
