//! Form factors: `F_ij`, the fraction of the energy leaving patch `i` that arrives directly at
//! patch `j` (000_59d10e371b5f300d.txt eq. 6). Rows are sparse: a row holds only the patches a
//! method found, sorted by patch index, so that no N × N array is ever allocated.
//!
//! Methods, one file each: [`monte_carlo`] (eq. 7, ray shooting).

pub mod monte_carlo;

/// One non-zero entry of a row of F: `(j, F_ij)`.
pub type Entry = (u32, f32);

/// Statistics of form-factor work.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FormFactorStats {
    /// Rows estimated (including re-estimates).
    pub rows: u64,
    /// Rays cast.
    pub rays: u64,
    /// Wall-clock seconds spent estimating rows.
    pub seconds: f64,
    /// Rows currently held in the cache.
    pub cached_rows: u64,
    /// Bytes held by cached rows.
    pub cached_bytes: u64,
}
