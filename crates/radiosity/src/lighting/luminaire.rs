//! A luminaire placed in a scene: its photometry, photometric centre, the orientation of its
//! frame in world coordinates, and its lamp's tilt factor.
//!
//! # The frame
//!
//! [`crate::photometry`] holds intensities in the luminaire's own frame: the photometric axis
//! along −z (type C: the nadir, γ = 0; types B and A: the beam, H = V = 0), +x across it (type
//! C: C = 0 at γ = 90°; types B and A: V = 90° at H = 0, the top of a floodlight), +y = z × x
//! (type C: C = 90°; types B and A: H = −90°, the left seen from behind the luminaire). A
//! [`Luminaire`] stores the world directions of those axes: `nadir` (world image of −z),
//! `c0` (of +x) and `c90` (of +y). They are orthonormal and right-handed: `c0 × c90 = −nadir`
//! (the luminaire's "up", world image of +z), so C increases counter-clockwise seen from above
//! the luminaire, as LM-63 and EULUMDAT turn, and a floodlight's H = 90° lies along
//! `nadir × c0`, to the right of its beam. [`Luminaire::new`] builds them from an aiming
//! direction and a C0 hint:
//!
//! 1. `nadir` = aim / |aim|;
//! 2. `c0` = the hint made perpendicular to the nadir by one Gram–Schmidt step,
//!    c0 − (c0 · nadir) nadir, normalised; without a hint, world +x, and where +x is parallel
//!    to the aim (a luminaire aimed along ±x) world +y instead;
//! 3. `c90` = c0 × nadir (so that c0 × c90 = −nadir).
//!
//! # Lamp tilt
//!
//! A photometric file with a tilt table ([`crate::photometry::Tilt`], IES `TILT=INCLUDE`)
//! rates the lamp at one tilt; installed at another, its light is multiplied by the table's
//! factor at the installed tilt angle. That angle depends on the luminaire's orientation and
//! the world's vertical, so it is applied per luminaire by [`Luminaire::with_lamp_tilt`]
//! (the schedule does, with the scene's up): the world's up is expressed in the luminaire's
//! frame, [`crate::photometry::Tilt::installed_angle`] gives the angle for the file's
//! lamp-to-luminaire geometry, the factor is interpolated linearly and multiplies
//! `multiplier`; an angle outside the table takes the nearer end's factor, with a warning.

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
    /// The world's up direction is zero or not finite.
    Up,
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
            FrameError::Up => "the up direction is zero or not finite",
        })
    }
}

impl std::error::Error for FrameError {}

/// The lamp tilt applied to a luminaire ([`Luminaire::with_lamp_tilt`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LampTilt {
    /// The installed tilt angle, degrees, as the file's lamp-to-luminaire geometry defines it
    /// ([`crate::photometry::LampGeometry`]).
    pub angle: f64,
    /// The tilt table's factor at that angle (already in [`Luminaire::multiplier`]).
    pub factor: f64,
    /// False when the angle lies outside the table's angles (the factor is the nearer end's).
    pub in_table: bool,
}

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
    /// Unit world direction of the photometric axis (the luminaire's −z): type C's γ = 0,
    /// types B and A's H = V = 0.
    pub nadir: [f64; 3],
    /// Unit world direction of the luminaire's +x, perpendicular to `nadir`: type C's C = 0,
    /// γ = 90°; types B and A's V = 90° at H = 0.
    pub c0: [f64; 3],
    /// Unit world direction of the luminaire's +y, `c0 × nadir`: type C's C = 90°, γ = 90°;
    /// types B and A's H = −90° at V = 0.
    pub c90: [f64; 3],
    /// Scales every intensity: the light-loss factor and dimming it was built with, times the
    /// lamp's tilt factor once [`Luminaire::with_lamp_tilt`] has applied it; finite and ≥ 0.
    /// The luminaire's flux is `photometry.flux() × multiplier`.
    pub multiplier: f64,
    /// The light scene (switching group) it belongs to.
    pub group: String,
    /// The lamp tilt applied, if any ([`Luminaire::with_lamp_tilt`]).
    pub tilt: Option<LampTilt>,
    /// What was doubtful in placing it (a tilt angle outside the file's tilt table), one line
    /// each; the photometry's own warnings are in [`Photometry::warnings`].
    pub warnings: Vec<String>,
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
            tilt: None,
            warnings: Vec::new(),
        })
    }

    /// The luminaire with its lamp's tilt factor applied, installed in a scene whose
    /// vertical is `up` (world coordinates; need not be unit length): see the module
    /// documentation. Without a tilt table in the photometry, or once applied already, it
    /// is returned as it is. Refused: a zero or non-finite `up`.
    pub fn with_lamp_tilt(mut self, up: [f64; 3]) -> Result<Luminaire, FrameError> {
        let up = unit(up).ok_or(FrameError::Up)?;
        let Some(table) = self.photometry.tilt.as_ref() else {
            return Ok(self);
        };
        if self.tilt.is_some() {
            return Ok(self);
        }
        let angle = table
            .installed_angle(self.to_local(up))
            .ok_or(FrameError::Up)?;
        let (factor, in_table) = table.factor(angle);
        if !in_table {
            let (first, last) = (
                table.angles.first().copied().unwrap_or(0.0),
                table.angles.last().copied().unwrap_or(0.0),
            );
            self.warnings.push(format!(
                "{}: the lamp's tilt, {angle:.1}°, is outside the tilt table's {first}..{last}° \
                 of {}: the factor at the nearer end, {factor}, is used",
                self.name, self.photometry.source
            ));
        }
        self.multiplier *= factor;
        self.tilt = Some(LampTilt {
            angle,
            factor,
            in_table,
        });
        Ok(self)
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

#[cfg(test)]
#[path = "tilt_tests.rs"]
mod tilt_tests;
