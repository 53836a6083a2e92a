//! `radiosity form-factors`: a view-factor matrix for a scene, for radiative heat transfer.

use crate::args::FormFactorsArgs;
use anyhow::{bail, Result};
use radiosity::accel::Bvh;
use radiosity::export::{write_patch_table, PatchRow};
use radiosity::formfactor::{aggregate, enforce, summary, Enforce, Estimator, Params, Storage};
use radiosity::geom::Vec3;
use radiosity::io::{matrix_market, FileFormat};
use radiosity::mesh::{check_planar, Mesh, MeshParams};
use radiosity::observe::Event;
use radiosity::scene::vector_area;
use std::time::Instant;

fn ext_is(path: &std::path::Path, format: FileFormat) -> bool {
    FileFormat::from_path(path) == Some(format)
}

/// Run the command.
pub fn run(a: FormFactorsArgs) -> Result<()> {
    let method = a.method.0;
    if a.resolution < 2 {
        bail!(
            "--resolution {}: at least 2 pixels along a face are needed",
            a.resolution
        );
    }
    if a.samples == 0 {
        bail!("--samples 0: at least one point per patch is needed");
    }
    if a.rays == 0 {
        bail!("--rays 0: at least one ray per row is needed");
    }
    let storage: Storage = a.storage.into();
    if !ext_is(&a.out, FileFormat::MatrixMarket) {
        bail!(
            "{}: unsupported output format (use .mtx, Matrix Market)",
            a.out.display()
        );
    }
    crate::settings::check_output(&a.out)?;
    if let Some(p) = &a.patches_out {
        if !ext_is(p, FileFormat::Csv) {
            bail!("{}: unsupported output format (use .csv)", p.display());
        }
        crate::settings::check_output(p)?;
    }
    let mesh_params = match (a.faces, a.patches, a.max_edge) {
        (true, _, _) => MeshParams::Faces,
        (_, _, Some(l)) if !(l.is_finite() && l > 0.0) => {
            bail!("--max-edge {l}: must be a positive length")
        }
        (_, _, Some(l)) => MeshParams::MaxEdge(l),
        (_, Some(0), _) => bail!("--patches 0: at least one patch is needed"),
        (_, Some(n), _) => MeshParams::Patches(n),
        (false, None, None) => MeshParams::default(),
    };
    crate::settings::threads(a.threads)?;
    let scene = crate::load_scene(&a.scene, false)?;
    // View factors need geometry, not light.
    scene.validate_geometry()?;
    if a.faces {
        check_planar(&scene)?;
    }
    let t = Instant::now();
    let memory = radiosity::pipeline::MemoryCheck {
        limit: radiosity::pipeline::available_memory().unwrap_or(u64::MAX),
        stored_rows: true,
        // Entries a row can hold at most: one per ray; one per pixel (or disc cell) of each
        // sample point; every other patch for the analytic method.
        rays: {
            use radiosity::formfactor::FormFactorMethod as M;
            let pixels = (a.resolution as u64).pow(2) * 3 * a.samples as u64;
            match method {
                M::MonteCarlo => a.rays,
                M::Hemicube | M::Tetrahedron | M::Hemisphere => pixels.min(u32::MAX as u64) as u32,
                M::Analytic => u32::MAX,
            }
        },
    };
    // A view-factor matrix is stored whatever the method: the remedy is fewer patches.
    let too_big = |e: radiosity::Error| {
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
    };
    memory
        .before_meshing(&scene, mesh_params)
        .map_err(too_big)?;
    let mesh = Mesh::build(&scene, mesh_params)?;
    memory.check(mesh.len() as u64).map_err(too_big)?;
    let bvh = Bvh::build(&mesh);
    let params = Params {
        method,
        resolution: a.resolution,
        samples: a.samples,
        rays: a.rays,
        seed: a.seed,
        ..Params::default()
    };
    let estimator = Estimator::new(&mesh, &bvh, params)?;
    let bar = indicatif::ProgressBar::new(mesh.len() as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{spinner} form factors {pos}/{len} rows [{bar:30}] {elapsed_precise} (eta {eta})",
        )
        .expect("valid template")
        .progress_chars("=> "),
    );
    let matrix = estimator
        .matrix(storage, &|e: Event<'_>| {
            if let Event::Progress { done, .. } = e {
                bar.set_position(done)
            }
        })
        .into_sparse();
    bar.finish_and_clear();
    let compute_s = t.elapsed().as_secs_f64();
    let area: Vec<f64> = mesh.patches.iter().map(|p| p.area as f64).collect();

    // One row per face, or per patch.
    let (matrix, area, rows) = if a.faces {
        let group: Vec<u32> = mesh.patches.iter().map(|p| p.surface).collect();
        let (m, face_area) = aggregate(&matrix, &area, &group, scene.polygons.len());
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
            "method {method}, resolution {}, samples {}, rays {}, seed {}, {}",
            a.resolution,
            a.samples,
            a.rays,
            a.seed,
            if a.faces {
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
        if a.faces { "faces" } else { "patches" },
        matrix.nnz(),
        100.0 * s.fill
    );
    println!("method      {method} in {compute_s:.3} s");
    println!("row sums    {:.6} … {:.6}", s.min_row_sum, s.max_row_sum);
    println!(
        "reciprocity worst |A_i F_ij − A_j F_ji| / mean area = {:.3e}",
        s.worst_reciprocity
    );
    println!("wrote       {}", a.out.display());
    if let Some(p) = &a.patches_out {
        println!("wrote       {}", p.display());
    }
    Ok(())
}
