//! What the relaxation methods share (Gortler, Cohen & Slusallek (1993) section 3): the unknowns `x`,
//! the exact residual `r = b − M x = E + ρ F x − x`, and the energy bookkeeping.
//!
//! Changing one unknown `x_i` by `δ` changes the residuals by column `i` of M (Gortler et al. eq. 14,
//! 16): `r_i −= δ`, then `r_j += ρ_j F_ji δ` for every j. Relaxing `x_i` is the change
//! `δ = ω r_i / M_ii` with `M_ii = 1 − ρ_i F_ii` (eq. 12, 18); ω = 1 zeroes `r_i`. Every step
//! costs one column of F, so the residual stays exact and Σ |r_i| A_i, the unshot energy, is
//! known after every step.
//!
//! Energy: a change δ of `x_i` is radiosity shot from i: power `δ A_i` leaves, `F_ji A_j δ`
//! arrives at each j (reciprocity turns the column into power), of which `ρ_j` stays unshot
//! and `1 − ρ_j` is absorbed; the rest escapes. Then emitted = absorbed + escaped + Σ r_i A_i
//! holds exactly at every step (the terms cancel in pairs), also for negative δ.

use super::select::{AmbientTree, Blocks, Keyed, MaxTree, Nodes, Pending, Setter};
use super::{Info, Operator, System};
use crate::color::Rgb;
use crate::hint;
use crate::system::{Column, Entry};

/// The [`super::SolverState`] methods that every relaxation method implements the same way from its
/// `core: Relaxation` field: the output (x, or x + r when the type's `plus_residual()` says so),
/// the unshot fraction, the iteration count and the bookkeeping.
macro_rules! relaxation_accessors {
    () => {
        fn radiosity(&self, out: &mut Vec<crate::color::Rgb>) {
            self.core.output(self.plus_residual(), out);
        }

        fn unshot_fraction(&mut self, _: &mut dyn crate::solve::Operator, _: bool) -> f64 {
            self.core.unshot_fraction()
        }

        fn iterations(&self) -> u64 {
            self.core.iterations
        }

        fn info(&mut self, _: &mut dyn crate::solve::Operator) -> crate::solve::Info {
            self.core.info()
        }
    };
}
pub(crate) use relaxation_accessors;

/// Unknowns, residuals and energy bookkeeping of a relaxation method.
#[derive(Clone, Debug)]
pub struct Relaxation<'s> {
    /// The system.
    pub system: &'s System,
    /// The unknowns x.
    pub x: Vec<Rgb>,
    /// Per patch: the residual r = E + ρ F x − x ([`Self::r`]) with what its update reads.
    cells: Vec<Cell>,
    /// Σ r_i A_i (signed), per channel.
    pub signed_unshot: Rgb,
    abs_unshot: f64,
    emitted: Rgb,
    emitted_total: f64,
    absorbed: Rgb,
    escaped: Rgb,
    /// Iterations done.
    pub iterations: u64,
    updates: u64,
    select: Select,
    row_sums: RowSums,
}

/// One patch as a shot's update reads and writes it: its residual, reflectance, area and key
/// in the shooter's max-tree, in one cache line. At 10⁵–10⁶ patches no cache holds the
/// patches, and a receiver scattered over four arrays cost four cache misses where this costs
/// one; the memory is the same (64 bytes a patch).
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
struct Cell {
    r: Rgb,
    rho: Rgb,
    area: f64,
    /// The shooter's key ([`SelectKind::Energy`] or [`SelectKind::Residual`]), else unused.
    key: f64,
}

const _: () = assert!(std::mem::size_of::<Cell>() == 64);

impl Cell {
    /// `|r|₁ A`, the unshot energy.
    #[inline(always)]
    fn energy(&self) -> f64 {
        abs_sum(self.r) * self.area
    }
}

impl Keyed for Cell {
    #[inline]
    fn key(&self) -> f64 {
        self.key
    }
    #[inline]
    fn set_key(&mut self, key: f64) {
        self.key = key;
    }
}

/// Which patch a method shoots next.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SelectKind {
    /// The largest unshot energy `|r_i|₁ A_i` (progressive refinement).
    Energy,
    /// The largest `|r_i|₁` (Southwell).
    Residual,
    /// The largest `|r_i + ρ_i · ambient|₁ A_i` (overshooting with the ambient term).
    Ambient,
}

/// The shooter's structure, kept up to date as residuals change ([`super::select`]).
#[derive(Clone, Debug)]
enum Select {
    /// None kept (the method sweeps in order).
    None,
    /// The largest unshot energy `|r_i|₁ A_i` (progressive refinement).
    Energy(Blocks),
    /// The largest `|r_i|₁` (Southwell).
    Residual(Blocks),
    /// The largest `|r_i + ρ_i · ambient|₁ A_i` (overshooting with the ambient term).
    Ambient(AmbientTree),
}

/// What a shot's receivers add to the bookkeeping, summed over a range of them: for a shot
/// of δ, the power arriving is `δ Σ F_ji A_j`, the part of it reflected (which stays unshot,
/// the change of Σ r_j A_j) `δ Σ ρ_j F_ji A_j`, and the rest is absorbed, so that two sums
/// serve all three.
///
/// The first two are kept as one 4-vector, `Σ (ρ_j, 1) F_ji A_j`, which a receiver adds with
/// one multiply and one add of four lanes: the two sums were a large part of a receiver's
/// update, and shuffling them into vectors most of it (docs/notes/solvers.md).
#[derive(Clone, Copy, Debug, Default)]
struct Sums {
    /// Σ ρ_j F_ji A_j per channel, then Σ F_ji A_j.
    fa: [f64; 4],
    /// Change of Σ |r_j| A_j.
    abs: f64,
}

impl Sums {
    /// Receiver j with column entry `f` = F_ji, area `a`, reflectance `rho`, and unshot energy
    /// `|r_j|₁ A_j` from `old` to `new`. `FA`: whether to add to [`Self::fa`] (not when the
    /// row's are known already).
    #[inline(always)]
    fn add<const FA: bool>(&mut self, f: f64, a: f64, rho: Rgb, old: f64, new: f64) {
        if FA {
            let fa = f * a;
            let w = [rho.r, rho.g, rho.b, 1.0];
            for (s, w) in self.fa.iter_mut().zip(w) {
                *s += w * fa;
            }
        }
        self.abs += new - old;
    }

    /// Σ F_ji A_j.
    fn arrived(&self) -> f64 {
        self.fa[3]
    }

    /// Σ ρ_j F_ji A_j.
    fn reflected(&self) -> Rgb {
        Rgb::new(self.fa[0], self.fa[1], self.fa[2])
    }
}

impl std::ops::Add for Sums {
    type Output = Sums;
    fn add(self, o: Sums) -> Sums {
        let mut fa = self.fa;
        for (s, o) in fa.iter_mut().zip(o.fa) {
            *s += o;
        }
        Sums {
            fa,
            abs: self.abs + o.abs,
        }
    }
}

/// Per patch, the [`Sums::fa`] of the last row it shot with an id ([`Column::id`]), under
/// that id: a row shot again (most shots reuse a cached row) gives the same sums, added in the
/// same order, so they are kept rather than added again by every receiver, which saves most
/// of what the sums cost an update (docs/notes/solvers.md). 40 bytes a patch, from the first
/// row with an id on.
#[derive(Clone, Debug, Default)]
struct RowSums {
    /// `(id, fa)`, `u64::MAX` for none.
    rows: Vec<(u64, [f64; 4])>,
}

impl RowSums {
    /// Row i's sums, if its row `id` is the one kept.
    fn get(&self, i: usize, id: Option<u64>) -> Option<[f64; 4]> {
        let id = id?;
        match self.rows.get(i) {
            Some(&(kept, fa)) if kept == id && id != u64::MAX => Some(fa),
            _ => None,
        }
    }

    /// The shot's sums: the `known` ones in place of the receivers' (which did not add
    /// them), or the receivers', kept under `id` for patch i of `n`.
    fn keep(
        &mut self,
        (i, n): (usize, usize),
        id: Option<u64>,
        known: Option<[f64; 4]>,
        mut sums: Sums,
    ) -> Sums {
        match (known, id) {
            (Some(fa), _) => sums.fa = fa,
            (None, Some(id)) => {
                if self.rows.len() != n {
                    self.rows = vec![(u64::MAX, [0.0; 4]); n];
                }
                self.rows[i] = (id, sums.fa);
            }
            (None, None) => {}
        }
        sums
    }
}

/// The receivers of a shot with patch indices from `first` on: their column entries, and the
/// patches and the max-tree's block nodes from `first` on.
struct Span<'a> {
    first: usize,
    column: &'a [Entry],
    cells: &'a mut [Cell],
    nodes: Option<Nodes<'a>>,
}

/// A span of more receivers than this is halved ([`halve`]), and the halves are updated by two
/// threads at once when a second one is free: a few microseconds of work at 10⁵–10⁶ patches,
/// long enough for the hand-over to pay (512 did better than 128 or 256: docs/notes/solvers.md).
const SPAN: usize = 512;

// A span short enough to update is one [`Setter`] can take.
const _: () = assert!(SPAN <= Nodes::CHUNK);

/// How many receivers ahead of the one being updated [`update`] asks the cache for: enough
/// misses in flight to cover a trip to memory where the records outgrow the last-level cache
/// (at 10⁶ patches, 64 MB of records, one thread's updates still wait on memory 32 ahead);
/// where they stay in the cache, any of 8 to 64 ahead does (docs/notes/solvers.md).
const AHEAD: usize = 64;

/// Where a span of receivers (its column entries, its first patch `first`) is halved: at the
/// block boundary at or below its middle receiver, or the next one up if that is the span's
/// start, so that both halves keep at least a quarter of the receivers. Returns the first entry
/// of the right half and that block's first patch.
fn halve(column: &[Entry], first: usize) -> (usize, usize) {
    let middle = column[column.len() / 2].0 as usize;
    let mut at = MaxTree::block_start(middle);
    if at <= first {
        at = MaxTree::block_start(middle + MaxTree::BLOCK);
    }
    // The first entry at or past `at`: a few steps from the middle (the column is sorted and a
    // block holds few receivers), where a binary search would wait on a chain of cache misses
    // in a column read from memory.
    let mut k = column.len() / 2;
    while k > 0 && column[k - 1].0 as usize >= at {
        k -= 1;
    }
    while k < column.len() && (column[k].0 as usize) < at {
        k += 1;
    }
    (k, at)
}

/// Update the receivers of `span` for a shot of `delta`: `r_j += ρ_j δ F_ji` and everything
/// that follows from it. Spans longer than [`SPAN`] are halved ([`halve`]), and while another
/// thread is free ([`super::awake::can_split`]) the halves are updated at once
/// ([`super::awake::join`]), so that the receivers' cache misses (arrays of 10⁶ patches do not
/// fit in any cache) are shared by the threads. The sums are added by the same halving
/// whether the halves ran at once or one after the other ([`Receivers::sums`]), so that they
/// depend on the column only, never on the threads.
fn update<const RESIDUAL: bool, const FA: bool>(
    delta: Rgb,
    reciprocal: Option<f32>,
    span: Span<'_>,
) -> Sums {
    let (first, column) = (span.first, span.column);
    if column.len() > SPAN && super::awake::can_split() {
        let (k, at) = halve(column, first);
        let (c0, c1) = span.cells.split_at_mut(at - first);
        let mut nodes = span.nodes;
        let (n0, n1) = match &mut nodes {
            Some(n) => {
                let (a, b) = n.split_at(at);
                (Some(a), Some(b))
            }
            None => (None, None),
        };
        let left = Span {
            first,
            column: &column[..k],
            cells: c0,
            nodes: n0,
        };
        let right = Span {
            first: at,
            column: &column[k..],
            cells: c1,
            nodes: n1,
        };
        let (a, b) = super::awake::join(
            || update::<RESIDUAL, FA>(delta, reciprocal, left),
            || update::<RESIDUAL, FA>(delta, reciprocal, right),
        );
        // The halves settled the tree above their own blocks; what straddles them is ours.
        if let Some(n) = &mut nodes {
            n.settle_across(at);
        }
        return a + b;
    }
    let Span {
        cells, mut nodes, ..
    } = span;
    // The first receivers and lines of the column, which the loop's look-ahead does not
    // cover: asked for here, by the thread that will use them (a line another core fetched
    // sits in that core's cache, not in the shared one).
    hint::prefetch(column.as_ptr(), column.len().div_ceil(8).min(4 * AHEAD / 8));
    for &(j, _) in &column[..column.len().min(AHEAD)] {
        hint::prefetch_at(cells, j as usize - first);
    }
    let mut pending = Pending::new();
    let mut receivers = Receivers::<RESIDUAL, FA> {
        delta,
        reciprocal,
        first,
        column,
        cells,
        nodes: nodes.as_mut(),
        pending: &mut pending,
    };
    let sums = receivers.sums(0, column.len(), first);
    // The max-tree above this span's blocks, while they are in the cache and in parallel
    // with the other spans.
    if let Some(l) = &mut nodes {
        l.settle(&mut pending);
    }
    sums
}

/// The receivers of a span that one thread updates, in order.
struct Receivers<'a, 'b, const RESIDUAL: bool, const FA: bool> {
    delta: Rgb,
    reciprocal: Option<f32>,
    /// The first patch of `cells`.
    first: usize,
    column: &'a [Entry],
    cells: &'a mut [Cell],
    nodes: Option<&'b mut Nodes<'a>>,
    pending: &'b mut Pending,
}

impl<const RESIDUAL: bool, const FA: bool> Receivers<'_, '_, RESIDUAL, FA> {
    /// Update entries `lo..hi` of the column, a span whose first patch is `first`; their sums
    /// added as [`update`] would add them if it ran the halves at once.
    fn sums(&mut self, lo: usize, hi: usize, first: usize) -> Sums {
        if hi - lo > SPAN {
            let (k, at) = halve(&self.column[lo..hi], first);
            let a = self.sums(lo, lo + k, first);
            return a + self.sums(lo + k, hi, at);
        }
        self.update(lo, hi)
    }

    /// Update entries `lo..hi` of the column ([`SPAN`] at most): one copy of the loop for each
    /// of the four cases, so that the loop itself tests neither.
    #[inline(always)]
    fn update(&mut self, lo: usize, hi: usize) -> Sums {
        let column = &self.column[lo..hi];
        // The look-ahead runs on past `hi`, into the leaf this thread updates next ([`run`]).
        let ahead = self.column.get(lo + AHEAD..).unwrap_or(&[]);
        let cells = &mut *self.cells;
        let (delta, first) = (self.delta, self.first);
        match (self.reciprocal, &mut self.nodes) {
            (Some(ai), Some(n)) => {
                let tree = n.setter(self.pending, column.len());
                run::<RESIDUAL, FA, true, true>(delta, ai, first, column, ahead, cells, tree)
            }
            (Some(ai), None) => {
                run::<RESIDUAL, FA, true, false>(delta, ai, first, column, ahead, cells, ())
            }
            (None, Some(n)) => {
                let tree = n.setter(self.pending, column.len());
                run::<RESIDUAL, FA, false, true>(delta, 0.0, first, column, ahead, cells, tree)
            }
            (None, None) => {
                run::<RESIDUAL, FA, false, false>(delta, 0.0, first, column, ahead, cells, ())
            }
        }
    }
}

/// Where a receiver's new key goes: a span's block nodes ([`Setter`]), or nowhere when no
/// shooter's tree is kept.
trait Tree {
    /// Key `i`, stored in `cells`, is now `key`, larger than before ([`Setter::rose`]).
    fn rose(&mut self, i: usize, key: f64);
    /// Set key `i` of `cells` to `key` ([`Setter::set`]).
    fn set(&mut self, cells: &mut [Cell], i: usize, key: f64);
}

impl Tree for Setter<'_> {
    #[inline(always)]
    fn rose(&mut self, i: usize, key: f64) {
        Setter::rose(self, i, key);
    }
    #[inline(always)]
    fn set(&mut self, cells: &mut [Cell], i: usize, key: f64) {
        Setter::set(self, cells, i, key);
    }
}

impl Tree for () {
    #[inline(always)]
    fn rose(&mut self, _: usize, _: f64) {}
    #[inline(always)]
    fn set(&mut self, _: &mut [Cell], _: usize, _: f64) {}
}

/// The receivers `column` of a shot of `delta`, their records `cells` from patch `first` on,
/// where `RECIPROCAL` says whether the column is a row read by reciprocity (then `ai` is the
/// shooter's area) and `TREE` whether a shooter's tree is kept (`tree`). The receivers are
/// scattered over an array that no cache holds at 10⁵–10⁶ patches: the loop asks for the one
/// [`AHEAD`] places on, so that the misses overlap, and for the column itself (a row cached
/// long ago, read from memory) further ahead still, a line at a time. `ahead` is the column
/// [`AHEAD`] entries on from `column`'s first, running past its end into the entries that
/// this thread updates next (the next leaf of a long span), so that their first receivers
/// are asked for too; only the last [`AHEAD`] receivers of a thread's span, already asked
/// for, go without. A look-ahead that stopped at each leaf's end left every leaf after a
/// span's first beginning with [`AHEAD`] receivers not asked for (docs/notes/solvers.md).
///
/// Everything the loop reads besides the column and the records is in locals, and the look-
/// ahead zips the column with itself, so that the compiler keeps bases and bounds in
/// registers. At 10⁵ patches the loop is bound by the core more than by memory (at 10⁶, on one
/// thread, by memory: [`AHEAD`]): a 32-byte record of `f32`s, half the lines, was slower for
/// its conversions, how far ahead receivers are asked for makes no difference there, and the
/// row's sums are a large part of an update ([`RowSums`]; docs/notes/solvers.md).
#[inline(always)]
fn run<const RESIDUAL: bool, const FA: bool, const RECIPROCAL: bool, const TREE: bool>(
    delta: Rgb,
    ai: f32,
    first: usize,
    column: &[Entry],
    ahead: &[Entry],
    cells: &mut [Cell],
    mut tree: impl Tree,
) -> Sums {
    let mut sums = Sums::default();
    for (n, (&now, next)) in column.iter().zip(ahead).enumerate() {
        if n % 8 == 0 {
            hint::prefetch(column.as_ptr().wrapping_add(n + 4 * AHEAD), 1);
        }
        // A prefetch never faults: the receiver's index is checked where it is read.
        let next = (next.0 as usize).wrapping_sub(first);
        hint::prefetch(cells.as_ptr().wrapping_add(next), 1);
        receiver::<RESIDUAL, FA, RECIPROCAL, TREE>(
            delta, ai, first, now, cells, &mut tree, &mut sums,
        );
    }
    for &now in &column[ahead.len().min(column.len())..] {
        receiver::<RESIDUAL, FA, RECIPROCAL, TREE>(
            delta, ai, first, now, cells, &mut tree, &mut sums,
        );
    }
    sums
}

/// Update receiver `(j, f)` of [`run`]: `r_j += ρ_j δ F_ji`, its key, and `sums` (the
/// row's [`Sums::fa`] only if `FA`).
#[inline(always)]
fn receiver<const RESIDUAL: bool, const FA: bool, const RECIPROCAL: bool, const TREE: bool>(
    delta: Rgb,
    ai: f32,
    first: usize,
    (j, f): Entry,
    cells: &mut [Cell],
    tree: &mut impl Tree,
    sums: &mut Sums,
) {
    let j = j as usize;
    let c = &mut cells[j - first];
    let (r, rho, a, key) = (c.r, c.rho, c.area, c.key);
    let f = if RECIPROCAL { f * ai / a as f32 } else { f } as f64;
    let rj = r + rho * delta * f;
    let e = abs_sum(rj) * a;
    // Progressive refinement's key is the receiver's unshot energy before the shot,
    // set from its residual by this very expression.
    let old = if !RESIDUAL && TREE {
        debug_assert_eq!(key, abs_sum(r) * a);
        key
    } else {
        abs_sum(r) * a
    };
    sums.add::<FA>(f, a, rho, old, e);
    c.r = rj;
    if TREE {
        let new = if RESIDUAL { e / a } else { e };
        // A key that rises (a receiver's, in progressive refinement always) is stored here,
        // and its block's node compared with it alone (`Setter::set_from`).
        if new.partial_cmp(&key) == Some(std::cmp::Ordering::Greater) {
            c.key = new;
            tree.rose(j, new);
        } else {
            tree.set(cells, j, new);
        }
    }
}

fn abs_sum(c: Rgb) -> f64 {
    c.r.abs() + c.g.abs() + c.b.abs()
}

impl<'s> Relaxation<'s> {
    /// Start from x = 0 (so r = E).
    pub fn from_zero(system: &'s System) -> Self {
        let n = system.len();
        let emitted = system.emitted_power();
        let cells: Vec<Cell> = (0..n)
            .map(|i| Cell {
                r: system.emission[i],
                rho: system.reflectance[i],
                area: system.area[i],
                key: 0.0,
            })
            .collect();
        let energy = cells.iter().map(Cell::energy);
        Self {
            x: vec![Rgb::BLACK; n],
            signed_unshot: emitted,
            abs_unshot: energy.sum(),
            cells,
            emitted,
            emitted_total: emitted.sum(),
            absorbed: Rgb::BLACK,
            escaped: Rgb::BLACK,
            iterations: 0,
            updates: 0,
            select: Select::None,
            row_sums: RowSums::default(),
            system,
        }
    }

    /// Start from x = E: the residual and the energy of that start come from every row of F.
    pub fn from_emission(system: &'s System, source: &mut dyn Operator) -> Self {
        let mut s = Self::from_zero(system);
        s.x = system.emission.to_vec();
        let (absorbed, escaped, _, _) = crate::system::balance(system, source, &s.x);
        let r = crate::system::residual(system, source, &s.x);
        for (c, r) in s.cells.iter_mut().zip(r) {
            c.r = r;
        }
        s.absorbed = absorbed;
        s.escaped = escaped;
        s.resum();
        s
    }

    /// Keep the shooter of `kind` up to date from now on, in O(log N) per changed residual.
    pub fn select_by(&mut self, kind: SelectKind) {
        self.select = match kind {
            SelectKind::Energy => Select::Energy(Blocks::new::<f64>(&[])),
            SelectKind::Residual => Select::Residual(Blocks::new::<f64>(&[])),
            SelectKind::Ambient => Select::Ambient(AmbientTree::new(&[], &[], &[])),
        };
        self.rebuild_selection();
    }

    fn rebuild_selection(&mut self) {
        let sys = self.system;
        let cells = &mut self.cells;
        match &mut self.select {
            Select::None => {}
            Select::Energy(t) => {
                for c in cells.iter_mut() {
                    c.key = c.energy();
                }
                *t = Blocks::new(cells);
            }
            Select::Residual(t) => {
                // `e / a` as a shot computes it, so that keys compare bit for bit.
                for c in cells.iter_mut() {
                    c.key = c.energy() / c.area;
                }
                *t = Blocks::new(cells);
            }
            Select::Ambient(t) => {
                let r: Vec<Rgb> = cells.iter().map(|c| c.r).collect();
                *t = AmbientTree::new(&r, &sys.reflectance, &sys.area);
            }
        }
    }

    /// The patch with the largest key of the selection kept, and that key. The ambient term is
    /// used by [`SelectKind::Ambient`] only.
    pub fn shooter(&self, ambient: Rgb) -> (usize, f64) {
        match &self.select {
            Select::None => (0, f64::NEG_INFINITY),
            Select::Energy(t) | Select::Residual(t) => {
                let (k, i) = t.max();
                (i, k)
            }
            Select::Ambient(t) => {
                let cells = &self.cells;
                t.argmax(ambient, |i| {
                    let a = cells[i].r + cells[i].rho * ambient;
                    (a.r.abs() + a.g.abs() + a.b.abs()) * cells[i].area
                })
            }
        }
    }

    /// Patch i's unshot energy `|r_i|₁ A_i`, derived from its residual whenever needed (one
    /// array fewer to keep and to miss in the cache).
    #[inline]
    pub fn energy(&self, i: usize) -> f64 {
        self.cells[i].energy()
    }

    /// Patch i's residual `r_i`.
    #[inline]
    pub fn r(&self, i: usize) -> Rgb {
        self.cells[i].r
    }

    /// The residuals, in patch order.
    pub fn residuals(&self) -> impl ExactSizeIterator<Item = Rgb> + '_ {
        self.cells.iter().map(|c| c.r)
    }

    /// Recompute the sums from the residuals (against rounding drift). The shooter's trees
    /// need no such care: every key and bound is set from its residual by the expression a
    /// rebuild would use, and carried up exactly.
    pub fn resum(&mut self) {
        self.abs_unshot = (0..self.cells.len()).map(|i| self.energy(i)).sum();
        self.signed_unshot = self.cells.iter().map(|c| c.r * c.area).sum();
        self.updates = 0;
    }

    fn set_r(&mut self, j: usize, v: Rgb) {
        let a = self.cells[j].area;
        let old = self.cells[j].r;
        self.signed_unshot += (v - old) * a;
        let e = abs_sum(v) * a;
        self.abs_unshot += e - abs_sum(old) * a;
        self.cells[j].r = v;
        let cells = &mut self.cells;
        match &mut self.select {
            Select::None => {}
            Select::Energy(t) => t.set(cells, j, e),
            Select::Residual(t) => t.set(cells, j, e / a),
            Select::Ambient(t) => t.set(j, v, a),
        }
    }

    /// Change `x_i` by `delta`, with `column` = column i of F (`(j, F_ji)`).
    ///
    /// The receivers are updated in parallel over disjoint ranges of patches,
    /// split where the column is (not by thread), so the result does not depend on the
    /// thread count; each range settles the shooter's max-tree above its own blocks, and the
    /// nodes that straddle two ranges are settled once both are done.
    pub fn add(&mut self, i: usize, delta: Rgb, column: &[Entry]) {
        self.add_column(i, delta, Column::Entries(column));
    }

    /// [`Self::add`] with the column as [`Operator::shot_column`] gives it: by reciprocity
    /// from row i, `F_ji = F_ij A_i / A_j`, applied per receiver.
    pub fn add_column(&mut self, i: usize, delta: Rgb, column: Column<'_>) {
        let reciprocal = match column {
            Column::Entries(_) => None,
            Column::Reciprocal { .. } => Some(self.cells[i].area as f32),
        };
        let id = column.id();
        let column = column.entries();
        // Ask for the column's first lines and its middle (where a split starts) while the
        // shooter's own update below waits on its own misses.
        hint::prefetch(column.as_ptr(), column.len().div_ceil(8).min(2 * AHEAD / 8));
        hint::prefetch_at(column, column.len() / 2);
        self.x[i] += delta;
        let ri = self.cells[i].r - delta;
        self.set_r(i, ri);
        let residual = matches!(self.select, Select::Residual(_));
        // The row's `Σ (ρ_j, 1) F_ji A_j`, if this row was shot before.
        let known = match &self.select {
            Select::Ambient(_) => None,
            _ => self.row_sums.get(i, id),
        };
        let cells = &mut self.cells;
        let sums = match &mut self.select {
            Select::Ambient(tree) => {
                let mut sums = Sums::default();
                for &(j, f) in column {
                    let j = j as usize;
                    let c = &mut cells[j];
                    let (r, rho, a) = (c.r, c.rho, c.area);
                    let f = reciprocal.map_or(f, |ai| f * ai / a as f32) as f64;
                    let rj = r + rho * delta * f;
                    sums.add::<true>(f, a, rho, abs_sum(r) * a, abs_sum(rj) * a);
                    c.r = rj;
                    tree.set(j, rj, a);
                }
                sums
            }
            Select::Energy(t) | Select::Residual(t) => {
                let span = Span {
                    first: 0,
                    column,
                    cells,
                    nodes: Some(t.nodes()),
                };
                // Two copies, so that progressive refinement's has no division by the area.
                match (residual, known.is_some()) {
                    (true, false) => update::<true, true>(delta, reciprocal, span),
                    (true, true) => update::<true, false>(delta, reciprocal, span),
                    (false, false) => update::<false, true>(delta, reciprocal, span),
                    (false, true) => update::<false, false>(delta, reciprocal, span),
                }
            }
            Select::None => {
                let span = Span {
                    first: 0,
                    column,
                    cells,
                    nodes: None,
                };
                match known {
                    None => update::<false, true>(delta, reciprocal, span),
                    Some(_) => update::<false, false>(delta, reciprocal, span),
                }
            }
        };
        let sums = self.row_sums.keep((i, self.cells.len()), id, known, sums);
        let arrived = delta * sums.arrived();
        let reflected = delta * sums.reflected();
        self.signed_unshot += reflected;
        self.abs_unshot += sums.abs;
        self.absorbed += arrived - reflected;
        self.escaped += delta * self.cells[i].area - arrived;
        self.updates += column.len() as u64 + 1;
        // Each receiver's update rounds the running sums by at most ε of the energy they hold
        // (never more than the emitted): they are recomputed, an O(N) pass, once that bound
        // could reach a millionth of the unshot energy left, and at most every 8N updates.
        // Far from convergence that is rare (at 10⁶ patches and 1.5 % unshot, every 10⁸
        // updates rather than every 8N = 8 × 10⁶, each pass reading 64 MB); near a tight
        // tolerance it is every 8N updates (docs/notes/solvers.md).
        if self.updates > 8 * self.cells.len() as u64 + 1024
            && self.updates as f64 * f64::EPSILON * self.emitted_total > 1e-6 * self.abs_unshot
        {
            self.resum();
        }
    }

    /// `M_ii = 1 − ρ_i F_ii`, from column i of F.
    pub fn diagonal(&self, i: usize, column: &[Entry]) -> Rgb {
        let f_ii = column
            .binary_search_by_key(&(i as u32), |e| e.0)
            .map_or(0.0, |k| column[k].1 as f64);
        Rgb::splat(1.0) - self.cells[i].rho * f_ii
    }

    /// Relax `x_i` with factor ω: `x_i += ω r_i / M_ii`. Returns false if `r_i` was zero.
    pub fn relax(&mut self, i: usize, omega: f64, source: &mut dyn Operator) -> bool {
        if matches!(self.select, Select::Energy(_) | Select::Residual(_)) {
            // The shooter's key falls, and its block of the max-tree is scanned again
            // ([`Self::set_r`]): its 64 records are asked for now, while the row is found, so
            // that their misses overlap the search (docs/notes/solvers.md).
            let first = MaxTree::block_start(i);
            let lines = (self.cells.len() - first).min(MaxTree::BLOCK);
            hint::prefetch(self.cells[first..].as_ptr(), lines);
        }
        // The shot's other reads of patch i, each a miss at 10⁵–10⁶ patches, asked for
        // together (its reflectance and area are read from its record, not the system's
        // arrays).
        hint::prefetch_at(&self.x, i);
        hint::prefetch_at(&self.row_sums.rows, i);
        let r = self.cells[i].r;
        if r == Rgb::BLACK {
            self.iterations += 1;
            return false;
        }
        let share = self.energy(i) / self.emitted_total;
        let column = source.shot_column(i, share);
        let m = match column {
            Column::Entries(c) => self.diagonal(i, c),
            Column::Reciprocal { row, diagonal, .. } => {
                // F_ii by reciprocity from itself, rounded as every other entry.
                let ai = self.cells[i].area as f32;
                let f_ii = diagonal.unwrap_or_else(|| {
                    row.binary_search_by_key(&(i as u32), |e| e.0)
                        .map_or(0.0, |k| row[k].1)
                });
                let f_ii = (f_ii * ai / ai) as f64;
                Rgb::splat(1.0) - self.cells[i].rho * f_ii
            }
        };
        let delta = Rgb::new(r.r / m.r, r.g / m.g, r.b / m.b) * omega;
        self.add_column(i, delta, column);
        self.iterations += 1;
        true
    }

    /// Σ |r_i| A_i over the emitted energy.
    pub fn unshot_fraction(&self) -> f64 {
        self.abs_unshot.max(0.0) / self.emitted_total
    }

    /// The emitted energy, channels summed.
    pub fn emitted_total(&self) -> f64 {
        self.emitted_total
    }

    /// Write `x` (or `x + r` when `plus_residual`) into `out`.
    pub fn output(&self, plus_residual: bool, out: &mut Vec<Rgb>) {
        out.clear();
        if plus_residual {
            out.extend(self.x.iter().zip(&self.cells).map(|(x, c)| *x + c.r));
        } else {
            out.extend_from_slice(&self.x);
        }
    }

    /// The bookkeeping as an [`Info`] (converged and seconds are the driver's).
    pub fn info(&self) -> Info {
        Info {
            iterations: self.iterations,
            converged: false,
            unshot_fraction: self.unshot_fraction(),
            seconds: 0.0,
            emitted: self.emitted,
            absorbed: self.absorbed,
            escaped: self.escaped,
            unshot: self.signed_unshot,
            estimated_error: 0.0,
            ray_seconds: 0.0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A row shot again under its id brings the sums kept from its last shot; a row with a new
    /// id (re-estimated, other entries) has its receivers add them again: the books are then
    /// bit for bit those of a solver that never keeps them, row after row for the same
    /// shooter, and they move as the rows differ.
    #[test]
    fn kept_row_sums_are_those_the_receivers_would_add() {
        let n = 2000;
        let system = System {
            area: (0..n).map(|j| 0.5 + (j % 7) as f64 * 0.25).collect(),
            reflectance: (0..n)
                .map(|j| Rgb::new(0.2, 0.5, 0.8) * (0.5 + (j % 3) as f64 * 0.2))
                .collect(),
            emission: (0..n)
                .map(|j| Rgb::splat(if j % 97 == 0 { 3.0 } else { 0.0 }))
                .collect(),
        };
        // Two versions of every row (as two Monte Carlo estimates would give), more than a
        // span long so that the receivers are halved.
        let row = |i: usize, version: u64| -> Vec<Entry> {
            (0..n as u32)
                .filter(|j| (*j as usize + i + version as usize) % 3 != 0)
                .map(|j| (j, 1e-4 * (1 + (j as u64 + version) % 5) as f32))
                .collect()
        };
        let rows: Vec<[Vec<Entry>; 2]> = (0..8).map(|i| [row(i, 0), row(i, 1)]).collect();
        // Shooter, version and id: a version shot again keeps its id; a new one a new id.
        let shots = [
            (0, 0, 1),
            (1, 0, 1),
            (0, 0, 1),
            (0, 1, 2),
            (0, 1, 2),
            (1, 1, 9),
        ];
        let books = |ids: bool| {
            let mut s = Relaxation::from_zero(&system);
            s.select_by(SelectKind::Energy);
            let mut after = Vec::new();
            for &(i, version, id) in &shots {
                let column = Column::Reciprocal {
                    row: &rows[i][version],
                    diagonal: None,
                    id: ids.then_some(id),
                };
                s.add_column(i, Rgb::new(0.3, 0.2, 0.1), column);
                let info = s.info();
                after.push([info.absorbed, info.escaped, info.unshot]);
            }
            after
        };
        let kept = books(true);
        assert_eq!(kept, books(false));
        // The second version differs from the first, and so do its books.
        assert_ne!(kept[3][0] - kept[2][0], kept[2][0] - kept[1][0]);
    }
}
