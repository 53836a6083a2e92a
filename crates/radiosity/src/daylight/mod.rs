//! ANNUAL DAYLIGHT (issue 58, item 3): a year of hourly skies from a weather file, turned into
//! illuminance at sensor points by daylight coefficients, and the climate-based metrics.
//!
//! The chain, one file a step:
//!
//! 1. [`epw`]: the EnergyPlus Weather file: the site (latitude, longitude, time zone,
//!    elevation) and the hourly records (direct-normal and diffuse-horizontal irradiance,
//!    their illuminances when measured, the dew point).
//! 2. [`solar`]: where the sun is at each hour (NOAA's algorithm after Meeus; EPW hours end
//!    at the hour, so the middle of the hour is used).
//! 3. [`perez`]: the Perez (1990) luminous efficacy model turns irradiance into illuminance
//!    and the Perez, Seals & Michalsky (1993) all-weather model gives the sky's luminance in
//!    every direction, normalised to the diffuse horizontal illuminance.
//! 4. [`patches`]: the sky cut into Tregenza's 145 patches or Reinhart's MF:n subdivision
//!    (plus the ground), each patch's exact solid angle, and the mean luminance of a sky
//!    function over each patch: the hourly *sky vector*.
//! 5. [`annual`]: daylight coefficients D (points × patches) times the sky vectors (patches ×
//!    hours), in blocks of hours over rayon, the sun either in the sky vector (the 2-phase
//!    method) or as exact direct-sun coefficients at its true position (as the 5-phase and
//!    DAYSIM methods do), streamed into [`metrics`]: sDA, ASE and UDI per point and per grid.
//!
//! Directions are in the sky's frame: z up (the zenith), y north, x east; azimuth is measured
//! clockwise from north (east = 90°), altitude up from the horizon. A scene's own frame (its
//! up axis and its north) is the caller's to map to this one.
//!
//! The library knows nothing of how the coefficients are computed: [`annual::annual`] takes a
//! coefficient matrix and a sun-coefficient callback ([`annual::SunCoefficients`]), so a
//! radiosity solve per sky patch, a ray tracer, or a closed form (an unobstructed point) can
//! supply them. `docs/daylight-annual.md` has the formulas and their sources.

pub mod annual;
pub mod epw;
pub mod metrics;
pub mod patches;
pub mod perez;
pub mod provision;
pub mod solar;

/// A unit direction from altitude and azimuth (radians; azimuth clockwise from north) in the
/// sky's frame (x east, y north, z up).
pub fn direction(altitude: f64, azimuth: f64) -> [f64; 3] {
    let (sa, ca) = altitude.sin_cos();
    let (sz, cz) = azimuth.sin_cos();
    [ca * sz, ca * cz, sa]
}

/// Altitude and azimuth (radians; azimuth in `[0, 2π)` clockwise from north) of a unit
/// direction in the sky's frame.
pub fn altitude_azimuth(d: [f64; 3]) -> (f64, f64) {
    let altitude = d[2].clamp(-1.0, 1.0).asin();
    let mut azimuth = d[0].atan2(d[1]);
    if azimuth < 0.0 {
        azimuth += std::f64::consts::TAU;
    }
    (altitude, azimuth)
}

/// A problem with a daylight input or parameter.
#[derive(Debug)]
pub enum DaylightError {
    /// The file could not be read (the operating system's reason is the source).
    Io {
        /// The file's name.
        file: String,
        /// The operating system's reason.
        source: std::io::Error,
    },
    /// A problem at a line of a weather file.
    Invalid {
        /// The file's name.
        file: String,
        /// The line, 1-based.
        line: usize,
        /// What is wrong, one line.
        message: String,
    },
    /// A parameter is out of range or inputs do not fit together.
    Parameter(String),
    /// An output could not be written.
    Output(crate::io::OutputError),
}

impl std::fmt::Display for DaylightError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            DaylightError::Io { file, .. } => write!(f, "{file}: cannot read the file"),
            DaylightError::Invalid {
                file,
                line,
                message,
            } => write!(f, "{file}:{line}: {message}"),
            DaylightError::Parameter(message) => f.write_str(message),
            DaylightError::Output(error) => write!(f, "{error}"),
        }
    }
}

impl std::error::Error for DaylightError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            DaylightError::Io { source, .. } => Some(source),
            DaylightError::Output(error) => error.source(),
            DaylightError::Invalid { .. } | DaylightError::Parameter(_) => None,
        }
    }
}

impl From<crate::io::OutputError> for DaylightError {
    fn from(error: crate::io::OutputError) -> Self {
        DaylightError::Output(error)
    }
}

/// An error at `line` of `file`, its message kept to one line.
pub(crate) fn invalid(file: &str, line: usize, message: impl Into<String>) -> DaylightError {
    let message: String = message.into();
    DaylightError::Invalid {
        file: file.to_string(),
        line: line.max(1),
        message: message.replace(['\n', '\r'], " "),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn direction_and_angles_round_trip() {
        for &(alt, az) in &[(0.3, 0.0), (1.2, 1.5), (-0.4, 3.5), (0.01, 6.2)] {
            let d = direction(alt, az);
            let n = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            assert!((n - 1.0).abs() < 1e-15);
            let (a, z) = altitude_azimuth(d);
            assert!((a - alt).abs() < 1e-12 && (z - az).abs() < 1e-12, "{a} {z}");
        }
        // East is +x, north +y.
        let east = direction(0.0, std::f64::consts::FRAC_PI_2);
        assert!((east[0] - 1.0).abs() < 1e-15 && east[1].abs() < 1e-15);
    }
}
