//! `radiosity form-factors`: a view-factor matrix for a scene, for radiative heat transfer.

use crate::args::{FormFactorsArgs, MatrixFormatArg};
use anyhow::{bail, Result};
use radiosity::export::{patch_table_to, PatchRow};
use radiosity::formfactor::{
    aggregate, enforce, summary, truncate, Enforce, FactorRows, FormFactorMethod, Params, Storage,
    TruncateInfo,
};
use radiosity::geom::Vec3;
use radiosity::io::{FileFormat, OutputError, Staged};
use radiosity::mesh::{Mesh, MeshParams};
use radiosity::observe::Event;
use radiosity::pipeline::{view_factors_over, ViewFactorSettings};
use radiosity::scene::{vector_area, vs3, Scene};
use radiosity::system::SparseMatrix;
use radiosity_experiments::MemoryProbe;
use std::io::Write;
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
    crate::settings::form_factor_files(&a.scene, &a.out, a.patches_out.as_deref())?;
    if let Some(t) = a.threshold {
        if !(0.0..=1.0).contains(&t) {
            bail!("--threshold {t}: must be a number in [0, 1], as a view factor is");
        }
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
    // Total exchange factors need a dense inverse: refused before any work if it cannot fit.
    if view3d && (a.script_f || vs3.as_ref().is_some_and(|v| v.control.emit)) {
        crate::settings::dense_exchange_memory(match &vs3 {
            Some(v) => v.reported.len(),
            None => scene.polygons.len(),
        })?;
    }
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
            matrix,
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
    let (factors, truncation) = truncated(matrix, &area, a.threshold)?;
    let mut comment = vec![
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
    if let Some(t) = truncation.as_ref().filter(|t| t.dropped > 0) {
        comment.push(format!(
            "threshold {}: {} entries dropped, rows and reciprocity restored by symmetric scaling",
            t.threshold, t.dropped
        ));
    }
    // Both outputs, or neither.
    let mut staged = Staged::default();
    for (path, which) in outputs(&a.out, a.patches_out.as_deref()) {
        if which == Output::Matrix {
            staged.write::<OutputError>(path, |w| write_matrix_market(w, &factors, &comment))?;
        } else {
            staged.write::<OutputError>(path, |w| patch_table_to(w, &rows))?;
        }
    }
    staged.commit::<OutputError>()?;
    let (min_row, max_row, reciprocity) = factors.summary(&area);
    println!(
        "rows        {} ({}), {} entries, fill {:.4}%",
        factors.n(),
        if faces { "faces" } else { "patches" },
        factors.nnz(),
        100.0 * factors.nnz() as f64 / (factors.n() as f64).powi(2)
    );
    println!("method      {method} in {compute_s:.3} s");
    if let Some(t) = &truncation {
        print_truncation(t);
    }
    // + 0.0: an empty row sums to −0.0.
    println!("row sums    {:.6} … {:.6}", min_row + 0.0, max_row + 0.0);
    println!("reciprocity worst |A_i F_ij − A_j F_ji| / mean area = {reciprocity:.3e}");
    if let Some(r) = &distributed {
        crate::report::ranks(r);
    }
    println!(
        "memory      heap peak {} MiB",
        crate::alloc::Probe.peak() >> 20
    );
    println!("wrote       {}", a.out.display());
    if let Some(p) = &a.patches_out {
        println!("wrote       {}", p.display());
    }
    Ok(())
}

/// Largest row-sum error `--threshold` accepts after rebalancing.
const ROW_TOLERANCE: f64 = 1e-6;

/// The factors as written: the estimate as computed (f32), or the truncated and rebalanced
/// rows (f64, so that reciprocity holds to rounding).
enum Factors {
    Estimate(SparseMatrix),
    Truncated(FactorRows),
}

impl Factors {
    fn n(&self) -> usize {
        match self {
            Factors::Estimate(m) => m.n(),
            Factors::Truncated(f) => f.n(),
        }
    }

    fn nnz(&self) -> usize {
        match self {
            Factors::Estimate(m) => m.nnz(),
            Factors::Truncated(f) => f.nnz(),
        }
    }

    /// Row `i`'s entries into `put(j, F_ij)`, columns increasing.
    fn row(&self, i: usize, mut put: impl FnMut(usize, f64)) {
        match self {
            Factors::Estimate(m) => m
                .row_entries(i)
                .iter()
                .for_each(|&(j, v)| put(j as usize, v as f64)),
            Factors::Truncated(f) => f.row(i).iter().for_each(|&(j, v)| put(j as usize, v)),
        }
    }

    /// Smallest and largest row sum, and the worst |A_i F_ij − A_j F_ji| / mean area.
    fn summary(&self, area: &[f64]) -> (f64, f64, f64) {
        match self {
            Factors::Estimate(m) => {
                let s = summary(m, area);
                (s.min_row_sum, s.max_row_sum, s.worst_reciprocity)
            }
            Factors::Truncated(f) => {
                let (mut lo, mut hi, mut worst) = (f64::INFINITY, f64::NEG_INFINITY, 0.0f64);
                for i in 0..f.n() {
                    let s = f.row_sum(i);
                    (lo, hi) = (lo.min(s), hi.max(s));
                    for &(j, v) in f.row(i) {
                        let j = j as usize;
                        let back = f
                            .row(j)
                            .binary_search_by_key(&(i as u32), |e| e.0)
                            .map_or(0.0, |k| f.row(j)[k].1);
                        worst = worst.max(
                            (area[i] * v - area[j] * back).abs() / (0.5 * (area[i] + area[j])),
                        );
                    }
                }
                (lo, hi, worst)
            }
        }
    }
}

/// `--threshold T`: drop the entries below T and rebalance ([`truncate`]); refused when a row
/// would lose everything or the rows cannot be closed to [`ROW_TOLERANCE`]. Without T, or when
/// T drops nothing, the estimate as it is.
fn truncated(
    m: SparseMatrix,
    area: &[f64],
    threshold: Option<f64>,
) -> Result<(Factors, Option<TruncateInfo>)> {
    let Some(t) = threshold else {
        return Ok((Factors::Estimate(m), None));
    };
    let start = std::time::Instant::now();
    let (rows, mut info) =
        truncate(&m, area, t).map_err(|e| anyhow::anyhow!("--threshold {t}: {e}"))?;
    info.seconds = start.elapsed().as_secs_f64();
    if info.dropped == 0 {
        return Ok((Factors::Estimate(m), Some(info)));
    }
    if info.worst_row_error > ROW_TOLERANCE {
        bail!(
            "--threshold {t}: the {} entries kept cannot restore every row's sum: worst row-sum error {:.2e} after rebalancing ({} of {} entries, {:.2} % of the exchange area, dropped); use a smaller threshold",
            rows.nnz(),
            info.worst_row_error,
            info.dropped,
            info.entries_before,
            100.0 * info.dropped_share
        );
    }
    Ok((Factors::Truncated(rows), Some(info)))
}

/// The summary's lines about a truncation.
fn print_truncation(t: &TruncateInfo) {
    if t.dropped == 0 {
        println!(
            "threshold   {}: no entry below it; factors as estimated",
            t.threshold
        );
        return;
    }
    let (f, i, j) = t.largest_dropped;
    println!(
        "threshold   {}: dropped {} of {} entries ({:.4} % of the exchange area Σ A_i F_ij), largest dropped F[{}][{}] = {f:.3e}; {} entries below it kept as the reciprocal partners of larger ones",
        t.threshold,
        t.dropped,
        t.entries_before,
        100.0 * t.dropped_share,
        i + 1,
        j + 1,
        t.kept_below
    );
    println!(
        "rebalanced  symmetric scaling of A F, {} Newton steps ({} products with S) in {:.3} s: worst row-sum error {:.2e} (after dropping, before rebalancing: {:.2e}); reciprocity to {:.1e} relative",
        t.newton_steps, t.products, t.seconds, t.worst_row_error, t.worst_row_loss, t.worst_reciprocity
    );
}

/// Matrix Market `coordinate real general`, 1-based, rows in order, streamed from the rows
/// (the format [`radiosity::io::matrix_market::write`] writes; an estimate's f32 entries
/// printed as f32, a truncation's as f64).
fn write_matrix_market(w: &mut dyn Write, f: &Factors, comment: &[String]) -> std::io::Result<()> {
    writeln!(w, "%%MatrixMarket matrix coordinate real general")?;
    for c in comment {
        writeln!(w, "% {c}")?;
    }
    writeln!(w, "{} {} {}", f.n(), f.n(), f.nnz())?;
    match f {
        Factors::Estimate(m) => {
            for (i, j, v) in m.triplets() {
                writeln!(w, "{} {} {}", i + 1, j + 1, v)?;
            }
        }
        Factors::Truncated(f) => {
            for i in 0..f.n() {
                for &(j, v) in f.row(i) {
                    writeln!(w, "{} {} {}", i + 1, j + 1, v)?;
                }
            }
        }
    }
    Ok(())
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum Output {
    Matrix,
    Patches,
}

/// The outputs in the order they are staged: a device or pipe first, since it is written at
/// the commit and cannot be taken back, so that a failure there leaves no file in place.
fn outputs<'p>(out: &'p Path, patches: Option<&'p Path>) -> Vec<(&'p Path, Output)> {
    let mut v = vec![(out, Output::Matrix)];
    if let Some(p) = patches {
        v.push((p, Output::Patches));
    }
    v.sort_by_key(|(p, _)| std::fs::metadata(p).map_or(true, |m| m.is_file()));
    v
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
    matrix: radiosity::system::SparseMatrix,
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
    // Patch i is surface i (every facet its own surface, no obstructions: the usual View3D
    // scene): the patch matrix is the surface matrix, used as it is, with no copy
    // (aggregating would multiply each entry by A_i / A_i = 1 exactly).
    let identity = group.len() == k && group.iter().enumerate().all(|(i, &g)| g as usize == i);
    let (grouped, group_area) = if identity {
        (matrix, area.to_vec())
    } else {
        let (grouped, group_area) = aggregate(&matrix, area, &group, k + 1);
        drop(matrix);
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
        drop(grouped);
        (
            radiosity::system::SparseMatrix::from_rows(rows),
            group_area[..k].to_vec(),
        )
    };
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
    let (grouped, truncation) = truncated(grouped, &group_area, a.threshold)?;
    let (min_row, max_row, reciprocity) = grouped.summary(&group_area);
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
    // Total exchange factors need the dense inverse (its memory was checked before the
    // work began); view factors stream from the sparse rows, one row of k values at a time.
    let exchange = if emit {
        if let Some(i) = emissivity.iter().position(|&e| e <= 0.0) {
            bail!("--script-f: surface {} has emissivity 0; total exchange factors need every emissivity in (0, 1]", i + 1);
        }
        crate::settings::dense_exchange_memory(k)?;
        let mut f = vec![0.0; k * k];
        for i in 0..k {
            grouped.row(i, |j, v| f[i * k + j] = v);
        }
        Some(radiosity::io::view3d::script_f(&f, &emissivity))
    } else {
        None
    };
    let mut staged = Staged::default();
    staged.write::<OutputError>(&a.out, |w| {
        radiosity::io::view3d::write_rows_to(
            w,
            &group_area,
            &emissivity,
            enclosure,
            emit,
            |m, row| match &exchange {
                Some(f) => row.copy_from_slice(&f[m * k..(m + 1) * k]),
                None => {
                    row.fill(0.0);
                    grouped.row(m, |j, v| row[j] = v);
                }
            },
        )
    })?;
    staged.commit::<OutputError>()?;
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
    if let Some(t) = &truncation {
        print_truncation(t);
    }
    // + 0.0: an empty row sums to −0.0.
    println!("row sums    {:.6} … {:.6}", min_row + 0.0, max_row + 0.0);
    println!("reciprocity worst |A_i F_ij − A_j F_ji| / mean area = {reciprocity:.3e}");
    println!(
        "memory      heap peak {} MiB",
        crate::alloc::Probe.peak() >> 20
    );
    println!("wrote       {}", a.out.display());
    Ok(())
}
