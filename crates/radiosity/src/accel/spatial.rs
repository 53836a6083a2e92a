//! Spatial splits (Stich, Friedrich & Dietrich 2009, "Spatial Splits in Bounding Volume
//! Hierarchies"): where a node's best object split leaves its halves overlapping, a plane
//! along its longest axis that cuts the triangles it crosses, each side keeping the box of
//! its part, within a budget of extra triangle references.

use super::build::{sweep, Prim, BINS, PARALLEL_MIN};
use super::node::Tri;
use crate::geom::{Aabb, Vec3};
use rayon::prelude::*;

/// References that spatial splits may add, as a fraction of the triangles: well above what the
/// hospital takes (docs/notes/accel.md).
pub(super) const SPLIT_BUDGET: f64 = 0.3;
/// A node whose best object split leaves children overlapping by more than this fraction of
/// the scene's surface area also tries a spatial split (Stich, Friedrich & Dietrich 2009, α;
/// they use 10⁻⁵, which builds slower for no faster rays: docs/notes/accel.md).
pub(super) const SPLIT_OVERLAP: f32 = 1e-4;
/// Bins of a spatial split, at most.
const SPATIAL_BINS: usize = 32;
const _: () = assert!(SPATIAL_BINS <= BINS, "sweep's arrays hold BINS");

/// Bins of a spatial split of `n` references: fewer for small nodes, whose triangles span
/// many of a fine grid's bins, each to be clipped.
fn spatial_bins(n: usize) -> usize {
    if n >= 64 {
        32
    } else if n >= 16 {
        16
    } else {
        4
    }
}

/// The box of the part of triangle `t` with `lo ≤ x[axis] ≤ hi`, within `within`, grown by a
/// few units in the last place so that rounding in the clipping never leaves a point of the
/// triangle outside every box made for it. Empty if the part is.
fn clip(t: &Tri, axis: usize, lo: f32, hi: f32, within: &Aabb) -> Aabb {
    let v = [t.v0, t.v0 + t.e1, t.v0 + t.e2];
    let mut b = Aabb::EMPTY;
    for k in 0..3 {
        let (p, q) = (v[k], v[(k + 1) % 3]);
        if p[axis] >= lo && p[axis] <= hi {
            b = b.grow(p);
        }
        for c in [lo, hi] {
            if (p[axis] < c && q[axis] > c) || (p[axis] > c && q[axis] < c) {
                let mut x = p + (q - p) * ((c - p[axis]) / (q[axis] - p[axis]));
                x[axis] = c;
                b = b.grow(x);
            }
        }
    }
    if b.is_empty() {
        return b;
    }
    let m = v.iter().fold(0f32, |m, p| m.max(p.abs().max_element()));
    let pad = Vec3::splat(m * 8.0 * f32::EPSILON);
    let b = Aabb {
        min: (b.min - pad).max(within.min),
        max: (b.max + pad).min(within.max),
    };
    if b.is_empty() {
        Aabb::EMPTY
    } else {
        b
    }
}

/// Add to `bins[b0..=b1]` the boxes of the parts of triangle `t` in each bin of a spatial
/// split along `axis` (bin `b` from `lo + b·width`; the first and last open-ended), within
/// `within`: each vertex goes to its bin, each point where an edge crosses a bin's boundary
/// to the bins on both sides. For the split's cost only: the partition clips exactly.
#[allow(clippy::too_many_arguments)]
fn chop(
    t: &Tri,
    axis: usize,
    lo: f32,
    width: f32,
    scale: f32,
    b0: usize,
    b1: usize,
    within: &Aabb,
    bins: &mut [(Aabb, usize, usize); SPATIAL_BINS],
) {
    let v = [t.v0, t.v0 + t.e1, t.v0 + t.e2];
    let vb = v.map(|p| spatial_bin(p[axis], lo, scale, SPATIAL_BINS).clamp(b0, b1));
    // The points where the edges cross the boundary below the current bin.
    let mut below = Aabb::EMPTY;
    for b in b0..=b1 {
        let mut part = below;
        for k in 0..3 {
            if vb[k] == b {
                part = part.grow(v[k]);
            }
        }
        below = Aabb::EMPTY;
        if b < b1 {
            let c = lo + (b + 1) as f32 * width;
            for k in 0..3 {
                let (p, q) = (v[k], v[(k + 1) % 3]);
                if (p[axis] < c && q[axis] > c) || (p[axis] > c && q[axis] < c) {
                    let mut x = p + (q - p) * ((c - p[axis]) / (q[axis] - p[axis]));
                    x[axis] = c;
                    below = below.grow(x);
                }
            }
            part = part.union(below);
        }
        let clipped = Aabb {
            min: part.min.max(within.min),
            max: part.max.min(within.max),
        };
        if !clipped.is_empty() {
            bins[b].0 = bins[b].0.union(clipped);
        }
    }
}

/// The bin of coordinate `x` of a spatial split from `lo` with bins `1 / scale` wide.
fn spatial_bin(x: f32, lo: f32, scale: f32, nb: usize) -> usize {
    (((x - lo) * scale).max(0.0) as usize).min(nb - 1)
}

/// The best spatial split of `prims` inside `bounds` along its longest axis (Stich,
/// Friedrich & Dietrich 2009, §4.2: bins of equal width, each reference chopped into the
/// bins it spans): its SAH cost, counting blocks of [`MAX_LEAF`](super::MAX_LEAF) as the
/// object split does, its bin boundary, and the references it cuts in two. Only the longest
/// axis is tried: a third of the cost of all three, for as fast a tree (docs/notes/accel.md).
pub(super) fn spatial_split(prims: &[Prim], bounds: &Aabb) -> Option<(f32, usize, usize, usize)> {
    let ext = bounds.extent();
    let axis = ext.max_position();
    if ext[axis] <= 0.0 {
        return None;
    }
    let nb = spatial_bins(prims.len());
    let lo = bounds.min[axis];
    let scale = nb as f32 / ext[axis];
    let width = ext[axis] / nb as f32;
    // Per bin: the box of the parts in it, the references that begin in it, and those
    // that end in it.
    let fill = |c: &[Prim]| {
        let mut bins = [(Aabb::EMPTY, 0usize, 0usize); SPATIAL_BINS];
        for p in c {
            let b0 = spatial_bin(p.bounds.min[axis], lo, scale, nb);
            let b1 = spatial_bin(p.bounds.max[axis], lo, scale, nb);
            bins[b0].1 += 1;
            bins[b1].2 += 1;
            if b0 == b1 {
                bins[b0].0 = bins[b0].0.union(p.bounds);
            } else {
                chop(&p.tri, axis, lo, width, scale, b0, b1, &p.bounds, &mut bins);
            }
        }
        bins
    };
    let bins = if prims.len() < PARALLEL_MIN {
        fill(prims)
    } else {
        prims.par_chunks(PARALLEL_MIN / 4).map(fill).reduce(
            || [(Aabb::EMPTY, 0usize, 0usize); SPATIAL_BINS],
            |mut a, b| {
                for (x, y) in a.iter_mut().zip(b) {
                    x.0 = x.0.union(y.0);
                    x.1 += y.1;
                    x.2 += y.2;
                }
                a
            },
        )
    };
    let best = sweep(&bins[..nb])?;
    Some((best.cost, axis, best.bin, best.nl + best.nr - prims.len()))
}

/// Cut `prims` at bin boundary `b` of the spatial split along `axis`: a reference wholly on
/// one side goes there; one that straddles the plane goes to both, each with the box of its
/// part on that side. The left side is written over the front of `prims` (it is shorter, and
/// each reference gives it at most one), the right side into a new list, so that a split
/// copies only half its node. `None`, with `prims` untouched, when a side would be empty or
/// hold every reference.
pub(super) fn spatial_partition(
    prims: &mut [Prim],
    bounds: &Aabb,
    axis: usize,
    b: usize,
) -> Option<(usize, Vec<Prim>)> {
    let ext = bounds.extent()[axis];
    let nb = spatial_bins(prims.len());
    let scale = nb as f32 / ext;
    let lo = bounds.min[axis];
    let plane = lo + b as f32 * (ext / nb as f32);
    let part = |p: &Prim, lo: f32, hi: f32| {
        let bx = clip(&p.tri, axis, lo, hi, &p.bounds);
        (!bx.is_empty()).then_some(Prim {
            bounds: bx,
            centroid: bx.centre(),
            tri: p.tri,
        })
    };
    // Which side each reference goes to: wholly left, wholly right, or cut.
    let side = |p: &Prim| {
        let b0 = spatial_bin(p.bounds.min[axis], lo, scale, nb);
        let b1 = spatial_bin(p.bounds.max[axis], lo, scale, nb);
        (b0 >= b, b1 < b)
    };
    let n = prims.len();
    let (mut left, mut right) = (0, Vec::new());
    for p in prims.iter() {
        match side(p) {
            (false, true) => left += 1,
            (true, false) => right.push(*p),
            _ => {
                left += part(p, f32::NEG_INFINITY, plane).is_some() as usize;
                right.extend(part(p, plane, f32::INFINITY));
            }
        }
    }
    if left == 0 || right.is_empty() || left == n || right.len() == n {
        return None;
    }
    let mut w = 0;
    for k in 0..n {
        let p = prims[k];
        let keep = match side(&p) {
            (false, true) => Some(p),
            (true, false) => None,
            _ => part(&p, f32::NEG_INFINITY, plane),
        };
        if let Some(q) = keep {
            prims[w] = q;
            w += 1;
        }
    }
    debug_assert_eq!(w, left);
    Some((left, right))
}
