//! Form factors: `F_ij`, the fraction of the energy leaving patch `i` that arrives directly at
//! patch `j` (000_59d10e371b5f300d.txt eq. 6). Rows are sparse: a row holds only the patches a
//! method found, sorted by patch index, so that no N × N array is ever allocated.
//!
//! Methods, one file each, selected by [`Method`]:
//! - [`hemicube`] and [`tetrahedron`]: z-buffer projections ([`projection`]);
//! - [`hemisphere`]: Nusselt's analog by casting rays through a disc of cells;
//! - [`monte_carlo`]: eq. 7, ray shooting;
//! - [`analytic`]: the exact unoccluded polygon-to-polygon factor.
//!
//! [`Estimator`] computes rows with any of them, and whole matrices in parallel, dense or sparse.
//! [`enforce`] optionally makes a matrix physical.

pub mod analytic;
pub mod closed_form;
pub mod hemicube;
pub mod hemisphere;
pub mod monte_carlo;
pub mod on_demand;
pub mod projection;
pub mod tetrahedron;

use crate::accel::Bvh;
use crate::geom::{orthonormal_basis, Ray, Vec3};
use crate::mesh::Mesh;
use crate::solve::matrix::SparseMatrix;
use glam::DVec3;
use rayon::prelude::*;
use std::f64::consts::PI;

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

/// The form-factor methods, named as on the command line (`--method`, `--form-factors`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Method {
    /// Hemicube z-buffer ([`hemicube`]).
    Hemicube,
    /// Nusselt's hemisphere ([`hemisphere`]).
    Hemisphere,
    /// Cubic tetrahedron z-buffer ([`tetrahedron`]).
    Tetrahedron,
    /// Monte Carlo ray shooting ([`monte_carlo`]).
    MonteCarlo,
    /// Exact unoccluded contour integral ([`analytic`]).
    Analytic,
}

impl Method {
    /// Every method.
    pub const ALL: [Method; 5] = [
        Method::Hemicube,
        Method::Hemisphere,
        Method::Tetrahedron,
        Method::MonteCarlo,
        Method::Analytic,
    ];

    /// The command-line name.
    pub fn name(self) -> &'static str {
        match self {
            Method::Hemicube => "hemicube",
            Method::Hemisphere => "hemisphere",
            Method::Tetrahedron => "tetrahedron",
            Method::MonteCarlo => "monte-carlo",
            Method::Analytic => "analytic",
        }
    }

    /// The method called `name`.
    pub fn from_name(name: &str) -> Option<Method> {
        Method::ALL.into_iter().find(|m| m.name() == name)
    }
}

impl std::fmt::Display for Method {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Parameters of the form-factor methods.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Params {
    /// The method.
    pub method: Method,
    /// P: pixels along a hemicube or tetrahedron face, cells along the hemisphere's disc.
    pub resolution: u32,
    /// Points spread over patch i for the projection methods (rounded up to a square).
    pub samples: u32,
    /// Rays per row for Monte Carlo.
    pub rays: u32,
    /// Seed of Monte Carlo's random streams.
    pub seed: u64,
}

impl Default for Params {
    fn default() -> Self {
        Self {
            method: Method::MonteCarlo,
            resolution: 128,
            samples: 16,
            rays: 1_000_000,
            seed: 1,
        }
    }
}

/// Bad form-factor parameters.
#[derive(Debug, thiserror::Error)]
pub enum FormFactorError {
    /// A parameter is out of range.
    #[error("{0}")]
    Invalid(String),
}

/// Matrix storage.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Storage {
    /// Dense up to [`DENSE_MAX`] patches, sparse beyond.
    Auto,
    /// N × N values.
    Dense,
    /// Sparse rows: never N² zeros.
    Sparse,
}

/// Largest N stored densely by [`Storage::Auto`] (64 MiB of f32).
pub const DENSE_MAX: usize = 4096;

/// A computed form-factor matrix.
#[derive(Clone, Debug)]
pub enum Matrix {
    /// Row-major N × N.
    Dense {
        /// N.
        n: usize,
        /// The values.
        values: Vec<f32>,
    },
    /// Sparse rows and columns.
    Sparse(SparseMatrix),
}

impl Matrix {
    /// As a sparse matrix (the dense one's zeros dropped).
    pub fn into_sparse(self) -> SparseMatrix {
        match self {
            Matrix::Sparse(m) => m,
            Matrix::Dense { n, values } => SparseMatrix::from_rows(
                values
                    .chunks(n)
                    .map(|r| {
                        r.iter()
                            .enumerate()
                            .filter(|(_, v)| **v != 0.0)
                            .map(|(j, v)| (j as u32, *v))
                            .collect()
                    })
                    .collect(),
            ),
        }
    }
}

/// Per-thread buffers of [`Estimator::row`]: nothing is allocated per row once they are warm.
#[derive(Debug, Default)]
pub struct Scratch {
    accum: Vec<f64>,
    touched: Vec<u32>,
    buffers: projection::Buffers,
    mc: monte_carlo::RowScratch,
    analytic: analytic::Scratch,
    points: Vec<(Vec3, f64)>,
    poly_i: Vec<DVec3>,
    poly_j: Vec<DVec3>,
}

/// Computes rows of F for a mesh by one method.
#[derive(Debug)]
pub struct Estimator<'a> {
    mesh: &'a Mesh,
    bvh: &'a Bvh,
    params: Params,
    solid: Option<projection::Solid>,
    cells: Vec<(f32, f32, f32)>,
    near: f32,
    offset: f32,
}

impl<'a> Estimator<'a> {
    /// An estimator; checks the parameters the method uses.
    pub fn new(mesh: &'a Mesh, bvh: &'a Bvh, params: Params) -> Result<Self, FormFactorError> {
        let p = params.resolution as usize;
        match params.method {
            Method::Hemicube | Method::Tetrahedron | Method::Hemisphere => {
                if params.resolution < 2 {
                    return Err(FormFactorError::Invalid(format!(
                        "--resolution {}: at least 2 pixels along a face are needed",
                        params.resolution
                    )));
                }
                if params.resolution > 8192 {
                    return Err(FormFactorError::Invalid(format!(
                        "--resolution {}: at most 8192",
                        params.resolution
                    )));
                }
                if params.samples == 0 {
                    return Err(FormFactorError::Invalid(
                        "--samples 0: at least one point per patch is needed".into(),
                    ));
                }
            }
            Method::MonteCarlo => {
                if params.rays == 0 {
                    return Err(FormFactorError::Invalid(
                        "--rays 0: at least one ray per row is needed".into(),
                    ));
                }
            }
            Method::Analytic => {}
        }
        let solid = match params.method {
            Method::Hemicube => Some(hemicube::solid(p)),
            Method::Tetrahedron => Some(tetrahedron::solid(p)),
            _ => None,
        };
        let cells = if params.method == Method::Hemisphere {
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
        })
    }

    /// Quadrature points over patch i with weights summing to 1, for the outer integral of eq. 6:
    /// an m × m Gauss–Legendre rule, m = ⌈√samples⌉. On a quad it is a tensor rule through the
    /// bilinear map, weighted by its Jacobian; on a triangle, a tensor rule through the collapsed
    /// (Duffy) map. The point-to-patch factor is smooth over the patch, so this converges far
    /// faster than a grid of cell centres.
    fn sample_points(&self, i: usize, samples: u32, out: &mut Vec<(Vec3, f64)>) {
        out.clear();
        let p = &self.mesh.patches[i];
        let v = |k: usize| self.mesh.vertices[p.vertices[k] as usize];
        let m = (samples as f64).sqrt().ceil().max(1.0) as usize;
        let (nodes, weights) = gauss_legendre(m);
        if p.is_triangle() {
            let (a, b, c) = (v(0), v(1), v(2));
            for (x, wx) in nodes.iter().zip(&weights) {
                for (y, wy) in nodes.iter().zip(&weights) {
                    let (s, t) = (*x, y * (1.0 - x));
                    let q = a + (b - a) * s as f32 + (c - a) * t as f32;
                    out.push((q, wx * wy * (1.0 - x)));
                }
            }
        } else {
            let (a, b, c, d) = (v(0), v(1), v(2), v(3));
            for (x, wx) in nodes.iter().zip(&weights) {
                for (y, wy) in nodes.iter().zip(&weights) {
                    let (s, t) = (*x as f32, *y as f32);
                    let q = a * ((1.0 - s) * (1.0 - t))
                        + b * (s * (1.0 - t))
                        + c * (s * t)
                        + d * ((1.0 - s) * t);
                    let ds = (b - a) * (1.0 - t) + (c - d) * t;
                    let dt = (d - a) * (1.0 - s) + (c - b) * s;
                    out.push((q, wx * wy * ds.cross(dt).length() as f64));
                }
            }
        }
        let total: f64 = out.iter().map(|p| p.1).sum();
        out.iter_mut().for_each(|p| p.1 /= total);
    }

    fn add(accum: &mut [f64], touched: &mut Vec<u32>, j: u32, v: f64) {
        let a = &mut accum[j as usize];
        if *a == 0.0 {
            touched.push(j);
        }
        *a += v;
    }

    /// Row i of F, `(j, F_ij)` sorted by j, into `out`.
    pub fn row(&self, i: usize, scratch: &mut Scratch, out: &mut Vec<Entry>) {
        let n = self.mesh.len();
        if scratch.accum.len() < n {
            scratch.accum.resize(n, 0.0);
        }
        scratch.touched.clear();
        match self.params.method {
            Method::MonteCarlo => {
                monte_carlo::estimate_row(
                    self.mesh,
                    self.bvh,
                    i,
                    self.params.rays,
                    self.params.seed,
                    0,
                    &mut scratch.mc,
                    out,
                );
                return;
            }
            Method::Hemicube | Method::Tetrahedron => self.projection_row(i, scratch),
            Method::Hemisphere => self.hemisphere_row(i, scratch),
            Method::Analytic => self.analytic_row(i, scratch),
        }
        scratch.touched.sort_unstable();
        out.clear();
        for &j in &scratch.touched {
            let v = std::mem::take(&mut scratch.accum[j as usize]);
            if v > 0.0 {
                out.push((j, v as f32));
            }
        }
    }

    fn projection_row(&self, i: usize, scratch: &mut Scratch) {
        let solid = self.solid.as_ref().expect("projection method");
        let mut points = std::mem::take(&mut scratch.points);
        self.sample_points(i, self.params.samples, &mut points);
        let normal = self.mesh.patches[i].normal;
        let (t, b) = orthonormal_basis(normal);
        for &(o, weight) in &points {
            scratch.buffers.clear(solid);
            let local = |p: Vec3| {
                let d = p - o;
                Vec3::new(d.dot(t), d.dot(b), d.dot(normal))
            };
            for (j, pj) in self.mesh.patches.iter().enumerate() {
                if j == i {
                    continue;
                }
                let front = pj.normal.dot(o - pj.centre) > 0.0;
                let id = j as u32 | if front { 0 } else { projection::BACK };
                for tri in pj.triangles() {
                    let q = tri.map(|k| local(self.mesh.vertices[k as usize]));
                    if q.iter().all(|p| p.z <= 0.0) {
                        continue;
                    }
                    projection::rasterise(solid, &mut scratch.buffers, &q, id, self.near);
                }
            }
            for (k, face) in solid.faces.iter().enumerate() {
                for (px, &item) in scratch.buffers.item[k].iter().enumerate() {
                    if item != projection::EMPTY && item & projection::BACK == 0 {
                        Self::add(
                            &mut scratch.accum,
                            &mut scratch.touched,
                            item,
                            weight * face.delta[px] as f64,
                        );
                    }
                }
            }
        }
        scratch.points = points;
    }

    fn hemisphere_row(&self, i: usize, scratch: &mut Scratch) {
        let mut points = std::mem::take(&mut scratch.points);
        self.sample_points(i, self.params.samples, &mut points);
        let n = self.mesh.patches[i].normal;
        let (t, b) = orthonormal_basis(n);
        for &(o, weight) in &points {
            let origin = o + n * self.offset;
            for &(x, y, w) in &self.cells {
                let z = (1.0 - x * x - y * y).max(0.0).sqrt();
                let d = t * x + b * y + n * z;
                if let Some(h) = self.bvh.closest_hit(&Ray::new(origin, d), f32::INFINITY) {
                    if h.front && h.patch as usize != i {
                        Self::add(
                            &mut scratch.accum,
                            &mut scratch.touched,
                            h.patch,
                            weight * w as f64,
                        );
                    }
                }
            }
        }
        scratch.points = points;
    }

    fn polygon(&self, k: usize, out: &mut Vec<DVec3>) {
        out.clear();
        let p = &self.mesh.patches[k];
        let n = if p.is_triangle() { 3 } else { 4 };
        out.extend(
            p.vertices[..n]
                .iter()
                .map(|&v| self.mesh.vertices[v as usize].as_dvec3()),
        );
    }

    fn analytic_row(&self, i: usize, scratch: &mut Scratch) {
        let mut pi = std::mem::take(&mut scratch.poly_i);
        let mut pj = std::mem::take(&mut scratch.poly_j);
        self.polygon(i, &mut pi);
        let p = &self.mesh.patches[i];
        let (ni, ai) = (p.normal.as_dvec3(), p.area as f64);
        for j in 0..self.mesh.len() {
            if j == i {
                continue;
            }
            self.polygon(j, &mut pj);
            let nj = self.mesh.patches[j].normal.as_dvec3();
            let f = analytic::polygon_factor(&pi, ni, ai, &pj, nj, &mut scratch.analytic);
            if f > 0.0 {
                Self::add(&mut scratch.accum, &mut scratch.touched, j as u32, f);
            }
        }
        scratch.poly_i = pi;
        scratch.poly_j = pj;
    }

    /// Every row, in parallel (deterministic), stored as asked. `progress` is called with the
    /// number of rows done (from worker threads).
    pub fn matrix(&self, storage: Storage, progress: &(dyn Fn(usize) + Sync)) -> Matrix {
        let n = self.mesh.len();
        let done = std::sync::atomic::AtomicUsize::new(0);
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
}

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

/// Gauss–Legendre nodes and weights on [0, 1] with `m` points (Newton's iteration on the
/// Legendre polynomial from the Chebyshev guess, Golub–Welsch accuracy for the sizes used).
pub fn gauss_legendre(m: usize) -> (Vec<f64>, Vec<f64>) {
    let mut nodes = Vec::with_capacity(m);
    let mut weights = Vec::with_capacity(m);
    for k in 0..m {
        let mut x = (PI * (k as f64 + 0.75) / (m as f64 + 0.5)).cos();
        let mut dp = 1.0;
        for _ in 0..100 {
            // P_m(x) and its derivative by the three-term recurrence.
            let (mut p0, mut p1) = (1.0, x);
            for n in 2..=m {
                let p2 = ((2 * n - 1) as f64 * x * p1 - (n - 1) as f64 * p0) / n as f64;
                p0 = p1;
                p1 = p2;
            }
            let pm = if m == 0 {
                1.0
            } else if m == 1 {
                x
            } else {
                p1
            };
            let pm1 = if m == 1 { 1.0 } else { p0 };
            dp = m as f64 * (x * pm - pm1) / (x * x - 1.0);
            let dx = pm / dp;
            x -= dx;
            if dx.abs() < 1e-16 {
                break;
            }
        }
        nodes.push(0.5 * (1.0 - x));
        weights.push(1.0 / ((1.0 - x * x) * dp * dp));
    }
    (nodes, weights)
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

#[cfg(test)]
mod tests {
    #[test]
    fn gauss_legendre_integrates_polynomials_exactly() {
        for m in 1..12 {
            let (x, w) = super::gauss_legendre(m);
            assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-14);
            // Exact for degree 2m − 1: ∫₀¹ x^d dx = 1/(d + 1).
            for d in 0..2 * m {
                let q: f64 = x.iter().zip(&w).map(|(x, w)| w * x.powi(d as i32)).sum();
                assert!((q - 1.0 / (d + 1) as f64).abs() < 1e-13, "m={m} d={d}: {q}");
            }
        }
    }
}
