//! Daylight: the sky, the sun and the ground outside as sources at infinity (issue 58).
//!
//! Each *column* of light is one source: the whole sky of a [`Sky`] (with the ground it
//! lights), the sun (with the ground it lights), or, for daylight coefficients, one patch of
//! a subdivided sky of unit luminance or one sun position of unit direct normal illuminance.
//! Radiosity is linear in its sources, so columns add, and a sky given as patch luminances is
//! the coefficient matrix times those luminances ([`daylight_coefficients`]).
//!
//! Per column the pipeline
//! 1. integrates, at each patch's centre and each sensor point, the light arriving straight
//!    from outside: `rays` directions cosine-distributed about the normal, stratified
//!    (a k × k grid of Malley's map, one jittered direction a cell), each either blocked by
//!    the opaque geometry or escaping, through any glazing it crosses (× τ(θ) a pane,
//!    [`Glazing`]), to the sky (luminance L(ω) above the horizon) or the ground (below it:
//!    luminance ρ_g E_h/π, E_h the unobstructed horizontal illuminance of the column's sky and
//!    sun); E ≈ π/N Σ L τ. The sun: shadow rays to stratified points of its disc (0.533°),
//!    E = E_n cos θ × the mean visibility × τ;
//! 2. solves the interreflection B = ρE + ρ F B (step 1 at the patches as E) on one stored
//!    sparse F, for blocks of 32 columns at once by Jacobi sweeps (the Neumann series, one
//!    bounce a sweep, each row of F read once for the whole block), to the settings'
//!    tolerance on the unshot luminous flux;
//! 3. adds at each sensor point the light arriving from the surfaces: the sensor's own sky
//!    rays that hit a patch's front read its exitance, E = (1/N) Σ B_hit (cosine sampling),
//!    a linear map from the solution to the points, traced once and applied to every
//!    column (so daylight coefficients add up exactly, and 145 columns cost 145 sums).
//!
//! Glazing (materials with a transmittance) is left out of the interreflection's mesh and
//! every ray that meets a pane branches, passed with τ(θ) and mirrored with R(θ)
//! ([`super::panes`]): the sky rays at patches and points, the points' gather of the
//! surfaces, and the form factors, which with panes are Monte Carlo rows of weighted rays
//! (whatever the settings' method), so that diffuse light crosses a pane both ways with its
//! hemispherical transmittance τ_d and the pane absorbs the rest. The sun's shadow rays are
//! attenuated by τ(θ) (its mirrored branches are not followed).

use super::lighting::{luminance, LightingSettings};
use super::panes::{End, Panes};
use super::sun_cone::{Cone, SunCones, SunGroups, Viewpoint, Wide};
use super::{patch_system, MemoryCheck};
use crate::accel::Bvh;
use crate::color::Rgb;
use crate::geom::{orthonormal_basis, Ray, Vec3};
use crate::lighting::glazing::{Glazing, GLASS_INDEX};
use crate::lighting::sky::{direction, Sky, SkyFrame, SunPosition, SUN_DIAMETER_DEG};
use crate::lighting::{LightingError, SensorPoint};
use crate::mesh::Mesh;
use crate::observe::{Event, Observer, Stage};
use crate::sampling::{stream, uniform};
use crate::scene::Scene;
use crate::Error;
use glam::DVec3;
use rayon::prelude::*;
use std::f64::consts::PI;

/// A point's patches hit by its sky rays, each with its rays' summed weight (1 a ray, less
/// through panes).
type PatchCounts = Vec<(u32, f64)>;

/// What decides a daylight calculation beyond [`LightingSettings`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DaylightSettings {
    /// Mesh, form factors, solver, gather, unit and memory, as for luminaires.
    pub lighting: LightingSettings,
    /// Sky rays at each sensor point (rounded to a square k × k of strata). Stratified
    /// sampling of a visibility edge errs about N^(−3/4): 16,384 keep a 10 % opening's sky
    /// component to a few tenths of a per cent.
    pub point_rays: u32,
    /// Refinement F of the points' sky strata (1: off): strata are traced F × F to a ray
    /// first, and only those near what sees outside at the full density (see
    /// `Outside::receive`): openings keep `point_rays` strata, walls get 1/F² of them.
    pub point_refine: u32,
    /// Sky rays at each patch's centre (its first shot; the same stratification).
    pub patch_rays: u32,
    /// Shadow rays to the sun's disc per receiver (stratified over the disc).
    pub sun_rays: u32,
    /// Reflectance of the ground plane outside, in [0, 1).
    pub ground_reflectance: f64,
    /// How the scene's axes sit in the sky frame.
    pub frame: SkyFrame,
}

impl Default for DaylightSettings {
    fn default() -> Self {
        Self {
            lighting: LightingSettings::default(),
            point_rays: 16_384,
            point_refine: 1,
            patch_rays: 1_024,
            sun_rays: 16,
            ground_reflectance: 0.2,
            frame: SkyFrame {
                up: [0.0, 0.0, 1.0],
                north: [0.0, 1.0, 0.0],
                east: [1.0, 0.0, 0.0],
            },
        }
    }
}

impl DaylightSettings {
    /// Check the ranges. Errors name the parameter.
    pub fn validate(&self) -> Result<(), LightingError> {
        if !(0.0..1.0).contains(&self.ground_reflectance) {
            return Err(LightingError::Parameter(format!(
                "ground reflectance {}: must be in [0, 1)",
                self.ground_reflectance
            )));
        }
        for (what, n) in [
            ("sky rays at points", self.point_rays),
            ("sky rays at patches", self.patch_rays),
            ("sun rays", self.sun_rays),
        ] {
            if n == 0 || n > 1 << 24 {
                return Err(LightingError::Parameter(format!(
                    "{what} {n}: must be 1 … 16777216"
                )));
            }
        }
        if !(1..=16).contains(&self.point_refine) {
            return Err(LightingError::Parameter(format!(
                "sky refinement {}: must be 1 … 16",
                self.point_refine
            )));
        }
        Ok(())
    }
}

/// One source of daylight coefficients.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum DaylightSource {
    /// A patch of the sky between two altitudes and two azimuths (degrees; azimuth clockwise
    /// from north, the range may wrap past 360, e.g. `[348, 372]`), of unit luminance
    /// (1 cd/m²). Tregenza's and Reinhart's patches are such; the zenith cap is altitude
    /// `[84, 90]`, azimuth `[0, 360]`.
    Patch {
        /// Lower and upper altitude, degrees, 0 ≤ lower < upper ≤ 90.
        altitude: [f64; 2],
        /// Start and end azimuth, degrees, start < end ≤ start + 360.
        azimuth: [f64; 2],
    },
    /// The sun's disc at this position, of unit direct normal illuminance (1 lx).
    Sun(SunPosition),
}

impl DaylightSource {
    /// Its solid angle, sr (a patch: Δaz (sin α₁ − sin α₀); the sun's disc).
    pub fn solid_angle(&self) -> f64 {
        match *self {
            DaylightSource::Patch { altitude, azimuth } => {
                (azimuth[1] - azimuth[0]).to_radians()
                    * (altitude[1].to_radians().sin() - altitude[0].to_radians().sin())
            }
            DaylightSource::Sun(_) => {
                2.0 * PI * (1.0 - (0.5 * SUN_DIAMETER_DEG).to_radians().cos())
            }
        }
    }

    /// Its central direction in the sky frame (a patch: mid altitude, mid azimuth).
    pub fn direction(&self) -> [f64; 3] {
        match *self {
            DaylightSource::Patch { altitude, azimuth } => direction(
                (0.5 * (altitude[0] + altitude[1])).to_radians(),
                (0.5 * (azimuth[0] + azimuth[1])).to_radians(),
            ),
            DaylightSource::Sun(s) => s.direction(),
        }
    }

    /// The unobstructed horizontal illuminance it gives per unit (patch: ∫ sin α dω =
    /// Δaz (sin² α₁ − sin² α₀)/2; sun: sin γ_s).
    pub fn horizontal(&self) -> f64 {
        match *self {
            DaylightSource::Patch { altitude, azimuth } => {
                let s = |a: f64| a.to_radians().sin().powi(2);
                0.5 * (azimuth[1] - azimuth[0]).to_radians() * (s(altitude[1]) - s(altitude[0]))
            }
            DaylightSource::Sun(s) => s.altitude.to_radians().sin(),
        }
    }

    fn validate(&self) -> Result<(), LightingError> {
        if let DaylightSource::Patch { altitude, azimuth } = *self {
            let ok = altitude.iter().chain(&azimuth).all(|x| x.is_finite())
                && 0.0 <= altitude[0]
                && altitude[0] < altitude[1]
                && altitude[1] <= 90.0
                && azimuth[0] < azimuth[1]
                && azimuth[1] <= azimuth[0] + 360.0;
            if !ok {
                return Err(LightingError::Parameter(format!(
                    "sky patch altitude {altitude:?}, azimuth {azimuth:?}: need 0 ≤ a₀ < a₁ ≤ 90 and az₀ < az₁ ≤ az₀ + 360"
                )));
            }
        }
        Ok(())
    }
}

/// Daylight coefficients: lux at each point per unit of each source, row-major points ×
/// sources (patches: per cd/m² of the patch's luminance; suns: per lux of direct normal
/// illuminance). The ground outside is lit by each source alone and is part of its column.
#[derive(Clone, Debug)]
pub struct DaylightCoefficients {
    /// The sources, in the order given.
    pub sources: usize,
    /// Everything: direct (through openings and glazing) and interreflected.
    pub total: Vec<f64>,
    /// Of `total`, what came straight from the sky, sun and ground.
    pub direct: Vec<f64>,
    /// Patches of the interreflection.
    pub patches: usize,
    /// Whether every column's interreflection reached the solver's tolerance.
    pub converged: bool,
}

impl DaylightCoefficients {
    /// The illuminance at each point under the source strengths `values` (cd/m² for patches,
    /// lux of direct normal illuminance for suns): E_i = Σ_k C_ik v_k.
    pub fn apply(&self, values: &[f64]) -> Vec<f64> {
        self.total
            .chunks_exact(self.sources.max(1))
            .map(|row| row.iter().zip(values).map(|(c, v)| c * v).sum())
            .collect()
    }
}

/// The illuminance from a sky (and sun) at the points.
#[derive(Clone, Debug)]
pub struct DaylightResult {
    /// `sky` (the sky and the ground it lights), then `sun` when its illuminance is > 0.
    pub groups: Vec<String>,
    /// Lux at each point, every group together.
    pub total: Vec<f64>,
    /// Lux, row-major points × groups.
    pub by_group: Vec<f64>,
    /// Of `total`, what came straight from outside.
    pub direct: Vec<f64>,
    /// Per cent of the sky's unobstructed horizontal illuminance: 100 E_sky / E_h (the `sky`
    /// group: the sky directly, the ground it lights and their interreflection; no sun).
    pub daylight_factor: Vec<f64>,
    /// Patches of the interreflection.
    pub patches: usize,
    /// Whether every group's interreflection reached the solver's tolerance.
    pub converged: bool,
}

/// The illuminance at `points` in `scene` from `sky` and, with `sun` = (position, direct
/// normal illuminance in lux > 0), the sun's disc, the ground outside lit by both, the
/// interreflection included. Errors: bad settings, glazing of an impossible transmittance,
/// meshing.
pub fn daylight(
    scene: &Scene,
    points: &[SensorPoint],
    sky: &Sky,
    sun: Option<(SunPosition, f64)>,
    settings: &DaylightSettings,
    observer: &dyn Observer,
) -> Result<DaylightResult, Error> {
    let rho_g = settings.ground_reflectance;
    let mut groups = vec!["sky".to_string()];
    let mut suns = Vec::new();
    if let Some((pos, en)) = sun {
        if !(en.is_finite() && en >= 0.0) {
            return Err(LightingError::Parameter(format!(
                "sun illuminance {en} lx: must be finite and ≥ 0"
            ))
            .into());
        }
        if en > 0.0 {
            groups.push("sun".to_string());
            let d = pos.direction();
            suns.push(SunColumn {
                direction: d,
                scale: en,
                ground: rho_g * en * d[2].max(0.0) / PI,
            });
        }
    }
    let columns = WholeSky {
        sky: *sky,
        ground: rho_g * sky.horizontal_illuminance / PI,
    };
    let c = solve_columns(scene, points, &columns, &suns, settings, observer)?;
    let ng = groups.len();
    let n = points.len();
    let total: Vec<f64> = (0..n)
        .map(|i| c.total[i * ng..(i + 1) * ng].iter().sum())
        .collect();
    let direct = (0..n)
        .map(|i| c.direct[i * ng..(i + 1) * ng].iter().sum())
        .collect();
    let eh = sky.horizontal_illuminance;
    let daylight_factor = (0..n)
        .map(|i| {
            if eh > 0.0 {
                100.0 * c.total[i * ng] / eh
            } else {
                0.0
            }
        })
        .collect();
    Ok(DaylightResult {
        groups,
        total,
        by_group: c.total,
        direct,
        daylight_factor,
        patches: c.patches,
        converged: c.converged,
    })
}

/// Daylight coefficients of `points` in `scene` for `sources` (a subdivided sky's patches,
/// Tregenza's 145 or Reinhart's finer ones, and sun positions): one column a source, each
/// the direct light integrated as in [`daylight`] (a ray counts for the patch whose altitude
/// and azimuth ranges hold its direction; rays below the horizon see the ground lit by the
/// source alone, luminance ρ_g × [`DaylightSource::horizontal`] / π) and its own
/// interreflection solve. A sky of patch luminances L_k and suns of E_n is then
/// [`DaylightCoefficients::apply`]. Sky directions that no patch holds get nothing. Errors:
/// bad settings or sources, glazing, meshing.
pub fn daylight_coefficients(
    scene: &Scene,
    points: &[SensorPoint],
    sources: &[DaylightSource],
    settings: &DaylightSettings,
    observer: &dyn Observer,
) -> Result<DaylightCoefficients, Error> {
    let rho_g = settings.ground_reflectance;
    let mut patches = Vec::new();
    let mut suns = Vec::new();
    let mut order = Vec::new(); // source k → column
    for s in sources {
        s.validate()?;
    }
    for s in sources {
        if let DaylightSource::Patch { altitude, azimuth } = *s {
            order.push(patches.len());
            patches.push(PatchBounds {
                altitude: [altitude[0].to_radians(), altitude[1].to_radians()],
                azimuth: [azimuth[0].to_radians(), azimuth[1].to_radians()],
                ground: rho_g * s.horizontal() / PI,
            });
        } else {
            order.push(usize::MAX);
        }
    }
    let np = patches.len();
    for (k, s) in sources.iter().enumerate() {
        if let DaylightSource::Sun(pos) = *s {
            order[k] = np + suns.len();
            let d = pos.direction();
            suns.push(SunColumn {
                direction: d,
                scale: 1.0,
                ground: rho_g * s.horizontal() / PI,
            });
        }
    }
    let columns = PatchSky::new(patches);
    let c = solve_columns(scene, points, &columns, &suns, settings, observer)?;
    let nc = sources.len();
    let reorder = |v: &[f64]| -> Vec<f64> {
        let mut out = vec![0.0; v.len()];
        for i in 0..points.len() {
            for (k, &col) in order.iter().enumerate() {
                out[i * nc + k] = v[i * nc + col];
            }
        }
        out
    };
    Ok(DaylightCoefficients {
        sources: nc,
        total: reorder(&c.total),
        direct: reorder(&c.direct),
        patches: c.patches,
        converged: c.converged,
    })
}

/// The sky's columns: which column a sky-frame direction above the horizon lights, and with
/// what luminance per unit of the column; the ground's luminance per unit of each column.
trait SkyColumns: Sync {
    fn columns(&self) -> usize;
    fn bin(&self, d: [f64; 3]) -> Option<(usize, f64)>;
    fn ground(&self, k: usize) -> f64;
}

/// One column: a whole [`Sky`] at its luminance.
struct WholeSky {
    sky: Sky,
    ground: f64,
}

impl SkyColumns for WholeSky {
    fn columns(&self) -> usize {
        1
    }
    fn bin(&self, d: [f64; 3]) -> Option<(usize, f64)> {
        Some((0, self.sky.luminance(d)))
    }
    fn ground(&self, _: usize) -> f64 {
        self.ground
    }
}

/// A patch of the sky in radians, and its ground luminance per unit luminance.
#[derive(Clone, Copy, Debug)]
struct PatchBounds {
    altitude: [f64; 2],
    azimuth: [f64; 2],
    ground: f64,
}

/// One column a patch of unit luminance; patches grouped by altitude band for the look-up.
struct PatchSky {
    patches: Vec<PatchBounds>,
    /// Bands (lower, upper altitude) sorted, each with its patches' indices.
    bands: Vec<([f64; 2], Vec<usize>)>,
    /// Each band's patches by where they start in azimuth, taken into [0, 2π), ascending:
    /// (start, patch).
    starts: Vec<Vec<(f64, usize)>>,
}

impl PatchSky {
    fn new(patches: Vec<PatchBounds>) -> Self {
        let mut bands: Vec<([f64; 2], Vec<usize>)> = Vec::new();
        for (k, p) in patches.iter().enumerate() {
            match bands.iter_mut().find(|(a, _)| *a == p.altitude) {
                Some((_, v)) => v.push(k),
                None => bands.push((p.altitude, vec![k])),
            }
        }
        bands.sort_by(|a, b| a.0[0].total_cmp(&b.0[0]));
        let starts = bands
            .iter()
            .map(|(_, members)| {
                let mut s: Vec<(f64, usize)> = members
                    .iter()
                    .map(|&k| {
                        let a = patches[k].azimuth[0].rem_euclid(std::f64::consts::TAU);
                        (a, k)
                    })
                    .collect();
                s.sort_by(|a, b| a.0.total_cmp(&b.0));
                s
            })
            .collect();
        Self {
            patches,
            bands,
            starts,
        }
    }

    /// Whether patch `k` holds azimuth `az` (in [0, 2π)).
    #[inline]
    fn holds(&self, k: usize, az: f64) -> bool {
        let p = &self.patches[k];
        // The azimuth measured from the patch's start, in [0, 2π).
        let from = (az - p.azimuth[0]).rem_euclid(std::f64::consts::TAU);
        from < p.azimuth[1] - p.azimuth[0]
    }
}

impl SkyColumns for PatchSky {
    fn columns(&self) -> usize {
        self.patches.len()
    }
    fn bin(&self, d: [f64; 3]) -> Option<(usize, f64)> {
        let alt = d[2].clamp(-1.0, 1.0).asin();
        let az = d[0].atan2(d[1]).rem_euclid(std::f64::consts::TAU);
        for ((a, members), starts) in self.bands.iter().zip(&self.starts) {
            if alt < a[0] || (alt >= a[1] && a[1] < std::f64::consts::FRAC_PI_2) {
                continue;
            }
            // The patch starting last at or before `az` (the last of all when none does,
            // the band's patch across north), found by bisection, and its neighbours, which
            // may also hold `az` by rounding at a boundary: the first of them in patch order
            // that holds it, as the scan over the band's patches in order finds. The scan
            // only when none does (a gap).
            let n = starts.len();
            let i = starts.partition_point(|&(s, _)| s <= az);
            let at = if i == 0 { n - 1 } else { i - 1 };
            let k = starts[at].1;
            // Well inside its patch (farther than rounding from either edge), no neighbour
            // can hold `az`.
            let p = &self.patches[k];
            let from = (az - p.azimuth[0]).rem_euclid(std::f64::consts::TAU);
            if from >= 1e-9 && from < p.azimuth[1] - p.azimuth[0] - 1e-9 {
                return Some((k, 1.0));
            }
            let near = [starts[(at + n - 1) % n].1, k, starts[(at + 1) % n].1];
            if let Some(k) = near.into_iter().filter(|&k| self.holds(k, az)).min() {
                return Some((k, 1.0));
            }
            for &k in members {
                if self.holds(k, az) {
                    return Some((k, 1.0));
                }
            }
        }
        None
    }
    fn ground(&self, k: usize) -> f64 {
        self.patches[k].ground
    }
}

/// A sun column: its sky-frame direction, direct normal illuminance, and the ground's
/// luminance it gives.
#[derive(Clone, Copy, Debug)]
struct SunColumn {
    direction: [f64; 3],
    scale: f64,
    ground: f64,
}

/// What [`solve_columns`] returns: lux at the points, row-major points × columns (sky
/// columns, then suns).
struct Columns {
    total: Vec<f64>,
    direct: Vec<f64>,
    patches: usize,
    converged: bool,
}

/// What light from outside meets: the opaque geometry and the panes.
struct Outside<'a> {
    bvh: &'a Bvh,
    glass: Option<&'a Panes>,
    frame: SkyFrame,
}

impl Outside<'_> {
    /// The transmittance along a ray that the opaque geometry does not block: the product
    /// of every pane it crosses.
    fn through_glass(&self, origin: Vec3, d: Vec3) -> f64 {
        match &self.glass {
            Some(p) => p.transmittance(origin, d),
            None => 1.0,
        }
    }

    /// The light from outside arriving at `x` facing `n` (scene frame), added into `out`
    /// (sky columns, then suns; lux per unit of each): `k × k` stratified sky rays and
    /// `sun_rays` shadow rays to each sun's disc. With `refine` F > 1 the strata are first
    /// traced F × F at a time (one ray a coarse stratum of the ⌈k/F⌉ grid); every coarse
    /// stratum whose ray, or a neighbour's, saw outside (escaped, or met a pane) is then
    /// traced at the full density, F × F rays in place of its coarse one (whose light is taken
    /// back), so openings get k × k strata and walls ⌈k/F⌉². A point's hits carry their weight
    /// relative to a stratum of the k × k grid.
    #[allow(clippy::too_many_arguments)]
    fn receive(
        &self,
        x: Vec3,
        n: Vec3,
        k: usize,
        refine: usize,
        sun_rays: usize,
        sky: &dyn SkyColumns,
        suns: &[SunColumn],
        rng: &mut crate::sampling::Rng64,
        out: &mut [f64],
        mut hits: Option<&mut Vec<(u32, f64)>>,
    ) {
        let n = n.normalize_or_zero();
        if n == Vec3::ZERO {
            return;
        }
        let origin = x + n * self.bvh.ray_offset();
        let (t, b) = orthonormal_basis(n);
        let mut ground = 0.0;
        let refine = refine.clamp(1, k.max(1));
        let kc = k.div_ceil(refine);
        // Hits' weights are relative to a stratum of the k × k grid (1 without refinement).
        let hc = (k * k) as f64 / (kc * kc) as f64;
        let wc = PI / (kc * kc) as f64;
        let mut coarse: Vec<(f32, f32)> = Vec::with_capacity(if refine > 1 { kc * kc } else { 0 });
        let mut seen: Vec<bool> = Vec::with_capacity(coarse.capacity());
        for i in 0..kc {
            for j in 0..kc {
                let u1 = (i as f32 + uniform(rng)) / kc as f32;
                let u2 = (j as f32 + uniform(rng)) / kc as f32;
                let d = concentric_cosine(n, t, b, u1, u2);
                let outside = self.shoot(
                    origin,
                    d,
                    wc,
                    hc,
                    sky,
                    out,
                    &mut ground,
                    hits.as_deref_mut(),
                );
                if refine > 1 {
                    coarse.push((u1, u2));
                    seen.push(outside);
                }
            }
        }
        if refine > 1 {
            let kf = kc * refine;
            let wf = PI / (kf * kf) as f64;
            let hf = (k * k) as f64 / (kf * kf) as f64;
            for i in 0..kc {
                for j in 0..kc {
                    let near = (i.saturating_sub(1)..(i + 2).min(kc))
                        .any(|a| (j.saturating_sub(1)..(j + 2).min(kc)).any(|c| seen[a * kc + c]));
                    if !near {
                        continue;
                    }
                    // Take the coarse ray back, then the stratum's fine rays.
                    let (u1, u2) = coarse[i * kc + j];
                    let d = concentric_cosine(n, t, b, u1, u2);
                    self.shoot(
                        origin,
                        d,
                        -wc,
                        -hc,
                        sky,
                        out,
                        &mut ground,
                        hits.as_deref_mut(),
                    );
                    for a in 0..refine {
                        for c in 0..refine {
                            let u1 = ((i * refine + a) as f32 + uniform(rng)) / kf as f32;
                            let u2 = ((j * refine + c) as f32 + uniform(rng)) / kf as f32;
                            let d = concentric_cosine(n, t, b, u1, u2);
                            self.shoot(
                                origin,
                                d,
                                wf,
                                hf,
                                sky,
                                out,
                                &mut ground,
                                hits.as_deref_mut(),
                            );
                        }
                    }
                }
            }
        }
        let nsky = sky.columns();
        for (c, o) in out[..nsky].iter_mut().enumerate() {
            *o += ground * sky.ground(c);
        }
        for (s, col) in suns.iter().zip(&mut out[nsky..]) {
            *col += ground * s.ground;
            *col += s.scale * self.sun(origin, n, s.direction, sun_rays, rng);
        }
    }

    /// One sky ray of solid-angle weight `w` (negative to take a ray back): the sky and
    /// ground it reaches through the panes added into `out` and `ground`, the patches it hits
    /// into `hits` with weight τ `hit` (`hit` being `w` over a k × k stratum's). Returns
    /// whether it saw outside (escaped, or met a pane).
    #[allow(clippy::too_many_arguments)]
    #[inline]
    fn shoot(
        &self,
        origin: Vec3,
        d: Vec3,
        w: f64,
        hit: f64,
        sky: &dyn SkyColumns,
        out: &mut [f64],
        ground: &mut f64,
        mut hits: Option<&mut Vec<(u32, f64)>>,
    ) -> bool {
        if let Some(panes) = &self.glass {
            // Every branch through and off the panes to its end.
            let frame = &self.frame;
            let mut outside = false;
            panes.follow(self.bvh, origin, d, &mut |end, tau| match end {
                End::Front(p) => {
                    outside |= tau < 1.0;
                    if let Some(list) = hits.as_deref_mut() {
                        list.push((p, tau * hit));
                    }
                }
                End::Back => outside |= tau < 1.0,
                End::Escape(e) => {
                    outside = true;
                    let ds = frame.to_sky(e.as_dvec3().to_array());
                    if ds[2] > 0.0 {
                        if let Some((c, l)) = sky.bin(ds) {
                            out[c] += w * tau * l;
                        }
                    } else {
                        *ground += w * tau;
                    }
                }
            });
            return outside;
        }
        let ray = Ray::new(origin, d);
        match hits {
            Some(list) => {
                if let Some(h) = self.bvh.closest_hit(&ray, f32::INFINITY) {
                    if h.front {
                        list.push((h.patch, hit));
                    }
                    return false;
                }
            }
            None => {
                if self.bvh.occluded(&ray, f32::INFINITY) {
                    return false;
                }
            }
        }
        let ds = self.frame.to_sky(d.as_dvec3().to_array());
        if ds[2] > 0.0 {
            if let Some((c, l)) = sky.bin(ds) {
                out[c] += w * l;
            }
        } else {
            *ground += w;
        }
        true
    }

    /// The scene-frame direction of the sun's centre, in single precision as the rays take it.
    fn sun_centre(&self, to_sun: [f64; 3]) -> Vec3 {
        let centre = self.frame.to_scene(to_sun);
        Vec3::new(centre[0] as f32, centre[1] as f32, centre[2] as f32)
    }

    /// [`Outside::sun`] where the whole disc is decided at once (`sun_cone`): every sample
    /// would find what the centre finds, 0 where an opaque polygon covers the disc, cos θ_c τ
    /// where nothing crosses it but whole panes; None when the disc must be sampled (a
    /// penumbra, or the disc across the receiver's horizon). `view` is the point's (its
    /// origin lifted off its surface) cache.
    fn sun_whole(
        &self,
        cones: &SunCones,
        view: &mut Viewpoint,
        n: Vec3,
        to_sun: [f64; 3],
    ) -> Option<f64> {
        let c = self.sun_centre(to_sun);
        let cos_c = n.dot(c);
        if cos_c <= 0.0 {
            return Some(0.0);
        }
        if cos_c <= cones.horizon_margin() {
            return None;
        }
        match cones.classify_from(view, c.as_dvec3()) {
            Cone::Blocked => Some(0.0),
            Cone::Clear(tau) => Some(cos_c as f64 * tau),
            Cone::Partial => None,
        }
    }

    /// The illuminance at `origin` (already lifted off its surface) facing `n` from a sun of
    /// unit direct normal illuminance in sky-frame direction `to_sun`: stratified points over
    /// its disc (concentric rings, equal areas, `sun_rays` rounded up to a square), each a
    /// shadow ray through the panes.
    fn sun(
        &self,
        origin: Vec3,
        n: Vec3,
        to_sun: [f64; 3],
        sun_rays: usize,
        rng: &mut crate::sampling::Rng64,
    ) -> f64 {
        let radius = (0.5 * SUN_DIAMETER_DEG).to_radians().tan() as f32;
        let m = ((sun_rays as f64).sqrt().ceil() as usize).max(1);
        let c = self.sun_centre(to_sun);
        if n.dot(c) <= 0.0 {
            return 0.0;
        }
        let (st, sb) = orthonormal_basis(c);
        // E_n is the disc's normal illuminance: E = E_n cos θ_c × the disc's mean visibility
        // and transmittance (cos θ over the disc averages to cos θ_c within (0.27°)² / 4 ≈
        // 5e-6).
        let cos_c = n.dot(c) as f64;
        let mut e = 0.0;
        let mut count = 0usize;
        for a in 0..m {
            for q in 0..m {
                let r = radius * ((a as f32 + uniform(rng)) / m as f32).sqrt();
                let phi = std::f32::consts::TAU * (q as f32 + uniform(rng)) / m as f32;
                let d = (c + st * (r * phi.cos()) + sb * (r * phi.sin())).normalize();
                count += 1;
                if n.dot(d) <= 0.0 || self.bvh.occluded(&Ray::new(origin, d), f32::INFINITY) {
                    continue;
                }
                e += cos_c * self.through_glass(origin, d);
            }
        }
        e / count as f64
    }
}

/// The sun's direct light at sensor points for any sun position (the 5-phase method's and
/// DAYSIM's direct-sun coefficients): shadow rays to the disc through the opaque geometry,
/// × τ(θ) of every pane crossed, as [`daylight`]'s sun column computes it, but with no
/// interreflection, for positions given one at a time (an annual run's hours).
pub struct DirectSun {
    bvh: Bvh,
    glass: Option<Panes>,
    frame: SkyFrame,
    points: Vec<SensorPoint>,
    sun_rays: usize,
    seed: u64,
    /// Whole-disc decisions (None: every point's disc is sampled).
    cones: Option<SunCones>,
}

impl DirectSun {
    /// The opaque scene's hierarchy (one patch a polygon) and its panes, for `points`, with
    /// the settings' sky frame, sun rays and seed. Errors: bad settings, glazing, meshing.
    pub fn new(
        scene: &Scene,
        points: &[SensorPoint],
        settings: &DaylightSettings,
    ) -> Result<DirectSun, Error> {
        settings.validate()?;
        scene.validate_geometry()?;
        let (opaque, glass) = split_panes(scene)?;
        let mesh = Mesh::build(&opaque, crate::mesh::MeshParams::Faces)?;
        let cones = SunCones::new(&mesh, glass.as_ref(), (0.5 * SUN_DIAMETER_DEG).to_radians());
        Ok(DirectSun {
            bvh: Bvh::build(&mesh),
            cones: Some(cones),
            glass,
            frame: settings.frame,
            points: points.to_vec(),
            sun_rays: settings.sun_rays as usize,
            seed: settings.lighting.params.seed,
        })
    }

    /// Every point's disc sampled, none decided whole (the reference for the whole-disc
    /// decisions).
    #[cfg(test)]
    fn sampled_only(mut self) -> DirectSun {
        self.cones = None;
        self
    }

    /// The illuminance at every point (lx) from a sun of 1 lx direct normal illuminance in
    /// sky-frame direction `to_sun` (x east, y north, z up), into `out`. The random streams
    /// are keyed by the point and the direction, so a value does not depend on the order or
    /// the threads of the calls.
    pub fn illuminance(&self, to_sun: [f64; 3], out: &mut [f64]) {
        for (i, o) in out.iter_mut().enumerate().take(self.points.len()) {
            *o = match self.receiver(i) {
                Some((origin, n)) => {
                    let mut view = Viewpoint::new(origin.as_dvec3());
                    self.at(i, origin, n, to_sun, &mut view)
                }
                None => 0.0,
            };
        }
    }

    /// The illuminance at every point (lx) from a sun of 1 lx direct normal illuminance in
    /// each of the sky-frame directions `suns` (None: no sun, 0), point-major into `out`
    /// (`out[i * suns.len() + h]`): the points in parallel, each through every direction with
    /// its own cache of what it sees (`sun_cone::Viewpoint`), the suns grouped by direction
    /// so that a group whose wide cone is decided whole is decided for all its suns at once
    /// (`sun_cone::SunGroups`). The values are [`DirectSun::illuminance`]'s, bit for bit.
    pub fn illuminance_many(&self, suns: &[Option<[f64; 3]>], out: &mut [f64]) {
        let nh = suns.len();
        if nh == 0 {
            return;
        }
        let outside = Outside {
            bvh: &self.bvh,
            glass: self.glass.as_ref(),
            frame: self.frame,
        };
        // The suns' scene-frame directions as the rays take them, grouped by direction.
        let groups = self.cones.as_ref().map(|cones| {
            let dirs: Vec<(usize, DVec3)> = suns
                .iter()
                .enumerate()
                .filter_map(|(h, s)| {
                    let c = outside.sun_centre((*s)?).as_dvec3().normalize_or_zero();
                    (c != DVec3::ZERO).then_some((h, c))
                })
                .collect();
            // τ of every pane class for every sun (the same for every point).
            let mut taus = vec![0.0; cones.pane_classes() * nh];
            for (class, row) in taus.chunks_exact_mut(nh.max(1)).enumerate() {
                for &(h, c) in &dirs {
                    row[h] = cones.class_transmittance(class, c);
                }
            }
            (cones, SunGroups::new(cones, &dirs), taus)
        });
        out.par_chunks_mut(nh)
            .take(self.points.len())
            .enumerate()
            .for_each(|(i, row)| {
                let Some((origin, n)) = self.receiver(i) else {
                    row.fill(0.0);
                    return;
                };
                let mut view = Viewpoint::new(origin.as_dvec3());
                let Some((cones, groups, taus)) = &groups else {
                    for (o, s) in row.iter_mut().zip(suns) {
                        *o = match s {
                            Some(d) => self.at(i, origin, n, *d, &mut view),
                            None => 0.0,
                        };
                    }
                    return;
                };
                // Every entry is written below but for the hours without a sun.
                row.fill(0.0);
                let one = |h: usize, view: &mut Viewpoint| match suns[h] {
                    Some(d) => self.at(i, origin, n, d, view),
                    None => 0.0,
                };
                if groups.nodes.is_empty() {
                    return;
                }
                let mut stack = [0u32; 64];
                let mut top = 1;
                while top > 0 {
                    top -= 1;
                    let k = stack[top] as usize;
                    let g = groups.nodes[k];
                    let wide = match g.aperture {
                        Some(ap) => cones.classify_wide(&mut view, g.axis, ap),
                        None => Wide::Partial,
                    };
                    match wide {
                        Wide::Partial if g.child != u32::MAX && top + 2 <= stack.len() => {
                            stack[top] = g.child;
                            stack[top + 1] = g.child + 1;
                            top += 2;
                        }
                        Wide::Partial => {
                            for &h in groups.members(k) {
                                row[h] = one(h, &mut view);
                            }
                        }
                        // Every member's disc is covered (its value 0, as `at` finds it).
                        Wide::Blocked => {}
                        Wide::Clear { panes, count } => {
                            let margin = cones.horizon_margin();
                            for &h in groups.members(k) {
                                let Some(d) = suns[h] else { continue };
                                let c = outside.sun_centre(d);
                                let cos_c = n.dot(c);
                                if cos_c <= 0.0 {
                                    continue;
                                }
                                if cos_c <= margin {
                                    row[h] = one(h, &mut view);
                                    continue;
                                }
                                let mut tau = 1.0;
                                for &p in &panes[..count] {
                                    tau *= match cones.pane_class(p) {
                                        Some(class) => taus[class * nh + h],
                                        None => cones
                                            .transmittance(&[p], c.as_dvec3().normalize_or_zero()),
                                    };
                                }
                                row[h] = cos_c as f64 * tau;
                            }
                        }
                    }
                }
            });
    }

    /// Point `i`'s ray origin (lifted off its surface) and unit normal; None for a point
    /// without a direction.
    fn receiver(&self, i: usize) -> Option<(Vec3, Vec3)> {
        let p = &self.points[i];
        let v = |a: [f64; 3]| Vec3::new(a[0] as f32, a[1] as f32, a[2] as f32);
        let n = v(p.normal).normalize_or_zero();
        (n != Vec3::ZERO).then(|| (v(p.position) + n * self.bvh.ray_offset(), n))
    }

    /// Point `i`'s illuminance from a sun of 1 lx in direction `to_sun`, from `origin` facing
    /// `n`; `view` its cache. The random stream (made only when the disc is sampled) is keyed
    /// by the point and the direction, so a value does not depend on the order or the threads
    /// of the calls.
    fn at(&self, i: usize, origin: Vec3, n: Vec3, to_sun: [f64; 3], view: &mut Viewpoint) -> f64 {
        let outside = Outside {
            bvh: &self.bvh,
            glass: self.glass.as_ref(),
            frame: self.frame,
        };
        if let Some(cones) = &self.cones {
            if let Some(e) = outside.sun_whole(cones, view, n, to_sun) {
                return e;
            }
        }
        let key = to_sun
            .iter()
            .fold(0u64, |h, v| h.rotate_left(21) ^ v.to_bits());
        let mut rng = stream(self.seed, 0x0053_554E, i as u64, key);
        outside.sun(origin, n, to_sun, self.sun_rays, &mut rng)
    }
}

/// A direction about `n` (frame `t, b, n`) with density cos θ/π: Shirley & Chiu's
/// concentric map of the unit square onto the disc, lifted onto the hemisphere (Malley).
/// Unlike the polar map it keeps square strata compact, so fewer of them straddle an
/// opening's edge.
#[inline]
fn concentric_cosine(n: Vec3, t: Vec3, b: Vec3, u1: f32, u2: f32) -> Vec3 {
    let (a, c) = (2.0 * u1 - 1.0, 2.0 * u2 - 1.0);
    let (r, phi) = if a == 0.0 && c == 0.0 {
        (0.0, 0.0)
    } else if a.abs() > c.abs() {
        (a, std::f32::consts::FRAC_PI_4 * (c / a))
    } else {
        (
            c,
            std::f32::consts::FRAC_PI_2 - std::f32::consts::FRAC_PI_4 * (a / c),
        )
    };
    let (s, co) = phi.sin_cos();
    let z = (1.0 - r * r).max(0.0).sqrt();
    t * (r * co) + b * (r * s) + n * z
}

/// The scene without its panes (materials with a transmittance), and the panes. Errors: a
/// pane of an impossible transmittance (its material named), meshing the panes.
fn split_panes(scene: &Scene) -> Result<(Scene, Option<Panes>), Error> {
    let mut panes = Vec::with_capacity(scene.materials.len());
    for m in &scene.materials {
        panes.push(if m.transmittance > 0.0 {
            let g = Glazing::new(m.transmittance, m.ior.unwrap_or(GLASS_INDEX))
                .map_err(|e| LightingError::Parameter(format!("material '{}': {e}", m.name)))?;
            Some(g)
        } else {
            None
        });
    }
    let mut opaque = scene.clone();
    opaque.polygons.retain(|p| panes[p.material].is_none());
    opaque.origins.clear();
    let glass = Panes::new(scene, panes)?;
    Ok((opaque, glass))
}

/// The columns' direct light at the patches and points, their interreflections and the
/// gathers: lux at the points per column.
fn solve_columns(
    scene: &Scene,
    points: &[SensorPoint],
    sky: &dyn SkyColumns,
    suns: &[SunColumn],
    settings: &DaylightSettings,
    observer: &dyn Observer,
) -> Result<Columns, Error> {
    settings.validate()?;
    let ls = &settings.lighting;
    scene.validate_geometry()?;
    ls.mesh.validate()?;
    ls.form_factors.validate()?;
    ls.params.validate()?;
    let (opaque, mut glass) = split_panes(scene)?;
    let limit = ls.memory_limit.bytes();
    let memory = MemoryCheck {
        limit,
        stored_rows: true,
        rays: ls.form_factors.rays,
    };
    memory.before_meshing(&opaque, ls.mesh)?;
    observer.event(Event::Stage(Stage::Mesh));
    let mesh = Mesh::build(&opaque, ls.mesh)?;
    memory.check(mesh.len() as u64)?;
    observer.event(Event::Stage(Stage::Bvh));
    let bvh = Bvh::build(&mesh);
    if let Some(g) = glass.as_mut() {
        g.join(&mesh);
    }
    let base = patch_system(&opaque, &mesh);
    let outside = Outside {
        bvh: &bvh,
        glass: glass.as_ref(),
        frame: settings.frame,
    };
    let nc = sky.columns() + suns.len();
    let seed = ls.params.seed;
    let side = |rays: u32| ((rays as f64).sqrt().round() as usize).max(1);
    let (kp, kx) = (side(settings.patch_rays), side(settings.point_rays));
    let sun_rays = settings.sun_rays as usize;
    // Step 1: the direct light, patches × columns and points × columns.
    let at_patches: Vec<f64> = mesh
        .patches
        .par_iter()
        .enumerate()
        .flat_map_iter(|(p, patch)| {
            let mut rng = stream(seed, 0x0044_4159, 0, p as u64);
            let mut out = vec![0.0; nc];
            outside.receive(
                patch.centre,
                patch.normal,
                kp,
                1,
                sun_rays,
                sky,
                suns,
                &mut rng,
                &mut out,
                None,
            );
            out
        })
        .collect();
    // At the points the same rays that miss the scene bring the sky, and those that hit a
    // patch's front read its exitance: E_from_surfaces = (1/N) Σ B_hit (cosine sampling),
    // kept as each point's patches and their ray counts, a linear map applied to every
    // column's solution.
    let at_points: Vec<(Vec<f64>, PatchCounts)> = points
        .par_iter()
        .enumerate()
        .map(|(i, p)| {
            let mut rng = stream(seed, 0x0044_4159, 1, i as u64);
            let mut out = vec![0.0; nc];
            let mut hits = Vec::new();
            let v = |a: [f64; 3]| Vec3::new(a[0] as f32, a[1] as f32, a[2] as f32);
            outside.receive(
                v(p.position),
                v(p.normal),
                kx,
                settings.point_refine as usize,
                sun_rays,
                sky,
                suns,
                &mut rng,
                &mut out,
                Some(&mut hits),
            );
            hits.sort_unstable_by_key(|&(p, _)| p);
            let mut counted: PatchCounts = Vec::new();
            for (h, w) in hits {
                match counted.last_mut() {
                    Some((q, c)) if *q == h => *c += w,
                    _ => counted.push((h, w)),
                }
            }
            (out, counted)
        })
        .collect();
    let direct: Vec<f64> = at_points
        .iter()
        .flat_map(|(d, _)| d.iter().copied())
        .collect();
    let gather_weight = 1.0 / (kx * kx) as f64;
    // Steps 2 and 3, a block of columns at a time.
    let mut total = direct.clone();
    let mut converged = true;
    // One F for every column (its rows at the settings' fixed rays), so that the columns are
    // solved with the same operator and add up exactly.
    let any = (0..nc).any(|c| {
        (0..mesh.len())
            .any(|p| at_patches[p * nc + c] > 0.0 && base.reflectance[p].max_channel() > 0.0)
    });
    if !any {
        return Ok(Columns {
            total,
            direct,
            patches: mesh.len(),
            converged,
        });
    }
    let f = if let Some(panes) = outside.glass {
        // Through the panes: weighted Monte Carlo rows (`panes::Panes::rows`).
        let (rows, _absorbed) = panes.rows(
            &mesh,
            &bvh,
            ls.form_factors.rays,
            ls.form_factors.seed,
            &memory,
            observer,
        )?;
        rows
    } else {
        observer.event(Event::Stage(Stage::FormFactors));
        let est = crate::formfactor::Estimator::new(&mesh, &bvh, ls.form_factors)?;
        est.matrix(crate::formfactor::Storage::Sparse, observer)
            .into_sparse()
    };
    observer.event(Event::Stage(Stage::Solve));
    let n = mesh.len();
    // Three arrays of n × 3 × block values: within half the memory limit, at most BLOCK.
    let per_column = (n as u64) * 3 * 3 * 8;
    let block = ((limit / 2) / per_column.max(1)).clamp(1, BLOCK_COLUMNS as u64) as usize;
    let sweeps = ls.params.max_iterations.min(MAX_SWEEPS);
    let mut work = BlockJacobi::new(n, block);
    for c0 in (0..nc).step_by(block) {
        let m = block.min(nc - c0);
        work.load(&base.reflectance, |p, c| at_patches[p * nc + c0 + c], m);
        if !work.emits() {
            continue;
        }
        converged &= work.solve(
            &f,
            &base.reflectance,
            &base.area,
            ls.params.tolerance,
            sweeps,
            observer,
        );
        if observer.cancelled() {
            break;
        }
        let y = work.luminance();
        // E_from_surfaces = (1/N) Σ n_hits B_hit per point, the block's columns together.
        total
            .par_chunks_mut(nc)
            .zip(at_points.par_iter())
            .for_each(|(row, (_, hits))| {
                let out = &mut row[c0..c0 + m];
                for &(p, count) in hits {
                    let w = gather_weight * count;
                    let src = &y[p as usize * m..(p as usize + 1) * m];
                    for (o, v) in out.iter_mut().zip(src) {
                        *o += w * v;
                    }
                }
            });
    }
    Ok(Columns {
        total,
        direct,
        patches: mesh.len(),
        converged,
    })
}

/// Columns solved together in one block of Jacobi sweeps.
const BLOCK_COLUMNS: usize = 32;

/// Most Jacobi sweeps of a block (each one more bounce; ρ F's spectral radius below 0.99
/// reaches 10⁻⁶ in about 1,400).
const MAX_SWEEPS: u64 = 100_000;

/// The interreflection of many columns at once: B = E + ρ ∘ F B for every column, by Jacobi
/// sweeps in the shooting form (Neumann series): Δ₀ = E, Δ_{k+1} = ρ ∘ F Δ_k, B = Σ Δ_k, each
/// sweep one more bounce of every column. A patch's values lie together, channel by channel
/// (`3 m` a patch, `m` columns a channel), so a sweep reads each row of the sparse F once for
/// every column of the block: nnz(F) × 3m multiply-adds, parallel over rows, each row's sum in
/// the same order on any thread count. A column stops counting when its unshot luminous
/// flux Σ A_i Y(Δ_i) is at most `tolerance` × its emitted Σ A_i Y(E_i), as the progressive
/// solver's criterion; the block sweeps until every column has (the linear map applied to all
/// columns is then the same partial Neumann sum).
struct BlockJacobi {
    n: usize,
    /// Columns of the block's arrays (the last block may use fewer).
    capacity: usize,
    /// Columns in use.
    m: usize,
    b: Vec<f64>,
    delta: Vec<f64>,
    next: Vec<f64>,
    /// Per column: emitted and unshot luminous flux.
    emitted: Vec<f64>,
    unshot: Vec<f64>,
}

impl BlockJacobi {
    fn new(n: usize, capacity: usize) -> Self {
        let len = n * 3 * capacity;
        Self {
            n,
            capacity,
            m: capacity,
            b: vec![0.0; len],
            delta: vec![0.0; len],
            next: vec![0.0; len],
            emitted: vec![0.0; capacity],
            unshot: vec![0.0; capacity],
        }
    }

    /// E = ρ × the first shot `first(p, c)` of patch p and column c, for `m` columns.
    fn load(&mut self, rho: &[Rgb], first: impl Fn(usize, usize) -> f64, m: usize) {
        assert!(m <= self.capacity);
        self.m = m;
        let w = 3 * m;
        for (p, row) in self.b[..self.n * w].chunks_exact_mut(w).enumerate() {
            for c in 0..m {
                let e = first(p, c);
                row[c] = rho[p].r * e;
                row[m + c] = rho[p].g * e;
                row[2 * m + c] = rho[p].b * e;
            }
        }
        let len = self.n * w;
        self.delta[..len].copy_from_slice(&self.b[..len]);
    }

    /// Whether any column emits.
    fn emits(&self) -> bool {
        self.b[..self.n * 3 * self.m].iter().any(|&v| v > 0.0)
    }

    /// Per column Σ_p A_p Y(v_p) of `v` (n × 3m), into `out`.
    fn flux(v: &[f64], area: &[f64], m: usize, out: &mut [f64]) {
        out[..m].fill(0.0);
        for (row, &a) in v.chunks_exact(3 * m).zip(area) {
            for (c, o) in out[..m].iter_mut().enumerate() {
                *o += a * luminance(Rgb::new(row[c], row[m + c], row[2 * m + c]));
            }
        }
    }

    /// Sweep until every column's unshot flux is within `tolerance` of its emitted flux, or
    /// `sweeps` sweeps, or the observer cancels; whether it converged.
    fn solve(
        &mut self,
        f: &crate::system::SparseMatrix,
        rho: &[Rgb],
        area: &[f64],
        tolerance: f64,
        sweeps: u64,
        observer: &dyn Observer,
    ) -> bool {
        let (m, w, len) = (self.m, 3 * self.m, self.n * 3 * self.m);
        Self::flux(&self.b[..len], area, m, &mut self.emitted);
        let done = |unshot: &[f64], emitted: &[f64]| {
            unshot[..m]
                .iter()
                .zip(&emitted[..m])
                .all(|(u, e)| *u <= tolerance * e)
        };
        let mut k = 0;
        loop {
            Self::flux(&self.delta[..len], area, m, &mut self.unshot);
            if done(&self.unshot, &self.emitted) {
                return true;
            }
            if k >= sweeps || observer.cancelled() {
                return false;
            }
            let delta = &self.delta[..len];
            self.next[..len]
                .par_chunks_mut(w)
                .enumerate()
                .with_min_len(64)
                .for_each(|(i, row)| {
                    row.fill(0.0);
                    for &(j, fij) in f.row_entries(i) {
                        let fij = fij as f64;
                        let src = &delta[j as usize * w..(j as usize + 1) * w];
                        for (o, s) in row.iter_mut().zip(src) {
                            *o += fij * s;
                        }
                    }
                    let r = rho[i];
                    for (ch, part) in row.chunks_exact_mut(m).enumerate() {
                        let rc = [r.r, r.g, r.b][ch];
                        part.iter_mut().for_each(|v| *v *= rc);
                    }
                });
            for (b, d) in self.b[..len].iter_mut().zip(&self.next[..len]) {
                *b += d;
            }
            std::mem::swap(&mut self.delta, &mut self.next);
            k += 1;
        }
    }

    /// Y(B) of every patch and column, n × m.
    fn luminance(&self) -> Vec<f64> {
        let m = self.m;
        self.b[..self.n * 3 * m]
            .chunks_exact(3 * m)
            .flat_map(|row| {
                (0..m).map(move |c| luminance(Rgb::new(row[c], row[m + c], row[2 * m + c])))
            })
            .collect()
    }
}

#[cfg(test)]
#[path = "daylight_tests.rs"]
mod tests;
