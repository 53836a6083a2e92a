//! `radiosity thermal`: net radiative heat transfer between grey diffuse surfaces.

use crate::args::{EnclosureArg, LinearSolverArg, ThermalArgs};
use anyhow::{bail, Result};
use radiosity::formfactor::{enforce, summary, Enforce, FormFactorMethod, Params, Storage};
use radiosity::io::FileFormat;
use radiosity::mesh::MeshParams;
use radiosity::scene::vs3;
use radiosity::thermal::{
    self, read_boundary_csv, Boundary, Condition, LinearSolver, ThermalParams, ThermalSystem,
};
use std::collections::HashMap;
use std::fmt::Write as _;
use std::path::Path;

/// Default Monte Carlo rays per row for `n` patches: 10⁶ up to 100 patches, then a total of
/// 10⁸ rays shared out, but at least 10⁴ a row (each facet's irradiation then has a relative
/// standard error of at most 1 % of the spread of the radiosities it sees).
pub fn default_rays(n: usize) -> u32 {
    (1e8 / n.max(1) as f64).clamp(1e4, 1e6) as u32
}

fn csv_name(name: &str) -> String {
    if name.contains([',', '"', '\n']) {
        format!("\"{}\"", name.replace('"', "\"\""))
    } else {
        name.to_string()
    }
}

/// Run the command.
pub fn run(a: ThermalArgs) -> Result<()> {
    for (p, what) in [(&a.out, "--out"), (&a.boundary, "--boundary")] {
        if FileFormat::from_path(p) != Some(FileFormat::Csv) {
            bail!("{what} {}: must be a .csv file", p.display());
        }
    }
    crate::settings::check_output(&a.out)?;
    if let Some(p) = &a.patches_out {
        if FileFormat::from_path(p) != Some(FileFormat::Csv) {
            bail!("--patches-out {}: must be a .csv file", p.display());
        }
        crate::settings::check_output(p)?;
    }
    if !(a.environment.is_finite() && a.environment >= 0.0) {
        bail!(
            "--environment {}: a temperature in kelvin, at least 0",
            a.environment
        );
    }
    if a.resolution < 2 {
        bail!(
            "--resolution {}: at least 2 pixels along a face are needed",
            a.resolution
        );
    }
    if a.samples == 0 {
        bail!("--samples 0: at least one point per patch is needed");
    }
    if a.rays == Some(0) {
        bail!("--rays 0: at least one ray per row is needed");
    }
    let mesh_params = match (a.patches, a.max_edge) {
        (_, Some(l)) if !(l.is_finite() && l > 0.0) => {
            bail!("--max-edge {l}: must be a positive length")
        }
        (_, Some(l)) => MeshParams::MaxEdge(l),
        (Some(0), _) => bail!("--patches 0: at least one patch is needed"),
        (Some(n), _) => MeshParams::Patches(n),
        (None, None) => MeshParams::Faces,
    };
    crate::settings::threads(a.threads)?;

    // The scene, and what View3D's file says of its surfaces.
    let is_vs3 = FileFormat::from_path(Path::new(&a.scene)) == Some(FileFormat::Vs3)
        && Path::new(&a.scene).exists();
    let (scene, vs3) = if is_vs3 {
        let v = vs3::load(Path::new(&a.scene))?;
        for w in &v.scene.warnings {
            eprintln!("radiosity: warning: {w}");
        }
        (v.scene.clone(), Some(v))
    } else {
        (crate::load_scene(&a.scene, a.one_sided)?, None)
    };
    scene.validate_geometry()?;

    // Boundary conditions by material.
    let rows = read_boundary_csv(&a.boundary)?;
    let mut used = vec![false; scene.materials.len()];
    for p in &scene.polygons {
        used[p.material] = true;
    }
    let by_name: HashMap<&str, usize> = scene
        .materials
        .iter()
        .enumerate()
        .filter(|(m, _)| used[*m])
        .map(|(m, mat)| (mat.name.as_str(), m))
        .collect();
    let mut boundary_of = vec![usize::MAX; scene.materials.len()];
    let mut boundaries = Vec::with_capacity(rows.len());
    for (k, r) in rows.iter().enumerate() {
        let Some(&m) = by_name.get(r.name.as_str()) else {
            let combined = vs3.as_ref().and_then(|v| {
                v.surfaces
                    .iter()
                    .find(|s| s.name == r.name && s.combined_into.is_some())
                    .map(|s| v.surfaces[s.combined_into.unwrap_or(0)].name.clone())
            });
            let hint = match combined {
                Some(t) => format!("it is combined into '{t}' (cmb); name that surface"),
                None => {
                    let mut names: Vec<&str> = by_name.keys().copied().collect();
                    names.sort_unstable();
                    let shown = names.len().min(20);
                    format!(
                        "the scene's surfaces are: {}{}",
                        names[..shown].join(", "),
                        if names.len() > shown {
                            format!(" and {} more", names.len() - shown)
                        } else {
                            String::new()
                        }
                    )
                }
            };
            bail!(
                "{}:{}: unknown surface '{}'; {hint}",
                a.boundary.display(),
                r.line,
                r.name
            );
        };
        let mat = &scene.materials[m];
        let emissivity = match r.emissivity {
            Some(e) => e,
            None => {
                let rho = mat.reflectance;
                1.0 - (rho.r + rho.g + rho.b) / 3.0
            }
        };
        boundary_of[m] = k;
        boundaries.push(Boundary {
            emissivity,
            condition: r.condition,
        });
    }
    let mut missing: Vec<&str> = (0..scene.materials.len())
        .filter(|&m| used[m] && boundary_of[m] == usize::MAX)
        .map(|m| scene.materials[m].name.as_str())
        .collect();
    if !missing.is_empty() {
        missing.sort_unstable();
        bail!(
            "{}: no boundary condition for {} surface{}: {} (add a row for each; leave temperature and flux empty for an adiabatic surface)",
            a.boundary.display(),
            missing.len(),
            if missing.len() == 1 { "" } else { "s" },
            missing.join(", ")
        );
    }

    // View factors.
    let method = a.method.0;
    let params = Params {
        method,
        resolution: a.resolution,
        samples: a.samples,
        seed: a.seed,
        rays: a.rays.unwrap_or(10_000),
        ..Params::default()
    };
    let rays_for = |n: usize| a.rays.unwrap_or_else(|| default_rays(n));
    let (mesh, matrix, params, ff_seconds) = crate::view_factors::compute(
        &scene,
        mesh_params,
        params,
        Storage::Sparse,
        Some(&rays_for),
    )?;
    let n = mesh.len();
    let unit2 = a.unit.metres().powi(2);
    let area: Vec<f64> = mesh.patches.iter().map(|p| p.area as f64).collect();
    let before = summary(&matrix, &area);
    let closed = match a.enclosure {
        EnclosureArg::Closed => true,
        EnclosureArg::Open => false,
        EnclosureArg::Auto => match &vs3 {
            Some(v) => v.control.enclosure,
            None => before.min_row_sum >= 0.99,
        },
    };
    let matrix = enforce(
        matrix,
        &area,
        Enforce {
            clamp: false,
            normalize_rows: closed,
            symmetrize: true,
        },
    );
    let after = summary(&matrix, &area);
    let system = ThermalSystem {
        area: area.iter().map(|a| a * unit2).collect(),
        group: mesh
            .patches
            .iter()
            .map(|p| boundary_of[p.material as usize] as u32)
            .collect(),
        boundaries: boundaries.clone(),
        environment: a.environment,
        closed,
    };
    let linear = match a.linear_solver {
        LinearSolverArg::Auto => LinearSolver::Auto,
        LinearSolverArg::Direct => LinearSolver::Direct,
        LinearSolverArg::Iterative => LinearSolver::Iterative,
    };
    let solution = thermal::solve(
        &system,
        &matrix,
        ThermalParams {
            linear,
            memory_limit: radiosity::pipeline::available_memory().unwrap_or(u64::MAX),
            ..ThermalParams::default()
        },
    )
    .map_err(|e| match e {
        thermal::ThermalError::Unphysical { group, value } => anyhow::anyhow!(
            "{}:{}: the flux prescribed for '{}' cannot be met: part of it would need a negative black-body exitance ({value:.4e} W/m²); it takes out more heat than the enclosure can supply",
            a.boundary.display(),
            rows[group].line,
            rows[group].name
        ),
        e => e.into(),
    })?;
    let per = solution.per_boundary(&system);

    // Outputs.
    let mut out = String::from("name,area,emissivity,temperature,flux,power\n");
    for (k, r) in rows.iter().enumerate() {
        let (ar, power, t) = per[k];
        let flux = if ar > 0.0 { power / ar } else { 0.0 };
        let _ = writeln!(
            out,
            "{},{ar},{},{t},{flux},{power}",
            csv_name(&r.name),
            boundaries[k].emissivity
        );
    }
    radiosity::export::write_text(&a.out, &out)?;
    if let Some(p) = &a.patches_out {
        let mut s = String::from("patch,name,x,y,z,area,emissivity,temperature,flux,power\n");
        for (i, patch) in mesh.patches.iter().enumerate() {
            let k = system.group[i] as usize;
            let c = patch.centre;
            let _ = writeln!(
                s,
                "{i},{},{},{},{},{},{},{},{},{}",
                csv_name(&rows[k].name),
                c.x,
                c.y,
                c.z,
                system.area[i],
                boundaries[k].emissivity,
                solution.temperature[i],
                solution.flux[i],
                system.area[i] * solution.flux[i]
            );
        }
        radiosity::export::write_text(p, &s)?;
    }

    // Summary.
    let info = &solution.info;
    println!(
        "scene       {} ({} surfaces, {} patches, 1 scene unit = {} m)",
        scene.place(),
        rows.len(),
        n,
        a.unit.metres()
    );
    let accuracy = match method {
        FormFactorMethod::MonteCarlo => format!(
            "{} rays per row: each irradiation within ~{:.2} % (1/√rays) of the spread of what it sees",
            params.rays,
            100.0 / (params.rays as f64).sqrt()
        ),
        FormFactorMethod::Analytic => "exact for unoccluded pairs, occlusion ignored".into(),
        _ => format!(
            "resolution {}, {} points per patch",
            params.resolution, params.samples
        ),
    };
    println!("view factors {method} in {ff_seconds:.2} s; {accuracy}");
    println!(
        "            row sums {:.6} … {:.6} before, {:.6} … {:.6} after {}reciprocity (worst |A_i F_ij − A_j F_ji| / mean area {:.1e} → {:.1e})",
        before.min_row_sum,
        before.max_row_sum,
        after.min_row_sum,
        after.max_row_sum,
        if closed { "closure and " } else { "" },
        before.worst_reciprocity,
        after.worst_reciprocity
    );
    println!(
        "enclosure   {}; {:.4} % of the area-weighted view reaches the surroundings at {} K",
        if closed { "closed" } else { "open" },
        100.0 * info.opening,
        a.environment
    );
    println!(
        "solve       {} in {:.3} s{}, relative residual {:.1e}",
        info.method,
        info.seconds,
        if info.iterations > 0 {
            format!(" ({} iterations)", info.iterations)
        } else {
            String::new()
        },
        info.residual
    );
    println!(
        "balance     Σ power {:.6e} W, net loss to the surroundings {:.6e} W, relative difference {:.1e}",
        info.total_power, info.environment_loss, info.balance_error
    );
    let width = rows.iter().map(|r| r.name.len()).max().unwrap_or(4).max(7);
    println!(
        "{:width$}  {:>14}  {:>5}  {:>10}  {:>13}  {:>13}",
        "surface", "area m²", "ε", "T K", "flux W/m²", "power W"
    );
    for (k, r) in rows.iter().enumerate().take(40) {
        let (ar, power, t) = per[k];
        let given = match r.condition {
            Condition::Temperature(_) => "T",
            Condition::Flux(_) => "q",
            Condition::Adiabatic => "0",
        };
        println!(
            "{:width$}  {:>14.4}  {:>5.3}  {:>9.2}{}  {:>13.5e}  {:>13.5e}",
            r.name,
            ar,
            boundaries[k].emissivity,
            t,
            if given == "T" { "*" } else { " " },
            if ar > 0.0 { power / ar } else { 0.0 },
            power
        );
    }
    if rows.len() > 40 {
        println!("… {} more in {}", rows.len() - 40, a.out.display());
    }
    println!("            (* prescribed temperature)");
    println!("wrote       {}", a.out.display());
    if let Some(p) = &a.patches_out {
        println!("wrote       {}", p.display());
    }
    Ok(())
}
