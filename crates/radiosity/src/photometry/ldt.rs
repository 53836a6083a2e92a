//! EULUMDAT photometric files (`.ldt`).
//!
//! The layout, one field a line (as tabulated at `www.helios32.com/Eulumdat.htm` and in
//! AGi32's Photometric Toolbox manual, "EULUMDAT File Format"):
//!
//! | line | field |
//! |---|---|
//! | 1 | company identification |
//! | 2 | Ityp, type indicator (0–3) |
//! | 3 | Isym, symmetry indicator (0–4) |
//! | 4, 5 | Mc, number of C-planes in 0..360°; Dc, their spacing (0: uneven) |
//! | 6, 7 | Ng, number of γ angles; Dg, their spacing |
//! | 8–12 | report number, luminaire name, luminaire number, file name, date/user |
//! | 13–15 | luminaire length (or diameter), width (0: round), height, mm |
//! | 16–21 | luminous area length (or diameter), width (0: round), heights at C0, C90, C180, C270, mm |
//! | 22–25 | downward flux fraction %, light output ratio LORL %, conversion factor for intensities, tilt during measurement |
//! | 26 | n, number of standard lamp sets |
//! | 26a–f | n lines each: number of lamps, lamp type, total lamp flux (lm), colour temperature, colour rendering, wattage |
//! | 27 | 10 direct ratios |
//! | 28 | Mc C angles |
//! | 29 | Ng γ angles |
//! | 30 | intensities, cd/klm, Ng for each stored C-plane |
//!
//! Which C-planes are stored follows Isym: 0 all Mc; 1 one (rotational symmetry); 2 the
//! Mc/2 + 1 planes from C0 to C180 (symmetric about the C0–C180 plane); 3 the Mc/2 + 1 planes
//! from C90 to C270 (symmetric about the C90–C270 plane); 4 the Mc/4 + 1 planes from C0 to C90
//! (symmetric about both). The counts are the format's (Mc1 … Mc2, e.g. as Transoft's KeyLIGHTS
//! manual, Appendix B, tabulates them). For Isym 3 that table starts at index 3·Mc/4 + 1, which
//! read literally is C270 running on through C0 to C90: this reader takes the planes C90 to
//! C270 in increasing order, as the symmetry's name says; both hold the same information for
//! a distribution that has the symmetry, but a file written the other way round would be read
//! mirrored about the C0–C180 plane.
//!
//! The lamp sets are alternative equipment for the same luminaire (the "standard sets" a
//! planner picks from), so the intensities are scaled by the first set's total flux; further
//! sets are noted in the warnings. Absolute photometry (LED luminaires) is written, by the
//! convention DIAL and Lighting Analysts agreed in 2009 ("Handling of absolute photometry data
//! in EULUMDAT files"), as a negative number of lamps with the luminaire's flux as the lamp
//! flux and a light output ratio of 100 %: the scaling is then the same, cd/klm × flux / 1000.
//!
//! Numbers may use a decimal comma (`99,8`), as some European writers do.

use super::{
    check_angles, count, invalid, last_line, number, prepare, shown, Lines, NumberReader, Opening,
    PhotometricType, Photometry, PhotometryError, Symmetry, Table, Words, MAX_TABLE_VALUES,
};

/// A number as EULUMDAT writes it: a decimal point or a single decimal comma.
fn ldt_number(word: &str, what: &str) -> Result<f64, String> {
    let word = word.trim();
    if word.is_empty() {
        return Err(format!("{what} is missing (an empty line)"));
    }
    if word.contains(',') && !word.contains('.') && word.matches(',').count() == 1 {
        return number(&word.replace(',', "."), what)
            .map_err(|_| format!("{what} '{}' is not a number", shown(word)));
    }
    number(word, what)
}

/// The fixed-layout lines, one field each, with errors at their lines.
struct Cursor<'a> {
    lines: Lines<'a>,
    file: &'a str,
    end_line: usize,
}

impl<'a> Cursor<'a> {
    fn line(&mut self, what: &str) -> Result<(usize, &'a str), PhotometryError> {
        self.lines.next().ok_or_else(|| {
            invalid(
                self.file,
                self.end_line,
                format!(
                    "expected {what} (line {} of the EULUMDAT layout), found the end of the file",
                    self.lines.number() + 1
                ),
            )
        })
    }

    fn number(&mut self, what: &str) -> Result<(f64, usize), PhotometryError> {
        let (line, text) = self.line(what)?;
        ldt_number(text, what)
            .map(|v| (v, line))
            .map_err(|m| invalid(self.file, line, m))
    }

    fn count(&mut self, what: &str, min: usize) -> Result<(usize, usize), PhotometryError> {
        let (line, text) = self.line(what)?;
        let value = ldt_number(text, what).map_err(|m| invalid(self.file, line, m))?;
        count(value, text.trim(), what, min)
            .map(|n| (n, line))
            .map_err(|m| invalid(self.file, line, m))
    }
}

/// The numeric tail (direct ratios, angles, intensities): one value a line as the format
/// writes it, but read as blank-separated words so that a writer putting several on a line
/// is read too.
type Tail<'a> = NumberReader<'a>;

/// Parse the text of an EULUMDAT file; `name` is the file's name, for messages and
/// [`Photometry::source`]. Intensities (cd/klm) are scaled to candela by the first lamp set's
/// total flux (further sets are alternative equipment, noted in the warnings) and the
/// conversion factor; dimensions are converted from millimetres to metres. A negative number
/// of lamps marks absolute photometry (the DIAL / Lighting Analysts convention of 2009): the
/// flux is then the luminaire's, and the scaling the same. Symmetry 3 (about the C90–C270
/// plane) is read as the planes C90 to C270 in increasing order; the format's own table of
/// stored planes can be read as C270 through C0 to C90, which for an asymmetric file would
/// mirror it about the C0–C180 plane.
pub fn parse_ldt(text: &str, name: &str) -> Result<Photometry, PhotometryError> {
    let text = prepare(text, name)?;
    let end_line = last_line(text);
    let mut c = Cursor {
        lines: Lines::new(text),
        file: name,
        end_line,
    };
    let mut warnings = Vec::new();

    c.line("the company identification")?;
    let (ityp, ityp_line) = c.number("the type indicator Ityp")?;
    if ![0.0, 1.0, 2.0, 3.0].contains(&ityp) {
        return Err(invalid(
            name,
            ityp_line,
            format!("type indicator Ityp {ityp}: expected 0, 1, 2 or 3"),
        ));
    }
    let (isym, isym_line) = c.number("the symmetry indicator Isym")?;
    let symmetry = match isym {
        0.0 => Symmetry::None,
        1.0 => Symmetry::Rotational,
        2.0 => Symmetry::AboutC0,
        3.0 => Symmetry::AboutC90,
        4.0 => Symmetry::Quadrant,
        s => {
            return Err(invalid(
                name,
                isym_line,
                format!("symmetry indicator Isym {s}: expected 0 to 4"),
            ))
        }
    };
    let (mc, mc_line) = c.count("the number of C-planes Mc", 1)?;
    c.number("the C-plane spacing Dc")?;
    let (ng, ng_line) = c.count("the number of γ angles Ng", 2)?;
    c.number("the γ spacing Dg")?;
    for what in [
        "the measurement report number",
        "the luminaire name",
        "the luminaire number",
        "the file name",
        "the date and user",
    ] {
        c.line(what)?;
    }
    c.number("the luminaire's length")?;
    c.number("the luminaire's width")?;
    c.number("the luminaire's height")?;
    let (area_length, _) = c.number("the luminous area's length")?;
    let (area_width, _) = c.number("the luminous area's width")?;
    let mut heights = 0.0;
    for what in [
        "the luminous area's height at C0",
        "the luminous area's height at C90",
        "the luminous area's height at C180",
        "the luminous area's height at C270",
    ] {
        heights += c.number(what)?.0.abs();
    }
    c.number("the downward flux fraction")?;
    let (lorl, lorl_line) = c.number("the light output ratio LORL")?;
    let (conversion, conversion_line) = c.number("the conversion factor for intensities")?;
    c.number("the tilt during measurement")?;
    let (sets, sets_line) = c.count("the number of lamp sets", 1)?;

    let mut first_lamps = 0.0;
    let mut first_flux = (0.0, 0);
    for k in 0..sets {
        let (lamps, line) = c.number("a number of lamps")?;
        if lamps.fract() != 0.0 {
            return Err(invalid(
                name,
                line,
                format!("number of lamps {lamps} is not a whole number"),
            ));
        }
        if k == 0 {
            first_lamps = lamps;
        }
    }
    for _ in 0..sets {
        c.line("a lamp type")?;
    }
    for k in 0..sets {
        let (flux, line) = c.number("a lamp set's total flux")?;
        if k == 0 {
            first_flux = (flux, line);
        }
    }
    for what in [
        "a colour temperature",
        "a colour rendering index",
        "a wattage",
    ] {
        for _ in 0..sets {
            c.line(what)?;
        }
    }
    let (flux, flux_line) = first_flux;
    if flux <= 0.0 {
        return Err(invalid(
            name,
            flux_line,
            format!("lamp flux {flux} lm is not positive: cd/klm cannot be made candela"),
        ));
    }
    if sets > 1 {
        warnings.push(format!(
            "{sets} lamp sets (line {sets_line}): intensities scaled by the first set's \
             {flux} lm"
        ));
    }
    let conversion = if conversion > 0.0 {
        conversion
    } else {
        warnings.push(format!(
            "conversion factor {conversion} (line {conversion_line}) is not positive: 1 used"
        ));
        1.0
    };

    let stored = match symmetry {
        Symmetry::None => mc,
        Symmetry::Rotational => 1,
        Symmetry::AboutC0 | Symmetry::AboutC90 => mc / 2 + 1,
        Symmetry::Quadrant => mc / 4 + 1,
    };
    let values = stored
        .checked_mul(ng)
        .filter(|&v| v <= MAX_TABLE_VALUES)
        .ok_or_else(|| {
            invalid(
                name,
                ng_line,
                format!(
                    "{stored} stored C-planes × {ng} γ angles: more than {MAX_TABLE_VALUES} \
                     intensities is not a photometric table"
                ),
            )
        })?;
    let mut t = Tail {
        words: Words::new(c.lines, false),
        file: name,
        end_line,
        parse: ldt_number,
    };
    let left = t.words.remaining();
    let needed = [
        (10, "direct ratios".to_string()),
        (mc, "C angles".to_string()),
        (ng, "γ angles".to_string()),
        (
            values,
            format!("intensities ({stored} C-planes × {ng} γ angles for Isym {isym})"),
        ),
    ];
    let mut before = 0;
    for (n, what) in &needed {
        if left < before + n {
            return Err(invalid(
                name,
                end_line,
                format!("expected {n} {what}, found {}", left - before),
            ));
        }
        before += n;
    }

    t.numbers(10, "direct ratio")?;
    let (c_all, c_lines) = t.numbers(mc, "C angle")?;
    let (gamma, g_lines) = t.numbers(ng, "γ angle")?;
    let declared_c = format!("the file declares Mc = {mc} on line {mc_line}");
    let declared_g = format!("the file declares Ng = {ng} on line {ng_line}");
    if symmetry != Symmetry::Rotational {
        check_angles(&c_all, &c_lines, "C angle", &declared_c, 0.0, 360.0)
            .map_err(|(line, m)| invalid(name, line, m))?;
    }
    check_angles(&gamma, &g_lines, "γ angle", &declared_g, 0.0, 180.0)
        .map_err(|(line, m)| invalid(name, line, m))?;

    // The stored planes' angles, and a check that they are the ones the symmetry names.
    let (first, planes, want) = match symmetry {
        Symmetry::None => (0, mc, None),
        Symmetry::Rotational => (0, 1, None),
        Symmetry::AboutC0 => (0, stored, Some((0.0, 180.0))),
        Symmetry::AboutC90 => (mc / 4, stored, Some((90.0, 270.0))),
        Symmetry::Quadrant => (0, stored, Some((0.0, 90.0))),
    };
    let c_stored: Vec<f64> = match c_all.get(first..first + planes) {
        Some(s) => s.to_vec(),
        None => Vec::new(),
    };
    if let Some((a, b)) = want {
        let ok = c_stored.len() == planes
            && (c_stored[0] - a).abs() <= 1e-6
            && (c_stored[planes - 1] - b).abs() <= 1e-6;
        if !ok {
            return Err(invalid(
                name,
                isym_line,
                format!(
                    "Isym {isym} stores the C-planes {a}..{b}, but with Mc = {mc} the C angles \
                     at positions {}..{} are not those",
                    first + 1,
                    first + planes
                ),
            ));
        }
    }

    let scale = flux / 1000.0 * conversion;
    let mut candela = Vec::with_capacity(values.min(t.words.remaining()));
    for _ in 0..values {
        let (v, line) = t.number("intensity")?;
        if v < 0.0 {
            return Err(invalid(name, line, format!("intensity {v} is negative")));
        }
        if !(v * scale).is_finite() {
            return Err(invalid(
                name,
                flux_line,
                format!("lamp flux {flux} lm makes the intensities overflow"),
            ));
        }
        candela.push(v * scale);
    }
    let mut junk = 0usize;
    while let Some((line, word)) = t.words.next() {
        if ldt_number(word, "").is_ok() {
            let more = 1 + t
                .words
                .clone()
                .filter(|(_, w)| ldt_number(w, "").is_ok())
                .count();
            return Err(invalid(
                name,
                line,
                format!(
                    "{more} more number(s) after the intensities: Mc, Ng or Isym (lines \
                     {mc_line}, {ng_line}, {isym_line}) do not match the data"
                ),
            ));
        }
        junk += 1;
    }
    if junk > 0 {
        warnings.push(format!("{junk} word(s) after the intensities ignored"));
    }

    let rated_flux = if lorl > 0.0 {
        Some(flux * lorl / 100.0 * conversion)
    } else {
        warnings.push(format!(
            "light output ratio {lorl} % (line {lorl_line}): no luminaire flux to check against"
        ));
        None
    };
    if first_lamps < 0.0 && (lorl - 100.0).abs() > 0.5 {
        warnings.push(format!(
            "absolute photometry (negative number of lamps) with a light output ratio of \
             {lorl} %, not 100 %"
        ));
    }
    let round = area_width == 0.0 && area_length != 0.0;
    let opening = Opening {
        length_m: area_length.abs() / 1000.0,
        width_m: if round {
            area_length.abs()
        } else {
            area_width.abs()
        } / 1000.0,
        height_m: heights / 4.0 / 1000.0,
        round,
    };
    Ok(Table {
        kind: PhotometricType::C,
        symmetry,
        c_angles: if symmetry == Symmetry::Rotational {
            vec![0.0]
        } else {
            c_stored
        },
        gamma_angles: gamma,
        candela,
        lumens: Some(flux),
        rated_flux,
        opening,
        tilt: None,
        warnings,
    }
    .into_photometry(name))
}
