//! `radiosity lighting --weather FILE.epw --annual OUT.csv`: daylight coefficients of the grid
//! points for a Tregenza/Reinhart sky (one coefficient solve), a year of the weather file's
//! Perez skies through them (`daylight::annual`), the per-point metrics CSV, the hourly CSV
//! and per grid sDA₃₀₀/₅₀%, ASE₁₀₀₀,₂₅₀ and UDI.

use crate::args::LightingArgs;
use anyhow::{bail, Context, Result};
use radiosity::daylight::annual::{
    annual, write_hourly_header, write_hourly_rows, write_metrics_csv, AnnualParams,
    DaylightMatrix, EpwSkies, HourBlock, Sun,
};
use radiosity::daylight::epw::read_epw;
use radiosity::daylight::metrics::PointMetrics;
use radiosity::daylight::patches::{SkyPatches, MAX_SUBDIVISION};
use radiosity::io::{FileFormat, OutputError, Staged};
use radiosity::lighting::sky::SkyFrame;
use radiosity::lighting::Up;
use radiosity::pipeline::{daylight_coefficients, DaylightSettings, DaylightSource};
use std::path::Path;

/// A grid's annual metrics: sDA (share of points with daylight autonomy ≥ 50 %), ASE (share
/// with more than 250 h of direct sun ≥ 1000 lx), the points' mean UDI shares and mean
/// daylight autonomy.
struct GridMetrics {
    sda: f64,
    ase: f64,
    udi: [f64; 4],
    autonomy: f64,
}

impl GridMetrics {
    fn of(points: &[PointMetrics]) -> GridMetrics {
        let n = points.len().max(1) as f64;
        let mut udi = [0.0; 4];
        for p in points {
            for (u, v) in udi.iter_mut().zip(p.udi) {
                *u += v / n;
            }
        }
        GridMetrics {
            sda: points.iter().filter(|p| p.in_sda).count() as f64 / n,
            ase: points.iter().filter(|p| p.in_ase).count() as f64 / n,
            udi,
            autonomy: points.iter().map(|p| p.daylight_autonomy).sum::<f64>() / n,
        }
    }
}

/// An output path: `.csv`, writable, not another input or output.
fn check_csv(flag: &str, p: &Path, a: &LightingArgs) -> Result<()> {
    if FileFormat::from_path(p) != Some(FileFormat::Csv) {
        bail!(
            "{flag} {}: unsupported output format (use .csv)",
            p.display()
        );
    }
    if a.grid.iter().any(|g| g == p) || a.weather.as_deref() == Some(p) {
        bail!("{flag} {}: an output would overwrite an input", p.display());
    }
    crate::settings::check_output(p)
}

/// Run the annual daylight command.
pub(crate) fn run(a: LightingArgs) -> Result<()> {
    let (Some(weather), Some(out)) = (&a.weather, &a.annual) else {
        if a.weather.is_some() {
            bail!("--weather needs --annual OUT.csv (the annual metrics' file)");
        }
        if a.annual.is_some() {
            bail!("--annual needs --weather FILE.epw (the year's weather)");
        }
        bail!("--hourly needs --weather FILE.epw and --annual OUT.csv");
    };
    for (set, flag) in [
        (a.sky.is_some(), "--sky"),
        (a.out.is_some(), "--out"),
        (a.luminaires.is_some(), "--luminaires"),
        (a.surfaces_out.is_some(), "--surfaces-out"),
    ] {
        if set {
            bail!("{flag} is not part of an annual run (--weather, --annual): leave it out");
        }
    }
    if !(1..=MAX_SUBDIVISION).contains(&a.sky_patches) {
        bail!(
            "--sky-patches {}: must be 1 … {MAX_SUBDIVISION} (Reinhart MF:N)",
            a.sky_patches
        );
    }
    check_csv("--annual", out, &a)?;
    if let Some(h) = &a.hourly {
        check_csv("--hourly", h, &a)?;
        if h == out {
            bail!("--hourly {}: the same file as --annual", h.display());
        }
    }
    if let Some(p) = &a.summary {
        if p.extension().and_then(|e| e.to_str()) != Some("json") {
            bail!("{}: unsupported output format (use .json)", p.display());
        }
        if p == out || a.hourly.as_ref() == Some(p) {
            bail!("--summary {}: the same file as another output", p.display());
        }
        crate::settings::check_output(p)?;
    }
    if let Some(dir) = &a.pictures {
        crate::false_colour::grid::check_dir(dir)?;
    }
    let (up, _) = crate::lighting::scene_up(&a)?;
    let epw = read_epw(weather).with_context(|| format!("--weather {}", weather.display()))?;
    let (mut points, mut grids) = crate::lighting::read_grids(&a)?;
    let mut scene = crate::load_scene(&a.scene, false)?;
    crate::daylight::glaze(&mut scene, &a.glazing)?;
    crate::lighting::add_workplane(&a, &scene, up, &mut points, &mut grids)?;
    if points.is_empty() {
        bail!("no calculation points: give --grid or --workplane");
    }
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

    // The sky's patches as daylight sources in the sky frame the `--sky` path uses. Each
    // patch's column includes the ground outside lit by that patch alone (ρ_g × its
    // horizontal illuminance / π), which is exactly the library's ground luminance
    // ρ_g (E_d + E_n sin α)/π summed over the patches (the sky vector's patches give E_d
    // and the sun's patch E_n sin α on the horizontal): the ground's own column is zero.
    let patches = SkyPatches::reinhart(a.sky_patches)?;
    let sources: Vec<DaylightSource> = (0..patches.sky_count())
        .map(|p| {
            let ([a0, a1], [z0, z1]) = patches.bounds(p);
            DaylightSource::Patch {
                altitude: [a0.to_degrees(), a1.to_degrees().min(90.0)],
                azimuth: [z0.to_degrees(), z1.to_degrees()],
            }
        })
        .collect();
    let settings = DaylightSettings {
        lighting: crate::lighting::lighting_settings(&a),
        point_rays: a.sky_rays,
        ground_reflectance: a.ground_reflectance,
        frame: SkyFrame::new(matches!(up, Up::Y), a.north).context("--north")?,
        ..DaylightSettings::default()
    };
    settings.validate()?;
    let params = AnnualParams {
        ground_reflectance: a.ground_reflectance,
        ..AnnualParams::default()
    };
    let progress = crate::report::Progress::new(a.tolerance.max(1e-12));
    let t = std::time::Instant::now();
    let c = daylight_coefficients(&scene, &points, &sources, &settings, &progress);
    progress.finish();
    let c = c?;
    let t_coefficients = t.elapsed().as_secs_f64();
    let (n, ns, np) = (points.len(), sources.len(), patches.len());
    let mut values = vec![0.0; n * np];
    for (row, src) in values.chunks_exact_mut(np).zip(c.total.chunks_exact(ns)) {
        row[..ns].copy_from_slice(src);
    }
    let d = DaylightMatrix::new(n, np, values)?;

    // The year, its outputs staged: all land or none.
    let t = std::time::Instant::now();
    let skies = EpwSkies::new(&epw, &patches, &params);
    let mut staged = Staged::default();
    let year = match &a.hourly {
        Some(h) => {
            let mut outcome = None;
            staged
                .write::<OutputError>(h, |w| {
                    write_hourly_header(w, n)?;
                    let mut failed: Option<std::io::Error> = None;
                    let mut sink = |b: &HourBlock| {
                        write_hourly_rows(w, &skies, b).map_err(|e| {
                            let msg = e.to_string();
                            failed = Some(e);
                            radiosity::daylight::DaylightError::Parameter(format!(
                                "writing the hourly illuminance: {msg}"
                            ))
                        })
                    };
                    let r = annual(&skies, &d, Sun::InPatch, &params, Some(&mut sink));
                    if let Some(e) = failed {
                        return Err(e);
                    }
                    let ok = r.is_ok();
                    outcome = Some(r);
                    if ok {
                        Ok(())
                    } else {
                        Err(std::io::Error::other("the annual run failed"))
                    }
                })
                .or_else(|e| match &outcome {
                    Some(Err(_)) => Ok(()),
                    _ => Err(e),
                })?;
            outcome.expect("the body runs the year")?
        }
        None => annual(&skies, &d, Sun::InPatch, &params, None)?,
    };
    let t_year = t.elapsed().as_secs_f64();
    let positions: Vec<[f64; 3]> = points.iter().map(|p| p.position).collect();
    staged.write::<OutputError>(out, |w| {
        write_metrics_csv(w, &year.metrics, Some(&positions))
    })?;
    let m = &year.metrics;
    let grid_metrics: Vec<(String, usize, GridMetrics)> = grids
        .iter()
        .map(|(name, r)| (name.clone(), r.len(), GridMetrics::of(&m.points[r.clone()])))
        .collect();
    if let Some(p) = &a.summary {
        let grids_json: Vec<serde_json::Value> = grid_metrics
            .iter()
            .map(|(name, count, g)| {
                serde_json::json!({
                    "file": name,
                    "points": count,
                    "sda": g.sda,
                    "ase": g.ase,
                    "daylight_autonomy": g.autonomy,
                    "udi": {
                        "fell_short": g.udi[0],
                        "supplementary": g.udi[1],
                        "autonomous": g.udi[2],
                        "exceeded": g.udi[3],
                        "useful": g.udi[1] + g.udi[2],
                    },
                })
            })
            .collect();
        let v = serde_json::json!({
            "scene": scene.name,
            "patches": c.patches,
            "converged": c.converged,
            "annual": {
                "weather": weather.display().to_string(),
                "location": epw.location.city,
                "sky_patches": patches.sky_count(),
                "hours": year.hours,
                "lit_hours": year.lit_hours,
                "occupied_hours": m.occupied_hours,
                "occupancy": [params.occupancy.start, params.occupancy.end],
                "ground_reflectance": a.ground_reflectance,
                "north": a.north,
                "sun": "patch",
                "grids": grids_json,
            },
            "seconds": {"coefficients": t_coefficients, "year": t_year},
        });
        staged.write::<OutputError>(p, |w| writeln!(w, "{v:#}"))?;
    }
    staged.commit::<OutputError>()?;

    println!(
        "scene       {} ({} polygons, {} patches)",
        scene.name,
        scene.polygons.len(),
        c.patches
    );
    println!(
        "weather     {} ({}): {} hours, {} lit, {} occupied ({}:00–{}:00)",
        weather.display(),
        epw.location.city,
        year.hours,
        year.lit_hours,
        m.occupied_hours,
        params.occupancy.start,
        params.occupancy.end
    );
    println!(
        "sky         {} patches (MF:{}), ground reflectance {}, sun in its patch",
        patches.sky_count(),
        a.sky_patches,
        a.ground_reflectance
    );
    for (name, count, g) in &grid_metrics {
        println!(
            "annual      {name}: {count} points, sDA300/50% {:.1} %, ASE1000,250 {:.1} %, UDI fell short {:.1} %, useful {:.1} % (supplementary {:.1} %, autonomous {:.1} %), exceeded {:.1} %",
            100.0 * g.sda,
            100.0 * g.ase,
            100.0 * g.udi[0],
            100.0 * (g.udi[1] + g.udi[2]),
            100.0 * g.udi[1],
            100.0 * g.udi[2],
            100.0 * g.udi[3]
        );
    }
    if !c.converged {
        eprintln!(
            "radiosity: warning: the interreflection stopped before its tolerance {}",
            a.tolerance
        );
    }
    println!("time        {t_coefficients:.3} s coefficients, {t_year:.3} s the year");
    if let Some((cpu, _)) = crate::report::resources() {
        println!("cpu         {cpu:.2} s (user and system, all threads)");
    }
    println!("wrote       {} ({n} points)", out.display());
    if let Some(h) = &a.hourly {
        println!("wrote       {} ({} hours)", h.display(), year.hours);
    }
    if let Some(p) = &a.summary {
        println!("wrote       {}", p.display());
    }
    if let Some(pictures) = &pictures {
        let autonomy: Vec<f64> = m
            .points
            .iter()
            .map(|p| 100.0 * p.daylight_autonomy)
            .collect();
        let caption = |da: &[f64]| {
            let n = da.len().max(1) as f64;
            format!(
                "DA₃₀₀: share of the {} occupied hours at 300 lx or more    mean {:.1} %    sDA₃₀₀/₅₀% {:.1} % of {} points",
                m.occupied_hours,
                da.iter().sum::<f64>() / n,
                100.0 * da.iter().filter(|&&v| v >= 50.0).count() as f64 / n,
                da.len()
            )
        };
        for p in pictures.write_maps(
            &autonomy,
            "daylight autonomy",
            "daylight-autonomy",
            "%",
            false,
            caption,
        )? {
            println!("wrote       {}", p.display());
        }
    }
    Ok(())
}
