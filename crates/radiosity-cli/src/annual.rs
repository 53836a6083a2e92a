//! `radiosity lighting --weather FILE.epw --annual OUT.csv`: daylight coefficients of the grid
//! points for a Tregenza/Reinhart sky (one coefficient solve), a year of the weather file's
//! Perez skies through them (`daylight::annual`), the per-point metrics CSV, the hourly CSV
//! and per grid sDA₃₀₀/₅₀%, ASE₁₀₀₀,₂₅₀ and UDI.

use crate::args::{LightingArgs, SunMethod};
use anyhow::{bail, Context, Result};
use radiosity::daylight::annual::{
    annual_by_grids, write_hourly_header, write_hourly_npy_header, write_hourly_npy_rows,
    write_hourly_rows, write_metrics_csv, AnnualParams, DaylightMatrix, EpwSkies, HourBlock,
    SkySource, Sun, SunCoefficients,
};
use radiosity::daylight::epw::read_epw;
use radiosity::daylight::metrics::{parse_schedule, MetricParams, Occupancy, PointMetrics};
use radiosity::daylight::patches::{SkyPatches, MAX_SUBDIVISION};
use radiosity::io::{FileFormat, OutputError, Staged};
use radiosity::lighting::sky::SkyFrame;
use radiosity::lighting::Up;
use radiosity::pipeline::{
    daylight_coefficients, DaylightCoefficients, DaylightSettings, DaylightSource, DirectSun,
};
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

/// `--sun-method exact`: the sun's direct light at its true position (shadow rays,
/// [`DirectSun`]) plus its interreflection taken from the patch that holds it, the patch's
/// column less its direct part scaled to the sun (E_n sin α / ∫_p sin θ dω, the patch
/// luminance of the 2-phase method): the 5-phase method's E = 3-phase − direct 3-phase +
/// direct sun (Subramaniam & Mistrick; Radiance's 5-phase tutorial).
struct ExactSun<'a> {
    direct: &'a DirectSun,
    patches: &'a SkyPatches,
    coefficients: &'a DaylightCoefficients,
}

impl SunCoefficients for ExactSun<'_> {
    fn sun(&self, to_sun: [f64; 3], out: &mut [f64]) {
        let mut direct = vec![0.0; out.len()];
        self.sun_parts(to_sun, out, &mut direct);
    }

    fn sun_parts(&self, to_sun: [f64; 3], total: &mut [f64], direct: &mut [f64]) {
        self.direct.illuminance(to_sun, direct);
        self.add_interreflection(to_sun, direct, total);
    }

    fn sun_block(&self, suns: &[Option<[f64; 3]>], total: &mut [f64], direct: &mut [f64]) {
        let nh = suns.len();
        let points = total.len() / nh.max(1);
        // The direct sun point by point through the hours (its shadow cache), then hour-major.
        let mut by_point = vec![0.0; points * nh];
        self.direct.illuminance_many(suns, &mut by_point);
        for (h, (t, d)) in total
            .chunks_exact_mut(points)
            .zip(direct.chunks_exact_mut(points))
            .enumerate()
        {
            for (i, v) in d.iter_mut().enumerate() {
                *v = by_point[i * nh + h];
            }
            match suns[h] {
                Some(s) => self.add_interreflection(s, d, t),
                None => t.fill(0.0),
            }
        }
    }
}

impl ExactSun<'_> {
    /// `total` = `direct` + the sun's interreflection taken from the patch that holds it.
    fn add_interreflection(&self, to_sun: [f64; 3], direct: &[f64], total: &mut [f64]) {
        let p = self.patches.find(to_sun);
        let c = self.coefficients;
        let ns = c.sources;
        let scale = if p < self.patches.sky_count() {
            to_sun[2].max(0.0) / self.patches.cosine_solid_angle(p)
        } else {
            0.0
        };
        for (i, (t, d)) in total.iter_mut().zip(direct.iter()).enumerate() {
            let k = i * ns + p;
            let inter = if scale > 0.0 {
                (c.total[k] - c.direct[k]).max(0.0)
            } else {
                0.0
            };
            *t = d + scale * inter;
        }
    }
}

/// Whether `--hourly` names a NumPy `.npy` file (else CSV).
fn is_npy(p: &Path) -> bool {
    p.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("npy"))
}

/// An output path: `.csv`, writable, not another input or output.
fn check_csv(flag: &str, p: &Path, a: &LightingArgs) -> Result<()> {
    if FileFormat::from_path(p) != Some(FileFormat::Csv) {
        bail!(
            "{flag} {}: unsupported output format (use .csv)",
            p.display()
        );
    }
    if a.grid.iter().any(|g| g == p)
        || a.weather.as_deref() == Some(p)
        || a.occupancy_schedule.as_deref() == Some(p)
    {
        bail!("{flag} {}: an output would overwrite an input", p.display());
    }
    crate::settings::check_output(p)
}

/// `--occupancy START-END`: the occupied hours. Errors name the flag and the value.
fn occupancy(spec: &str) -> Result<Occupancy> {
    let parsed = spec.split_once('-').and_then(|(a, b)| {
        let (a, b): (f64, f64) = (a.trim().parse().ok()?, b.trim().parse().ok()?);
        Some(Occupancy { start: a, end: b })
    });
    let Some(o) = parsed else {
        bail!("--occupancy {spec}: expected START-END in hours, e.g. 8-18");
    };
    if o.validate().is_err() {
        bail!("--occupancy {spec}: need 0 ≤ START < END ≤ 24");
    }
    Ok(o)
}

/// The metric flags over the library's defaults (`--sda-threshold` also starts UDI's
/// autonomous bin). Errors name the flag.
fn metric_params(a: &LightingArgs) -> Result<MetricParams> {
    let mut m = MetricParams::default();
    let positive = |flag: &str, v: f64| -> Result<f64> {
        if !(v.is_finite() && v > 0.0) {
            bail!("{flag} {v}: must be a positive number of lux");
        }
        Ok(v)
    };
    if let Some(v) = a.sda_threshold {
        m.sda_illuminance = positive("--sda-threshold", v)?;
        m.udi_autonomous = v;
    }
    if let Some(f) = a.sda_fraction {
        if !(f > 0.0 && f <= 1.0) {
            bail!("--sda-fraction {f}: must be in (0, 1]");
        }
        m.sda_fraction = f;
    }
    if let Some(v) = a.ase_threshold {
        m.ase_illuminance = positive("--ase-threshold", v)?;
    }
    if let Some(h) = a.ase_hours {
        m.ase_hours = h;
    }
    if let Some(spec) = &a.udi_range {
        let parsed = spec.split_once(',').and_then(|(l, h)| {
            Some((l.trim().parse::<f64>().ok()?, h.trim().parse::<f64>().ok()?))
        });
        let Some((low, high)) = parsed else {
            bail!("--udi-range {spec}: expected LOW,HIGH in lux, e.g. 100,3000");
        };
        if !(low.is_finite() && high.is_finite() && low > 0.0 && low < high) {
            bail!("--udi-range {spec}: need 0 < LOW < HIGH");
        }
        (m.udi_low, m.udi_high) = (low, high);
    }
    if !(m.udi_low..=m.udi_high).contains(&m.udi_autonomous) {
        bail!(
            "--udi-range {},{}: UDI's autonomous bin starts at the sDA threshold {} lx, which must lie within it",
            m.udi_low,
            m.udi_high,
            m.udi_autonomous
        );
    }
    m.validate()?;
    Ok(m)
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
        for (set, flag) in [
            (a.occupancy.is_some(), "--occupancy"),
            (a.occupancy_schedule.is_some(), "--occupancy-schedule"),
            (a.sda_threshold.is_some(), "--sda-threshold"),
            (a.sda_fraction.is_some(), "--sda-fraction"),
            (a.ase_threshold.is_some(), "--ase-threshold"),
            (a.ase_hours.is_some(), "--ase-hours"),
            (a.udi_range.is_some(), "--udi-range"),
            (a.sun_method.is_some(), "--sun-method"),
        ] {
            if set {
                bail!("{flag} is part of an annual run: it needs --weather FILE.epw and --annual OUT.csv");
            }
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
    let occupancy = match &a.occupancy {
        Some(spec) => occupancy(spec)?,
        None => Occupancy::default(),
    };
    if a.occupancy.is_some() && a.occupancy_schedule.is_some() {
        bail!("--occupancy and --occupancy-schedule both set the occupied hours: give one");
    }
    let metrics = metric_params(&a)?;
    check_csv("--annual", out, &a)?;
    if let Some(h) = &a.hourly {
        if !is_npy(h) {
            check_csv("--hourly", h, &a)?;
        } else if a.grid.iter().any(|g| g == h)
            || a.weather.as_deref() == Some(h)
            || a.occupancy_schedule.as_deref() == Some(h)
        {
            bail!(
                "--hourly {}: an output would overwrite an input",
                h.display()
            );
        } else {
            crate::settings::check_output(h)?;
        }
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
    let schedule = match &a.occupancy_schedule {
        Some(p) => {
            let name = p.display().to_string();
            let text = std::fs::read_to_string(p)
                .with_context(|| format!("--occupancy-schedule {name}: cannot be read"))?;
            Some(
                parse_schedule(&text, &name, epw.records.len())
                    .with_context(|| format!("--occupancy-schedule {name}"))?,
            )
        }
        None => None,
    };
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
        point_refine: a.sky_refine,
        sun_rays: a.sun_rays,
        ground_reflectance: a.ground_reflectance,
        frame: SkyFrame::new(matches!(up, Up::Y), a.north).context("--north")?,
        ..DaylightSettings::default()
    };
    settings.validate()?;
    let params = AnnualParams {
        ground_reflectance: a.ground_reflectance,
        occupancy,
        metrics,
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
    // Exact unless asked otherwise (why: docs/daylight-radiance.md, "A year").
    let exact = match a.sun_method {
        Some(SunMethod::Patch) => None,
        Some(SunMethod::Exact) | None => Some(DirectSun::new(&scene, &points, &settings)?),
    };
    let exact_sun = exact.as_ref().map(|direct| ExactSun {
        direct,
        patches: &patches,
        coefficients: &c,
    });
    let sun = match &exact_sun {
        Some(x) => Sun::Exact(x),
        None => Sun::InPatch,
    };
    let t = std::time::Instant::now();
    let skies = EpwSkies::new(&epw, &patches, &params);
    let skies = match &schedule {
        Some(s) => skies.with_schedule(s.clone())?,
        None => skies,
    };
    // EN 17037 a grid (file) at a time: each is a room's reference plane.
    let ranges: Vec<std::ops::Range<usize>> = grids.iter().map(|(_, r)| r.clone()).collect();
    let mut staged = Staged::default();
    let year = match &a.hourly {
        Some(h) => {
            let mut outcome = None;
            staged
                .write::<OutputError>(h, |w| {
                    let npy = is_npy(h);
                    if npy {
                        write_hourly_npy_header(w, skies.hours(), n)?;
                    } else {
                        write_hourly_header(w, n)?;
                    }
                    let mut failed: Option<std::io::Error> = None;
                    let mut sink = |b: &HourBlock| {
                        let written = if npy {
                            write_hourly_npy_rows(w, b)
                        } else {
                            write_hourly_rows(w, &skies, b)
                        };
                        written.map_err(|e| {
                            let msg = e.to_string();
                            failed = Some(e);
                            radiosity::daylight::DaylightError::Parameter(format!(
                                "writing the hourly illuminance: {msg}"
                            ))
                        })
                    };
                    let r = annual_by_grids(&skies, &d, sun, &params, &ranges, Some(&mut sink));
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
        None => annual_by_grids(&skies, &d, sun, &params, &ranges, None)?,
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
            .zip(&year.provision)
            .map(|((name, count, g), p)| {
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
                    "en17037": en17037_json(p),
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
                "occupancy": match &a.occupancy_schedule {
                    Some(p) => serde_json::json!(p.display().to_string()),
                    None => serde_json::json!([params.occupancy.start, params.occupancy.end]),
                },
                "thresholds": {
                    "sda_illuminance": params.metrics.sda_illuminance,
                    "sda_fraction": params.metrics.sda_fraction,
                    "ase_illuminance": params.metrics.ase_illuminance,
                    "ase_hours": params.metrics.ase_hours,
                    "udi": [params.metrics.udi_low, params.metrics.udi_autonomous, params.metrics.udi_high],
                },
                "ground_reflectance": a.ground_reflectance,
                "north": a.north,
                "sun": if exact.is_some() { "exact" } else { "patch" },
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
        "weather     {} ({}): {} hours, {} lit, {} occupied ({})",
        weather.display(),
        epw.location.city,
        year.hours,
        year.lit_hours,
        m.occupied_hours,
        match &a.occupancy_schedule {
            Some(p) => format!("schedule {}", p.display()),
            None => format!("{}:00–{}:00", params.occupancy.start, params.occupancy.end),
        }
    );
    println!(
        "sky         {} patches (MF:{}), ground reflectance {}, {}",
        patches.sky_count(),
        a.sky_patches,
        a.ground_reflectance,
        if exact.is_some() {
            "sun exact (direct at its position, interreflection from its patch)"
        } else {
            "sun in its patch"
        }
    );
    for (name, count, g) in &grid_metrics {
        println!(
            "annual      {name}: {count} points, sDA{}/{}% {:.1} %, ASE{},{} {:.1} %, UDI fell short {:.1} %, useful {:.1} % (supplementary {:.1} %, autonomous {:.1} %), exceeded {:.1} %",
            params.metrics.sda_illuminance,
            100.0 * params.metrics.sda_fraction,
            100.0 * g.sda,
            params.metrics.ase_illuminance,
            params.metrics.ase_hours,
            100.0 * g.ase,
            100.0 * g.udi[0],
            100.0 * (g.udi[1] + g.udi[2]),
            100.0 * g.udi[1],
            100.0 * g.udi[2],
            100.0 * g.udi[3]
        );
    }
    for ((name, _, _), p) in grid_metrics.iter().zip(&year.provision) {
        let [minimum, medium, high] = p.shares;
        println!(
            "EN 17037    {name}: daylight provision {} ({} daylight hours; share of them with 300 lx over 50 % / 100 lx over 95 % of the points {:.1} / {:.1} %, 500/300 lx {:.1} / {:.1} %, 750/500 lx {:.1} / {:.1} %)",
            p.level_name(),
            p.daylight_hours,
            100.0 * minimum[0],
            100.0 * minimum[1],
            100.0 * medium[0],
            100.0 * medium[1],
            100.0 * high[0],
            100.0 * high[1]
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

/// EN 17037's daylight provision of a grid as JSON: the level met, the daylight hours, and
/// per level its illuminances and the shares of daylight hours meeting each.
fn en17037_json(p: &radiosity::daylight::provision::Provision) -> serde_json::Value {
    use radiosity::daylight::provision::LEVELS;
    let levels: serde_json::Map<String, serde_json::Value> = LEVELS
        .iter()
        .zip(&p.shares)
        .map(|(&(name, target, minimum), s)| {
            (
                name.to_string(),
                serde_json::json!({
                    "target_illuminance": target,
                    "minimum_illuminance": minimum,
                    "target_hours_share": s[0],
                    "minimum_hours_share": s[1],
                }),
            )
        })
        .collect();
    serde_json::json!({
        "level": p.level_name(),
        "daylight_hours": p.daylight_hours,
        "levels": levels,
    })
}
