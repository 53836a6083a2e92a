//! The plane of a calculation grid and the axes it is drawn in.
//!
//! The plane is the least-squares fit through the points: through their centroid, normal to
//! the eigenvector of the smallest eigenvalue of their scatter matrix Σ (p − c)(p − c)ᵀ
//! (cyclic Jacobi rotations on the 3 × 3 matrix). A grid is drawable when every point lies
//! within 1 % of the grid's in-plane size of that plane (a work plane over a floor with a
//! shallow step passes, drawn projected); points on several planes (floor and walls), on a
//! line or at one spot are refused with the reason.
//!
//! The axes: a plane within 45° of horizontal is drawn in plan, seen from above, in the
//! scene's horizontal coordinates (z up: x to the right, y up the page; y up: z to the
//! right, x up the page, as `lighting::workplane` reads them); a steeper plane in elevation,
//! seen from the side its sensors face, the scene's vertical up the page. Coordinates are
//! the points' projections on the axes through the scene's origin, so an axis along a scene
//! axis reads that axis's coordinates.

use radiosity::lighting::Up;

/// A grid's plane and its drawing axes (unit vectors; `u × v = normal`).
#[derive(Clone, Debug, PartialEq)]
pub struct GridPlane {
    /// The normal the plane is seen along (towards the viewer).
    pub normal: [f64; 3],
    /// The axis drawn to the right.
    pub u: [f64; 3],
    /// The axis drawn up the page.
    pub v: [f64; 3],
    /// The axes' names: a scene axis (`x`, `−y`, …) or `u`, `v` for an oblique plane.
    pub names: [String; 2],
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn scaled(a: [f64; 3], s: f64) -> [f64; 3] {
    a.map(|x| x * s)
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn normalised(a: [f64; 3]) -> [f64; 3] {
    scaled(a, 1.0 / dot(a, a).sqrt())
}

/// Eigenvalues (ascending) and unit eigenvectors of a symmetric 3 × 3 matrix, by cyclic
/// Jacobi rotations (Golub & Van Loan, Matrix Computations, § 8.5).
fn eigen_symmetric(mut a: [[f64; 3]; 3]) -> ([f64; 3], [[f64; 3]; 3]) {
    let mut v = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    let scale = a.iter().flatten().map(|x| x * x).sum::<f64>();
    for _sweep in 0..64 {
        let off = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
        if off <= 1e-30 * scale {
            break;
        }
        for (p, q) in [(0, 1), (0, 2), (1, 2)] {
            if a[p][q] == 0.0 {
                continue;
            }
            let theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
            let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
            let c = 1.0 / (t * t + 1.0).sqrt();
            let s = t * c;
            for k in 0..3 {
                let (akp, akq) = (a[k][p], a[k][q]);
                a[k][p] = c * akp - s * akq;
                a[k][q] = s * akp + c * akq;
            }
            for k in 0..3 {
                let (apk, aqk) = (a[p][k], a[q][k]);
                a[p][k] = c * apk - s * aqk;
                a[q][k] = s * apk + c * aqk;
            }
            for row in &mut v {
                let (vp, vq) = (row[p], row[q]);
                row[p] = c * vp - s * vq;
                row[q] = s * vp + c * vq;
            }
        }
    }
    let mut order = [0, 1, 2];
    order.sort_by(|&i, &j| a[i][i].total_cmp(&a[j][j]));
    let values = order.map(|i| a[i][i]);
    let vectors = order.map(|i| [v[0][i], v[1][i], v[2][i]]);
    (values, vectors)
}

/// The name of a unit axis: a scene axis when it is one (to 1e-9), else `fallback`.
fn axis_name(a: [f64; 3], fallback: &str) -> String {
    for (k, name) in ["x", "y", "z"].iter().enumerate() {
        if a[k].abs() > 1.0 - 1e-9 {
            return if a[k] > 0.0 {
                (*name).to_string()
            } else {
                format!("−{name}")
            };
        }
    }
    fallback.to_string()
}

/// The tolerance of the planarity test, as a fraction of the grid's in-plane size.
pub const PLANAR_FRACTION: f64 = 0.01;

impl GridPlane {
    /// Fit the plane of `positions` (sensors facing `normals`, which choose the side an
    /// upright plane is seen from) in a scene whose vertical is `up`. The error says why the
    /// grid cannot be drawn: on a line, at one spot, or not on one plane (how far off, in
    /// scene units).
    pub fn fit(positions: &[[f64; 3]], normals: &[[f64; 3]], up: Up) -> Result<GridPlane, String> {
        let n = positions.len().max(1) as f64;
        let mut c = [0.0; 3];
        for p in positions {
            for k in 0..3 {
                c[k] += p[k] / n;
            }
        }
        let mut m = [[0.0; 3]; 3];
        for p in positions {
            let d = sub(*p, c);
            for i in 0..3 {
                for j in 0..3 {
                    m[i][j] += d[i] * d[j];
                }
            }
        }
        let (values, vectors) = eigen_symmetric(m);
        if values[2] <= 0.0 {
            return Err("all its points are at one spot: no plane to draw".into());
        }
        if values[1] <= 1e-12 * values[2] {
            return Err("its points lie on a line: no plane to draw".into());
        }
        let normal = vectors[0];
        let vertical = match up {
            Up::Z => [0.0, 0.0, 1.0],
            Up::Y => [0.0, 1.0, 0.0],
        };
        let plane = if dot(normal, vertical).abs() >= std::f64::consts::FRAC_1_SQRT_2 {
            // Plan, seen from above: the scene's first horizontal axis to the right.
            let n = scaled(normal, dot(normal, vertical).signum());
            let right = match up {
                Up::Z => [1.0, 0.0, 0.0],
                Up::Y => [0.0, 0.0, 1.0],
            };
            let u = normalised(sub(right, scaled(n, dot(right, n))));
            let v = cross(n, u);
            (n, u, v)
        } else {
            // Elevation, seen from the side the sensors face; the vertical up the page.
            let facing: [f64; 3] = normals
                .iter()
                .fold([0.0; 3], |s, d| [s[0] + d[0], s[1] + d[1], s[2] + d[2]]);
            let side = dot(normal, facing);
            let n = if side.abs() > 1e-9 * n {
                scaled(normal, side.signum())
            } else {
                // Sensors lying in the plane: seen from the side of +x, +y or +z, whichever
                // the normal is closest to.
                let k = (0..3)
                    .max_by(|&i, &j| normal[i].abs().total_cmp(&normal[j].abs()))
                    .unwrap_or(0);
                scaled(normal, normal[k].signum())
            };
            let v = normalised(sub(vertical, scaled(n, dot(vertical, n))));
            let u = cross(v, n);
            (n, u, v)
        };
        let (normal, u, v) = plane;
        let grid = GridPlane {
            normal,
            u,
            v,
            names: [axis_name(u, "u"), axis_name(v, "v")],
        };
        // Planarity: every point within a fraction of the in-plane size of the fitted plane.
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        let mut off: f64 = 0.0;
        for p in positions {
            let q = grid.project(*p);
            for k in 0..2 {
                lo[k] = lo[k].min(q[k]);
                hi[k] = hi[k].max(q[k]);
            }
            off = off.max(dot(sub(*p, c), normal).abs());
        }
        let size = (hi[0] - lo[0]).max(hi[1] - lo[1]);
        if off > PLANAR_FRACTION * size {
            return Err(format!(
                "its points are not on one plane (up to {} from their best plane, {} allowed: \
                 1 % of the grid's size); give each plane its own --grid file",
                short(off),
                short(PLANAR_FRACTION * size)
            ));
        }
        Ok(grid)
    }

    /// A point's coordinates along (`u`, `v`).
    pub fn project(&self, p: [f64; 3]) -> [f64; 2] {
        [dot(p, self.u), dot(p, self.v)]
    }
}

/// A length with four significant digits and no trailing zeros.
fn short(x: f64) -> String {
    let digits = (3 - x.abs().max(1e-300).log10().floor() as i32).clamp(0, 12) as usize;
    let s = format!("{x:.digits$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lattice(f: impl Fn(f64, f64) -> [f64; 3]) -> Vec<[f64; 3]> {
        (0..5)
            .flat_map(|i| (0..4).map(move |j| (i as f64, j as f64)))
            .map(|(a, b)| f(a, b))
            .collect()
    }

    /// A floor (z up) is drawn x right, y up, in the scene's coordinates; in a y-up scene z
    /// right, x up; a wall facing −x in elevation: −y right (seen from −x), z up.
    #[test]
    fn axes_follow_the_scene() {
        let floor = lattice(|a, b| [a, b, 0.8]);
        let g = GridPlane::fit(&floor, &vec![[0.0, 0.0, 1.0]; 20], Up::Z).unwrap();
        assert_eq!(g.names, ["x".to_string(), "y".to_string()]);
        assert!((g.project([2.0, 3.0, 0.8])[0] - 2.0).abs() < 1e-12);
        assert!((g.project([2.0, 3.0, 0.8])[1] - 3.0).abs() < 1e-12);
        let floor_y = lattice(|a, b| [b, 0.8, a]);
        let g = GridPlane::fit(&floor_y, &vec![[0.0, 1.0, 0.0]; 20], Up::Y).unwrap();
        assert_eq!(g.names, ["z".to_string(), "x".to_string()]);
        let wall = lattice(|a, b| [5.0, a, b]);
        let g = GridPlane::fit(&wall, &vec![[-1.0, 0.0, 0.0]; 20], Up::Z).unwrap();
        assert_eq!(g.names, ["−y".to_string(), "z".to_string()]);
        for (a, b) in [(g.u, g.v), (g.v, g.normal), (g.normal, g.u)] {
            assert!(dot(a, b).abs() < 1e-12);
        }
        assert!(dot(cross(g.u, g.v), g.normal) > 1.0 - 1e-12);
    }

    /// A tilted plane is found to rounding (its normal from the eigenvector); points on
    /// two planes, on a line, or at one spot are refused, saying which.
    #[test]
    fn planes_are_fitted_and_non_planes_refused() {
        let n = normalised([0.3, -0.2, 1.0]);
        let a = normalised(cross(n, [1.0, 0.0, 0.0]));
        let b = cross(n, a);
        let tilted = lattice(|s, t| [0, 1, 2].map(|k| 1.0 + s * a[k] + 0.7 * t * b[k]));
        let g = GridPlane::fit(&tilted, &vec![n; 20], Up::Z).unwrap();
        assert!(dot(g.normal, n).abs() > 1.0 - 1e-12, "{:?}", g.normal);
        let mut two = lattice(|a, b| [a, b, 0.0]);
        two.extend(lattice(|a, b| [a, 0.0, b + 1.0]));
        let e = GridPlane::fit(&two, &vec![[0.0, 0.0, 1.0]; 40], Up::Z).unwrap_err();
        assert!(e.contains("not on one plane"), "{e}");
        let line: Vec<[f64; 3]> = (0..6).map(|k| [k as f64, 2.0, 0.8]).collect();
        let e = GridPlane::fit(&line, &[[0.0, 0.0, 1.0]; 6], Up::Z).unwrap_err();
        assert!(e.contains("line"), "{e}");
        let e = GridPlane::fit(&[[1.0, 1.0, 1.0]; 3], &[[0.0, 0.0, 1.0]; 3], Up::Z).unwrap_err();
        assert!(e.contains("one spot"), "{e}");
        assert_eq!(short(0.012345), "0.01235");
        assert_eq!(short(2.0), "2");
    }
}
