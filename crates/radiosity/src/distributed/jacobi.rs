//! Jacobi iteration over ranks (Szirmay-Kalos & Márton 1995, eq. 8–11): every rank relaxes the
//! rows of its block from the previous sweep's B,
//!
//! ```text
//! B_i ← (E_i + ρ_i Σ_{j≠i} F_ij B_j) / (1 − ρ_i F_ii)        i in the rank's block,
//! ```
//!
//! in parallel over its threads, and the new blocks are all-gathered (24 bytes a patch a sweep).
//! The residual of the previous B, `r_i = E_i + ρ_i H_i − B_i` with `H_i = Σ_j F_ij B_j`, comes
//! with the sweep (H is gathered beside B), so the unshot energy Σ |r_i|₁ A_i needs no extra
//! product; it is summed over the gathered vector in patch
//! order on every rank, so all ranks stop after the same sweep and the result is the same bytes
//! for any number of ranks. It stops when the unshot energy of the previous sweep's B is within
//! the tolerance, and returns the new B, one sweep better. Unlike [`crate::solve::jacobi`], which
//! counts and can stop after single rows (the experiments' traces), it runs whole sweeps; the
//! iteration count is rows relaxed, N a sweep, as there.

use super::rows::RowBlock;
use crate::color::Rgb;
use crate::comm::Ranks;
use crate::solve::{Info, SolverParams, System};
use rayon::prelude::*;
use std::time::Instant;

/// One sweep, for the report.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Sweep {
    /// Unshot energy of the B the sweep started from, as a fraction of the emitted energy.
    pub unshot_fraction: f64,
    /// Wall seconds of the sweep: the rows, then the all-gather.
    pub seconds: f64,
    /// Of which in the all-gather (waiting for the slowest rank included).
    pub communication: f64,
}

/// Solve by Jacobi sweeps over the ranks; `block` is this rank's rows of F. Every rank returns
/// the same B and report.
pub fn solve(
    system: &System,
    block: &RowBlock,
    params: &SolverParams,
    ranks: &Ranks<'_>,
    each: &mut dyn FnMut(&Sweep, &[Rgb]) -> bool,
) -> (Vec<Rgb>, Info, Vec<Sweep>) {
    let start = Instant::now();
    let n = system.len();
    let emitted = system.emitted_power();
    let energy = |c: Rgb| c.r.abs() + c.g.abs() + c.b.abs();
    let emitted_energy: f64 = (0..n)
        .map(|i| energy(system.emission[i]) * system.area[i])
        .sum();
    // Each row's sum (the fraction of its view that reaches a patch), replicated once.
    let sums: Vec<f64> = block
        .range
        .clone()
        .map(|i| block.row(i).iter().map(|&(_, f)| f as f64).sum())
        .collect();
    let sums = ranks.all_gather(&sums);
    let mut b = system.emission.clone();
    let mut sweeps = Vec::new();
    let cap = crate::solve::default_iteration_cap(crate::solve::Solver::Jacobi, n, params)
        .min(params.max_iterations);
    let (mut iterations, mut converged) = (0u64, false);
    let (mut unshot_fraction, mut absorbed, mut escaped, mut unshot_power);
    loop {
        let t = Instant::now();
        // (new B_i, H_i = Σ_j F_ij B_j) for the rows of the block.
        let mine: Vec<(Rgb, Rgb)> = block
            .range
            .clone()
            .into_par_iter()
            .map(|i| {
                let (mut gathered, mut f_ii) = (Rgb::BLACK, 0.0);
                for &(j, f) in block.row(i) {
                    if j as usize == i {
                        f_ii = f as f64;
                    } else {
                        gathered += b[j as usize] * f as f64;
                    }
                }
                let rho = system.reflectance[i];
                let num = system.emission[i] + rho * gathered;
                let den = Rgb::splat(1.0) - rho * f_ii;
                let new = Rgb::new(num.r / den.r, num.g / den.g, num.b / den.b);
                (new, gathered + b[i] * f_ii)
            })
            .collect();
        let compute = t.elapsed().as_secs_f64();
        let new = ranks.all_gather(&mine);
        let communication = t.elapsed().as_secs_f64() - compute;
        // The residual of the B the sweep started from, r_i = E_i + ρ_i H_i − B_i, and its
        // energy books: absorbed Σ (1 − ρ_i) H_i A_i, escaped Σ B_i A_i (1 − Σ_j F_ij).
        let mut unshot = 0.0;
        (absorbed, escaped, unshot_power) = (Rgb::BLACK, Rgb::BLACK, Rgb::BLACK);
        for i in 0..n {
            let (_, h) = new[i];
            let rho = system.reflectance[i];
            let r = system.emission[i] + rho * h - b[i];
            unshot += energy(r) * system.area[i];
            unshot_power += r * system.area[i];
            absorbed += (Rgb::splat(1.0) - rho) * h * system.area[i];
            escaped += b[i] * (system.area[i] * (1.0 - sums[i]).max(0.0));
        }
        unshot_fraction = unshot / emitted_energy;
        iterations += n as u64;
        for (bi, (nb, _)) in b.iter_mut().zip(&new) {
            *bi = *nb;
        }
        let sweep = Sweep {
            unshot_fraction,
            seconds: t.elapsed().as_secs_f64(),
            communication,
        };
        sweeps.push(sweep);
        let go_on = each(&sweep, &b);
        if unshot_fraction <= params.tolerance {
            converged = true;
            break;
        }
        if iterations >= cap || !go_on {
            break;
        }
    }
    let info = Info {
        iterations,
        converged,
        unshot_fraction,
        seconds: start.elapsed().as_secs_f64(),
        emitted,
        absorbed,
        escaped,
        unshot: unshot_power,
        estimated_error: 0.0,
        ray_seconds: 0.0,
    };
    (b, info, sweeps)
}
