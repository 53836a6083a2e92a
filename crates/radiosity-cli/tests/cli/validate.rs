//! `radiosity validate cie171`: one case's table and CSV, and impossible options.

use crate::common::*;

/// `validate cie171 --case 5.2 --csv`: the table printed with its verdicts, and the CSV with
/// the header the docs give, one row per point of case 5.2 (ten floor points, six wall
/// points), its numbers consistent: each deviation is 100 (ours − reference) / reference, and
/// the reference under the source is I₀ / h² = 1000 / 9 lux.
#[test]
fn validate_cie171_one_case_with_csv() {
    let dir = scratch("validate-5.2");
    let out = run_ok(
        &["validate", "cie171", "--case", "5.2", "--csv", "table.csv"],
        &dir,
    );
    assert!(out.contains("test case 5.2"), "{out}");
    assert!(out.contains("CIE criterion"), "{out}");
    assert!(out.contains("target (1 % every point): pass"), "{out}");
    assert!(!out.contains("test case 5.3"), "{out}");
    let (header, rows) = read_csv(&dir.join("table.csv"));
    assert_eq!(
        header,
        [
            "case",
            "point",
            "x",
            "y",
            "z",
            "reference",
            "ours",
            "deviation_percent"
        ]
    );
    assert_eq!(rows.len(), 16);
    let num = |s: &str| -> f64 { s.parse().unwrap() };
    for r in &rows {
        assert_eq!(r[0], "5.2");
        let (reference, ours, dev) = (num(&r[5]), num(&r[6]), num(&r[7]));
        assert!(reference > 0.0);
        assert!(
            (dev - 100.0 * (ours - reference) / reference).abs() < 1e-9,
            "{r:?}"
        );
        assert!(dev.abs() < 1.0, "{r:?}");
    }
    let a = &rows[0];
    assert_eq!(a[1], "A");
    assert_eq!((num(&a[2]), num(&a[3]), num(&a[4])), (2.0, 2.0, 0.0));
    assert!((num(&a[5]) - 1000.0 / 9.0).abs() < 1e-9);
}

/// An unknown case and a CSV in a missing folder: one line each, nothing written.
#[test]
fn validate_refuses_impossible_options() {
    let dir = scratch("validate-bad");
    let out = run(&["validate", "cie171", "--case", "5.5"], &dir);
    assert_fails(&out, &["--case 5.5", "unknown case", "5.8"], &dir, &[]);
    let out = run(
        &[
            "validate",
            "cie171",
            "--case",
            "5.2",
            "--csv",
            "missing/t.csv",
        ],
        &dir,
    );
    assert_fails(&out, &["missing", "does not exist"], &dir, &[]);
    let out = run(&["validate", "cie999"], &dir);
    assert_fails(&out, &["cie999"], &dir, &[]);
}
