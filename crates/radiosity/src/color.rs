//! RGB triples of radiometric quantities (reflectance, exitance, radiosity, power), kept apart
//! from geometric vectors. Components are `f64`: energies are accumulated over many shots, and the
//! solvers' convergence tests look at differences of 1e-6 and below.

use std::ops::{Add, AddAssign, Div, Mul, MulAssign, Sub, SubAssign};

/// One value per colour channel (linear, not gamma-encoded). What the channels mean
/// (reflectance, exitance in W/m², radiosity, power) depends on where the triple is used.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Rgb {
    /// Red channel.
    pub r: f64,
    /// Green channel.
    pub g: f64,
    /// Blue channel.
    pub b: f64,
}

impl Rgb {
    /// All channels zero.
    pub const BLACK: Rgb = Rgb::splat(0.0);

    /// A triple from its channels.
    pub const fn new(r: f64, g: f64, b: f64) -> Self {
        Self { r, g, b }
    }

    /// The same value in every channel.
    pub const fn splat(v: f64) -> Self {
        Self { r: v, g: v, b: v }
    }

    /// The channels as an array `[r, g, b]`.
    pub fn to_array(self) -> [f64; 3] {
        [self.r, self.g, self.b]
    }

    /// A triple from an array `[r, g, b]`.
    pub fn from_array(a: [f64; 3]) -> Self {
        Self::new(a[0], a[1], a[2])
    }

    /// Sum of the channels: the scalar used to rank shooters by unshot energy.
    pub fn sum(self) -> f64 {
        self.r + self.g + self.b
    }

    /// Largest channel.
    pub fn max_channel(self) -> f64 {
        self.r.max(self.g).max(self.b)
    }

    /// Smallest channel.
    pub fn min_channel(self) -> f64 {
        self.r.min(self.g).min(self.b)
    }

    /// Relative luminance of linear sRGB primaries (ITU-R BT.709 weights).
    pub fn luminance(self) -> f64 {
        0.2126 * self.r + 0.7152 * self.g + 0.0722 * self.b
    }

    /// True when every channel is finite.
    pub fn is_finite(self) -> bool {
        self.r.is_finite() && self.g.is_finite() && self.b.is_finite()
    }

    /// Apply `f` to each channel.
    pub fn map(self, f: impl Fn(f64) -> f64) -> Self {
        Self::new(f(self.r), f(self.g), f(self.b))
    }

    /// Largest absolute channel difference to `o`.
    pub fn max_abs_diff(self, o: Rgb) -> f64 {
        (self - o).map(f64::abs).max_channel()
    }
}

impl Add for Rgb {
    type Output = Rgb;
    fn add(self, o: Rgb) -> Rgb {
        Rgb::new(self.r + o.r, self.g + o.g, self.b + o.b)
    }
}
impl AddAssign for Rgb {
    fn add_assign(&mut self, o: Rgb) {
        *self = *self + o;
    }
}
impl Sub for Rgb {
    type Output = Rgb;
    fn sub(self, o: Rgb) -> Rgb {
        Rgb::new(self.r - o.r, self.g - o.g, self.b - o.b)
    }
}
impl SubAssign for Rgb {
    fn sub_assign(&mut self, o: Rgb) {
        *self = *self - o;
    }
}
impl Mul for Rgb {
    type Output = Rgb;
    fn mul(self, o: Rgb) -> Rgb {
        Rgb::new(self.r * o.r, self.g * o.g, self.b * o.b)
    }
}
impl Mul<f64> for Rgb {
    type Output = Rgb;
    fn mul(self, s: f64) -> Rgb {
        Rgb::new(self.r * s, self.g * s, self.b * s)
    }
}
impl MulAssign<f64> for Rgb {
    fn mul_assign(&mut self, s: f64) {
        *self = *self * s;
    }
}
impl Div<f64> for Rgb {
    type Output = Rgb;
    fn div(self, s: f64) -> Rgb {
        Rgb::new(self.r / s, self.g / s, self.b / s)
    }
}
impl std::iter::Sum for Rgb {
    fn sum<I: Iterator<Item = Rgb>>(iter: I) -> Rgb {
        iter.fold(Rgb::BLACK, |a, b| a + b)
    }
}

impl std::fmt::Display for Rgb {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match f.precision() {
            Some(p) => write!(f, "({:.p$}, {:.p$}, {:.p$})", self.r, self.g, self.b),
            None => write!(f, "({}, {}, {})", self.r, self.g, self.b),
        }
    }
}

/// The sRGB decoding function (IEC 61966-2-1): the linear value of an encoded value in `[0, 1]`
/// (8-bit colours in images and PLY files are encoded).
pub fn srgb_to_linear(c: f64) -> f64 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}
