//! Rows of F computed when a solver asks for them, by any [`Estimator`], and cached under a
//! memory budget: the [`Operator`] that lets shooting methods run without a stored matrix.
//!
//! This is how Szirmay-Kalos & Márton (1995) run progressive refinement with a hemicube:
//! "having selected a surface, the corresponding column of the form factor matrix should be
//! calculated", one hemicube per shot, the column obtained from the row by reciprocity (their
//! eq. 24). Memory is O(N) plus the cache ([`Params::cache_bytes`], 0 for none) instead of the
//! O(N²) of a stored matrix; the price is recomputing a row that was not kept when its patch
//! shoots again.
//!
//! Monte Carlo rows get rays in proportion to the power about to be shot ([`Params::rays_for`]);
//! a cached row is reused unless the power now shot would want 4× its rays, and a row estimated
//! again gets fresh random streams (its version). Photons ([`PhotonSampler`]) are single rays,
//! for Monte Carlo only.

use super::{
    monte_carlo, Effort, Entry, Estimator, FormFactorMethod, FormFactorStats, Params, Scratch,
};
use crate::sampling::Rng64;
use crate::system::{Operator, PhotonSampler};
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

#[derive(Debug)]
struct Cached {
    entries: Box<[Entry]>,
    rays: u32,
    /// `F_ii`, kept aside while the row is in the cache: a shot needs it first, and searching
    /// a row read from memory for it waits on a cache miss at every step.
    diagonal: f32,
}

/// An [`Operator`] whose rows an estimator computes when asked, cached under a budget.
#[derive(Debug)]
pub struct OnDemandRows<'a> {
    estimator: Estimator<'a>,
    cache: Vec<Option<Cached>>,
    versions: Vec<u32>,
    scratch: Scratch,
    /// The last row computed, when it is not in the cache, and its `F_ii`.
    current: Vec<Entry>,
    current_diagonal: f32,
    current_row: Option<usize>,
    column: Vec<Entry>,
    stats: FormFactorStats,
    /// Photon rays cast (from any thread).
    photon_rays: AtomicU64,
}

impl<'a> OnDemandRows<'a> {
    /// Rows by `estimator`, cached under its parameters' `cache_bytes`.
    pub fn new(estimator: Estimator<'a>) -> Self {
        let n = estimator.mesh().len();
        Self {
            estimator,
            cache: (0..n).map(|_| None).collect(),
            versions: vec![0; n],
            scratch: Scratch::default(),
            current: Vec::new(),
            current_diagonal: 0.0,
            current_row: None,
            column: Vec::new(),
            stats: FormFactorStats::default(),
            photon_rays: AtomicU64::new(0),
        }
    }

    /// Work done so far.
    pub fn stats(&self) -> FormFactorStats {
        let mut s = self.stats;
        s.rays += self.photon_rays.load(Ordering::Relaxed);
        s
    }

    /// The Monte Carlo rays of the cached row `i`, if it is cached.
    pub fn cached_rays(&self, i: usize) -> Option<u32> {
        self.cache[i].as_ref().map(|c| c.rays)
    }

    fn params(&self) -> &Params {
        self.estimator.params()
    }

    /// Make row i available; true if it is in the cache, false if only in `current`.
    fn ensure_row(&mut self, i: usize, share: f64) -> bool {
        let monte_carlo = self.params().method == FormFactorMethod::MonteCarlo;
        let need = if monte_carlo {
            self.params().rays_for(share, self.cache.len())
        } else {
            0
        };
        // A cached row is good enough unless the power now shot would want 4× more rays.
        if matches!(&self.cache[i], Some(c) if (c.rays as u64) * 4 >= need as u64) {
            return true;
        }
        if !monte_carlo && self.current_row == Some(i) {
            return false;
        }
        let start = Instant::now();
        let version = self.versions[i] as u64;
        self.versions[i] += 1;
        self.estimator.row_with(
            i,
            Effort {
                rays: need,
                version,
            },
            &mut self.scratch,
            &mut self.current,
        );
        self.current_row = Some(i);
        self.current_diagonal = self
            .current
            .binary_search_by_key(&(i as u32), |e| e.0)
            .map_or(0.0, |k| self.current[k].1);
        self.stats.rows += 1;
        self.stats.rays += need as u64;
        let bytes = (self.current.len() * std::mem::size_of::<Entry>()) as u64;
        if let Some(old) = self.cache[i].take() {
            self.stats.cached_bytes -= (old.entries.len() * std::mem::size_of::<Entry>()) as u64;
            self.stats.cached_rows -= 1;
        }
        let cached = self.stats.cached_bytes + bytes <= self.params().cache_bytes as u64;
        if cached {
            self.stats.cached_bytes += bytes;
            self.stats.cached_rows += 1;
            // The row was estimated into exactly its length ([`Estimator::row_with`]): kept
            // as it is, not copied. A copy cost most of its time in the first touch of the
            // cache's fresh memory (docs/notes/library.md), which the estimator pays as it
            // writes the row, inside this row's time.
            self.cache[i] = Some(Cached {
                entries: std::mem::take(&mut self.current).into_boxed_slice(),
                rays: need,
                diagonal: self.current_diagonal,
            });
            self.current_row = None;
        }
        self.stats.seconds += start.elapsed().as_secs_f64();
        cached
    }

    fn row_slice(&self, i: usize, cached: bool) -> &[Entry] {
        if cached {
            &self.cache[i].as_ref().expect("cached").entries
        } else {
            &self.current
        }
    }
}

impl Operator for OnDemandRows<'_> {
    fn len(&self) -> usize {
        self.cache.len()
    }

    fn row(&mut self, i: usize, share: f64) -> &[Entry] {
        let cached = self.ensure_row(i, share);
        self.row_slice(i, cached)
    }

    /// By reciprocity from row i: `F_ji = F_ij A_i / A_j` (Szirmay-Kalos & Márton, eq. 24).
    fn column(&mut self, i: usize, share: f64) -> &[Entry] {
        let cached = self.ensure_row(i, share);
        let patches = &self.estimator.mesh().patches;
        let ai = patches[i].area;
        let mut column = std::mem::take(&mut self.column);
        column.clear();
        column.extend(
            self.row_slice(i, cached)
                .iter()
                .map(|&(j, f)| (j, f * ai / patches[j as usize].area)),
        );
        self.column = column;
        &self.column
    }

    /// The row itself: the solver applies reciprocity as it reads each receiver.
    fn shot_column(&mut self, i: usize, share: f64) -> crate::system::Column<'_> {
        let cached = self.ensure_row(i, share);
        let diagonal = match &self.cache[i] {
            Some(c) if cached => c.diagonal,
            _ => self.current_diagonal,
        };
        crate::system::Column::Reciprocal {
            row: self.row_slice(i, cached),
            diagonal: Some(diagonal),
            // Every estimate of row i has a version of its own, the last one the row in hand.
            id: Some(self.versions[i] as u64),
        }
    }

    /// Monte Carlo only: photons are single rays, which threads can cast at once. Rows of the
    /// other methods are computed when asked, which a shared sampler cannot do.
    fn photons(&self) -> Option<&dyn PhotonSampler> {
        (self.params().method == FormFactorMethod::MonteCarlo).then_some(self as &dyn PhotonSampler)
    }
}

impl PhotonSampler for OnDemandRows<'_> {
    /// One ray from a uniform point of patch i in a cosine-distributed direction.
    fn sample(&self, i: usize, rng: &mut Rng64) -> Option<u32> {
        self.photon_rays.fetch_add(1, Ordering::Relaxed);
        monte_carlo::sample_photon(self.estimator.mesh(), self.estimator.bvh(), i, rng)
    }

    /// The same rays, cast several at a time ([`monte_carlo::sample_photons`]).
    fn sample_many(&self, sources: &[u32], rng: &mut Rng64, out: &mut [u32]) {
        self.photon_rays
            .fetch_add(sources.len() as u64, Ordering::Relaxed);
        let (mesh, bvh) = (self.estimator.mesh(), self.estimator.bvh());
        monte_carlo::sample_photons(mesh, bvh, sources, rng, out);
    }

    /// The same ray, unless the point is covered ([`monte_carlo::gather_photon`]).
    fn gather(&self, i: usize, rng: &mut Rng64) -> crate::system::Gathered {
        self.photon_rays.fetch_add(1, Ordering::Relaxed);
        monte_carlo::gather_photon(self.estimator.mesh(), self.estimator.bvh(), i, rng)
    }

    /// The same rays, cast several at a time ([`monte_carlo::gather_photons`]).
    fn gather_many(
        &self,
        patches: &[u32],
        per: usize,
        rngs: &mut [Rng64],
        out: &mut [crate::system::Gathered],
    ) {
        self.photon_rays
            .fetch_add((patches.len() * per) as u64, Ordering::Relaxed);
        let (mesh, bvh) = (self.estimator.mesh(), self.estimator.bvh());
        monte_carlo::gather_photons(mesh, bvh, patches, per, rngs, out);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::Bvh;
    use crate::formfactor::{FormFactorMethod, Params, Storage};
    use crate::mesh::Mesh;
    use crate::mesh::MeshParams;
    use crate::scene::builtin;
    use crate::system::Operator;

    /// Photons cast several at a time land where they land one at a time, with the same
    /// draws from the random stream (which then goes on in step).
    #[test]
    fn photons_in_batches_are_the_photons_one_at_a_time() {
        use crate::system::PhotonSampler;
        let scene = builtin::cornell();
        let mesh = Mesh::build(&scene, MeshParams::Patches(500)).unwrap();
        let bvh = Bvh::build(&mesh);
        let params = Params {
            method: FormFactorMethod::MonteCarlo,
            ..Default::default()
        };
        let rows = OnDemandRows::new(Estimator::new(&mesh, &bvh, params).unwrap());
        let sources: Vec<u32> = (0..300).map(|k| (k * 7 % mesh.len()) as u32).collect();
        let mut a = crate::sampling::stream(3, 1, 4, 1);
        let mut b = a.clone();
        let one: Vec<u32> = sources
            .iter()
            .map(|&i| rows.sample(i as usize, &mut a).unwrap_or(u32::MAX))
            .collect();
        let mut many = vec![0; sources.len()];
        rows.sample_many(&sources, &mut b, &mut many);
        assert_eq!(many, one);
        assert!(one.iter().filter(|&&j| j != u32::MAX).count() > 200);
        assert_eq!(
            crate::sampling::uniform(&mut a),
            crate::sampling::uniform(&mut b)
        );
    }

    /// Rows on demand are the rows of the stored matrix, and columns follow by reciprocity.
    #[test]
    fn on_demand_rows_match_the_stored_matrix() {
        let scene = builtin::cube(builtin::CubeVariant::Dim);
        let mesh = Mesh::build(&scene, MeshParams::Patches(60)).unwrap();
        let bvh = Bvh::build(&mesh);
        let params = Params {
            method: FormFactorMethod::Hemicube,
            resolution: 32,
            samples: 1,
            ..Default::default()
        };
        let mut stored = Estimator::new(&mesh, &bvh, params)
            .unwrap()
            .matrix(Storage::Sparse, &crate::observe::Silent)
            .into_sparse();
        let mut rows = OnDemandRows::new(Estimator::new(&mesh, &bvh, params).unwrap());
        for i in [0, 7, mesh.len() - 1] {
            assert_eq!(rows.row(i, 0.0), stored.row(i, 0.0));
            let column = rows.column(i, 0.0).to_vec();
            for (j, f) in column {
                let fij = stored.row_entries(i).iter().find(|e| e.0 == j).unwrap().1;
                let (ai, aj) = (mesh.patches[i].area, mesh.patches[j as usize].area);
                assert!((f - fij * ai / aj).abs() <= 1e-6 * f.abs().max(1e-9));
            }
        }
        assert_eq!(rows.stats().rows, 3);
    }
}
