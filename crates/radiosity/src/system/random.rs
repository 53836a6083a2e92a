//! Random radiosity systems for tests and experiments: reciprocal systems with a given fill and
//! the random sparse row-diagonally-dominant systems of section 6 of Gortler, Cohen & Slusallek (1993).
//! Both are seeded: the same arguments give the same system on every machine.

use super::StoredSystem;
use super::{Entry, SparseMatrix, System};
use crate::color::Rgb;
use crate::sampling::{stream, uniform, Rng64};

/// A random system (the same shape as any stored system).
pub type Random = StoredSystem;

fn u(rng: &mut Rng64) -> f64 {
    uniform(rng) as f64
}

/// A random reciprocal system: symmetric exchanges S_ij = A_i F_ij = A_j F_ji with a fill of
/// `density`, scaled so every row of F sums to at most `max_row_sum`.
pub fn reciprocal(
    n: usize,
    density: f64,
    max_row_sum: f64,
    rho: (f64, f64),
    emitters: usize,
    seed: u64,
) -> Random {
    let mut rng = stream(seed, 1, 2, 3);
    let area: Vec<f64> = (0..n).map(|_| 0.5 + 1.5 * u(&mut rng)).collect();
    let mut s: Vec<Vec<(u32, f64)>> = vec![Vec::new(); n];
    for i in 0..n {
        for j in i + 1..n {
            if u(&mut rng) < density {
                let v = u(&mut rng);
                s[i].push((j as u32, v));
                s[j].push((i as u32, v));
            }
        }
    }
    // Largest row sum of F = S_i· / A_i; one global scale keeps S symmetric.
    let worst = (0..n)
        .map(|i| s[i].iter().map(|e| e.1).sum::<f64>() / area[i])
        .fold(0.0, f64::max);
    let scale = max_row_sum / worst.max(1e-12);
    let rows: Vec<Vec<Entry>> = (0..n)
        .map(|i| {
            let mut r: Vec<Entry> = s[i]
                .iter()
                .map(|&(j, v)| (j, (v * scale / area[i]) as f32))
                .collect();
            r.sort_by_key(|e| e.0);
            r
        })
        .collect();
    let mut reflectance = Vec::with_capacity(n);
    for _ in 0..n {
        let mut c = [0.0; 3];
        for v in &mut c {
            *v = rho.0 + (rho.1 - rho.0) * u(&mut rng);
        }
        reflectance.push(Rgb::from_array(c));
    }
    let mut emission = vec![Rgb::BLACK; n];
    for k in 0..emitters.min(n) {
        let i = if emitters >= n {
            k
        } else {
            (u(&mut rng) * n as f64) as usize % n
        };
        emission[i] = Rgb::new(1.0 + u(&mut rng), 1.0 + u(&mut rng), 1.0 + u(&mut rng));
    }
    Random {
        system: System {
            area,
            reflectance,
            emission,
        },
        f: SparseMatrix::from_rows(rows),
    }
}

/// A random sparse row-diagonally-dominant system as in section 6 of Gortler et al.: unit areas, each
/// row with about `fill·n` random form factors summing to 0.5–0.95 (not reciprocal), grey
/// reflectances around `rho`, and `emitters` random emitters.
pub fn section6(n: usize, fill: f64, rho: f64, emitters: usize, seed: u64) -> Random {
    let mut rng = stream(seed, 6, 6, 6);
    let mut rows: Vec<Vec<Entry>> = Vec::with_capacity(n);
    for i in 0..n {
        let mut r: Vec<(u32, f64)> = Vec::new();
        for j in 0..n {
            if j != i && u(&mut rng) < fill {
                r.push((j as u32, u(&mut rng)));
            }
        }
        let total: f64 = r.iter().map(|e| e.1).sum();
        let target = 0.5 + 0.45 * u(&mut rng);
        rows.push(
            r.into_iter()
                .map(|(j, v)| (j, (v * target / total.max(1e-12)) as f32))
                .collect(),
        );
    }
    let reflectance = (0..n)
        .map(|_| Rgb::splat((rho + 0.1 * (u(&mut rng) - 0.5)).clamp(0.0, 0.95)))
        .collect();
    let mut emission = vec![Rgb::BLACK; n];
    if emitters >= n {
        emission
            .iter_mut()
            .for_each(|e| *e = Rgb::splat(u(&mut rng)));
    } else {
        for _ in 0..emitters {
            let i = (u(&mut rng) * n as f64) as usize % n;
            emission[i] = Rgb::splat(1.0 + 9.0 * u(&mut rng));
        }
    }
    Random {
        system: System {
            area: vec![1.0; n],
            reflectance,
            emission,
        },
        f: SparseMatrix::from_rows(rows),
    }
}
