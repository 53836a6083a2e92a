//! The hemicube (Cohen & Greenberg 1985; the z-buffer pseudo-code of Szirmay-Kalos & Márton (1995)):
//! a top face and four half side faces of resolution P × P around a point of patch i, each pixel
//! carrying its precomputed delta form factor ([`super::projection`]). Eq. 6 evaluates the inner
//! integral at one point; averaged over `--samples` points spread over patch i, the row's error
//! goes to zero as both the number of points and P grow. O(N + P²) per point: every triangle is
//! projected, every pixel read.

use super::estimator::{Estimator, Scratch};
use super::projection::Solid;

/// The hemicube's projection solid at resolution `p`.
pub fn solid(p: usize) -> Solid {
    Solid::hemicube(p)
}

/// Row `i` of F through the hemicube: [`super::projection`]'s z-buffer row with this solid.
pub(super) fn row(est: &Estimator, i: usize, scratch: &mut Scratch) {
    let solid = est
        .solid
        .as_ref()
        .expect("the estimator builds the hemicube for its method");
    super::projection::row(est, solid, i, scratch);
}
