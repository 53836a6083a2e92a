//! Finding the shooter in O(log N): the patch with the largest key (its unshot energy, or a
//! quantity derived from it), kept in a binary max-tree that is updated as residuals change.
//!
//! Ties go to the lowest patch index, as a linear scan "first strictly greater" does, so every
//! method picks exactly the shooter it picked with the scan it replaces (tested against one).
//! A shot that changes k residuals costs O(k log N) instead of the scan's O(N).

use crate::color::Rgb;

/// Keys a leaf block of the tree holds: one cache line of `f64`.
const BLOCK: usize = 8;

/// Something that holds a key of the max-tree: the key itself, or a patch's record with the
/// key beside the data it is derived from, so that an update reads and writes one cache line
/// ([`super::relaxation`]).
pub trait Keyed {
    /// The key.
    fn key(&self) -> f64;
    /// Replace the key.
    fn set_key(&mut self, key: f64);
}

impl Keyed for f64 {
    #[inline]
    fn key(&self) -> f64 {
        *self
    }
    #[inline]
    fn set_key(&mut self, key: f64) {
        *self = key;
    }
}

/// The part of a max-tree above its keys: each block of [`MaxTree::BLOCK`] keys' maximum and the binary
/// tree over those maxima, a sixteenth of the size of a tree over single keys, so that its
/// lower levels stay in the cache. The keys live elsewhere (in [`MaxTree`], or in the
/// records of [`super::relaxation`]) and are passed in where they are read.
#[derive(Clone, Debug)]
pub struct Blocks {
    size: usize,
    node: Vec<(f64, u32)>,
    /// Blocks whose node [`Nodes::set`] changed and [`Blocks::settle`] has not yet carried up.
    dirty: Vec<bool>,
    /// The nodes of one level that [`Blocks::settle_all`] recomputes.
    level: Vec<u32>,
}

impl Blocks {
    /// The tree over `keys`.
    pub fn new<K: Keyed>(keys: &[K]) -> Self {
        let blocks = keys.len().div_ceil(BLOCK);
        let size = blocks.next_power_of_two().max(1);
        let mut tree = Self {
            size,
            node: vec![(f64::NEG_INFINITY, 0u32); 2 * size],
            dirty: vec![false; blocks],
            level: Vec::new(),
        };
        for b in 0..blocks {
            tree.node[size + b] = block_max(&keys[b * BLOCK..], b * BLOCK);
        }
        for p in (1..size).rev() {
            tree.node[p] = better(tree.node[2 * p], tree.node[2 * p + 1]);
        }
        tree
    }

    /// The blocks' nodes, to set keys of disjoint ranges from several threads
    /// ([`Nodes::split_at`]). The nodes above the blocks are brought up to date by
    /// [`Self::settle`] afterwards; [`Self::max`] is stale until then.
    pub fn nodes(&mut self) -> Nodes<'_> {
        let blocks = self.dirty.len();
        Nodes {
            first: 0,
            blocks: &mut self.node[self.size..self.size + blocks],
            dirty: &mut self.dirty,
        }
    }

    /// Carry the change of block `b`'s node made by [`Nodes::set`] up the tree, if it changed.
    /// Cheap for a block that did not: one flag.
    pub fn settle(&mut self, b: usize) {
        if !std::mem::take(&mut self.dirty[b]) {
            return;
        }
        let mut p = (self.size + b) / 2;
        while p >= 1 {
            let best = better(self.node[2 * p], self.node[2 * p + 1]);
            if self.node[p] == best {
                break;
            }
            self.node[p] = best;
            p /= 2;
        }
    }

    /// [`Self::settle`] every block in `blocks` (in ascending order, repeats allowed), a level
    /// of the tree at a time: the parents of one level's changed nodes are recomputed together,
    /// each once, and in ascending order, so their reads do not wait on one another as a walk
    /// from each block to the root would (at 10⁶ patches the tree's lower levels are not in
    /// the cache). The tree ends as the walks would leave it.
    pub fn settle_all(&mut self, blocks: impl Iterator<Item = usize>) {
        let mut level = std::mem::take(&mut self.level);
        level.clear();
        for b in blocks {
            if std::mem::take(&mut self.dirty[b]) {
                let p = ((self.size + b) / 2) as u32;
                if level.last() != Some(&p) {
                    level.push(p);
                }
            }
        }
        while !level.is_empty() {
            let mut kept = 0;
            for k in 0..level.len() {
                let p = level[k] as usize;
                let best = better(self.node[2 * p], self.node[2 * p + 1]);
                if self.node[p] != best {
                    self.node[p] = best;
                    let q = (p / 2) as u32;
                    if q >= 1 && (kept == 0 || level[kept - 1] != q) {
                        level[kept] = q;
                        kept += 1;
                    }
                }
            }
            level.truncate(kept);
        }
        self.level = level;
    }

    /// The largest key and its index (the lowest index among equal keys).
    pub fn max(&self) -> (f64, usize) {
        let (k, i) = self.node[1];
        (k, i as usize)
    }
}

/// The larger of two entries; `a` (the left, lower indices) on ties.
fn better(a: (f64, u32), b: (f64, u32)) -> (f64, u32) {
    if b.0 > a.0 {
        b
    } else {
        a
    }
}

/// A max-tree over N keys: update and arg-max in O(log N); ties to the lowest index.
///
/// The keys are kept in blocks of [`MaxTree::BLOCK`], one cache line each, under [`Blocks`].
/// Setting a key that is not its block's maximum and does not become it touches only the key
/// and the block's node; a block's maximum that falls is found again by scanning its line.
#[derive(Clone, Debug)]
pub struct MaxTree {
    keys: Vec<f64>,
    blocks: Blocks,
}

impl MaxTree {
    /// A tree over `keys`.
    pub fn new(keys: &[f64]) -> Self {
        Self {
            keys: keys.to_vec(),
            blocks: Blocks::new(keys),
        }
    }

    /// Set key `i`: its block's node, then the nodes above it while they change.
    pub fn set(&mut self, i: usize, key: f64) {
        self.blocks.nodes().set(&mut self.keys, i, key);
        self.blocks.settle(i / BLOCK);
    }

    /// Keys a block holds.
    pub const BLOCK: usize = BLOCK;

    /// The block of key `i`, for [`Blocks::settle`].
    pub fn block_of(i: usize) -> usize {
        i / BLOCK
    }

    /// The first key of the block of key `i`: where [`Nodes::split_at`] can split.
    pub fn block_start(i: usize) -> usize {
        i / BLOCK * BLOCK
    }

    /// The largest key and its index (the lowest index among equal keys).
    pub fn max(&self) -> (f64, usize) {
        self.blocks.max()
    }

    /// Key `i`.
    pub fn get(&self, i: usize) -> f64 {
        self.keys[i]
    }
}

/// The largest key of `keys[..BLOCK]` (fewer at the end) and its index plus `first`, the
/// lowest on ties.
fn block_max<K: Keyed>(keys: &[K], first: usize) -> (f64, u32) {
    let keys = &keys[..keys.len().min(BLOCK)];
    let mut best = (keys[0].key(), first as u32);
    for (k, key) in keys.iter().enumerate().skip(1) {
        if key.key() > best.0 {
            best = (key.key(), (first + k) as u32);
        }
    }
    best
}

/// The nodes of the blocks of keys `first..`, borrowed to be set apart from the nodes above
/// (which [`Blocks::settle`] updates afterwards). `first` is a multiple of the block size, so
/// that disjoint spans own disjoint blocks.
#[derive(Debug)]
pub struct Nodes<'a> {
    first: usize,
    blocks: &'a mut [(f64, u32)],
    dirty: &'a mut [bool],
}

impl<'a> Nodes<'a> {
    /// The first key index of the span.
    pub fn first(&self) -> usize {
        self.first
    }

    /// Split into the blocks before key `at` (rounded down to a block) and from it; `at` is
    /// clamped to the span.
    pub fn split_at(self, at: usize) -> (Nodes<'a>, Nodes<'a>) {
        let end = self.first + self.blocks.len() * BLOCK;
        let at = (at / BLOCK * BLOCK).clamp(self.first, end);
        let b = (at - self.first) / BLOCK;
        let (b0, b1) = self.blocks.split_at_mut(b);
        let (d0, d1) = self.dirty.split_at_mut(b);
        (
            Nodes {
                first: self.first,
                blocks: b0,
                dirty: d0,
            },
            Nodes {
                first: at,
                blocks: b1,
                dirty: d1,
            },
        )
    }

    /// Ask the cache for the node of key `i`'s block.
    #[inline]
    pub fn prefetch(&self, i: usize) {
        crate::hint::prefetch_at(self.blocks, i.wrapping_sub(self.first) / BLOCK);
    }

    /// Set key `i` (an index of the whole tree, inside the span) to `key` in `keys`, the keys
    /// of the span (`keys[0]` is key `first`), and its block's node; the block is marked for
    /// [`Blocks::settle`] if its node changed.
    #[inline]
    pub fn set<K: Keyed>(&mut self, keys: &mut [K], i: usize, key: f64) {
        let k = i - self.first;
        let old = keys[k].key();
        if old == key {
            return;
        }
        keys[k].set_key(key);
        let b = k / BLOCK;
        let cur = self.blocks[b];
        let me = (key, i as u32);
        let new = if cur.1 == me.1 {
            if key > old {
                me
            } else {
                block_max(&keys[b * BLOCK..], self.first + b * BLOCK)
            }
        } else if key > cur.0 || (key == cur.0 && me.1 < cur.1) {
            me
        } else {
            return;
        };
        if new != cur {
            self.blocks[b] = new;
            self.dirty[b] = true;
        }
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

    /// Keys set through split spans of block nodes (as a shot's receivers are updated by
    /// several threads), then settled block by block, give the linear scan's arg-max.
    #[test]
    fn nodes_set_apart_then_settled_agree_with_a_linear_scan() {
        let mut rng = stream(4, 0, 0, 0);
        for n in [1usize, 9, 64, 1000] {
            let mut keys: Vec<f64> = (0..n)
                .map(|_| (uniform(&mut rng) * 8.0).floor() as f64)
                .collect();
            let mut blocks = Blocks::new(&keys);
            for _ in 0..300 {
                let cut = (uniform(&mut rng) * n as f32) as usize;
                let changed: Vec<usize> = (0..1 + n / 10)
                    .map(|_| (uniform(&mut rng) * n as f32) as usize % n)
                    .collect();
                {
                    let (mut a, mut b) = blocks.nodes().split_at(cut);
                    let at = b.first().min(n);
                    let (ka, kb) = keys.split_at_mut(at);
                    for &i in &changed {
                        let key = (uniform(&mut rng) * 8.0).floor() as f64;
                        if i < at {
                            a.set(ka, i, key);
                        } else {
                            b.set(kb, i, key);
                        }
                    }
                }
                for &i in &changed {
                    blocks.settle(MaxTree::block_of(i));
                }
                let (k, j) = blocks.max();
                assert_eq!((j, k), scan(&keys));
            }
        }
    }

    /// Keys set through [`Nodes`] and settled a level at a time ([`Blocks::settle_all`]) give
    /// the linear scan's arg-max, for keys that rise and fall, blocks repeated and ties common.
    #[test]
    fn blocks_settled_a_level_at_a_time_agree_with_a_linear_scan() {
        let mut rng = stream(6, 0, 0, 0);
        for n in [1usize, 8, 9, 100, 1000, 5000] {
            let mut keys: Vec<f64> = (0..n)
                .map(|_| (uniform(&mut rng) * 8.0).floor() as f64)
                .collect();
            let mut blocks = Blocks::new(&keys);
            for _ in 0..300 {
                let mut changed: Vec<usize> = (0..1 + n / 7)
                    .map(|_| (uniform(&mut rng) * n as f32) as usize % n)
                    .collect();
                changed.sort_unstable();
                let mut nodes = blocks.nodes();
                for &i in &changed {
                    let key = (uniform(&mut rng) * 8.0).floor() as f64;
                    nodes.set(&mut keys, i, key);
                    assert_eq!(keys[i], key);
                }
                blocks.settle_all(changed.iter().map(|&i| MaxTree::block_of(i)));
                let (k, j) = blocks.max();
                assert_eq!((j, k), scan(&keys));
            }
        }
    }

    /// After every random update the tree's arg-max is the linear scan's, ties included.
    #[test]
    fn max_tree_agrees_with_a_linear_scan() {
        let mut rng = stream(3, 0, 0, 0);
        for n in [1usize, 2, 3, 7, 8, 9, 17, 64, 1000] {
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
