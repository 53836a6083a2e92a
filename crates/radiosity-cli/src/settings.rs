//! Arguments to library settings, with the checks that span several flags.

use crate::args::{CameraArgs, SolveArgs};
use anyhow::{bail, Context, Result};
use radiosity::formfactor::monte_carlo::MonteCarloParams;
use radiosity::geom::Vec3;
use radiosity::mesh::MeshParams;
use radiosity::pipeline::Settings;
use radiosity::scene::Camera;
use radiosity::solve::progressive::ProgressiveParams;
use std::path::Path;

/// Library settings from the shared solve options.
pub fn settings(a: &SolveArgs) -> Result<Settings> {
    let mesh = match (a.patches, a.max_edge) {
        (_, Some(l)) if !(l.is_finite() && l > 0.0) => {
            bail!("--max-edge {l}: must be a positive length")
        }
        (_, Some(l)) => MeshParams::MaxEdge(l),
        (Some(0), _) => bail!("--patches 0: at least one patch is needed"),
        (Some(n), _) => MeshParams::Patches(n),
        (None, None) => MeshParams::default(),
    };
    if a.rays == 0 {
        bail!("--rays 0: at least one ray per form-factor row is needed");
    }
    if !(a.tolerance.is_finite() && a.tolerance > 0.0 && a.tolerance < 1.0) {
        bail!("--tolerance {}: must be in (0, 1)", a.tolerance);
    }
    if a.threads == Some(0) {
        bail!("--threads 0: at least one thread is needed");
    }
    Ok(Settings {
        mesh,
        monte_carlo: MonteCarloParams {
            rays: a.rays,
            seed: a.seed,
            ..Default::default()
        },
        progressive: ProgressiveParams {
            tolerance: a.tolerance,
            max_iterations: a.max_iterations.unwrap_or(u64::MAX),
        },
        memory_limit: 0,
    })
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

/// Set the worker-thread count of the global pool.
pub fn threads(t: Option<usize>) -> Result<()> {
    if let Some(t) = t {
        if t == 0 {
            bail!("--threads 0: at least one thread is needed");
        }
        rayon::ThreadPoolBuilder::new()
            .num_threads(t)
            .build_global()
            .context("could not start the worker threads")?;
    }
    Ok(())
}
