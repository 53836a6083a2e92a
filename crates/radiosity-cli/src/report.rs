//! Progress bars (only on a terminal) and the end-of-run summary.

use indicatif::{ProgressBar, ProgressStyle};
use radiosity::pipeline::{Event, Solution, Stage};
use radiosity::scene::Scene;

/// The progress bar of a solve: stage messages, then the unshot energy falling towards the
/// tolerance (position on a log scale).
pub struct Progress {
    bar: ProgressBar,
    log_tol: f64,
    last: u64,
}

impl Progress {
    /// A bar for a solve to `tolerance`.
    pub fn new(tolerance: f64) -> Self {
        let bar = ProgressBar::new(1000);
        bar.set_style(
            ProgressStyle::with_template("{spinner} {msg:<40} [{bar:30}] {elapsed_precise}")
                .expect("valid template")
                .progress_chars("=> "),
        );
        Self {
            bar,
            log_tol: tolerance.ln(),
            last: 0,
        }
    }

    /// Follow a pipeline event.
    pub fn event(&mut self, e: Event) {
        match e {
            Event::Stage(s) => self.bar.set_message(match s {
                Stage::Mesh => "meshing".to_string(),
                Stage::Bvh => "building the hierarchy".to_string(),
                Stage::Solve => "form factors".to_string(),
                Stage::Render => "rendering".to_string(),
            }),
            Event::Matrix(..) => self.bar.set_message("solving".to_string()),
            Event::Solve(s, _) => {
                // Update about every 64 iterations: cheap, and smooth enough.
                if s.iterations - self.last >= 64 || s.iterations == 0 {
                    self.last = s.iterations;
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
        }
    }

    /// Remove the bar.
    pub fn finish(self) {
        self.bar.finish_and_clear();
    }
}

/// A bar counting image rows.
pub fn rows_bar(rows: u32) -> ProgressBar {
    let bar = ProgressBar::new(rows as u64);
    bar.set_style(
        ProgressStyle::with_template(
            "{spinner} rendering {pos}/{len} rows [{bar:30}] {elapsed_precise}",
        )
        .expect("valid template")
        .progress_chars("=> "),
    );
    bar
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
    println!(
        "patches     {} (max edge {:.4} scene units)",
        s.mesh.len(),
        s.mesh.max_edge
    );
    println!("rays        {} in {} form-factor rows", ff.rays, ff.rows);
    println!(
        "iterations  {} by {} ({}; unshot energy left {:.3}% of emitted)",
        i.iterations,
        s.method,
        if i.converged {
            "converged"
        } else {
            "stopped at --max-iterations"
        },
        100.0 * i.unshot_fraction
    );
    println!(
        "energy      emitted {:.6e}: absorbed {:.2}%, escaped {:.2}%, unshot {:.2}%",
        e,
        100.0 * i.absorbed.sum() / e,
        100.0 * i.escaped.sum() / e,
        100.0 * i.unshot.sum() / e
    );
    let t = &s.timings;
    let mut line = format!(
        "time        mesh {:.3} s, hierarchy {:.3} s, form factors {:.3} s, solve {:.3} s",
        t.mesh, t.bvh, t.form_factors, t.solve
    );
    if let Some((r, w)) = render {
        line += &format!(", render {r:.3} s, write {w:.3} s");
    }
    println!("{line}");
    {
        use radiosity::experiment::MemoryProbe;
        println!(
            "memory      peak heap {:.1} MiB (every allocation since start, counted)",
            crate::alloc::Probe.peak() as f64 / (1024.0 * 1024.0)
        );
    }
}
