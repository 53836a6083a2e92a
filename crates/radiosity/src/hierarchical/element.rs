//! The element quadtrees: every input piece (a convex quad or a triangle) is the root of a tree
//! whose nodes split into four children of a quarter of the parent's parametric area (quads at
//! the midpoints of their edges and their centre, triangles at their edge midpoints).
//!
//! Midpoints are computed as `(a + b) · ½` of the two end points, an expression symmetric in
//! `a` and `b`: two neighbours that split a shared edge produce bit-identical points, which is
//! what lets [`super::output`] find T-vertices by position.

use crate::geom::{triangle_cross, Vec3};

/// Marker for "none" in element links (no parent, no children).
pub const NONE: u32 = u32::MAX;

/// Points a receiver is sampled at ([`Element::receiver_points`]).
pub const POINTS: usize = 16;

/// A node of an element quadtree: a planar convex quad or a triangle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Element {
    /// Corners, counter-clockwise about the normal; `corners[3]` repeats `corners[2]` for a
    /// triangle.
    pub corners: [Vec3; 4],
    /// True for a triangle.
    pub tri: bool,
    /// Area (square scene units).
    pub area: f32,
    /// Unit normal of the front side.
    pub normal: Vec3,
    /// Centroid.
    pub centre: Vec3,
    /// Largest distance from the centroid to a corner.
    pub radius: f32,
    /// The root element (input piece) of this tree.
    pub root: u32,
    /// The parent, [`NONE`] for a root.
    pub parent: u32,
    /// The first of the four children (stored consecutively), [`NONE`] for a leaf.
    pub children: u32,
    /// Depth below the root (0 for the root).
    pub level: u16,
}

impl Element {
    /// An element from its corners (a triangle when `tri`, with `corners[3]` ignored).
    pub fn new(corners: [Vec3; 4], tri: bool, root: u32, parent: u32, level: u16) -> Self {
        let [a, b, c, d] = corners;
        let corners = if tri { [a, b, c, c] } else { corners };
        let t1 = triangle_cross(a, b, c);
        let (vector, centre) = if tri {
            (t1 * 0.5, (a + b + c) / 3.0)
        } else {
            let t2 = triangle_cross(a, c, d);
            let (w1, w2) = (t1.length(), t2.length());
            let c1 = (a + b + c) / 3.0;
            let c2 = (a + c + d) / 3.0;
            let centre = if w1 + w2 > 0.0 {
                (c1 * w1 + c2 * w2) / (w1 + w2)
            } else {
                (a + b + c + d) * 0.25
            };
            ((t1 + t2) * 0.5, centre)
        };
        let n = if tri { 3 } else { 4 };
        let radius = corners[..n]
            .iter()
            .map(|p| (*p - centre).length())
            .fold(0.0, f32::max);
        Self {
            corners,
            tri,
            area: vector.length(),
            normal: vector.normalize_or_zero(),
            centre,
            radius,
            root,
            parent,
            children: NONE,
            level,
        }
    }

    /// The root elements of `mesh`'s patches (one per input piece; element `i` is patch `i`).
    pub fn roots(mesh: &crate::mesh::Mesh) -> Vec<Element> {
        mesh.patches
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let v = |k: usize| {
                    let k = if p.vertices[k] == crate::mesh::Patch::NONE {
                        2
                    } else {
                        k
                    };
                    mesh.vertices[p.vertices[k] as usize]
                };
                Element::new([v(0), v(1), v(2), v(3)], p.is_triangle(), i as u32, NONE, 0)
            })
            .collect()
    }

    /// For each root, the first root (lowest index) that is the same polygon facing the same
    /// way, or itself: coincident *twins*, such as a scene that includes an object twice.
    /// Corners are compared as a set after rounding to a grid of `tolerance`, normals to
    /// 10⁻³; only roots for which `eligible` holds are grouped.
    pub fn twins(roots: &[Element], tolerance: f32, eligible: impl Fn(usize) -> bool) -> Vec<u32> {
        use std::collections::HashMap;
        let mut first: HashMap<Vec<i64>, u32> = HashMap::new();
        let mut out: Vec<u32> = (0..roots.len() as u32).collect();
        if tolerance.is_nan() || tolerance <= 0.0 {
            return out;
        }
        for (i, e) in roots.iter().enumerate() {
            if !eligible(i) || e.area <= 0.0 {
                continue;
            }
            let key =
                crate::geom::coincidence_key(e.polygon().iter().copied(), e.normal, tolerance);
            out[i] = *first.entry(key).or_insert(i as u32);
        }
        out
    }

    /// The corners that exist (3 or 4).
    pub fn polygon(&self) -> &[Vec3] {
        if self.tri {
            &self.corners[..3]
        } else {
            &self.corners
        }
    }

    /// True when the element has no children.
    pub fn is_leaf(&self) -> bool {
        self.children == NONE
    }

    /// The corners of the four children.
    pub fn child_corners(&self) -> [[Vec3; 4]; 4] {
        let mid = |p: Vec3, q: Vec3| (p + q) * 0.5;
        let [a, b, c, d] = self.corners;
        if self.tri {
            let (ab, bc, ca) = (mid(a, b), mid(b, c), mid(c, a));
            [
                [a, ab, ca, ca],
                [ab, b, bc, bc],
                [ca, bc, c, c],
                [bc, ca, ab, ab],
            ]
        } else {
            let (ab, bc, cd, da) = (mid(a, b), mid(b, c), mid(c, d), mid(d, a));
            let o = (a + b + c + d) * 0.25;
            [
                [a, ab, o, da],
                [ab, b, bc, o],
                [o, bc, c, cd],
                [da, o, cd, d],
            ]
        }
    }

    /// The point at parameters `(u, v)` in `[0, 1]²`: bilinear over a quad; over a triangle
    /// `a + u (b − a) + v (c − a)` (the caller keeps `u + v ≤ 1`).
    pub fn point(&self, u: f32, v: f32) -> Vec3 {
        let [a, b, c, d] = self.corners;
        if self.tri {
            a + (b - a) * u + (c - a) * v
        } else {
            a * ((1.0 - u) * (1.0 - v)) + b * (u * (1.0 - v)) + c * (u * v) + d * ((1.0 - u) * v)
        }
    }

    /// A point uniform over the element's area from three uniforms in `[0, 1)`.
    pub fn sample(&self, u1: f32, u2: f32, u3: f32) -> Vec3 {
        let [a, b, c, d] = self.corners;
        let (b, c) = if self.tri {
            (b, c)
        } else {
            let w1 = triangle_cross(a, b, c).length();
            let w2 = triangle_cross(a, c, d).length();
            if u3 * (w1 + w2) < w1 {
                (b, c)
            } else {
                (c, d)
            }
        };
        let (s, t) = crate::sampling::uniform_triangle(u1, u2);
        a + (b - a) * s + (c - a) * t
    }

    /// Sixteen points spread over the element, one uniform in each of its grandchildren
    /// (stratified jitter from the uniforms `u`): where a link's kernel is evaluated on its
    /// receiver. Jittered, not fixed, so that the mean over the points is an unbiased
    /// estimate of the element's mean (a fixed pattern would see a shadow between its points
    /// as absent on every element alike); sixteen, so that a shadow crossing the element is
    /// seen by some points and missed by others, which is what the oracle looks for.
    pub fn receiver_points(&self, u: &[f32; 2 * POINTS]) -> [Vec3; POINTS] {
        if self.tri {
            let grandchildren = self
                .child_corners()
                .map(|corners| Element { corners, ..*self }.child_corners());
            std::array::from_fn(|k| {
                let [a, b, c, _] = grandchildren[k / 4][k % 4];
                let (s, t) = crate::sampling::uniform_triangle(u[2 * k], u[2 * k + 1]);
                a + (b - a) * s + (c - a) * t
            })
        } else {
            std::array::from_fn(|k| {
                let (i, j) = ((k % 4) as f32, (k / 4) as f32);
                self.point(0.25 * (i + u[2 * k]), 0.25 * (j + u[2 * k + 1]))
            })
        }
    }
}

/// Every element of every tree, roots first (root `i` is element `i`), children of one parent
/// consecutive.
#[derive(Clone, Debug, Default)]
pub struct Elements {
    /// The elements.
    pub items: Vec<Element>,
    /// Number of roots.
    pub roots: usize,
}

impl Elements {
    /// The first of `e`'s four children, made now if `e` is a leaf.
    pub fn subdivide(&mut self, e: u32) -> u32 {
        let parent = self.items[e as usize];
        if !parent.is_leaf() {
            return parent.children;
        }
        let first = self.items.len() as u32;
        for corners in parent.child_corners() {
            self.items.push(Element::new(
                corners,
                parent.tri,
                parent.root,
                e,
                parent.level + 1,
            ));
        }
        self.items[e as usize].children = first;
        first
    }

    /// The leaves below `e` (itself if it is one), depth first, children in order.
    pub fn leaves_below(&self, e: u32, out: &mut Vec<u32>) {
        let mut stack = vec![e];
        while let Some(x) = stack.pop() {
            let el = &self.items[x as usize];
            if el.is_leaf() {
                out.push(x);
            } else {
                for c in (0..4).rev() {
                    stack.push(el.children + c);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn children_tile_their_parent() {
        let quad = Element::new(
            [
                Vec3::new(0.0, 0.0, 0.0),
                Vec3::new(2.0, 0.0, 0.0),
                Vec3::new(2.5, 1.0, 0.0),
                Vec3::new(0.0, 1.5, 0.0),
            ],
            false,
            0,
            NONE,
            0,
        );
        let tri = Element::new(
            [
                Vec3::new(0.0, 0.0, 0.0),
                Vec3::new(1.0, 0.0, 0.0),
                Vec3::new(0.0, 0.0, -1.0),
                Vec3::ZERO,
            ],
            true,
            1,
            NONE,
            0,
        );
        for parent in [quad, tri] {
            let kids = parent
                .child_corners()
                .map(|c| Element::new(c, parent.tri, 0, 0, 1));
            let sum: f32 = kids.iter().map(|k| k.area).sum();
            assert!(
                (sum - parent.area).abs() < 1e-5 * parent.area,
                "{sum} {}",
                parent.area
            );
            for k in &kids {
                assert!(k.normal.dot(parent.normal) > 0.9999);
            }
        }
        // A triangle's children each hold a quarter of its area.
        let kids = tri.child_corners().map(|c| Element::new(c, true, 0, 0, 1));
        for k in &kids {
            assert!((k.area - tri.area / 4.0).abs() < 1e-6);
        }
    }

    #[test]
    fn shared_edges_split_at_identical_points() {
        // Two quads sharing the edge (b, c): their children's corners on it coincide bit for bit.
        let (a, b, c, d, e, f) = (
            Vec3::new(0.1, 0.0, 0.3),
            Vec3::new(1.3, 0.0, 0.7),
            Vec3::new(1.1, 0.0, 2.9),
            Vec3::new(0.2, 0.0, 2.2),
            Vec3::new(2.7, 0.0, 0.1),
            Vec3::new(3.1, 0.0, 3.3),
        );
        let left = Element::new([a, b, c, d], false, 0, NONE, 0);
        let right = Element::new([b, e, f, c], false, 1, NONE, 0);
        let l = left.child_corners();
        let r = right.child_corners();
        assert_eq!(l[1][2].to_array(), r[3][0].to_array());
        assert_eq!(l[1][2].to_array(), ((b + c) * 0.5).to_array());
    }
}
