//! Rows of F computed when a solver asks for them, by any [`Estimator`], and not kept.
//!
//! This is how 000_59d10e371b5f300d.txt runs progressive refinement with a hemicube: "having
//! selected a surface, the corresponding column of the form factor matrix should be calculated",
//! one hemicube per shot, the column obtained from the row by reciprocity (its eq. 24). Memory is
//! O(N) (one row and the estimator's buffers) instead of the O(N²) of a stored matrix; the price
//! is recomputing a row each time its patch shoots again. For Monte Carlo rows that are cached
//! under a budget, see [`super::monte_carlo::MonteCarloRows`].

use super::{Entry, Estimator, FormFactorStats, Scratch};
use crate::mesh::Mesh;
use crate::sampling::{uniform, Rng64};
use crate::solve::RowSource;
use std::time::Instant;

/// A [`RowSource`] that runs an estimator for every row asked for (the last row is reused
/// while the same patch is asked for again).
#[derive(Debug)]
pub struct OnDemandRows<'a> {
    mesh: &'a Mesh,
    estimator: Estimator<'a>,
    scratch: Scratch,
    current: Option<usize>,
    row: Vec<Entry>,
    column: Vec<Entry>,
    stats: FormFactorStats,
}

impl<'a> OnDemandRows<'a> {
    /// Rows of `mesh` by `estimator` (which must have been made for the same mesh).
    pub fn new(mesh: &'a Mesh, estimator: Estimator<'a>) -> Self {
        Self {
            mesh,
            estimator,
            scratch: Scratch::default(),
            current: None,
            row: Vec::new(),
            column: Vec::new(),
            stats: FormFactorStats::default(),
        }
    }

    /// Rows computed and time spent so far.
    pub fn stats(&self) -> FormFactorStats {
        self.stats
    }

    fn ensure(&mut self, i: usize) {
        if self.current == Some(i) {
            return;
        }
        let t = Instant::now();
        self.estimator.row(i, &mut self.scratch, &mut self.row);
        self.stats.rows += 1;
        self.stats.seconds += t.elapsed().as_secs_f64();
        self.current = Some(i);
    }
}

impl RowSource for OnDemandRows<'_> {
    fn len(&self) -> usize {
        self.mesh.len()
    }

    fn row(&mut self, i: usize, _share: f64) -> &[Entry] {
        self.ensure(i);
        &self.row
    }

    /// By reciprocity from row i: `F_ji = F_ij A_i / A_j` (000_… eq. 24).
    fn column(&mut self, i: usize, _share: f64) -> &[Entry] {
        self.ensure(i);
        let patches = &self.mesh.patches;
        let ai = patches[i].area;
        self.column.clear();
        self.column.extend(
            self.row
                .iter()
                .map(|&(j, f)| (j, f * ai / patches[j as usize].area)),
        );
        &self.column
    }

    /// A draw from row i: patch j with probability F_ij, none with 1 − Σ_j F_ij.
    fn sample(&mut self, i: usize, rng: &mut Rng64) -> Option<u32> {
        self.ensure(i);
        let mut u = uniform(rng) as f64;
        for &(j, f) in &self.row {
            u -= f as f64;
            if u < 0.0 {
                return Some(j);
            }
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::Bvh;
    use crate::formfactor::{Method, Params, Storage};
    use crate::mesh::MeshParams;
    use crate::scene::builtin;

    /// Rows on demand are the rows of the stored matrix, and columns follow by reciprocity.
    #[test]
    fn on_demand_rows_match_the_stored_matrix() {
        let scene = builtin::cube(builtin::CubeVariant::Dim);
        let mesh = Mesh::build(&scene, MeshParams::Patches(60)).unwrap();
        let bvh = Bvh::build(&mesh);
        let params = Params {
            method: Method::Hemicube,
            resolution: 32,
            samples: 1,
            ..Default::default()
        };
        let mut stored = Estimator::new(&mesh, &bvh, params)
            .unwrap()
            .matrix(Storage::Sparse, &|_| {})
            .into_sparse();
        let mut rows = OnDemandRows::new(&mesh, Estimator::new(&mesh, &bvh, params).unwrap());
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
