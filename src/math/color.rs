//! `Color`: linear RGB radiance, power or reflectance, a type of its own so that colours and
//! directions cannot be mixed by mistake.
//!
//! It is a transparent wrapper of a `Vec3` whose every operation forwards to glam's, so colour
//! arithmetic is the same float operations, bit for bit, as when colours were plain `Vec3`s. The
//! one place where data really is one or the other, a normal map (a texture read as colours whose
//! texels encode tangent-space normals), converts explicitly with [`Color::to_vec3`].

use std::fmt;
use std::iter::Sum;
use std::ops::{Add, AddAssign, Div, DivAssign, Index, Mul, MulAssign, Neg, Sub, SubAssign};

use glam::{DVec3, Vec3};

/// Linear RGB radiance or reflectance: three `f32` channels.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(transparent)]
pub struct Color(Vec3);

impl Color {
    pub const ZERO: Color = Color(Vec3::ZERO);
    pub const ONE: Color = Color(Vec3::ONE);

    #[inline(always)]
    pub const fn new(r: f32, g: f32, b: f32) -> Self {
        Color(Vec3::new(r, g, b))
    }

    /// All three channels `v`.
    #[inline(always)]
    pub const fn splat(v: f32) -> Self {
        Color(Vec3::splat(v))
    }

    #[inline(always)]
    pub const fn from_array(a: [f32; 3]) -> Self {
        Color(Vec3::from_array(a))
    }

    #[inline(always)]
    pub const fn to_array(self) -> [f32; 3] {
        self.0.to_array()
    }

    /// The channels as a vector: only for data that is one or the other, such as a normal map's
    /// texels decoded into a tangent-space normal. Colours and directions do not otherwise mix.
    #[inline(always)]
    pub const fn to_vec3(self) -> Vec3 {
        self.0
    }

    #[inline(always)]
    pub fn r(self) -> f32 {
        self.0.x
    }

    #[inline(always)]
    pub fn g(self) -> f32 {
        self.0.y
    }

    #[inline(always)]
    pub fn b(self) -> f32 {
        self.0.z
    }

    /// The channels in `f64`, for sums over many colours.
    #[inline(always)]
    pub fn as_dvec3(self) -> DVec3 {
        self.0.as_dvec3()
    }

    /// The colour of channels summed in `f64` (see [`Color::as_dvec3`]), each rounded to `f32`.
    #[inline(always)]
    pub fn from_dvec3(v: DVec3) -> Self {
        Color(v.as_vec3())
    }

    #[inline(always)]
    pub fn max_element(self) -> f32 {
        self.0.max_element()
    }

    #[inline(always)]
    pub fn min_element(self) -> f32 {
        self.0.min_element()
    }

    /// The sum of the three channels, `r + g + b` in that order.
    #[inline(always)]
    pub fn sum(self) -> f32 {
        self.0.element_sum()
    }

    /// The mean of the three channels, `(r + g + b) / 3`.
    #[inline(always)]
    pub fn mean(self) -> f32 {
        self.0.element_sum() / 3.0
    }

    /// True when every channel is finite (no NaN, no infinity).
    #[inline(always)]
    pub fn is_finite(self) -> bool {
        self.0.is_finite()
    }

    #[inline(always)]
    pub fn abs(self) -> Self {
        Color(self.0.abs())
    }

    #[inline(always)]
    pub fn max(self, other: Color) -> Self {
        Color(self.0.max(other.0))
    }

    /// The square root of each channel (negative channels give 0).
    #[inline(always)]
    pub fn sqrt(self) -> Self {
        Color(self.0.max(glam::Vec3::ZERO).map(f32::sqrt))
    }

    /// True when every channel is within `max_abs_diff` of `other`'s.
    #[inline(always)]
    pub fn abs_diff_eq(self, other: Color, max_abs_diff: f32) -> bool {
        self.0.abs_diff_eq(other.0, max_abs_diff)
    }
}

impl fmt::Display for Color {
    /// Printed as a `Vec3` is: `[r, g, b]`, with any precision given applied to each channel.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Display::fmt(&self.0, f)
    }
}

impl Index<usize> for Color {
    type Output = f32;
    #[inline(always)]
    fn index(&self, i: usize) -> &f32 {
        &self.0[i]
    }
}

impl Add for Color {
    type Output = Color;
    #[inline(always)]
    fn add(self, rhs: Color) -> Color {
        Color(self.0 + rhs.0)
    }
}

impl Sub for Color {
    type Output = Color;
    #[inline(always)]
    fn sub(self, rhs: Color) -> Color {
        Color(self.0 - rhs.0)
    }
}

impl Mul for Color {
    type Output = Color;
    #[inline(always)]
    fn mul(self, rhs: Color) -> Color {
        Color(self.0 * rhs.0)
    }
}

impl Mul<f32> for Color {
    type Output = Color;
    #[inline(always)]
    fn mul(self, rhs: f32) -> Color {
        Color(self.0 * rhs)
    }
}

impl Mul<Color> for f32 {
    type Output = Color;
    #[inline(always)]
    fn mul(self, rhs: Color) -> Color {
        Color(self * rhs.0)
    }
}

impl Div for Color {
    type Output = Color;
    #[inline(always)]
    fn div(self, rhs: Color) -> Color {
        Color(self.0 / rhs.0)
    }
}

impl Div<f32> for Color {
    type Output = Color;
    #[inline(always)]
    fn div(self, rhs: f32) -> Color {
        Color(self.0 / rhs)
    }
}

impl Neg for Color {
    type Output = Color;
    #[inline(always)]
    fn neg(self) -> Color {
        Color(-self.0)
    }
}

impl AddAssign for Color {
    #[inline(always)]
    fn add_assign(&mut self, rhs: Color) {
        self.0 += rhs.0;
    }
}

impl SubAssign for Color {
    #[inline(always)]
    fn sub_assign(&mut self, rhs: Color) {
        self.0 -= rhs.0;
    }
}

impl MulAssign for Color {
    #[inline(always)]
    fn mul_assign(&mut self, rhs: Color) {
        self.0 *= rhs.0;
    }
}

impl MulAssign<f32> for Color {
    #[inline(always)]
    fn mul_assign(&mut self, rhs: f32) {
        self.0 *= rhs;
    }
}

impl DivAssign for Color {
    #[inline(always)]
    fn div_assign(&mut self, rhs: Color) {
        self.0 /= rhs.0;
    }
}

impl DivAssign<f32> for Color {
    #[inline(always)]
    fn div_assign(&mut self, rhs: f32) {
        self.0 /= rhs;
    }
}

impl Sum for Color {
    /// Added in order from zero, as `Vec3`'s sum is.
    #[inline]
    fn sum<I: Iterator<Item = Color>>(iter: I) -> Color {
        Color(iter.map(|c| c.0).sum())
    }
}

impl<'a> Sum<&'a Color> for Color {
    #[inline]
    fn sum<I: Iterator<Item = &'a Color>>(iter: I) -> Color {
        Color(iter.map(|c| c.0).sum())
    }
}
