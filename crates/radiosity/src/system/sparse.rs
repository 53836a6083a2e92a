//! A stored form-factor matrix: sparse, both by rows (CSR) and by columns (CSC), with
//! per-row cumulative sums for sampling photons. Never allocated as N × N: memory is
//! proportional to the number of non-zero entries.

use super::{Entry, Operator, PhotonSampler};
use crate::sampling::{uniform, Rng64};

/// A sparse N × N form-factor matrix.
#[derive(Clone, Debug, Default)]
pub struct SparseMatrix {
    n: usize,
    row_ptr: Vec<usize>,
    rows: Vec<Entry>,
    /// Cumulative sums of each row's entries, for sampling.
    cumulative: Vec<f32>,
    col_ptr: Vec<usize>,
    cols: Vec<Entry>,
}

impl SparseMatrix {
    /// From rows: `rows[i]` holds `(j, F_ij)` sorted by `j`, without duplicates.
    pub fn from_rows(rows: Vec<Vec<Entry>>) -> Self {
        let n = rows.len();
        let mut row_ptr = Vec::with_capacity(n + 1);
        row_ptr.push(0);
        let nnz: usize = rows.iter().map(Vec::len).sum();
        let mut flat = Vec::with_capacity(nnz);
        for r in rows {
            flat.extend_from_slice(&r);
            row_ptr.push(flat.len());
        }
        Self::from_csr(n, row_ptr, flat)
    }

    /// From triplets `(i, j, F_ij)`, 0-based, in any order; duplicates are summed.
    pub fn from_triplets(n: usize, mut t: Vec<(u32, u32, f32)>) -> Self {
        t.sort_unstable_by_key(|e| (e.0, e.1));
        let mut rows: Vec<Vec<Entry>> = vec![Vec::new(); n];
        for (i, j, v) in t {
            let r = &mut rows[i as usize];
            match r.last_mut() {
                Some(last) if last.0 == j => last.1 += v,
                _ => r.push((j, v)),
            }
        }
        Self::from_rows(rows)
    }

    /// From compressed rows: row `i` is `rows[row_ptr[i]..row_ptr[i + 1]]`, sorted by column,
    /// without duplicates.
    pub(crate) fn from_csr(n: usize, row_ptr: Vec<usize>, rows: Vec<Entry>) -> Self {
        let mut cumulative = Vec::with_capacity(rows.len());
        for i in 0..n {
            let mut acc = 0.0f32;
            for e in &rows[row_ptr[i]..row_ptr[i + 1]] {
                acc += e.1;
                cumulative.push(acc);
            }
        }
        // Transpose by counting.
        let mut count = vec![0usize; n + 1];
        for e in &rows {
            count[e.0 as usize + 1] += 1;
        }
        for k in 0..n {
            count[k + 1] += count[k];
        }
        let col_ptr = count.clone();
        let mut cols = vec![(0u32, 0f32); rows.len()];
        let mut next = count;
        for i in 0..n {
            for e in &rows[row_ptr[i]..row_ptr[i + 1]] {
                let c = e.0 as usize;
                cols[next[c]] = (i as u32, e.1);
                next[c] += 1;
            }
        }
        Self {
            n,
            row_ptr,
            rows,
            cumulative,
            col_ptr,
            cols,
        }
    }

    /// Number of rows (= columns).
    pub fn n(&self) -> usize {
        self.n
    }

    /// Number of stored entries.
    pub fn nnz(&self) -> usize {
        self.rows.len()
    }

    /// Bytes held.
    pub fn bytes(&self) -> usize {
        self.rows.len() * (2 * std::mem::size_of::<Entry>() + 4) + (2 * self.n + 2) * 8
    }

    /// Row `i`.
    pub fn row_entries(&self, i: usize) -> &[Entry] {
        &self.rows[self.row_ptr[i]..self.row_ptr[i + 1]]
    }

    /// Column `i`: `(j, F_ji)`.
    pub fn column_entries(&self, i: usize) -> &[Entry] {
        &self.cols[self.col_ptr[i]..self.col_ptr[i + 1]]
    }

    /// Sum of row `i`.
    pub fn row_sum(&self, i: usize) -> f64 {
        self.row_entries(i).iter().map(|e| e.1 as f64).sum()
    }

    /// All entries `(i, j, F_ij)` in row order.
    pub fn triplets(&self) -> impl Iterator<Item = (usize, u32, f32)> + '_ {
        (0..self.n).flat_map(move |i| self.row_entries(i).iter().map(move |e| (i, e.0, e.1)))
    }
}

impl Operator for SparseMatrix {
    fn len(&self) -> usize {
        self.n
    }

    fn row(&mut self, i: usize, _share: f64) -> &[Entry] {
        self.row_entries(i)
    }

    fn column(&mut self, i: usize, _share: f64) -> &[Entry] {
        self.column_entries(i)
    }

    fn photons(&self) -> Option<&dyn PhotonSampler> {
        Some(self)
    }
}

/// A draw from the stored row by its cumulative sums.
impl PhotonSampler for SparseMatrix {
    fn sample(&self, i: usize, rng: &mut Rng64) -> Option<u32> {
        let (a, b) = (self.row_ptr[i], self.row_ptr[i + 1]);
        if a == b {
            return None;
        }
        let cum = &self.cumulative[a..b];
        let u = uniform(rng);
        if u >= cum[cum.len() - 1] {
            return None;
        }
        let k = cum.partition_point(|&c| c <= u);
        Some(self.rows[a + k.min(b - a - 1)].0)
    }
}
