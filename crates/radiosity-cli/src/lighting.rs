//! `radiosity lighting`: flags → `pipeline::lighting`, the grid CSV and the summary (with the
//! energy books, which `render --luminaires` prints too).

use crate::args::{LightingArgs, UpArg};
use anyhow::{bail, Context, Result};
use radiosity::io::{write_atomic, FileFormat, OutputError};
use radiosity::lighting::{
    gltf_luminaires, read_points, read_schedule, workplane, write_points, Luminaire, SensorPoint,
    Up,
};
use radiosity::mesh::MeshParams;
use radiosity::pipeline::{lighting, EnergyBooks, LightingSettings};
use radiosity::solve::SolverParams;
use std::io::Write as _;

/// Statistics of one grid's illuminance.
struct Stats {
    points: usize,
    mean: f64,
    min: f64,
    max: f64,
}

impl Stats {
    fn of(e: &[f64]) -> Stats {
        let mean = e.iter().sum::<f64>() / e.len().max(1) as f64;
        let min = e.iter().copied().fold(f64::INFINITY, f64::min);
        let max = e.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        Stats {
            points: e.len(),
            mean,
            min,
            max,
        }
    }

    /// U₀ = E_min / Ē (0 where the grid is dark).
    fn u0(&self) -> f64 {
        if self.mean > 0.0 {
            self.min / self.mean
        } else {
            0.0
        }
    }

    /// E_min / E_max (0 where the grid is dark).
    fn ud(&self) -> f64 {
        if self.max > 0.0 {
            self.min / self.max
        } else {
            0.0
        }
    }
}

/// Print each photometric file's warnings once (a file shared by several luminaires is read
/// once).
pub(crate) fn warn_photometry(luminaires: &[Luminaire]) {
    let mut warned = std::collections::HashSet::new();
    for l in luminaires {
        if warned.insert(std::sync::Arc::as_ptr(&l.photometry)) {
            for w in &l.photometry.warnings {
                eprintln!("radiosity: warning: {}: {w}", l.photometry.source);
            }
        }
        // The luminaire's own (its lamp's installed tilt outside the file's tilt table).
        for w in &l.warnings {
            eprintln!("radiosity: warning: luminaire '{}': {w}", l.name);
        }
    }
}

/// The energy books, one line a group when there are several, then the total: lumens emitted,
/// reaching surfaces directly, absorbed, escaped and left unshot, and the balance error
/// (the two counts of the escape apart, as a fraction of the emitted flux).
pub(crate) fn print_books(groups: &[String], books: &[EnergyBooks]) {
    let line = |name: &str, b: &EnergyBooks| {
        println!(
            "flux        {name}: emitted {:.1} lm, on surfaces directly {:.1} lm, absorbed {:.1} lm, escaped {:.1} lm, unshot {:.1} lm (balance error {:.3} %)",
            b.emitted,
            b.direct_to_surfaces,
            b.absorbed,
            b.escaped,
            b.unshot,
            100.0 * b.balance_error()
        );
    };
    if books.len() > 1 {
        for (g, b) in groups.iter().zip(books) {
            line(g, b);
        }
    }
    line("total", &EnergyBooks::total(books));
}

/// The energy books as JSON: `{"groups": [{"group", "emitted", "direct_to_surfaces",
/// "absorbed", "escaped", "unshot", "escaped_counted", "balance_error"}, …], "total": {…}}`,
/// lumens (the balance error a fraction of the emitted flux).
pub(crate) fn books_json(groups: &[String], books: &[EnergyBooks]) -> serde_json::Value {
    let one = |b: &EnergyBooks| {
        serde_json::json!({
            "emitted": b.emitted,
            "direct_to_surfaces": b.direct_to_surfaces,
            "absorbed": b.absorbed,
            "escaped": b.escaped,
            "unshot": b.unshot,
            "escaped_counted": b.escaped_counted,
            "balance_error": b.balance_error(),
        })
    };
    let per_group: Vec<serde_json::Value> = groups
        .iter()
        .zip(books)
        .map(|(g, b)| {
            let mut v = one(b);
            v["group"] = serde_json::json!(g);
            v
        })
        .collect();
    serde_json::json!({
        "groups": per_group,
        "total": one(&EnergyBooks::total(books)),
    })
}

/// The scene's up axis from `--up` and its format (glTF is always y-up), and whether it is
/// glTF. Errors: `--up z` on a glTF scene.
pub(crate) fn scene_up(a: &LightingArgs) -> Result<(Up, bool)> {
    let is_gltf = matches!(
        FileFormat::from_path(std::path::Path::new(&a.scene)),
        Some(FileFormat::Gltf | FileFormat::Glb)
    );
    let up = match (a.up, is_gltf) {
        (Some(UpArg::Z), true) => {
            bail!("--up z: {} is glTF, whose scenes are always y-up", a.scene)
        }
        (Some(UpArg::Y), _) | (None, true) => Up::Y,
        (Some(UpArg::Z), false) | (None, false) => Up::Z,
    };
    Ok((up, is_gltf))
}

/// A named grid and its points' range in the concatenated points.
pub(crate) type Grids = Vec<(String, std::ops::Range<usize>)>;

/// The `--grid` files' points, concatenated, and each grid's range. Errors: a file that
/// cannot be read or has no points.
pub(crate) fn read_grids(a: &LightingArgs) -> Result<(Vec<SensorPoint>, Grids)> {
    let mut points = Vec::new();
    let mut grids = Vec::new();
    for g in &a.grid {
        let p = read_points(g)?;
        if p.is_empty() {
            bail!("{}: no calculation points", g.display());
        }
        grids.push((
            g.display().to_string(),
            points.len()..points.len() + p.len(),
        ));
        points.extend(p);
    }
    Ok((points, grids))
}

/// `--workplane MATERIAL[:HEIGHT]`: its grid appended to `points` and `grids` (and written
/// to `--grid-out`).
pub(crate) fn add_workplane(
    a: &LightingArgs,
    scene: &radiosity::scene::Scene,
    up: Up,
    points: &mut Vec<SensorPoint>,
    grids: &mut Grids,
) -> Result<()> {
    if let Some(spec) = &a.workplane {
        let (material, height) = match spec.rsplit_once(':') {
            Some((m, h)) => match h.parse::<f64>() {
                Ok(h) if h.is_finite() => (m, h),
                _ => bail!("--workplane {spec}: the height after ':' must be a number of metres"),
            },
            None => (spec.as_str(), 0.8),
        };
        let grid = workplane(scene, material, height, a.unit.metres(), up)?;
        if let Some(p) = &a.grid_out {
            write_points(p, &grid)?;
            println!("wrote       {} ({} points)", p.display(), grid.len());
        }
        grids.push((
            format!("workplane {material}"),
            points.len()..points.len() + grid.len(),
        ));
        points.extend(grid);
    }
    Ok(())
}

/// A daylight-factor map's caption: the mean, least and greatest DF, the share of points at
/// 2 % or more (the BRE / BS 8206-2 "adequately daylit" average, applied per point), their
/// count.
fn df_caption(df: &[f64]) -> String {
    let n = df.len().max(1) as f64;
    let mean = df.iter().sum::<f64>() / n;
    let min = df.iter().copied().fold(f64::INFINITY, f64::min);
    let max = df.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let lit = df.iter().filter(|&&v| v >= 2.0).count() as f64 / n;
    format!(
        "DF mean {mean:.2} %    min {min:.2} %    max {max:.2} %    ≥ 2 %: {:.0} % of {} points",
        100.0 * lit,
        df.len()
    )
}

/// Mesh, solver and gather settings from the flags.
pub(crate) fn lighting_settings(a: &LightingArgs) -> LightingSettings {
    let mut settings = LightingSettings {
        mesh: MeshParams::Patches(a.patches),
        params: SolverParams {
            tolerance: a.tolerance,
            seed: a.seed,
            ..LightingSettings::default().params
        },
        unit_metres: a.unit.metres(),
        ..LightingSettings::default()
    };
    settings.form_factors.seed = a.seed;
    settings.gather.indirect = a.indirect_samples;
    settings
}

/// Run the command.
pub fn run(a: LightingArgs) -> Result<()> {
    let annual_only = a.occupancy.is_some()
        || a.occupancy_schedule.is_some()
        || a.sda_threshold.is_some()
        || a.sda_fraction.is_some()
        || a.ase_threshold.is_some()
        || a.ase_hours.is_some()
        || a.udi_range.is_some()
        || a.sun_method.is_some();
    if a.weather.is_some() || a.annual.is_some() || a.hourly.is_some() || annual_only {
        return crate::annual::run(a);
    }
    let Some(out_path) = a.out.clone() else {
        bail!("lighting needs --out grid.csv (or --weather FILE.epw --annual OUT.csv)");
    };
    if FileFormat::from_path(&out_path) != Some(FileFormat::Csv) {
        bail!(
            "{}: unsupported output format (use .csv)",
            out_path.display()
        );
    }
    crate::settings::check_output(&out_path)?;
    if let Some(p) = &a.surfaces_out {
        if FileFormat::from_path(p) != Some(FileFormat::Csv) {
            bail!("{}: unsupported output format (use .csv)", p.display());
        }
        if p == &out_path || a.grid.contains(p) || a.summary.as_ref() == Some(p) {
            bail!(
                "--surfaces-out {}: the same file as another input or output",
                p.display()
            );
        }
        crate::settings::check_output(p)?;
    }
    if let Some(p) = &a.grid_out {
        if p == &out_path
            || a.surfaces_out.as_ref() == Some(p)
            || a.grid.contains(p)
            || a.summary.as_ref() == Some(p)
        {
            bail!(
                "--grid-out {}: the same file as another input or output",
                p.display()
            );
        }
        crate::settings::check_output(p)?;
    }
    if let Some(p) = &a.summary {
        if p.extension().and_then(|e| e.to_str()) != Some("json") {
            bail!("{}: unsupported output format (use .json)", p.display());
        }
        if p == &out_path {
            bail!("--summary {}: the same file as --out", p.display());
        }
        crate::settings::check_output(p)?;
    }
    for g in &a.grid {
        if g == &out_path || a.summary.as_ref() == Some(g) {
            bail!("--grid {}: an output would overwrite it", g.display());
        }
    }
    if let Some(dir) = &a.pictures {
        crate::false_colour::grid::check_dir(dir)?;
    }
    let (up, is_gltf) = scene_up(&a)?;
    let mut luminaires = match &a.luminaires {
        Some(p) => read_schedule(p, up)?,
        None => Vec::new(),
    };
    if is_gltf {
        let (own, warnings) = gltf_luminaires(std::path::Path::new(&a.scene))?;
        for w in warnings {
            eprintln!("radiosity: warning: {w}");
        }
        if !own.is_empty() {
            println!("lights      {} from the glTF file", own.len());
        }
        luminaires.extend(own);
    }
    warn_photometry(&luminaires);
    let (mut points, mut grids) = read_grids(&a)?;
    let mut scene = crate::load_scene(&a.scene, false)?;
    crate::daylight::glaze(&mut scene, &a.glazing)?;
    add_workplane(&a, &scene, up, &mut points, &mut grids)?;
    let pictures = match &a.pictures {
        Some(dir) => {
            let unit = clap::ValueEnum::to_possible_value(&a.unit)
                .map(|v| v.get_name().to_string())
                .unwrap_or_default();
            Some(crate::false_colour::grid::GridPictures::prepare(
                dir, &grids, &a.grid, &points, up, &unit,
            )?)
        }
        None => None,
    };
    let settings = lighting_settings(&a);
    let day = crate::daylight::prepare(&a, up, settings)?;
    let progress = crate::report::Progress::new(a.tolerance.max(1e-12));
    let t = std::time::Instant::now();
    let result = (|| -> Result<(radiosity::pipeline::LightingResult, Option<Vec<f64>>)> {
        let Some(d) = &day else {
            return Ok((
                lighting(&scene, &luminaires, &points, &settings, &progress)?,
                None,
            ));
        };
        // Luminaires beside the sky: their light passes the panes (the luminaire pipeline
        // has no glazing; the panes are left out of its scene).
        let emits = scene
            .polygons
            .iter()
            .any(|p| scene.materials[p.material].emission.max_channel() > 0.0);
        let lum = if luminaires.is_empty() && !emits {
            None
        } else {
            let mut opaque = scene.clone();
            opaque
                .polygons
                .retain(|p| opaque.materials[p.material].transmittance <= 0.0);
            opaque.origins.clear();
            Some(lighting(
                &opaque,
                &luminaires,
                &points,
                &settings,
                &progress,
            )?)
        };
        let (r, df) = crate::daylight::run(&scene, &points, d, lum, &progress)?;
        Ok((r, Some(df)))
    })();
    progress.finish();
    let (r, daylight_factor) = result?;
    let seconds = t.elapsed().as_secs_f64();

    // grid.csv: the fixed columns, then a column a group when there are several.
    let several = r.groups.len() > 1;
    write_atomic::<OutputError>(&out_path, |out| {
        write!(out, "x,y,z,nx,ny,nz,illuminance")?;
        if several {
            for g in &r.groups {
                write!(out, ",illuminance_{g}")?;
            }
        }
        if daylight_factor.is_some() {
            write!(out, ",daylight_factor")?;
        }
        writeln!(out)?;
        let ng = r.groups.len();
        for (i, p) in points.iter().enumerate() {
            let [x, y, z] = p.position;
            let [nx, ny, nz] = p.normal;
            write!(out, "{x},{y},{z},{nx},{ny},{nz},{}", r.total[i])?;
            if several {
                for e in &r.by_group[i * ng..(i + 1) * ng] {
                    write!(out, ",{e}")?;
                }
            }
            if let Some(df) = &daylight_factor {
                write!(out, ",{}", df[i])?;
            }
            writeln!(out)?;
        }
        Ok(())
    })
    .context("writing the grid")?;

    if let Some(p) = &a.surfaces_out {
        write_atomic::<OutputError>(p, |out| {
            writeln!(out, "name,area,reflectance,illuminance,exitance,luminance")?;
            for s in &r.surfaces {
                let name = if s.name.contains([',', '"', '\n']) {
                    format!("\"{}\"", s.name.replace('"', "\"\""))
                } else {
                    s.name.clone()
                };
                writeln!(
                    out,
                    "{name},{},{},{},{},{}",
                    s.area, s.reflectance, s.illuminance, s.exitance, s.luminance
                )?;
            }
            Ok(())
        })
        .context("writing the surfaces")?;
    }

    // The summary.
    println!(
        "scene       {} ({} polygons, {} patches)",
        scene.name,
        scene.polygons.len(),
        r.patches
    );
    println!(
        "light       {} luminaires in {} group{}: {}",
        luminaires.len(),
        r.groups.len(),
        if r.groups.len() == 1 { "" } else { "s" },
        r.groups.join(", ")
    );
    if let Some(d) = &day {
        println!(
            "daylight    sky {}: {:.0} lx horizontal, zenith {:.1} cd/m²{}, ground reflectance {}",
            d.sky.model.name(),
            d.sky.horizontal_illuminance,
            d.sky.zenith_luminance,
            match d.sun {
                Some((s, en)) => format!(
                    "; sun at {}°, azimuth {}°, {:.0} lx direct normal",
                    s.altitude, s.azimuth, en
                ),
                None => String::new(),
            },
            d.settings.ground_reflectance
        );
    }
    let mut grid_json = Vec::new();
    for (name, range) in &grids {
        if let Some(df) = &daylight_factor {
            let s = Stats::of(&df[range.clone()]);
            println!(
                "daylight    {name}: daylight factor average {:.2} %, min {:.2} %, max {:.2} %",
                s.mean, s.min, s.max
            );
        }
        let s = Stats::of(&r.total[range.clone()]);
        println!(
            "grid        {name}: {} points, average {:.1} lx, min {:.1} lx, max {:.1} lx, U0 {:.3}, min/max {:.3}",
            s.points,
            s.mean,
            s.min,
            s.max,
            s.u0(),
            s.ud()
        );
        let mut g = serde_json::json!({
            "file": name,
            "points": s.points,
            "average": s.mean,
            "min": s.min,
            "max": s.max,
            "u0": s.u0(),
            "min_over_max": s.ud(),
        });
        if let Some(df) = &daylight_factor {
            let d = Stats::of(&df[range.clone()]);
            g["daylight_factor"] =
                serde_json::json!({"average": d.mean, "min": d.min, "max": d.max});
        }
        grid_json.push(g);
    }
    let luminaire_json: Vec<serde_json::Value> = luminaires
        .iter()
        .map(|l| {
            serde_json::json!({
                "name": l.name,
                "file": l.photometry.source,
                "group": l.group,
                "lumens": l.photometry.rated_flux,
                "flux": l.photometry.flux() * l.multiplier,
                "multiplier": l.multiplier,
                "kind": l.photometry.kind.to_string(),
                "tilt": l.tilt.map(|t| serde_json::json!({
                    "angle": t.angle,
                    "factor": t.factor,
                    "in_table": t.in_table,
                })),
            })
        })
        .collect();
    if !r.books.is_empty() {
        print_books(&r.groups, &r.books);
    }
    if !r.converged {
        eprintln!(
            "radiosity: warning: the interreflection stopped before its tolerance {}; the light left unshot is in the books",
            a.tolerance
        );
    }
    println!("time        {seconds:.3} s");
    if let Some((cpu, _)) = crate::report::resources() {
        println!("cpu         {cpu:.2} s (user and system, all threads)");
    }
    println!(
        "wrote       {} ({} points)",
        out_path.display(),
        points.len()
    );
    if let Some(p) = &a.surfaces_out {
        println!(
            "wrote       {} ({} surfaces)",
            p.display(),
            r.surfaces.len()
        );
    }
    if let Some(p) = &a.summary {
        let v = serde_json::json!({
            "scene": scene.name,
            "patches": r.patches,
            "groups": r.groups,
            "group_flux": r.flux,
            "grids": grid_json,
            "luminaires": luminaire_json,
            "books": books_json(&r.groups, &r.books),
            "converged": r.converged,
            "seconds": seconds,
            "daylight": day.as_ref().map(|d| serde_json::json!({
                "sky": d.sky.model.name(),
                "sky_illuminance": d.sky.horizontal_illuminance,
                "zenith_luminance": d.sky.zenith_luminance,
                "sun": d.sun.map(|(s, en)| serde_json::json!({
                    "altitude": s.altitude,
                    "azimuth": s.azimuth,
                    "illuminance": en,
                })),
                "ground_reflectance": d.settings.ground_reflectance,
                "north": a.north,
            })),
        });
        write_atomic::<OutputError>(p, |out| writeln!(out, "{v:#}"))
            .context("writing the summary")?;
        println!("wrote       {}", p.display());
    }
    if let Some(pictures) = &pictures {
        let mut written = pictures.write(&r.total)?;
        if let Some(df) = &daylight_factor {
            written.extend(pictures.write_maps(
                df,
                "daylight factor",
                "daylight-factor",
                "%",
                true,
                df_caption,
            )?);
        }
        for p in written {
            println!("wrote       {}", p.display());
        }
    }
    Ok(())
}
