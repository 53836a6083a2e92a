//! `solve --bake lightmap`: a lightmapped glTF that the Khronos validator passes with no errors
//! and no warnings, the linear atlas as EXR, and bad lightmap options refused on one line.

use crate::common::*;

#[test]
#[ignore = "needs Node.js and the glTF validator (run with --include-ignored, as .ci/run does)"]
fn lightmap_bake_writes_a_valid_gltf_and_an_exr() {
    let dir = scratch("lightmap-bake");
    let out = run_ok(
        &[
            "solve",
            "cornell",
            "--patches",
            "400",
            "--out",
            "lit.glb",
            "--bake",
            "lightmap",
            "--lightmap-size",
            "128",
            "--lightmap-out",
            "lit.exr",
        ],
        &dir,
    );
    assert!(out.contains("lightmap    128×128 atlas"), "{out}");
    let exr = read_bytes(&dir, "lit.exr");
    assert_eq!(&exr[..4], &[0x76, 0x2f, 0x31, 0x01], "OpenEXR magic");
    run_ok(
        &[
            "solve",
            "cornell",
            "--patches",
            "400",
            "--out",
            "lit.gltf",
            "--bake",
            "lightmap",
            "--texel-size",
            "20",
        ],
        &dir,
    );
    let report =
        crate::validator::validate_gltf_report(&[dir.join("lit.glb"), dir.join("lit.gltf")]);
    assert_eq!(
        report.matches(": 0 errors, 0 warnings").count(),
        2,
        "{report}"
    );
    let text = read(&dir, "lit.gltf");
    for needle in ["\"MOZ_lightmap\"", "\"TEXCOORD_1\"", "\"image/png\""] {
        assert!(text.contains(needle), "{needle}");
    }
}

#[test]
fn lightmap_options_are_checked() {
    let dir = scratch("lightmap-bad");
    let base = ["solve", "cornell", "--patches", "50", "--out", "x.glb"];
    let with = |extra: &[&str]| {
        let mut a: Vec<&str> = base.to_vec();
        a.extend_from_slice(extra);
        a.iter().map(|s| s.to_string()).collect::<Vec<_>>()
    };
    for (extra, needles) in [
        (
            vec!["--bake", "lightmap", "--lightmap-size", "0"],
            vec!["--lightmap-size 0", "1 to 16384"],
        ),
        (
            vec!["--bake", "lightmap", "--lightmap-size", "1000000"],
            vec!["--lightmap-size 1000000"],
        ),
        (
            vec!["--bake", "lightmap", "--texel-size=-1"],
            vec!["--texel-size -1", "positive"],
        ),
        (
            vec!["--bake", "lightmap", "--texel-size", "0.001"],
            vec!["texel size 0.001", "more than 16384"],
        ),
        (
            vec!["--lightmap-size", "64"],
            vec!["--lightmap-size", "--bake lightmap"],
        ),
        (
            vec!["--bake", "lightmap", "--lightmap-out", "a.png"],
            vec!["a.png", ".exr"],
        ),
    ] {
        let args = with(&extra);
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        fails(&args, &dir, &needles, &[]);
    }
    fails(
        &["solve", "cornell", "--out", "x.csv", "--bake", "lightmap"],
        &dir,
        &["x.csv", "glTF"],
        &[],
    );
    // A mesh with no area.
    write(&dir, "flat.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n");
    fails(
        &["solve", "flat.obj", "--out", "x.glb", "--bake", "lightmap"],
        &dir,
        &["flat.obj"],
        &["flat.obj"],
    );
}

/// `view` shows a lightmap bake lit by its lightmap: the picture's mean (linear, PFM) within
/// 4 % of the vertex bake's of the same solution (the two bakes' methods differ by a few
/// per cent per quad, `tests/lightmap.rs`); baking the lightmapped file again keeps its
/// TEXCOORD_1; `--gather` on it asks for a vertex bake's radiosity.
#[test]
fn view_shows_a_lightmap_and_a_rebake_keeps_its_uvs() {
    let dir = scratch("lightmap-view");
    let solve = ["solve", "cornell", "--patches", "1500"];
    let lm = [
        &solve[..],
        &[
            "--out",
            "lit.glb",
            "--bake",
            "lightmap",
            "--lightmap-size",
            "128",
        ],
    ]
    .concat();
    run_ok(&lm, &dir);
    run_ok(&[&solve[..], &["--out", "vertex.glb"]].concat(), &dir);
    let out = run_ok(
        &[
            "view", "lit.glb", "-o", "lit.pfm", "--width", "96", "--height", "96",
        ],
        &dir,
    );
    assert!(
        out.contains("triangles lit by their lightmap (128×128)"),
        "{out}"
    );
    run_ok(
        &[
            "view",
            "vertex.glb",
            "-o",
            "vertex.pfm",
            "--width",
            "96",
            "--height",
            "96",
        ],
        &dir,
    );
    let mean = |name: &str| {
        let p = read_pfm_pixels(&dir.join(name));
        p.iter().map(|c| (c[0] + c[1] + c[2]) as f64).sum::<f64>() / p.len() as f64
    };
    let (a, b) = (mean("lit.pfm"), mean("vertex.pfm"));
    eprintln!("picture means: lightmap view {a:.5}, vertex view {b:.5}");
    assert!(
        (a - b).abs() <= 0.04 * b,
        "lightmap view mean {a}, vertex view {b}"
    );
    let again = run_ok(
        &[
            "solve",
            "lit.glb",
            "--patches",
            "1500",
            "--out",
            "again.glb",
            "--bake",
            "lightmap",
            "--lightmap-size",
            "128",
        ],
        &dir,
    );
    assert!(again.contains("(the input's TEXCOORD_1, kept"), "{again}");
    fails(
        &["view", "lit.glb", "--gather", "-o", "g.png"],
        &dir,
        &["lit.glb", "_RADIOSITY"],
        &[
            "lit.glb",
            "vertex.glb",
            "lit.pfm",
            "vertex.pfm",
            "again.glb",
        ],
    );
}

/// Several atlases: a texel size whose charts do not fit one `--lightmap-size` atlas packs
/// into several, the glTF (a material and a texture per atlas) passes the validator with no
/// errors and no warnings, and `--lightmap-out x.exr` writes `x-0.exr`, `x-1.exr`, …; the
/// denoised bake of the same runs too.
#[test]
#[ignore = "needs Node.js and the glTF validator (run with --include-ignored, as .ci/run does)"]
fn lightmap_in_several_atlases() {
    let dir = scratch("lightmap-atlases");
    let out = run_ok(
        &[
            "solve",
            "cornell",
            "--patches",
            "300",
            "--out",
            "many.glb",
            "--bake",
            "lightmap",
            "--texel-size",
            "12",
            "--lightmap-size",
            "64",
            "--lightmap-indirect",
            "16",
            "--lightmap-denoise",
            "--lightmap-out",
            "many.exr",
        ],
        &dir,
    );
    let atlases: usize = out
        .split("64×64 atlases ×")
        .nth(1)
        .and_then(|r| r.split(',').next())
        .and_then(|n| n.trim().parse().ok())
        .unwrap_or_else(|| panic!("{out}"));
    assert!(atlases >= 2, "{out}");
    for a in 0..atlases {
        let exr = read_bytes(&dir, &format!("many-{a}.exr"));
        assert_eq!(&exr[..4], &[0x76, 0x2f, 0x31, 0x01], "OpenEXR magic");
    }
    assert!(!dir.join("many.exr").exists());
    let report = crate::validator::validate_gltf_report(&[dir.join("many.glb")]);
    assert!(report.contains(": 0 errors, 0 warnings"), "{report}");
    // Its TEXCOORD_1 spans several atlases whose UV squares overlap: a rebake warns and
    // generates a new UV set instead of keeping it.
    let again = run(
        &[
            "solve",
            "many.glb",
            "--patches",
            "300",
            "--out",
            "again.glb",
            "--bake",
            "lightmap",
            "--texel-size",
            "12",
            "--lightmap-indirect",
            "16",
        ],
        &dir,
    );
    let (text, err) = (succeed(&again), stderr(&again));
    assert!(
        err.contains(&format!("spans {atlases} lightmap atlases")),
        "{err}"
    );
    assert!(!text.contains("kept"), "{text}");
}

#[test]
fn lightmap_denoise_options_are_checked() {
    let dir = scratch("lightmap-denoise-bad");
    let base = ["solve", "cornell", "--patches", "50", "--out", "x.glb"];
    for (extra, needles) in [
        (
            vec!["--lightmap-denoise"],
            vec!["--lightmap-denoise", "--bake lightmap"],
        ),
        (
            vec!["--bake", "lightmap", "--lightmap-denoise-radius", "4"],
            vec!["--lightmap-denoise-radius", "add --lightmap-denoise"],
        ),
        (
            vec![
                "--bake",
                "lightmap",
                "--lightmap-denoise",
                "--lightmap-denoise-radius",
                "0",
            ],
            vec!["--lightmap-denoise-radius 0", "at least 1"],
        ),
    ] {
        let mut args: Vec<&str> = base.to_vec();
        args.extend_from_slice(&extra);
        fails(&args, &dir, &needles, &[]);
    }
}
