//! `radiosity experiment`: the paper's convergence and complexity experiments in their quick
//! form, their tables and plots, and impossible options.

use crate::common::*;
use std::path::PathBuf;

/// Run `radiosity experiment KIND --quick` in a fresh folder; the results' folder.
fn quick_experiment(kind: &str) -> PathBuf {
    let dir = scratch(kind);
    run_ok(&["experiment", kind, "--quick", "--out", "res"], &dir);
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
    let md = read(&res, "convergence.md");
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
        fails(args, &dir, &[needle], &[]);
    }
}
