//! F as an operator, and the separate photon-drawing interface.

use super::Entry;
use crate::color::Rgb;
use crate::sampling::Rng64;
use std::ops::Range;

/// The form-factor matrix F as the solvers see it: rows and columns on demand, blocks of rows,
/// and the products `F x` and `Fᵀ x`. A stored [`super::SparseMatrix`] implements it, and so do
/// estimators that compute rows when asked (`formfactor::OnDemandRows`), so solvers never
/// depend on how F was obtained. Methods take `&mut self` because an estimator may compute and
/// cache what it hands out.
pub trait Operator {
    /// Number of rows (= columns = patches).
    fn len(&self) -> usize;

    /// True when there are no rows.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Row `i` of F: `(j, F_ij)` for the non-zero entries, sorted by `j`. `share` is the fraction
    /// of the scene's emitted power the caller is about to shoot from `i`; estimators may use
    /// it to choose their effort, stored matrices ignore it.
    fn row(&mut self, i: usize, share: f64) -> &[Entry];

    /// Column `i` of F: `(j, F_ji)` for the non-zero entries, sorted by `j`: where the energy
    /// shot from `i` lands, as fractions of each receiver's own exitance (shooting needs it,
    /// Szirmay-Kalos & Márton 1995, eq. 23–24). `share` as for [`Operator::row`].
    fn column(&mut self, i: usize, share: f64) -> &[Entry];

    /// Column `i` as a shooting solver takes it: [`Operator::column`], or row `i` itself when
    /// the operator holds rows and would only turn the row into the column by reciprocity.
    /// The solver then does that on the fly, with the system's areas, where it reads each
    /// receiver anyway: one pass over the receivers instead of two.
    fn shot_column(&mut self, i: usize, share: f64) -> Column<'_> {
        Column::Entries(self.column(i, share))
    }

    /// Rows `range`, in order, each handed to `each` with its index: the unit of work that
    /// distributed or blocked methods share out.
    fn rows(&mut self, range: Range<usize>, each: &mut dyn FnMut(usize, &[Entry])) {
        for i in range {
            each(i, self.row(i, 0.0));
        }
    }

    /// `y = F x` (`y` has one value per row).
    fn apply(&mut self, x: &[Rgb], y: &mut [Rgb]) {
        let n = self.len();
        self.rows(0..n, &mut |i, row| {
            y[i] = row.iter().map(|&(j, f)| x[j as usize] * f as f64).sum();
        });
    }

    /// `y = Fᵀ x`.
    fn apply_transpose(&mut self, x: &[Rgb], y: &mut [Rgb]) {
        y.iter_mut().for_each(|v| *v = Rgb::BLACK);
        let n = self.len();
        self.rows(0..n, &mut |i, row| {
            for &(j, f) in row {
                y[j as usize] += x[i] * f as f64;
            }
        });
    }

    /// The photon sampler that goes with this operator, if it has one (the photon-shooting
    /// and stochastic Jacobi solvers need it).
    fn photons(&self) -> Option<&dyn PhotonSampler> {
        None
    }
}

/// Column `i` of F as [`Operator::shot_column`] hands it out.
#[derive(Clone, Copy, Debug)]
pub enum Column<'a> {
    /// `(j, F_ji)`, sorted by `j`.
    Entries(&'a [Entry]),
    /// Row `i`, `(j, F_ij)` sorted by `j`, to be read as the column by reciprocity
    /// (Szirmay-Kalos & Márton 1995, eq. 24): `F_ji = F_ij A_i / A_j`, computed in `f32` as
    /// `(F_ij · A_i) / A_j` with the system's areas.
    Reciprocal {
        /// Row `i`.
        row: &'a [Entry],
        /// `F_ii` (0 where the row has no entry `i`) if the operator kept it aside, so that a
        /// solver need not search a row that is not in the cache for it; `None`: search.
        diagonal: Option<f32>,
        /// What tells this row apart from the other rows this operator hands out for patch
        /// `i`: the same id for the same entries whenever the row is handed out again (a
        /// cached row; a stored matrix can give one id for all), so that a solver may keep
        /// what it derives from the row under it. `None`: nothing is to be kept.
        id: Option<u64>,
    },
}

impl<'a> Column<'a> {
    /// The entries, whichever way they are to be read.
    pub fn entries(&self) -> &'a [Entry] {
        match *self {
            Column::Entries(e) | Column::Reciprocal { row: e, .. } => e,
        }
    }

    /// The row's id ([`Column::Reciprocal`]), if it has one.
    pub fn id(&self) -> Option<u64> {
        match *self {
            Column::Entries(_) => None,
            Column::Reciprocal { id, .. } => id,
        }
    }
}

/// Where a photon leaving patch `i` first arrives: patch `j` with probability `F_ij`, `None`
/// (lost) with probability `1 − Σ_j F_ij`. A stored matrix draws from its row; a scene casts a
/// ray. Shared by threads: each brings its own random stream.
pub trait PhotonSampler: Sync {
    /// One draw, from the random stream `rng`.
    fn sample(&self, i: usize, rng: &mut Rng64) -> Option<u32>;

    /// [`Self::sample`] for each patch of `sources` in turn, drawing from `rng` in the same
    /// order, into `out` (`u32::MAX` where lost): the same draws, but a sampler that casts
    /// rays casts them several at a time.
    fn sample_many(&self, sources: &[u32], rng: &mut Rng64, out: &mut [u32]) {
        for (o, &i) in out.iter_mut().zip(sources) {
            *o = self.sample(i as usize, rng).unwrap_or(u32::MAX);
        }
    }

    /// One draw for *gathering* at patch `i` (a ray from i finding what i sees): as
    /// [`Self::sample`], except where a scene knows that part of `i` is covered (by a
    /// coincident twin or a flush surface), which then sees nothing ([`Gathered::Covered`]).
    /// A stored matrix has no such knowledge and draws from its row.
    fn gather(&self, i: usize, rng: &mut Rng64) -> Gathered {
        match self.sample(i, rng) {
            Some(j) => Gathered::Hit(j),
            None => Gathered::Lost,
        }
    }

    /// [`Self::gather`] `per` times for each patch of `patches`, patch `p` drawing from
    /// `rngs[p]`, into `out[p · per + s]`: the same draws and answers, but a sampler that
    /// casts rays casts them several at a time.
    fn gather_many(&self, patches: &[u32], per: usize, rngs: &mut [Rng64], out: &mut [Gathered]) {
        for ((&i, rng), out) in patches.iter().zip(rngs).zip(out.chunks_mut(per.max(1))) {
            for o in &mut out[..per] {
                *o = self.gather(i as usize, rng);
            }
        }
    }
}

/// What one gathering draw found ([`PhotonSampler::gather`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Gathered {
    /// The ray from the point met patch `j` first.
    Hit(u32),
    /// It left the scene or met a back side.
    Lost,
    /// The point lies under another surface (a coincident twin reported first, or a surface
    /// flush in front of it): it sees nothing at all, whatever the patch's shooting rays saw.
    Covered,
}
