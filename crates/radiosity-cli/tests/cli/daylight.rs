//! `radiosity lighting --sky`: daylight through a roof opening against the configuration
//! factor, glazing from the MTL file, and bad daylight input.

use crate::common::*;
use std::f64::consts::PI;
use std::path::Path;

/// A black `6 × 4 × 3` m room, its ceiling open over x 2–4, y 1.5–2.5 (four ceiling pieces
/// round the opening, facing down); with `glass`, a pane of MTL `d` = 1 − 0.8 fills it.
fn room(dir: &Path, glass: bool) {
    let mut obj = String::from("mtllib room.mtl\n");
    let mut n = 0;
    let mut quad = |obj: &mut String, m: &str, p: [[f64; 3]; 4]| {
        obj.push_str(&format!("usemtl {m}\n"));
        for v in p {
            obj.push_str(&format!("v {} {} {}\n", v[0], v[1], v[2]));
        }
        obj.push_str(&format!("f {} {} {} {}\n", n + 1, n + 2, n + 3, n + 4));
        n += 4;
    };
    let (w, d, h) = (6.0, 4.0, 3.0);
    quad(
        &mut obj,
        "black",
        [[0., 0., 0.], [w, 0., 0.], [w, d, 0.], [0., d, 0.]],
    );
    quad(
        &mut obj,
        "black",
        [[0., 0., 0.], [0., 0., h], [w, 0., h], [w, 0., 0.]],
    );
    quad(
        &mut obj,
        "black",
        [[0., d, 0.], [w, d, 0.], [w, d, h], [0., d, h]],
    );
    quad(
        &mut obj,
        "black",
        [[0., 0., 0.], [0., d, 0.], [0., d, h], [0., 0., h]],
    );
    quad(
        &mut obj,
        "black",
        [[w, 0., 0.], [w, 0., h], [w, d, h], [w, d, 0.]],
    );
    let rect =
        |a0: f64, a1: f64, b0: f64, b1: f64| [[a0, b0, h], [a0, b1, h], [a1, b1, h], [a1, b0, h]];
    quad(&mut obj, "black", rect(0., w, 0., 1.5));
    quad(&mut obj, "black", rect(0., w, 2.5, d));
    quad(&mut obj, "black", rect(0., 2., 1.5, 2.5));
    quad(&mut obj, "black", rect(4., w, 1.5, 2.5));
    if glass {
        quad(&mut obj, "pane", rect(2., 4., 1.5, 2.5));
    }
    write(dir, "room.obj", &obj);
    write(
        dir,
        "room.mtl",
        "newmtl black\nKd 0 0 0\nnewmtl pane\nKd 0 0 0\nd 0.2\n",
    );
    write(
        dir,
        "floor.pts",
        "3 2 0 0 0 1\n1 1 0 0 0 1\n5 3.5 0 0 0 1\n",
    );
}

/// The configuration factor from a point facing up to the parallel opening 3 m above it.
fn cf(px: f64, py: f64) -> f64 {
    let f = |a: f64, b: f64| {
        let (a, b) = (a / 3.0, b / 3.0);
        let (sa, sb) = ((1.0 + a * a).sqrt(), (1.0 + b * b).sqrt());
        (a / sa * (b / sa).atan() + b / sb * (a / sb).atan()) / (2.0 * PI)
    };
    let (x0, x1, y0, y1) = (2.0 - px, 4.0 - px, 1.5 - py, 2.5 - py);
    f(x1, y1) - f(x0, y1) - f(x1, y0) + f(x0, y0)
}

/// A uniform sky: the daylight factor of a floor point is 100 × its configuration factor to
/// the opening (E_h = πL), within the 65,536 stratified rays' error (well under 1 %).
#[test]
fn the_daylight_factor_under_a_roof_opening_is_the_configuration_factor() {
    let dir = scratch("daylight-roof");
    room(&dir, false);
    let out = run_ok(
        &[
            "lighting",
            "room.obj",
            "--sky",
            "uniform",
            "--grid",
            "floor.pts",
            "--out",
            "grid.csv",
            "--patches",
            "300",
            "--sky-rays",
            "65536",
            "--summary",
            "s.json",
        ],
        &dir,
    );
    assert!(out.contains("daylight factor average"), "{out}");
    let (header, rows) = read_csv(&dir.join("grid.csv"));
    assert_eq!(header.last().unwrap(), "daylight_factor");
    let (e, df) = (
        column(&header, "illuminance"),
        column(&header, "daylight_factor"),
    );
    for r in &rows {
        let v: Vec<f64> = r.iter().map(|t| t.parse().unwrap()).collect();
        let want = 100.0 * cf(v[0], v[1]);
        assert!((v[df] - want).abs() < 0.01 * want, "{r:?}: {want} %");
        assert!(
            (v[e] - 100.0 * v[df]).abs() < 1e-9 * v[e],
            "10,000 lx × DF / 100"
        );
    }
    let summary: serde_json::Value = serde_json::from_str(&read(&dir, "s.json")).unwrap();
    assert_eq!(summary["daylight"]["sky"], "uniform");
    assert!(
        summary["grids"][0]["daylight_factor"]["average"]
            .as_f64()
            .unwrap()
            > 0.0
    );
}

/// The sun straight overhead through the glazed opening (MTL `d 0.2`: τ_n = 0.8): the point
/// below it gets the normal transmittance × E_n; the sun group is its own column.
#[test]
fn the_sun_passes_an_mtl_pane_at_its_normal_transmittance() {
    let dir = scratch("daylight-pane");
    room(&dir, true);
    run_ok(
        &[
            "lighting",
            "room.obj",
            "--sky",
            "uniform",
            "--sky-illuminance",
            "0",
            "--sun",
            "90,0",
            "--sun-illuminance",
            "50000",
            "--grid",
            "floor.pts",
            "--out",
            "grid.csv",
            "--patches",
            "300",
        ],
        &dir,
    );
    let (header, rows) = read_csv(&dir.join("grid.csv"));
    let sun = column(&header, "illuminance_sun");
    let v: f64 = rows[0][sun].parse().unwrap();
    assert!((v - 0.8 * 50_000.0).abs() < 1e-3 * v, "{v}");
    let off: f64 = rows[1][sun].parse().unwrap();
    assert_eq!(off, 0.0);
}

/// Bad daylight input: one line, no output.
#[test]
fn daylight_refuses_bad_input() {
    let dir = scratch("daylight-bad");
    room(&dir, false);
    let keep = ["room.obj", "room.mtl", "floor.pts"];
    let base = [
        "lighting",
        "room.obj",
        "--grid",
        "floor.pts",
        "--out",
        "grid.csv",
    ];
    let with = |extra: &[&'static str]| -> Vec<&'static str> {
        let mut v: Vec<&str> = base.to_vec();
        v.extend_from_slice(extra);
        v
    };
    fails(&with(&["--sky", "cie-12"]), &dir, &["cie-12", "sun"], &keep);
    fails(&with(&["--sky", "cie-16"]), &dir, &["cie-16"], &keep);
    fails(
        &with(&["--sky", "uniform", "--sun", "95,0"]),
        &dir,
        &["--sun", "altitude"],
        &keep,
    );
    fails(
        &with(&["--sky", "uniform", "--sun", "30"]),
        &dir,
        &["--sun 30"],
        &keep,
    );
    fails(
        &with(&["--sky", "uniform", "--ground-reflectance", "1"]),
        &dir,
        &["ground reflectance"],
        &keep,
    );
    fails(
        &with(&["--sky", "uniform", "--glazing", "black"]),
        &dir,
        &["--glazing black"],
        &keep,
    );
    fails(
        &with(&["--sky", "uniform", "--glazing", "black=0.99"]),
        &dir,
        &["black", "0.9183"],
        &keep,
    );
    fails(
        &with(&["--sky", "uniform", "--sun", "30,0", "--sun-rays", "0"]),
        &dir,
        &["sun rays 0", "1 … 16777216"],
        &keep,
    );
    fails(
        &with(&["--sky", "uniform", "--sky-illuminance", "-5"]),
        &dir,
        &["-5"],
        &keep,
    );
}
