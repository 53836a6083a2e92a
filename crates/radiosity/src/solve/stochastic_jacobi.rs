//! Stochastic Jacobi radiosity (L. Neumann, M. Feda, M. Kopp, W. Purgathofer, "A new stochastic
//! radiosity method for highly complex scenes", EGWR 1994; P. Bekaert, "Hierarchical and
//! stochastic algorithms for radiosity", PhD thesis, KU Leuven 1999, chapters 4–5; RenderPark's
//! recommended method): every iteration shoots the unshot power of all patches at once with a
//! fixed budget of R rays, in parallel.
//!
//! **Incremental shooting iterations.** With unshot radiosity ΔB_i and p_i = |ΔB_i|₁ A_i, P =
//! Σ p_i, an iteration casts R = `iteration_rays` · N · P/P₀ rays (P₀ the emitted energy: each
//! ray carries about the same power in every iteration; at least N/4), and ray k leaves the patch i whose cumulative share of P contains
//! (k + ξ)/R (systematic sampling: patch i gets n_i = ⌊R p_i/P⌋ or ⌈R p_i/P⌉ rays; in the first
//! iteration every emitter at least one), from a uniform point in a cosine direction
//! ([`PhotonSampler`]), and carries the power w_i = ΔB_i A_i / n_i. A ray landing on j adds
//! ρ_j w_i / A_j to B_j and to the new unshot ΔB'_j; a lost ray's power escapes. A source without
//! rays keeps its unshot for a later iteration, so the books close exactly: emitted = absorbed +
//! escaped + Σ ΔB_i A_i after every iteration. The expected transfer is one Jacobi step on the
//! power system, so the estimate is unbiased.
//!
//! **The final regular iteration** (Bekaert's "regular" gathering step), run once when the
//! unshot energy is below the tolerance or the iteration cap is reached, if asked for
//! ([`SolverParams::gather_rays`] = n > 0; none by default): n rays from every patch
//! j gather `B_j = E_j + ρ_j Σ_i F_ji B_i` from the current estimate, which averages the
//! shooting noise of many patches into each result. It uses the **constant control variate**
//! β (the area-weighted mean of B per channel): `Σ_i F_ji B_i = β s_j + Σ_i F_ji (B_i − β)`,
//! where s_j = Σ_i F_ji is the fraction of rays from j that hit anything. s_j is estimated from
//! all the rays j shot in earlier iterations (independent of the gathering rays, so the
//! estimator stays unbiased; s_j = 1 in a closed scene); a patch that never shot gathers
//! without the variate. Only the reflected part `B − E` is gathered: the direct light is taken
//! from the first iteration, in which every emitter shoots all its emission from its own surface
//! (so a gathering ray that sees the wrong one of two coincident surfaces, a light and a
//! ceiling, cannot lose it). Gathering rays come from [`PhotonSampler::gather`], which a scene
//! answers with nothing at points another surface covers (a coincident twin, a panel flush on a
//! wall): a ray launched a ray offset above such a point would start above the cover and see
//! light that only the cover receives. The standard error of B follows from the gathering rays' sample
//! variance and the first iteration's arrivals, and is reported
//! ([`super::Info::estimated_error`]).
//!
//! **Why not by default.** On RenderPark's hospital the gathering made B noisier, not smoother,
//! at every ray count tried (docs/notes/solvers.md). The light there comes from a few bright
//! surfaces beside the lamps; a gathering ray picks its direction by the cosine alone and
//! seldom meets them, while every ray of the shooting iterations carries the same power
//! wherever it lands. On the Cornell box the two were about even. Without it, B is the
//! shooting iterations' estimate, and its standard error follows from each patch's arrivals:
//! nearly a Poisson process of rays of about equal power w̄, so that what arrived, S, has a
//! variance of about S ρ w̄ / A (it leaves out the noise an iteration inherits from the one
//! before, which the reflectances damp).
//!
//! **Determinism.** Rays are traced in chunks of [`CHUNK`], each with its own random stream keyed
//! by (seed, iteration, chunk); hits are reduced in chunk order, so B does not depend on the
//! number of threads. The reduction is serial, and runs while the threads trace the next
//! batch (nothing a batch draws depends on the one before). A hit adds only the power it
//! carries to its receiver's sum; reflectance and area turn each patch's sum into B, ΔB and
//! the energy books in one pass after the iteration's last batch. Memory: B, ΔB, the
//! iteration's arrived power, a variance and two ray counters per patch (and with the final
//! gathering the direct light), plus two batches of hits.

use super::{Info, Operator, SolveError, Solver, SolverParams, SolverState, System};
use crate::color::Rgb;
use crate::sampling::{stream, uniform};
use crate::system::{Gathered, PhotonSampler};
use rayon::prelude::*;

/// Rays per parallel task and per random stream.
pub const CHUNK: usize = 256;
/// Patches of a part of the pass after each iteration, whose sums are added in order.
const PASS: usize = 1 << 14;
/// Rays of a batch, whose hits are held at once (8 bytes each; two batches, the one reduced
/// and the one traced meanwhile).
const BATCH: usize = 1 << 20;
/// The most gathering rays a patch may ask for ([`SolverParams::gather_rays`]): a patch's draws
/// are held at once (8 MiB at this count), and more would not improve a per-patch mean that
/// the shooting's noise already bounds.
pub const MAX_GATHER_RAYS: u32 = 1 << 20;
/// Gathering rays a group of patches casts together in the final iteration.
const GATHER_RAYS: usize = 256;
/// How many rays ahead of the one being reduced its receiver is asked for from memory: enough
/// misses in flight to cover a trip to memory at 10⁶ patches (docs/notes/solvers.md).
const AHEAD: usize = 48;
/// Stream tag of the final gathering iteration.
const GATHER: u64 = u64::MAX;

/// Stochastic Jacobi in progress.
#[derive(Clone, Debug)]
pub struct StochasticJacobi<'s> {
    system: &'s System,
    b: Vec<Rgb>,
    unshot: Vec<Rgb>,
    /// Rays shot from each patch so far, and how many of them hit a patch: s_j's estimate.
    rays: Vec<u32>,
    hits: Vec<u32>,
    /// What the first iteration delivered, ρ_j × the direct irradiance from the emitters: kept
    /// for the final gathering only.
    direct: Vec<Rgb>,
    /// Per patch, the variance (channels summed) of what the shooting iterations delivered:
    /// the first iteration's, and without a final gathering every later one's too. The arrivals
    /// are nearly a Poisson process of rays of equal power, so that an iteration adds what
    /// arrived times the size of one arrival ([`Self::shoot`]).
    shot_var: Vec<f64>,
    rays_per_patch: u32,
    /// Rays per patch of the final gathering iteration; 0 for none.
    gather_rays: u32,
    seed: u64,
    emitted: Rgb,
    emitted_total: f64,
    /// Σ |E_i|₁ A_i: the unshot energy of the first iteration.
    emitted_energy: f64,
    absorbed: Rgb,
    escaped: Rgb,
    iterations: u64,
    /// The final step ([`SolverState::finish`]) is done: gathered, or the error estimated.
    finished: bool,
    estimated_error: f64,
    /// Ranks sharing the rays of each iteration, if distributed.
    ranks: Option<&'s crate::comm::Ranks<'s>>,
    /// Where the shooting iterations' time went.
    timing: Timing,
    /// Buffers an iteration fills, kept for the next.
    scratch: Scratch,
    /// [`Self::unshot_energy`], kept up to date: one pass over the patches an iteration, where
    /// the iteration and the driver's status each made their own.
    unshot_left: f64,
}

/// What a shooting iteration fills and the next reuses (no allocation, and no fresh pages for
/// the kernel to clear, per iteration): the cumulative ray counts of the sources, the power
/// that arrived at each patch, and a batch's (source, hit) pairs.
#[derive(Clone, Debug, Default)]
struct Scratch {
    end: Vec<u64>,
    arrived: Vec<Rgb>,
    buf: Vec<(u32, u32)>,
    /// The batch traced while `buf`'s is reduced.
    spare: Vec<(u32, u32)>,
}

/// Seconds of the iterations by part: the shooting iterations' tracing (parallel, shared
/// among ranks), exchanging the hits (ranks only) and reducing them in ray order (serial, on
/// every rank); the final gathering's parallel part.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Timing {
    /// Tracing rays.
    pub trace: f64,
    /// All-gathering the hits.
    pub exchange: f64,
    /// Reducing the hits into B and ΔB.
    pub reduce: f64,
    /// The final gathering's parallel part: drawing and casting its rays, and each patch's
    /// average of what they found.
    pub gather: f64,
    /// Rays cast by all ranks.
    pub rays: u64,
}

impl<'s> StochasticJacobi<'s> {
    /// Start: B = ΔB = E; each iteration casts `params.iteration_rays` rays per patch.
    pub fn new(system: &'s System, params: &SolverParams) -> Result<Self, SolveError> {
        if params.iteration_rays == 0 {
            return Err(SolveError::Parameter {
                parameter: super::Parameter::IterationRays,
                value: 0.0,
                range: "[1, 2³²)",
            });
        }
        if params.gather_rays > MAX_GATHER_RAYS {
            return Err(SolveError::Parameter {
                parameter: super::Parameter::GatherRays,
                value: params.gather_rays as f64,
                range: "[0, 2²⁰]",
            });
        }
        let n = system.len();
        let emitted = system.emitted_power();
        let mut sj = Self {
            b: system.emission.clone(),
            unshot: system.emission.clone(),
            rays: vec![0; n],
            hits: vec![0; n],
            direct: Vec::new(),
            shot_var: Vec::new(),
            rays_per_patch: params.iteration_rays,
            gather_rays: params.gather_rays,
            seed: params.seed,
            emitted,
            emitted_total: emitted.sum(),
            emitted_energy: system
                .emission
                .iter()
                .zip(&system.area)
                .map(|(e, a)| (e.r.abs() + e.g.abs() + e.b.abs()) * a)
                .sum(),
            absorbed: Rgb::BLACK,
            escaped: Rgb::BLACK,
            iterations: 0,
            finished: false,
            estimated_error: 0.0,
            ranks: None,
            timing: Timing::default(),
            scratch: Scratch::default(),
            unshot_left: 0.0,
            system,
        };
        sj.unshot_left = sj.unshot_energy();
        Ok(sj)
    }

    /// Where the shooting iterations' time went.
    pub fn timing(&self) -> Timing {
        self.timing
    }

    /// Share every iteration's rays among `ranks`: each traces a contiguous run of the
    /// iteration's chunks and the hits are all-gathered (4 bytes a ray), so every rank reduces
    /// the same hits in the same order and B is the same bytes as on one process.
    pub fn distributed(mut self, ranks: &'s crate::comm::Ranks<'s>) -> Self {
        self.ranks = Some(ranks);
        self
    }

    /// Rays of one iteration: the per-patch budget times N.
    fn budget(&self) -> u64 {
        self.rays_per_patch as u64 * self.system.len() as u64
    }

    /// Σ |ΔB_i|₁ A_i, the unshot energy, from the unshot radiosities.
    fn unshot_energy(&self) -> f64 {
        self.unshot
            .iter()
            .zip(&self.system.area)
            .map(|(u, a)| (u.r.abs() + u.g.abs() + u.b.abs()) * a)
            .sum()
    }

    fn unshot_fraction_now(&self) -> f64 {
        self.unshot_left / self.emitted_total
    }

    /// One incremental shooting iteration of about R rays.
    fn shoot(&mut self, sampler: &dyn PhotonSampler) {
        let sys = self.system;
        let n = sys.len();
        let energy = |u: Rgb, a: f64| (u.r.abs() + u.g.abs() + u.b.abs()) * a;
        let total = self.unshot_left;
        if total <= 0.0 {
            return;
        }
        // Rays per source by systematic sampling: patch i gets the k with (k + ξ)/R · P in its
        // slice of the cumulative unshot energy, ⌊R p_i/P⌋ or ⌈R p_i/P⌉ of them. In the first
        // iteration every emitter shoots at least once, so that all emitted light leaves in it.
        // Rays in proportion to the power left (Bekaert's advice: every ray then carries about
        // the same power in every iteration, so later, weaker iterations cost fewer rays), at
        // least a quarter ray a patch.
        let r = (self.budget() as f64 * (total / self.emitted_energy)).max(n as f64 * 0.25);
        let mut rng = stream(self.seed, self.iterations, u64::MAX, 0);
        let xi = uniform(&mut rng) as f64;
        let first = self.iterations == 0;
        let Scratch {
            mut end,
            mut arrived,
            mut buf,
            mut spare,
        } = std::mem::take(&mut self.scratch);
        end.clear();
        // All zero: the iteration before set each back once it was read.
        arrived.resize(n, Rgb::BLACK);
        let (mut acc, mut before, mut rays) = (0.0f64, 0u64, 0u64);
        // The power the sources with rays shoot, per channel.
        let mut shot = Rgb::BLACK;
        for i in 0..n {
            acc += energy(self.unshot[i], sys.area[i]);
            let upto = (acc / total * r - xi).ceil().max(0.0) as u64;
            let mut count = upto.saturating_sub(before);
            before = before.max(upto);
            if first && count == 0 && self.unshot[i] != Rgb::BLACK {
                count = 1;
            }
            if count > 0 {
                shot += self.unshot[i] * sys.area[i];
            }
            rays += count;
            end.push(rays);
        }
        let source_of = |k: u64| end.partition_point(|&e| e <= k).min(n - 1);
        // Each source shoots all its unshot radiosity, split evenly over its rays; a source
        // without rays keeps it for a later iteration. The books stay exact.
        let weight = |i: usize| {
            let count = end[i] - if i == 0 { 0 } else { end[i - 1] };
            self.unshot[i] * (sys.area[i] / count as f64)
        };
        if first {
            self.shot_var = vec![0.0; n];
        }
        // The power a ray of this iteration carries, on average (each source's rays carry
        // its power over its count, ⌊R p_i/P⌋ or ⌈R p_i/P⌉, so nearly this).
        let ray_power = shot * (1.0 / rays.max(1) as f64);
        let mut escaped = self.escaped;
        // (source, hit) of each ray of a batch, filled in parallel, reduced in ray order.
        buf.resize((rays as usize).min(BATCH), (0, 0));
        let seed = self.seed;
        let iteration = self.iterations;
        self.timing.rays += rays;
        // Chunk `c` of the batch whose first ray is `done`, into `out`.
        let trace = |done: u64, c: usize, out: &mut [(u32, u32)]| {
            let mut rng = stream(seed, iteration, done / CHUNK as u64 + c as u64, 1);
            let start = done + (c * CHUNK) as u64;
            // The chunk's sources, then their draws in order, several rays at a time.
            let (mut from, mut hit) = ([0u32; CHUNK], [0u32; CHUNK]);
            let (from, hit) = (&mut from[..out.len()], &mut hit[..out.len()]);
            // The sources of consecutive rays: one search, then a walk along `end`.
            let mut i = source_of(start);
            for (s, k) in from.iter_mut().zip(start..) {
                while end[i] <= k && i + 1 < n {
                    i += 1;
                }
                *s = i as u32;
            }
            sampler.sample_many(from, &mut rng, hit);
            for ((slot, &i), &j) in out.iter_mut().zip(from.iter()).zip(hit.iter()) {
                *slot = (i, j);
            }
        };
        // The whole batch whose first ray is `done`, in parallel.
        let trace_batch = |done: u64, out: &mut [(u32, u32)]| {
            out.par_chunks_mut(CHUNK)
                .enumerate()
                .for_each(|(c, out)| trace(done, c, out))
        };
        // In ray order, so that the sums do not depend on the threads. A hit adds only the
        // power it carries: the receiver's reflectance and area, and with them B, ΔB and the
        // books, are applied once per patch after the last batch, so a ray waits on one cache
        // miss (its receiver's sum), not on four arrays scattered over memory. The rays of a
        // source are consecutive: its weight is found once, and its hits are counted here and
        // added to its count when its rays end.
        let source_hits = &mut self.hits;
        let mut reduce = |hits: &[(u32, u32)], arrived: &mut [Rgb], escaped: &mut Rgb| {
            let (mut source, mut w, mut landed) = (usize::MAX, Rgb::BLACK, 0u32);
            for (k, &(i, j)) in hits.iter().enumerate() {
                // Ask for the receiver AHEAD rays on, so that the misses overlap (a lost ray's
                // u32::MAX asks for nothing).
                if let Some(&(_, next)) = hits.get(k + AHEAD) {
                    crate::hint::prefetch_at(arrived, next as usize);
                }
                let i = i as usize;
                if i != source {
                    if let Some(h) = source_hits.get_mut(source) {
                        *h = h.saturating_add(landed);
                    }
                    (source, w, landed) = (i, weight(i), 0);
                }
                if j == u32::MAX {
                    *escaped += w;
                } else {
                    landed += 1;
                    arrived[j as usize] += w;
                }
            }
            if let Some(h) = source_hits.get_mut(source) {
                *h = h.saturating_add(landed);
            }
        };
        match self.ranks {
            None => {
                // Each batch is reduced while the next is traced: the reduction is serial,
                // and the other threads go on tracing. Its cost to the wall time is then the
                // share of the threads it takes (its own time over their number), counted as
                // the reduction's; the rest of the overlap is the rays'.
                spare.resize(buf.len(), (0, 0));
                let threads = rayon::current_num_threads() as f64;
                let (mut cur, mut next) = (&mut buf, &mut spare);
                let mut batch = (rays as usize).min(BATCH);
                let t = std::time::Instant::now();
                trace_batch(0, &mut cur[..batch]);
                self.timing.trace += t.elapsed().as_secs_f64();
                let mut done = 0u64;
                loop {
                    let after = done + batch as u64;
                    let upcoming = (rays - after).min(BATCH as u64) as usize;
                    let t = std::time::Instant::now();
                    let (own, ()) = rayon::join(
                        || {
                            let t = std::time::Instant::now();
                            reduce(&cur[..batch], &mut arrived, &mut escaped);
                            t.elapsed().as_secs_f64()
                        },
                        || trace_batch(after, &mut next[..upcoming]),
                    );
                    let wall = t.elapsed().as_secs_f64();
                    let reducing = if upcoming > 0 { own / threads } else { wall };
                    self.timing.reduce += reducing;
                    self.timing.trace += (wall - reducing).max(0.0);
                    if upcoming == 0 {
                        break;
                    }
                    std::mem::swap(&mut cur, &mut next);
                    (done, batch) = (after, upcoming);
                }
            }
            Some(ranks) => {
                let mut done = 0u64;
                while done < rays {
                    let t = std::time::Instant::now();
                    let batch = (rays - done).min(BATCH as u64) as usize;
                    // This rank's chunks of the batch; then everyone's hits, in chunk order.
                    let chunks = batch.div_ceil(CHUNK);
                    let mine =
                        &crate::comm::balance(&vec![1.0; chunks], ranks.size())[ranks.rank()];
                    let (lo, hi) = (mine.start * CHUNK, (mine.end * CHUNK).min(batch));
                    buf[lo..hi]
                        .par_chunks_mut(CHUNK)
                        .enumerate()
                        .for_each(|(c, out)| trace(done, mine.start + c, out));
                    let hits: Vec<u32> = buf[lo..hi].iter().map(|&(_, j)| j).collect();
                    self.timing.trace += t.elapsed().as_secs_f64();
                    let t = std::time::Instant::now();
                    let all = ranks.all_gather(&hits);
                    self.timing.exchange += t.elapsed().as_secs_f64();
                    let mut i = 0;
                    for (k, (slot, j)) in buf[..batch].iter_mut().zip(all).enumerate() {
                        let k = done + k as u64;
                        while end[i] <= k {
                            i += 1;
                        }
                        *slot = (i as u32, j);
                    }
                    let t = std::time::Instant::now();
                    reduce(&buf[..batch], &mut arrived, &mut escaped);
                    self.timing.reduce += t.elapsed().as_secs_f64();
                    done += batch as u64;
                }
            }
        }
        // What arrived at j is reflected as ΔB_j = ρ_j P_j / A_j, added to B_j and left
        // unshot; the rest, (1 − ρ_j) P_j, is absorbed. One pass, in parallel over fixed
        // ranges of patches whose sums are added in order, so that the books do not depend on
        // the threads.
        let t = std::time::Instant::now();
        let variance = first || self.gather_rays == 0;
        let parts: Vec<(Rgb, f64)> = arrived
            .par_chunks_mut(PASS)
            .zip(self.unshot.par_chunks_mut(PASS))
            .zip(self.b.par_chunks_mut(PASS))
            .zip(self.rays.par_chunks_mut(PASS))
            .zip(self.shot_var.par_chunks_mut(PASS))
            .enumerate()
            .map(|(c, ((((arrived, unshot), b), rays), var))| {
                let (mut absorbed, mut left) = (Rgb::BLACK, 0.0);
                for (k, p) in arrived.iter_mut().enumerate() {
                    let i = c * PASS + k;
                    let count = end[i] - if i == 0 { 0 } else { end[i - 1] };
                    if count > 0 {
                        unshot[k] = Rgb::BLACK;
                        rays[k] = rays[k].saturating_add(count.min(u32::MAX as u64) as u32);
                    }
                    let p = std::mem::replace(p, Rgb::BLACK);
                    if p != Rgb::BLACK {
                        let rho = sys.reflectance[i];
                        let a = sys.area[i];
                        let got = rho * p * (1.0 / a);
                        b[k] += got;
                        unshot[k] += got;
                        absorbed += (Rgb::splat(1.0) - rho) * p;
                        if variance {
                            // got = Σ_k ρ_i w_k / A_i over its arrivals, each about
                            // ρ_i w̄ / A_i (channels summed).
                            var[k] += got.sum().abs() * (rho * ray_power).sum().abs() / a;
                        }
                    }
                    left += energy(unshot[k], sys.area[i]);
                }
                (absorbed, left)
            })
            .collect();
        let (mut absorbed, mut left) = (self.absorbed, 0.0);
        for (a, l) in parts {
            absorbed += a;
            left += l;
        }
        if first && self.gather_rays > 0 {
            // The first iteration's arrivals are the direct light: B − E now.
            self.direct = self
                .b
                .iter()
                .zip(&sys.emission)
                .map(|(&b, &e)| b - e)
                .collect();
        }
        (self.escaped, self.absorbed) = (escaped, absorbed);
        self.timing.reduce += t.elapsed().as_secs_f64();
        self.scratch = Scratch {
            end,
            arrived,
            buf,
            spare,
        };
        self.unshot_left = left;
    }

    /// The final regular iteration: direct light as shot in the first iteration (every emitter
    /// shoots then, from its own surface), plus the reflected light `ρ_j Σ_i F_ji (B_i − E_i)`
    /// gathered by rays from every patch j, with the constant control variate β (the
    /// area-weighted mean of B − E). Gathering only the reflected part keeps the direct light
    /// exact where a light and another surface coincide and a gathering ray would see the
    /// wrong one of the two (as in RenderPark's hospital).
    fn gather(&mut self, sampler: &dyn PhotonSampler) {
        // The shooting iterations are over: their buffers go before this one's.
        self.scratch = Scratch::default();
        let sys = self.system;
        let n = sys.len();
        let total_area = sys.total_area();
        let beta = (0..n)
            .map(|i| (self.b[i] - sys.emission[i]) * sys.area[i])
            .sum::<Rgb>()
            * (1.0 / total_area);
        let per = self.gather_rays as usize;
        let old = &self.b;
        let (rays, hits, direct, direct_sq) =
            (&self.rays, &self.hits, &self.direct, &self.shot_var);
        let seed = self.seed;
        // Per patch: the gathered B and the variance of its estimate (channels summed), from
        // its `per` draws in order.
        let gather_one = |j: usize, draws: &[Gathered]| {
            // The variate only where s_j has an independent estimate.
            let (cv, s) = if rays[j] > 0 {
                (beta, hits[j] as f64 / rays[j] as f64)
            } else {
                (Rgb::BLACK, 0.0)
            };
            let (mut sum, mut sum_sq) = (Rgb::BLACK, 0.0f64);
            for &g in draws {
                let v = match g {
                    Gathered::Hit(i) => old[i as usize] - sys.emission[i as usize] - cv,
                    Gathered::Lost => Rgb::BLACK,
                    // A covered point sees nothing: its share of the variate's own term
                    // (cv · s, with s from rays that were shot from above the cover) is
                    // taken back.
                    Gathered::Covered => Rgb::BLACK - cv,
                };
                sum += v;
                sum_sq += v.sum() * v.sum();
            }
            let mean = sum * (1.0 / per as f64);
            let var = if per > 1 {
                (sum_sq / per as f64 - mean.sum() * mean.sum()).max(0.0) / (per - 1) as f64
            } else {
                0.0
            };
            let rho = sys.reflectance[j];
            let direct = direct.get(j).copied().unwrap_or(Rgb::BLACK);
            let b = sys.emission[j] + direct + rho * (cv * s + mean);
            let rho_mean = rho.sum() / 3.0;
            let direct_var = direct_sq.get(j).copied().unwrap_or(0.0);
            (b, rho_mean * rho_mean * var + direct_var)
        };
        let range = match self.ranks {
            None => 0..n,
            Some(r) => crate::comm::balance(&vec![1.0; n], r.size())[r.rank()].clone(),
        };
        // Groups of patches whose draws are cast together ([`PhotonSampler::gather_many`]);
        // patch j draws from its own stream, so B does not depend on the grouping.
        let group = (GATHER_RAYS / per.max(1)).clamp(1, GATHER_RAYS);
        let t = std::time::Instant::now();
        let mut mine = vec![(Rgb::BLACK, 0.0); range.len()];
        mine.par_chunks_mut(group).enumerate().for_each_init(
            || (Vec::new(), Vec::new(), Vec::new()),
            |(patches, rngs, draws): &mut (Vec<u32>, Vec<_>, Vec<Gathered>), (c, out)| {
                let first = range.start + c * group;
                patches.clear();
                patches.extend((first..first + out.len()).map(|j| j as u32));
                rngs.clear();
                rngs.extend(patches.iter().map(|&j| stream(seed, GATHER, j as u64, 2)));
                draws.clear();
                draws.resize(out.len() * per, Gathered::Lost);
                sampler.gather_many(patches, per, rngs, draws);
                for ((o, &j), d) in out
                    .iter_mut()
                    .zip(patches.iter())
                    .zip(draws.chunks(per.max(1)))
                {
                    *o = gather_one(j as usize, &d[..per]);
                }
            },
        );
        self.timing.gather += t.elapsed().as_secs_f64();
        let gathered = match self.ranks {
            None => mine,
            Some(r) => r.all_gather(&mine),
        };
        let (mut err, mut norm) = (0.0, 0.0);
        for (j, (b, var)) in gathered.into_iter().enumerate() {
            self.b[j] = b;
            err += sys.area[j] * var;
            norm += sys.area[j] * b.sum() * b.sum();
        }
        self.estimated_error = if norm > 0.0 { (err / norm).sqrt() } else { 0.0 };
    }

    /// The standard error of the shooting iterations' B alone (no final gathering), from the
    /// variance of each patch's arrivals ([`Self::shot_var`]). It leaves out the noise a later iteration inherits
    /// from the unshot radiosity the iteration before left (each source's ΔB is itself an
    /// estimate), and so falls short of the error by up to the scene's reflected share.
    fn shooting_error(&mut self) {
        let sys = self.system;
        let (mut err, mut norm) = (0.0, 0.0);
        for j in 0..sys.len() {
            let var = self.shot_var.get(j).copied().unwrap_or(0.0);
            err += sys.area[j] * var;
            norm += sys.area[j] * self.b[j].sum() * self.b[j].sum();
        }
        self.estimated_error = if norm > 0.0 { (err / norm).sqrt() } else { 0.0 };
    }
}

impl SolverState for StochasticJacobi<'_> {
    fn method(&self) -> Solver {
        Solver::StochasticJacobi
    }

    fn step(&mut self, source: &mut dyn Operator) -> bool {
        if self.finished {
            return false;
        }
        let sampler = source.photons().expect("checked by solve::start");
        if self.unshot_fraction_now() <= 0.0 {
            return false;
        }
        self.shoot(sampler);
        self.iterations += 1;
        true
    }

    fn finish(&mut self, source: &mut dyn Operator) -> bool {
        if self.finished {
            return false;
        }
        self.finished = true;
        if self.gather_rays == 0 {
            self.shooting_error();
            return false;
        }
        let sampler = source.photons().expect("checked by solve::start");
        self.gather(sampler);
        true
    }

    fn radiosity(&self, out: &mut Vec<Rgb>) {
        out.clear();
        out.extend_from_slice(&self.b);
    }

    fn unshot(&self) -> Option<std::borrow::Cow<'_, [Rgb]>> {
        Some(std::borrow::Cow::Borrowed(&self.unshot))
    }

    fn unshot_fraction(&mut self, _: &mut dyn Operator, _: bool) -> f64 {
        self.unshot_fraction_now()
    }

    fn iterations(&self) -> u64 {
        self.iterations
    }

    fn info(&mut self, _: &mut dyn Operator) -> Info {
        let unshot: Rgb = self
            .unshot
            .iter()
            .zip(&self.system.area)
            .map(|(u, a)| *u * *a)
            .sum();
        Info {
            iterations: self.iterations,
            converged: false,
            unshot_fraction: self.unshot_fraction_now(),
            seconds: 0.0,
            emitted: self.emitted,
            absorbed: self.absorbed,
            escaped: self.escaped,
            unshot,
            estimated_error: self.estimated_error,
            ray_seconds: self.timing.trace + self.timing.gather,
        }
    }
}
