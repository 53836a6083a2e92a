//! `radiosity thermal`: radiative heat transfer between grey surfaces against the exchange
//! formula, the textbook networks and enclosure formulas, units and prescribed fluxes, and
//! bad boundary conditions.

use crate::common::*;
use std::path::Path;

const SIGMA: f64 = 5.670_374_419e-8;

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
fn balance_of(text: &str) -> f64 {
    let line = text
        .lines()
        .find(|l| l.starts_with("balance"))
        .unwrap_or_else(|| panic!("no balance line in {text}"));
    line.rsplit(' ').next().unwrap().parse().unwrap()
}

/// `radiosity thermal ARGS` in `dir`, which must succeed; its stdout.
fn thermal(dir: &Path, args: &[&str]) -> String {
    let mut all = vec!["thermal"];
    all.extend_from_slice(args);
    run_ok(&all, dir)
}

/// View3D's unit cube with every face black at its own temperature: Q_i = A_i Σ_j F_ij σ(T_i⁴ −
/// T_j⁴) with Howell's exact factors (opposite 0.1998248957, adjacent 0.2000437761). The
/// analytic factors are exact; F is stored in f32, so agreement is to ~1e-7 of σT⁴.
#[test]
#[ignore = "needs View3D's examples in ../shared/scenes/view3d (run with --include-ignored, as .ci/run does)"]
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
#[ignore = "needs View3D's examples in ../shared/scenes/view3d (run with --include-ignored, as .ci/run does)"]
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
            &["bc.csv", "no boundary condition for 1 surface name: 'back'"],
        ),
    ] {
        write(&dir, "bc.csv", &format!("{h}{body}"));
        // Two plates back to back see nothing: closed only if told so.
        fails(
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
            needles,
            &keep,
        );
    }
    // A closed enclosure with no temperature anywhere.
    let cube = shared_view3d("cube.vs3");
    write(
        &dir,
        "bc.csv",
        &format!("{h}zeq0,,,100\nxeq0,,,\nyeq0,,,\nzeq1,,,\nxeq1,,,\nyeq1,,,-100\n"),
    );
    fails(
        &[
            "thermal",
            cube.to_str().unwrap(),
            "--boundary",
            "bc.csv",
            "--out",
            "s.csv",
        ],
        &dir,
        &["no surface has a prescribed temperature"],
        &keep,
    );
    write(&dir, "bc.csv", "name,temperature\n");
    fails(
        &["thermal", "p.obj", "--boundary", "bc.csv", "--out", "s.csv"],
        &dir,
        &["bc.csv:1", "header"],
        &keep,
    );
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
        fails(&all, &dir, &[needle], &keep);
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

/// Radiant temperatures at points (`--grid`, `--mrt-out`): a closed black 2 m cube, floor at
/// 350 K, the rest at 300 K. At the centre each face subtends 4π/6, so T_mr⁴ = (350⁴ +
/// 5·300⁴)/6; a sensor there facing the floor sees it with the parallel-square factor
/// 4 · (1/2π)·2·(1/√2)·atan(1/√2) = 0.554…, so T_pr⁴ = F·350⁴ + (1 − F)·300⁴. The stratified
/// estimate errs by under 4·√(3√n)/n of the spread of T⁴ (see `pipeline::radiant`).
#[test]
fn thermal_radiant_temperatures_at_points() {
    let dir = scratch("thermal-mrt");
    write(
        &dir,
        "cube.mtl",
        "newmtl floor\nKd 0 0 0\nnewmtl walls\nKd 0 0 0\n",
    );
    let mut obj = String::from("mtllib cube.mtl\n");
    for k in 0..8 {
        let c = |bit: usize| if k & bit != 0 { 2.0 } else { 0.0 };
        obj += &format!("v {} {} {}\n", c(1), c(2), c(4));
    }
    // Inward faces: the outward corner orders reversed; z− (the floor) first.
    let faces = [
        [0, 2, 3, 1],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [4, 5, 7, 6],
    ];
    for (i, f) in faces.iter().enumerate() {
        if i < 2 {
            obj += if i == 0 {
                "usemtl floor\n"
            } else {
                "usemtl walls\n"
            };
        }
        let f = f.map(|v| v + 1);
        obj += &format!("f {} {} {} {}\n", f[3], f[2], f[1], f[0]);
    }
    write(&dir, "cube.obj", &obj);
    write(
        &dir,
        "bc.csv",
        "name,emissivity,temperature,flux\nfloor,1,350,\nwalls,1,300,\n",
    );
    write(&dir, "p.pts", "1 1 1 0 0 -1\n1 1 1 0 0 1\n");
    let out = thermal(
        &dir,
        &[
            "cube.obj",
            "--boundary",
            "bc.csv",
            "--out",
            "s.csv",
            "--grid",
            "p.pts",
            "--mrt-out",
            "mrt.csv",
        ],
    );
    assert!(out.contains("radiant     2 points"), "{out}");
    let (header, rows) = read_csv(&dir.join("mrt.csv"));
    assert_eq!(
        header.join(","),
        "x,y,z,mean_radiant_temperature,plane_radiant_temperature,sky_view"
    );
    let (hot, cold) = (350f64.powi(4), 300f64.powi(4));
    let f = 4.0 / (2.0 * std::f64::consts::PI) * 2.0 / 2f64.sqrt() * (1.0 / 2f64.sqrt()).atan();
    let n = 2048.0; // 2k², k = 32, for the default 2,048 rays
    let bound = 4.0 * (3.0 * f64::sqrt(n)).sqrt() / n * (hot - cold);
    let v = |r: &Vec<String>, c: usize| r[c].parse::<f64>().unwrap();
    let mean = (hot + 5.0 * cold) / 6.0;
    for (r, facing_floor) in rows.iter().zip([true, false]) {
        assert!((v(r, 3).powi(4) - mean).abs() < bound, "T_mr {}", v(r, 3));
        let share = if facing_floor { f } else { 0.0 };
        let plane = share * hot + (1.0 - share) * cold;
        assert!((v(r, 4).powi(4) - plane).abs() < bound, "T_pr {}", v(r, 4));
        assert_eq!(v(r, 5), 0.0, "a closed box has no sky");
    }
    // A bad grid: named with its line, before any work; no output left.
    write(&dir, "bad.pts", "1 1 1 0 0 1\n1 1 nan 0 0 1\n");
    fails(
        &[
            "thermal",
            "cube.obj",
            "--boundary",
            "bc.csv",
            "--out",
            "t.csv",
            "--grid",
            "bad.pts",
            "--mrt-out",
            "m.csv",
        ],
        &dir,
        &["bad.pts:2"],
        &[
            "cube.obj", "cube.mtl", "bc.csv", "p.pts", "s.csv", "mrt.csv", "bad.pts",
        ],
    );
}

/// A View3D file whose surface names repeat (View3D numbers its surfaces and reads it): a unit
/// cube whose top and bottom are both `side` (400 K) and whose four walls are all `wall`
/// (300 K), black. Each name's boundary applies to all its surfaces, and the flux of `side` is
/// F σ(400⁴ − 300⁴) with F = 1 − F_opposite = 1 − 0.1998248957 (Howell C-11), to the Monte
/// Carlo error of 10⁶ rays a row (1e-3).
#[test]
fn thermal_reads_repeated_view3d_names() {
    let dir = scratch("thermal-repeated-names");
    let mut vs3 = String::from("T cube\nC encl=1\nF 3\n");
    for (k, v) in [
        [0, 0, 0],
        [1, 0, 0],
        [1, 1, 0],
        [0, 1, 0],
        [0, 0, 1],
        [1, 0, 1],
        [1, 1, 1],
        [0, 1, 1],
    ]
    .iter()
    .enumerate()
    {
        vs3 += &format!("V {} {} {} {}\n", k + 1, v[0], v[1], v[2]);
    }
    for (k, (f, name)) in [
        ([2, 3, 4, 1], "side"),
        ([8, 7, 6, 5], "side"),
        ([5, 6, 2, 1], "wall"),
        ([6, 7, 3, 2], "wall"),
        ([7, 8, 4, 3], "wall"),
        ([8, 5, 1, 4], "wall"),
    ]
    .iter()
    .enumerate()
    {
        vs3 += &format!(
            "S {} {} {} {} {} 0 0 1 {name}\n",
            k + 1,
            f[0],
            f[1],
            f[2],
            f[3]
        );
    }
    vs3 += "End of data\n";
    write(&dir, "c.vs3", &vs3);
    write(
        &dir,
        "bc.csv",
        "name,emissivity,temperature,flux\nside,1,400,\nwall,1,300,\n",
    );
    let out = run(
        &["thermal", "c.vs3", "--boundary", "bc.csv", "--out", "s.csv"],
        &dir,
    );
    let text = succeed(&out);
    assert!(
        stderr(&out).contains("4 surface name(s) repeat"),
        "{}",
        stderr(&out)
    );
    assert!(balance_of(&text) < 1e-9);
    let s = read_surfaces(&dir.join("s.csv"));
    let q = (1.0 - 0.199_824_895_7) * SIGMA * (400f64.powi(4) - 300f64.powi(4));
    let got = s["side"];
    assert!((got[0] - 2.0).abs() < 1e-9, "both sides count: {}", got[0]);
    assert!((got[3] - q).abs() < 1e-3 * q, "{} vs {q}", got[3]);
}

/// `--solver matrix-free` on the hot-plate room (examples/, 4 × 4 patches a face at
/// `--patches 200`): every surface's flux within 4 of its reported standard error of the
/// stored solve's (adaptive factors), the `flux_std_error` columns written, the books' line,
/// the adaptive stage's line, and the adaptive method's counts and accuracy on the stored
/// run's summary; bad counts and flux-error targets refused naming the flag.
#[test]
fn thermal_matrix_free_matches_the_stored_solve() {
    let dir = scratch("thermal-matrix-free");
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples");
    let scene = root.join("hot-plate.obj");
    let bc = root.join("hot-plate-bc.csv");
    let common = [
        scene.to_str().unwrap(),
        "--boundary",
        bc.to_str().unwrap(),
        "--patches",
        "200",
    ];
    let mut stored_args = common.to_vec();
    stored_args.extend(["--out", "s.csv", "--solver", "stored", "--accuracy", "1e-6"]);
    let stored_out = thermal(&dir, &stored_args);
    assert!(
        stored_out.contains("accuracy 1e-6 an entry") && stored_out.contains("facing pairs"),
        "{stored_out}"
    );
    let mut free_args = common.to_vec();
    free_args.extend([
        "--out",
        "m.csv",
        "--patches-out",
        "mp.csv",
        "--solver",
        "matrix-free",
    ]);
    let free_out = thermal(&dir, &free_args);
    assert!(free_out.contains("matrix-free in"), "{free_out}");
    assert!(free_out.contains("standard errors: Σ power"), "{free_out}");
    assert!(
        free_out.contains("adaptive    flux target") && free_out.contains("left above it"),
        "{free_out}"
    );
    let stored = read_surfaces(&dir.join("s.csv"));
    let (header, rows) = read_csv(&dir.join("m.csv"));
    assert_eq!(
        header.join(","),
        "name,area,emissivity,temperature,flux,power,flux_std_error"
    );
    for r in &rows {
        let (flux, se): (f64, f64) = (r[4].parse().unwrap(), r[6].parse().unwrap());
        let reference = stored[&r[0]][3];
        if r[0] == "floor" {
            assert_eq!((flux, se), (0.0, 0.0), "a prescribed flux has no error");
        } else {
            assert!(se > 0.0 && se < 0.02 * reference.abs(), "{r:?}");
            assert!(
                (flux - reference).abs() < 4.0 * se + 1e-4 * reference.abs(),
                "{}: {flux} ± {se} against {reference}",
                r[0]
            );
        }
    }
    let (header, rows) = read_csv(&dir.join("mp.csv"));
    let (q, t) = (
        column(&header, "flux_std_error"),
        column(&header, "temperature_std_error"),
    );
    assert!(rows.iter().all(|r| {
        let (q, t): (f64, f64) = (r[q].parse().unwrap(), r[t].parse().unwrap());
        q.is_finite() && t.is_finite() && q >= 0.0 && t >= 0.0
    }));
    for (flag, value) in [
        ("--batches", "1"),
        ("--flux-rays", "0"),
        ("--temperature-rays", "0"),
        ("--carry-rays", "0"),
        ("--flux-error", "1.5"),
        ("--flux-error", "NaN"),
    ] {
        let mut args = vec!["thermal"];
        args.extend_from_slice(&common);
        args.extend(["--out", "x.csv", flag, value]);
        fails(&args, &dir, &[flag, value], &["s.csv", "m.csv", "mp.csv"]);
    }
}
