//! `radiosity`: the command-line front end. Parses arguments, runs the library, reports.

mod args;
mod bench;
mod report;
mod settings;

use anyhow::{Context, Result};
use args::{Cli, Command, RenderArgs, SolveArgs, SolveCmdArgs};
use clap::Parser;
use radiosity::export::{write_image, write_patches_csv, ImageFormat};
use radiosity::pipeline::{self, Solution};
use radiosity::render::{auto_exposure, RenderParams};
use radiosity::scene::{self, Scene};
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Render(a) => render(a),
        Command::Solve(a) => solve(a),
        Command::Bench(a) => bench::run(a),
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
fn load_scene(name: &str) -> Result<Scene> {
    let scene = scene::load(name)?;
    for w in &scene.warnings {
        eprintln!("radiosity: warning: {w}");
    }
    Ok(scene)
}

/// Load and solve, with a progress bar.
fn solve_scene(a: &SolveArgs) -> Result<(Scene, Solution)> {
    let settings = settings::settings(a)?;
    let scene = load_scene(&a.scene)?;
    let mut progress = report::Progress::new(settings.progressive.tolerance);
    let solution = pipeline::solve(&scene, &settings, &mut |e| progress.event(e))?;
    progress.finish();
    Ok((scene, solution))
}

fn render(a: RenderArgs) -> Result<()> {
    let out = a
        .out
        .clone()
        .unwrap_or_else(|| default_output(&a.solve.scene, "png"));
    ImageFormat::from_path(&out)?;
    settings::check_output(&out)?;
    settings::settings(&a.solve)?;
    if a.width == 0 || a.height == 0 {
        anyhow::bail!(
            "--width {} --height {}: the image needs at least one pixel",
            a.width,
            a.height
        );
    }
    if a.spp == 0 {
        anyhow::bail!("--spp 0: at least one sample per pixel is needed");
    }
    if !a.exposure.is_finite() {
        anyhow::bail!(
            "--exposure {}: must be a finite number of stops",
            a.exposure
        );
    }
    settings::threads(a.solve.threads)?;
    let (scene, solution) = solve_scene(&a.solve)?;
    let camera = settings::camera(scene.camera_or_default(), &a.camera)?;
    let params = RenderParams {
        width: a.width,
        height: a.height,
        samples_per_pixel: a.spp,
        seed: a.solve.seed,
    };
    let t = Instant::now();
    let bar = report::rows_bar(a.height);
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
        a.width,
        a.height,
        a.spp
    );
    Ok(())
}

fn solve(a: SolveCmdArgs) -> Result<()> {
    let ext = a
        .out
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase());
    if ext.as_deref() != Some("csv") {
        anyhow::bail!("{}: unsupported output format (use .csv)", a.out.display());
    }
    settings::check_output(&a.out)?;
    settings::settings(&a.solve)?;
    settings::threads(a.solve.threads)?;
    let (scene, solution) = solve_scene(&a.solve)?;
    let t = Instant::now();
    write_patches_csv(&a.out, &scene, &solution.mesh, &solution.radiosity)?;
    let write_s = t.elapsed().as_secs_f64();
    report::summary(&scene, &solution, None);
    println!(
        "wrote       {} ({} patches) in {write_s:.3} s",
        a.out.display(),
        solution.mesh.len()
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
