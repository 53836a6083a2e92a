//! `radiosity solve-system`: a system given as a Matrix Market form-factor matrix and a patch
//! CSV, solved by every method against Cramer's rule, traced, refused when malformed, and
//! stopped by the iteration cap when it converges too slowly.

use crate::common::*;

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
        run_ok(
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
        let b = read(&dir, "B.csv");
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
        let trace = read(&dir, "trace.csv");
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
    run_ok(
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
    let b = read(&dir, "B.csv");
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
        fails(
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
            needles,
            &["F.mtx", "patches.csv"],
        );
    }
    let dir = scratch("sysbadsolver");
    write(&dir, "F.mtx", MTX);
    write(&dir, "patches.csv", PATCHES);
    fails(
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
        &["--solver magic", "progressive"],
        &["F.mtx", "patches.csv"],
    );
    fails(
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
        &["missing.mtx"],
        &["F.mtx", "patches.csv"],
    );
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
    let err = stderr(&out);
    assert!(!out.status.success());
    assert_ne!(out.status.code(), Some(101), "panicked: {err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.contains("b.csv") && err.contains("default cap of 20000 iterations"),
        "{err}"
    );
    assert!(t.elapsed().as_secs_f64() < 10.0);
    let text = stdout(&out);
    assert!(
        text.contains("stopped after 20000 iterations without converging"),
        "{text}"
    );
}
