//! The hemicube (Cohen & Greenberg 1985; the z-buffer pseudo-code of 000_59d10e371b5f300d.txt):
//! a top face and four half side faces of resolution P × P around a point of patch i, each pixel
//! carrying its precomputed delta form factor ([`super::projection`]). Eq. 6 evaluates the inner
//! integral at one point; averaged over `--samples` points spread over patch i, the row's error
//! goes to zero as both the number of points and P grow. O(N + P²) per point: every triangle is
//! projected, every pixel read.

use super::projection::Solid;

/// The hemicube's projection solid at resolution `p`.
pub fn solid(p: usize) -> Solid {
    Solid::hemicube(p)
}
