//! `Color`: linear RGB radiance, power or reflectance, a type of its own so that colours and
//! directions cannot be mixed by mistake.
//!
//! It wraps a `Vec4`: four lanes, so that spectral mode can carry four wavelengths per path
//! (`spectrum::lanes`). An RGB colour keeps a copy of its red channel in the fourth lane. Every
//! lane-wise operation (sums, products, quotients, square roots, maxima) does to the copy what it
//! does to red, so the copy stays exact, and the reductions that see all four lanes (largest and
//! smallest lane, finiteness, equality) then give what they gave on three channels, bit for bit:
//! RGB arithmetic is the same float operations as when colours were `Vec3`s. The channel sums
//! and means (`sum`, `mean`) are over the first three lanes, as colours need; spectral code
//! that averages its four lanes says so ([`Color::lane_sum`]).
//!
//! The one place where data really is a colour or a direction, a normal map (a texture read as
//! colours whose texels encode tangent-space normals), converts explicitly with
//! [`Color::to_vec3`].

use std::fmt;
use std::iter::Sum;
use std::ops::{Add, AddAssign, Div, DivAssign, Index, Mul, MulAssign, Neg, Sub, SubAssign};

use glam::{DVec3, Vec3, Vec4};

/// Linear RGB radiance or reflectance (three `f32` channels, red copied in a fourth lane), or in
/// spectral mode a value at each of four wavelengths.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(transparent)]
pub struct Color(Vec4);

impl Color {
    pub const ZERO: Color = Color(Vec4::ZERO);
    pub const ONE: Color = Color(Vec4::ONE);

    /// An RGB colour (red copied into the fourth lane).
    #[inline(always)]
    pub const fn new(r: f32, g: f32, b: f32) -> Self {
        Color(Vec4::new(r, g, b, r))
    }

    /// All lanes `v`.
    #[inline(always)]
    pub const fn splat(v: f32) -> Self {
        Color(Vec4::splat(v))
    }

    #[inline(always)]
    pub const fn from_array(a: [f32; 3]) -> Self {
        Color::new(a[0], a[1], a[2])
    }

    /// The three colour channels.
    #[inline(always)]
    pub fn to_array(self) -> [f32; 3] {
        [self.0.x, self.0.y, self.0.z]
    }

    /// Four lanes as they are: a spectral value at each of a path's wavelengths.
    #[inline(always)]
    pub const fn from_lanes(a: [f32; 4]) -> Self {
        Color(Vec4::from_array(a))
    }

    /// The four lanes (an RGB colour's fourth is its red).
    #[inline(always)]
    pub fn lanes(self) -> [f32; 4] {
        self.0.to_array()
    }

    /// `f` of each lane, for a pure `f`. An RGB colour's copy of red (a fourth lane bit-equal
    /// to the first) takes the first lane's result instead of calling `f` again.
    #[inline(always)]
    pub fn map(self, f: impl Fn(f32) -> f32) -> Self {
        let v = self.0;
        let x = f(v.x);
        let w = if v.w.to_bits() == v.x.to_bits() { x } else { f(v.w) };
        Color(Vec4::new(x, f(v.y), f(v.z), w))
    }

    /// `f` of each pair of lanes of `self` and `other` (see [`Color::map`]).
    #[inline(always)]
    pub fn zip_map(self, other: Color, f: impl Fn(f32, f32) -> f32) -> Self {
        let (a, b) = (self.0, other.0);
        let x = f(a.x, b.x);
        let copy = a.w.to_bits() == a.x.to_bits() && b.w.to_bits() == b.x.to_bits();
        let w = if copy { x } else { f(a.w, b.w) };
        Color(Vec4::new(x, f(a.y, b.y), f(a.z, b.z), w))
    }

    /// The channels as a vector: only for data that is one or the other, such as a normal map's
    /// texels decoded into a tangent-space normal. Colours and directions do not otherwise mix.
    #[inline(always)]
    pub fn to_vec3(self) -> Vec3 {
        self.0.truncate()
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
        self.0.truncate().as_dvec3()
    }

    /// The colour of channels summed in `f64` (see [`Color::as_dvec3`]), each rounded to `f32`.
    #[inline(always)]
    pub fn from_dvec3(v: DVec3) -> Self {
        let v = v.as_vec3();
        Color::new(v.x, v.y, v.z)
    }

    /// The largest lane: max(r, max(g, b)) as `Vec3` computed it, and then the fourth lane,
    /// taken only when larger (an RGB colour's copy of red never is).
    #[inline(always)]
    pub fn max_element(self) -> f32 {
        let max = |a: f32, b: f32| if a > b { a } else { b };
        let v = self.0;
        max(v.w, max(v.x, max(v.y, v.z)))
    }

    /// The smallest lane (see [`Color::max_element`]).
    #[inline(always)]
    pub fn min_element(self) -> f32 {
        let min = |a: f32, b: f32| if a < b { a } else { b };
        let v = self.0;
        min(v.w, min(v.x, min(v.y, v.z)))
    }

    /// The sum of the three colour channels, `r + g + b` in that order (the fourth lane is not
    /// counted: see [`Color::lane_sum`]).
    #[inline(always)]
    pub fn sum(self) -> f32 {
        self.0.x + self.0.y + self.0.z
    }

    /// The mean of the three colour channels, `(r + g + b) / 3`.
    #[inline(always)]
    pub fn mean(self) -> f32 {
        self.sum() / 3.0
    }

    /// The sum of the first `n` lanes in order: 3 for an RGB colour (its `sum`), 4 for a
    /// spectral value at four wavelengths.
    #[inline(always)]
    pub fn lane_sum(self, n: usize) -> f32 {
        if n > 3 { self.sum() + self.0.w } else { self.sum() }
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
        Color(self.0.max(Vec4::ZERO).map(f32::sqrt))
    }

    /// Each lane no larger than `m` (`f32::min`).
    #[inline(always)]
    pub fn min_splat(self, m: f32) -> Self {
        self.map(|v| v.min(m))
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
        fmt::Display::fmt(&self.0.truncate(), f)
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

/// A colour stored in 12 bytes, for the arrays of colours that are RGB in either mode (SPPM's
/// per-pixel sums and visible points, photon hits): a [`Color`] takes 16 (its fourth lane
/// carries spectral mode's fourth wavelength) and aligns to 16.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PackedColor([f32; 3]);

impl PackedColor {
    pub const ZERO: PackedColor = PackedColor([0.0; 3]);

    /// The colour (its red copied into the fourth lane).
    #[inline(always)]
    pub fn get(self) -> Color {
        Color::from_array(self.0)
    }
}

impl From<Color> for PackedColor {
    /// The three colour channels (the fourth lane is not kept).
    #[inline(always)]
    fn from(c: Color) -> Self {
        PackedColor(c.to_array())
    }
}

/// A four-lane value stored in 16 bytes aligned to 4, for stored records that keep spectral
/// mode's four wavelengths (VCM's light vertices): a [`Color`] aligns to 16, which would pad
/// the records around it.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PackedLanes([f32; 4]);

impl PackedLanes {
    #[inline(always)]
    pub fn get(self) -> Color {
        Color::from_lanes(self.0)
    }
}

impl From<Color> for PackedLanes {
    #[inline(always)]
    fn from(c: Color) -> Self {
        PackedLanes(c.lanes())
    }
}
