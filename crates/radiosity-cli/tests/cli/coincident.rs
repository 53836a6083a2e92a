//! Coincident polygons through the command line: a floor given 1,000 times is one surface,
//! with one warning, and the same matrix as the floor given once.

use crate::common::*;

fn room(copies: usize) -> String {
    let mut s =
        String::from("v 0 0 0\nv 4 0 0\nv 4 4 0\nv 0 4 0\nv 0 0 3\nv 4 0 3\nv 4 4 3\nv 0 4 3\n");
    for _ in 0..copies {
        s.push_str("f 1 2 3 4\n");
    }
    s.push_str("f 5 8 7 6\nf 1 5 6 2\nf 2 6 7 3\nf 3 7 8 4\nf 4 8 5 1\n");
    s
}

#[test]
fn a_thousand_copies_of_a_floor_are_one_surface() {
    let dir = scratch("coincident");
    write(&dir, "one.obj", &room(1));
    write(&dir, "many.obj", &room(1000));
    let args = |scene: &str, out: &str| {
        run(
            &[
                "form-factors",
                scene,
                "--method",
                "analytic",
                "--patches",
                "100",
                "-o",
                out,
            ],
            &dir,
        )
    };
    let one = args("one.obj", "one.mtx");
    succeed(&one);
    assert!(!stderr(&one).contains("coincident"), "{}", stderr(&one));
    let many = args("many.obj", "many.mtx");
    succeed(&many);
    let err = stderr(&many);
    let warnings: Vec<&str> = err.lines().filter(|l| l.contains("coincident")).collect();
    assert_eq!(warnings.len(), 1, "{err}");
    assert!(
        warnings[0].contains("many.obj") && warnings[0].contains("999 coincident polygons"),
        "{err}"
    );
    let read = |f: &str| std::fs::read_to_string(dir.join(f)).unwrap();
    let body = |t: String| {
        t.lines()
            .filter(|l| !l.starts_with('%'))
            .collect::<Vec<_>>()
            .join("\n")
    };
    assert_eq!(body(read("one.mtx")), body(read("many.mtx")));
}

/// A View3D box whose floor is given twice under another name: the copy is solved as the
/// floor, the warning names the pair, and the copy's row shows area 0; the box's books still
/// close (the floor's power is the top's, negated).
#[test]
fn thermal_names_a_surface_solved_as_the_one_it_lies_on() {
    let dir = scratch("coincident-thermal");
    write(
        &dir,
        "box.vs3",
        "T box\nC encl=1 list=0 eps=1.e-4\nF 3\nV 1 0. 0. 0.\nV 2 1. 0. 0.\nV 3 1. 1. 0.\nV 4 0. 1. 0.\n\
         V 5 0. 0. 1.\nV 6 1. 0. 1.\nV 7 1. 1. 1.\nV 8 0. 1. 1.\nS 1 1 2 3 4 0 0 0.50 floor\n\
         S 2 1 4 8 5 0 0 0.50 w1\nS 3 1 5 6 2 0 0 0.50 w2\nS 4 7 6 5 8 0 0 0.90 top\n\
         S 5 7 3 2 6 0 0 0.50 w3\nS 6 7 8 4 3 0 0 0.50 w4\nS 7 1 2 3 4 0 0 0.50 copy\nEnd of data\n",
    );
    write(
        &dir,
        "bc.csv",
        "name,emissivity,temperature,flux\nfloor,0.5,400,\nw1,0.5,,\nw2,0.5,,\ntop,0.9,300,\nw3,0.5,,\nw4,0.5,,\ncopy,0.5,350,\n",
    );
    let out = run(
        &[
            "thermal",
            "box.vs3",
            "--boundary",
            "bc.csv",
            "--out",
            "s.csv",
        ],
        &dir,
    );
    succeed(&out);
    let err = stderr(&out);
    assert!(err.contains("'copy' on 'floor'"), "{err}");
    let csv = std::fs::read_to_string(dir.join("s.csv")).unwrap();
    let row = |name: &str| -> Vec<f64> {
        csv.lines()
            .find(|l| l.starts_with(&format!("{name},")))
            .unwrap()
            .split(',')
            .skip(1)
            .map(|v| v.parse().unwrap())
            .collect()
    };
    assert_eq!(row("copy")[0], 0.0);
    let (floor, top) = (row("floor")[4], row("top")[4]);
    assert!(
        floor > 0.0 && (floor + top).abs() < 1e-9 * floor,
        "{floor} {top}"
    );
}
