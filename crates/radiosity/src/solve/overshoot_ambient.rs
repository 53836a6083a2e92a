//! Overshooting with the ambient term (Feda 1992, as given in Gortler, Cohen & Slusallek (1993)
//! section 2.2.1): progressive refinement that shoots its unshot radiosity plus an estimate of
//! what will still arrive, `ΔB̂_i = ρ_i · ambient`, where the ambient term (eq. 2) is the
//! area-weighted mean unshot radiosity times `1/(1 − ρ̄)`. After the shot the patch's unshot
//! radiosity is `−ΔB̂_i`, which later shots bring back towards zero (or which is shot back,
//! negative, if the estimate was too high). The shooter is the patch with the largest
//! `|ΔB_i + ΔB̂_i|·A_i`. Output: B = x + r, as progressive refinement.

use super::relaxation::{Relaxation, SelectKind};
use super::{Operator, Solver, SolverState, System};
use crate::color::Rgb;

/// Overshooting with the ambient term in progress.
#[derive(Clone, Debug)]
pub struct OvershootAmbient<'s> {
    core: Relaxation<'s>,
    total_area: f64,
    mean_reflectance: Rgb,
}

impl<'s> OvershootAmbient<'s> {
    /// Start: B = ΔB = E.
    pub fn new(system: &'s System) -> Self {
        let total_area: f64 = system.area.iter().sum();
        let mean_reflectance = system
            .reflectance
            .iter()
            .zip(&system.area)
            .map(|(r, a)| *r * *a)
            .sum::<Rgb>()
            / total_area;
        let mut core = Relaxation::from_zero(system);
        core.select_by(SelectKind::Ambient);
        Self {
            core,
            total_area,
            mean_reflectance,
        }
    }

    /// The ambient radiosity of eq. 2 now: ΔB̄ / (1 − ρ̄), per channel.
    pub fn ambient(&self) -> Rgb {
        let mean = self.core.signed_unshot / self.total_area;
        let r = self.mean_reflectance;
        Rgb::new(
            mean.r / (1.0 - r.r),
            mean.g / (1.0 - r.g),
            mean.b / (1.0 - r.b),
        )
    }
}

impl OvershootAmbient<'_> {
    /// Whether the output adds the residuals to the unknowns.
    fn plus_residual(&self) -> bool {
        true
    }
}

impl SolverState for OvershootAmbient<'_> {
    fn method(&self) -> Solver {
        Solver::OvershootAmbient
    }

    fn step(&mut self, source: &mut dyn Operator) -> bool {
        let ambient = self.ambient();
        let sys = self.core.system;
        let core = &self.core;
        let amount = |i: usize| core.r(i) + sys.reflectance[i] * ambient;
        let (i, best) = self.core.shooter(ambient);
        if best <= 0.0 {
            return false;
        }
        let shot = amount(i);
        let share = best / self.core.emitted_total();
        let column = source.column(i, share);
        let m = self.core.diagonal(i, column);
        let delta = Rgb::new(shot.r / m.r, shot.g / m.g, shot.b / m.b);
        self.core.add(i, delta, column);
        self.core.iterations += 1;
        true
    }

    super::relaxation::relaxation_accessors!();
}
