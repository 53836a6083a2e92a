//! `radiosity render`: pictures of a solved scene (PNG, EXR, PFM) from built-in, OBJ, MGF, glTF
//! and PLY scenes, by the radiosity solution, the final gather and the path tracer.

use crate::common::*;
use crate::validator;
use std::path::Path;

/// A lit box as OBJ: floor, ceiling light, one wall.
const GOOD_OBJ: &str = "mtllib box.mtl\nv 0 0 0\nv 1 0 0\nv 1 0 1\nv 0 0 1\nv 0 1 0\nv 1 1 0\nv 1 1 1\nv 0 1 1\nusemtl white\nf 1 4 3 2\nf 1 2 6 5\nusemtl lamp\nf 5 6 7 8\n";
const GOOD_MTL: &str = "newmtl white\nKd 0.7 0.7 0.7\nnewmtl lamp\nKd 0.5 0.5 0.5\nKe 10 10 10\n";

#[test]
fn render_writes_png_exr_and_pfm() {
    let dir = scratch("render");
    let stdout = run_ok(
        &[
            "render",
            "--patches",
            "1500",
            "--width",
            "96",
            "--height",
            "96",
            "--out",
            "c.png",
        ],
        &dir,
    );
    for key in ["patches", "rays", "iterations", "unshot", "time"] {
        assert!(stdout.contains(key), "summary lacks {key}: {stdout}");
    }
    let img = image::open(dir.join("c.png")).unwrap().to_rgb8();
    assert_eq!(img.dimensions(), (96, 96));
    // The red wall is on the left, the green wall on the right (camera looks along +z, +x left).
    let mean = |x0: u32, x1: u32| {
        let mut s = [0f64; 3];
        for y in 20..76 {
            for x in x0..x1 {
                for c in 0..3 {
                    s[c] += img.get_pixel(x, y)[c] as f64;
                }
            }
        }
        s
    };
    let (l, r) = (mean(4, 14), mean(82, 92));
    // sRGB encoding compresses ratios (linear green wall ≈ (0.09, 0.40, 0.08) under a warm
    // light), so compare the walls with each other, with margin.
    assert!(l[0] > 1.5 * l[1], "left is not red: {l:?}");
    assert!(r[1] > 1.3 * r[0], "right is not green: {r:?}");
    assert!(
        l[0] / l[1] > 3.0 * (r[0] / r[1]),
        "left {l:?} vs right {r:?}"
    );
    // Linear HDR outputs.
    for name in ["c.exr", "c.pfm"] {
        run_ok(
            &[
                "render",
                "--patches",
                "300",
                "--width",
                "32",
                "--height",
                "24",
                "--out",
                name,
            ],
            &dir,
        );
    }
    let pfm = read_bytes(&dir, "c.pfm");
    assert!(pfm.starts_with(b"PF\n32 24\n-1.0\n"));
    assert_eq!(pfm.len(), b"PF\n32 24\n-1.0\n".len() + 32 * 24 * 12);
    let exr = read_bytes(&dir, "c.exr");
    assert_eq!(&exr[..4], &[0x76, 0x2f, 0x31, 0x01], "not an OpenEXR file");
}

#[test]
fn obj_scene_renders_with_camera_flags() {
    let dir = scratch("obj");
    write(&dir, "box.obj", GOOD_OBJ);
    write(&dir, "box.mtl", GOOD_MTL);
    run_ok(
        &[
            "render",
            "box.obj",
            "--patches",
            "200",
            "--width",
            "32",
            "--height",
            "32",
            "--eye",
            "0.5,0.5,3",
            "--target",
            "0.5,0.5,0",
            "--fov",
            "40",
        ],
        &dir,
    );
    let img = image::open(dir.join("box.png")).unwrap().to_rgb8();
    assert!(img.pixels().any(|p| p[0] > 0), "the picture is black");
}

/// A small MGF scene of our own, with an include, an array and primitives, solves and renders
/// from its default (inside) camera; the picture is not black.
#[test]
fn mgf_scene_solves_and_renders() {
    let dir = scratch("mgf-room");
    // A 4 × 4 × 3 m room seen from inside: a prism turned inside out, a ceiling light, and an
    // array of three spheres from an included file.
    let room = "m wall =\n c\n cxy 0.4 0.35\n rd 0.6\n\
                v f0 =\n p 0 0 0\nv f1 =\n p 4 0 0\nv f2 =\n p 4 4 0\nv f3 =\n p 0 4 0\n\
                prism f0 f1 f2 f3 -3\n\
                m lamp =\n c\n ed 2000\n rd 0.1\n sides 1\n\
                v l0 =\n p 1.5 1.5 2.99\nv l1 =\n p 2.5 1.5 2.99\nv l2 =\n p 2.5 2.5 2.99\nv l3 =\n p 1.5 2.5 2.99\n\
                f l3 l2 l1 l0\n\
                i balls.mgf -t 1 2 0.5 -a 3 -t 1 0 0\n";
    let balls = "m red =\n c\n cxy 0.55 0.32\n rd 0.4\nv c =\n p 0 0 0\nsph c 0.3\n";
    write(&dir, "room.mgf", room);
    write(&dir, "balls.mgf", balls);
    let text = run_ok(
        &[
            "render",
            "room.mgf",
            "--patches",
            "2000",
            "--width",
            "64",
            "--height",
            "48",
            "-o",
            "room.png",
        ],
        &dir,
    );
    // 6 room faces + 1 light + 3 spheres × 128 facets, the room and spheres doubled (two-sided).
    assert!(
        text.contains(&format!("({} polygons)", 2 * (6 + 3 * 128) + 1)),
        "{text}"
    );
    let img = image::open(dir.join("room.png")).unwrap().to_rgb8();
    let lit = img.pixels().filter(|p| p.0.iter().any(|c| *c > 20)).count();
    assert!(
        lit * 10 > 9 * img.pixels().count() as usize,
        "mostly black: {lit}"
    );
}

#[test]
#[ignore = "needs Node and the glTF validator that .ci/run installs (run with --include-ignored, as .ci/run does)"]
fn gltf_and_ply_scenes_solve_render_and_bake() {
    let dir = scratch("interchange");
    let mut written = Vec::new();
    for (scene, stem) in [
        ("room.gltf", "room"),
        ("room.ply", "box"),
        ("room_be.ply", "box_be"),
    ] {
        let src = test_scene(scene);
        let src = src.to_str().unwrap();
        // Solved and rendered: the glTF from its own camera, the PLY boxes from inside.
        let png = format!("{stem}.png");
        let text = run_ok(
            &[
                "render",
                src,
                "--patches",
                "1500",
                "--width",
                "64",
                "--height",
                "48",
                "-o",
                &png,
            ],
            &dir,
        );
        assert!(text.contains("escaped"), "{text}");
        assert!(lit_fraction(&dir.join(&png)) > 0.9, "{stem}: mostly black");
        // Baked to every format.
        for ext in ["glb", "gltf", "ply"] {
            let out = format!("{stem}.{ext}");
            run_ok(&["solve", src, "--patches", "1500", "-o", &out], &dir);
            if ext != "ply" {
                written.push(dir.join(&out));
            }
        }
    }
    // A baked file is a scene too: rendered from the camera it carries.
    run_ok(
        &[
            "render",
            "room.glb",
            "--patches",
            "1500",
            "--width",
            "64",
            "--height",
            "48",
            "-o",
            "again.png",
        ],
        &dir,
    );
    assert!(lit_fraction(&dir.join("again.png")) > 0.9);
    // The built-in scenes baked too, with a darker exposure.
    for (scene, out) in [("cornell", "cornell.glb"), ("cube", "cube.gltf")] {
        run_ok(
            &[
                "solve",
                scene,
                "--patches",
                "800",
                "--exposure",
                "-1",
                "-o",
                out,
            ],
            &dir,
        );
        written.push(dir.join(out));
    }
    validator::validate_gltf(&written);
}

// ---------------------------------------------------------------------------------------------
// Pictures: final gather and path tracer.

/// The furnace (closed, every surface emits E = 1 and reflects ρ): every pixel's radiance is
/// E/(π(1 − ρ)). The path tracer and the gather both give it: the mean over the picture
/// within 4 standard errors (from the pixels' own spread), plus for the gather the deficit
/// its solve may leave, and 1 %.
#[test]
fn furnace_pictures_by_path_and_gather() {
    let dir = scratch("furnace-pictures");
    for (args, unshot) in [
        (&["--integrator", "path", "--spp", "64"][..], 0.0),
        (&["--gather", "--spp", "4", "--tolerance", "0.0001"], 1e-4),
    ] {
        let mut all = vec![
            "render", "furnace", "--width", "24", "--height", "24", "-o", "f.pfm",
        ];
        all.extend_from_slice(args);
        run_ok(&all, &dir);
        assert_furnace_picture(&dir.join("f.pfm"), unshot, &format!("{args:?}"));
    }
}

/// Gather and path pictures are the same bytes whatever the thread count.
#[test]
fn gather_and_path_do_not_depend_on_threads() {
    let dir = scratch("picture-threads");
    for args in [
        &["--gather", "--spp", "4", "--patches", "500"][..],
        &["--integrator", "path", "--spp", "8"],
    ] {
        let mut bytes = Vec::new();
        for t in ["1", "2"] {
            let mut all = vec![
                "render",
                "cornell",
                "--width",
                "32",
                "--height",
                "32",
                "-o",
                "c.pfm",
                "--threads",
                t,
            ];
            all.extend_from_slice(args);
            run_ok(&all, &dir);
            bytes.push(read_bytes(&dir, "c.pfm"));
        }
        assert_eq!(bytes[0], bytes[1], "{args:?}");
    }
}

#[test]
fn picture_options_are_checked() {
    let dir = scratch("picture-options");
    for (args, needle) in [
        (
            &["--gather", "--direct-samples", "0"][..],
            "--direct-samples 0",
        ),
        (&["--gather", "--cache-accuracy", "0"], "--cache-accuracy 0"),
        (&["--gather", "--gather-near=-1"], "--gather-near -1"),
        (&["--gather", "--integrator", "path"], "cannot be used with"),
    ] {
        let mut all = vec!["render", "cornell", "-o", "x.png"];
        all.extend_from_slice(args);
        fails(&all, &dir, &[needle], &[]);
    }
}

/// Every pixel of a furnace picture is E/(π(1 − ρ)) (E = 1, ρ = 0.3, 0.5, 0.7): the mean over
/// the picture within 4 standard errors (from the pixels' own spread) plus the deficit of a
/// solve stopped at the fraction `unshot` of the emitted energy, and 1 %.
///
/// That deficit: the output x + r of progressive refinement lacks ρF(I − ρF)⁻¹ r, whose
/// area-weighted sum in a closed furnace of one ρ is ρ/(1 − ρ) Σ r_i A_i. A channel holds at
/// most all the unshot energy, `unshot` times the three channels' emission, so the mean
/// radiosity 1/(1 − ρ) falls short by at most the relative 3 · unshot · ρ.
pub(crate) fn assert_furnace_picture(path: &Path, unshot: f64, what: &str) {
    let px = read_pfm_pixels(path);
    for (c, rho) in [0.3, 0.5, 0.7].into_iter().enumerate() {
        let exact = 1.0 / (std::f64::consts::PI * (1.0 - rho));
        let v: Vec<f64> = px.iter().map(|p| p[c] as f64).collect();
        let n = v.len() as f64;
        let mean = v.iter().sum::<f64>() / n;
        let sd = (v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
        let deficit = 3.0 * unshot * rho * exact;
        assert!(
            (mean - exact).abs() < 4.0 * sd / n.sqrt() + deficit + 1e-9
                && (mean - exact).abs() < 0.01 * exact,
            "{what} channel {c}: {mean} vs {exact} (sd {sd})"
        );
    }
}
