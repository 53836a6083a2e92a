//! The luminaire schedule: which luminaires a lighting design places where, one CSV row each.
//!
//! # Format
//!
//! A CSV file (RFC 4180 subset) whose first line is exactly
//!
//! ```text
//! name,file,x,y,z,aim_x,aim_y,aim_z,c0_x,c0_y,c0_z,multiplier,group
//! ```
//!
//! (users' scripts depend on these names; blanks around a name are allowed, nothing else),
//! then one luminaire a line, 13 fields:
//!
//! | field | meaning | empty |
//! |---|---|---|
//! | `name` | the luminaire's name, unique in the schedule | refused |
//! | `file` | its `.ies` or `.ldt` file, relative to the schedule's folder (or absolute) | refused |
//! | `x,y,z` | the photometric centre, scene units | refused |
//! | `aim_x,aim_y,aim_z` | the photometric axis: type C's γ = 0 (nadir), types B and A's H = V = 0 (the beam); need not be unit | −up (straight down) |
//! | `c0_x,c0_y,c0_z` | made perpendicular to the aim: type C's C = 0 half-plane; types B and A's V = 90° (the top of a floodlight) | type C: +x (+y where +x is parallel to the aim); types B and A: up (+x where up is parallel to the aim) |
//! | `multiplier` | scales intensities (light-loss factor × dimming), finite, ≥ 0 | 1 |
//! | `group` | the light scene (switching group) | [`DEFAULT_GROUP`] |
//!
//! A direction's three fields are all given or all empty. Fields may be double-quoted
//! (`"a, b"`, a quote inside doubled: `""`) but may not hold a line end; blanks around a
//! field are dropped. Blank lines are skipped. Line ends may be LF, CRLF or CR; the bytes are
//! UTF-8, else Latin-1.
//!
//! Each luminaire's lamp tilt is applied for the scene's up
//! ([`Luminaire::with_lamp_tilt`]): rows sharing a file but aimed differently get their own
//! factors.
//!
//! Duplicate names are refused (the second names the line of the first): reports and
//! per-luminaire outputs are keyed by name, and two rows of one name are almost always a
//! copy-and-paste slip. Each distinct photometric file (by its path, canonicalised where it
//! exists) is read once and shared ([`std::sync::Arc`]).
//!
//! Every error is one line naming the schedule's file and line; a photometric file that
//! cannot be read gives its own error (naming that file) after the schedule's place.

use super::luminaire::{Luminaire, PARALLEL_SIN};
use super::{dot, invalid, name_of, read_text, LightingError};
use crate::photometry::{self, shown, Lines, PhotometricType, Photometry};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// The schedule's header line, exactly.
pub const SCHEDULE_HEADER: &str =
    "name,file,x,y,z,aim_x,aim_y,aim_z,c0_x,c0_y,c0_z,multiplier,group";

/// The group of a luminaire whose `group` field is empty.
pub const DEFAULT_GROUP: &str = "default";

const COLUMNS: usize = 13;

/// The scene's vertical axis: which way is up (the default aim is straight down).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Up {
    /// +z is up (the default).
    #[default]
    Z,
    /// +y is up (glTF, many modellers).
    Y,
}

impl Up {
    /// The unit up vector.
    pub fn vector(self) -> [f64; 3] {
        match self {
            Up::Z => [0.0, 0.0, 1.0],
            Up::Y => [0.0, 1.0, 0.0],
        }
    }
}

/// Read a luminaire schedule (see the module documentation); `up` is the scene's vertical,
/// which the default aim (−up) follows. Photometric files are read relative to the
/// schedule's folder.
pub fn read_schedule(path: &Path, up: Up) -> Result<Vec<Luminaire>, LightingError> {
    let text = read_text(path)?;
    let folder = path.parent().unwrap_or(Path::new(""));
    parse_schedule(&text, &name_of(path), folder, up)
}

/// Parse a schedule's text; `name` is the schedule's name for messages, `folder` where its
/// relative photometric paths start.
pub fn parse_schedule(
    text: &str,
    name: &str,
    folder: &Path,
    up: Up,
) -> Result<Vec<Luminaire>, LightingError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut lines = Lines::new(text).filter(|(_, l)| !l.trim().is_empty());
    let Some((hline, header)) = lines.next() else {
        return Err(invalid(
            name,
            1,
            format!("empty schedule: expected the header {SCHEDULE_HEADER}"),
        ));
    };
    let names = fields(header).map_err(|m| invalid(name, hline, m))?;
    let expected: Vec<&str> = SCHEDULE_HEADER.split(',').collect();
    if names
        .iter()
        .map(String::as_str)
        .ne(expected.iter().copied())
    {
        return Err(invalid(
            name,
            hline,
            format!(
                "the header is '{}', expected exactly {SCHEDULE_HEADER}",
                shown_long(header)
            ),
        ));
    }
    let mut files: HashMap<PathBuf, Arc<Photometry>> = HashMap::new();
    let mut seen: HashMap<String, usize> = HashMap::new();
    let mut out = Vec::new();
    for (line, text) in lines {
        let at = |m: String| invalid(name, line, m);
        let f = fields(text).map_err(at)?;
        if f.len() != COLUMNS {
            return Err(at(format!(
                "{} fields, expected {COLUMNS} ({SCHEDULE_HEADER})",
                f.len()
            )));
        }
        let lum_name = f[0].clone();
        if lum_name.is_empty() {
            return Err(at("the name is empty".into()));
        }
        if let Some(first) = seen.insert(lum_name.clone(), line) {
            return Err(at(format!(
                "the name '{}' is already used at line {first}",
                shown(&lum_name)
            )));
        }
        if f[1].is_empty() {
            return Err(at("the file is empty".into()));
        }
        let position = vector(&f[2..5], &expected[2..5])
            .map_err(at)?
            .ok_or_else(|| at("the position x,y,z is empty".into()))?;
        let aim = vector(&f[5..8], &expected[5..8]).map_err(at)?;
        let c0 = vector(&f[8..11], &expected[8..11]).map_err(at)?;
        let multiplier = if f[11].is_empty() {
            1.0
        } else {
            photometry::number(&f[11], "multiplier").map_err(at)?
        };
        if multiplier < 0.0 {
            return Err(at(format!("the multiplier {multiplier} is negative")));
        }
        let group = if f[12].is_empty() {
            DEFAULT_GROUP.to_string()
        } else {
            f[12].clone()
        };
        let aim = match aim {
            Some(a) => a,
            None => up.vector().map(|v| -v),
        };
        let file = folder.join(&f[1]);
        let key = std::fs::canonicalize(&file).unwrap_or_else(|_| file.clone());
        let photometry = match files.get(&key) {
            Some(p) => p.clone(),
            None => {
                let p = Arc::new(photometry::read(&file).map_err(|error| {
                    LightingError::Photometry {
                        file: name.to_string(),
                        line,
                        error,
                    }
                })?);
                files.insert(key, p.clone());
                p
            }
        };
        // A floodlight (types B and A) keeps its top (V = 90°) up unless told otherwise.
        let c0 = match (c0, photometry.kind) {
            (None, PhotometricType::B | PhotometricType::A) => {
                let u = up.vector();
                let along = dot(u, aim) / dot(aim, aim).sqrt();
                (along.is_finite() && along.abs() < 1.0 - PARALLEL_SIN).then_some(u)
            }
            (c0, _) => c0,
        };
        let luminaire = Luminaire::new(lum_name, photometry, position, aim, c0, multiplier, group)
            .and_then(|l| l.with_lamp_tilt(up.vector()))
            .map_err(|e| at(e.to_string()))?;
        out.push(luminaire);
    }
    if out.is_empty() {
        return Err(invalid(
            name,
            photometry::last_line(text),
            "no luminaires: the schedule has only its header",
        ));
    }
    Ok(out)
}

/// Three fields as a vector: `None` when all are empty; an error when only some are, or one
/// is not a finite number (`what` names them).
fn vector(f: &[String], what: &[&str]) -> Result<Option<[f64; 3]>, String> {
    let empty = f.iter().filter(|s| s.is_empty()).count();
    if empty == 3 {
        return Ok(None);
    }
    if empty > 0 {
        return Err(format!(
            "{},{},{}: give all three or none",
            what[0], what[1], what[2]
        ));
    }
    let mut v = [0.0; 3];
    for k in 0..3 {
        v[k] = photometry::number(&f[k], what[k])?;
    }
    Ok(Some(v))
}

/// The fields of one CSV line: split at commas outside double quotes, blanks around each
/// dropped, quotes removed (`""` inside quotes is one quote).
fn fields(line: &str) -> Result<Vec<String>, String> {
    let mut out = Vec::new();
    let mut chars = line.chars().peekable();
    loop {
        // One field.
        while chars.peek().is_some_and(|c| *c == ' ' || *c == '\t') {
            chars.next();
        }
        let mut field = String::new();
        if chars.peek() == Some(&'"') {
            chars.next();
            loop {
                match chars.next() {
                    None => return Err(format!("field {} has no closing quote", out.len() + 1)),
                    Some('"') if chars.peek() == Some(&'"') => {
                        chars.next();
                        field.push('"');
                    }
                    Some('"') => break,
                    Some(c) => field.push(c),
                }
            }
            while chars.peek().is_some_and(|c| *c == ' ' || *c == '\t') {
                chars.next();
            }
            match chars.peek() {
                None | Some(',') => {}
                Some(c) => {
                    return Err(format!(
                        "field {} has '{}' after its closing quote",
                        out.len() + 1,
                        c.escape_debug()
                    ))
                }
            }
        } else {
            while let Some(&c) = chars.peek() {
                if c == ',' {
                    break;
                }
                if c == '"' {
                    return Err(format!(
                        "field {} has a quote inside it (quote the whole field and double it)",
                        out.len() + 1
                    ));
                }
                field.push(c);
                chars.next();
            }
            field.truncate(field.trim_end().len());
        }
        out.push(field);
        match chars.next() {
            None => return Ok(out),
            Some(',') => {}
            // A field ends at a comma or the line's end; kept as an error, never a panic.
            Some(c) => return Err(format!("unexpected '{}'", c.escape_debug())),
        }
    }
}

/// A line as it may be quoted in a message: at most 80 characters, control characters
/// escaped.
fn shown_long(line: &str) -> String {
    let mut out: String = line.chars().take(80).flat_map(char::escape_debug).collect();
    if line.chars().count() > 80 {
        out.push('…');
    }
    out
}
