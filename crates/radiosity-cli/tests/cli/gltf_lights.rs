//! `radiosity lighting` on a glTF scene lit by its own `KHR_lights_punctual` light.

use crate::common::*;
use std::path::Path;

/// A black 8 × 8 m floor at y = 0 (glTF is y-up) and a 300 cd point light 2 m above its
/// centre, as `floor.gltf` + `floor.bin`.
fn floor_scene(dir: &Path) {
    let corners: [[f32; 3]; 4] = [
        [-4.0, 0.0, -4.0],
        [4.0, 0.0, -4.0],
        [4.0, 0.0, 4.0],
        [-4.0, 0.0, 4.0],
    ];
    // Counter-clockwise seen from above (+y): the floor faces up.
    let indices: [u16; 6] = [0, 3, 2, 0, 2, 1];
    let mut bin = Vec::new();
    for c in corners {
        for v in c {
            bin.extend_from_slice(&v.to_le_bytes());
        }
    }
    for i in indices {
        bin.extend_from_slice(&i.to_le_bytes());
    }
    std::fs::write(dir.join("floor.bin"), &bin).unwrap();
    let gltf = r#"{"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0,1]}],
"nodes":[{"mesh":0},{"name":"bulb","translation":[0,2,0],"extensions":{"KHR_lights_punctual":{"light":0}}}],
"extensionsUsed":["KHR_lights_punctual"],
"extensions":{"KHR_lights_punctual":{"lights":[{"type":"point","intensity":300}]}},
"meshes":[{"primitives":[{"attributes":{"POSITION":0},"indices":1,"material":0}]}],
"materials":[{"name":"floor","pbrMetallicRoughness":{"baseColorFactor":[0,0,0,1]}}],
"buffers":[{"uri":"floor.bin","byteLength":60}],
"bufferViews":[{"buffer":0,"byteOffset":0,"byteLength":48},{"buffer":0,"byteOffset":48,"byteLength":12}],
"accessors":[{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3","min":[-4,0,-4],"max":[4,0,4]},
{"bufferView":1,"componentType":5123,"count":6,"type":"SCALAR"}]}"#;
    write(dir, "floor.gltf", gltf);
    let mut pts = String::new();
    for i in 0..5 {
        for k in 0..4 {
            pts += &format!("{} 0 {} 0 1 0\n", -2.0 + i as f64, -1.5 + k as f64);
        }
    }
    write(dir, "floor.pts", &pts);
}

/// No schedule: the file's own light, y-up without `--up`, gives E = I h / d³ exactly (a
/// black floor alone reflects nothing back to itself).
#[test]
fn a_gltf_scene_is_lit_by_its_own_lights() {
    let dir = scratch("gltf-lights");
    floor_scene(&dir);
    let out = run_ok(
        &[
            "lighting",
            "floor.gltf",
            "--grid",
            "floor.pts",
            "--out",
            "grid.csv",
            "--patches",
            "200",
        ],
        &dir,
    );
    assert!(out.contains("lights      1 from the glTF file"), "{out}");
    let (header, rows) = read_csv(&dir.join("grid.csv"));
    let e = column(&header, "illuminance");
    assert_eq!(rows.len(), 20);
    for r in &rows {
        let v: Vec<f64> = r.iter().map(|x| x.parse().unwrap()).collect();
        let d2 = v[0] * v[0] + 4.0 + v[2] * v[2];
        let want = 300.0 * 2.0 / (d2 * d2.sqrt());
        assert!((v[e] - want).abs() <= 1e-6 * want, "{} vs {want}", v[e]);
    }
    fails(
        &[
            "lighting",
            "floor.gltf",
            "--grid",
            "floor.pts",
            "--out",
            "z.csv",
            "--up",
            "z",
        ],
        &dir,
        &["--up z", "y-up"],
        &["floor.bin", "floor.pts", "floor.gltf", "grid.csv"],
    );
}

/// `render --luminaires` on a glTF scene adds the file's own lights to the schedule's: the
/// floor made grey (ρ = 0.5), its 300 cd point light 2 m above the centre and a scheduled
/// 1,000 cd isotropic luminaire at (1, 2, 0) (y-up without `--vertical`); the one pixel, at
/// the image's centre, sees the floor's centre, whose luminance is ρ E / π with
/// E = 300/2² + 1000 · 2/5^{3/2} lx (the inverse-square cosine law; a lone floor
/// interreflects nothing), to `f32` rounding; the schedule's alone would be 30 % of it.
#[test]
fn render_takes_a_gltf_scenes_own_lights() {
    let dir = scratch("render-gltf-lights");
    floor_scene(&dir);
    let gltf = std::fs::read_to_string(dir.join("floor.gltf")).unwrap();
    write(
        &dir,
        "floor.gltf",
        &gltf.replace("[0,0,0,1]", "[0.5,0.5,0.5,1]"),
    );
    let gammas: Vec<String> = (0..=36).map(|k| (5 * k).to_string()).collect();
    write(
        &dir,
        "iso.ies",
        &format!(
            "IESNA:LM-63-2002\nTILT=NONE\n1 -1 1 37 1 1 2 0 0 0\n1 1 0\n{}\n0\n{}\n",
            gammas.join(" "),
            vec!["1000"; 37].join(" ")
        ),
    );
    write(
        &dir,
        "schedule.csv",
        "name,file,x,y,z,aim_x,aim_y,aim_z,c0_x,c0_y,c0_z,multiplier,group\n\
         lamp,iso.ies,1,2,0,,,,,,,1,\n",
    );
    run_ok(
        &[
            "render",
            "floor.gltf",
            "--luminaires",
            "schedule.csv",
            "--luminance",
            "-o",
            "floor.pfm",
            "--eye",
            "0,6,0",
            "--target",
            "0,0,0",
            "--up",
            "0,0,-1",
            "--width",
            "1",
            "--height",
            "1",
            "--spp",
            "1",
            "--patches",
            "64",
        ],
        &dir,
    );
    let pixels = read_pfm_pixels(&dir.join("floor.pfm"));
    let e = 300.0 / 4.0 + 1000.0 * 2.0 / 5f64.powf(1.5);
    let want = 0.5 * e / std::f64::consts::PI;
    for c in pixels[0] {
        assert!(
            (c as f64 - want).abs() < 1e-4 * want,
            "{:?} cd/m², law {want}",
            pixels[0]
        );
    }
    // `--vertical z` contradicts glTF's y-up.
    let out = run(
        &[
            "render",
            "floor.gltf",
            "--luminaires",
            "schedule.csv",
            "--vertical",
            "z",
            "-o",
            "x.pfm",
        ],
        &dir,
    );
    let err = stderr(&out);
    assert!(
        !out.status.success() && out.status.code() != Some(101),
        "{err}"
    );
    assert!(err.contains("y-up"), "{err}");
}
