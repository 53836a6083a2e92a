//! `radiosity render --luminaires … --luminance`: the lit scene in cd/m² against the
//! inverse-square cosine law; the energy books in `lighting`'s summary; bad combinations.

use crate::common::*;
use radiosity_cli::false_colour::{Bands, RasterFrame, Scale};
use std::f64::consts::PI;
use std::path::Path;

/// An isotropic luminaire of `i0` candela, as an IES file (absolute photometry).
fn isotropic(i0: f64) -> String {
    let gammas: Vec<String> = (0..=36).map(|k| (5 * k).to_string()).collect();
    let cd = vec![i0.to_string(); 37];
    format!(
        "IESNA:LM-63-2002\nTILT=NONE\n1 -1 1 37 1 1 2 0 0 0\n1 1 0\n{}\n0\n{}\n",
        gammas.join(" "),
        cd.join(" ")
    )
}

/// A lone 4 × 4 m floor (ρ = 0.5) centred on the origin, facing up, and a 1,000 cd isotropic
/// luminaire 2 m above its centre.
fn floor(dir: &Path) {
    write(
        dir,
        "floor.obj",
        "mtllib floor.mtl\nv -2 -2 0\nv 2 -2 0\nv 2 2 0\nv -2 2 0\nusemtl floor\nf 1 2 3 4\n",
    );
    write(dir, "floor.mtl", "newmtl floor\nKd 0.5 0.5 0.5\n");
    write(dir, "iso.ies", &isotropic(1000.0));
    write(
        dir,
        "schedule.csv",
        "name,file,x,y,z,aim_x,aim_y,aim_z,c0_x,c0_y,c0_z,multiplier,group\n\
         lamp,iso.ies,0,0,2,,,,,,,1,\n",
    );
}

/// The unit direction of the ray through image point (px, py) of the pinhole camera
/// (`render`'s: forward, right = forward × up, up' = right × forward; the image plane at
/// tan(fov/2) vertically, scaled by the aspect horizontally).
fn ray(
    eye: [f64; 3],
    target: [f64; 3],
    up: [f64; 3],
    fov: f64,
    size: (f64, f64),
    p: (f64, f64),
) -> [f64; 3] {
    let sub = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let cross = |a: [f64; 3], b: [f64; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let unit = |a: [f64; 3]| {
        let n = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
        [a[0] / n, a[1] / n, a[2] / n]
    };
    let f = unit(sub(target, eye));
    let r = unit(cross(f, up));
    let u = cross(r, f);
    let ty = (fov.to_radians() / 2.0).tan();
    let tx = ty * size.0 / size.1;
    let sx = (2.0 * p.0 / size.0 - 1.0) * tx;
    let sy = (1.0 - 2.0 * p.1 / size.1) * ty;
    unit([
        f[0] + r[0] * sx + u[0] * sy,
        f[1] + r[1] * sx + u[1] * sy,
        f[2] + r[2] * sx + u[2] * sy,
    ])
}

/// A point luminaire over a Lambertian floor, nothing else: one camera sample at each pixel's
/// centre sees the floor point x there, whose luminance is ρ I cos³θ / (π h²) (the
/// inverse-square cosine law times ρ/π; nothing is interreflected), to `f32` rounding; the
/// PFM holds it in all three channels. The books: 4π I emitted, I Ω on the floor (Ω = 4
/// asin(L² / (L² + 4h²)) = 2π/3 sr) to 10⁻⁶ (the first shot integrates each patch's solid
/// angle exactly for an isotropic source), and escaped = emitted − absorbed − unshot.
#[test]
fn render_luminance_follows_the_cosine_cubed_law() {
    let dir = scratch("render-luminance");
    floor(&dir);
    let text = run_ok(
        &[
            "render",
            "floor.obj",
            "--luminaires",
            "schedule.csv",
            "--luminance",
            "-o",
            "floor.pfm",
            "--false-colour",
            "floor.png",
            "--eye",
            "0.3,0.2,6",
            "--target",
            "0,0,0",
            "--up",
            "0,1,0",
            "--fov",
            "50",
            "--width",
            "32",
            "--height",
            "32",
            "--spp",
            "1",
            "--patches",
            "256",
            "--report",
            "json",
        ],
        &dir,
    );
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    let pixels = read_pfm_pixels(&dir.join("floor.pfm"));
    assert_eq!(pixels.len(), 32 * 32);
    let (eye, h, rho, i0) = ([0.3, 0.2, 6.0], 2.0, 0.5, 1000.0);
    let mut checked = 0;
    for py in 0..32 {
        for px in 0..32 {
            let d = ray(
                eye,
                [0.0; 3],
                [0.0, 1.0, 0.0],
                50.0,
                (32.0, 32.0),
                (px as f64 + 0.5, py as f64 + 0.5),
            );
            let t = -eye[2] / d[2];
            let (x, y) = (eye[0] + t * d[0], eye[1] + t * d[1]);
            // PFM rows run bottom to top.
            let p = pixels[(31 - py) * 32 + px];
            if x.abs() > 1.99 || y.abs() > 1.99 {
                continue;
            }
            let cos = h / (x * x + y * y + h * h).sqrt();
            let want = rho * i0 * cos.powi(3) / (PI * h * h);
            for c in p {
                assert!(
                    (c as f64 - want).abs() < 1e-4 * want,
                    "pixel ({px}, {py}) at ({x}, {y}): {p:?} cd/m², law {want}"
                );
            }
            checked += 1;
        }
    }
    assert!(checked > 300, "{checked}");
    let total = &v["books"]["total"];
    let f = |k: &str| total[k].as_f64().unwrap();
    let emitted = 4.0 * PI * i0;
    assert!((f("emitted") - emitted).abs() < 1e-9 * emitted, "{total}");
    let on_floor = i0 * 4.0 * (16.0f64 / 32.0).asin();
    assert!(
        (f("direct_to_surfaces") - on_floor).abs() < 1e-6 * on_floor,
        "{total}"
    );
    assert!((f("escaped") - (f("emitted") - f("absorbed") - f("unshot"))).abs() < 1e-9 * emitted);
    assert_eq!(v["luminance"], true);
    // The false-colour picture: every pixel of the drawn raster has the legend colour of the
    // band of the luminance it shows (the bands are the picture's own: logarithmic over the
    // same values).
    let y: Vec<f64> = (0..32 * 32)
        .map(|k| {
            let (row, col) = (k / 32, k % 32);
            pixels[(31 - row) * 32 + col][1] as f64
        })
        .collect();
    let bands = Bands::of_values(&y, Scale::Log);
    let png = image::open(dir.join("floor.png")).unwrap().to_rgb8();
    let frame = RasterFrame::of(32, 32);
    assert_eq!(png.dimensions(), frame.size);
    let mut seen = std::collections::BTreeSet::new();
    for py in (frame.origin.1..frame.origin.1 + frame.drawn.1).step_by(7) {
        for px in (frame.origin.0..frame.origin.0 + frame.drawn.0).step_by(7) {
            let (c, r) = frame.value_at(px, py, 32, 32).unwrap();
            let k = bands.band(y[r * 32 + c]);
            assert_eq!(
                png.get_pixel(px, py).0,
                bands.colour(k),
                "pixel ({px}, {py})"
            );
            seen.insert(k);
        }
    }
    assert!(
        seen.len() >= 3,
        "the floor's fall-off spans bands: {seen:?}"
    );
}

/// A closed black box, two luminaires in two groups: nothing is reflected, so the flux on the
/// surfaces is absorbed whole, and every ray cast from the luminaires reaches a surface (the
/// counted escape is 0): the escape the books report, emitted − absorbed, is the first shot's
/// patch-sampling error, which is the balance error; under 1 % on 0.26 m patches 1.5 m from
/// the sources. Printed a line a group and the total, and in the JSON summary.
#[test]
fn lighting_keeps_the_books() {
    let dir = scratch("lighting-books");
    write(
        &dir,
        "box.obj",
        "mtllib box.mtl\nv 0 0 0\nv 4 0 0\nv 4 4 0\nv 0 4 0\nv 0 0 3\nv 4 0 3\nv 4 4 3\nv 0 4 3\nusemtl black\nf 1 2 3 4\nf 5 8 7 6\nf 1 5 6 2\nf 2 6 7 3\nf 3 7 8 4\nf 4 8 5 1\n",
    );
    write(&dir, "box.mtl", "newmtl black\nKd 0 0 0\n");
    write(&dir, "a.ies", &isotropic(800.0));
    write(&dir, "b.ies", &isotropic(200.0));
    write(
        &dir,
        "schedule.csv",
        "name,file,x,y,z,aim_x,aim_y,aim_z,c0_x,c0_y,c0_z,multiplier,group\n\
         A,a.ies,2,2,1.5,,,,,,,1,north\n\
         B,b.ies,2,2,1.5,,,,,,,0.5,south\n",
    );
    write(&dir, "p.pts", "2 2 0.8 0 0 1\n");
    let text = run_ok(
        &[
            "lighting",
            "box.obj",
            "--luminaires",
            "schedule.csv",
            "--grid",
            "p.pts",
            "--out",
            "grid.csv",
            "--summary",
            "summary.json",
            "--patches",
            "1200",
        ],
        &dir,
    );
    for g in ["north", "south", "total"] {
        assert!(
            text.contains(&format!("flux        {g}: emitted")),
            "{text}"
        );
    }
    let v: serde_json::Value = serde_json::from_str(&read(&dir, "summary.json")).unwrap();
    let books = &v["books"];
    for (k, (name, i0)) in [("north", 800.0), ("south", 100.0)].into_iter().enumerate() {
        let b = &books["groups"][k];
        assert_eq!(b["group"], name);
        let f = |key: &str| b[key].as_f64().unwrap();
        let emitted = 4.0 * PI * i0;
        assert!((f("emitted") - emitted).abs() < 1e-9 * emitted, "{b}");
        assert_eq!(f("unshot"), 0.0, "{b}");
        assert_eq!(f("escaped_counted"), 0.0, "{b}");
        assert!(
            (f("absorbed") - f("direct_to_surfaces")).abs() < 1e-9 * emitted,
            "{b}"
        );
        assert!(
            (f("escaped") - (emitted - f("absorbed"))).abs() < 1e-9 * emitted,
            "{b}"
        );
        assert!(
            (f("balance_error") * emitted - f("escaped")).abs() < 1e-9 * emitted,
            "{b}"
        );
        assert!(f("balance_error").abs() < 0.01, "{b}");
    }
    let total = books["total"]["emitted"].as_f64().unwrap();
    assert!((total - 4.0 * PI * 900.0).abs() < 1e-9 * total);
}

/// Combinations that cannot work: one line naming the option, nothing written.
#[test]
fn render_refuses_what_luminance_and_luminaires_cannot_do() {
    let dir = scratch("render-luminance-bad");
    floor(&dir);
    let keep = ["floor.obj", "floor.mtl", "iso.ies", "schedule.csv"];
    let base = ["render", "floor.obj", "--width", "8", "--height", "8"];
    for (extra, needles) in [
        (
            &["--luminance", "-o", "f.png"][..],
            &["--luminance", ".exr"][..],
        ),
        (
            &["--unit", "cm", "-o", "f.exr"][..],
            &["--unit", "--luminaires"][..],
        ),
        (
            &["--vertical", "y", "-o", "f.exr"][..],
            &["--vertical", "--luminaires"][..],
        ),
        (
            &[
                "--luminaires",
                "schedule.csv",
                "--integrator",
                "path",
                "-o",
                "f.exr",
            ][..],
            &["--luminaires", "path"][..],
        ),
        (
            &[
                "--luminaires",
                "schedule.csv",
                "--solver",
                "hierarchical",
                "-o",
                "f.exr",
            ][..],
            &["--luminaires", "hierarchical"][..],
        ),
        (
            &["--luminaires", "missing.csv", "-o", "f.exr"][..],
            &["missing.csv"][..],
        ),
        (
            &["--luminance", "-o", "f.exr", "--false-colour", "f.tif"][..],
            &["--false-colour", "f.tif"][..],
        ),
        (
            &["--luminance", "-o", "f.exr", "--false-colour", "f.exr"][..],
            &["--false-colour", "f.exr"][..],
        ),
        (
            &["-o", "f.exr", "--false-colour", "f.png"][..],
            &["--luminance"][..],
        ),
    ] {
        let args: Vec<&str> = base.iter().chain(extra).copied().collect();
        fails(&args, &dir, needles, &keep);
    }
}
