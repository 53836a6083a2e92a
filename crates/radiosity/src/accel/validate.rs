//! Validation of a built hierarchy's invariants, for the tests.

use super::node::{WideNode, EMPTY_LANE, LEAF, NO_TRIANGLE, WIDTH};
use super::Bvh;
use crate::geom::{Aabb, Vec3};
use glam::Vec4;

impl Bvh {
    /// Check the hierarchy's invariants: children inside parents, every triangle in at least
    /// one leaf (more than one where a spatial split cut it), meeting each box it is in, and
    /// every point of it (a grid of 15 barycentric points) inside the box of one of its
    /// leaves. Tests call it.
    pub fn validate(&self) -> Result<(), String> {
        // Triangle ids (patch << 1 | sub) are unique: where each is in `tris`.
        let index: std::collections::HashMap<u32, usize> = self
            .tris
            .iter()
            .enumerate()
            .map(|(k, t)| (t.id, k))
            .collect();
        if index.len() != self.tris.len() {
            return Err("two triangles share an id".into());
        }
        let mut boxes: Vec<Vec<Aabb>> = vec![Vec::new(); self.tris.len()];
        let lane_box = |n: &WideNode, l: usize| Aabb {
            min: Vec3::new(n.planes[0][l], n.planes[1][l], n.planes[2][l]),
            max: Vec3::new(n.planes[3][l], n.planes[4][l], n.planes[5][l]),
        };
        let tol = |a: f32| 1e-4 * a.abs().max(1.0);
        let inside = |p: Vec3, b: &Aabb| {
            (0..3).all(|k| p[k] >= b.min[k] - tol(p[k]) && p[k] <= b.max[k] + tol(p[k]))
        };
        // (node, box of the node as its parent stores it)
        let mut stack = vec![(
            0usize,
            Aabb {
                min: Vec3::splat(f32::NEG_INFINITY),
                max: Vec3::splat(f32::INFINITY),
            },
        )];
        let mut references = 0;
        while let Some((i, parent)) = stack.pop() {
            let n = &self.nodes[i];
            for l in 0..WIDTH {
                let c = n.child[l];
                if c == EMPTY_LANE {
                    continue;
                }
                let b = lane_box(n, l);
                if !inside(b.min, &parent) || !inside(b.max, &parent) {
                    return Err(format!("a child of node {i} sticks out of it"));
                }
                if c & LEAF == 0 {
                    stack.push((c as usize, b));
                    continue;
                }
                let blk = &self.blocks[(c & !LEAF) as usize];
                for lane in 0..4 {
                    if blk.id[lane] == NO_TRIANGLE {
                        continue;
                    }
                    references += 1;
                    let get = |a: &[Vec4; 3]| Vec3::new(a[0][lane], a[1][lane], a[2][lane]);
                    let (v0, e1, e2) = (get(&blk.v0), get(&blk.e1), get(&blk.e2));
                    let Some(&k) = index.get(&blk.id[lane]).filter(|&&k| {
                        let t = &self.tris[k];
                        (t.v0, t.e1, t.e2) == (v0, e1, e2)
                    }) else {
                        return Err(format!(
                            "leaf lane holds an unknown triangle {}",
                            blk.id[lane]
                        ));
                    };
                    let tb = Aabb::from_points(&[v0, v0 + e1, v0 + e2]);
                    let meets = (0..3).all(|a| {
                        tb.min[a] <= b.max[a] + tol(tb.min[a])
                            && tb.max[a] >= b.min[a] - tol(tb.max[a])
                    });
                    if !meets {
                        return Err(format!("triangle {k} does not meet its leaf's box"));
                    }
                    boxes[k].push(b);
                }
            }
        }
        if references != self.references {
            return Err(format!(
                "{references} triangle references in the leaves, {} counted",
                self.references
            ));
        }
        for (k, (t, bs)) in self.tris.iter().zip(&boxes).enumerate() {
            if bs.is_empty() {
                return Err(format!("triangle {k} in no leaf"));
            }
            // A point's rounding is relative to the vertices' coordinates, not its own.
            let m = [t.v0, t.v0 + t.e1, t.v0 + t.e2]
                .iter()
                .fold(1f32, |m, v| m.max(v.abs().max_element()));
            let near = |p: Vec3, b: &Aabb| {
                (0..3).all(|k| p[k] >= b.min[k] - tol(m) && p[k] <= b.max[k] + tol(m))
            };
            for i in 0..=4 {
                for j in 0..=4 - i {
                    let p = t.v0 + t.e1 * (i as f32 / 4.0) + t.e2 * (j as f32 / 4.0);
                    if !bs.iter().any(|b| near(p, b)) {
                        return Err(format!(
                            "a point of triangle {k} lies in none of its leaves' boxes"
                        ));
                    }
                }
            }
        }
        Ok(())
    }
}
