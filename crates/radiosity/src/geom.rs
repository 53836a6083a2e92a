//! Geometric leaves: points and vectors (`glam::Vec3`, `f32`), rays and axis-aligned bounds.
//!
//! Geometry is stored in `f32` (scene units, whatever the scene uses: millimetres for the Cornell
//! box, metres for glTF); energies and areas are accumulated in `f64` elsewhere. That choice is made
//! once here and not parametrised.

pub use glam::Vec3;

/// A half-line `origin + t·direction`, `t ≥ 0`. `direction` need not be normalised, but every ray
/// the library builds has a unit direction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    /// Start point.
    pub origin: Vec3,
    /// Direction of travel (unit length for all rays built by this crate).
    pub direction: Vec3,
}

impl Ray {
    /// A ray from `origin` along `direction`.
    pub fn new(origin: Vec3, direction: Vec3) -> Self {
        Self { origin, direction }
    }

    /// The point at parameter `t`.
    pub fn at(&self, t: f32) -> Vec3 {
        self.origin + self.direction * t
    }
}

/// An axis-aligned bounding box. The empty box has `min = +∞`, `max = −∞`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// Lower corner.
    pub min: Vec3,
    /// Upper corner.
    pub max: Vec3,
}

impl Default for Aabb {
    fn default() -> Self {
        Self::EMPTY
    }
}

impl Aabb {
    /// The empty box (the identity of [`Aabb::union`]).
    pub const EMPTY: Aabb = Aabb {
        min: Vec3::splat(f32::INFINITY),
        max: Vec3::splat(f32::NEG_INFINITY),
    };

    /// The smallest box containing every point of `points`.
    pub fn from_points<'a>(points: impl IntoIterator<Item = &'a Vec3>) -> Self {
        points.into_iter().fold(Self::EMPTY, |b, p| b.grow(*p))
    }

    /// This box grown to contain `p`.
    pub fn grow(self, p: Vec3) -> Self {
        Self {
            min: self.min.min(p),
            max: self.max.max(p),
        }
    }

    /// The smallest box containing both boxes.
    pub fn union(self, o: Aabb) -> Self {
        Self {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }

    /// `max − min` (negative for the empty box).
    pub fn extent(&self) -> Vec3 {
        self.max - self.min
    }

    /// Centre point.
    pub fn centre(&self) -> Vec3 {
        (self.min + self.max) * 0.5
    }

    /// Length of the diagonal (0 for the empty box).
    pub fn diagonal(&self) -> f32 {
        if self.is_empty() {
            0.0
        } else {
            self.extent().length()
        }
    }

    /// True when the box holds no point.
    pub fn is_empty(&self) -> bool {
        self.min.x > self.max.x || self.min.y > self.max.y || self.min.z > self.max.z
    }

    /// Surface area (0 for the empty box), the cost measure of the SAH.
    pub fn surface_area(&self) -> f32 {
        if self.is_empty() {
            return 0.0;
        }
        let e = self.extent();
        2.0 * (e.x * e.y + e.y * e.z + e.z * e.x)
    }
}

/// Twice the signed area vector of the triangle `(a, b, c)`: its direction is the geometric
/// normal, its length twice the area.
pub fn triangle_cross(a: Vec3, b: Vec3, c: Vec3) -> Vec3 {
    (b - a).cross(c - a)
}

/// An orthonormal basis `(t, b)` completing the unit vector `n` (Duff et al., "Building an
/// Orthonormal Basis, Revisited", JCGT 2017): branch-free and continuous except at `n.z = −1`.
pub fn orthonormal_basis(n: Vec3) -> (Vec3, Vec3) {
    let sign = 1.0f32.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        Vec3::new(b, sign + n.y * n.y * a, -n.y),
    )
}

/// The key under which coincident polygons meet (*twins*: a scene that includes an object
/// twice, a wall on a wall): the corners as a set, each rounded to a grid of `step`, and the
/// unit normal rounded to 10⁻³, so that only polygons facing the same way coincide. The one
/// definition the hierarchical solver, the light tracer and the benchmarks group by.
pub fn coincidence_key(
    corners: impl IntoIterator<Item = Vec3>,
    normal: Vec3,
    step: f32,
) -> Vec<i64> {
    let q = |v: f32, s: f32| (v / s).round() as i64;
    let mut c: Vec<[i64; 3]> = corners
        .into_iter()
        .map(|p| [q(p.x, step), q(p.y, step), q(p.z, step)])
        .collect();
    c.sort_unstable();
    let mut key = c.concat();
    key.extend([q(normal.x, 1e-3), q(normal.y, 1e-3), q(normal.z, 1e-3)]);
    key
}

/// The grid step for [`coincidence_key`] over `points`: 10⁻⁶ of their bounding box's diagonal.
pub fn coincidence_step(points: impl IntoIterator<Item = Vec3>) -> f32 {
    let (mut lo, mut hi) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
    for v in points {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    ((hi - lo).length() * 1e-6).max(f32::MIN_POSITIVE)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn basis_is_orthonormal() {
        for n in [
            Vec3::X,
            Vec3::Y,
            Vec3::Z,
            -Vec3::Z,
            Vec3::new(0.3, -0.5, 0.8).normalize(),
            Vec3::new(-1e-4, 1e-4, -1.0).normalize(),
        ] {
            let (t, b) = orthonormal_basis(n);
            assert!((t.length() - 1.0).abs() < 1e-5);
            assert!((b.length() - 1.0).abs() < 1e-5);
            assert!(t.dot(b).abs() < 1e-5 && t.dot(n).abs() < 1e-5 && b.dot(n).abs() < 1e-5);
            // Right-handed: t × b = n.
            assert!((t.cross(b) - n).length() < 1e-4);
        }
    }

    #[test]
    fn aabb_area_and_union() {
        let a = Aabb::from_points(&[Vec3::ZERO, Vec3::new(1.0, 2.0, 3.0)]);
        assert_eq!(a.surface_area(), 2.0 * (2.0 + 6.0 + 3.0));
        assert_eq!(Aabb::EMPTY.union(a), a);
        assert!(Aabb::EMPTY.is_empty());
        assert_eq!(Aabb::EMPTY.surface_area(), 0.0);
    }
}
