//! The binary tree by the binned surface-area heuristic (32 bins per axis, Wald 2007, "On
//! fast Construction of SAH-based Bounding Volume Hierarchies"), its subtrees built in
//! parallel, each node split by objects or, where the objects' halves overlap, by a plane
//! ([`super::spatial`]); then laid out depth first for the collapse.

use super::node::{Node, Tri, MAX_LEAF};
use super::spatial::{spatial_partition, spatial_split};
use crate::geom::{Aabb, Vec3};
use rayon::prelude::*;

pub(super) const BINS: usize = 32;

/// Deepest level of the binary tree, which bounds the builder's recursion.
const MAX_DEPTH: usize = 64;

/// From this level of the binary tree down, splits halve the triangles by count: fewer than
/// 2³¹ triangles then reach leaves of [`MAX_LEAF`] within [`MAX_DEPTH`] levels.
const HALVING_DEPTH: usize = MAX_DEPTH - 31;

#[derive(Clone, Copy)]
pub(super) struct Prim {
    pub(super) bounds: Aabb,
    pub(super) centroid: Vec3,
    pub(super) tri: Tri,
}

/// Slices at least this long are split over threads (bounds, bins).
pub(super) const PARALLEL_MIN: usize = 16 * 1024;

/// Nodes of at least this many references build their two subtrees on two threads.
const JOIN_MIN: usize = 1024;

/// A node of the binary tree while it is built.
pub(super) enum Built {
    Leaf { bounds: Aabb, tris: Vec<Tri> },
    Inner { bounds: Aabb, kids: Box<[Built; 2]> },
}

/// The union of `f(p)` over `prims`, in parallel for long slices: min and max are exact, so
/// the result does not depend on how the work is split.
pub(super) fn bounds_of<T: Sync>(prims: &[T], f: impl Fn(&T) -> Aabb + Sync) -> Aabb {
    if prims.len() < PARALLEL_MIN {
        return prims.iter().fold(Aabb::EMPTY, |b, p| b.union(f(p)));
    }
    prims
        .par_chunks(PARALLEL_MIN / 4)
        .map(|c| c.iter().fold(Aabb::EMPTY, |b, p| b.union(f(p))))
        .reduce(|| Aabb::EMPTY, Aabb::union)
}

/// What the spatial splits of a build share.
pub(super) struct Splits {
    /// The overlap, in units of surface area, from which a spatial split is tried.
    pub(super) min_overlap: f32,
}

/// How a node is split.
enum Cut {
    /// A leaf.
    Leaf,
    /// The first `mid` references (reordered in place) and the rest.
    At(usize),
    /// A spatial split: the first `n` references (rewritten in place) and a new list.
    Spatial(usize, Vec<Prim>),
}

/// Build the binary tree over the references `prims` (reordered in place), which may grow by
/// `budget` more references through spatial splits.
pub(super) fn build_tree(prims: &mut [Prim], depth: usize, budget: usize, split: &Splits) -> Built {
    let count = prims.len();
    let bounds = bounds_of(prims, |p| p.bounds);
    let cut = if count <= MAX_LEAF {
        Cut::Leaf
    } else if depth >= HALVING_DEPTH {
        // Deep enough that only halving by count keeps the tree within MAX_DEPTH levels
        // (which the traversal stacks are sized for); a pathological input gets here.
        Cut::At(count / 2)
    } else {
        choose_split(prims, bounds, budget, split)
    };
    let kids = |l: &mut [Prim], r: &mut [Prim]| {
        // The budget left, shared in proportion to the references on each side.
        let (nl, nr) = (l.len(), r.len());
        let left = budget.saturating_sub(nl + nr - count);
        let lb = (left as u128 * nl as u128 / (nl + nr) as u128) as usize;
        let rb = left - lb;
        let (a, b) = if count >= JOIN_MIN {
            rayon::join(
                || build_tree(l, depth + 1, lb, split),
                || build_tree(r, depth + 1, rb, split),
            )
        } else {
            (
                build_tree(l, depth + 1, lb, split),
                build_tree(r, depth + 1, rb, split),
            )
        };
        Built::Inner {
            bounds,
            kids: Box::new([a, b]),
        }
    };
    match cut {
        Cut::At(mid) => {
            let (l, r) = prims.split_at_mut(mid);
            kids(l, r)
        }
        Cut::Spatial(nl, mut r) => kids(&mut prims[..nl], &mut r),
        Cut::Leaf => Built::Leaf {
            bounds,
            tris: prims.iter().map(|p| p.tri).collect(),
        },
    }
}

/// Write `t` into `nodes[at]`, its children after the end of `nodes`, depth first, and its
/// leaves' triangles at the end of `tris`.
pub(super) fn lay_out(t: &Built, at: usize, nodes: &mut Vec<Node>, tris: &mut Vec<Tri>) {
    let (b, first, count) = match t {
        Built::Leaf { bounds, tris: mine } => {
            let first = tris.len() as u32;
            tris.extend_from_slice(mine);
            (*bounds, first, mine.len() as u32)
        }
        Built::Inner { bounds, .. } => (*bounds, nodes.len() as u32, 0),
    };
    nodes[at] = Node {
        min: b.min.to_array(),
        first,
        max: b.max.to_array(),
        count,
    };
    if let Built::Inner { kids, .. } = t {
        let left = nodes.len();
        for _ in 0..2 {
            nodes.push(Node {
                min: [0.0; 3],
                first: 0,
                max: [0.0; 3],
                count: 0,
            });
        }
        lay_out(&kids[0], left, nodes, tris);
        lay_out(&kids[1], left + 1, nodes, tris);
    }
}

/// The cheapest boundary of a binned sweep: its SAH cost (counting blocks of [`MAX_LEAF`]),
/// the first bin above it, and each side's box and references.
pub(super) struct Sweep {
    pub(super) cost: f32,
    pub(super) bin: usize,
    left: Aabb,
    right: Aabb,
    pub(super) nl: usize,
    pub(super) nr: usize,
}

/// The cheapest boundary between `bins` (at most [`BINS`]), each holding a box, the references
/// that begin in it and those that end in it (the same count for an object split, whose
/// references each fall in one bin); `None` when every boundary leaves a side empty.
pub(super) fn sweep(bins: &[(Aabb, usize, usize)]) -> Option<Sweep> {
    // From the right: the boxes and counts above each boundary.
    let mut right = [(Aabb::EMPTY, 0usize); BINS];
    let (mut rb, mut rc) = (Aabb::EMPTY, 0);
    for b in (1..bins.len()).rev() {
        rb = rb.union(bins[b].0);
        rc += bins[b].2;
        right[b] = (rb, rc);
    }
    let mut best: Option<Sweep> = None;
    let (mut lb, mut lc) = (Aabb::EMPTY, 0);
    for b in 1..bins.len() {
        lb = lb.union(bins[b - 1].0);
        lc += bins[b - 1].1;
        let (rbox, rcount) = right[b];
        if lc == 0 || rcount == 0 {
            continue;
        }
        let cost = lb.surface_area() * lc.div_ceil(MAX_LEAF) as f32
            + rbox.surface_area() * rcount.div_ceil(MAX_LEAF) as f32;
        if best.as_ref().is_none_or(|s| cost < s.cost) {
            best = Some(Sweep {
                cost,
                bin: b,
                left: lb,
                right: rbox,
                nl: lc,
                nr: rcount,
            });
        }
    }
    best
}

/// Split `prims` (more than [`MAX_LEAF`]) by the binned SAH, by objects or, where the objects'
/// halves would overlap and the budget allows, by a plane that cuts the triangles it crosses
/// into a part for each side (a spatial split); or a leaf.
fn choose_split(prims: &mut [Prim], bounds: Aabb, budget: usize, split: &Splits) -> Cut {
    let object = object_split(prims);
    if budget > 0 {
        if let Some(o) = &object {
            let overlap = Aabb {
                min: o.left.min.max(o.right.min),
                max: o.left.max.min(o.right.max),
            };
            if overlap.surface_area() > split.min_overlap {
                if let Some((cost, axis, b, cut)) = spatial_split(prims, &bounds) {
                    if cost < o.cost && cut <= budget {
                        if let Some((nl, r)) = spatial_partition(prims, &bounds, axis, b) {
                            return Cut::Spatial(nl, r);
                        }
                    }
                }
            }
        }
    }
    match object {
        Some(o) => {
            partition(prims, o.axis, o.bin, o.lo, o.scale);
            Cut::At(o.mid)
        }
        // All centroids coincide: split by count.
        None if prims.len() > MAX_LEAF => Cut::At(prims.len() / 2),
        None => Cut::Leaf,
    }
}

/// The binned SAH's bins of `prims` along `axis`: each bin's bounds and count, in parallel for
/// long slices (exact, whatever the split).
fn bins_of(prims: &[Prim], axis: usize, lo: f32, scale: f32) -> [(Aabb, usize); BINS] {
    let fill = |c: &[Prim]| {
        let mut bins = [(Aabb::EMPTY, 0usize); BINS];
        for p in c {
            let b = (((p.centroid[axis] - lo) * scale) as usize).min(BINS - 1);
            bins[b].0 = bins[b].0.union(p.bounds);
            bins[b].1 += 1;
        }
        bins
    };
    if prims.len() < PARALLEL_MIN {
        return fill(prims);
    }
    prims.par_chunks(PARALLEL_MIN / 4).map(fill).reduce(
        || [(Aabb::EMPTY, 0usize); BINS],
        |mut a, b| {
            for (x, y) in a.iter_mut().zip(b) {
                x.0 = x.0.union(y.0);
                x.1 += y.1;
            }
            a
        },
    )
}

/// The best object split of the binned SAH: its cost, where it cuts, and the two sides' boxes.
struct ObjectSplit {
    cost: f32,
    axis: usize,
    bin: usize,
    lo: f32,
    scale: f32,
    /// How many references go left.
    mid: usize,
    left: Aabb,
    right: Aabb,
}

/// Choose an object split of `prims` by the binned SAH; `None` when their centroids coincide.
fn object_split(prims: &[Prim]) -> Option<ObjectSplit> {
    let cb = bounds_of(prims, |p| Aabb {
        min: p.centroid,
        max: p.centroid,
    });
    let ext = cb.extent();
    let mut best: Option<ObjectSplit> = None;
    for axis in 0..3 {
        if ext[axis] <= 0.0 {
            continue;
        }
        let scale = BINS as f32 / ext[axis];
        let bins = bins_of(prims, axis, cb.min[axis], scale).map(|(b, n)| (b, n, n));
        let Some(s) = sweep(&bins) else {
            continue;
        };
        if best.as_ref().is_none_or(|o| s.cost < o.cost) {
            best = Some(ObjectSplit {
                cost: s.cost,
                axis,
                bin: s.bin,
                lo: cb.min[axis],
                scale,
                mid: s.nl,
                left: s.left,
                right: s.right,
            });
        }
    }
    best
}

/// Put the references whose centroid falls below bin `b` first.
fn partition(prims: &mut [Prim], axis: usize, b: usize, lo: f32, scale: f32) {
    let (mut i, mut j) = (0, prims.len());
    while i < j {
        let bin = (((prims[i].centroid[axis] - lo) * scale) as usize).min(BINS - 1);
        if bin < b {
            i += 1;
        } else {
            j -= 1;
            prims.swap(i, j);
        }
    }
}
