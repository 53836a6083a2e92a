//! `radiosity-bench scale SCENE --sizes N,N,…`: solve a scene at each size with one method,
//! each size in a fresh child process (`radiosity solve`), so that its CPU time and peak
//! resident memory are its own; print patches, rays, wall and CPU seconds, the time of each
//! stage, peak resident memory, and the fitted exponents of time against N; and, so that a
//! run's bookkeeping can be read against the machine it met, the share of the wall time it took
//! and how long a value took to go between two cores and back just before and just after it.

use crate::args::ScaleArgs;
use anyhow::{bail, Context, Result};
use radiosity_experiments::fit_exponent;
use std::process::Command;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::{Duration, Instant};

/// Batches of round trips that [`cross_core_round_trip`] times, their size, and the most time
/// it spends.
const BATCHES: usize = 11;
const TRIPS: u64 = 2_000;
const TRIPS_BUDGET: Duration = Duration::from_millis(200);

/// Nanoseconds for a value written by one thread to be seen by another and answered: between
/// two threads that spin (so that each holds a core), the median over [`BATCHES`] batches of
/// each batch's mean of [`TRIPS`] round trips (the first trips also wait for the new thread to
/// find its core); batches that the [`TRIPS_BUDGET`] cuts short count their mean so far.
/// `None` on a machine of one core.
///
/// Shooting methods hand half of a shot's receivers to the other core and read back what it
/// wrote, so that their bookkeeping depends on this latency as no other stage does. On a
/// virtual machine it can change from minute to minute, as the host places the virtual cores
/// on cores that share a cache or not (docs/notes/workbench.md).
fn cross_core_round_trip() -> Option<f64> {
    if std::thread::available_parallelism().map_or(1, |n| n.get()) < 2 {
        return None;
    }
    // Odd: asked, even: answered; each on a line of its own.
    #[repr(align(128))]
    struct Line<T>(T);
    let value = Line(AtomicU64::new(0));
    let stop = Line(AtomicBool::new(false));
    std::thread::scope(|s| {
        s.spawn(|| {
            let mut next = 1;
            let mut spins = 0u32;
            while next < 2 * TRIPS * BATCHES as u64 {
                if value.0.load(Ordering::Acquire) == next {
                    value.0.store(next + 1, Ordering::Release);
                    next += 2;
                } else {
                    spins = spins.wrapping_add(1);
                    if spins % 1024 == 0 && stop.0.load(Ordering::Relaxed) {
                        return;
                    }
                    std::hint::spin_loop();
                }
            }
        });
        let start = Instant::now();
        let mut means = Vec::with_capacity(BATCHES);
        let mut k = 0;
        'batches: for _ in 0..BATCHES {
            let batch = Instant::now();
            let mut done = 0;
            for _ in 0..TRIPS {
                value.0.store(2 * k + 1, Ordering::Release);
                let mut spins = 0u32;
                while value.0.load(Ordering::Acquire) != 2 * k + 2 {
                    spins = spins.wrapping_add(1);
                    if spins % 1024 == 0 && start.elapsed() > TRIPS_BUDGET {
                        // A trip that did not come back counts as one.
                        means.push(batch.elapsed().as_secs_f64() / (done + 1) as f64);
                        break 'batches;
                    }
                    std::hint::spin_loop();
                }
                k += 1;
                done += 1;
            }
            means.push(batch.elapsed().as_secs_f64() / done as f64);
        }
        stop.0.store(true, Ordering::Relaxed);
        means.sort_by(f64::total_cmp);
        Some(means[means.len() / 2] * 1e9)
    })
}

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

/// One solve's figures from the child's `--report json`.
fn parse(report: &str) -> Result<Row> {
    let v: serde_json::Value = serde_json::from_str(report.trim())
        .context("radiosity solve --report json printed no JSON object")?;
    let num = |p: &str| {
        v.pointer(p)
            .and_then(serde_json::Value::as_f64)
            .unwrap_or(f64::NAN)
    };
    // A solver's own rays (stochastic Jacobi's), part of its solve: counted with the rows, so
    // that `solve s` is everything but rays for every method.
    let solve_rays = num("/seconds/solve_rays");
    Ok(Row {
        patches: num("/patches"),
        rays: num("/rays"),
        iterations: num("/iterations"),
        wall: f64::NAN,
        cpu: num("/cpu_seconds"),
        mesh: num("/seconds/mesh"),
        bvh: num("/seconds/bvh"),
        form_factors: num("/seconds/form_factors") + solve_rays,
        solve: num("/seconds/solve") - solve_rays,
        resident_mib: num("/memory/peak_resident_bytes") / (1024.0 * 1024.0),
    })
}

/// Run the scale benchmark.
pub fn run(a: &ScaleArgs, threads: Option<usize>) -> Result<()> {
    let (scene, sizes) = (a.scene.as_str(), &a.sizes);
    if sizes.is_empty() || sizes.contains(&0) {
        bail!("--sizes: patch counts must be positive");
    }
    if a.bookkeeping {
        return crate::bookkeeping::run(a);
    }
    let exe = crate::radiosity_exe()?;
    let dir = std::env::temp_dir().join(format!("radiosity-scale-{}", std::process::id()));
    std::fs::create_dir_all(&dir).with_context(|| format!("cannot create {}", dir.display()))?;
    println!(
        "scale: {scene}, {} to {:.2}% unshot, {} threads; each size solved in a fresh process",
        a.solve.solver.0,
        100.0 * a.solve.tolerance,
        threads.unwrap_or_else(rayon::current_num_threads)
    );
    println!(
        "{:>9} {:>11} {:>8} {:>9} {:>9} {:>8} {:>8} {:>9} {:>9} {:>10} {:>8} {:>7} {:>9} {:>9}",
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
        "cpu/wall",
        "solve %",
        "xcore0 ns",
        "xcore1 ns"
    );
    let mut rows = Vec::new();
    for &n in sizes {
        let out = dir.join(format!("{n}.csv"));
        let mut cmd = Command::new(&exe);
        cmd.arg("solve")
            .arg(scene)
            .args(["--patches", &n.to_string()])
            .args(["--solver", a.solve.solver.0.name()])
            .args(["--tolerance", &a.solve.tolerance.to_string()])
            .args(["--iteration-rays", &a.solve.iteration_rays.to_string()])
            .args(["--gather-rays", &a.solve.gather_rays.to_string()])
            .args(["--report", "json"])
            .arg("--out")
            .arg(&out);
        if a.solve.one_sided {
            cmd.arg("--one-sided");
        }
        if let Some(t) = threads {
            cmd.args(["--threads", &t.to_string()]);
        }
        let before = cross_core_round_trip();
        let t = Instant::now();
        let result = cmd.output().context("cannot run radiosity solve")?;
        let wall = t.elapsed().as_secs_f64();
        let after = cross_core_round_trip();
        let _ = std::fs::remove_file(&out);
        if !result.status.success() {
            let _ = std::fs::remove_dir_all(&dir);
            bail!(
                "{n} patches: {}",
                String::from_utf8_lossy(&result.stderr).trim()
            );
        }
        let mut row = parse(&String::from_utf8_lossy(&result.stdout))?;
        row.wall = wall;
        let [xcore0, xcore1] =
            [before, after].map(|t| t.map_or("—".to_string(), |t| format!("{t:.0}")));
        println!(
            "{:>9} {:>11} {:>8} {:>9.2} {:>9.2} {:>8.3} {:>8.3} {:>9.2} {:>9.2} {:>10.0} {:>8.2} {:>7.1} {:>9} {:>9}",
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
            row.cpu / row.wall,
            100.0 * row.solve / row.wall,
            xcore0,
            xcore1
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
