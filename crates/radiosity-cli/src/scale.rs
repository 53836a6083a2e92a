//! `radiosity bench --scale SCENE --sizes N,N,…`: solve a scene at each size with one method,
//! each size in a fresh child process (`radiosity solve`), so that its CPU time and peak
//! resident memory are its own; print patches, rays, wall and CPU seconds, the time of each
//! stage, peak resident memory, and the fitted exponents of time against N.

use crate::args::BenchArgs;
use anyhow::{bail, Context, Result};
use radiosity::experiment::fit_exponent;
use std::process::Command;
use std::time::Instant;

/// One solve's figures, read from the child's summary.
#[derive(Debug, Default)]
struct Row {
    patches: f64,
    rays: f64,
    iterations: f64,
    wall: f64,
    cpu: f64,
    mesh: f64,
    bvh: f64,
    form_factors: f64,
    solve: f64,
    resident_mib: f64,
}

/// The numbers of a summary line, in order (commas inside numbers are not used).
fn numbers(line: &str) -> Vec<f64> {
    line.split(|c: char| !(c.is_ascii_digit() || c == '.' || c == 'e' || c == '-'))
        .filter_map(|t| t.parse::<f64>().ok())
        .collect()
}

fn parse(summary: &str) -> Row {
    let mut row = Row::default();
    for line in summary.lines() {
        let n = numbers(line);
        let get = |k: usize| n.get(k).copied().unwrap_or(f64::NAN);
        if line.starts_with("patches ") {
            row.patches = get(0);
        } else if line.starts_with("rays ") {
            row.rays = get(0);
        } else if line.starts_with("iterations ") {
            row.iterations = get(0);
        } else if line.starts_with("time ") {
            (row.mesh, row.bvh, row.form_factors, row.solve) = (get(0), get(1), get(2), get(3));
            // A solver's own rays (stochastic Jacobi's), part of its solve: counted with the
            // rows, so that `solve s` is everything but rays for every method.
            if let Some(k) = line.find("(rays ") {
                let rays = numbers(&line[k..]).first().copied().unwrap_or(f64::NAN);
                row.form_factors += rays;
                row.solve -= rays;
            }
        } else if line.starts_with("memory ") {
            row.resident_mib = get(0);
        } else if line.starts_with("cpu ") {
            row.cpu = get(0);
        }
    }
    row
}

/// Run the scale benchmark.
pub fn run(a: &BenchArgs, scene: &str) -> Result<()> {
    let sizes = a
        .sizes
        .as_ref()
        .context("--scale needs --sizes N,N,… (patch counts)")?;
    if sizes.is_empty() || sizes.contains(&0) {
        bail!("--sizes: patch counts must be positive");
    }
    if a.bookkeeping {
        return crate::bookkeeping::run(a, scene, sizes);
    }
    let exe = std::env::current_exe().context("cannot find the radiosity executable")?;
    let dir = std::env::temp_dir().join(format!("radiosity-scale-{}", std::process::id()));
    std::fs::create_dir_all(&dir).with_context(|| format!("cannot create {}", dir.display()))?;
    println!(
        "scale: {scene}, {} to {:.2}% unshot, {} threads; each size solved in a fresh process",
        a.solver.0,
        100.0 * a.tolerance,
        a.threads.unwrap_or_else(rayon::current_num_threads)
    );
    println!(
        "{:>9} {:>11} {:>8} {:>9} {:>9} {:>8} {:>8} {:>9} {:>9} {:>10} {:>7}",
        "patches",
        "rays",
        "iters",
        "wall s",
        "cpu s",
        "mesh s",
        "bvh s",
        "rows s",
        "solve s",
        "peak MiB",
        "cpu/wall"
    );
    let mut rows = Vec::new();
    for &n in sizes {
        let out = dir.join(format!("{n}.csv"));
        let mut cmd = Command::new(&exe);
        cmd.arg("solve")
            .arg(scene)
            .args(["--patches", &n.to_string()])
            .args(["--solver", a.solver.0.name()])
            .args(["--tolerance", &a.tolerance.to_string()])
            .args(["--iteration-rays", &a.iteration_rays.to_string()])
            .arg("--out")
            .arg(&out);
        if a.one_sided {
            cmd.arg("--one-sided");
        }
        if let Some(t) = a.threads {
            cmd.args(["--threads", &t.to_string()]);
        }
        let t = Instant::now();
        let result = cmd.output().context("cannot run radiosity solve")?;
        let wall = t.elapsed().as_secs_f64();
        let _ = std::fs::remove_file(&out);
        if !result.status.success() {
            let _ = std::fs::remove_dir_all(&dir);
            bail!(
                "{n} patches: {}",
                String::from_utf8_lossy(&result.stderr).trim()
            );
        }
        let mut row = parse(&String::from_utf8_lossy(&result.stdout));
        row.wall = wall;
        println!(
            "{:>9} {:>11} {:>8} {:>9.2} {:>9.2} {:>8.3} {:>8.3} {:>9.2} {:>9.2} {:>10.0} {:>7.2}",
            row.patches,
            row.rays,
            row.iterations,
            row.wall,
            row.cpu,
            row.mesh,
            row.bvh,
            row.form_factors,
            row.solve,
            row.resident_mib,
            row.cpu / row.wall
        );
        rows.push(row);
    }
    let _ = std::fs::remove_dir_all(&dir);
    let fit = |f: &dyn Fn(&Row) -> f64| {
        fit_exponent(&rows.iter().map(|r| (r.patches, f(r))).collect::<Vec<_>>())
    };
    let show = |e: Option<f64>| e.map_or("—".to_string(), |e| format!("{e:.2}"));
    // The stages' own exponents come last: the rows' (the rays' cost, which memory makes grow
    // faster than the rays) and the solver's bookkeeping's; "—" where a stage took no time.
    println!(
        "fitted exponents against N: wall {}, cpu {}, rays {}, peak memory {}, rows {}, solve {}",
        show(fit(&|r| r.wall)),
        show(fit(&|r| r.cpu)),
        show(fit(&|r| r.rays)),
        show(fit(&|r| r.resident_mib)),
        show(fit(&|r| r.form_factors)),
        show(fit(&|r| r.solve))
    );
    Ok(())
}
