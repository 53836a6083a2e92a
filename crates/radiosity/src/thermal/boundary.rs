//! The boundary-condition table `bc.csv`: header `name,emissivity,temperature,flux`, one row per
//! surface name.
//!
//! - `name`: a material name of the scene (OBJ `newmtl`, MGF `m`, glTF material) or a View3D
//!   surface name;
//! - `emissivity` in (0, 1]; empty takes the scene's own (View3D's `emit` column, or 1 − the
//!   material's mean reflectance);
//! - `temperature` in kelvin (≥ 0), or `flux` in W/m², the net radiative flux leaving (positive:
//!   the surface loses heat by radiation); exactly one of them, or neither for an adiabatic
//!   (re-radiating) surface.
//!
//! Blank lines and lines starting with `#` are skipped; fields may be double-quoted.

use super::{Condition, MAX_FLUX, MAX_TEMPERATURE};
use crate::io::{at, read_text, InputError};
use std::path::Path;

/// One row of the table.
#[derive(Clone, Debug, PartialEq)]
pub struct BoundaryRow {
    /// Surface name.
    pub name: String,
    /// Emissivity, or `None` for the scene's own.
    pub emissivity: Option<f64>,
    /// What is prescribed.
    pub condition: Condition,
    /// 1-based line in the file, for messages.
    pub line: usize,
}

/// The exact header.
pub const HEADER: &str = "name,emissivity,temperature,flux";

/// Read and check `bc.csv`: the header, four fields a row, numbers in range, no name twice.
pub fn read_boundary_csv(path: &Path) -> Result<Vec<BoundaryRow>, InputError> {
    let text = read_text(path)?;
    parse_boundary_csv(path, &text)
}

fn unquote(s: &str) -> &str {
    let s = s.trim();
    s.strip_prefix('"')
        .and_then(|t| t.strip_suffix('"'))
        .unwrap_or(s)
        .trim()
}

/// [`read_boundary_csv`] on text already read (`path` names it in messages).
pub fn parse_boundary_csv(path: &Path, text: &str) -> Result<Vec<BoundaryRow>, InputError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut rows: Vec<BoundaryRow> = Vec::new();
    // Name → line of its row: duplicates found in O(1) each, whatever the file's length.
    let mut seen: std::collections::HashMap<String, usize> = std::collections::HashMap::new();
    let mut header_seen = false;
    for (k, raw) in text.lines().enumerate() {
        let line = k + 1;
        let l = raw.trim();
        if l.is_empty() || l.starts_with('#') {
            continue;
        }
        let fields: Vec<&str> = l.split(',').map(unquote).collect();
        if !header_seen {
            let header: Vec<String> = fields.iter().map(|f| f.to_ascii_lowercase()).collect();
            if header.join(",") != HEADER {
                return Err(at(
                    path,
                    line,
                    format!("the header must be '{HEADER}', found '{l}'"),
                ));
            }
            header_seen = true;
            continue;
        }
        if fields.len() != 4 {
            return Err(at(
                path,
                line,
                format!(
                    "{} fields; a row has 4 ({HEADER}), empty ones included",
                    fields.len()
                ),
            ));
        }
        let name = fields[0];
        if name.is_empty() {
            return Err(at(path, line, "the name is empty"));
        }
        if let Some(first) = seen.get(name) {
            return Err(at(
                path,
                line,
                format!("'{name}' is given twice (first on line {first})"),
            ));
        }
        seen.insert(name.to_string(), line);
        let number = |field: &str, what: &str| -> Result<Option<f64>, InputError> {
            if field.is_empty() {
                return Ok(None);
            }
            match field.parse::<f64>() {
                Ok(v) if v.is_finite() => Ok(Some(v)),
                _ => Err(at(
                    path,
                    line,
                    format!("{what} '{field}' of '{name}' is not a finite number"),
                )),
            }
        };
        let emissivity = number(fields[1], "emissivity")?;
        if let Some(e) = emissivity {
            if !(e > 0.0 && e <= 1.0) {
                return Err(at(
                    path,
                    line,
                    format!("emissivity {e} of '{name}' is outside (0, 1]"),
                ));
            }
        }
        let temperature = number(fields[2], "temperature")?;
        let flux = number(fields[3], "flux")?;
        let condition = match (temperature, flux) {
            (Some(_), Some(_)) => {
                return Err(at(
                    path,
                    line,
                    format!("'{name}' has both a temperature and a flux; give one (or neither for an adiabatic surface)"),
                ))
            }
            (Some(t), None) if t < 0.0 => {
                return Err(at(
                    path,
                    line,
                    format!("temperature {t} K of '{name}' is negative (kelvin, ≥ 0)"),
                ))
            }
            (Some(t), None) if t > MAX_TEMPERATURE => {
                return Err(at(
                    path,
                    line,
                    format!("temperature {t:e} K of '{name}' is out of range (give 0 to {MAX_TEMPERATURE:e} K; σT⁴ past that overflows the heat balance)"),
                ))
            }
            (Some(t), None) => Condition::Temperature(t),
            (None, Some(q)) if q.abs() > MAX_FLUX => {
                return Err(at(
                    path,
                    line,
                    format!("flux {q:e} W/m² of '{name}' is out of range (give −{MAX_FLUX:e} to {MAX_FLUX:e} W/m², the black-body exitance at {MAX_TEMPERATURE:e} K)"),
                ))
            }
            (None, Some(q)) => Condition::Flux(q),
            (None, None) => Condition::Adiabatic,
        };
        rows.push(BoundaryRow {
            name: name.to_string(),
            emissivity,
            condition,
            line,
        });
    }
    if !header_seen {
        return Err(at(
            path,
            0,
            format!("empty: expected the header '{HEADER}' and one row per surface"),
        ));
    }
    Ok(rows)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<Vec<BoundaryRow>, String> {
        parse_boundary_csv(Path::new("bc.csv"), text).map_err(|e| e.to_string())
    }

    #[test]
    fn reads_every_kind_of_row() {
        let rows = parse(
            "\u{feff}Name, Emissivity,temperature,flux\n# comment\n\nhot,0.9,1200,\ncold,1,,-50.5\n\"wall\",,,\n",
        )
        .unwrap();
        assert_eq!(rows.len(), 3);
        assert_eq!(rows[0].condition, Condition::Temperature(1200.0));
        assert_eq!(rows[0].emissivity, Some(0.9));
        assert_eq!(rows[0].line, 4);
        assert_eq!(rows[1].condition, Condition::Flux(-50.5));
        assert_eq!(rows[2].name, "wall");
        assert_eq!(rows[2].condition, Condition::Adiabatic);
        assert_eq!(rows[2].emissivity, None);
    }

    #[test]
    fn bad_rows_are_located() {
        let h = "name,emissivity,temperature,flux\n";
        for (body, needle) in [
            ("a,0.5,300,10\n", "bc.csv:2: 'a' has both"),
            (
                "a,1.5,300,\n",
                "bc.csv:2: emissivity 1.5 of 'a' is outside (0, 1]",
            ),
            ("a,0,300,\n", "outside (0, 1]"),
            (
                "a,0.5,-3,\n",
                "bc.csv:2: temperature -3 K of 'a' is negative",
            ),
            ("a,0.5,nan,\n", "not a finite number"),
            ("a,0.5,300\n", "3 fields"),
            (
                "a,0.5,300,\na,0.5,,\n",
                "bc.csv:3: 'a' is given twice (first on line 2)",
            ),
            (",0.5,300,\n", "the name is empty"),
        ] {
            let e = parse(&format!("{h}{body}")).unwrap_err();
            assert!(e.contains(needle), "{body:?}: {e}");
        }
        assert!(parse("name,temperature\n").unwrap_err().contains("header"));
        assert!(parse("").unwrap_err().contains("empty"));
    }
}
