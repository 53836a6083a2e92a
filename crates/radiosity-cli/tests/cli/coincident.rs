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
