//! The adaptive method's form-factor stage alone on a `.vs3` scene: CPU seconds of the stage
//! (this process's user + system time, from `/proc/self/stat`), the method's counts, and the
//! row sums, written to a file for comparing two builds.
//!
//! `cargo run --release -p radiosity --example adaptive_speed -- SCENE.vs3 [OUT.bin [REF.bin]]
//! [--accuracy E]`: OUT.bin gets the matrix as (i, j, f) records, REF.bin (such a file from
//! another build or accuracy) is compared with it.

use radiosity::accel::Bvh;
use radiosity::formfactor::{Estimator, FormFactorMethod, Params, Storage};
use radiosity::mesh::{Mesh, MeshParams};
use radiosity::observe::Event;
use std::io::Write;

/// User + system CPU seconds of this process so far (Linux).
fn cpu_seconds() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").expect("/proc/self/stat");
    let after = &stat[stat.rfind(')').expect("comm") + 2..];
    let f: Vec<&str> = after.split_whitespace().collect();
    // Fields 14 and 15 (utime, stime) in clock ticks; after the comm they are 11 and 12.
    let ticks: f64 = f[11].parse::<f64>().expect("utime") + f[12].parse::<f64>().expect("stime");
    ticks / 100.0
}

fn main() {
    let mut args: Vec<String> = std::env::args().collect();
    let mut accuracy = 1e-5;
    if let Some(k) = args.iter().position(|a| a == "--accuracy") {
        accuracy = args[k + 1].parse().expect("--accuracy E");
        args.drain(k..k + 2);
    }
    let path = std::path::Path::new(&args[1]);
    let v = radiosity::scene::vs3::load(path).expect("scene");
    let mesh = Mesh::build(&v.scene, MeshParams::Faces).expect("mesh");
    let bvh = Bvh::build(&mesh);
    let params = Params {
        method: FormFactorMethod::Adaptive,
        accuracy,
        ..Params::default()
    };
    let t0 = cpu_seconds();
    let w0 = std::time::Instant::now();
    let est = Estimator::new(&mesh, &bvh, params).expect("estimator");
    let t1 = cpu_seconds();
    let m = est
        .matrix(Storage::Sparse, &|_: Event<'_>| {})
        .into_sparse();
    let t2 = cpu_seconds();
    let wall = w0.elapsed().as_secs_f64();
    let n = mesh.len();
    let sums: Vec<f64> = (0..n).map(|i| m.row_sum(i)).collect();
    println!(
        "{n} patches: prepare {:.2} CPU-s, matrix {:.2} CPU-s, wall {wall:.2} s, {} entries, mean row sum {:.7}",
        t1 - t0,
        t2 - t1,
        m.nnz(),
        sums.iter().sum::<f64>() / n as f64
    );
    println!("{:?}", est.adaptive().expect("adaptive").stats());
    // The matrix as (i, j, f) little-endian records, and its differences from a reference.
    if let Some(out) = args.get(2) {
        let mut f = std::io::BufWriter::new(std::fs::File::create(out).expect("out"));
        for (i, j, v) in m.triplets() {
            f.write_all(&(i as u32).to_le_bytes()).expect("write");
            f.write_all(&j.to_le_bytes()).expect("write");
            f.write_all(&v.to_le_bytes()).expect("write");
        }
    }
    if let Some(reference) = args.get(3) {
        let bytes = std::fs::read(reference).expect("reference");
        let mut dense = std::collections::HashMap::new();
        for (i, j, v) in m.triplets() {
            dense.insert((i as u32, j), v as f64);
        }
        let (mut worst, mut sum_abs) = (0.0f64, 0.0f64);
        let mut ref_sums = vec![0.0f64; n];
        for r in bytes.chunks_exact(12) {
            let i = u32::from_le_bytes(r[0..4].try_into().expect("4"));
            let j = u32::from_le_bytes(r[4..8].try_into().expect("4"));
            let v = f32::from_le_bytes(r[8..12].try_into().expect("4")) as f64;
            ref_sums[i as usize] += v;
            let d = (dense.remove(&(i, j)).unwrap_or(0.0) - v).abs();
            worst = worst.max(d);
            sum_abs += d;
        }
        for (_, v) in dense {
            worst = worst.max(v.abs());
            sum_abs += v.abs();
        }
        let row: Vec<f64> = (0..n).map(|i| (sums[i] - ref_sums[i]).abs()).collect();
        let (at, worst_row) =
            row.iter().enumerate().fold(
                (0, 0.0f64),
                |(k, w), (i, d)| if *d > w { (i, *d) } else { (k, w) },
            );
        println!(
            "against {reference}: mean |dF| {:.2e}, worst |dF| {:.2e}, mean |d row sum| {:.2e}, worst {:.2e} (row {at}: {:.7} here, {:.7} there)",
            sum_abs / (n * n) as f64,
            worst,
            row.iter().sum::<f64>() / n as f64,
            worst_row,
            sums[at],
            ref_sums[at]
        );
    }
}
