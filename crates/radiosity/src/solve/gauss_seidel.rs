//! Gauss-Seidel iteration (Szirmay-Kalos & Márton (1995) eq. 12–20; Gortler, Cohen & Slusallek (1993)
//! section 3.1): relax the unknowns in order, each with the newest values of the others,
//! `x_i ← (E_i + ρ_i Σ_{j≠i} F_ij x_j) / (1 − ρ_i F_ii)`, the same as `x_i += r_i / M_ii`.
//! Three variants, the first three of section 6 of Gortler et al.:
//! - `gauss-seidel-0`: start at x = 0, output x;
//! - `gauss-seidel`: start at x = E, output x (gathering, Gortler et al. section 2.1);
//! - `gauss-seidel-jacobi`: start at x = 0, output x + r (one free Jacobi sweep, equivalent to
//!   shooting in order).
//!
//! Eq. 20 proves its per-sweep attenuation β/(1 − α) is below Jacobi's q.

use super::relaxation::Relaxation;
use super::{Operator, Solver, SolverState, System};

/// Which Gauss-Seidel.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Variant {
    /// From 0, output the unknowns.
    Zero,
    /// From E, output the unknowns (gathering).
    Emission,
    /// From 0, output unknowns plus residuals.
    ZeroPlusResidual,
}

/// Gauss-Seidel in progress.
#[derive(Clone, Debug)]
pub struct GaussSeidel<'s> {
    core: Relaxation<'s>,
    variant: Variant,
    next: usize,
}

impl<'s> GaussSeidel<'s> {
    /// Start the given variant.
    pub fn new(system: &'s System, source: &mut dyn Operator, variant: Variant) -> Self {
        let core = match variant {
            Variant::Emission => Relaxation::from_emission(system, source),
            _ => Relaxation::from_zero(system),
        };
        Self {
            core,
            variant,
            next: 0,
        }
    }
}

impl GaussSeidel<'_> {
    /// Whether the output adds the residuals to the unknowns.
    fn plus_residual(&self) -> bool {
        self.variant == Variant::ZeroPlusResidual
    }
}

impl SolverState for GaussSeidel<'_> {
    fn method(&self) -> Solver {
        match self.variant {
            Variant::Zero => Solver::GaussSeidel0,
            Variant::Emission => Solver::GaussSeidel,
            Variant::ZeroPlusResidual => Solver::GaussSeidelJacobi,
        }
    }

    fn step(&mut self, source: &mut dyn Operator) -> bool {
        if self.core.unshot_fraction() == 0.0 {
            return false;
        }
        let i = self.next;
        self.core.relax(i, 1.0, source);
        self.next = (i + 1) % self.core.system.len();
        true
    }

    super::relaxation::relaxation_accessors!();
}
