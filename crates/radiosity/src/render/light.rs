//! Direct light with exact visibility: points sampled on the emitting patches and shadow rays,
//! shared by the final gather ([`super::gather`]) and the path tracer ([`super::path`]).
//!
//! The irradiance that the emitters give a point x with normal n is
//! `H(x) = Σ_j ∫_{A_j} (E_j/π) cos θ_x cos θ_y V(x, y) / |x − y|² dA_y`. One sample picks an
//! emitting patch j with probability `p_j` proportional to its emitted power (luminance of
//! `E_j` times `A_j`), a point y uniform on it, and returns
//! `(E_j/π) cos θ_x cos θ_y V / d² · A_j / p_j`: unbiased for `H(x)`.

use crate::accel::Bvh;
use crate::color::Rgb;
use crate::geom::{Ray, Vec3};
use crate::mesh::Mesh;
use crate::sampling::{uniform, Rng64};

/// The emitting patches and the distribution they are drawn from.
#[derive(Clone, Debug, Default)]
pub struct Lights {
    /// Emitting patches.
    patches: Vec<u32>,
    /// Cumulative probabilities (the last is 1).
    cdf: Vec<f64>,
    /// Probability of each.
    pdf: Vec<f64>,
}

/// Per-patch shading data: reflectance and emission.
#[derive(Clone, Copy, Debug)]
pub struct Surfaces<'a> {
    /// The patches.
    pub mesh: &'a Mesh,
    /// Their hierarchy.
    pub bvh: &'a Bvh,
    /// Diffuse reflectance per patch.
    pub reflectance: &'a [Rgb],
    /// Emitted exitance per patch, W/m².
    pub emission: &'a [Rgb],
}

impl Lights {
    /// The emitters of `emission` (patches with any channel above 0), weighted by power.
    pub fn new(mesh: &Mesh, emission: &[Rgb]) -> Self {
        Self::of(mesh, emission, |_| true)
    }

    /// The emitters of `emission` for which `keep(patch)` holds, weighted by power.
    pub fn of(mesh: &Mesh, emission: &[Rgb], keep: impl Fn(usize) -> bool) -> Self {
        let mut patches = Vec::new();
        let mut weight = Vec::new();
        for (i, e) in emission.iter().enumerate() {
            if e.max_channel() > 0.0 && keep(i) {
                patches.push(i as u32);
                // Luminance, but never 0 for a patch that emits in some channel.
                let w = e.luminance().max(e.max_channel() * 1e-3) * mesh.patches[i].area as f64;
                weight.push(w);
            }
        }
        let total: f64 = weight.iter().sum();
        let pdf: Vec<f64> = weight.iter().map(|w| w / total).collect();
        let mut acc = 0.0;
        let mut cdf: Vec<f64> = pdf
            .iter()
            .map(|p| {
                acc += p;
                acc
            })
            .collect();
        if let Some(last) = cdf.last_mut() {
            *last = 1.0;
        }
        Self { patches, cdf, pdf }
    }

    /// True when nothing emits.
    pub fn is_empty(&self) -> bool {
        self.patches.is_empty()
    }

    /// The emitting patch that the uniform `u` in [0, 1) draws, with its probability; `None`
    /// when nothing emits.
    pub fn pick(&self, u: f64) -> Option<(u32, f64)> {
        if self.patches.is_empty() {
            return None;
        }
        let k = self
            .cdf
            .partition_point(|&c| c <= u)
            .min(self.patches.len() - 1);
        Some((self.patches[k], self.pdf[k]))
    }

    /// Every emitting patch with its probability.
    pub fn emitters(&self) -> impl Iterator<Item = (u32, f64)> + '_ {
        self.patches.iter().copied().zip(self.pdf.iter().copied())
    }

    /// One-sample estimate of the irradiance the emitters give point `x` (normal `n`, on patch
    /// `own`, which is skipped: a planar patch does not light itself).
    pub fn irradiance(&self, s: &Surfaces<'_>, x: Vec3, n: Vec3, own: u32, rng: &mut Rng64) -> Rgb {
        let u = uniform(rng) as f64;
        self.irradiance_with(s, x, n, own, u, rng)
    }

    /// [`Lights::irradiance`] with the uniform `u` in [0, 1) that picks the emitting patch
    /// given, so that a caller can stratify it over the samples of a pixel (the patches of an
    /// emitter are in order, so strata of `u` are strata of the emitter).
    pub fn irradiance_with(
        &self,
        s: &Surfaces<'_>,
        x: Vec3,
        n: Vec3,
        own: u32,
        u: f64,
        rng: &mut Rng64,
    ) -> Rgb {
        let Some((j, pdf)) = self.pick(u) else {
            return Rgb::BLACK;
        };
        let (u1, u2, u3) = (uniform(rng), uniform(rng), uniform(rng));
        if j == own {
            return Rgb::BLACK;
        }
        let y = s.mesh.sample_point(j as usize, u1, u2, u3);
        let patch = &s.mesh.patches[j as usize];
        let d = y - x;
        let d2 = d.length_squared();
        if d2 <= 0.0 {
            return Rgb::BLACK;
        }
        let dist = d2.sqrt();
        let w = d / dist;
        let cos_x = n.dot(w);
        let cos_y = -patch.normal.dot(w);
        if cos_x <= 0.0 || cos_y <= 0.0 {
            return Rgb::BLACK;
        }
        let offset = s.bvh.ray_offset();
        let ray = Ray::new(x + n * offset, w);
        // Anything short of the emitter (less the offsets at both ends) blocks it.
        if s.bvh.occluded(&ray, dist - 4.0 * offset) {
            return Rgb::BLACK;
        }
        let g = cos_x as f64 * cos_y as f64 / d2 as f64;
        s.emission[j as usize] * (std::f64::consts::FRAC_1_PI * g * patch.area as f64 / pdf)
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::color::Rgb;
    use crate::mesh::{Mesh, MeshParams};
    use crate::scene::{Material, Polygon, Scene};

    /// An emitting square of side `a` (ρ = 0, exitance `e`), facing down at height `c` over
    /// the centre of a large receiving floor (ρ = `rho`, side 40·a), and nothing else: the
    /// floor's radiance at its centre is ρ/π · e · F, F the differential factor to a parallel
    /// square centred above it (Howell's catalogue B-3, four corner rectangles).
    pub(crate) fn lamp_over_floor(a: f32, c: f32, e: f64, rho: f64) -> Scene {
        let h = a / 2.0;
        let f = 20.0 * a;
        let v = Vec3::new;
        Scene {
            name: "lamp".into(),
            materials: vec![
                Material::emitter("lamp", Rgb::BLACK, Rgb::splat(e)),
                Material::diffuse("floor", Rgb::splat(rho)),
            ],
            polygons: vec![
                Polygon {
                    vertices: vec![v(-h, c, -h), v(h, c, -h), v(h, c, h), v(-h, c, h)],
                    material: 0,
                    line: 0,
                    group: 0,
                },
                Polygon {
                    vertices: vec![v(-f, 0.0, -f), v(-f, 0.0, f), v(f, 0.0, f), v(f, 0.0, -f)],
                    material: 1,
                    line: 0,
                    group: 0,
                },
            ],
            ..Scene::default()
        }
    }

    /// Howell B-3: a differential area and a parallel rectangle a × b at distance c, the area
    /// under one corner.
    pub(crate) fn corner_factor(a: f64, b: f64, c: f64) -> f64 {
        crate::formfactor::closed_form::point_parallel_rectangle(a, b, c)
    }

    /// A scene meshed, with its hierarchy and per-patch materials: what the integrators' tests
    /// shade.
    pub(crate) struct Fixture {
        pub(crate) mesh: Mesh,
        pub(crate) bvh: Bvh,
        pub(crate) system: crate::system::System,
    }

    impl Fixture {
        pub(crate) fn new(scene: &Scene, patches: usize) -> Self {
            let mesh = Mesh::build(scene, MeshParams::Patches(patches)).unwrap();
            let bvh = Bvh::build(&mesh);
            let system = crate::mesh::patch_system(scene, &mesh);
            Self { mesh, bvh, system }
        }

        pub(crate) fn surfaces(&self) -> Surfaces<'_> {
            Surfaces {
                mesh: &self.mesh,
                bvh: &self.bvh,
                reflectance: &self.system.reflectance,
                emission: &self.system.emission,
            }
        }

        pub(crate) fn lights(&self) -> Lights {
            Lights::new(&self.mesh, &self.system.emission)
        }

        /// A patch of the floor (the upward-facing surface of [`lamp_over_floor`]).
        pub(crate) fn floor(&self) -> u32 {
            (0..self.mesh.len())
                .find(|&i| self.mesh.patches[i].normal.y > 0.5)
                .unwrap() as u32
        }
    }

    /// Mean of `n` draws of `f` and its standard error.
    pub(crate) fn mean_and_se(n: usize, mut f: impl FnMut() -> f64) -> (f64, f64) {
        let (mut s1, mut s2) = (0.0, 0.0);
        for _ in 0..n {
            let v = f();
            s1 += v;
            s2 += v * v;
        }
        let m = s1 / n as f64;
        (m, ((s2 / n as f64 - m * m).max(0.0) / n as f64).sqrt())
    }

    /// Next-event estimation is unbiased for the irradiance under a square lamp: E · F with
    /// F from the closed form, within 4 standard errors of the sample mean.
    #[test]
    fn irradiance_under_a_lamp_matches_the_closed_form() {
        let f = Fixture::new(&lamp_over_floor(1.0, 0.8, 10.0, 0.5), 400);
        let (s, lights, floor) = (f.surfaces(), f.lights(), f.floor());
        let exact = 10.0 * 4.0 * corner_factor(0.5, 0.5, 0.8);
        let mut rng = crate::sampling::stream(1, 2, 3, 4);
        let (mean, se) = mean_and_se(200_000, || {
            lights
                .irradiance(&s, Vec3::ZERO, Vec3::Y, floor, &mut rng)
                .g
        });
        assert!((mean - exact).abs() < 4.0 * se, "{mean} vs {exact} ± {se}");
        assert!(se < 0.01 * exact);
    }
}
