//! `radiosity-bench`: the workbench that measures the engine. One subcommand per measurement
//! (`radiosity-bench --help`); none of it is part of the `radiosity` product.

mod accuracy;
mod args;
mod bookkeeping;
mod canyon;
mod cornell;
#[cfg(feature = "embree")]
mod embree;
mod floor;
mod pictures;
mod ranks;
mod rays;
mod scale;
mod view3d;

use anyhow::Result;
use args::{BenchCli, Mode};
use clap::Parser;
use std::process::ExitCode;

/// The median of `v` (the mean of the middle two for an even count).
pub(crate) fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// The `radiosity` binary the child-process measurements run: `$RADIOSITY_BIN`, else the one
/// beside this executable (cargo builds both into the same folder).
pub(crate) fn radiosity_exe() -> Result<std::path::PathBuf> {
    if let Some(p) = std::env::var_os("RADIOSITY_BIN") {
        return Ok(p.into());
    }
    let me = std::env::current_exe()?;
    let exe = me.with_file_name(format!("radiosity{}", std::env::consts::EXE_SUFFIX));
    if !exe.is_file() {
        anyhow::bail!(
            "{}: no radiosity executable beside radiosity-bench (build it: cargo build --release -p radiosity-cli, or set RADIOSITY_BIN)",
            exe.display()
        );
    }
    Ok(exe)
}

/// Repetitions and counts must be positive.
pub(crate) fn positive(what: &[(&str, usize)]) -> Result<()> {
    for (flag, v) in what {
        if *v == 0 {
            anyhow::bail!("{flag} 0: must be positive");
        }
    }
    Ok(())
}

fn run(mode: Mode, threads: Option<usize>) -> Result<()> {
    if !matches!(mode, Mode::Ranks(_)) {
        radiosity_cli::ranks::refuse_unless_single("radiosity-bench (except ranks)")?;
    }
    match mode {
        Mode::Cornell(a) => cornell::run(&a),
        Mode::Rays(a) => rays::run(&a),
        Mode::Solvers(a) => cornell::solvers(&a),
        Mode::FormFactors(a) => cornell::form_factor_table(a.runs),
        Mode::City => cornell::city(),
        Mode::Canyon(a) => canyon::run(&a),
        Mode::View3d(a) => view3d::run(&a, threads),
        Mode::Ranks(a) => ranks::run(&a),
        Mode::Scale(a) => scale::run(&a, threads),
        Mode::Pictures(a) => pictures::run(&a),
        Mode::Hierarchical(a) => accuracy::run(&a),
        Mode::DaylightFloor(a) => floor::run(&a),
    }
}

fn main() -> ExitCode {
    let cli = match BenchCli::try_parse() {
        Ok(cli) => cli,
        Err(e) if e.use_stderr() => {
            eprintln!("radiosity-bench: error: {}", radiosity_cli::usage_error(&e));
            return ExitCode::from(2);
        }
        Err(e) => e.exit(),
    };
    if let Err(e) = radiosity_cli::ranks::start() {
        eprintln!("radiosity-bench: error: {e:#}");
        return ExitCode::FAILURE;
    }
    let threads = cli.threads;
    let result = radiosity_cli::settings::threads(threads).and_then(|()| {
        if radiosity_cli::ranks::launched().is_some() {
            run(cli.mode, threads)
        } else {
            radiosity_cli::settings::on_worker(|| run(cli.mode, threads))
        }
    });
    match result {
        Ok(()) => {
            radiosity_cli::ranks::finish();
            ExitCode::SUCCESS
        }
        Err(e) if radiosity_cli::ranks::distributed() => {
            radiosity_cli::ranks::fail(&format!("{e:#}"))
        }
        Err(e) => {
            eprintln!("radiosity-bench: error: {e:#}");
            radiosity_cli::ranks::finish();
            ExitCode::FAILURE
        }
    }
}
