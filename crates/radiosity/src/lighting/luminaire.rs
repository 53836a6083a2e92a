//! A luminaire placed in a scene: its photometry, photometric centre, and the orientation of
//! its C-γ frame in world coordinates.
//!
//! # The frame
//!
//! [`crate::photometry`] holds intensities in the luminaire's own frame: nadir (γ = 0) along
//! −z, C = 0 (γ = 90°) along +x, C = 90° along +y. A [`Luminaire`] stores the world
//! directions of those axes: `nadir` (world image of −z), `c0` (of +x) and `c90` (of +y). They
//! are orthonormal and right-handed: `c0 × c90 = −nadir` (the luminaire's "up", world image of
//! +z), so C increases counter-clockwise seen from above the luminaire, as LM-63 and
//! EULUMDAT turn. [`Luminaire::new`] builds them from an aiming direction and a C0 hint:
//!
//! 1. `nadir` = aim / |aim|;
//! 2. `c0` = the hint made perpendicular to the nadir by one Gram–Schmidt step,
//!    c0 − (c0 · nadir) nadir, normalised; without a hint, world +x, and where +x is parallel
//!    to the aim (a luminaire aimed along ±x) world +y instead;
//! 3. `c90` = c0 × nadir (so that c0 × c90 = −nadir).

use super::{cross, dot, norm, scale, sub, unit};
use crate::photometry::Photometry;
use std::fmt;
use std::sync::Arc;

/// Below this |sin| of the angle between the C0 hint and the aim, the two count as parallel.
pub const PARALLEL_SIN: f64 = 1e-6;

/// Why [`Luminaire::new`] could not build a luminaire.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FrameError {
    /// The position is not finite.
    Position,
    /// The aiming direction is zero or not finite.
    Aim,
    /// The C0 direction is zero or not finite.
    C0,
    /// The C0 direction is parallel to the aim, so it names no half-plane.
    C0ParallelToAim,
    /// The multiplier is negative or not finite.
    Multiplier,
}

impl fmt::Display for FrameError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            FrameError::Position => "the position is not finite",
            FrameError::Aim => "the aim (the direction of gamma = 0) is zero or not finite",
            FrameError::C0 => "the C0 direction is zero or not finite",
            FrameError::C0ParallelToAim => {
                "the C0 direction is parallel to the aim, so it names no C = 0 half-plane"
            }
            FrameError::Multiplier => "the multiplier must be a finite number >= 0",
        })
    }
}

impl std::error::Error for FrameError {}

/// A luminaire in the scene: a point source at `position` sending
/// `multiplier × photometry` in the frame `(c0, c90, −nadir)` (see the module documentation).
#[derive(Clone, Debug)]
pub struct Luminaire {
    /// The schedule's name for it.
    pub name: String,
    /// Its intensity distribution, shared by every luminaire of the same file.
    pub photometry: Arc<Photometry>,
    /// The photometric centre, scene units.
    pub position: [f64; 3],
    /// Unit world direction of γ = 0 (the luminaire's −z).
    pub nadir: [f64; 3],
    /// Unit world direction of C = 0, γ = 90° (the luminaire's +x), perpendicular to `nadir`.
    pub c0: [f64; 3],
    /// Unit world direction of C = 90°, γ = 90° (the luminaire's +y): `c0 × nadir`.
    pub c90: [f64; 3],
    /// Scales every intensity (light-loss factor, dimming); finite and ≥ 0.
    pub multiplier: f64,
    /// The light scene (switching group) it belongs to.
    pub group: String,
}

impl Luminaire {
    /// A luminaire at `position` whose γ = 0 points along `aim` and whose C = 0 half-plane
    /// contains `c0` (made perpendicular to `aim`; `None`: world +x, or +y where +x is
    /// parallel to `aim`). Neither direction need be unit length. Refused: a non-finite
    /// position, a zero or non-finite aim or C0, a C0 parallel to the aim, a negative or
    /// non-finite multiplier.
    pub fn new(
        name: impl Into<String>,
        photometry: Arc<Photometry>,
        position: [f64; 3],
        aim: [f64; 3],
        c0: Option<[f64; 3]>,
        multiplier: f64,
        group: impl Into<String>,
    ) -> Result<Luminaire, FrameError> {
        if !position.iter().all(|v| v.is_finite()) {
            return Err(FrameError::Position);
        }
        if !(multiplier.is_finite() && multiplier >= 0.0) {
            return Err(FrameError::Multiplier);
        }
        let nadir = unit(aim).ok_or(FrameError::Aim)?;
        // The hint less its component along the nadir, or None where that leaves (almost)
        // nothing.
        let perpendicular = |hint: [f64; 3]| -> Option<[f64; 3]> {
            let u = unit(hint)?;
            let p = sub(u, scale(nadir, dot(u, nadir)));
            if norm(p) < PARALLEL_SIN {
                None
            } else {
                unit(p)
            }
        };
        let c0 = match c0 {
            Some(hint) => {
                unit(hint).ok_or(FrameError::C0)?;
                perpendicular(hint).ok_or(FrameError::C0ParallelToAim)?
            }
            None => perpendicular([1.0, 0.0, 0.0])
                .or_else(|| perpendicular([0.0, 1.0, 0.0]))
                .ok_or(FrameError::Aim)?,
        };
        let c90 = cross(c0, nadir);
        Ok(Luminaire {
            name: name.into(),
            photometry,
            position,
            nadir,
            c0,
            c90,
            multiplier,
            group: group.into(),
        })
    }

    /// The luminaire's "up", the world image of its +z: `−nadir` (= `c0 × c90`).
    pub fn up(&self) -> [f64; 3] {
        scale(self.nadir, -1.0)
    }

    /// A world direction expressed in the luminaire's frame (x along C0, y along C90, z up,
    /// so the nadir is −z): the frame [`Photometry::intensity_dir`] takes.
    pub fn to_local(&self, world_dir: [f64; 3]) -> [f64; 3] {
        [
            dot(world_dir, self.c0),
            dot(world_dir, self.c90),
            -dot(world_dir, self.nadir),
        ]
    }

    /// The world direction of a direction given in the luminaire's frame: the inverse of
    /// [`Luminaire::to_local`].
    pub fn to_world(&self, local: [f64; 3]) -> [f64; 3] {
        let mut w = [0.0; 3];
        for (k, wk) in w.iter_mut().enumerate() {
            *wk = local[0] * self.c0[k] + local[1] * self.c90[k] - local[2] * self.nadir[k];
        }
        w
    }

    /// The intensity, candela, the luminaire sends along the world direction `world_dir`
    /// (from the luminaire outwards; need not be unit length): `multiplier` × the photometry's
    /// intensity of that direction in the luminaire's frame. Zero or non-finite: 0.
    pub fn intensity_towards(&self, world_dir: [f64; 3]) -> f64 {
        self.multiplier * self.photometry.intensity_dir(self.to_local(world_dir))
    }
}
