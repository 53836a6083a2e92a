//! Arguments to library settings, with the checks that span several flags.

use crate::args::{CameraArgs, ImageArgs, SolveArgs};
use anyhow::{bail, Context, Result};
use radiosity::formfactor::{FormFactorError, Parameter, Params as FormFactorParams};
use radiosity::geom::Vec3;
use radiosity::hierarchical::{
    HierarchicalError, Parameter as HierarchicalParameter, Params as HierarchicalParams,
};
use radiosity::mesh::{MeshParamError, MeshParams};
use radiosity::pipeline::{Settings, Uniform};
use radiosity::scene::Camera;
use radiosity::solve::Solver;
use radiosity::solve::{Parameter as SolverParameter, SolveError, SolverParams};
use std::path::Path;

/// `--patches N` or `--max-edge L` (checked), else `default`.
pub fn mesh_params(
    patches: Option<usize>,
    max_edge: Option<f32>,
    default: MeshParams,
) -> Result<MeshParams> {
    let p = match (patches, max_edge) {
        (_, Some(l)) => MeshParams::MaxEdge(l),
        (Some(n), _) => MeshParams::Patches(n),
        (None, None) => default,
    };
    p.validate().map_err(|e| match e {
        MeshParamError::NoPatches => anyhow::anyhow!("--patches 0: at least one patch is needed"),
        MeshParamError::MaxEdge(l) => anyhow::anyhow!("--max-edge {l}: must be a positive length"),
    })?;
    Ok(p)
}

/// `--resolution`, `--samples` and `--rays` (when given) in range, by the library's check.
pub fn form_factor_numbers(resolution: u32, samples: u32, rays: Option<u32>) -> Result<()> {
    FormFactorParams {
        resolution,
        samples,
        rays: rays.unwrap_or(1),
        ..FormFactorParams::default()
    }
    .validate()
    .map_err(flag_error_of_form_factors)
}

/// `--accuracy` in range, by the library's check.
pub fn accuracy(accuracy: f64) -> Result<()> {
    FormFactorParams {
        accuracy,
        ..FormFactorParams::default()
    }
    .validate()
    .map_err(flag_error_of_form_factors)
}

/// A form-factor parameter error as the flag's one-line message.
fn flag_error_of_form_factors(e: FormFactorError) -> anyhow::Error {
    match e {
        FormFactorError::Parameter {
            parameter,
            value,
            min,
            max,
            ..
        } => anyhow::anyhow!(
            "{} {value}: must be in [{min}, {max}] ({parameter})",
            match parameter {
                Parameter::Resolution => "--resolution",
                Parameter::Samples => "--samples",
                Parameter::Rays => "--rays",
            }
        ),
        FormFactorError::Accuracy { value, min, max } => {
            anyhow::anyhow!("--accuracy {value}: must be in [{min:e}, {max}]")
        }
    }
}

/// Library settings from the shared solve options.
pub fn settings(a: &SolveArgs) -> Result<Settings> {
    let mesh = mesh_params(a.patches, a.max_edge, MeshParams::default())?;
    if a.rays == 0 {
        bail!("--rays 0: at least one ray per form-factor row is needed");
    }
    form_factor_numbers(a.resolution, a.samples, None)?;
    let form_factors = FormFactorParams {
        method: a.form_factors.0,
        resolution: a.resolution,
        samples: a.samples,
        rays: a.rays,
        ..FormFactorParams::shooting()
    };
    form_factors.validate().map_err(flag_error)?;
    let tolerance = a.flags.tolerance.unwrap_or(if a.picture {
        SolverParams::PICTURE_TOLERANCE
    } else {
        SolverParams::default().tolerance
    });
    let hierarchical = match a.solver.0 {
        Some(_) => None,
        None => {
            if a.trace.is_some() {
                bail!("--trace: the hierarchical solver has no stored matrix to trace against; use a linear-system solver");
            }
            let defaults = HierarchicalParams::default();
            let p = HierarchicalParams {
                link_error: a.link_error,
                min_area: a.min_area.unwrap_or(0.0),
                visibility_rays: a.visibility_rays,
                max_passes: a.passes,
                tolerance,
                max_iterations: a.flags.max_iterations.unwrap_or(defaults.max_iterations),
                ..defaults
            };
            if a.min_area == Some(0.0) {
                bail!("--min-area 0: must be a positive area");
            }
            if a.passes == 0 {
                bail!("--passes 0: at least one refinement pass is needed");
            }
            p.validate().map_err(|e| match flag_of(&e) {
                Some(flag) => anyhow::anyhow!("{flag}: {e}"),
                None => e.into(),
            })?;
            Some(p)
        }
    };
    // Every solver flag is checked, whichever method reads it.
    let params = solver_params(
        tolerance,
        a.flags.max_iterations,
        a.flags.omega,
        a.flags.photons,
        a.flags.iteration_rays,
        a.flags.gather_rays,
        a.seed,
    )?;
    let mut settings = match hierarchical {
        Some(p) => Settings::from(p),
        None => Settings::from(Uniform {
            mesh,
            form_factors,
            rows: a.rows.into(),
            solver: a.solver.0.unwrap_or(Solver::Progressive),
            params,
            trace: a.trace.is_some(),
        }),
    };
    settings.set_seed(a.seed);
    Ok(settings)
}

/// The option a library parameter error is about, for messages that name it.
pub fn flag_of(e: &(dyn std::error::Error + 'static)) -> Option<&'static str> {
    if let Some(FormFactorError::Parameter { parameter, .. }) = e.downcast_ref() {
        return Some(match parameter {
            Parameter::Resolution => "--resolution",
            Parameter::Samples => "--samples",
            Parameter::Rays => "--rays",
        });
    }
    if let Some(FormFactorError::Accuracy { .. }) = e.downcast_ref() {
        return Some("--accuracy");
    }
    if let Some(HierarchicalError::Parameter { parameter, .. }) = e.downcast_ref() {
        return Some(match parameter {
            HierarchicalParameter::LinkError => "--link-error",
            HierarchicalParameter::MinArea => "--min-area",
            HierarchicalParameter::VisibilityRays => "--visibility-rays",
            HierarchicalParameter::Tolerance => "--tolerance",
        });
    }
    if let Some(SolveError::Parameter { parameter, .. }) = e.downcast_ref() {
        return Some(solver_flag(*parameter));
    }
    None
}

/// The option of a solver parameter.
fn solver_flag(p: SolverParameter) -> &'static str {
    match p {
        SolverParameter::Tolerance => "--tolerance",
        SolverParameter::Omega => "--omega",
        SolverParameter::Photons => "--photons",
        SolverParameter::IterationRays => "--iteration-rays",
        SolverParameter::GatherRays => "--gather-rays",
    }
}

/// The options that answer a library error about memory, for a hint after the message.
pub fn hint_of(e: &(dyn std::error::Error + 'static)) -> Option<&'static str> {
    match e.downcast_ref::<radiosity::Error>() {
        Some(radiosity::Error::OutOfMemory {
            stored_rows: true, ..
        }) => Some("--solver progressive, --patches N or --rays N"),
        Some(radiosity::Error::OutOfMemory { .. }) => Some("--patches N or --max-edge L"),
        _ => None,
    }
}

/// A library parameter error, prefixed with the option it is about.
fn flag_error(e: FormFactorError) -> anyhow::Error {
    match flag_of(&e) {
        Some(flag) => anyhow::anyhow!("{flag}: {e}"),
        None => e.into(),
    }
}

/// Solver parameters from the flags, checked.
pub fn solver_params(
    tolerance: f64,
    max_iterations: Option<u64>,
    omega: f64,
    photons: u32,
    iteration_rays: u32,
    gather_rays: u32,
    seed: u64,
) -> Result<SolverParams> {
    let params = SolverParams {
        tolerance,
        max_iterations: max_iterations.unwrap_or(u64::MAX),
        omega,
        photons,
        iteration_rays,
        gather_rays,
        seed,
        ..Default::default()
    };
    params.validate().map_err(|e| match e {
        radiosity::solve::SolveError::Parameter {
            parameter,
            value,
            range,
        } => anyhow::anyhow!(
            "{} {value}: must be in {range} ({parameter})",
            solver_flag(parameter)
        ),
        e => e.into(),
    })?;
    Ok(params)
}

fn vec3(flag: &str, s: &str) -> Result<Vec3> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    if parts.len() != 3 {
        bail!("--{flag} {s}: expected three comma-separated numbers x,y,z");
    }
    let mut v = [0f32; 3];
    for (k, p) in parts.iter().enumerate() {
        v[k] = p
            .parse::<f32>()
            .ok()
            .filter(|x| x.is_finite())
            .with_context(|| format!("--{flag} {s}: '{p}' is not a finite number"))?;
    }
    Ok(Vec3::from_array(v))
}

/// The camera: the scene's (or a framing default) with the flags' overrides.
pub fn camera(base: Camera, a: &CameraArgs) -> Result<Camera> {
    let mut c = base;
    if let Some(s) = &a.eye {
        c.eye = vec3("eye", s)?;
    }
    if let Some(s) = &a.target {
        c.target = vec3("target", s)?;
    }
    if let Some(s) = &a.up {
        c.up = vec3("up", s)?;
    }
    if let Some(f) = a.fov {
        c.fov_y_deg = f;
    }
    c.validate().map_err(|m| anyhow::anyhow!("camera: {m}"))?;
    Ok(c)
}

/// Render parameters from `--width`, `--height` and `--spp` (each at least 1).
pub fn image(
    a: &ImageArgs,
    seed: u64,
    default_spp: u32,
) -> Result<radiosity::render::RenderParams> {
    let spp = a.spp.unwrap_or(default_spp);
    if a.width == 0 || a.height == 0 {
        bail!(
            "--width {} --height {}: the image needs at least one pixel",
            a.width,
            a.height
        );
    }
    if spp == 0 {
        bail!("--spp 0: at least one sample per pixel is needed");
    }
    if a.width > MAX_IMAGE_SIDE || a.height > MAX_IMAGE_SIDE {
        bail!(
            "--width {} --height {}: at most {MAX_IMAGE_SIDE} pixels a side",
            a.width,
            a.height
        );
    }
    // The float image, its 8-bit or encoded copy: about 24 bytes a pixel.
    let needed = 24 * a.width as u64 * a.height as u64;
    if let Some(free) = radiosity::pipeline::available_memory() {
        if needed > free / 2 {
            bail!(
                "--width {} --height {}: the image would need about {} MiB, more than half the {} MiB available",
                a.width,
                a.height,
                needed >> 20,
                free >> 20
            );
        }
    }
    Ok(radiosity::render::RenderParams {
        width: a.width,
        height: a.height,
        samples_per_pixel: spp,
        seed,
    })
}

/// Fail early, before any work, if `path` cannot be an output: its folder must exist.
pub fn check_output(path: &Path) -> Result<()> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    if !dir.is_dir() {
        bail!(
            "{}: folder '{}' does not exist",
            path.display(),
            dir.display()
        );
    }
    if path.is_dir() {
        bail!("{}: is a folder, not a file name", path.display());
    }
    Ok(())
}

/// Largest image side, pixels.
pub const MAX_IMAGE_SIDE: u32 = 32768;

/// Most worker threads.
pub const MAX_THREADS: usize = 1024;

/// Stack of each worker thread. The command itself runs on a worker ([`on_worker`]), so its
/// serial parts (recursive parsers, tree builds) get more than the main thread's usual 8 MiB;
/// it is address space, not memory, until used.
const WORKER_STACK: usize = 64 << 20;

/// Start the global pool with `t` worker threads (rayon's default, one per core or
/// `RAYON_NUM_THREADS`, when `None`). Called once by `main` before the command runs; a later
/// call with the same count is a no-op, so the commands can state their count again.
pub fn threads(t: Option<usize>) -> Result<()> {
    if let Some(t) = t {
        if t == 0 {
            bail!("--threads 0: at least one thread is needed");
        }
        if t > MAX_THREADS {
            bail!("--threads {t}: at most {MAX_THREADS}");
        }
    }
    static STARTED: std::sync::OnceLock<usize> = std::sync::OnceLock::new();
    if let Some(&n) = STARTED.get() {
        if t.is_none_or(|t| t == n) {
            return Ok(());
        }
        bail!(
            "--threads {}: the worker pool already has {n} threads",
            t.unwrap_or(n)
        );
    }
    rayon::ThreadPoolBuilder::new()
        .num_threads(t.unwrap_or(0))
        .stack_size(WORKER_STACK)
        .build_global()
        .context("could not start the worker threads")?;
    let _ = STARTED.set(rayon::current_num_threads());
    Ok(())
}

/// Run `f` on a worker of the global pool and wait for it.
///
/// A solve that alternates short parallel steps with serial ones (progressive refinement: one
/// shot's rays in parallel, then its receivers' bookkeeping, 10⁵–10⁶ times) pays for every
/// parallel step started from outside the pool: the caller queues the work, wakes a worker and
/// sleeps until it is done. Started from a worker, the step is pushed on the worker's own queue
/// and the other workers take from it while still spinning: the same output, sooner
/// (docs/notes/workbench.md).
pub fn on_worker<T: Send>(f: impl FnOnce() -> T + Send) -> T {
    rayon::scope(|_| f())
}

/// What a path names, for telling whether two paths are one file: the canonical path of an
/// existing file (so `./a.csv`, `a.csv`, `dir/../a.csv` and a symbolic link to it agree), or the
/// canonical folder and the name of a file still to be made. On Unix an existing file is also
/// known by its device and inode, which catches hard links.
#[derive(Debug, Clone, PartialEq, Eq)]
enum FileIdentity {
    Existing {
        path: std::path::PathBuf,
        inode: Option<(u64, u64)>,
        regular: bool,
    },
    New(std::path::PathBuf),
}

impl FileIdentity {
    fn of(path: &Path) -> Option<Self> {
        if let Ok(meta) = std::fs::metadata(path) {
            #[cfg(unix)]
            let inode = {
                use std::os::unix::fs::MetadataExt;
                Some((meta.dev(), meta.ino()))
            };
            #[cfg(not(unix))]
            let inode = None;
            let path = std::fs::canonicalize(path).ok()?;
            return Some(FileIdentity::Existing {
                path,
                inode,
                regular: meta.is_file(),
            });
        }
        // A new file (or a dangling link: the link's own place is what a write would replace).
        let dir = match path.parent() {
            Some(d) if !d.as_os_str().is_empty() => d,
            _ => Path::new("."),
        };
        let dir = std::fs::canonicalize(dir).ok()?;
        Some(FileIdentity::New(dir.join(path.file_name()?)))
    }

    fn same(&self, other: &Self) -> bool {
        match (self, other) {
            (
                FileIdentity::Existing {
                    path: a, inode: ia, ..
                },
                FileIdentity::Existing {
                    path: b, inode: ib, ..
                },
            ) => a == b || (ia.is_some() && ia == ib),
            (FileIdentity::New(a), FileIdentity::New(b)) => a == b,
            _ => false,
        }
    }

    /// A device or a pipe (`/dev/null`, `/dev/stdout`): several outputs may share it.
    fn is_special(&self) -> bool {
        matches!(self, FileIdentity::Existing { regular: false, .. })
    }
}

/// Refuse, before any work, an output that is one of the command's inputs or another of its
/// outputs: the same file by identity (canonical paths, hard links), however it is spelt.
/// `inputs` and `outputs` pair each path with the flag or place that names it (`"--boundary"`,
/// `"the scene"`); the message names both and the file. A device or pipe (`/dev/null`) may
/// take several outputs; a path that cannot be resolved (its folder is missing) is left to
/// [`check_output`]'s message.
pub fn distinct_files(inputs: &[(&str, &Path)], outputs: &[(&str, &Path)]) -> Result<()> {
    let ins: Vec<(&str, &Path, FileIdentity)> = inputs
        .iter()
        .filter_map(|&(f, p)| FileIdentity::of(p).map(|id| (f, p, id)))
        // An input that is not a file (a built-in scene's name) cannot be overwritten.
        .filter(|(_, _, id)| matches!(id, FileIdentity::Existing { .. }))
        .collect();
    let mut seen: Vec<(&str, &Path, FileIdentity)> = Vec::new();
    for &(flag, path) in outputs {
        let Some(id) = FileIdentity::of(path) else {
            continue;
        };
        if let Some((f, p, _)) = ins.iter().find(|(_, _, i)| i.same(&id)) {
            bail!(
                "{flag} {}: is the input {f} {}; writing it would destroy the input (choose another output file)",
                path.display(),
                p.display()
            );
        }
        if !id.is_special() {
            if let Some((f, p, _)) = seen.iter().find(|(_, _, i)| i.same(&id)) {
                bail!(
                    "{flag} {}: is also {f} {}; each output needs its own file",
                    path.display(),
                    p.display()
                );
            }
        }
        seen.push((flag, path, id));
    }
    Ok(())
}

/// [`distinct_files`] for `form-factors`: the scene (when it is a file) against `-o` and the
/// optional `--patches-out`. The command calls it after its output checks, before any work.
pub fn form_factor_files(scene: &str, out: &Path, patches_out: Option<&Path>) -> Result<()> {
    let scene = Path::new(scene);
    let mut outputs = vec![("-o", out)];
    if let Some(p) = patches_out {
        outputs.push(("--patches-out", p));
    }
    distinct_files(&[("scene", scene)], &outputs)
}

/// Refuse, in one line and before any work, a dense View3D exchange-factor table
/// (`--format view3d` with emissivities: Hottel's script-F needs the dense inverse) whose
/// memory, [`radiosity::io::view3d::script_f_bytes`], passes half of what is available. The plain
/// view-factor table needs no dense copy when written with
/// [`radiosity::io::view3d::write_rows`].
pub fn dense_exchange_memory(surfaces: usize) -> Result<()> {
    let needed = radiosity::io::view3d::script_f_bytes(surfaces);
    if let Some(free) = radiosity::pipeline::available_memory() {
        if needed > free / 2 {
            bail!(
                "--format view3d: the total exchange factors of {surfaces} surfaces need a dense inverse of about {} MiB, more than half the {} MiB available; write view factors without emissivities, or Matrix Market",
                needed >> 20,
                free >> 20
            );
        }
    }
    Ok(())
}
