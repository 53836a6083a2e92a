//! The luminaires' first shot into the patches: the flux each patch receives straight from
//! each luminaire, integrated over the patch, with visibility.
//!
//! # The integral
//!
//! A point luminaire of intensity I(ω) sends a patch P the flux
//!
//! ```text
//! Φ_P = ∫_P I(ω(x)) V(x) cos θ(x) / d(x)² dA  =  ∫_Ω(P) I(ω) V(ω) dω
//! ```
//!
//! (the inverse-square cosine law integrated over the patch, which is the intensity
//! integrated over the solid angle the patch subtends, cos θ dA / d² = dω), with V the
//! visibility. The patch's mean illuminance Φ_P / A_P is what the interreflection starts from
//! (its first reflection ρ Φ_P / A_P).
//!
//! # The rule
//!
//! Taking E at the patch's centre (the midpoint rule) errs by the curvature of cos θ / d²
//! over the patch: about (s/d)²/8 of E for a patch of size s at distance d under the
//! luminaire, and without bound as d → 0 (a patch next to a luminaire, a fitting's own
//! housing, books many times the luminaire's flux). So each (patch, luminaire) pair is
//! integrated adaptively, over cells each of which is a point sample of I V weighted by the
//! cell's exact solid angle:
//!
//! 1. a patch whose diameter s is at most [`SPLIT_RATIO`] × d, d the distance from the
//!    photometric centre to its nearest possible point (|c − x_L| − s/2), is one cell, its
//!    centre the sample;
//! 2. otherwise each of its triangles is split recursively into the four congruent triangles
//!    between its edges' midpoints while its longest edge e exceeds [`SPLIT_RATIO`] × (its
//!    centroid's distance − e), at most [`MAX_DEPTH`] times (cells down to 1/64 of a side,
//!    only around the luminaire's foot); each leaf is sampled at its centroid with its own
//!    shadow ray (a luminaire in the near field of a point keeps its opening cells,
//!    32/2^depth along a side, so a cell costs at most a few rays);
//! 3. for a point luminaire (no opening, or the patch five openings away) each cell's
//!    geometric factor is exact: its area times E at the sample is scaled by the cell's solid
//!    angle Ω_k over A_k cos θ_k / d_k², so Φ_P = Σ_k Ω_k I_k V_k, with Ω_k by Van Oosterom
//!    and Strackee's formula (IEEE Trans. Biomed. Eng. BME-30(2):125–126, 1983) for the
//!    triangle of vertices r₁, r₂, r₃ seen from the luminaire,
//!
//!    ```text
//!    tan(Ω/2) = |r₁ · (r₂ × r₃)| / (r₁r₂r₃ + (r₁·r₂) r₃ + (r₁·r₃) r₂ + (r₂·r₃) r₁)
//!    ```
//!
//!    The rule is then exact for an unshadowed isotropic source whatever the patch's size
//!    (a closed room's patches book 4π I to rounding), and otherwise errs by the variation
//!    of I and V across cells of at most [`SPLIT_RATIO`] radian seen from the luminaire: the
//!    centroid rule's O(SPLIT_RATIO²) for a smooth I, and a cell's share wherever a shadow
//!    edge or a cut-off crosses it.
//!
//! Parallel over patches, deterministic (no sampling; each patch sums its luminaires in list
//! order). The inner loops allocate nothing.

use super::direct::{groups_of, illuminance, DirectResult, MAX_CELLS};
use super::luminaire::Luminaire;
use super::points::SensorPoint;
use super::{cross, dot, norm, sub, LightingError};
use crate::accel::Bvh;
use crate::mesh::{Mesh, Patch};
use rayon::prelude::*;

/// The largest patch size over distance, s/d, taken at the patch's centre alone; above it the
/// patch is cut into cells of at most this angular size (radian) seen from the luminaire.
pub const SPLIT_RATIO: f64 = 0.1;

/// Most halvings of a patch's triangles (cells down to 1/64 of a side near a luminaire).
pub const MAX_DEPTH: usize = 6;

/// Each patch's mean direct illuminance, lux, from `luminaires` (the flux it receives over
/// its area, see the module documentation), shadowed by `bvh`'s scene when given;
/// `unit_metres` is one scene unit in metres. Rows are `mesh`'s patches, as
/// [`super::direct_illuminance`]'s are its points. Refused: `unit_metres` not finite and > 0.
pub fn patch_illuminance(
    mesh: &Mesh,
    luminaires: &[Luminaire],
    bvh: Option<&Bvh>,
    unit_metres: f64,
) -> Result<DirectResult, LightingError> {
    patch_illuminance_with(mesh, luminaires, bvh, unit_metres, SPLIT_RATIO, MAX_DEPTH)
}

/// [`patch_illuminance`] with its rule's bounds: cells of at most `ratio` × distance, split
/// at most `max_depth` times (at most [`MAX_DEPTH`]).
pub fn patch_illuminance_with(
    mesh: &Mesh,
    luminaires: &[Luminaire],
    bvh: Option<&Bvh>,
    unit_metres: f64,
    ratio: f64,
    max_depth: usize,
) -> Result<DirectResult, LightingError> {
    if !(unit_metres.is_finite() && unit_metres > 0.0) {
        return Err(LightingError::Parameter(format!(
            "the scene unit must be a finite length > 0 metres, not {unit_metres}"
        )));
    }
    if ratio.is_nan() || ratio <= 0.0 || max_depth > MAX_DEPTH {
        return Err(LightingError::Parameter(format!(
            "the first shot's cells need a size ratio > 0 and at most {MAX_DEPTH} halvings, \
             not {ratio} and {max_depth}"
        )));
    }
    let (groups, group_of) = groups_of(luminaires);
    let ng = groups.len();
    let offset = bvh.map_or(0.0, |b| b.ray_offset());
    let mut by_group = vec![0.0; mesh.len() * ng];
    if ng > 0 {
        let rule = Rule {
            bvh,
            offset,
            unit: unit_metres,
            ratio,
            max_depth,
        };
        by_group
            .par_chunks_mut(ng)
            .zip(mesh.patches.par_iter())
            .for_each(|(row, patch)| {
                let shape = Shape::of(mesh, patch);
                for (l, &g) in luminaires.iter().zip(&group_of) {
                    row[g] += rule.mean_illuminance(&shape, l);
                }
            });
    }
    let total = if ng == 0 {
        vec![0.0; mesh.len()]
    } else {
        by_group.chunks(ng).map(|row| row.iter().sum()).collect()
    };
    Ok(DirectResult {
        groups,
        total,
        by_group,
    })
}

/// A patch's geometry in `f64`: its one or two triangles, centre, normal, area and diameter.
struct Shape {
    triangles: [[[f64; 3]; 3]; 2],
    count: usize,
    centre: [f64; 3],
    normal: [f64; 3],
    area: f64,
    diameter: f64,
}

impl Shape {
    fn of(mesh: &Mesh, patch: &Patch) -> Shape {
        let v = |i: u32| {
            let p = mesh.vertices[i as usize].as_dvec3();
            [p.x, p.y, p.z]
        };
        let [a, b, c, d] = patch.vertices;
        let mut triangles = [[[0.0; 3]; 3]; 2];
        let mut areas = [0.0f64; 2];
        triangles[0] = [v(a), v(b), v(c)];
        let count = if patch.is_triangle() {
            1
        } else {
            triangles[1] = [v(a), v(c), v(d)];
            2
        };
        for (t, area) in triangles.iter().zip(&mut areas).take(count) {
            *area = 0.5 * norm(cross(sub(t[1], t[0]), sub(t[2], t[0])));
        }
        let mut diameter: f64 = 0.0;
        let corners = [v(a), v(b), v(c), if count == 2 { v(d) } else { v(a) }];
        for i in 0..4 {
            for j in i + 1..4 {
                diameter = diameter.max(norm(sub(corners[i], corners[j])));
            }
        }
        let c = patch.centre.as_dvec3();
        let n = patch.normal.as_dvec3();
        Shape {
            triangles,
            count,
            centre: [c.x, c.y, c.z],
            normal: [n.x, n.y, n.z],
            area: areas[0] + areas[1],
            diameter,
        }
    }

    /// The solid angle the patch subtends at `x` (Van Oosterom and Strackee, per triangle).
    fn solid_angle(&self, x: [f64; 3]) -> f64 {
        self.triangles[..self.count]
            .iter()
            .map(|t| triangle_solid_angle(sub(t[0], x), sub(t[1], x), sub(t[2], x)))
            .sum()
    }
}

/// The solid angle of the triangle with corners `r1`, `r2`, `r3` seen from the origin,
/// steradian (Van Oosterom and Strackee 1983; either winding).
pub(crate) fn triangle_solid_angle(r1: [f64; 3], r2: [f64; 3], r3: [f64; 3]) -> f64 {
    let (l1, l2, l3) = (norm(r1), norm(r2), norm(r3));
    let triple = dot(r1, cross(r2, r3)).abs();
    let den = l1 * l2 * l3 + dot(r1, r2) * l3 + dot(r1, r3) * l2 + dot(r2, r3) * l1;
    2.0 * triple.atan2(den)
}

/// The bounds of the adaptive rule and what its shadow rays need.
struct Rule<'a> {
    bvh: Option<&'a Bvh>,
    offset: f32,
    unit: f64,
    ratio: f64,
    max_depth: usize,
}

/// The most triangles on the subdivision stack: each split replaces one by four, at most
/// `max_depth` deep.
const STACK: usize = 3 * MAX_DEPTH + 1;

impl Rule<'_> {
    /// The mean illuminance over `shape` from `l`, lux (the module documentation's rule).
    fn mean_illuminance(&self, shape: &Shape, l: &Luminaire) -> f64 {
        if shape.area <= 0.0 {
            return 0.0;
        }
        let to_light = sub(l.position, shape.centre);
        let o = &l.photometry.opening;
        let size_m = o.width_m.max(o.length_m);
        let near = norm(to_light) - 0.5 * shape.diameter;
        // A point source for every point of the patch: the solid angles are exact then.
        let point_like = size_m <= 0.0 || near * self.unit >= 5.0 * size_m;
        if point_like && dot(shape.normal, to_light) <= 0.0 {
            // The patch's plane hides its front from the luminaire.
            return 0.0;
        }
        let mut flux = 0.0;
        if shape.diameter <= self.ratio * near {
            flux += self.cell(shape.centre, shape.area, shape, l, point_like, 0, || {
                shape.solid_angle(l.position)
            });
        } else {
            let mut stack = [([[0.0; 3]; 3], 0usize); STACK];
            for t in &shape.triangles[..shape.count] {
                stack[0] = (*t, 0);
                let mut top = 1;
                while top > 0 {
                    top -= 1;
                    let (t, depth) = stack[top];
                    let centroid = mid3(t[0], t[1], t[2]);
                    let size = norm(sub(t[1], t[0]))
                        .max(norm(sub(t[2], t[1])))
                        .max(norm(sub(t[0], t[2])));
                    let dist = norm(sub(l.position, centroid)) - size;
                    if size > self.ratio * dist && depth < self.max_depth {
                        // The four congruent triangles between the edges' midpoints.
                        let (ab, bc, ca) = (mid2(t[0], t[1]), mid2(t[1], t[2]), mid2(t[2], t[0]));
                        for child in [[t[0], ab, ca], [ab, t[1], bc], [ca, bc, t[2]], [ab, bc, ca]]
                        {
                            stack[top] = (child, depth + 1);
                            top += 1;
                        }
                        continue;
                    }
                    let area = 0.5 * norm(cross(sub(t[1], t[0]), sub(t[2], t[0])));
                    flux += self.cell(centroid, area, shape, l, point_like, depth, || {
                        let x = l.position;
                        triangle_solid_angle(sub(t[0], x), sub(t[1], x), sub(t[2], x))
                    });
                }
            }
        }
        flux / shape.area
    }

    /// A cell's share of the flux, lux × square scene units: its area times E at `x`, its
    /// geometric factor made exact (the cell's solid angle over A cos θ / d²) for a point
    /// source. A cell `depth` splits deep keeps MAX_CELLS / 2^depth opening cells a side.
    #[allow(clippy::too_many_arguments)]
    fn cell(
        &self,
        x: [f64; 3],
        area: f64,
        shape: &Shape,
        l: &Luminaire,
        point_like: bool,
        depth: usize,
        solid_angle: impl Fn() -> f64,
    ) -> f64 {
        let p = SensorPoint {
            position: x,
            normal: shape.normal,
        };
        let cells = (MAX_CELLS >> depth.min(31)).max(1);
        let e = illuminance(&p, l, self.bvh, self.offset, self.unit, cells);
        if e <= 0.0 || !point_like {
            return area * e;
        }
        let r = sub(l.position, x);
        let d = norm(r);
        let weight = area * dot(shape.normal, r) / (d * d * d);
        let factor = solid_angle() / weight;
        if weight > 0.0 && factor.is_finite() {
            area * e * factor
        } else {
            area * e
        }
    }
}

fn mid2(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        0.5 * (a[0] + b[0]),
        0.5 * (a[1] + b[1]),
        0.5 * (a[2] + b[2]),
    ]
}

fn mid3(a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> [f64; 3] {
    [
        (a[0] + b[0] + c[0]) / 3.0,
        (a[1] + b[1] + c[1]) / 3.0,
        (a[2] + b[2] + c[2]) / 3.0,
    ]
}

#[cfg(test)]
#[path = "first_shot_tests.rs"]
mod tests;
