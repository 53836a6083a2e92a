//! `radiosity lighting`: illuminance at calculation points from luminaires placed by a
//! schedule, against the inverse-square cosine law, and its bad input.

use crate::common::*;
use std::path::Path;

/// A closed box `6 × 4 × 3` m with black surfaces (nothing interreflects).
const ROOM: &str = "mtllib room.mtl\nv 0 0 0\nv 6 0 0\nv 6 4 0\nv 0 4 0\nv 0 0 3\nv 6 0 3\nv 6 4 3\nv 0 4 3\nusemtl black\nf 1 2 3 4\nf 5 8 7 6\nf 1 5 6 2\nf 2 6 7 3\nf 3 7 8 4\nf 4 8 5 1\n";

/// An isotropic luminaire of `i0` candela, as an IES file (absolute photometry).
fn isotropic(i0: f64) -> String {
    let gammas: Vec<String> = (0..=36).map(|k| (5 * k).to_string()).collect();
    let cd = vec![i0.to_string(); 37];
    format!(
        "IESNA:LM-63-2002\nTILT=NONE\n1 -1 1 37 1 1 2 0 0 0\n1 1 0\n{}\n0\n{}\n",
        gammas.join(" "),
        cd.join(" ")
    )
}

fn room(dir: &Path, reflectance: f64) {
    write(dir, "room.obj", ROOM);
    write(
        dir,
        "room.mtl",
        &format!("newmtl black\nKd {reflectance} {reflectance} {reflectance}\n"),
    );
    std::fs::create_dir_all(dir.join("ies")).unwrap();
    write(dir, "ies/a.ies", &isotropic(800.0));
    write(dir, "ies/b.ies", &isotropic(200.0));
    write(
        dir,
        "schedule.csv",
        "name,file,x,y,z,aim_x,aim_y,aim_z,c0_x,c0_y,c0_z,multiplier,group\n\
         A,ies/a.ies,1.5,2,2.5,,,,,,,1,north\n\
         B,ies/b.ies,4.5,2,2.5,0,0,-1,1,0,0,0.5,south\n",
    );
    let mut pts = String::new();
    for i in 0..6 {
        for j in 0..4 {
            pts += &format!("{} {} 0.8 0 0 1\n", 0.5 + i as f64, 0.5 + j as f64);
        }
    }
    write(dir, "desk.pts", &pts);
}

/// The schedule's direct illuminance at the point of a grid row (x, y, z first, facing up):
/// I cos θ / d² from A (800 cd at (1.5, 2, 2.5)) and B (200 cd × 0.5 at (4.5, 2, 2.5)).
fn direct(v: &[f64]) -> f64 {
    let law = |i: f64, lx: f64| {
        let d2 = (v[0] - lx).powi(2) + (v[1] - 2.0).powi(2) + (2.5 - v[2]).powi(2);
        i * (2.5 - v[2]) / d2.sqrt() / d2
    };
    law(800.0, 1.5) + 0.5 * law(200.0, 4.5)
}

/// Black walls: every point's illuminance is the two luminaires' direct light, I cos θ / d²
/// summed (exact: the table is constant), and the group columns add up to it.
#[test]
fn lighting_matches_the_inverse_square_cosine_law() {
    let dir = scratch("lighting-law");
    room(&dir, 0.0);
    run_ok(
        &[
            "lighting",
            "room.obj",
            "--luminaires",
            "schedule.csv",
            "--grid",
            "desk.pts",
            "--out",
            "grid.csv",
            "--summary",
            "summary.json",
            "--patches",
            "500",
        ],
        &dir,
    );
    let (header, rows) = read_csv(&dir.join("grid.csv"));
    assert_eq!(
        header,
        [
            "x",
            "y",
            "z",
            "nx",
            "ny",
            "nz",
            "illuminance",
            "illuminance_north",
            "illuminance_south"
        ]
    );
    assert_eq!(rows.len(), 24);
    let e = column(&header, "illuminance");
    for r in &rows {
        let v: Vec<f64> = r.iter().map(|t| t.parse().unwrap()).collect();
        let want = direct(&v);
        assert!((v[e] - want).abs() < 1e-9 * want, "{r:?}: {want}");
        assert!((v[7] + v[8] - v[e]).abs() < 1e-9 * want);
    }
    let summary: serde_json::Value = serde_json::from_str(&read(&dir, "summary.json")).unwrap();
    assert_eq!(summary["grids"][0]["points"], 24);
    let flux = summary["luminaires"][0]["flux"].as_f64().unwrap();
    assert!((flux - 4.0 * std::f64::consts::PI * 800.0).abs() < 1e-6 * flux);
}

/// Reflecting walls add light: every point gets more than its direct illuminance.
#[test]
fn lighting_adds_the_interreflection() {
    let dir = scratch("lighting-inter");
    room(&dir, 0.6);
    run_ok(
        &[
            "lighting",
            "room.obj",
            "--luminaires",
            "schedule.csv",
            "--grid",
            "desk.pts",
            "--out",
            "grid.csv",
            "--patches",
            "800",
        ],
        &dir,
    );
    let (header, rows) = read_csv(&dir.join("grid.csv"));
    let e = column(&header, "illuminance");
    for r in &rows {
        let v: Vec<f64> = r.iter().map(|t| t.parse().unwrap()).collect();
        assert!(v[e] > 1.1 * direct(&v), "{r:?}: direct {}", direct(&v));
    }
}

/// Bad schedules, points and options: one line naming the file and line, nothing written.
#[test]
fn lighting_refuses_bad_input() {
    let dir = scratch("lighting-bad");
    room(&dir, 0.5);
    write(
        &dir,
        "bad-header.csv",
        "name,file,x,y,z\nA,ies/a.ies,1,1,1\n",
    );
    write(
        &dir,
        "bad-number.csv",
        "name,file,x,y,z,aim_x,aim_y,aim_z,c0_x,c0_y,c0_z,multiplier,group\nA,ies/a.ies,1,one,1,,,,,,,1,\n",
    );
    write(&dir, "bad.pts", "1 1 1 0 0 1\n1 1 nan 0 0 1\n");
    let base = |schedule: &str, grid: &str| {
        vec![
            "lighting".to_string(),
            "room.obj".into(),
            "--luminaires".into(),
            schedule.into(),
            "--grid".into(),
            grid.into(),
            "--out".into(),
            "grid.csv".into(),
        ]
    };
    let keep = [
        "room.obj",
        "room.mtl",
        "ies",
        "schedule.csv",
        "desk.pts",
        "bad-header.csv",
        "bad-number.csv",
        "bad.pts",
    ];
    for (args, needles) in [
        (base("bad-header.csv", "desk.pts"), vec!["bad-header.csv:1"]),
        (base("bad-number.csv", "desk.pts"), vec!["bad-number.csv:2"]),
        (base("schedule.csv", "bad.pts"), vec!["bad.pts:2"]),
        (base("missing.csv", "desk.pts"), vec!["missing.csv"]),
    ] {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        fails(&args, &dir, &needles, &keep);
    }
}

/// `--workplane floor`: the EN 12464-1 grid over the floor, 0.8 m up (8 × 5 points over a
/// 6 × 4 m floor), written with `--grid-out` and read back as the same grid by `--grid`.
#[test]
fn lighting_lays_a_workplane_grid() {
    let dir = scratch("lighting-workplane");
    room(&dir, 0.5);
    write(
        &dir,
        "room.obj",
        &ROOM.replace(
            "usemtl black\nf 1 2 3 4\n",
            "usemtl floor\nf 1 2 3 4\nusemtl black\n",
        ),
    );
    write(
        &dir,
        "room.mtl",
        "newmtl black\nKd 0.5 0.5 0.5\nnewmtl floor\nKd 0.2 0.2 0.2\n",
    );
    let text = run_ok(
        &[
            "lighting",
            "room.obj",
            "--luminaires",
            "schedule.csv",
            "--workplane",
            "floor",
            "--grid-out",
            "wp.pts",
            "--out",
            "a.csv",
            "--patches",
            "400",
        ],
        &dir,
    );
    assert!(text.contains("workplane floor: 40 points"), "{text}");
    let pts = read(&dir, "wp.pts");
    assert_eq!(pts.lines().count(), 40);
    assert!(
        pts.lines()
            .all(|l| l.split_whitespace().nth(2) == Some("0.8")),
        "{pts}"
    );
    run_ok(
        &[
            "lighting",
            "room.obj",
            "--luminaires",
            "schedule.csv",
            "--grid",
            "wp.pts",
            "--out",
            "b.csv",
            "--patches",
            "400",
        ],
        &dir,
    );
    assert_eq!(read(&dir, "a.csv"), read(&dir, "b.csv"));
    fails(
        &[
            "lighting",
            "room.obj",
            "--luminaires",
            "schedule.csv",
            "--workplane",
            "carpet",
            "--out",
            "c.csv",
        ],
        &dir,
        &["'carpet'", "floor"],
        &[
            "room.obj",
            "room.mtl",
            "ies",
            "schedule.csv",
            "desk.pts",
            "wp.pts",
            "a.csv",
            "b.csv",
        ],
    );
}
