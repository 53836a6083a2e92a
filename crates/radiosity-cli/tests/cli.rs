//! The `radiosity` command as a user runs it: outputs, and bad input that must fail with one
//! line naming the file and the problem, a non-zero exit, and no output file.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

#[path = "../../radiosity/tests/validator.rs"]
mod validator;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_radiosity"))
}

/// A fresh scratch folder for one test.
fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("radiosity-cli-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn run(args: &[&str], dir: &Path) -> Output {
    bin().args(args).current_dir(dir).output().unwrap()
}

/// Assert a failure: non-zero exit, exactly one line on stderr containing every `needles`,
/// no panic, and no file left in `dir` besides `keep`.
fn assert_fails(out: &Output, needles: &[&str], dir: &Path, keep: &[&str]) {
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "succeeded: {err}");
    assert_ne!(out.status.code(), Some(101), "panicked: {err}");
    let lines: Vec<&str> = err.lines().filter(|l| !l.contains("warning:")).collect();
    assert_eq!(lines.len(), 1, "expected one line, got: {err}");
    for n in needles {
        assert!(lines[0].contains(n), "'{}' lacks '{n}'", lines[0]);
    }
    let left: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| !keep.contains(&n.as_str()))
        .collect();
    assert!(left.is_empty(), "files left behind: {left:?}");
}

fn write(dir: &Path, name: &str, text: &str) {
    std::fs::write(dir.join(name), text).unwrap();
}

/// A lit box as OBJ: floor, ceiling light, one wall.
const GOOD_OBJ: &str = "mtllib box.mtl\nv 0 0 0\nv 1 0 0\nv 1 0 1\nv 0 0 1\nv 0 1 0\nv 1 1 0\nv 1 1 1\nv 0 1 1\nusemtl white\nf 1 4 3 2\nf 1 2 6 5\nusemtl lamp\nf 5 6 7 8\n";
const GOOD_MTL: &str = "newmtl white\nKd 0.7 0.7 0.7\nnewmtl lamp\nKd 0.5 0.5 0.5\nKe 10 10 10\n";

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
            let out = run(&args, &dir);
            assert_fails(&out, needles, &dir, &keep);
        }
    }
}

#[test]
fn missing_file_and_bad_options_fail_cleanly() {
    let dir = scratch("opts");
    let out = run(&["render", "nowhere.obj", "--out", "x.png"], &dir);
    assert_fails(&out, &["nowhere.obj"], &dir, &[]);
    let out = run(&["render", "no-such-scene"], &dir);
    assert_fails(&out, &["no-such-scene", "cornell"], &dir, &[]);
    let out = run(
        &["render", "cornell", "--rays", "0", "--out", "x.png"],
        &dir,
    );
    assert_fails(&out, &["--rays 0"], &dir, &[]);
    let out = run(&["render", "cornell", "--out", "x.jpg"], &dir);
    assert_fails(&out, &["x.jpg", "unsupported image format"], &dir, &[]);
    let out = run(&["render", "cornell", "--out", "nofolder/x.png"], &dir);
    assert_fails(&out, &["nofolder"], &dir, &[]);
    let out = run(&["solve", "cornell", "--out", "x.txt"], &dir);
    assert_fails(&out, &["x.txt", ".csv"], &dir, &[]);
    let out = run(
        &["render", "cornell", "--eye", "1,2", "--out", "x.png"],
        &dir,
    );
    assert_fails(&out, &["--eye"], &dir, &[]);
    let out = run(
        &["render", "cornell", "--tolerance", "1.5", "--out", "x.png"],
        &dir,
    );
    assert_fails(&out, &["--tolerance"], &dir, &[]);
}

#[test]
fn solve_writes_the_documented_csv() {
    let dir = scratch("csv");
    let out = run(
        &[
            "solve",
            "furnace",
            "--patches",
            "150",
            "--rays",
            "512",
            "--tolerance",
            "1e-6",
            "--out",
            "f.csv",
        ],
        &dir,
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(dir.join("f.csv")).unwrap();
    let mut lines = text.lines();
    assert_eq!(
        lines.next().unwrap(),
        "patch,surface,area,cx,cy,cz,nx,ny,nz,reflectance_r,reflectance_g,reflectance_b,emission_r,emission_g,emission_b,radiosity_r,radiosity_g,radiosity_b"
    );
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    assert!(rows.len() > 100);
    let (mut area, mut weighted) = (0.0, 0.0);
    for (k, r) in rows.iter().enumerate() {
        assert_eq!(r.len(), 18);
        assert_eq!(r[0] as usize, k);
        area += r[2];
        weighted += r[2] * r[16];
    }
    // Furnace, green channel: ρ = 0.5, E = 1, so the area-weighted mean radiosity is 2.
    assert!((weighted / area - 2.0).abs() < 1e-4, "{}", weighted / area);
    // Surface area of the 1 m box plus the inner block.
    assert!((area - (6.0 + 2.0 * (0.4 * 0.35 + 0.35 * 0.3 + 0.4 * 0.3))).abs() < 1e-4);
}

#[test]
fn solve_output_does_not_depend_on_threads() {
    let dir = scratch("threads");
    for t in ["1", "2"] {
        let out = run(
            &[
                "solve",
                "cornell",
                "--patches",
                "600",
                "--threads",
                t,
                "--out",
                &format!("t{t}.csv"),
            ],
            &dir,
        );
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    let a = std::fs::read(dir.join("t1.csv")).unwrap();
    let b = std::fs::read(dir.join("t2.csv")).unwrap();
    assert!(a == b, "CSV differs between --threads 1 and --threads 2");
}

#[test]
fn render_writes_png_exr_and_pfm() {
    let dir = scratch("render");
    let out = run(
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
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
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
        let out = run(
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
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    let pfm = std::fs::read(dir.join("c.pfm")).unwrap();
    assert!(pfm.starts_with(b"PF\n32 24\n-1.0\n"));
    assert_eq!(pfm.len(), b"PF\n32 24\n-1.0\n".len() + 32 * 24 * 12);
    let exr = std::fs::read(dir.join("c.exr")).unwrap();
    assert_eq!(&exr[..4], &[0x76, 0x2f, 0x31, 0x01], "not an OpenEXR file");
}

#[test]
fn obj_scene_renders_with_camera_flags() {
    let dir = scratch("obj");
    write(&dir, "box.obj", GOOD_OBJ);
    write(&dir, "box.mtl", GOOD_MTL);
    let out = run(
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
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let img = image::open(dir.join("box.png")).unwrap().to_rgb8();
    assert!(img.pixels().any(|p| p[0] > 0), "the picture is black");
}

/// A 3-patch system: equal areas, symmetric F with row sums 0.9, 0.8, 0.7.
const MTX: &str = "%%MatrixMarket matrix coordinate real general\n% three patches\n3 3 6\n1 2 0.5\n1 3 0.4\n2 1 0.5\n2 3 0.3\n3 1 0.4\n3 2 0.3\n";
const PATCHES: &str = "patch,area,reflectance,emission\n0,1,0.5,1\n1,1,0.8,0\n2,1,0.3,0\n";

/// B of the 3-patch system, by Cramer's rule on (I − diag(ρ) F) B = E.
fn three_patch_exact() -> [f64; 3] {
    let f = [[0.0, 0.5, 0.4], [0.5, 0.0, 0.3], [0.4, 0.3, 0.0]];
    let rho = [0.5, 0.8, 0.3];
    let e = [1.0, 0.0, 0.0];
    let m: Vec<Vec<f64>> = (0..3)
        .map(|i| {
            (0..3)
                .map(|j| (i == j) as u8 as f64 - rho[i] * (f[i][j] as f32 as f64))
                .collect()
        })
        .collect();
    let det = |m: &Vec<Vec<f64>>| {
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    };
    let d = det(&m);
    let mut out = [0.0; 3];
    for k in 0..3 {
        let mut mk = m.clone();
        for i in 0..3 {
            mk[i][k] = e[i];
        }
        out[k] = det(&mk) / d;
    }
    out
}

#[test]
fn solve_system_solves_and_traces() {
    let dir = scratch("system");
    write(&dir, "F.mtx", MTX);
    write(&dir, "patches.csv", PATCHES);
    let exact = three_patch_exact();
    for solver in [
        "gauss",
        "jacobi",
        "gauss-seidel-0",
        "gauss-seidel",
        "gauss-seidel-jacobi",
        "sor",
        "southwell",
        "progressive",
        "overshoot-ambient",
        "overshoot",
    ] {
        let out = run(
            &[
                "solve-system",
                "--form-factors",
                "F.mtx",
                "--patches",
                "patches.csv",
                "--solver",
                solver,
                "--tolerance",
                "1e-12",
                "--out",
                "B.csv",
                "--trace",
                "trace.csv",
            ],
            &dir,
        );
        assert!(
            out.status.success(),
            "{solver}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let b = std::fs::read_to_string(dir.join("B.csv")).unwrap();
        let mut lines = b.lines();
        assert_eq!(lines.next(), Some("radiosity"));
        let values: Vec<f64> = lines.map(|l| l.parse().unwrap()).collect();
        assert_eq!(values.len(), 3);
        for k in 0..3 {
            assert!(
                (values[k] - exact[k]).abs() < 1e-6 * exact[k].max(1.0),
                "{solver}: {values:?} vs {exact:?}"
            );
        }
        let trace = std::fs::read_to_string(dir.join("trace.csv")).unwrap();
        let mut rows = trace.lines();
        assert_eq!(rows.next(), Some("iteration,seconds,error,unshot"));
        let rows: Vec<Vec<&str>> = rows.map(|r| r.split(',').collect()).collect();
        assert!(!rows.is_empty());
        let last = rows.last().unwrap();
        let error: f64 = last[2].parse().unwrap();
        let unshot: f64 = last[3].parse().unwrap();
        assert!(
            error.abs() < 1e-6 && unshot <= 1e-12,
            "{solver}: last trace row {last:?}"
        );
        // Iterations count up from 0.
        assert_eq!(rows[0][0], "0");
    }
    // Stochastic: within its statistical error.
    let out = run(
        &[
            "solve-system",
            "--form-factors",
            "F.mtx",
            "--patches",
            "patches.csv",
            "--solver",
            "stochastic",
            "--photons",
            "20000",
            "--tolerance",
            "1e-3",
            "--out",
            "B.csv",
        ],
        &dir,
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let b = std::fs::read_to_string(dir.join("B.csv")).unwrap();
    let values: Vec<f64> = b.lines().skip(1).map(|l| l.parse().unwrap()).collect();
    for k in 0..3 {
        assert!(
            (values[k] - exact[k]).abs() < 0.03 * exact[k] + 1e-3,
            "stochastic: {values:?} vs {exact:?}"
        );
    }
}

#[test]
fn solve_system_rejects_bad_input() {
    let cases: &[(&str, &str, &[&str])] = &[
        (
            MTX,
            "area,reflectance,emission\n1,0.5,1\n1,1.0,0\n1,0.3,0\n",
            &["patches.csv:3", "reflectance"],
        ),
        (
            MTX,
            "area,reflectance,emission\n1,0.5,1\n1,NaN,0\n1,0.3,0\n",
            &["patches.csv:3", "not finite"],
        ),
        (
            MTX,
            "area,reflectance,emission\n1,0.5,1\n1,0.5,0\n",
            &["patches.csv", "2 patches", "F.mtx"],
        ),
        (
            MTX,
            "area,rho,emission\n1,0.5,1\n",
            &["patches.csv:1", "reflectance"],
        ),
        (
            "%%MatrixMarket matrix coordinate real general\n3 3 1\n1 2 -0.5\n",
            PATCHES,
            &["F.mtx:3", "negative"],
        ),
        (
            "%%MatrixMarket matrix coordinate real general\n3 3 1\n1 2 nan\n",
            PATCHES,
            &["F.mtx:3", "not finite"],
        ),
        (
            "%%MatrixMarket matrix coordinate real general\n3 4 1\n1 2 0.5\n",
            PATCHES,
            &["F.mtx:2", "square"],
        ),
        (
            "%%MatrixMarket matrix coordinate real general\n3 3 2\n1 2 0.7\n1 3 0.6\n",
            PATCHES,
            &["F.mtx", "row 1", "1 + 1e-3"],
        ),
        (
            "%%MatrixMarket matrix coordinate real general\n3 3 1\n1 5 0.5\n",
            PATCHES,
            &["F.mtx:3", "out of range"],
        ),
        (
            "%%MatrixMarket matrix coordinate real general\n3 3 2\n1 2 0.5\n",
            PATCHES,
            &["F.mtx", "announces 2"],
        ),
        ("hello\n", PATCHES, &["F.mtx:1", "Matrix Market"]),
    ];
    for (k, (mtx, csv, needles)) in cases.iter().enumerate() {
        let dir = scratch(&format!("sysbad{k}"));
        write(&dir, "F.mtx", mtx);
        write(&dir, "patches.csv", csv);
        let out = run(
            &[
                "solve-system",
                "--form-factors",
                "F.mtx",
                "--patches",
                "patches.csv",
                "--solver",
                "gauss-seidel",
                "--out",
                "B.csv",
                "--trace",
                "t.csv",
            ],
            &dir,
        );
        assert_fails(&out, needles, &dir, &["F.mtx", "patches.csv"]);
    }
    let dir = scratch("sysbadsolver");
    write(&dir, "F.mtx", MTX);
    write(&dir, "patches.csv", PATCHES);
    let out = run(
        &[
            "solve-system",
            "--form-factors",
            "F.mtx",
            "--patches",
            "patches.csv",
            "--solver",
            "magic",
            "--out",
            "B.csv",
        ],
        &dir,
    );
    assert_fails(
        &out,
        &["--solver magic", "progressive"],
        &dir,
        &["F.mtx", "patches.csv"],
    );
    let out = run(
        &[
            "solve-system",
            "--form-factors",
            "missing.mtx",
            "--patches",
            "patches.csv",
            "--out",
            "B.csv",
        ],
        &dir,
    );
    assert_fails(&out, &["missing.mtx"], &dir, &["F.mtx", "patches.csv"]);
}

#[test]
fn solve_traces_a_scene() {
    let dir = scratch("scenetrace");
    let out = run(
        &[
            "solve",
            "cube-dim",
            "--max-edge",
            "0.25",
            "--solver",
            "gauss-seidel",
            "--tolerance",
            "1e-6",
            "--trace",
            "t.csv",
            "--out",
            "p.csv",
        ],
        &dir,
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let trace = std::fs::read_to_string(dir.join("t.csv")).unwrap();
    let rows: Vec<Vec<f64>> = trace
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    // 96 patches: a few sweeps to 1e-6.
    assert!(rows.len() > 96);
    let (first, last) = (&rows[0], rows.last().unwrap());
    assert!(first[2] > 0.5, "error at start {}", first[2]);
    assert!(last[2].abs() < 1e-5 && last[3] <= 1e-6, "last row {last:?}");
}

const SQUARES: &str = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 0 1 1\nv 1 1 1\nv 1 0 1\nf 1 2 3 4\nf 5 6 7 8\n";

fn read_mtx(path: &Path) -> (usize, Vec<(usize, usize, f64)>) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines().filter(|l| !l.starts_with('%'));
    let n: usize = lines
        .next()
        .unwrap()
        .split_whitespace()
        .next()
        .unwrap()
        .parse()
        .unwrap();
    let entries = lines
        .map(|l| {
            let t: Vec<&str> = l.split_whitespace().collect();
            (
                t[0].parse().unwrap(),
                t[1].parse().unwrap(),
                t[2].parse().unwrap(),
            )
        })
        .collect();
    (n, entries)
}

#[test]
fn form_factors_face_to_face() {
    let dir = scratch("ff");
    write(&dir, "squares.obj", SQUARES);
    // Howell C-11 for two unit squares at distance 1.
    let exact = 0.199_824_9;
    for (method, tol) in [
        ("analytic", 1e-6),
        ("hemicube", 0.01 * exact),
        ("hemisphere", 0.01 * exact),
        ("tetrahedron", 0.01 * exact),
        ("monte-carlo", 0.01 * exact),
    ] {
        let out = run(
            &[
                "form-factors",
                "squares.obj",
                "--faces",
                "--method",
                method,
                "--out",
                "F.mtx",
                "--patches-out",
                "p.csv",
            ],
            &dir,
        );
        assert!(
            out.status.success(),
            "{method}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let (n, e) = read_mtx(&dir.join("F.mtx"));
        assert_eq!(n, 2);
        for &(i, j, f) in &e {
            assert!(
                i != j && (f - exact).abs() < tol,
                "{method}: F[{i},{j}] = {f}"
            );
        }
        assert_eq!(e.len(), 2);
        let csv = std::fs::read_to_string(dir.join("p.csv")).unwrap();
        assert!(csv.starts_with("patch,surface,area,cx,cy,cz,nx,ny,nz,reflectance_r,reflectance_g,reflectance_b,emission_r,emission_g,emission_b\n"));
        assert_eq!(csv.lines().count(), 3);
    }
}

#[test]
fn form_factors_aggregates_a_triangulated_face() {
    // An L-shaped (non-convex) floor under a unit square: one row per face.
    let dir = scratch("ffl");
    write(
        &dir,
        "l.obj",
        "v 0 0 0\nv 2 0 0\nv 2 1 0\nv 1 1 0\nv 1 2 0\nv 0 2 0\nv 0 0 1\nv 0 1 1\nv 1 1 1\nv 1 0 1\nf 1 2 3 4 5 6\nf 7 8 9 10\n",
    );
    let out = run(
        &[
            "form-factors",
            "l.obj",
            "--faces",
            "--method",
            "analytic",
            "--out",
            "F.mtx",
            "--patches-out",
            "p.csv",
        ],
        &dir,
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let (n, e) = read_mtx(&dir.join("F.mtx"));
    assert_eq!(n, 2);
    let f = |i, j| e.iter().find(|x| x.0 == i && x.1 == j).map_or(0.0, |x| x.2);
    // Reciprocity between the L (area 3) and the square (area 1), exact for the analytic method.
    assert!(
        (3.0 * f(1, 2) - f(2, 1)).abs() < 1e-6,
        "{} vs {}",
        3.0 * f(1, 2),
        f(2, 1)
    );
    // The square sees more than a unit square would: the L extends beyond it.
    assert!(f(2, 1) > 0.199_824_9 && f(2, 1) < 1.0);
}

#[test]
fn form_factors_symmetrize_keeps_row_sums() {
    let dir = scratch("ffsym");
    let base = [
        "form-factors",
        "cornell",
        "--patches",
        "150",
        "--method",
        "monte-carlo",
        "--rays",
        "4000",
    ];
    let mut plain = base.to_vec();
    plain.extend(["--out", "a.mtx", "--patches-out", "p.csv"]);
    let mut sym = base.to_vec();
    sym.extend(["--symmetrize", "--out", "b.mtx"]);
    for args in [&plain, &sym] {
        let out = run(args, &dir);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    let areas: Vec<f64> = std::fs::read_to_string(dir.join("p.csv"))
        .unwrap()
        .lines()
        .skip(1)
        .map(|l| l.split(',').nth(2).unwrap().parse().unwrap())
        .collect();
    let (n, a) = read_mtx(&dir.join("a.mtx"));
    let (_, b) = read_mtx(&dir.join("b.mtx"));
    let row_sums = |e: &[(usize, usize, f64)]| {
        let mut s = vec![0.0; n];
        for &(i, _, f) in e {
            s[i - 1] += f;
        }
        s
    };
    let (sa, sb) = (row_sums(&a), row_sums(&b));
    for i in 0..n {
        assert!(
            (sa[i] - sb[i]).abs() < 1e-5,
            "row {i}: {} → {}",
            sa[i],
            sb[i]
        );
    }
    let g = |e: &[(usize, usize, f64)], i: usize, j: usize| {
        e.iter().find(|x| x.0 == i && x.1 == j).map_or(0.0, |x| x.2)
    };
    let mut worst: f64 = 0.0;
    for &(i, j, f) in &b {
        worst = worst.max((areas[i - 1] * f - areas[j - 1] * g(&b, j, i)).abs() / areas[i - 1]);
    }
    assert!(worst < 1e-5, "reciprocity after --symmetrize: {worst}");
}

#[test]
fn form_factors_rejects_bad_input() {
    let dir = scratch("ffbad");
    write(&dir, "squares.obj", SQUARES);
    write(
        &dir,
        "np.obj",
        "v 0 0 0\nv 1 0 0\nv 1 1 0.3\nv 0 1 0\nf 1 2 3 4\n",
    );
    let keep = ["squares.obj", "np.obj"];
    for (args, needles) in [
        (
            vec![
                "form-factors",
                "squares.obj",
                "--resolution",
                "0",
                "--out",
                "F.mtx",
            ],
            vec!["--resolution 0"],
        ),
        (
            vec![
                "form-factors",
                "squares.obj",
                "--rays",
                "0",
                "--out",
                "F.mtx",
            ],
            vec!["--rays 0"],
        ),
        (
            vec![
                "form-factors",
                "squares.obj",
                "--method",
                "radar",
                "--out",
                "F.mtx",
            ],
            vec!["--method radar", "hemicube"],
        ),
        (
            vec!["form-factors", "np.obj", "--faces", "--out", "F.mtx"],
            vec!["np.obj:5", "not planar"],
        ),
        (
            vec!["form-factors", "squares.obj", "--out", "F.txt"],
            vec!["F.txt", ".mtx"],
        ),
        (
            vec![
                "solve",
                "furnace",
                "--form-factors",
                "radar",
                "--out",
                "x.csv",
            ],
            // `--form-factors` is the older name of `--form-factor-method`.
            vec!["--form-factor-method radar", "monte-carlo"],
        ),
        (
            vec![
                "solve",
                "furnace",
                "--solver",
                "progresive",
                "--out",
                "x.csv",
            ],
            vec!["--solver progresive", "did you mean 'progressive'"],
        ),
    ] {
        let out = run(&args, &dir);
        assert_fails(&out, &needles, &dir, &keep);
    }
}

#[test]
fn solve_with_hemicube_form_factors_keeps_the_furnace_exact_on_average() {
    let dir = scratch("ffsolve");
    let out = run(
        &[
            "solve",
            "furnace",
            "--patches",
            "120",
            "--form-factors",
            "hemicube",
            "--resolution",
            "64",
            "--samples",
            "4",
            "--tolerance",
            "1e-7",
            "--out",
            "f.csv",
        ],
        &dir,
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(dir.join("f.csv")).unwrap();
    let (mut area, mut weighted) = (0.0, 0.0);
    for l in text.lines().skip(1) {
        let r: Vec<f64> = l.split(',').map(|v| v.parse().unwrap()).collect();
        area += r[2];
        weighted += r[2] * r[16];
    }
    // Rows sum to 1 within a pixel (delta ≤ 3.1e-4 at P = 64), so the mean is exact to that.
    assert!(
        (weighted / area - 2.0).abs() < 2.0 * 2.0 * 3.2e-4,
        "{}",
        weighted / area
    );
}

/// A CSV as a header and rows of fields.
fn read_csv(path: &Path) -> (Vec<String>, Vec<Vec<String>>) {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut lines = text.lines();
    let header: Vec<String> = lines.next().unwrap().split(',').map(String::from).collect();
    let rows = lines
        .map(|l| l.split(',').map(String::from).collect::<Vec<_>>())
        .collect();
    (header, rows)
}

fn column(header: &[String], name: &str) -> usize {
    header
        .iter()
        .position(|h| h == name)
        .unwrap_or_else(|| panic!("no column {name} in {header:?}"))
}

/// Run `radiosity experiment KIND --quick` in a fresh folder; the results' folder.
fn quick_experiment(kind: &str) -> PathBuf {
    let dir = scratch(kind);
    let out = run(&["experiment", kind, "--quick", "--out", "res"], &dir);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    dir.join("res")
}

/// `experiment convergence --quick`: every case's CSV and plots; eq. 22 is exactly 1 at B = E
/// and above 1 at B = 0; the paper's section-6 ordering on the random systems with few
/// emitters; every deterministic method's error falls.
#[test]
fn experiment_convergence_quick() {
    let res = quick_experiment("convergence");
    let cases = [
        "office",
        "cube-dim",
        "cube-bright",
        "random-dim-few",
        "random-bright-few",
        "random-dim-many",
        "random-bright-many",
    ];
    for case in cases {
        for ext in ["svg", "png"] {
            for stem in [
                format!("convergence-{case}"),
                format!("convergence-{case}-time"),
            ] {
                let p = res.join(format!("{stem}.{ext}"));
                assert!(
                    std::fs::metadata(&p).unwrap().len() > 1000,
                    "{}",
                    p.display()
                );
            }
        }
        let (h, rows) = read_csv(&res.join(format!("convergence-{case}.csv")));
        assert_eq!(h, ["method", "iteration", "seconds", "error"]);
        let first =
            |m: &str| -> f64 { rows.iter().find(|r| r[0] == m).unwrap()[3].parse().unwrap() };
        // Progressive starts from B = E: none of the reflected light is there, error 1.
        assert!((first("progressive") - 1.0).abs() < 1e-12, "{case}");
        assert!((first("gauss-seidel") - 1.0).abs() < 1e-12, "{case}");
        // Gauss-Seidel-0 starts from B = 0: even the emitted light is missing.
        assert!(first("gauss-seidel-0") > 1.0, "{case}");
    }
    let (h, rows) = read_csv(&res.join("convergence-summary.csv"));
    let (case_c, method_c) = (column(&h, "case"), column(&h, "method"));
    let (q, half, two) = (
        column(&h, "error_at_quarter_n"),
        column(&h, "error_at_half_n"),
        column(&h, "error_at_2n"),
    );
    let get = |case: &str, m: &str, c: usize| -> f64 {
        rows.iter()
            .find(|r| r[case_c] == case && r[method_c] == m)
            .unwrap_or_else(|| panic!("{case} {m}"))[c]
            .parse()
            .unwrap()
    };
    for case in ["random-dim-few", "random-bright-few"] {
        let (os, pr, gs) = (
            get(case, "overshoot", half),
            get(case, "progressive", half),
            get(case, "gauss-seidel-0", half),
        );
        assert!(os <= pr && pr < gs, "{case}: {os} {pr} {gs}");
    }
    for case in cases {
        for m in [
            "gauss-seidel-0",
            "gauss-seidel-jacobi",
            "southwell",
            "progressive",
            "gauss-seidel",
            "overshoot",
            "jacobi",
        ] {
            let (early, late) = (get(case, m, q), get(case, m, two));
            assert!(late.abs() < early.abs(), "{case} {m}: {early} → {late}");
        }
    }
    let md = std::fs::read_to_string(res.join("convergence.md")).unwrap();
    assert!(md.contains("Southwell+Jacobi") && md.contains("figure 3"));
}

/// `experiment complexity --quick`: the counts the paper derives (not timings, which belong
/// to benchmarks): Jacobi and Gauss-Seidel sweeps independent of N, progressive shots and
/// photons ∝ N, the Monte Carlo matrix's memory ∝ N; plots and tables written.
#[test]
fn experiment_complexity_quick() {
    let res = quick_experiment("complexity");
    for stem in [
        "complexity-time",
        "complexity-memory",
        "complexity-iterations",
    ] {
        for ext in ["svg", "png"] {
            assert!(res.join(format!("{stem}.{ext}")).exists(), "{stem}.{ext}");
        }
    }
    let (h, rows) = read_csv(&res.join("complexity.csv"));
    assert_eq!(
        h,
        [
            "case",
            "patches",
            "seconds",
            "iterations",
            "peak_bytes",
            "nnz",
            "converged"
        ]
    );
    assert_eq!(rows.len(), 7 * 5);
    for r in &rows {
        if !r[6].is_empty() {
            assert_eq!(r[6], "true", "{r:?} did not converge");
        }
    }
    let (h, rows) = read_csv(&res.join("complexity-fits.csv"));
    let fitted = |case: &str, q: &str| -> f64 {
        rows.iter()
            .find(|r| r[0] == case && r[1] == q)
            .unwrap_or_else(|| panic!("{case} {q}"))[column(&h, "fitted_exponent")]
        .parse()
        .unwrap()
    };
    for (case, q, claim) in [
        ("jacobi", "iterations", 0.0),
        ("gauss-seidel", "iterations", 0.0),
        ("progressive", "iterations", 1.0),
        ("stochastic", "iterations", 1.0),
        ("monte-carlo-matrix", "peak_bytes", 1.0),
        ("stochastic", "peak_bytes", 1.0),
    ] {
        let k = fitted(case, q);
        assert!(
            (k - claim).abs() <= 0.3,
            "{case} {q}: fitted {k}, claim {claim}"
        );
    }
}

#[test]
fn experiment_rejects_impossible_options() {
    let dir = scratch("experiment-bad");
    for (args, needle) in [
        (
            &["experiment", "convergence", "--sweeps", "0"][..],
            "--sweeps",
        ),
        (
            &["experiment", "complexity", "--sizes", "100"][..],
            "--sizes",
        ),
        (
            &["experiment", "complexity", "--sizes", "0,100"][..],
            "--sizes",
        ),
        (
            &["experiment", "convergence", "--sizes", "10,20"][..],
            "--sizes",
        ),
    ] {
        let out = run(args, &dir);
        assert_fails(&out, &[needle], &dir, &[]);
    }
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
        std::fs::write(dir.join("scene.mgf"), text).unwrap();
        let mut keep = vec!["scene.mgf"];
        if !part.is_empty() {
            std::fs::write(dir.join("part.mgf"), part).unwrap();
            keep.push("part.mgf");
        }
        for (cmd, out) in [("render", "out.png"), ("solve", "out.csv")] {
            let out = run(&[cmd, "scene.mgf", "-o", out], &dir);
            assert_fails(&out, needles, &dir, &keep);
        }
    }
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
    std::fs::write(dir.join("room.mgf"), room).unwrap();
    std::fs::write(dir.join("balls.mgf"), balls).unwrap();
    let out = run(
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
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
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

/// The committed glTF and PLY test scenes of the library (`crates/radiosity/tests/data`).
fn test_scene(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../radiosity/tests/data")
        .join(name)
}

/// The share of pixels brighter than 20 of 255 in any channel.
fn lit_fraction(png: &Path) -> f64 {
    let img = image::open(png).unwrap().to_rgb8();
    let lit = img.pixels().filter(|p| p.0.iter().any(|c| *c > 20)).count();
    lit as f64 / img.pixels().count() as f64
}

fn succeed(out: &Output) -> String {
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

#[test]
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
        let text = succeed(&run(
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
        ));
        assert!(text.contains("escaped"), "{text}");
        assert!(lit_fraction(&dir.join(&png)) > 0.9, "{stem}: mostly black");
        // Baked to every format.
        for ext in ["glb", "gltf", "ply"] {
            let out = format!("{stem}.{ext}");
            succeed(&run(&["solve", src, "--patches", "1500", "-o", &out], &dir));
            if ext != "ply" {
                written.push(dir.join(&out));
            }
        }
    }
    // A baked file is a scene too: rendered from the camera it carries.
    succeed(&run(
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
    ));
    assert!(lit_fraction(&dir.join("again.png")) > 0.9);
    // The built-in scenes baked too, with a darker exposure.
    for (scene, out) in [("cornell", "cornell.glb"), ("cube", "cube.gltf")] {
        succeed(&run(
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
        ));
        written.push(dir.join(out));
    }
    validator::validate_gltf(&written);
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
    std::fs::write(dir.join("tri.gltf"), json).unwrap();
}

#[test]
fn tiny_gltf_is_a_valid_scene() {
    let dir = scratch("tiny-gltf");
    tiny_gltf(&dir, &[0, 1, 2], 4, false);
    let text = succeed(&run(
        &["solve", "tri.gltf", "--patches", "50", "-o", "out.csv"],
        &dir,
    ));
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
                let out = run(
                    &["solve", "cornell", "--patches", "100", "-o", "whole.glb"],
                    d,
                );
                assert!(out.status.success());
                validator::validate_gltf(&[d.join("whole.glb")]);
                let bytes = std::fs::read(d.join("whole.glb")).unwrap();
                std::fs::write(d.join("cut.glb"), &bytes[..bytes.len() / 2]).unwrap();
                std::fs::remove_file(d.join("whole.glb")).unwrap();
            },
            "cut.glb",
            &["cut.glb"],
            &["cut.glb", "truncated GLB"],
        ),
        (
            |d| {
                std::fs::write(
                    d.join("lie.ply"),
                    ascii_ply(4, "0 0 0\n1 0 0\n0 0 -1\n3 0 1 2 1\n"),
                )
                .unwrap();
            },
            "lie.ply",
            &["lie.ply"],
            &["lie.ply:14", "element counts (4 vertex, 1 face)"],
        ),
        (
            |d| {
                std::fs::write(
                    d.join("lie.ply"),
                    ascii_ply(2, "0 0 0\n1 0 0\n0 0 -1\n3 0 1 2 1\n"),
                )
                .unwrap();
            },
            "lie.ply",
            &["lie.ply"],
            &["lie.ply:", "element counts (2 vertex, 1 face)"],
        ),
        (
            |d| {
                std::fs::write(
                    d.join("idx.ply"),
                    ascii_ply(3, "0 0 0\n1 0 0\n0 0 -1\n3 0 1 7 1\n"),
                )
                .unwrap();
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
            let out = run(&[cmd, scene, "-o", out], &dir);
            assert_fails(&out, needles, &dir, keep);
        }
    }
}

#[test]
fn view_shows_a_baked_gltf_without_solving() {
    let dir = scratch("view");
    succeed(&run(
        &["solve", "cornell", "--patches", "800", "-o", "baked.glb"],
        &dir,
    ));
    let text = succeed(&run(
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
    ));
    assert!(text.contains("triangles shown"), "{text}");
    validator::validate_gltf(&[dir.join("baked.glb")]);
    let img = image::open(dir.join("shot.png")).unwrap().to_rgb8();
    // Seen through the open side, from the camera stored in the file: the box fills the view,
    // and the light, far brighter than the walls, is clipped to white.
    assert!(lit_fraction(&dir.join("shot.png")) > 0.9);
    assert!(img.pixels().any(|p| p.0 == [255, 255, 255]));
    // A glTF without vertex colours, and a PLY, are refused.
    let room = test_scene("room.gltf");
    let out = run(&["view", room.to_str().unwrap(), "-o", "room.png"], &dir);
    assert_fails(
        &out,
        &["room.gltf", "no COLOR_0"],
        &dir,
        &["baked.glb", "shot.png"],
    );
    let ply = test_scene("room.ply");
    let out = run(&["view", ply.to_str().unwrap(), "-o", "room.png"], &dir);
    assert_fails(
        &out,
        &["room.ply", ".glb or .gltf"],
        &dir,
        &["baked.glb", "shot.png"],
    );
}

/// Each class of hostile input found by mutating files and options: a one-line located error,
/// a non-zero exit, no panic or signal, no output, within seconds (a hang or an abort on
/// allocation fails the test, which runs them all in a few seconds).
#[test]
fn hostile_inputs_get_one_line_errors_quickly() {
    let dir = scratch("hostile");
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("../radiosity/tests/data");
    for f in ["room.gltf", "room.bin", "checker.png"] {
        std::fs::copy(data.join(f), dir.join(f)).unwrap();
    }
    let room = std::fs::read_to_string(dir.join("room.gltf")).unwrap();
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
            vec!["nested.mgf:3", "nested transform arrays"],
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
        let err = String::from_utf8_lossy(&out.stderr);
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

/// A system whose reflectance is nearly 1 converges arbitrarily slowly: the default iteration
/// cap stops it, saying so, with the unshot energy it reached, and the exit is non-zero (the
/// result is written, marked unconverged).
#[test]
fn iterative_solves_always_stop() {
    let dir = scratch("cap");
    write(
        &dir,
        "f.mtx",
        "%%MatrixMarket matrix coordinate real general\n2 2 2\n1 2 1\n2 1 1\n",
    );
    write(
        &dir,
        "p.csv",
        "area,reflectance,emission\n1,0.9999999,1\n1,0.9999999,0\n",
    );
    let t = std::time::Instant::now();
    let out = run(
        &[
            "solve-system",
            "--matrix",
            "f.mtx",
            "--patches",
            "p.csv",
            "--solver",
            "jacobi",
            "--tolerance",
            "1e-9",
            "-o",
            "b.csv",
        ],
        &dir,
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert_ne!(out.status.code(), Some(101), "panicked: {err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.contains("b.csv") && err.contains("default cap of 20000 iterations"),
        "{err}"
    );
    assert!(t.elapsed().as_secs_f64() < 10.0);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("stopped after 20000 iterations without converging"),
        "{text}"
    );
}

/// Outputs are replaced by renaming only when they are regular files: a symbolic link stays a
/// link with its target rewritten, and a link to nothing is refused.
#[cfg(unix)]
#[test]
fn outputs_through_links_keep_the_link() {
    let dir = scratch("links");
    std::fs::write(dir.join("real.csv"), "old").unwrap();
    std::os::unix::fs::symlink(dir.join("real.csv"), dir.join("link.csv")).unwrap();
    let out = run(
        &["solve", "furnace", "--patches", "50", "-o", "link.csv"],
        &dir,
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(std::fs::symlink_metadata(dir.join("link.csv"))
        .unwrap()
        .file_type()
        .is_symlink());
    assert!(std::fs::read_to_string(dir.join("real.csv"))
        .unwrap()
        .starts_with("patch,"));
    std::os::unix::fs::symlink(dir.join("nothing.csv"), dir.join("dangling.csv")).unwrap();
    let out = run(
        &["solve", "furnace", "--patches", "50", "-o", "dangling.csv"],
        &dir,
    );
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("symbolic link to nothing"));
}

/// More hostile-input classes: a face whose repeated vertex makes a zero-area patch is named
/// by its file and line; a missing file gives the operating system's message once; the
/// summary reports resident memory first; and a short seeded fuzz of the option parser runs
/// clean.
#[test]
fn located_errors_os_messages_once_resident_memory_and_option_fuzz() {
    let dir = scratch("hostile2");
    write(&dir, "l.mtl", "newmtl light\nKd 0.5 0.5 0.5\nKe 1 1 1\n");
    write(
        &dir,
        "deg.obj",
        "mtllib l.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nusemtl light\nf 1 2 4 3\nf 1 2 2 3\n",
    );
    let out = run(
        &["solve", "deg.obj", "--patches", "100", "-o", "x.csv"],
        &dir,
    );
    assert_fails(&out, &["deg.obj:8", "area 0"], &dir, &["l.mtl", "deg.obj"]);
    let out = run(&["solve", "missing.obj", "-o", "x.csv"], &dir);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(err.matches("No such file or directory").count(), 1, "{err}");
    assert!(err.contains("cannot read missing.obj"), "{err}");
    let out = run(
        &["solve", "furnace", "--patches", "50", "-o", "x.csv"],
        &dir,
    );
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("memory      peak resident"), "{text}");
    let out = run(
        &[
            "fuzz",
            "--cases",
            "500",
            "--targets",
            "options",
            "--out",
            "fz",
        ],
        &dir,
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(String::from_utf8_lossy(&out.stdout).contains("options"));
}

// ---------------------------------------------------------------------------------------------
// Heat transfer and View3D interchange.

const SIGMA: f64 = 5.670_374_419e-8;

fn shared_view3d(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/scenes/view3d")
        .join(name)
}

#[cfg(feature = "mpi")]
fn shared_renderpark(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/scenes/renderpark")
        .join(name)
}

/// `surfaces.csv` as (name → [area, emissivity, temperature, flux, power]).
fn read_surfaces(path: &Path) -> std::collections::HashMap<String, [f64; 5]> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    assert_eq!(
        lines.next(),
        Some("name,area,emissivity,temperature,flux,power")
    );
    lines
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            let v: Vec<f64> = f[1..].iter().map(|x| x.parse().unwrap()).collect();
            (f[0].to_string(), [v[0], v[1], v[2], v[3], v[4]])
        })
        .collect()
}

/// The relative energy-balance error the summary prints.
fn balance_of(out: &Output) -> f64 {
    let text = String::from_utf8_lossy(&out.stdout);
    let line = text
        .lines()
        .find(|l| l.starts_with("balance"))
        .unwrap_or_else(|| panic!("no balance line in {text}"));
    line.rsplit(' ').next().unwrap().parse().unwrap()
}

fn thermal(dir: &Path, args: &[&str]) -> Output {
    let mut all = vec!["thermal"];
    all.extend_from_slice(args);
    let out = run(&all, dir);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// View3D's unit cube with every face black at its own temperature: Q_i = A_i Σ_j F_ij σ(T_i⁴ −
/// T_j⁴) with Howell's exact factors (opposite 0.1998248957, adjacent 0.2000437761). The
/// analytic factors are exact; F is stored in f32, so agreement is to ~1e-7 of σT⁴.
#[test]
fn thermal_black_enclosure_matches_the_exchange_formula() {
    let dir = scratch("thermal-black");
    let names = ["zeq0", "xeq0", "yeq0", "zeq1", "xeq1", "yeq1"];
    let t: [f64; 6] = [300.0, 400.0, 500.0, 600.0, 700.0, 800.0];
    let mut bc = String::from("name,emissivity,temperature,flux\n");
    for (n, t) in names.iter().zip(t) {
        bc += &format!("{n},1,{t},\n");
    }
    write(&dir, "bc.csv", &bc);
    let cube = shared_view3d("cube.vs3");
    let out = thermal(
        &dir,
        &[
            cube.to_str().unwrap(),
            "--boundary",
            "bc.csv",
            "--out",
            "s.csv",
            "--form-factors",
            "analytic",
        ],
    );
    assert!(balance_of(&out) < 1e-9);
    let s = read_surfaces(&dir.join("s.csv"));
    let opposite = [3, 4, 5, 0, 1, 2];
    for i in 0..6 {
        let q: f64 = (0..6)
            .filter(|&j| j != i)
            .map(|j| {
                let f = if opposite[i] == j {
                    0.199_824_895_7
                } else {
                    0.200_043_776_1
                };
                f * SIGMA * (t[i].powi(4) - t[j].powi(4))
            })
            .sum();
        let got = s[names[i]];
        assert!(
            (got[3] - q).abs() < 1e-6 * SIGMA * 800f64.powi(4),
            "{}: {} vs {q}",
            names[i],
            got[3]
        );
        assert!((got[0] - 1.0).abs() < 1e-6 && got[2] == t[i]);
    }
}

/// A regular tetrahedron of edge a: heater (one face), panels (one face), and an insulated
/// wall (two faces; by symmetry they share one radiosity, so the textbook's three-node network
/// is exact). Every F_ij = 1/3. The network with a re-radiating surface (Incropera & DeWitt,
/// ch. 13) gives q₁ = (E_b1 − E_b2) / [(1−ε₁)/(ε₁A) + 1/(A F₁₂ + 1/(1/(A F₁R) + 1/(A F₂R)))
/// + (1−ε₂)/(ε₂A)] and J_R = (J₁ + J₂)/2 (equal resistances): the wall's temperature.
#[test]
fn thermal_three_surface_enclosure_with_a_reradiating_wall() {
    let dir = scratch("thermal-tetra");
    // Vertices of a regular tetrahedron (edge 2√2); faces wound with normals inward.
    let obj = "mtllib t.mtl\nv 1 1 1\nv 1 -1 -1\nv -1 1 -1\nv -1 -1 1\n\
               usemtl heater\nf 3 2 1\nusemtl panel\nf 2 4 1\nusemtl wall\nf 4 3 1\nf 3 4 2\n";
    let mtl = "newmtl heater\nKd 0.2 0.2 0.2\nnewmtl panel\nKd 0.6 0.6 0.6\nnewmtl wall\nKd 0.2 0.2 0.2\n";
    write(&dir, "t.obj", obj);
    write(&dir, "t.mtl", mtl);
    write(
        &dir,
        "bc.csv",
        "name,emissivity,temperature,flux\nheater,0.8,1200,\npanel,0.4,500,\nwall,0.8,,\n",
    );
    let out = thermal(
        &dir,
        &[
            "t.obj",
            "--boundary",
            "bc.csv",
            "--out",
            "s.csv",
            "--form-factors",
            "analytic",
        ],
    );
    assert!(balance_of(&out) < 1e-9);
    let s = read_surfaces(&dir.join("s.csv"));
    let a = s["heater"][0];
    // Face of a regular tetrahedron with edge 2√2: (√3/4)·8.
    assert!((a - 3f64.sqrt() * 2.0).abs() < 1e-5, "{a}");
    let (e1, e2) = (0.8, 0.4);
    let (eb1, eb2) = (SIGMA * 1200f64.powi(4), SIGMA * 500f64.powi(4));
    let f = 1.0 / 3.0;
    let r_mid = 1.0 / (a * f + 1.0 / (1.0 / (a * 2.0 * f) + 1.0 / (a * 2.0 * f)));
    let q1 = (eb1 - eb2) / ((1.0 - e1) / (e1 * a) + r_mid + (1.0 - e2) / (e2 * a));
    let j1 = eb1 - q1 * (1.0 - e1) / (e1 * a);
    let j2 = eb2 + q1 * (1.0 - e2) / (e2 * a);
    let t_wall = ((j1 + j2) / 2.0 / SIGMA).powf(0.25);
    assert!(
        (s["heater"][4] - q1).abs() < 1e-6 * q1,
        "{} vs {q1}",
        s["heater"][4]
    );
    assert!((s["panel"][4] + q1).abs() < 1e-6 * q1);
    assert!(s["wall"][4].abs() < 1e-6 * q1);
    assert!(
        (s["wall"][2] - t_wall).abs() < 1e-4,
        "{} vs {t_wall}",
        s["wall"][2]
    );
}

/// Write an axis-aligned box as OBJ faces with material `m`, normals outward or inward.
fn obj_box(obj: &mut String, m: &str, lo: f64, hi: f64, outward: bool) {
    let base = obj.matches("\nv ").count() + usize::from(obj.starts_with("v "));
    for k in 0..8 {
        let c = |bit: usize| if k & bit != 0 { hi } else { lo };
        *obj += &format!("v {} {} {}\n", c(1), c(2), c(4));
    }
    *obj += &format!("usemtl {m}\n");
    // Faces with outward normals (x−, x+, y−, y+, z−, z+), 1-based corner indices.
    for f in [
        [0, 4, 6, 2],
        [1, 3, 7, 5],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 2, 3, 1],
        [4, 5, 7, 6],
    ] {
        let mut f = f.map(|v| v + base + 1);
        if !outward {
            f.reverse();
        }
        *obj += &format!("f {} {} {} {}\n", f[0], f[1], f[2], f[3]);
    }
}

/// A convex body inside an enclosure: q₁ = σ(T₁⁴ − T₂⁴) / (1/ε₁ + A₁/A₂ (1/ε₂ − 1)). With a
/// black enclosure the formula is exact for any shapes (every ray from the body reaches the
/// enclosure, which absorbs it), so Monte Carlo noise cannot enter: agreement to the f32
/// storage of F. With a grey enclosure it assumes uniform radiosity on each surface, which
/// nested cubes only approximate: the per-patch solve lies 0.25 % below it at 400 patches and
/// at 4,000 alike (so that is the formula's error, not the mesh's), and Monte Carlo noise at
/// 20,000 rays a row is under 0.1 %: 1 % covers both.
#[test]
fn thermal_convex_body_inside_an_enclosure() {
    let dir = scratch("thermal-nested");
    let mut obj = String::from("mtllib n.mtl\n");
    obj_box(&mut obj, "inner", -0.5, 0.5, true);
    obj_box(&mut obj, "outer", -2.0, 2.0, false);
    write(&dir, "n.obj", &obj);
    write(
        &dir,
        "n.mtl",
        "newmtl inner\nKd 0.5 0.5 0.5\nnewmtl outer\nKd 0.5 0.5 0.5\n",
    );
    let (t1, t2, e1) = (500.0f64, 300.0f64, 0.6);
    let (a1, a2) = (6.0, 6.0 * 16.0);
    for (e2, tolerance) in [(1.0, 1e-5), (0.5, 0.01)] {
        write(
            &dir,
            "bc.csv",
            &format!("name,emissivity,temperature,flux\ninner,{e1},{t1},\nouter,{e2},{t2},\n"),
        );
        let out = thermal(
            &dir,
            &[
                "n.obj",
                "--boundary",
                "bc.csv",
                "--out",
                "s.csv",
                "--patches",
                "400",
                "--rays",
                "20000",
            ],
        );
        assert!(balance_of(&out) < 1e-9);
        let s = read_surfaces(&dir.join("s.csv"));
        let q1 = SIGMA * (t1.powi(4) - t2.powi(4)) / (1.0 / e1 + a1 / a2 * (1.0 / e2 - 1.0));
        let got = s["inner"][3];
        assert!(
            (got - q1).abs() < tolerance * q1,
            "ε₂ = {e2}: {got} vs {q1}"
        );
        // Closed: what the body loses the enclosure gains.
        assert!((s["inner"][4] + s["outer"][4]).abs() < 1e-9 * s["inner"][4]);
    }
}

/// An open plate and a prescribed flux: a 1000 mm square at 500 K facing surroundings at 300 K
/// loses εσ(T⁴ − T_e⁴) W/m² over 1 m²; prescribing that flux gives back 500 K.
#[test]
fn thermal_open_plate_units_and_prescribed_flux() {
    let dir = scratch("thermal-plate");
    write(
        &dir,
        "p.obj",
        "mtllib p.mtl\nv 0 0 0\nv 1000 0 0\nv 1000 1000 0\nv 0 1000 0\nusemtl plate\nf 1 2 3 4\n",
    );
    write(&dir, "p.mtl", "newmtl plate\nKd 0.3 0.3 0.3\n");
    let q = 0.7 * SIGMA * (500f64.powi(4) - 300f64.powi(4));
    write(
        &dir,
        "bc.csv",
        "name,emissivity,temperature,flux\nplate,,500,\n",
    );
    let args = [
        "p.obj",
        "--boundary",
        "bc.csv",
        "--out",
        "s.csv",
        "--unit",
        "mm",
        "--environment",
        "300",
    ];
    thermal(&dir, &args);
    let s = read_surfaces(&dir.join("s.csv"))["plate"];
    // Emissivity from the material: 1 − 0.3.
    assert!((s[1] - 0.7).abs() < 1e-6);
    assert!((s[0] - 1.0).abs() < 1e-6, "area {} m²", s[0]);
    assert!((s[3] - q).abs() < 1e-6 * q, "{} vs {q}", s[3]);
    write(
        &dir,
        "bc.csv",
        &format!("name,emissivity,temperature,flux\nplate,0.7,,{q}\n"),
    );
    thermal(&dir, &args);
    let s = read_surfaces(&dir.join("s.csv"))["plate"];
    assert!((s[2] - 500.0).abs() < 1e-4, "{}", s[2]);
}

#[test]
fn thermal_rejects_bad_boundaries() {
    let dir = scratch("thermal-bad");
    write(
        &dir,
        "p.obj",
        "mtllib p.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nusemtl plate\nf 1 2 3 4\nusemtl back\nf 4 3 2 1\n",
    );
    write(
        &dir,
        "p.mtl",
        "newmtl plate\nKd 0.3 0.3 0.3\nnewmtl back\nKd 0.3 0.3 0.3\n",
    );
    let h = "name,emissivity,temperature,flux\n";
    let keep = ["p.obj", "p.mtl", "bc.csv"];
    for (body, needles) in [
        (
            "plate,0.5,300,\nfoo,0.5,300,\n",
            &["bc.csv:3", "unknown surface 'foo'", "back, plate"][..],
        ),
        (
            "plate,0.5,300,10\nback,0.5,300,\n",
            &["bc.csv:2", "both a temperature and a flux"],
        ),
        (
            "plate,1.5,300,\nback,0.5,300,\n",
            &["bc.csv:2", "emissivity 1.5", "(0, 1]"],
        ),
        (
            "plate,0.5,-4,\nback,0.5,300,\n",
            &["bc.csv:2", "temperature -4 K", "negative"],
        ),
        (
            "plate,0.5,300,\n",
            &["bc.csv", "no boundary condition for 1 surface: back"],
        ),
    ] {
        write(&dir, "bc.csv", &format!("{h}{body}"));
        // Two plates back to back see nothing: closed only if told so.
        let out = run(
            &[
                "thermal",
                "p.obj",
                "--boundary",
                "bc.csv",
                "--out",
                "s.csv",
                "--enclosure",
                "closed",
            ],
            &dir,
        );
        assert_fails(&out, needles, &dir, &keep);
    }
    // A closed enclosure with no temperature anywhere.
    let cube = shared_view3d("cube.vs3");
    write(
        &dir,
        "bc.csv",
        &format!("{h}zeq0,,,100\nxeq0,,,\nyeq0,,,\nzeq1,,,\nxeq1,,,\nyeq1,,,-100\n"),
    );
    let out = run(
        &[
            "thermal",
            cube.to_str().unwrap(),
            "--boundary",
            "bc.csv",
            "--out",
            "s.csv",
        ],
        &dir,
    );
    assert_fails(
        &out,
        &["no surface has a prescribed temperature"],
        &dir,
        &keep,
    );
    write(&dir, "bc.csv", "name,temperature\n");
    let out = run(
        &["thermal", "p.obj", "--boundary", "bc.csv", "--out", "s.csv"],
        &dir,
    );
    assert_fails(&out, &["bc.csv:1", "header"], &dir, &keep);
    write(
        &dir,
        "bc.csv",
        &format!("{h}plate,0.5,300,\nback,0.5,300,\n"),
    );
    for (args, needle) in [
        (&["--environment=-1"][..], "--environment -1"),
        (&["--rays", "0"], "--rays 0"),
        (&["--patches", "0"], "--patches 0"),
    ] {
        let mut all = vec!["thermal", "p.obj", "--boundary", "bc.csv", "--out", "s.csv"];
        all.extend_from_slice(args);
        assert_fails(&run(&all, &dir), &[needle], &dir, &keep);
    }
}

/// Parse a View3D view-factor file: (header words, areas, rows, emissivities).
fn read_view3d(text: &str) -> (Vec<String>, Vec<f64>, Vec<Vec<f64>>, Vec<f64>) {
    let mut lines = text.lines();
    let header: Vec<String> = lines
        .next()
        .unwrap()
        .split_whitespace()
        .map(String::from)
        .collect();
    let n: usize = header[5].parse().unwrap();
    let nums = |l: &str| -> Vec<f64> { l.split_whitespace().map(|x| x.parse().unwrap()).collect() };
    let area = nums(lines.next().unwrap());
    let rows: Vec<Vec<f64>> = (0..n).map(|_| nums(lines.next().unwrap())).collect();
    let emit = nums(lines.next().unwrap());
    (header, area, rows, emit)
}

/// View3D's own examples against View3D 4.0's own output (built from jasondegraw/View3D at
/// e95f316 and run on each file; its factors are converged to eps = 1e-4 or better). Ours
/// are Monte Carlo with 10⁶ rays per input surface: one entry's standard deviation is at most
/// √(F(1−F)/10⁶) ≤ 5e-4, so 2.5e-3 is 5σ. The cube is also checked with the exact analytic
/// method, to 1e-6 (View3D prints six decimals).
#[test]
fn form_factors_view3d_matches_view3d_on_its_examples() {
    let dir = scratch("view3d");
    let view3d_output: [(&str, &str); 4] = [
        ("cube.vs3", "View3D 4.0.0 0 1 0 6\n1 1 1 1 1 1\n0.000000 0.200044 0.200044 0.199825 0.200044 0.200044\n0.200044 0.000000 0.200044 0.200044 0.199825 0.200044\n0.200044 0.200044 0.000000 0.200044 0.200044 0.199825\n0.199825 0.200044 0.200044 0.000000 0.200044 0.200044\n0.200044 0.199825 0.200044 0.200044 0.000000 0.200044\n0.200044 0.200044 0.199825 0.200044 0.200044 0.000000\n0.500 0.500 0.500 0.500 0.500 0.500\n"),
        ("square-obstruction.vs3", "View3D 4.0.0 0 0 0 3\n1 1 0.25\n0.000000 0.149870 0.000000\n0.149870 0.000000 0.103813\n0.000000 0.415254 0.000000\n0.500 0.500 0.500\n"),
        ("pinney-bean-test-4.vs3", "View3D 4.0.0 0 1 1 8\n9 3 6 6 3 9 5 5\n0.030132 0.099218 0.314268 0.032561 0.030812 0.159022 0.116993 0.116993\n0.297654 0.009602 0.273178 0.007439 0.003718 0.092436 0.107986 0.107986\n0.471402 0.136589 0.025214 0.006158 0.003720 0.048841 0.104038 0.104038\n0.048841 0.003720 0.006158 0.025214 0.136589 0.471402 0.104038 0.104038\n0.092436 0.003718 0.007439 0.273178 0.009602 0.297654 0.107986 0.107986\n0.159022 0.030812 0.032561 0.314268 0.099218 0.030132 0.116993 0.116993\n0.210588 0.064792 0.124846 0.124846 0.064792 0.210588 0.010932 0.088616\n0.210588 0.064792 0.124846 0.124846 0.064792 0.210588 0.088616 0.010932\n0.900 0.900 0.900 0.900 0.900 0.900 0.900 0.900\n"),
        ("pinney-bean-test-4-f3a.vs3", "View3D 4.0.0 0 1 0 8\n9 3 6 6 3 9 5 5\n0.000000 0.113147 0.378091 0.027473 0.032905 0.182349 0.133016 0.133019\n0.339441 0.000000 0.318989 0.000000 0.000000 0.098715 0.121428 0.121427\n0.567137 0.159494 0.000000 0.000000 0.000000 0.041210 0.116080 0.116079\n0.041210 0.000000 0.000000 0.000000 0.159494 0.567138 0.116080 0.116079\n0.098714 0.000000 0.000000 0.318988 0.000000 0.339442 0.121428 0.121427\n0.182349 0.032905 0.027473 0.378092 0.113147 0.000000 0.133017 0.133016\n0.239429 0.072857 0.139296 0.139295 0.072857 0.239430 0.000000 0.096836\n0.239434 0.072856 0.139295 0.139295 0.072856 0.239429 0.096836 0.000000\n0.900 0.900 0.900 0.900 0.900 0.900 0.900 0.900\n"),
    ];
    for (file, expected) in view3d_output {
        let path = shared_view3d(file);
        let out = run(
            &[
                "form-factors",
                path.to_str().unwrap(),
                "--format",
                "view3d",
                "-o",
                "f.vf",
            ],
            &dir,
        );
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let ours = read_view3d(&std::fs::read_to_string(dir.join("f.vf")).unwrap());
        let theirs = read_view3d(expected);
        assert_eq!(ours.0[0], "View3D");
        assert_eq!(ours.0[2..], theirs.0[2..], "{file}: out encl emit N");
        assert_eq!(ours.1, theirs.1, "{file}: areas");
        assert_eq!(ours.3, theirs.3, "{file}: emissivities");
        for (m, (a, b)) in ours.2.iter().zip(&theirs.2).enumerate() {
            for (k, (x, y)) in a.iter().zip(b).enumerate() {
                assert!(
                    (x - y).abs() < 2.5e-3,
                    "{file}: F[{m}][{k}] {x} vs View3D {y}"
                );
            }
        }
    }
    let cube = shared_view3d("cube.vs3");
    let out = run(
        &[
            "form-factors",
            cube.to_str().unwrap(),
            "--format",
            "view3d",
            "--method",
            "analytic",
            "-o",
            "f.vf",
        ],
        &dir,
    );
    assert!(out.status.success());
    let ours = read_view3d(&std::fs::read_to_string(dir.join("f.vf")).unwrap());
    for (m, row) in ours.2.iter().enumerate() {
        for (k, &x) in row.iter().enumerate() {
            let exact = if m == k {
                0.0
            } else if (m + 3) % 6 == k {
                0.199_825
            } else {
                0.200_044
            };
            assert!((x - exact).abs() < 1e-6, "F[{m}][{k}] = {x}");
        }
    }
}

#[test]
fn vs3_errors_are_located() {
    let dir = scratch("vs3-bad");
    for (text, needles) in [
        (
            "F 3\nV 1 0 0 0\nV 2 1 0 0\nV 3 0 1 0\nS 1 1 2 3 0 2 0 0.5 a\n",
            &["x.vs3:5", "subsurfaces"][..],
        ),
        (
            "F 3\nV 1 0 0 0\nV 3 1 0 0\n",
            &["x.vs3:3", "vertex 3 out of sequence"],
        ),
        (
            "F 3\nV 1 0 0 0\nV 2 1 0 0\nV 3 0 1 0\nS 1 1 2 9 0 0 0 0.5 a\n",
            &["x.vs3:5", "third vertex 9"],
        ),
    ] {
        write(&dir, "x.vs3", text);
        let out = run(
            &["form-factors", "x.vs3", "--format", "view3d", "-o", "f.vf"],
            &dir,
        );
        assert_fails(&out, needles, &dir, &["x.vs3"]);
    }
}

/// Concentric spheres (octahedra subdivided twice and pushed onto radii 1 and 2, 128 triangles
/// each, inner facing out, outer facing in): q₁ = σ(T₁⁴ − T₂⁴) / (1/ε₁ + A₁/A₂ (1/ε₂ − 1)) with
/// the tessellated areas. By symmetry each sphere's radiosity is uniform up to the
/// tessellation's irregularity; measured 1.3e-5 off the formula at 20,000 and 200,000 rays a
/// row alike. Monte Carlo enters only through the outer sphere's radiosity averaged over all
/// its patches (≈ 1/√(20,000 · 128) of its small spread): 1e-3 covers both.
#[test]
fn thermal_concentric_spheres() {
    let dir = scratch("thermal-spheres");
    let mut v: Vec<[f64; 3]> = vec![
        [1.0, 0.0, 0.0],
        [-1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, -1.0, 0.0],
        [0.0, 0.0, 1.0],
        [0.0, 0.0, -1.0],
    ];
    let mut t: Vec<[usize; 3]> = vec![
        [0, 2, 4],
        [2, 1, 4],
        [1, 3, 4],
        [3, 0, 4],
        [2, 0, 5],
        [1, 2, 5],
        [3, 1, 5],
        [0, 3, 5],
    ];
    for _ in 0..2 {
        let mut cache = std::collections::HashMap::new();
        let mut mid = |a: usize, b: usize, v: &mut Vec<[f64; 3]>| {
            *cache.entry((a.min(b), a.max(b))).or_insert_with(|| {
                let p: Vec<f64> = (0..3).map(|i| (v[a][i] + v[b][i]) / 2.0).collect();
                let n = p.iter().map(|x| x * x).sum::<f64>().sqrt();
                v.push([p[0] / n, p[1] / n, p[2] / n]);
                v.len() - 1
            })
        };
        let mut next = Vec::new();
        for &[a, b, c] in &t {
            let (ab, bc, ca) = (mid(a, b, &mut v), mid(b, c, &mut v), mid(c, a, &mut v));
            next.extend([[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]);
        }
        t = next;
    }
    let area = |r: f64| -> f64 {
        t.iter()
            .map(|&[a, b, c]| {
                let (p, q, s) = (v[a], v[b], v[c]);
                let u: Vec<f64> = (0..3).map(|i| r * (q[i] - p[i])).collect();
                let w: Vec<f64> = (0..3).map(|i| r * (s[i] - p[i])).collect();
                let x = [
                    u[1] * w[2] - u[2] * w[1],
                    u[2] * w[0] - u[0] * w[2],
                    u[0] * w[1] - u[1] * w[0],
                ];
                0.5 * x.iter().map(|k| k * k).sum::<f64>().sqrt()
            })
            .sum()
    };
    let mut obj = String::from("mtllib s.mtl\n");
    for r in [1.0, 2.0] {
        for p in &v {
            obj += &format!("v {:.9} {:.9} {:.9}\n", r * p[0], r * p[1], r * p[2]);
        }
    }
    obj += "usemtl inner\n";
    for &[a, b, c] in &t {
        obj += &format!("f {} {} {}\n", a + 1, b + 1, c + 1);
    }
    obj += "usemtl outer\n";
    let o = v.len();
    for &[a, b, c] in &t {
        obj += &format!("f {} {} {}\n", c + 1 + o, b + 1 + o, a + 1 + o);
    }
    write(&dir, "s.obj", &obj);
    write(
        &dir,
        "s.mtl",
        "newmtl inner\nKd 0.5 0.5 0.5\nnewmtl outer\nKd 0.5 0.5 0.5\n",
    );
    write(
        &dir,
        "bc.csv",
        "name,emissivity,temperature,flux\ninner,0.6,500,\nouter,0.5,300,\n",
    );
    let out = thermal(
        &dir,
        &[
            "s.obj",
            "--boundary",
            "bc.csv",
            "--out",
            "s.csv",
            "--rays",
            "20000",
        ],
    );
    assert!(balance_of(&out) < 1e-9);
    let (a1, a2) = (area(1.0), area(2.0));
    let q1 = SIGMA * (500f64.powi(4) - 300f64.powi(4)) / (1.0 / 0.6 + a1 / a2 * (1.0 / 0.5 - 1.0));
    let s = read_surfaces(&dir.join("s.csv"));
    assert!((s["inner"][0] - a1).abs() < 1e-5 * a1);
    assert!(
        (s["inner"][3] - q1).abs() < 1e-3 * q1,
        "{} vs {q1}",
        s["inner"][3]
    );
}

// ---------------------------------------------------------------------------------------------
// Pictures: final gather and path tracer.

/// Pixels of a PFM the CLI wrote (rows bottom to top; order does not matter here).
fn read_pfm_pixels(path: &Path) -> Vec<[f32; 3]> {
    let bytes = std::fs::read(path).unwrap();
    let mut parts = bytes.splitn(4, |&b| b == b'\n');
    assert_eq!(parts.next(), Some(&b"PF"[..]));
    let _size = parts.next().unwrap();
    let _scale = parts.next().unwrap();
    parts
        .next()
        .unwrap()
        .chunks_exact(12)
        .map(|c| {
            let f = |k: usize| f32::from_le_bytes(c[4 * k..4 * k + 4].try_into().unwrap());
            [f(0), f(1), f(2)]
        })
        .collect()
}

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
        let out = run(&all, &dir);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
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
            let out = run(&all, &dir);
            assert!(
                out.status.success(),
                "{}",
                String::from_utf8_lossy(&out.stderr)
            );
            bytes.push(std::fs::read(dir.join("c.pfm")).unwrap());
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
        assert_fails(&run(&all, &dir), &[needle], &dir, &[]);
    }
}

/// The gather reads a baked glTF's `_RADIOSITY` and materials: the furnace baked, then viewed
/// with `--gather`, is E/(π(1 − ρ)) everywhere (mean within 1 % and 4 standard errors).
#[test]
fn gather_over_a_baked_gltf() {
    let dir = scratch("baked-gather");
    let out = run(
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
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let out = run(
        &[
            "view", "f.glb", "--gather", "--width", "24", "--height", "24", "--spp", "4", "-o",
            "f.pfm",
        ],
        &dir,
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_furnace_picture(&dir.join("f.pfm"), 1e-4, "baked furnace, gathered");
}

/// Every pixel of a furnace picture is E/(π(1 − ρ)) (E = 1, ρ = 0.3, 0.5, 0.7): the mean over
/// the picture within 4 standard errors (from the pixels' own spread) plus the deficit of a
/// solve stopped at the fraction `unshot` of the emitted energy, and 1 %.
///
/// That deficit: the output x + r of progressive refinement lacks ρF(I − ρF)⁻¹ r, whose
/// area-weighted sum in a closed furnace of one ρ is ρ/(1 − ρ) Σ r_i A_i. A channel holds at
/// most all the unshot energy, `unshot` times the three channels' emission, so the mean
/// radiosity 1/(1 − ρ) falls short by at most the relative 3 · unshot · ρ.
fn assert_furnace_picture(path: &Path, unshot: f64, what: &str) {
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

/// `bench --hierarchical SCENE`: the reference surface means are made (by the light tracer
/// unless `--reference-tracer path`) and written as `surface,b_r,b_g,b_b,se_r,se_g,se_b`, one
/// row a polygon; the table gives each method's errors against them and the reference's own
/// noise floor; a second run reads the file instead of tracing again.
#[test]
fn bench_hierarchical_makes_and_reads_its_reference() {
    let dir = scratch("bench-hierarchical");
    for tracer in ["light", "path"] {
        let file = format!("{tracer}.csv");
        let args = [
            "bench",
            "--hierarchical",
            "cornell",
            "--link-errors",
            "1e-3",
            "--reference",
            &file,
            "--reference-paths",
            "1000000",
            "--reference-tracer",
            tracer,
        ];
        let out = run(&args, &dir);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let text = String::from_utf8_lossy(&out.stdout).to_string();
        assert!(
            text.contains(if tracer == "light" {
                "light tracer"
            } else {
                "path tracer"
            }),
            "{text}"
        );
        let csv = std::fs::read_to_string(dir.join(&file)).unwrap();
        let mut lines = csv.lines();
        assert_eq!(lines.next(), Some("surface,b_r,b_g,b_b,se_r,se_g,se_b"));
        assert_eq!(lines.count(), 19, "{csv}");
        let row = text
            .lines()
            .find(|l| l.starts_with("hierarchical 1e-3"))
            .expect("a hierarchical row");
        let v: Vec<f64> = row
            .split_whitespace()
            .skip(2)
            .map(|t| t.parse().unwrap())
            .collect();
        // elements, links, wall s, mean %, worst %, L1 %, floor %.
        assert!(v[5] < 3.0 && v[6] < 0.5, "{row}");
        let again = run(&args, &dir);
        assert!(String::from_utf8_lossy(&again.stdout).contains("(read)"));
    }
    // `--solve-seeds`: a row a seed, each its own draw.
    let out = run(
        &[
            "bench",
            "--hierarchical",
            "cornell",
            "--link-errors",
            "1e-3",
            "--reference",
            "light.csv",
            "--solve-seeds",
            "1,2",
        ],
        &dir,
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout).to_string();
    let rows: Vec<&str> = text
        .lines()
        .filter(|l| l.starts_with("hierarchical 1e-3 s"))
        .collect();
    assert_eq!(rows.len(), 2, "{text}");
    assert_ne!(
        rows[0].split_whitespace().nth(3),
        rows[1].split_whitespace().nth(3),
        "{text}"
    );
}

/// Run `bench --scale cornell --sizes 200,800` with `extra` options; its output and the
/// table's rows (the lines of fourteen numbers, "—" read as NaN).
fn bench_scale_cornell(extra: &[&str], dir: &Path) -> (String, Vec<Vec<f64>>) {
    let out = run(
        &[
            &["bench", "--scale", "cornell", "--sizes", "200,800"],
            extra,
        ]
        .concat(),
        dir,
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout).to_string();
    let rows: Vec<Vec<f64>> = text
        .lines()
        .filter_map(|l| {
            let v: Result<Vec<f64>, _> = l
                .split_whitespace()
                .map(|t| if t == "—" { Ok(f64::NAN) } else { t.parse() })
                .collect();
            v.ok().filter(|v| v.len() == 14 && !v[0].is_nan())
        })
        .collect();
    assert_eq!(rows.len(), 2, "{text}");
    (text, rows)
}

/// What `solve cornell --patches SIZE --tolerance 0.05` prints.
fn cornell_alone(size: &str, dir: &Path) -> String {
    let solo = run(
        &[
            "solve",
            "cornell",
            "--patches",
            size,
            "--tolerance",
            "0.05",
            "--out",
            "s.csv",
        ],
        dir,
    );
    succeed(&solo)
}

/// The exponent `name` on `bench --scale`'s last line; `None` where it reads "—".
fn scale_exponent(text: &str, name: &str) -> Option<f64> {
    let line = text
        .lines()
        .find(|l| l.starts_with("fitted exponents against N:"))
        .unwrap();
    let at = line.find(&format!(" {name} ")).unwrap() + name.len() + 2;
    line[at..].split(',').next().unwrap().trim().parse().ok()
}

/// `bench --scale`: each size is solved by a fresh `radiosity solve`, and the table reports its
/// patches, rays and iterations exactly as that command, run alone, reports them (they depend
/// on the seed only); its stages fit inside the wall time measured around the child; the
/// exponent of the rays is the slope through the table's own two points. Bad sizes are refused
/// with a one-line error naming the option.
#[test]
fn bench_scale_reports_each_solve_and_fits_its_exponents() {
    let dir = scratch("bench-scale");
    let (text, rows) = bench_scale_cornell(&["--tolerance", "0.05"], &dir);
    for (row, size) in rows.iter().zip(["200", "800"]) {
        let said = cornell_alone(size, &dir);
        let first = |key: &str| -> f64 {
            let line = said.lines().find(|l| l.starts_with(key)).unwrap();
            line[key.len()..]
                .split_whitespace()
                .next()
                .unwrap()
                .parse()
                .unwrap()
        };
        assert_eq!(row[0], first("patches "), "{text}\n{said}");
        assert_eq!(row[1], first("rays "), "{text}\n{said}");
        assert_eq!(row[2], first("iterations "), "{text}\n{said}");
        // Mesh, hierarchy, rows and solve happen inside the child; each printed value is off
        // by at most half its last digit: 0.005 for the wall and the rows and solve times,
        // 0.0005 for the mesh and hierarchy.
        let stages = row[5] + row[6] + row[7] + row[8];
        assert!(stages <= row[3] + 0.016 + 1e-9, "{text}");
        assert!(row[1] > 0.0 && row[2] > 0.0 && row[9] > 0.0, "{text}");
        // `solve %` is the solve's share of the wall time, both printed to ±0.005 s and the
        // share to ±0.05.
        let (solve, wall, share) = (row[8], row[3], row[11]);
        let low = 100.0 * (solve - 0.005).max(0.0) / (wall + 0.005) - 0.05;
        let high = 100.0 * (solve + 0.005) / (wall - 0.005) + 0.05;
        assert!(low - 1e-9 <= share && share <= high + 1e-9, "{text}");
        // The cross-core round trips before and after: a time on a machine of two cores or
        // more (under the 200 ms that the probe may take), "—" on one.
        let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
        for t in [row[12], row[13]] {
            if cores > 1 {
                assert!(t > 0.0 && t < 2e8, "{text}");
            } else {
                assert!(t.is_nan(), "{text}");
            }
        }
    }
    let slope = (rows[1][1] / rows[0][1]).ln() / (rows[1][0] / rows[0][0]).ln();
    let rays = scale_exponent(&text, "rays").unwrap();
    assert!((rays - slope).abs() <= 0.005 + 1e-9, "{text}: {slope}");
    for bad in ["0", "200,0"] {
        let out = run(&["bench", "--scale", "cornell", "--sizes", bad], &dir);
        let err = String::from_utf8_lossy(&out.stderr).to_string();
        assert!(!out.status.success() && err.contains("--sizes"), "{err}");
        assert_eq!(err.trim().lines().count(), 1, "{err}");
    }
}

/// `bench --scale … --bookkeeping`: each size is solved once, which fills the row cache, and
/// then again on the cached rows. On the Cornell box at 5 % no row is estimated twice, so the
/// solves on the cached rows take exactly the shots of `solve` run alone, and the rows counted
/// are the rows it reports; every shot updates at least one receiver. A method that does not
/// use rows is refused with a one-line error naming the option.
#[test]
fn bench_bookkeeping_replays_the_solve_on_cached_rows() {
    let dir = scratch("bench-bookkeeping");
    let out = run(
        &[
            "bench",
            "--scale",
            "cornell",
            "--sizes",
            "800",
            "--bookkeeping",
            "--runs",
            "2",
            "--tolerance",
            "0.05",
        ],
        &dir,
    );
    let text = succeed(&out);
    let row: Vec<f64> = text
        .lines()
        .filter_map(|l| {
            let v: Result<Vec<f64>, _> = l.split_whitespace().map(str::parse).collect();
            v.ok().filter(|v| v.len() == 7)
        })
        .next()
        .unwrap_or_else(|| panic!("{text}"));
    let said = cornell_alone("800", &dir);
    let words = |key: &str| -> Vec<String> {
        let line = said.lines().find(|l| l.starts_with(key)).unwrap();
        line.split_whitespace().map(String::from).collect()
    };
    assert_eq!(
        row[0],
        words("patches ")[1].parse::<f64>().unwrap(),
        "{text}\n{said}"
    );
    assert_eq!(
        row[1],
        words("iterations ")[1].parse::<f64>().unwrap(),
        "{text}\n{said}"
    );
    // "rays        409726 in 729 form-factor rows"
    assert_eq!(
        row[3],
        words("rays ")[3].parse::<f64>().unwrap(),
        "{text}\n{said}"
    );
    assert!(row[2] >= row[1] && row[6] > 0.0, "{text}");
    let out = run(
        &[
            "bench",
            "--scale",
            "cornell",
            "--sizes",
            "200",
            "--bookkeeping",
            "--solver",
            "stochastic-jacobi",
        ],
        &dir,
    );
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(
        !out.status.success() && err.contains("--bookkeeping"),
        "{err}"
    );
    assert_eq!(err.trim().lines().count(), 1, "{err}");
}

/// Stochastic Jacobi casts its rays inside its solve: `solve` says how much of the solve
/// stage they took, and `bench --scale` counts them with the rows, so that its `solve s`
/// column is everything but rays for every method.
#[test]
fn stochastic_jacobi_reports_its_rays_apart_from_its_bookkeeping() {
    let dir = scratch("sj-rays");
    let args = ["--solver", "stochastic-jacobi", "--tolerance", "0.05"];
    let solo = run(
        &[
            &["solve", "cornell", "--patches", "800", "--out", "s.csv"],
            &args[..],
        ]
        .concat(),
        &dir,
    );
    assert!(solo.status.success());
    let said = String::from_utf8_lossy(&solo.stdout).to_string();
    let time = said.lines().find(|l| l.starts_with("time ")).unwrap();
    let after = |key: &str| -> f64 {
        let at = time.find(key).unwrap_or_else(|| panic!("{time}")) + key.len();
        time[at..]
            .split_whitespace()
            .next()
            .unwrap()
            .parse()
            .unwrap()
    };
    let (solve, rays) = (after("solve "), after("(rays "));
    assert!(rays > 0.0 && rays <= solve, "{time}");
    let (text, rows) = bench_scale_cornell(&args, &dir);
    for row in &rows {
        // Every stage fits in the wall time, to the printed values' rounding.
        assert!(row[7] >= 0.0 && row[8] >= 0.0, "{text}");
        assert!(
            row[5] + row[6] + row[7] + row[8] <= row[3] + 0.016 + 1e-9,
            "{text}"
        );
    }
    // The rows' exponent is fitted (not "—"): their times, unrounded, were not zero.
    assert!(scale_exponent(&text, "rows").is_some(), "{text}");
}

/// `--gather-rays`: stochastic Jacobi's final gathering iteration runs only when asked for.
/// Without the flag the output is that of `--gather-rays 0` byte for byte; with it, B differs
/// (gathered again), both report a standard error, and the area-weighted mean of B stays
/// within the two runs' Monte Carlo noise of each other.
#[test]
fn stochastic_jacobi_gathers_only_when_asked() {
    let dir = scratch("sj-gather");
    let solve = |extra: &[&str], out: &str| {
        let o = run(
            &[
                &[
                    "solve",
                    "cornell",
                    "--patches",
                    "800",
                    "--solver",
                    "stochastic-jacobi",
                    "--iteration-rays",
                    "64",
                    "--out",
                    out,
                ][..],
                extra,
            ]
            .concat(),
            &dir,
        );
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let said = String::from_utf8_lossy(&o.stdout).to_string();
        assert!(said.contains("estimated standard error"), "{said}");
        std::fs::read_to_string(dir.join(out)).unwrap()
    };
    let plain = solve(&[], "plain.csv");
    let zero = solve(&["--gather-rays", "0"], "zero.csv");
    let gathered = solve(&["--gather-rays", "64"], "gathered.csv");
    assert_eq!(plain, zero);
    assert_ne!(plain, gathered);
    // Area-weighted mean radiosity (channels summed) of each CSV.
    let mean = |csv: &str| {
        let mut lines = csv.lines();
        let head: Vec<&str> = lines.next().unwrap().split(',').collect();
        let col = |name: &str| head.iter().position(|h| *h == name).unwrap();
        let (a, r, g, b) = (
            col("area"),
            col("radiosity_r"),
            col("radiosity_g"),
            col("radiosity_b"),
        );
        let (mut total, mut area) = (0.0, 0.0);
        for l in lines {
            let v: Vec<f64> = l.split(',').map(|x| x.parse().unwrap_or(0.0)).collect();
            total += v[a] * (v[r] + v[g] + v[b]);
            area += v[a];
        }
        total / area
    };
    // More gathering rays than a patch may hold at once: refused before anything is built,
    // one line naming the flag, no output file.
    let refused = run(
        &[
            "solve",
            "cornell",
            "--solver",
            "stochastic-jacobi",
            "--gather-rays",
            "4000000000",
            "--out",
            "refused.csv",
        ],
        &dir,
    );
    assert!(!refused.status.success());
    let err = String::from_utf8_lossy(&refused.stderr);
    assert!(err.contains("--gather-rays 4000000000"), "{err}");
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(!dir.join("refused.csv").exists());
    let (m0, m1) = (mean(&plain), mean(&gathered));
    eprintln!("mean B {m0} without gathering, {m1} with");
    // 64 rays a patch over 800 patches: the scene's mean is known to a fraction of a per
    // cent; 3 % holds both runs' noise many times over.
    assert!((m1 / m0 - 1.0).abs() < 0.03, "{m0} against {m1}");
}

/// `bench --rays SCENE`: the form-factor ray workload on a scene, with its figures.
#[test]
fn bench_rays_on_a_scene() {
    let dir = scratch("bench-rays");
    let out = run(
        &[
            "bench",
            "--rays",
            "cornell",
            "--rays",
            "20000",
            "--runs",
            "1",
            "--patches",
            "500",
        ],
        &dir,
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    let line = text
        .lines()
        .find(|l| l.starts_with("radiosity BVH"))
        .expect("a BVH line");
    // A closed box: every ray from a wall hits the front of another (the light's back is
    // outside), so the hit rate is high.
    let hit: f64 = line
        .split_whitespace()
        .nth(3)
        .unwrap()
        .trim_end_matches('%')
        .parse()
        .unwrap();
    assert!(hit > 70.0, "{line}");
    // The same rays cast in batches (`closest_hits`, one at a time on a hierarchy this
    // small; the command checks that they find the same hits, and fails otherwise): the
    // same hit rate.
    let batch = text
        .lines()
        .find(|l| l.starts_with("BVH, batches"))
        .expect("a line for the batches");
    assert_eq!(
        batch.split_whitespace().nth(3),
        line.split_whitespace().nth(3),
        "{batch}"
    );
    assert!(text.lines().any(|l| l.starts_with("hierarchy: ")), "{text}");
    // Any-hit queries that stop just short of each ray's closest hit: the point hit is
    // visible from the ray's origin, so (but for rays through an edge where two walls meet
    // at the same distance) nothing blocks them.
    let bounded = text
        .lines()
        .find(|l| l.starts_with("BVH any, bounded"))
        .expect("a line for bounded any-hit queries");
    let blocked: f64 = bounded
        .split_whitespace()
        .nth(4)
        .unwrap()
        .trim_end_matches('%')
        .parse()
        .unwrap();
    assert!(blocked < 0.1, "{bounded}");
    // The Cornell box's walls are grids met whole; the same rays cast against every patch's
    // own triangles hit the same patches, but for ties (coincident faces, none here) and
    // rays within rounding of a patch's edge: a band of a ray offset (2 × 10⁻³ here) about
    // edges some 50 apart, 10⁻⁴ of the rays, 2 of these 20,000.
    let hierarchy = text.lines().find(|l| l.starts_with("hierarchy: ")).unwrap();
    let whole: usize = hierarchy
        .split(" pieces met whole")
        .next()
        .and_then(|s| s.rsplit('(').next())
        .and_then(|s| s.parse().ok())
        .expect("pieces met whole");
    assert!(whole >= 10, "{hierarchy}");
    assert!(
        text.lines().any(|l| l.starts_with("BVH of patches ")),
        "{text}"
    );
    let cmp = text
        .lines()
        .find(|l| l.starts_with("BVH of patches / radiosity BVH"))
        .expect("the comparison with every patch's triangles");
    assert!(hits_differing(cmp) <= 20, "{cmp}");
}

/// The count of rays in a `bench --rays` comparison line `… hits differ on K of N rays …`.
fn hits_differing(line: &str) -> usize {
    line.split("differ on ")
        .nth(1)
        .and_then(|s| s.split_whitespace().next())
        .and_then(|s| s.parse().ok())
        .unwrap_or_else(|| panic!("no count of differing hits in {line:?}"))
}

/// With the `embree` feature, Embree casts the same rays and hits the same patches (rounding
/// may part them on a few rays that graze an edge: under 0.01 %).
#[cfg(feature = "embree")]
#[test]
fn embree_agrees_with_the_bvh_hit_for_hit() {
    let dir = scratch("bench-embree");
    let out = run(
        &[
            "bench", "--rays", "cornell", "--rays", "200000", "--runs", "1",
        ],
        &dir,
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    let line = text
        .lines()
        .find(|l| l.starts_with("Embree 3 / radiosity BVH") && l.contains("hits differ on"))
        .expect("a comparison line");
    assert!(hits_differing(line) as f64 / 200_000.0 < 1e-4, "{line}");
}

/// Without the `embree` feature, asking for Embree is a one-line error that says how to get it.
#[cfg(not(feature = "embree"))]
#[test]
fn embree_backend_needs_the_feature() {
    let dir = scratch("bench-no-embree");
    let out = run(&["bench", "--rays", "cornell", "--backend", "embree"], &dir);
    assert_fails(&out, &["--backend embree", "--features embree"], &dir, &[]);
}

/// `solve --solver hierarchical`: the leaves as CSV rows (one per leaf in the elements file),
/// the links and elements written, the furnace uniform per surface, a baked glTF and a picture
/// from the same solution.
#[test]
fn hierarchical_solve_writes_leaves_links_and_elements() {
    let dir = scratch("hierarchical");
    let out = run(
        &[
            "solve",
            "furnace",
            "--solver",
            "hierarchical",
            "--tolerance",
            "1e-7",
            "-o",
            "f.csv",
            "--links-out",
            "links.csv",
            "--elements-out",
            "elements.csv",
        ],
        &dir,
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("leaf elements") && text.contains("by hierarchical"),
        "{text}"
    );
    let rows = std::fs::read_to_string(dir.join("f.csv")).unwrap();
    let elements = std::fs::read_to_string(dir.join("elements.csv")).unwrap();
    let links = std::fs::read_to_string(dir.join("links.csv")).unwrap();
    assert!(links.starts_with(
        "receiver,source,source_kind,form_factor,uncertainty,power_r,power_g,power_b\n"
    ));
    assert!(links.lines().count() > 1000);
    let leaves = elements
        .lines()
        .skip(1)
        .filter(|l| l.split(',').nth(4) == Some("1"))
        .count();
    assert_eq!(leaves, rows.lines().count() - 1);
    // Furnace: B = E/(1 − ρ) = 2 (green); each surface's area mean within 0.5 %.
    let mut per = std::collections::HashMap::<String, (f64, f64)>::new();
    let header: Vec<&str> = rows.lines().next().unwrap().split(',').collect();
    let col = |n: &str| header.iter().position(|h| *h == n).unwrap();
    let (s, a, g) = (col("surface"), col("area"), col("radiosity_g"));
    for line in rows.lines().skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        let area: f64 = f[a].parse().unwrap();
        let e = per.entry(f[s].to_string()).or_default();
        e.0 += area * f[g].parse::<f64>().unwrap();
        e.1 += area;
    }
    for (k, (b, area)) in per {
        assert!(
            (b / area / 2.0 - 1.0).abs() < 0.005,
            "surface {k}: {}",
            b / area
        );
    }
    // Baked and rendered from the hierarchical leaves.
    for args in [
        &[
            "solve",
            "cornell",
            "--solver",
            "hierarchical",
            "-o",
            "c.glb",
        ][..],
        &[
            "render",
            "cornell",
            "--solver",
            "hierarchical",
            "--width",
            "64",
            "--height",
            "64",
            "-o",
            "c.png",
        ][..],
    ] {
        let out = run(args, &dir);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    assert!(std::fs::metadata(dir.join("c.glb")).unwrap().len() > 10_000);
    assert!(std::fs::metadata(dir.join("c.png")).unwrap().len() > 1_000);
}

/// Impossible hierarchical options fail on one line, naming the option, writing nothing.
#[test]
fn hierarchical_rejects_bad_options() {
    let dir = scratch("hierarchical-bad");
    for (args, needle) in [
        (
            &[
                "solve",
                "cornell",
                "--solver",
                "hierarchical",
                "--link-error",
                "0",
                "-o",
                "x.csv",
            ][..],
            "--link-error",
        ),
        (
            &[
                "solve",
                "cornell",
                "--solver",
                "hierarchical",
                "--min-area",
                "0",
                "-o",
                "x.csv",
            ][..],
            "--min-area",
        ),
        (
            &[
                "solve",
                "cornell",
                "--solver",
                "hierarchical",
                "--visibility-rays",
                "0",
                "-o",
                "x.csv",
            ][..],
            "--visibility-rays",
        ),
        (
            &["solve", "cornell", "--links-out", "l.csv", "-o", "x.csv"][..],
            "--links-out",
        ),
        (
            &[
                "solve",
                "cornell",
                "--solver",
                "hierarchical",
                "--trace",
                "t.csv",
                "-o",
                "x.csv",
            ][..],
            "--trace",
        ),
    ] {
        let out = run(args, &dir);
        assert_fails(&out, &[needle], &dir, &[]);
    }
}

/// `mpirun -np K radiosity ARGS` in `dir` (as root too; oversubscribed, one thread a rank).
#[cfg(feature = "mpi")]
fn mpirun(k: usize, args: &[&str], dir: &Path) -> Output {
    Command::new("mpirun")
        .args([
            "--allow-run-as-root",
            "--oversubscribe",
            "-np",
            &k.to_string(),
        ])
        .arg(env!("CARGO_BIN_EXE_radiosity"))
        .args(args)
        .args(["--threads", "1"])
        .current_dir(dir)
        .output()
        .expect("mpirun (Open MPI's openmpi-bin) on the PATH")
}

/// Issue 21: every distributed method gives the same bytes on 1, 2 and 4 ranks, on the Cornell
/// box, the city and the hospital; the stochastic methods and the view factors also equal a run
/// without mpirun byte for byte.
#[test]
#[cfg_attr(
    not(feature = "mpi"),
    ignore = "needs the mpi feature (cargo test --features mpi) and Open MPI's mpirun"
)]
fn mpi_ranks_give_identical_bytes() {
    #[cfg(feature = "mpi")]
    {
        let dir = scratch("mpi-bytes");
        let hospital = shared_renderpark("hospital/hosp.mgf");
        let hospital = hospital.to_str().unwrap();
        write(
            &dir,
            "bc.csv",
            "name,emissivity,temperature,flux\nzeq0,0.8,300,\nxeq0,0.5,400,\nyeq0,0.3,,\nzeq1,0.9,600,\nxeq1,0.7,,\nyeq1,0.6,800,\n",
        );
        let cube = shared_view3d("cube.vs3");
        let cube = cube.to_str().unwrap();
        let jobs: Vec<(&str, Vec<&str>)> = vec![
            (
                "cornell-jacobi.csv",
                vec![
                    "solve",
                    "cornell",
                    "--solver",
                    "jacobi",
                    "--patches",
                    "1500",
                    "--tolerance",
                    "1e-4",
                ],
            ),
            (
                "cornell-sj.csv",
                vec![
                    "solve",
                    "cornell",
                    "--solver",
                    "stochastic-jacobi",
                    "--patches",
                    "1500",
                ],
            ),
            (
                "city-jacobi.csv",
                vec![
                    "solve",
                    "city",
                    "--solver",
                    "jacobi",
                    "--max-edge",
                    "1e9",
                    "--rays",
                    "64",
                ],
            ),
            (
                "city-sj.csv",
                vec![
                    "solve",
                    "city",
                    "--solver",
                    "stochastic-jacobi",
                    "--max-edge",
                    "1e9",
                ],
            ),
            (
                "hospital-jacobi.csv",
                vec![
                    "solve",
                    hospital,
                    "--one-sided",
                    "--solver",
                    "jacobi",
                    "--patches",
                    "8000",
                    "--rays",
                    "64",
                ],
            ),
            (
                "hospital-sj.csv",
                vec![
                    "solve",
                    hospital,
                    "--one-sided",
                    "--solver",
                    "stochastic-jacobi",
                    "--patches",
                    "8000",
                ],
            ),
            (
                "cornell.mtx",
                vec![
                    "form-factors",
                    "cornell",
                    "--patches",
                    "400",
                    "--rays",
                    "4000",
                ],
            ),
            (
                "city.mtx",
                vec!["form-factors", "city", "--faces", "--rays", "200"],
            ),
            (
                "hospital.mtx",
                vec![
                    "form-factors",
                    hospital,
                    "--patches",
                    "3000",
                    "--rays",
                    "300",
                ],
            ),
            (
                "cube.csv",
                vec![
                    "thermal",
                    cube,
                    "--boundary",
                    "bc.csv",
                    "--patches",
                    "150",
                    "--rays",
                    "3000",
                ],
            ),
            (
                "cube-jacobi.csv",
                vec![
                    "thermal",
                    cube,
                    "--boundary",
                    "bc.csv",
                    "--patches",
                    "150",
                    "--rays",
                    "3000",
                    "--linear-solver",
                    "jacobi",
                ],
            ),
        ];
        for (out, args) in &jobs {
            let mut bytes = Vec::new();
            for k in [1, 2, 4] {
                let name = format!("{k}-{out}");
                let mut all = args.clone();
                all.extend(["-o", &name]);
                let o = mpirun(k, &all, &dir);
                assert!(
                    o.status.success(),
                    "{k} ranks, {all:?}: {}",
                    String::from_utf8_lossy(&o.stderr)
                );
                let text = String::from_utf8_lossy(&o.stdout);
                assert!(
                    text.contains(&format!("ranks       {k} (MPI")),
                    "no ranks line: {text}"
                );
                bytes.push(std::fs::read(dir.join(&name)).unwrap());
            }
            assert!(bytes[0] == bytes[1], "{out}: 1 and 2 ranks differ");
            assert!(bytes[0] == bytes[2], "{out}: 1 and 4 ranks differ");
            // Without mpirun: the same bytes, but for Jacobi (which runs whole sweeps over
            // ranks, and row by row alone); thermal's default alone is LU, so the plain run is
            // given the BiCGSTAB that mpirun defaults to.
            if !out.contains("jacobi.csv") {
                let mut all = args.clone();
                let name = format!("serial-{out}");
                all.extend(["-o", &name, "--threads", "1"]);
                if *out == "cube.csv" {
                    all.extend(["--linear-solver", "iterative"]);
                }
                let o = run(&all, &dir);
                assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
                assert!(
                    std::fs::read(dir.join(&name)).unwrap() == bytes[0],
                    "{out}: mpirun differs from a plain run"
                );
            }
        }
    }
}

/// Issue 21: the sequential methods and the commands that do not distribute refuse clearly
/// over several ranks, naming the distributed alternatives, and write nothing.
#[test]
#[cfg_attr(
    not(feature = "mpi"),
    ignore = "needs the mpi feature (cargo test --features mpi) and Open MPI's mpirun"
)]
fn mpi_refuses_what_does_not_distribute() {
    #[cfg(feature = "mpi")]
    {
        let dir = scratch("mpi-refuse");
        for (args, needles) in [
            (
                vec!["solve", "cornell", "--solver", "progressive", "-o", "x.csv"],
                vec!["--solver progressive", "stochastic-jacobi"],
            ),
            (
                vec!["solve", "cornell", "--solver", "southwell", "-o", "x.csv"],
                vec!["southwell", "jacobi"],
            ),
            (
                vec![
                    "solve",
                    "cornell",
                    "--solver",
                    "hierarchical",
                    "-o",
                    "x.csv",
                ],
                vec!["hierarchical", "stochastic-jacobi"],
            ),
            (
                vec!["render", "cornell", "-o", "x.png"],
                vec!["render", "without mpirun"],
            ),
            (vec!["bench", "--rays", "cornell"], vec!["bench", "--ranks"]),
        ] {
            let o = mpirun(2, &args, &dir);
            let err = String::from_utf8_lossy(&o.stderr);
            assert!(!o.status.success(), "{args:?} succeeded");
            let lines: Vec<&str> = err
                .lines()
                .filter(|l| l.starts_with("radiosity: error"))
                .collect();
            assert_eq!(lines.len(), 1, "{args:?}: {err}");
            for n in needles {
                assert!(lines[0].contains(n), "'{}' lacks '{n}'", lines[0]);
            }
            assert!(!dir.join("x.csv").exists() && !dir.join("x.png").exists());
        }
    }
}

/// A binary built without the feature, launched as one of several ranks, says so instead of
/// running the whole job on every rank.
#[test]
#[cfg_attr(feature = "mpi", ignore = "checks the build without the mpi feature")]
fn launched_by_mpirun_without_the_feature_is_refused() {
    let dir = scratch("mpi-absent");
    let o = bin()
        .args(["solve", "cornell", "-o", "x.csv"])
        .env("OMPI_COMM_WORLD_SIZE", "4")
        .current_dir(&dir)
        .output()
        .unwrap();
    assert_fails(&o, &["4 MPI ranks", "--features mpi"], &dir, &[]);
    // A plain command inside a batch job (Slurm's variables, no MPI launcher's) runs.
    let o = bin()
        .args(["solve", "cornell", "--patches", "200", "-o", "x.csv"])
        .env("SLURM_NTASKS", "16")
        .current_dir(&dir)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}
