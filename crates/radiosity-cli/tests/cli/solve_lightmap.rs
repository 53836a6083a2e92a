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
