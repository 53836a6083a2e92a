//! A convergence trace: one row per iteration with the iteration, the seconds spent in the
//! solver, the error of eq. 22 of Gortler, Cohen & Slusallek (1993) against an exact solution
//! (empty without one), and the unshot energy as a fraction of the emitted energy. Kept as the
//! CSV text it is written as (`export::write_text`).

use super::{relative_error, SolverState, Status};
use crate::color::Rgb;
use std::fmt::Write as _;

/// The header of convergence traces.
pub const TRACE_HEADER: &str = "iteration,seconds,error,unshot";

/// A convergence trace.
#[derive(Clone, Debug, Default)]
pub struct Trace {
    text: String,
    exact: Option<Vec<Rgb>>,
    emission: Vec<Rgb>,
    buf: Vec<Rgb>,
}

impl Trace {
    /// A trace measuring the error against `exact` (if given) of a system with `emission`.
    pub fn new(exact: Option<Vec<Rgb>>, emission: &[Rgb]) -> Self {
        Self {
            text: format!("{TRACE_HEADER}\n"),
            exact,
            emission: emission.to_vec(),
            buf: Vec::new(),
        }
    }

    /// Record the solver's state.
    pub fn record(&mut self, status: &Status, solver: &dyn SolverState) {
        let error = match &self.exact {
            Some(exact) => {
                solver.radiosity(&mut self.buf);
                relative_error(exact, &self.emission, &self.buf).to_string()
            }
            None => String::new(),
        };
        let _ = writeln!(
            self.text,
            "{},{},{},{}",
            status.iterations, status.seconds, error, status.unshot_fraction
        );
    }

    /// Rows recorded.
    pub fn len(&self) -> usize {
        self.text.lines().count() - 1
    }

    /// True when nothing was recorded.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The trace as CSV, header first.
    pub fn csv(&self) -> &str {
        &self.text
    }
}
