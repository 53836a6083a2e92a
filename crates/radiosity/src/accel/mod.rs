//! Ray casting over the patches: a bounding-volume hierarchy of the patches' triangles, where
//! a piece of the input that the mesh cut into a regular grid of patches is one or two
//! triangles, however many patches it holds, and the patch a ray meets on it is found from
//! where it met it ([`Locator`], [`Bvh::build`]). The hierarchy is then the size of the
//! input scene, not of its mesh: the one-sided hospital cut into 996,217 patches makes a tree
//! of 42,324 triangles and 2.8 MB instead of 1,189,437 and 75 MB, which the cache holds.
//!
//! Build: a binary tree by the binned surface-area heuristic (32 bins per axis, Wald 2007 "On
//! fast Construction of SAH-based Bounding Volume Hierarchies"; the cost counts blocks of
//! [`MAX_LEAF`] triangles, which one SIMD test takes), leaves of at most [`MAX_LEAF`]
//! triangles. Where a node's best split by objects leaves its halves overlapping (by more
//! than 10⁻⁴ of the scene's surface area), a spatial split is tried too (Stich, Friedrich &
//! Dietrich 2009, "Spatial Splits in Bounding Volume Hierarchies"): a plane along the node's
//! longest axis that cuts the triangles it crosses, each side keeping the box of its part,
//! chosen when its SAH cost is lower, within a budget of 30 % more triangle references; a
//! triangle may then sit in several leaves. The binary tree is then collapsed into an 8-wide
//! tree by the SAH-optimal dynamic programme of Ylitie, Karras & Laine 2017 ("Efficient
//! Incoherent Ray Traversal on GPUs Through Compressed Wide BVHs", §3.1). A node holds its
//! eight children's boxes in structure-of-arrays form, so one AVX pass tests all eight (the layout of Embree's BVH8): each slab's near and far
//! planes are chosen once per ray by the direction's signs, and each distance is one fused
//! multiply-add. Traversal: iterative; every child met is prefetched into the cache at once
//! (the latency of a tree larger than the cache then overlaps with the work on its
//! siblings); the children met are ordered nearest first by a branch-free sorting network
//! (with fast paths for one and two), pushed without branches, and skipped when they begin
//! beyond the closest hit; the stack is a small fixed array that spills to the heap only for
//! a pathologically deep tree. Triangle test: Möller–Trumbore on blocks of four, edges
//! precomputed, which also tells which side was hit; each triangle's edges are widened by a
//! few epsilons of the distance along the ray over its smallest height, which closes `f32`
//! cracks between neighbours without fattening triangles near the ray's origin (front sides
//! only, in closest-hit queries: `lanes_hit_front_slack`).
//!
//! Ties (two faces at the same distance, within a relative 10⁻⁶ or the ray offset): the front side
//! wins, and between faces of the same side the lower triangle id (patch order, the grids met
//! whole after the patches met one by one), so coincident copies of a surface resolve the same
//! way whichever side a ray comes from and whatever order the traversal meets them in.
//!
//! Portable builds (without `-C target-cpu=native`, which `.cargo/config.toml` sets) compile
//! the queries a second time for AVX2, FMA and BMI and choose that copy at run time where the
//! CPU has them (module `simd::dispatch`). With `unsafe` also: the box test in AVX2
//! intrinsics (module `simd::avx`, run by builds that assume AVX2 and FMA and by that run-time
//! copy), the prefetch hint (`hint`) and the traversal stack's uninitialised array
//! (`stack::Stack`).
//!
//! Self-intersection: callers start rays a small distance off the surface (see
//! [`Bvh::ray_offset`]) along its normal; since patches are planar, a piece is met whole only
//! if it is planar to within a quarter of that offset, and rays leave into the front
//! hemisphere, a ray cannot hit its own patch or the rest of its piece.
//!
//! The files, one stage each: `node` (binary and wide nodes, leaf blocks), `build` (the
//! binned SAH binary tree), `spatial` (spatial splits), `collapse` (binary to 8-wide),
//! `intersect` (the prepared ray, box and triangle tests), `stack` (the traversal stack),
//! `traverse` (the queries), `simd` (AVX2 intrinsics and run-time dispatch), `validate`
//! (invariant checks for the tests); this file holds the public types and the build's
//! outline. Measurements behind the constants: docs/notes/accel.md.

mod build;
mod collapse;
mod intersect;
mod node;
mod simd;
mod spatial;
mod stack;
mod traverse;
mod validate;

#[cfg(test)]
mod occlusion_tests;
#[cfg(test)]
mod tests;

pub use node::{MAX_LEAF, WIDTH};
pub use traverse::IN_FLIGHT;

use crate::geom::{Aabb, Vec3};
use crate::mesh::{Locator, Mesh};
use build::{bounds_of, build_tree, lay_out, Prim, Splits};
use collapse::{collapse, plan_collapse};
use node::{Node, Tri, TriBlock, WideNode, EMPTY_LANE, LEAF};
use rayon::prelude::*;
use spatial::{SPLIT_BUDGET, SPLIT_OVERLAP};

/// [`Bvh::ray_offset`] of a scene within `bounds`.
fn offset_of(bounds: &Aabb) -> f32 {
    let m = bounds.min.abs().max(bounds.max.abs()).max_element();
    let d = bounds.diagonal();
    (m * 4e-6).max(d * 1e-6).max(f32::MIN_POSITIVE)
}

/// A ray-patch intersection.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Distance along the ray (in units of the ray direction's length).
    pub t: f32,
    /// The patch hit.
    pub patch: u32,
    /// Which triangle of the patch: 0 = `(v0, v1, v2)`, 1 = `(v0, v2, v3)`.
    pub sub: u8,
    /// Barycentric coordinates of the hit point in that triangle: `p = (1−u−v)·a + u·b + v·c`.
    pub u: f32,
    /// See `u`.
    pub v: f32,
    /// True when the ray hit the front (emitting, reflecting) side.
    pub front: bool,
}

/// The hierarchy over all patches of a mesh.
#[derive(Clone, Debug)]
pub struct Bvh {
    nodes: Vec<WideNode>,
    /// One block per leaf.
    blocks: Vec<TriBlock>,
    /// Every triangle once, in the mesh's order (kept for validation and statistics).
    tris: Vec<Tri>,
    /// Triangle references in the leaves: the triangles, and the copies spatial splits made.
    references: usize,
    bounds: Aabb,
    /// Absolute distance within which two hits also count as one: [`Bvh::ray_offset`]. Two
    /// coplanar triangles (a two-sided surface's back-to-back copies, meshed differently) give
    /// distances that differ by the rounding of the coordinates, amplified at grazing angles, far
    /// beyond the relative [`TIE`](traverse::TIE); surfaces closer than the ray offset are not
    /// told apart anyway.
    tie: f32,
    /// Patches of the mesh: triangle ids `k << 1 | sub` with `k` below it are a patch's,
    /// from it on a grid's.
    patches: u32,
    /// The grids met whole, which find the patch a ray met: grid `k` has the ids
    /// `(patches + k) << 1 | sub`.
    grids: Vec<Locator>,
}

/// Statistics of a built hierarchy.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BvhInfo {
    /// Number of nodes.
    pub nodes: usize,
    /// Number of triangles.
    pub triangles: usize,
    /// Triangle references in the leaves: the triangles and the extra copies of those that
    /// spatial splits cut.
    pub references: usize,
    /// Depth of the deepest leaf.
    pub depth: usize,
    /// Number of leaves (blocks of at most [`MAX_LEAF`] triangles).
    pub leaves: usize,
    /// Bytes held.
    pub bytes: usize,
    /// Of which the nodes'.
    pub node_bytes: usize,
    /// The surface-area-heuristic cost of visiting the nodes: the sum of their boxes' areas
    /// over the root's (the expected number of nodes a random line through the scene's box
    /// visits), as Embree's `verbose=2` statistics count it.
    pub sah_nodes: f64,
    /// The same for the leaves (one block of triangles each).
    pub sah_leaves: f64,
    /// Pieces of the mesh met as a whole (their one or two triangles in the hierarchy in place
    /// of their patches'), the patch hit found from where ([`Bvh::build`]).
    pub whole_pieces: usize,
    /// Patches in those pieces.
    pub patches_in_whole_pieces: usize,
}

impl Bvh {
    /// Build over the triangles of `mesh`'s patches, except that a piece cut into a regular
    /// grid of two or more patches ([`Mesh::grids`]) is put in as its own one or two triangles,
    /// and a ray that meets it is told the patch at the point met ([`Locator`]): the same
    /// answers (up to the rounding at the patches' edges) from a hierarchy whose size does not
    /// grow with the patch count. On the one-sided hospital (22,271 polygons) cut into 996,217
    /// patches, the tree shrinks from 1,189,437 triangles and 75 MB to 42,324 and 2.8 MB, and
    /// each ray visits the nodes of the coarse scene only (rays per second against the tree
    /// over every patch and Embree's: docs/notes/accel.md). A grid is met whole only if the
    /// mesh still holds what it says (its patches' vertices numbered as the grid numbers them
    /// and lying where its formula puts them, to a quarter of [`Bvh::ray_offset`]) and its
    /// piece is planar and convex to that tolerance, so that a ray leaving one of its patches
    /// a ray offset off cannot meet the piece itself; else its patches go in one by one.
    pub fn build(mesh: &Mesh) -> Bvh {
        let n = mesh.len();
        let tol = 0.25 * offset_of(&bounds_of(&mesh.vertices, |v| Aabb::from_points(&[*v])));
        // Grids in patch order, disjoint, and few enough for their ids.
        let usable = mesh
            .grids
            .windows(2)
            .all(|w| w[0].first_patch as usize + w[0].patches() <= w[1].first_patch as usize)
            && n + mesh.grids.len() < (1 << 31);
        let found: Vec<_> = if usable {
            mesh.grids
                .par_iter()
                .map(|g| {
                    (g.patches() >= 2)
                        .then(|| Locator::new(mesh, g, tol))
                        .flatten()
                })
                .collect()
        } else {
            Vec::new()
        };
        let mut covered = vec![false; n];
        let mut grids = Vec::new();
        let mut pieces = Vec::new();
        for (g, f) in mesh.grids.iter().zip(found) {
            if let Some((locator, tris, count)) = f {
                let first = g.first_patch as usize;
                covered[first..first + g.patches()].fill(true);
                pieces.push((((n + grids.len()) as u32) << 1, tris, count));
                grids.push(locator);
            }
        }
        let prim = |a: Vec3, b: Vec3, c: Vec3, id: u32| {
            let bounds = Aabb::from_points(&[a, b, c]);
            Prim {
                bounds,
                centroid: bounds.centre(),
                tri: Tri {
                    v0: a,
                    e1: b - a,
                    e2: c - a,
                    id,
                },
            }
        };
        let mut prims: Vec<Prim> = mesh
            .patches
            .par_iter()
            .enumerate()
            .filter(|(k, _)| !covered[*k])
            .flat_map_iter(|(k, p)| {
                p.triangles().enumerate().map(move |(sub, t)| {
                    let [a, b, c] = t.map(|i| mesh.vertices[i as usize]);
                    prim(a, b, c, (k as u32) << 1 | sub as u32)
                })
            })
            .collect();
        for (id, tris, count) in pieces {
            for (sub, [a, b, c]) in tris.into_iter().take(count).enumerate() {
                prims.push(prim(a, b, c, id | sub as u32));
            }
        }
        let mut bvh = Self::from_prims(prims);
        bvh.patches = n as u32;
        bvh.grids = grids;
        bvh
    }

    fn from_prims(prims: Vec<Prim>) -> Bvh {
        let n = prims.len();
        let bounds = bounds_of(&prims, |p| p.bounds);
        let unique: Vec<Tri> = prims.iter().map(|p| p.tri).collect();
        // The binary tree, subtrees built in parallel (each owns its references, and every
        // choice depends only on them and on its share of the split budget, so the tree is
        // the same for any number of threads), then laid out depth first, left first, each
        // node's two children side by side.
        let split = Splits {
            min_overlap: SPLIT_OVERLAP * bounds.surface_area(),
        };
        let budget = (n as f64 * SPLIT_BUDGET) as usize;
        let mut prims = prims;
        let tree = build_tree(&mut prims, 0, budget, &split);
        drop(prims);
        let mut nodes = Vec::with_capacity((2 * n / MAX_LEAF.max(1)).max(1) * 2);
        nodes.push(Node {
            min: [0.0; 3],
            first: 0,
            max: [0.0; 3],
            count: 0,
        });
        let mut tris = Vec::with_capacity(n + n / 4);
        lay_out(&tree, 0, &mut nodes, &mut tris);
        drop(tree);
        if n == 0 {
            nodes[0].min = [f32::INFINITY; 3];
            nodes[0].max = [f32::NEG_INFINITY; 3];
        }
        let mut wide = Vec::with_capacity(nodes.len() / 2 + 1);
        let mut blocks = Vec::with_capacity(nodes.len() / 2 + 2);
        blocks.push(TriBlock::EMPTY); // what empty lanes refer to
        if n > 0 {
            let plan = plan_collapse(&nodes);
            collapse(&nodes, &plan, 0, &tris, &mut wide, &mut blocks);
        } else {
            wide.push(WideNode::EMPTY);
        }
        let mut bvh = Bvh {
            nodes: wide,
            blocks,
            references: tris.len(),
            tris: unique,
            bounds,
            tie: 0.0,
            patches: 0,
            grids: Vec::new(),
        };
        bvh.tie = bvh.ray_offset();
        bvh
    }

    /// Bounds of the whole scene.
    pub fn bounds(&self) -> Aabb {
        self.bounds
    }

    /// How far off a surface rays should start: large enough to clear `f32` rounding of the
    /// scene's coordinates (the largest coordinate times 2⁻¹⁸), small against any patch.
    pub fn ray_offset(&self) -> f32 {
        offset_of(&self.bounds)
    }

    /// Sizes and depth.
    pub fn info(&self) -> BvhInfo {
        let mut depth = 0;
        let root = f64::from(self.bounds.surface_area());
        let (mut sah_nodes, mut sah_leaves) = (0.0, 0.0);
        let mut stack = vec![(0usize, 1usize)];
        while let Some((i, d)) = stack.pop() {
            depth = depth.max(d);
            let n = &self.nodes[i];
            for (lane, &c) in n.child.iter().enumerate() {
                if c == EMPTY_LANE {
                    continue;
                }
                let area = f64::from(
                    Aabb {
                        min: Vec3::from_array([0, 1, 2].map(|a| n.planes[a][lane])),
                        max: Vec3::from_array([3, 4, 5].map(|a| n.planes[a][lane])),
                    }
                    .surface_area(),
                ) / root;
                if c & LEAF == 0 {
                    sah_nodes += area;
                    stack.push((c as usize, d + 1));
                } else {
                    sah_leaves += area;
                }
            }
        }
        if !self.tris.is_empty() {
            sah_nodes += 1.0; // the root
        }
        let node_bytes = self.nodes.len() * std::mem::size_of::<WideNode>();
        BvhInfo {
            nodes: self.nodes.len(),
            triangles: self.tris.len(),
            references: self.references,
            depth,
            // The first block is the one empty lanes refer to.
            leaves: self.blocks.len() - 1,
            bytes: self.bytes(),
            node_bytes,
            sah_nodes,
            sah_leaves,
            whole_pieces: self.grids.len(),
            patches_in_whole_pieces: self.grids.iter().map(Locator::patches).sum(),
        }
    }

    /// Bytes of the nodes and leaf blocks, which a traversal reads.
    fn bytes(&self) -> usize {
        self.nodes.len() * std::mem::size_of::<WideNode>()
            + self.blocks.len() * std::mem::size_of::<TriBlock>()
    }
}
