//! Collapse of the binary tree into the 8-wide tree the queries traverse, by the SAH-optimal
//! dynamic programme of Ylitie, Karras & Laine 2017, and the filling of the leaves' blocks.

use super::node::{Node, Tri, TriBlock, WideNode, EDGE_EPS, LEAF, SLACK_ULPS, WIDTH};
use crate::geom::{Aabb, Vec3};

/// SAH cost of testing a wide node's child boxes, per unit of the node's surface area.
const COST_NODE: f32 = 1.0;
/// SAH cost of testing a leaf's block of triangles, per unit of the leaf's surface area.
const COST_BLOCK: f32 = 1.0;

/// How to cut the binary tree into wide nodes with the least SAH cost, by dynamic programming
/// over the subtrees (the collapse of Ylitie, Karras & Laine 2017, "Efficient Incoherent Ray
/// Traversal on GPUs Through Compressed Wide BVHs", §3.1), instead of greedily opening the
/// largest child, which leaves many nodes with two or three children.
///
/// For binary node `n` and `i ≥ 2`, `plan[n][i − 1]` tells how its subtree best fills at most
/// `i` child slots of a wide node: 0 as with `i − 1` slots (with one slot, `n` itself is the
/// child), `k > 0` by giving `k` slots to its left subtree and `i − k` to its right.
/// `plan[n][0]` tells how an interior `n` made a wide node shares out its [`WIDTH`] slots.
pub(super) fn plan_collapse(bin: &[Node]) -> Vec<[u8; WIDTH]> {
    let mut cost = vec![[0f32; WIDTH]; bin.len()];
    let mut plan = vec![[0u8; WIDTH]; bin.len()];
    // Children come after their parent in `bin`: backwards is bottom up.
    for n in (0..bin.len()).rev() {
        let a = node_area(&bin[n]);
        if bin[n].count > 0 {
            cost[n] = [a * COST_BLOCK; WIDTH];
            continue;
        }
        let (l, r) = (bin[n].first as usize, bin[n].first as usize + 1);
        // split[i − 1]: the best cost of `i` slots shared between the two subtrees (one
        // slot to the left where every cost overflows to ∞, so the plan stays valid).
        let mut split = [(f32::INFINITY, 1u8); WIDTH];
        for i in 2..=WIDTH {
            for k in 1..i {
                let c = cost[l][k - 1] + cost[r][i - k - 1];
                if c < split[i - 1].0 {
                    split[i - 1] = (c, k as u8);
                }
            }
        }
        cost[n][0] = a * COST_NODE + split[WIDTH - 1].0;
        plan[n][0] = split[WIDTH - 1].1;
        for i in 2..=WIDTH {
            if split[i - 1].0 < cost[n][i - 2] {
                cost[n][i - 1] = split[i - 1].0;
                plan[n][i - 1] = split[i - 1].1;
            } else {
                cost[n][i - 1] = cost[n][i - 2];
            }
        }
    }
    plan
}

fn node_area(n: &Node) -> f32 {
    Aabb {
        min: Vec3::from_array(n.min),
        max: Vec3::from_array(n.max),
    }
    .surface_area()
}

/// The wide-node children that binary subtree `n` becomes when given at most `slots` slots.
fn gather(bin: &[Node], plan: &[[u8; WIDTH]], n: usize, slots: usize, kids: &mut Vec<usize>) {
    let mut i = slots;
    while i > 1 && plan[n][i - 1] == 0 {
        i -= 1;
    }
    if i == 1 {
        kids.push(n);
        return;
    }
    let k = plan[n][i - 1] as usize;
    let l = bin[n].first as usize;
    gather(bin, plan, l, k, kids);
    gather(bin, plan, l + 1, i - k, kids);
}

/// Collapse the binary tree under `b` into wide nodes appended to `out` as `plan` says;
/// returns the index of the node made for `b` (which must be interior, or the root).
pub(super) fn collapse(
    bin: &[Node],
    plan: &[[u8; WIDTH]],
    b: usize,
    tris: &[Tri],
    out: &mut Vec<WideNode>,
    blocks: &mut Vec<TriBlock>,
) -> u32 {
    let mut kids = Vec::with_capacity(WIDTH);
    if bin[b].count > 0 {
        kids.push(b); // a root that is a leaf
    } else {
        let k = plan[b][0] as usize;
        let l = bin[b].first as usize;
        gather(bin, plan, l, k, &mut kids);
        gather(bin, plan, l + 1, WIDTH - k, &mut kids);
    }
    debug_assert!(kids.len() <= WIDTH);
    let me = out.len();
    out.push(WideNode::EMPTY);
    for (lane, &k) in kids.iter().enumerate() {
        let n = bin[k];
        let r = if n.count > 0 {
            assert!(n.count as usize <= 4, "leaf of more than four triangles");
            let mut blk = TriBlock::EMPTY;
            for (lane, t) in tris[n.first as usize..(n.first + n.count) as usize]
                .iter()
                .enumerate()
            {
                for a in 0..3 {
                    blk.v0[a][lane] = t.v0[a];
                    blk.e1[a][lane] = t.e1[a];
                    blk.e2[a][lane] = t.e2[a];
                }
                blk.id[lane] = t.id;
                // Rounding of a few ulps of the distance from the ray's origin to the
                // triangle's first vertex, in world units, over the triangle's smallest height
                // (twice its area over its longest edge).
                let longest = t.e1.length().max(t.e2.length()).max((t.e2 - t.e1).length());
                let height = t.e1.cross(t.e2).length() / longest;
                let per_length = SLACK_ULPS * f32::EPSILON / height;
                if per_length.is_finite() {
                    blk.slack0[lane] = (per_length * longest).max(EDGE_EPS);
                    blk.slack1[lane] = per_length;
                } else {
                    blk.slack0[lane] = EDGE_EPS;
                }
            }
            blocks.push(blk);
            LEAF | (blocks.len() - 1) as u32
        } else {
            collapse(bin, plan, k, tris, out, blocks)
        };
        let node = &mut out[me];
        for a in 0..3 {
            node.planes[a][lane] = n.min[a];
            node.planes[3 + a][lane] = n.max[a];
        }
        node.child[lane] = r;
    }
    me as u32
}
