//! Coincident polygons: one surface, whatever the number of copies.
//!
//! Real models are full of polygons lying exactly on one another: a scene that includes an
//! object twice (half of RenderPark's hospital), CAD exports that repeat faces, a wall modelled
//! on a wall. Left as they are, every method would treat the copies as different surfaces in
//! the same place, and which of them a ray meets first is then a matter of the ray caster's
//! traversal order: light lands on one copy, the picture shows the other, and a thousand
//! copies make every ray near them test a thousand polygons.
//!
//! So the mesher finds them first ([`Coincidence::find`]) and meshes each group once: two
//! polygons are *coincident* when they have the same corners as a set, each rounded to a grid
//! of 10⁻⁶ of the scene's bounding-box diagonal ([`crate::geom::coincidence_key`]), and face
//! the same way (normals within 10⁻³). The group is one surface with the representative's
//! material: the first polygon of the group that emits, or the first one when none does (a
//! lamp face laid on a ceiling panel of the same shape stays a lamp). The other copies get no
//! patches; every solver, the gather, the path tracer, view factors and heat transfer then see
//! one surface, and a copy's radiosity is its representative's ([`Coincidence::of`],
//! [`super::Mesh::surface_radiosity`]). Emission is counted once: the group is one surface.
//!
//! What is not merged:
//! - polygons back to back (the same corners facing opposite ways: the two sides of a thin
//!   wall, an MGF `sides 2` surface) are two surfaces, as they should be;
//! - partial overlaps (a smaller polygon lying on a larger one, two that overlap in part) stay
//!   separate surfaces: where they overlap, rays meet whichever the ray caster resolves first,
//!   the same one from every direction ([`crate::accel`]), so energy is conserved but the
//!   overlap's light goes to one of them;
//! - coincident polygons of different materials are merged all the same (they are one surface
//!   in space); the representative's material is used and [`Coincidence::mixed`] counts the
//!   copies whose material differs, for a warning.

use crate::geom::{coincidence_key, coincidence_step, Vec3};
use crate::scene::{vector_area, Scene};
use std::collections::HashMap;

/// Coincident polygons of a scene, grouped.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Coincidence {
    /// For each polygon, the polygon that stands for its group (itself when it has no copy).
    /// Empty when the scene has no coincident polygons.
    pub of: Vec<u32>,
    /// Copies merged into another polygon (polygons with no patches of their own).
    pub merged: usize,
    /// Of those, copies whose material differs from their representative's.
    pub mixed: usize,
}

impl Coincidence {
    /// Group `scene`'s coincident polygons (the same corners facing the same way). Linear in
    /// the number of corners (one hash per polygon). Polygons of zero area are never grouped.
    pub fn find(scene: &Scene) -> Coincidence {
        let n = scene.polygons.len();
        if n < 2 {
            return Coincidence::default();
        }
        let step = coincidence_step(
            scene
                .polygons
                .iter()
                .flat_map(|p| p.vertices.iter().copied()),
        );
        let emits = |i: usize| {
            scene
                .materials
                .get(scene.polygons[i].material)
                .is_some_and(|m| m.emission.max_channel() > 0.0)
        };
        // The group of each polygon: the first polygon with its key.
        // The map holds a 64-bit hash of each key and the first polygon with it (16 bytes a
        // polygon, not the key itself); a hit is confirmed by comparing the keys, and a
        // collision of different keys probes on.
        let key = |i: usize| {
            let v = &scene.polygons[i].vertices;
            let normal: Vec3 = vector_area(v).normalize_or_zero();
            (normal != Vec3::ZERO && normal.is_finite())
                .then(|| coincidence_key(v.iter().copied(), normal, step))
        };
        let hash = |k: &[i64]| {
            use std::hash::{Hash, Hasher};
            let mut h = std::collections::hash_map::DefaultHasher::new();
            k.hash(&mut h);
            h.finish()
        };
        let mut first: HashMap<u64, u32> = HashMap::with_capacity(n);
        let mut group: Vec<u32> = (0..n as u32).collect();
        let mut any = false;
        for i in 0..n {
            let Some(k) = key(i) else { continue };
            let mut h = hash(&k);
            let g = loop {
                match first.entry(h) {
                    std::collections::hash_map::Entry::Vacant(e) => {
                        e.insert(i as u32);
                        break i as u32;
                    }
                    std::collections::hash_map::Entry::Occupied(e) => {
                        let g = *e.get();
                        if key(g as usize).as_deref() == Some(&k[..]) {
                            break g;
                        }
                        h = h.wrapping_add(0x9E37_79B9_7F4A_7C15);
                    }
                }
            };
            any |= g as usize != i;
            group[i] = g;
        }
        if !any {
            return Coincidence::default();
        }
        // Each group's representative: its first emitter, else its first polygon.
        let mut rep = group.clone();
        for i in 0..n {
            let g = group[i] as usize;
            if emits(i) && !emits(rep[g] as usize) {
                rep[g] = i as u32;
            }
        }
        let of: Vec<u32> = group.iter().map(|&g| rep[g as usize]).collect();
        let (mut merged, mut mixed) = (0, 0);
        for (i, &r) in of.iter().enumerate() {
            if r as usize != i {
                merged += 1;
                mixed +=
                    usize::from(scene.polygons[i].material != scene.polygons[r as usize].material);
            }
        }
        Coincidence { of, merged, mixed }
    }

    /// Whether polygon `i` is a copy (it has no patches of its own).
    pub fn is_copy(&self, i: usize) -> bool {
        self.of.get(i).is_some_and(|&r| r as usize != i)
    }

    /// The polygon that stands for polygon `i`'s group.
    pub fn representative(&self, i: usize) -> usize {
        self.of.get(i).map_or(i, |&r| r as usize)
    }

    /// The warning for a scene with merged copies, or `None`.
    pub fn warning(&self) -> Option<String> {
        (self.merged > 0).then(|| {
            let mixed = match self.mixed {
                0 => String::new(),
                m => format!(
                    "; {m} of them with another material than the polygon they lie on, whose material is used"
                ),
            };
            format!(
                "{} coincident polygon{} (the same corners facing the same way as another) merged: each group is solved as one surface{mixed}",
                self.merged,
                if self.merged == 1 { "" } else { "s" }
            )
        })
    }
}
