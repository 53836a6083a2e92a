//! Southwell relaxation (003_6556f2e3d50166bb.txt section 3.1 and appendix A): start at x = 0,
//! r = E, and relax the unknown with the largest residual (channels summed), updating the
//! residuals through one column of F (eq. 16). Outputs the unknowns x. Converges for
//! radiosity matrices, which are row diagonally dominant (appendix A).

use super::relaxation::Relaxation;
use super::{Method, RowSource, Solver, System};

/// Southwell relaxation in progress.
#[derive(Clone, Debug)]
pub struct Southwell<'s> {
    core: Relaxation<'s>,
}

impl<'s> Southwell<'s> {
    /// Start from x = 0.
    pub fn new(system: System<'s>) -> Self {
        Self {
            core: Relaxation::from_zero(system),
        }
    }
}

impl Southwell<'_> {
    /// Whether the output adds the residuals to the unknowns.
    fn plus_residual(&self) -> bool {
        false
    }
}

impl Solver for Southwell<'_> {
    fn method(&self) -> Method {
        Method::Southwell
    }

    fn step(&mut self, source: &mut dyn RowSource) -> bool {
        let area = self.core.system.area;
        let energy = &self.core.energy;
        let (i, best) = self.core.argmax(|i| energy[i] / area[i]);
        if best <= 0.0 {
            return false;
        }
        self.core.relax(i, 1.0, source);
        true
    }

    super::relaxation::relaxation_accessors!();
}
