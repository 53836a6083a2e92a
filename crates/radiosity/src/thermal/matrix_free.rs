//! The net-radiation equations solved without storing F: stochastic Jacobi iteration on the
//! radiosities J, each sweep gathering every patch's irradiation with rays from the BVH.
//!
//! The equations are [the stored solve's](super), with the irradiation an integral over the
//! hemisphere instead of a row of F:
//!
//! ```text
//! J_i = ε_i σT_i⁴ + (1 − ε_i) H_i      prescribed temperature
//! J_i = q_i + H_i                      prescribed flux (adiabatic: q = 0)
//! H_i = Σ_j F_ij J_j + F_ie σT_e⁴ = (1/π) ∫ J(ω) cos θ dω,
//! ```
//!
//! J(ω) the radiosity of the patch met first along ω, or σT_e⁴ of the surroundings where the ray
//! meets nothing (or a back side, as the Monte Carlo form factors count it).
//!
//! **Why stochastic iteration** (Neumann, Feda, Kopp & Purgathofer, "A new stochastic radiosity
//! method for highly complex scenes", EGWR 1994; Bekaert, *Hierarchical and stochastic
//! algorithms for radiosity*, PhD thesis, KU Leuven 1999, ch. 4–5; Szirmay-Kalos, "Stochastic
//! iteration for non-diffuse global illumination", Eurographics 1999). Each Jacobi sweep
//! `J ← e + D H(J)` needs only the previous J and a ray caster: memory O(N) (a dozen numbers a
//! patch besides the mesh and BVH), time O(rays · log N), and the expected sweep is the exact
//! Jacobi sweep, so the iterates converge (at the rate ρ(DK) of the stored Jacobi solver) to the
//! exact solution plus zero-mean noise. Hierarchical radiosity (Hanrahan, Salzman & Aupperle,
//! SIGGRAPH 1991) would also avoid N² storage, but its links need a visibility estimate per
//! link and an error bound on the kernel that is loose for the narrow street canyons and
//! grazing pairs of urban scenes; the stochastic sweep needs neither, its error is measured
//! rather than bounded, and each patch's own error is what a thermal engineer asks for.
//!
//! **Gathering, not shooting.** The irradiation of a patch is estimated by `n` rays from it
//! (Bekaert's "regular gathering"): its error is then of the patch's own making, σ_i/√n, with
//! σ_i the spread of the radiosities it sees. Shooting (power-proportional rays, the lighting
//! solver's incremental stochastic Jacobi) spends rays where power is, which leaves the many
//! patches that receive little with a few hits each. The `n = s²` rays of a patch are
//! stratified: the point on the patch in an s × s grid of jittered cells, the direction in an
//! s × s grid of jittered cells of Malley's map (equal cosine-weighted solid angle), the two
//! grids paired by a random permutation. For radiosity constant over each patch the error then
//! comes from the cells an outline crosses, falling faster than 1/√n.
//!
//! **Schedule and error.** Sweeps with `sweep_rays` a patch from `J⁰ = e + D σT_e⁴` (every
//! patch seeing the surroundings) until the estimated remaining bias of the area-weighted mean
//! radiosity, δ_k ρ̂/(1 − ρ̂) with δ_k = |Σ A_i (J_i^k − J_i^{k−1})| and ρ̂ the contraction over
//! the last three sweeps, falls below `tolerance` of Σ A_i |J_i|, or stops decreasing (the
//! noise floor). The slowest mode of the non-negative D K has a non-negative eigenvector
//! (Perron–Frobenius), so it shows whole in this area-weighted sum, where the noise of N
//! patches averages out. Then `batches` independent batches, each `batch_sweeps` sweeps from
//! that common start with streams of its own, the next-to-last gathering `carry_rays` at
//! every patch (the radiosities the last sweep gathers from: their noise is carried into
//! every flux, and no ray of the last sweep reduces it), the last gathering `flux_rays` at
//! each patch of prescribed temperature (whose flux is the answer) and `temperature_rays` at
//! the others (whose temperature is); the result is
//! the mean of the batches and its **standard error** (of every patch's flux and temperature,
//! of each boundary's power, of the energy balance) the batches' sample standard deviation
//! over √batches. What it leaves out: the common start's own noise, which reaches a batch's
//! result only after `batch_sweeps` sweeps, each damping it by D K and averaging it over the
//! many patches a patch sees; and the start's remaining bias (below `tolerance`, damped the
//! same way).
//!
//! **The adaptive stage** (`flux_error`, default 1 % of the mean |flux| of the patches at a
//! prescribed temperature). On the city, the patches' reported errors spread from half to
//! more than twice their mean, but two seeds' reports correlate at only about 0.1 patch by
//! patch: the spread is the estimate's own noise (the standard deviation of 8 batches is
//! uncertain by a quarter, and the largest of 10⁵ such estimates is twice the mean), not
//! patches that are harder than others. Raising every patch's rays until the worst estimate
//! is below the target would cost about four times the rays; the adaptive stage instead gives
//! more rays to the patches whose estimate is above the target, **within every batch**: the
//! patch gathers `m` more stratified rays from each batch's own radiosities with streams of
//! that batch, and the batch's irradiation becomes the mean over all the batch's rays. The
//! batches stay independent and alike, so their spread is still the error. Choosing a patch
//! by the batches' spread does not bias its mean (for nearly normal batch means, the sample
//! mean and the sample variance are independent), and the re-estimated spread of a chosen
//! patch still holds the old rays' share, which the choice made large: the report errs on
//! the high side there. Rounds repeat (at most 4) while estimates remain above the target; a
//! patch's rays grow at most fourfold a round and to 64 times the flux rays in all, past
//! which what is left is the noise carried in the radiosities it gathers from (those are
//! reported as left above). Why not importance sampling toward the hot or cold parts of the
//! hemisphere: it needs to know where they are, and the errors are spread evenly over the
//! patches rather than concentrated where the hemisphere is split.
//!
//! **Energy books.** The power lost to the surroundings is estimated from the same rays as the
//! irradiation: `Σ_i A_i F̂_ie (J_i − σT_e⁴)`, F̂_ie the share of patch i's final rays in a
//! batch that met nothing, taken with the mean J of the *other* batches (a batch's own J is
//! correlated with its shares: a patch that lost more rays gathered less). Σ A_i q_i equals it
//! in expectation (by reciprocity, Σ_i A_i F_ij = A_j (1 − F_je)) once the iteration has
//! converged, not to rounding as in the stored solve, whose irradiation goes through Fᵀ: the
//! difference is the Monte Carlo error of the sums (reported with its standard error) plus
//! Σ A_j (1 − F_je)(J_j − J_j^prev), what the last sweep still moved.
//!
//! **Determinism.** Every patch's rays come from a stream keyed by (seed, batch, sweep,
//! patch); every sum over patches is taken in patch order. The result is the same bits for
//! any number of threads.

use super::{
    Condition, ThermalError, ThermalInfo, ThermalSolution, ThermalSystem, STEFAN_BOLTZMANN,
};
use crate::accel::{Bvh, Hit};
use crate::geom::{orthonormal_basis, Ray};
use crate::mesh::Mesh;
use crate::sampling::{cosine_direction_in, stream, uniform, Rng64};
use rand::Rng;
use rayon::prelude::*;

/// Most rays a patch gathers in one sweep (`s²` with s ≤ 1024).
pub const MAX_RAYS: u32 = 1 << 20;

/// Rays cast together by one thread.
const CAST: usize = 64;

/// Parameters of the matrix-free solve.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MatrixFreeParams {
    /// Rays each patch at a prescribed temperature (whose flux is computed) gathers in the
    /// last sweep of a batch (rounded up to a square).
    pub flux_rays: u32,
    /// Rays each other patch (prescribed flux or adiabatic: its temperature is computed)
    /// gathers in the last sweep of a batch (rounded up to a square).
    pub temperature_rays: u32,
    /// Rays each patch gathers in the other sweeps (rounded up to a square).
    pub sweep_rays: u32,
    /// Rays each patch gathers in the next-to-last sweep of a batch (rounded up to a
    /// square): the radiosities the last sweep gathers from, whose noise is carried into
    /// every flux and which no ray of the last sweep can reduce.
    pub carry_rays: u32,
    /// Independent batches (at least 2: their spread is the standard error).
    pub batches: u32,
    /// Sweeps of each batch from the common start (at least 1).
    pub batch_sweeps: u32,
    /// Most sweeps before the batches.
    pub max_sweeps: u32,
    /// Remaining bias of the area-weighted mean radiosity, relative, at which the common
    /// sweeps stop.
    pub tolerance: f64,
    /// Per-patch flux error wanted, relative to the mean |flux| of the patches at a
    /// prescribed temperature: patches whose standard error is above it after the batches
    /// gather more rays in the adaptive stage (see [the module](self)); 0: no adaptive stage.
    pub flux_error: f64,
    /// Seed of every random stream.
    pub seed: u64,
}

impl Default for MatrixFreeParams {
    fn default() -> Self {
        Self {
            flux_rays: 400,
            temperature_rays: 64,
            sweep_rays: 16,
            carry_rays: 64,
            batches: 8,
            batch_sweeps: 3,
            max_sweeps: 400,
            tolerance: 1e-4,
            flux_error: 0.01,
            seed: 1,
        }
    }
}

impl MatrixFreeParams {
    /// Check the ranges; the message names the parameter.
    pub fn validate(&self) -> Result<(), String> {
        for (what, n) in [
            ("flux rays", self.flux_rays),
            ("temperature rays", self.temperature_rays),
            ("carry rays", self.carry_rays),
        ] {
            if !(1..=MAX_RAYS).contains(&n) {
                return Err(format!("{what} {n}: give 1 to {MAX_RAYS}"));
            }
        }
        if !(1..=MAX_RAYS).contains(&self.sweep_rays) {
            return Err(format!(
                "sweep rays {}: give 1 to {MAX_RAYS}",
                self.sweep_rays
            ));
        }
        if !(2..=4096).contains(&self.batches) {
            return Err(format!("batches {}: give 2 to 4096", self.batches));
        }
        if !(1..=1000).contains(&self.batch_sweeps) {
            return Err(format!(
                "sweeps a batch {}: give 1 to 1000",
                self.batch_sweeps
            ));
        }
        if self.max_sweeps > 100_000 {
            return Err(format!(
                "most sweeps {}: give at most 100000",
                self.max_sweeps
            ));
        }
        if !(self.tolerance > 0.0 && self.tolerance < 1.0) {
            return Err(format!("tolerance {}: give (0, 1)", self.tolerance));
        }
        if !(self.flux_error >= 0.0 && self.flux_error < 1.0) {
            return Err(format!(
                "flux error {}: give [0, 1) (0: no adaptive stage)",
                self.flux_error
            ));
        }
        Ok(())
    }

    /// The side s of the s × s stratified rays for `n` rays.
    fn side(n: u32) -> u32 {
        let mut s = (n as f64).sqrt() as u32;
        while s * s < n {
            s += 1;
        }
        s.max(1)
    }
}

/// What the matrix-free solve did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MatrixFreeInfo {
    /// Sweeps before the batches.
    pub sweeps: usize,
    /// Independent batches.
    pub batches: usize,
    /// Sweeps of each batch.
    pub batch_sweeps: usize,
    /// Rays a patch at a prescribed temperature gathered in each batch's last sweep (a square).
    pub flux_rays: u32,
    /// Rays any other patch gathered in each batch's last sweep (a square).
    pub temperature_rays: u32,
    /// Rays a patch gathered in the other sweeps (a square).
    pub sweep_rays: u32,
    /// Rays cast in all.
    pub rays_cast: u64,
    /// Contraction ρ̂ of the common sweeps (the last three's mean ratio of δ).
    pub contraction: f64,
    /// Estimated remaining bias of the area-weighted mean radiosity when the common sweeps
    /// stopped, relative to Σ A |J|.
    pub remaining_bias: f64,
    /// Standard error of Σ A_i q_i, W.
    pub total_power_std_error: f64,
    /// Standard error of Σ A_i q_i − the power lost to the surroundings, W.
    pub balance_std_error: f64,
    /// The adaptive stage's per-patch flux target (one standard error), W/m²: the requested
    /// share of the mean |flux| of the patches at a prescribed temperature; 0 when off.
    pub flux_target: f64,
    /// Rounds of the adaptive stage that gathered more rays.
    pub refine_rounds: usize,
    /// Patches that gathered more rays in the adaptive stage.
    pub refined_patches: usize,
    /// Rays the adaptive stage cast (all batches).
    pub refine_rays: u64,
    /// Most rays any patch gathered in a batch's last sweep, the adaptive stage's included.
    pub most_flux_rays: u32,
    /// Patches at a prescribed temperature left above the target (at the ray cap or after
    /// the last round).
    pub above_target: usize,
}

/// The patches' fixed parts: `J = e + d H`.
struct Parts {
    e: Vec<f64>,
    d: Vec<f64>,
}

fn parts(system: &ThermalSystem) -> Parts {
    let n = system.area.len();
    let mut e = vec![0.0; n];
    let mut d = vec![0.0; n];
    for i in 0..n {
        let b = system.boundaries[system.group[i] as usize];
        match b.condition {
            Condition::Temperature(t) => {
                e[i] = b.emissivity * STEFAN_BOLTZMANN * t.powi(4);
                d[i] = 1.0 - b.emissivity;
            }
            Condition::Flux(q) => {
                e[i] = q;
                d[i] = 1.0;
            }
            Condition::Adiabatic => {
                e[i] = 0.0;
                d[i] = 1.0;
            }
        }
    }
    Parts { e, d }
}

/// One sweep's gathering: every patch's irradiation from `j` and the share of its rays that
/// met nothing.
struct Gather<'a> {
    mesh: &'a Mesh,
    bvh: &'a Bvh,
    closed: bool,
    sigma_te4: f64,
    seed: u64,
}

impl Gather<'_> {
    /// `(H_i, lost share)` of every patch from `j`, `s(i)²` rays a patch i from the streams
    /// tagged `tag`, into `h` and `lost`.
    fn sweep(
        &self,
        j: &[f64],
        s: &(dyn Fn(usize) -> u32 + Sync),
        tag: u64,
        h: &mut [f64],
        lost: &mut [f64],
    ) {
        h.par_iter_mut()
            .zip(lost.par_iter_mut())
            .enumerate()
            .with_min_len(64)
            .for_each_init(
                || {
                    (
                        Vec::<u32>::new(),
                        Vec::<Ray>::new(),
                        Vec::<Option<Hit>>::new(),
                    )
                },
                |(perm, rays, hits), (i, (h, lost))| {
                    (*h, *lost) = self.patch(i, j, s(i), tag, perm, rays, hits);
                },
            );
    }

    /// Patch i's gathering: `s²` stratified rays.
    #[allow(clippy::too_many_arguments)]
    fn patch(
        &self,
        i: usize,
        j: &[f64],
        s: u32,
        tag: u64,
        perm: &mut Vec<u32>,
        rays: &mut Vec<Ray>,
        hits: &mut Vec<Option<Hit>>,
    ) -> (f64, f64) {
        let mut rng: Rng64 = stream(self.seed, tag, i as u64, 0x7e4a);
        let n = (s * s) as usize;
        // Direction cells, paired with the point cells by a random permutation.
        perm.clear();
        perm.extend(0..n as u32);
        for k in (1..n).rev() {
            let r = rng.random_range(0..=k);
            perm.swap(k, r);
        }
        let normal = self.mesh.patches[i].normal;
        let (t, b) = orthonormal_basis(normal);
        let offset = self.bvh.ray_offset();
        let inv = 1.0 / s as f32;
        let (mut sum, mut hit_count, mut lost_count) = (0.0f64, 0u32, 0u32);
        rays.resize(CAST, Ray::new(normal, normal));
        hits.resize(CAST, None);
        let mut k = 0;
        while k < n {
            let m = (n - k).min(CAST);
            for (c, ray) in rays[..m].iter_mut().enumerate() {
                let cell = (k + c) as u32;
                let (pu, pv) = (
                    ((cell % s) as f32 + uniform(&mut rng)) * inv,
                    ((cell / s) as f32 + uniform(&mut rng)) * inv,
                );
                let p = self.mesh.sample_point(i, pu, pv, uniform(&mut rng));
                let dcell = perm[k + c];
                let (du, dv) = (
                    ((dcell % s) as f32 + uniform(&mut rng)) * inv,
                    ((dcell / s) as f32 + uniform(&mut rng)) * inv,
                );
                let d = cosine_direction_in(normal, t, b, du.min(1.0), dv.min(1.0));
                *ray = Ray::new(p + normal * offset, d);
            }
            self.bvh
                .closest_hits(&rays[..m], f32::INFINITY, &mut hits[..m]);
            for h in &hits[..m] {
                match h {
                    Some(h) if h.front && h.patch as usize != i => {
                        sum += j[h.patch as usize];
                        hit_count += 1;
                    }
                    _ => lost_count += 1,
                }
            }
            k += m;
        }
        if self.closed {
            // A closed enclosure: rays lost through cracks are rounding, not openings; the
            // irradiation is the mean over the rays that met a surface.
            let h = if hit_count > 0 {
                sum / hit_count as f64
            } else {
                0.0
            };
            (h, 0.0)
        } else {
            let lost = lost_count as f64 / n as f64;
            ((sum + lost_count as f64 * self.sigma_te4) / n as f64, lost)
        }
    }
}

/// Most rounds of the adaptive stage.
const REFINE_ROUNDS: usize = 4;

/// The adaptive stage aims a patch it refines at this share of the target, so that the
/// re-estimated error (itself uncertain by a quarter with 8 batches) lands below the target
/// without another round.
const REFINE_AIM: f64 = 0.7;

/// Most growth of a patch's rays in one round of the adaptive stage: an error estimate far
/// above the others is more likely the estimate's own noise than the patch's.
const REFINE_GROWTH: f64 = 4.0;

/// Most rays the adaptive stage gives a patch, as a multiple of the flux rays: past it, what
/// is left of a patch's error is the noise carried in the radiosities it gathers from, which
/// its own rays do not reduce.
const REFINE_MOST: u32 = 64;

/// What the adaptive stage did.
#[derive(Clone, Copy, Debug, Default)]
struct Refinement {
    /// The per-patch flux target, W/m².
    target: f64,
    rounds: usize,
    patches: usize,
    rays: u64,
    /// Patches at a prescribed temperature still above the target at the end.
    above: usize,
}

/// The adaptive stage: rounds in which every patch at a prescribed temperature whose flux
/// standard error (the spread of the batches over √batches) is above the target
/// `params.flux_error` × (mean |flux| of those patches) gathers `m` more stratified rays in
/// **every** batch, from that batch's radiosities `from_of[b]` and with streams of that batch
/// and round, so the batches stay independent and identically distributed and their spread
/// stays the error. The batch's irradiation and lost share become the ray-weighted means of
/// the old and new estimates (`(c h + m h')/(c + m)`, c the rays so far: the mean of all the
/// batch's rays). `m` aims the patch's error at [`REFINE_AIM`] of the target assuming the
/// error falls as 1/√rays (a bound: stratification falls faster, while the noise carried in
/// the batch's radiosities does not fall at all, which the next round then sees), at most
/// [`REFINE_GROWTH`] times the rays so far and [`REFINE_MOST`] times the flux rays in all
/// (and [`MAX_RAYS`]).
#[allow(clippy::too_many_arguments)]
fn refine_flux(
    gather: &Gather,
    known_t: &[bool],
    (e, d): (&[f64], &[f64]),
    from_of: &[Vec<f64>],
    h_of: &mut [Vec<f64>],
    lost_of: &mut [Vec<f32>],
    count: &mut [u32],
    params: &MatrixFreeParams,
) -> Refinement {
    let (n, b) = (count.len(), h_of.len());
    let mut out = Refinement::default();
    let mut refined = vec![false; n];
    let mut chosen: Vec<(u32, u32)> = Vec::new();
    let mut extra: Vec<(f64, f64)> = Vec::new();
    let mut se = vec![0.0; n];
    let mut q_abs = vec![0.0; n];
    let most = MatrixFreeParams::side(params.flux_rays)
        .pow(2)
        .saturating_mul(REFINE_MOST)
        .min(MAX_RAYS);
    for round in 0..=REFINE_ROUNDS {
        // Each patch's mean flux e − ε h̄ and its standard error ε s(h)/√b.
        let hv = &*h_of;
        se.par_iter_mut()
            .zip(q_abs.par_iter_mut())
            .enumerate()
            .for_each(|(i, (se, qa))| {
                if !known_t[i] {
                    return;
                }
                let mean = (0..b).map(|k| hv[k][i]).sum::<f64>() / b as f64;
                let var = (0..b).map(|k| (hv[k][i] - mean).powi(2)).sum::<f64>() / (b as f64 - 1.0);
                let eps = 1.0 - d[i];
                *se = eps * (var / b as f64).sqrt();
                *qa = (e[i] - eps * mean).abs();
            });
        let flux_patches = known_t.iter().filter(|&&k| k).count();
        let mean_abs = (0..n)
            .filter(|&i| known_t[i])
            .map(|i| q_abs[i])
            .sum::<f64>()
            / flux_patches.max(1) as f64;
        let target = params.flux_error * mean_abs;
        out.target = target;
        chosen.clear();
        let mut above = 0;
        for i in 0..n {
            if !(known_t[i] && se[i] > target) {
                continue;
            }
            above += 1;
            if count[i] >= most {
                continue;
            }
            let c = count[i] as f64;
            let want = (c * (se[i] / (REFINE_AIM * target)).powi(2))
                .min(c * REFINE_GROWTH)
                .min(most as f64);
            let mut side = (want - c).max(1.0).sqrt().ceil() as u32;
            while side > 1 && count[i] + side * side > most {
                side -= 1;
            }
            chosen.push((i as u32, side));
        }
        out.above = above;
        if round == REFINE_ROUNDS || chosen.is_empty() {
            break;
        }
        for (batch, (h, lost)) in h_of.iter_mut().zip(lost_of.iter_mut()).enumerate() {
            let tag = ((batch as u64 + 1) << 32) | (1 << 31) | (round as u64 + 1);
            let from = &from_of[batch];
            chosen
                .par_iter()
                .with_min_len(16)
                .map_init(
                    || {
                        (
                            Vec::<u32>::new(),
                            Vec::<Ray>::new(),
                            Vec::<Option<Hit>>::new(),
                        )
                    },
                    |(perm, rays, hits), &(i, s)| {
                        gather.patch(i as usize, from, s, tag, perm, rays, hits)
                    },
                )
                .collect_into_vec(&mut extra);
            for (&(i, s), &(hx, lx)) in chosen.iter().zip(&extra) {
                let i = i as usize;
                let (c, m) = (count[i] as f64, (s * s) as f64);
                h[i] = (c * h[i] + m * hx) / (c + m);
                lost[i] = ((c * lost[i] as f64 + m * lx) / (c + m)) as f32;
            }
        }
        for &(i, s) in &chosen {
            count[i as usize] += s * s;
            refined[i as usize] = true;
            out.rays += b as u64 * (s * s) as u64;
        }
        out.rounds += 1;
    }
    out.patches = refined.iter().filter(|&&r| r).count();
    out
}

/// Running mean and sum of squares over batches (Welford), per patch.
#[derive(Clone, Default)]
struct Moments {
    mean: Vec<f64>,
    m2: Vec<f64>,
}

impl Moments {
    fn new(n: usize) -> Self {
        Self {
            mean: vec![0.0; n],
            m2: vec![0.0; n],
        }
    }

    /// Add batch `k` (0-based) of values `x`.
    fn add(&mut self, k: usize, x: impl IndexedParallelIterator<Item = f64>) {
        let w = 1.0 / (k + 1) as f64;
        self.mean
            .par_iter_mut()
            .zip(self.m2.par_iter_mut())
            .zip(x)
            .for_each(|((m, m2), x)| {
                let d = x - *m;
                *m += d * w;
                *m2 += d * (x - *m);
            });
    }

    /// Standard error of the mean of `b` batches.
    fn std_error(&self, b: usize) -> Vec<f64> {
        let f = 1.0 / (b as f64 * (b as f64 - 1.0));
        self.m2.iter().map(|m2| (m2.max(0.0) * f).sqrt()).collect()
    }
}

/// Mean and standard error of the mean of scalar batch values.
fn mean_and_error(x: &[f64]) -> (f64, f64) {
    let b = x.len() as f64;
    let mean = x.iter().sum::<f64>() / b;
    let var = x.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (b - 1.0);
    (mean, (var / b).sqrt())
}

/// Solve `system` on the patches of `mesh` (areas in `system`, m²) without F, by stochastic
/// Jacobi sweeps of gathering rays cast in `bvh` (built on `mesh`). `progress(done, total)`
/// is told after each sweep (total: the sweeps of the batches plus the common ones so far).
///
/// The solution's `flux_std_error`, `temperature_std_error` and `boundary_power_std_error`
/// are filled; `info.matrix_free` holds the schedule and the balance's error.
pub fn solve_matrix_free(
    system: &ThermalSystem,
    mesh: &Mesh,
    bvh: &Bvh,
    params: &MatrixFreeParams,
    progress: &(dyn Fn(u64, u64) + Sync),
) -> Result<ThermalSolution, ThermalError> {
    let n = system.area.len();
    params.validate().map_err(ThermalError::Malformed)?;
    system.validate_patches(n)?;
    if mesh.len() != n {
        return Err(ThermalError::Malformed(format!(
            "{} patches in the mesh, {} in the system",
            mesh.len(),
            n
        )));
    }
    let any_temperature = system
        .boundaries
        .iter()
        .any(|b| matches!(b.condition, Condition::Temperature(_)));
    if !any_temperature && system.closed {
        return Err(ThermalError::Undetermined);
    }
    let start = std::time::Instant::now();
    let sigma_te4 = STEFAN_BOLTZMANN * system.environment.powi(4);
    let Parts { e, d } = parts(system);
    let gather = Gather {
        mesh,
        bvh,
        closed: system.closed,
        sigma_te4,
        seed: params.seed,
    };
    let area = &system.area;
    let s_carry = MatrixFreeParams::side(params.carry_rays);
    let (s_sweep, s_flux, s_temperature) = (
        MatrixFreeParams::side(params.sweep_rays),
        MatrixFreeParams::side(params.flux_rays),
        MatrixFreeParams::side(params.temperature_rays),
    );
    let known_t: Vec<bool> = system
        .group
        .iter()
        .map(|&g| {
            matches!(
                system.boundaries[g as usize].condition,
                Condition::Temperature(_)
            )
        })
        .collect();
    let final_side = |i: usize| {
        if known_t[i] {
            s_flux
        } else {
            s_temperature
        }
    };
    let final_rays: u64 = (0..n).map(|i| (final_side(i) as u64).pow(2)).sum();
    let mut rays_cast = 0u64;
    let update = |h: &[f64], j: &mut [f64]| {
        j.par_iter_mut()
            .enumerate()
            .for_each(|(i, j)| *j = e[i] + d[i] * h[i]);
    };

    // Common sweeps from every patch seeing the surroundings.
    let mut j: Vec<f64> = (0..n)
        .map(|i| e[i] + d[i] * if system.closed { 0.0 } else { sigma_te4 })
        .collect();
    let mut h = vec![0.0; n];
    let mut lost = vec![0.0; n];
    let mut next = vec![0.0; n];
    let mut deltas: Vec<f64> = Vec::new();
    let (mut contraction, mut remaining_bias) = (0.0, f64::INFINITY);
    let tail = (params.batches * params.batch_sweeps) as u64;
    let mut sweeps = 0usize;
    while sweeps < params.max_sweeps as usize {
        sweeps += 1;
        gather.sweep(&j, &|_| s_sweep, sweeps as u64, &mut h, &mut lost);
        rays_cast += (n as u64) * (s_sweep * s_sweep) as u64;
        next.copy_from_slice(&j);
        update(&h, &mut next);
        let delta: f64 = (0..n)
            .map(|i| area[i] * (next[i] - j[i]))
            .sum::<f64>()
            .abs();
        let scale: f64 = (0..n).map(|i| area[i] * next[i].abs()).sum();
        std::mem::swap(&mut j, &mut next);
        deltas.push(delta);
        progress(sweeps as u64, sweeps as u64 + tail);
        if scale == 0.0 || delta == 0.0 {
            remaining_bias = 0.0;
            break;
        }
        if deltas.len() >= 4 {
            let k = deltas.len() - 1;
            let ratio = (deltas[k] / deltas[k - 3]).powf(1.0 / 3.0);
            contraction = ratio.min(0.999);
            remaining_bias = delta * contraction / (1.0 - contraction) / scale;
            // Below the tolerance, or no longer decreasing: the noise floor of the sum.
            if remaining_bias <= params.tolerance || ratio >= 1.0 {
                break;
            }
        }
    }

    // Independent batches from the common start: each batch's last irradiation and lost
    // shares are kept (and, for the adaptive stage, the radiosities it gathered from), so
    // that the adaptive stage can add rays within each batch before the batch is summed.
    let b_count = params.batches as usize;
    let adaptive = params.flux_error > 0.0 && any_temperature;
    let mut h_of: Vec<Vec<f64>> = Vec::with_capacity(b_count);
    // Lost shares in f32: a share of at most 2²⁰ rays is exact.
    let mut lost_of: Vec<Vec<f32>> = Vec::with_capacity(b_count);
    let mut from_of: Vec<Vec<f64>> = Vec::with_capacity(if adaptive { b_count } else { 0 });
    let mut jb = vec![0.0; n];
    let mut done = sweeps as u64;
    for batch in 0..b_count {
        jb.copy_from_slice(&j);
        for sweep in 1..=params.batch_sweeps as usize {
            let tag = ((batch as u64 + 1) << 32) | sweep as u64;
            if sweep == params.batch_sweeps as usize {
                if adaptive {
                    from_of.push(jb.clone());
                }
                gather.sweep(&jb, &final_side, tag, &mut h, &mut lost);
                rays_cast += final_rays;
            } else {
                // The next-to-last sweep sets the radiosities the last one gathers from.
                let s = if sweep + 1 == params.batch_sweeps as usize {
                    s_carry
                } else {
                    s_sweep
                };
                gather.sweep(&jb, &|_| s, tag, &mut h, &mut lost);
                rays_cast += (n as u64) * (s * s) as u64;
            }
            update(&h, &mut jb);
            done += 1;
            progress(done, sweeps as u64 + tail);
        }
        h_of.push(h.clone());
        lost_of.push(lost.iter().map(|&x| x as f32).collect());
    }
    drop((h, lost, next));

    // The adaptive stage: more rays, within every batch, where the flux's error is above
    // the target.
    let eps = |i: usize| system.boundaries[system.group[i] as usize].emissivity;
    let mut final_count: Vec<u32> = (0..n).map(|i| final_side(i).pow(2)).collect();
    let mut refine = Refinement::default();
    if adaptive {
        refine = refine_flux(
            &gather,
            &known_t,
            (&e, &d),
            &from_of,
            &mut h_of,
            &mut lost_of,
            &mut final_count,
            params,
        );
        rays_cast += refine.rays;
    }
    drop(from_of);

    // Each batch's flux (exactly the prescribed one where given), εσT⁴, and books.
    let mut m_h = Moments::new(n);
    let mut m_q = Moments::new(n);
    let mut m_eb = Moments::new(n);
    let mut m_lost = Moments::new(n);
    let k_groups = system.boundaries.len();
    let mut group_power = vec![vec![0.0; b_count]; k_groups];
    let mut totals = vec![0.0; b_count];
    // Σ A lost J of each batch and Σ A lost: the loss to the surroundings is estimated with
    // each batch's shares and the other batches' J (the same batch's J is correlated with
    // its shares).
    let mut own = vec![0.0; b_count];
    let mut lost_area = vec![0.0; b_count];
    let mut j_sum = vec![0.0; n];
    let flux_given: Vec<Option<f64>> = system
        .boundaries
        .iter()
        .map(|b| match b.condition {
            Condition::Temperature(_) => None,
            Condition::Flux(q) => Some(q),
            Condition::Adiabatic => Some(0.0),
        })
        .collect();
    let mut q = vec![0.0; n];
    for batch in 0..b_count {
        let (h, lost) = (&h_of[batch], &lost_of[batch]);
        jb.par_iter_mut()
            .enumerate()
            .for_each(|(i, j)| *j = e[i] + d[i] * h[i]);
        q.par_iter_mut()
            .enumerate()
            .for_each(|(i, q)| *q = flux_given[system.group[i] as usize].unwrap_or(jb[i] - h[i]));
        m_h.add(batch, h.par_iter().copied());
        m_q.add(batch, q.par_iter().copied());
        m_eb.add(
            batch,
            (0..n)
                .into_par_iter()
                .map(|i| (jb[i] - (1.0 - eps(i)) * h[i]) / eps(i)),
        );
        m_lost.add(batch, lost.par_iter().map(|&x| x as f64));
        for i in 0..n {
            group_power[system.group[i] as usize][batch] += area[i] * q[i];
        }
        totals[batch] = (0..n).map(|i| area[i] * q[i]).sum();
        own[batch] = (0..n).map(|i| area[i] * lost[i] as f64 * jb[i]).sum();
        lost_area[batch] = (0..n).map(|i| area[i] * lost[i] as f64).sum();
        for i in 0..n {
            j_sum[i] += jb[i];
        }
    }
    drop(h_of);
    // Batch b's loss: Σ A_i lost_i^b (J̄_i without b − σT_e⁴).
    let losses: Vec<f64> = (0..b_count)
        .map(|b| {
            let cross: f64 = (0..n)
                .map(|i| area[i] * lost_of[b][i] as f64 * j_sum[i])
                .sum();
            (cross - own[b]) / (b_count - 1) as f64 - sigma_te4 * lost_area[b]
        })
        .collect();
    drop(lost_of);

    // The means and their standard errors.
    let flux = m_q.mean.clone();
    let flux_std_error = m_q.std_error(b_count);
    let irradiation = m_h.mean.clone();
    let eb_error = m_eb.std_error(b_count);
    let mut temperature = vec![0.0; n];
    let mut temperature_std_error = vec![0.0; n];
    let mut worst: Vec<Option<f64>> = vec![None; k_groups];
    for i in 0..n {
        let k = system.group[i] as usize;
        if let Condition::Temperature(t) = system.boundaries[k].condition {
            temperature[i] = t;
            continue;
        }
        let eb = m_eb.mean[i];
        // Negative beyond its noise: a prescription no temperature meets.
        let scale = eb.abs().max(irradiation[i].abs()).max(1e-300);
        if eb < -(4.0 * eb_error[i]).max(1e-8 * scale) {
            let w = worst[k].get_or_insert(eb);
            *w = w.min(eb);
        }
        let t = (eb.max(0.0) / STEFAN_BOLTZMANN).powf(0.25);
        temperature[i] = t;
        temperature_std_error[i] = if t > 0.0 {
            eb_error[i] / (4.0 * STEFAN_BOLTZMANN * t.powi(3))
        } else {
            (eb_error[i] / STEFAN_BOLTZMANN).powf(0.25)
        };
    }
    if let Some((group, value)) = worst
        .iter()
        .enumerate()
        .find_map(|(k, w)| w.map(|v| (k, v)))
    {
        return Err(ThermalError::Unphysical { group, value });
    }
    let radiosity: Vec<f64> = (0..n).map(|i| e[i] + d[i] * irradiation[i]).collect();
    let (total_power, total_power_std_error) = mean_and_error(&totals);
    let (environment_loss, _) = mean_and_error(&losses);
    let differences: Vec<f64> = totals.iter().zip(&losses).map(|(t, l)| t - l).collect();
    let (_, balance_std_error) = mean_and_error(&differences);
    let abs_scale: f64 = (0..n).map(|i| (area[i] * flux[i]).abs()).sum();
    let balance_error = if abs_scale > 0.0 {
        (total_power - environment_loss).abs() / abs_scale
    } else {
        0.0
    };
    let total_area: f64 = area.iter().sum();
    let opening = (0..n).map(|i| area[i] * m_lost.mean[i]).sum::<f64>() / total_area;
    let boundary_power_std_error = group_power.iter().map(|p| mean_and_error(p).1).collect();
    Ok(ThermalSolution {
        radiosity,
        irradiation,
        temperature,
        flux,
        flux_std_error,
        temperature_std_error,
        boundary_power_std_error,
        info: ThermalInfo {
            method: "matrix-free",
            iterations: sweeps + b_count * params.batch_sweeps as usize,
            residual: remaining_bias,
            total_power,
            environment_loss,
            balance_error,
            opening,
            seconds: start.elapsed().as_secs_f64(),
            matrix_free: Some(MatrixFreeInfo {
                sweeps,
                batches: b_count,
                batch_sweeps: params.batch_sweeps as usize,
                flux_rays: s_flux * s_flux,
                temperature_rays: s_temperature * s_temperature,
                sweep_rays: s_sweep * s_sweep,
                rays_cast,
                contraction,
                remaining_bias,
                total_power_std_error,
                balance_std_error,
                flux_target: refine.target,
                refine_rounds: refine.rounds,
                refined_patches: refine.patches,
                refine_rays: refine.rays,
                most_flux_rays: (0..n)
                    .filter(|&i| known_t[i])
                    .map(|i| final_count[i])
                    .max()
                    .unwrap_or(0),
                above_target: refine.above,
            }),
        },
    })
}

/// The area-weighted share of the view of `mesh`'s patches that reaches no surface
/// (Σ A_i F_ie / Σ A_i), from `rays` stratified rays a patch: what decides whether a scene is
/// a closed enclosure when nothing says so.
pub fn open_share(mesh: &Mesh, bvh: &Bvh, rays: u32, seed: u64) -> f64 {
    let n = mesh.len();
    let gather = Gather {
        mesh,
        bvh,
        closed: false,
        sigma_te4: 0.0,
        seed,
    };
    let (mut h, mut lost) = (vec![0.0; n], vec![0.0; n]);
    let zero = vec![0.0; n];
    let s = MatrixFreeParams::side(rays);
    gather.sweep(&zero, &|_| s, u64::MAX, &mut h, &mut lost);
    let area = |i: usize| mesh.patches[i].area as f64;
    let total: f64 = (0..n).map(area).sum();
    if total > 0.0 {
        (0..n).map(|i| area(i) * lost[i]).sum::<f64>() / total
    } else {
        0.0
    }
}
