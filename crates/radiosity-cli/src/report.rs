//! Progress bars (only on a terminal) and the end-of-run summary.

use indicatif::{ProgressBar, ProgressStyle};
use radiosity::observe::{Event, Observer, Stage};
use radiosity::pipeline::Solution;
use radiosity::scene::Scene;
use std::sync::atomic::{AtomicU64, Ordering};

/// The progress bar of a run: stage messages, rows of F and of the image, then the unshot
/// energy falling towards the tolerance (position on a log scale); warnings are printed. An
/// [`Observer`] for every stage.
pub struct Progress {
    bar: ProgressBar,
    log_tol: f64,
    last: AtomicU64,
}

fn style(template: &str) -> ProgressStyle {
    ProgressStyle::with_template(template)
        .expect("valid template")
        .progress_chars("=> ")
}

impl Progress {
    /// A bar for a run that solves to `tolerance`.
    pub fn new(tolerance: f64) -> Self {
        let bar = ProgressBar::new(1000);
        bar.set_style(style("{spinner} {msg:<40} [{bar:30}] {elapsed_precise}"));
        Self {
            bar,
            log_tol: tolerance.ln(),
            last: AtomicU64::new(0),
        }
    }

    /// Remove the bar.
    pub fn finish(&self) {
        self.bar.finish_and_clear();
    }
}

impl Observer for Progress {
    fn event(&self, e: Event<'_>) {
        match e {
            Event::Stage(s) => {
                let message = match s {
                    Stage::Mesh => "meshing",
                    Stage::Bvh => "building the hierarchy",
                    Stage::FormFactors => "form factors",
                    Stage::Solve => "solving",
                    Stage::Render => "rendering",
                    Stage::Experiment => "experiment",
                };
                self.bar.set_message(message);
                self.bar.set_position(0);
            }
            Event::Progress { stage, done, total } => {
                if matches!(stage, Stage::FormFactors | Stage::Render) && total > 0 {
                    self.bar.set_position(1000 * done / total);
                }
            }
            Event::Solve(s, _) => {
                // Update about every 64 iterations: cheap, and smooth enough.
                let last = self.last.load(Ordering::Relaxed);
                if s.iterations.wrapping_sub(last) >= 64 || s.iterations == 0 {
                    self.last.store(s.iterations, Ordering::Relaxed);
                    let f = s.unshot_fraction.max(1e-300);
                    let pos = (f.ln() / self.log_tol).clamp(0.0, 1.0);
                    self.bar.set_position((pos * 1000.0) as u64);
                    self.bar.set_message(format!(
                        "solving: {} iterations, unshot {:.2}%",
                        s.iterations,
                        100.0 * s.unshot_fraction
                    ));
                }
            }
            Event::Warning(w) => self.bar.suspend(|| eprintln!("radiosity: warning: {w}")),
            Event::Matrix(..) | Event::Case { .. } | Event::CaseEnd { .. } => {}
        }
    }
}

/// This process's CPU seconds (user + system) and peak resident set in bytes, from `/proc`
/// (Linux; `None` elsewhere). Clock ticks are taken as 100 per second, Linux's `USER_HZ`.
pub fn resources() -> Option<(f64, u64)> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    // Fields after the parenthesised command name; utime and stime are the 14th and 15th.
    let rest = &stat[stat.rfind(')')? + 2..];
    let f: Vec<&str> = rest.split_whitespace().collect();
    let ticks: u64 = f.get(11)?.parse::<u64>().ok()? + f.get(12)?.parse::<u64>().ok()?;
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let hwm = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: u64 = hwm.split_whitespace().nth(1)?.parse().ok()?;
    Some((ticks as f64 / 100.0, kib * 1024))
}

/// Print what was done: patches, rays, iterations, energy, time per stage.
pub fn summary(scene: &Scene, s: &Solution, render: Option<(f64, f64)>) {
    let i = &s.info;
    let ff = &s.form_factors;
    let e = i.emitted.sum();
    println!(
        "scene       {} ({} polygons)",
        scene.name,
        scene.polygons.len()
    );
    match &s.hierarchy {
        Some(h) => {
            let hi = &h.hierarchy.info;
            println!(
                "patches     {} leaf elements of {} ({} levels at most; minimum area {:.4e} square scene units)",
                s.mesh.len(),
                hi.elements,
                h.hierarchy
                    .elements
                    .items
                    .iter()
                    .map(|e| e.level)
                    .max()
                    .unwrap_or(0)
                    + 1,
                hi.min_area
            );
            println!(
                "links       {} ({:.1} an element, {:.1} a leaf) over {} clusters; {} dropped as invisible; {} refinements in {} passes; {} visibility rays; {:.1} MiB",
                hi.links,
                hi.links as f64 / hi.elements.max(1) as f64,
                hi.links as f64 / s.mesh.len().max(1) as f64,
                hi.clusters,
                hi.invisible,
                hi.refinements,
                hi.passes,
                hi.rays,
                hi.bytes as f64 / (1024.0 * 1024.0)
            );
            if hi.twins > 0 {
                println!(
                    "twins       {} input pieces coincide with an earlier one (same corners, same side): each pair solved as one surface",
                    hi.twins
                );
            }
        }
        None => {
            println!(
                "patches     {} (max edge {:.4} scene units)",
                s.mesh.len(),
                s.mesh.max_edge
            );
            println!("rays        {} in {} form-factor rows", ff.rays, ff.rows);
        }
    }
    println!(
        "iterations  {} by {} ({}; unshot energy left {:.3}% of emitted)",
        i.iterations,
        s.method_name(),
        if i.converged {
            "converged".to_string()
        } else {
            format!(
                "stopped after {} iterations without converging",
                i.iterations
            )
        },
        100.0 * i.unshot_fraction
    );
    if i.estimated_error > 0.0 {
        println!(
            "error       estimated standard error of B {:.2}% (area-weighted RMS, relative)",
            100.0 * i.estimated_error
        );
    }
    println!(
        "energy      emitted {:.6e}: absorbed {:.2}%, escaped {:.2}%, unshot {:.2}%",
        e,
        100.0 * i.absorbed.sum() / e,
        100.0 * i.escaped.sum() / e,
        100.0 * i.unshot.sum() / e
    );
    let t = &s.timings;
    let mut line = format!(
        "time        mesh {:.3} s, hierarchy {:.3} s, {} {:.3} s, solve {:.3} s",
        t.mesh,
        t.bvh,
        if s.hierarchy.is_some() {
            "link refinement"
        } else {
            "form factors"
        },
        t.form_factors,
        t.solve
    );
    if t.solve_rays > 0.0 {
        line += &format!(" (rays {:.3} s)", t.solve_rays);
    }
    if let Some((r, w)) = render {
        line += &format!(", render {r:.3} s, write {w:.3} s");
    }
    println!("{line}");
    // Resident memory is what the run used; the heap count also includes memory reserved and
    // never touched (a linear-algebra library's per-thread scratch), so it comes second.
    let heap = {
        use radiosity_experiments::MemoryProbe;
        crate::alloc::Probe.peak() as f64 / (1024.0 * 1024.0)
    };
    match resources() {
        Some((cpu, resident)) => {
            println!(
                "memory      peak resident {:.1} MiB (heap allocated at most {heap:.1} MiB)",
                resident as f64 / (1024.0 * 1024.0)
            );
            println!("cpu         {cpu:.2} s (user and system, all threads)");
        }
        None => println!("memory      heap allocated at most {heap:.1} MiB"),
    }
}

/// The lines of a distributed run: ranks and their blocks, traffic, balance, sweeps.
pub fn ranks(r: &radiosity::distributed::Report) {
    let blocks: Vec<String> = r
        .blocks
        .iter()
        .map(|b| format!("{}–{}", b.start, b.end.saturating_sub(1)))
        .collect();
    let shown = blocks.len().min(8);
    println!(
        "ranks       {} ({}): patches {}{}",
        r.blocks.len(),
        r.transport,
        blocks[..shown].join(" | "),
        if blocks.len() > shown { " | …" } else { "" }
    );
    let waiting = r.traffic.iter().map(|t| t.seconds).fold(0.0, f64::max);
    let calls = r.traffic.first().map_or(0, |t| t.calls);
    println!(
        "traffic     {:.2} MiB sent by all ranks in {calls} collectives, {waiting:.3} s in them at most; load balance {:.2} (mean / busiest rank's work){}",
        r.bytes_sent() as f64 / (1 << 20) as f64,
        r.balance(),
        if r.pilot_seconds > 0.0 {
            format!("; cost pilot {:.3} s", r.pilot_seconds)
        } else {
            String::new()
        }
    );
    if !r.sweeps.is_empty() {
        let n = r.sweeps.len() as f64;
        let mean = r.sweeps.iter().map(|s| s.seconds).sum::<f64>() / n;
        let comm = r.sweeps.iter().map(|s| s.communication).sum::<f64>() / n;
        println!(
            "sweeps      {} of {:.4} s each ({:.4} s of it exchanging B), {:.3} MiB a rank a sweep",
            r.sweeps.len(),
            mean,
            comm,
            // Each rank all-gathers 48 bytes (B and H) a patch.
            48.0 * r.blocks.last().map_or(0, |b| b.end) as f64 / (1 << 20) as f64
        );
    }
}

/// The summary as one JSON object (`--report json`): what [`summary`] prints, as numbers.
/// Keys: `scene`, `polygons`, `patches`, `rays`, `rows`, `iterations`, `method`, `converged`,
/// `unshot_fraction`, `estimated_error`, `energy` (`emitted`, `absorbed`, `escaped`,
/// `unshot`: sums over the three channels), `seconds` (`mesh`, `bvh`, `form_factors`,
/// `solve`, `solve_rays`, and `render`, `write` where a picture was made), `memory`
/// (`peak_resident_bytes`, `heap_peak_bytes`), `cpu_seconds`; for hierarchical radiosity also
/// `elements` and `links`. Absent measurements are `null`.
pub fn summary_json(scene: &Scene, s: &Solution, render: Option<(f64, f64)>) -> serde_json::Value {
    use radiosity_experiments::MemoryProbe;
    use serde_json::json;
    let i = &s.info;
    let t = &s.timings;
    let mut seconds = json!({
        "mesh": t.mesh,
        "bvh": t.bvh,
        "form_factors": t.form_factors,
        "solve": t.solve,
        "solve_rays": t.solve_rays,
    });
    if let Some((r, w)) = render {
        seconds["render"] = json!(r);
        seconds["write"] = json!(w);
    }
    let res = resources();
    let mut v = json!({
        "scene": scene.name,
        "polygons": scene.polygons.len(),
        "patches": s.mesh.len(),
        "rays": s.form_factors.rays,
        "rows": s.form_factors.rows,
        "iterations": i.iterations,
        "method": s.method_name(),
        "converged": i.converged,
        "unshot_fraction": i.unshot_fraction,
        "estimated_error": i.estimated_error,
        "energy": {
            "emitted": i.emitted.sum(),
            "absorbed": i.absorbed.sum(),
            "escaped": i.escaped.sum(),
            "unshot": i.unshot.sum(),
        },
        "seconds": seconds,
        "memory": {
            "peak_resident_bytes": res.map(|r| r.1),
            "heap_peak_bytes": crate::alloc::Probe.peak(),
        },
        "cpu_seconds": res.map(|r| r.0),
    });
    if let Some(h) = &s.hierarchy {
        v["elements"] = json!(h.hierarchy.info.elements);
        v["links"] = json!(h.hierarchy.info.links);
    }
    v
}
