//! Luminaire photometry: how much light a luminaire sends in each direction, read from the two
//! file formats lighting makers publish, for lighting design (luminaires as light sources).
//!
//! # The formats
//!
//! - **IES LM-63** (`.ies`), the North American format, in its revisions 1986 (no header line),
//!   1991 (`IESNA91`), 1995 (`IESNA:LM-63-1995`), 2002 (`IESNA:LM-63-2002`) and 2019
//!   (`IES:LM-63-2019`): keyword lines (`[MANUFAC] …`), a `TILT=` line, then numbers separated by
//!   blanks, commas or line ends, wrapped anywhere: the counts, multipliers and the luminous
//!   opening, the vertical and horizontal angles, and the candela table. Read by
//!   [`parse_ies`]; the fields and their order are as LM-63-2002 lays them out (described by
//!   AGi32's Photometric Toolbox manual, `docs.agi32.com/PhotometricToolbox`, "IESNA LM-63
//!   Format") and as Ian Ashdown describes the 1986 and 1991 variants (ltblight.com, "Appendix C
//!   – IES-NA data interchange format").
//! - **EULUMDAT** (`.ldt`), the European format: a fixed layout of one field a line (maker,
//!   type and symmetry indicators, counts, names, dimensions in millimetres, lamp sets, direct
//!   ratios), then the C angles, the γ angles and the intensities in cd/klm of lamp flux for the
//!   C-planes the symmetry leaves. Read by [`parse_ldt`]; the layout is the one tabulated at
//!   `www.helios32.com/Eulumdat.htm` and in AGi32's manual ("EULUMDAT File Format").
//!
//! [`read`] reads either from a file, by its extension (case-insensitive), decoding Latin-1
//! where the bytes are not UTF-8 (real files are Latin-1) and taking CRLF, LF or CR line ends.
//!
//! # The coordinate systems
//!
//! A table is held in the coordinates it was measured in ([`PhotometricType`]), and every
//! system is placed in one frame of the luminaire, the frame [`Photometry::intensity_dir`]
//! takes: **−z** is the photometric axis (the aim: type C's nadir, types B and A's beam),
//! **+x** the reference direction across it (C0; the top of a floodlight) and **+y** = z × x
//! (C90). The luminous opening's length lies along x, its width along y, its height along z.
//!
//! - **Type C** (CIE's C-γ system; all of EULUMDAT): the polar axis is the luminaire's
//!   vertical axis; γ is the angle from the photometric nadir (γ = 0 straight down out of the
//!   luminaire, 90° horizontal, 180° straight up); the C-planes are half-planes hinged on the
//!   polar axis, C = 0 the reference half-plane (along the luminaire's length, for a linear
//!   one), C increasing counter-clockwise seen from above (LM-63-2002 defines type C
//!   horizontal angles as counter-clockwise; EULUMDAT's C angles turn the same way). A
//!   direction `(x, y, z)` has γ = acos(−z/|d|) and C = atan2(y, x) ([`Photometry::angles`]).
//! - **Type B** (CIE's B-β system, IES photometric type 2; floodlights): the polar axis is
//!   the luminaire's lateral axis, horizontal and across the beam (LM-63: "the polar axis
//!   coincides with the minor axis (width) of the luminaire", here y). The **vertical angle
//!   V** turns the planes hinged on that axis (B): V = 0 holds the beam, V > 0 tilts up
//!   towards +x; the **horizontal angle H** is measured within a plane (β), from the plane
//!   through the beam and the top, positive to the right seen from behind the luminaire
//!   looking along the beam (clockwise seen from above the aimed floodlight), that is
//!   towards −y. A unit direction is `(cos H sin V, −sin H, −cos H cos V)`: H = asin(−y),
//!   V = atan2(x, −z).
//! - **Type A** (CIE's A-α system, IES photometric type 3; automotive lamps): the polar axis
//!   is the luminaire's top–bottom axis across the beam (LM-63: "the polar axis coincides
//!   with the major axis (length) of the luminaire", here x). The **horizontal angle H**
//!   turns the planes hinged on it (A), H > 0 to the right (towards −y); the **vertical angle
//!   V** is the elevation within a plane (α), V > 0 up (towards +x). A unit direction is
//!   `(sin V, −cos V sin H, −cos V cos H)`: H = atan2(−y, −z), V = asin(x).
//!
//! In both B and A the photometric axis H = V = 0 is −z, V = 90° at H = 0 is +x and H = 90°
//! at V = 0 is −y; they differ off those two great circles (B's H is a latitude and V a
//! longitude; A's the other way round). These are the goniometers of CIE 70 and LM-75 (type
//! B: a fixed vertical axis carrying a horizontal one that carries the luminaire; type A: a
//! fixed horizontal axis carrying a vertical one), and LM-63's lateral symmetry of B and A
//! (horizontal angles from 0: the same either side of a vertical plane) is H → −H in both.
//! Radiance's `source.cal` puts the type B photometric axis at −z with V towards +x and H
//! towards −y as well (it approximates H by a plane angle). [`crate::lighting`] aims −z
//! and turns +x as its schedule says (`aim`, `c0`).
//!
//! # What is applied
//!
//! [`Photometry::candela`] holds absolute candela for the luminaire as the file rates it:
//! IES values times the candela multiplier and the ballast factor (and, for the 1986 and 1991
//! revisions, the ballast-lamp photometric factor, a field later revisions leave to "future
//! use"); EULUMDAT values (cd/klm) times the first lamp set's total flux / 1000 and the
//! conversion factor. Type C tables are expanded to the full circle of C-planes, 0° to 360°
//! both included; type B and A tables with lateral symmetry (horizontal angles from 0) are
//! mirrored to negative horizontal angles.
//!
//! An IES tilt table (`TILT=INCLUDE`) is kept as [`Photometry::tilt`]: the multiplying factor
//! of the lamp's light output against the tilt angle, which depends on how the luminaire is
//! installed; [`crate::lighting::Luminaire::with_lamp_tilt`] applies it to each placed
//! luminaire ([`Tilt`] says which angle each lamp-to-luminaire geometry means). The
//! photometry itself is the luminaire at the tilt it was measured at.
//!
//! [`Photometry::flux`] integrates the table over the sphere (type C: exact for
//! distributions linear in cos γ between tabulated angles, so a constant and a cosine law
//! come out exactly; types B and A: the exact integral of the interpolated distribution),
//! and [`Photometry::flux_mismatch`] compares it with the flux the file states; a mismatch
//! past 5 % is also noted in [`Photometry::warnings`].

mod ies;
mod ldt;
#[cfg(test)]
mod tests;

pub use ies::parse_ies;
pub use ldt::parse_ldt;

use std::borrow::Cow;
use std::fmt;
use std::path::Path;

/// Largest photometric file read, bytes. Real files are a few kilobytes to a few hundred (a
/// 0.5° × 1° full table of 361 × 361 values is about 1 MiB); anything far past that is not one.
pub const MAX_FILE_BYTES: usize = 16 << 20;

/// Most values a candela table may hold (C-planes × γ angles, as stored in the file): counts
/// past this are refused before anything is allocated.
pub const MAX_TABLE_VALUES: usize = 10_000_000;

/// Share of the stated flux past which [`Photometry::warnings`] notes that the integrated flux
/// differs.
pub const FLUX_WARNING: f64 = 0.05;

/// Tolerance on angles, degrees: two angles closer than this are the same angle.
const ANGLE_EPS: f64 = 1e-9;

/// The goniometer coordinate system a table was measured in (LM-63's "photometric type").
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PhotometricType {
    /// Type C: C-planes through the vertical axis, γ from the nadir (IES type 1; all of
    /// EULUMDAT).
    C,
    /// Type B: planes (V) through the horizontal lateral axis, H within them (IES type 2;
    /// floodlights).
    B,
    /// Type A: planes (H) through the luminaire's top–bottom axis, V the elevation within
    /// them (IES type 3; automotive lamps).
    A,
}

impl fmt::Display for PhotometricType {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            PhotometricType::C => "C",
            PhotometricType::B => "B",
            PhotometricType::A => "A",
        })
    }
}

/// The luminous opening: the emitting area's size, metres, in the luminaire's frame (length
/// along x, the C0 direction; width along y, the C90 direction; height along z).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Opening {
    /// Extent along y (C90–C270), metres; the diameter when `round`.
    pub width_m: f64,
    /// Extent along x (C0–C180), metres; the diameter when `round`.
    pub length_m: f64,
    /// Extent along z, metres.
    pub height_m: f64,
    /// True for a round opening (IES: a negative width or length; EULUMDAT: a luminous width
    /// of 0 with a non-zero diameter).
    pub round: bool,
}

/// How the lamp sits in the luminaire, which says what a tilt table's angle is (LM-63's
/// "lamp-to-luminaire geometry"; its wording, and the reading taken here).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LampGeometry {
    /// 1: "the lamp base is vertical (base up or base down) when the luminaire is aimed
    /// straight down": the lamp lies along the photometric axis (z), and the tilt angle is
    /// the angle between the photometric axis and straight down, 0..=180° (90° aimed
    /// horizontally, 180° straight up).
    Vertical,
    /// 2: "the lamp is horizontal and remains horizontal when the luminaire is aimed straight
    /// down or rotated about the zero-degree horizontal plane": the lamp lies along the C0
    /// axis (x), and the tilt angle is the lamp's inclination to the horizontal, 0..=90°
    /// (Radiance's `ies2rad` reads 2 as "horizontal in the 0° plane" too).
    AlongC0,
    /// 3: "the lamp is horizontal when the luminaire is pointed straight down, but does not
    /// remain horizontal when rotated about the zero-degree horizontal plane": the lamp lies
    /// along the C90 axis (y), and the tilt angle is its inclination to the horizontal,
    /// 0..=90°.
    AcrossC0,
}

/// A lamp's tilt table (IES `TILT=INCLUDE`): the factor its light output is multiplied by
/// against the tilt angle (metal-halide lamps give less light tilted off their design
/// burning position). LM-63: the candela values are multiplied by the factor at the tilt
/// angle of the installed luminaire.
#[derive(Clone, Debug, PartialEq)]
pub struct Tilt {
    /// What the angle measures.
    pub geometry: LampGeometry,
    /// Tilt angles, degrees, increasing.
    pub angles: Vec<f64>,
    /// The multiplying factor at each angle, ≥ 0.
    pub factors: Vec<f64>,
}

impl Tilt {
    /// The tilt angle, degrees, of a luminaire installed so that `up`, the world's vertical,
    /// is the direction `up` in the luminaire's frame (photometric axis −z, C0 +x, C90 +y;
    /// need not be unit length): see [`LampGeometry`]. A luminaire aimed straight down
    /// (`up` = +z) has tilt 0 in every geometry. `None` for a zero or non-finite `up`.
    pub fn installed_angle(&self, up: [f64; 3]) -> Option<f64> {
        let [x, y, z] = up;
        let len = (x * x + y * y + z * z).sqrt();
        if len == 0.0 || !len.is_finite() {
            return None;
        }
        Some(match self.geometry {
            // The photometric axis −z against straight down −up: acos(z · up).
            LampGeometry::Vertical => (z / len).clamp(-1.0, 1.0).acos().to_degrees(),
            // The lamp axis's angle with the horizontal plane: asin |axis · up|.
            LampGeometry::AlongC0 => x.abs().atan2(y.hypot(z)).to_degrees(),
            LampGeometry::AcrossC0 => y.abs().atan2(x.hypot(z)).to_degrees(),
        })
    }

    /// The factor at `angle` degrees, linear between the tabulated angles, and whether
    /// `angle` lies within the table (outside, the factor of the nearer end). A non-finite
    /// angle gives the first factor, outside.
    pub fn factor(&self, angle: f64) -> (f64, bool) {
        let n = self.angles.len().min(self.factors.len());
        if n == 0 {
            return (1.0, false);
        }
        let (first, last) = (self.angles[0], self.angles[n - 1]);
        if !angle.is_finite() {
            return (self.factors[0], false);
        }
        let inside = angle >= first - ANGLE_EPS && angle <= last + ANGLE_EPS;
        let (k, t) = locate(&self.angles[..n], angle.clamp(first, last));
        let f = lerp(self.factors[k], self.factors[(k + 1).min(n - 1)], t);
        (f, inside)
    }
}

/// A luminaire's luminous intensity distribution: a table over the horizontal and vertical
/// angles of its [`PhotometricType`] (see the module documentation for the three systems).
#[derive(Clone, Debug, PartialEq)]
pub struct Photometry {
    /// The horizontal angles, degrees, increasing. Type C: the C-planes, from 0 to 360 (both
    /// included: the last plane closes the circle), after expanding the file's symmetry.
    /// Types B and A: H, within −90..=90 (B) or −180..=180 (A), a laterally symmetric
    /// table mirrored to negative angles.
    pub c_angles: Vec<f64>,
    /// The vertical angles, degrees, increasing. Type C: γ, within 0..=180 (0 = nadir).
    /// Type B: V, within −180..=180; type A: V, within −90..=90. The table's range, which need
    /// not be the whole sphere: outside it the intensity is 0.
    pub gamma_angles: Vec<f64>,
    /// Intensities, candela, one row per horizontal angle (`c_angles.len()` rows) and one
    /// column per vertical angle: the value at `c_angles[i]`, `gamma_angles[j]` is
    /// `candela[i * gamma_angles.len() + j]`. Absolute: the file's multipliers, lamp flux and
    /// ballast factor applied (a tilt factor is not: see [`Photometry::tilt`]).
    pub candela: Vec<f64>,
    /// The file's rated lamp lumens (IES: number of lamps × lumens per lamp; EULUMDAT: the
    /// first lamp set's total flux, which for absolute photometry is the luminaire's), or
    /// `None` for IES absolute photometry (lumens −1).
    pub lumens: Option<f64>,
    /// The luminaire flux the file states or implies, lumens, which the integrated
    /// [`Photometry::flux`] should match: IES, `lumens` × ballast factor (a luminaire's
    /// efficiency is not in IES files, so for relative photometry this is an upper bound);
    /// EULUMDAT, lamp flux × light output ratio × conversion factor. `None` when the file
    /// states none.
    pub rated_flux: Option<f64>,
    /// The coordinate system the table is in (see the module documentation).
    pub kind: PhotometricType,
    /// The lamp's tilt table (IES `TILT=INCLUDE`), applied per installed luminaire by
    /// [`crate::lighting::Luminaire::with_lamp_tilt`]; `None` for `TILT=NONE` and EULUMDAT.
    pub tilt: Option<Tilt>,
    /// The luminous opening.
    pub opening: Opening,
    /// The file's name, as given to the parser.
    pub source: String,
    /// What was read but is doubtful or not applied, one line each.
    pub warnings: Vec<String>,
}

/// Why a photometric file could not be read.
#[derive(Debug, thiserror::Error)]
pub enum PhotometryError {
    /// The file could not be read (the operating system's reason is the source).
    #[error("{file}: cannot read the file")]
    Io {
        /// The file's name.
        file: String,
        /// The operating system's reason.
        source: std::io::Error,
    },
    /// The file's name ends in neither `.ies` nor `.ldt`.
    #[error("{file}: not a photometric file name (expected the extension .ies or .ldt)")]
    UnknownExtension {
        /// The file's name.
        file: String,
    },
    /// A problem at a line of the file.
    #[error("{file}:{line}: {message}")]
    Invalid {
        /// The file's name.
        file: String,
        /// The line, 1-based.
        line: usize,
        /// What is wrong, one line.
        message: String,
    },
}

impl PhotometryError {
    /// The line the problem is at (1-based), for problems in the file's text.
    pub fn line(&self) -> Option<usize> {
        match self {
            PhotometryError::Invalid { line, .. } => Some(*line),
            _ => None,
        }
    }
}

/// An error at `line` of `file`.
pub(crate) fn invalid(file: &str, line: usize, message: impl Into<String>) -> PhotometryError {
    let message: String = message.into();
    PhotometryError::Invalid {
        file: file.to_string(),
        line: line.max(1),
        // One line whatever the message quotes.
        message: message.replace(['\n', '\r'], " "),
    }
}

/// Read a photometric file: IES LM-63 for `.ies`, EULUMDAT for `.ldt` (case-insensitive).
/// Errors name the file by its name (not the whole path) and the line.
pub fn read(path: &Path) -> Result<Photometry, PhotometryError> {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| path.display().to_string());
    let format = Format::of(&name)
        .ok_or_else(|| PhotometryError::UnknownExtension { file: name.clone() })?;
    let io = |source| PhotometryError::Io {
        file: name.clone(),
        source,
    };
    let meta = std::fs::metadata(path).map_err(io)?;
    if meta.len() > MAX_FILE_BYTES as u64 {
        return Err(too_large(&name));
    }
    let bytes = crate::io::read_input(path).map_err(io)?;
    format.parse(&bytes, &name)
}

/// Parse a photometric file already in memory; `name`'s extension (`.ies` or `.ldt`,
/// case-insensitive) tells the format. The bytes are decoded as by [`decode`].
pub fn parse_bytes(bytes: &[u8], name: &str) -> Result<Photometry, PhotometryError> {
    let format = Format::of(name).ok_or_else(|| PhotometryError::UnknownExtension {
        file: name.to_string(),
    })?;
    format.parse(bytes, name)
}

/// A file's bytes as text: UTF-8 when they are valid UTF-8 (a byte-order mark dropped), else
/// Latin-1 (ISO 8859-1, each byte the character of that code), which is what photometric
/// files written on Windows are.
pub fn decode(bytes: &[u8]) -> Cow<'_, str> {
    match std::str::from_utf8(bytes) {
        Ok(text) => Cow::Borrowed(text.strip_prefix('\u{feff}').unwrap_or(text)),
        Err(_) => Cow::Owned(bytes.iter().map(|&b| b as char).collect()),
    }
}

#[derive(Clone, Copy)]
enum Format {
    Ies,
    Ldt,
}

impl Format {
    fn of(name: &str) -> Option<Format> {
        let ext = Path::new(name).extension()?.to_str()?.to_ascii_lowercase();
        match ext.as_str() {
            "ies" => Some(Format::Ies),
            "ldt" => Some(Format::Ldt),
            _ => None,
        }
    }

    fn parse(self, bytes: &[u8], name: &str) -> Result<Photometry, PhotometryError> {
        if bytes.len() > MAX_FILE_BYTES {
            return Err(too_large(name));
        }
        let text = decode(bytes);
        match self {
            Format::Ies => parse_ies(&text, name),
            Format::Ldt => parse_ldt(&text, name),
        }
    }
}

fn too_large(name: &str) -> PhotometryError {
    invalid(
        name,
        1,
        format!(
            "larger than {} MiB: not a photometric file",
            MAX_FILE_BYTES >> 20
        ),
    )
}

/// The checks both parsers start with: not too large, not empty. Returns the text without a
/// byte-order mark.
pub(crate) fn prepare<'a>(text: &'a str, name: &str) -> Result<&'a str, PhotometryError> {
    if text.len() > MAX_FILE_BYTES {
        return Err(too_large(name));
    }
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    if text.trim().is_empty() {
        return Err(invalid(name, 1, "empty file"));
    }
    Ok(text)
}

impl Photometry {
    /// The intensity, candela, at the table's own angles, degrees: C = `h_deg`, γ = `v_deg`
    /// for type C, H = `h_deg`, V = `v_deg` for types B and A. Bilinear interpolation
    /// between the tabulated angles, so it never leaves the range of the four values around
    /// it. Type C: C is periodic over 360°, γ outside the table's range gives 0 (a table of
    /// 0..=90 sends nothing upwards). Types B and A: either angle outside the table's range
    /// gives 0. Non-finite angles give 0.
    pub fn intensity(&self, h_deg: f64, v_deg: f64) -> f64 {
        let (h, v) = (&self.c_angles, &self.gamma_angles);
        let (nh, nv) = (h.len(), v.len());
        if !h_deg.is_finite()
            || !v_deg.is_finite()
            || nh == 0
            || nv == 0
            || self.candela.len() != nh * nv
        {
            return 0.0;
        }
        let outside =
            |xs: &[f64], x: f64| x < xs[0] - ANGLE_EPS || x > xs[xs.len() - 1] + ANGLE_EPS;
        if outside(v, v_deg) {
            return 0.0;
        }
        let h_deg = match self.kind {
            PhotometricType::C => h_deg.rem_euclid(360.0),
            PhotometricType::B | PhotometricType::A if outside(h, h_deg) => return 0.0,
            PhotometricType::B | PhotometricType::A => h_deg.clamp(h[0], h[nh - 1]),
        };
        let (j, tv) = locate(v, v_deg.clamp(v[0], v[nv - 1]));
        let (i, th) = locate(h, h_deg);
        let at = |i: usize, j: usize| self.candela[i * nv + j];
        let (j1, i1) = ((j + 1).min(nv - 1), (i + 1).min(nh - 1));
        let lo = lerp(at(i, j), at(i, j1), tv);
        let hi = lerp(at(i1, j), at(i1, j1), tv);
        lerp(lo, hi, th)
    }

    /// The intensity, candela, towards `dir` in the luminaire's frame (photometric axis −z,
    /// +x the reference across it, +y = z × x; see the module documentation; need not be unit
    /// length), for a table of any type. A zero or non-finite direction gives 0.
    pub fn intensity_dir(&self, dir: [f64; 3]) -> f64 {
        match self.table_angles(dir) {
            Some((h, v)) => self.intensity(h, v),
            None => 0.0,
        }
    }

    /// The table's angles (horizontal, vertical), degrees, of a direction in the luminaire's
    /// frame: (C, γ) with C in [0, 360) for type C ([`Photometry::angles`]); (H, V) for type
    /// B, H = asin(−y) in [−90, 90] and V = atan2(x, −z) in (−180, 180]; (H, V) for type A,
    /// H = atan2(−y, −z) in (−180, 180] and V = asin(x) in [−90, 90] (for a unit direction).
    /// `None` for a zero or non-finite direction. On a type B or A pole (±y, ±x) the
    /// longitude is 0.
    pub fn table_angles(&self, dir: [f64; 3]) -> Option<(f64, f64)> {
        let [x, y, z] = dir;
        let len = (x * x + y * y + z * z).sqrt();
        if len == 0.0 || !len.is_finite() {
            return None;
        }
        // A latitude from its sine and the other two components: atan2 keeps it accurate
        // next to the pole, where asin loses digits.
        let latitude = |s: f64, a: f64, b: f64| s.atan2(a.hypot(b)).to_degrees();
        match self.kind {
            PhotometricType::C => angles_of(dir),
            PhotometricType::B => Some((latitude(-y, x, z), x.atan2(-z).to_degrees())),
            PhotometricType::A => Some(((-y).atan2(-z).to_degrees(), latitude(x, y, z))),
        }
    }

    /// The unit direction, in the luminaire's frame, of the table's angles `h_deg`, `v_deg`
    /// (degrees): the inverse of [`Photometry::table_angles`].
    pub fn table_direction(&self, h_deg: f64, v_deg: f64) -> [f64; 3] {
        let (h, v) = (h_deg.to_radians(), v_deg.to_radians());
        match self.kind {
            PhotometricType::C => Photometry::direction(h_deg, v_deg),
            PhotometricType::B => [h.cos() * v.sin(), -h.sin(), -h.cos() * v.cos()],
            PhotometricType::A => [v.sin(), -v.cos() * h.sin(), -v.cos() * h.cos()],
        }
    }

    /// The unit direction, in the luminaire's frame, of C = `c_deg`, γ = `gamma_deg` (type C
    /// angles): the inverse of [`Photometry::angles`].
    pub fn direction(c_deg: f64, gamma_deg: f64) -> [f64; 3] {
        let (c, g) = (c_deg.to_radians(), gamma_deg.to_radians());
        [g.sin() * c.cos(), g.sin() * c.sin(), -g.cos()]
    }

    /// The type C angles (C, γ), degrees, of a direction in the luminaire's frame, C in
    /// [0, 360); `None` for a zero or non-finite direction. Straight down and straight up have
    /// C = 0.
    pub fn angles(dir: [f64; 3]) -> Option<(f64, f64)> {
        angles_of(dir)
    }

    /// The luminous flux, lumens, the table sends out.
    ///
    /// Type C: Σ over the cells of the (C, γ) grid of the mean of the four corner intensities
    /// times the cell's exact solid angle (cos γ₁ − cos γ₂)·ΔC (ΔC in radians; over a full
    /// zone, 2π(cos γ₁ − cos γ₂)·ΔC/360°). That is the trapezoid rule in C and in cos γ: exact
    /// for any distribution linear in cos γ between tabulated angles, a constant (4π I) and a
    /// cosine law (π I₀ over the lower hemisphere) included, whatever the angle step. It
    /// differs from the integral of [`Photometry::intensity`], which is linear in γ, by
    /// O(Δγ²).
    ///
    /// Types B and A: the exact integral of [`Photometry::intensity`] over the table, with
    /// the solid angle dΩ = cos φ dφ dλ of the latitude φ (B: H; A: V) and the longitude λ
    /// (B: V; A: H). The interpolant is Σ I_ij h_i(H) h_j(V) with hat functions h, and the
    /// weight factorises, so Φ = Σ I_ij w_i w_j with w the integrals of the hats against
    /// cos φ (in closed form) or 1 (the trapezoid weights).
    pub fn flux(&self) -> f64 {
        let (c, g) = (&self.c_angles, &self.gamma_angles);
        let (nc, ng) = (c.len(), g.len());
        if nc < 2 || ng < 2 || self.candela.len() != nc * ng {
            return 0.0;
        }
        if self.kind != PhotometricType::C {
            let (wh, wv) = match self.kind {
                PhotometricType::B => (latitude_weights(c), longitude_weights(g)),
                _ => (longitude_weights(c), latitude_weights(g)),
            };
            return self
                .candela
                .chunks(ng)
                .zip(&wh)
                .map(|(row, w)| w * row.iter().zip(&wv).map(|(i, w)| i * w).sum::<f64>())
                .sum();
        }
        let cos: Vec<f64> = g.iter().map(|a| a.to_radians().cos()).collect();
        let mut total = 0.0;
        for i in 0..nc - 1 {
            let dc = (c[i + 1] - c[i]).to_radians();
            let (lo, hi) = (
                &self.candela[i * ng..(i + 1) * ng],
                &self.candela[(i + 1) * ng..(i + 2) * ng],
            );
            let mut zone = 0.0;
            for j in 0..ng - 1 {
                zone += (cos[j] - cos[j + 1]) * (lo[j] + lo[j + 1] + hi[j] + hi[j + 1]);
            }
            total += dc * zone / 4.0;
        }
        total
    }

    /// |[`flux`](Photometry::flux) − stated| / stated, where stated is
    /// [`rated_flux`](Photometry::rated_flux) (the file's lumens times its multipliers), or
    /// `None` when the file states no flux (IES absolute photometry).
    pub fn flux_mismatch(&self) -> Option<f64> {
        let rated = self.rated_flux.filter(|r| *r > 0.0 && r.is_finite())?;
        Some((self.flux() - rated).abs() / rated)
    }

    /// The largest intensity, candela: the largest tabulated value, which the interpolation
    /// never exceeds.
    pub fn max_intensity(&self) -> f64 {
        self.candela.iter().copied().fold(0.0, f64::max)
    }

    /// The intensities of horizontal angle `i` (`c_angles[i]`: a C-plane for type C), one a
    /// vertical angle.
    pub fn plane(&self, i: usize) -> &[f64] {
        let ng = self.gamma_angles.len();
        self.candela
            .get(i * ng..(i + 1) * ng)
            .unwrap_or(&self.candela[..0])
    }
}

/// The integrals ∫ h_k(λ) dλ of the hat functions of the angles `deg` (degrees, increasing)
/// over their range, λ in radians: the trapezoid weights (h_{k−1} + h_k)/2.
fn longitude_weights(deg: &[f64]) -> Vec<f64> {
    let mut w = vec![0.0; deg.len()];
    for k in 0..deg.len().saturating_sub(1) {
        let half = 0.5 * (deg[k + 1] - deg[k]).to_radians();
        w[k] += half;
        w[k + 1] += half;
    }
    w
}

/// The integrals ∫ h_k(φ) cos φ dφ of the hat functions of the latitudes `deg` (degrees,
/// increasing) over their range, in closed form: on a cell [φ₀, φ₁] of width h and middle m,
/// the falling hat gives (cos φ₀ − cos φ₁)/h − sin φ₀ and the rising one
/// sin φ₁ − (cos φ₀ − cos φ₁)/h, with (cos φ₀ − cos φ₁)/h = sin m · sin(h/2)/(h/2) written
/// so that a narrow cell loses no digits. The two add up to sin φ₁ − sin φ₀, the cell's
/// ∫ cos φ dφ.
fn latitude_weights(deg: &[f64]) -> Vec<f64> {
    let mut w = vec![0.0; deg.len()];
    for k in 0..deg.len().saturating_sub(1) {
        let (a, b) = (deg[k].to_radians(), deg[k + 1].to_radians());
        let h = b - a;
        if h <= 0.0 {
            continue;
        }
        let chord = ((a + b) / 2.0).sin() * (h / 2.0).sin() / (h / 2.0);
        w[k] += chord - a.sin();
        w[k + 1] += b.sin() - chord;
    }
    w
}

fn angles_of(dir: [f64; 3]) -> Option<(f64, f64)> {
    let [x, y, z] = dir;
    let len = (x * x + y * y + z * z).sqrt();
    if len == 0.0 || !len.is_finite() {
        return None;
    }
    let gamma = (-z / len).clamp(-1.0, 1.0).acos().to_degrees();
    let c = y.atan2(x).to_degrees().rem_euclid(360.0);
    // rem_euclid can round a tiny negative angle up to 360 itself.
    Some((if c >= 360.0 { 0.0 } else { c }, gamma))
}

/// The interval `[xs[k], xs[k + 1]]` holding `x` (clamped to the ends) and where in it `x` is,
/// 0..=1. `xs` is increasing and not empty.
fn locate(xs: &[f64], x: f64) -> (usize, f64) {
    let n = xs.len();
    if n < 2 {
        return (0, 0.0);
    }
    let k = xs.partition_point(|&v| v <= x).saturating_sub(1).min(n - 2);
    let width = xs[k + 1] - xs[k];
    let t = if width > 0.0 {
        ((x - xs[k]) / width).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (k, t)
}

/// (1 − t)·a + t·b, kept within [min(a, b), max(a, b)] whatever the rounding.
fn lerp(a: f64, b: f64, t: f64) -> f64 {
    ((1.0 - t) * a + t * b).clamp(a.min(b), a.max(b))
}

/// How the stored C-planes cover the circle.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Symmetry {
    /// One plane for all (rotationally symmetric).
    Rotational,
    /// Planes 0..=90, mirrored about C0–C180 and C90–C270.
    Quadrant,
    /// Planes 0..=180, mirrored about the C0–C180 plane: I(C) = I(360° − C).
    AboutC0,
    /// Planes 90..=270, mirrored about the C90–C270 plane: I(C) = I(180° − C).
    AboutC90,
    /// Planes given over the whole circle (type C), or the table as given (types B and A,
    /// whose lateral symmetry the IES reader mirrors itself: [`mirror`]).
    None,
}

/// What a parser hands over to be expanded into a [`Photometry`].
pub(crate) struct Table {
    pub kind: PhotometricType,
    pub symmetry: Symmetry,
    /// The stored planes' C angles (increasing).
    pub c_angles: Vec<f64>,
    /// The γ angles (increasing).
    pub gamma_angles: Vec<f64>,
    /// Stored planes × γ angles, candela (already scaled).
    pub candela: Vec<f64>,
    pub lumens: Option<f64>,
    pub rated_flux: Option<f64>,
    pub opening: Opening,
    pub tilt: Option<Tilt>,
    pub warnings: Vec<String>,
}

impl Table {
    /// Expand a type C table's symmetry to C-planes over 0..=360 (types B and A come whole)
    /// and note a flux mismatch.
    pub(crate) fn into_photometry(self, source: &str) -> Photometry {
        let ng = self.gamma_angles.len();
        let (c_angles, candela) = match self.kind {
            PhotometricType::C => expand(self.symmetry, &self.c_angles, &self.candela, ng),
            PhotometricType::B | PhotometricType::A => (self.c_angles, self.candela),
        };
        let mut photometry = Photometry {
            c_angles,
            gamma_angles: self.gamma_angles,
            candela,
            lumens: self.lumens,
            rated_flux: self.rated_flux,
            kind: self.kind,
            tilt: self.tilt,
            opening: self.opening,
            source: source.to_string(),
            warnings: self.warnings,
        };
        if let (Some(mismatch), Some(rated)) = (photometry.flux_mismatch(), photometry.rated_flux) {
            if mismatch > FLUX_WARNING {
                let flux = photometry.flux();
                photometry.warnings.push(format!(
                    "the table's flux, {flux:.0} lm, differs from the {rated:.0} lm the file \
                     states by {:.1} %",
                    100.0 * mismatch
                ));
            }
        }
        photometry
    }
}

/// The stored planes (`angles`, rows of `ng` values in `rows`) mirrored by `symmetry` onto the
/// whole circle: planes sorted from 0° to 360°, both ends present (equal rows, unless the file
/// gives both 0° and 360°).
fn expand(symmetry: Symmetry, angles: &[f64], rows: &[f64], ng: usize) -> (Vec<f64>, Vec<f64>) {
    // (angle, stored plane) for every image of every stored plane.
    let mut planes: Vec<(f64, usize)> = Vec::with_capacity(4 * angles.len() + 2);
    for (k, &a) in angles.iter().enumerate() {
        match symmetry {
            Symmetry::Rotational => {
                planes.push((0.0, k));
                break;
            }
            Symmetry::Quadrant => {
                planes.extend([(a, k), (180.0 - a, k), (180.0 + a, k), (360.0 - a, k)])
            }
            Symmetry::AboutC0 => planes.extend([(a, k), (360.0 - a, k)]),
            Symmetry::AboutC90 => planes.extend([(a, k), ((180.0 - a).rem_euclid(360.0), k)]),
            Symmetry::None => planes.push((a, k)),
        }
    }
    planes.sort_by(|a, b| a.0.total_cmp(&b.0));
    planes.dedup_by(|later, earlier| (later.0 - earlier.0).abs() <= ANGLE_EPS);
    let row = |k: usize| &rows[k * ng..(k + 1) * ng];
    let mut c_out = Vec::with_capacity(planes.len() + 2);
    let mut out = Vec::with_capacity((planes.len() + 2) * ng);
    let (Some(&(first, kf)), Some(&(last, kl))) = (planes.first(), planes.last()) else {
        return (c_out, out);
    };
    let starts = first.abs() <= ANGLE_EPS;
    let ends = (last - 360.0).abs() <= ANGLE_EPS;
    // The row at 0° (= 360°) where the stored planes leave a gap across it: the planes each
    // side, linearly (the same rule as the interpolation).
    let wrap: Vec<f64> = match (starts, ends) {
        (true, _) => row(kf).to_vec(),
        (false, true) => row(kl).to_vec(),
        (false, false) => {
            let (before, after) = (last - 360.0, first);
            let t = if after > before {
                (0.0 - before) / (after - before)
            } else {
                0.0
            };
            row(kl)
                .iter()
                .zip(row(kf))
                .map(|(&a, &b)| lerp(a, b, t))
                .collect()
        }
    };
    if !starts {
        c_out.push(0.0);
        out.extend_from_slice(&wrap);
    }
    for &(a, k) in &planes {
        c_out.push(a.clamp(0.0, 360.0));
        out.extend_from_slice(row(k));
    }
    if !ends {
        c_out.push(360.0);
        out.extend_from_slice(&wrap);
    }
    (c_out, out)
}

/// The rows of horizontal angles `angles` (from 0, increasing; rows of `ng` values in `rows`)
/// and their mirror images at −H, in increasing order: the lateral symmetry of types B and A.
pub(crate) fn mirror(angles: &[f64], rows: &[f64], ng: usize) -> (Vec<f64>, Vec<f64>) {
    let n = angles.len();
    let mut h = Vec::with_capacity(2 * n);
    let mut out = Vec::with_capacity(2 * n * ng);
    // 0 itself (the first angle) is its own image.
    for k in (1..n).rev() {
        h.push(-angles[k]);
        out.extend_from_slice(&rows[k * ng..(k + 1) * ng]);
    }
    h.extend_from_slice(angles);
    out.extend_from_slice(rows);
    (h, out)
}

/// Lines of a text, numbered from 1: `"\r\n"`, `"\n"` and a lone `"\r"` each end one.
#[derive(Clone)]
pub(crate) struct Lines<'a> {
    rest: &'a str,
    number: usize,
}

impl<'a> Lines<'a> {
    pub(crate) fn new(text: &'a str) -> Self {
        Self {
            rest: text,
            number: 0,
        }
    }

    /// The number of the last line handed out (0 before the first).
    pub(crate) fn number(&self) -> usize {
        self.number
    }
}

impl<'a> Iterator for Lines<'a> {
    type Item = (usize, &'a str);

    fn next(&mut self) -> Option<Self::Item> {
        if self.rest.is_empty() {
            return None;
        }
        self.number += 1;
        let bytes = self.rest.as_bytes();
        let (line, next) = match bytes.iter().position(|&b| b == b'\n' || b == b'\r') {
            Some(i) if bytes[i] == b'\r' && bytes.get(i + 1) == Some(&b'\n') => (i, i + 2),
            Some(i) => (i, i + 1),
            None => (bytes.len(), bytes.len()),
        };
        let out = &self.rest[..line];
        self.rest = &self.rest[next..];
        Some((self.number, out))
    }
}

/// The number of lines of `text` (at least 1), for errors at its end.
pub(crate) fn last_line(text: &str) -> usize {
    Lines::new(text).count().max(1)
}

/// Numbers read in order from [`Words`], each error at its line: the tables of both formats,
/// which differ only in how a word is read as a number (EULUMDAT allows a decimal comma).
pub(crate) struct NumberReader<'a> {
    pub(crate) words: Words<'a>,
    pub(crate) file: &'a str,
    /// The file's last line, where "found the end of the file" is reported.
    pub(crate) end_line: usize,
    /// A word as a number, or the message (`what` names the value).
    pub(crate) parse: fn(&str, &str) -> Result<f64, String>,
}

impl<'a> NumberReader<'a> {
    /// The next word, or an error naming `what` was expected.
    pub(crate) fn word(&mut self, what: &str) -> Result<(usize, &'a str), PhotometryError> {
        self.words.next().ok_or_else(|| {
            invalid(
                self.file,
                self.end_line,
                format!("expected {what}, found the end of the file"),
            )
        })
    }

    /// The next number and its line.
    pub(crate) fn number(&mut self, what: &str) -> Result<(f64, usize), PhotometryError> {
        let (line, word) = self.word(what)?;
        (self.parse)(word, what)
            .map(|v| (v, line))
            .map_err(|m| invalid(self.file, line, m))
    }

    /// The next number, a count of at least `min`.
    pub(crate) fn count(
        &mut self,
        what: &str,
        min: usize,
    ) -> Result<(usize, usize), PhotometryError> {
        let (line, word) = self.word(what)?;
        let value = (self.parse)(word, what).map_err(|m| invalid(self.file, line, m))?;
        count(value, word, what, min)
            .map(|n| (n, line))
            .map_err(|m| invalid(self.file, line, m))
    }

    /// `n` numbers (the caller has checked that `n` words are left), with their lines.
    pub(crate) fn numbers(
        &mut self,
        n: usize,
        what: &str,
    ) -> Result<(Vec<f64>, Vec<usize>), PhotometryError> {
        // No more room than the words left can fill, whatever the count says.
        let room = n.min(self.words.remaining());
        let mut values = Vec::with_capacity(room);
        let mut lines = Vec::with_capacity(room);
        for _ in 0..n {
            let (v, line) = self.number(what)?;
            values.push(v);
            lines.push(line);
        }
        Ok((values, lines))
    }
}

/// Blank- (and, for IES, comma-) separated words of the lines that follow, with their line
/// numbers. Allocates nothing.
#[derive(Clone)]
pub(crate) struct Words<'a> {
    lines: Lines<'a>,
    current: &'a str,
    line: usize,
    commas: bool,
}

impl<'a> Words<'a> {
    pub(crate) fn new(lines: Lines<'a>, commas: bool) -> Self {
        let line = lines.number();
        Self {
            lines,
            current: "",
            line,
            commas,
        }
    }

    fn separator(&self, c: char) -> bool {
        c.is_whitespace() || (self.commas && c == ',')
    }

    /// How many words are left (walks a copy: O(rest of the text)).
    pub(crate) fn remaining(&self) -> usize {
        self.clone().count()
    }
}

impl<'a> Iterator for Words<'a> {
    type Item = (usize, &'a str);

    fn next(&mut self) -> Option<Self::Item> {
        loop {
            let trimmed = self.current.trim_start_matches(|c| self.separator(c));
            if trimmed.is_empty() {
                let (number, line) = self.lines.next()?;
                self.line = number;
                self.current = line;
                continue;
            }
            let end = trimmed.find(|c| self.separator(c)).unwrap_or(trimmed.len());
            self.current = &trimmed[end..];
            return Some((self.line, &trimmed[..end]));
        }
    }
}

/// A word as it may be quoted in a message: at most 24 characters, control characters escaped.
pub(crate) fn shown(word: &str) -> String {
    let mut out: String = word.chars().take(24).flat_map(char::escape_debug).collect();
    if word.chars().count() > 24 {
        out.push('…');
    }
    out
}

/// A finite number, or why not (`what` names the field).
pub(crate) fn number(word: &str, what: &str) -> Result<f64, String> {
    match word.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        Ok(_) => Err(format!("{what} '{}' is not a finite number", shown(word))),
        Err(_) => Err(format!("{what} '{}' is not a number", shown(word))),
    }
}

/// A count: a whole number from `min` to [`MAX_TABLE_VALUES`].
pub(crate) fn count(value: f64, word: &str, what: &str, min: usize) -> Result<usize, String> {
    if value.fract() != 0.0 {
        return Err(format!("{what} '{}' is not a whole number", shown(word)));
    }
    if value < min as f64 {
        return Err(format!("{what} is {value}: at least {min} needed"));
    }
    if value > MAX_TABLE_VALUES as f64 {
        return Err(format!(
            "{what} is {value}: more than {MAX_TABLE_VALUES} is not a photometric table"
        ));
    }
    Ok(value as usize)
}

/// Check that `angles` increase strictly and lie within `lo..=hi`; `lines` are where each
/// was read, `what` names them ("vertical angle").
pub(crate) fn check_angles(
    angles: &[f64],
    lines: &[usize],
    what: &str,
    declared: &str,
    lo: f64,
    hi: f64,
) -> Result<(), (usize, String)> {
    for (k, &a) in angles.iter().enumerate() {
        if a < lo - ANGLE_EPS || a > hi + ANGLE_EPS {
            return Err((
                lines[k],
                format!("{what} {a} is outside {lo}..{hi} degrees"),
            ));
        }
        if k > 0 && a <= angles[k - 1] {
            return Err((
                lines[k],
                format!(
                    "{what} {a} does not increase on the one before, {} ({declared})",
                    angles[k - 1]
                ),
            ));
        }
    }
    Ok(())
}
