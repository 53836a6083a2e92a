//! Glazing: the angular transmittance of a clear pane (issue 58).
//!
//! A pane of refractive index n (1.52 for soda-lime float glass unless a glTF IOR says
//! otherwise) between two air interfaces. For each polarisation j ∈ {s, p} the interface's
//! Fresnel reflectance at incidence θ (refraction angle θ_t, sin θ = n sin θ_t) is
//!
//! ```text
//! r_s = ((cos θ − n cos θ_t) / (cos θ + n cos θ_t))²,
//! r_p = ((n cos θ − cos θ_t) / (n cos θ + cos θ_t))²,
//! ```
//!
//! and the light bouncing between the two faces, a the internal transmittance along the
//! refracted path, a = a₀^(1/cos θ_t), sums to the geometric series
//!
//! ```text
//! T_j = (1 − r_j)² a / (1 − r_j² a²)
//! ```
//!
//! (Born & Wolf, *Principles of Optics*, §1.5; Rubin (1985), "Optical properties of soda lime
//! silica glasses"; the same model as Radiance's `glass` material and the Window program's
//! uncoated panes). The transmittance of unpolarised light is τ(θ) = (T_s + T_p)/2. The
//! normal transmittance τ_n is given; the absorption a₀ is the root of
//! r₀² τ_n a₀² + (1 − r₀)² a₀ − τ_n = 0 (r₀ = ((n − 1)/(n + 1))²), so τ(0) = τ_n exactly.
//! A pane cannot pass more than its non-absorbing value (1 − r₀)/(1 + r₀) (0.9183 at 1.52).
//!
//! The same series gives the pane's (specular) reflectance, the first face's reflection plus
//! what comes back out through it after bouncing inside,
//!
//! ```text
//! R_j = r_j + (1 − r_j)² r_j a² / (1 − r_j² a²),
//! ```
//!
//! and the pane absorbs 1 − τ − R. The diffuse (hemispherical, cosine-weighted) averages
//! τ_d = 2 ∫ τ cos θ sin θ dθ and ρ_d likewise are what a pane passes and returns of diffuse
//! light.

use super::LightingError;

/// The refractive index of soda-lime float glass.
pub const GLASS_INDEX: f64 = 1.52;

/// A clear pane of given normal transmittance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Glazing {
    /// Refractive index.
    pub index: f64,
    /// Internal transmittance at normal incidence, a₀ in (0, 1].
    pub absorption_pass: f64,
    /// Transmittance at normal incidence.
    pub normal: f64,
}

impl Glazing {
    /// A pane of index `index` passing `normal` of normally incident light. Errors: an index
    /// outside (1, 4], a transmittance outside (0, (1 − r₀)/(1 + r₀)].
    pub fn new(normal: f64, index: f64) -> Result<Glazing, LightingError> {
        if !(index > 1.0 && index <= 4.0) {
            return Err(LightingError::Parameter(format!(
                "glazing index {index}: must be in (1, 4]"
            )));
        }
        let r0 = ((index - 1.0) / (index + 1.0)).powi(2);
        let clear = (1.0 - r0) / (1.0 + r0);
        if !(normal > 0.0 && normal <= clear + 1e-12) {
            return Err(LightingError::Parameter(format!(
                "glazing transmittance {normal}: must be in (0, {clear:.4}], what a clear pane of index {index} passes without absorbing"
            )));
        }
        let q = (1.0 - r0) * (1.0 - r0);
        let a0 = if r0 * normal == 0.0 {
            normal / q
        } else {
            let c = r0 * r0 * normal;
            (-q + (q * q + 4.0 * c * normal).sqrt()) / (2.0 * c)
        };
        Ok(Glazing {
            index,
            absorption_pass: a0.min(1.0),
            normal,
        })
    }

    /// At incidence cosine `ci` (0 < ci ≤ 1): the Fresnel reflectances of one interface for
    /// s and p polarisation, and the glass's internal transmittance along the refracted path.
    fn interfaces(&self, ci: f64) -> (f64, f64, f64) {
        let n = self.index;
        let si = (1.0 - ci * ci).max(0.0).sqrt();
        let st = si / n;
        let ct = (1.0 - st * st).max(0.0).sqrt();
        let rs = ((ci - n * ct) / (ci + n * ct)).powi(2);
        let rp = ((n * ci - ct) / (n * ci + ct)).powi(2);
        (rs, rp, self.absorption_pass.powf(1.0 / ct))
    }

    /// The transmittance at incidence angle θ given by its cosine (either side; |cos θ|).
    pub fn transmittance(&self, cos_theta: f64) -> f64 {
        let ci = cos_theta.abs().min(1.0);
        // Grazing: τ → 0 continuously (below 1e-9 the series' 0/0 would only add rounding).
        if ci <= 1e-9 {
            return 0.0;
        }
        let (rs, rp, a) = self.interfaces(ci);
        let t = |r: f64| (1.0 - r) * (1.0 - r) * a / (1.0 - r * r * a * a);
        0.5 * (t(rs) + t(rp))
    }

    /// The (specular) reflectance at incidence angle θ given by its cosine, either side:
    /// ½ Σ_j r_j + (1 − r_j)² r_j a² / (1 − r_j² a²) (the module's series).
    pub fn reflectance(&self, cos_theta: f64) -> f64 {
        let ci = cos_theta.abs().min(1.0);
        if ci <= 1e-9 {
            return 1.0;
        }
        let (rs, rp, a) = self.interfaces(ci);
        let r = |r: f64| r + (1.0 - r) * (1.0 - r) * r * a * a / (1.0 - r * r * a * a);
        0.5 * (r(rs) + r(rp))
    }

    /// The reflectance averaged over a diffuse (cosine-weighted) hemisphere of incidence, ρ_d
    /// (the rule of [`Glazing::diffuse`]).
    pub fn diffuse_reflectance(&self) -> f64 {
        super::sky::gauss_legendre(64)
            .iter()
            .map(|&(x, w)| 0.5 * w * self.reflectance((0.5 * (x + 1.0)).sqrt()))
            .sum()
    }

    /// The transmittance averaged over a diffuse (cosine-weighted) hemisphere of incidence,
    /// 2 ∫ τ(θ) cos θ sin θ dθ (Gauss–Legendre, 64 points in cos² θ).
    pub fn diffuse(&self) -> f64 {
        // With u = cos² θ, 2 cos θ sin θ dθ = du over (0, 1).
        super::sky::gauss_legendre(64)
            .iter()
            .map(|&(x, w)| 0.5 * w * self.transmittance((0.5 * (x + 1.0)).sqrt()))
            .sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The pane's series summed term by term, independently: each polarisation's field
    /// bounces between the faces, transmitted (1 − r) a (r a)^{2k} (1 − r).
    fn series(n: f64, a0: f64, theta: f64) -> f64 {
        let si = theta.sin();
        let tt = (si / n).asin();
        let ct = tt.cos();
        // Fresnel's amplitude coefficients, squared (energy).
        let rs = ((theta - tt).sin() / (theta + tt).sin()).powi(2);
        let rp = ((theta - tt).tan() / (theta + tt).tan()).powi(2);
        let a = a0.powf(1.0 / ct);
        let sum = |r: f64| {
            (0..2000)
                .map(|k| (1.0 - r) * (1.0 - r) * a * (r * a).powi(2 * k))
                .sum::<f64>()
        };
        0.5 * (sum(rs) + sum(rp))
    }

    /// The pane's reflection summed term by term: r, then (1 − r) a (r a)^{2k} r a (1 − r).
    fn reflected_series(n: f64, a0: f64, theta: f64) -> f64 {
        let tt = (theta.sin() / n).asin();
        let rs = ((theta - tt).sin() / (theta + tt).sin()).powi(2);
        let rp = ((theta - tt).tan() / (theta + tt).tan()).powi(2);
        let a = a0.powf(1.0 / tt.cos());
        let sum = |r: f64| {
            r + (0..2000)
                .map(|k| (1.0 - r) * (1.0 - r) * r * a * a * (r * a).powi(2 * k))
                .sum::<f64>()
        };
        0.5 * (sum(rs) + sum(rp))
    }

    /// The reflectance against its series, and the books of a pane: what is not passed or
    /// returned is absorbed, the absorption of each polarisation being the light lost inside,
    /// (1 − r)(1 − a) Σ_k (r a)^k = (1 − r)(1 − a)/(1 − r a) (a third route); a clear pane absorbs nothing.
    #[test]
    fn the_reflectance_is_the_pane_series_and_the_books_close() {
        for tau in [0.918, 0.88, 0.6] {
            let g = Glazing::new(tau, GLASS_INDEX).unwrap();
            for deg in 1..90 {
                let th = (deg as f64).to_radians();
                let (c, n, a0) = (th.cos(), GLASS_INDEX, g.absorption_pass);
                let got = g.reflectance(c);
                let want = reflected_series(n, a0, th);
                assert!((got - want).abs() < 1e-12, "{tau} at {deg}°: {got} {want}");
                let tt = (th.sin() / n).asin();
                let rs = ((th - tt).sin() / (th + tt).sin()).powi(2);
                let rp = ((th - tt).tan() / (th + tt).tan()).powi(2);
                let a = a0.powf(1.0 / tt.cos());
                let lost = |r: f64| (1.0 - r) * (1.0 - a) / (1.0 - r * a);
                let absorbed = 0.5 * (lost(rs) + lost(rp));
                let books = g.transmittance(c) + got + absorbed;
                assert!((books - 1.0).abs() < 1e-12, "{tau} at {deg}°: {books}");
            }
        }
        // Normal incidence of a clear pane: R = 2 r₀/(1 + r₀) = 0.0817.
        let r0: f64 = (0.52f64 / 2.52).powi(2);
        let clear = Glazing::new((1.0 - r0) / (1.0 + r0), GLASS_INDEX).unwrap();
        assert!((clear.reflectance(1.0) - 2.0 * r0 / (1.0 + r0)).abs() < 1e-5);
        let (td, rd) = (clear.diffuse(), clear.diffuse_reflectance());
        assert!((td + rd - 1.0).abs() < 1e-9, "{td} + {rd}");
    }

    /// Against the series (the sin/tan forms of Fresnel's equations, a different route to the
    /// same reflectances) at 0–89°, to 1e-12; the normal transmittance is the one given.
    #[test]
    fn the_angular_transmittance_is_the_pane_series() {
        for tau in [0.9174, 0.88, 0.75, 0.5] {
            let g = Glazing::new(tau, GLASS_INDEX).unwrap();
            assert!((g.transmittance(1.0) - tau).abs() < 1e-12, "{tau}");
            for deg in 1..90 {
                let th = (deg as f64).to_radians();
                let want = series(GLASS_INDEX, g.absorption_pass, th);
                let got = g.transmittance(th.cos());
                assert!((got - want).abs() < 1e-12, "{tau} at {deg}°: {got} {want}");
            }
            assert_eq!(g.transmittance(0.0), 0.0);
        }
    }

    /// Known values of a non-absorbing pane at n = 1.52: r₀ = 0.04258, τ(0) = (1 − r₀)/(1 + r₀)
    /// = 0.91832; at Brewster's angle (atan 1.52 = 56.66°) the p wave passes whole, so
    /// τ = (1 + T_s)/2; it falls monotonically to 0 at grazing incidence.
    #[test]
    fn a_clear_pane_has_the_known_values() {
        let r0: f64 = (0.52f64 / 2.52).powi(2);
        let clear = (1.0 - r0) / (1.0 + r0);
        let g = Glazing::new(clear, GLASS_INDEX).unwrap();
        assert!((g.absorption_pass - 1.0).abs() < 1e-9);
        assert!((clear - 0.918_32).abs() < 1e-5, "{clear}");
        let b = 1.52f64.atan();
        let (ci, si) = (b.cos(), b.sin());
        let ct = (1.0 - (si / 1.52).powi(2)).sqrt();
        let rs = ((ci - 1.52 * ct) / (ci + 1.52 * ct)).powi(2);
        let ts = (1.0 - rs) / (1.0 + rs);
        assert!((g.transmittance(ci) - 0.5 * (1.0 + ts)).abs() < 1e-12);
        let mut last = 1.0;
        for deg in 0..=90 {
            let t = g.transmittance((deg as f64).to_radians().cos());
            assert!(t <= last + 1e-15, "{deg}°");
            last = t;
        }
        assert!(last < 1e-9);
        // Diffuse light passes less than normal light (about 0.85 where a clear pane passes 0.918 at normal incidence).
        let d = g.diffuse();
        assert!(d > 0.80 && d < 0.86, "{d}");
        assert!(Glazing::new(0.95, GLASS_INDEX).is_err());
        assert!(Glazing::new(0.0, GLASS_INDEX).is_err());
    }
}
