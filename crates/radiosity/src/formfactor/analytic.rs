//! The exact form factor between two unoccluded planar polygons, by the contour integral that
//! Stokes' theorem turns eq. 6's double area integral into (Sparrow 1963; Mitalas & Stephenson):
//!
//! ```text
//! A_i F_ij = 1/(2π) Σ_{edges p of i} Σ_{edges q of j} (e_p · e_q) ∫₀¹∫₀¹ ln |P(s) − Q(t)| ds dt
//! ```
//!
//! The inner integral along an edge has a closed form. With `w = x − c`, `α = |v|²`,
//! `t₀ = v·w/α` and `h² = |w|²/α − t₀²` it is ½ [ln α + G(1 − t₀) − G(−t₀)], where
//! `G(τ) = τ ln(τ² + h²) − 2τ + 2h atan(τ/h)`. The outer integral is done by adaptive
//! Gauss–Kronrod (7/15 points) to 1e-13, which handles the logarithmic singularities of edges that
//! touch or coincide (adjacent patches), where point-sampling methods are least accurate.
//!
//! Only the parts of each polygon in front of the other count (a one-sided surface neither sends
//! to nor receives from behind). So each polygon is first clipped to the other's front
//! half-space, which is exact because the integrand's sign depends on each point's side of the
//! other plane alone. Occlusion is ignored: this is the reference for unoccluded pairs.

use glam::DVec3;

/// Gauss–Kronrod 15-point nodes (positive half) and weights, with the embedded 7-point Gauss
/// weights (QUADPACK's qk15).
const XGK: [f64; 8] = [
    0.991_455_371_120_812_6,
    0.949_107_912_342_758_5,
    0.864_864_423_359_769_1,
    0.741_531_185_599_394_4,
    0.586_087_235_467_691_1,
    0.405_845_151_377_397_2,
    0.207_784_955_007_898_5,
    0.0,
];
const WGK: [f64; 8] = [
    0.022_935_322_010_529_22,
    0.063_092_092_629_978_55,
    0.104_790_010_322_250_2,
    0.140_653_259_715_525_9,
    0.169_004_726_639_267_9,
    0.190_350_578_064_785_4,
    0.204_432_940_075_298_9,
    0.209_482_141_084_727_8,
];
const WG: [f64; 4] = [
    0.129_484_966_168_869_7,
    0.279_705_391_489_276_7,
    0.381_830_050_505_118_9,
    0.417_959_183_673_469_4,
];

/// Kronrod estimate, error estimate |K15 − G7|, and ∫|f| (for the round-off floor).
fn gk15(f: &impl Fn(f64) -> f64, a: f64, b: f64) -> (f64, f64, f64) {
    let c = 0.5 * (a + b);
    let h = 0.5 * (b - a);
    let fc = f(c);
    let mut k = WGK[7] * fc;
    let mut g = WG[3] * fc;
    let mut abs = WGK[7] * fc.abs();
    for j in 0..7 {
        let x = h * XGK[j];
        let (f1, f2) = (f(c - x), f(c + x));
        k += WGK[j] * (f1 + f2);
        abs += WGK[j] * (f1.abs() + f2.abs());
        if j % 2 == 1 {
            g += WG[j / 2] * (f1 + f2);
        }
    }
    (k * h, (k - g).abs() * h, abs * h)
}

fn adaptive(f: &impl Fn(f64) -> f64, a: f64, b: f64, tol: f64, depth: u32) -> f64 {
    let (k, err, abs) = gk15(f, a, b);
    // Stop at the tolerance, at the round-off floor of the integrand's magnitude (QUADPACK's
    // test: further bisection cannot gain accuracy), at the depth limit, or on a non-number.
    let floor = 50.0 * f64::EPSILON * abs;
    if err <= tol.max(floor) || depth == 0 || !err.is_finite() {
        return k;
    }
    let m = 0.5 * (a + b);
    adaptive(f, a, m, 0.5 * tol, depth - 1) + adaptive(f, m, b, 0.5 * tol, depth - 1)
}

/// 8-point Gauss–Legendre on [0, 1]: nodes and weights.
const GL8: [(f64, f64); 8] = [
    (0.019_855_071_751_231_88, 0.050_614_268_145_188_13),
    (0.101_666_761_293_186_6, 0.111_190_517_226_687_2),
    (0.237_233_795_041_835_5, 0.156_853_322_938_943_6),
    (0.408_282_678_752_175, 0.181_341_891_689_181),
    (0.591_717_321_247_825, 0.181_341_891_689_181),
    (0.762_766_204_958_164_5, 0.156_853_322_938_943_6),
    (0.898_333_238_706_813_4, 0.111_190_517_226_687_2),
    (0.980_144_928_248_768_1, 0.050_614_268_145_188_13),
];

/// ∫₀¹ ln |x − (c + t v)| dt. Near the edge, in closed form; far from it (distance from the
/// edge's middle above four edge lengths) the closed form loses digits to cancellation between
/// two large terms, while the integrand is smooth there: 8-point Gauss–Legendre is exact to
/// rounding.
fn log_distance_integral(x: DVec3, c: DVec3, v: DVec3) -> f64 {
    let w = x - c;
    let alpha = v.length_squared();
    if (w - 0.5 * v).length_squared() > 16.0 * alpha {
        return GL8
            .iter()
            .map(|&(t, wt)| wt * (w - t * v).length().ln())
            .sum();
    }
    let t0 = v.dot(w) / alpha;
    // h² = |w|²/α − t₀² cancels when x lies on the edge's line (edges shared by adjacent
    // patches): below the rounding level of its terms it is exactly 0, else the noise makes the
    // integrand rough and the adaptive rule bisects without end.
    let ww = w.length_squared() / alpha;
    let h2 = ww - t0 * t0;
    let h2 = if h2 <= 64.0 * f64::EPSILON * (ww + t0 * t0) {
        0.0
    } else {
        h2
    };
    let h = h2.sqrt();
    let g = |tau: f64| {
        let s = tau * tau + h2;
        let l = if s > 0.0 { tau * s.ln() } else { 0.0 };
        let a = if h > 0.0 {
            2.0 * h * (tau / h).atan()
        } else {
            0.0
        };
        l - 2.0 * tau + a
    };
    0.5 * (alpha.ln() + g(1.0 - t0) - g(-t0))
}

/// Keep the part of `poly` where `(p − origin)·normal ≥ 0`.
fn clip(poly: &[DVec3], origin: DVec3, normal: DVec3, out: &mut Vec<DVec3>) {
    out.clear();
    let n = poly.len();
    let scale = poly
        .iter()
        .map(|p| (*p - origin).length())
        .fold(0.0, f64::max)
        .max(1e-300);
    let side = |p: DVec3| {
        let d = (p - origin).dot(normal);
        // Points within rounding of the plane count as on it.
        if d.abs() <= 1e-12 * scale {
            0.0
        } else {
            d
        }
    };
    for k in 0..n {
        let (a, b) = (poly[k], poly[(k + 1) % n]);
        let (da, db) = (side(a), side(b));
        if da >= 0.0 {
            out.push(a);
        }
        if (da > 0.0 && db < 0.0) || (da < 0.0 && db > 0.0) {
            out.push(a + (b - a) * (da / (da - db)));
        }
    }
}

/// Newell's vector area of a polygon.
fn vector_area(p: &[DVec3]) -> DVec3 {
    let mut s = DVec3::ZERO;
    for k in 1..p.len().saturating_sub(1) {
        s += (p[k] - p[0]).cross(p[k + 1] - p[0]);
    }
    0.5 * s
}

/// Reusable buffers for [`polygon_factor`].
#[derive(Clone, Debug, Default)]
pub struct Scratch {
    a: Vec<DVec3>,
    b: Vec<DVec3>,
}

/// The unoccluded form factor F_ij from polygon `pi` (unit normal `ni`, area `area_i`) to
/// polygon `pj` (unit normal `nj`), both counter-clockwise about their normals.
pub fn polygon_factor(
    pi: &[DVec3],
    ni: DVec3,
    area_i: f64,
    pj: &[DVec3],
    nj: DVec3,
    scratch: &mut Scratch,
) -> f64 {
    polygon_factor_tol(pi, ni, area_i, pj, nj, 1e-13, scratch)
}

/// [`polygon_factor`] with each edge pair's outer integral to the relative tolerance `tol`
/// (of the integral of its integrand's magnitude) instead of 1e-13: the adaptive method asks
/// for what its accuracy needs.
pub fn polygon_factor_tol(
    pi: &[DVec3],
    ni: DVec3,
    area_i: f64,
    pj: &[DVec3],
    nj: DVec3,
    tol: f64,
    scratch: &mut Scratch,
) -> f64 {
    // A polygon lying in the other's plane sees it at cos θ = 0 everywhere: F = 0 exactly (the
    // contour integral would reach 0 only through the cancellation of singular terms).
    let size = pi
        .iter()
        .chain(pj.iter())
        .map(|p| (*p - pi[0]).length())
        .fold(0.0, f64::max);
    let in_plane = |poly: &[DVec3], o: DVec3, n: DVec3| {
        poly.iter().all(|p| ((*p - o).dot(n)).abs() <= 1e-9 * size)
    };
    if in_plane(pj, pi[0], ni) || in_plane(pi, pj[0], nj) {
        return 0.0;
    }
    clip(pi, pj[0], nj, &mut scratch.a);
    clip(pj, pi[0], ni, &mut scratch.b);
    let (a, b) = (&scratch.a, &scratch.b);
    if a.len() < 3 || b.len() < 3 {
        return 0.0;
    }
    let size = a
        .iter()
        .chain(b.iter())
        .map(|p| (*p - a[0]).length())
        .fold(0.0, f64::max);
    if vector_area(a).length() <= 1e-14 * size * size
        || vector_area(b).length() <= 1e-14 * size * size
    {
        return 0.0;
    }
    let mut sum = 0.0;
    for p in 0..a.len() {
        let (pa, pb) = (a[p], a[(p + 1) % a.len()]);
        let ep = pb - pa;
        for q in 0..b.len() {
            let (qa, qb) = (b[q], b[(q + 1) % b.len()]);
            let eq = qb - qa;
            let dot = ep.dot(eq);
            if dot.abs() <= 1e-15 * ep.length() * eq.length() {
                continue;
            }
            let f = |s: f64| log_distance_integral(pa + ep * s, qa, eq);
            let (first, _, abs) = gk15(&f, 0.0, 1.0);
            let tol = tol * abs.max(first.abs()).max(1e-300);
            sum += dot * adaptive(&f, 0.0, 1.0, tol, 24);
        }
    }
    // Both contours run counter-clockwise about their own normals, for which the double contour
    // integral is +2π A_i F_ij. Rounding can leave a tiny negative value for pairs that barely
    // see each other; F ≥ 0.
    (sum / (2.0 * std::f64::consts::PI * area_i)).max(0.0)
}

fn polygon(mesh: &crate::mesh::Mesh, k: usize, out: &mut Vec<DVec3>) {
    out.clear();
    let p = &mesh.patches[k];
    let n = if p.is_triangle() { 3 } else { 4 };
    out.extend(
        p.vertices[..n]
            .iter()
            .map(|&v| mesh.vertices[v as usize].as_dvec3()),
    );
}

/// Row `i` of F: the exact unoccluded factor from patch i to every other patch.
pub(super) fn row(est: &super::Estimator, i: usize, scratch: &mut super::Scratch) {
    let mesh = est.mesh;
    let mut pi = std::mem::take(&mut scratch.poly_i);
    let mut pj = std::mem::take(&mut scratch.poly_j);
    polygon(mesh, i, &mut pi);
    let p = &mesh.patches[i];
    let (ni, ai) = (p.normal.as_dvec3(), p.area as f64);
    for j in 0..mesh.len() {
        if j == i {
            continue;
        }
        polygon(mesh, j, &mut pj);
        let nj = mesh.patches[j].normal.as_dvec3();
        let f = polygon_factor(&pi, ni, ai, &pj, nj, &mut scratch.analytic);
        if f > 0.0 {
            scratch.add(j as u32, f);
        }
    }
    scratch.poly_i = pi;
    scratch.poly_j = pj;
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square(z: f64, up: bool) -> Vec<DVec3> {
        let mut v = vec![
            DVec3::new(0.0, 0.0, z),
            DVec3::new(1.0, 0.0, z),
            DVec3::new(1.0, 1.0, z),
            DVec3::new(0.0, 1.0, z),
        ];
        if !up {
            v.reverse();
        }
        v
    }

    #[test]
    fn gauss_kronrod_integrates_a_log_singularity() {
        // ∫₀¹ ln x dx = −1.
        let v = adaptive(
            &|x: f64| if x > 0.0 { x.ln() } else { 0.0 },
            0.0,
            1.0,
            1e-13,
            50,
        );
        assert!((v + 1.0).abs() < 1e-10, "{v}");
    }

    #[test]
    fn facing_squares_and_back_to_back_squares() {
        let mut s = Scratch::default();
        let f = polygon_factor(
            &square(0.0, true),
            DVec3::Z,
            1.0,
            &square(1.0, false),
            -DVec3::Z,
            &mut s,
        );
        // Howell C-11 for X = Y = 1 (see the integration tests for the closed form): 0.1998249.
        assert!((f - 0.199_824_9).abs() < 1e-6, "{f}");
        // Facing away: nothing.
        let g = polygon_factor(
            &square(0.0, false),
            -DVec3::Z,
            1.0,
            &square(1.0, true),
            DVec3::Z,
            &mut s,
        );
        assert_eq!(g, 0.0);
    }
}
