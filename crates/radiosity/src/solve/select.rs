//! Finding the shooter in O(log N): the patch with the largest key (its unshot energy, or a
//! quantity derived from it), kept in a binary max-tree that is updated as residuals change.
//!
//! Ties go to the lowest patch index, as a linear scan "first strictly greater" does, so every
//! method picks exactly the shooter it picked with the scan it replaces (tested against one).
//! A shot that changes k residuals costs O(k log N) instead of the scan's O(N).

use crate::color::Rgb;

/// Keys a leaf block of the tree holds. A key that rises changes its block's node only when it
/// beats the block's largest, which the bigger the block the rarer it is, and each change is
/// carried up the tree; a block whose largest key falls is scanned again (once per shot, the
/// shooter's). Blocks of 64 change their node far more rarely than blocks of 8, which more
/// than pays for the longer scan (docs/notes/solvers.md).
const BLOCK: usize = 64;

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
/// tree over those maxima, a 64th of the size of a tree over single keys, so that it stays in
/// the cache. The keys live elsewhere (in [`MaxTree`], or in the
/// records of [`super::relaxation`]) and are passed in where they are read.
///
/// The nodes are stored as a binary heap (node `p`'s children are `2p` and `2p + 1`), so the
/// nodes of one level are contiguous: [`Blocks::nodes`] hands out every level, and a span of
/// blocks split from it ([`Nodes::split_at`]) owns, at each level, the nodes whose blocks all lie
/// inside it. Threads that update disjoint spans of keys can then also settle the tree above
/// them ([`Nodes::settle`]), and the node whose blocks straddle two spans is settled after both
/// ([`Nodes::settle_across`]).
#[derive(Clone, Debug)]
pub struct Blocks {
    size: usize,
    node: Vec<(f64, u32)>,
}

/// Levels a tree over `u32` key indices can have (2³² keys are at most 2²⁹ blocks; more
/// levels than the blocks need stay empty).
const LEVELS: usize = 32;

impl Blocks {
    /// The tree over `keys`.
    pub fn new<K: Keyed>(keys: &[K]) -> Self {
        let blocks = keys.len().div_ceil(BLOCK);
        let size = blocks.next_power_of_two().max(1);
        let mut tree = Self {
            size,
            node: vec![(f64::NEG_INFINITY, 0u32); 2 * size],
        };
        for b in 0..blocks {
            tree.node[size + b] = block_max(&keys[b * BLOCK..], b * BLOCK);
        }
        for p in (1..size).rev() {
            tree.node[p] = better(tree.node[2 * p], tree.node[2 * p + 1]);
        }
        tree
    }

    /// Every node, by levels, to set keys of disjoint ranges from several threads
    /// ([`Nodes::split_at`]) and to settle the tree above them ([`Nodes::settle`],
    /// [`Nodes::settle_across`]); [`Self::max`] is stale until the span this returns (or one it
    /// was split into, for the nodes it owns) is settled.
    pub fn nodes(&mut self) -> Nodes<'_> {
        let mut levels: [&mut [(f64, u32)]; LEVELS] = Default::default();
        // The heap's levels from the blocks (node[size..2 size]) up to the root (node[1..2]).
        let mut rest = &mut self.node[1..];
        let mut count = 1;
        let mut top = 0;
        while count <= self.size {
            let (level, more) = rest.split_at_mut(count);
            top += 1;
            levels[self.size.trailing_zeros() as usize + 1 - top] = level;
            rest = more;
            count *= 2;
        }
        Nodes {
            first: 0,
            lo: 0,
            hi: self.size,
            height: top,
            levels,
        }
    }

    /// Set key `i` of `keys` (all of them) and carry the change of its block's node up the
    /// tree.
    pub fn set<K: Keyed>(&mut self, keys: &mut [K], i: usize, key: f64) {
        let b = i / BLOCK;
        let node = &mut self.node[self.size + b];
        if set_in_block(node, &mut keys[b * BLOCK..], b * BLOCK, i, key) {
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
/// The keys are kept in blocks of [`MaxTree::BLOCK`] (eight cache lines), under [`Blocks`].
/// Setting a key that is not its block's maximum and does not become it touches only the key
/// and the block's node; a block's maximum that falls is found again by scanning its lines.
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
        self.blocks.set(&mut self.keys, i, key);
    }

    /// Keys a block holds.
    pub const BLOCK: usize = BLOCK;

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

/// Set key `i` (a key of the block whose first key is `first`, `keys[0]`) to `key` and the
/// block's `node` with it; true if the node changed.
#[inline(always)]
fn set_in_block<K: Keyed>(
    node: &mut (f64, u32),
    keys: &mut [K],
    first: usize,
    i: usize,
    key: f64,
) -> bool {
    let k = i - first;
    let old = keys[k].key();
    if old == key {
        return false;
    }
    keys[k].set_key(key);
    let cur = *node;
    let me = (key, i as u32);
    let new = if cur.1 == me.1 {
        if key > old {
            me
        } else {
            block_max(keys, first)
        }
    } else if key > cur.0 || (key == cur.0 && me.1 < cur.1) {
        me
    } else {
        return false;
    };
    *node = new;
    new != cur
}

/// The nodes of a span of blocks `lo..hi` (keys from `first = lo · BLOCK` on): at each level,
/// the nodes all of whose blocks lie in the span, which no other span owns, so that disjoint
/// spans can be set and settled by several threads at once. A span's blocks' nodes are set
/// through [`Nodes::setter`], the nodes above them settled by [`Nodes::settle`]; the nodes that straddle
/// two spans split from one belong to that one, and are settled by
/// [`Nodes::settle_across`] once both halves are.
#[derive(Debug)]
pub struct Nodes<'a> {
    first: usize,
    lo: usize,
    hi: usize,
    /// Levels in use (the blocks' level is 0; the root's is `height − 1` in the whole tree).
    height: usize,
    /// `levels[h]`: the nodes of height h whose 2^h blocks lie in `lo..hi`, from the first,
    /// node `lo.div_ceil(2^h)` of its level.
    levels: [&'a mut [(f64, u32)]; LEVELS],
}

/// The parents of the block nodes that a [`Setter`] changed and no [`Nodes::settle`] has yet
/// carried up, ascending and distinct (keys are set in ascending order), in a fixed array: no
/// allocation, and no second pass over the keys set to find the changed blocks. Carried up
/// whenever it fills.
#[derive(Debug)]
pub struct Pending {
    queue: [u32; Nodes::CHUNK],
    n: usize,
}

impl Pending {
    /// Nothing pending.
    pub fn new() -> Self {
        Self {
            queue: [0; Nodes::CHUNK],
            n: 0,
        }
    }
}

impl Default for Pending {
    fn default() -> Self {
        Self::new()
    }
}

/// The nodes of height `h` inside blocks `lo..hi`: from `lo.div_ceil(2^h)` to `hi >> h`.
fn inside(h: usize, lo: usize, hi: usize) -> (usize, usize) {
    let a = lo.div_ceil(1 << h);
    (a, (hi >> h).max(a))
}

impl<'a> Nodes<'a> {
    /// The first key index of the span.
    pub fn first(&self) -> usize {
        self.first
    }

    /// Split into the blocks before key `at` (rounded down to a block) and from it; `at` is
    /// clamped to the span. The nodes that straddle the two stay with `self`, for
    /// [`Self::settle_across`] once the halves are settled and dropped.
    pub fn split_at(&mut self, at: usize) -> (Nodes<'_>, Nodes<'_>) {
        let at = (at / BLOCK * BLOCK).clamp(self.first, self.hi * BLOCK);
        let m = at / BLOCK;
        let mut left: [&mut [(f64, u32)]; LEVELS] = Default::default();
        let mut right: [&mut [(f64, u32)]; LEVELS] = Default::default();
        for (h, level) in self.levels[..self.height].iter_mut().enumerate() {
            let (a, _) = inside(h, self.lo, self.hi);
            let (_, left_end) = inside(h, self.lo, m);
            let (right_start, _) = inside(h, m, self.hi);
            let (l, rest) = level.split_at_mut(left_end - a);
            left[h] = l;
            // Empty where the span holds no node of this height.
            let skip = (right_start - left_end).min(rest.len());
            right[h] = &mut rest[skip..];
        }
        (
            Nodes {
                first: self.first,
                lo: self.lo,
                hi: m,
                height: self.height,
                levels: left,
            },
            Nodes {
                first: at,
                lo: m,
                hi: self.hi,
                height: self.height,
                levels: right,
            },
        )
    }

    /// Recompute the nodes of this span that straddle its split at key `at` (the
    /// [`Self::split_at`] whose halves are now settled), from the bottom up.
    pub fn settle_across(&mut self, at: usize) {
        let m = (at / BLOCK * BLOCK).clamp(self.first, self.hi * BLOCK) / BLOCK;
        for h in 1..self.height {
            let k = m >> h;
            // Node k of height h straddles m if m is not its first block; it is this span's if
            // all its blocks are inside.
            if k << h == m {
                continue;
            }
            if (k << h) < self.lo || ((k + 1) << h) > self.hi {
                break;
            }
            let a = self.lo.div_ceil(1 << h);
            let c = self.lo.div_ceil(1 << (h - 1));
            let (below, this) = self.levels.split_at_mut(h);
            let children = &below[h - 1];
            this[0][k - a] = better(children[2 * k - c], children[2 * k + 1 - c]);
        }
    }

    /// Carry the changes `pending` holds up to the span's highest nodes, a level at a time,
    /// the parents of one level's changed nodes recomputed together, each once, in ascending
    /// order: their reads do not wait on one another as a walk from each block to the root
    /// would (at 10⁶ patches the tree's lower levels are not in the cache).
    pub fn settle(&mut self, pending: &mut Pending) {
        self.carry(&mut pending.queue, pending.n);
        pending.n = 0;
    }

    /// Changed blocks' parents [`Pending`] holds before they are carried up.
    pub const CHUNK: usize = 512;

    /// Recompute the nodes of height 1 in `queue[..n]` (ascending, distinct) and those above
    /// that change, inside the span.
    fn carry(&mut self, queue: &mut [u32], mut n: usize) {
        for h in 1..self.height {
            // Keep the nodes of this height inside the span; the others straddle its edge.
            let (a, end) = inside(h, self.lo, self.hi);
            let c = self.lo.div_ceil(1 << (h - 1));
            let (below, this) = self.levels.split_at_mut(h);
            let (children, level) = (&below[h - 1], &mut this[0]);
            let mut kept = 0;
            for q in 0..n {
                let k = queue[q] as usize;
                if k < a || k >= end {
                    continue;
                }
                let best = better(children[2 * k - c], children[2 * k + 1 - c]);
                if level[k - a] != best {
                    level[k - a] = best;
                    let up = (k / 2) as u32;
                    if kept == 0 || queue[kept - 1] != up {
                        queue[kept] = up;
                        kept += 1;
                    }
                }
            }
            n = kept;
            if n == 0 {
                break;
            }
        }
    }

    /// The span's block nodes and `pending`, to set up to `count` ([`Self::CHUNK`] at most)
    /// keys in ascending order: `pending` is carried up first if it lacks room for `count`
    /// more changed blocks, so that a [`Setter`] never needs the levels above the blocks.
    pub fn setter<'n>(&'n mut self, pending: &'n mut Pending, count: usize) -> Setter<'n> {
        assert!(
            count <= Self::CHUNK,
            "{count} keys to set, a Pending holds {}",
            Self::CHUNK
        );
        if pending.n + count > Self::CHUNK {
            self.settle(pending);
        }
        Setter {
            first: self.first,
            lo: self.lo,
            blocks: &mut *self.levels[0],
            pending,
        }
    }
}

/// A span's block nodes, borrowed from [`Nodes::setter`] with room in its [`Pending`] for the
/// keys it is to set: what a receiver's update reads besides its own record, held in locals
/// rather than reached through the whole span each time.
#[derive(Debug)]
pub struct Setter<'n> {
    first: usize,
    lo: usize,
    blocks: &'n mut [(f64, u32)],
    pending: &'n mut Pending,
}

impl Setter<'_> {
    /// Set key `i` (an index of the whole tree, inside the span, past every key set since
    /// the `Pending` was last settled) to `key` in `keys`, the keys of the span (`keys[0]` is
    /// key `first`), and its block's node; if the node changed, its parent is added to the
    /// `Pending` for [`Nodes::settle`].
    #[inline(always)]
    pub fn set<K: Keyed>(&mut self, keys: &mut [K], i: usize, key: f64) {
        let d = (i - self.first) / BLOCK;
        let node = &mut self.blocks[d];
        if set_in_block(node, &mut keys[d * BLOCK..], self.first + d * BLOCK, i, key) {
            self.changed(d);
        }
    }

    /// [`Self::set`] where the caller knows the key's value before, `old`: a key that rises
    /// (a receiver's, in progressive refinement always) changes its block's node only if it
    /// beats it, which is decided without the block's other keys and the checks that a
    /// falling key needs (measured with one loop per case in [`super::relaxation`]:
    /// docs/notes/solvers.md).
    #[inline(always)]
    pub fn set_from<K: Keyed>(&mut self, keys: &mut [K], i: usize, old: f64, key: f64) {
        let k = i - self.first;
        debug_assert_eq!(keys[k].key(), old);
        if key.partial_cmp(&old) != Some(std::cmp::Ordering::Greater) {
            return self.set(keys, i, key);
        }
        keys[k].set_key(key);
        self.rose(i, key);
    }

    /// The block node's part of [`Self::set_from`] for a key that rose, once the caller has
    /// stored it: key `i` (of the whole tree) is now `key`, larger than it was.
    #[inline(always)]
    pub fn rose(&mut self, i: usize, key: f64) {
        let d = (i - self.first) / BLOCK;
        let node = &mut self.blocks[d];
        // The node held this key (then smaller, now beaten) or a larger one; ties go to the
        // lower index, as in `set_in_block`.
        let me = i as u32;
        if key > node.0 || (key == node.0 && me < node.1) {
            *node = (key, me);
            self.changed(d);
        }
    }

    /// Block `d` of the span changed its node: its parent is added to the `Pending`, which
    /// [`Nodes::setter`] left room in.
    #[inline(always)]
    fn changed(&mut self, d: usize) {
        let parent = ((self.lo + d) / 2) as u32;
        let p = &mut *self.pending;
        if p.n > 0 && p.queue[p.n - 1] == parent {
            return;
        }
        debug_assert!(p.n == 0 || p.queue[p.n - 1] < parent);
        p.queue[p.n] = parent;
        p.n += 1;
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

    /// Set `changes` (ascending by key) in the span `n` (whose keys are `keys`, `keys[0]`
    /// being key `n.first()`), split at random into spans set and settled apart, as a shot's
    /// receivers are by several threads, each split's straddling nodes settled after its halves.
    fn set_in_spans(
        n: &mut Nodes<'_>,
        keys: &mut [f64],
        changes: &[(usize, f64)],
        rng: &mut crate::sampling::Rng64,
    ) {
        if changes.len() <= 2 || uniform(rng) < 0.15 {
            let mut pending = Pending::new();
            for &(i, key) in changes {
                // Either way of setting a key, `set_from` with the key it replaces.
                let old = keys[i - n.first()];
                let mut setter = n.setter(&mut pending, 1);
                if uniform(rng) < 0.5 {
                    setter.set(keys, i, key);
                } else {
                    setter.set_from(keys, i, old, key);
                }
                assert_eq!(keys[i - n.first()], key);
            }
            n.settle(&mut pending);
            return;
        }
        let first = n.first();
        // Anywhere in the span, also at or past its end (a split that leaves one half empty).
        let at = first + (uniform(rng) * (keys.len() + 2 * BLOCK) as f32) as usize;
        {
            let (mut a, mut b) = n.split_at(at);
            let m = b.first();
            let (ka, kb) = keys.split_at_mut((m - first).min(keys.len()));
            let cut = changes.partition_point(|c| c.0 < m);
            set_in_spans(&mut a, ka, &changes[..cut], rng);
            set_in_spans(&mut b, kb, &changes[cut..], rng);
        }
        n.settle_across(at);
    }

    /// Keys set through spans split at random and settled apart (as [`super::super::relaxation`]
    /// does over threads) leave every node of the tree as a tree built afresh over the keys
    /// has it, so the arg-max is the linear scan's: keys that rise and fall, ties common, blocks
    /// repeated; keys set by [`Setter::set`] and by [`Setter::set_from`] mixed. (Its spans
    /// change too few blocks to fill a [`Pending`]: the next test does.)
    #[test]
    fn nodes_set_and_settled_in_spans_are_the_tree_built_afresh() {
        let mut rng = stream(4, 0, 0, 0);
        for n in [1usize, 8, 9, 64, 100, 1000, 5000, 20_000] {
            let mut keys: Vec<f64> = (0..n)
                .map(|_| (uniform(&mut rng) * 8.0).floor() as f64)
                .collect();
            let mut blocks = Blocks::new(&keys);
            for _ in 0..200 {
                let mut changes: Vec<(usize, f64)> = (0..1 + n / 5)
                    .map(|_| {
                        let i = (uniform(&mut rng) * n as f32) as usize % n;
                        (i, (uniform(&mut rng) * 8.0).floor() as f64)
                    })
                    .collect();
                changes.sort_by_key(|c| c.0);
                set_in_spans(&mut blocks.nodes(), &mut keys, &changes, &mut rng);
                let fresh = Blocks::new(&keys);
                assert_eq!(blocks.node[1..], fresh.node[1..], "n = {n}");
                let (k, j) = blocks.max();
                assert_eq!((j, k), scan(&keys));
            }
        }
    }

    /// One span whose every block's node changes, by keys that rise above their block's and
    /// then fall below it: 1,563 changed parents, more than a [`Pending`] holds, set through
    /// setters of up to [`Nodes::CHUNK`] keys as the relaxation methods' spans are, so that
    /// [`Nodes::setter`] carries the queue up before it would overflow; every node is then a
    /// tree built afresh's.
    #[test]
    fn a_span_changing_more_blocks_than_a_pending_holds_is_carried_up_in_time() {
        let n = 200_000;
        let mut keys: Vec<f64> = (0..n).map(|i| (i % 97) as f64).collect();
        let mut blocks = Blocks::new(&keys);
        for (round, rise) in [(0, true), (1, false)] {
            let changes: Vec<(usize, f64)> = (round..n)
                .step_by(BLOCK)
                .map(|i| (i, if rise { 1000.0 + i as f64 } else { -1.0 }))
                .collect();
            let mut nodes = blocks.nodes();
            let mut pending = Pending::new();
            for chunk in changes.chunks(Nodes::CHUNK) {
                let mut setter = nodes.setter(&mut pending, chunk.len());
                for &(i, key) in chunk {
                    let old = keys[i];
                    setter.set_from(&mut keys, i, old, key);
                }
            }
            nodes.settle(&mut pending);
            assert_eq!(
                blocks.node[1..],
                Blocks::new(&keys).node[1..],
                "round {round}"
            );
            let (k, j) = blocks.max();
            assert_eq!((j, k), scan(&keys));
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
