//! A year of daylight by daylight coefficients (Tregenza & Waters 1983, "Daylight
//! coefficients", *Lighting Research and Technology* 15(2):65–71).
//!
//! Light is linear in its sources: if D_ip is the illuminance at point i from patch p of the
//! sky shining alone with unit luminance (1 cd/m², all else dark), then the illuminance under
//! a sky of patch luminances L_p is E_i = Σ_p D_ip L_p. For a year, with the hourly sky
//! vectors as the columns of S (patches × hours), E = D S: one matrix product. A radiosity
//! solve per patch gives D with every interreflection; here D is an input
//! ([`DaylightMatrix`]), so anything can supply it.
//!
//! Each hour's sky vector ([`EpwSkies`]): the sun's position ([`super::solar`]) at the middle
//! of the hour, the Perez condition and efficacies ([`super::perez`]) from the record's
//! direct-normal and diffuse-horizontal irradiance and dew point, the mean relative
//! luminance of the Perez sky over each patch ([`SkyPatches::sky_means`]), scaled so that
//! an unobstructed horizontal surface receives exactly the diffuse illuminance E_d from the
//! patches (Σ_p L_p ∫_p sin θ dω = E_d: the normalisation is over the patches, as
//! `gendaymtx` does, so the discretisation does not change the sky's horizontal
//! illuminance), and the ground, a uniform luminance ρ_g (E_d + E_n sin α)/π.
//!
//! The sun ([`Sun`]) is either in its patch (the 2-phase method: its luminance over the
//! patch containing it, [`SkyPatches::add_sun`]) or at its true position through
//! [`SunCoefficients`], the illuminance at every point from a sun of unit direct normal
//! illuminance (the 5-phase method's and DAYSIM's direct-sun coefficients). Annual sunlight
//! exposure needs the direct sun apart: with the sun in its patch, it is that patch's term
//! D_ip L_sun (which includes the sunlight interreflected, so it over-counts ASE's direct-only
//! definition); with [`Sun::Exact`] it is the direct part the callback gives
//! ([`SunCoefficients::sun_parts`]) times E_n, the illuminance its whole.
//!
//! The product streams: hours go in blocks of [`AnnualParams::block_hours`], the sky vectors
//! of a block (hours × patches) are built in parallel, then each thread takes points in
//! chunks and forms their dot products with every lit hour of the block, so memory stays
//! points × block and each entry is summed by one thread in a fixed order (the result does
//! not depend on the thread count). Dark hours (no diffuse light) give 0 without a product.
//! Each block's hours go to the metrics ([`super::metrics`]) and to EN 17037's daylight
//! provision per grid ([`super::provision`], over the daylight hours chosen first from every
//! hour's diffuse horizontal illuminance, [`SkySource::diffuse_illuminance`]).

use super::epw::Epw;
use super::metrics::{Accumulator, MetricParams, Metrics, Occupancy};
use super::patches::{PatchSamples, SkyPatches};
use super::perez::{Condition, PerezSky, DEFAULT_DEW_POINT};
use super::provision::{daylight_hours, Provision, ProvisionAccumulator};
use super::solar::{solar_position, Site, SolarPosition};
use super::DaylightError;
use rayon::prelude::*;
use std::f64::consts::PI;

/// Daylight coefficients: illuminance (lx) at each point per unit luminance (cd/m²) of each
/// patch, points × patches, row-major; the patches are a [`SkyPatches`]' (the sky's, then the
/// ground).
#[derive(Clone, Debug, PartialEq)]
pub struct DaylightMatrix {
    points: usize,
    patches: usize,
    values: Vec<f64>,
}

impl DaylightMatrix {
    /// The matrix from its values (row-major, `points × patches`, finite).
    pub fn new(
        points: usize,
        patches: usize,
        values: Vec<f64>,
    ) -> Result<DaylightMatrix, DaylightError> {
        if points.checked_mul(patches) != Some(values.len()) {
            return Err(DaylightError::Parameter(format!(
                "{} daylight coefficients for {points} points × {patches} patches",
                values.len()
            )));
        }
        if let Some(k) = values.iter().position(|v| !v.is_finite()) {
            return Err(DaylightError::Parameter(format!(
                "daylight coefficient of point {} and patch {} is not finite",
                k / patches.max(1),
                k % patches.max(1)
            )));
        }
        Ok(DaylightMatrix {
            points,
            patches,
            values,
        })
    }

    /// The matrix of `f(point, patch)`.
    pub fn from_fn(
        points: usize,
        patches: usize,
        f: impl Fn(usize, usize) -> f64,
    ) -> DaylightMatrix {
        let mut values = Vec::with_capacity(points * patches);
        for i in 0..points {
            for p in 0..patches {
                values.push(f(i, p));
            }
        }
        DaylightMatrix {
            points,
            patches,
            values,
        }
    }

    /// The coefficients of an unobstructed point facing straight up: ∫_p sin θ dω for each
    /// sky patch, 0 for the ground (the closed form the tests and examples use).
    pub fn unobstructed_horizontal(patches: &SkyPatches, points: usize) -> DaylightMatrix {
        DaylightMatrix::from_fn(points, patches.len(), |_, p| patches.cosine_solid_angle(p))
    }

    /// Points.
    pub fn points(&self) -> usize {
        self.points
    }

    /// Patches.
    pub fn patches(&self) -> usize {
        self.patches
    }

    /// Point `i`'s coefficients.
    pub fn row(&self, i: usize) -> &[f64] {
        &self.values[i * self.patches..(i + 1) * self.patches]
    }
}

/// Illuminance at every point from a sun of unit direct normal illuminance (1 lx).
pub trait SunCoefficients: Sync {
    /// Write into `out` (one value a point) the illuminance from a sun in unit direction
    /// `to_sun` (x east, y north, z up) of 1 lx direct normal illuminance.
    fn sun(&self, to_sun: [f64; 3], out: &mut [f64]);

    /// The same into `total`, and into `direct` its part straight from the sun's disc (what
    /// ASE counts, IES LM-83-12's direct sunlight). By default the whole is taken as direct.
    fn sun_parts(&self, to_sun: [f64; 3], total: &mut [f64], direct: &mut [f64]) {
        self.sun(to_sun, total);
        direct.copy_from_slice(total);
    }

    /// [`SunCoefficients::sun_parts`] for many hours at once, hour-major (`total[h × points +
    /// i]`, points = `total.len() / suns.len()`); a `None` sun gives zeros. By default an
    /// hour a task; an implementation that gains from taking a point through many hours
    /// (a shadow cache) overrides it, with the same values.
    fn sun_block(&self, suns: &[Option<[f64; 3]>], total: &mut [f64], direct: &mut [f64]) {
        let points = total.len() / suns.len().max(1);
        if points == 0 {
            return;
        }
        total
            .par_chunks_mut(points)
            .zip(direct.par_chunks_mut(points))
            .zip(suns.par_iter())
            .for_each(|((t, d), s)| match s {
                Some(s) => self.sun_parts(*s, t, d),
                None => {
                    t.fill(0.0);
                    d.fill(0.0);
                }
            });
    }
}

impl<F: Fn([f64; 3], &mut [f64]) + Sync> SunCoefficients for F {
    fn sun(&self, to_sun: [f64; 3], out: &mut [f64]) {
        self(to_sun, out)
    }
}

/// Where the sun goes (see the module documentation).
#[derive(Clone, Copy)]
pub enum Sun<'a> {
    /// Into the sky patch that contains it (2-phase).
    InPatch,
    /// At its true position, by direct-sun coefficients.
    Exact(&'a dyn SunCoefficients),
}

/// The annual run's settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AnnualParams {
    /// Reflectance of the ground outside (0…1; 0.2).
    pub ground_reflectance: f64,
    /// Which hours the metrics count.
    pub occupancy: Occupancy,
    /// The metrics' thresholds.
    pub metrics: MetricParams,
    /// Hours per block of the product (168: a week).
    pub block_hours: usize,
    /// Cells per patch side for the patches' mean luminance (4: 16 cells a patch).
    pub patch_samples: usize,
}

impl Default for AnnualParams {
    fn default() -> Self {
        AnnualParams {
            ground_reflectance: 0.2,
            occupancy: Occupancy::default(),
            metrics: MetricParams::default(),
            block_hours: 168,
            patch_samples: 4,
        }
    }
}

impl AnnualParams {
    /// Check every setting is in range.
    pub fn validate(&self) -> Result<(), DaylightError> {
        if !(0.0..=1.0).contains(&self.ground_reflectance) {
            return Err(DaylightError::Parameter(format!(
                "the ground reflectance {} is outside 0…1",
                self.ground_reflectance
            )));
        }
        if !(1..=8784).contains(&self.block_hours) || !(1..=64).contains(&self.patch_samples) {
            return Err(DaylightError::Parameter(format!(
                "{} hours a block (1…8784) and {} samples a patch side (1…64)",
                self.block_hours, self.patch_samples
            )));
        }
        self.occupancy.validate()?;
        self.metrics.validate()
    }
}

/// One hour's light, besides its sky vector.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct HourLight {
    /// Whether the metrics count this hour.
    pub occupied: bool,
    /// Whether there is any light (a sky vector not all zero).
    pub lit: bool,
    /// Unit direction towards the sun.
    pub sun: [f64; 3],
    /// Direct normal illuminance, lx (0 when the sun is below the horizon).
    pub direct_normal: f64,
    /// Diffuse horizontal illuminance, lx.
    pub diffuse_horizontal: f64,
    /// With the sun in its patch: the patch and the luminance added to it.
    pub sun_patch: Option<(usize, f64)>,
}

/// A sequence of hourly skies over a patch subdivision.
pub trait SkySource: Sync {
    /// The patches the sky vectors are over.
    fn patches(&self) -> &SkyPatches;
    /// Hours.
    fn hours(&self) -> usize;
    /// Hour `h`'s month, day and hour (1…24, the hour ending) for output; `[0, 0, h]` when
    /// the source has no calendar.
    fn stamp(&self, h: usize) -> [u32; 3] {
        [0, 0, h as u32]
    }
    /// Hour `h`'s diffuse horizontal illuminance outside, lx (what its sky is scaled to);
    /// by default from [`SkySource::sky`], which also computes the sky.
    fn diffuse_illuminance(&self, h: usize) -> Result<f64, DaylightError> {
        let mut out = vec![0.0; self.patches().len()];
        Ok(self.sky(h, false, &mut out)?.diffuse_horizontal)
    }
    /// Hour `h`'s patch luminances (cd/m², the ground last) into `out`, the sun added to its
    /// patch when `sun_in_patch`; its light otherwise.
    fn sky(
        &self,
        h: usize,
        sun_in_patch: bool,
        out: &mut [f64],
    ) -> Result<HourLight, DaylightError>;
}

/// The skies of an EPW file's hours (see the module documentation).
pub struct EpwSkies<'a> {
    epw: &'a Epw,
    patches: &'a SkyPatches,
    params: AnnualParams,
    site: Site,
    /// The patches' sample directions, computed once (None past [`SAMPLE_TABLE_MAX`]
    /// directions: each hour then computes its own).
    samples: Option<PatchSamples>,
    /// Which hours are occupied, in place of the params' daily period
    /// ([`EpwSkies::with_schedule`]).
    schedule: Option<Vec<bool>>,
}

/// Most sample directions kept in a table (32 bytes each).
const SAMPLE_TABLE_MAX: usize = 1 << 22;

thread_local! {
    /// Each thread's scratch for a sky's per-row gradation terms.
    static ROWS: std::cell::RefCell<Vec<f64>> = const { std::cell::RefCell::new(Vec::new()) };
}

impl<'a> EpwSkies<'a> {
    /// The skies of `epw` over `patches`.
    pub fn new(epw: &'a Epw, patches: &'a SkyPatches, params: &AnnualParams) -> EpwSkies<'a> {
        let l = &epw.location;
        EpwSkies {
            epw,
            patches,
            params: *params,
            site: Site {
                latitude: l.latitude,
                longitude: l.longitude,
                time_zone: l.time_zone,
            },
            samples: {
                let sub = params.patch_samples.max(1);
                (patches.sky_count().saturating_mul(sub * sub) <= SAMPLE_TABLE_MAX)
                    .then(|| patches.samples(sub))
            },
            schedule: None,
        }
    }

    /// The occupied hours from a schedule, an hour each of the weather file's
    /// ([`super::metrics::parse_schedule`]), in place of the params' daily period. Errors: a
    /// schedule of another length.
    pub fn with_schedule(mut self, schedule: Vec<bool>) -> Result<EpwSkies<'a>, DaylightError> {
        if schedule.len() != self.epw.records.len() {
            return Err(DaylightError::Parameter(format!(
                "an occupancy schedule of {} hours for a weather file of {}",
                schedule.len(),
                self.epw.records.len()
            )));
        }
        self.schedule = Some(schedule);
        Ok(self)
    }
}

/// Day of the year (1…366) of a record's date, in its own year.
fn day_of_year(year: i32, month: u32, day: u32) -> u32 {
    let leap = (year % 4 == 0 && year % 100 != 0) || year % 400 == 0;
    let feb = if leap { 29 } else { 28 };
    let days = [31, feb, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31];
    days[..(month as usize - 1)].iter().sum::<u32>() + day
}

/// An hour's Perez condition with its diffuse horizontal and direct normal illuminances, lx.
type PerezHour = (Condition, f64, f64);

impl EpwSkies<'_> {
    /// Hour `h`'s record checked: its light with the occupancy and the sun's direction set,
    /// the sun's position, and, when it has diffuse light, its Perez condition with the
    /// diffuse horizontal and direct normal illuminances (lx). Errors: a missing irradiance.
    fn hour(
        &self,
        h: usize,
    ) -> Result<(HourLight, SolarPosition, Option<PerezHour>), DaylightError> {
        let r = &self.epw.records[h];
        let at = |what: &str| {
            super::invalid(&self.epw.name, r.line, format!("{what} is missing (9999)"))
        };
        let direct = r
            .direct_normal
            .ok_or_else(|| at("the direct normal irradiance"))?;
        let diffuse = r
            .diffuse_horizontal
            .ok_or_else(|| at("the diffuse horizontal irradiance"))?;
        // Typical-year files mix years; a year outside the algorithm's range is taken as a
        // common year.
        let year = if (1800..=2200).contains(&r.year) {
            r.year
        } else {
            2019
        };
        let pos = solar_position(&self.site, year, r.month, r.day, r.mid_hour());
        let light = HourLight {
            occupied: match &self.schedule {
                Some(s) => s[h],
                None => self.params.occupancy.occupied(r.mid_hour()),
            },
            sun: pos.direction(),
            ..Default::default()
        };
        if diffuse <= 0.0 {
            return Ok((light, pos, None));
        }
        let doy = day_of_year(year, r.month, r.day);
        let condition = Condition::new(
            direct,
            diffuse,
            pos.altitude,
            doy,
            r.dew_point.unwrap_or(DEFAULT_DEW_POINT),
        );
        let e_d = diffuse * condition.diffuse_efficacy();
        let e_n = if pos.altitude > 0.0 {
            direct * condition.direct_efficacy()
        } else {
            0.0
        };
        Ok((light, pos, Some((condition, e_d, e_n))))
    }
}

impl SkySource for EpwSkies<'_> {
    fn patches(&self) -> &SkyPatches {
        self.patches
    }

    fn hours(&self) -> usize {
        self.epw.records.len()
    }

    fn stamp(&self, h: usize) -> [u32; 3] {
        let r = &self.epw.records[h];
        [r.month, r.day, r.hour]
    }

    fn diffuse_illuminance(&self, h: usize) -> Result<f64, DaylightError> {
        Ok(self.hour(h)?.2.map_or(0.0, |(_, e_d, _)| e_d))
    }

    fn sky(
        &self,
        h: usize,
        sun_in_patch: bool,
        out: &mut [f64],
    ) -> Result<HourLight, DaylightError> {
        out.iter_mut().for_each(|v| *v = 0.0);
        let (mut light, pos, perez) = self.hour(h)?;
        let Some((condition, e_d, e_n)) = perez else {
            // No diffuse light: a dark hour (gendaymtx does the same).
            return Ok(light);
        };
        let sky = PerezSky::relative(&condition, pos.azimuth);
        let patches = self.patches;
        match &self.samples {
            Some(t) => ROWS.with_borrow_mut(|rows| sky.patch_means(t, rows, out)),
            None => patches.sky_means(&|d| sky.luminance(d), self.params.patch_samples, out),
        }
        let horizontal: f64 = (0..patches.sky_count())
            .map(|p| out[p] * patches.cosine_solid_angle(p))
            .sum();
        if horizontal > 0.0 {
            let k = e_d / horizontal;
            out[..patches.sky_count()].iter_mut().for_each(|v| *v *= k);
        }
        out[patches.ground()] =
            self.params.ground_reflectance * (e_d + e_n * pos.altitude.sin().max(0.0)) / PI;
        light.lit = true;
        light.direct_normal = e_n;
        light.diffuse_horizontal = e_d;
        if sun_in_patch {
            if let Some(p) = patches.add_sun(light.sun, e_n, out) {
                light.sun_patch = Some((p, e_n * light.sun[2] / patches.cosine_solid_angle(p)));
            }
        }
        Ok(light)
    }
}

/// A block of hours' illuminance, handed to the hourly sink.
pub struct HourBlock<'a> {
    /// Index of the block's first hour.
    pub first: usize,
    /// Hours in the block.
    pub hours: usize,
    /// Points.
    pub points: usize,
    /// `total[i * hours + h]`: point i's illuminance in hour `first + h`, lx.
    pub total: &'a [f64],
}

/// Where [`annual`] hands each block of hourly illuminance (an hourly CSV, a plot, a test).
pub type HourlySink<'a> = &'a mut dyn FnMut(&HourBlock) -> Result<(), DaylightError>;

/// The year's result.
#[derive(Clone, Debug, PartialEq)]
pub struct Annual {
    /// Hours run.
    pub hours: usize,
    /// Hours with light.
    pub lit_hours: usize,
    /// The metrics over the occupied hours.
    pub metrics: Metrics,
    /// EN 17037's daylight provision, a grid at a time.
    pub provision: Vec<Provision>,
}

/// Dot product, four partial sums (the order is fixed: the result does not depend on
/// threads).
fn dot(a: &[f64], b: &[f64]) -> f64 {
    let mut s = [0.0f64; 4];
    let (ca, cb) = (a.chunks_exact(4), b.chunks_exact(4));
    let (ra, rb) = (ca.remainder(), cb.remainder());
    for (x, y) in ca.zip(cb) {
        for k in 0..4 {
            s[k] += x[k] * y[k];
        }
    }
    let mut t = (s[0] + s[1]) + (s[2] + s[3]);
    for (x, y) in ra.iter().zip(rb) {
        t += x * y;
    }
    t
}

/// Points a thread takes at a time in the product.
const POINT_CHUNK: usize = 32;

/// Run the year: every hour of `skies` through `coefficients`, the sun as `sun` says, the
/// metrics accumulated and each block of hourly illuminance handed to `hourly` (when given)
/// in order. EN 17037's daylight provision is taken over all the points as one grid
/// ([`annual_by_grids`] for several).
pub fn annual(
    skies: &dyn SkySource,
    coefficients: &DaylightMatrix,
    sun: Sun,
    params: &AnnualParams,
    hourly: Option<HourlySink>,
) -> Result<Annual, DaylightError> {
    let all = 0..coefficients.points();
    annual_by_grids(skies, coefficients, sun, params, &[all], hourly)
}

/// [`annual`] with EN 17037's daylight provision ([`super::provision`]) for each of `grids`
/// (ranges of point indices, one a room's reference plane), over the daylight hours of
/// `skies` (the half of its hours with the most diffuse horizontal illuminance).
pub fn annual_by_grids(
    skies: &dyn SkySource,
    coefficients: &DaylightMatrix,
    sun: Sun,
    params: &AnnualParams,
    grids: &[std::ops::Range<usize>],
    mut hourly: Option<HourlySink>,
) -> Result<Annual, DaylightError> {
    params.validate()?;
    let patches = skies.patches().len();
    if coefficients.patches() != patches {
        return Err(DaylightError::Parameter(format!(
            "the daylight coefficients have {} patches, the sky {patches}",
            coefficients.patches()
        )));
    }
    let points = coefficients.points();
    if points == 0 {
        return Err(DaylightError::Parameter(
            "no points to compute daylight at".into(),
        ));
    }
    let hours = skies.hours();
    let block = params.block_hours.min(hours.max(1));
    let in_patch = matches!(sun, Sun::InPatch);
    // The block's buffers, allocated once.
    let mut s = vec![0.0; block * patches];
    let mut light = vec![HourLight::default(); block];
    let mut total = vec![0.0; points * block];
    let mut direct = vec![0.0; block * points];
    // The exact sun's whole contribution (`direct` holds its direct part for ASE).
    let mut sun_total = vec![0.0; block * points];
    let mut occupied = vec![false; block];
    let mut suns: Vec<Option<[f64; 3]>> = vec![None; block];
    let mut acc = Accumulator::new(points, params.metrics);
    if let Some(g) = grids.iter().find(|g| g.end > points || g.start > g.end) {
        return Err(DaylightError::Parameter(format!(
            "a grid of points {}..{} outside the {points} points",
            g.start, g.end
        )));
    }
    let diffuse: Vec<f64> = (0..hours)
        .into_par_iter()
        .map(|h| skies.diffuse_illuminance(h))
        .collect::<Result<_, _>>()?;
    let daylight = daylight_hours(&diffuse);
    let mut provision = ProvisionAccumulator::new(grids.to_vec());
    let mut lit_hours = 0;
    let mut first = 0;
    while first < hours {
        let nb = block.min(hours - first);
        // The sky vectors (and the exact sun's coefficients), an hour a task.
        s[..nb * patches]
            .par_chunks_mut(patches)
            .zip(light[..nb].par_iter_mut())
            .zip(direct[..nb * points].par_chunks_mut(points))
            .zip(sun_total[..nb * points].par_chunks_mut(points))
            .enumerate()
            .try_for_each(|(h, (((sky, l), d), t))| -> Result<(), DaylightError> {
                *l = skies.sky(first + h, in_patch, sky)?;
                d.iter_mut().for_each(|v| *v = 0.0);
                t.iter_mut().for_each(|v| *v = 0.0);
                Ok(())
            })?;
        // The exact sun's coefficients for the block's sunny hours, scaled by E_n.
        if let Sun::Exact(c) = sun {
            for (k, l) in light[..nb].iter().enumerate() {
                suns[k] = (l.lit && l.direct_normal > 0.0).then_some(l.sun);
            }
            if suns[..nb].iter().any(Option::is_some) {
                c.sun_block(
                    &suns[..nb],
                    &mut sun_total[..nb * points],
                    &mut direct[..nb * points],
                );
                let l_ref = &light[..nb];
                sun_total[..nb * points]
                    .par_chunks_mut(points)
                    .zip(direct[..nb * points].par_chunks_mut(points))
                    .zip(l_ref.par_iter())
                    .for_each(|((t, d), l)| {
                        let e = if l.lit { l.direct_normal.max(0.0) } else { 0.0 };
                        t.iter_mut().for_each(|v| *v *= e);
                        d.iter_mut().for_each(|v| *v *= e);
                    });
            }
        }
        // E = D S for the block's lit hours, points in chunks.
        let (s_ref, l_ref, d_ref) = (&s, &light[..nb], &sun_total);
        total[..points * nb]
            .par_chunks_mut(POINT_CHUNK * nb)
            .enumerate()
            .for_each(|(c, out)| {
                for (k, row_out) in out.chunks_mut(nb).enumerate() {
                    let i = c * POINT_CHUNK + k;
                    let row = coefficients.row(i);
                    for h in 0..nb {
                        row_out[h] = if l_ref[h].lit {
                            dot(row, &s_ref[h * patches..(h + 1) * patches])
                                + if in_patch { 0.0 } else { d_ref[h * points + i] }
                        } else {
                            0.0
                        };
                    }
                }
            });
        if in_patch {
            // ASE's direct sun: the sun patch's term alone.
            direct[..nb * points]
                .par_chunks_mut(points)
                .zip(light[..nb].par_iter())
                .for_each(|(d, l)| match l.sun_patch {
                    Some((p, lum)) => d
                        .iter_mut()
                        .enumerate()
                        .for_each(|(i, v)| *v = coefficients.row(i)[p] * lum),
                    None => d.iter_mut().for_each(|v| *v = 0.0),
                });
        }
        for h in 0..nb {
            occupied[h] = light[h].occupied;
        }
        lit_hours += light[..nb].iter().filter(|l| l.lit).count();
        acc.add_block(
            &occupied[..nb],
            &total[..points * nb],
            &direct[..nb * points],
        );
        provision.add_block(&daylight[first..first + nb], &total[..points * nb]);
        if let Some(sink) = hourly.as_mut() {
            sink(&HourBlock {
                first,
                hours: nb,
                points,
                total: &total[..points * nb],
            })?;
        }
        first += nb;
    }
    Ok(Annual {
        hours,
        lit_hours,
        metrics: acc.finish(),
        provision: provision.finish(),
    })
}

/// Write the metrics as CSV: one row a point, `point` (0-based), its position when
/// `positions` are given (`x,y,z`), `daylight_autonomy` (share of occupied hours ≥ the sDA
/// illuminance), `sun_hours` (occupied hours of direct sun ≥ the ASE illuminance),
/// `udi_fell_short`, `udi_supplementary`, `udi_autonomous`, `udi_exceeded` (shares of occupied
/// hours), `in_sda` and `in_ase` (1 or 0).
pub fn write_metrics_csv(
    w: &mut dyn std::io::Write,
    metrics: &Metrics,
    positions: Option<&[[f64; 3]]>,
) -> std::io::Result<()> {
    write!(w, "point")?;
    if positions.is_some() {
        write!(w, ",x,y,z")?;
    }
    writeln!(
        w,
        ",daylight_autonomy,sun_hours,udi_fell_short,udi_supplementary,udi_autonomous,udi_exceeded,in_sda,in_ase"
    )?;
    for (i, m) in metrics.points.iter().enumerate() {
        write!(w, "{i}")?;
        if let Some(p) = positions.and_then(|p| p.get(i)) {
            write!(w, ",{},{},{}", p[0], p[1], p[2])?;
        }
        writeln!(
            w,
            ",{:.4},{},{:.4},{:.4},{:.4},{:.4},{},{}",
            m.daylight_autonomy,
            m.sun_hours,
            m.udi[0],
            m.udi[1],
            m.udi[2],
            m.udi[3],
            m.in_sda as u8,
            m.in_ase as u8
        )?;
    }
    Ok(())
}

/// The hourly CSV's header: `month,day,hour,p0,p1,…` for `points` points.
pub fn write_hourly_header(w: &mut dyn std::io::Write, points: usize) -> std::io::Result<()> {
    write!(w, "month,day,hour")?;
    for i in 0..points {
        write!(w, ",p{i}")?;
    }
    writeln!(w)
}

/// The hourly CSV's rows of a block: an hour a row, its stamp from `skies`, then each
/// point's illuminance in lx to 0.1 lx (as `{:.1}` prints it, but for a half-tenth tie,
/// which may round either way). The rows are formatted in parallel, then written in order.
pub fn write_hourly_rows(
    w: &mut dyn std::io::Write,
    skies: &dyn SkySource,
    b: &HourBlock,
) -> std::io::Result<()> {
    let rows: Vec<Vec<u8>> = (0..b.hours)
        .into_par_iter()
        .map(|h| {
            let [m, d, hr] = skies.stamp(b.first + h);
            let mut row = Vec::with_capacity(16 + 10 * b.points);
            let stamp = |v: u32, row: &mut Vec<u8>| push_integer(row, v as u64);
            stamp(m, &mut row);
            row.push(b',');
            stamp(d, &mut row);
            row.push(b',');
            stamp(hr, &mut row);
            for i in 0..b.points {
                row.push(b',');
                push_tenths(&mut row, b.total[i * b.hours + h]);
            }
            row.push(b'\n');
            row
        })
        .collect();
    for row in rows {
        w.write_all(&row)?;
    }
    Ok(())
}

/// The hourly matrix as NumPy's `.npy` format (version 1.0): the header of a C-order
/// `hours × points` array of little-endian `float32`, lux. A row an hour, in the weather
/// file's order; [`write_hourly_npy_rows`] then writes the rows.
pub fn write_hourly_npy_header(
    w: &mut dyn std::io::Write,
    hours: usize,
    points: usize,
) -> std::io::Result<()> {
    let mut dict =
        format!("{{'descr': '<f4', 'fortran_order': False, 'shape': ({hours}, {points}), }}");
    // Magic (6) + version (2) + length (2) + the dict and its padding end on a multiple of 64,
    // the last byte a newline.
    let total = (10 + dict.len() + 1).div_ceil(64) * 64;
    dict.extend(std::iter::repeat_n(' ', total - 10 - dict.len() - 1));
    dict.push('\n');
    w.write_all(b"\x93NUMPY\x01\x00")?;
    w.write_all(&(dict.len() as u16).to_le_bytes())?;
    w.write_all(dict.as_bytes())
}

/// The `.npy` rows of a block (after [`write_hourly_npy_header`]): an hour a row, each
/// point's illuminance as a little-endian `float32`.
pub fn write_hourly_npy_rows(w: &mut dyn std::io::Write, b: &HourBlock) -> std::io::Result<()> {
    let mut row = Vec::with_capacity(4 * b.points);
    for h in 0..b.hours {
        row.clear();
        for i in 0..b.points {
            row.extend_from_slice(&(b.total[i * b.hours + h] as f32).to_le_bytes());
        }
        w.write_all(&row)?;
    }
    Ok(())
}

/// Append the decimal digits of `v`.
fn push_integer(out: &mut Vec<u8>, mut v: u64) {
    let mut digits = [0u8; 20];
    let mut k = digits.len();
    loop {
        k -= 1;
        digits[k] = b'0' + (v % 10) as u8;
        v /= 10;
        if v == 0 {
            break;
        }
    }
    out.extend_from_slice(&digits[k..]);
}

/// Append `v` to one decimal (`{:.1}`), by integer arithmetic on the tenths where they fit.
fn push_tenths(out: &mut Vec<u8>, v: f64) {
    let tenths = (v * 10.0).round();
    if !tenths.is_finite() || tenths.abs() >= 1e15 {
        out.extend_from_slice(format!("{v:.1}").as_bytes());
        return;
    }
    if tenths < 0.0 {
        out.push(b'-');
    }
    let t = tenths.abs() as u64;
    push_integer(out, t / 10);
    out.push(b'.');
    out.push(b'0' + (t % 10) as u8);
}

/// Run [`annual`] writing every hour's illuminance to `path` as CSV, whole or not at all
/// ([`crate::io::write_atomic`]): a header `month,day,hour,p0,p1,…` and one row an hour, the
/// illuminance of each point in lx to 0.1 lx.
pub fn annual_with_hourly_csv(
    path: &std::path::Path,
    skies: &dyn SkySource,
    coefficients: &DaylightMatrix,
    sun: Sun,
    params: &AnnualParams,
) -> Result<Annual, DaylightError> {
    let mut outcome: Option<Result<Annual, DaylightError>> = None;
    let written = crate::io::write_atomic::<DaylightError>(path, |w| {
        write_hourly_header(w, coefficients.points())?;
        let mut failed: Option<std::io::Error> = None;
        let mut sink = |b: &HourBlock| -> Result<(), DaylightError> {
            let result = write_hourly_rows(w, skies, b);
            result.map_err(|e| {
                failed = Some(e);
                DaylightError::Parameter("the hourly output could not be written".into())
            })
        };
        let result = annual(skies, coefficients, sun, params, Some(&mut sink));
        if let Some(e) = failed {
            return Err(e);
        }
        let ok = result.is_ok();
        outcome = Some(result);
        if ok {
            Ok(())
        } else {
            Err(std::io::Error::other("the annual run failed"))
        }
    });
    match (outcome, written) {
        // The run failed: its error, the partial file removed.
        (Some(Err(e)), _) => Err(e),
        (_, Err(e)) => Err(e),
        (Some(Ok(a)), Ok(())) => Ok(a),
        (None, Ok(())) => unreachable!("the body always runs the year"),
    }
}

#[cfg(test)]
mod tests;
