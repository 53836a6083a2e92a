//! Test cases 5.6 and 5.7: light at points after one diffuse reflection. One surface S₂
//! reflects (grey, reflectance ρ); every other surface is black, and S₂ is planar, so it does
//! not light itself: the light reaching a point from the surfaces is exactly S₂'s first
//! reflection. The pipeline's result there is its total less its exact direct part.
//!
//! CIE 171 lights S₂ uniformly (a sun) and tabulates E / (ρ E_S₂), a configuration factor;
//! the engine has no sun, so S₂ is lit here by a point luminaire and the reference carries
//! S₂'s non-uniform illuminance E_d(y), known in closed form (E = I cos θ / d²):
//!
//! ```text
//! E(P) = ρ ∫_{S₂ seen from P} E_d(y) cos θ_P cos θ_y / (π r²) dA_y
//! ```
//!
//! by a product composite Gauss–Legendre rule (32 × 32 panels, 8 × 8 nodes each): the
//! integrand is smooth over the region of integration, so the rule's error is far below
//! 10⁻⁶ (with E_d ≡ 1 it reproduces Howell's closed-form factor to 10⁻¹⁰, see the tests).
//!
//! - 5.6 (CIE 171's second scenario): S₂ a 4 × 4 m floor, ρ = 0.3; S₁-v a black wall 4 m
//!   wide, 2.5 m high, its bottom 0.5 m above the floor, along the floor's edge y = 0; S₁-hz a
//!   black 4 × 4 m ceiling 3 m above the floor. Points B–F up the middle of S₁-v (z = 0.75 …
//!   2.75), G–N across the middle of S₁-hz facing down (y = 0.25 … 3.75). Chosen here: the
//!   light, a Lambertian point of I₀ = 1,000 cd at the centre of the ceiling, aimed down.
//! - 5.7: S₂ a 4 m wide, 3 m high wall at y = 4, ρ = 0.6; S₁-v a black 4 × 3 m wall at y = 0
//!   and S₁-hz a black floor 4 × 2.5 m in front of it; between them a black obstruction 4 m
//!   wide, 1 m high, 0.2 m deep at y = 2.5 … 2.7. Points A–F up the middle of S₁-v (z = 2.75 …
//!   0.25), G–K along the middle of S₁-hz (y = 0.25 … 2.25). Chosen here: the light, an
//!   isotropic point of 1,000 cd at (2, 0.5, 2.9), high enough that the obstruction casts no
//!   shadow on S₂. A ray from a point in front of the obstruction to S₂ passes over it iff
//!   it is at least 1 m high at both of the obstruction's faces (its height is linear along
//!   the ray, and the obstruction spans S₂'s whole width): each point therefore sees the part
//!   z ≥ z_min(P) of S₂ exactly, and the integral runs over that rectangle.
//!
//! Both geometries reproduce CIE 171's own factors with S₂ uniformly lit (its Table 17, and
//! Table 19 as corrected by the published Iray validation, CIE's printed one being among the
//! report's errata) to every printed digit: `geometry_reproduces_cie_171s_published_factors`.

use super::closed_form::{composite, dot, kernel, norm, sub, Rect, V3};
use super::photometry::{isotropic, lambertian};
use super::{grey, light, polygon, rows, scene, sensor, Case, CaseResult};
use radiosity::lighting::{Luminaire, SensorPoint};
use radiosity::pipeline::LightingSettings;
use std::time::Instant;

/// Panels along each side of the quadrature's region.
const PANELS: usize = 32;
/// Gauss–Legendre nodes along each side of a panel.
const NODES: usize = 8;

/// Gather sample pairs per point (the `lighting` default is 1,024). A point sees S₂ through about a third
/// of its hemisphere, so a cosine ray finds it with probability ~0.3, and 256 pairs leave the
/// estimate a per cent or two off (docs/validation.md); the error falls as 1/√n, so 16,384
/// pairs bring it eight times lower, for a dozen points.
const GATHER_PAIRS: u32 = 16_384;

/// ρ ∫ E_d(y) kernel(P, y) dA over `region` of the plane of `s2` (normal `n2`).
fn reflected(p: V3, np: V3, region: &Rect, n2: V3, rho: f64, e_d: impl Fn(V3) -> f64) -> f64 {
    let us = composite(region.lo[0], region.hi[0], PANELS, NODES);
    let vs = composite(region.lo[1], region.hi[1], PANELS, NODES);
    let mut sum = 0.0;
    for &(u, wu) in &us {
        for &(v, wv) in &vs {
            let y = region.point(u, v);
            sum += wu * wv * e_d(y) * kernel(p, np, y, n2);
        }
    }
    rho * sum
}

fn settings() -> (LightingSettings, Vec<String>) {
    let mut s = LightingSettings::default();
    s.gather.indirect = GATHER_PAIRS;
    let why = format!(
        "{GATHER_PAIRS} gather sample pairs per point (default 1,024): the reflecting surface fills \
         about a third of each point's hemisphere, and 256 pairs leave the estimate 1-2 % off"
    );
    (s, vec![why])
}

/// Test case 5.6.
pub(super) fn floor() -> Result<CaseResult, radiosity::Error> {
    let rho = 0.3;
    let s2 = Rect {
        axis: 2,
        at: 0.0,
        lo: [0.0, 0.0],
        hi: [4.0, 4.0],
    };
    let s1v = Rect {
        axis: 1,
        at: 0.0,
        lo: [0.0, 0.5],
        hi: [4.0, 3.0],
    };
    let s1hz = Rect {
        axis: 2,
        at: 3.0,
        lo: [0.0, 0.0],
        hi: [4.0, 4.0],
    };
    let materials = vec![grey("S2", rho), grey("S1-v", 0.0), grey("S1-hz", 0.0)];
    let polygons = vec![
        polygon(&s2, 1.0, 0),
        polygon(&s1v, 1.0, 1),
        polygon(&s1hz, -1.0, 2),
    ];
    let room = scene("cie171-5.6", materials, polygons);
    let (i0, source) = (1000.0, [2.0, 2.0, 3.0]);
    let lum = Luminaire::new(
        "lambertian",
        lambertian(i0, 0.0, 0.0),
        source,
        [0.0, 0.0, -1.0],
        None,
        1.0,
        "",
    )
    .expect("a finite position and aim");
    let mut points: Vec<(String, SensorPoint)> = Vec::new();
    for k in 0..5 {
        let label = ((b'B' + k as u8) as char).to_string();
        points.push((
            label,
            sensor([2.0, 0.0, 0.75 + 0.5 * k as f64], [0.0, 1.0, 0.0]),
        ));
    }
    for k in 0..8 {
        let label = ((b'G' + k as u8) as char).to_string();
        points.push((
            label,
            sensor([2.0, 0.25 + 0.5 * k as f64, 3.0], [0.0, 0.0, -1.0]),
        ));
    }
    let sensors: Vec<SensorPoint> = points.iter().map(|p| p.1).collect();
    let (settings, why) = settings();
    let t = Instant::now();
    let r = light(&room, std::slice::from_ref(&lum), &sensors, &settings)?;
    let seconds = t.elapsed().as_secs_f64();
    // The floor's direct illuminance: I₀ cos γ cos θ / d² = I₀ h² / d⁴ (cos γ = cos θ = h/d).
    let e_d = |y: V3| {
        let d = norm(sub(y, source));
        let h = source[2] - y[2];
        i0 * h * h / (d * d * d * d)
    };
    let values = points
        .iter()
        .enumerate()
        .map(|(i, (label, s))| {
            let reference = reflected(s.position, s.normal, &s2, [0.0, 0.0, 1.0], rho, e_d);
            (
                label.clone(),
                s.position,
                reference,
                r.total[i] - r.direct[i],
            )
        })
        .collect();
    Ok(CaseResult {
        case: Case::Reflection,
        rows: rows(values, "lx"),
        settings: why,
        seconds,
    })
}

/// 5.7's obstruction: its faces at y = [`OBSTRUCTION_Y`], its top at z = 1 m.
const OBSTRUCTION_Y: [f64; 2] = [2.5, 2.7];
/// 5.7's obstruction's height, metres.
const OBSTRUCTION_TOP: f64 = 1.0;
/// 5.7's reflecting wall: its plane y, metres.
const S2_Y: f64 = 4.0;
/// 5.7's light: isotropic, candela, and its position.
const WALL_LIGHT: (f64, V3) = (1000.0, [2.0, 0.5, 2.9]);

/// The lowest height on S₂ that a point at (y, z), in front of the obstruction, sees over it:
/// a ray to S₂'s height z' is at height z + (z' − z) t at the fraction t = (y_k − y)/(4 − y)
/// of the way, and must be at least the obstruction's top at both faces y_k.
pub(crate) fn lowest_visible(y: f64, z: f64) -> f64 {
    OBSTRUCTION_Y
        .iter()
        .map(|&yk| {
            let t = (yk - y) / (S2_Y - y);
            (OBSTRUCTION_TOP - z * (1.0 - t)) / t
        })
        .fold(f64::NEG_INFINITY, f64::max)
}

/// Test case 5.7.
pub(super) fn obstructed_wall() -> Result<CaseResult, radiosity::Error> {
    let rho = 0.6;
    let s2 = Rect {
        axis: 1,
        at: S2_Y,
        lo: [0.0, 0.0],
        hi: [4.0, 3.0],
    };
    let s1v = Rect {
        axis: 1,
        at: 0.0,
        lo: [0.0, 0.0],
        hi: [4.0, 3.0],
    };
    let s1hz = Rect {
        axis: 2,
        at: 0.0,
        lo: [0.0, 0.0],
        hi: [4.0, OBSTRUCTION_Y[0]],
    };
    let [y0, y1] = OBSTRUCTION_Y;
    let top = OBSTRUCTION_TOP;
    let obstruction = [
        (
            Rect {
                axis: 1,
                at: y0,
                lo: [0.0, 0.0],
                hi: [4.0, top],
            },
            -1.0,
        ),
        (
            Rect {
                axis: 1,
                at: y1,
                lo: [0.0, 0.0],
                hi: [4.0, top],
            },
            1.0,
        ),
        (
            Rect {
                axis: 2,
                at: top,
                lo: [0.0, y0],
                hi: [4.0, y1],
            },
            1.0,
        ),
        (
            Rect {
                axis: 0,
                at: 0.0,
                lo: [y0, 0.0],
                hi: [y1, top],
            },
            -1.0,
        ),
        (
            Rect {
                axis: 0,
                at: 4.0,
                lo: [y0, 0.0],
                hi: [y1, top],
            },
            1.0,
        ),
    ];
    let materials = vec![
        grey("S2", rho),
        grey("S1-v", 0.0),
        grey("S1-hz", 0.0),
        grey("obstruction", 0.0),
    ];
    let mut polygons = vec![
        polygon(&s2, -1.0, 0),
        polygon(&s1v, 1.0, 1),
        polygon(&s1hz, 1.0, 2),
    ];
    polygons.extend(obstruction.iter().map(|(r, s)| polygon(r, *s, 3)));
    let room = scene("cie171-5.7", materials, polygons);
    let (intensity, source) = WALL_LIGHT;
    let lum = Luminaire::new(
        "isotropic",
        isotropic(intensity),
        source,
        [0.0, 0.0, -1.0],
        None,
        1.0,
        "",
    )
    .expect("a finite position and aim");
    let mut points: Vec<(String, SensorPoint)> = Vec::new();
    for k in 0..6 {
        let label = ((b'A' + k as u8) as char).to_string();
        points.push((
            label,
            sensor([2.0, 0.0, 2.75 - 0.5 * k as f64], [0.0, 1.0, 0.0]),
        ));
    }
    for k in 0..5 {
        let label = ((b'G' + k as u8) as char).to_string();
        points.push((
            label,
            sensor([2.0, 0.25 + 0.5 * k as f64, 0.0], [0.0, 0.0, 1.0]),
        ));
    }
    let sensors: Vec<SensorPoint> = points.iter().map(|p| p.1).collect();
    let (settings, why) = settings();
    let t = Instant::now();
    let r = light(&room, std::slice::from_ref(&lum), &sensors, &settings)?;
    let seconds = t.elapsed().as_secs_f64();
    // S₂'s direct illuminance, I cos θ / d², wholly lit (see `lowest_visible(source)` < 0).
    let n2 = [0.0, -1.0, 0.0];
    let e_d = |y: V3| {
        let to_light = sub(source, y);
        let d = norm(to_light);
        intensity * dot(n2, to_light) / (d * d * d)
    };
    let values = points
        .iter()
        .enumerate()
        .map(|(i, (label, s))| {
            let z_min = lowest_visible(s.position[1], s.position[2]).max(s2.lo[1]);
            let reference = if z_min >= s2.hi[1] {
                0.0
            } else {
                let seen = Rect {
                    lo: [s2.lo[0], z_min],
                    ..s2
                };
                reflected(s.position, s.normal, &seen, n2, rho, e_d)
            };
            (
                label.clone(),
                s.position,
                reference,
                r.total[i] - r.direct[i],
            )
        })
        .collect();
    Ok(CaseResult {
        case: Case::Obstruction,
        rows: rows(values, "lx"),
        settings: why,
        seconds,
    })
}

/// 5.7's light's position (for the test that it casts no shadow on S₂).
#[cfg(test)]
pub(crate) fn wall_light() -> V3 {
    WALL_LIGHT.1
}
