//! `radiosity experiment convergence|complexity`: run the library's experiments with a
//! progress bar per case, and write their CSVs, plots and a Markdown summary into `--out`.

use crate::args::{ExperimentArgs, ExperimentKind};
use anyhow::{bail, Context, Result};
use indicatif::{ProgressBar, ProgressStyle};
use radiosity::observe::{Event, Observer};
use radiosity::solve::Solver;
use radiosity_experiments as exp;
use radiosity_experiments::complexity::{self, Quantity, CASES};
use radiosity_experiments::convergence::{self, paper_name, Case, Curve};
use radiosity_experiments::plot::{write_plot, Mark, Plot, Series};
use std::fmt::Write as _;
use std::path::Path;
use std::sync::Mutex;

/// One indicatif bar per case (hidden when stderr is not a terminal); the case's summary is
/// printed when it ends.
struct Bars {
    bar: Mutex<Option<ProgressBar>>,
}

impl Observer for Bars {
    fn event(&self, e: Event<'_>) {
        let mut bar = self.bar.lock().expect("no panic while holding the bar");
        match e {
            Event::Case { label, total } => {
                let b = ProgressBar::new(total.max(1));
                b.set_style(
                    ProgressStyle::with_template(
                        "{msg:<42} [{bar:30}] {pos}/{len} {elapsed_precise}",
                    )
                    .expect("valid template")
                    .progress_chars("=> "),
                );
                b.set_message(label.to_string());
                *bar = Some(b);
            }
            Event::Progress { done, .. } => {
                if let Some(b) = bar.as_ref() {
                    b.set_position(done);
                }
            }
            Event::CaseEnd { summary } => {
                if let Some(b) = bar.take() {
                    let label = b.message();
                    b.finish_and_clear();
                    println!("{label}: {summary} ({:.1} s)", b.elapsed().as_secs_f64());
                }
            }
            Event::Warning(w) => eprintln!("radiosity: warning: {w}"),
            _ => {}
        }
    }
}

fn write_text(path: &Path, text: &str) -> Result<()> {
    radiosity::export::write_text(path, text)?;
    Ok(())
}

/// Run the experiment `a.kind`.
pub fn run(a: ExperimentArgs) -> Result<()> {
    if !(a.sweeps > 0.0 && a.sweeps.is_finite()) {
        bail!("--sweeps {}: must be a positive number", a.sweeps);
    }
    if a.kind == ExperimentKind::Convergence && a.sizes.is_some() {
        bail!("--sizes applies to the complexity experiment only");
    }
    if let Some(s) = &a.sizes {
        if s.len() < 2 || s.contains(&0) {
            bail!("--sizes: at least two positive patch counts are needed");
        }
    }
    std::fs::create_dir_all(&a.out)
        .with_context(|| format!("{}: cannot create the folder", a.out.display()))?;
    let bars = Bars {
        bar: Mutex::new(None),
    };
    match a.kind {
        ExperimentKind::Convergence => {
            let params = convergence::Params {
                quick: a.quick,
                sweeps: a.sweeps,
                seed: a.seed,
                ..Default::default()
            };
            convergence_experiment(&params, &a.out, &bars)
        }
        ExperimentKind::Complexity => {
            let mut params = if a.quick {
                complexity::Params::quick()
            } else {
                complexity::Params::full()
            };
            if let Some(s) = &a.sizes {
                params.sizes = s.clone();
            }
            params.seed = a.seed;
            complexity_experiment(&params, &a.out, &bars)
        }
    }
}

fn label(m: Solver) -> String {
    match paper_name(m) {
        Some(p) => format!("{m} ({p})"),
        None => m.name().to_string(),
    }
}

fn convergence_experiment(params: &convergence::Params, out: &Path, bars: &Bars) -> Result<()> {
    let mut cases = convergence::cases(params, bars)?;
    let mut summary = String::from(
        "case,patches,method,error_at_quarter_n,error_at_half_n,error_at_n,error_at_2n,iterations_to_1e-3,seconds_to_1e-3\n",
    );
    let mut md = String::new();
    for case in &mut cases {
        let curves = convergence::run_case(case, params, bars)?;
        write_case(case, &curves, out)?;
        let n = case.system.len();
        let _ = writeln!(
            md,
            "\n### {}{}\n\n| method | N/4 | N/2 | N | 2N | iterations to 1e-3 | CPU s to 1e-3 |\n|---|---|---|---|---|---|---|",
            case.title,
            case.figure
                .map(|f| format!(" (paper's figure {f})"))
                .unwrap_or_default()
        );
        for c in &curves {
            let at = |k: f64| c.error_at(k * n as f64);
            let cell = |v: Option<f64>| v.map_or("–".into(), |e| format!("{e:.2e}"));
            let below = c.settled_below(1e-3);
            let _ = writeln!(
                summary,
                "{},{},{},{},{},{},{},{},{}",
                case.name,
                n,
                c.method,
                at(0.25).map_or(String::new(), |e| e.to_string()),
                at(0.5).map_or(String::new(), |e| e.to_string()),
                at(1.0).map_or(String::new(), |e| e.to_string()),
                at(2.0).map_or(String::new(), |e| e.to_string()),
                below.map_or(String::new(), |p| p.iteration.to_string()),
                below.map_or(String::new(), |p| p.seconds.to_string()),
            );
            if c.method == Solver::Gauss {
                let _ = writeln!(
                    md,
                    "| {} | – | – | – | – | direct | {} |",
                    label(c.method),
                    below.map_or("–".into(), |p| format!("{:.4}", p.seconds))
                );
                continue;
            }
            let _ = writeln!(
                md,
                "| {} | {} | {} | {} | {} | {} | {} |",
                label(c.method),
                cell(at(0.25)),
                cell(at(0.5)),
                cell(at(1.0)),
                cell(at(2.0)),
                below.map_or("–".into(), |p| format!("{:.0}", p.iteration)),
                below.map_or("–".into(), |p| format!("{:.4}", p.seconds)),
            );
        }
    }
    write_text(&out.join("convergence-summary.csv"), &summary)?;
    let md = format!(
        "## Convergence: eq. 22 error after N/4, N/2, N and 2N iterations\n\nGenerated by `radiosity experiment convergence{}`.\n{md}",
        if params.quick { " --quick" } else { "" }
    );
    write_text(&out.join("convergence.md"), &md)?;
    println!("{md}");
    println!("wrote {}", out.display());
    Ok(())
}

fn write_case(case: &Case, curves: &[Curve], out: &Path) -> Result<()> {
    let mut csv = String::from("method,iteration,seconds,error\n");
    for c in curves {
        for p in &c.points {
            let _ = writeln!(
                csv,
                "{},{},{},{}",
                c.method, p.iteration, p.seconds, p.error
            );
        }
    }
    write_text(&out.join(format!("convergence-{}.csv", case.name)), &csv)?;
    // Gauss' error is rounding noise (B* is its own answer): it is drawn at the lowest error
    // the iterative methods reached, as a marker of when the direct solution is ready.
    let lowest = curves
        .iter()
        .filter(|c| c.method != Solver::Gauss)
        .flat_map(|c| c.points.iter().map(|p| p.error.abs()))
        .filter(|&e| e > 0.0)
        .fold(1.0f64, f64::min);
    let floor = |m: Solver, e: f64| {
        if m == Solver::Gauss {
            lowest
        } else {
            e.abs().max(1e-12)
        }
    };
    let series = |x: fn(&convergence::Point) -> f64, with_gauss: bool| -> Vec<Series> {
        curves
            .iter()
            .filter(|c| with_gauss || c.method != Solver::Gauss)
            .map(|c| Series {
                name: if c.method == Solver::Gauss {
                    "gauss (direct: time to B*)".into()
                } else {
                    label(c.method)
                },
                points: c
                    .points
                    .iter()
                    .map(|p| (x(p), floor(c.method, p.error)))
                    .collect(),
                mark: if c.method == Solver::Gauss {
                    Mark::LinePoints
                } else {
                    Mark::Line
                },
            })
            .collect()
    };
    let figure = case
        .figure
        .map(|f| format!(" (cf. figure {f})"))
        .unwrap_or_default();
    write_plot(
        &out.join(format!("convergence-{}", case.name)),
        &Plot {
            title: format!("{}{figure}", case.title),
            x_label: "iteration (rows or columns of F; stochastic: photons / n)".into(),
            y_label: "|error| of eq. 22".into(),
            log_x: false,
            log_y: true,
            series: series(|p| p.iteration, false),
        },
    )?;
    write_plot(
        &out.join(format!("convergence-{}-time", case.name)),
        &Plot {
            title: format!("{}: error against CPU time", case.title),
            x_label: "CPU seconds (F stored; error evaluation excluded)".into(),
            y_label: "|error| of eq. 22".into(),
            log_x: true,
            log_y: true,
            series: series(|p| p.seconds, true),
        },
    )?;
    Ok(())
}

fn complexity_experiment(params: &complexity::Params, out: &Path, bars: &Bars) -> Result<()> {
    let probe = crate::alloc::Probe;
    let ms = complexity::run_all(params, Some(&probe), bars)?;
    let opt = |v: Option<f64>| v.map_or(String::new(), |x| x.to_string());
    let mut csv = String::from("case,patches,seconds,iterations,peak_bytes,nnz,converged\n");
    for m in &ms {
        let _ = writeln!(
            csv,
            "{},{},{},{},{},{},{}",
            m.case,
            m.patches,
            m.seconds,
            opt(m.iterations),
            m.peak_bytes.map_or(String::new(), |b| b.to_string()),
            m.nnz.map_or(String::new(), |b| b.to_string()),
            m.converged.map_or(String::new(), |b| b.to_string()),
        );
    }
    write_text(&out.join("complexity.csv"), &csv)?;
    let fits = complexity::fits(&ms);
    let mut fcsv =
        String::from("case,quantity,fitted_exponent,paper_exponent,paper_claim,within_0.3\n");
    let mut md = format!(
        "## Complexity: fitted exponents of N\n\nGenerated by `radiosity experiment complexity{}`; Cornell box, N = {}; hemicube P = {}, Monte Carlo n = {} rays per row, photons n = {}; tolerance {} ({} for stochastic); {} threads.\n\n| case | quantity | fitted | paper | claim |\n|---|---|---|---|---|\n",
        if params.sizes == complexity::Params::quick().sizes { " --quick" } else { "" },
        ms.iter()
            .filter(|m| m.case == CASES[0])
            .map(|m| m.patches.to_string())
            .collect::<Vec<_>>()
            .join(", "),
        params.resolution,
        params.rays,
        params.photons,
        params.tolerance,
        params.stochastic_tolerance,
        rayon::current_num_threads()
    );
    for f in &fits {
        let within = f.fitted.map(|x| (x - f.claim.exponent).abs() <= 0.3);
        let _ = writeln!(
            fcsv,
            "{},{},{},{},{},{}",
            f.claim.case,
            f.claim.quantity.name(),
            opt(f.fitted),
            f.claim.exponent,
            f.claim.text,
            within.map_or(String::new(), |w| w.to_string())
        );
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} | {} |",
            f.claim.case,
            f.claim.quantity.name(),
            f.fitted.map_or("–".into(), |x| format!("{x:.2}")),
            f.claim.exponent,
            f.claim.text
        );
    }
    write_text(&out.join("complexity-fits.csv"), &fcsv)?;
    let _ = writeln!(
        md,
        "\n| case | N | seconds | iterations | peak memory | nnz |\n|---|---|---|---|---|---|"
    );
    for m in &ms {
        let _ = writeln!(
            md,
            "| {} | {} | {:.4} | {} | {} | {} |",
            m.case,
            m.patches,
            m.seconds,
            m.iterations.map_or("–".into(), |x| format!("{x:.1}")),
            m.peak_bytes.map_or("–".into(), human_bytes),
            m.nnz.map_or("–".into(), |x| x.to_string()),
        );
    }
    for (q, stem, title) in [
        (Quantity::Seconds, "complexity-time", "time against N"),
        (
            Quantity::Memory,
            "complexity-memory",
            "peak heap memory against N",
        ),
        (
            Quantity::Iterations,
            "complexity-iterations",
            "iterations to the tolerance against N",
        ),
    ] {
        let series: Vec<Series> = CASES
            .iter()
            .filter_map(|&case| {
                let pts: Vec<(f64, f64)> = ms
                    .iter()
                    .filter(|m| m.case == case)
                    .filter_map(|m| Some((m.patches as f64, m.value(q)?)))
                    .collect();
                let fit = exp::fit_exponent(&pts)?;
                Some(Series {
                    name: format!("{case} (slope {fit:.2})"),
                    points: pts,
                    mark: Mark::LinePoints,
                })
            })
            .collect();
        write_plot(
            &out.join(stem),
            &Plot {
                title: format!("Cornell box: {title}"),
                x_label: "patches N".into(),
                y_label: match q {
                    Quantity::Seconds => "seconds",
                    Quantity::Memory => "bytes",
                    Quantity::Iterations => "sweeps (jacobi, gauss-seidel), shots, photons",
                }
                .into(),
                log_x: true,
                log_y: true,
                series,
            },
        )?;
    }
    write_text(&out.join("complexity.md"), &md)?;
    println!("{md}");
    println!("wrote {}", out.display());
    Ok(())
}

fn human_bytes(b: u64) -> String {
    if b >= 1 << 20 {
        format!("{:.1} MiB", b as f64 / (1u64 << 20) as f64)
    } else {
        format!("{:.1} KiB", b as f64 / 1024.0)
    }
}
