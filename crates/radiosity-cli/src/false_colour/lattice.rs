//! Values on a regular lattice in a grid's plane ([`Field`]), and whether a grid's points
//! form one ([`detect`]): the work-plane grid of `lighting::workplane` does, cell centres
//! `step` apart along both drawing axes, with holes where the floor has none.

/// Values at the nodes of a regular lattice: node (i, j) at `origin + (i·step₀, j·step₁)`,
/// row-major from j = 0, NaN where there is no value.
#[derive(Clone, Debug, PartialEq)]
pub struct Field {
    /// Node (0, 0), scene units along the drawing axes.
    pub origin: [f64; 2],
    /// Spacing along u and v.
    pub step: [f64; 2],
    /// Nodes along u.
    pub nu: usize,
    /// Nodes along v.
    pub nv: usize,
    /// `nu × nv` values, NaN where none.
    pub values: Vec<f64>,
}

impl Field {
    /// An empty field (every value NaN).
    pub fn empty(origin: [f64; 2], step: [f64; 2], nu: usize, nv: usize) -> Field {
        Field {
            origin,
            step,
            nu,
            nv,
            values: vec![f64::NAN; nu * nv],
        }
    }

    /// The position of node (i, j).
    pub fn node(&self, i: usize, j: usize) -> [f64; 2] {
        [
            self.origin[0] + i as f64 * self.step[0],
            self.origin[1] + j as f64 * self.step[1],
        ]
    }

    /// The value at node (i, j).
    pub fn value(&self, i: usize, j: usize) -> f64 {
        self.values[j * self.nu + i]
    }

    /// The field subdivided `k` times along each axis, the new nodes bilinear between the
    /// four around them (NaN where one of them is): the same surface on a finer lattice, whose
    /// marching squares follow the bilinear interpolant's curved isolines.
    pub fn refined(&self, k: usize) -> Field {
        let k = k.max(1);
        let (nu, nv) = ((self.nu - 1) * k + 1, (self.nv - 1) * k + 1);
        let mut f = Field::empty(
            self.origin,
            [self.step[0] / k as f64, self.step[1] / k as f64],
            nu,
            nv,
        );
        for j in 0..nv {
            for i in 0..nu {
                let (i0, j0) = (
                    (i / k).min(self.nu.saturating_sub(2)),
                    (j / k).min(self.nv.saturating_sub(2)),
                );
                let (s, t) = (
                    (i - i0 * k) as f64 / k as f64,
                    (j - j0 * k) as f64 / k as f64,
                );
                let (i1, j1) = ((i0 + 1).min(self.nu - 1), (j0 + 1).min(self.nv - 1));
                // Corners at weight zero do not count (a node on the lattice's edge or hole).
                let corners = [
                    (self.value(i0, j0), (1.0 - s) * (1.0 - t)),
                    (self.value(i1, j0), s * (1.0 - t)),
                    (self.value(i0, j1), (1.0 - s) * t),
                    (self.value(i1, j1), s * t),
                ];
                f.values[j * nu + i] = corners
                    .iter()
                    .filter(|c| c.1 > 0.0)
                    .map(|c| c.0 * c.1)
                    .sum();
            }
        }
        f
    }

    /// The smallest and largest finite values (`None` when there is none).
    pub fn range(&self) -> Option<(f64, f64)> {
        let mut r: Option<(f64, f64)> = None;
        for &v in self.values.iter().filter(|v| v.is_finite()) {
            r = Some(match r {
                Some((lo, hi)) => (lo.min(v), hi.max(v)),
                None => (v, v),
            });
        }
        r
    }
}

/// Most nodes a lattice axis may have.
const MAX_AXIS: usize = 4096;
/// Least fraction of the lattice's nodes the points must fill.
const MIN_FILL: f64 = 0.3;

/// The lattice of one coordinate: first value, step and count, when the distinct values
/// (within `tol`) are all the multiples of the smallest gap between them.
fn axis(mut xs: Vec<f64>, tol: f64) -> Option<(f64, f64, usize)> {
    xs.sort_by(f64::total_cmp);
    let mut distinct: Vec<f64> = Vec::new();
    for x in xs {
        match distinct.last() {
            Some(&d) if x - d <= tol => {}
            _ => distinct.push(x),
        }
    }
    if distinct.len() < 2 {
        return None;
    }
    let step = distinct
        .windows(2)
        .map(|w| w[1] - w[0])
        .fold(f64::INFINITY, f64::min);
    let x0 = distinct[0];
    let n = ((distinct[distinct.len() - 1] - x0) / step).round() as usize + 1;
    // Every column present: a missing one is a coarser lattice or scattered points.
    if n != distinct.len() || n > MAX_AXIS {
        return None;
    }
    for (k, &x) in distinct.iter().enumerate() {
        if (x - x0 - k as f64 * step).abs() > 1e-3 * step {
            return None;
        }
    }
    Some((x0, step, n))
}

/// Whether `points` (in the drawing plane) sit one a node on a regular lattice along the
/// drawing axes, with every row and column present and at least 30 % of the nodes filled:
/// the lattice (values NaN) and each point's node index. Two points on one node, a lattice
/// of one row or over 4096 nodes a side are not one.
pub fn detect(points: &[[f64; 2]]) -> Option<(Field, Vec<usize>)> {
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in points {
        for k in 0..2 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let size = (hi[0] - lo[0]).max(hi[1] - lo[1]);
    if !(size > 0.0 && size.is_finite()) {
        return None;
    }
    let tol = 1e-6 * size;
    let (u0, du, nu) = axis(points.iter().map(|p| p[0]).collect(), tol)?;
    let (v0, dv, nv) = axis(points.iter().map(|p| p[1]).collect(), tol)?;
    if (points.len() as f64) < MIN_FILL * (nu * nv) as f64 {
        return None;
    }
    let mut taken = vec![false; nu * nv];
    let mut node = Vec::with_capacity(points.len());
    for p in points {
        let i = ((p[0] - u0) / du).round() as usize;
        let j = ((p[1] - v0) / dv).round() as usize;
        let k = j * nu + i;
        if std::mem::replace(&mut taken[k], true) {
            return None;
        }
        node.push(k);
    }
    Some((Field::empty([u0, v0], [du, dv], nu, nv), node))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Subdividing reproduces a bilinear field a + bu + cv + d·uv exactly, keeps the nodes'
    /// values, and leaves NaN only in the squares touching a missing node.
    #[test]
    fn refining_is_bilinear() {
        let f = |p: [f64; 2]| 2.0 + 0.5 * p[0] - 1.5 * p[1] + 0.25 * p[0] * p[1];
        let mut coarse = Field::empty([1.0, -2.0], [0.5, 0.25], 5, 4);
        for j in 0..4 {
            for i in 0..5 {
                coarse.values[j * 5 + i] = f(coarse.node(i, j));
            }
        }
        coarse.values[3 * 5 + 4] = f64::NAN; // the top-right corner missing
        let fine = coarse.refined(4);
        assert_eq!((fine.nu, fine.nv), (17, 13));
        for j in 0..fine.nv {
            for i in 0..fine.nu {
                let v = fine.value(i, j);
                let in_last_square = i > 12 && j > 8;
                if in_last_square {
                    assert!(v.is_nan(), "({i}, {j})");
                } else {
                    assert!((v - f(fine.node(i, j))).abs() < 1e-12, "({i}, {j})");
                }
            }
        }
        let same = coarse.refined(1);
        assert!(same
            .values
            .iter()
            .zip(&coarse.values)
            .all(|(a, b)| a.to_bits() == b.to_bits()));
    }

    /// The work-plane grid (cell centres, an L-shaped floor leaving a corner out) is a
    /// lattice; one column, a lattice missing a column, two points on a node, and jittered
    /// points are not.
    #[test]
    fn lattices_are_recognised() {
        let mut l = Vec::new();
        for j in 0..5 {
            for i in 0..8 {
                if !(i >= 5 && j >= 3) {
                    l.push([0.5 + (i as f64 + 0.5) * 0.625, 0.5 + (j as f64 + 0.5) * 0.6]);
                }
            }
        }
        let (f, node) = detect(&l).unwrap();
        assert_eq!((f.nu, f.nv), (8, 5));
        assert!((f.step[0] - 0.625).abs() < 1e-12 && (f.step[1] - 0.6).abs() < 1e-12);
        for (p, &k) in l.iter().zip(&node) {
            let q = f.node(k % f.nu, k / f.nu);
            assert!((p[0] - q[0]).abs() < 1e-9 && (p[1] - q[1]).abs() < 1e-9);
        }
        let column: Vec<[f64; 2]> = l
            .iter()
            .copied()
            .filter(|p| p[0] > 1.0 && p[0] < 2.0)
            .collect();
        assert!(detect(&column).is_none());
        let missing: Vec<[f64; 2]> = l
            .iter()
            .copied()
            .filter(|p| ((p[0] - 0.5) / 0.625 - 2.5).abs() > 0.1)
            .collect();
        assert!(detect(&missing).is_none());
        let mut twice = l.clone();
        twice.push(l[3]);
        assert!(detect(&twice).is_none());
        let jittered: Vec<[f64; 2]> = l
            .iter()
            .enumerate()
            .map(|(k, p)| [p[0] + 0.01 * ((k * 7919) % 13) as f64 / 13.0, p[1]])
            .collect();
        assert!(detect(&jittered).is_none());
    }
}
