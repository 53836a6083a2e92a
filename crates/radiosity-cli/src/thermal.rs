//! `radiosity thermal`: net radiative heat transfer between grey diffuse surfaces.

use crate::args::{EnclosureArg, LinearSolverArg, ThermalArgs, ThermalSolverArg};
use anyhow::{bail, Result};
use radiosity::formfactor::{FormFactorMethod, Params};
use radiosity::io::FileFormat;
use radiosity::mesh::MeshParams;
use radiosity::observe::{Event, Stage};
use radiosity::pipeline::{Enclosure, ThermalSettings};
use radiosity::scene::vs3;
use radiosity::thermal::{
    self, read_boundary_csv, Boundary, Condition, LinearSolver, MatrixFreeParams, ThermalSolver,
};
use std::fmt::Write as _;
use std::path::Path;

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
    if let Some(p) = &a.mrt_out {
        if FileFormat::from_path(p) != Some(FileFormat::Csv) {
            bail!("--mrt-out {}: must be a .csv file", p.display());
        }
        crate::settings::check_output(p)?;
        if a.mrt_rays == 0 || a.mrt_rays > radiosity::pipeline::MAX_RADIANT_RAYS {
            bail!(
                "--mrt-rays {}: give 1 to {}",
                a.mrt_rays,
                radiosity::pipeline::MAX_RADIANT_RAYS
            );
        }
    }
    // No output over an input or another output.
    let inputs: Vec<(&str, &Path)> = [
        ("scene", Path::new(&a.scene)),
        ("--boundary", a.boundary.as_path()),
    ]
    .into_iter()
    .chain(a.grid.iter().map(|g| ("--grid", g.as_path())))
    .collect();
    let outputs: Vec<(&str, &Path)> = [
        Some(("--out", a.out.as_path())),
        a.patches_out.as_deref().map(|p| ("--patches-out", p)),
        a.mrt_out.as_deref().map(|p| ("--mrt-out", p)),
    ]
    .into_iter()
    .flatten()
    .collect();
    crate::settings::distinct_files(&inputs, &outputs)?;
    // The points, read before any work.
    let mut points = Vec::new();
    for g in &a.grid {
        let p = radiosity::lighting::read_points(g)?;
        if p.is_empty() {
            bail!("{}: no points", g.display());
        }
        points.extend(p);
    }
    if !(a.environment.is_finite() && (0.0..=thermal::MAX_TEMPERATURE).contains(&a.environment)) {
        bail!(
            "--environment {:e}: a temperature in kelvin, 0 to {:e} (σT⁴ past that overflows the heat balance)",
            a.environment,
            thermal::MAX_TEMPERATURE
        );
    }
    crate::settings::form_factor_numbers(a.resolution, a.samples, a.rays)?;
    crate::settings::accuracy(a.accuracy)?;
    let matrix_free = MatrixFreeParams {
        flux_rays: a.flux_rays,
        temperature_rays: a.temperature_rays,
        sweep_rays: a.sweep_rays,
        carry_rays: a.carry_rays,
        batches: a.batches,
        flux_error: a.flux_error,
        seed: a.seed,
        ..MatrixFreeParams::default()
    };
    if !(a.flux_error.is_finite() && (0.0..1.0).contains(&a.flux_error)) {
        bail!(
            "--flux-error {}: give a share of the mean |flux| in [0, 1) (0: no adaptive stage)",
            a.flux_error
        );
    }
    for (flag, value, lo, hi) in [
        (
            "--flux-rays",
            a.flux_rays,
            1,
            thermal::matrix_free::MAX_RAYS,
        ),
        (
            "--temperature-rays",
            a.temperature_rays,
            1,
            thermal::matrix_free::MAX_RAYS,
        ),
        (
            "--sweep-rays",
            a.sweep_rays,
            1,
            thermal::matrix_free::MAX_RAYS,
        ),
        (
            "--carry-rays",
            a.carry_rays,
            1,
            thermal::matrix_free::MAX_RAYS,
        ),
        ("--batches", a.batches, 2, 4096),
    ] {
        if !(lo..=hi).contains(&value) {
            bail!("{flag} {value}: give {lo} to {hi}");
        }
    }
    let solver = match a.solver {
        ThermalSolverArg::Auto => ThermalSolver::Auto,
        ThermalSolverArg::Stored => ThermalSolver::Stored,
        ThermalSolverArg::MatrixFree => ThermalSolver::MatrixFree,
    };
    if solver == ThermalSolver::MatrixFree && crate::ranks::current().is_some() {
        bail!("--solver matrix-free: does not run over ranks (mpirun); use --solver stored");
    }
    // Engineers' default: one patch per face.
    let mesh_params = crate::settings::mesh_params(a.patches, a.max_edge, MeshParams::Faces)?;

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
    let boundaries: Vec<Boundary> = rows
        .iter()
        .map(|r| {
            // Empty emissivity: the scene's own (View3D's emit column, or 1 − mean ρ).
            let emissivity = r.emissivity.unwrap_or_else(|| {
                scene
                    .materials
                    .iter()
                    .find(|m| m.name == r.name)
                    .map_or(1.0, |m| {
                        let rho = m.reflectance;
                        1.0 - (rho.r + rho.g + rho.b) / 3.0
                    })
            });
            Boundary {
                emissivity,
                condition: r.condition,
            }
        })
        .collect();
    let named: Vec<(String, Boundary)> = rows
        .iter()
        .zip(&boundaries)
        .map(|(r, b)| (r.name.clone(), *b))
        .collect();
    let combined = |name: &str| {
        vs3.as_ref().and_then(|v| {
            v.surfaces
                .iter()
                .find(|s| s.name == name && s.combined_into.is_some())
                .map(|s| v.surfaces[s.combined_into.unwrap_or(0)].name.clone())
        })
    };
    let boundary_of = radiosity::pipeline::thermal_boundaries(&scene, &named, &combined).map_err(
        |(k, message)| match k {
            Some(k) => anyhow::anyhow!("{}:{}: {message}", a.boundary.display(), rows[k].line),
            None => anyhow::anyhow!("{}: {message}", a.boundary.display()),
        },
    )?;

    // View factors and the solve.
    let method = a.method.0;
    let settings = ThermalSettings {
        mesh: mesh_params,
        form_factors: Params {
            method,
            resolution: a.resolution,
            samples: a.samples,
            seed: a.seed,
            rays: a.rays.unwrap_or(10_000),
            accuracy: a.accuracy,
            ..Params::default()
        },
        default_rays: a.rays.is_none(),
        unit_metres: a.unit.metres(),
        environment: a.environment,
        enclosure: match a.enclosure {
            EnclosureArg::Auto => Enclosure::Auto,
            EnclosureArg::Closed => Enclosure::Closed,
            EnclosureArg::Open => Enclosure::Open,
        },
        enclosure_hint: vs3.as_ref().map(|v| v.control.enclosure),
        linear: match a.linear_solver {
            // Under mpirun BiCGSTAB over the ranks, on one rank too (the same bytes as on K):
            // dense LU would not split.
            LinearSolverArg::Auto if crate::ranks::current().is_some() => LinearSolver::Iterative,
            LinearSolverArg::Auto => LinearSolver::Auto,
            LinearSolverArg::Direct => LinearSolver::Direct,
            LinearSolverArg::Iterative => LinearSolver::Iterative,
            LinearSolverArg::Jacobi => LinearSolver::Jacobi,
        },
        memory_limit: radiosity::pipeline::MemoryLimit::Available,
        solver,
        matrix_free,
    };
    let bar = indicatif::ProgressBar::new(0);
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{spinner} {msg} {pos}/{len} [{bar:30}] {elapsed_precise} (eta {eta})",
        )
        .expect("valid template")
        .progress_chars("=> "),
    );
    let progress = |e: Event<'_>| match e {
        Event::Stage(Stage::FormFactors) => bar.set_message("form factors, rows"),
        Event::Stage(Stage::Solve) => bar.set_message("solve, sweeps"),
        Event::Progress {
            stage: Stage::FormFactors | Stage::Solve,
            done,
            total,
        } => {
            bar.set_length(total);
            bar.set_position(done)
        }
        _ => {}
    };
    warn_coincident_boundaries(&scene);
    let outcome = radiosity::pipeline::thermal_over(
        &scene,
        &boundary_of,
        &boundaries,
        &settings,
        crate::ranks::current(),
        &progress,
    );
    bar.finish_and_clear();
    let (outcome, distributed) = outcome.map_err(|e| match e {
        radiosity::Error::Thermal(thermal::ThermalError::Unphysical { group, value }) => anyhow::anyhow!(
            "{}:{}: the flux prescribed for '{}' cannot be met: part of it would need a negative black-body exitance ({value:.4e} W/m²); it takes out more heat than the enclosure can supply",
            a.boundary.display(),
            rows[group].line,
            rows[group].name
        ),
        radiosity::Error::OutOfMemory { what, needed, limit, .. } => anyhow::anyhow!(
            "{what} would need about {} MiB but only {} MiB are available; use fewer patches (--patches N, a larger --max-edge, or the default one patch per face)",
            needed >> 20,
            limit >> 20
        ),
        e => e.into(),
    })?;
    if !crate::ranks::is_root() {
        return Ok(());
    }
    let (mesh, system, solution, per) = (
        &outcome.mesh,
        &outcome.system,
        &outcome.solution,
        &outcome.per_boundary,
    );
    let (params, ff_seconds, before, after, closed) = (
        outcome.form_factors,
        outcome.form_factor_seconds,
        outcome.before,
        outcome.after,
        outcome.closed,
    );
    let n = mesh.len();
    // The matrix-free solve's standard errors: one more column in each table.
    let errors = !solution.flux_std_error.is_empty();

    // Outputs.
    let mut out = String::from("name,area,emissivity,temperature,flux,power");
    out += if errors { ",flux_std_error\n" } else { "\n" };
    for (k, r) in rows.iter().enumerate() {
        let (ar, power, t) = per[k];
        let flux = if ar > 0.0 { power / ar } else { 0.0 };
        let _ = write!(
            out,
            "{},{ar},{},{t},{flux},{power}",
            csv_name(&r.name),
            boundaries[k].emissivity
        );
        if errors {
            let e = solution.boundary_power_std_error[k];
            let _ = write!(out, ",{}", if ar > 0.0 { e / ar } else { 0.0 });
        }
        out.push('\n');
    }
    let mut patches_csv = None;
    if let Some(p) = &a.patches_out {
        let mut s = String::from("patch,name,x,y,z,area,emissivity,temperature,flux,power");
        s += if errors {
            ",flux_std_error,temperature_std_error\n"
        } else {
            "\n"
        };
        for (i, patch) in mesh.patches.iter().enumerate() {
            let k = system.group[i] as usize;
            let c = patch.centre;
            let _ = write!(
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
            if errors {
                let _ = write!(
                    s,
                    ",{},{}",
                    solution.flux_std_error[i], solution.temperature_std_error[i]
                );
            }
            s.push('\n');
        }
        patches_csv = Some((p, s));
    }

    let radiant = if let Some(p) = &a.mrt_out {
        let bvh = radiosity::accel::Bvh::build(mesh);
        let params = radiosity::pipeline::RadiantParams {
            rays: a.mrt_rays,
            seed: a.seed,
        };
        let t = std::time::Instant::now();
        let r = radiosity::pipeline::radiant_temperatures(
            mesh,
            &bvh,
            &solution.radiosity,
            a.environment,
            &points,
            params,
        )
        .map_err(|m| anyhow::anyhow!("radiant temperatures: {m}"))?;
        let mut s =
            String::from("x,y,z,mean_radiant_temperature,plane_radiant_temperature,sky_view\n");
        for (q, v) in points.iter().zip(&r.points) {
            let _ = writeln!(
                s,
                "{},{},{},{},{},{}",
                q.position[0],
                q.position[1],
                q.position[2],
                v.mean_radiant_temperature,
                v.plane_radiant_temperature,
                v.sky_view
            );
        }
        Some((p, r, t.elapsed().as_secs_f64(), s))
    } else {
        None
    };

    // Every output or none, and no NaN or infinity in any: the inputs' ranges keep the
    // physics finite, and this is the last line of defence.
    let files: Vec<(&Path, &str, &str)> = std::iter::once((a.out.as_path(), "--out", out.as_str()))
        .chain(
            patches_csv
                .as_ref()
                .map(|(p, s)| (p.as_path(), "--patches-out", s.as_str())),
        )
        .chain(
            radiant
                .as_ref()
                .map(|(p, _, _, s)| (p.as_path(), "--mrt-out", s.as_str())),
        )
        .collect();
    let not_finite = |flag: &str, path: &Path, row: Option<usize>| {
        anyhow::anyhow!(
            "{flag} {}: {} would hold a value that is not finite; nothing was written (the inputs are outside the range the heat balance can represent)",
            path.display(),
            row.map_or("a row".to_string(), |r| format!("line {}", r + 2))
        )
    };
    if let Some(k) = (0..rows.len()).find(|&k| {
        let (ar, power, t) = per[k];
        let e = solution
            .boundary_power_std_error
            .get(k)
            .copied()
            .unwrap_or(0.0);
        ![ar, power, t, boundaries[k].emissivity, e]
            .iter()
            .all(|v| v.is_finite())
    }) {
        return Err(not_finite("--out", &a.out, Some(k)));
    }
    if let Some((p, _)) = &patches_csv {
        if let Some(i) = (0..n).find(|&i| {
            ![
                system.area[i],
                solution.temperature[i],
                solution.flux[i],
                system.area[i] * solution.flux[i],
                solution.flux_std_error.get(i).copied().unwrap_or(0.0),
                solution
                    .temperature_std_error
                    .get(i)
                    .copied()
                    .unwrap_or(0.0),
            ]
            .iter()
            .all(|v| v.is_finite())
        }) {
            return Err(not_finite("--patches-out", p, Some(i)));
        }
    }
    if let Some((p, r, _, _)) = &radiant {
        if let Some(i) = r.points.iter().position(|v| {
            ![
                v.mean_radiant_temperature,
                v.plane_radiant_temperature,
                v.sky_view,
            ]
            .iter()
            .all(|x| x.is_finite())
        }) {
            return Err(not_finite("--mrt-out", p, Some(i)));
        }
    }
    let mut staged = radiosity::io::Staged::default();
    for (path, _, text) in &files {
        staged.write::<radiosity::io::OutputError>(path, |w| w.write_all(text.as_bytes()))?;
    }
    staged.commit::<radiosity::io::OutputError>()?;

    // Summary.
    let info = &solution.info;
    println!(
        "scene       {} ({} surfaces, {} patches, 1 scene unit = {} m)",
        scene.place(),
        rows.len(),
        n,
        a.unit.metres()
    );
    if let Some(mf) = &info.matrix_free {
        println!("view factors none stored: the irradiation gathered by rays from every patch");
        println!(
            "enclosure   {}; {:.4} % of the area-weighted view reaches the surroundings at {} K",
            if closed { "closed" } else { "open" },
            100.0 * info.opening,
            a.environment
        );
        println!(
            "solve       matrix-free in {:.2} s: {} sweeps of {} rays a patch (contraction {:.3}, remaining bias {:.1e}), then {} batches of {} sweeps, the last of {} rays a patch at a prescribed temperature and {} a patch elsewhere; {:.3e} rays",
            info.seconds,
            mf.sweeps,
            mf.sweep_rays,
            mf.contraction,
            mf.remaining_bias,
            mf.batches,
            mf.batch_sweeps,
            mf.flux_rays,
            mf.temperature_rays,
            mf.rays_cast as f64
        );
        if mf.flux_target > 0.0 {
            println!(
                "adaptive    flux target {:.3e} W/m² ({} of the mean |flux|): {} patches gathered more rays in {} rounds ({:.3e} rays, at most {} a patch a batch); {} left above it",
                mf.flux_target,
                a.flux_error,
                mf.refined_patches,
                mf.refine_rounds,
                mf.refine_rays as f64,
                mf.most_flux_rays,
                mf.above_target
            );
        }
        matrix_free_errors(system, solution);
    } else {
        let accuracy = match method {
            FormFactorMethod::MonteCarlo => format!(
                "{} rays per row: each irradiation within ~{:.2} % (1/√rays) of the spread of what it sees",
                params.rays,
                100.0 / (params.rays as f64).sqrt()
            ),
            FormFactorMethod::Analytic => "exact for unoccluded pairs, occlusion ignored".into(),
            FormFactorMethod::Adaptive => format!("accuracy {:e} an entry", params.accuracy),
            _ => format!(
                "resolution {}, {} points per patch",
                params.resolution, params.samples
            ),
        };
        println!("view factors {method} in {ff_seconds:.2} s; {accuracy}");
        if let Some(st) = &outcome.adaptive {
            println!(
                "            {} facing pairs: {} by the product rule, {} by the contour integral, {} occluded ({} found clear, {} hidden, {} at the cell cap, {} sampled by {} rays); {} visibility points",
                st.facing,
                st.product_rule,
                st.contour,
                st.occluded,
                st.occluded_clear,
                st.occluded_hidden,
                st.capped,
                st.sampled,
                st.rays,
                st.points
            );
        }
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
    }
    println!(
        "balance     Σ power {:.6e} W, net loss to the surroundings {:.6e} W, relative difference {:.1e}",
        info.total_power, info.environment_loss, info.balance_error
    );
    if let Some(mf) = &info.matrix_free {
        // The books close in expectation: the difference should be within a few of its
        // standard errors; say so only when it is.
        let z = (info.total_power - info.environment_loss).abs() / mf.balance_std_error;
        let verdict = if z.is_finite() && z <= 3.0 {
            "within its Monte Carlo error"
        } else {
            "more than its Monte Carlo error explains: see docs/heat-transfer.md, the books"
        };
        println!(
            "            standard errors: Σ power {:.3e} W, the difference {:.3e} W; the difference is {z:.1} of them ({verdict})",
            mf.total_power_std_error, mf.balance_std_error
        );
    }
    let width = rows.iter().map(|r| r.name.len()).max().unwrap_or(4).max(7);
    println!(
        "{:width$}  {:>14}  {:>5}  {:>10}  {:>13}  {:>13}{}",
        "surface",
        "area m²",
        "ε",
        "T K",
        "flux W/m²",
        "power W",
        if errors { "   ± flux W/m²" } else { "" }
    );
    for (k, r) in rows.iter().enumerate().take(40) {
        let (ar, power, t) = per[k];
        let given = match r.condition {
            Condition::Temperature(_) => "T",
            Condition::Flux(_) => "q",
            Condition::Adiabatic => "0",
        };
        println!(
            "{:width$}  {:>14.4}  {:>5.3}  {:>9.2}{}  {:>13.5e}  {:>13.5e}{}",
            r.name,
            ar,
            boundaries[k].emissivity,
            t,
            if given == "T" { "*" } else { " " },
            if ar > 0.0 { power / ar } else { 0.0 },
            power,
            match solution.boundary_power_std_error.get(k) {
                Some(e) if ar > 0.0 => format!("  {:>12.3e}", e / ar),
                Some(_) => format!("  {:>12.3e}", 0.0),
                None => String::new(),
            }
        );
    }
    if rows.len() > 40 {
        println!("… {} more in {}", rows.len() - 40, a.out.display());
    }
    println!("            (* prescribed temperature)");
    if let Some(r) = &distributed {
        crate::report::ranks(r);
    }
    println!("wrote       {}", a.out.display());
    if let Some(p) = &a.patches_out {
        println!("wrote       {}", p.display());
    }
    if let Some((p, r, seconds, _)) = &radiant {
        let (lo, hi) = r
            .points
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
                (
                    lo.min(v.mean_radiant_temperature),
                    hi.max(v.mean_radiant_temperature),
                )
            });
        println!(
            "radiant     {} points, mean radiant temperature {lo:.2}..{hi:.2} K, {} rays in {seconds:.2} s",
            r.points.len(),
            r.rays
        );
        if r.back_hits > 0 {
            eprintln!(
                "radiosity: warning: {} of {} rays met the back of a surface (points inside a solid?); they count as the surroundings",
                r.back_hits, r.rays
            );
        }
        println!("wrote       {}", p.display());
    }
    Ok(())
}

/// The matrix-free solve's error line: each patch's flux standard error against the mean
/// absolute flux of the patches whose flux it computes (those at a prescribed temperature),
/// and the temperatures' standard errors where it computes those.
fn matrix_free_errors(system: &thermal::ThermalSystem, solution: &thermal::ThermalSolution) {
    let (mut n_t, mut abs_flux, mut se_sum, mut se_max) = (0usize, 0.0, 0.0, 0.0f64);
    let (mut n_q, mut te_sum, mut te_max) = (0usize, 0.0, 0.0f64);
    for i in 0..system.area.len() {
        match system.boundaries[system.group[i] as usize].condition {
            Condition::Temperature(_) => {
                n_t += 1;
                abs_flux += solution.flux[i].abs();
                se_sum += solution.flux_std_error[i];
                se_max = se_max.max(solution.flux_std_error[i]);
            }
            _ => {
                n_q += 1;
                te_sum += solution.temperature_std_error[i];
                te_max = te_max.max(solution.temperature_std_error[i]);
            }
        }
    }
    if n_t > 0 {
        let mean_abs = abs_flux / n_t as f64;
        let pct = |x: f64| {
            if mean_abs > 0.0 {
                100.0 * x / mean_abs
            } else {
                0.0
            }
        };
        println!(
            "error       flux (one standard error) over the {n_t} patches at a prescribed temperature: mean {:.3e}, worst {:.3e} W/m², {:.2} % and {:.2} % of their mean |flux| {:.4e} W/m²",
            se_sum / n_t as f64,
            se_max,
            pct(se_sum / n_t as f64),
            pct(se_max),
            mean_abs
        );
    }
    if n_q > 0 {
        println!(
            "            temperature over the {n_q} other patches: mean {:.3e}, worst {:.3e} K",
            te_sum / n_q as f64,
            te_max
        );
    }
}

/// Coincident surfaces are one surface (`radiosity::mesh::Coincidence`): a surface lying
/// wholly on another of another name is solved as that one, so its own boundary row is not
/// used (its results show area 0). Say so, naming the first few pairs.
fn warn_coincident_boundaries(scene: &radiosity::scene::Scene) {
    let c = radiosity::mesh::Coincidence::find(scene);
    let mut pairs: Vec<(&str, &str)> = Vec::new();
    for i in 0..scene.polygons.len() {
        let r = c.representative(i);
        if r == i {
            continue;
        }
        let name = |k: usize| scene.materials[scene.polygons[k].material].name.as_str();
        let pair = (name(i), name(r));
        if pair.0 != pair.1 && !pairs.contains(&pair) {
            pairs.push(pair);
        }
    }
    if pairs.is_empty() {
        return;
    }
    const SHOWN: usize = 5;
    let list: Vec<String> = pairs
        .iter()
        .take(SHOWN)
        .map(|(a, b)| format!("'{a}' on '{b}'"))
        .collect();
    let more = match pairs.len().saturating_sub(SHOWN) {
        0 => String::new(),
        n => format!(" and {n} more"),
    };
    eprintln!(
        "radiosity: warning: {}: surfaces lying exactly on a surface of another name are solved as it, and their own boundary conditions are not used (their rows show area 0): {}{more}",
        scene.place(),
        radiosity::loc::shorten(list.join(", "))
    );
}
