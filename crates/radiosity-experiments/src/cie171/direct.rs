//! Test cases 5.2, 5.3 and 5.4: direct light in a closed black room 4 × 4 × 3 m (x, y ∈
//! [0, 4], z ∈ [0, 3], z up), where nothing is reflected and the pipeline's result is its
//! direct illuminance alone.
//!
//! - 5.2: a point source of I(γ) = I₀ cos γ, I₀ = 1,000 cd, at the centre of the ceiling,
//!   aimed down. Points: CIE 171's ten floor points A–J (offsets (0, 0) … (1.5, 1.5) m from the
//!   centre, one eighth of the floor by symmetry) and six points K–P up the middle of the wall
//!   y = 0 (z = 2.75 … 0.25 m; chosen here: the CIE table has the floor only).
//! - 5.3: a 1 × 1 m Lambertian luminous rectangle of luminance L = 1,000 cd/m² at the centre
//!   of the ceiling, facing down; CIE 171's points A–F up the middle of the wall y = 0 and G–N
//!   across the middle of the floor. Twice: as a luminaire (a Lambertian IES distribution of
//!   I₀ = L × 1 m² with a 1 × 1 m luminous opening: the near-field integration of
//!   [`radiosity::lighting::direct`]) and as an emitting surface of the scene (exitance π L:
//!   the final gather's shadow rays to the emitter).
//! - 5.4: an isotropic point source of 10,000 lm at (1.0, 1.5, 2.0) and a Lambertian
//!   downlight of I₀ = 1,000 cd (π × 1,000 lm) on the ceiling at (3.0, 2.5, 3.0), both chosen
//!   off-centre here so that every surface receives a different flux. Each surface's flux is
//!   its area times its mean illuminance from the pipeline's surfaces table (the first shot at
//!   patch centres, summed); the reference is I Ω for the isotropic source (Ω the surface's
//!   solid angle) and π I₀ F for the downlight (F Howell's factor from the source's position,
//!   facing down, to the surface). Their sum over the closed room is the emitted flux.

use super::closed_form::{dot, factor, norm, solid_angle, sub, Rect};
use super::photometry::{isotropic, lambertian};
use super::{grey, light, polygon, room_faces, rows, scene, sensor, Case, CaseResult};
use radiosity::lighting::{Luminaire, SensorPoint};
use radiosity::pipeline::LightingSettings;
use radiosity::scene::Material;
use radiosity::Rgb;
use std::f64::consts::PI;
use std::time::Instant;

/// The room's width, depth and height, metres.
const ROOM: [f64; 3] = [4.0, 4.0, 3.0];

/// 5.2's and 5.3's nadir intensity, candela (5.3: L × 1 m²).
const I0: f64 = 1000.0;

/// Gather shadow rays per point for 5.3's emitting surface (the default is 16). The emitter's
/// light at a point is estimated by shadow rays to points drawn on its patches, stratified by
/// patch: 16 rays sample few of its ~125 patches and leave the estimate a per cent or two off
/// at the wall points, where the patches' contributions differ most (docs/validation.md);
/// 4,096 sample every patch about 30 times.
const EMITTER_SHADOW_RAYS: u32 = 4096;

/// The black room, each face its own material (so the surfaces table has a row per face),
/// the ceiling cut around `hole` (a rectangle in the ceiling's plane) when given.
fn black_room(hole: Option<&Rect>) -> radiosity::scene::Scene {
    let [w, d, h] = ROOM;
    let mut materials = Vec::new();
    let mut polygons = Vec::new();
    for (name, rect, sign) in room_faces(w, d, h) {
        materials.push(grey(name, 0.0));
        let m = materials.len() - 1;
        match hole {
            Some(hole) if name == "ceiling" => {
                // Four pieces around the hole: below, above (full width), left, right of it.
                let [x0, y0] = hole.lo;
                let [x1, y1] = hole.hi;
                for piece in [
                    Rect {
                        lo: [0.0, 0.0],
                        hi: [w, y0],
                        ..rect
                    },
                    Rect {
                        lo: [0.0, y1],
                        hi: [w, d],
                        ..rect
                    },
                    Rect {
                        lo: [0.0, y0],
                        hi: [x0, y1],
                        ..rect
                    },
                    Rect {
                        lo: [x1, y0],
                        hi: [w, y1],
                        ..rect
                    },
                ] {
                    polygons.push(polygon(&piece, sign, m));
                }
            }
            _ => polygons.push(polygon(&rect, sign, m)),
        }
    }
    scene("cie171-black-room", materials, polygons)
}

fn down(
    name: &str,
    photometry: std::sync::Arc<radiosity::photometry::Photometry>,
    at: [f64; 3],
) -> Luminaire {
    Luminaire::new(name, photometry, at, [0.0, 0.0, -1.0], None, 1.0, "")
        .expect("a finite position and aim")
}

/// I₀ cos γ cos θ / d² at `p` (normal `n`) from a downward Lambertian point at `s`.
fn lambert_point(s: [f64; 3], p: [f64; 3], n: [f64; 3]) -> f64 {
    let to_point = sub(p, s);
    let d = norm(to_point);
    let cos_gamma = -to_point[2] / d;
    let cos_theta = -dot(n, to_point) / d;
    if cos_gamma <= 0.0 || cos_theta <= 0.0 {
        return 0.0;
    }
    I0 * cos_gamma * cos_theta / (d * d)
}

/// Test case 5.2.
pub(super) fn point_source() -> Result<CaseResult, radiosity::Error> {
    let source = [2.0, 2.0, 3.0];
    let mut points: Vec<(String, SensorPoint)> = Vec::new();
    let floor = [
        (0.0, 0.0),
        (0.5, 0.0),
        (1.0, 0.0),
        (1.5, 0.0),
        (0.5, 0.5),
        (1.0, 0.5),
        (1.5, 0.5),
        (1.0, 1.0),
        (1.5, 1.0),
        (1.5, 1.5),
    ];
    for (k, (dx, dy)) in floor.iter().enumerate() {
        let label = ((b'A' + k as u8) as char).to_string();
        points.push((label, sensor([2.0 + dx, 2.0 + dy, 0.0], [0.0, 0.0, 1.0])));
    }
    for k in 0..6 {
        let label = ((b'K' + k as u8) as char).to_string();
        let z = 2.75 - 0.5 * k as f64;
        points.push((label, sensor([2.0, 0.0, z], [0.0, 1.0, 0.0])));
    }
    let lum = down("lambertian", lambertian(I0, 0.0, 0.0), source);
    let sensors: Vec<SensorPoint> = points.iter().map(|p| p.1).collect();
    let t = Instant::now();
    let r = light(
        &black_room(None),
        std::slice::from_ref(&lum),
        &sensors,
        &LightingSettings::default(),
    )?;
    let seconds = t.elapsed().as_secs_f64();
    let values = points
        .iter()
        .zip(&r.total)
        .map(|((label, s), &ours)| {
            let reference = lambert_point(source, s.position, s.normal);
            (label.clone(), s.position, reference, ours)
        })
        .collect();
    Ok(CaseResult {
        case: Case::PointSource,
        rows: rows(values, "lx"),
        settings: vec![],
        seconds,
    })
}

/// The points of 5.3 (and 5.6's layout): A–F up the middle of the wall y = 0, z = 2.75 …
/// 0.25, facing +y; G–N across the middle of the floor, y = 0.25 … 3.75, facing up.
fn area_points() -> Vec<(String, SensorPoint)> {
    let mut points = Vec::new();
    for k in 0..6 {
        let label = ((b'A' + k as u8) as char).to_string();
        points.push((
            label,
            sensor([2.0, 0.0, 2.75 - 0.5 * k as f64], [0.0, 1.0, 0.0]),
        ));
    }
    for k in 0..8 {
        let label = ((b'G' + k as u8) as char).to_string();
        points.push((
            label,
            sensor([2.0, 0.25 + 0.5 * k as f64, 0.0], [0.0, 0.0, 1.0]),
        ));
    }
    points
}

/// The axis (0, 1, 2) and sign of an axis-aligned unit normal.
fn axis_of(n: [f64; 3]) -> (usize, f64) {
    let k = (0..3)
        .max_by(|&a, &b| n[a].abs().total_cmp(&n[b].abs()))
        .unwrap_or(2);
    (k, n[k].signum())
}

/// Test case 5.3.
pub(super) fn area_source() -> Result<CaseResult, radiosity::Error> {
    let [_, _, h] = ROOM;
    let source = Rect {
        axis: 2,
        at: h,
        lo: [1.5, 1.5],
        hi: [2.5, 2.5],
    };
    let luminance = I0 / source.area();
    let points = area_points();
    let sensors: Vec<SensorPoint> = points.iter().map(|p| p.1).collect();
    let t = Instant::now();
    // The luminaire: a Lambertian distribution with a 1 × 1 m opening at the centre.
    let lum = down("panel", lambertian(I0, 1.0, 1.0), [2.0, 2.0, h]);
    let as_luminaire = light(
        &black_room(None),
        std::slice::from_ref(&lum),
        &sensors,
        &LightingSettings::default(),
    )?;
    // The emitting surface: the ceiling cut around the rectangle, which emits π L downwards.
    let mut room = black_room(Some(&source));
    room.materials.push(Material::emitter(
        "panel",
        Rgb::BLACK,
        Rgb::splat(PI * luminance),
    ));
    let m = room.materials.len() - 1;
    room.polygons.push(polygon(&source, -1.0, m));
    let mut settings = LightingSettings::default();
    settings.gather.direct = EMITTER_SHADOW_RAYS;
    let as_surface = light(&room, &[], &sensors, &settings)?;
    let seconds = t.elapsed().as_secs_f64();
    let mut values = Vec::new();
    for (variant, r) in [("luminaire", &as_luminaire), ("surface", &as_surface)] {
        for ((label, s), &ours) in points.iter().zip(&r.total) {
            let (axis, sign) = axis_of(s.normal);
            let reference = PI * luminance * factor(s.position, axis, sign, &source);
            values.push((format!("{variant}:{label}"), s.position, reference, ours));
        }
    }
    Ok(CaseResult {
        case: Case::AreaSource,
        rows: rows(values, "lx"),
        settings: vec![format!(
            "emitting surface: {EMITTER_SHADOW_RAYS} gather shadow rays per point (default 16): \
             the emitter's light is estimated over its patches, and 16 rays sample few of the \
             panel's ~125 (1-2 % off at the wall points)"
        )],
        seconds,
    })
}

/// 5.4's isotropic source: position and flux, lumens.
const ISOTROPIC: ([f64; 3], f64) = ([1.0, 1.5, 2.0], 10_000.0);
/// 5.4's Lambertian downlight on the ceiling: position (its I₀ is [`I0`]).
const DOWNLIGHT: [f64; 3] = [3.0, 2.5, 3.0];

/// Test case 5.4.
pub(super) fn flux() -> Result<CaseResult, radiosity::Error> {
    let (iso_at, iso_flux) = ISOTROPIC;
    let intensity = iso_flux / (4.0 * PI);
    let lums = [
        down("isotropic", isotropic(intensity), iso_at),
        down("downlight", lambertian(I0, 0.0, 0.0), DOWNLIGHT),
    ];
    let t = Instant::now();
    let r = light(&black_room(None), &lums, &[], &LightingSettings::default())?;
    let seconds = t.elapsed().as_secs_f64();
    let [w, d, h] = ROOM;
    let mut values = Vec::new();
    let (mut total_ref, mut total_ours) = (0.0, 0.0);
    for (name, rect, _) in room_faces(w, d, h) {
        let reference =
            intensity * solid_angle(iso_at, &rect) + PI * I0 * factor(DOWNLIGHT, 2, -1.0, &rect);
        let ours = r
            .surfaces
            .iter()
            .find(|s| s.name == name)
            .map_or(0.0, |s| s.area * s.illuminance);
        let [a, b] = rect.span_axes();
        let mut centre = [0.0; 3];
        centre[rect.axis] = rect.at;
        centre[a] = 0.5 * (rect.lo[0] + rect.hi[0]);
        centre[b] = 0.5 * (rect.lo[1] + rect.hi[1]);
        total_ref += reference;
        total_ours += ours;
        values.push((name.to_string(), centre, reference, ours));
    }
    values.push((
        "total".to_string(),
        [w / 2.0, d / 2.0, h / 2.0],
        total_ref,
        total_ours,
    ));
    Ok(CaseResult {
        case: Case::Flux,
        rows: rows(values, "lm"),
        settings: vec![],
        seconds,
    })
}

/// The emitted flux of 5.4's two sources, lumens: the reference total's closed form.
#[cfg(test)]
pub(crate) fn flux_emitted() -> f64 {
    ISOTROPIC.1 + PI * I0
}

/// Rows of one variant of a case (the part of the label before ':').
#[cfg(test)]
pub(crate) fn variant<'a>(rows: &'a [super::Row], name: &str) -> Vec<&'a super::Row> {
    rows.iter()
        .filter(|r| r.point.split(':').next() == Some(name))
        .collect()
}
