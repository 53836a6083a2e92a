//! Built-in scenes, selected by name: `cornell` (the default), `office`, `cube-dim`,
//! `cube-bright` (alias `cube` = `cube-dim`), `furnace` and `city`.

use super::spectrum::{cornell_wavelengths, interpolate, spectrum_to_rgb};
use super::{vector_area, Camera, Material, Polygon, Scene};
use crate::color::Rgb;
use crate::geom::Vec3;

/// Names accepted by [`by_name`].
pub const NAMES: &[&str] = &[
    "cornell",
    "office",
    "cube-dim",
    "cube-bright",
    "cube",
    "furnace",
    "city",
];

/// The built-in scene called `name`, if there is one.
pub fn by_name(name: &str) -> Option<Scene> {
    match name {
        "cornell" => Some(cornell()),
        "office" => Some(office()),
        "cube" | "cube-dim" => Some(cube(CubeVariant::Dim)),
        "cube-bright" => Some(cube(CubeVariant::Bright)),
        "furnace" => Some(furnace()),
        "city" => Some(city(63)),
        _ => None,
    }
}

/// Measured white paint reflectance, 400–700 nm every 4 nm ("Cornell Box Data").
const WHITE: [f64; 76] = [
    0.343, 0.445, 0.551, 0.624, 0.665, 0.687, 0.708, 0.723, 0.715, 0.710, 0.745, 0.758, 0.739,
    0.767, 0.777, 0.765, 0.751, 0.745, 0.748, 0.729, 0.745, 0.757, 0.753, 0.750, 0.746, 0.747,
    0.735, 0.732, 0.739, 0.734, 0.725, 0.721, 0.733, 0.725, 0.732, 0.743, 0.744, 0.748, 0.728,
    0.716, 0.733, 0.726, 0.713, 0.740, 0.754, 0.764, 0.752, 0.736, 0.734, 0.741, 0.740, 0.732,
    0.745, 0.755, 0.751, 0.744, 0.731, 0.733, 0.744, 0.731, 0.712, 0.708, 0.729, 0.730, 0.727,
    0.707, 0.703, 0.729, 0.750, 0.760, 0.751, 0.739, 0.724, 0.730, 0.740, 0.737,
];
/// Measured red paint reflectance, 400–700 nm every 4 nm.
const RED: [f64; 76] = [
    0.040, 0.046, 0.048, 0.053, 0.049, 0.050, 0.053, 0.055, 0.057, 0.056, 0.059, 0.057, 0.061,
    0.061, 0.060, 0.062, 0.062, 0.062, 0.061, 0.062, 0.060, 0.059, 0.057, 0.058, 0.058, 0.058,
    0.056, 0.055, 0.056, 0.059, 0.057, 0.055, 0.059, 0.059, 0.058, 0.059, 0.061, 0.061, 0.063,
    0.063, 0.067, 0.068, 0.072, 0.080, 0.090, 0.099, 0.124, 0.154, 0.192, 0.255, 0.287, 0.349,
    0.402, 0.443, 0.487, 0.513, 0.558, 0.584, 0.620, 0.606, 0.609, 0.651, 0.612, 0.610, 0.650,
    0.638, 0.627, 0.620, 0.630, 0.628, 0.642, 0.639, 0.657, 0.639, 0.635, 0.642,
];
/// Measured green paint reflectance, 400–700 nm every 4 nm.
const GREEN: [f64; 76] = [
    0.092, 0.096, 0.098, 0.097, 0.098, 0.095, 0.095, 0.097, 0.095, 0.094, 0.097, 0.098, 0.096,
    0.101, 0.103, 0.104, 0.107, 0.109, 0.112, 0.115, 0.125, 0.140, 0.160, 0.187, 0.229, 0.285,
    0.343, 0.390, 0.435, 0.464, 0.472, 0.476, 0.481, 0.462, 0.447, 0.441, 0.426, 0.406, 0.373,
    0.347, 0.337, 0.314, 0.285, 0.277, 0.266, 0.250, 0.230, 0.207, 0.186, 0.171, 0.160, 0.148,
    0.141, 0.136, 0.130, 0.126, 0.123, 0.121, 0.122, 0.119, 0.114, 0.115, 0.117, 0.117, 0.118,
    0.120, 0.122, 0.128, 0.132, 0.139, 0.144, 0.146, 0.150, 0.152, 0.157, 0.159,
];
/// Light emission knots (nm, spectral radiance in the data page's arbitrary units).
const LIGHT: [(f64, f64); 4] = [(400.0, 0.0), (500.0, 8.0), (600.0, 15.6), (700.0, 18.4)];

/// RGB reflectances of the Cornell box's white, red and green paints, and the light's exitance,
/// by [`spectrum_to_rgb`]. Exitance is π times the published radiance (Lambertian emitter).
pub fn cornell_colours() -> (Rgb, Rgb, Rgb, Rgb) {
    let nm = cornell_wavelengths();
    let light: Vec<f64> = nm.iter().map(|&l| interpolate(&LIGHT, l)).collect();
    (
        spectrum_to_rgb(&nm, &WHITE),
        spectrum_to_rgb(&nm, &RED),
        spectrum_to_rgb(&nm, &GREEN),
        spectrum_to_rgb(&nm, &light) * std::f64::consts::PI,
    )
}

fn v(x: f32, y: f32, z: f32) -> Vec3 {
    Vec3::new(x, y, z)
}

fn poly(vertices: Vec<Vec3>, material: usize) -> Polygon {
    Polygon {
        vertices,
        material,
        line: 0,
        group: 0,
    }
}

/// The Cornell box as published by the Cornell University Program of Computer Graphics
/// ("Cornell Box Data", graphics.cornell.edu/online/box/data.html): geometry in millimetres, the
/// published camera (eye (278, 273, −800) looking along +z, 35 mm lens on 25 mm film, so a
/// vertical field of view of 2·atan(12.5/35) ≈ 39.3°), RGB reflectances and light exitance from
/// the measured spectra (see [`super::spectrum`]).
///
/// The light, published in the ceiling's own plane, is kept there and the ceiling is cut around
/// it into four rectangles, so that no surface overlaps another. The light's diffuser is given
/// the white paint's reflectance (the data page gives none for it). The front of the box is open,
/// as published.
pub fn cornell() -> Scene {
    let (white, red, green, light) = cornell_colours();
    let materials = vec![
        Material::diffuse("white", white),
        Material::diffuse("red", red),
        Material::diffuse("green", green),
        Material::emitter("light", white, light),
    ];
    let (w, r, g, l) = (0, 1, 2, 3);
    let y = 548.8;
    // Ceiling rectangle x∈[x0,x1], z∈[z0,z1] facing down, in the published ceiling's order.
    let ceiling = |x0: f32, x1: f32, z0: f32, z1: f32| {
        vec![v(x1, y, z0), v(x1, y, z1), v(x0, y, z1), v(x0, y, z0)]
    };
    let mut polygons = vec![
        // floor
        poly(
            vec![
                v(552.8, 0.0, 0.0),
                v(0.0, 0.0, 0.0),
                v(0.0, 0.0, 559.2),
                v(549.6, 0.0, 559.2),
            ],
            w,
        ),
        // light
        poly(
            vec![
                v(343.0, y, 227.0),
                v(343.0, y, 332.0),
                v(213.0, y, 332.0),
                v(213.0, y, 227.0),
            ],
            l,
        ),
        // ceiling, cut around the light
        poly(ceiling(0.0, 556.0, 0.0, 227.0), w),
        poly(ceiling(0.0, 556.0, 332.0, 559.2), w),
        poly(ceiling(343.0, 556.0, 227.0, 332.0), w),
        poly(ceiling(0.0, 213.0, 227.0, 332.0), w),
        // back wall
        poly(
            vec![
                v(549.6, 0.0, 559.2),
                v(0.0, 0.0, 559.2),
                v(0.0, y, 559.2),
                v(556.0, y, 559.2),
            ],
            w,
        ),
        // right wall (green)
        poly(
            vec![
                v(0.0, 0.0, 559.2),
                v(0.0, 0.0, 0.0),
                v(0.0, y, 0.0),
                v(0.0, y, 559.2),
            ],
            g,
        ),
        // left wall (red), slightly non-planar as published
        poly(
            vec![
                v(552.8, 0.0, 0.0),
                v(549.6, 0.0, 559.2),
                v(556.0, y, 559.2),
                v(556.0, y, 0.0),
            ],
            r,
        ),
    ];
    let short_block: [[[f32; 3]; 4]; 5] = [
        [
            [130.0, 165.0, 65.0],
            [82.0, 165.0, 225.0],
            [240.0, 165.0, 272.0],
            [290.0, 165.0, 114.0],
        ],
        [
            [290.0, 0.0, 114.0],
            [290.0, 165.0, 114.0],
            [240.0, 165.0, 272.0],
            [240.0, 0.0, 272.0],
        ],
        [
            [130.0, 0.0, 65.0],
            [130.0, 165.0, 65.0],
            [290.0, 165.0, 114.0],
            [290.0, 0.0, 114.0],
        ],
        [
            [82.0, 0.0, 225.0],
            [82.0, 165.0, 225.0],
            [130.0, 165.0, 65.0],
            [130.0, 0.0, 65.0],
        ],
        [
            [240.0, 0.0, 272.0],
            [240.0, 165.0, 272.0],
            [82.0, 165.0, 225.0],
            [82.0, 0.0, 225.0],
        ],
    ];
    let tall_block: [[[f32; 3]; 4]; 5] = [
        [
            [423.0, 330.0, 247.0],
            [265.0, 330.0, 296.0],
            [314.0, 330.0, 456.0],
            [472.0, 330.0, 406.0],
        ],
        [
            [423.0, 0.0, 247.0],
            [423.0, 330.0, 247.0],
            [472.0, 330.0, 406.0],
            [472.0, 0.0, 406.0],
        ],
        [
            [472.0, 0.0, 406.0],
            [472.0, 330.0, 406.0],
            [314.0, 330.0, 456.0],
            [314.0, 0.0, 456.0],
        ],
        [
            [314.0, 0.0, 456.0],
            [314.0, 330.0, 456.0],
            [265.0, 330.0, 296.0],
            [265.0, 0.0, 296.0],
        ],
        [
            [265.0, 0.0, 296.0],
            [265.0, 330.0, 296.0],
            [423.0, 330.0, 247.0],
            [423.0, 0.0, 247.0],
        ],
    ];
    for face in short_block.iter().chain(tall_block.iter()) {
        polygons.push(poly(face.iter().map(|p| Vec3::from_array(*p)).collect(), w));
    }
    let fov = 2.0 * (12.5f32 / 35.0).atan().to_degrees();
    Scene {
        name: "cornell".into(),
        source: None,
        materials,
        polygons,
        camera: Some(Camera {
            eye: v(278.0, 273.0, -800.0),
            target: v(278.0, 273.0, 0.0),
            up: Vec3::Y,
            fov_y_deg: fov,
        }),
        warnings: vec![],
        origins: vec![],
        up: None,
    }
}

/// A quad with the given corners, reordered if needed so that its normal points along `facing`.
fn oriented_quad(mut corners: Vec<Vec3>, facing: Vec3, material: usize) -> Polygon {
    if vector_area(&corners).dot(facing) < 0.0 {
        corners.reverse();
    }
    poly(corners, material)
}

/// The six faces of the box `[lo, hi]`, normals pointing inwards (`inward`) or outwards.
fn box_faces(lo: Vec3, hi: Vec3, materials: [usize; 6], inward: bool) -> Vec<Polygon> {
    let mut out = Vec::with_capacity(6);
    let s = if inward { 1.0 } else { -1.0 };
    for axis in 0..3 {
        for (side, at) in [(0usize, lo[axis]), (1, hi[axis])] {
            let (u, w) = ((axis + 1) % 3, (axis + 2) % 3);
            let corner = |a: f32, b: f32| {
                let mut p = Vec3::ZERO;
                p[axis] = at;
                p[u] = a;
                p[w] = b;
                p
            };
            let corners = vec![
                corner(lo[u], lo[w]),
                corner(hi[u], lo[w]),
                corner(hi[u], hi[w]),
                corner(lo[u], hi[w]),
            ];
            let mut facing = Vec3::ZERO;
            facing[axis] = if side == 0 { s } else { -s };
            out.push(oriented_quad(corners, facing, materials[axis * 2 + side]));
        }
    }
    out
}

/// The two cube variants of section 6 of Gortler, Cohen & Slusallek (1993).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CubeVariant {
    /// Reflectances around 0.3.
    Dim,
    /// Reflectances around 0.8.
    Bright,
}

/// The inside of an empty 1 m cube with a few emitting polygons on the ceiling (section 6 of
/// Gortler, Cohen & Slusallek (1993)): the ceiling is a 4 × 4 grid of 0.25 m squares of which four,
/// scattered, emit 1 W/m² of white light. Each face has its own reflectance "around" the
/// variant's value (0.28–0.32 dim, 0.78–0.82 bright). Meshed at `--max-edge 0.125` it has
/// 384 patches, close to the paper's 390.
pub fn cube(variant: CubeVariant) -> Scene {
    let base = match variant {
        CubeVariant::Dim => 0.3,
        CubeVariant::Bright => 0.8,
    };
    // Face order of box_faces: x=0, x=1, y=0 (floor), y=1 (ceiling), z=0, z=1.
    let offsets = [-0.02, 0.01, 0.0, -0.01, 0.02, -0.015];
    let mut materials: Vec<Material> = offsets
        .iter()
        .enumerate()
        .map(|(k, o)| Material::diffuse(&format!("face{k}"), Rgb::splat(base + o)))
        .collect();
    materials.push(Material::emitter(
        "light",
        Rgb::splat(base),
        Rgb::splat(1.0),
    ));
    let light = materials.len() - 1;
    let mut polygons: Vec<Polygon> = box_faces(Vec3::ZERO, Vec3::ONE, [0, 1, 2, 3, 4, 5], true)
        .into_iter()
        .filter(|p| !(p.vertices.iter().all(|v| v.y == 1.0)))
        .collect();
    let lights = [(0, 1), (1, 3), (2, 0), (3, 2)];
    for i in 0..4 {
        for k in 0..4 {
            let (x0, z0) = (i as f32 * 0.25, k as f32 * 0.25);
            let corners = vec![
                v(x0, 1.0, z0),
                v(x0 + 0.25, 1.0, z0),
                v(x0 + 0.25, 1.0, z0 + 0.25),
                v(x0, 1.0, z0 + 0.25),
            ];
            let m = if lights.contains(&(i, k)) { light } else { 3 };
            polygons.push(oriented_quad(corners, -Vec3::Y, m));
        }
    }
    Scene {
        name: match variant {
            CubeVariant::Dim => "cube-dim".into(),
            CubeVariant::Bright => "cube-bright".into(),
        },
        source: None,
        materials,
        polygons,
        camera: Some(Camera {
            eye: v(0.5, 0.45, 0.98),
            target: v(0.5, 0.5, 0.0),
            up: Vec3::Y,
            fov_y_deg: 80.0,
        }),
        warnings: vec![],
        origins: vec![],
        up: None,
    }
}

/// Size of the `office` room (x, y = height, z), metres.
pub const OFFICE_SIZE: [f32; 3] = [4.0, 2.7, 3.5];

/// A small office in the spirit of figure 2 of Gortler, Cohen & Slusallek (1993) (whose model is not
/// published): a 4 × 2.7 × 3.5 m room with a desk, a bookcase with books, a chair and a ceiling
/// light fixture whose underside emits 12 W/m². Furniture is made of closed boxes; faces that lie
/// on the room's walls, floor or ceiling are left out (they would be hidden). Meshed with
/// `--patches 270` it has about 270 patches, the size of the paper's office system.
pub fn office() -> Scene {
    let [w, h, d] = OFFICE_SIZE;
    let materials = vec![
        Material::diffuse("wall", Rgb::new(0.72, 0.70, 0.64)),
        Material::diffuse("floor", Rgb::new(0.26, 0.28, 0.33)),
        Material::diffuse("ceiling", Rgb::splat(0.8)),
        Material::diffuse("wood", Rgb::new(0.48, 0.34, 0.22)),
        Material::diffuse("shelf", Rgb::new(0.60, 0.52, 0.42)),
        Material::diffuse("fabric", Rgb::new(0.55, 0.16, 0.12)),
        Material::diffuse("book-blue", Rgb::new(0.12, 0.20, 0.50)),
        Material::diffuse("book-green", Rgb::new(0.15, 0.42, 0.20)),
        Material::diffuse("book-yellow", Rgb::new(0.70, 0.60, 0.18)),
        Material::diffuse("fixture", Rgb::splat(0.7)),
        Material::emitter("light", Rgb::splat(0.8), Rgb::splat(12.0)),
    ];
    const WALL: usize = 0;
    let mut polygons = box_faces(Vec3::ZERO, v(w, h, d), [WALL, WALL, 1, 2, WALL, WALL], true);
    // A closed box, outward normals, without the faces on the room's boundary planes;
    // `materials` in box_faces' order (−x, +x, −y, +y, −z, +z).
    let mut solid = |lo: Vec3, hi: Vec3, m: [usize; 6]| {
        for p in box_faces(lo, hi, m, false) {
            let on_boundary = (0..3).any(|axis| {
                let room = [0.0, OFFICE_SIZE[axis]];
                room.iter()
                    .any(|&at| p.vertices.iter().all(|q| q[axis] == at))
            });
            if !on_boundary {
                polygons.push(p);
            }
        }
    };
    let (wood, shelf, fabric, fixture, light) = (3, 4, 5, 9, 10);
    // Desk against the back wall (z = 0): a top on two side panels.
    solid(v(1.2, 0.72, 0.05), v(2.8, 0.76, 0.85), [wood; 6]);
    solid(v(1.25, 0.0, 0.1), v(1.3, 0.72, 0.8), [wood; 6]);
    solid(v(2.7, 0.0, 0.1), v(2.75, 0.72, 0.8), [wood; 6]);
    // Bookcase against the left wall (x = 0): two sides, four boards, three rows of books.
    solid(v(0.0, 0.0, 1.9), v(0.35, 1.9, 1.93), [shelf; 6]);
    solid(v(0.0, 0.0, 2.97), v(0.35, 1.9, 3.0), [shelf; 6]);
    for y in [0.05f32, 0.65, 1.25, 1.85] {
        solid(v(0.0, y, 1.935), v(0.35, y + 0.03, 2.965), [shelf; 6]);
    }
    for (y, z0, z1, m) in [
        (0.08f32, 1.95f32, 2.45f32, 6usize),
        (0.68, 2.2, 2.9, 7),
        (1.28, 1.96, 2.3, 8),
    ] {
        solid(v(0.02, y, z0), v(0.28, y + 0.3, z1), [m; 6]);
    }
    // Chair in front of the desk: seat, back and a central post.
    solid(v(1.75, 0.45, 1.2), v(2.25, 0.5, 1.7), [fabric; 6]);
    solid(v(1.75, 0.5, 1.65), v(2.25, 1.0, 1.7), [fabric; 6]);
    solid(v(1.97, 0.0, 1.42), v(2.03, 0.45, 1.48), [fabric; 6]);
    // Ceiling fixture: a shallow box whose underside is the lamp.
    solid(
        v(1.4, 2.62, 1.45),
        v(2.6, h, 2.05),
        [fixture, fixture, light, fixture, fixture, fixture],
    );
    Scene {
        name: "office".into(),
        source: None,
        materials,
        polygons,
        camera: Some(Camera {
            eye: v(3.8, 1.7, 3.4),
            target: v(1.2, 0.7, 0.8),
            up: Vec3::Y,
            fov_y_deg: 62.0,
        }),
        warnings: vec![],
        origins: vec![],
        up: None,
    }
}

/// Reflectance of every surface of the furnace scene.
pub const FURNACE_REFLECTANCE: Rgb = Rgb::new(0.3, 0.5, 0.7);
/// Emission of every surface of the furnace scene (W/m²).
pub const FURNACE_EMISSION: Rgb = Rgb::new(1.0, 1.0, 1.0);

/// The white-furnace test: a closed 1 m box with a floating inner block (so that surfaces
/// occlude each other), every surface with the same reflectance [`FURNACE_REFLECTANCE`] and the
/// same emission [`FURNACE_EMISSION`]. In a closed enclosure every row of F sums to 1, so the
/// exact solution is B = E/(1 − ρ) on every patch, whatever the geometry.
pub fn furnace() -> Scene {
    let materials = vec![Material::emitter(
        "furnace",
        FURNACE_REFLECTANCE,
        FURNACE_EMISSION,
    )];
    let mut polygons = box_faces(Vec3::ZERO, Vec3::ONE, [0; 6], true);
    polygons.extend(box_faces(
        v(0.3, 0.25, 0.35),
        v(0.7, 0.6, 0.65),
        [0; 6],
        false,
    ));
    Scene {
        name: "furnace".into(),
        source: None,
        materials,
        polygons,
        camera: Some(Camera {
            eye: v(0.5, 0.5, 0.98),
            target: v(0.5, 0.45, 0.0),
            up: Vec3::Y,
            fov_y_deg: 80.0,
        }),
        warnings: vec![],
        origins: vec![],
        up: None,
    }
}

/// A city for view-factor benchmarks: a k × k grid of box buildings (four walls and a roof each,
/// 12 m square on a 20 m grid, heights 10–60 m from a fixed hash) on one ground polygon, under
/// an emitting sky quad 200 m up. Geometry in metres; 5k² + 2 polygons (19,847 for k = 63, the
/// built-in `city`), with plenty of occlusion.
pub fn city(k: usize) -> Scene {
    let materials = vec![
        Material::diffuse("ground", Rgb::splat(0.2)),
        Material::diffuse("facade", Rgb::new(0.6, 0.55, 0.5)),
        Material::emitter("sky", Rgb::BLACK, Rgb::new(0.8, 0.9, 1.0)),
    ];
    let size = 20.0 * k as f32;
    let mut polygons = vec![
        oriented_quad(
            vec![
                v(-10.0, 0.0, -10.0),
                v(size, 0.0, -10.0),
                v(size, 0.0, size),
                v(-10.0, 0.0, size),
            ],
            Vec3::Y,
            0,
        ),
        oriented_quad(
            vec![
                v(-10.0, 200.0, -10.0),
                v(size, 200.0, -10.0),
                v(size, 200.0, size),
                v(-10.0, 200.0, size),
            ],
            -Vec3::Y,
            2,
        ),
    ];
    for i in 0..k {
        for j in 0..k {
            let h = 10.0 + (crate::sampling::mix64((i * 1000 + j) as u64) % 5001) as f32 / 100.0;
            let lo = v(20.0 * i as f32 - 6.0, 0.0, 20.0 * j as f32 - 6.0);
            let hi = v(20.0 * i as f32 + 6.0, h, 20.0 * j as f32 + 6.0);
            // Outward faces without the bottom (box_faces order: x−, x+, y− (bottom), y+, z−, z+).
            polygons.extend(
                box_faces(lo, hi, [1; 6], false)
                    .into_iter()
                    .enumerate()
                    .filter(|(f, _)| *f != 2)
                    .map(|(_, p)| p),
            );
        }
    }
    Scene {
        name: format!("city{k}"),
        source: None,
        materials,
        polygons,
        camera: Some(Camera {
            eye: v(-150.0, 300.0, -150.0),
            target: v(size * 0.5, 0.0, size * 0.5),
            up: Vec3::Y,
            fov_y_deg: 50.0,
        }),
        warnings: vec![],
        origins: vec![],
        up: None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_builtin_validates() {
        for name in NAMES {
            let s = by_name(name).unwrap();
            s.validate().unwrap_or_else(|e| panic!("{name}: {e}"));
        }
    }

    /// The office is a closed room of closed furniture: every ray from every patch lands on the
    /// front of some patch (rows of F sum to 1), and `--patches 270` gives the paper's size.
    #[test]
    fn office_is_closed_and_the_papers_size() {
        use crate::accel::Bvh;
        use crate::mesh::{Mesh, MeshParams};
        let s = office();
        let mesh = Mesh::build(&s, MeshParams::Patches(270)).unwrap();
        assert!((250..=300).contains(&mesh.len()), "{} patches", mesh.len());
        let bvh = Bvh::build(&mesh);
        let f = crate::formfactor::Estimator::new(
            &mesh,
            &bvh,
            crate::formfactor::Params::monte_carlo(4000, 7),
        )
        .expect("valid parameters")
        .sparse_matrix();
        let (mut lost, mut whole) = (0.0, 0);
        for i in 0..mesh.len() {
            let sum: f64 = f.row_entries(i).iter().map(|e| e.1 as f64).sum();
            lost += (1.0 - sum) * mesh.patches[i].area as f64;
            whole += usize::from((sum - 1.0).abs() < 1e-4);
        }
        // Rays are lost only from where two faces touch: 1.05 m² of footprints on the room
        // (fixture 0.72, bookcase 0.26, desk and chair legs 0.07 + 0.004) and 0.50 m² of
        // furniture resting on furniture (books 0.40, desk top 0.07, chair 0.03), counted on
        // both faces: 2.05 m² in all. An open seam or a flipped face would lose far more.
        assert!(
            (1.85..2.2).contains(&lost),
            "{lost} m² of patch area sees nothing"
        );
        assert!(
            whole * 10 >= mesh.len() * 8,
            "{whole} of {} rows sum to 1",
            mesh.len()
        );
    }

    #[test]
    fn cornell_colours_are_plausible() {
        let (white, red, green, light) = cornell_colours();
        // White paint is a light, nearly neutral grey.
        assert!(
            white.min_channel() > 0.6 && white.max_channel() < 0.8,
            "{white}"
        );
        // Red reflects red, green reflects green.
        assert!(red.r > 3.0 * red.g && red.r > 3.0 * red.b, "{red}");
        assert!(
            green.g > 1.5 * green.r && green.g > 1.5 * green.b,
            "{green}"
        );
        // The light's spectrum rises towards the red: a warm light.
        assert!(light.r > light.g && light.g > light.b, "{light}");
    }

    #[test]
    fn cornell_surfaces_face_into_the_box() {
        let s = cornell();
        let centre = Vec3::new(278.0, 274.0, 280.0);
        // The first nine polygons are the room (floor, light, ceiling ×4, walls): they face in.
        for p in &s.polygons[..9] {
            let n = vector_area(&p.vertices);
            assert!(n.dot(centre - p.vertices[0]) > 0.0);
        }
        // The block faces face out of their blocks, i.e. away from the block's centre.
        for (range, c) in [
            (9..14, Vec3::new(186.0, 82.0, 169.0)),
            (14..19, Vec3::new(368.0, 165.0, 351.0)),
        ] {
            for p in &s.polygons[range] {
                let n = vector_area(&p.vertices);
                let mid = p.vertices.iter().copied().sum::<Vec3>() / 4.0;
                assert!(n.dot(mid - c) > 0.0);
            }
        }
        // The ceiling and its hole cover exactly the published ceiling's area.
        let ceiling: f64 = s.polygons[1..6]
            .iter()
            .map(|p| super::super::polygon_area(&p.vertices))
            .sum();
        assert!((ceiling - 556.0 * 559.2).abs() < 1.0, "{ceiling}");
    }
}
