//! Sky luminance distributions and the sun, for daylight (issue 58).
//!
//! Directions here are in the **sky frame**: x east, y north, z up (the zenith). A scene's
//! own frame is tied to it by [`SkyFrame`] (its up axis and the direction of north).
//!
//! The skies:
//!
//! - the fifteen **CIE standard general skies** of ISO 15469:2004 / CIE S 011/E:2003: the
//!   luminance of a sky element at zenith angle Z and angular distance χ from the sun, relative
//!   to the zenith's, is
//!
//!   ```text
//!   L(Z, χ) / L_z = f(χ) φ(Z) / (f(Z_s) φ(0)),
//!   φ(Z) = 1 + a exp(b / cos Z)            (gradation; φ(π/2) = 1),
//!   f(χ) = 1 + c [exp(d χ) − exp(d π/2)] + e cos² χ   (scattering indicatrix),
//!   ```
//!
//!   Z_s the sun's zenith angle, with the standard's six gradation groups (a, b) and six
//!   indicatrix groups (c, d, e) combined into the fifteen types of its Table 1
//!   ([`CIE_GENERAL_SKIES`]);
//! - the traditional **CIE overcast sky** (Moon & Spencer 1942; CIE 1955):
//!   L(θ) = L_z (1 + 2 sin θ) / 3, θ the altitude;
//! - a **uniform** sky, L the same everywhere.
//!
//! Each is scaled so that the horizontal illuminance it gives an unobstructed plane,
//! E_h = ∫ L(ω) cos Z dω over the upper hemisphere, is the one asked for
//! ([`Sky::new`]). The integral is computed numerically ([`relative_horizontal_illuminance`]):
//! in polar coordinates about the sun (where the indicatrix's cusp at χ = 0 is smooth),
//! Gauss–Legendre in χ up to the horizon and the trapezoid rule around the sun (the
//! integrand is periodic there, so the rule converges spectrally); to better than 1e-6
//! relative, checked against the closed forms of the uniform (πL) and overcast (7πL_z/9)
//! skies and against an independent quadrature in (Z, azimuth).
//!
//! The **sun** is a disc of 0.533° ([`SUN_DIAMETER_DEG`]) of direct normal illuminance E_n.
//! The **ground** below the horizon is a diffuse plane of reflectance ρ_g lit by the
//! unobstructed sky and sun: its luminance is ρ_g (E_h + E_n sin γ_s) / π.

use std::f64::consts::{FRAC_PI_2, PI, TAU};

use super::LightingError;

/// The sun's apparent diameter, degrees.
pub const SUN_DIAMETER_DEG: f64 = 0.533;

/// The gradation (a, b) and indicatrix (c, d, e) parameters of the fifteen CIE standard
/// general skies, types 1 to 15 (ISO 15469:2004 / CIE S 011/E:2003, Table 1: gradation groups
/// I (4, −0.7), II (1.1, −0.8), III (0, −1), IV (−1, −0.55), V (−1, −0.32), VI (−1, −0.15);
/// indicatrix groups 1 (0, −1, 0), 2 (2, −1.5, 0.15), 3 (5, −2.5, 0.3), 4 (10, −3, 0.45),
/// 5 (16, −3, 0.3), 6 (24, −2.8, 0.15)).
pub const CIE_GENERAL_SKIES: [[f64; 5]; 15] = [
    [4.0, -0.70, 0.0, -1.0, 0.00],
    [4.0, -0.70, 2.0, -1.5, 0.15],
    [1.1, -0.80, 0.0, -1.0, 0.00],
    [1.1, -0.80, 2.0, -1.5, 0.15],
    [0.0, -1.00, 0.0, -1.0, 0.00],
    [0.0, -1.00, 2.0, -1.5, 0.15],
    [0.0, -1.00, 5.0, -2.5, 0.30],
    [0.0, -1.00, 10.0, -3.0, 0.45],
    [-1.0, -0.55, 2.0, -1.5, 0.15],
    [-1.0, -0.55, 5.0, -2.5, 0.30],
    [-1.0, -0.55, 10.0, -3.0, 0.45],
    [-1.0, -0.32, 10.0, -3.0, 0.45],
    [-1.0, -0.32, 16.0, -3.0, 0.30],
    [-1.0, -0.15, 16.0, -3.0, 0.30],
    [-1.0, -0.15, 24.0, -2.8, 0.15],
];

/// A sky luminance distribution.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SkyModel {
    /// CIE standard general sky of this type, 1–15.
    Cie(u8),
    /// The traditional CIE overcast sky, L = L_z (1 + 2 sin θ)/3.
    CieOvercast,
    /// The same luminance everywhere.
    Uniform,
}

impl SkyModel {
    /// Every model's name, as [`SkyModel::parse`] reads them.
    pub const NAMES: [&'static str; 17] = [
        "cie-1",
        "cie-2",
        "cie-3",
        "cie-4",
        "cie-5",
        "cie-6",
        "cie-7",
        "cie-8",
        "cie-9",
        "cie-10",
        "cie-11",
        "cie-12",
        "cie-13",
        "cie-14",
        "cie-15",
        "cie-overcast",
        "uniform",
    ];

    /// `cie-1` … `cie-15`, `cie-overcast` or `uniform`.
    pub fn parse(s: &str) -> Result<SkyModel, LightingError> {
        match s {
            "cie-overcast" => return Ok(SkyModel::CieOvercast),
            "uniform" => return Ok(SkyModel::Uniform),
            _ => {}
        }
        if let Some(k) = s.strip_prefix("cie-").and_then(|k| k.parse::<u8>().ok()) {
            if (1..=15).contains(&k) {
                return Ok(SkyModel::Cie(k));
            }
        }
        Err(LightingError::Parameter(format!(
            "sky '{s}': not one of cie-1 … cie-15, cie-overcast, uniform"
        )))
    }

    /// Whether the distribution depends on where the sun is (the CIE general skies whose
    /// indicatrix is not constant: all but types 1, 3 and 5).
    pub fn needs_sun(self) -> bool {
        match self {
            SkyModel::Cie(k) => {
                let p = CIE_GENERAL_SKIES[k as usize - 1];
                p[2] != 0.0 || p[4] != 0.0
            }
            _ => false,
        }
    }

    /// The luminance relative to the zenith's in the sky-frame unit direction `d` (z up),
    /// with the sun's unit direction `sun` (ignored by skies that do not depend on it);
    /// 0 below the horizon.
    pub fn relative(self, d: [f64; 3], sun: [f64; 3]) -> f64 {
        let cz = d[2];
        if cz <= 0.0 {
            return 0.0;
        }
        match self {
            SkyModel::Uniform => 1.0,
            SkyModel::CieOvercast => (1.0 + 2.0 * cz) / 3.0,
            SkyModel::Cie(k) => {
                let [a, b, c, dd, e] = CIE_GENERAL_SKIES[k as usize - 1];
                let grad = |cos_z: f64| {
                    if cos_z <= 0.0 {
                        1.0
                    } else {
                        1.0 + a * (b / cos_z).exp()
                    }
                };
                let ind = |chi: f64| {
                    1.0 + c * ((dd * chi).exp() - (dd * FRAC_PI_2).exp()) + e * chi.cos().powi(2)
                };
                let cos_chi = (d[0] * sun[0] + d[1] * sun[1] + d[2] * sun[2]).clamp(-1.0, 1.0);
                let zs = sun[2].clamp(-1.0, 1.0).acos();
                ind(cos_chi.acos()) * grad(cz) / (ind(zs) * grad(1.0))
            }
        }
    }
}

/// The unit direction, in the sky frame, of altitude `alt` and azimuth `az` (radians;
/// azimuth clockwise from north seen from above: 0 north, π/2 east).
pub fn direction(alt: f64, az: f64) -> [f64; 3] {
    [az.sin() * alt.cos(), az.cos() * alt.cos(), alt.sin()]
}

/// Gauss–Legendre nodes and weights on [−1, 1] (Newton on the Legendre recurrence).
pub(crate) fn gauss_legendre(n: usize) -> Vec<(f64, f64)> {
    let mut out = Vec::with_capacity(n);
    for i in 0..n {
        let mut x = (PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        let mut dp = 1.0;
        for _ in 0..100 {
            let (mut p0, mut p1) = (1.0, x);
            for k in 2..=n {
                let p2 = ((2 * k - 1) as f64 * x * p1 - (k - 1) as f64 * p0) / k as f64;
                p0 = p1;
                p1 = p2;
            }
            dp = n as f64 * (x * p1 - p0) / (x * x - 1.0);
            let dx = p1 / dp;
            x -= dx;
            if dx.abs() < 1e-16 {
                break;
            }
        }
        out.push((x, 2.0 / ((1.0 - x * x) * dp * dp)));
    }
    out
}

/// ∫ L(ω)/L_z cos Z dω over the upper hemisphere: the unobstructed horizontal illuminance of
/// a sky of unit zenith luminance. In polar coordinates (χ, ψ) about the sun's direction
/// (the zenith for skies that do not depend on it): for each ψ the directions above the
/// horizon are an interval of χ, integrated by composite Gauss–Legendre (8 panels × 16
/// points, with dω = sin χ dχ dψ); ψ by the trapezoid rule over 720 points (periodic).
pub fn relative_horizontal_illuminance(model: SkyModel, sun: [f64; 3]) -> f64 {
    integrate(model, sun, 8, 720)
}

/// The rule of [`relative_horizontal_illuminance`] with `panels` Gauss–Legendre panels of 16
/// points in χ and `m` trapezoid points in ψ.
fn integrate(model: SkyModel, sun: [f64; 3], panels: usize, m: usize) -> f64 {
    let s = if model.needs_sun() {
        sun
    } else {
        [0.0, 0.0, 1.0]
    };
    // A frame (u, v, s) about the sun.
    let (u, v) = {
        let a = if s[2].abs() < 0.9 {
            [0.0, 0.0, 1.0]
        } else {
            [1.0, 0.0, 0.0]
        };
        let cross = |p: [f64; 3], q: [f64; 3]| {
            [
                p[1] * q[2] - p[2] * q[1],
                p[2] * q[0] - p[0] * q[2],
                p[0] * q[1] - p[1] * q[0],
            ]
        };
        let u = cross(a, s);
        let n = (u[0] * u[0] + u[1] * u[1] + u[2] * u[2]).sqrt();
        let u = [u[0] / n, u[1] / n, u[2] / n];
        (u, cross(s, u))
    };
    let gl = gauss_legendre(16);
    let mut total = 0.0;
    for j in 0..m {
        let psi = TAU * j as f64 / m as f64;
        let (sp, cp) = psi.sin_cos();
        let w = cp * u[2] + sp * v[2];
        // z(χ) = s_z cos χ + w sin χ = R cos(χ − δ) > 0 for |χ − δ| < π/2.
        let delta = w.atan2(s[2]);
        let lo = (delta - FRAC_PI_2).max(0.0);
        let hi = (delta + FRAC_PI_2).min(PI);
        if hi <= lo {
            continue;
        }
        let h = (hi - lo) / panels as f64;
        let mut line = 0.0;
        for k in 0..panels {
            let a = lo + h * k as f64;
            for &(x, wt) in &gl {
                let chi = a + 0.5 * h * (x + 1.0);
                let (sc, cc) = chi.sin_cos();
                let d = [
                    cc * s[0] + sc * (cp * u[0] + sp * v[0]),
                    cc * s[1] + sc * (cp * u[1] + sp * v[1]),
                    cc * s[2] + sc * w,
                ];
                line += 0.5 * h * wt * model.relative(d, s) * d[2].max(0.0) * sc;
            }
        }
        total += line;
    }
    total * TAU / m as f64
}

/// Where the sun is: altitude above the horizon and azimuth clockwise from north, degrees.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SunPosition {
    /// Degrees above the horizon, 0–90.
    pub altitude: f64,
    /// Degrees clockwise from north seen from above (90 = east).
    pub azimuth: f64,
}

impl SunPosition {
    /// A checked position: altitude in [0°, 90°], azimuth finite.
    pub fn new(altitude: f64, azimuth: f64) -> Result<Self, LightingError> {
        if !(0.0..=90.0).contains(&altitude) || !azimuth.is_finite() {
            return Err(LightingError::Parameter(format!(
                "sun at altitude {altitude}°, azimuth {azimuth}°: the altitude must be 0–90° and the azimuth finite"
            )));
        }
        Ok(Self { altitude, azimuth })
    }

    /// Its unit direction in the sky frame.
    pub fn direction(&self) -> [f64; 3] {
        direction(self.altitude.to_radians(), self.azimuth.to_radians())
    }
}

/// A sky scaled to its horizontal illuminance, with the sun's position it depends on.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sky {
    /// The distribution.
    pub model: SkyModel,
    /// The sun's direction in the sky frame (the zenith when none was given).
    pub sun: [f64; 3],
    /// The zenith luminance, cd/m² (for a uniform sky its luminance everywhere).
    pub zenith_luminance: f64,
    /// The unobstructed horizontal illuminance it gives, lux.
    pub horizontal_illuminance: f64,
}

impl Sky {
    /// `model` scaled so that an unobstructed horizontal plane receives `illuminance` lux from
    /// it; `sun` is needed by the general skies that depend on it. Errors: a sky that needs
    /// the sun without one, an illuminance that is not finite and ≥ 0.
    pub fn new(
        model: SkyModel,
        sun: Option<SunPosition>,
        illuminance: f64,
    ) -> Result<Sky, LightingError> {
        if !(illuminance.is_finite() && illuminance >= 0.0) {
            return Err(LightingError::Parameter(format!(
                "sky illuminance {illuminance} lx: must be finite and ≥ 0"
            )));
        }
        let sun = match (sun, model.needs_sun()) {
            (Some(s), _) => s.direction(),
            (None, false) => [0.0, 0.0, 1.0],
            (None, true) => {
                return Err(LightingError::Parameter(format!(
                    "sky {}: its luminance depends on the sun's position; give the sun",
                    model.name()
                )))
            }
        };
        let rel = relative_horizontal_illuminance(model, sun);
        Ok(Sky {
            model,
            sun,
            zenith_luminance: illuminance / rel,
            horizontal_illuminance: illuminance,
        })
    }

    /// Luminance, cd/m², in the sky-frame unit direction `d` (0 below the horizon).
    #[inline]
    pub fn luminance(&self, d: [f64; 3]) -> f64 {
        self.zenith_luminance * self.model.relative(d, self.sun)
    }
}

impl SkyModel {
    /// The model's name as [`SkyModel::parse`] reads it.
    pub fn name(self) -> String {
        match self {
            SkyModel::Cie(k) => format!("cie-{k}"),
            SkyModel::CieOvercast => "cie-overcast".into(),
            SkyModel::Uniform => "uniform".into(),
        }
    }
}

/// How a scene's axes sit in the sky frame: its up axis and where north is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SkyFrame {
    /// The scene's up, unit (z-up scenes: +z; y-up: +y).
    pub up: [f64; 3],
    /// The scene's north, unit, perpendicular to `up`.
    pub north: [f64; 3],
    /// East = north × up.
    pub east: [f64; 3],
}

impl SkyFrame {
    /// The frame of a z-up (`y_up` false: north +y, east +x) or y-up (north −z, east +x) scene,
    /// north then turned `north_deg` degrees counter-clockwise seen from above (the convention
    /// of Ladybug Tools' `north`: the angle from the scene's default north to true north).
    pub fn new(y_up: bool, north_deg: f64) -> Result<SkyFrame, LightingError> {
        if !north_deg.is_finite() {
            return Err(LightingError::Parameter(format!(
                "north {north_deg}°: must be finite"
            )));
        }
        let (up, n0, e0) = if y_up {
            ([0.0, 1.0, 0.0], [0.0, 0.0, -1.0], [1.0, 0.0, 0.0])
        } else {
            ([0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0])
        };
        // Counter-clockwise seen from above: north turns towards west (−east).
        let (s, c) = north_deg.to_radians().sin_cos();
        let north = [
            c * n0[0] - s * e0[0],
            c * n0[1] - s * e0[1],
            c * n0[2] - s * e0[2],
        ];
        let east = [
            c * e0[0] + s * n0[0],
            c * e0[1] + s * n0[1],
            c * e0[2] + s * n0[2],
        ];
        Ok(SkyFrame { up, north, east })
    }

    /// A scene direction in the sky frame (east, north, up components).
    #[inline]
    pub fn to_sky(&self, d: [f64; 3]) -> [f64; 3] {
        let dot = |a: [f64; 3]| a[0] * d[0] + a[1] * d[1] + a[2] * d[2];
        [dot(self.east), dot(self.north), dot(self.up)]
    }

    /// A sky-frame direction in the scene's axes.
    #[inline]
    pub fn to_scene(&self, d: [f64; 3]) -> [f64; 3] {
        [
            d[0] * self.east[0] + d[1] * self.north[0] + d[2] * self.up[0],
            d[0] * self.east[1] + d[1] * self.north[1] + d[2] * self.up[1],
            d[0] * self.east[2] + d[1] * self.north[2] + d[2] * self.up[2],
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An independent quadrature of E_h/L_z in (Z, azimuth) with many midpoints, the cusp at
    /// the sun resolved by sheer count: agrees with the sun-centred rule to its own error.
    fn brute(model: SkyModel, sun: [f64; 3], nz: usize, na: usize) -> f64 {
        let mut t = 0.0;
        for i in 0..nz {
            let z = FRAC_PI_2 * (i as f64 + 0.5) / nz as f64;
            for j in 0..na {
                let az = TAU * (j as f64 + 0.5) / na as f64;
                let d = [z.sin() * az.sin(), z.sin() * az.cos(), z.cos()];
                t += model.relative(d, sun) * z.cos() * z.sin();
            }
        }
        t * FRAC_PI_2 / nz as f64 * TAU / na as f64
    }

    /// The closed forms: uniform πL, traditional overcast 7πL_z/9; and CIE types 1, 3, 5
    /// (no sun dependence) in closed form by a 1-D Gauss–Legendre in Z to 1e-12:
    /// 2π ∫ φ(Z)/φ(0) cos Z sin Z dZ.
    #[test]
    fn normalisation_matches_closed_forms() {
        let up = [0.0, 0.0, 1.0];
        let u = relative_horizontal_illuminance(SkyModel::Uniform, up);
        assert!((u - PI).abs() < 1e-9 * PI, "{u}");
        let o = relative_horizontal_illuminance(SkyModel::CieOvercast, up);
        assert!((o - 7.0 * PI / 9.0).abs() < 1e-9, "{o}");
        for k in [1u8, 3, 5] {
            let [a, b, ..] = CIE_GENERAL_SKIES[k as usize - 1];
            let gl = gauss_legendre(64);
            let mut s = 0.0;
            // 16 panels of 64 points over Z in (0, π/2): φ is smooth (its derivatives vanish
            // at the horizon).
            for p in 0..16 {
                let h = FRAC_PI_2 / 16.0;
                for &(x, w) in &gl {
                    let z = h * p as f64 + 0.5 * h * (x + 1.0);
                    s += 0.5 * h * w * (1.0 + a * (b / z.cos()).exp()) * z.cos() * z.sin();
                }
            }
            let want = TAU * s / (1.0 + a * b.exp());
            let got = relative_horizontal_illuminance(SkyModel::Cie(k), up);
            assert!((got - want).abs() < 1e-9 * want, "cie-{k}: {got} {want}");
        }
    }

    /// Every general sky, the sun at three altitudes: the rule agrees with itself at twice the
    /// panels and points to 1e-8 (so its own error is far below 1e-6), and with an
    /// independent midpoint rule in (Z, azimuth) of 800 × 1,600 points to that rule's error
    /// (the cusp at the sun and the horizon cost it about 1e-5).
    #[test]
    fn normalisation_of_every_general_sky() {
        for k in 1..=15u8 {
            for alt in [5.0f64, 35.0, 80.0] {
                let sun = direction(alt.to_radians(), 1.0);
                let m = SkyModel::Cie(k);
                let got = relative_horizontal_illuminance(m, sun);
                let fine = integrate(m, sun, 16, 1440);
                assert!(
                    (got - fine).abs() < 1e-8 * fine,
                    "cie-{k} sun {alt}°: {got} {fine}"
                );
                let want = brute(m, sun, 800, 1600);
                assert!(
                    (got - want).abs() < 2e-5 * want,
                    "cie-{k} sun {alt}°: {got} {want}"
                );
                // Azimuth does not change E_h (the sky turns with the sun).
                let turned = relative_horizontal_illuminance(m, direction(alt.to_radians(), 2.3));
                assert!((turned - got).abs() < 1e-9 * got, "cie-{k}: {turned} {got}");
            }
        }
    }

    /// The scaled sky gives back its horizontal illuminance; its zenith is L_z.
    #[test]
    fn a_sky_is_scaled_to_its_illuminance() {
        let s = Sky::new(SkyModel::CieOvercast, None, 10_000.0).unwrap();
        assert!((s.zenith_luminance - 10_000.0 * 9.0 / (7.0 * PI)).abs() < 1e-6);
        assert!((s.luminance([0.0, 0.0, 1.0]) - s.zenith_luminance).abs() < 1e-9);
        assert!(
            (s.luminance(direction(1e-9, 0.0)) - s.zenith_luminance / 3.0).abs()
                < 1e-8 * s.zenith_luminance,
            "the horizon is a third of the zenith"
        );
        assert!(Sky::new(SkyModel::Cie(12), None, 1.0).is_err());
        let sun = SunPosition::new(40.0, 180.0).unwrap();
        let c = Sky::new(SkyModel::Cie(12), Some(sun), 20_000.0).unwrap();
        // At the zenith the relative luminance is 1 by definition.
        assert!((c.luminance([0.0, 0.0, 1.0]) - c.zenith_luminance).abs() < 1e-9);
        assert!(SunPosition::new(-1.0, 0.0).is_err());
        assert!(SkyModel::parse("cie-16").is_err());
        assert_eq!(SkyModel::parse("cie-7").unwrap(), SkyModel::Cie(7));
    }

    /// North +y and east +x in a z-up scene; north −z in a y-up one; turning north by 90°
    /// counter-clockwise puts it on −x.
    #[test]
    fn the_frame_turns_north() {
        let z = SkyFrame::new(false, 0.0).unwrap();
        assert_eq!(z.to_sky([0.0, 1.0, 0.0]), [0.0, 1.0, 0.0]);
        let y = SkyFrame::new(true, 0.0).unwrap();
        assert_eq!(y.to_sky([0.0, 0.0, -1.0]), [0.0, 1.0, 0.0]);
        assert_eq!(y.to_sky([0.0, 1.0, 0.0]), [0.0, 0.0, 1.0]);
        let t = SkyFrame::new(false, 90.0).unwrap();
        let n = t.to_sky([-1.0, 0.0, 0.0]);
        assert!((n[1] - 1.0).abs() < 1e-12, "{n:?}");
        let back = t.to_scene(t.to_sky([0.3, -0.2, 0.9]));
        assert!((back[0] - 0.3).abs() < 1e-12 && (back[2] - 0.9).abs() < 1e-12);
    }
}
