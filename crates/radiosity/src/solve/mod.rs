//! Solvers of the radiosity system (000_59d10e371b5f300d.txt eq. 3; 003_6556f2e3d50166bb.txt
//! eq. 1)
//!
//! ```text
//! B_i = E_i + ρ_i Σ_j F_ij B_j        for every patch i, in each colour channel,
//! ```
//!
//! They know only the linear system: areas, reflectances, emissions ([`System`]) and rows of F
//! from a [`RowSource`], never geometry, so a solver can be run on a hand-written 3 × 3 system
//! or on a matrix from another program. One file per solver: [`progressive`].

pub mod progressive;

use crate::color::Rgb;
use crate::formfactor::Entry;

/// The data of the radiosity system besides F: per patch, area `A_i`, reflectance `ρ_i` and
/// emission `E_i` (all three channels at once).
#[derive(Clone, Copy, Debug)]
pub struct System<'a> {
    /// Patch areas (> 0).
    pub area: &'a [f64],
    /// Reflectances, each channel in `[0, 1)`.
    pub reflectance: &'a [Rgb],
    /// Emissions (radiant exitance, ≥ 0).
    pub emission: &'a [Rgb],
}

impl System<'_> {
    /// Number of unknowns (patches).
    pub fn len(&self) -> usize {
        self.area.len()
    }

    /// True for the empty system.
    pub fn is_empty(&self) -> bool {
        self.area.is_empty()
    }

    /// Total emitted power Σ E_i A_i per channel.
    pub fn emitted_power(&self) -> Rgb {
        self.emission
            .iter()
            .zip(self.area)
            .map(|(e, a)| *e * *a)
            .sum()
    }

    /// Check sizes and physical ranges.
    pub fn validate(&self) -> Result<(), SolveError> {
        let n = self.len();
        if self.reflectance.len() != n || self.emission.len() != n {
            return Err(SolveError::Invalid(format!(
                "{} areas, {} reflectances, {} emissions: lengths differ",
                n,
                self.reflectance.len(),
                self.emission.len()
            )));
        }
        for i in 0..n {
            let (a, r, e) = (self.area[i], self.reflectance[i], self.emission[i]);
            if !(a.is_finite() && a > 0.0) {
                return Err(SolveError::Invalid(format!(
                    "patch {i}: area {a} is not positive"
                )));
            }
            if !r.is_finite() || r.min_channel() < 0.0 || r.max_channel() >= 1.0 {
                return Err(SolveError::Invalid(format!(
                    "patch {i}: reflectance {r} outside [0, 1)"
                )));
            }
            if !e.is_finite() || e.min_channel() < 0.0 {
                return Err(SolveError::Invalid(format!(
                    "patch {i}: emission {e} is negative or not finite"
                )));
            }
        }
        if self.emitted_power().max_channel() <= 0.0 {
            return Err(SolveError::Invalid(
                "no patch emits: the solution is zero".into(),
            ));
        }
        Ok(())
    }
}

/// Where a solver gets rows of F: a stored matrix or an estimator run on demand.
pub trait RowSource {
    /// Number of patches (rows).
    fn len(&self) -> usize;

    /// True when there are no rows.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Row `i` of F: `(j, F_ij)` for the non-zero entries, sorted by `j`. `share` is the
    /// fraction of the scene's emitted power the caller is about to shoot from `i`; estimators
    /// may use it to choose their effort, stored matrices ignore it.
    fn row(&mut self, i: usize, share: f64) -> &[Entry];
}

/// What a solver reports after each iteration.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Status {
    /// Iterations (shots, or relaxations) done.
    pub iterations: u64,
    /// Unshot (residual) energy as a fraction of the emitted energy.
    pub unshot_fraction: f64,
}

/// What a solver did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Info {
    /// Iterations done (shots for shooting methods).
    pub iterations: u64,
    /// True when the tolerance was reached.
    pub converged: bool,
    /// Unshot energy left, as a fraction of the emitted energy (channels summed).
    pub unshot_fraction: f64,
    /// Wall-clock seconds, form factors computed on demand included.
    pub seconds: f64,
    /// Emitted power Σ E_i A_i.
    pub emitted: Rgb,
    /// Power absorbed by the patches, Σ (1 − ρ_j) × (power arriving at j).
    pub absorbed: Rgb,
    /// Power shot that reached no patch (left an open scene or hit a back side).
    pub escaped: Rgb,
    /// Power not yet shot, Σ ΔB_i A_i.
    pub unshot: Rgb,
}

/// Why a solver could not run.
#[derive(Debug, thiserror::Error)]
pub enum SolveError {
    /// The system is malformed or unphysical.
    #[error("invalid radiosity system: {0}")]
    Invalid(String),
}

/// The ambient term of Cohen, Chen, Wallace and Greenberg (1988), quoted as eq. 2 of
/// 003_6556f2e3d50166bb.txt: the area-weighted mean unshot radiosity times the geometric series
/// of the area-weighted mean reflectance, `ΔB̄ / (1 − ρ̄)`. Added as `ρ_i · ambient` to each patch
/// for display only, it stands for the light not yet shot.
pub fn ambient_term(system: &System, unshot: &[Rgb]) -> Rgb {
    let total_area: f64 = system.area.iter().sum();
    let mut mean_unshot = Rgb::BLACK;
    let mut mean_rho = Rgb::BLACK;
    for i in 0..system.len() {
        mean_unshot += unshot[i] * system.area[i];
        mean_rho += system.reflectance[i] * system.area[i];
    }
    let (u, r) = (mean_unshot / total_area, mean_rho / total_area);
    Rgb::new(u.r / (1.0 - r.r), u.g / (1.0 - r.g), u.b / (1.0 - r.b))
}
