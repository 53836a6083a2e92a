//! Bad input that every command refuses alike: broken OBJ, MGF, glTF and PLY scenes, missing
//! files and impossible options, and hostile input found by mutation — one line naming the
//! file and the problem, a non-zero exit, no panic, no output file.

use crate::common::*;
use crate::validator;
use std::path::Path;

#[test]
fn bad_scenes_fail_cleanly() {
    let cases: &[(&str, &str, &str, &[&str])] = &[
        // (obj text, mtl text, expected fragments of the message)
        (
            "v 0 0 0\nv 1 0 x\n",
            "",
            "",
            &["scene.obj:2", "malformed number 'x'"],
        ),
        ("v nan 0 0\n", "", "", &["scene.obj:1", "not finite"]),
        (
            "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n",
            "",
            "",
            &["scene.obj:4", "zero area"],
        ),
        (
            "v 0 0 0\nv 1 0 0\nf 1 2\n",
            "",
            "",
            &["scene.obj:3", "at least 3"],
        ),
        (
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n",
            "",
            "",
            &["scene.obj:4", "out of range"],
        ),
        (
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
            "",
            "",
            &["scene.obj", "no light source"],
        ),
        (
            "mtllib box.mtl\n",
            "newmtl a\nKd 1.2 0.5 0.5\n",
            "",
            &["box.mtl:2", "Kd", "[0, 1)"],
        ),
        (
            "mtllib missing.mtl\n",
            "",
            "",
            &["scene.obj:1", "missing.mtl", "not found"],
        ),
        (
            "v 0 0 0\nusemtl nothing\n",
            "",
            "",
            &["scene.obj:2", "unknown material 'nothing'"],
        ),
    ];
    for (k, (obj, mtl, _, needles)) in cases.iter().enumerate() {
        let dir = scratch(&format!("bad{k}"));
        write(&dir, "scene.obj", obj);
        let mut keep = vec!["scene.obj"];
        if !mtl.is_empty() {
            write(&dir, "box.mtl", mtl);
            keep.push("box.mtl");
        }
        for args in [
            vec!["render", "scene.obj", "--out", "out.png", "--patches", "50"],
            vec!["solve", "scene.obj", "--out", "out.csv", "--patches", "50"],
        ] {
            fails(&args, &dir, needles, &keep);
        }
    }
}

#[test]
fn missing_file_and_bad_options_fail_cleanly() {
    let dir = scratch("opts");
    fails(
        &["render", "nowhere.obj", "--out", "x.png"],
        &dir,
        &["nowhere.obj"],
        &[],
    );
    fails(
        &["render", "no-such-scene"],
        &dir,
        &["no-such-scene", "cornell"],
        &[],
    );
    fails(
        &["render", "cornell", "--rays", "0", "--out", "x.png"],
        &dir,
        &["--rays 0"],
        &[],
    );
    fails(
        &["render", "cornell", "--out", "x.jpg"],
        &dir,
        &["x.jpg", "unsupported image format"],
        &[],
    );
    fails(
        &["render", "cornell", "--out", "nofolder/x.png"],
        &dir,
        &["nofolder"],
        &[],
    );
    fails(
        &["solve", "cornell", "--out", "x.txt"],
        &dir,
        &["x.txt", ".csv"],
        &[],
    );
    fails(
        &["render", "cornell", "--eye", "1,2", "--out", "x.png"],
        &dir,
        &["--eye"],
        &[],
    );
    fails(
        &["render", "cornell", "--tolerance", "1.5", "--out", "x.png"],
        &dir,
        &["--tolerance"],
        &[],
    );
}

/// Bad MGF through the CLI: one line with the file and line, a non-zero exit, no output.
#[test]
fn bad_mgf_is_refused_with_file_and_line() {
    let square = "m w =\n rd 0.5\n ed 100\nv a =\n p 0 0 0\nv b =\n p 1 0 0\nv c =\n p 1 1 0\n";
    let cases: &[(&str, &str, &[&str])] = &[
        // (scene.mgf, part.mgf, expected fragments)
        ("f a b c\n", "", &["scene.mgf:1", "undefined vertex 'a'"]),
        (
            "v a =\n p 0 0.5.1 0\n",
            "",
            &["scene.mgf:2", "malformed number '0.5.1'"],
        ),
        (
            "i missing.mgf\n",
            "",
            &["scene.mgf:1", "missing.mgf", "not found"],
        ),
        (
            "i part.mgf\n",
            "i scene.mgf\n",
            &["part.mgf:1", "include loop"],
        ),
        ("", "", &["scene.mgf:10", "at least 3"]),
    ];
    for (k, (scene, part, needles)) in cases.iter().enumerate() {
        let dir = scratch(&format!("badmgf{k}"));
        let text = if scene.is_empty() {
            format!("{square}f a b\n")
        } else {
            scene.to_string()
        };
        write(&dir, "scene.mgf", &text);
        let mut keep = vec!["scene.mgf"];
        if !part.is_empty() {
            write(&dir, "part.mgf", part);
            keep.push("part.mgf");
        }
        for (cmd, out) in [("render", "out.png"), ("solve", "out.csv")] {
            fails(&[cmd, "scene.mgf", "-o", out], &dir, needles, &keep);
        }
    }
}

/// A one-triangle glTF with its buffer in `tri.bin`: three positions (36 bytes) then the
/// given u16 indices; `mode` is the primitive mode.
fn tiny_gltf(dir: &Path, indices: &[u16], mode: u32, extra_accessor: bool) {
    let mut bin = Vec::new();
    for p in [[0f32, 0., 0.], [1., 0., 0.], [0., 0., -1.]] {
        for c in p {
            bin.extend_from_slice(&c.to_le_bytes());
        }
    }
    for i in indices {
        bin.extend_from_slice(&i.to_le_bytes());
    }
    std::fs::write(dir.join("tri.bin"), &bin).unwrap();
    let index_accessor = if extra_accessor { 7 } else { 1 };
    let json = format!(
        r#"{{"asset": {{"version": "2.0"}}, "scene": 0, "scenes": [{{"nodes": [0]}}],
        "nodes": [{{"mesh": 0}}],
        "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}, "indices": {index_accessor}, "mode": {mode}, "material": 0}}]}}],
        "materials": [{{"emissiveFactor": [1, 1, 1]}}],
        "accessors": [
          {{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, -1], "max": [1, 0, 0]}},
          {{"bufferView": 1, "componentType": 5123, "count": {n}, "type": "SCALAR"}}],
        "bufferViews": [{{"buffer": 0, "byteOffset": 0, "byteLength": 36}},
                        {{"buffer": 0, "byteOffset": 36, "byteLength": {len}}}],
        "buffers": [{{"uri": "tri.bin", "byteLength": {total}}}]}}"#,
        n = indices.len(),
        len = indices.len() * 2,
        total = bin.len()
    );
    write(dir, "tri.gltf", &json);
}

/// The glTF that `bad_gltf_and_ply_fail_cleanly` breaks is a scene as it stands.
#[test]
fn tiny_gltf_is_a_valid_scene() {
    let dir = scratch("tiny-gltf");
    tiny_gltf(&dir, &[0, 1, 2], 4, false);
    let text = run_ok(
        &["solve", "tri.gltf", "--patches", "50", "-o", "out.csv"],
        &dir,
    );
    assert!(text.contains("(1 polygons)"), "{text}");
}

/// An ASCII PLY triangle whose header declares `vertices` vertices and one face with an
/// emission, followed by `body`.
fn ascii_ply(vertices: usize, body: &str) -> String {
    format!(
        "ply\nformat ascii 1.0\nelement vertex {vertices}\nproperty float x\nproperty float y\nproperty float z\n\
         element face 1\nproperty list uchar int vertex_indices\nproperty float emission\nend_header\n{body}"
    )
}

#[test]
#[ignore = "needs Node and the glTF validator that .ci/run installs (run with --include-ignored, as .ci/run does)"]
fn bad_gltf_and_ply_fail_cleanly() {
    // (setup, scene file, files it leaves, expected fragments)
    type Setup = fn(&Path);
    let cases: &[(Setup, &str, &[&str], &[&str])] = &[
        (
            |d| tiny_gltf(d, &[0, 1, 5], 4, false),
            "tri.gltf",
            &["tri.gltf", "tri.bin"],
            &["tri.gltf", "index 5", "out of range"],
        ),
        (
            |d| tiny_gltf(d, &[0, 1, 2], 1, false),
            "tri.gltf",
            &["tri.gltf", "tri.bin"],
            &["tri.gltf", "mode LINES", "not supported"],
        ),
        (
            |d| tiny_gltf(d, &[0, 1, 2], 4, true),
            "tri.gltf",
            &["tri.gltf", "tri.bin"],
            &["tri.gltf", "indices", "Index out of bounds"],
        ),
        (
            |d| {
                tiny_gltf(d, &[0, 1, 2], 4, false);
                std::fs::remove_file(d.join("tri.bin")).unwrap();
            },
            "tri.gltf",
            &["tri.gltf"],
            &["tri.gltf", "tri.bin", "cannot read"],
        ),
        (
            |d| {
                // A real .glb cut short.
                run_ok(
                    &["solve", "cornell", "--patches", "100", "-o", "whole.glb"],
                    d,
                );
                validator::validate_gltf(&[d.join("whole.glb")]);
                let bytes = read_bytes(d, "whole.glb");
                std::fs::write(d.join("cut.glb"), &bytes[..bytes.len() / 2]).unwrap();
                std::fs::remove_file(d.join("whole.glb")).unwrap();
            },
            "cut.glb",
            &["cut.glb"],
            &["cut.glb", "truncated GLB"],
        ),
        (
            |d| {
                write(
                    d,
                    "lie.ply",
                    &ascii_ply(4, "0 0 0\n1 0 0\n0 0 -1\n3 0 1 2 1\n"),
                );
            },
            "lie.ply",
            &["lie.ply"],
            &["lie.ply:14", "element counts (4 vertex, 1 face)"],
        ),
        (
            |d| {
                write(
                    d,
                    "lie.ply",
                    &ascii_ply(2, "0 0 0\n1 0 0\n0 0 -1\n3 0 1 2 1\n"),
                );
            },
            "lie.ply",
            &["lie.ply"],
            &["lie.ply:", "element counts (2 vertex, 1 face)"],
        ),
        (
            |d| {
                write(
                    d,
                    "idx.ply",
                    &ascii_ply(3, "0 0 0\n1 0 0\n0 0 -1\n3 0 1 7 1\n"),
                );
            },
            "idx.ply",
            &["idx.ply"],
            &["idx.ply:14", "index 7 is out of range"],
        ),
        (
            |d| {
                let mut ply = b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n".to_vec();
                for c in [0f32, 0., 0., 1., 0., 0.] {
                    ply.extend_from_slice(&c.to_le_bytes());
                }
                std::fs::write(d.join("short.ply"), ply).unwrap();
            },
            "short.ply",
            &["short.ply"],
            &["short.ply", "ends in vertex 2", "declares 3 vertex"],
        ),
    ];
    for (k, (setup, scene, keep, needles)) in cases.iter().enumerate() {
        let dir = scratch(&format!("badmesh{k}"));
        setup(&dir);
        for (cmd, out) in [
            ("render", "out.png"),
            ("solve", "out.glb"),
            ("solve", "out.ply"),
        ] {
            fails(&[cmd, scene, "-o", out], &dir, needles, keep);
        }
    }
}

/// Each class of hostile input found by mutating files and options: a one-line located error,
/// a non-zero exit, no panic or signal, no output, within seconds (a hang or an abort on
/// allocation fails the test, which runs them all in a few seconds).
#[test]
fn hostile_inputs_get_one_line_errors_quickly() {
    let dir = scratch("hostile");
    for f in ["room.gltf", "room.bin", "checker.png"] {
        std::fs::copy(test_scene(f), dir.join(f)).unwrap();
    }
    let room = read(&dir, "room.gltf");
    let mut json: serde_json::Value = serde_json::from_str(&room).unwrap();
    // glTF that the dependency's own validation lets through and then panicked on.
    let gltf_case = |name: &str, edit: &dyn Fn(&mut serde_json::Value)| {
        let mut j = json.clone();
        edit(&mut j);
        write(&dir, name, &j.to_string());
    };
    gltf_case("attr.gltf", &|j| {
        j["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = 999.into()
    });
    gltf_case("camera.gltf", &|j| {
        j["cameras"] = serde_json::json!([{ "type": "orthographic" }]);
    });
    gltf_case("image.gltf", &|j| {
        j["images"] = serde_json::json!([{}]);
    });
    json["buffers"][0]["uri"] = "/dev/zero".into();
    write(&dir, "zero.gltf", &json.to_string());
    // MGF: a chain of 200 includes, a huge transform array, arrays nested to 10⁹ statements.
    for k in 0..200 {
        write(
            &dir,
            &format!("inc{k}.mgf"),
            &format!("i inc{}.mgf\n", k + 1),
        );
    }
    write(&dir, "inc200.mgf", "v a =\np 0 0 0\n");
    write(
        &dir,
        "array.mgf",
        "xf -a 4000000000 -t 1 0 0\nv a =\np 0 0 0\nxf\n",
    );
    write(
        &dir,
        "nested.mgf",
        "xf -a 1000 -t 1 0 0\nxf -a 1000 -t 0 1 0\nxf -a 1000 -t 0 0 1\nv a =\np 0 0 0\nxf\nxf\nxf\n",
    );
    // OBJ: one polygon of 20,000 vertices; a face repeating its indices 10⁵ times; a material
    // library that is a device; a face with a repeated vertex (zero area once meshed); a
    // megabyte-long token.
    let mut big = String::from("mtllib l.mtl\nusemtl light\n");
    for k in 0..20_000 {
        let t = k as f64 / 20_000.0 * std::f64::consts::TAU;
        big += &format!("v {} {} 0\n", t.cos(), t.sin());
    }
    big += "f";
    for k in 1..=20_000 {
        big += &format!(" {k}");
    }
    write(&dir, "big.obj", &(big + "\n"));
    write(&dir, "l.mtl", "newmtl light\nKd 0.5 0.5 0.5\nKe 1 1 1\n");
    let tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
    write(
        &dir,
        "repeat.obj",
        &format!("{tri}f{}\n", " 1 2 3".repeat(100_000)),
    );
    write(
        &dir,
        "zero.obj",
        &format!("mtllib /dev/zero\n{tri}f 1 2 3\n"),
    );
    write(
        &dir,
        "long.obj",
        &format!("v 0 0 {}\n", "9".repeat(1 << 19) + "x"),
    );
    write(
        &dir,
        "longline.obj",
        &format!("# {}\n", "y".repeat(2 << 20)),
    );
    // Matrix Market whose size line promises more than the file holds.
    write(
        &dir,
        "rows.mtx",
        "%%MatrixMarket matrix coordinate real general\n4000000000 4000000000 1\n1 1 0.5\n",
    );
    write(
        &dir,
        "entries.mtx",
        "%%MatrixMarket matrix coordinate real general\n1 1 4000000000\n1 1 0.5\n",
    );
    write(&dir, "p.csv", "area,reflectance,emission\n1,0.5,1\n");
    let keep: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    let keep: Vec<&str> = keep.iter().map(String::as_str).collect();
    let solve = |scene: &str| {
        vec!["solve", scene, "--patches", "200", "-o", "out.csv"]
            .into_iter()
            .map(String::from)
            .collect::<Vec<_>>()
    };
    let args = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
    let cases: Vec<(Vec<String>, Vec<&str>)> = vec![
        (solve("attr.gltf"), vec!["attr.gltf", "no accessor 999"]),
        (solve("camera.gltf"), vec!["camera.gltf", "cameras[0]"]),
        (solve("image.gltf"), vec!["image.gltf", "images[0]"]),
        (solve("zero.gltf"), vec!["/dev/zero", "not a regular file"]),
        (solve("inc0.mgf"), vec!["includes nest deeper than 64"]),
        (solve("array.mgf"), vec!["array.mgf:1", "transform"]),
        (
            solve("nested.mgf"),
            vec!["nested.mgf:2", "transform arrays would make 1001000 copies"],
        ),
        (solve("big.obj"), vec!["big.obj:20003", "at most 4096"]),
        (solve("repeat.obj"), vec!["repeat.obj:4", "at most 4096"]),
        (solve("zero.obj"), vec!["zero.obj:1", "not a regular file"]),
        (solve("long.obj"), vec!["long.obj:1", "…"]),
        (
            solve("longline.obj"),
            vec!["longline.obj:1", "longer than 1 MiB"],
        ),
        (
            args(&["solve", "cornell", "--max-edge", "0.00001", "-o", "out.csv"]),
            vec!["patches would need", "--max-edge"],
        ),
        (
            args(&[
                "solve",
                "cornell",
                "--patches",
                "1000000000000",
                "-o",
                "out.csv",
            ]),
            vec!["1000000000000 patches would need"],
        ),
        (
            args(&[
                "form-factors",
                "cornell",
                "--method",
                "hemicube",
                "--max-edge",
                "0.01",
                "-o",
                "F.mtx",
            ]),
            vec!["patches with every form-factor row stored", "--faces"],
        ),
        (
            args(&["render", "cornell", "--width", "100000", "-o", "out.png"]),
            vec!["--width 100000", "at most 32768"],
        ),
        (
            args(&["render", "cornell", "--threads", "100000", "-o", "out.png"]),
            vec!["--threads 100000", "at most"],
        ),
        (
            args(&[
                "solve",
                "cornell",
                "--solver",
                "gauss",
                "--patches",
                "60000",
                "-o",
                "out.csv",
            ]),
            vec!["gauss on", "iterative solver"],
        ),
        (
            args(&[
                "solve-system",
                "--matrix",
                "rows.mtx",
                "--patches",
                "p.csv",
                "-o",
                "out.csv",
            ]),
            vec!["rows.mtx:2", "4000000000 rows"],
        ),
        (
            args(&[
                "solve-system",
                "--matrix",
                "entries.mtx",
                "--patches",
                "p.csv",
                "-o",
                "out.csv",
            ]),
            vec!["entries.mtx:2", "4000000000 entries"],
        ),
    ];
    for (args, needles) in cases {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let t = std::time::Instant::now();
        let out = run(&args, &dir);
        let err = stderr(&out);
        assert!(
            t.elapsed().as_secs_f64() < 10.0,
            "{args:?} took {:?}",
            t.elapsed()
        );
        assert!(
            err.lines().all(|l| l.chars().count() <= 600),
            "{args:?}: a long line: {} characters",
            err.len()
        );
        assert_fails(&out, &needles, &dir, &keep);
    }
}

/// More hostile-input classes: a face whose repeated vertex makes a zero-area patch is named
/// by its file and line; a missing file gives the operating system's message once; the
/// summary reports resident memory first.
#[test]
fn located_errors_os_messages_once_and_resident_memory() {
    let dir = scratch("hostile2");
    write(&dir, "l.mtl", "newmtl light\nKd 0.5 0.5 0.5\nKe 1 1 1\n");
    write(
        &dir,
        "deg.obj",
        "mtllib l.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nusemtl light\nf 1 2 4 3\nf 1 2 2 3\n",
    );
    fails(
        &["solve", "deg.obj", "--patches", "100", "-o", "x.csv"],
        &dir,
        &["deg.obj:8", "area 0"],
        &["l.mtl", "deg.obj"],
    );
    let out = run(&["solve", "missing.obj", "-o", "x.csv"], &dir);
    let err = stderr(&out);
    assert_eq!(err.matches("No such file or directory").count(), 1, "{err}");
    assert!(err.contains("cannot read missing.obj"), "{err}");
    let out = run(
        &["solve", "furnace", "--patches", "50", "-o", "x.csv"],
        &dir,
    );
    let text = stdout(&out);
    assert!(text.contains("memory      peak resident"), "{text}");
}

/// A two-sided plate at 300 K for the thermal cases: `p.obj`, `p.mtl`, `bc.csv`.
fn thermal_plate(dir: &Path) -> [&'static str; 3] {
    write(
        dir,
        "p.obj",
        "mtllib p.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nusemtl plate\nf 1 2 3 4\nusemtl back\nf 4 3 2 1\n",
    );
    write(
        dir,
        "p.mtl",
        "newmtl plate\nKd 0.3 0.3 0.3\nnewmtl back\nKd 0.3 0.3 0.3\n",
    );
    write(
        dir,
        "bc.csv",
        "name,emissivity,temperature,flux\nplate,0.5,300,\nback,0.5,300,\n",
    );
    ["p.obj", "p.mtl", "bc.csv"]
}

/// The inputs of a case, byte for byte, to check that a refusal left them alone.
fn snapshot(dir: &Path, names: &[&str]) -> Vec<Vec<u8>> {
    names.iter().map(|n| read_bytes(dir, n)).collect()
}

/// No output is written over an input of its command or over another of its outputs, however
/// the path is spelt (`./`, a folder and back, a symbolic link).
#[test]
fn outputs_never_overwrite_inputs_or_each_other() {
    let dir = scratch("hostile-same-file");
    let mut keep = thermal_plate(&dir).to_vec();
    std::os::unix::fs::symlink("bc.csv", dir.join("link.csv")).unwrap();
    keep.push("link.csv");
    std::fs::create_dir(dir.join("sub")).unwrap();
    keep.push("sub");
    let t = ["thermal", "p.obj", "--boundary", "bc.csv"];
    let cases: Vec<(Vec<&str>, Vec<&str>)> = vec![
        (
            vec!["--out", "bc.csv"],
            vec!["--out bc.csv", "--boundary bc.csv"],
        ),
        (
            vec!["--out", "s.csv", "--patches-out", "./bc.csv"],
            vec!["--patches-out ./bc.csv", "--boundary bc.csv"],
        ),
        (
            vec!["--out", "sub/../bc.csv"],
            vec!["--out sub/../bc.csv", "--boundary bc.csv"],
        ),
        (
            vec!["--out", "link.csv"],
            vec!["--out link.csv", "--boundary bc.csv"],
        ),
        (
            vec!["--out", "s.csv", "--patches-out", "./s.csv"],
            vec!["--patches-out ./s.csv", "--out s.csv", "own file"],
        ),
        (
            vec!["--out", "s.csv", "--mrt-out", "s.csv", "--grid", "bc.csv"],
            vec!["--mrt-out s.csv", "--out s.csv"],
        ),
        (
            vec!["--out", "s.csv", "--mrt-out", "bc.csv", "--grid", "bc.csv"],
            vec!["--mrt-out bc.csv", "--boundary bc.csv"],
        ),
    ];
    let before = snapshot(&dir, &["p.obj", "p.mtl", "bc.csv"]);
    for (extra, needles) in cases {
        let mut args = t.to_vec();
        args.extend(extra);
        fails(&args, &dir, &needles, &keep);
        assert_eq!(snapshot(&dir, &["p.obj", "p.mtl", "bc.csv"]), before);
    }
    // solve-system: --out or --trace over its matrix or patch file.
    write(
        &dir,
        "p2.csv",
        "patch,area,reflectance,emission\n0,1,0.5,1\n",
    );
    write(
        &dir,
        "m.mtx",
        "%%MatrixMarket matrix coordinate real general\n1 1 0\n",
    );
    keep.extend(["p2.csv", "m.mtx"]);
    let before = snapshot(&dir, &["p2.csv", "m.mtx"]);
    for (extra, needles) in [
        (
            &["-o", "./p2.csv"][..],
            &["--out ./p2.csv", "--patches p2.csv"][..],
        ),
        (
            &["-o", "r.csv", "--solver", "jacobi", "--trace", "m.mtx"],
            &["--trace m.mtx", "--matrix m.mtx"],
        ),
    ] {
        let mut args = vec!["solve-system", "--matrix", "m.mtx", "--patches", "p2.csv"];
        args.extend_from_slice(extra);
        fails(&args, &dir, needles, &keep);
        assert_eq!(snapshot(&dir, &["p2.csv", "m.mtx"]), before);
    }
    // solve and render: the output over the scene, or the trace over the output.
    write(
        &dir,
        "x.ply",
        &ascii_ply(3, "0 0 0\n1 0 0\n0 1 0\n3 0 1 2 1\n"),
    );
    keep.push("x.ply");
    let scene = read_bytes(&dir, "x.ply");
    fails(
        &["solve", "x.ply", "--out", "x.ply"],
        &dir,
        &["--out x.ply", "scene x.ply"],
        &keep,
    );
    fails(
        &[
            "solve", "x.ply", "--out", "o.csv", "--solver", "jacobi", "--trace", "./o.csv",
        ],
        &dir,
        &["--trace ./o.csv", "--out o.csv"],
        &keep,
    );
    assert_eq!(read_bytes(&dir, "x.ply"), scene);
}

/// Every output of a command is written or none is: thermal's `--out` is not kept when its
/// `--patches-out` cannot be written (a symbolic link to nothing).
#[test]
fn thermal_writes_every_output_or_none() {
    let dir = scratch("hostile-staged");
    let mut keep = thermal_plate(&dir).to_vec();
    std::os::unix::fs::symlink("nowhere/x.csv", dir.join("dangling.csv")).unwrap();
    keep.push("dangling.csv");
    let before = snapshot(&dir, &["p.obj", "p.mtl", "bc.csv"]);
    fails(
        &[
            "thermal",
            "p.obj",
            "--boundary",
            "bc.csv",
            "--out",
            "s.csv",
            "--patches-out",
            "dangling.csv",
        ],
        &dir,
        &["dangling.csv"],
        &keep,
    );
    assert_eq!(snapshot(&dir, &["p.obj", "p.mtl", "bc.csv"]), before);
    // Both land when both can: the patch rows add up to the surfaces' powers.
    run_ok(
        &[
            "thermal",
            "p.obj",
            "--boundary",
            "bc.csv",
            "--out",
            "s.csv",
            "--patches-out",
            "q.csv",
        ],
        &dir,
    );
    assert!(dir.join("s.csv").is_file() && dir.join("q.csv").is_file());
}

/// Inputs whose σT⁴ would overflow are refused with the range that works, before any work.
#[test]
fn thermal_refuses_temperatures_and_fluxes_that_overflow() {
    let dir = scratch("hostile-overflow");
    let mut keep = thermal_plate(&dir).to_vec();
    keep.push("bc2.csv");
    fails(
        &[
            "thermal",
            "p.obj",
            "--boundary",
            "bc.csv",
            "--out",
            "s.csv",
            "--environment",
            "1e78",
        ],
        &dir,
        &["--environment 1e78", "0 to 1e6"],
        &keep,
    );
    for (row, needles) in [
        (
            "plate,0.5,1e100,",
            &["bc2.csv:2", "1e100 K", "0 to 1e6 K"][..],
        ),
        ("plate,0.5,,-1e308", &["bc2.csv:2", "-1e308", "1e17"]),
    ] {
        write(
            &dir,
            "bc2.csv",
            &format!("name,emissivity,temperature,flux\n{row}\nback,0.5,300,\n"),
        );
        fails(
            &[
                "thermal",
                "p.obj",
                "--boundary",
                "bc2.csv",
                "--out",
                "s.csv",
            ],
            &dir,
            needles,
            &keep,
        );
    }
    // The top of the range still solves, finitely: the plate at 10⁶ K facing nothing loses
    // ε σ T⁴ per square metre and side to surroundings at 0 K.
    write(
        &dir,
        "bc2.csv",
        "name,emissivity,temperature,flux\nplate,0.5,1e6,\nback,0.5,1e6,\n",
    );
    run_ok(
        &[
            "thermal",
            "p.obj",
            "--boundary",
            "bc2.csv",
            "--out",
            "s.csv",
        ],
        &dir,
    );
    let (header, rows) = read_csv(&dir.join("s.csv"));
    let flux = column(&header, "flux");
    let expected = 0.5 * 5.670_374_419e-8 * 1e24;
    for r in &rows {
        let q: f64 = r[flux].parse().unwrap();
        assert!((q - expected).abs() < 1e-9 * expected, "{q} vs {expected}");
    }
}

/// Absurd requests are refused before the work: a hierarchical link error below what f32
/// geometry can resolve, an MGF array of 10⁵ copies; an include of a device names the file
/// and line that include it.
#[test]
fn absurd_requests_are_refused_quickly() {
    let dir = scratch("hostile-absurd");
    write(
        &dir,
        "arr.mgf",
        "m light =\n c\n ed 10\nv a =\n p 0 0 1\n n 0 0 -1\nv b =\n p 1 0 1\n n 0 0 -1\nv c =\n p 0 1 1\n n 0 0 -1\nxf -a 100000\nf a b c\nxf\n",
    );
    write(&dir, "dev.mgf", "# a device\ni /dev/zero\n");
    let keep = ["arr.mgf", "dev.mgf"];
    for (args, needles) in [
        (
            &[
                "solve",
                "cornell",
                "--solver",
                "hierarchical",
                "--link-error",
                "1e-9",
                "-o",
                "a.csv",
            ][..],
            &["--link-error", "1e-7"][..],
        ),
        (
            &["solve", "arr.mgf", "-o", "a.csv"],
            &["arr.mgf:13", "100000 copies", "10000"],
        ),
        (
            &["solve", "dev.mgf", "-o", "a.csv"],
            &["dev.mgf:2", "/dev/zero", "not a regular file"],
        ),
    ] {
        let t = std::time::Instant::now();
        fails(args, &dir, needles, &keep);
        assert!(
            t.elapsed().as_secs_f64() < 10.0,
            "{args:?} took {:?}",
            t.elapsed()
        );
    }
}
