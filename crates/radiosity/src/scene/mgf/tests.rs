//! Unit tests of the MGF loader.

use super::*;
use crate::scene::vector_area;

/// Write `files` (name, text) into a fresh folder and return it.
fn folder(tag: &str, files: &[(&str, &str)]) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("radiosity-mgf-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    for (name, text) in files {
        let path = dir.join(name);
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(path, text).unwrap();
    }
    dir
}

fn load_text(tag: &str, text: &str) -> Result<Scene, SceneError> {
    let dir = folder(tag, &[("s.mgf", text)]);
    load_with(&dir.join("s.mgf"), true)
}

const SQUARE: &str =
    "m white =\n c\n rd 0.5\nv a =\n p 0 0 0\nv b =\n p 1 0 0\nv c =\n p 1 1 0\nv d =\n p 0 1 0\n";

#[test]
fn arrays_repeat_the_block_with_growing_transforms() {
    let s = load_text(
        "array",
        &format!("{SQUARE}xf -t 0 0 1 -a 3 -t 2 0 0 -a 2 -t 0 5 0\nf a b c d\nxf\n"),
    )
    .unwrap();
    assert_eq!(s.polygons.len(), 6);
    let mut origins: Vec<(i32, i32, i32)> = s
        .polygons
        .iter()
        .map(|p| {
            let v = p.vertices[0];
            (v.x as i32, v.y as i32, v.z as i32)
        })
        .collect();
    origins.sort();
    assert_eq!(
        origins,
        vec![
            (0, 0, 1),
            (0, 5, 1),
            (2, 0, 1),
            (2, 5, 1),
            (4, 0, 1),
            (4, 5, 1)
        ]
    );
}

#[test]
fn transforms_apply_in_order_and_mirrors_keep_faces_facing_out() {
    // Rotate 90° about z, then translate: (1, 0, 0) → (0, 1, 0) → (10, 1, 0).
    let s = load_text(
        "order",
        &format!("{SQUARE}xf -rz 90 -t 10 0 0\nf a b c d\nxf\n"),
    )
    .unwrap();
    assert!((s.polygons[0].vertices[1] - Vec3::new(10.0, 1.0, 0.0)).length() < 1e-5);
    // A mirror in x keeps the face looking up (+z).
    let s = load_text("mirror", &format!("{SQUARE}xf -mx\nf a b c d\nxf\n")).unwrap();
    assert!(vector_area(&s.polygons[0].vertices).z > 0.0);
    // -i repeats: three quarter turns about z.
    let s = load_text(
        "iterate",
        &format!("{SQUARE}xf -i 3 -rz 90\nf a b c d\nxf\n"),
    )
    .unwrap();
    assert!((s.polygons[0].vertices[1] - Vec3::new(0.0, -1.0, 0.0)).length() < 1e-5);
}

#[test]
fn prisms_and_spheres_are_closed_and_face_out() {
    let text = format!("{SQUARE}prism a b c d 1\nv o =\n p 5 5 5\nsph o 2\n");
    let s = load_text("solids", &text).unwrap();
    let (prism, sphere) = s.polygons.split_at(6);
    // Closed surfaces: the vector areas sum to zero; outward: the divergence theorem gives
    // the volume as (1/3) Σ centroid · vector area > 0.
    for (solid, volume, tol) in [
        (prism, 1.0, 1e-5),
        // The inscribed polyhedron's volume is a little below (4/3)π r³.
        (sphere, 4.0 / 3.0 * std::f64::consts::PI * 8.0, 0.1),
    ] {
        let total: Vec3 = solid.iter().map(|p| vector_area(&p.vertices)).sum();
        assert!(total.length() < 1e-4, "{total}");
        let v: f64 = solid
            .iter()
            .map(|p| {
                let c = p.vertices.iter().copied().sum::<Vec3>() / p.vertices.len() as f32;
                (c.dot(vector_area(&p.vertices)) / 3.0) as f64
            })
            .sum();
        assert!(
            v > 0.0 && (v - volume).abs() < tol * volume,
            "{v} vs {volume}"
        );
    }
    // 8 bands × 16 segments.
    assert_eq!(sphere.len(), 8 * 16);
}

#[test]
fn cylinders_cones_rings_and_tori_face_the_documented_way() {
    let text = format!(
        "{SQUARE}v p =\n p 0 0 0\n n 0 0 1\nv q =\n p 0 0 2\n\
         cyl p 1 q\ncyl p -1 q\ncone p 1 q 0\nring p 0.5 1\ntorus p 1 2\n"
    );
    let s = load_text("revolution", &text).unwrap();
    let n = 16;
    let groups: Vec<&[Polygon]> = {
        let (cyl, rest) = s.polygons.split_at(n);
        let (inv, rest) = rest.split_at(n);
        let (cone, rest) = rest.split_at(n);
        let (ring, torus) = rest.split_at(n);
        vec![cyl, inv, cone, ring, torus]
    };
    let radial = |p: &Polygon| {
        let c = p.vertices.iter().copied().sum::<Vec3>() / p.vertices.len() as f32;
        let a = vector_area(&p.vertices);
        Vec3::new(c.x, c.y, 0.0).dot(a)
    };
    assert!(
        groups[0].iter().all(|p| radial(p) > 0.0),
        "cylinder faces out"
    );
    assert!(
        groups[1].iter().all(|p| radial(p) < 0.0),
        "negative radius faces in"
    );
    assert!(groups[2].iter().all(|p| radial(p) > 0.0), "cone faces out");
    assert!(
        groups[3].iter().all(|p| vector_area(&p.vertices).z > 0.0),
        "ring faces n"
    );
    assert_eq!(groups[4].len(), 16 * 16);
    // Ring area: π (1 − 0.25) less the polygon's shortfall; torus area 4π² R r.
    let area = |g: &[Polygon]| {
        g.iter()
            .map(|p| super::super::polygon_area(&p.vertices))
            .sum::<f64>()
    };
    let pi = std::f64::consts::PI;
    assert!((area(groups[3]) / (pi * 0.75) - 1.0).abs() < 0.03);
    assert!((area(groups[4]) / (4.0 * pi * pi * 1.5 * 0.5) - 1.0).abs() < 0.04);
}

#[test]
fn colours_and_emission_convert_as_documented() {
    let text =
        "c red =\n cxy 0.64 0.33\nm lamp =\n c\n ed 179\n rd 0.2\nm paint =\n c red\n rd 0.2\n\
                v a =\n p 0 0 0\nv b =\n p 1 0 0\nv c =\n p 1 1 0\n\
                m lamp\nf a b c\nm paint\nf a b c\n";
    let s = load_text("colour", text).unwrap();
    let lamp = &s.materials[s.polygons[0].material];
    // ed 179 lm/m² of white is 1 W/m² in every channel; rd 0.2 of white is grey 0.2.
    assert!(
        lamp.emission.max_abs_diff(Rgb::splat(1.0)) < 1e-9,
        "{}",
        lamp.emission
    );
    assert!(lamp.reflectance.max_abs_diff(Rgb::splat(0.2)) < 1e-9);
    // The sRGB red primary's chromaticity is pure red, its luminance Y = 0.2 (the red
    // primary's luminance weight is 0.2126, so R = 0.2 / 0.2126 after balancing).
    let paint = &s.materials[s.polygons[1].material];
    assert!(
        paint.reflectance.r > 0.5 && paint.reflectance.g < 0.02 && paint.reflectance.b < 0.02,
        "{}",
        paint.reflectance
    );
}

#[test]
fn two_sided_surfaces_are_doubled_unless_one_sided() {
    let dir = folder(
        "sides",
        &[(
            "s.mgf",
            &format!("{SQUARE}f a b c d\nm white\nsides 1\nf a b c d\n"),
        )],
    );
    assert_eq!(
        load_with(&dir.join("s.mgf"), false).unwrap().polygons.len(),
        3
    );
    assert_eq!(
        load_with(&dir.join("s.mgf"), true).unwrap().polygons.len(),
        2
    );
}

#[test]
fn faces_with_holes_mesh_into_the_right_area() {
    let text = format!(
        "{SQUARE}v e =\n p 0.25 0.25 0\nv f =\n p 0.75 0.25 0\nv g =\n p 0.75 0.75 0\nv h =\n p 0.25 0.75 0\n\
         fh a b c d - h g f e\n"
    );
    let s = load_text("holes", &text).unwrap();
    let mesh = crate::mesh::Mesh::build(&s, crate::mesh::MeshParams::Faces).unwrap();
    assert!(
        (mesh.total_area() - 0.75).abs() < 1e-5,
        "{}",
        mesh.total_area()
    );
}

#[test]
fn includes_transform_and_report_their_own_file() {
    let dir = folder(
        "include",
        &[
            ("top.mgf", "i sub/part.mgf -t 0 0 3 -a 2 -t 1 0 0\n"),
            ("sub/part.mgf", ""),
        ],
    );
    std::fs::write(
        dir.join("sub/part.mgf"),
        format!("{SQUARE}f a b c\nf a b\n"),
    )
    .unwrap();
    let err = load(&dir.join("top.mgf")).unwrap_err().to_string();
    assert!(
        err.contains("part.mgf:13") && err.contains("at least 3"),
        "{err}"
    );
    std::fs::write(dir.join("sub/part.mgf"), format!("{SQUARE}f a b c\n")).unwrap();
    let s = load_with(&dir.join("top.mgf"), true).unwrap();
    assert_eq!(s.polygons.len(), 2);
    assert_eq!(s.polygons[1].vertices[0], Vec3::new(1.0, 0.0, 3.0));
    assert!(
        s.place_of(1).to_string().contains("part.mgf:12"),
        "{}",
        s.place_of(1)
    );
}

#[test]
fn bad_input_names_the_file_and_line() {
    let cases = [
        ("f a b c\n", "s.mgf:1", "undefined vertex 'a'"),
        ("v a =\n p 0 x 0\n", "s.mgf:2", "malformed number 'x'"),
        ("i nowhere.mgf\n", "s.mgf:1", "not found"),
        ("i s.mgf\n", "s.mgf:1", "include loop"),
        ("v a =\nf a a\n", "s.mgf:2", "at least 3"),
        ("xf -t 1 2 3\n", "s.mgf:1", "never closed"),
        ("xf\n", "s.mgf:1", "without a matching"),
        ("m x =\n rd 1.5\n", "s.mgf:2", "out of range"),
        ("xf -q\nxf\n", "s.mgf:1", "unknown transform option"),
    ];
    for (k, (text, place, what)) in cases.iter().enumerate() {
        let err = load_text(&format!("bad{k}"), text).unwrap_err().to_string();
        assert!(err.contains(place) && err.contains(what), "{text:?}: {err}");
        assert!(!err.contains('\n'), "one line: {err}");
    }
}
