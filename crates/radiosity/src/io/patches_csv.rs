//! Per-patch CSV: a header naming the columns, then one row per patch. Required: `area`, and
//! either one channel (`reflectance`, `emission`) or three (`reflectance_r`, `reflectance_g`,
//! `reflectance_b`, `emission_r`, `emission_g`, `emission_b`); other columns (such as those of
//! `radiosity solve`'s output) are ignored. Areas must be positive, reflectances in [0, 1),
//! emissions non-negative, all finite.

use super::{at, read_text, InputError};
use crate::color::Rgb;
use crate::system::System;
use std::path::Path;

/// The patches of a system as read from CSV.
#[derive(Clone, Debug, PartialEq)]
pub struct Patches {
    /// Areas, reflectances (one channel is spread to all three) and emissions.
    pub system: System,
    /// True when the file gave one channel.
    pub single_channel: bool,
}

/// Read patches from `path`.
pub fn read(path: &Path) -> Result<Patches, InputError> {
    let text = read_text(path)?;
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(k, l)| (k + 1, l))
        .filter(|(_, l)| !l.trim().is_empty());
    let (_, header) = lines
        .next()
        .ok_or_else(|| at(path, 1, "empty file; expected a header line"))?;
    let names: Vec<&str> = header.split(',').map(str::trim).collect();
    let col = |name: &str| names.iter().position(|n| *n == name);
    let area = col("area").ok_or_else(|| at(path, 1, "no 'area' column"))?;
    let rgb = [
        "reflectance_r",
        "reflectance_g",
        "reflectance_b",
        "emission_r",
        "emission_g",
        "emission_b",
    ];
    let (single, cols): (bool, Vec<usize>) =
        if let (Some(r), Some(e)) = (col("reflectance"), col("emission")) {
            (true, vec![r, e])
        } else if rgb.iter().all(|n| col(n).is_some()) {
            (false, rgb.iter().map(|n| col(n).unwrap()).collect())
        } else {
            return Err(at(
            path,
            1,
            "needs columns 'reflectance' and 'emission', or reflectance_r/g/b and emission_r/g/b",
        ));
        };
    let mut out = Patches {
        system: System::default(),
        single_channel: single,
    };
    for (line, raw) in lines {
        let fields: Vec<&str> = raw.split(',').map(str::trim).collect();
        let get = |c: usize| -> Result<f64, InputError> {
            let t = fields
                .get(c)
                .ok_or_else(|| at(path, line, format!("missing column '{}'", names[c])))?;
            let v: f64 = t.parse().map_err(|_| {
                at(
                    path,
                    line,
                    format!("malformed number '{t}' in column '{}'", names[c]),
                )
            })?;
            if !v.is_finite() {
                return Err(at(
                    path,
                    line,
                    format!("'{t}' in column '{}' is not finite", names[c]),
                ));
            }
            Ok(v)
        };
        let a = get(area)?;
        if a <= 0.0 {
            return Err(at(path, line, format!("area {a} must be positive")));
        }
        let (rho, e) = if single {
            (Rgb::splat(get(cols[0])?), Rgb::splat(get(cols[1])?))
        } else {
            (
                Rgb::new(get(cols[0])?, get(cols[1])?, get(cols[2])?),
                Rgb::new(get(cols[3])?, get(cols[4])?, get(cols[5])?),
            )
        };
        if rho.min_channel() < 0.0 || rho.max_channel() >= 1.0 {
            return Err(at(path, line, format!("reflectance {rho} outside [0, 1)")));
        }
        if e.min_channel() < 0.0 {
            return Err(at(path, line, format!("emission {e} is negative")));
        }
        out.system.area.push(a);
        out.system.reflectance.push(rho);
        out.system.emission.push(e);
    }
    if out.system.is_empty() {
        return Err(at(path, 0, "no patches after the header"));
    }
    Ok(out)
}
