//! `radiosity-bench view3d`: side by side with NIST View3D, built from its source. The end-to-end
//! run needs that source (`VIEW3D_SOURCE`: a checkout of jasondegraw/View3D) and a C compiler;
//! what it refuses needs neither.

use crate::common::*;
use std::path::PathBuf;

/// A missing source folder, or one that is not View3D's, is one line and leaves nothing.
#[test]
fn bench_view3d_refuses_a_missing_source_or_compiler() {
    let dir = scratch("bench-view3d-refuse");
    fails(
        &["view3d", "--source", "no-such-dir", "--out", "o"],
        &dir,
        &["no-such-dir: no View3D source folder"],
        &[],
    );
    std::fs::create_dir_all(dir.join("empty")).unwrap();
    fails(
        &["view3d", "--source", "empty", "--out", "o"],
        &dir,
        &["empty: no View3D source here"],
        &["empty"],
    );
    // A source whose CMakeLists names a file that is not there.
    std::fs::create_dir_all(dir.join("fake/src")).unwrap();
    write(
        &dir,
        "fake/src/CMakeLists.txt",
        "set(SRCS v3main.c\n  gone.c)\n",
    );
    write(&dir, "fake/src/v3main.c", "int main(void) { return 0; }\n");
    fails(
        &["view3d", "--source", "fake", "--out", "o"],
        &dir,
        &["gone.c: listed in", "but missing"],
        &["fake", "empty"],
    );
    // No compiler: named in one line, and the folder this run made is gone again.
    write(&dir, "fake/src/CMakeLists.txt", "set(SRCS v3main.c)\n");
    let out = bin()
        .args(["view3d", "--source", "fake", "--out", "o", "--sizes", "484"])
        .env("CC", "/no/such/cc")
        .current_dir(&dir)
        .output()
        .unwrap();
    assert_fails(
        &out,
        &["/no/such/cc: no C compiler"],
        &dir,
        &["fake", "empty"],
    );
    fails(
        &["view3d", "--source", "fake", "--runs", "0"],
        &dir,
        &["--runs 0: must be positive"],
        &["fake", "empty"],
    );
}

/// Where View3D's source is: `$VIEW3D_SOURCE`.
fn view3d_source() -> PathBuf {
    std::env::var_os("VIEW3D_SOURCE")
        .expect("set VIEW3D_SOURCE to a checkout of https://github.com/jasondegraw/View3D")
        .into()
}

/// The smallest canyon (484 facets) by both tools. View3D converges each factor to its
/// `eps` = 10⁻⁴ (relative; NISTIR 6925), ours to 10⁻⁵: the mean |ΔF| over all N² entries
/// must be well under 10⁻⁵ (most entries are 0 in both or far-field pairs both integrate to
/// 10⁻⁶) and the rows within 2·10⁻⁴ on average (issue 60's target; measured 7.7·10⁻⁵). Closed
/// form: the roofs of the two 30 m buildings are above everything else, so every one of their
/// facets sees only sky (sky view 1, printed `%.6f`) in both. And the worst |ΔF| is a pair
/// of perpendicular squares touching at one corner (facet 4, the ground's corner square at
/// the first building, and facet 165, the foot of that building's −x wall): by view-factor
/// algebra on Howell's C-14 (common edge), F = F(l = 2) − F(l = 1) = 0.0405922 for any size,
/// which ours gives to its printed digits and View3D 7.8·10⁻⁵ low.
#[test]
#[ignore = "needs View3D's source: set VIEW3D_SOURCE to a checkout of jasondegraw/View3D, and a C compiler"]
fn bench_view3d_agrees_with_view3d_at_484_facets() {
    let dir = scratch("bench-view3d");
    let src = view3d_source();
    let text = run_ok(
        &[
            "view3d",
            "--source",
            src.to_str().unwrap(),
            "--sizes",
            "484",
            "--out",
            "o",
            "--keep",
        ],
        &dir,
    );
    let row = |tool: &str| -> Vec<String> {
        text.lines()
            .map(|l| l.split_whitespace().map(String::from).collect::<Vec<_>>())
            .find(|w| w.len() == 10 && w[0] == "484" && w[1] == tool)
            .unwrap_or_else(|| panic!("no {tool} row in:\n{text}"))
    };
    let (ours, theirs) = (row("ours"), row("View3D"));
    let num = |s: &str| s.parse::<f64>().unwrap();
    for r in [&ours, &theirs] {
        assert!(
            num(&r[2]) > 0.0 && num(&r[3]) > 0.0 && num(&r[4]) > 0.0,
            "{text}"
        );
    }
    assert!(num(&ours[5]) < 1e-5, "mean |ΔF| {}", ours[5]);
    assert!(num(&ours[7]) <= 2e-4, "mean |Δ row sum| {}", ours[7]);
    assert!((num(&ours[9]) - num(&theirs[9])).abs() <= 2e-4, "{text}");
    let (header, rows) = read_csv(&dir.join("o/skyview-484.csv"));
    assert_eq!(header, ["facet", "sky_view_ours", "sky_view_view3d"]);
    assert_eq!(rows.len(), 484);
    let scene = read(&dir, "o/canyon-484.vs3");
    let top: Vec<usize> = scene
        .lines()
        .filter(|l| l.starts_with("S "))
        .filter(|l| {
            // A facet all of whose corners are 30 m up.
            let w: Vec<&str> = l.split_whitespace().collect();
            w[2..6].iter().all(|v| {
                let k: usize = v.parse().unwrap();
                let line = scene
                    .lines()
                    .find(|l| l.starts_with(&format!("V {k} ")))
                    .unwrap();
                line.split_whitespace().nth(4) == Some("30.000000")
            })
        })
        .map(|l| l.split_whitespace().nth(1).unwrap().parse().unwrap())
        .collect();
    assert_eq!(top.len(), 2 * 4, "two 30 m roofs of 2 × 2 facets");
    for k in top {
        let r = &rows[k - 1];
        assert_eq!(
            (r[1].as_str(), r[2].as_str()),
            ("1.000000", "1.000000"),
            "facet {k}"
        );
    }
    let entry = |file: &str| -> f64 {
        let text = read(&dir, file);
        let row: Vec<&str> = text
            .lines()
            .nth(1 + 4)
            .unwrap()
            .split_whitespace()
            .collect();
        row[164].parse().unwrap()
    };
    let (o, t) = (entry("o/ours-484.vf"), entry("o/view3d-484.vf"));
    assert!((o - 0.040_592_2).abs() < 1e-6, "ours F[4][165] = {o}");
    assert!(text.contains("worst |ΔF| at F[4][165]"), "{text}");
    assert_eq!(format!("{:.2e}", (o - t).abs()), ours[6], "{text}");
    for r in &rows {
        let (a, b) = (num(&r[1]), num(&r[2]));
        assert!((0.0..=1.0).contains(&b) && (a - b).abs() < 1e-3, "{r:?}");
    }
}
