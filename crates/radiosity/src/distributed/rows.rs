//! Rows of F split over ranks: each rank computes the rows of its block of patches, balanced by
//! their estimated cost, and keeps them ([`RowBlock`]); [`gather_matrix`] assembles the whole
//! matrix on one rank for writing. Every row has its own random streams (keyed by the row, not
//! the rank), so the matrix is the same bytes for any number of ranks.

use crate::comm::{balance, Ranks};
use crate::formfactor::{monte_carlo, Estimator, FormFactorMethod, Scratch};
use crate::observe::{Event, Observer, Stage};
use crate::sampling::stream;
use crate::system::{Entry, SparseMatrix};
use rayon::prelude::*;
use std::ops::Range;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

/// Patches a pilot chunk times together.
const PILOT_CHUNK: usize = 64;
/// Pilot rays per patch.
const PILOT_RAYS: usize = 4;

/// The rows of F of a contiguous block of patches, CSR.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RowBlock {
    /// The patches whose rows these are.
    pub range: Range<usize>,
    /// `entries[ptr[k]..ptr[k + 1]]` is row `range.start + k`.
    pub ptr: Vec<usize>,
    /// `(j, F_ij)`, each row sorted by j.
    pub entries: Vec<Entry>,
}

impl RowBlock {
    /// Row `i` (a patch of the block).
    pub fn row(&self, i: usize) -> &[Entry] {
        let k = i - self.range.start;
        &self.entries[self.ptr[k]..self.ptr[k + 1]]
    }

    /// Stored entries.
    pub fn nnz(&self) -> usize {
        self.entries.len()
    }

    /// Bytes held.
    pub fn bytes(&self) -> usize {
        self.ptr.len() * 8 + self.entries.len() * 8
    }
}

/// The estimated cost of each row of F, the same on every rank. Monte Carlo rows cost their rays
/// times the depth of the BVH where the rays go, which varies over the scene: it is measured by a
/// pilot of a few rays a patch, timed per chunk of patches, the chunks split over the ranks and
/// the timings all-gathered. The other methods' rows cost about the same (a hemicube
/// rasterizes every patch for every row; the analytic method visits every pair).
pub fn row_costs(estimator: &Estimator<'_>, ranks: &Ranks<'_>) -> Vec<f64> {
    let mesh = estimator.mesh();
    let n = mesh.len();
    if estimator.params().method != FormFactorMethod::MonteCarlo || n == 0 {
        return vec![1.0; n];
    }
    let bvh = estimator.bvh();
    let chunks = n.div_ceil(PILOT_CHUNK);
    let mine = &super::balance(&vec![1.0; chunks], ranks.size())[ranks.rank()];
    let seed = estimator.params().seed;
    let timed: Vec<f64> = mine
        .clone()
        .into_par_iter()
        .map(|c| {
            // The faster of two passes: the first may pay for cold caches, page faults or a
            // descheduled thread, none of which the real rows will.
            let pass = || {
                let t = Instant::now();
                for i in c * PILOT_CHUNK..((c + 1) * PILOT_CHUNK).min(n) {
                    let mut rng = stream(seed, i as u64, u64::MAX - 1, 0);
                    for _ in 0..PILOT_RAYS {
                        std::hint::black_box(monte_carlo::sample_photon(mesh, bvh, i, &mut rng));
                    }
                }
                t.elapsed().as_secs_f64()
            };
            pass().min(pass())
        })
        .collect();
    let all = ranks.all_gather(&timed);
    // A fixed part per row (sampling, accumulating) beside the measured tracing.
    let floor = all.iter().sum::<f64>() / n as f64 * 0.1;
    (0..n)
        .map(|i| floor + all[i / PILOT_CHUNK] / PILOT_CHUNK as f64)
        .collect()
}

/// Each rank's block of patches for rows of these costs.
pub fn blocks(costs: &[f64], ranks: &Ranks<'_>) -> Vec<Range<usize>> {
    balance(costs, ranks.size())
}

/// Compute the rows of `range` in parallel (rayon), reporting progress over the whole matrix
/// as `done` scaled by the number of ranks (every rank advances at about the same pace).
pub fn compute(
    estimator: &Estimator<'_>,
    range: Range<usize>,
    scale: u64,
    observer: &dyn Observer,
) -> RowBlock {
    let total = estimator.mesh().len() as u64;
    observer.event(Event::Stage(Stage::FormFactors));
    let done = AtomicU64::new(0);
    let rows: Vec<Vec<Entry>> = range
        .clone()
        .into_par_iter()
        .map_init(Scratch::default, |scratch, i| {
            let mut row = Vec::new();
            estimator.row(i, scratch, &mut row);
            let d = done.fetch_add(1, Ordering::Relaxed) + 1;
            observer.event(Event::Progress {
                stage: Stage::FormFactors,
                done: (d * scale).min(total),
                total,
            });
            row
        })
        .collect();
    let mut ptr = Vec::with_capacity(rows.len() + 1);
    ptr.push(0);
    let mut entries = Vec::with_capacity(rows.iter().map(Vec::len).sum());
    for r in rows {
        entries.extend_from_slice(&r);
        ptr.push(entries.len());
    }
    RowBlock {
        range,
        ptr,
        entries,
    }
}

/// This rank's share of F: the row costs estimated, the blocks recorded in `report` (with the
/// pilot's time and every rank's stored entries), and this rank's rows computed. Returns them
/// and the seconds the rows took.
pub fn split(
    estimator: &Estimator<'_>,
    ranks: &Ranks<'_>,
    observer: &dyn Observer,
    report: &mut super::Report,
) -> (RowBlock, f64) {
    let t = Instant::now();
    let costs = row_costs(estimator, ranks);
    report.pilot_seconds = t.elapsed().as_secs_f64();
    report.blocks = blocks(&costs, ranks);
    let t = Instant::now();
    let block = compute(
        estimator,
        report.blocks[ranks.rank()].clone(),
        ranks.size() as u64,
        observer,
    );
    let busy = t.elapsed().as_secs_f64();
    report.stored_entries = ranks.all_gather(&[block.nnz() as u64]);
    (block, busy)
}

/// Every rank's block, assembled into the whole matrix on `root` (`None` elsewhere).
pub fn gather_matrix(
    block: &RowBlock,
    n: usize,
    root: usize,
    ranks: &Ranks<'_>,
) -> Option<SparseMatrix> {
    let lengths = ranks.gather(root, &row_lengths(block));
    let entries = ranks.gather(root, &block.entries);
    (ranks.rank() == root).then(|| assemble(n, &lengths, &entries))
}

/// Every rank's block, assembled into the whole matrix on every rank.
pub fn all_gather_matrix(block: &RowBlock, n: usize, ranks: &Ranks<'_>) -> SparseMatrix {
    let lengths = ranks.all_gather(&row_lengths(block));
    let entries = ranks.all_gather(&block.entries);
    assemble(n, &lengths, &entries)
}

fn row_lengths(block: &RowBlock) -> Vec<u32> {
    block.ptr.windows(2).map(|w| (w[1] - w[0]) as u32).collect()
}

fn assemble(n: usize, lengths: &[u32], entries: &[Entry]) -> SparseMatrix {
    debug_assert_eq!(lengths.len(), n);
    let mut rows = Vec::with_capacity(n);
    let mut at = 0;
    for &len in lengths {
        let len = len as usize;
        rows.push(entries[at..at + len].to_vec());
        at += len;
    }
    SparseMatrix::from_rows(rows)
}
