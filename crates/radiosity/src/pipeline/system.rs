//! A given linear system (areas, reflectances, emissions and a stored F) solved, with its
//! convergence trace measured against the LU solution.

use super::*;
use crate::color::Rgb;
use crate::observe::{Event, Observer, Stage};
use crate::solve::trace::Trace;
use crate::solve::{Info, Solver, SolverParams};
use crate::system::{SparseMatrix, System};
use crate::Error;

/// Largest system whose trace measures the error against an LU solution.
pub const TRACE_EXACT_MAX: usize = 5000;

/// The exact solution a trace's error column is measured against: the LU solution of the
/// stored matrix `f`, when the system has at most [`TRACE_EXACT_MAX`] patches and the dense
/// matrix fits in half the available memory; otherwise `None`, with a warning to `observer`.
pub fn trace_reference(
    system: &System,
    f: &SparseMatrix,
    observer: &dyn Observer,
) -> Option<Vec<Rgb>> {
    let n = system.len();
    let limit = available_memory().unwrap_or(u64::MAX) / 2;
    if n > TRACE_EXACT_MAX || crate::solve::gauss::bytes_needed(n) > limit {
        observer.event(Event::Warning(&format!(
            "{n} patches: the trace's error column is left empty (LU reference only up to {TRACE_EXACT_MAX} patches)"
        )));
        return None;
    }
    match crate::solve::gauss::dense_solve_matrix(system, f, limit) {
        Ok(b) => Some(b),
        Err(e) => {
            observer.event(Event::Warning(&format!(
                "no reference solution for the trace: {e}"
            )));
            None
        }
    }
}

/// A given linear system, solved.
#[derive(Debug)]
pub struct SystemSolution {
    /// Radiosity per patch.
    pub radiosity: Vec<Rgb>,
    /// The solver's report.
    pub info: Info,
    /// The convergence trace, when asked for.
    pub trace: Option<Trace>,
}

/// Solve a given system (areas, reflectances, emissions and a stored F, e.g. read from files)
/// by `solver`; with `trace`, record the convergence of every iteration, each status exact
/// ([`crate::solve::run`]). The solver may use half the available memory.
pub fn solve_system(
    system: &System,
    f: &mut SparseMatrix,
    solver: Solver,
    params: &SolverParams,
    trace: bool,
    observer: &dyn Observer,
) -> Result<SystemSolution, Error> {
    let mut params = *params;
    params.memory_limit = available_memory().unwrap_or(u64::MAX) / 2;
    system.validate().map_err(crate::solve::SolveError::from)?;
    system
        .check_operator(f)
        .map_err(crate::solve::SolveError::from)?;
    let mut trace =
        trace.then(|| Trace::new(trace_reference(system, f, observer), &system.emission));
    observer.event(Event::Stage(Stage::Solve));
    let mut state = crate::solve::start(solver, system, f, &params)?;
    let info = crate::solve::run(&mut *state, f, &params, trace.is_some(), &mut |s, sv| {
        if let Some(t) = trace.as_mut() {
            t.record(s, sv);
        }
        observer.event(Event::Solve(s, sv));
        !observer.cancelled()
    });
    let mut radiosity = Vec::new();
    state.radiosity(&mut radiosity);
    Ok(SystemSolution {
        radiosity,
        info,
        trace,
    })
}
