//! Lighting design: luminaires with measured photometry placed in a scene, and the
//! illuminance they give at sensor points (issue 57's `radiosity lighting` command builds on
//! this layer).
//!
//! - [`schedule`]: the luminaire schedule, a CSV file naming each luminaire's photometric
//!   file ([`crate::photometry`]), position, aiming, multiplier and group (light scene).
//! - [`points`]: sensor points in Radiance's points format (`x y z dx dy dz` a line, as
//!   `rtrace -I` reads them).
//! - [`luminaire`]: a placed luminaire, its local C-γ frame in world coordinates and the
//!   intensity it sends in a world direction.
//! - [`workplane`](mod@workplane): a calculation grid over a material's surfaces, spaced as EN 12464-1 asks.
//! - [`direct`]: the exact direct illuminance at points from point luminaires, by the
//!   inverse-square cosine law E = I(ω) cos θ / d², with one shadow ray each.
//! - [`first_shot`]: the luminaires' first shot into the patches, each patch's flux
//!   integrated over its solid angle with visibility (an adaptive rule, exact for an
//!   unshadowed isotropic source).
//! - [`sky`]: the CIE standard general skies, the CIE overcast and uniform skies scaled to
//!   their horizontal illuminance, the sun's position, the scene's frame (daylight, issue 58).
//! - [`glazing`]: a clear pane's angular transmittance (Fresnel, interreflections in the
//!   pane, absorption scaled to the given normal transmittance).
//! - [`gltf`](mod@gltf): luminaires from a glTF scene's own `KHR_lights_punctual` and
//!   `EXT_lights_ies` lights.
//!
//! The calculation over a whole scene (the luminaires' first shot into the patches, the
//! interreflection, the gather at the points, the surfaces table) is
//! [`crate::pipeline::lighting`].

pub mod direct;
pub mod first_shot;
pub mod glazing;
pub mod gltf;
pub mod luminaire;
pub mod points;
pub mod schedule;
pub mod sky;
#[cfg(test)]
mod tests;
pub mod workplane;

pub use direct::{direct_illuminance, DirectResult};
pub use first_shot::patch_illuminance;
pub use gltf::gltf_luminaires;
pub use luminaire::{FrameError, Luminaire};
pub use points::{read_points, write_points, SensorPoint};
pub use schedule::{read_schedule, Up, DEFAULT_GROUP, SCHEDULE_HEADER};
pub use workplane::workplane;

use crate::io::OutputError;
use crate::photometry::PhotometryError;

/// Why a lighting input could not be read or a computation could not run. Every variant
/// displays as one line; those about a file's text name the file (by its name) and the line.
///
/// [`std::error::Error::source`] leads to what the line does not already say (the operating
/// system's reason), so that a chain printed whole (`anyhow`'s `{:#}`) repeats nothing.
#[derive(Debug)]
pub enum LightingError {
    /// The file could not be read (the operating system's reason is the source).
    Io {
        /// The file's name.
        file: String,
        /// The operating system's reason.
        source: std::io::Error,
    },
    /// A problem at a line of a schedule or points file.
    Invalid {
        /// The file's name.
        file: String,
        /// The line, 1-based.
        line: usize,
        /// What is wrong, one line.
        message: String,
    },
    /// A photometric file a schedule line names could not be read; the photometry error
    /// names that file (and its line, for a problem in its text). Displayed after the
    /// schedule's place; the source is the photometry error's own (the operating system's
    /// reason, for a file that cannot be read).
    Photometry {
        /// The schedule's name.
        file: String,
        /// The schedule line naming the photometric file.
        line: usize,
        /// The photometric file's own error.
        error: PhotometryError,
    },
    /// A parameter is out of range.
    Parameter(String),
    /// An output could not be written.
    Output(OutputError),
}

impl std::fmt::Display for LightingError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            LightingError::Io { file, .. } => write!(f, "{file}: cannot read the file"),
            LightingError::Invalid {
                file,
                line,
                message,
            } => write!(f, "{file}:{line}: {message}"),
            LightingError::Photometry { file, line, error } => {
                write!(f, "{file}:{line}: {error}")
            }
            LightingError::Parameter(message) => f.write_str(message),
            LightingError::Output(error) => write!(f, "{error}"),
        }
    }
}

impl std::error::Error for LightingError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            LightingError::Io { source, .. } => Some(source),
            LightingError::Photometry { error, .. } => error.source(),
            LightingError::Output(error) => error.source(),
            LightingError::Invalid { .. } | LightingError::Parameter(_) => None,
        }
    }
}

impl From<OutputError> for LightingError {
    fn from(error: OutputError) -> Self {
        LightingError::Output(error)
    }
}

impl LightingError {
    /// The line of the schedule or points file the problem is at, when it is at one.
    pub fn line(&self) -> Option<usize> {
        match self {
            LightingError::Invalid { line, .. } | LightingError::Photometry { line, .. } => {
                Some(*line)
            }
            _ => None,
        }
    }
}

/// An error at `line` of `file`, kept to one line whatever it quotes.
pub(crate) fn invalid(file: &str, line: usize, message: impl Into<String>) -> LightingError {
    let message: String = message.into();
    LightingError::Invalid {
        file: file.to_string(),
        line: line.max(1),
        message: message.replace(['\n', '\r'], " "),
    }
}

/// A path's file name, for messages (the whole path when it has none).
pub(crate) fn name_of(path: &std::path::Path) -> String {
    path.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| path.display().to_string())
}

/// Read a text input whole (size-limited by [`crate::io::read_input`]), decoded as UTF-8 or
/// else Latin-1 ([`crate::photometry::decode`]).
pub(crate) fn read_text(path: &std::path::Path) -> Result<String, LightingError> {
    let bytes = crate::io::read_input(path).map_err(|source| LightingError::Io {
        file: name_of(path),
        source,
    })?;
    Ok(crate::photometry::decode(&bytes).into_owned())
}

pub(crate) fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

pub(crate) fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

pub(crate) fn scale(a: [f64; 3], s: f64) -> [f64; 3] {
    [a[0] * s, a[1] * s, a[2] * s]
}

pub(crate) fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

pub(crate) fn norm(a: [f64; 3]) -> f64 {
    dot(a, a).sqrt()
}

/// `a` at unit length, or `None` for a zero or non-finite vector. Scaled by its largest
/// component first, so that neither tiny (subnormal) nor huge components under- or overflow.
pub(crate) fn unit(a: [f64; 3]) -> Option<[f64; 3]> {
    let m = a.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    if m == 0.0 || !m.is_finite() || a.iter().any(|v| v.is_nan()) {
        return None;
    }
    let b = a.map(|v| v / m);
    Some(scale(b, 1.0 / norm(b)))
}
