//! `radiosity lighting --sky …`: the daylight flags → `pipeline::daylight`, merged with the
//! luminaires' result as further light groups (`sky`, `sun`).

use crate::args::LightingArgs;
use anyhow::{bail, Context, Result};
use radiosity::lighting::sky::{Sky, SkyFrame, SkyModel, SunPosition};
use radiosity::lighting::{SensorPoint, Up};
use radiosity::observe::Observer;
use radiosity::pipeline::{daylight, DaylightSettings, LightingResult, LightingSettings};
use radiosity::scene::Scene;

/// What a daylight run needs, read from the flags.
pub(crate) struct Daylight {
    pub sky: Sky,
    pub sun: Option<(SunPosition, f64)>,
    pub settings: DaylightSettings,
}

/// `--glazing NAME=TRANSMITTANCE`: those materials become clear panes. Errors: a malformed
/// value, a name no material has.
pub(crate) fn glaze(scene: &mut Scene, specs: &[String]) -> Result<()> {
    for spec in specs {
        let Some((name, t)) = spec.rsplit_once('=') else {
            bail!("--glazing {spec}: expected NAME=TRANSMITTANCE");
        };
        let t: f64 = match t.trim().parse() {
            Ok(t) if (0.0..=1.0).contains(&t) && t > 0.0 => t,
            _ => bail!("--glazing {spec}: the transmittance must be a number in (0, 1]"),
        };
        let mut found = false;
        for m in scene.materials.iter_mut().filter(|m| m.name == name) {
            m.transmittance = t;
            found = true;
        }
        if !found {
            bail!("--glazing {spec}: the scene has no material '{name}'");
        }
    }
    Ok(())
}

/// The daylight flags, or None without `--sky`.
pub(crate) fn prepare(
    a: &LightingArgs,
    up: Up,
    lighting: LightingSettings,
) -> Result<Option<Daylight>> {
    let Some(name) = &a.sky else {
        return Ok(None);
    };
    let model = SkyModel::parse(name)?;
    let sun = match &a.sun {
        Some(s) => {
            let parts: Vec<&str> = s.split(',').map(str::trim).collect();
            let nums: Option<Vec<f64>> = parts.iter().map(|p| p.parse().ok()).collect();
            match nums.as_deref() {
                Some(&[alt, az]) => {
                    Some(SunPosition::new(alt, az).with_context(|| format!("--sun {s}"))?)
                }
                _ => bail!("--sun {s}: expected ALTITUDE,AZIMUTH in degrees"),
            }
        }
        None => None,
    };
    if a.sun_illuminance > 0.0 && sun.is_none() {
        bail!("--sun-illuminance needs --sun ALTITUDE,AZIMUTH");
    }
    let sky = Sky::new(model, sun, a.sky_illuminance).context("--sky")?;
    let frame = SkyFrame::new(matches!(up, Up::Y), a.north).context("--north")?;
    let settings = DaylightSettings {
        lighting,
        point_rays: a.sky_rays,
        point_refine: a.sky_refine,
        sun_rays: a.sun_rays,
        ground_reflectance: a.ground_reflectance,
        frame,
        ..DaylightSettings::default()
    };
    settings.validate()?;
    Ok(Some(Daylight {
        sky,
        sun: sun.map(|s| (s, a.sun_illuminance)),
        settings,
    }))
}

/// Run the daylight and fold it into `result` (the luminaires', or None when there are
/// none): its groups appended, the totals added; the daylight factor at each point returned.
pub(crate) fn run(
    scene: &Scene,
    points: &[SensorPoint],
    d: &Daylight,
    result: Option<LightingResult>,
    observer: &dyn Observer,
) -> Result<(LightingResult, Vec<f64>)> {
    let day = daylight(scene, points, &d.sky, d.sun, &d.settings, observer)?;
    let n = points.len();
    let mut r = result.unwrap_or(LightingResult {
        groups: Vec::new(),
        total: vec![0.0; n],
        by_group: Vec::new(),
        direct: vec![0.0; n],
        patches: day.patches,
        flux: Vec::new(),
        surfaces: Vec::new(),
        books: Vec::new(),
        converged: true,
    });
    let (g0, g1) = (r.groups.len(), day.groups.len());
    let mut by_group = Vec::with_capacity(n * (g0 + g1));
    for i in 0..n {
        by_group.extend_from_slice(&r.by_group[i * g0..(i + 1) * g0]);
        by_group.extend_from_slice(&day.by_group[i * g1..(i + 1) * g1]);
        r.total[i] += day.total[i];
        r.direct[i] += day.direct[i];
    }
    r.by_group = by_group;
    r.groups.extend(day.groups);
    r.converged &= day.converged;
    Ok((r, day.daylight_factor))
}
