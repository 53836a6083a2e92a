//! `radiosity-bench`, every mode: `hierarchical` against its reference, `scale` and its
//! `--bookkeeping` against `radiosity solve` run alone, `rays` and its Embree backend.

use crate::common::*;
use std::path::Path;

/// `radiosity-bench hierarchical SCENE`: the reference surface means are made (by the light tracer
/// unless `--reference-tracer path`) and written as `surface,b_r,b_g,b_b,se_r,se_g,se_b`, one
/// row a polygon; the table gives each method's errors against them and the reference's own
/// noise floor; a second run reads the file instead of tracing again.
#[test]
fn bench_hierarchical_makes_and_reads_its_reference() {
    let dir = scratch("bench-hierarchical");
    for tracer in ["light", "path"] {
        let file = format!("{tracer}.csv");
        let args = [
            "hierarchical",
            "cornell",
            "--link-errors",
            "1e-3",
            "--reference",
            &file,
            "--reference-paths",
            "1000000",
            "--reference-tracer",
            tracer,
        ];
        let text = run_ok(&args, &dir);
        assert!(
            text.contains(if tracer == "light" {
                "light tracer"
            } else {
                "path tracer"
            }),
            "{text}"
        );
        let csv = read(&dir, &file);
        let mut lines = csv.lines();
        assert_eq!(lines.next(), Some("surface,b_r,b_g,b_b,se_r,se_g,se_b"));
        assert_eq!(lines.count(), 19, "{csv}");
        let row = text
            .lines()
            .find(|l| l.starts_with("hierarchical 1e-3"))
            .expect("a hierarchical row");
        let v: Vec<f64> = row
            .split_whitespace()
            .skip(2)
            .map(|t| t.parse().unwrap())
            .collect();
        // elements, links, wall s, mean %, worst %, L1 %, floor %.
        assert!(v[5] < 3.0 && v[6] < 0.5, "{row}");
        let again = run(&args, &dir);
        assert!(stdout(&again).contains("(read)"));
    }
    // `--solve-seeds`: a row a seed, each its own draw.
    let text = run_ok(
        &[
            "hierarchical",
            "cornell",
            "--link-errors",
            "1e-3",
            "--reference",
            "light.csv",
            "--solve-seeds",
            "1,2",
        ],
        &dir,
    );
    let rows: Vec<&str> = text
        .lines()
        .filter(|l| l.starts_with("hierarchical 1e-3 s"))
        .collect();
    assert_eq!(rows.len(), 2, "{text}");
    assert_ne!(
        rows[0].split_whitespace().nth(3),
        rows[1].split_whitespace().nth(3),
        "{text}"
    );
}

/// Run `radiosity-bench scale cornell --sizes 200,800` with `extra` options; its output and the
/// table's rows (the lines of fourteen numbers, "—" read as NaN).
fn bench_scale_cornell(extra: &[&str], dir: &Path) -> (String, Vec<Vec<f64>>) {
    let text = run_ok(
        &[&["scale", "cornell", "--sizes", "200,800"], extra].concat(),
        dir,
    );
    let rows: Vec<Vec<f64>> = text
        .lines()
        .filter_map(|l| {
            let v: Result<Vec<f64>, _> = l
                .split_whitespace()
                .map(|t| if t == "—" { Ok(f64::NAN) } else { t.parse() })
                .collect();
            v.ok().filter(|v| v.len() == 14 && !v[0].is_nan())
        })
        .collect();
    assert_eq!(rows.len(), 2, "{text}");
    (text, rows)
}

/// What `solve cornell --patches SIZE --tolerance 0.05` prints.
fn cornell_alone(size: &str, dir: &Path) -> String {
    radiosity_ok(
        &[
            "solve",
            "cornell",
            "--patches",
            size,
            "--tolerance",
            "0.05",
            "--out",
            "s.csv",
        ],
        dir,
    )
}

/// The exponent `name` on `radiosity-bench scale`'s last line; `None` where it reads "—".
fn scale_exponent(text: &str, name: &str) -> Option<f64> {
    let line = text
        .lines()
        .find(|l| l.starts_with("fitted exponents against N:"))
        .unwrap();
    let at = line.find(&format!(" {name} ")).unwrap() + name.len() + 2;
    line[at..].split(',').next().unwrap().trim().parse().ok()
}

/// `radiosity-bench scale`: each size is solved by a fresh `radiosity solve`, and the table reports its
/// patches, rays and iterations exactly as that command, run alone, reports them (they depend
/// on the seed only); its stages fit inside the wall time measured around the child; the
/// exponent of the rays is the slope through the table's own two points. Bad sizes are refused
/// with a one-line error naming the option.
#[test]
fn bench_scale_reports_each_solve_and_fits_its_exponents() {
    let dir = scratch("bench-scale");
    let (text, rows) = bench_scale_cornell(&["--tolerance", "0.05"], &dir);
    for (row, size) in rows.iter().zip(["200", "800"]) {
        let said = cornell_alone(size, &dir);
        let first = |key: &str| -> f64 {
            let line = said.lines().find(|l| l.starts_with(key)).unwrap();
            line[key.len()..]
                .split_whitespace()
                .next()
                .unwrap()
                .parse()
                .unwrap()
        };
        assert_eq!(row[0], first("patches "), "{text}\n{said}");
        assert_eq!(row[1], first("rays "), "{text}\n{said}");
        assert_eq!(row[2], first("iterations "), "{text}\n{said}");
        // Mesh, hierarchy, rows and solve happen inside the child; each printed value is off
        // by at most half its last digit: 0.005 for the wall and the rows and solve times,
        // 0.0005 for the mesh and hierarchy.
        let stages = row[5] + row[6] + row[7] + row[8];
        assert!(stages <= row[3] + 0.016 + 1e-9, "{text}");
        assert!(row[1] > 0.0 && row[2] > 0.0 && row[9] > 0.0, "{text}");
        // `solve %` is the solve's share of the wall time, both printed to ±0.005 s and the
        // share to ±0.05.
        let (solve, wall, share) = (row[8], row[3], row[11]);
        let low = 100.0 * (solve - 0.005).max(0.0) / (wall + 0.005) - 0.05;
        let high = 100.0 * (solve + 0.005) / (wall - 0.005) + 0.05;
        assert!(low - 1e-9 <= share && share <= high + 1e-9, "{text}");
        // The cross-core round trips before and after: a time on a machine of two cores or
        // more (under the 200 ms that the probe may take), "—" on one.
        let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
        for t in [row[12], row[13]] {
            if cores > 1 {
                assert!(t > 0.0 && t < 2e8, "{text}");
            } else {
                assert!(t.is_nan(), "{text}");
            }
        }
    }
    let slope = (rows[1][1] / rows[0][1]).ln() / (rows[1][0] / rows[0][0]).ln();
    let rays = scale_exponent(&text, "rays").unwrap();
    assert!((rays - slope).abs() <= 0.005 + 1e-9, "{text}: {slope}");
    for bad in ["0", "200,0"] {
        let out = run(&["scale", "cornell", "--sizes", bad], &dir);
        let err = stderr(&out);
        assert!(!out.status.success() && err.contains("--sizes"), "{err}");
        assert_eq!(err.trim().lines().count(), 1, "{err}");
    }
}

/// `radiosity-bench scale … --bookkeeping`: each size is solved once, which fills the row cache, and
/// then again on the cached rows. On the Cornell box at 5 % no row is estimated twice, so the
/// solves on the cached rows take exactly the shots of `solve` run alone, and the rows counted
/// are the rows it reports; every shot updates at least one receiver. A method that does not
/// use rows is refused with a one-line error naming the option.
#[test]
fn bench_bookkeeping_replays_the_solve_on_cached_rows() {
    let dir = scratch("bench-bookkeeping");
    let text = run_ok(
        &[
            "scale",
            "cornell",
            "--sizes",
            "800",
            "--bookkeeping",
            "--runs",
            "2",
            "--tolerance",
            "0.05",
        ],
        &dir,
    );
    let row: Vec<f64> = text
        .lines()
        .filter_map(|l| {
            let v: Result<Vec<f64>, _> = l.split_whitespace().map(str::parse).collect();
            v.ok().filter(|v| v.len() == 7)
        })
        .next()
        .unwrap_or_else(|| panic!("{text}"));
    let said = cornell_alone("800", &dir);
    let words = |key: &str| -> Vec<String> {
        let line = said.lines().find(|l| l.starts_with(key)).unwrap();
        line.split_whitespace().map(String::from).collect()
    };
    assert_eq!(
        row[0],
        words("patches ")[1].parse::<f64>().unwrap(),
        "{text}\n{said}"
    );
    assert_eq!(
        row[1],
        words("iterations ")[1].parse::<f64>().unwrap(),
        "{text}\n{said}"
    );
    // "rays        409726 in 729 form-factor rows"
    assert_eq!(
        row[3],
        words("rays ")[3].parse::<f64>().unwrap(),
        "{text}\n{said}"
    );
    assert!(row[2] >= row[1] && row[6] > 0.0, "{text}");
    let out = run(
        &[
            "scale",
            "cornell",
            "--sizes",
            "200",
            "--bookkeeping",
            "--solver",
            "stochastic-jacobi",
        ],
        &dir,
    );
    let err = stderr(&out);
    assert!(
        !out.status.success() && err.contains("--bookkeeping"),
        "{err}"
    );
    assert_eq!(err.trim().lines().count(), 1, "{err}");
}

/// Stochastic Jacobi casts its rays inside its solve: `solve` says how much of the solve
/// stage they took, and `radiosity-bench scale` counts them with the rows, so that its `solve s`
/// column is everything but rays for every method.
#[test]
fn stochastic_jacobi_reports_its_rays_apart_from_its_bookkeeping() {
    let dir = scratch("sj-rays");
    let args = ["--solver", "stochastic-jacobi", "--tolerance", "0.05"];
    let said = radiosity_ok(
        &[
            &["solve", "cornell", "--patches", "800", "--out", "s.csv"],
            &args[..],
        ]
        .concat(),
        &dir,
    );
    let time = said.lines().find(|l| l.starts_with("time ")).unwrap();
    let after = |key: &str| -> f64 {
        let at = time.find(key).unwrap_or_else(|| panic!("{time}")) + key.len();
        time[at..]
            .split_whitespace()
            .next()
            .unwrap()
            .parse()
            .unwrap()
    };
    let (solve, rays) = (after("solve "), after("(rays "));
    assert!(rays > 0.0 && rays <= solve, "{time}");
    let (text, rows) = bench_scale_cornell(&args, &dir);
    for row in &rows {
        // Every stage fits in the wall time, to the printed values' rounding.
        assert!(row[7] >= 0.0 && row[8] >= 0.0, "{text}");
        assert!(
            row[5] + row[6] + row[7] + row[8] <= row[3] + 0.016 + 1e-9,
            "{text}"
        );
    }
    // The rows' exponent is fitted (not "—"): their times, unrounded, were not zero.
    assert!(scale_exponent(&text, "rows").is_some(), "{text}");
}

/// `radiosity-bench rays SCENE`: the form-factor ray workload on a scene, with its figures.
#[test]
fn bench_rays_on_a_scene() {
    let dir = scratch("bench-rays");
    let text = run_ok(
        &[
            "rays",
            "cornell",
            "--rays",
            "20000",
            "--runs",
            "1",
            "--patches",
            "500",
        ],
        &dir,
    );
    let line = text
        .lines()
        .find(|l| l.starts_with("radiosity BVH"))
        .expect("a BVH line");
    // A closed box: every ray from a wall hits the front of another (the light's back is
    // outside), so the hit rate is high.
    let hit: f64 = line
        .split_whitespace()
        .nth(3)
        .unwrap()
        .trim_end_matches('%')
        .parse()
        .unwrap();
    assert!(hit > 70.0, "{line}");
    // The same rays cast in batches (`closest_hits`, one at a time on a hierarchy this
    // small; the command checks that they find the same hits, and fails otherwise): the
    // same hit rate.
    let batch = text
        .lines()
        .find(|l| l.starts_with("BVH, batches"))
        .expect("a line for the batches");
    assert_eq!(
        batch.split_whitespace().nth(3),
        line.split_whitespace().nth(3),
        "{batch}"
    );
    assert!(text.lines().any(|l| l.starts_with("hierarchy: ")), "{text}");
    // Any-hit queries that stop just short of each ray's closest hit: the point hit is
    // visible from the ray's origin, so (but for rays through an edge where two walls meet
    // at the same distance) nothing blocks them.
    let bounded = text
        .lines()
        .find(|l| l.starts_with("BVH any, bounded"))
        .expect("a line for bounded any-hit queries");
    let blocked: f64 = bounded
        .split_whitespace()
        .nth(4)
        .unwrap()
        .trim_end_matches('%')
        .parse()
        .unwrap();
    assert!(blocked < 0.1, "{bounded}");
    // The Cornell box's walls are grids met whole; the same rays cast against every patch's
    // own triangles hit the same patches, but for ties (coincident faces, none here) and
    // rays within rounding of a patch's edge: a band of a ray offset (2 × 10⁻³ here) about
    // edges some 50 apart, 10⁻⁴ of the rays, 2 of these 20,000.
    let hierarchy = text.lines().find(|l| l.starts_with("hierarchy: ")).unwrap();
    let whole: usize = hierarchy
        .split(" pieces met whole")
        .next()
        .and_then(|s| s.rsplit('(').next())
        .and_then(|s| s.parse().ok())
        .expect("pieces met whole");
    assert!(whole >= 10, "{hierarchy}");
    assert!(
        text.lines().any(|l| l.starts_with("BVH of patches ")),
        "{text}"
    );
    let cmp = text
        .lines()
        .find(|l| l.starts_with("BVH of patches / radiosity BVH"))
        .expect("the comparison with every patch's triangles");
    assert!(hits_differing(cmp) <= 20, "{cmp}");
}

/// The count of rays in a `radiosity-bench rays` comparison line `… hits differ on K of N rays …`.
fn hits_differing(line: &str) -> usize {
    line.split("differ on ")
        .nth(1)
        .and_then(|s| s.split_whitespace().next())
        .and_then(|s| s.parse().ok())
        .unwrap_or_else(|| panic!("no count of differing hits in {line:?}"))
}

/// With the `embree` feature, Embree casts the same rays and hits the same patches (rounding
/// may part them on a few rays that graze an edge: under 0.01 %).
#[cfg(feature = "embree")]
#[test]
fn embree_agrees_with_the_bvh_hit_for_hit() {
    let dir = scratch("bench-embree");
    let text = run_ok(
        &["rays", "cornell", "--rays", "200000", "--runs", "1"],
        &dir,
    );
    let line = text
        .lines()
        .find(|l| l.starts_with("Embree 3 / radiosity BVH") && l.contains("hits differ on"))
        .expect("a comparison line");
    assert!(hits_differing(line) as f64 / 200_000.0 < 1e-4, "{line}");
}

/// Without the `embree` feature, asking for Embree is a one-line error that says how to get it.
#[cfg(not(feature = "embree"))]
#[test]
fn embree_backend_needs_the_feature() {
    let dir = scratch("bench-no-embree");
    fails(
        &["rays", "cornell", "--backend", "embree"],
        &dir,
        &["--backend embree", "--features embree"],
        &[],
    );
}

/// Under `mpirun` every mode but `ranks` refuses on one line and runs nothing.
#[test]
#[cfg_attr(
    not(feature = "mpi"),
    ignore = "needs the mpi feature (cargo test --features mpi) and Open MPI's mpirun"
)]
fn under_mpirun_only_ranks_runs() {
    #[cfg(feature = "mpi")]
    {
        let dir = scratch("bench-mpi-refuse");
        let o = mpirun(
            2,
            &["rays", "cornell", "--rays", "1000", "--runs", "1"],
            &dir,
        );
        let err = stderr(&o);
        assert!(!o.status.success(), "{err}");
        let lines: Vec<&str> = err
            .lines()
            .filter(|l| l.starts_with("radiosity: error"))
            .collect();
        assert_eq!(lines.len(), 1, "{err}");
        for n in ["radiosity-bench (except ranks)", "radiosity-bench ranks"] {
            assert!(lines[0].contains(n), "'{}' lacks '{n}'", lines[0]);
        }
    }
}
