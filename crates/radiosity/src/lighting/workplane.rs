//! A work-plane grid laid over the surfaces of one material (a floor), as EN 12464-1 lays
//! calculation grids: a spacing p = 0.2 × 5^log₁₀(d) metres (d the longer side of the area,
//! p at most 10 m), a border band of 0.5 m left out, points at the centres of the cells, at a
//! height above the surface, facing up.

use super::{LightingError, SensorPoint, Up};
use crate::scene::Scene;

/// Border band left out of a work-plane grid, metres (EN 12464-1).
pub const BORDER_M: f64 = 0.5;

/// The EN 12464-1 grid spacing for an area whose longer side is `d` metres:
/// p = 0.2 × 5^log₁₀(d), at most 10 m.
pub fn spacing(d: f64) -> f64 {
    (0.2 * 5f64.powf(d.max(1e-9).log10())).min(10.0)
}

/// The horizontal coordinates of a point for the vertical `up` (right-handed: z-up reads
/// (x, y), y-up reads (z, x)) and its height.
fn split(p: [f64; 3], up: Up) -> ([f64; 2], f64) {
    match up {
        Up::Z => ([p[0], p[1]], p[2]),
        Up::Y => ([p[2], p[0]], p[1]),
    }
}

/// The point of horizontal coordinates `h` at height `z`.
fn join(h: [f64; 2], z: f64, up: Up) -> [f64; 3] {
    match up {
        Up::Z => [h[0], h[1], z],
        Up::Y => [h[1], z, h[0]],
    }
}

/// Whether `q` lies inside the polygon `poly` (even–odd rule, in the horizontal plane).
fn inside(q: [f64; 2], poly: &[[f64; 2]]) -> bool {
    let mut c = false;
    let n = poly.len();
    for i in 0..n {
        let (a, b) = (poly[i], poly[(i + n - 1) % n]);
        if (a[1] > q[1]) != (b[1] > q[1]) {
            let x = b[0] + (q[1] - b[1]) / (a[1] - b[1]) * (a[0] - b[0]);
            if q[0] < x {
                c = !c;
            }
        }
    }
    c
}

/// A grid over the surfaces of `material` in `scene`, `height_m` metres above them, for a
/// scene in units of `unit_metres` metres whose vertical is `up`. Refused: an unknown
/// material (the message lists the scene's), surfaces that face neither up nor down, or an
/// area with no point inside it.
pub fn workplane(
    scene: &Scene,
    material: &str,
    height_m: f64,
    unit_metres: f64,
    up: Up,
) -> Result<Vec<SensorPoint>, LightingError> {
    if !(height_m.is_finite() && unit_metres.is_finite() && unit_metres > 0.0) {
        return Err(LightingError::Parameter(format!(
            "work plane: height {height_m} m and unit {unit_metres} m must be finite"
        )));
    }
    let polys: Vec<&crate::scene::Polygon> = scene
        .polygons
        .iter()
        .filter(|p| scene.materials[p.material].name == material)
        .collect();
    if polys.is_empty() {
        let mut names: Vec<&str> = scene.materials.iter().map(|m| m.name.as_str()).collect();
        names.sort_unstable();
        names.dedup();
        return Err(LightingError::Parameter(crate::loc::shorten(format!(
            "work plane: no surface of material '{material}' (the scene's materials: {})",
            names.join(", ")
        ))));
    }
    // Each polygon in the horizontal plane, with its plane's height as a function of (u, v).
    let mut flat = Vec::new();
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in &polys {
        let v: Vec<[f64; 3]> = p.vertices.iter().map(|v| v.as_dvec3().to_array()).collect();
        let n = crate::scene::vector_area(&p.vertices).as_dvec3();
        let (nh, nz) = split(n.to_array(), up);
        if nz.abs() < 1e-6 * (nh[0].hypot(nh[1]) + nz.abs()) {
            return Err(LightingError::Parameter(crate::loc::shorten(format!(
                "work plane: a surface of material '{material}' is vertical"
            ))));
        }
        let (h0, z0) = split(v[0], up);
        let plane = move |q: [f64; 2]| z0 - (nh[0] * (q[0] - h0[0]) + nh[1] * (q[1] - h0[1])) / nz;
        let hs: Vec<[f64; 2]> = v.iter().map(|&p| split(p, up).0).collect();
        for h in &hs {
            for k in 0..2 {
                lo[k] = lo[k].min(h[k]);
                hi[k] = hi[k].max(h[k]);
            }
        }
        flat.push((hs, plane));
    }
    let size = [(hi[0] - lo[0]) * unit_metres, (hi[1] - lo[1]) * unit_metres];
    let p = spacing(size[0].max(size[1]));
    let mut axes = [Vec::new(), Vec::new()];
    for k in 0..2 {
        let border = if size[k] > 2.0 * BORDER_M {
            BORDER_M
        } else {
            0.0
        };
        let span = size[k] - 2.0 * border;
        let n = ((span / p).ceil() as usize).clamp(1, 100_000);
        let step = span / n as f64;
        axes[k] = (0..n)
            .map(|i| lo[k] + (border + (i as f64 + 0.5) * step) / unit_metres)
            .collect();
    }
    let lift = height_m / unit_metres;
    let normal = join([0.0, 0.0], 1.0, up);
    let mut out = Vec::new();
    for &v in &axes[1] {
        for &u in &axes[0] {
            let q = [u, v];
            if let Some((_, plane)) = flat.iter().find(|(hs, _)| inside(q, hs)) {
                let point = join(q, plane(q) + lift, up);
                out.extend(SensorPoint::new(point, normal));
            }
        }
    }
    if out.is_empty() {
        return Err(LightingError::Parameter(crate::loc::shorten(format!(
            "work plane: no grid point falls on the surfaces of material '{material}'"
        ))));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::color::Rgb;
    use crate::geom::Vec3;
    use crate::scene::{Material, Scene};

    fn floor(up: Up) -> Scene {
        let v = |x: f32, y: f32| match up {
            Up::Z => Vec3::new(x, y, 0.0),
            Up::Y => Vec3::new(y, 0.0, x),
        };
        let mut s = Scene::of_polygons(
            "room",
            Material::diffuse("floor", Rgb::splat(0.2)),
            vec![vec![v(0., 0.), v(6., 0.), v(6., 4.), v(0., 4.)]],
        );
        s.materials.push(Material::diffuse("wall", Rgb::splat(0.5)));
        s
    }

    /// EN 12464-1's spacing for a 6 m side: 0.2 × 5^log₁₀ 6 = 0.700 m; with the 0.5 m border
    /// the 5 × 3 m interior takes 8 × 5 cells.
    #[test]
    fn a_floor_gets_the_standard_grid() {
        assert!((spacing(6.0) - 0.2 * 5f64.powf(6f64.log10())).abs() < 1e-12);
        assert_eq!(spacing(1e6), 10.0);
        for up in [Up::Z, Up::Y] {
            let g = workplane(&floor(up), "floor", 0.8, 1.0, up).unwrap();
            assert_eq!(g.len(), 40);
            for p in &g {
                let (h, z) = split(p.position, up);
                assert!((z - 0.8).abs() < 1e-9);
                assert!(
                    h[0] > 0.5 && h[0] < 5.5 && h[1] > 0.5 && h[1] < 3.5,
                    "{h:?}"
                );
                assert_eq!(split(p.normal, up), ([0.0, 0.0], 1.0));
            }
        }
        // In millimetres: the same grid, scaled.
        let mut mm = floor(Up::Z);
        for p in &mut mm.polygons {
            for v in &mut p.vertices {
                *v *= 1000.0;
            }
        }
        let g = workplane(&mm, "floor", 0.8, 0.001, Up::Z).unwrap();
        assert_eq!(g.len(), 40);
        assert!((g[0].position[2] - 800.0).abs() < 1e-6);
    }

    #[test]
    fn unknown_and_vertical_surfaces_are_refused() {
        let e = workplane(&floor(Up::Z), "carpet", 0.8, 1.0, Up::Z).unwrap_err();
        assert!(e.to_string().contains("'carpet'") && e.to_string().contains("floor, wall"));
        let e = workplane(&floor(Up::Y), "floor", 0.8, 1.0, Up::Z).unwrap_err();
        assert!(e.to_string().contains("vertical"), "{e}");
    }
}
