//! `radiosity fuzz`: the long run of the library's mutation fuzzer ([`radiosity::fuzz`]) over
//! every parser and over the option parser, with a watchdog that stops the run, keeping the
//! input, if a case takes more than 10 s, and a heap count per case (more than 1 GiB fails).

use crate::args::{Cli, FuzzArgs};
use anyhow::{bail, Context, Result};
use clap::Parser;
use radiosity::experiment::MemoryProbe;
use radiosity::fuzz::{run, Target};
use radiosity::sampling::stream;
use rand::Rng;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// Longest a case may take.
const HANG: Duration = Duration::from_secs(10);
/// Most heap a case may allocate.
const HEAP: u64 = 1 << 30;

/// Run the fuzzer.
pub fn run_all(a: FuzzArgs) -> Result<()> {
    if a.cases == 0 {
        bail!("--cases 0: at least one case is needed");
    }
    std::fs::create_dir_all(&a.out)
        .with_context(|| format!("{}: cannot create the folder", a.out.display()))?;
    // The watchdog: the start of the case in progress, in ms since `epoch` (0: none).
    let epoch = Instant::now();
    let started = Arc::new(AtomicU64::new(0));
    {
        let started = started.clone();
        std::thread::spawn(move || loop {
            std::thread::sleep(Duration::from_millis(250));
            let s = started.load(Ordering::Relaxed);
            if s > 0
                && (epoch.elapsed().as_millis() as u64).saturating_sub(s) > HANG.as_millis() as u64
            {
                eprintln!(
                    "radiosity: error: a fuzz case ran past {} s; its input is the newest file under the output folder",
                    HANG.as_secs()
                );
                std::process::exit(3);
            }
        });
    }
    println!(
        "{:<14} {:>10} {:>10} {:>7} {:>12} {:>12}",
        "parser", "cases", "loaded", "panics", "slowest ms", "peak heap MiB"
    );
    let mut failed = false;
    for target in Target::ALL {
        if !a.targets.is_empty() && !a.targets.iter().any(|t| t == target.name()) {
            continue;
        }
        let mut peak = 0u64;
        let mut heavy = false;
        started.store(epoch.elapsed().as_millis() as u64 + 1, Ordering::Relaxed);
        crate::alloc::Probe.reset_peak();
        let base = crate::alloc::Probe.current();
        let report = run(target, a.cases, a.seed, &a.out, &mut |_, _| {
            let used = crate::alloc::Probe.peak().saturating_sub(base);
            peak = peak.max(used);
            heavy |= used > HEAP;
            crate::alloc::Probe.reset_peak();
            started.store(epoch.elapsed().as_millis() as u64 + 1, Ordering::Relaxed);
        })
        .context("writing the fuzz cases")?;
        started.store(0, Ordering::Relaxed);
        println!(
            "{:<14} {:>10} {:>10} {:>7} {:>12.1} {:>12.1}",
            target.name(),
            report.cases,
            report.accepted,
            report.panics.len(),
            report.slowest.as_secs_f64() * 1e3,
            peak as f64 / (1024.0 * 1024.0)
        );
        for p in &report.panics {
            println!("  panic: {}", p.display());
        }
        failed |= !report.panics.is_empty() || heavy;
    }
    if a.targets.is_empty() || a.targets.iter().any(|t| t == "options") {
        let (cases, errors) = options(a.cases, a.seed);
        println!(
            "{:<14} {:>10} {:>10} {:>7}",
            "options",
            cases,
            cases - errors,
            0
        );
    }
    if failed {
        bail!("the fuzzer found panics or a case that allocated more than 1 GiB");
    }
    Ok(())
}

/// Mutated command lines through the option parser and its checks (no solving): returns the
/// cases and how many were refused. A panic here ends the run with its message.
fn options(cases: u64, seed: u64) -> (u64, u64) {
    const WORDS: [&str; 24] = [
        "render",
        "solve",
        "form-factors",
        "solve-system",
        "bench",
        "view",
        "--patches",
        "--max-edge",
        "--rays",
        "--solver",
        "--form-factor-method",
        "--tolerance",
        "--threads",
        "--width",
        "--height",
        "--spp",
        "--eye",
        "-1",
        "0",
        "1e309",
        "nan",
        "99999999999",
        "gauss",
        "--rows",
    ];
    let mut refused = 0;
    for case in 0..cases {
        let mut rng = stream(seed, 0x0F7, 0, case);
        let n = 1 + rng.random::<u32>() % 8;
        let mut args = vec!["radiosity".to_string()];
        for _ in 0..n {
            args.push(WORDS[rng.random::<u32>() as usize % WORDS.len()].to_string());
        }
        match Cli::try_parse_from(&args) {
            Err(_) => refused += 1,
            Ok(cli) => {
                // The cross-flag checks that run before any work.
                if let crate::args::Command::Render(r) = &cli.command {
                    refused += u64::from(crate::settings::settings(&r.solve).is_err());
                    let _ = crate::settings::image(&r.image, 1, 4);
                }
            }
        }
    }
    (cases, refused)
}
