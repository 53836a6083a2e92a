//! `radiosity`: the command-line front end. Parses arguments, runs the library, reports.
//!
//! A library so that the workbench's binaries (`radiosity-bench`, `radiosity-fuzz`) share the
//! command's argument types, settings, worker pool and ranks; the `radiosity` binary is
//! [`main`]. Nothing here is physics: that is the `radiosity` crate's.

pub mod alloc;
mod annual;
pub mod args;
mod daylight;
mod experiment;
pub mod false_colour;
mod lighting;
pub mod ranks;
mod render;
mod report;
pub mod settings;
mod solve_lightmap;
mod thermal;
mod validate;
mod view_factors;

use anyhow::{Context, Result};
use args::{Cli, Command, ReportFormat, SolveArgs, SolveCmdArgs, SolveSystemArgs, ViewArgs};
use clap::Parser;
use radiosity::export::bake::{self, Bake};
use radiosity::export::{
    write_image, write_patches_csv, write_radiosity_csv, write_text, ImageFormat,
};
use radiosity::io::FileFormat;
use radiosity::observe::Silent;
use radiosity::pipeline::{self, Solution};
use radiosity::render::auto_exposure;
use radiosity::render::baked::BakedView;
use radiosity::scene::{self, Scene};
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

/// Run one command.
fn run(command: Command) -> Result<()> {
    let single = |what: &str| ranks::refuse_unless_single(what);
    match command {
        Command::Render(a) => single("render").and_then(|()| render::run(a)),
        Command::Solve(a) => solve(a),
        Command::View(a) => single("view").and_then(|()| view(a)),
        Command::SolveSystem(a) => single("solve-system").and_then(|()| solve_system(a)),
        Command::FormFactors(a) => view_factors::run(a),
        Command::Experiment(a) => single("experiment").and_then(|()| experiment::run(a)),
        Command::Lighting(a) => single("lighting").and_then(|()| lighting::run(a)),
        Command::Thermal(a) => thermal::run(a),
        Command::Validate(a) => single("validate").and_then(|()| validate::run(a)),
    }
}

/// The `radiosity` command: parse the arguments, run, and say what went wrong on one line.
pub fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) if e.use_stderr() => {
            eprintln!("radiosity: error: {}", usage_error(&e));
            return ExitCode::from(2);
        }
        Err(e) => e.exit(),
    };
    if let Err(e) = ranks::start() {
        eprintln!("radiosity: error: {e:#}");
        return ExitCode::FAILURE;
    }
    let result = settings::threads(cli.threads).and_then(|()| {
        // MPI was initialised on this thread (its communicator is thread-local, and MPI is
        // told only this thread calls it): under mpirun the command stays here.
        if ranks::launched().is_some() {
            run(cli.command)
        } else {
            settings::on_worker(|| run(cli.command))
        }
    });
    match result {
        Ok(()) => {
            ranks::finish();
            ExitCode::SUCCESS
        }
        Err(e) if ranks::distributed() => ranks::fail(&format!("{e:#}")),
        Err(e) => {
            // The chain once: each error's text says what went wrong at its level, and a
            // library error about a parameter is given the option's name.
            let flag = e.chain().find_map(settings::flag_of);
            let hint = e
                .chain()
                .find_map(settings::hint_of)
                .map_or(String::new(), |h| format!(" ({h})"));
            match flag {
                Some(flag) if !format!("{e:#}").contains(flag) => {
                    eprintln!("radiosity: error: {flag}: {e:#}{hint}")
                }
                _ => eprintln!("radiosity: error: {e:#}{hint}"),
            }
            ranks::finish();
            ExitCode::FAILURE
        }
    }
}

/// A command-line error on one line: for a value that is not one of a flag's possible values,
/// `--flag value: unknown value (possible: …; did you mean 'x'?)`; otherwise clap's message and
/// its tips.
pub fn usage_error(e: &clap::Error) -> String {
    use clap::error::{ContextKind, ContextValue, ErrorKind};
    let text = |kind| match e.get(kind) {
        Some(ContextValue::String(s)) => Some(s.clone()),
        Some(ContextValue::Strings(v)) => Some(v.join(", ")),
        _ => None,
    };
    if e.kind() == ErrorKind::InvalidValue {
        if let (Some(arg), Some(value)) = (
            text(ContextKind::InvalidArg),
            text(ContextKind::InvalidValue),
        ) {
            let flag = arg.split_whitespace().next().unwrap_or(&arg).to_string();
            let mut line = format!("{flag} {value}: unknown value");
            if let Some(valid) = text(ContextKind::ValidValue) {
                line += &format!(" (possible: {valid}");
                if let Some(s) = text(ContextKind::SuggestedValue) {
                    line += &format!("; did you mean '{s}'?");
                }
                line += ")";
            }
            return line;
        }
    }
    let rendered = e.render().to_string();
    rendered
        .lines()
        .map(str::trim)
        .filter(|l| {
            !l.is_empty() && !l.starts_with("Usage:") && !l.starts_with("For more information")
        })
        .map(|l| l.strip_prefix("error: ").unwrap_or(l))
        .collect::<Vec<_>>()
        .join("; ")
}

/// Load the scene named on the command line and print its warnings.
pub fn load_scene(name: &str, one_sided: bool) -> Result<Scene> {
    let scene = scene::load_with(name, &scene::LoadOptions { one_sided })?;
    // Every rank loads the scene; one says what is wrong with it.
    if ranks::is_root() {
        for w in &scene.warnings {
            eprintln!("radiosity: warning: {w}");
        }
    }
    Ok(scene)
}

/// Load and solve, with a progress bar (and the trace, if asked). Under mpirun, the
/// distributed methods (and, over several ranks, every method, to be refused if sequential)
/// run over the ranks, and their report comes back too.
fn solve_scene(a: &SolveArgs) -> Result<(Scene, Solution, Option<radiosity::distributed::Report>)> {
    let settings = settings::settings(a)?;
    let scene = load_scene(&a.scene, a.one_sided)?;
    let progress = report::Progress::new(settings.tolerance());
    let solution = pipeline::solve_over(&scene, &settings, ranks::current(), &progress);
    progress.finish();
    let (solution, distributed) = solution?;
    if let (Some(path), Some(t)) = (&a.trace, &solution.trace) {
        write_text(path, &t.csv()).context("writing the trace")?;
        if a.report == ReportFormat::Text {
            println!("trace       {} ({} rows)", path.display(), t.len());
        }
    }
    Ok((scene, solution, distributed))
}

fn solve_system(a: SolveSystemArgs) -> Result<()> {
    let solver = a.solver.0;
    let params = settings::solver_params(
        a.flags
            .tolerance
            .unwrap_or(radiosity::solve::SolverParams::default().tolerance),
        a.flags.max_iterations,
        a.flags.omega,
        a.flags.photons,
        a.flags.iteration_rays,
        a.flags.gather_rays,
        a.seed,
    )?;
    if FileFormat::from_path(&a.out) != Some(FileFormat::Csv) {
        anyhow::bail!("{}: unsupported output format (use .csv)", a.out.display());
    }
    settings::check_output(&a.out)?;
    if let Some(t) = &a.trace {
        settings::check_output(t)?;
    }
    let mut outputs = vec![("--out", a.out.as_path())];
    outputs.extend(a.trace.as_deref().map(|p| ("--trace", p)));
    settings::distinct_files(
        &[
            ("--matrix", a.matrix.as_path()),
            ("--patches", a.patches.as_path()),
        ],
        &outputs,
    )?;
    let patches = radiosity::io::patches_csv::read(&a.patches)?;
    let mut matrix = radiosity::io::matrix_market::read(&a.matrix)?;
    if matrix.n() != patches.system.len() {
        anyhow::bail!(
            "{}: {} patches, but {} is {} × {}",
            a.patches.display(),
            patches.system.len(),
            a.matrix.display(),
            matrix.n(),
            matrix.n()
        );
    }
    let progress = report::Progress::new(params.tolerance);
    let solved = pipeline::solve_system(
        &patches.system,
        &mut matrix,
        solver,
        &params,
        a.trace.is_some(),
        &progress,
    );
    progress.finish();
    let solved = solved?;
    let info = &solved.info;
    write_radiosity_csv(&a.out, &solved.radiosity, patches.single_channel)?;
    if let (Some(path), Some(t)) = (&a.trace, &solved.trace) {
        write_text(path, &t.csv()).context("writing the trace")?;
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
        solver,
        if info.converged {
            "converged".to_string()
        } else {
            format!(
                "stopped after {} iterations without converging",
                info.iterations
            )
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
    capped_at(a.flags.max_iterations, info, &a.out)
}

/// A solve that the default iteration cap stopped before it converged (the user gave no
/// `--max-iterations`) is an error once its result is written: a non-zero exit, and a line
/// saying what was reached and what to change.
fn capped(a: &SolveArgs, info: &radiosity::solve::Info, out: &std::path::Path) -> Result<()> {
    capped_at(a.flags.max_iterations, info, out)
}

fn capped_at(
    max_iterations: Option<u64>,
    info: &radiosity::solve::Info,
    out: &std::path::Path,
) -> Result<()> {
    if info.converged || max_iterations.is_some() {
        return Ok(());
    }
    anyhow::bail!(
        "{}: the solve did not converge within the default cap of {} iterations (unshot energy left {:.3e} of emitted); the result written is unconverged: give --max-iterations to go further or a larger --tolerance",
        out.display(),
        info.iterations,
        info.unshot_fraction
    )
}

fn solve(a: SolveCmdArgs) -> Result<()> {
    let format = FileFormat::from_path(&a.out);
    let baked = format.is_some_and(FileFormat::is_baked_mesh);
    if format != Some(FileFormat::Csv) && !baked {
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
    for (flag, path) in [
        ("--links-out", &a.links_out),
        ("--elements-out", &a.elements_out),
    ] {
        if let Some(p) = path {
            if a.solve.solver.0.is_some() {
                anyhow::bail!("{flag}: only the hierarchical solver has links and elements (add --solver hierarchical)");
            }
            settings::check_output(p)?;
        }
    }
    let lightmap = solve_lightmap::params(&a)?;
    settings::distinct_files(
        &[("scene", std::path::Path::new(&a.solve.scene))],
        &[
            Some(("--out", a.out.as_path())),
            a.lightmap_out.as_deref().map(|p| ("--lightmap-out", p)),
            a.solve.trace.as_deref().map(|p| ("--trace", p)),
            a.links_out.as_deref().map(|p| ("--links-out", p)),
            a.elements_out.as_deref().map(|p| ("--elements-out", p)),
        ]
        .into_iter()
        .flatten()
        .collect::<Vec<_>>(),
    )?;
    settings::settings(&a.solve)?;
    let (scene, solution, distributed) = solve_scene(&a.solve)?;
    if !ranks::is_root() {
        return Ok(());
    }
    if let Some(h) = &solution.hierarchy {
        if let Some(p) = &a.links_out {
            radiosity::export::write_links_csv(p, &h.hierarchy)?;
            if a.solve.report == ReportFormat::Text {
                println!(
                    "links       {} ({} rows)",
                    p.display(),
                    h.hierarchy.links.len()
                );
            }
        }
        if let Some(p) = &a.elements_out {
            radiosity::export::write_elements_csv(p, &h.hierarchy, &h.root_surfaces)?;
            if a.solve.report == ReportFormat::Text {
                println!(
                    "elements    {} ({} rows)",
                    p.display(),
                    h.hierarchy.elements.items.len()
                );
            }
        }
    }
    let t = Instant::now();
    let mut lightmap_summary = None;
    if let Some(params) = &lightmap {
        let (map, kept, exrs) = solve_lightmap::write(&a, params, &scene, &solution)?;
        lightmap_summary = Some((
            map.width(),
            map.height(),
            map.atlases(),
            map.surface_texels(),
            map.unwrap.texel,
            map.unwrap.charts.len(),
            kept,
            exrs,
        ));
    } else if baked {
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
    if a.solve.report == ReportFormat::Json {
        let mut v = report::summary_json(&scene, &solution, None);
        v["seconds"]["write"] = serde_json::json!(write_s);
        v["out"] = serde_json::json!(a.out);
        if let Some((w, h, atlases, texels, texel, charts, kept, exrs)) = lightmap_summary {
            v["lightmap"] = serde_json::json!({"width": w, "height": h, "atlases": atlases,
                "texels": texels, "texel_size": texel, "charts": charts, "exr": exrs,
                "uv": if kept { "input" } else { "generated" }, "seconds": write_s});
        }
        if let Some(r) = &distributed {
            v["ranks"] = serde_json::json!(r.blocks.len());
            v["bytes_sent"] = serde_json::json!(r.bytes_sent());
        }
        println!("{v}");
        return capped(&a.solve, &solution.info, &a.out);
    }
    report::summary(&scene, &solution, None);
    if let Some(r) = &distributed {
        report::ranks(r);
    }
    if let Some((w, h, atlases, texels, texel, charts, kept, exrs)) = lightmap_summary {
        let atlases = if atlases == 1 {
            "atlas".to_string()
        } else {
            format!("atlases ×{atlases}")
        };
        println!(
            "lightmap    {w}×{h} {atlases}, {texels} surface texels of {texel:.4} scene units in {charts} charts{}",
            if kept {
                " (the input's TEXCOORD_1, kept; mean texel size)"
            } else {
                ""
            }
        );
        let exrs: Vec<String> = exrs.iter().map(|p| p.display().to_string()).collect();
        println!(
            "wrote       {}{} in {write_s:.3} s (bake included)",
            a.out.display(),
            if exrs.is_empty() {
                String::new()
            } else {
                format!(" and {}", exrs.join(", "))
            }
        );
        return capped(&a.solve, &solution.info, &a.out);
    }
    println!(
        "wrote       {} ({} patches) in {write_s:.3} s",
        a.out.display(),
        solution.mesh.len()
    );
    capped(&a.solve, &solution.info, &a.out)
}

/// Show a baked glTF's vertex colours from its camera (or `--eye`/`--target`), as an unlit
/// glTF viewer would: no solving, PNG pixels are the sRGB encoding of COLOR_0. A lightmapped
/// file (`MOZ_lightmap`) is shown lit by its lightmaps, as three.js shows it.
fn view(a: ViewArgs) -> Result<()> {
    let out = a
        .out
        .clone()
        .unwrap_or_else(|| default_output(&a.file.to_string_lossy(), "png"));
    ImageFormat::from_path(&out)?;
    settings::check_output(&out)?;
    settings::distinct_files(&[("file", a.file.as_path())], &[("--out", out.as_path())])?;
    let params = settings::image(&a.image, 1, if a.gather { 16 } else { 4 })?;
    if !matches!(
        FileFormat::from_path(&a.file),
        Some(FileFormat::Glb | FileFormat::Gltf)
    ) {
        anyhow::bail!(
            "{}: view shows baked glTF files (.glb or .gltf)",
            a.file.display()
        );
    }
    if a.gather && a.direct_samples == 0 {
        anyhow::bail!("--direct-samples 0: at least one shadow ray per sample is needed");
    }
    // A lightmapped file (MOZ_lightmap) is shown by its lightmaps; --gather needs the
    // radiosity a vertex bake carries.
    if !a.gather {
        if let Some(baked) = BakedView::load_lightmap(&a.file)? {
            for w in &baked.scene.warnings {
                eprintln!("radiosity: warning: {w}");
            }
            let camera = settings::camera(baked.default_camera(), &a.camera)?;
            let image = baked.render(&camera, &params, &Silent);
            write_image(&out, &image, 1.0).context("writing the image")?;
            let lit = baked.lightmapped_triangles();
            let all = baked.mesh.patches.len();
            let sizes: Vec<String> = baked
                .lightmap
                .iter()
                .flat_map(|l| l.set.images.iter())
                .map(|i| format!("{}×{}", i.width, i.height))
                .collect();
            println!(
                "wrote       {} ({}×{}, {lit} triangles lit by their lightmap ({}){})",
                out.display(),
                params.width,
                params.height,
                sizes.join(", "),
                if lit < all {
                    format!(", {} without one shown black", all - lit)
                } else {
                    String::new()
                }
            );
            return Ok(());
        }
    }
    let which = if a.gather {
        radiosity::scene::gltf::VertexValues::Radiosity
    } else {
        radiosity::scene::gltf::VertexValues::Colour
    };
    let baked = BakedView::load_values(&a.file, which)?;
    for w in &baked.scene.warnings {
        eprintln!("radiosity: warning: {w}");
    }
    let camera = settings::camera(baked.default_camera(), &a.camera)?;
    if a.gather {
        let image = baked.render_gather(
            &camera,
            &params,
            radiosity::render::gather::GatherParams {
                direct: a.direct_samples,
                cache_samples: a.cache_samples,
                ..Default::default()
            },
            &Silent,
        );
        write_image(&out, &image, auto_exposure(&image)).context("writing the image")?;
        println!(
            "wrote       {} ({}×{}, final gather over the baked radiosity of {} triangles)",
            out.display(),
            params.width,
            params.height,
            baked.mesh.patches.len()
        );
        return Ok(());
    }
    let image = baked.render(&camera, &params, &Silent);
    write_image(&out, &image, 1.0).context("writing the image")?;
    println!(
        "wrote       {} ({}×{}, {} triangles shown with their COLOR_0)",
        out.display(),
        params.width,
        params.height,
        baked.mesh.patches.len()
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
