//! A convergence trace: one row per iteration with the iteration, the seconds spent in the
//! solver, the error of eq. 22 of Gortler, Cohen & Slusallek (1993) against an exact solution
//! (empty without one), and the unshot energy as a fraction of the emitted energy. Kept as numbers ([`TraceRow`]);
//! [`Trace::csv`] is the text written out.

use super::{relative_error, SolverState, Status};
use crate::color::Rgb;
use std::fmt::Write as _;

/// The header of convergence traces.
pub const TRACE_HEADER: &str = "iteration,seconds,error,unshot";

/// One row of a trace: after `iteration` iterations and `seconds` in the solver, the error of
/// eq. 22 against the exact solution (`None` without one) and the unshot energy as a fraction
/// of the emitted energy.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TraceRow {
    /// Iterations done.
    pub iteration: u64,
    /// Seconds spent in the solver.
    pub seconds: f64,
    /// Eq. 22 error, when an exact solution was given.
    pub error: Option<f64>,
    /// Unshot energy over emitted energy.
    pub unshot: f64,
}

/// A convergence trace.
#[derive(Clone, Debug, Default)]
pub struct Trace {
    rows: Vec<TraceRow>,
    exact: Option<Vec<Rgb>>,
    emission: Vec<Rgb>,
    buf: Vec<Rgb>,
}

impl Trace {
    /// A trace measuring the error against `exact` (if given) of a system with `emission`.
    pub fn new(exact: Option<Vec<Rgb>>, emission: &[Rgb]) -> Self {
        Self {
            rows: Vec::new(),
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
                Some(relative_error(exact, &self.emission, &self.buf))
            }
            None => None,
        };
        self.rows.push(TraceRow {
            iteration: status.iterations,
            seconds: status.seconds,
            error,
            unshot: status.unshot_fraction,
        });
    }

    /// The rows recorded, in order.
    pub fn rows(&self) -> &[TraceRow] {
        &self.rows
    }

    /// Rows recorded.
    pub fn len(&self) -> usize {
        self.rows.len()
    }

    /// True when nothing was recorded.
    pub fn is_empty(&self) -> bool {
        self.rows.is_empty()
    }

    /// The trace as CSV, header first (an empty error field where no exact solution was
    /// given).
    pub fn csv(&self) -> String {
        let mut text = format!("{TRACE_HEADER}\n");
        for r in &self.rows {
            let error = r.error.map_or(String::new(), |e| e.to_string());
            let _ = writeln!(text, "{},{},{},{}", r.iteration, r.seconds, error, r.unshot);
        }
        text
    }
}
