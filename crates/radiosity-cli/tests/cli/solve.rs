//! `radiosity solve`: the documented CSV, traces, determinism across threads, outputs through
//! links, and the stochastic Jacobi and hierarchical solvers' outputs and options.

use crate::common::*;

#[test]
fn solve_writes_the_documented_csv() {
    let dir = scratch("csv");
    run_ok(
        &[
            "solve",
            "furnace",
            "--patches",
            "150",
            "--rays",
            "512",
            "--tolerance",
            "1e-6",
            "--out",
            "f.csv",
        ],
        &dir,
    );
    let text = read(&dir, "f.csv");
    let mut lines = text.lines();
    assert_eq!(
        lines.next().unwrap(),
        "patch,surface,area,cx,cy,cz,nx,ny,nz,reflectance_r,reflectance_g,reflectance_b,emission_r,emission_g,emission_b,radiosity_r,radiosity_g,radiosity_b"
    );
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    assert!(rows.len() > 100);
    let (mut area, mut weighted) = (0.0, 0.0);
    for (k, r) in rows.iter().enumerate() {
        assert_eq!(r.len(), 18);
        assert_eq!(r[0] as usize, k);
        area += r[2];
        weighted += r[2] * r[16];
    }
    // Furnace, green channel: ρ = 0.5, E = 1, so the area-weighted mean radiosity is 2.
    assert!((weighted / area - 2.0).abs() < 1e-4, "{}", weighted / area);
    // Surface area of the 1 m box plus the inner block.
    assert!((area - (6.0 + 2.0 * (0.4 * 0.35 + 0.35 * 0.3 + 0.4 * 0.3))).abs() < 1e-4);
}

#[test]
fn solve_output_does_not_depend_on_threads() {
    let dir = scratch("threads");
    for t in ["1", "2"] {
        run_ok(
            &[
                "solve",
                "cornell",
                "--patches",
                "600",
                "--threads",
                t,
                "--out",
                &format!("t{t}.csv"),
            ],
            &dir,
        );
    }
    let a = read_bytes(&dir, "t1.csv");
    let b = read_bytes(&dir, "t2.csv");
    assert!(a == b, "CSV differs between --threads 1 and --threads 2");
}

#[test]
fn solve_traces_a_scene() {
    let dir = scratch("scenetrace");
    run_ok(
        &[
            "solve",
            "cube-dim",
            "--max-edge",
            "0.25",
            "--solver",
            "gauss-seidel",
            "--tolerance",
            "1e-6",
            "--trace",
            "t.csv",
            "--out",
            "p.csv",
        ],
        &dir,
    );
    let trace = read(&dir, "t.csv");
    let rows: Vec<Vec<f64>> = trace
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    // 96 patches: a few sweeps to 1e-6.
    assert!(rows.len() > 96);
    let (first, last) = (&rows[0], rows.last().unwrap());
    assert!(first[2] > 0.5, "error at start {}", first[2]);
    assert!(last[2].abs() < 1e-5 && last[3] <= 1e-6, "last row {last:?}");
}

#[test]
fn solve_with_hemicube_form_factors_keeps_the_furnace_exact_on_average() {
    let dir = scratch("ffsolve");
    run_ok(
        &[
            "solve",
            "furnace",
            "--patches",
            "120",
            "--form-factors",
            "hemicube",
            "--resolution",
            "64",
            "--samples",
            "4",
            "--tolerance",
            "1e-7",
            "--out",
            "f.csv",
        ],
        &dir,
    );
    let text = read(&dir, "f.csv");
    let (mut area, mut weighted) = (0.0, 0.0);
    for l in text.lines().skip(1) {
        let r: Vec<f64> = l.split(',').map(|v| v.parse().unwrap()).collect();
        area += r[2];
        weighted += r[2] * r[16];
    }
    // Rows sum to 1 within a pixel (delta ≤ 3.1e-4 at P = 64), so the mean is exact to that.
    assert!(
        (weighted / area - 2.0).abs() < 2.0 * 2.0 * 3.2e-4,
        "{}",
        weighted / area
    );
}

/// Outputs are replaced by renaming only when they are regular files: a symbolic link stays a
/// link with its target rewritten, and a link to nothing is refused.
#[cfg(unix)]
#[test]
fn outputs_through_links_keep_the_link() {
    let dir = scratch("links");
    write(&dir, "real.csv", "old");
    std::os::unix::fs::symlink(dir.join("real.csv"), dir.join("link.csv")).unwrap();
    run_ok(
        &["solve", "furnace", "--patches", "50", "-o", "link.csv"],
        &dir,
    );
    assert!(std::fs::symlink_metadata(dir.join("link.csv"))
        .unwrap()
        .file_type()
        .is_symlink());
    assert!(read(&dir, "real.csv").starts_with("patch,"));
    std::os::unix::fs::symlink(dir.join("nothing.csv"), dir.join("dangling.csv")).unwrap();
    let out = run(
        &["solve", "furnace", "--patches", "50", "-o", "dangling.csv"],
        &dir,
    );
    assert!(!out.status.success());
    assert!(stderr(&out).contains("symbolic link to nothing"));
}

/// `--gather-rays`: stochastic Jacobi's final gathering iteration runs only when asked for.
/// Without the flag the output is that of `--gather-rays 0` byte for byte; with it, B differs
/// (gathered again), both report a standard error, and the area-weighted mean of B stays
/// within the two runs' Monte Carlo noise of each other.
#[test]
fn stochastic_jacobi_gathers_only_when_asked() {
    let dir = scratch("sj-gather");
    let solve = |extra: &[&str], out: &str| {
        let said = run_ok(
            &[
                &[
                    "solve",
                    "cornell",
                    "--patches",
                    "800",
                    "--solver",
                    "stochastic-jacobi",
                    "--iteration-rays",
                    "64",
                    "--out",
                    out,
                ][..],
                extra,
            ]
            .concat(),
            &dir,
        );
        assert!(said.contains("estimated standard error"), "{said}");
        read(&dir, out)
    };
    let plain = solve(&[], "plain.csv");
    let zero = solve(&["--gather-rays", "0"], "zero.csv");
    let gathered = solve(&["--gather-rays", "64"], "gathered.csv");
    assert_eq!(plain, zero);
    assert_ne!(plain, gathered);
    // Area-weighted mean radiosity (channels summed) of each CSV.
    let mean = |csv: &str| {
        let mut lines = csv.lines();
        let head: Vec<&str> = lines.next().unwrap().split(',').collect();
        let col = |name: &str| head.iter().position(|h| *h == name).unwrap();
        let (a, r, g, b) = (
            col("area"),
            col("radiosity_r"),
            col("radiosity_g"),
            col("radiosity_b"),
        );
        let (mut total, mut area) = (0.0, 0.0);
        for l in lines {
            let v: Vec<f64> = l.split(',').map(|x| x.parse().unwrap_or(0.0)).collect();
            total += v[a] * (v[r] + v[g] + v[b]);
            area += v[a];
        }
        total / area
    };
    // More gathering rays than a patch may hold at once: refused before anything is built,
    // one line naming the flag, no output file.
    let refused = run(
        &[
            "solve",
            "cornell",
            "--solver",
            "stochastic-jacobi",
            "--gather-rays",
            "4000000000",
            "--out",
            "refused.csv",
        ],
        &dir,
    );
    assert!(!refused.status.success());
    let err = stderr(&refused);
    assert!(err.contains("--gather-rays 4000000000"), "{err}");
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(!dir.join("refused.csv").exists());
    let (m0, m1) = (mean(&plain), mean(&gathered));
    eprintln!("mean B {m0} without gathering, {m1} with");
    // 64 rays a patch over 800 patches: the scene's mean is known to a fraction of a per
    // cent; 3 % holds both runs' noise many times over.
    assert!((m1 / m0 - 1.0).abs() < 0.03, "{m0} against {m1}");
}

/// `solve --solver hierarchical`: the leaves as CSV rows (one per leaf in the elements file),
/// the links and elements written, the furnace uniform per surface, a baked glTF and a picture
/// from the same solution.
#[test]
fn hierarchical_solve_writes_leaves_links_and_elements() {
    let dir = scratch("hierarchical");
    let text = run_ok(
        &[
            "solve",
            "furnace",
            "--solver",
            "hierarchical",
            "--tolerance",
            "1e-7",
            "-o",
            "f.csv",
            "--links-out",
            "links.csv",
            "--elements-out",
            "elements.csv",
        ],
        &dir,
    );
    assert!(
        text.contains("leaf elements") && text.contains("by hierarchical"),
        "{text}"
    );
    let rows = read(&dir, "f.csv");
    let elements = read(&dir, "elements.csv");
    let links = read(&dir, "links.csv");
    assert!(links.starts_with(
        "receiver,source,source_kind,form_factor,uncertainty,power_r,power_g,power_b\n"
    ));
    assert!(links.lines().count() > 1000);
    let leaves = elements
        .lines()
        .skip(1)
        .filter(|l| l.split(',').nth(4) == Some("1"))
        .count();
    assert_eq!(leaves, rows.lines().count() - 1);
    // Furnace: B = E/(1 − ρ) = 2 (green); each surface's area mean within 0.5 %.
    let mut per = std::collections::HashMap::<String, (f64, f64)>::new();
    let header: Vec<&str> = rows.lines().next().unwrap().split(',').collect();
    let col = |n: &str| header.iter().position(|h| *h == n).unwrap();
    let (s, a, g) = (col("surface"), col("area"), col("radiosity_g"));
    for line in rows.lines().skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        let area: f64 = f[a].parse().unwrap();
        let e = per.entry(f[s].to_string()).or_default();
        e.0 += area * f[g].parse::<f64>().unwrap();
        e.1 += area;
    }
    for (k, (b, area)) in per {
        assert!(
            (b / area / 2.0 - 1.0).abs() < 0.005,
            "surface {k}: {}",
            b / area
        );
    }
    // Baked and rendered from the hierarchical leaves.
    for args in [
        &[
            "solve",
            "cornell",
            "--solver",
            "hierarchical",
            "-o",
            "c.glb",
        ][..],
        &[
            "render",
            "cornell",
            "--solver",
            "hierarchical",
            "--width",
            "64",
            "--height",
            "64",
            "-o",
            "c.png",
        ][..],
    ] {
        run_ok(args, &dir);
    }
    assert!(std::fs::metadata(dir.join("c.glb")).unwrap().len() > 10_000);
    assert!(std::fs::metadata(dir.join("c.png")).unwrap().len() > 1_000);
}

/// Impossible hierarchical options fail on one line, naming the option, writing nothing.
#[test]
fn hierarchical_rejects_bad_options() {
    let dir = scratch("hierarchical-bad");
    for (args, needle) in [
        (
            &[
                "solve",
                "cornell",
                "--solver",
                "hierarchical",
                "--link-error",
                "0",
                "-o",
                "x.csv",
            ][..],
            "--link-error",
        ),
        (
            &[
                "solve",
                "cornell",
                "--solver",
                "hierarchical",
                "--min-area",
                "0",
                "-o",
                "x.csv",
            ][..],
            "--min-area",
        ),
        (
            &[
                "solve",
                "cornell",
                "--solver",
                "hierarchical",
                "--visibility-rays",
                "0",
                "-o",
                "x.csv",
            ][..],
            "--visibility-rays",
        ),
        (
            &["solve", "cornell", "--links-out", "l.csv", "-o", "x.csv"][..],
            "--links-out",
        ),
        (
            &[
                "solve",
                "cornell",
                "--solver",
                "hierarchical",
                "--trace",
                "t.csv",
                "-o",
                "x.csv",
            ][..],
            "--trace",
        ),
    ] {
        fails(args, &dir, &[needle], &[]);
    }
}
