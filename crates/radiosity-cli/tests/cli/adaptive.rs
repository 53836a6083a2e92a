//! The adaptive view-factor method through the command: the default for View3D input and for
//! `thermal`, `--accuracy`, and View3D's own examples against View3D's printed answers.

use crate::common::*;
use radiosity::formfactor::closed_form::parallel_rectangles;
use std::path::Path;

/// A View3D file: plates A1 = [0, x0] × [0, 1] at z = 0 (up) and A2 = [0, 1.5] × [0, 1] at
/// z = 0.8 (down), and an obstruction wall x = x0 across the gap. From every point of A1
/// exactly [0, x0] × [0, 1] of A2 is seen, so F₁₂ is Howell's C-11 for x0 × 1 at 0.8 (the
/// library's tests derive it).
const PARTITION: &str = "T partition between parallel plates
C encl=0 list=0
F 3
V 1 0 0 0
V 2 0.6 0 0
V 3 0.6 1 0
V 4 0 1 0
V 5 0 0 0.8
V 6 1.5 0 0.8
V 7 1.5 1 0.8
V 8 0 1 0.8
V 9 0.6 0 0
V 10 0.6 1 0
V 11 0.6 1 0.8
V 12 0.6 0 0.8
S 1 1 2 3 4 0 0 0.9 lower
S 2 8 7 6 5 0 0 0.9 upper
O 3 9 10 11 12
End of data
";

/// Parse View3D's text output: the rows of factors.
fn view3d_rows(text: &str) -> Vec<Vec<f64>> {
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split_whitespace().collect();
    let n: usize = header[5].parse().unwrap();
    lines.next();
    (0..n)
        .map(|_| {
            lines
                .next()
                .unwrap()
                .split_whitespace()
                .map(|x| x.parse().unwrap())
                .collect()
        })
        .collect()
}

fn form_factors(dir: &Path, args: &[&str]) -> String {
    let mut all = vec!["form-factors"];
    all.extend_from_slice(args);
    run_ok(&all, dir)
}

/// A .vs3 scene gets the adaptive method without asking, and its obstructed factor is
/// Howell's closed form to View3D's six printed decimals; `--method` still chooses another.
#[test]
fn vs3_input_defaults_to_adaptive_and_is_exact() {
    let dir = scratch("adaptive-vs3");
    write(&dir, "partition.vs3", PARTITION);
    let out = form_factors(&dir, &["partition.vs3", "--format", "view3d", "-o", "f.vf"]);
    assert!(out.contains("method      adaptive"), "{out}");
    let rows = view3d_rows(&read(&dir, "f.vf"));
    let exact = parallel_rectangles(0.6, 1.0, 0.8);
    // Six decimals printed: within half a unit of the last, plus the method's 1e-6.
    assert!(
        (rows[0][1] - exact).abs() < 1.5e-6,
        "{} vs {exact}",
        rows[0][1]
    );
    assert!(
        (rows[1][0] - exact * 0.6 / 1.5).abs() < 1.5e-6,
        "{}",
        rows[1][0]
    );
    let out = form_factors(
        &dir,
        &[
            "partition.vs3",
            "--method",
            "monte-carlo",
            "--rays",
            "10000",
            "--format",
            "view3d",
            "-o",
            "g.vf",
        ],
    );
    assert!(out.contains("method      monte-carlo"), "{out}");
    // Another format keeps Monte Carlo as its default.
    let out = form_factors(
        &dir,
        &["cube-dim", "--faces", "--rays", "1000", "-o", "F.mtx"],
    );
    assert!(out.contains("method      monte-carlo"), "{out}");
}

/// `--accuracy` reaches the library and is recorded in the matrix's header; a tighter one
/// moves the factor towards the closed form; impossible values are refused with one line
/// naming the flag, and nothing is written.
#[test]
fn accuracy_is_passed_on_and_checked() {
    let dir = scratch("adaptive-accuracy");
    write(&dir, "partition.vs3", PARTITION);
    let exact = parallel_rectangles(0.6, 1.0, 0.8);
    for accuracy in ["1e-4", "1e-7"] {
        form_factors(
            &dir,
            &["partition.vs3", "--accuracy", accuracy, "-o", "F.mtx"],
        );
        let text = read(&dir, "F.mtx");
        assert!(
            text.contains(&format!("method adaptive, accuracy {accuracy}")),
            "{text}"
        );
        let f: f64 = text
            .lines()
            .find(|l| l.starts_with("1 2 "))
            .and_then(|l| l.split_whitespace().nth(2))
            .unwrap()
            .parse()
            .unwrap();
        let tol = accuracy.parse::<f64>().unwrap().max(2e-7);
        assert!(
            (f - exact).abs() < tol,
            "accuracy {accuracy}: {f} vs {exact}"
        );
    }
    for bad in ["0", "-1e-5", "0.5", "nan", "inf"] {
        fails(
            &[
                "form-factors",
                "partition.vs3",
                &format!("--accuracy={bad}"),
                "-o",
                "bad.mtx",
            ],
            &dir,
            &["--accuracy"],
            &["partition.vs3", "F.mtx"],
        );
    }
}

/// `thermal` uses the adaptive method unless told otherwise.
#[test]
fn thermal_defaults_to_adaptive() {
    let dir = scratch("adaptive-thermal");
    write(&dir, "partition.vs3", PARTITION);
    write(
        &dir,
        "bc.csv",
        "name,emissivity,temperature,flux\nlower,1,400,\nupper,1,300,\nobstruction-3,1,,0\n",
    );
    let out = run_ok(
        &[
            "thermal",
            "partition.vs3",
            "--boundary",
            "bc.csv",
            "--out",
            "s.csv",
        ],
        &dir,
    );
    assert!(out.contains("view factors adaptive"), "{out}");
}

/// View3D 4.0's printed answers for its own examples (as in the form-factors tests): the cube
/// exactly (Howell's values to the six printed decimals); the square obstruction within 2e-6
/// of View3D's 0.149870 (the exact value, from the closed-form shadow integral in the library's
/// tests, is 0.1498687); Pinney & Bean's L-shaped room within View3D's own error: its view
/// factors (`-f3a`, eps = 1e-5) within 5e-5, View3D's answer being off by 4.4e-5 on srf-2 →
/// srf-6 (a 10⁹-ray Monte Carlo row, σ ≈ 1e-5, gives 0.098679, this method 0.098671, View3D
/// 0.098715); its total exchange factors (`pinney-bean-test-4`, eps = 1e-4, emit = 1), where
/// solving the grey-enclosure system with ε = 0.9 triples such a difference, within 2e-4.
#[test]
#[ignore = "needs View3D's examples in ../shared/scenes/view3d (run with --include-ignored, as .ci/run does)"]
fn view3d_examples_match_view3d() {
    let dir = scratch("adaptive-view3d");
    let expected: [(&str, f64, &str); 4] = [
        ("cube.vs3", 1e-6, "0.000000 0.200044 0.200044 0.199825 0.200044 0.200044\n0.200044 0.000000 0.200044 0.200044 0.199825 0.200044\n0.200044 0.200044 0.000000 0.200044 0.200044 0.199825\n0.199825 0.200044 0.200044 0.000000 0.200044 0.200044\n0.200044 0.199825 0.200044 0.200044 0.000000 0.200044\n0.200044 0.200044 0.199825 0.200044 0.200044 0.000000"),
        ("square-obstruction.vs3", 2e-6, "0.000000 0.149870 0.000000\n0.149870 0.000000 0.103813\n0.000000 0.415254 0.000000"),
        ("pinney-bean-test-4.vs3", 2e-4, "0.030132 0.099218 0.314268 0.032561 0.030812 0.159022 0.116993 0.116993\n0.297654 0.009602 0.273178 0.007439 0.003718 0.092436 0.107986 0.107986\n0.471402 0.136589 0.025214 0.006158 0.003720 0.048841 0.104038 0.104038\n0.048841 0.003720 0.006158 0.025214 0.136589 0.471402 0.104038 0.104038\n0.092436 0.003718 0.007439 0.273178 0.009602 0.297654 0.107986 0.107986\n0.159022 0.030812 0.032561 0.314268 0.099218 0.030132 0.116993 0.116993\n0.210588 0.064792 0.124846 0.124846 0.064792 0.210588 0.010932 0.088616\n0.210588 0.064792 0.124846 0.124846 0.064792 0.210588 0.088616 0.010932"),
        ("pinney-bean-test-4-f3a.vs3", 5e-5, "0.000000 0.113147 0.378091 0.027473 0.032905 0.182349 0.133016 0.133019\n0.339441 0.000000 0.318989 0.000000 0.000000 0.098715 0.121428 0.121427\n0.567137 0.159494 0.000000 0.000000 0.000000 0.041210 0.116080 0.116079\n0.041210 0.000000 0.000000 0.000000 0.159494 0.567138 0.116080 0.116079\n0.098714 0.000000 0.000000 0.318988 0.000000 0.339442 0.121428 0.121427\n0.182349 0.032905 0.027473 0.378092 0.113147 0.000000 0.133017 0.133016\n0.239429 0.072857 0.139296 0.139295 0.072857 0.239430 0.000000 0.096836\n0.239434 0.072856 0.139295 0.139295 0.072856 0.239429 0.096836 0.000000"),
    ];
    for (file, tol, theirs) in expected {
        let path = shared_view3d(file);
        let out = form_factors(
            &dir,
            &[path.to_str().unwrap(), "--format", "view3d", "-o", "f.vf"],
        );
        assert!(out.contains("method      adaptive"), "{out}");
        let ours = view3d_rows(&read(&dir, "f.vf"));
        let theirs: Vec<Vec<f64>> = theirs
            .lines()
            .map(|l| l.split_whitespace().map(|x| x.parse().unwrap()).collect())
            .collect();
        for (m, (a, b)) in ours.iter().zip(&theirs).enumerate() {
            for (k, (x, y)) in a.iter().zip(b).enumerate() {
                assert!(
                    (x - y).abs() <= tol + 5e-7,
                    "{file}: F[{m}][{k}] {x} vs View3D {y}"
                );
            }
        }
    }
}
