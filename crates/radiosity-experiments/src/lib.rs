//! The papers' experiments, reproducible by one call each (and one command each in the CLI):
//!
//! - [`convergence`]: section 6 of Gortler, Cohen & Slusallek (1993) — the error of eq. 22 after every
//!   iteration of every solver on the office, the dim and bright cube and random sparse systems
//!   (its figures 3–8), also against CPU time;
//! - [`complexity`]: the claims of Szirmay-Kalos & Márton (1995) — time, iterations and memory of the
//!   form-factor methods and the solvers as N grows, with fitted exponents beside the paper's;
//! - [`cie171`]: the electric-lighting test cases of CIE 171:2006 (5.2–5.8) through the lighting
//!   pipeline, each point against a reference computed here by closed forms and quadratures.
//!
//! [`random`] makes the random systems. Memory is measured through a [`MemoryProbe`] that the
//! program provides (a library cannot own the global allocator); progress is reported to an
//! [`Observer`].

pub mod cie171;
pub mod complexity;
pub mod convergence;
pub mod plot;
/// The random systems (moved to the library: they are systems to compare solvers on).
pub use radiosity::system::random;

use radiosity::observe::{Event, Observer, Stage};

pub use radiosity::system::StoredSystem;

/// Heap memory in use, as the program sees it.
pub trait MemoryProbe: Sync {
    /// Bytes allocated now.
    fn current(&self) -> u64;
    /// Start a new peak: from now on [`MemoryProbe::peak`] is the highest [`current`] since
    /// this call.
    ///
    /// [`current`]: MemoryProbe::current
    fn reset_peak(&self);
    /// The highest bytes allocated since the last [`MemoryProbe::reset_peak`].
    fn peak(&self) -> u64;
}

/// The progress of one case of an experiment, reported to an [`Observer`] as
/// [`Event::Case`], [`Event::Progress`] of [`Stage::Experiment`] and [`Event::CaseEnd`].
pub(crate) struct CaseProgress<'a> {
    observer: &'a dyn Observer,
    total: u64,
}

impl<'a> CaseProgress<'a> {
    /// A case of `total` steps begins.
    pub(crate) fn begin(observer: &'a dyn Observer, label: &str, total: u64) -> Self {
        observer.event(Event::Case { label, total });
        Self { observer, total }
    }

    /// `done` of the case's steps are done.
    pub(crate) fn advance(&self, done: u64) {
        self.observer.event(Event::Progress {
            stage: Stage::Experiment,
            done,
            total: self.total,
        });
    }

    /// The case is over; `summary` says what it found.
    pub(crate) fn end(self, summary: &str) {
        self.observer.event(Event::CaseEnd { summary });
    }
}

/// Run `f` and measure its wall-clock seconds and, with a probe, the peak of the heap above
/// what was allocated when it started.
pub fn measure<T>(probe: Option<&dyn MemoryProbe>, f: impl FnOnce() -> T) -> (T, f64, Option<u64>) {
    let base = probe.map(|p| {
        p.reset_peak();
        p.current()
    });
    let t = std::time::Instant::now();
    let out = f();
    let seconds = t.elapsed().as_secs_f64();
    let peak = probe.zip(base).map(|(p, b)| p.peak().saturating_sub(b));
    (out, seconds, peak)
}

/// The least-squares slope of log y against log x: the exponent k of y ∝ x^k. Points with a
/// non-positive coordinate are ignored; `None` with fewer than two usable points or one x.
pub fn fit_exponent(points: &[(f64, f64)]) -> Option<f64> {
    let logs: Vec<(f64, f64)> = points
        .iter()
        .filter(|p| p.0 > 0.0 && p.1 > 0.0 && p.0.is_finite() && p.1.is_finite())
        .map(|p| (p.0.ln(), p.1.ln()))
        .collect();
    let n = logs.len() as f64;
    if logs.len() < 2 {
        return None;
    }
    let mx = logs.iter().map(|p| p.0).sum::<f64>() / n;
    let my = logs.iter().map(|p| p.1).sum::<f64>() / n;
    let sxx: f64 = logs.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let sxy: f64 = logs.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    (sxx > 0.0).then(|| sxy / sxx)
}

/// Why an experiment failed.
#[derive(Debug, thiserror::Error)]
pub enum ExperimentError {
    /// A stage of the engine failed.
    #[error(transparent)]
    Engine(#[from] radiosity::Error),
    /// Writing a result failed.
    #[error(transparent)]
    Export(#[from] radiosity::export::ExportError),
    /// The parameters cannot work.
    #[error("{0}")]
    Invalid(String),
}

impl From<radiosity::solve::SolveError> for ExperimentError {
    fn from(e: radiosity::solve::SolveError) -> Self {
        Self::Engine(e.into())
    }
}

impl From<radiosity::scene::SceneError> for ExperimentError {
    fn from(e: radiosity::scene::SceneError) -> Self {
        Self::Engine(e.into())
    }
}

impl From<radiosity::formfactor::FormFactorError> for ExperimentError {
    fn from(e: radiosity::formfactor::FormFactorError) -> Self {
        Self::Invalid(e.to_string())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fit_recovers_exact_power_laws() {
        for k in [0.0, 1.0, 2.0, 3.0, -0.5] {
            let pts: Vec<(f64, f64)> = [10.0, 20.0, 40.0, 160.0]
                .iter()
                .map(|&x: &f64| (x, 3.0 * x.powf(k)))
                .collect();
            assert!((fit_exponent(&pts).unwrap() - k).abs() < 1e-12);
        }
        assert_eq!(fit_exponent(&[(1.0, 1.0)]), None);
        assert_eq!(fit_exponent(&[(2.0, 1.0), (2.0, 5.0)]), None);
    }
}
