//! Progress from every stage through one observer type. The library never prints: the stages
//! report [`Event`]s to an [`Observer`] that the program gives them (a progress bar, a trace
//! recorder, a log), and [`Silent`] ignores them. Observers take `&self` and are `Sync`,
//! because rows of F and of an image are computed on worker threads.

use crate::solve::{SolverState, Status};
use crate::system::{SparseMatrix, System};

/// The stages of a run, in the order the pipeline takes them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stage {
    /// Cutting surfaces into patches.
    Mesh,
    /// Building the ray-casting hierarchy.
    Bvh,
    /// Computing (and storing) every row of F.
    FormFactors,
    /// Solving (rows of F computed on demand count here).
    Solve,
    /// Rendering the picture.
    Render,
    /// A case of an experiment.
    Experiment,
}

/// What an observer is told.
#[derive(Clone, Copy)]
pub enum Event<'a> {
    /// A stage begins.
    Stage(Stage),
    /// `done` of `total` units of a stage are finished (rows of F, image rows, steps of an
    /// experiment's case). May come from worker threads, out of order.
    Progress {
        /// The stage.
        stage: Stage,
        /// Units finished.
        done: u64,
        /// Units in all.
        total: u64,
    },
    /// Every row of F has been computed and stored: the system about to be solved.
    Matrix(&'a SparseMatrix, &'a System),
    /// The solver's status before each iteration, and the solver (whose current B can be read).
    Solve(&'a Status, &'a dyn SolverState),
    /// Something the user should know that does not stop the run.
    Warning(&'a str),
    /// A case of an experiment begins, of `total` steps.
    Case {
        /// What the case is.
        label: &'a str,
        /// Its steps.
        total: u64,
    },
    /// The case is over; `summary` says what it found.
    CaseEnd {
        /// One line.
        summary: &'a str,
    },
}

/// Where events go.
pub trait Observer: Sync {
    /// Take one event.
    fn event(&self, event: Event<'_>);

    /// True when the caller wants the work stopped: solves check it every iteration and stop
    /// with the result so far (reported as not converged). Cheap: called often.
    fn cancelled(&self) -> bool {
        false
    }
}

impl<F: Fn(Event<'_>) + Sync> Observer for F {
    fn event(&self, event: Event<'_>) {
        self(event)
    }
}

/// An observer that ignores everything.
#[derive(Clone, Copy, Debug, Default)]
pub struct Silent;

impl Observer for Silent {
    fn event(&self, _: Event<'_>) {}
}
