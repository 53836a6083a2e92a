//! The linear system of radiosity, and nothing else: no geometry, no solver, no file format.
//!
//! ```text
//! B_i = E_i + ρ_i Σ_j F_ij B_j        for every patch i, in each colour channel,
//! ```
//!
//! (Szirmay-Kalos & Márton 1995, eq. 3; Gortler, Cohen & Slusallek 1993, eq. 1), i.e.
//! `M B = E` with `M = I − diag(ρ) F`. This module is the one boundary that form-factor methods
//! and solvers meet at:
//!
//! - [`System`] owns the per-patch data besides F: area `A_i`, reflectance `ρ_i`, emission `E_i`;
//! - [`Operator`] is F as the solvers see it, in the manner of faer's `LinOp`: row `i`, column
//!   `j`, a range of rows, `F x` and `Fᵀ x`. A stored [`SparseMatrix`] implements it, and so do
//!   the form-factor estimators that compute rows on demand;
//! - [`PhotonSampler`] is the separate interface of the photon-shooting solver: where a photon
//!   leaving patch `i` first lands;
//! - [`residual`] and [`balance`] are the two measures every solver shares.
//!
//! `formfactor` produces operators and `solve` consumes them; neither imports the other.

mod operator;
pub mod random;
mod sparse;

pub use operator::{Column, Gathered, Operator, PhotonSampler};
pub use sparse::SparseMatrix;

/// A radiosity system with its form factors stored: what the papers' solvers are compared
/// on when a system is given rather than a scene (random systems, a Matrix Market file).
#[derive(Clone, Debug)]
pub struct StoredSystem {
    /// Areas, reflectances, emissions.
    pub system: System,
    /// The form factors.
    pub f: SparseMatrix,
}

impl StoredSystem {
    /// The system and, separately borrowed, its matrix.
    pub fn parts(&mut self) -> (&System, &mut SparseMatrix) {
        (&self.system, &mut self.f)
    }

    /// Number of patches.
    pub fn len(&self) -> usize {
        self.system.len()
    }

    /// True for the empty system.
    pub fn is_empty(&self) -> bool {
        self.system.is_empty()
    }
}

use crate::color::Rgb;

/// One non-zero entry of a row of F: `(j, F_ij)` (or of a column: `(j, F_ji)`).
pub type Entry = (u32, f32);

/// The data of the radiosity system besides F, per patch and in all three colour channels.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct System {
    /// Patch areas `A_i` (> 0), in square scene units.
    pub area: Vec<f64>,
    /// Reflectances `ρ_i`, each channel in `[0, 1)`.
    pub reflectance: Vec<Rgb>,
    /// Emissions `E_i` (radiant exitance, ≥ 0), W per square scene unit.
    pub emission: Vec<Rgb>,
}

/// Why a system is not fit to solve.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SystemError {
    /// The per-patch arrays have different lengths.
    #[error("{areas} areas, {reflectances} reflectances, {emissions} emissions: lengths differ")]
    Lengths {
        /// Areas given.
        areas: usize,
        /// Reflectances given.
        reflectances: usize,
        /// Emissions given.
        emissions: usize,
    },
    /// A patch's area is not a positive finite number.
    #[error("patch {patch}: area {value} is not positive")]
    Area {
        /// The patch.
        patch: usize,
        /// Its area.
        value: f64,
    },
    /// A patch's reflectance is outside `[0, 1)`.
    #[error("patch {patch}: reflectance {value} outside [0, 1)")]
    Reflectance {
        /// The patch.
        patch: usize,
        /// Its reflectance.
        value: Rgb,
    },
    /// A patch's emission is negative or not finite.
    #[error("patch {patch}: emission {value} is negative or not finite")]
    Emission {
        /// The patch.
        patch: usize,
        /// Its emission.
        value: Rgb,
    },
    /// Nothing emits, so the solution is zero.
    #[error("no patch emits: the solution is zero")]
    NoEmitter,
    /// F and the per-patch data disagree in size.
    #[error("the form-factor matrix has {rows} rows but the system {patches} patches")]
    Size {
        /// Rows of F.
        rows: usize,
        /// Patches of the system.
        patches: usize,
    },
}

impl System {
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
            .zip(&self.area)
            .map(|(e, a)| *e * *a)
            .sum()
    }

    /// Total area Σ A_i.
    pub fn total_area(&self) -> f64 {
        self.area.iter().sum()
    }

    /// Check sizes and physical ranges: areas positive, reflectances in `[0, 1)`, emissions
    /// non-negative, all finite, and some patch emitting.
    pub fn validate(&self) -> Result<(), SystemError> {
        let n = self.len();
        if self.reflectance.len() != n || self.emission.len() != n {
            return Err(SystemError::Lengths {
                areas: n,
                reflectances: self.reflectance.len(),
                emissions: self.emission.len(),
            });
        }
        for i in 0..n {
            let (a, r, e) = (self.area[i], self.reflectance[i], self.emission[i]);
            if !(a.is_finite() && a > 0.0) {
                return Err(SystemError::Area { patch: i, value: a });
            }
            if !r.is_finite() || r.min_channel() < 0.0 || r.max_channel() >= 1.0 {
                return Err(SystemError::Reflectance { patch: i, value: r });
            }
            if !e.is_finite() || e.min_channel() < 0.0 {
                return Err(SystemError::Emission { patch: i, value: e });
            }
        }
        if self.emitted_power().max_channel() <= 0.0 {
            return Err(SystemError::NoEmitter);
        }
        Ok(())
    }

    /// Check that `f` has one row per patch.
    pub fn check_operator(&self, f: &dyn Operator) -> Result<(), SystemError> {
        if f.len() != self.len() {
            return Err(SystemError::Size {
                rows: f.len(),
                patches: self.len(),
            });
        }
        Ok(())
    }
}

/// The residual `r = E + ρ F B − B` of `b`, from rows of F.
pub fn residual(system: &System, f: &mut dyn Operator, b: &[Rgb]) -> Vec<Rgb> {
    (0..system.len())
        .map(|i| {
            let g: Rgb = f
                .row(i, 0.0)
                .iter()
                .map(|e| b[e.0 as usize] * e.1 as f64)
                .sum();
            system.emission[i] + system.reflectance[i] * g - b[i]
        })
        .collect()
}

/// The energy bookkeeping of radiosities `b` that are taken to have been shot once each:
/// `(absorbed, escaped, unshot, |unshot|)` with unshot = Σ r_i A_i (signed) and |unshot| =
/// Σ |r_i| A_i over channels, so that emitted = absorbed + escaped + unshot exactly.
pub fn balance(system: &System, f: &mut dyn Operator, b: &[Rgb]) -> (Rgb, Rgb, Rgb, f64) {
    let (mut absorbed, mut escaped, mut unshot, mut abs) =
        (Rgb::BLACK, Rgb::BLACK, Rgb::BLACK, 0.0);
    for i in 0..system.len() {
        let a = system.area[i];
        let rho = system.reflectance[i];
        let g: Rgb = f
            .row(i, 0.0)
            .iter()
            .map(|e| b[e.0 as usize] * e.1 as f64)
            .sum();
        // Under reciprocity, g A_i is the power arriving at i.
        absorbed += (Rgb::splat(1.0) - rho) * g * a;
        escaped += b[i] * a - g * a;
        let r = system.emission[i] + rho * g - b[i];
        unshot += r * a;
        abs += r.map(f64::abs).sum() * a;
    }
    (absorbed, escaped, unshot, abs)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn two_patches() -> (System, SparseMatrix) {
        let system = System {
            area: vec![1.0, 2.0],
            reflectance: vec![Rgb::splat(0.5), Rgb::splat(0.25)],
            emission: vec![Rgb::splat(1.0), Rgb::BLACK],
        };
        // A_0 F_01 = A_1 F_10: 1 · 0.6 = 2 · 0.3.
        let f = SparseMatrix::from_rows(vec![vec![(1, 0.6)], vec![(0, 0.3), (1, 0.1)]]);
        (system, f)
    }

    /// `apply` and `apply_transpose` agree with the entries, and the rows of a range come in
    /// order.
    #[test]
    fn operator_products_match_the_entries() {
        let (_, mut f) = two_patches();
        let x = [Rgb::new(1.0, 2.0, 3.0), Rgb::new(-1.0, 0.5, 4.0)];
        let mut y = [Rgb::BLACK; 2];
        f.apply(&x, &mut y);
        assert_eq!(y[0], x[1] * 0.6f32 as f64);
        assert_eq!(y[1], x[0] * 0.3f32 as f64 + x[1] * 0.1f32 as f64);
        f.apply_transpose(&x, &mut y);
        assert_eq!(y[0], x[1] * 0.3f32 as f64);
        assert_eq!(y[1], x[0] * 0.6f32 as f64 + x[1] * 0.1f32 as f64);
        let mut seen = Vec::new();
        f.rows(0..2, &mut |i, r| seen.push((i, r.len())));
        assert_eq!(seen, vec![(0, 1), (1, 2)]);
    }

    /// The residual of the exact solution is zero, and the balance closes: emitted = absorbed
    /// + escaped + unshot.
    #[test]
    fn residual_and_balance_of_the_exact_solution() {
        let (system, mut f) = two_patches();
        // B0 = 1 + 0.5·0.6·B1, B1 = 0.25·(0.3·B0 + 0.1·B1) → solve the 2×2 system.
        let (f01, f10, f11) = (0.6f32 as f64, 0.3f32 as f64, 0.1f32 as f64);
        let a = 1.0 - 0.25 * f11;
        let b0 = 1.0 / (1.0 - 0.5 * f01 * 0.25 * f10 / a);
        let b1 = 0.25 * f10 * b0 / a;
        let b = [Rgb::splat(b0), Rgb::splat(b1)];
        for r in residual(&system, &mut f, &b) {
            assert!(r.max_channel().abs() < 1e-15, "{r}");
        }
        let (absorbed, escaped, unshot, _) = balance(&system, &mut f, &b);
        let total = absorbed + escaped + unshot;
        assert!((total - system.emitted_power()).max_channel().abs() < 1e-12);
    }

    #[test]
    fn validation_names_the_patch() {
        let (mut system, f) = two_patches();
        assert!(system.validate().is_ok());
        assert!(system.check_operator(&f).is_ok());
        system.reflectance[1] = Rgb::splat(1.0);
        assert_eq!(
            system.validate(),
            Err(SystemError::Reflectance {
                patch: 1,
                value: Rgb::splat(1.0)
            })
        );
        system.area.push(1.0);
        assert!(matches!(
            system.validate(),
            Err(SystemError::Lengths { .. })
        ));
    }
}
