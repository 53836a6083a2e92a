//! `radiosity form-factors --threshold`: truncated factors rebalanced for reciprocity and
//! closure, through Matrix Market and View3D output; and the command's outputs (issue 56):
//! never over the scene or each other, all written or none, the View3D table streamed without
//! an N × N copy; View3D quads with a repeated corner read as triangles by every command.

use crate::common::*;
use std::collections::HashMap;
use std::path::Path;

/// `radiosity form-factors ARGS` in `dir`, which must succeed; its stdout.
fn form_factors(dir: &Path, args: &[&str]) -> String {
    let mut all = vec!["form-factors"];
    all.extend_from_slice(args);
    run_ok(&all, dir)
}

/// A Matrix Market file's entries, 0-based.
fn read_mtx0(dir: &Path, name: &str) -> (usize, HashMap<(usize, usize), f64>) {
    let (n, e) = read_mtx(&dir.join(name));
    (
        n,
        e.into_iter().map(|(i, j, v)| ((i - 1, j - 1), v)).collect(),
    )
}

fn row_sums(n: usize, f: &HashMap<(usize, usize), f64>) -> Vec<f64> {
    let mut s = vec![0.0; n];
    for (&(i, _), v) in f {
        s[i] += v;
    }
    s
}

/// The prism x, y ≥ 0, x + y ≤ 1, 0 ≤ z ≤ 1 as View3D input, its two triangular ends given as
/// quads with a repeated corner (lines 10 and 11), facing inwards: a closed enclosure.
const PRISM: &str = "T prism, triangle ends given as quads
C encl=1
F 3
V 1 0 0 0
V 2 1 0 0
V 3 0 1 0
V 4 0 0 1
V 5 1 0 1
V 6 0 1 1
S 1 1 2 3 3 0 0 0.5 bottom
S 2 4 6 5 5 0 0 0.5 top
S 3 1 4 5 2 0 0 0.5 side-y
S 4 1 3 6 4 0 0 0.5 side-x
S 5 2 5 6 3 0 0 0.5 slant
End of data
";

/// The rows of View3D's text output, with the areas.
fn read_view3d(text: &str) -> (Vec<f64>, Vec<Vec<f64>>) {
    let lines: Vec<&str> = text.lines().collect();
    let n: usize = lines[0].split_whitespace().nth(5).unwrap().parse().unwrap();
    let nums = |l: &str| -> Vec<f64> { l.split_whitespace().map(|x| x.parse().unwrap()).collect() };
    (
        nums(lines[1]),
        lines[2..2 + n].iter().map(|l| nums(l)).collect(),
    )
}

/// The Cornell box's Monte Carlo factors truncated at 10⁻³: the dropped entries are reported,
/// every row keeps its sum to 1e-6 (the box's rows, open where the light's rim and the gaps
/// let energy out, keep their own sums), every pair is reciprocal to 1e-9 relative (the areas
/// from --patches-out), and every entry left is ≥ T or the partner of one that is. A
/// threshold of 0 writes the very bytes of the untruncated run.
#[test]
fn truncated_factors_keep_rows_and_reciprocity() {
    let dir = scratch("ff-threshold");
    let common = ["cornell", "--patches", "150", "--rays", "20000"];
    let run = |out: &str, extra: &[&str]| {
        let mut args = common.to_vec();
        args.extend_from_slice(&["-o", out]);
        args.extend_from_slice(extra);
        form_factors(&dir, &args)
    };
    run("F.mtx", &["--patches-out", "p.csv"]);
    let text = run("T.mtx", &["--threshold", "1e-3"]);
    let report = text.lines().find(|l| l.starts_with("threshold")).unwrap();
    assert!(
        report.contains("dropped") && report.contains("of the exchange area"),
        "{report}"
    );
    let rebalanced = text.lines().find(|l| l.starts_with("rebalanced")).unwrap();
    assert!(rebalanced.contains("worst row-sum error"), "{rebalanced}");

    let (n, f) = read_mtx0(&dir, "F.mtx");
    let (m, t) = read_mtx0(&dir, "T.mtx");
    assert_eq!(n, m);
    assert!(t.len() < f.len(), "{} of {}", t.len(), f.len());
    let (header, rows) = read_csv(&dir.join("p.csv"));
    let a = column(&header, "area");
    let area: Vec<f64> = rows.iter().map(|r| r[a].parse().unwrap()).collect();
    assert_eq!(area.len(), n);
    let (before, after) = (row_sums(n, &f), row_sums(n, &t));
    for i in 0..n {
        assert!(
            (before[i] - after[i]).abs() < 1e-6,
            "row {i}: {} vs {}",
            after[i],
            before[i]
        );
    }
    for (&(i, j), &v) in &t {
        let back = t.get(&(j, i)).copied().unwrap_or(0.0);
        let (x, y) = (area[i] * v, area[j] * back);
        assert!((x - y).abs() <= 1e-9 * x.max(y), "({i}, {j}): {x} vs {y}");
        let (fij, fji) = (
            f.get(&(i, j)).copied().unwrap_or(0.0),
            f.get(&(j, i)).copied().unwrap_or(0.0),
        );
        assert!(fij.max(fji) >= 1e-3, "({i}, {j}) kept below T");
    }
    // T = 0 drops nothing and changes nothing.
    let zero = run("Z.mtx", &["--threshold", "0"]);
    assert!(zero.contains("no entry below it"), "{zero}");
    assert_eq!(read_bytes(&dir, "Z.mtx"), read_bytes(&dir, "F.mtx"));
}

/// View3D output truncated: rows of the closed prism still sum to 1 and pairs are reciprocal
/// to View3D's six printed decimals; the triangle ends (quads with a repeated corner) have the
/// triangle's area, with a warning naming the file and line.
#[test]
fn truncated_view3d_output_closes() {
    let dir = scratch("ff-threshold-view3d");
    write(&dir, "prism.vs3", PRISM);
    let out = run(
        &[
            "form-factors",
            "prism.vs3",
            "--format",
            "view3d",
            "-o",
            "f.vf",
            "--threshold",
            "0.13",
        ],
        &dir,
    );
    let err = stderr(&out);
    assert!(
        err.contains("prism.vs3:10: surface 1 repeats a corner; read as the triangle"),
        "{err}"
    );
    assert!(err.contains("prism.vs3:11: surface 2"), "{err}");
    let text = succeed(&out);
    assert!(text.contains("dropped 2 of 20 entries"), "{text}");
    let (area, f) = read_view3d(&read(&dir, "f.vf"));
    // The slant's area √2, printed as C's %g (six digits).
    assert_eq!(area[..4], [0.5, 0.5, 1.0, 1.0]);
    assert!((area[4] - std::f64::consts::SQRT_2).abs() < 5e-6);
    // The two ends see each other with 0.115 < T: gone both ways.
    assert_eq!((f[0][1], f[1][0]), (0.0, 0.0));
    for i in 0..5 {
        let s: f64 = f[i].iter().sum();
        assert!((s - 1.0).abs() <= 5.0 * 5e-7, "row {i} sums to {s}");
        for j in 0..5 {
            let (x, y) = (area[i] * f[i][j], area[j] * f[j][i]);
            // Six decimals of F, and the slant's area to six digits.
            assert!((x - y).abs() <= 2e-6, "({i}, {j}): {x} vs {y}");
        }
    }
}

/// A threshold that leaves a row nothing is refused in one line naming the row and the
/// threshold that would keep it, and writes nothing; so are thresholds that are no number.
#[test]
fn impossible_thresholds_are_refused() {
    let dir = scratch("ff-threshold-bad");
    write(&dir, "prism.vs3", PRISM);
    let base = [
        "form-factors",
        "prism.vs3",
        "--format",
        "view3d",
        "-o",
        "f.vf",
    ];
    let with = |t: &'static str| {
        let mut v = base.to_vec();
        v.extend_from_slice(&["--threshold", t]);
        v
    };
    fails(
        &with("0.9"),
        &dir,
        &[
            "--threshold 0.9",
            "row 1 would keep no entry: it sums to",
            "too fine",
        ],
        &["prism.vs3"],
    );
    for t in ["-0.1", "NaN", "inf", "1.5"] {
        let mut args = base.to_vec();
        let flag = format!("--threshold={t}");
        args.push(&flag);
        fails(
            &args,
            &dir,
            &["--threshold", "a number in [0, 1]"],
            &["prism.vs3"],
        );
    }
}

/// `-o` naming the scene is refused before any work, naming both, even when --format skips
/// the extension check; the scene is left as it was. So is --patches-out equal to -o.
#[test]
fn outputs_never_overwrite_the_scene_or_each_other() {
    let dir = scratch("ff-over-input");
    write(&dir, "prism.vs3", PRISM);
    fails(
        &[
            "form-factors",
            "prism.vs3",
            "--format",
            "view3d",
            "-o",
            "prism.vs3",
        ],
        &dir,
        &["-o prism.vs3", "is the input scene prism.vs3"],
        &["prism.vs3"],
    );
    fails(
        &[
            "form-factors",
            "prism.vs3",
            "--format",
            "mtx",
            "-o",
            "./prism.vs3",
        ],
        &dir,
        &["-o ./prism.vs3", "is the input scene prism.vs3"],
        &["prism.vs3"],
    );
    assert_eq!(read(&dir, "prism.vs3"), PRISM);
    fails(
        &[
            "form-factors",
            "cornell",
            "--patches",
            "20",
            "--rays",
            "1000",
            "-o",
            "a.csv",
            "--format",
            "mtx",
            "--patches-out",
            "a.csv",
        ],
        &dir,
        &["--patches-out a.csv", "is also -o a.csv"],
        &["prism.vs3"],
    );
}

/// When --patches-out cannot be written, -o is not left behind either: a folder where no file
/// can be made (/proc/self) fails while staging, /dev/full at the commit (a device is written
/// first, so that the files are not yet in place).
#[cfg(target_os = "linux")]
#[test]
fn no_matrix_without_its_patches() {
    let dir = scratch("ff-all-or-none");
    for bad in ["/proc/self/p.csv", "/dev/full"] {
        let out = run(
            &[
                "form-factors",
                "cornell",
                "--patches",
                "20",
                "--rays",
                "1000",
                "-o",
                "F.mtx",
                "--patches-out",
                bad,
            ],
            &dir,
        );
        assert_fails(&out, &[bad], &dir, &[]);
    }
}

/// The View3D table is streamed from the sparse rows: at N = 2,000 faces, whose dense f64
/// table alone would take 30.5 MiB, the heap's peak (the command's own counting allocator)
/// stays under half of that. The faces: two facing 40 × 25 grids, 64 rays a row, stored
/// sparse while computing (`--storage auto` holds N ≤ 4,096 rows dense, 15 MiB here).
#[test]
fn view3d_output_holds_no_dense_table() {
    let dir = scratch("ff-view3d-stream");
    let (nx, ny) = (40, 25);
    let mut obj = String::new();
    for (z, flip) in [(0.0, false), (0.5, true)] {
        for a in 0..nx {
            for b in 0..ny {
                let (x, y) = (a as f64 / nx as f64, b as f64 / ny as f64);
                let (dx, dy) = (1.0 / nx as f64, 1.0 / ny as f64);
                let mut c = [(x, y), (x + dx, y), (x + dx, y + dy), (x, y + dy)];
                if flip {
                    c.reverse();
                }
                for (px, py) in c {
                    obj += &format!("v {px} {py} {z}\n");
                }
                obj += "f -4 -3 -2 -1\n";
            }
        }
    }
    write(&dir, "plates.obj", &obj);
    let text = form_factors(
        &dir,
        &[
            "plates.obj",
            "--format",
            "view3d",
            "--method",
            "monte-carlo",
            "--rays",
            "64",
            "--storage",
            "sparse",
            "-o",
            "f.vf",
        ],
    );
    let n = 2 * nx * ny;
    let peak: u64 = text
        .lines()
        .find_map(|l| l.strip_prefix("memory      heap peak "))
        .and_then(|l| l.split_whitespace().next())
        .unwrap()
        .parse()
        .unwrap();
    let dense = (8 * n * n) as u64 >> 20;
    assert!(
        peak * 2 < dense,
        "heap peak {peak} MiB, a dense table {dense} MiB"
    );
    let (area, f) = read_view3d(&read(&dir, "f.vf"));
    assert_eq!((area.len(), f.len(), f[0].len()), (n, n, n));
}

/// A View3D triangle given as a quad (a repeated corner) is read as that triangle by
/// `thermal` as by `form-factors` (it was "patch has area 0"): in the closed prism, black,
/// the bottom triangle at 300 K and every other surface at 0 K, the bottom loses σT⁴ times
/// its area, 1/2, whatever the factors (its row sums to 1).
#[test]
fn thermal_reads_a_quad_with_a_repeated_corner_as_its_triangle() {
    let dir = scratch("thermal-repeated-corner");
    write(&dir, "prism.vs3", PRISM);
    write(
        &dir,
        "bc.csv",
        "name,emissivity,temperature,flux\nbottom,1,300,\ntop,1,0,\nside-y,1,0,\nside-x,1,0,\nslant,1,0,\n",
    );
    let out = run(
        &[
            "thermal",
            "prism.vs3",
            "--boundary",
            "bc.csv",
            "--out",
            "s.csv",
        ],
        &dir,
    );
    let err = stderr(&out);
    succeed(&out);
    assert!(
        err.contains("prism.vs3:10: surface 1 repeats a corner; read as the triangle"),
        "{err}"
    );
    let (header, rows) = read_csv(&dir.join("s.csv"));
    let bottom = rows.iter().find(|r| r[0] == "bottom").unwrap();
    let area: f64 = bottom[column(&header, "area")].parse().unwrap();
    let power: f64 = bottom[column(&header, "power")].parse().unwrap();
    assert!((area - 0.5).abs() < 1e-6, "{area}");
    let expected = 5.670_374_419e-8 * 300f64.powi(4) * 0.5;
    assert!(
        (power - expected).abs() < 1e-6 * expected,
        "{power} vs {expected}"
    );
}
