//! Southwell relaxation (Gortler, Cohen & Slusallek (1993) section 3.1 and appendix A): start at x = 0,
//! r = E, and relax the unknown with the largest residual (channels summed), updating the
//! residuals through one column of F (eq. 16). Outputs the unknowns x. Converges for
//! radiosity matrices, which are row diagonally dominant (appendix A).

use super::relaxation::{Relaxation, SelectKind};
use super::{Operator, Solver, SolverState, System};

/// Southwell relaxation in progress.
#[derive(Clone, Debug)]
pub struct Southwell<'s> {
    core: Relaxation<'s>,
}

impl<'s> Southwell<'s> {
    /// Start from x = 0.
    pub fn new(system: &'s System) -> Self {
        let mut core = Relaxation::from_zero(system);
        core.select_by(SelectKind::Residual);
        Self { core }
    }
}

impl Southwell<'_> {
    /// Whether the output adds the residuals to the unknowns.
    fn plus_residual(&self) -> bool {
        false
    }
}

impl SolverState for Southwell<'_> {
    fn method(&self) -> Solver {
        Solver::Southwell
    }

    fn step(&mut self, source: &mut dyn Operator) -> bool {
        let (i, best) = self.core.shooter(crate::color::Rgb::BLACK);
        if best <= 0.0 {
            return false;
        }
        self.core.relax(i, 1.0, source);
        true
    }

    super::relaxation::relaxation_accessors!();
}
