//! Jacobi iteration (Szirmay-Kalos & Márton (1995) eq. 8–11; Gortler, Cohen & Slusallek (1993) section 3.2):
//! `B(m+1) = E + R B(m)` with `R = diag(ρ) F`, starting from `B(0) = E`. One iteration computes
//! one row: `x_i ← (E_i + ρ_i Σ_{j≠i} F_ij x_j^old) / (1 − ρ_i F_ii)` from the values of the
//! previous sweep, which are kept aside until the sweep is complete. Converges for any
//! physical system, since ‖R‖∞ = max_i ρ_i Σ_j F_ij < 1 (eq. 10–11).

use super::relaxation::Relaxation;
use super::{Operator, Solver, SolverState, System};
use crate::color::Rgb;

/// Jacobi iteration in progress.
#[derive(Clone, Debug)]
pub struct Jacobi<'s> {
    core: Relaxation<'s>,
    old: Vec<Rgb>,
    next: usize,
}

impl<'s> Jacobi<'s> {
    /// Start from B = E.
    pub fn new(system: &'s System, source: &mut dyn Operator) -> Self {
        let core = Relaxation::from_emission(system, source);
        Self {
            old: core.x.clone(),
            core,
            next: 0,
        }
    }
}

impl Jacobi<'_> {
    /// Whether the output adds the residuals to the unknowns.
    fn plus_residual(&self) -> bool {
        false
    }
}

impl SolverState for Jacobi<'_> {
    fn method(&self) -> Solver {
        Solver::Jacobi
    }

    fn step(&mut self, source: &mut dyn Operator) -> bool {
        if self.core.unshot_fraction() == 0.0 {
            return false;
        }
        let i = self.next;
        if i == 0 {
            self.old.copy_from_slice(&self.core.x);
        }
        let sys = self.core.system;
        let mut gathered = Rgb::BLACK;
        let mut f_ii = 0.0;
        for &(j, f) in source.row(i, 0.0) {
            if j as usize == i {
                f_ii = f as f64;
            } else {
                gathered += self.old[j as usize] * f as f64;
            }
        }
        let rho = sys.reflectance[i];
        let num = sys.emission[i] + rho * gathered;
        let den = Rgb::splat(1.0) - rho * f_ii;
        let new = Rgb::new(num.r / den.r, num.g / den.g, num.b / den.b);
        let delta = new - self.core.x[i];
        let share = self.core.energy(i) / self.core.emitted_total();
        let column = source.column(i, share);
        self.core.add(i, delta, column);
        self.core.iterations += 1;
        self.next = (i + 1) % sys.len();
        true
    }

    super::relaxation::relaxation_accessors!();
}
