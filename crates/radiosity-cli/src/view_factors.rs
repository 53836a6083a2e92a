//! `radiosity form-factors`: a view-factor matrix for a scene, for radiative heat transfer.

use crate::args::{FormFactorsArgs, MatrixFormatArg};
use anyhow::{bail, Result};
use radiosity::export::{write_patch_table, PatchRow};
use radiosity::formfactor::{
    aggregate, enforce, summary, Enforce, FormFactorMethod, Params, Storage,
};
use radiosity::geom::Vec3;
use radiosity::io::{matrix_market, FileFormat};
use radiosity::mesh::{Mesh, MeshParams};
use radiosity::observe::Event;
use radiosity::pipeline::{view_factors_over, ViewFactorSettings};
use radiosity::scene::{vector_area, vs3, Scene};
use std::path::Path;

fn ext_is(path: &std::path::Path, format: FileFormat) -> bool {
    FileFormat::from_path(path) == Some(format)
}

/// Run the command.
pub fn run(a: FormFactorsArgs) -> Result<()> {
    crate::settings::form_factor_numbers(a.resolution, a.samples, Some(a.rays))?;
    crate::settings::accuracy(a.accuracy)?;
    let storage: Storage = a.storage.into();
    let view3d = match a.format {
        Some(MatrixFormatArg::View3d) => true,
        Some(MatrixFormatArg::Mtx) => false,
        None if ext_is(&a.out, FileFormat::MatrixMarket) => false,
        None => bail!(
            "{}: unsupported output format (use .mtx, Matrix Market, or --format view3d)",
            a.out.display()
        ),
    };
    if view3d && a.patches_out.is_some() {
        bail!("--patches-out: not written with --format view3d (the View3D file holds the surfaces' areas)");
    }
    if a.script_f && !view3d {
        bail!("--script-f: total exchange factors are written only with --format view3d");
    }
    crate::settings::check_output(&a.out)?;
    if let Some(p) = &a.patches_out {
        if !ext_is(p, FileFormat::Csv) {
            bail!("{}: unsupported output format (use .csv)", p.display());
        }
        crate::settings::check_output(p)?;
    }
    let is_vs3 = FileFormat::from_path(Path::new(&a.scene)) == Some(FileFormat::Vs3)
        && Path::new(&a.scene).exists();
    // View3D's users expect View3D's accuracy: the adaptive method is their default.
    let method = match a.method {
        Some(m) => m.0,
        None if is_vs3 => FormFactorMethod::Adaptive,
        None => FormFactorMethod::MonteCarlo,
    };
    // View3D's users and output think in surfaces.
    let mesh_params =
        if a.faces || ((is_vs3 || view3d) && a.patches.is_none() && a.max_edge.is_none()) {
            MeshParams::Faces
        } else {
            crate::settings::mesh_params(a.patches, a.max_edge, MeshParams::default())?
        };
    let faces = mesh_params == MeshParams::Faces;
    let vs3 = if is_vs3 {
        let v = vs3::load(Path::new(&a.scene))?;
        for w in &v.scene.warnings {
            eprintln!("radiosity: warning: {w}");
        }
        if !v.control.unmapped.is_empty() {
            eprintln!(
                "radiosity: warning: {}: control {} ignored: parameters of View3D's own integrator (accuracy here is set by --method and --accuracy or --rays)",
                a.scene,
                v.control.unmapped.join(", ")
            );
        }
        Some(v)
    } else {
        None
    };
    let scene = match &vs3 {
        Some(v) => v.scene.clone(),
        None => crate::load_scene(&a.scene, false)?,
    };
    let params = Params {
        method,
        resolution: a.resolution,
        samples: a.samples,
        rays: a.rays,
        seed: a.seed,
        accuracy: a.accuracy,
        ..Params::default()
    };
    let bar = indicatif::ProgressBar::new(0);
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{spinner} form factors {pos}/{len} rows [{bar:30}] {elapsed_precise} (eta {eta})",
        )
        .expect("valid template")
        .progress_chars("=> "),
    );
    let settings = ViewFactorSettings {
        mesh: mesh_params,
        form_factors: params,
        storage,
        memory_limit: radiosity::pipeline::MemoryLimit::Available,
    };
    let computed = view_factors_over(
        &scene,
        &settings,
        None,
        crate::ranks::current(),
        &|e: Event<'_>| {
            if let Event::Progress { done, total, .. } = e {
                bar.set_length(total);
                bar.set_position(done)
            }
        },
    );
    bar.finish_and_clear();
    let (vf, distributed) = computed.map_err(too_big)?;
    // Under mpirun rank 0 writes; the others are done.
    if vf.matrix.is_none() {
        return Ok(());
    }
    let per_face = if faces && !view3d {
        vf.per_face(&scene)
    } else {
        None
    };
    let area = vf.areas();
    let radiosity::pipeline::ViewFactors {
        mesh,
        matrix,
        seconds: compute_s,
        ..
    } = vf;
    let matrix = matrix.expect("rank 0 holds the matrix");
    let mesh = &mesh;
    if view3d {
        return write_view3d(
            &a,
            method,
            &scene,
            vs3.as_ref(),
            mesh,
            &matrix,
            &area,
            compute_s,
        );
    }

    // One row per face, or per patch.
    let (matrix, area, rows) = if faces {
        drop(matrix);
        let (m, face_area) = per_face.expect("rank 0 holds the matrix");
        let rows = scene
            .polygons
            .iter()
            .enumerate()
            .map(|(k, p)| {
                let mat = &scene.materials[p.material];
                PatchRow {
                    surface: k as u32,
                    area: face_area[k],
                    centre: p.vertices.iter().copied().sum::<Vec3>() / p.vertices.len() as f32,
                    normal: vector_area(&p.vertices).normalize_or_zero(),
                    reflectance: mat.reflectance,
                    emission: mat.emission,
                }
            })
            .collect::<Vec<_>>();
        (m, face_area, rows)
    } else {
        let rows = mesh
            .patches
            .iter()
            .map(|p| {
                let mat = &scene.materials[p.material as usize];
                PatchRow {
                    surface: p.surface,
                    area: p.area as f64,
                    centre: p.centre,
                    normal: p.normal,
                    reflectance: mat.reflectance,
                    emission: mat.emission,
                }
            })
            .collect::<Vec<_>>();
        (matrix, area, rows)
    };
    let fix = Enforce {
        clamp: a.clamp,
        normalize_rows: a.normalize_rows,
        symmetrize: a.symmetrize,
    };
    let matrix = if fix != Enforce::default() {
        enforce(matrix, &area, fix)
    } else {
        matrix
    };
    let s = summary(&matrix, &area);
    let comment = vec![
        format!(
            "view factors of {} by radiosity form-factors",
            scene.place()
        ),
        format!(
            "method {method}, {}, {}",
            match method {
                FormFactorMethod::Adaptive => format!("accuracy {:e}", a.accuracy),
                FormFactorMethod::Analytic => "exact, occlusion ignored".to_string(),
                FormFactorMethod::MonteCarlo => format!("rays {}, seed {}", a.rays, a.seed),
                _ => format!("resolution {}, samples {}", a.resolution, a.samples),
            },
            if faces {
                "one row per face".to_string()
            } else {
                format!("{} patches", mesh.len())
            }
        ),
        format!(
            "clamp {}, normalize-rows {}, symmetrize {}",
            a.clamp, a.normalize_rows, a.symmetrize
        ),
    ];
    matrix_market::write(&a.out, &matrix, &comment)?;
    if let Some(p) = &a.patches_out {
        write_patch_table(p, &rows)?;
    }
    println!(
        "rows        {} ({}), {} entries, fill {:.4}%",
        matrix.n(),
        if faces { "faces" } else { "patches" },
        matrix.nnz(),
        100.0 * s.fill
    );
    println!("method      {method} in {compute_s:.3} s");
    println!("row sums    {:.6} … {:.6}", s.min_row_sum, s.max_row_sum);
    println!(
        "reciprocity worst |A_i F_ij − A_j F_ji| / mean area = {:.3e}",
        s.worst_reciprocity
    );
    if let Some(r) = &distributed {
        crate::report::ranks(r);
    }
    println!("wrote       {}", a.out.display());
    if let Some(p) = &a.patches_out {
        println!("wrote       {}", p.display());
    }
    Ok(())
}

/// A stored view-factor matrix too large for memory: the remedy is fewer patches, whatever the
/// method.
fn too_big(e: radiosity::Error) -> anyhow::Error {
    match e {
        radiosity::Error::OutOfMemory {
            what,
            needed,
            limit,
            ..
        } => anyhow::anyhow!(
            "{what} would need about {} MiB but only {} MiB are available; use fewer patches (--patches N, a larger --max-edge, or --faces)",
            needed >> 20,
            limit >> 20
        ),
        e => e.into(),
    }
}

/// `--format view3d`: one row per View3D surface (combined pieces merged, obstructions left
/// out) or per input face, enclosure and exchange factors as the .vs3 control line says.
#[allow(clippy::too_many_arguments)]
fn write_view3d(
    a: &FormFactorsArgs,
    method: FormFactorMethod,
    scene: &Scene,
    vs3: Option<&vs3::Vs3>,
    mesh: &Mesh,
    matrix: &radiosity::system::SparseMatrix,
    area: &[f64],
    compute_s: f64,
) -> Result<()> {
    // Output surface of each patch; `k` (one past the last) collects obstructions.
    let (group_of_material, k): (Vec<Option<u32>>, usize) = match vs3 {
        Some(v) => {
            let mut g = vec![None; scene.materials.len()];
            for (r, &m) in v.reported.iter().enumerate() {
                g[m] = Some(r as u32);
            }
            (g, v.reported.len())
        }
        None => (Vec::new(), scene.polygons.len()),
    };
    let group: Vec<u32> = mesh
        .patches
        .iter()
        .map(|p| match vs3 {
            Some(_) => group_of_material[p.material as usize].unwrap_or(k as u32),
            None => p.surface,
        })
        .collect();
    let (grouped, group_area) = aggregate(matrix, area, &group, k + 1);
    // Drop the obstruction group.
    let rows: Vec<Vec<(u32, f32)>> = (0..k)
        .map(|i| {
            grouped
                .row_entries(i)
                .iter()
                .copied()
                .filter(|&(j, _)| (j as usize) < k)
                .collect()
        })
        .collect();
    let grouped = radiosity::system::SparseMatrix::from_rows(rows);
    let group_area = group_area[..k].to_vec();
    let enclosure = vs3.is_some_and(|v| v.control.enclosure) || a.normalize_rows;
    let fix = Enforce {
        clamp: a.clamp,
        normalize_rows: enclosure,
        symmetrize: a.symmetrize || enclosure,
    };
    let grouped = if fix != Enforce::default() {
        enforce(grouped, &group_area, fix)
    } else {
        grouped
    };
    let s = summary(&grouped, &group_area);
    let mut f = vec![0.0; k * k];
    for (i, j, v) in grouped.triplets() {
        f[i * k + j as usize] = v as f64;
    }
    let emissivity: Vec<f64> = match vs3 {
        Some(v) => v
            .reported
            .iter()
            .map(|&m| 1.0 - scene.materials[m].reflectance.r)
            .collect(),
        None => scene
            .polygons
            .iter()
            .map(|p| {
                let r = scene.materials[p.material].reflectance;
                1.0 - (r.r + r.g + r.b) / 3.0
            })
            .collect(),
    };
    let emit = a.script_f || vs3.is_some_and(|v| v.control.emit);
    if emit {
        if let Some(i) = emissivity.iter().position(|&e| e <= 0.0) {
            bail!("--script-f: surface {} has emissivity 0; total exchange factors need every emissivity in (0, 1]", i + 1);
        }
        let needed = 3 * 8 * (k as u64).pow(2);
        let limit = radiosity::pipeline::available_memory().unwrap_or(u64::MAX);
        if needed > limit {
            bail!(
                "total exchange factors for {k} surfaces need {} MiB of dense matrices but only {} MiB are available",
                needed >> 20,
                limit >> 20
            );
        }
        f = radiosity::io::view3d::script_f(&f, &emissivity);
    }
    let table = radiosity::io::view3d::ViewFactorTable {
        area: group_area,
        f,
        emissivity,
        enclosure,
        emit,
    };
    radiosity::io::view3d::write(&a.out, &table)?;
    println!(
        "rows        {k} ({}), View3D format{}",
        if vs3.is_some() {
            "View3D surfaces"
        } else {
            "faces"
        },
        if emit {
            ", total exchange factors (script-F)"
        } else {
            ""
        }
    );
    println!("method      {method} in {compute_s:.3} s");
    println!("row sums    {:.6} … {:.6}", s.min_row_sum, s.max_row_sum);
    println!(
        "reciprocity worst |A_i F_ij − A_j F_ji| / mean area = {:.3e}",
        s.worst_reciprocity
    );
    println!("wrote       {}", a.out.display());
    Ok(())
}
