//! `radiosity-bench canyon`: the adaptive view factors against Monte Carlo on urban canyons
//! written as View3D files: 3 × 3 box buildings (10 m square, 8–16 m high, 10 m streets) on a
//! 70 m ground, every face cut into facets of about equal size, each facet a View3D surface;
//! with `--closed` a lid 30 m up and four sides, also faceted, close the scene, so that every
//! row of F must sum to 1. Each file is written to `--out` (to run `radiosity form-factors` on
//! it), then read back through the View3D reader and timed in this process: time, CPU time,
//! the rows' sums, and what the adaptive method did. Closed, `mean|Σ−1|` is each method's
//! error of closure (Monte Carlo's is 0 by construction: every ray lands somewhere); open,
//! `mean|ΔΣ|` is the mean difference of Monte Carlo's row sums from the adaptive ones beside
//! `MC σ(Σ)`, what Monte Carlo's noise alone makes it.

use crate::args::CanyonArgs;
use anyhow::{Context, Result};
use radiosity::accel::Bvh;
use radiosity::formfactor::{Estimator, FormFactorMethod, Params, Storage};
use radiosity::mesh::{Mesh, MeshParams};
use radiosity::observe::Silent;
use radiosity::system::SparseMatrix;
use std::collections::HashMap;
use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

/// The buildings' heights, row by row (metres).
const HEIGHTS: [f64; 9] = [10.0, 14.0, 8.0, 12.0, 10.0, 16.0, 8.0, 12.0, 10.0];
/// Building width (metres).
const B: f64 = 10.0;
/// Street width (metres).
const W: f64 = 10.0;

/// The canyon's rectangles: origin and two edges (the normal is `e1 × e2`, facing the open
/// space).
fn rectangles(closed: bool, heights: &[f64; 9]) -> Vec<([f64; 3], [f64; 3], [f64; 3])> {
    let size = 3.0 * B + 4.0 * W;
    let cuts = [
        0.0,
        W,
        W + B,
        2.0 * W + B,
        2.0 * (W + B),
        3.0 * W + 2.0 * B,
        3.0 * (W + B),
        size,
    ];
    let mut r = Vec::new();
    for i in 0..7 {
        for j in 0..7 {
            if i % 2 == 1 && j % 2 == 1 {
                continue; // a building's footprint
            }
            let (x0, x1, y0, y1) = (cuts[i], cuts[i + 1], cuts[j], cuts[j + 1]);
            r.push(([x0, y0, 0.0], [x1 - x0, 0.0, 0.0], [0.0, y1 - y0, 0.0]));
        }
    }
    for (k, h) in heights.iter().copied().enumerate() {
        let x0 = W + (k / 3) as f64 * (B + W);
        let y0 = W + (k % 3) as f64 * (B + W);
        let (x1, y1) = (x0 + B, y0 + B);
        r.push(([x0, y0, h], [B, 0.0, 0.0], [0.0, B, 0.0])); // roof
        r.push(([x0, y0, 0.0], [0.0, 0.0, h], [0.0, B, 0.0])); // −x
        r.push(([x1, y0, 0.0], [0.0, B, 0.0], [0.0, 0.0, h])); // +x
        r.push(([x0, y0, 0.0], [B, 0.0, 0.0], [0.0, 0.0, h])); // −y
        r.push(([x0, y1, 0.0], [0.0, 0.0, h], [B, 0.0, 0.0])); // +y
    }
    if closed {
        let top = 30.0;
        r.push(([0.0, 0.0, top], [0.0, size, 0.0], [size, 0.0, 0.0]));
        r.push(([0.0, 0.0, 0.0], [0.0, size, 0.0], [0.0, 0.0, top]));
        r.push(([size, 0.0, 0.0], [0.0, 0.0, top], [0.0, size, 0.0]));
        r.push(([0.0, 0.0, 0.0], [0.0, 0.0, top], [size, 0.0, 0.0]));
        r.push(([0.0, size, 0.0], [size, 0.0, 0.0], [0.0, 0.0, top]));
    }
    r
}

/// The canyon with about `facets` facets as View3D text (`F 3`: shared vertices, one surface a
/// facet), and its facet count.
pub fn canyon_vs3(facets: usize, closed: bool) -> (String, usize) {
    canyon_vs3_with(facets, closed, &HEIGHTS)
}

/// [`canyon_vs3`] with the nine buildings' heights (metres, row by row).
pub fn canyon_vs3_with(facets: usize, closed: bool, heights: &[f64; 9]) -> (String, usize) {
    let rects = rectangles(closed, heights);
    let len = |e: [f64; 3]| (e[0] * e[0] + e[1] * e[1] + e[2] * e[2]).sqrt();
    let area: f64 = rects.iter().map(|(_, a, b)| len(*a) * len(*b)).sum();
    let s = (area / facets.max(1) as f64).sqrt();
    let mut vertices: Vec<String> = Vec::new();
    let mut index: HashMap<String, usize> = HashMap::new();
    let mut surfaces = String::new();
    let mut n = 0;
    for (o, e1, e2) in rects {
        let n1 = (len(e1) / s).round().max(1.0) as usize;
        let n2 = (len(e2) / s).round().max(1.0) as usize;
        let mut corner = |a: usize, b: usize| {
            let (u, v) = (a as f64 / n1 as f64, b as f64 / n2 as f64);
            let p: Vec<String> = (0..3)
                .map(|k| format!("{:.6}", o[k] + e1[k] * u + e2[k] * v))
                .collect();
            let key = p.join(" ");
            let next = vertices.len() + 1;
            *index.entry(key.clone()).or_insert_with(|| {
                vertices.push(key);
                next
            })
        };
        for i in 0..n1 {
            for j in 0..n2 {
                let c = [
                    corner(i, j),
                    corner(i + 1, j),
                    corner(i + 1, j + 1),
                    corner(i, j + 1),
                ];
                n += 1;
                let _ = writeln!(
                    surfaces,
                    "S {n} {} {} {} {} 0 0 0.90 f{n}",
                    c[0], c[1], c[2], c[3]
                );
            }
        }
    }
    let mut text = format!(
        "T urban canyon: 3 x 3 buildings, {n} facets{}\nC encl={} list=0\nF 3\n",
        if closed { ", closed" } else { "" },
        u8::from(closed)
    );
    for (k, v) in vertices.iter().enumerate() {
        let _ = writeln!(text, "V {} {v}", k + 1);
    }
    text += &surfaces;
    text += "End of data\n";
    (text, n)
}

/// CPU seconds of this process so far (user + system, from /proc/self/stat).
fn cpu_seconds() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    let fields: Vec<&str> = stat
        .rsplit(')')
        .next()
        .unwrap_or("")
        .split_whitespace()
        .collect();
    let tick = |k: usize| {
        fields
            .get(k)
            .and_then(|x| x.parse::<f64>().ok())
            .unwrap_or(0.0)
    };
    (tick(11) + tick(12)) / 100.0
}

fn row_sums(m: &SparseMatrix) -> Vec<f64> {
    (0..m.n())
        .map(|i| m.row_entries(i).iter().map(|e| e.1 as f64).sum())
        .collect()
}

/// Run the mode.
pub fn run(a: &CanyonArgs) -> Result<()> {
    std::fs::create_dir_all(&a.out).with_context(|| format!("{}", a.out.display()))?;
    println!(
        "{:>7} {:>9} {:>10} {:>8} {:>8} {:>11} {:>11} {:>9} {:>9} {:>12} {:>12}",
        "facets",
        "method",
        "pairs",
        "wall s",
        "cpu s",
        "mean|Σ−1|",
        "max|Σ−1|",
        "occluded",
        "sampled",
        "mean|ΔΣ|",
        "MC σ(Σ)"
    );
    for &size in &a.sizes {
        let (text, n) = canyon_vs3(size, a.closed);
        let path = a.out.join(format!(
            "canyon-{n}{}.vs3",
            if a.closed { "-closed" } else { "" }
        ));
        radiosity::io::write_atomic::<radiosity::io::OutputError>(&path, |w| {
            std::io::Write::write_all(w, text.as_bytes())
        })?;
        let vs3 = radiosity::scene::vs3::parse(Path::new(&path), &text)?;
        let mesh = Mesh::build(&vs3.scene, MeshParams::Faces)?;
        let bvh = Bvh::build(&mesh);
        let mut sums = Vec::new();
        for (method, rays) in [
            (FormFactorMethod::Adaptive, 0),
            (FormFactorMethod::MonteCarlo, a.rays),
        ] {
            let params = Params {
                method,
                rays: rays.max(1),
                accuracy: a.accuracy,
                ..Params::default()
            };
            let (t, c) = (Instant::now(), cpu_seconds());
            let est = Estimator::new(&mesh, &bvh, params)?;
            let m = est.matrix(Storage::Sparse, &Silent).into_sparse();
            let (wall, cpu) = (t.elapsed().as_secs_f64(), cpu_seconds() - c);
            let s = row_sums(&m);
            let err: Vec<f64> = s.iter().map(|x| (x - 1.0).abs()).collect();
            let stats = est.adaptive().map(|p| p.stats());
            let (mean_rs, max_rs) = if a.closed {
                (
                    format!("{:.2e}", err.iter().sum::<f64>() / n as f64),
                    format!("{:.2e}", err.iter().copied().fold(0.0, f64::max)),
                )
            } else {
                ("-".into(), "-".into())
            };
            // Open scenes: the mean difference of the row sums from the adaptive ones, beside
            // what Monte Carlo's noise alone gives (σ of a row sum s is √(s(1 − s)/rays),
            // and E|N(0, σ)| = σ √(2/π)).
            let (delta, noise) =
                if method == FormFactorMethod::MonteCarlo && !sums.is_empty() && !a.closed {
                    let d: f64 = s
                        .iter()
                        .zip(&sums)
                        .map(|(x, y): (&f64, &f64)| (x - y).abs())
                        .sum::<f64>()
                        / n as f64;
                    let sigma: f64 = sums
                        .iter()
                        .map(|y: &f64| {
                            (y.clamp(0.0, 1.0) * (1.0 - y.clamp(0.0, 1.0)) / rays as f64).sqrt()
                        })
                        .sum::<f64>()
                        / n as f64
                        * (2.0 / std::f64::consts::PI).sqrt();
                    (format!("{d:.2e}"), format!("{sigma:.2e}"))
                } else {
                    ("-".into(), "-".into())
                };
            println!(
                "{:>7} {:>9} {:>10} {:>8.2} {:>8.2} {:>11} {:>11} {:>9} {:>9} {:>12} {:>12}",
                n,
                if method == FormFactorMethod::Adaptive {
                    "adaptive".to_string()
                } else {
                    format!("mc {}", rays)
                },
                stats.map_or("-".into(), |s| s.facing.to_string()),
                wall,
                cpu,
                mean_rs,
                max_rs,
                stats.map_or("-".into(), |s| s.occluded.to_string()),
                stats.map_or("-".into(), |s| s.sampled.to_string()),
                delta,
                noise
            );
            if sums.is_empty() {
                sums = s;
            }
        }
        println!("        wrote {}", path.display());
    }
    Ok(())
}
