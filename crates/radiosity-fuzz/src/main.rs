//! `radiosity-fuzz`: the long run of the mutation fuzzer ([`targets`]) over every parser of
//! the `radiosity` library and over the `radiosity` command's option parser, with a watchdog that stops the run, keeping the
//! input, if a case takes more than 10 s, and a heap count per case (more than 1 GiB fails).

mod targets;

use anyhow::{bail, Context, Result};
use clap::Parser;
use radiosity::sampling::stream;
use radiosity_cli::alloc::Probe;
use radiosity_cli::args::Cli;
use radiosity_experiments::MemoryProbe;
use rand::Rng;
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};
use targets::{run, Target};

/// Longest a case may take.
const HANG: Duration = Duration::from_secs(10);
/// Most heap a case may allocate.
const HEAP: u64 = 1 << 30;

/// Fuzz every input parser and the `radiosity` option parser with seeded mutations of valid
/// files: panics, cases over 10 s or over 1 GiB of heap fail the run.
#[derive(Debug, Parser)]
#[command(name = "radiosity-fuzz", version, about, long_about = None, after_help = EXAMPLES)]
struct FuzzArgs {
    /// Cases per parser.
    #[arg(long, value_name = "N", default_value_t = 10_000)]
    cases: u64,
    /// Seed of the mutations.
    #[arg(long, value_name = "S", default_value_t = 1)]
    seed: u64,
    /// Only these parsers (default: all).
    #[arg(long, value_name = "P,P,…", value_delimiter = ',')]
    targets: Vec<String>,
    /// Folder for the scratch files and the inputs that failed.
    #[arg(long, value_name = "DIR", default_value = "fuzz-out")]
    out: PathBuf,
}

const EXAMPLES: &str = "Examples:
  radiosity-fuzz --cases 1000000 --out fuzz-out
  radiosity-fuzz --cases 10000 --targets gltf,glb --seed 7";

fn main() -> ExitCode {
    let a = match FuzzArgs::try_parse() {
        Ok(a) => a,
        Err(e) if e.use_stderr() => {
            eprintln!("radiosity-fuzz: error: {}", radiosity_cli::usage_error(&e));
            return ExitCode::from(2);
        }
        Err(e) => e.exit(),
    };
    match radiosity_cli::settings::threads(None).and_then(|()| run_all(a)) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("radiosity-fuzz: error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

/// Run the fuzzer.
fn run_all(a: FuzzArgs) -> Result<()> {
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
                    "radiosity-fuzz: error: a fuzz case ran past {} s; its input is the newest file under the output folder",
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
        Probe.reset_peak();
        let base = Probe.current();
        let report = run(target, a.cases, a.seed, &a.out, &mut |_, _| {
            let used = Probe.peak().saturating_sub(base);
            peak = peak.max(used);
            heavy |= used > HEAP;
            Probe.reset_peak();
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
                if let radiosity_cli::args::Command::Render(r) = &cli.command {
                    refused += u64::from(radiosity_cli::settings::settings(&r.solve).is_err());
                    let _ = radiosity_cli::settings::image(&r.image, 1, 4);
                }
            }
        }
    }
    (cases, refused)
}
