//! Final gather over a radiosity solution: per pixel what the mesh cannot hold, the rest from
//! the solution (the two-pass methods of Chen, Rushmeier, Miller & Turner 1991 and Reichert
//! 1992; the final gather of production lightmappers).
//!
//! At the point x a camera ray hits (patch i), the radiance towards the camera is
//!
//! ```text
//! L(x) = E_i/π + ρ_i/π · H_direct(x) + ρ_i · mean over cosine rays of (B(y) − E_s(y))/π
//! ```
//!
//! - `H_direct` is the irradiance of the *sampled* emitters with exact visibility, by points
//!   on them and shadow rays ([`super::light`]): shadows have no mesh bias. An emitter is
//!   sampled when its exitance is brighter than the scene's mean radiosity (luminance, area
//!   weighted); a dimmer one (a glowing wall, every surface of a furnace) fills the hemisphere
//!   rather than a small part of it, so cosine rays find it with less variance than shadow
//!   rays to points on it, and the gather reads its light with the rest. `E_s(y)` is `y`'s
//!   emission if it is sampled, else 0: each emitter is counted by exactly one of the two
//!   terms;
//! - the indirect term gathers, along `indirect` cosine-distributed rays, the light the
//!   solution says the surfaces y send and the direct term has not counted, `B(y) − E_s(y)`,
//!   with `B` interpolated smoothly across each surface (the vertex radiosities of
//!   [`super::vertex_radiosity`]), so the solution's mesh and Monte Carlo noise are averaged
//!   over the hemisphere instead of shown. Where some patches send much more than the mean
//!   (a bright spot), a second strategy draws points on them by power and the two are
//!   combined by multiple importance sampling; where none sends more than
//!   [`FLAT`] times the mean, the cosine rays alone are the better estimator (in a furnace,
//!   whose radiosity is uniform, every ray then returns exactly B and the gather has no
//!   variance);
//! - where a gather ray hits a surface closer than `near` times that patch's size (corners,
//!   contact shadows, where the solution's interpolation is least right), the reflected light
//!   of y is itself estimated one level deeper: its direct light by a shadow ray and its
//!   indirect by one more gather ray into the solution. Both estimate the same quantity, so
//!   this changes the bias, not the mean of what is right.
//!
//! No ambient term: the solution's radiosity is used as solved.

use super::light::{Lights, Surfaces};
use super::{gouraud, render_with, CameraRays, Image, RenderParams};
use crate::accel::Hit;
use crate::color::Rgb;
use crate::geom::{orthonormal_basis, Ray, Vec3};
use crate::observe::Observer;
use crate::sampling::{cosine_direction_in, stream, uniform, Rng64};
use crate::scene::Camera;
use rayon::prelude::*;

/// Samples of the gather.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GatherParams {
    /// Shadow rays to the emitters per camera sample.
    pub direct: u32,
    /// Indirect samples (pairs: one of each strategy) per camera sample when there is no
    /// irradiance cache, or where the cache has no record.
    pub indirect: u32,
    /// A gather ray that hits closer than this many times the square root of the hit patch's
    /// area is followed one level deeper (0: never).
    pub near: f32,
    /// Irradiance cache (Ward, Rubinstein & Clear 1988): the indirect irradiance is gathered at
    /// sparse points with `cache_samples` sample pairs each and interpolated; 0 turns it off
    /// (every camera sample gathers `indirect` pairs itself).
    pub cache_samples: u32,
    /// The cache's accuracy `a`: a record serves points whose Ward weight exceeds 1/a (smaller
    /// is more records, closer together where the geometry is close).
    pub cache_accuracy: f32,
}

impl Default for GatherParams {
    fn default() -> Self {
        Self {
            direct: 4,
            indirect: 16,
            near: 1.0,
            cache_samples: 1024,
            cache_accuracy: 0.1,
        }
    }
}

/// An emitter is sampled by shadow rays when its exitance exceeds this many times the scene's
/// mean radiosity (luminance, area weighted); otherwise the gather reads its light.
pub const SAMPLED_EMITTER: f64 = 1.0;

/// The secondary-source strategy is used when some patch sends more than this many times the
/// mean of what the gather reads (luminance, area weighted): below, the light is flat enough
/// that cosine rays alone have the lower variance.
pub const FLAT: f64 = 1.5;

/// One irradiance-cache record.
#[derive(Clone, Copy, Debug)]
struct Record {
    p: Vec3,
    n: Vec3,
    /// Harmonic mean distance of the record's gather rays (clamped).
    r: f32,
    /// Indirect irradiance.
    h: Rgb,
}

/// Records, found by screen tile: a record is looked up from the pixels within two tiles of
/// the one it was made for.
struct Cache {
    records: Vec<Record>,
    tiles: Vec<Vec<u32>>,
    tiles_x: u32,
    tiles_y: u32,
    a: f32,
}

/// The cache as one camera sample sees it: the cache, the pixel, (sample, samples a pixel).
type CacheAt<'c> = (&'c Cache, (u32, u32), (u32, u32));

/// Screen tile size of the cache's index, pixels (the coarsest record spacing).
const TILE: u32 = 16;

impl Cache {
    fn new(w: u32, h: u32, a: f32) -> Self {
        let (tx, ty) = (w.div_ceil(TILE), h.div_ceil(TILE));
        Self {
            records: Vec::new(),
            tiles: vec![Vec::new(); (tx * ty) as usize],
            tiles_x: tx,
            tiles_y: ty,
            a,
        }
    }

    fn add(&mut self, pixel: (u32, u32), r: Record) {
        let t = (pixel.1 / TILE) * self.tiles_x + pixel.0 / TILE;
        self.tiles[t as usize].push(self.records.len() as u32);
        self.records.push(r);
    }

    /// Ward's weighted mean of the records that serve (x, n), seen from `pixel`; `None` where
    /// none does.
    fn lookup(&self, pixel: (u32, u32), x: Vec3, n: Vec3) -> Option<Rgb> {
        let (tx, ty) = ((pixel.0 / TILE) as i64, (pixel.1 / TILE) as i64);
        let (mut sum, mut wsum) = (Rgb::BLACK, 0.0f64);
        let inv_a = 1.0 / self.a;
        for dy in -1..=1 {
            for dx in -1..=1 {
                let (u, v) = (tx + dx, ty + dy);
                if u < 0 || v < 0 || u >= self.tiles_x as i64 || v >= self.tiles_y as i64 {
                    continue;
                }
                for &k in &self.tiles[(v * self.tiles_x as i64 + u) as usize] {
                    let rec = &self.records[k as usize];
                    let d = x - rec.p;
                    // A record in front of the point does not see what it sees.
                    if d.dot((n + rec.n) * 0.5) < -0.05 * rec.r {
                        continue;
                    }
                    let e = d.length() / rec.r + (1.0 - n.dot(rec.n)).max(0.0).sqrt();
                    let w = 1.0 / e.max(1e-6);
                    if w > inv_a {
                        sum += rec.h * w as f64;
                        wsum += w as f64;
                    }
                }
            }
        }
        (wsum > 0.0).then(|| sum / wsum)
    }
}

/// What the gather reads: the surfaces, the solution's radiosity at the mesh vertices, the
/// emitters.
pub struct Gather<'a> {
    /// Surfaces, emitters.
    pub surfaces: Surfaces<'a>,
    /// Radiosity at each mesh vertex (interpolated within surfaces, no ambient term).
    pub vertex_radiosity: &'a [Rgb],
    lights: Lights,
    /// Whether each patch's emission is sampled by shadow rays (else the gather reads it).
    sampled: Vec<bool>,
    sources: Sources,
    params: GatherParams,
}

/// The solution's reflecting patches as secondary sources, drawn in proportion to the power
/// they reflect, `(B_k − E_k) A_k` (luminance): the second sampling strategy of the gather.
struct Sources {
    patches: Vec<u32>,
    cdf: Vec<f64>,
    /// Probability of drawing each patch (0 for those never drawn), dense.
    prob: Vec<f64>,
}

/// Each patch's mean radiosity from its vertices (what the gather reads, before emission is
/// taken off).
fn patch_radiosity(mesh: &crate::mesh::Mesh, vertex_radiosity: &[Rgb]) -> Vec<Rgb> {
    mesh.patches
        .iter()
        .map(|p| {
            let m = if p.is_triangle() { 3 } else { 4 };
            p.vertices[..m]
                .iter()
                .map(|&v| vertex_radiosity[v as usize])
                .sum::<Rgb>()
                / m as f64
        })
        .collect()
}

impl Sources {
    /// Patches drawn by `B_k − E_s,k` (`sent`), or none where that is flat ([`FLAT`]).
    fn new(mesh: &crate::mesh::Mesh, sent: &[Rgb]) -> Self {
        let mut patches = Vec::new();
        let mut weight = Vec::new();
        let (mut area, mut peak) = (0.0f64, 0.0f64);
        for (k, p) in mesh.patches.iter().enumerate() {
            let l = sent[k].luminance().max(0.0);
            let w = l * p.area as f64;
            area += p.area as f64;
            if w > 0.0 {
                peak = peak.max(l);
                patches.push(k as u32);
                weight.push(w);
            }
        }
        let total: f64 = weight.iter().sum();
        let mut prob = vec![0.0; mesh.len()];
        if peak <= FLAT * total / area.max(f64::MIN_POSITIVE) {
            return Self {
                patches: Vec::new(),
                cdf: Vec::new(),
                prob,
            };
        }
        let mut acc = 0.0;
        let mut cdf = Vec::with_capacity(patches.len());
        for (&k, w) in patches.iter().zip(&weight) {
            let p = w / total;
            prob[k as usize] = p;
            acc += p;
            cdf.push(acc);
        }
        if let Some(last) = cdf.last_mut() {
            *last = 1.0;
        }
        Self { patches, cdf, prob }
    }
}

impl<'a> Gather<'a> {
    /// Prepare a gather over `vertex_radiosity` (e.g. [`super::vertex_radiosity`] of the
    /// solution's radiosity).
    pub fn new(surfaces: Surfaces<'a>, vertex_radiosity: &'a [Rgb], params: GatherParams) -> Self {
        let mesh = surfaces.mesh;
        let b = patch_radiosity(mesh, vertex_radiosity);
        let (mut sum, mut area) = (0.0f64, 0.0f64);
        for (bk, p) in b.iter().zip(&mesh.patches) {
            sum += bk.luminance().max(0.0) * p.area as f64;
            area += p.area as f64;
        }
        let mean = sum / area.max(f64::MIN_POSITIVE);
        let sampled: Vec<bool> = surfaces
            .emission
            .iter()
            .map(|e| {
                e.max_channel() > 0.0
                    && e.luminance().max(e.max_channel() * 1e-3) > SAMPLED_EMITTER * mean
            })
            .collect();
        let lights = Lights::of(mesh, surfaces.emission, |k| sampled[k]);
        let sent: Vec<Rgb> = b
            .iter()
            .zip(surfaces.emission)
            .zip(&sampled)
            .map(|((b, e), &s)| if s { *b - *e } else { *b })
            .collect();
        let sources = Sources::new(mesh, &sent);
        Self {
            surfaces,
            vertex_radiosity,
            lights,
            sampled,
            sources,
            params,
        }
    }

    /// Emitters sampled by shadow rays, and whether the secondary-source strategy is on (for
    /// reports and tests).
    pub fn strategies(&self) -> (usize, bool) {
        (
            self.sampled.iter().filter(|&&s| s).count(),
            !self.sources.patches.is_empty(),
        )
    }

    /// What the gather reads at a ray's hit: `(B(y) − E_s(y))/π`, the radiance the solution
    /// says y sends less the emission the direct term samples.
    fn solution_reflected(&self, hit: &Hit) -> Rgb {
        let b = gouraud(self.surfaces.mesh, self.vertex_radiosity, hit);
        let k = hit.patch as usize;
        let r = if self.sampled[k] {
            b - self.surfaces.emission[k]
        } else {
            b
        };
        Rgb::new(r.r.max(0.0), r.g.max(0.0), r.b.max(0.0)) * std::f64::consts::FRAC_1_PI
    }

    /// One cosine ray from x; the hit, if it is a front side of another patch.
    fn trace(&self, x: Vec3, n: Vec3, own: u32, u: (f32, f32)) -> Option<(Hit, Ray)> {
        let s = &self.surfaces;
        let (t, b) = orthonormal_basis(n);
        let d = cosine_direction_in(n, t, b, u.0, u.1);
        let ray = Ray::new(x + n * s.bvh.ray_offset(), d);
        match s.bvh.closest_hit(&ray, f32::INFINITY) {
            Some(h) if h.front && h.patch != own => Some((h, ray)),
            _ => None,
        }
    }

    /// Whether a hit at distance `t` on patch `k` is near: followed one level deeper and
    /// never drawn as a secondary source.
    fn near(&self, t: f32, k: usize) -> bool {
        self.params.near > 0.0 && t < self.params.near * self.surfaces.mesh.patches[k].area.sqrt()
    }

    /// Solid-angle density of drawing the point y (distance `d`, cosine `cos_y` at the
    /// source) by the secondary-source strategy.
    fn source_density(&self, k: usize, d: f32, cos_y: f32) -> f64 {
        let a = self.surfaces.mesh.patches[k].area as f64;
        self.sources.prob[k] / a * (d as f64 * d as f64) / cos_y.max(1e-12) as f64
    }

    /// Reflected radiance leaving x (normal n, on `patch`), divided by ρ: the emitters'
    /// irradiance over π plus the gathered indirect irradiance over π.
    ///
    /// The indirect irradiance `∫ L_r(y) cos θ dω` is estimated by multiple importance
    /// sampling (Veach & Guibas 1995, balance heuristic) of two strategies with `n` samples
    /// each: cosine-distributed rays, and points on the solution's patches drawn in proportion
    /// to the power they reflect (with a shadow ray), so that a bright spot is found by the
    /// second and a near wall by the first. Near hits (see [`GatherParams::near`]) belong to
    /// the cosine strategy alone and are followed one level deeper.
    fn incoming(&self, x: Vec3, n: Vec3, patch: u32, depth: u32, rng: &mut Rng64) -> Rgb {
        let (nd, ni) = if depth == 0 {
            (self.params.direct.max(1), self.params.indirect)
        } else {
            (1, 1)
        };
        let shift = uniform(rng) as f64;
        let direct = self.direct(x, n, patch, nd, (0, nd, shift), rng);
        let (indirect, _) = self.indirect(x, n, patch, ni, depth, rng);
        (direct + indirect) * std::f64::consts::FRAC_1_PI
    }

    /// The emitters' irradiance at x, `nd` shadow rays; the emitter choice of ray j is
    /// stratified as stratum `first + j` of `strata`, shifted by `shift` (Cranley–Patterson
    /// rotation: unbiased for any shift in [0, 1)).
    #[allow(clippy::too_many_arguments)]
    fn direct(
        &self,
        x: Vec3,
        n: Vec3,
        patch: u32,
        nd: u32,
        (first, strata, shift): (u32, u32, f64),
        rng: &mut Rng64,
    ) -> Rgb {
        let mut direct = Rgb::BLACK;
        for j in 0..nd {
            let u = ((first + j) as f64 + 0.5) / strata.max(1) as f64 + shift;
            let u = u - u.floor();
            direct += self
                .lights
                .irradiance_with(&self.surfaces, x, n, patch, u, rng);
        }
        direct / nd.max(1) as f64
    }

    /// The indirect irradiance at x from `ni` sample pairs, and the harmonic mean distance of
    /// the cosine rays (misses count as infinitely far).
    fn indirect(
        &self,
        x: Vec3,
        n: Vec3,
        patch: u32,
        ni: u32,
        depth: u32,
        rng: &mut Rng64,
    ) -> (Rgb, f32) {
        let s = &self.surfaces;
        let inv_pi = std::f64::consts::FRAC_1_PI;
        let mis = !self.sources.patches.is_empty();
        let mut inv_dist = 0.0f64;
        // Σ f / (p_cos + p_src) over both strategies' samples (irradiance, times n).
        let mut indirect = Rgb::BLACK;
        // Stratified: the cosine rays on a k × k grid of the unit square (k² ≤ ni, the rest
        // random), the sources' choice in ni strata; both shifted at random.
        let k = (ni as f64).sqrt().floor() as u32;
        let (sx, sy, ss) = (uniform(rng), uniform(rng), uniform(rng) as f64);
        for i in 0..ni {
            let u = if i < k * k {
                let gx = ((i % k) as f32 + uniform(rng)) / k as f32 + sx;
                let gy = ((i / k) as f32 + uniform(rng)) / k as f32 + sy;
                (
                    (gx - gx.floor()).min(0.999_999_9),
                    (gy - gy.floor()).min(0.999_999_9),
                )
            } else {
                (uniform(rng), uniform(rng))
            };
            // Strategy 1: a cosine-distributed ray.
            if let Some((h, ray)) = self.trace(x, n, patch, u) {
                inv_dist += 1.0 / h.t.max(1e-12) as f64;
                let k = h.patch as usize;
                let cos_x = n.dot(ray.direction).max(1e-12) as f64;
                let p_cos = cos_x * inv_pi;
                if depth == 0 && self.near(h.t, k) {
                    let y = ray.at(h.t);
                    let rho = s.reflectance[k];
                    // y's own emission, unless the direct term sampled it.
                    let mut l = if self.sampled[k] {
                        Rgb::BLACK
                    } else {
                        s.emission[k] * inv_pi
                    };
                    if rho.max_channel() > 0.0 {
                        l += rho * self.incoming(y, s.mesh.patches[k].normal, h.patch, 1, rng);
                    }
                    indirect += l * (cos_x / p_cos);
                } else {
                    let cos_y = -s.mesh.patches[k].normal.dot(ray.direction);
                    let p_src = if mis {
                        self.source_density(k, h.t, cos_y)
                    } else {
                        0.0
                    };
                    indirect += self.solution_reflected(&h) * (cos_x / (p_cos + p_src));
                }
            }
            // Strategy 2: a point on a reflecting patch.
            if mis {
                let u = (i as f64 + 0.5) / ni as f64 + ss;
                indirect += self.source_sample(x, n, patch, depth, u - u.floor(), rng);
            }
        }
        let h = if ni > 0 {
            indirect / ni as f64
        } else {
            Rgb::BLACK
        };
        let r = if inv_dist > 0.0 {
            (ni as f64 / inv_dist) as f32
        } else {
            f32::INFINITY
        };
        (h, r)
    }

    /// One sample of the secondary-source strategy: `f / (p_cos + p_src)`, or 0.
    fn source_sample(
        &self,
        x: Vec3,
        n: Vec3,
        own: u32,
        depth: u32,
        u: f64,
        rng: &mut Rng64,
    ) -> Rgb {
        let s = &self.surfaces;
        let src = &self.sources;
        let idx = src
            .cdf
            .partition_point(|&c| c <= u)
            .min(src.patches.len() - 1);
        let k = src.patches[idx] as usize;
        let (u1, u2, u3) = (uniform(rng), uniform(rng), uniform(rng));
        if k as u32 == own {
            return Rgb::BLACK;
        }
        let p = &s.mesh.patches[k];
        let y = s.mesh.sample_point(k, u1, u2, u3);
        let d = y - x;
        let dist = d.length();
        if dist <= 0.0 {
            return Rgb::BLACK;
        }
        let w = d / dist;
        let cos_x = n.dot(w);
        let cos_y = -p.normal.dot(w);
        if cos_x <= 0.0 || cos_y <= 0.0 || (depth == 0 && self.near(dist, k)) {
            return Rgb::BLACK;
        }
        let offset = s.bvh.ray_offset();
        let ray = Ray::new(x + n * offset, w);
        if s.bvh.occluded(&ray, dist - 4.0 * offset) {
            return Rgb::BLACK;
        }
        // The sampled point's own interpolated value, with sample_point's triangle choice.
        let (su, sv) = crate::sampling::uniform_triangle(u1, u2);
        let hit = Hit {
            t: dist,
            patch: k as u32,
            sub: u8::from(!(u3 < p.split || p.vertices[3] == crate::mesh::Patch::NONE)),
            u: su,
            v: sv,
            front: true,
        };
        let p_src = self.source_density(k, dist, cos_y);
        let p_cos = cos_x as f64 * std::f64::consts::FRAC_1_PI;
        self.solution_reflected(&hit) * (cos_x as f64 / (p_cos + p_src))
    }

    /// Radiance towards the camera at the hit of a camera ray (every sample gathers).
    pub fn radiance(&self, ray: &Ray, hit: &Hit, rng: &mut Rng64) -> Rgb {
        self.radiance_cached(ray, hit, None, Rgb::BLACK, rng)
    }

    /// [`Gather::radiance`], with the indirect irradiance from `cache` where it has records,
    /// and `extra` added to the irradiance reflected (light the solution does not hold).
    fn radiance_cached(
        &self,
        ray: &Ray,
        hit: &Hit,
        cache: Option<CacheAt<'_>>,
        extra: Rgb,
        rng: &mut Rng64,
    ) -> Rgb {
        let s = &self.surfaces;
        let i = hit.patch as usize;
        let x = ray.at(hit.t);
        let n = s.mesh.patches[i].normal;
        let inv_pi = std::f64::consts::FRAC_1_PI;
        let e = s.emission[i] * inv_pi;
        let rho = s.reflectance[i];
        if rho.max_channel() <= 0.0 {
            return e;
        }
        let cached = cache.and_then(|(c, pixel, _)| c.lookup(pixel, x, n));
        match (cached, cache) {
            (Some(h_ind), Some((_, pixel, (k, spp)))) => {
                // The emitter strata run over all the pixel's samples, shifted per pixel.
                let nd = self.params.direct.max(1);
                let key = crate::sampling::mix64(
                    ((pixel.1 as u64) << 32 | pixel.0 as u64) ^ 0x4c49_4748_5453,
                );
                let shift = (key >> 11) as f64 / (1u64 << 53) as f64;
                let direct = self.direct(x, n, hit.patch, nd, (k * nd, spp * nd, shift), rng);
                e + rho * (direct + h_ind + extra) * inv_pi
            }
            _ => e + rho * (self.incoming(x, n, hit.patch, 0, rng) + extra * inv_pi),
        }
    }

    /// The irradiance at a point `x` with normal `n` that lies on no patch (a sensor in the
    /// air, on a work plane): the emitters' by shadow rays and the solution's reflected light
    /// gathered, as in a camera sample ([`GatherParams::direct`] and
    /// [`GatherParams::indirect`] samples), in the scene's exitance units. One estimate.
    pub fn irradiance_at(&self, x: Vec3, n: Vec3, rng: &mut Rng64) -> Rgb {
        self.incoming(x, n, u32::MAX, 0, rng) * std::f64::consts::PI
    }

    /// The irradiance at a point `x` (normal `n`) on patch `own` (or `u32::MAX` when on
    /// none) in two parts, each in the scene's exitance units: the sampled emitters' by
    /// `direct` shadow rays (their choice stratified, shifted by one draw), and the solution's
    /// reflected light gathered by `indirect` sample pairs, near hits followed one level
    /// deeper, as in a camera sample. `B(x) = E + ρ (direct + indirect)`: how a lightmap texel
    /// is computed ([`crate::bake::lightmap`]). One estimate each; `indirect` 0 gives 0.
    pub fn irradiance_parts(
        &self,
        x: Vec3,
        n: Vec3,
        own: u32,
        (direct, indirect): (u32, u32),
        rng: &mut Rng64,
    ) -> (Rgb, Rgb) {
        let nd = direct.max(1);
        let shift = uniform(rng) as f64;
        let d = self.direct(x, n, own, nd, (0, nd, shift), rng);
        let i = if indirect > 0 {
            self.indirect(x, n, own, indirect, 0, rng).0
        } else {
            Rgb::BLACK
        };
        (d, i)
    }

    /// Radiance leaving point `x` on `patch` (for tests and probes): one gather estimate.
    pub fn radiance_at(&self, x: Vec3, patch: u32, rng: &mut Rng64) -> Rgb {
        let n = self.surfaces.mesh.patches[patch as usize].normal;
        let (ray, hit) = super::arriving(x, n, patch);
        self.radiance(&ray, &hit, rng)
    }

    /// Build the irradiance cache for a view: candidate points at the pixel centres of
    /// successively finer grids (every 16th pixel, then 8th, 4th, 2nd, each), a record made
    /// where the records of the coarser grids do not serve the point. Each level's records are
    /// computed in parallel from streams keyed by pixel and added in pixel order, so the cache
    /// does not depend on the thread count.
    fn build_cache(&self, camera: &Camera, params: &RenderParams) -> Cache {
        let (w, h) = (params.width.max(1), params.height.max(1));
        let rays = CameraRays::new(camera, w, h);
        let s = &self.surfaces;
        let diag = s.bvh.bounds().diagonal();
        let (r_min, r_max) = (diag * 1e-3, diag * 0.25);
        let mut cache = Cache::new(w, h, self.params.cache_accuracy);
        let mut stride = TILE;
        while stride >= 2 {
            let mut candidates = Vec::new();
            for y in (0..h).step_by(stride as usize) {
                for x in (0..w).step_by(stride as usize) {
                    // Skip the points of coarser grids.
                    if stride < TILE && x % (2 * stride) == 0 && y % (2 * stride) == 0 {
                        continue;
                    }
                    candidates.push((x, y));
                }
            }
            let made: Vec<Option<Record>> = candidates
                .par_iter()
                .map(|&(x, y)| {
                    let ray = rays.ray(x as f32 + 0.5, y as f32 + 0.5);
                    let hit = s.bvh.closest_hit(&ray, f32::INFINITY)?;
                    if !hit.front || s.reflectance[hit.patch as usize].max_channel() <= 0.0 {
                        return None;
                    }
                    let p = ray.at(hit.t);
                    let n = s.mesh.patches[hit.patch as usize].normal;
                    if cache.lookup((x, y), p, n).is_some() {
                        return None;
                    }
                    let mut rng = stream(params.seed, 0x4943_4143, y as u64, x as u64);
                    let (h_ind, r) =
                        self.indirect(p, n, hit.patch, self.params.cache_samples, 0, &mut rng);
                    Some(Record {
                        p,
                        n,
                        r: r.clamp(r_min, r_max),
                        h: h_ind,
                    })
                })
                .collect();
            for (&pixel, rec) in candidates.iter().zip(made) {
                if let Some(rec) = rec {
                    cache.add(pixel, rec);
                }
            }
            stride /= 2;
        }
        cache
    }

    /// Render with the gather at every camera sample (the indirect from the irradiance cache
    /// when it is on).
    pub fn render(&self, camera: &Camera, params: &RenderParams, observer: &dyn Observer) -> Image {
        let cache = (self.params.cache_samples > 0).then(|| self.build_cache(camera, params));
        render_with(
            self.surfaces.bvh,
            camera,
            params,
            observer,
            1.0,
            |ray, hit, pixel, sample, rng| {
                let cache = cache.as_ref().map(|c| (c, pixel, sample));
                self.radiance_cached(ray, hit, cache, Rgb::BLACK, rng)
            },
        )
    }

    /// [`Gather::render`] with a white irradiance that the solution does not hold added, at
    /// each camera sample, to what the hit point reflects: L = E/π + ρ (H_gathered +
    /// E_extra)/π. `extra` is called once per image row with the row's front-side hits and
    /// fills their irradiance (in the solution's exitance units), so that it can be computed
    /// in one batch a row: the luminaires' exact direct light
    /// ([`crate::pipeline::LightingSolution::render`]). The camera samples and the gather's
    /// streams are those of [`Gather::render`]: with `extra` 0 the image is the same.
    pub fn render_with_irradiance<P>(
        &self,
        camera: &Camera,
        params: &RenderParams,
        observer: &dyn Observer,
        extra: P,
    ) -> Image
    where
        P: Fn(&[super::SamplePoint], &mut Vec<f64>) + Sync,
    {
        let cache = (self.params.cache_samples > 0).then(|| self.build_cache(camera, params));
        super::render_rows_with(
            self.surfaces.mesh,
            self.surfaces.bvh,
            camera,
            params,
            observer,
            1.0,
            extra,
            |ray, hit, pixel, sample, e, rng| {
                let cache = cache.as_ref().map(|c| (c, pixel, sample));
                self.radiance_cached(ray, hit, cache, Rgb::splat(e), rng)
            },
        )
    }

    /// Records the cache would hold for this view (for reports).
    pub fn cache_records(&self, camera: &Camera, params: &RenderParams) -> usize {
        if self.params.cache_samples == 0 {
            return 0;
        }
        self.build_cache(camera, params).records.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::light::tests::{corner_factor, lamp_over_floor, mean_and_se, Fixture};
    use crate::sampling::stream;

    /// The furnace with its exact solution B = E/(1 − ρ): every surface's exitance E is below
    /// the mean radiosity, so no emitter is sampled and the gather reads their light; the
    /// radiosity is uniform, so no secondary source is drawn; every cosine ray then returns B
    /// and the gather is B/π at every point with no variance (to rounding), and so is every
    /// pixel of its picture, irradiance cache and near hits included.
    #[test]
    fn gather_of_the_furnace_is_exact() {
        let scene = crate::scene::builtin::furnace();
        let f = Fixture::new(&scene, 600);
        let rho = crate::scene::builtin::FURNACE_REFLECTANCE;
        let e = crate::scene::builtin::FURNACE_EMISSION;
        let b = Rgb::new(
            e.r / (1.0 - rho.r),
            e.g / (1.0 - rho.g),
            e.b / (1.0 - rho.b),
        );
        let vertex = vec![b; f.mesh.vertices.len()];
        let g = Gather::new(f.surfaces(), &vertex, GatherParams::default());
        assert_eq!(g.strategies(), (0, false));
        let exact = b * std::f64::consts::FRAC_1_PI;
        let close = |v: Rgb, tol: f64| {
            (v.r - exact.r).abs() <= tol * exact.r
                && (v.g - exact.g).abs() <= tol * exact.g
                && (v.b - exact.b).abs() <= tol * exact.b
        };
        let mut rng = stream(3, 0, 0, 0);
        for i in (0..f.mesh.len()).step_by(7) {
            let x = f.mesh.patches[i].centre;
            for _ in 0..20 {
                let v = g.radiance_at(x, i as u32, &mut rng);
                assert!(close(v, 1e-9), "patch {i}: {v:?} vs {exact:?}");
            }
        }
        let image = g.render(
            &scene.camera.unwrap(),
            &RenderParams {
                width: 48,
                height: 48,
                samples_per_pixel: 4,
                seed: 1,
            },
            &crate::observe::Silent,
        );
        for (k, p) in image.pixels.iter().enumerate() {
            let v = Rgb::new(p[0] as f64, p[1] as f64, p[2] as f64);
            assert!(close(v, 1e-5), "pixel {k}: {v:?} vs {exact:?}");
        }
    }

    /// An irradiance added at every camera sample (a luminaire's direct light) is reflected
    /// as ρ E/π on top of the gather: in the furnace, whose gather is exact, every pixel is
    /// (B + ρ E)/π; with nothing added, the picture is [`Gather::render`]'s bit for bit (the
    /// same camera samples and streams), irradiance cache and near hits included.
    #[test]
    fn an_added_irradiance_is_reflected_once() {
        let scene = crate::scene::builtin::furnace();
        let f = Fixture::new(&scene, 600);
        let rho = crate::scene::builtin::FURNACE_REFLECTANCE;
        let e = crate::scene::builtin::FURNACE_EMISSION;
        let b = Rgb::new(
            e.r / (1.0 - rho.r),
            e.g / (1.0 - rho.g),
            e.b / (1.0 - rho.b),
        );
        let vertex = vec![b; f.mesh.vertices.len()];
        let camera = scene.camera.unwrap();
        let params = RenderParams {
            width: 24,
            height: 24,
            samples_per_pixel: 4,
            seed: 2,
        };
        for cache_samples in [0, 64] {
            let g = Gather::new(
                f.surfaces(),
                &vertex,
                GatherParams {
                    cache_samples,
                    ..Default::default()
                },
            );
            let plain = g.render(&camera, &params, &crate::observe::Silent);
            let none =
                g.render_with_irradiance(&camera, &params, &crate::observe::Silent, |_, _| {});
            assert_eq!(plain, none);
            let extra = 3.0;
            let lit =
                g.render_with_irradiance(&camera, &params, &crate::observe::Silent, |hits, out| {
                    out.extend(hits.iter().map(|_| extra));
                });
            let want = (b + rho * extra) * std::f64::consts::FRAC_1_PI;
            for (k, p) in lit.pixels.iter().enumerate() {
                let v = Rgb::new(p[0] as f64, p[1] as f64, p[2] as f64);
                assert!(
                    v.max_abs_diff(want) < 1e-5 * want.max_channel(),
                    "pixel {k}: {v:?} vs {want:?}"
                );
            }
        }
    }

    /// A dim emitter (exitance below the scene's mean radiosity) is gathered, not sampled, and
    /// its light is still counted once: a lamp of exitance 0.5 over a floor whose radiosity
    /// reads 1 gives the floor's centre ρ/π · E · F (Howell B-3) within 4 standard errors.
    #[test]
    fn a_dim_emitter_is_gathered_once() {
        let f = Fixture::new(&lamp_over_floor(1.0, 0.8, 0.5, 0.5), 400);
        let per_patch: Vec<Rgb> = f
            .system
            .emission
            .iter()
            .map(|e| {
                if e.max_channel() == 0.0 {
                    Rgb::splat(1.0)
                } else {
                    *e
                }
            })
            .collect();
        let vertex = crate::render::vertex_radiosity(&f.mesh, &per_patch);
        let g = Gather::new(f.surfaces(), &vertex, GatherParams::default());
        assert_eq!(g.strategies().0, 0, "the dim lamp is gathered");
        let floor = f.floor();
        let exact = 0.5 / std::f64::consts::PI * 0.5 * 4.0 * corner_factor(0.5, 0.5, 0.8);
        let mut rng = stream(5, 0, 0, 0);
        let (m, se) = mean_and_se(20_000, || g.radiance_at(Vec3::ZERO, floor, &mut rng).g);
        assert!((m - exact).abs() < 4.0 * se, "{m} vs {exact} ± {se}");
    }

    /// A lamp over an open floor: the gather at the floor's centre is ρ/π · E · F (Howell B-3)
    /// within 4 standard errors; nothing indirect reaches it (the lamp is black).
    #[test]
    fn gather_under_a_lamp_matches_the_closed_form() {
        let f = Fixture::new(&lamp_over_floor(1.0, 0.8, 10.0, 0.5), 400);
        // The lamp's radiosity is its emission; the floor's does not matter to its own gather.
        let per_patch: Vec<Rgb> = f
            .system
            .emission
            .iter()
            .map(|e| {
                if e.max_channel() == 0.0 {
                    Rgb::splat(1.0)
                } else {
                    *e
                }
            })
            .collect();
        let vertex = crate::render::vertex_radiosity(&f.mesh, &per_patch);
        let g = Gather::new(f.surfaces(), &vertex, GatherParams::default());
        assert!(g.strategies().0 > 0, "the bright lamp is sampled");
        let floor = f.floor();
        let exact = 0.5 / std::f64::consts::PI * 10.0 * 4.0 * corner_factor(0.5, 0.5, 0.8);
        let mut rng = stream(4, 0, 0, 0);
        let (m, se) = mean_and_se(20_000, || g.radiance_at(Vec3::ZERO, floor, &mut rng).g);
        assert!((m - exact).abs() < 4.0 * se, "{m} vs {exact} ± {se}");
    }
}
