//! Progressive refinement radiosity (Cohen, Chen, Wallace, Greenberg 1988), as given in
//! 003_6556f2e3d50166bb.txt section 2.1 and 000_59d10e371b5f300d.txt eq. 23–28.
//!
//! Each patch holds its radiosity `B_i` and unshot radiosity `ΔB_i`, both starting at `E_i`.
//! An iteration picks the shooter `i` with the most unshot energy `ΔB_i·A_i` (the choice that
//! makes it Southwell relaxation on the energy system, 003_… section 5.1), takes row `i` of F
//! and uses reciprocity (000_… eq. 24), `F_ji = F_ij A_i / A_j`, to shoot:
//!
//! ```text
//! ΔB_j += ρ_j ΔB_i F_ij A_i / A_j,   B_j += same,   then ΔB_i = 0      (eq. 23)
//! ```
//!
//! All three channels in one pass. It stops when the unshot energy Σ ΔB_i A_i falls to
//! `tolerance` times the emitted energy, or after `max_iterations` shots. The output
//! `B = ∇B + ΔB` is Southwell's unknowns plus one free Jacobi sweep (003_… section 4).
//!
//! Energy bookkeeping: the power of each shot is split into what arrives at patches — of which
//! `ρ_j` is re-emitted as unshot and `1 − ρ_j` absorbed — and what reaches no patch
//! (escaped). So at every step `emitted = absorbed + escaped + unshot` up to rounding.

use super::{Info, RowSource, Status, System};
use crate::color::Rgb;
use std::time::Instant;

/// Parameters of progressive refinement.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProgressiveParams {
    /// Stop when the unshot energy is at most this fraction of the emitted energy.
    pub tolerance: f64,
    /// Stop after this many shots at the latest.
    pub max_iterations: u64,
}

impl Default for ProgressiveParams {
    fn default() -> Self {
        Self {
            tolerance: 0.01,
            max_iterations: u64::MAX,
        }
    }
}

/// The state of a progressive-refinement solution, advanced one shot at a time.
#[derive(Clone, Debug)]
pub struct Progressive<'s> {
    system: System<'s>,
    radiosity: Vec<Rgb>,
    unshot: Vec<Rgb>,
    /// Unshot energy per patch, channels summed: the shooter's ranking key.
    energy: Vec<f64>,
    emitted: Rgb,
    emitted_total: f64,
    absorbed: Rgb,
    escaped: Rgb,
    iterations: u64,
}

impl<'s> Progressive<'s> {
    /// Start: `B = ΔB = E`. The system should have passed [`System::validate`].
    pub fn new(system: System<'s>) -> Self {
        let emitted = system.emitted_power();
        Self {
            radiosity: system.emission.to_vec(),
            unshot: system.emission.to_vec(),
            energy: (0..system.len())
                .map(|i| system.emission[i].sum() * system.area[i])
                .collect(),
            emitted,
            emitted_total: emitted.sum(),
            absorbed: Rgb::BLACK,
            escaped: Rgb::BLACK,
            iterations: 0,
            system,
        }
    }

    /// Current radiosities `B` (the estimate after the free Jacobi sweep).
    pub fn radiosity(&self) -> &[Rgb] {
        &self.radiosity
    }

    /// Current unshot radiosities `ΔB` (the residuals).
    pub fn unshot(&self) -> &[Rgb] {
        &self.unshot
    }

    /// Shots done.
    pub fn iterations(&self) -> u64 {
        self.iterations
    }

    /// The shooter (most unshot energy) and the total unshot energy, by one scan.
    fn scan(&self) -> (usize, f64, f64) {
        let (mut best, mut best_e, mut total) = (0usize, f64::NEG_INFINITY, 0.0f64);
        for (i, &e) in self.energy.iter().enumerate() {
            total += e;
            if e > best_e {
                best_e = e;
                best = i;
            }
        }
        (best, best_e, total)
    }

    /// Unshot energy as a fraction of the emitted energy.
    pub fn unshot_fraction(&self) -> f64 {
        self.scan().2 / self.emitted_total
    }

    /// Shoot from patch `i` with row `i` of F from `source`.
    pub fn shoot(&mut self, i: usize, source: &mut dyn RowSource) {
        let sys = self.system;
        let u = self.unshot[i];
        let share = self.energy[i] / self.emitted_total;
        let ai = sys.area[i];
        let mut reached = 0.0f64;
        for &(j, f) in source.row(i, share) {
            let j = j as usize;
            if j == i {
                continue;
            }
            let f = f as f64;
            reached += f;
            let power = u * (f * ai);
            let rho = sys.reflectance[j];
            let db = rho * power / sys.area[j];
            self.radiosity[j] += db;
            self.unshot[j] += db;
            self.energy[j] = self.unshot[j].sum() * sys.area[j];
            self.absorbed += (Rgb::splat(1.0) - rho) * power;
        }
        self.escaped += u * (ai * (1.0 - reached).max(0.0));
        self.unshot[i] = Rgb::BLACK;
        self.energy[i] = 0.0;
        self.iterations += 1;
    }

    /// The bookkeeping so far.
    pub fn info(&self, converged: bool, seconds: f64) -> Info {
        let unshot: Rgb = self
            .unshot
            .iter()
            .zip(self.system.area)
            .map(|(u, a)| *u * *a)
            .sum();
        Info {
            iterations: self.iterations,
            converged,
            unshot_fraction: unshot.sum() / self.emitted_total,
            seconds,
            emitted: self.emitted,
            absorbed: self.absorbed,
            escaped: self.escaped,
            unshot,
        }
    }

    /// Shoot until the tolerance or the iteration limit is reached; `observer` sees the status
    /// before every shot and once at the end.
    pub fn run(
        &mut self,
        source: &mut dyn RowSource,
        params: &ProgressiveParams,
        observer: &mut dyn FnMut(&Status),
    ) -> Info {
        let start = Instant::now();
        loop {
            let (i, best, total) = self.scan();
            let status = Status {
                iterations: self.iterations,
                unshot_fraction: total / self.emitted_total,
            };
            observer(&status);
            if status.unshot_fraction <= params.tolerance || best <= 0.0 {
                return self.info(true, start.elapsed().as_secs_f64());
            }
            if self.iterations >= params.max_iterations {
                return self.info(false, start.elapsed().as_secs_f64());
            }
            self.shoot(i, source);
        }
    }
}

/// Solve by progressive refinement: returns `(B, ΔB, info)`.
pub fn solve(
    system: System,
    source: &mut dyn RowSource,
    params: &ProgressiveParams,
    observer: &mut dyn FnMut(&Status),
) -> (Vec<Rgb>, Vec<Rgb>, Info) {
    let mut pr = Progressive::new(system);
    let info = pr.run(source, params, observer);
    (pr.radiosity, pr.unshot, info)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::formfactor::Entry;

    /// A dense matrix as a row source, for hand-written systems.
    struct Dense(Vec<Vec<Entry>>);
    impl RowSource for Dense {
        fn len(&self) -> usize {
            self.0.len()
        }
        fn row(&mut self, i: usize, _: f64) -> &[Entry] {
            &self.0[i]
        }
    }

    #[test]
    fn three_patches_match_the_direct_solution() {
        // Equal areas, so F is symmetric (reciprocity). Rows sum to 0.9, 0.8, 0.7.
        let f = [[0.0, 0.5, 0.4], [0.5, 0.0, 0.3], [0.4, 0.3, 0.0]];
        let rho = [0.5, 0.8, 0.3];
        let e = [1.0, 0.0, 0.0];
        let area = [1.0; 3];
        // Direct solve of (I − diag(ρ) F) B = E by Cramer's rule, with F rounded to f32 as
        // rows store it.
        let m: Vec<Vec<f64>> = (0..3)
            .map(|i| {
                (0..3)
                    .map(|j| (i == j) as u8 as f64 - rho[i] * (f[i][j] as f32 as f64))
                    .collect()
            })
            .collect();
        let det3 = |m: &Vec<Vec<f64>>| {
            m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
                - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
                + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
        };
        let d = det3(&m);
        let exact: Vec<f64> = (0..3)
            .map(|k| {
                let mut mk = m.clone();
                for i in 0..3 {
                    mk[i][k] = e[i];
                }
                det3(&mk) / d
            })
            .collect();
        let refl: Vec<Rgb> = rho.iter().map(|&r| Rgb::splat(r)).collect();
        let emis: Vec<Rgb> = e.iter().map(|&x| Rgb::splat(x)).collect();
        let sys = System {
            area: &area,
            reflectance: &refl,
            emission: &emis,
        };
        sys.validate().unwrap();
        let mut src = Dense(
            f.iter()
                .map(|r| {
                    r.iter()
                        .enumerate()
                        .filter(|(_, v)| **v > 0.0)
                        .map(|(j, v)| (j as u32, *v as f32))
                        .collect()
                })
                .collect(),
        );
        let params = ProgressiveParams {
            tolerance: 1e-12,
            ..Default::default()
        };
        let (b, _, info) = solve(sys, &mut src, &params, &mut |_| {});
        assert!(info.converged);
        for i in 0..3 {
            assert!(
                (b[i].r - exact[i]).abs() < 1e-9 * exact[i].max(1.0),
                "{} vs {}",
                b[i].r,
                exact[i]
            );
        }
        // Energy: emitted = absorbed + escaped + unshot.
        let balance = info.emitted - info.absorbed - info.escaped - info.unshot;
        assert!(balance.max_abs_diff(Rgb::BLACK) < 1e-9);
        // Unshot energy never increases (Southwell on the energy system, 003_… appendix B).
        let mut pr = Progressive::new(sys);
        let mut last = pr.unshot_fraction();
        for _ in 0..20 {
            let (i, _, _) = pr.scan();
            pr.shoot(i, &mut src);
            let now = pr.unshot_fraction();
            assert!(now <= last + 1e-15);
            last = now;
        }
    }
}
