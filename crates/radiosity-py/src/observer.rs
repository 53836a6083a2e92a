//! The bridge from the library's [`Observer`] to Python: progress reports to a callback, and
//! Ctrl-C or the callback's exception as a cancelled solve.

use pyo3::prelude::*;
use radiosity::observe::{Event, Observer, Stage};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// Forwards progress to a Python callable `(stage: str, done: int, total: int)`, at most every
/// 50 ms, taking the GIL only for the call; the first exception it raises stops the reports.
pub(crate) struct Progress {
    callback: Option<Py<PyAny>>,
    last: Mutex<(Instant, Option<PyErr>)>,
    /// Set with the first exception: solves stop at their next iteration.
    stop: AtomicBool,
}

impl Progress {
    pub(crate) fn new(callback: Option<Py<PyAny>>) -> Self {
        Self {
            callback,
            last: Mutex::new((Instant::now() - Duration::from_secs(1), None)),
            stop: AtomicBool::new(false),
        }
    }

    /// The exception the callback raised (or Ctrl-C's `KeyboardInterrupt`), if any: raise it
    /// rather than the stage's result.
    pub(crate) fn error(self) -> Option<PyErr> {
        self.last.into_inner().ok().and_then(|l| l.1)
    }
}

impl Observer for Progress {
    fn cancelled(&self) -> bool {
        self.stop.load(Ordering::Relaxed)
    }

    fn event(&self, e: Event<'_>) {
        let (stage, done, total) = match e {
            Event::Progress { stage, done, total } => (stage, done, total),
            Event::Stage(stage) => (stage, 0, 0),
            // A solve's iterations: reported as (solve, iterations, 0), and where Ctrl-C is
            // noticed during a long solve.
            Event::Solve(status, _) => (Stage::Solve, status.iterations.max(1), 0),
            _ => return,
        };
        let Ok(mut last) = self.last.lock() else {
            return;
        };
        if last.1.is_some()
            || (done != total && last.0.elapsed() < Duration::from_millis(50) && done != 0)
        {
            return;
        }
        last.0 = Instant::now();
        let Some(cb) = &self.callback else {
            // No callback: still notice Ctrl-C (the KeyboardInterrupt is raised when the
            // stage returns; the library has no way to stop a stage midway).
            Python::with_gil(|py| {
                if let Err(err) = py.check_signals() {
                    last.1 = Some(err);
                    self.stop.store(true, Ordering::Relaxed);
                }
            });
            return;
        };
        let name = match stage {
            Stage::Mesh => "mesh",
            Stage::Bvh => "bvh",
            Stage::FormFactors => "form-factors",
            Stage::Solve => "solve",
            Stage::Render => "render",
            Stage::Experiment => "experiment",
        };
        Python::with_gil(|py| {
            if let Err(err) = cb.call1(py, (name, done, total)) {
                last.1 = Some(err);
                self.stop.store(true, Ordering::Relaxed);
            }
        });
    }
}
