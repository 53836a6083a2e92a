//! `radiosity view`: pictures of a baked glTF without solving again, by its vertex colours or
//! by a final gather over its stored radiosity; scenes that carry no solution are refused.

use crate::common::*;
use crate::render::assert_furnace_picture;
use crate::validator;

#[test]
#[ignore = "needs Node and the glTF validator that .ci/run installs (run with --include-ignored, as .ci/run does)"]
fn view_shows_a_baked_gltf_without_solving() {
    let dir = scratch("view");
    run_ok(
        &["solve", "cornell", "--patches", "800", "-o", "baked.glb"],
        &dir,
    );
    let text = run_ok(
        &[
            "view",
            "baked.glb",
            "--width",
            "96",
            "--height",
            "96",
            "-o",
            "shot.png",
        ],
        &dir,
    );
    assert!(text.contains("triangles shown"), "{text}");
    validator::validate_gltf(&[dir.join("baked.glb")]);
    let img = image::open(dir.join("shot.png")).unwrap().to_rgb8();
    // Seen through the open side, from the camera stored in the file: the box fills the view,
    // and the light, far brighter than the walls, is clipped to white.
    assert!(lit_fraction(&dir.join("shot.png")) > 0.9);
    assert!(img.pixels().any(|p| p.0 == [255, 255, 255]));
    // A glTF without vertex colours, and a PLY, are refused.
    let room = test_scene("room.gltf");
    fails(
        &["view", room.to_str().unwrap(), "-o", "room.png"],
        &dir,
        &["room.gltf", "no COLOR_0"],
        &["baked.glb", "shot.png"],
    );
    let ply = test_scene("room.ply");
    fails(
        &["view", ply.to_str().unwrap(), "-o", "room.png"],
        &dir,
        &["room.ply", ".glb or .gltf"],
        &["baked.glb", "shot.png"],
    );
}

/// The gather reads a baked glTF's `_RADIOSITY` and materials: the furnace baked, then viewed
/// with `--gather`, is E/(π(1 − ρ)) everywhere (mean within 1 % and 4 standard errors).
#[test]
fn gather_over_a_baked_gltf() {
    let dir = scratch("baked-gather");
    run_ok(
        &[
            "solve",
            "furnace",
            "--tolerance",
            "0.0001",
            "--out",
            "f.glb",
        ],
        &dir,
    );
    run_ok(
        &[
            "view", "f.glb", "--gather", "--width", "24", "--height", "24", "--spp", "4", "-o",
            "f.pfm",
        ],
        &dir,
    );
    assert_furnace_picture(&dir.join("f.pfm"), 1e-4, "baked furnace, gathered");
}
