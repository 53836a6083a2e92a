//! `radiosity render`: solve a scene (or, with `--luminaires`, light it by the lighting
//! pipeline) and write a picture: tone-mapped PNG, linear OpenEXR / PFM, or with
//! `--luminance` each pixel's luminance in cd/m².

use crate::args::{IntegratorArg, RenderArgs, ReportFormat, UpArg};
use crate::{capped, default_output, load_scene, report, settings, solve_scene};
use anyhow::{bail, Context, Result};
use radiosity::export::{write_image, ImageFormat};
use radiosity::io::FileFormat;
use radiosity::lighting::{read_schedule, Up};
use radiosity::pipeline::{self, lighting_solution, LightingSettings, Method};
use radiosity::render::gather::GatherParams;
use radiosity::render::{auto_exposure, Image, RenderParams};
use radiosity::scene::Scene;
use std::path::Path;
use std::time::Instant;

/// Run the command.
pub fn run(mut a: RenderArgs) -> Result<()> {
    a.solve.picture = true;
    let out = a
        .out
        .clone()
        .unwrap_or_else(|| default_output(&a.solve.scene, "png"));
    let format = ImageFormat::from_path(&out)?;
    if a.luminance && format == ImageFormat::Png {
        bail!(
            "--luminance: {}: luminance in cd/m² is written to .exr or .pfm (a PNG is tone-mapped)",
            out.display()
        );
    }
    if a.luminaires.is_none() {
        if a.unit.is_some() {
            bail!("--unit: the length unit of a lighting schedule; give --luminaires too");
        }
        if a.vertical.is_some() {
            bail!("--vertical: what 'down' means for a luminaire; give --luminaires too");
        }
    }
    settings::check_output(&out)?;
    if let Some(p) = &a.false_colour {
        if !matches!(ImageFormat::from_path(p), Ok(ImageFormat::Png)) {
            bail!(
                "--false-colour {}: the false-colour picture is a .png",
                p.display()
            );
        }
        if p == &out {
            bail!("--false-colour {}: the same file as --out", p.display());
        }
        settings::check_output(p)?;
    }
    if let Some(t) = &a.solve.trace {
        settings::check_output(t)?;
    }
    let mut outputs = vec![("--out", out.as_path())];
    outputs.extend(a.solve.trace.as_deref().map(|p| ("--trace", p)));
    outputs.extend(a.false_colour.as_deref().map(|p| ("--false-colour", p)));
    let mut inputs = vec![("scene", Path::new(&a.solve.scene))];
    inputs.extend(a.luminaires.as_deref().map(|p| ("--luminaires", p)));
    settings::distinct_files(&inputs, &outputs)?;
    let integrator = if a.gather {
        IntegratorArg::Gather
    } else {
        a.integrator
    };
    let settings = settings::settings(&a.solve)?;
    let default_spp = match integrator {
        IntegratorArg::Path => 256,
        IntegratorArg::Gather => 16,
        IntegratorArg::Radiosity => 4,
    };
    let params = settings::image(&a.image, a.solve.seed, default_spp)?;
    if !a.exposure.is_finite() {
        bail!(
            "--exposure {}: must be a finite number of stops",
            a.exposure
        );
    }
    if a.direct_samples == 0 {
        bail!("--direct-samples 0: at least one shadow ray per sample is needed");
    }
    if !(a.cache_accuracy.is_finite() && a.cache_accuracy > 0.0) {
        bail!(
            "--cache-accuracy {}: must be a positive number",
            a.cache_accuracy
        );
    }
    if !(a.gather_near.is_finite() && a.gather_near >= 0.0) {
        bail!(
            "--gather-near {}: a number of patch sizes, at least 0",
            a.gather_near
        );
    }
    let gather = GatherParams {
        direct: a.direct_samples,
        indirect: a.indirect_samples,
        near: a.gather_near,
        cache_samples: a.cache_samples,
        cache_accuracy: a.cache_accuracy,
    };
    if a.luminaires.is_some() {
        return luminaires(&a, &out, integrator, &settings, &params, gather);
    }
    if integrator == IntegratorArg::Path {
        let scene = load_scene(&a.solve.scene, a.solve.one_sided)?;
        let camera = settings::camera(default_camera_unsolved(&scene), &a.camera)?;
        let t = Instant::now();
        let progress = report::Progress::new(settings.tolerance());
        let image = pipeline::path_trace(&scene, &camera, &params, &progress);
        progress.finish();
        let image = image?;
        let render_s = t.elapsed().as_secs_f64();
        write_picture(
            &out,
            &image,
            a.luminance,
            a.exposure,
            a.false_colour.as_deref(),
        )?;
        if a.solve.report == ReportFormat::Json {
            let res = report::resources();
            let v = serde_json::json!({
                "scene": scene.name,
                "polygons": scene.polygons.len(),
                "integrator": "path",
                "samples_per_pixel": params.samples_per_pixel,
                "seconds": { "render": render_s },
                "cpu_seconds": res.map(|r| r.0),
                "memory": { "peak_resident_bytes": res.map(|r| r.1) },
                "luminance": a.luminance,
                "out": out,
            });
            println!("{v}");
            return Ok(());
        }
        println!(
            "path traced {} in {render_s:.2} s ({} paths per pixel)",
            scene.place(),
            params.samples_per_pixel
        );
        if let Some((cpu, _)) = report::resources() {
            println!("cpu         {cpu:.2} s (user and system, all threads)");
        }
        println!(
            "wrote       {} ({}×{}{})",
            out.display(),
            params.width,
            params.height,
            luminance_note(a.luminance)
        );
        return Ok(());
    }
    let (scene, solution, _) = solve_scene(&a.solve)?;
    let camera = settings::camera(solution.default_camera(&scene), &a.camera)?;
    let t = Instant::now();
    let progress = report::Progress::new(settings.tolerance());
    let image = match integrator {
        IntegratorArg::Gather => solution.render_gather(&camera, &params, gather, &progress),
        _ => solution.render(&camera, &params, &progress),
    };
    progress.finish();
    let render_s = t.elapsed().as_secs_f64();
    let t = Instant::now();
    write_picture(
        &out,
        &image,
        a.luminance,
        a.exposure,
        a.false_colour.as_deref(),
    )?;
    let write_s = t.elapsed().as_secs_f64();
    if a.solve.report == ReportFormat::Json {
        let mut v = report::summary_json(&scene, &solution, Some((render_s, write_s)));
        v["integrator"] = serde_json::json!(match integrator {
            IntegratorArg::Gather => "gather",
            _ => "radiosity",
        });
        v["samples_per_pixel"] = serde_json::json!(params.samples_per_pixel);
        v["luminance"] = serde_json::json!(a.luminance);
        v["out"] = serde_json::json!(out);
        println!("{v}");
        return Ok(());
    }
    report::summary(&scene, &solution, Some((render_s, write_s)));
    println!(
        "wrote       {} ({}×{}, {} samples per pixel{}{})",
        out.display(),
        params.width,
        params.height,
        params.samples_per_pixel,
        if integrator == IntegratorArg::Gather {
            format!(
                ", gather {} direct + {} indirect rays each",
                a.direct_samples, a.indirect_samples
            )
        } else {
            String::new()
        },
        luminance_note(a.luminance)
    );
    capped(&a.solve, &solution.info, &out)
}

/// `, luminance in cd/m²` when the picture holds luminance.
fn luminance_note(luminance: bool) -> &'static str {
    if luminance {
        ", luminance in cd/m²"
    } else {
        ""
    }
}

/// Write the picture: a PNG tone-mapped by automatic exposure adjusted by `exposure` stops,
/// an OpenEXR or PFM linear; with `luminance` (OpenEXR or PFM) each pixel's photometric Y in
/// all three channels. Returns the luminance values when they were written: the buffer a
/// false-colour picture is to be drawn from.
fn write_picture(
    out: &Path,
    image: &Image,
    luminance: bool,
    exposure: f32,
    false_colour: Option<&Path>,
) -> Result<Option<Vec<f32>>> {
    if luminance {
        let y = image.luminance();
        let grey = Image::grey(image.width, image.height, &y)
            .context("the luminance picture has one value a pixel")?;
        if let Some(p) = false_colour {
            let values: Vec<f64> = y.iter().map(|&v| v as f64).collect();
            let mut sorted: Vec<f32> = y.iter().copied().filter(|v| v.is_finite()).collect();
            sorted.sort_unstable_by(f32::total_cmp);
            let median = sorted.get(sorted.len() / 2).copied().unwrap_or(0.0);
            let max = sorted.last().copied().unwrap_or(0.0);
            let title = format!(
                "luminance of {}",
                out.file_name().map_or_else(
                    || out.display().to_string(),
                    |n| n.to_string_lossy().into_owned()
                )
            );
            let caption = format!("median {median:.3} cd/m², max {max:.3} cd/m²");
            crate::false_colour::write_raster_png(
                p,
                &crate::false_colour::Raster {
                    width: image.width as usize,
                    height: image.height as usize,
                    values: &values,
                    unit: "cd/m²",
                    title: &title,
                    caption: &caption,
                    scale: crate::false_colour::Scale::Log,
                },
            )?;
        }
        write_image(out, &grey, 1.0).context("writing the image")?;
        return Ok(Some(y));
    }
    let scale = auto_exposure(image) * 2f32.powf(exposure);
    write_image(out, image, scale).context("writing the image")?;
    Ok(None)
}

/// `render --luminaires`: the lighting pipeline's solution (the luminaires' first shot into
/// the patches, the interreflection) seen by the camera, each sample's direct light from the
/// luminaires exact, the interreflected gathered.
fn luminaires(
    a: &RenderArgs,
    out: &Path,
    integrator: IntegratorArg,
    settings: &pipeline::Settings,
    params: &RenderParams,
    gather: GatherParams,
) -> Result<()> {
    if integrator != IntegratorArg::Gather {
        bail!(
            "--luminaires: the picture is made by final gather (--integrator gather); the {} integrator does not take luminaires",
            match integrator {
                IntegratorArg::Path => "path",
                _ => "radiosity",
            }
        );
    }
    if a.solve.trace.is_some() {
        bail!("--trace: the lighting pipeline's interreflection keeps no trace; leave out --trace or --luminaires");
    }
    let Method::Uniform(u) = settings.method else {
        bail!("--luminaires: the interreflection is solved on uniform patches; the hierarchical solver does not take luminaires");
    };
    let schedule = a.luminaires.as_deref().context("--luminaires")?;
    // A glTF scene is y-up, and its own lights (KHR_lights_punctual, EXT_lights_ies) light
    // it beside the schedule's, as in `lighting`.
    let is_gltf = matches!(
        FileFormat::from_path(Path::new(&a.solve.scene)),
        Some(FileFormat::Gltf | FileFormat::Glb)
    );
    let up = match (a.vertical, is_gltf) {
        (Some(UpArg::Z), true) => {
            bail!(
                "--vertical z: {} is glTF, whose scenes are always y-up",
                a.solve.scene
            )
        }
        (Some(UpArg::Y), _) | (None, true) => Up::Y,
        (Some(UpArg::Z), false) | (None, false) => Up::Z,
    };
    let unit = a.unit.unwrap_or(crate::args::UnitArg::M).metres();
    let mut lums = read_schedule(schedule, up)?;
    if is_gltf {
        let (own, warnings) = radiosity::lighting::gltf_luminaires(Path::new(&a.solve.scene))?;
        for w in warnings {
            eprintln!("radiosity: warning: {w}");
        }
        lums.extend(own);
    }
    crate::lighting::warn_photometry(&lums);
    let scene = load_scene(&a.solve.scene, a.solve.one_sided)?;
    let lighting = LightingSettings {
        mesh: u.mesh,
        form_factors: u.form_factors,
        solver: u.solver,
        params: u.params,
        unit_metres: unit,
        memory_limit: settings.memory_limit,
        ..LightingSettings::default()
    };
    let t = Instant::now();
    let progress = report::Progress::new(settings.tolerance());
    let solved = lighting_solution(&scene, &lums, &[], &lighting, &progress);
    progress.finish();
    let (result, solution) = solved?;
    let lighting_s = t.elapsed().as_secs_f64();
    if !result.converged {
        eprintln!(
            "radiosity: warning: the interreflection stopped before its tolerance {}; the picture shows the light shot so far",
            u.params.tolerance
        );
    }
    let camera = settings::camera(solution.default_camera(&scene), &a.camera)?;
    let t = Instant::now();
    let progress = report::Progress::new(settings.tolerance());
    let image = solution.render(&camera, params, gather, &progress);
    progress.finish();
    let image = image?;
    let render_s = t.elapsed().as_secs_f64();
    let t = Instant::now();
    write_picture(
        out,
        &image,
        a.luminance,
        a.exposure,
        a.false_colour.as_deref(),
    )?;
    let write_s = t.elapsed().as_secs_f64();
    if a.solve.report == ReportFormat::Json {
        let res = report::resources();
        let v = serde_json::json!({
            "scene": scene.name,
            "polygons": scene.polygons.len(),
            "patches": result.patches,
            "luminaires": lums.len(),
            "groups": result.groups,
            "books": crate::lighting::books_json(&result.groups, &result.books),
            "converged": result.converged,
            "integrator": "gather",
            "samples_per_pixel": params.samples_per_pixel,
            "seconds": { "lighting": lighting_s, "render": render_s, "write": write_s },
            "cpu_seconds": res.map(|r| r.0),
            "memory": { "peak_resident_bytes": res.map(|r| r.1) },
            "luminance": a.luminance,
            "out": out,
        });
        println!("{v}");
        return Ok(());
    }
    println!(
        "scene       {} ({} polygons, {} patches)",
        scene.name,
        scene.polygons.len(),
        result.patches
    );
    println!(
        "light       {} luminaires in {} group{}: {}",
        lums.len(),
        result.groups.len(),
        if result.groups.len() == 1 { "" } else { "s" },
        result.groups.join(", ")
    );
    crate::lighting::print_books(&result.groups, &result.books);
    println!(
        "time        lighting {lighting_s:.3} s, picture {render_s:.3} s, write {write_s:.3} s"
    );
    if let Some((cpu, _)) = report::resources() {
        println!("cpu         {cpu:.2} s (user and system, all threads)");
    }
    println!(
        "wrote       {} ({}×{}, {} samples per pixel, gather {} direct + {} indirect rays each{})",
        out.display(),
        params.width,
        params.height,
        params.samples_per_pixel,
        a.direct_samples,
        a.indirect_samples,
        luminance_note(a.luminance)
    );
    Ok(())
}

/// The camera for a scene rendered without a solution: its own, else from inside when it is
/// an interior with a known vertical, else framing it (as [`pipeline::Solution::default_camera`]).
fn default_camera_unsolved(scene: &Scene) -> radiosity::scene::Camera {
    match (scene.camera, scene.up) {
        (Some(c), _) => c,
        (None, Some(up)) => {
            match radiosity::mesh::Mesh::build(scene, radiosity::mesh::MeshParams::Faces) {
                Ok(mesh) => {
                    let bvh = radiosity::accel::Bvh::build(&mesh);
                    radiosity::render::camera::default_camera(&bvh, up)
                }
                Err(_) => scene.camera_or_default(),
            }
        }
        (None, None) => scene.camera_or_default(),
    }
}
