//! Sensor points in Radiance's points format, the input of `rtrace -I` and the output of
//! `rfluxmtx`'s and `genpts`-like grid generators: one sensor a line, six numbers separated by
//! blanks, `x y z dx dy dz`: the position (scene units) and the direction the sensor faces
//! (its normal: a horizontal illuminance sensor on a work plane faces up).
//!
//! Read by [`read_points`]: blank lines are skipped, and `#` starts a comment to the end of
//! its line (a whole-line comment or after the six numbers). The direction is normalised; a
//! zero or non-finite direction, a non-finite coordinate, or a line of other than six
//! numbers is refused with the file's name and the line. Written by [`write_points`], each
//! number in the shortest form that reads back to the same `f64`.

use super::{invalid, name_of, read_text, unit, LightingError};
use crate::photometry::{self, Lines};
use std::io::Write as _;
use std::path::Path;

/// A sensor: where illuminance is computed and the unit normal of the surface it is on (the
/// way it faces).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SensorPoint {
    /// Position, scene units.
    pub position: [f64; 3],
    /// Unit normal.
    pub normal: [f64; 3],
}

impl SensorPoint {
    /// A sensor at `position` facing `normal` (normalised here); `None` when the position is
    /// not finite or the normal is zero or not finite.
    pub fn new(position: [f64; 3], normal: [f64; 3]) -> Option<SensorPoint> {
        if !position.iter().all(|v| v.is_finite()) {
            return None;
        }
        Some(SensorPoint {
            position,
            normal: unit(normal)?,
        })
    }
}

/// Read a points file (see the module documentation).
pub fn read_points(path: &Path) -> Result<Vec<SensorPoint>, LightingError> {
    let text = read_text(path)?;
    parse_points(&text, &name_of(path))
}

/// Parse a points file's text; `name` names it in messages.
pub fn parse_points(text: &str, name: &str) -> Result<Vec<SensorPoint>, LightingError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut out = Vec::new();
    for (line, content) in Lines::new(text) {
        let content = content.split('#').next().unwrap_or("");
        let words: Vec<&str> = content.split_whitespace().collect();
        if words.is_empty() {
            continue;
        }
        let at = |m: String| invalid(name, line, m);
        if words.len() != 6 {
            return Err(at(format!(
                "{} numbers, expected 6 (x y z dx dy dz)",
                words.len()
            )));
        }
        const WHAT: [&str; 6] = ["x", "y", "z", "dx", "dy", "dz"];
        let mut v = [0.0; 6];
        for k in 0..6 {
            v[k] = photometry::number(words[k], WHAT[k]).map_err(at)?;
        }
        let point = SensorPoint::new([v[0], v[1], v[2]], [v[3], v[4], v[5]])
            .ok_or_else(|| at("the direction dx dy dz is zero".into()))?;
        out.push(point);
    }
    Ok(out)
}

/// Write `points` in the points format, one `x y z dx dy dz` line each, whole or not at all
/// ([`crate::io::write_atomic`]).
pub fn write_points(path: &Path, points: &[SensorPoint]) -> Result<(), LightingError> {
    crate::io::write_atomic::<LightingError>(path, |w| {
        for p in points {
            let [x, y, z] = p.position;
            let [dx, dy, dz] = p.normal;
            writeln!(w, "{x:?} {y:?} {z:?} {dx:?} {dy:?} {dz:?}")?;
        }
        Ok(())
    })
}
