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
