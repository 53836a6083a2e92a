//! IES LM-63 photometric files (1986, 1991, 1995, 2002, 2019).
//!
//! The layout (LM-63-2002 as AGi32's Photometric Toolbox manual lists it, "IESNA LM-63
//! Format"; the 1986 and 1991 variants as Ian Ashdown describes them, ltblight.com "Appendix C
//! – IES-NA data interchange format"): a header line naming the revision (none in 1986, whose
//! file starts with free label lines), keyword lines `[KEY] value`, a line `TILT=NONE`,
//! `TILT=INCLUDE` or `TILT=<file>`, the tilt table when included (lamp-to-luminaire geometry,
//! number of pairs, angles, multiplying factors), then the numbers:
//!
//! ```text
//! lamps  lumens/lamp  multiplier  #vertical  #horizontal  type  units  width  length  height
//! ballast-factor  ballast-lamp-factor (1986, 1991) or future use (later)  input-watts
//! vertical angles…
//! horizontal angles…
//! candela values…   (all vertical angles of the first horizontal angle, then the next …)
//! ```
//!
//! separated by blanks, commas or line ends, wrapped anywhere.

use super::{
    check_angles, invalid, last_line, mirror, number, prepare, shown, LampGeometry, Lines,
    NumberReader, Opening, PhotometricType, Photometry, PhotometryError, Symmetry, Table, Tilt,
    Words, MAX_TABLE_VALUES,
};

/// Metres in a foot (exact, by the international yard and pound agreement of 1959).
const FOOT_M: f64 = 0.3048;

/// The LM-63 revision a file declares on its first line.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
enum Revision {
    /// No header line: LM-63-1986.
    Y1986,
    /// `IESNA91`.
    Y1991,
    /// `IESNA:LM-63-1995` (and the `IESNA95` some older files carry).
    Y1995,
    /// `IESNA:LM-63-2002`.
    Y2002,
    /// `IES:LM-63-2019`.
    Y2019,
    /// A header line of another form, read as the later revisions.
    Other,
}

impl Revision {
    fn of(first_line: &str) -> Revision {
        let header = first_line.trim().to_ascii_uppercase();
        if !(header.starts_with("IESNA") || header.starts_with("IES:")) {
            return Revision::Y1986;
        }
        if header.contains("2019") {
            Revision::Y2019
        } else if header.contains("2002") {
            Revision::Y2002
        } else if header.contains("1995") || header == "IESNA95" {
            Revision::Y1995
        } else if header.contains("1991") || header == "IESNA91" {
            Revision::Y1991
        } else {
            Revision::Other
        }
    }
}

/// The numbers after the `TILT=` line, read in order, with errors at their lines.
type Reader<'a> = NumberReader<'a>;

/// Parse the text of an IES LM-63 file; `name` is the file's name, for messages and
/// [`Photometry::source`].
///
/// Type C photometry (LM-63 photometric type 1): the horizontal angles may run 0 (one angle:
/// rotationally symmetric), 0–90 (symmetric in each quadrant), 0–180 (symmetric about the
/// C0–C180 plane), 0 to more than 180 up to 360 (no symmetry) or 90–270 (symmetric about the
/// C90–C270 plane), and the vertical angles 0–90, 90–180 or 0–180 (other ranges within 0–180
/// are read with a warning).
///
/// Types B (2) and A (3): the horizontal angles run −90–90, or 0–90 for a laterally symmetric
/// distribution (the same at −H; mirrored), the vertical angles −90–90 or 0–90 (as for type
/// C's vertical angles, a range is where the light is: a table of 0–90 sends nothing below
/// V = 0; LM-63 names a symmetry only for the horizontal angles). Other ranges are read with a
/// warning where the geometry allows them: the latitude (B's H, A's V) within −90–90, the
/// longitude (B's V, A's H) within −180–180. At least two angles of each are needed.
///
/// An included tilt table (`TILT=INCLUDE`) is read into [`Photometry::tilt`]; a file naming
/// an external tilt file (`TILT=<file>`) is refused.
pub fn parse_ies(text: &str, name: &str) -> Result<Photometry, PhotometryError> {
    let text = prepare(text, name)?;
    let end_line = last_line(text);
    let mut lines = Lines::new(text);
    let revision = Revision::of(lines.clone().next().map_or("", |(_, l)| l));
    if revision != Revision::Y1986 {
        lines.next();
    }
    let mut warnings = Vec::new();
    if revision == Revision::Other {
        warnings.push("unrecognised header line: read as LM-63-2002".to_string());
    }

    // Keyword (or label) lines up to TILT=.
    let mut tilt = None;
    for (number, line) in lines.by_ref() {
        let t = line.trim_start();
        if t.len() >= 4 && t.is_char_boundary(4) && t[..4].eq_ignore_ascii_case("TILT") {
            if let Some(value) = t[4..].trim_start().strip_prefix('=') {
                tilt = Some((number, value.trim()));
                break;
            }
        }
    }
    let Some((tilt_line, tilt)) = tilt else {
        return Err(invalid(
            name,
            end_line,
            "no TILT= line: not an IES LM-63 photometric file",
        ));
    };
    let mut r = Reader {
        words: Words::new(lines, true),
        file: name,
        end_line,
        parse: number,
    };
    let tilt_table = if tilt.eq_ignore_ascii_case("INCLUDE") {
        Some(read_tilt_table(&mut r)?)
    } else {
        None
    };
    if tilt_table.is_none() && !tilt.eq_ignore_ascii_case("NONE") {
        return Err(invalid(
            name,
            tilt_line,
            if tilt.is_empty() {
                "TILT= names nothing: expected NONE, INCLUDE or a file".to_string()
            } else {
                format!(
                    "TILT={}: tilt data in another file is not supported (include it with \
                     TILT=INCLUDE, or use TILT=NONE)",
                    shown(tilt)
                )
            },
        ));
    }

    let (lamps, lamps_line) = r.number("the number of lamps")?;
    let (lumens_per_lamp, _) = r.number("the lumens per lamp")?;
    let (multiplier, multiplier_line) = r.number("the candela multiplier")?;
    let (n_v, n_v_line) = r.count("the number of vertical angles", 2)?;
    let (n_h, n_h_line) = r.count("the number of horizontal angles", 1)?;
    let (kind, kind_line) = r.number("the photometric type")?;
    let (units, units_line) = r.number("the units type")?;
    let (width, _) = r.number("the luminous opening's width")?;
    let (length, _) = r.number("the luminous opening's length")?;
    let (height, _) = r.number("the luminous opening's height")?;
    let (ballast, ballast_line) = r.number("the ballast factor")?;
    let (lamp_factor, lamp_factor_line) = r.number(if revision <= Revision::Y1991 {
        "the ballast-lamp photometric factor"
    } else {
        "the future-use field"
    })?;
    r.number("the input watts")?;

    let absolute = lumens_per_lamp < 0.0;
    if absolute && lumens_per_lamp != -1.0 {
        warnings.push(format!(
            "lumens per lamp {lumens_per_lamp}: read as -1, absolute photometry"
        ));
    }
    if !absolute && (lamps < 1.0 || lamps.fract() != 0.0) {
        return Err(invalid(
            name,
            lamps_line,
            format!("number of lamps {lamps}: a whole number of at least 1 needed"),
        ));
    }
    if lumens_per_lamp == 0.0 {
        warnings.push("lumens per lamp 0: the file states no flux".to_string());
    }
    if multiplier <= 0.0 {
        return Err(invalid(
            name,
            multiplier_line,
            format!("candela multiplier {multiplier} is not positive"),
        ));
    }
    let kind = match kind {
        1.0 => PhotometricType::C,
        2.0 => PhotometricType::B,
        3.0 => PhotometricType::A,
        k => {
            return Err(invalid(
                name,
                kind_line,
                format!("photometric type {k}: expected 1 (C), 2 (B) or 3 (A)"),
            ))
        }
    };
    let unit_m = match units {
        1.0 => FOOT_M,
        2.0 => 1.0,
        u => {
            return Err(invalid(
                name,
                units_line,
                format!("units type {u}: expected 1 (feet) or 2 (metres)"),
            ))
        }
    };
    if ballast <= 0.0 {
        return Err(invalid(
            name,
            ballast_line,
            format!("ballast factor {ballast} is not positive"),
        ));
    }
    // The 1986 and 1991 revisions multiply by the ballast-lamp photometric factor; later ones
    // leave the field to "future use" (and LM-63-2019 puts a code there), so it is ignored.
    let lamp_factor = if revision <= Revision::Y1991 {
        if lamp_factor <= 0.0 {
            return Err(invalid(
                name,
                lamp_factor_line,
                format!("ballast-lamp photometric factor {lamp_factor} is not positive"),
            ));
        }
        lamp_factor
    } else {
        1.0
    };

    // The table's size, checked before anything is allocated: against a fixed cap, then
    // against the numbers the file has left.
    let values = n_v
        .checked_mul(n_h)
        .filter(|&v| v <= MAX_TABLE_VALUES)
        .ok_or_else(|| {
            invalid(
                name,
                n_v_line,
                format!(
                    "{n_v} vertical × {n_h} horizontal angles: more than {MAX_TABLE_VALUES} \
                     candela values is not a photometric table"
                ),
            )
        })?;
    let left = r.words.remaining();
    // Where the data run short, say which list is short: the angles increase, so a list that
    // stops increasing before its count is the one missing values.
    let (v_run, v_break) = increasing_run(r.words.clone(), n_v, 180.0);
    let (h_run, h_break) = increasing_run(r.words.clone().skip(n_v), n_h, 360.0);
    let shortfall = if left < n_v || v_run < n_v {
        let line = if v_run < n_v { v_break } else { end_line };
        Some((
            line,
            format!("expected {n_v} vertical angles, found {}", v_run.min(left)),
        ))
    } else if left < n_v + n_h || h_run < n_h {
        let line = if h_run < n_h { h_break } else { end_line };
        Some((
            line,
            format!(
                "expected {n_h} horizontal angles, found {}",
                h_run.min(left - n_v)
            ),
        ))
    } else if left < n_v + n_h + values {
        Some((
            end_line,
            format!(
                "expected {values} candela values ({n_h} horizontal × {n_v} vertical angles), \
                 found {}",
                left - n_v - n_h
            ),
        ))
    } else {
        None
    };
    if let Some((line, message)) = shortfall.filter(|_| left < n_v + n_h + values) {
        return Err(invalid(name, line, message));
    }

    let declared_v = format!("the file declares {n_v} vertical angles on line {n_v_line}");
    let declared_h = format!("the file declares {n_h} horizontal angles on line {n_v_line}");
    let (vertical, v_lines) = r.numbers(n_v, "vertical angle")?;
    let (horizontal, h_lines) = r.numbers(n_h, "horizontal angle")?;
    let (lo, hi) = if kind == PhotometricType::C {
        (0.0, 360.0)
    } else {
        (-180.0, 180.0)
    };
    check_angles(
        &vertical,
        &v_lines,
        "vertical angle",
        &declared_v,
        -180.0,
        180.0,
    )
    .and_then(|()| {
        check_angles(
            &horizontal,
            &h_lines,
            "horizontal angle",
            &declared_h,
            lo,
            hi,
        )
    })
    .map_err(|(line, m)| invalid(name, line, m))?;
    let mut candela = Vec::with_capacity(values.min(r.words.remaining()));
    for _ in 0..values {
        let (line, word) = r.word("a candela value")?;
        let v = number(word, "candela value").map_err(|m| invalid(name, line, m))?;
        if v < 0.0 {
            return Err(invalid(
                name,
                line,
                format!("candela value {} is negative", shown(word)),
            ));
        }
        candela.push(v);
    }
    trailing(&mut r, &mut warnings, n_v_line)?;

    let angles = Angles {
        file: name,
        horizontal: &horizontal,
        h_lines: &h_lines,
        declared_h: &declared_h,
        vertical: &vertical,
        v_lines: &v_lines,
        declared_v: &declared_v,
    };
    // Type C's symmetry is expanded with the table's ([`Table::into_photometry`]); a
    // laterally symmetric type B or A table is mirrored here.
    let (symmetry, horizontal, mut candela) = match kind {
        PhotometricType::C => (angles.type_c(&mut warnings)?, horizontal, candela),
        PhotometricType::B | PhotometricType::A => {
            if n_h < 2 {
                return Err(invalid(
                    name,
                    n_h_line,
                    format!(
                        "{n_h} horizontal angle: type {kind} photometry needs at least 2 (it has \
                         no rotational symmetry)"
                    ),
                ));
            }
            if angles.type_b_or_a(kind, &mut warnings)? {
                let (h, c) = mirror(&horizontal, &candela, n_v);
                (Symmetry::None, h, c)
            } else {
                (Symmetry::None, horizontal, candela)
            }
        }
    };

    let scale = multiplier * ballast * lamp_factor;
    for v in &mut candela {
        *v *= scale;
        if !v.is_finite() {
            return Err(invalid(
                name,
                multiplier_line,
                format!("candela multiplier {multiplier} makes the candela values overflow"),
            ));
        }
    }
    let lumens = (!absolute && lumens_per_lamp > 0.0).then_some(lamps * lumens_per_lamp);
    let rated_flux = lumens.map(|l| l * ballast * lamp_factor);
    let opening = Opening {
        width_m: width.abs() * unit_m,
        length_m: length.abs() * unit_m,
        height_m: height.abs() * unit_m,
        round: width < 0.0 || length < 0.0,
    };
    Ok(Table {
        kind,
        symmetry,
        c_angles: horizontal,
        gamma_angles: vertical,
        candela,
        lumens,
        rated_flux,
        opening,
        tilt: tilt_table,
        warnings,
    }
    .into_photometry(name))
}

/// A file's angle lists with the lines they were read at, for the checks of each photometric
/// type's ranges.
struct Angles<'a> {
    file: &'a str,
    horizontal: &'a [f64],
    h_lines: &'a [usize],
    declared_h: &'a str,
    vertical: &'a [f64],
    v_lines: &'a [usize],
    declared_v: &'a str,
}

impl Angles<'_> {
    /// Type C's ranges: vertical angles within 0..180 (a range other than LM-63's three with a
    /// warning), horizontal angles one of the five forms; the symmetry they declare.
    fn type_c(&self, warnings: &mut Vec<String>) -> Result<Symmetry, PhotometryError> {
        let (name, vertical, horizontal) = (self.file, self.vertical, self.horizontal);
        check_angles(
            vertical,
            self.v_lines,
            "vertical angle",
            self.declared_v,
            0.0,
            180.0,
        )
        .map_err(|(line, m)| invalid(name, line, m))?;
        let (v0, v1) = (vertical[0], vertical[vertical.len() - 1]);
        let standard = [(0.0, 90.0), (90.0, 180.0), (0.0, 180.0)];
        if !standard.iter().any(|&(a, b)| same(v0, a) && same(v1, b)) {
            warnings.push(format!(
                "vertical angles run {v0}..{v1}: LM-63 expects 0..90, 90..180 or 0..180"
            ));
        }
        let (h0, h1) = (horizontal[0], horizontal[horizontal.len() - 1]);
        Ok(if horizontal.len() == 1 {
            if !same(h0, 0.0) {
                warnings.push(format!(
                    "a single horizontal angle of {h0}: read as 0 (rotationally symmetric)"
                ));
            }
            Symmetry::Rotational
        } else if same(h0, 0.0) && same(h1, 90.0) {
            Symmetry::Quadrant
        } else if same(h0, 0.0) && same(h1, 180.0) {
            Symmetry::AboutC0
        } else if same(h0, 0.0) && h1 > 180.0 && h1 <= 360.0 + 1e-9 {
            Symmetry::None
        } else if same(h0, 90.0) && same(h1, 270.0) {
            Symmetry::AboutC90
        } else {
            return Err(invalid(
                name,
                self.h_lines[0],
                format!(
                    "horizontal angles run {h0}..{h1}: type C wants 0 alone, 0..90, 0..180, \
                     0..(more than 180, up to 360) or 90..270"
                ),
            ));
        })
    }

    /// Types B and A: the latitude (B's horizontal, A's vertical angles) within −90..90 (the
    /// longitude's −180..180 is checked with every type's); ranges other than LM-63's −90..90
    /// and 0..90 with a warning. True for lateral symmetry: horizontal angles from 0.
    fn type_b_or_a(
        &self,
        kind: PhotometricType,
        warnings: &mut Vec<String>,
    ) -> Result<bool, PhotometryError> {
        let (latitude, lines, what, declared) = if kind == PhotometricType::B {
            (self.horizontal, self.h_lines, "horizontal", self.declared_h)
        } else {
            (self.vertical, self.v_lines, "vertical", self.declared_v)
        };
        check_angles(
            latitude,
            lines,
            &format!("type {kind} {what} angle"),
            declared,
            -90.0,
            90.0,
        )
        .map_err(|(line, m)| invalid(self.file, line, m))?;
        for (list, what) in [(self.horizontal, "horizontal"), (self.vertical, "vertical")] {
            let (a, b) = (list[0], list[list.len() - 1]);
            if !((same(a, -90.0) || same(a, 0.0)) && same(b, 90.0)) {
                warnings.push(format!(
                    "type {kind} {what} angles run {a}..{b}: LM-63 expects -90..90 or 0..90 \
                     (outside the table the intensity is 0)"
                ));
            }
        }
        Ok(same(self.horizontal[0], 0.0))
    }
}

/// Read and check the tilt table of `TILT=INCLUDE`: geometry (1, 2 or 3), the number of
/// pairs, the angles (increasing), the multiplying factors (not negative).
fn read_tilt_table(r: &mut Reader<'_>) -> Result<Tilt, PhotometryError> {
    let (geometry, line) = r.number("the tilt table's lamp-to-luminaire geometry")?;
    let geometry = match geometry {
        1.0 => LampGeometry::Vertical,
        2.0 => LampGeometry::AlongC0,
        3.0 => LampGeometry::AcrossC0,
        g => {
            return Err(invalid(
                r.file,
                line,
                format!("lamp-to-luminaire geometry {g}: expected 1, 2 or 3"),
            ))
        }
    };
    let (pairs, pairs_line) = r.count("the number of tilt angles", 1)?;
    let left = r.words.remaining();
    if left < 2 * pairs {
        return Err(invalid(
            r.file,
            r.end_line,
            format!(
                "the tilt table declares {pairs} angles and factors on line {pairs_line}, \
                 but only {left} numbers follow"
            ),
        ));
    }
    let mut angles = Vec::with_capacity(pairs);
    let mut previous = f64::NEG_INFINITY;
    for _ in 0..pairs {
        let (angle, line) = r.number("tilt angle")?;
        if angle <= previous {
            return Err(invalid(
                r.file,
                line,
                format!("tilt angle {angle} does not increase on the one before, {previous}"),
            ));
        }
        previous = angle;
        angles.push(angle);
    }
    let mut factors = Vec::with_capacity(pairs);
    for _ in 0..pairs {
        let (factor, line) = r.number("tilt multiplying factor")?;
        if factor < 0.0 {
            return Err(invalid(
                r.file,
                line,
                format!("tilt multiplying factor {factor} is negative"),
            ));
        }
        factors.push(factor);
    }
    Ok(Tilt {
        geometry,
        angles,
        factors,
    })
}

/// What follows the candela table: numbers mean the counts are wrong (an error); other words
/// (an end-of-file mark, a note) are ignored with a warning.
fn trailing(
    r: &mut Reader<'_>,
    warnings: &mut Vec<String>,
    counts_line: usize,
) -> Result<(), PhotometryError> {
    let mut junk = 0usize;
    while let Some((line, word)) = r.words.next() {
        if word.parse::<f64>().is_ok() {
            let more = 1 + r
                .words
                .clone()
                .filter(|(_, w)| w.parse::<f64>().is_ok())
                .count();
            return Err(invalid(
                r.file,
                line,
                format!(
                    "{more} more number(s) after the candela table: the counts on line \
                     {counts_line} do not match the data"
                ),
            ));
        }
        junk += 1;
    }
    if junk > 0 {
        warnings.push(format!("{junk} word(s) after the candela table ignored"));
    }
    Ok(())
}

/// How many of the first `n` words are numbers that increase strictly from the first without
/// passing `max` (angles), and the line of the first one that does not. A word that is not a
/// number ends the run with `n` itself (the reading then reports it).
fn increasing_run<'a>(
    words: impl Iterator<Item = (usize, &'a str)>,
    n: usize,
    max: f64,
) -> (usize, usize) {
    let mut previous = f64::NEG_INFINITY;
    let mut run = 0;
    for (line, word) in words.take(n) {
        match word.parse::<f64>() {
            Ok(v) if v > previous && v <= max => previous = v,
            Ok(_) => return (run, line),
            Err(_) => return (n, 0),
        }
        run += 1;
    }
    (run, 0)
}

fn same(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-6
}
