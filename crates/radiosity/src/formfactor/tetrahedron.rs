//! The cubic tetrahedron (Beran-Koehn & Pavicic, "A cubic tetrahedral adaptation of the
//! hemi-cube algorithm", Graphics Gems II, ref. \[BKP91\] of 000_59d10e371b5f300d.txt): three faces
//! of a cube whose main diagonal is the patch normal, each a right triangle of a P × P grid, with
//! their own delta form factors ([`super::projection`]). It sees the same hemisphere as the
//! hemicube with three faces instead of five.

use super::projection::Solid;

/// The cubic tetrahedron's projection solid at resolution `p`.
pub fn solid(p: usize) -> Solid {
    Solid::tetrahedron(p)
}
