//! Successive over-relaxation (Szirmay-Kalos & Márton (1995) eq. 21; Gortler, Cohen & Slusallek (1993)
//! section 3.3): Gauss-Seidel from B = E whose every change is scaled by ω,
//! `x_i += ω r_i / M_ii`, leaving `r_i = (1 − ω) r_i` (eq. 18–19). Cohen et al. suggest
//! ω ≈ 1.1 for radiosity; it converges for 0 < ω < 2 on these diagonally dominant systems.

use super::relaxation::Relaxation;
use super::{Operator, SolveError, Solver, SolverState, System};

/// Over-relaxation in progress.
#[derive(Clone, Debug)]
pub struct Sor<'s> {
    core: Relaxation<'s>,
    omega: f64,
    next: usize,
}

impl<'s> Sor<'s> {
    /// Start from B = E with factor `omega` in (0, 2).
    pub fn new(
        system: &'s System,
        source: &mut dyn Operator,
        omega: f64,
    ) -> Result<Self, SolveError> {
        if !(omega > 0.0 && omega < 2.0) {
            return Err(SolveError::Parameter {
                parameter: super::Parameter::Omega,
                value: omega,
                range: "(0, 2)",
            });
        }
        Ok(Self {
            core: Relaxation::from_emission(system, source),
            omega,
            next: 0,
        })
    }
}

impl Sor<'_> {
    /// Whether the output adds the residuals to the unknowns.
    fn plus_residual(&self) -> bool {
        false
    }
}

impl SolverState for Sor<'_> {
    fn method(&self) -> Solver {
        Solver::Sor
    }

    fn step(&mut self, source: &mut dyn Operator) -> bool {
        if self.core.unshot_fraction() == 0.0 {
            return false;
        }
        let i = self.next;
        self.core.relax(i, self.omega, source);
        self.next = (i + 1) % self.core.system.len();
        true
    }

    super::relaxation::relaxation_accessors!();
}
