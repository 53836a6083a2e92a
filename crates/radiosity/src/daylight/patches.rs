//! The sky cut into patches: Tregenza's 145 and Reinhart's MF:n subdivision, plus the ground.
//!
//! Tregenza (1987, "Subdivision of the sky hemisphere for luminance measurements", *Lighting
//! Research and Technology* 19(1):13–14) cuts the sky into seven bands 12° high with 30, 30,
//! 24, 24, 18, 12 and 6 patches and a cap 6° in radius around the zenith: 145 patches of
//! nearly equal solid angle. Reinhart's MF:n (Reinhart & Walkenhorst 2001; Radiance's
//! `reinhart.cal` and `gendaymtx -m n`) splits each band into n bands and each patch of a
//! band into n in azimuth, keeping one zenith cap: 144 n² + 1 patches (MF:1 is Tregenza's,
//! MF:2 has 577, MF:4 2,305). All bands are α = 90°/(7n + ½) high and the cap's radius is
//! α/2, as in `gendaymtx`.
//!
//! Patch j of a band of N covers azimuths (j − ½)·360°/N … (j + ½)·360°/N clockwise from
//! north, so patch 0 of every band is centred on north; bands are numbered from the horizon
//! up, the cap last among the sky patches and the ground (the whole lower hemisphere) after
//! it. A patch's solid angle is exact: 2π (sin θ₁ − sin θ₀)/N for a band patch between
//! altitudes θ₀ and θ₁, 2π (1 − sin θ₀) for the cap; so is the cosine-weighted solid angle
//! ∫ sin θ dω a horizontal surface sees it with, π (sin² θ₁ − sin² θ₀)/N and π cos² θ₀.
//!
//! The sun is handled in one of two ways, as in Radiance's methods: put into the patch that
//! contains it ([`SkyPatches::add_sun`]; the 2-phase method, `gendaymtx` spreading it over
//! its four nearest patches instead), or kept at its true position as direct-sun
//! coefficients ([`super::annual::SunCoefficients`]; the 5-phase method and DAYSIM).

use super::DaylightError;
use std::f64::consts::{FRAC_PI_2, TAU};

/// Patches a band of Tregenza's subdivision, from the horizon up (the cap is apart).
pub const TREGENZA_BANDS: [usize; 7] = [30, 30, 24, 24, 18, 12, 6];

/// The finest Reinhart subdivision accepted (MF:16 has 36,865 patches).
pub const MAX_SUBDIVISION: usize = 16;

/// A band of patches between two altitudes.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Band {
    /// Lower and upper altitude, radians.
    lo: f64,
    hi: f64,
    /// Patches in the band.
    count: usize,
    /// Index of its first patch.
    first: usize,
}

/// A subdivision of the sky into patches, and the ground.
#[derive(Clone, Debug, PartialEq)]
pub struct SkyPatches {
    subdivision: usize,
    /// The bands, the zenith cap last (a band of one patch).
    bands: Vec<Band>,
    sky: usize,
}

impl SkyPatches {
    /// Tregenza's 145 patches (MF:1).
    pub fn tregenza() -> SkyPatches {
        SkyPatches::reinhart(1).expect("MF:1 is in range")
    }

    /// Reinhart's MF:`n` subdivision (1…[`MAX_SUBDIVISION`]).
    pub fn reinhart(n: usize) -> Result<SkyPatches, DaylightError> {
        if !(1..=MAX_SUBDIVISION).contains(&n) {
            return Err(DaylightError::Parameter(format!(
                "the sky subdivision MF:{n} is outside 1…{MAX_SUBDIVISION}"
            )));
        }
        let rows = 7 * n;
        let alpha = FRAC_PI_2 / (rows as f64 + 0.5);
        let mut bands = Vec::with_capacity(rows + 1);
        let mut first = 0;
        for i in 0..rows {
            let count = TREGENZA_BANDS[i / n] * n;
            bands.push(Band {
                lo: alpha * i as f64,
                hi: alpha * (i + 1) as f64,
                count,
                first,
            });
            first += count;
        }
        bands.push(Band {
            lo: alpha * rows as f64,
            hi: FRAC_PI_2,
            count: 1,
            first,
        });
        Ok(SkyPatches {
            subdivision: n,
            bands,
            sky: first + 1,
        })
    }

    /// The Reinhart subdivision n (1 for Tregenza's).
    pub fn subdivision(&self) -> usize {
        self.subdivision
    }

    /// Sky patches (without the ground).
    pub fn sky_count(&self) -> usize {
        self.sky
    }

    /// All patches: the sky's and the ground.
    pub fn len(&self) -> usize {
        self.sky + 1
    }

    /// Never empty; for the lint.
    pub fn is_empty(&self) -> bool {
        false
    }

    /// The ground patch's index (the last).
    pub fn ground(&self) -> usize {
        self.sky
    }

    fn band_of(&self, patch: usize) -> &Band {
        let k = self.bands.partition_point(|b| b.first + b.count <= patch);
        &self.bands[k]
    }

    /// The patch's altitudes (lo, hi) and azimuths (lo, hi), radians; the cap spans all
    /// azimuths, the ground altitudes −90°…0.
    pub fn bounds(&self, patch: usize) -> ([f64; 2], [f64; 2]) {
        assert!(patch < self.len(), "patch {patch} of {}", self.len());
        if patch == self.ground() {
            return ([-FRAC_PI_2, 0.0], [0.0, TAU]);
        }
        let b = self.band_of(patch);
        if b.count == 1 {
            return ([b.lo, b.hi], [0.0, TAU]);
        }
        let w = TAU / b.count as f64;
        let j = (patch - b.first) as f64;
        ([b.lo, b.hi], [(j - 0.5) * w, (j + 0.5) * w])
    }

    /// The patch's centre direction (x east, y north, z up): the middle of its altitudes and
    /// azimuths; the cap's is the zenith, the ground's the nadir.
    pub fn centre(&self, patch: usize) -> [f64; 3] {
        if patch == self.ground() {
            return [0.0, 0.0, -1.0];
        }
        let ([lo, hi], [a0, a1]) = self.bounds(patch);
        if hi == FRAC_PI_2 {
            return [0.0, 0.0, 1.0];
        }
        super::direction(0.5 * (lo + hi), 0.5 * (a0 + a1))
    }

    /// The patch's solid angle, sr (the ground's is 2π).
    pub fn solid_angle(&self, patch: usize) -> f64 {
        let ([lo, hi], [a0, a1]) = self.bounds(patch);
        (a1 - a0) * (hi.sin() - lo.sin()).abs()
    }

    /// ∫ sin θ dω over the patch: the illuminance an unobstructed horizontal surface facing
    /// up receives from it per unit luminance (0 for the ground).
    pub fn cosine_solid_angle(&self, patch: usize) -> f64 {
        if patch == self.ground() {
            return 0.0;
        }
        let ([lo, hi], [a0, a1]) = self.bounds(patch);
        0.5 * (a1 - a0) * (hi.sin().powi(2) - lo.sin().powi(2))
    }

    /// The patch that contains unit direction `d` (the ground below the horizon).
    pub fn find(&self, d: [f64; 3]) -> usize {
        if d[2] < 0.0 {
            return self.ground();
        }
        let (alt, az) = super::altitude_azimuth(d);
        let k = self
            .bands
            .partition_point(|b| b.hi <= alt)
            .min(self.bands.len() - 1);
        let b = &self.bands[k];
        if b.count == 1 {
            return b.first;
        }
        let w = TAU / b.count as f64;
        let j = ((az / w + 0.5).floor() as usize) % b.count;
        b.first + j
    }

    /// Each sky patch's mean of `l` (a luminance over directions) into `out[..sky_count]`,
    /// by the midpoint rule on `sub` × `sub` cells of equal solid angle (uniform in sin θ and
    /// in azimuth; the cap in `sub` rings of `4·sub` cells); `out[ground]` is left as it is.
    pub fn sky_means(&self, l: &dyn Fn([f64; 3]) -> f64, sub: usize, out: &mut [f64]) {
        assert!(out.len() >= self.sky_count() && sub >= 1);
        out[..self.sky].fill(0.0);
        self.each_sample(sub, |p, _, _, d| out[p] += l(d));
        for b in &self.bands {
            let cells = if b.count == 1 {
                4 * sub * sub
            } else {
                sub * sub
            };
            for o in &mut out[b.first..b.first + b.count] {
                *o /= cells as f64;
            }
        }
    }

    /// The sample directions of [`SkyPatches::sky_means`] at `sub` cells a side, computed
    /// once for a run that takes the means of many skies ([`PatchSamples`]).
    pub fn samples(&self, sub: usize) -> PatchSamples {
        assert!(sub >= 1);
        let mut s = PatchSamples {
            directions: Vec::new(),
            row: Vec::new(),
            heights: Vec::new(),
            ends: Vec::with_capacity(self.sky),
        };
        self.each_sample(sub, |p, row, z, d| {
            if row == s.heights.len() {
                s.heights.push(z);
            }
            if p == s.ends.len() {
                s.ends.push(0);
            }
            s.directions.push(d);
            s.row.push(row as u32);
            s.ends[p] = s.directions.len() as u32;
        });
        s
    }

    /// Every sample direction of [`SkyPatches::sky_means`] at `sub` cells a side, patch by
    /// patch in patch order: `visit(patch, row, z, direction)`, `row` numbering the heights
    /// z = sin θ of the cells' rows over all bands (the rows of a band are shared by its
    /// patches).
    fn each_sample(&self, sub: usize, mut visit: impl FnMut(usize, usize, f64, [f64; 3])) {
        let mut first_row = 0;
        for b in &self.bands {
            let (s0, s1) = (b.lo.sin(), b.hi.sin());
            let (na, nz) = if b.count == 1 {
                (4 * sub, sub)
            } else {
                (sub, sub)
            };
            let w = TAU / b.count as f64;
            for j in 0..b.count {
                let a0 = (j as f64 - 0.5) * w;
                for iz in 0..nz {
                    let z = s0 + (s1 - s0) * (iz as f64 + 0.5) / nz as f64;
                    let r = (1.0 - z * z).max(0.0).sqrt();
                    for ia in 0..na {
                        let az = if b.count == 1 {
                            TAU * (ia as f64 + 0.5) / na as f64
                        } else {
                            a0 + w * (ia as f64 + 0.5) / na as f64
                        };
                        let (sa, ca) = az.sin_cos();
                        visit(b.first + j, first_row + iz, z, [r * sa, r * ca, z]);
                    }
                }
            }
            first_row += nz;
        }
    }

    /// The 2-phase sun: add to `sky` (patch luminances, cd/m²) a sun of direct normal
    /// illuminance `direct_normal` (lx) towards unit `sun`, as a uniform luminance over the
    /// patch that contains it, E_n sin α / ∫ sin θ dω, so that an unobstructed horizontal
    /// surface receives exactly the sun's E_n sin α from it. Returns that patch (None when the
    /// sun is below the horizon, where nothing is added).
    pub fn add_sun(&self, sun: [f64; 3], direct_normal: f64, sky: &mut [f64]) -> Option<usize> {
        if sun[2] <= 0.0 || direct_normal <= 0.0 {
            return None;
        }
        let p = self.find(sun);
        sky[p] += direct_normal * sun[2] / self.cosine_solid_angle(p);
        Some(p)
    }
}

/// The sample directions of [`SkyPatches::sky_means`], patch by patch, with the height
/// (sin of the altitude) row each lies on, so that a function of the altitude alone is
/// evaluated once a row ([`PatchSamples::means`]).
#[derive(Clone, Debug, PartialEq)]
pub struct PatchSamples {
    directions: Vec<[f64; 3]>,
    /// Index into `heights` of each direction's row.
    row: Vec<u32>,
    heights: Vec<f64>,
    /// End of each sky patch's directions (patch order).
    ends: Vec<u32>,
}

impl PatchSamples {
    /// The heights (sin of the altitude, z) of the rows of samples.
    pub fn heights(&self) -> &[f64] {
        &self.heights
    }

    /// Each sky patch's mean of `l(direction, row_value)` over its samples, into `out`, where
    /// `row_value[k]` is any per-row quantity the caller computed from [`Self::heights`]:
    /// [`SkyPatches::sky_means`] of the same function, in the same order of summation.
    pub fn means(&self, row_value: &[f64], l: impl Fn([f64; 3], f64) -> f64, out: &mut [f64]) {
        assert!(row_value.len() >= self.heights.len() && out.len() >= self.ends.len());
        let mut start = 0usize;
        for (o, &end) in out.iter_mut().zip(&self.ends) {
            let end = end as usize;
            let mut sum = 0.0;
            for k in start..end {
                sum += l(self.directions[k], row_value[self.row[k] as usize]);
            }
            *o = sum / (end - start) as f64;
            start = end;
        }
    }
}

/// The Tregenza/Reinhart patch count of MF:`n`: 144 n² + 1 sky patches.
pub fn sky_patch_count(n: usize) -> usize {
    144 * n * n + 1
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    #[test]
    fn counts_and_exact_solid_angles() {
        for n in [1, 2, 3, 4, 6] {
            let p = SkyPatches::reinhart(n).unwrap();
            assert_eq!(p.sky_count(), sky_patch_count(n));
            assert_eq!(p.len(), p.sky_count() + 1);
            let omega: f64 = (0..p.sky_count()).map(|i| p.solid_angle(i)).sum();
            assert!((omega - TAU).abs() < 1e-12, "MF:{n}: {omega}");
            let cos: f64 = (0..p.sky_count()).map(|i| p.cosine_solid_angle(i)).sum();
            assert!((cos - PI).abs() < 1e-12, "MF:{n}: {cos}");
            assert!((p.solid_angle(p.ground()) - TAU).abs() < 1e-12);
        }
        assert_eq!(SkyPatches::tregenza().sky_count(), 145);
        assert_eq!(SkyPatches::reinhart(2).unwrap().sky_count(), 577);
        assert!(SkyPatches::reinhart(0).is_err() && SkyPatches::reinhart(17).is_err());
    }

    #[test]
    fn tregenza_geometry() {
        // Bands 12° high centred at 6°, 18°, … 78°, the cap 6° in radius; the first band's
        // 30 patches are 12° wide, patch 0 centred on north.
        let p = SkyPatches::tregenza();
        let ([lo, hi], [a0, a1]) = p.bounds(0);
        assert!((lo - 0.0).abs() < 1e-15 && (hi.to_degrees() - 12.0).abs() < 1e-12);
        assert!((a0.to_degrees() + 6.0).abs() < 1e-12 && (a1.to_degrees() - 6.0).abs() < 1e-12);
        let c = p.centre(0);
        assert!(c[0].abs() < 1e-15 && c[1] > 0.0);
        let (alt, _) = crate::daylight::altitude_azimuth(p.centre(60));
        assert!((alt.to_degrees() - 30.0).abs() < 1e-12); // band 3 starts at patch 60
        assert_eq!(p.centre(144), [0.0, 0.0, 1.0]);
        let ([lo, _], _) = p.bounds(144);
        assert!((lo.to_degrees() - 84.0).abs() < 1e-12);
        // The cap's solid angle: 2π (1 − cos 6°).
        assert!((p.solid_angle(144) - TAU * (1.0 - 6f64.to_radians().cos())).abs() < 1e-14);
    }

    #[test]
    fn every_patch_contains_its_centre() {
        for n in [1, 2, 5] {
            let p = SkyPatches::reinhart(n).unwrap();
            for i in 0..p.len() {
                assert_eq!(p.find(p.centre(i)), i, "MF:{n} patch {i}");
            }
            // Just east and just west of north in the lowest band: patches 0 and the last.
            assert_eq!(p.find(crate::daylight::direction(0.01, 0.001)), 0);
            let last = TREGENZA_BANDS[0] * n - 1;
            assert_eq!(p.find(crate::daylight::direction(0.01, TAU - 0.001)), 0);
            let w = TAU / (TREGENZA_BANDS[0] * n) as f64;
            assert_eq!(
                p.find(crate::daylight::direction(0.01, TAU - 0.6 * w)),
                last
            );
        }
    }

    #[test]
    fn sky_means_integrate_exactly_for_polynomials_in_z() {
        // The mean of z = sin θ over a band patch is (sin θ₀ + sin θ₁)/2 exactly by the
        // midpoint rule in z; so Σ mean·ω = ∫ z dω = π.
        let p = SkyPatches::reinhart(2).unwrap();
        let mut out = vec![0.0; p.len()];
        p.sky_means(&|d| d[2], 3, &mut out);
        let total: f64 = (0..p.sky_count()).map(|i| out[i] * p.solid_angle(i)).sum();
        assert!((total - PI).abs() < 1e-12, "{total}");
        // A uniform sky of luminance L gives πL on a horizontal surface.
        p.sky_means(&|_| 2.0, 2, &mut out);
        let e: f64 = (0..p.sky_count())
            .map(|i| out[i] * p.cosine_solid_angle(i))
            .sum();
        assert!((e - 2.0 * PI).abs() < 1e-12);
    }

    /// The sample table gives [`SkyPatches::sky_means`] bit for bit, with a per-row factor.
    #[test]
    fn sample_table_means_equal_sky_means() {
        for n in [1, 2] {
            let p = SkyPatches::reinhart(n).unwrap();
            let f = |d: [f64; 3]| (1.0 + 0.3 * (-2.0 / d[2].max(0.01)).exp()) * (d[0] + 2.0);
            let mut want = vec![0.0; p.len()];
            p.sky_means(&f, 3, &mut want);
            let t = p.samples(3);
            let rows: Vec<f64> = t
                .heights()
                .iter()
                .map(|&z| 1.0 + 0.3 * (-2.0 / z.max(0.01)).exp())
                .collect();
            let mut got = vec![0.0; p.len()];
            t.means(&rows, |d, g| g * (d[0] + 2.0), &mut got);
            assert_eq!(got[..p.sky_count()], want[..p.sky_count()]);
        }
    }

    #[test]
    fn sun_in_its_patch_keeps_its_horizontal_illuminance() {
        let p = SkyPatches::tregenza();
        let mut sky = vec![0.0; p.len()];
        let sun = crate::daylight::direction(23f64.to_radians(), 2.0);
        let k = p.add_sun(sun, 80_000.0, &mut sky).unwrap();
        assert_eq!(k, p.find(sun));
        let e: f64 = (0..p.len()).map(|i| sky[i] * p.cosine_solid_angle(i)).sum();
        assert!((e / (80_000.0 * 23f64.to_radians().sin()) - 1.0).abs() < 1e-12);
        assert_eq!(p.add_sun([0.0, 1.0, -0.1], 80_000.0, &mut sky), None);
    }
}
