//! What a form-factor matrix looks like: row sums, reciprocity, fill, the smallest entry.

use crate::system::SparseMatrix;

/// What a matrix looks like: row sums, reciprocity, fill.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Summary {
    /// Smallest row sum.
    pub min_row_sum: f64,
    /// Largest row sum.
    pub max_row_sum: f64,
    /// Largest |A_i F_ij − A_j F_ji| / ((A_i + A_j)/2), in units of F.
    pub worst_reciprocity: f64,
    /// Stored entries over N².
    pub fill: f64,
    /// Smallest entry (negative only for unclamped numerical noise).
    pub min_entry: f64,
}

/// Summarise `m` with patch areas `area`.
pub fn summary(m: &SparseMatrix, area: &[f64]) -> Summary {
    let n = m.n();
    let mut s = Summary {
        min_row_sum: f64::INFINITY,
        max_row_sum: f64::NEG_INFINITY,
        worst_reciprocity: 0.0,
        fill: m.nnz() as f64 / (n as f64 * n as f64),
        min_entry: 0.0,
    };
    for i in 0..n {
        let rs = m.row_sum(i);
        s.min_row_sum = s.min_row_sum.min(rs);
        s.max_row_sum = s.max_row_sum.max(rs);
        let (r, c) = (m.row_entries(i), m.column_entries(i));
        // Merge row i (F_ij) with column i (F_ji).
        let (mut a, mut b) = (0, 0);
        while a < r.len() || b < c.len() {
            let ja = r.get(a).map_or(u32::MAX, |x| x.0);
            let jb = c.get(b).map_or(u32::MAX, |x| x.0);
            let j = ja.min(jb);
            let fij = if ja == j { r[a].1 as f64 } else { 0.0 };
            let fji = if jb == j { c[b].1 as f64 } else { 0.0 };
            s.min_entry = s.min_entry.min(fij);
            let jj = j as usize;
            let mismatch = (area[i] * fij - area[jj] * fji).abs() / (0.5 * (area[i] + area[jj]));
            s.worst_reciprocity = s.worst_reciprocity.max(mismatch);
            if ja == j {
                a += 1;
            }
            if jb == j {
                b += 1;
            }
        }
    }
    s
}
