//! The energy books of a lighting calculation: where each light group's luminous flux goes,
//! in lumens.
//!
//! For a group of luminaires (flux Φ integrated from their distributions, after multipliers),
//! with E_p the mean direct illuminance over patch p (the first shot, its flux over its solid
//! angle: [`crate::lighting::first_shot`]), A_p its area and ρ_p
//! its reflectance (photometric Y: the luminaires are white, so Y((1 − ρ) E) = (1 − Y(ρ)) E):
//!
//! ```text
//! emitted             Φ
//! direct_to_surfaces  Φ_d = Σ_p A_p E_p                       (integrated over each patch)
//! absorbed            Σ_p A_p (1 − ρ_p) E_p + Φ_a,inter       (first shot + interreflection)
//! unshot              Φ_u = Σ_i ΔB_i A_i                      (the solver's residual)
//! escaped             Φ − absorbed − Φ_u
//! escaped_counted     Σ_l Φ_l (1 − reach_l) + Φ_x,inter
//! ```
//!
//! The interreflection's absorbed and escaped power Φ_a,inter and Φ_x,inter are the solver's
//! own books ([`crate::solve::Info`]: at each shot, Σ_j (1 − ρ_j) × the power arriving at j,
//! and what reached no front face). `reach_l` is the fraction of luminaire l's flux sent in
//! directions that reach a front face of the scene, counted independently of the patches by
//! casting the luminaire's distribution against the scene on a grid of equal solid angle
//! ([`ESCAPE_BANDS`] × [`ESCAPE_SECTORS`] cells, one ray at each cell's centre, weighted by
//! the intensity there): [`EnergyBooks::balance_error`], (escaped − escaped_counted)/Φ, is then
//! Φ_reach − Φ_d over Φ, how well the patches' cells sample the first shot's visibility (plus
//! the grid's own error, the cells a shadow edge crosses). In a closed room both escapes are 0 and
//! absorbed + unshot = emitted to that error.
//!
//! For the scene's own emitting surfaces (exitance M_i), Φ = Σ_i Y(M_i) A_i, the first shot
//! is Σ_i Y(M_i) A_i Σ_j F_ij, and the rest is the solver's books alone.

use crate::accel::Bvh;
use crate::geom::{Ray, Vec3};
use crate::lighting::Luminaire;
use rayon::prelude::*;

/// Bands of equal solid angle (uniform in cos γ) of the grid on which a luminaire's flux is
/// cast against the scene to count what escapes.
pub const ESCAPE_BANDS: usize = 64;

/// Sectors (uniform in C) of that grid: [`ESCAPE_BANDS`] × [`ESCAPE_SECTORS`] cells of
/// 4π / 8192 sr each.
pub const ESCAPE_SECTORS: usize = 128;

/// Where one light group's luminous flux goes (or every group's together), lumens. See the
/// module documentation of `pipeline::lighting` for the definitions.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct EnergyBooks {
    /// Flux emitted: the luminaires' (integrated from their distributions, after
    /// multipliers), or the scene's own emitting surfaces' Σ M A.
    pub emitted: f64,
    /// Flux that reaches surfaces directly (the first shot into the patches).
    pub direct_to_surfaces: f64,
    /// Flux absorbed by the surfaces, Σ A (1 − ρ) E over the first shot and the
    /// interreflection (luminance-weighted).
    pub absorbed: f64,
    /// Flux that left the scene (through openings, or onto back faces):
    /// emitted − absorbed − unshot.
    pub escaped: f64,
    /// The flux the interreflection's solver left unshot (its residual).
    pub unshot: f64,
    /// The escape counted on its own: the luminaires' flux in directions that reach no front
    /// face, plus the interreflection's shots that reached none.
    pub escaped_counted: f64,
}

impl EnergyBooks {
    /// (escaped − escaped_counted) / emitted: the books' two ways of counting the escape
    /// disagree by the first shot's patch-sampling error (0 where nothing is emitted).
    pub fn balance_error(&self) -> f64 {
        if self.emitted > 0.0 {
            (self.escaped - self.escaped_counted) / self.emitted
        } else {
            0.0
        }
    }

    /// The books of several groups together (sums, in order).
    pub fn total(groups: &[EnergyBooks]) -> EnergyBooks {
        groups
            .iter()
            .fold(EnergyBooks::default(), |t, b| EnergyBooks {
                emitted: t.emitted + b.emitted,
                direct_to_surfaces: t.direct_to_surfaces + b.direct_to_surfaces,
                absorbed: t.absorbed + b.absorbed,
                escaped: t.escaped + b.escaped,
                unshot: t.unshot + b.unshot,
                escaped_counted: t.escaped_counted + b.escaped_counted,
            })
    }
}

/// For each luminaire, the fraction of its flux sent in directions that reach a front face of
/// the scene (see the module documentation): its intensity summed over the centres of the
/// [`ESCAPE_BANDS`] × [`ESCAPE_SECTORS`] equal solid-angle cells whose ray from the
/// photometric centre first meets a front face, over its sum over all cells (so the
/// distribution's own flux, integrated exactly elsewhere, is not re-estimated). Each ray
/// starts [`Bvh::ray_offset`] from the centre, so a luminaire mounted on a ceiling does not
/// meet that ceiling. A luminaire that sends nothing reaches nothing (0). Parallel over
/// luminaires and bands, summed in a fixed order: deterministic.
pub(super) fn reach(luminaires: &[Luminaire], bvh: &Bvh) -> Vec<f64> {
    let offset = bvh.ray_offset();
    let bands: Vec<(f64, f64)> = (0..luminaires.len() * ESCAPE_BANDS)
        .into_par_iter()
        .map(|k| {
            let (l, band) = (&luminaires[k / ESCAPE_BANDS], k % ESCAPE_BANDS);
            let z = -1.0 + 2.0 * (band as f64 + 0.5) / ESCAPE_BANDS as f64;
            let r = (1.0 - z * z).max(0.0).sqrt();
            let at = Vec3::new(
                l.position[0] as f32,
                l.position[1] as f32,
                l.position[2] as f32,
            );
            let (mut hit, mut all) = (0.0, 0.0);
            for s in 0..ESCAPE_SECTORS {
                let phi = std::f64::consts::TAU * (s as f64 + 0.5) / ESCAPE_SECTORS as f64;
                let local = [r * phi.cos(), r * phi.sin(), z];
                let i = l.photometry.intensity_dir(local);
                if i.is_nan() || i <= 0.0 {
                    continue;
                }
                all += i;
                let w = l.to_world(local);
                let d = Vec3::new(w[0] as f32, w[1] as f32, w[2] as f32).normalize_or_zero();
                let ray = Ray::new(at + d * offset, d);
                if bvh
                    .closest_hit(&ray, f32::INFINITY)
                    .is_some_and(|h| h.front)
                {
                    hit += i;
                }
            }
            (hit, all)
        })
        .collect();
    bands
        .chunks(ESCAPE_BANDS)
        .map(|c| {
            let (hit, all) = c
                .iter()
                .fold((0.0, 0.0), |(h, a), &(bh, ba)| (h + bh, a + ba));
            if all > 0.0 {
                hit / all
            } else {
                0.0
            }
        })
        .collect()
}
