//! The cubic tetrahedron (Beran-Koehn & Pavicic, "A cubic tetrahedral adaptation of the
//! hemi-cube algorithm", Graphics Gems II, ref. \[BKP91\] of Szirmay-Kalos & Márton (1995)): three faces
//! of a cube whose main diagonal is the patch normal, each a right triangle of a P × P grid, with
//! their own delta form factors ([`super::projection`]). It sees the same hemisphere as the
//! hemicube with three faces instead of five.

use super::estimator::{Estimator, Scratch};
use super::projection::Solid;

/// The cubic tetrahedron's projection solid at resolution `p`.
pub fn solid(p: usize) -> Solid {
    Solid::tetrahedron(p)
}

/// Row `i` of F through the tetrahedron: [`super::projection`]'s z-buffer row with this solid.
pub(super) fn row(est: &Estimator, i: usize, scratch: &mut Scratch) {
    let solid = est
        .solid
        .as_ref()
        .expect("the estimator builds the tetrahedron for its method");
    super::projection::row(est, solid, i, scratch);
}
