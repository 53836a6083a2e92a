//! [`Estimator`]: rows of F for a mesh by any method, one row at a time or every row in
//! parallel (dense or sparse). The row algorithms live in the methods' own files; this file
//! dispatches to them and owns the buffers they share.

use super::{
    adaptive, analytic, hemicube, hemisphere, monte_carlo, projection, tetrahedron,
    FormFactorError, FormFactorMethod, Matrix, Params, Storage, DENSE_MAX,
};
use crate::accel::Bvh;
use crate::geom::Vec3;
use crate::mesh::Mesh;
use crate::observe::{Event, Observer, Silent, Stage};
use crate::system::{Entry, SparseMatrix};
use glam::DVec3;
use rayon::prelude::*;

/// Per-thread buffers of [`Estimator::row`]: nothing is allocated per row once they are warm.
#[derive(Debug, Default)]
pub struct Scratch {
    accum: Vec<f64>,
    touched: Vec<u32>,
    pub(super) buffers: projection::Buffers,
    pub(super) mc: monte_carlo::RowScratch,
    pub(super) analytic: analytic::Scratch,
    pub(super) adaptive: adaptive::Scratch,
    pub(super) points: Vec<(Vec3, f64)>,
    pub(super) poly_i: Vec<DVec3>,
    pub(super) poly_j: Vec<DVec3>,
}

impl Scratch {
    /// Add `v` to the accumulating row's entry `j`.
    pub(super) fn add(&mut self, j: u32, v: f64) {
        let a = &mut self.accum[j as usize];
        if *a == 0.0 {
            self.touched.push(j);
        }
        *a += v;
    }
}

/// How much work a row gets: Monte Carlo's ray count and the version of its random streams
/// (a row estimated again gets fresh streams). The deterministic methods ignore it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Effort {
    /// Monte Carlo rays.
    pub rays: u32,
    /// Version of the row's random streams.
    pub version: u64,
}

/// Computes rows of F for a mesh by one method.
#[derive(Debug)]
pub struct Estimator<'a> {
    pub(super) mesh: &'a Mesh,
    pub(super) bvh: &'a Bvh,
    pub(super) params: Params,
    pub(super) solid: Option<projection::Solid>,
    pub(super) cells: Vec<(f32, f32, f32)>,
    pub(super) near: f32,
    pub(super) offset: f32,
    pub(super) adaptive: Option<adaptive::Prepared>,
}

impl<'a> Estimator<'a> {
    /// An estimator; checks the parameters the method uses ([`Params::validate`]).
    pub fn new(mesh: &'a Mesh, bvh: &'a Bvh, params: Params) -> Result<Self, FormFactorError> {
        params.validate()?;
        let p = params.resolution as usize;
        let solid = match params.method {
            FormFactorMethod::Hemicube => Some(hemicube::solid(p)),
            FormFactorMethod::Tetrahedron => Some(tetrahedron::solid(p)),
            _ => None,
        };
        let cells = if params.method == FormFactorMethod::Hemisphere {
            hemisphere::cells(p)
        } else {
            Vec::new()
        };
        Ok(Self {
            mesh,
            bvh,
            params,
            solid,
            cells,
            near: bvh.ray_offset() * 0.25,
            offset: bvh.ray_offset(),
            adaptive: (params.method == FormFactorMethod::Adaptive)
                .then(|| adaptive::Prepared::new(mesh, params.accuracy)),
        })
    }

    /// The mesh whose rows this estimates.
    pub fn mesh(&self) -> &'a Mesh {
        self.mesh
    }

    /// The hierarchy it casts rays through.
    pub fn bvh(&self) -> &'a Bvh {
        self.bvh
    }

    /// Its parameters.
    pub fn params(&self) -> &Params {
        &self.params
    }

    /// What the adaptive method prepared (its counts so far), when that is the method.
    pub fn adaptive(&self) -> Option<&adaptive::Prepared> {
        self.adaptive.as_ref()
    }

    /// Row i of F, `(j, F_ij)` sorted by j, into `out`, with the parameters' effort
    /// (`params.rays` rays for Monte Carlo, streams of version 0).
    pub fn row(&self, i: usize, scratch: &mut Scratch, out: &mut Vec<Entry>) {
        let effort = Effort {
            rays: self.params.rays,
            version: 0,
        };
        self.row_with(i, effort, scratch, out);
    }

    /// Row i of F with the given effort.
    pub fn row_with(&self, i: usize, effort: Effort, scratch: &mut Scratch, out: &mut Vec<Entry>) {
        let n = self.mesh.len();
        if scratch.accum.len() < n {
            scratch.accum.resize(n, 0.0);
        }
        scratch.touched.clear();
        match self.params.method {
            FormFactorMethod::MonteCarlo => {
                monte_carlo::estimate_row(
                    self.mesh,
                    self.bvh,
                    i,
                    effort.rays,
                    self.params.seed,
                    effort.version,
                    &mut scratch.mc,
                    out,
                );
                return;
            }
            FormFactorMethod::Hemicube => hemicube::row(self, i, scratch),
            FormFactorMethod::Tetrahedron => tetrahedron::row(self, i, scratch),
            FormFactorMethod::Hemisphere => hemisphere::row(self, i, scratch),
            FormFactorMethod::Analytic => analytic::row(self, i, scratch),
            FormFactorMethod::Adaptive => adaptive::row(self, i, scratch),
        }
        scratch.touched.sort_unstable();
        out.clear();
        out.reserve_exact(scratch.touched.len());
        for &j in &scratch.touched {
            let v = std::mem::take(&mut scratch.accum[j as usize]);
            if v > 0.0 {
                out.push((j, v as f32));
            }
        }
    }

    /// Every row, in parallel (deterministic), stored as asked. `observer` hears of
    /// [`Stage::FormFactors`] and of each row done (from worker threads).
    pub fn matrix(&self, storage: Storage, observer: &dyn Observer) -> Matrix {
        if self.params.method == FormFactorMethod::Adaptive {
            // Each pair once, both entries from its exchange area.
            return adaptive::matrix(self, storage, observer);
        }
        let n = self.mesh.len();
        observer.event(Event::Stage(Stage::FormFactors));
        let done = std::sync::atomic::AtomicU64::new(0);
        let progress = |done: u64| {
            observer.event(Event::Progress {
                stage: Stage::FormFactors,
                done,
                total: n as u64,
            })
        };
        let dense = match storage {
            Storage::Dense => true,
            Storage::Sparse => false,
            Storage::Auto => n <= DENSE_MAX,
        };
        if dense {
            let mut values = vec![0.0f32; n * n];
            values.par_chunks_mut(n.max(1)).enumerate().for_each_init(
                || (Scratch::default(), Vec::new()),
                |(scratch, row), (i, out)| {
                    self.row(i, scratch, row);
                    for &(j, f) in row.iter() {
                        out[j as usize] = f;
                    }
                    progress(done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1);
                },
            );
            Matrix::Dense { n, values }
        } else {
            let rows: Vec<Vec<Entry>> = (0..n)
                .into_par_iter()
                .map_init(Scratch::default, |scratch, i| {
                    let mut row = Vec::new();
                    self.row(i, scratch, &mut row);
                    progress(done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1);
                    row
                })
                .collect();
            Matrix::Sparse(SparseMatrix::from_rows(rows))
        }
    }

    /// Every row, stored sparse: the matrix the solvers that need all rows take.
    pub fn sparse_matrix(&self) -> SparseMatrix {
        self.matrix(Storage::Sparse, &Silent).into_sparse()
    }
}
