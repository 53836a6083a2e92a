//! Monte Carlo form factors by ray shooting (000_59d10e371b5f300d.txt, "Randomized form factor
//! calculation", eq. 7 and its pseudo-code): `n` rays leave patch `i` from points uniform over its
//! area in cosine-distributed directions; if `k_j` of them hit patch `j` first (on its front
//! side), `F̂_ij = k_j / n`, an unbiased estimate with variance `F_ij (1 − F_ij) / n ≤ 1/(4n)`.
//!
//! A ray that escapes the scene or hits the back of a patch transfers nothing: surfaces are
//! one-sided, which keeps `A_i F_ij = A_j F_ji` (a back side neither sends nor receives).
//!
//! [`MonteCarloRows`] supplies rows to the shooting solvers on demand and caches them (sparse,
//! under a memory budget), so a patch that shoots again costs no rays. The number of rays of a
//! row grows with the power about to be shot from it (see [`MonteCarloParams::rays_for`]): an
//! emitter that carries a large share of the scene's power gets proportionally more rays, so
//! that each ray carries about the same power everywhere, which is what keeps the noise of the
//! direct lighting at the level of the indirect.
//!
//! Determinism: rays are traced in parallel in chunks of [`CHUNK`]; each chunk has its own
//! random stream keyed by `(seed, patch, row version, chunk)`, and the hits are counted in a
//! fixed order, so a row does not depend on the number of threads.

use super::{Entry, FormFactorStats};
use crate::accel::Bvh;
use crate::geom::orthonormal_basis;
use crate::geom::Ray;
use crate::mesh::Mesh;
use crate::sampling::{cosine_direction_in, stream, uniform};
use rand::Rng;
use rayon::prelude::*;
use std::time::Instant;

/// Rays per parallel task (and per random stream).
pub const CHUNK: usize = 32;
const MISS: u32 = u32::MAX;

/// Parameters of the Monte Carlo estimator.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MonteCarloParams {
    /// Rays per row (eq. 7's `n`) for a patch that shoots an average share of the power
    /// (`1/N` of the emitted power); the minimum for any row.
    pub rays: u32,
    /// Upper bound on the rays of one row.
    pub max_rays: u32,
    /// Seed of all random streams.
    pub seed: u64,
    /// Memory budget of the row cache, bytes. Rows beyond it are recomputed when needed.
    pub cache_bytes: usize,
}

impl Default for MonteCarloParams {
    fn default() -> Self {
        Self {
            rays: 256,
            max_rays: 1 << 24,
            seed: 1,
            cache_bytes: 2 << 30,
        }
    }
}

impl MonteCarloParams {
    /// Rays for a row of a patch about to shoot the fraction `share` of the scene's emitted
    /// power, in a mesh of `patches` patches: `max(rays, ⌈rays · patches · share⌉)`, at most
    /// `max_rays`. So every ray carries at most the power that a ray of an average patch carries.
    pub fn rays_for(&self, share: f64, patches: usize) -> u32 {
        let want = (self.rays as f64 * patches as f64 * share).ceil();
        (want.min(self.max_rays as f64) as u32)
            .max(self.rays)
            .max(1)
    }
}

/// Reusable buffers for estimating rows (no allocation per row once warmed up).
#[derive(Debug, Default)]
pub struct RowScratch {
    hits: Vec<u32>,
    counts: Vec<u32>,
    touched: Vec<u32>,
}

/// Estimate row `i` of F with `n` rays (eq. 7) into `out` (cleared first), using the random
/// streams of `(seed, i, version)`. Returns nothing; `out` holds `(j, k_j/n)` sorted by `j`.
pub fn estimate_row(
    mesh: &Mesh,
    bvh: &Bvh,
    i: usize,
    n: u32,
    seed: u64,
    version: u64,
    scratch: &mut RowScratch,
    out: &mut Vec<Entry>,
) {
    let n = n as usize;
    let offset = bvh.ray_offset();
    let patch = &mesh.patches[i];
    let normal = patch.normal;
    let (tangent, bitangent) = orthonormal_basis(normal);
    scratch.hits.clear();
    scratch.hits.resize(n, MISS);
    let trace = |c: usize, chunk: &mut [u32]| {
        let mut rng = stream(seed, i as u64, version, c as u64);
        for slot in chunk.iter_mut() {
            let (u1, u2, u3) = (uniform(&mut rng), uniform(&mut rng), uniform(&mut rng));
            let p = mesh.sample_point(i, u1, u2, u3);
            let d = cosine_direction_in(
                normal,
                tangent,
                bitangent,
                uniform(&mut rng),
                uniform(&mut rng),
            );
            let ray = Ray::new(p + normal * offset, d);
            *slot = match bvh.closest_hit(&ray, f32::INFINITY) {
                Some(h) if h.front && h.patch as usize != i => h.patch,
                _ => MISS,
            };
        }
    };
    if n > CHUNK {
        scratch
            .hits
            .par_chunks_mut(CHUNK)
            .enumerate()
            .for_each(|(c, chunk)| trace(c, chunk));
    } else {
        trace(0, &mut scratch.hits);
    }
    // Count hits per patch in a fixed order.
    if scratch.counts.len() < mesh.len() {
        scratch.counts.resize(mesh.len(), 0);
    }
    scratch.touched.clear();
    for &h in &scratch.hits {
        if h != MISS {
            let c = &mut scratch.counts[h as usize];
            if *c == 0 {
                scratch.touched.push(h);
            }
            *c += 1;
        }
    }
    scratch.touched.sort_unstable();
    out.clear();
    let inv_n = 1.0 / n as f64;
    for &j in &scratch.touched {
        let c = std::mem::take(&mut scratch.counts[j as usize]);
        out.push((j, (c as f64 * inv_n) as f32));
    }
}

/// Trace `count` rays from random patches (uniform over patch indices), from uniform points in
/// cosine-distributed directions: the incoherent rays of form-factor estimation, without the
/// coherence of tracing one patch's row at a time. Returns how many hit a front side. For
/// measuring ray-casting speed.
pub fn trace_random_rays(mesh: &Mesh, bvh: &Bvh, count: usize, seed: u64) -> u64 {
    let offset = bvh.ray_offset();
    let n = mesh.len() as u64;
    let chunks = count.div_ceil(1024);
    (0..chunks)
        .into_par_iter()
        .map(|c| {
            let mut rng = stream(seed, u64::MAX, 0, c as u64);
            let todo = (count - c * 1024).min(1024);
            let mut hits = 0u64;
            for _ in 0..todo {
                let i = ((rng.random::<u32>() as u64 * n) >> 32) as usize;
                let p =
                    mesh.sample_point(i, uniform(&mut rng), uniform(&mut rng), uniform(&mut rng));
                let n = mesh.patches[i].normal;
                let (t, b) = orthonormal_basis(n);
                let d = cosine_direction_in(n, t, b, uniform(&mut rng), uniform(&mut rng));
                if let Some(h) = bvh.closest_hit(&Ray::new(p + n * offset, d), f32::INFINITY) {
                    hits += h.front as u64;
                }
            }
            hits
        })
        .sum()
}

/// Every row of F with `rays` rays each (eq. 7), rows in parallel, as a stored matrix: for the
/// methods that need all rows before they start. Deterministic for a given seed.
pub fn estimate_all_rows(
    mesh: &Mesh,
    bvh: &Bvh,
    rays: u32,
    seed: u64,
) -> crate::solve::matrix::SparseMatrix {
    let rows: Vec<Vec<Entry>> = (0..mesh.len())
        .into_par_iter()
        .map_init(RowScratch::default, |scratch, i| {
            let mut row = Vec::new();
            estimate_row(mesh, bvh, i, rays, seed, 0, scratch, &mut row);
            row
        })
        .collect();
    crate::solve::matrix::SparseMatrix::from_rows(rows)
}

#[derive(Debug)]
struct Cached {
    entries: Box<[Entry]>,
    rays: u32,
}

/// Rows of F estimated on demand by [`estimate_row`] and cached.
#[derive(Debug)]
pub struct MonteCarloRows<'a> {
    mesh: &'a Mesh,
    bvh: &'a Bvh,
    params: MonteCarloParams,
    cache: Vec<Option<Cached>>,
    versions: Vec<u32>,
    scratch: RowScratch,
    current: Vec<Entry>,
    column: Vec<Entry>,
    offset: f32,
    stats: FormFactorStats,
}

impl<'a> MonteCarloRows<'a> {
    /// A row source over `mesh` (whose hierarchy is `bvh`).
    pub fn new(mesh: &'a Mesh, bvh: &'a Bvh, params: MonteCarloParams) -> Self {
        Self {
            mesh,
            bvh,
            params,
            cache: (0..mesh.len()).map(|_| None).collect(),
            versions: vec![0; mesh.len()],
            scratch: RowScratch::default(),
            current: Vec::new(),
            column: Vec::new(),
            offset: bvh.ray_offset(),
            stats: FormFactorStats::default(),
        }
    }

    /// Work done so far.
    pub fn stats(&self) -> FormFactorStats {
        self.stats
    }

    /// The rays used for the cached row `i`, if it is cached.
    pub fn cached_rays(&self, i: usize) -> Option<u32> {
        self.cache[i].as_ref().map(|c| c.rays)
    }
}

impl MonteCarloRows<'_> {
    /// Make row i available; true if it is in the cache, false if only in `current`.
    fn ensure_row(&mut self, i: usize, share: f64) -> bool {
        let need = self.params.rays_for(share, self.mesh.len());
        // A cached row is good enough unless the power now shot would want 4× more rays.
        if matches!(&self.cache[i], Some(c) if (c.rays as u64) * 4 >= need as u64) {
            return true;
        }
        let start = Instant::now();
        let version = self.versions[i] as u64;
        self.versions[i] += 1;
        estimate_row(
            self.mesh,
            self.bvh,
            i,
            need,
            self.params.seed,
            version,
            &mut self.scratch,
            &mut self.current,
        );
        self.stats.rows += 1;
        self.stats.rays += need as u64;
        self.stats.seconds += start.elapsed().as_secs_f64();
        let bytes = (self.current.len() * std::mem::size_of::<Entry>()) as u64;
        if let Some(old) = self.cache[i].take() {
            self.stats.cached_bytes -= (old.entries.len() * std::mem::size_of::<Entry>()) as u64;
            self.stats.cached_rows -= 1;
        }
        if self.stats.cached_bytes + bytes <= self.params.cache_bytes as u64 {
            self.stats.cached_bytes += bytes;
            self.stats.cached_rows += 1;
            self.cache[i] = Some(Cached {
                entries: self.current.as_slice().into(),
                rays: need,
            });
            true
        } else {
            false
        }
    }
}

impl crate::solve::RowSource for MonteCarloRows<'_> {
    fn len(&self) -> usize {
        self.mesh.len()
    }

    fn row(&mut self, i: usize, share: f64) -> &[Entry] {
        if self.ensure_row(i, share) {
            &self.cache[i].as_ref().expect("cached").entries
        } else {
            &self.current
        }
    }

    /// By reciprocity from row i: `F_ji = F_ij A_i / A_j` (000_… eq. 24).
    fn column(&mut self, i: usize, share: f64) -> &[Entry] {
        let cached = self.ensure_row(i, share);
        let row: &[Entry] = if cached {
            &self.cache[i].as_ref().expect("cached").entries
        } else {
            &self.current
        };
        let patches = &self.mesh.patches;
        let ai = patches[i].area;
        self.column.clear();
        self.column.extend(
            row.iter()
                .map(|&(j, f)| (j, f * ai / patches[j as usize].area)),
        );
        &self.column
    }

    /// One ray from a uniform point of patch i in a cosine-distributed direction.
    fn sample(&mut self, i: usize, rng: &mut crate::sampling::Rng64) -> Option<u32> {
        let p = self
            .mesh
            .sample_point(i, uniform(rng), uniform(rng), uniform(rng));
        let n = self.mesh.patches[i].normal;
        let (t, b) = orthonormal_basis(n);
        let d = cosine_direction_in(n, t, b, uniform(rng), uniform(rng));
        self.stats.rays += 1;
        match self
            .bvh
            .closest_hit(&Ray::new(p + n * self.offset, d), f32::INFINITY)
        {
            Some(h) if h.front && h.patch as usize != i => Some(h.patch),
            _ => None,
        }
    }
}
