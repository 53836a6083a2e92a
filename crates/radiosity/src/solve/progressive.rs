//! Progressive refinement radiosity (Cohen, Chen, Wallace, Greenberg 1988), as given in
//! Gortler, Cohen & Slusallek (1993) section 2.1 and Szirmay-Kalos & Márton (1995) eq. 23–28.
//!
//! Each patch holds its radiosity `B_i` and unshot radiosity `ΔB_i`, both starting at `E_i`.
//! An iteration picks the shooter `i` with the most unshot energy `ΔB_i·A_i` and shoots with
//! column i of F (from a row by reciprocity, Szirmay-Kalos & Márton eq. 24, `F_ji = F_ij A_i / A_j`, when the
//! source estimates rows):
//!
//! ```text
//! ΔB_j += ρ_j ΔB_i F_ji,   B_j += same,   then ΔB_i = 0      (eq. 23)
//! ```
//!
//! All three channels in one pass. In the terms of [`super::relaxation`] this is Southwell
//! relaxation on the energy system (Gortler et al. section 5.1: the unknowns are the shot radiosity
//! ∇B, the residuals the unshot ΔB), and the output `B = ∇B + ΔB` adds one free Jacobi sweep
//! (Gortler et al. section 4). The unshot energy never increases, and by eq. 25 it falls by at least the
//! factor `1 − (1 − q)/N` per shot, where `q = max_i Σ_j ρ_j F_ij`.

use super::relaxation::{Relaxation, SelectKind};
use super::{Operator, Solver, SolverState, System};
use crate::color::Rgb;
use std::borrow::Cow;

/// Progressive refinement in progress.
#[derive(Clone, Debug)]
pub struct Progressive<'s> {
    core: Relaxation<'s>,
}

impl<'s> Progressive<'s> {
    /// Start: B = ΔB = E.
    pub fn new(system: &'s System) -> Self {
        let mut core = Relaxation::from_zero(system);
        core.select_by(SelectKind::Energy);
        Self { core }
    }

    /// The patch with the most unshot energy and that energy (the lowest index on ties), in
    /// O(1) from a max-tree kept up to date in O(log N) per changed residual.
    pub fn shooter(&self) -> (usize, f64) {
        self.core.shooter(Rgb::BLACK)
    }

    /// Shoot from patch `i`.
    pub fn shoot(&mut self, i: usize, source: &mut dyn Operator) {
        self.core.relax(i, 1.0, source);
    }

    /// Current unshot radiosities ΔB.
    pub fn unshot(&self) -> Vec<Rgb> {
        self.core.residuals().collect()
    }
}

impl Progressive<'_> {
    /// Whether the output adds the residuals to the unknowns.
    fn plus_residual(&self) -> bool {
        true
    }
}

impl SolverState for Progressive<'_> {
    fn method(&self) -> Solver {
        Solver::Progressive
    }

    fn step(&mut self, source: &mut dyn Operator) -> bool {
        let (i, best) = self.shooter();
        if best <= 0.0 {
            return false;
        }
        self.shoot(i, source);
        true
    }

    fn unshot(&self) -> Option<Cow<'_, [Rgb]>> {
        Some(Cow::Owned(Progressive::unshot(self)))
    }

    super::relaxation::relaxation_accessors!();
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solve::{solve, SolverParams};
    use crate::system::SparseMatrix;

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
            area: area.to_vec(),
            reflectance: refl.to_vec(),
            emission: emis.to_vec(),
        };
        sys.validate().unwrap();
        let mut src = SparseMatrix::from_rows(
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
        let params = SolverParams {
            tolerance: 1e-12,
            ..Default::default()
        };
        let (b, info) = solve(Solver::Progressive, &sys, &mut src, &params).unwrap();
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
        // Unshot energy never increases (Southwell on the energy system, Gortler et al. appendix B).
        let mut pr = Progressive::new(&sys);
        let mut last = pr.unshot_fraction(&mut src, true);
        for _ in 0..20 {
            pr.step(&mut src);
            let now = pr.unshot_fraction(&mut src, true);
            assert!(now <= last + 1e-15);
            last = now;
        }
    }
}
