//! Finding the shooter in O(log N): the patch with the largest key (its unshot energy, or a
//! quantity derived from it), kept in a binary max-tree that is updated as residuals change.
//!
//! Ties go to the lowest patch index, as a linear scan "first strictly greater" does, so every
//! method picks exactly the shooter it picked with the scan it replaces (tested against one).
//! A shot that changes k residuals costs O(k log N) instead of the scan's O(N).

use crate::color::Rgb;

/// A binary max-tree over N keys: update and arg-max in O(log N); ties to the lowest index.
#[derive(Clone, Debug)]
pub struct MaxTree {
    size: usize,
    node: Vec<(f64, u32)>,
}

impl MaxTree {
    /// A tree over `keys`.
    pub fn new(keys: &[f64]) -> Self {
        let size = keys.len().next_power_of_two().max(1);
        let mut node = vec![(f64::NEG_INFINITY, 0u32); 2 * size];
        for (i, &k) in keys.iter().enumerate() {
            node[size + i] = (k, i as u32);
        }
        for p in (1..size).rev() {
            node[p] = Self::better(node[2 * p], node[2 * p + 1]);
        }
        Self { size, node }
    }

    /// The larger of two entries; `a` (the left, lower indices) on ties.
    fn better(a: (f64, u32), b: (f64, u32)) -> (f64, u32) {
        if b.0 > a.0 {
            b
        } else {
            a
        }
    }

    /// Set key `i`.
    pub fn set(&mut self, i: usize, key: f64) {
        let mut p = self.size + i;
        let old = self.node[p].0;
        if old == key {
            return;
        }
        self.node[p].0 = key;
        p /= 2;
        if key > old {
            // A key that grows only climbs while it beats the maximum above it (a parent holds
            // the larger of its children, the lower index on ties): one read a level, and most
            // receivers of a shot stop at the first.
            let me = (key, i as u32);
            while p >= 1 {
                let cur = self.node[p];
                if cur.0 > key || (cur.0 == key && cur.1 < me.1) {
                    break;
                }
                self.node[p] = me;
                p /= 2;
            }
            return;
        }
        while p >= 1 {
            let b = Self::better(self.node[2 * p], self.node[2 * p + 1]);
            if self.node[p] == b {
                break;
            }
            self.node[p] = b;
            p /= 2;
        }
    }

    /// The largest key and its index (the lowest index among equal keys).
    pub fn max(&self) -> (f64, usize) {
        let (k, i) = self.node[1];
        (k, i as usize)
    }

    /// Key `i`.
    pub fn get(&self, i: usize) -> f64 {
        self.node[self.size + i].0
    }
}

/// Per node of [`AmbientTree`]: the largest `|r_c| A` and `ρ_c A` of each channel below it.
#[derive(Clone, Copy, Debug)]
struct Bounds {
    unshot: [f64; 3],
    reflect: [f64; 3],
}

impl Bounds {
    const EMPTY: Bounds = Bounds {
        unshot: [f64::NEG_INFINITY; 3],
        reflect: [f64::NEG_INFINITY; 3],
    };

    fn join(a: Bounds, b: Bounds) -> Bounds {
        let m = |x: [f64; 3], y: [f64; 3]| [x[0].max(y[0]), x[1].max(y[1]), x[2].max(y[2])];
        Bounds {
            unshot: m(a.unshot, b.unshot),
            reflect: m(a.reflect, b.reflect),
        }
    }

    /// An upper bound of `Σ_c |r_c + ρ_c a_c| A` over the node, for `a` ≥ 0 per channel or not.
    fn bound(&self, ambient: [f64; 3]) -> f64 {
        (0..3)
            .map(|c| self.unshot[c] + ambient[c].abs() * self.reflect[c])
            .sum()
    }
}

/// The shooter of overshooting with the ambient term (Gortler et al. 1993, §2.2.1): the largest
/// `|r_i + ρ_i · ambient|₁ · A_i`, where the ambient term changes with every shot, so that no
/// key can be kept. Each node holds per-channel maxima of `|r_c| A` and `ρ_c A`, whose sum with
/// the current ambient bounds every key below it (triangle inequality); a best-first descent
/// visits only nodes whose bound beats the best key found, left (lower indices) first.
#[derive(Clone, Debug)]
pub struct AmbientTree {
    size: usize,
    node: Vec<Bounds>,
}

/// Relative slack on a node's bound, so that rounding in the bound never prunes the true best.
const SLACK: f64 = 1e-12;

impl AmbientTree {
    /// A tree over residuals `r`, reflectances `rho` and areas `area`.
    pub fn new(r: &[Rgb], rho: &[Rgb], area: &[f64]) -> Self {
        let n = r.len();
        let size = n.next_power_of_two().max(1);
        let mut node = vec![Bounds::EMPTY; 2 * size];
        for i in 0..n {
            node[size + i] = Bounds {
                unshot: (r[i].map(f64::abs) * area[i]).to_array(),
                reflect: (rho[i] * area[i]).to_array(),
            };
        }
        for p in (1..size).rev() {
            node[p] = Bounds::join(node[2 * p], node[2 * p + 1]);
        }
        Self { size, node }
    }

    /// Residual `i` is now `r` (area `area`).
    pub fn set(&mut self, i: usize, r: Rgb, area: f64) {
        let mut p = self.size + i;
        self.node[p].unshot = (r.map(f64::abs) * area).to_array();
        p /= 2;
        while p >= 1 {
            self.node[p] = Bounds::join(self.node[2 * p], self.node[2 * p + 1]);
            p /= 2;
        }
    }

    /// The index with the largest `key(i)` (the lowest on ties) and its key, where `key(i)`
    /// must be at most the node bound for the `ambient` given.
    pub fn argmax(&self, ambient: Rgb, key: impl Fn(usize) -> f64) -> (usize, f64) {
        let ambient = ambient.to_array();
        let mut best = (0usize, f64::NEG_INFINITY);
        let mut stack = vec![1usize];
        while let Some(p) = stack.pop() {
            // Bounds are sums of non-negative terms (−∞ for padding): a node whose bound, with
            // slack for rounding, cannot beat the best strictly is skipped.
            let b = self.node[p].bound(ambient);
            if b == f64::NEG_INFINITY || b * (1.0 + SLACK) <= best.1 {
                continue;
            }
            if p >= self.size {
                let i = p - self.size;
                let k = key(i);
                // Nodes are visited in index order, so a later equal key never wins.
                if k > best.1 {
                    best = (i, k);
                }
            } else {
                // Right pushed first so that the left subtree is explored first.
                stack.push(2 * p + 1);
                stack.push(2 * p);
            }
        }
        best
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::{stream, uniform};

    fn scan(keys: &[f64]) -> (usize, f64) {
        let mut best = (0, f64::NEG_INFINITY);
        for (i, &k) in keys.iter().enumerate() {
            if k > best.1 {
                best = (i, k);
            }
        }
        best
    }

    /// After every random update the tree's arg-max is the linear scan's, ties included.
    #[test]
    fn max_tree_agrees_with_a_linear_scan() {
        let mut rng = stream(3, 0, 0, 0);
        for n in [1usize, 2, 3, 7, 64, 1000] {
            // Few distinct values, so ties are common.
            let mut keys: Vec<f64> = (0..n)
                .map(|_| (uniform(&mut rng) * 8.0).floor() as f64)
                .collect();
            let mut tree = MaxTree::new(&keys);
            for _ in 0..5000 {
                let i = (uniform(&mut rng) * n as f32) as usize % n;
                keys[i] = (uniform(&mut rng) * 8.0).floor() as f64;
                tree.set(i, keys[i]);
                let (k, j) = tree.max();
                assert_eq!((j, k), scan(&keys));
                assert_eq!(tree.get(i), keys[i]);
            }
        }
    }

    /// The ambient tree's best-first search finds the linear scan's shooter for residuals of
    /// both signs and ambient terms of both signs.
    #[test]
    fn ambient_tree_agrees_with_a_linear_scan() {
        let mut rng = stream(5, 0, 0, 0);
        let u = |rng: &mut crate::sampling::Rng64| uniform(rng) as f64;
        for n in [1usize, 5, 33, 500] {
            let rgb = |rng: &mut crate::sampling::Rng64, s: f64| {
                Rgb::new(u(rng) * s, u(rng) * s, u(rng) * s)
            };
            let mut r: Vec<Rgb> = (0..n)
                .map(|_| rgb(&mut rng, 2.0) - Rgb::splat(0.5))
                .collect();
            let rho: Vec<Rgb> = (0..n).map(|_| rgb(&mut rng, 0.9)).collect();
            let area: Vec<f64> = (0..n).map(|_| 0.1 + u(&mut rng)).collect();
            let mut tree = AmbientTree::new(&r, &rho, &area);
            for step in 0..2000 {
                let i = (u(&mut rng) * n as f64) as usize % n;
                r[i] = if step % 7 == 0 {
                    Rgb::BLACK
                } else {
                    rgb(&mut rng, 2.0) - Rgb::splat(1.0)
                };
                tree.set(i, r[i], area[i]);
                let ambient = rgb(&mut rng, 1.0) - Rgb::splat(0.3);
                let key = |k: usize| {
                    let a = r[k] + rho[k] * ambient;
                    (a.r.abs() + a.g.abs() + a.b.abs()) * area[k]
                };
                let keys: Vec<f64> = (0..n).map(key).collect();
                assert_eq!(tree.argmax(ambient, key), scan(&keys));
            }
        }
    }
}
