//! Spectra to RGB, for the built-in Cornell box whose materials are published as measured
//! spectra (Cornell University Program of Computer Graphics, "Cornell Box Data").
//!
//! The conversion:
//! 1. CIE 1931 2° colour-matching functions x̄, ȳ, z̄ by the multi-lobe Gaussian fit of Wyman,
//!    Sloan and Shirley, "Simple Analytic Approximations to the CIE XYZ Color Matching
//!    Functions", JCGT 2(2), 2013 (their eq. 2; mean error below the variation between
//!    published tables).
//! 2. XYZ = Σ s(λ)·(x̄, ȳ, z̄)(λ)·Δλ over the sampled wavelengths (400–700 nm, trapezoid rule),
//!    under an equal-energy illuminant.
//! 3. Linear sRGB by the IEC 61966-2-1 matrix, then each channel divided by the value for a
//!    perfect white (s ≡ 1): a white-balanced conversion in which a spectrally flat reflectance
//!    or radiance r maps to RGB (r, r, r). Channels that come out negative for saturated colours
//!    are clamped to zero.
//!
//! The same mapping serves reflectances and emitted radiances, so a flat white light on a
//! flat grey wall stays grey, as it would under the white-balanced eye.

use crate::color::Rgb;

fn lobe(x: f64, mu: f64, s1: f64, s2: f64) -> f64 {
    let t = (x - mu) / if x < mu { s1 } else { s2 };
    (-0.5 * t * t).exp()
}

/// CIE 1931 2° colour-matching functions at wavelength `nm` (Wyman et al. 2013 fit).
pub fn cie_xyz(nm: f64) -> [f64; 3] {
    let x = 1.056 * lobe(nm, 599.8, 37.9, 31.0) + 0.362 * lobe(nm, 442.0, 16.0, 26.7)
        - 0.065 * lobe(nm, 501.1, 20.4, 26.2);
    let y = 0.821 * lobe(nm, 568.8, 46.9, 40.5) + 0.286 * lobe(nm, 530.9, 16.3, 31.1);
    let z = 1.217 * lobe(nm, 437.0, 11.8, 36.0) + 0.681 * lobe(nm, 459.0, 26.0, 13.8);
    [x, y, z]
}

fn xyz_to_linear_srgb([x, y, z]: [f64; 3]) -> [f64; 3] {
    [
        3.2406 * x - 1.5372 * y - 0.4986 * z,
        -0.9689 * x + 1.8758 * y + 0.0415 * z,
        0.0557 * x - 0.2040 * y + 1.0570 * z,
    ]
}

/// White-balanced linear RGB of a CIE XYZ triple: linear sRGB (IEC 61966-2-1 matrix) with each
/// channel divided by its value for the equal-energy white X = Y = Z = 1, so that a colour of
/// chromaticity (⅓, ⅓) maps to grey `(Y, Y, Y)`. Channels are not clamped: saturated colours
/// outside the gamut give negative values, which callers clamp.
pub fn xyz_to_rgb(xyz: [f64; 3]) -> Rgb {
    let c = xyz_to_linear_srgb(xyz);
    let w = xyz_to_linear_srgb([1.0; 3]);
    Rgb::new(c[0] / w[0], c[1] / w[1], c[2] / w[2])
}

/// CIE XYZ of a spectrum given at wavelengths `nm` (ascending) by `values`, integrated with the
/// trapezoid rule.
pub fn spectrum_xyz(nm: &[f64], values: &[f64]) -> [f64; 3] {
    let mut xyz = [0.0; 3];
    for k in 0..nm.len() - 1 {
        let h = nm[k + 1] - nm[k];
        for (l, v) in [(nm[k], values[k]), (nm[k + 1], values[k + 1])] {
            let c = cie_xyz(l);
            for a in 0..3 {
                xyz[a] += 0.5 * h * v * c[a];
            }
        }
    }
    xyz
}

/// Unnormalised linear sRGB of a sampled spectrum.
fn raw_rgb(nm: &[f64], values: &[f64]) -> [f64; 3] {
    xyz_to_linear_srgb(spectrum_xyz(nm, values))
}

/// Spectral radiance of a black body at `kelvin`, wavelength `nm`, up to a constant factor
/// (Planck's law).
pub fn planck(nm: f64, kelvin: f64) -> f64 {
    // c₂ = hc/k = 1.4388e7 nm·K.
    let l = nm * 1e-9;
    1.0 / (l.powi(5) * ((1.4388e7 / (nm * kelvin)).exp() - 1.0))
}

/// White-balanced linear RGB of a spectrum sampled at `nm` (see the module docs).
pub fn spectrum_to_rgb(nm: &[f64], values: &[f64]) -> Rgb {
    assert_eq!(nm.len(), values.len());
    assert!(nm.len() >= 2);
    let white = raw_rgb(nm, &vec![1.0; nm.len()]);
    let c = raw_rgb(nm, values);
    Rgb::new(c[0] / white[0], c[1] / white[1], c[2] / white[2]).map(|v| v.max(0.0))
}

/// Wavelengths 400, 404, …, 700 nm (76 samples), the grid of the Cornell reflectance data.
pub fn cornell_wavelengths() -> Vec<f64> {
    (0..76).map(|k| 400.0 + 4.0 * k as f64).collect()
}

/// Piecewise-linear interpolation of `(nm, value)` knots at `x`, constant beyond the ends.
pub fn interpolate(knots: &[(f64, f64)], x: f64) -> f64 {
    if x <= knots[0].0 {
        return knots[0].1;
    }
    for w in knots.windows(2) {
        let ((x0, y0), (x1, y1)) = (w[0], w[1]);
        if x <= x1 {
            return y0 + (y1 - y0) * (x - x0) / (x1 - x0);
        }
    }
    knots[knots.len() - 1].1
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flat_spectrum_is_grey() {
        let nm = cornell_wavelengths();
        let c = spectrum_to_rgb(&nm, &vec![0.5; nm.len()]);
        assert!(c.max_abs_diff(Rgb::splat(0.5)) < 1e-12);
    }

    #[test]
    fn cmf_peaks_where_published() {
        // ȳ peaks near 555 nm at about 1.0; x̄ near 600 nm at about 1.06; z̄ near 445 nm at 1.78.
        let argmax = |a: usize| {
            (380..780)
                .map(|n| (n, cie_xyz(n as f64)[a]))
                .fold((0, f64::MIN), |m, v| if v.1 > m.1 { v } else { m })
        };
        let (ny, vy) = argmax(1);
        assert!(
            (550..=562).contains(&ny) && (vy - 1.0).abs() < 0.03,
            "{ny} {vy}"
        );
        let (nx, vx) = argmax(0);
        assert!(
            (595..=605).contains(&nx) && (vx - 1.06).abs() < 0.04,
            "{nx} {vx}"
        );
        let (nz, vz) = argmax(2);
        assert!(
            (440..=450).contains(&nz) && (vz - 1.78).abs() < 0.06,
            "{nz} {vz}"
        );
    }
}
