//! Direct illuminance at sensor points from point luminaires, exactly: no sampling.
//!
//! # The law
//!
//! A point source of intensity I(ω) candela towards ω gives, at a point at distance d metres
//! whose surface normal n makes the angle θ with the direction from the point back to the
//! source, the illuminance (the inverse-square cosine law; e.g. CIE S 017 "illuminance",
//! IES Lighting Handbook, "point method")
//!
//! ```text
//! E = I(ω) · cos θ / d²      lux,   0 where cos θ ≤ 0
//! ```
//!
//! with ω the direction luminaire → point in the luminaire's frame
//! ([`Luminaire::intensity_towards`], multiplier included), summed over luminaires. CIE
//! 171:2006 ("Test cases to assess the accuracy of lighting computer programs") computes the
//! references of its analytical point-source cases by this law (issue 57 cites test case 5.2);
//! the tests here derive theirs by hand the same way.
//!
//! # Visibility
//!
//! With a scene ([`Bvh`]), each luminaire–point pair casts one shadow ray (`f32`, scene
//! units) from the point, lifted off its surface by [`Bvh::ray_offset`] along the sensor
//! normal, towards the photometric centre, stopping short of it by twice that offset: so a
//! sensor on a floor does not shadow itself, and a luminaire whose centre lies on a ceiling
//! (surface-mounted, recessed) is not hidden by that ceiling. Anything else on the segment,
//! either side facing, blocks the pair entirely. Without a scene nothing is occluded.
//!
//! # Units
//!
//! Intensities are candela; positions are scene units, turned into metres by `unit_metres`
//! (1 for metres, 0.001 for millimetres), so E is lux (lm/m²).
//!
//! # The near field
//!
//! The point-source law is the far-field limit: it holds to about 1 % (for a uniform diffuse
//! disc) where d is at least five times the luminous opening's largest dimension
//! ([`crate::photometry::Opening`]), the "five-times rule". Closer, the opening (a rectangle
//! of its length along C0 and width along C90, or a disc) is split into n × n cells, n =
//! ⌈10 s / d⌉ for its largest side s (at most 32), each a point source of the same
//! distribution carrying its share of the intensity, each with its own shadow ray: the
//! illuminance of the opening integrated by the midpoint rule.

use super::luminaire::Luminaire;
use super::points::SensorPoint;
use super::{dot, norm, sub, LightingError};
use crate::accel::Bvh;
use crate::geom::{Ray, Vec3};
use rayon::prelude::*;

/// The direct illuminance at each point: in total and per group (light scene).
#[derive(Clone, Debug, PartialEq)]
pub struct DirectResult {
    /// The luminaires' groups, in the order they first appear in the luminaire list.
    pub groups: Vec<String>,
    /// Lux, one per point: the sum of that point's group values (in group order).
    pub total: Vec<f64>,
    /// Lux, row-major points × groups: point `i`, group `g` at `i * groups.len() + g`.
    pub by_group: Vec<f64>,
}

impl DirectResult {
    /// The illuminance of point `i` from each group, in [`DirectResult::groups`] order.
    pub fn point(&self, i: usize) -> &[f64] {
        let n = self.groups.len();
        &self.by_group[i * n..(i + 1) * n]
    }
}

/// The direct illuminance, lux, at `points` from `luminaires` as point sources (see the module
/// documentation), shadowed by `bvh`'s scene when given; `unit_metres` is the length of one
/// scene unit in metres. Parallel over points, deterministic (each point sums its
/// luminaires in list order; nothing random). A point at a luminaire's photometric centre
/// gets nothing from it. Refused: `unit_metres` not finite and > 0.
pub fn direct_illuminance(
    points: &[SensorPoint],
    luminaires: &[Luminaire],
    bvh: Option<&Bvh>,
    unit_metres: f64,
) -> Result<DirectResult, LightingError> {
    if !(unit_metres.is_finite() && unit_metres > 0.0) {
        return Err(LightingError::Parameter(format!(
            "the scene unit must be a finite length > 0 metres, not {unit_metres}"
        )));
    }
    let (groups, group_of) = groups_of(luminaires);
    let ng = groups.len();
    let offset = bvh.map_or(0.0, |b| b.ray_offset());
    let mut by_group = vec![0.0; points.len() * ng];
    if ng > 0 {
        by_group
            .par_chunks_mut(ng)
            .zip(points.par_iter())
            .for_each(|(row, p)| {
                for (l, &g) in luminaires.iter().zip(&group_of) {
                    row[g] += illuminance(p, l, bvh, offset, unit_metres, MAX_CELLS);
                }
            });
    }
    let total = if ng == 0 {
        vec![0.0; points.len()]
    } else {
        by_group.chunks(ng).map(|row| row.iter().sum()).collect()
    };
    Ok(DirectResult {
        groups,
        total,
        by_group,
    })
}

/// The luminaires' groups in the order they first appear, and each luminaire's group index.
pub(crate) fn groups_of(luminaires: &[Luminaire]) -> (Vec<String>, Vec<usize>) {
    let mut groups: Vec<String> = Vec::new();
    let group_of = luminaires
        .iter()
        .map(|l| match groups.iter().position(|g| *g == l.group) {
            Some(k) => k,
            None => {
                groups.push(l.group.clone());
                groups.len() - 1
            }
        })
        .collect();
    (groups, group_of)
}

/// Most cells along a side of a luminous opening in the near field.
pub(crate) const MAX_CELLS: usize = 32;

/// E at `p` from `l`, lux: the point-source law, or the opening integrated cell by cell in the
/// near field, at most `max_cells` cells along a side. Allocates nothing.
pub(crate) fn illuminance(
    p: &SensorPoint,
    l: &Luminaire,
    bvh: Option<&Bvh>,
    offset: f32,
    unit: f64,
    max_cells: usize,
) -> f64 {
    let o = &l.photometry.opening;
    let size = o.width_m.max(o.length_m);
    let d_m = norm(sub(l.position, p.position)) * unit;
    if !(size > 0.0 && d_m.is_finite() && d_m < 5.0 * size) {
        return from_point(p, l, l.position, 1.0, bvh, offset, unit);
    }
    let n = ((10.0 * size / d_m.max(1e-9)).ceil() as usize).clamp(1, max_cells.max(1));
    let (len, wid) = (o.length_m / unit, o.width_m / unit);
    // The cells' centres in the opening's (u, v), |u|, |v| ≤ 1/2; a disc keeps those inside.
    let centre = |i: usize, j: usize| {
        (
            (i as f64 + 0.5) / n as f64 - 0.5,
            (j as f64 + 0.5) / n as f64 - 0.5,
        )
    };
    let inside = |(u, v): (f64, f64)| !o.round || u * u + v * v <= 0.25;
    let count = (0..n * n).filter(|&k| inside(centre(k / n, k % n))).count();
    let share = 1.0 / count.max(1) as f64;
    let mut e = 0.0;
    for k in 0..n * n {
        let (u, v) = centre(k / n, k % n);
        if !inside((u, v)) {
            continue;
        }
        let c = [
            l.position[0] + u * len * l.c0[0] + v * wid * l.c90[0],
            l.position[1] + u * len * l.c0[1] + v * wid * l.c90[1],
            l.position[2] + u * len * l.c0[2] + v * wid * l.c90[2],
        ];
        e += from_point(p, l, c, share, bvh, offset, unit);
    }
    e
}

/// E at `p` from a point source of `l`'s distribution at `at`, scaled by `share`, lux.
fn from_point(
    p: &SensorPoint,
    l: &Luminaire,
    at: [f64; 3],
    share: f64,
    bvh: Option<&Bvh>,
    offset: f32,
    unit: f64,
) -> f64 {
    let to_light = sub(at, p.position);
    let d = norm(to_light);
    if d == 0.0 || !d.is_finite() {
        return 0.0;
    }
    let cos_theta = dot(p.normal, to_light) / d;
    if cos_theta <= 0.0 {
        return 0.0;
    }
    let intensity = share * l.intensity_towards(to_light.map(|v| -v));
    if intensity <= 0.0 {
        return 0.0;
    }
    if let Some(bvh) = bvh {
        let f = |a: [f64; 3]| Vec3::new(a[0] as f32, a[1] as f32, a[2] as f32);
        let origin = f(p.position) + f(p.normal) * offset;
        let target = f(at);
        let segment = target - origin;
        let length = segment.length();
        let t_max = length - 2.0 * offset;
        if t_max > 0.0 && bvh.occluded(&Ray::new(origin, segment / length), t_max) {
            return 0.0;
        }
    }
    let dm = d * unit;
    intensity * cos_theta / (dm * dm)
}
