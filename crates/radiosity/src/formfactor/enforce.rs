//! Corrections that make an estimated matrix physical (each optional, all off by default), and
//! the exact aggregation of patch rows into groups.

use crate::system::{Entry, SparseMatrix};

/// Optional corrections that make a matrix physical (all off by default).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Enforce {
    /// Drop negative entries (F ≥ 0).
    pub clamp: bool,
    /// Rescale every non-empty row to sum to 1 (only meaningful in a closed enclosure).
    pub normalize_rows: bool,
    /// Make A_i F_ij = A_j F_ji while keeping each row's sum.
    pub symmetrize: bool,
}

/// Apply `e` to `m` (areas `area`). Symmetrisation takes the symmetric exchange matrix
/// G = (A F + (A F)ᵀ)/2 and scales it as D G D with a positive diagonal D so that each row of
/// D G D sums to A_i × (row i's sum before). That is the symmetric matrix-scaling problem, solved
/// by the fixed-point iteration d_i ← √(d_i t_i / (G d)_i) (Knight, "The Sinkhorn–Knopp
/// algorithm: convergence and applications", SIAM J. Matrix Anal. Appl. 30, 2008, section 5),
/// to a relative error of 1e-12. F' = D G D / A is then reciprocal with the original row sums.
pub fn enforce(m: SparseMatrix, area: &[f64], e: Enforce) -> SparseMatrix {
    let n = m.n();
    let mut rows: Vec<Vec<Entry>> = (0..n).map(|i| m.row_entries(i).to_vec()).collect();
    if e.clamp {
        rows.iter_mut().for_each(|r| r.retain(|x| x.1 > 0.0));
    }
    if e.normalize_rows {
        for r in &mut rows {
            let s: f64 = r.iter().map(|x| x.1 as f64).sum();
            if s > 0.0 {
                r.iter_mut().for_each(|x| x.1 = (x.1 as f64 / s) as f32);
            }
        }
    }
    if e.symmetrize {
        let m = SparseMatrix::from_rows(rows);
        let target: Vec<f64> = (0..n).map(|i| m.row_sum(i) * area[i]).collect();
        // G on the union pattern of F and Fᵀ.
        let g: Vec<Vec<(u32, f64)>> = (0..n)
            .map(|i| {
                let (r, c) = (m.row_entries(i), m.column_entries(i));
                let (mut a, mut b) = (0, 0);
                let mut out = Vec::with_capacity(r.len().max(c.len()));
                while a < r.len() || b < c.len() {
                    let ja = r.get(a).map_or(u32::MAX, |x| x.0);
                    let jb = c.get(b).map_or(u32::MAX, |x| x.0);
                    let j = ja.min(jb);
                    let mut v = 0.0;
                    if ja == j {
                        v += area[i] * r[a].1 as f64;
                        a += 1;
                    }
                    if jb == j {
                        v += area[j as usize] * c[b].1 as f64;
                        b += 1;
                    }
                    out.push((j, 0.5 * v));
                }
                out
            })
            .collect();
        let mut d = vec![1.0f64; n];
        for _ in 0..10_000 {
            let gd: Vec<f64> = g
                .iter()
                .map(|r| r.iter().map(|&(j, v)| v * d[j as usize]).sum())
                .collect();
            let mut worst: f64 = 0.0;
            for i in 0..n {
                if gd[i] > 0.0 && target[i] > 0.0 {
                    worst = worst.max((d[i] * gd[i] / target[i] - 1.0).abs());
                    d[i] = (d[i] * target[i] / gd[i]).sqrt();
                }
            }
            if worst < 1e-12 {
                break;
            }
        }
        rows = g
            .iter()
            .enumerate()
            .map(|(i, r)| {
                r.iter()
                    .map(|&(j, v)| (j, (d[i] * v * d[j as usize] / area[i]) as f32))
                    .filter(|x| x.1 > 0.0)
                    .collect()
            })
            .collect();
    }
    SparseMatrix::from_rows(rows)
}

/// Merge patches into groups (e.g. the pieces of each input face): F_IJ = Σ_{i∈I} (A_i/A_I)
/// Σ_{j∈J} F_ij, exact for any partition. Returns the grouped matrix and the groups' areas.
pub fn aggregate(
    m: &SparseMatrix,
    area: &[f64],
    group: &[u32],
    groups: usize,
) -> (SparseMatrix, Vec<f64>) {
    let mut group_area = vec![0.0; groups];
    for (i, &g) in group.iter().enumerate() {
        group_area[g as usize] += area[i];
    }
    let mut triplets = Vec::with_capacity(m.nnz());
    for (i, j, f) in m.triplets() {
        let (gi, gj) = (group[i], group[j as usize]);
        let w = area[i] / group_area[gi as usize];
        triplets.push((gi, gj, (w * f as f64) as f32));
    }
    (SparseMatrix::from_triplets(groups, triplets), group_area)
}
