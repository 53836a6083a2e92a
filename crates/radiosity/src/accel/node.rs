//! Node and leaf layout: the binary tree's nodes as the builder lays them out, the 8-wide
//! nodes the queries traverse (children's boxes in structure-of-arrays form, one SIMD lane
//! each, the layout of Embree's BVH8), and the leaves' blocks of four triangles.

use crate::geom::Vec3;
use glam::Vec4;

/// Children per node of the wide tree.
pub const WIDTH: usize = 8;

/// Most triangles in a leaf.
pub const MAX_LEAF: usize = 4;

/// Marks a child reference as a leaf.
pub(super) const LEAF: u32 = 1 << 31;

/// The child reference of an empty lane of a wide node: block 0, which holds no triangle,
/// so a lane entered by mistake (a box test gone NaN on absurd coordinates) costs a wasted
/// test, never a wrong index.
pub(super) const EMPTY_LANE: u32 = LEAF;

/// The id of an unused lane of a [`TriBlock`].
pub(super) const NO_TRIANGLE: u32 = u32::MAX;

/// Least barycentric slack that keeps shared edges watertight under rounding (see
/// [`TriBlock::slack0`] for the slack each triangle gets).
pub(super) const EDGE_EPS: f32 = 1e-6;
/// Machine epsilons of the distance that a triangle's edges are widened by (see
/// [`TriBlock::slack0`]).
pub(super) const SLACK_ULPS: f32 = 4.0;

#[derive(Clone, Copy, Debug)]
#[repr(C)]
pub(super) struct Node {
    pub(super) min: [f32; 3],
    /// Interior: index of the left child (right is `first + 1`). Leaf: first triangle.
    pub(super) first: u32,
    pub(super) max: [f32; 3],
    /// Number of triangles for a leaf, 0 for an interior node.
    pub(super) count: u32,
}

/// A wide node: the boxes of up to [`WIDTH`] children in structure-of-arrays form, one SIMD
/// lane each. An empty lane's box is +∞ in every coordinate, which no ray enters.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub(super) struct WideNode {
    /// The children's bounding planes: lower x, y, z, then upper x, y, z (`planes[a]` and
    /// `planes[3 + a]` bound axis `a`), each for every child.
    pub(super) planes: [[f32; WIDTH]; 6],
    /// Child references: a node index, or [`LEAF`] | block index; [`EMPTY_LANE`] for none.
    pub(super) child: [u32; WIDTH],
}

impl WideNode {
    pub(super) const EMPTY: WideNode = WideNode {
        planes: [[f32::INFINITY; WIDTH]; 6],
        child: [EMPTY_LANE; WIDTH],
    };
}

#[derive(Clone, Copy, Debug)]
pub(super) struct Tri {
    pub(super) v0: Vec3,
    pub(super) e1: Vec3,
    pub(super) e2: Vec3,
    /// `patch << 1 | sub`, `sub` = which triangle of the patch; for a grid met whole
    /// ([`Bvh::build`](super::Bvh::build)), `(patches + grid) << 1 | sub`, `sub` = which
    /// triangle of its piece.
    pub(super) id: u32,
}

/// The (up to) four triangles of a leaf in structure-of-arrays form, tested in one SIMD pass.
/// Unused lanes hold a degenerate triangle (zero edges), which no ray hits. Aligned to cache
/// lines, so that one spans exactly three.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub(super) struct TriBlock {
    pub(super) v0: [Vec4; 3],
    pub(super) e1: [Vec4; 3],
    pub(super) e2: [Vec4; 3],
    /// Barycentric slack of each triangle at distance `t` along the ray: `slack0 + slack1·t`.
    /// Möller–Trumbore's `f32` rounding is a few machine epsilons of `|o − v0|` (at most `t`
    /// plus the triangle's longest edge) in world units, which is that over the triangle's
    /// smallest height in barycentric units. Without it, a ray through the edge two small
    /// triangles share, far from its origin, can slip between them (a crack: 3 in 2 × 10⁶
    /// form-factor rays in the 40,000-patch Cornell box); a slack that ignores the distance
    /// (a few epsilons of the largest coordinate) fattens triangles near the ray's origin
    /// beyond what rounding needs, and rays leaving a corner then graze the next wall.
    pub(super) slack0: Vec4,
    /// See `slack0`.
    pub(super) slack1: Vec4,
    pub(super) id: [u32; 4],
}

impl TriBlock {
    /// Four unused lanes: zero edges, which no ray hits (Möller–Trumbore's determinant is 0
    /// and every comparison of its NaN results fails).
    pub(super) const EMPTY: TriBlock = TriBlock {
        v0: [Vec4::ZERO; 3],
        e1: [Vec4::ZERO; 3],
        e2: [Vec4::ZERO; 3],
        slack0: Vec4::ZERO,
        slack1: Vec4::ZERO,
        id: [NO_TRIANGLE; 4],
    };
}
