//! `radiosity-bench pictures SCENE`: CPU time against picture error for the three ways to
//! make a picture, each run in a fresh child process (`radiosity render … -o X.pfm`) so its
//! CPU time is its own, each compared with one path-traced reference (relative RMSE with the
//! emitters left out, [`radiosity::render::compare`]).
//!
//! The reference has noise of its own, σ_ref. The path tracer's runs are unbiased, so their
//! squared errors are σ₁²/n + σ_ref² for n paths a pixel: a least-squares fit over them gives
//! σ_ref, and every error is also reported with it taken out, √(e² − σ_ref²).

use crate::args::PicturesArgs;
use anyhow::{bail, Context, Result};
use radiosity::render::compare::{difference, read_pfm};
use radiosity_experiments::plot::{write_plot, Mark, Plot, Series};
use std::fmt::Write as _;
use std::path::Path;
use std::process::Command;
use std::time::Instant;

/// One run: integrator, its settings (render flags), CPU and wall seconds, errors.
struct Run {
    integrator: &'static str,
    label: String,
    args: Vec<String>,
    cpu: f64,
    wall: f64,
    rmse: f64,
    bias: f64,
    spp: f64,
}

fn ladder() -> Vec<Run> {
    let mut runs = Vec::new();
    let mut add = |integrator: &'static str, label: &str, args: &str, spp: f64| {
        runs.push(Run {
            integrator,
            label: label.to_string(),
            args: args.split_whitespace().map(String::from).collect(),
            cpu: 0.0,
            wall: 0.0,
            rmse: 0.0,
            bias: 0.0,
            spp,
        })
    };
    for n in [1000, 3000, 10000, 30000] {
        add(
            "radiosity",
            &format!("{n} patches"),
            &format!("--integrator radiosity --patches {n} --spp 16"),
            16.0,
        );
    }
    for (n, spp, cache) in [
        (3000, 4, 512),
        (10000, 16, 1024),
        (10000, 64, 1024),
        (30000, 64, 2048),
    ] {
        add(
            "gather",
            &format!("{n} patches, {spp} spp, cache {cache}"),
            &format!("--integrator gather --patches {n} --spp {spp} --cache-samples {cache}"),
            spp as f64,
        );
    }
    // The way to 1 %: a finer mesh, gathers followed one level deeper near corners, a finer
    // cache, and enough samples for the direct light's noise.
    add(
        "gather",
        "100000 patches, 512 spp, cache 4096, near 3",
        "--integrator gather --patches 100000 --spp 512 --cache-samples 4096 --gather-near 3 --cache-accuracy 0.05",
        512.0,
    );
    for spp in [64, 256, 1024, 4096] {
        add(
            "path",
            &format!("{spp} spp"),
            &format!("--integrator path --spp {spp}"),
            spp as f64,
        );
    }
    runs
}

/// CPU seconds from a child `radiosity render --report json`.
fn cpu_of(stdout: &str) -> Result<f64> {
    let v: serde_json::Value = serde_json::from_str(stdout.trim())
        .context("radiosity render --report json printed no JSON object")?;
    Ok(v.get("cpu_seconds")
        .and_then(serde_json::Value::as_f64)
        .unwrap_or(f64::NAN))
}

fn render(exe: &Path, scene: &str, size: u32, args: &[String], out: &Path) -> Result<(f64, f64)> {
    let mut cmd = Command::new(exe);
    cmd.arg("render")
        .arg(scene)
        .args(["--width", &size.to_string(), "--height", &size.to_string()])
        .args(args)
        .args(["--report", "json"])
        .arg("-o")
        .arg(out);
    let t = Instant::now();
    let result = cmd.output().context("cannot run radiosity render")?;
    let wall = t.elapsed().as_secs_f64();
    if !result.status.success() {
        bail!(
            "render {}: {}",
            args.join(" "),
            String::from_utf8_lossy(&result.stderr).trim()
        );
    }
    Ok((cpu_of(&String::from_utf8_lossy(&result.stdout))?, wall))
}

/// Run the picture benchmark.
pub fn run(a: &PicturesArgs) -> Result<()> {
    let scene = a.scene.as_str();
    if a.size == 0 || a.size > 4096 {
        bail!("--size {}: between 1 and 4096 pixels", a.size);
    }
    if a.reference_spp == 0 {
        bail!("--reference-spp 0: at least one path per pixel is needed");
    }
    let read_reference = |path: &Path| -> Result<radiosity::render::Image> {
        let image = read_pfm(path)?;
        if (image.width, image.height) != (a.size, a.size) {
            bail!(
                "{}: the reference is {}×{}, the pictures {}×{} (give --size)",
                path.display(),
                image.width,
                image.height,
                a.size,
                a.size
            );
        }
        // A relative error needs a reference with some light and nothing but numbers.
        if let Some(k) = image
            .pixels
            .iter()
            .position(|p| !p.iter().all(|c| c.is_finite()))
        {
            bail!(
                "{}: pixel {} of the reference is not a finite number (NaN or infinity); give a finite PFM",
                path.display(),
                k
            );
        }
        if image.pixels.iter().all(|p| p.iter().all(|&c| c == 0.0)) {
            bail!(
                "{}: the reference is black everywhere; a relative error against it is undefined",
                path.display()
            );
        }
        Ok(image)
    };
    // Given references are checked before the output folder is made, so a refused one leaves
    // nothing behind.
    let given = a.reference.as_deref().map(read_reference).transpose()?;
    let given_b = a.reference_b.as_deref().map(read_reference).transpose()?;
    let exe = crate::radiosity_exe()?;
    std::fs::create_dir_all(&a.out)
        .with_context(|| format!("cannot create {}", a.out.display()))?;
    let reference_path = match &a.reference {
        Some(p) => p.clone(),
        None => {
            let p = a.out.join("reference.pfm");
            println!(
                "reference: path tracing {scene} at {} paths a pixel …",
                a.reference_spp
            );
            let args: Vec<String> =
                format!("--integrator path --spp {} --seed 1000003", a.reference_spp)
                    .split_whitespace()
                    .map(String::from)
                    .collect();
            let (cpu, _) = render(&exe, scene, a.size, &args, &p)?;
            println!("reference: {cpu:.1} CPU-s");
            p
        }
    };
    let mut reference = match given {
        Some(r) => r,
        None => read_reference(&reference_path)?,
    };
    // With a second reference: the noise of one is their difference over √2, and the pictures
    // are compared with their average, whose noise is that over √2 again.
    let measured_var = match given_b {
        Some(b) => {
            let one = difference(&reference, &b).rmse / std::f64::consts::SQRT_2;
            for (x, y) in reference.pixels.iter_mut().zip(&b.pixels) {
                for c in 0..3 {
                    x[c] = 0.5 * (x[c] + y[c]);
                }
            }
            println!(
                "references: each has σ_ref = {:.2}% (their difference over √2); comparing with their average",
                100.0 * one
            );
            Some(one * one / 2.0)
        }
        None => None,
    };
    println!(
        "{:<10} {:<34} {:>9} {:>9} {:>9} {:>9}",
        "integrator", "settings", "cpu s", "wall s", "rel RMSE", "bias"
    );
    let mut runs = ladder();
    for (k, r) in runs.iter_mut().enumerate() {
        let out = a.out.join(format!("{k:02}-{}.pfm", r.integrator));
        let (cpu, wall) = render(&exe, scene, a.size, &r.args, &out)?;
        let d = difference(&reference, &read_pfm(&out)?);
        (r.cpu, r.wall, r.rmse, r.bias) = (cpu, wall, d.rmse, d.bias);
        println!(
            "{:<10} {:<34} {:>9.2} {:>9.2} {:>8.2}% {:>+8.2}%",
            r.integrator,
            r.label,
            r.cpu,
            r.wall,
            100.0 * r.rmse,
            100.0 * r.bias
        );
    }
    // σ_ref from the path runs: e² = s/n + σ_ref², least squares in (1/n, e²).
    let path: Vec<(f64, f64)> = runs
        .iter()
        .filter(|r| r.integrator == "path")
        .map(|r| (1.0 / r.spp, r.rmse * r.rmse))
        .collect();
    let m = path.len() as f64;
    let (sx, sy) = path.iter().fold((0.0, 0.0), |s, p| (s.0 + p.0, s.1 + p.1));
    let (mx, my) = (sx / m, sy / m);
    let sxx: f64 = path.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let sxy: f64 = path.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let (slope, ref_var) = match measured_var {
        // σ_ref known: the path runs' e² − σ_ref² = s/n, least squares through the origin.
        Some(v) => {
            let sxx0: f64 = path.iter().map(|p| p.0 * p.0).sum();
            let sxy0: f64 = path.iter().map(|p| p.0 * (p.1 - v)).sum();
            (if sxx0 > 0.0 { sxy0 / sxx0 } else { 0.0 }, v)
        }
        None => {
            let slope = if sxx > 0.0 { sxy / sxx } else { 0.0 };
            (slope, (my - slope * mx).max(0.0))
        }
    };
    let corrected = |e: f64| (e * e - ref_var).max(0.0).sqrt();
    println!(
        "reference noise σ ≈ {:.2}% ({}; the path runs: e² = {:.3}/n + σ²)",
        100.0 * ref_var.sqrt(),
        if measured_var.is_some() {
            "measured from the two references"
        } else {
            "fitted from the path runs"
        },
        slope
    );
    // The path tracer's CPU time for a given error, from its own fit (time ∝ n).
    let cpu_per_path: f64 = runs
        .iter()
        .filter(|r| r.integrator == "path")
        .map(|r| r.cpu / r.spp)
        .sum::<f64>()
        / m;
    let mut csv = String::from(
        "integrator,settings,cpu_s,wall_s,rel_rmse,rel_bias,rel_rmse_without_reference_noise,path_cpu_s_for_same_error\n",
    );
    for r in &runs {
        let e = corrected(r.rmse);
        let path_cpu = if e > 0.0 {
            slope / (e * e) * cpu_per_path
        } else {
            f64::NAN
        };
        let _ = writeln!(
            csv,
            "{},\"{}\",{:.3},{:.3},{:.5},{:.5},{:.5},{:.1}",
            r.integrator, r.label, r.cpu, r.wall, r.rmse, r.bias, e, path_cpu
        );
    }
    let csv_path = a.out.join("pictures.csv");
    radiosity::export::write_text(&csv_path, &csv)?;
    let series = ["radiosity", "gather", "path"]
        .iter()
        .map(|name| Series {
            name: match *name {
                "radiosity" => "radiosity shown directly".into(),
                "gather" => "final gather".into(),
                _ => "path tracer".into(),
            },
            points: runs
                .iter()
                .filter(|r| r.integrator == *name)
                .map(|r| (r.cpu, 100.0 * corrected(r.rmse)))
                .collect(),
            mark: Mark::LinePoints,
        })
        .collect();
    let plot = Plot {
        title: format!(
            "{scene}, {0}×{0}: error against a path-traced reference (its noise taken out)",
            a.size
        ),
        x_label: "CPU seconds".into(),
        y_label: "relative RMSE, % (emitters excluded)".into(),
        log_x: true,
        log_y: true,
        series,
    };
    let files = write_plot(&a.out.join("pictures"), &plot)?;
    println!("wrote       {}", csv_path.display());
    for f in files {
        println!("wrote       {}", f.display());
    }
    Ok(())
}
