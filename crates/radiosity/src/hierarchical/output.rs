//! Leaf elements as a [`Mesh`]: one patch per leaf, vertices shared inside each input piece's
//! quadtree, and the T-vertices where a leaf meets finer neighbours recorded in
//! [`Mesh::hanging`], so that interpolated colours are continuous across them.
//!
//! A T-vertex is found by position: the midpoint of a leaf's edge, computed as the quadtree
//! computes it (see [`super::element`]), is a vertex of the same tree exactly when the
//! neighbour across that edge was split there. The search recurses into both halves, so
//! vertices of neighbours several levels finer are found too, longest edges first.

use super::element::Element;
use super::Hierarchy;
use crate::geom::Vec3;
use crate::mesh::{Mesh, Patch};
use std::collections::HashMap;

type Key = (u32, [u32; 3]);

fn key(root: u32, p: Vec3) -> Key {
    // Adding 0.0 maps −0.0 to +0.0, so that equal positions have equal bits.
    (
        root,
        [
            (p.x + 0.0).to_bits(),
            (p.y + 0.0).to_bits(),
            (p.z + 0.0).to_bits(),
        ],
    )
}

/// The leaves of `h` as a mesh (patch `k` is leaf `leaves[k]`), with the surfaces, materials
/// and smoothing groups of `roots` (the input pieces the hierarchy was built on).
pub fn leaf_mesh(h: &Hierarchy, roots: &Mesh, leaves: &[u32]) -> Mesh {
    let items = &h.elements.items;
    let mut mesh = Mesh {
        max_edge: 0.0,
        groups: roots.groups.clone(),
        coincident: roots.coincident.clone(),
        ..Default::default()
    };
    let mut index: HashMap<Key, u32> = HashMap::with_capacity(leaves.len() * 2);
    mesh.patches.reserve(leaves.len());
    for &l in leaves {
        let e = &items[l as usize];
        let root = &roots.patches[e.root as usize];
        let mut vs = [Patch::NONE; 4];
        for (k, p) in e.polygon().iter().enumerate() {
            vs[k] = *index.entry(key(e.root, *p)).or_insert_with(|| {
                mesh.vertices.push(*p);
                (mesh.vertices.len() - 1) as u32
            });
        }
        mesh.patches.push(patch(e, vs, root));
    }
    // T-vertices: (edge length, v, a, b), longest first.
    let mut hanging: Vec<(f32, [u32; 3])> = Vec::new();
    for (&l, p) in leaves.iter().zip(&mesh.patches) {
        let e = &items[l as usize];
        let n = if e.tri { 3 } else { 4 };
        for k in 0..n {
            let (a, b) = (p.vertices[k], p.vertices[(k + 1) % n]);
            split_edge(&mesh.vertices, &index, e.root, a, b, 48, &mut hanging);
        }
    }
    hanging.sort_by(|x, y| y.0.total_cmp(&x.0).then(x.1.cmp(&y.1)));
    // A vertex could in principle be found on two edges; keep its first (longest) constraint.
    let mut seen = vec![false; mesh.vertices.len()];
    mesh.hanging = hanging
        .into_iter()
        .filter(|(_, [v, ..])| !std::mem::replace(&mut seen[*v as usize], true))
        .map(|(_, c)| c)
        .collect();
    mesh
}

fn split_edge(
    vertices: &[Vec3],
    index: &HashMap<Key, u32>,
    root: u32,
    a: u32,
    b: u32,
    depth: u32,
    out: &mut Vec<(f32, [u32; 3])>,
) {
    let (pa, pb) = (vertices[a as usize], vertices[b as usize]);
    let m = (pa + pb) * 0.5;
    if depth == 0 || m == pa || m == pb {
        return;
    }
    if let Some(&v) = index.get(&key(root, m)) {
        out.push(((pb - pa).length(), [v, a, b]));
        split_edge(vertices, index, root, a, v, depth - 1, out);
        split_edge(vertices, index, root, v, b, depth - 1, out);
    }
}

fn patch(e: &Element, vertices: [u32; 4], root: &Patch) -> Patch {
    let [a, b, c, d] = e.corners;
    let split = if e.tri {
        1.0
    } else {
        let w1 = crate::geom::triangle_cross(a, b, c).length();
        let w2 = crate::geom::triangle_cross(a, c, d).length();
        if w1 + w2 > 0.0 {
            w1 / (w1 + w2)
        } else {
            0.5
        }
    };
    Patch {
        vertices,
        surface: root.surface,
        material: root.material,
        area: e.area,
        normal: e.normal,
        centre: e.centre,
        split,
    }
}
