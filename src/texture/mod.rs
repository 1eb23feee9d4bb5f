//! Textures: values that vary over a surface with its (u, v), as Mitsuba 3 defines them.
//!
//! - `bitmap`: an image (`image`) looked up with bilinear or nearest filtering after the `to_uv`
//!   transform; texel (i, j) is centred at ((i + 0.5) / W, (j + 0.5) / H) and row 0 is the top of
//!   the image, so v = 0 is the top; wrap modes act on integer texel indices.
//! - `checkerboard`: two colours in squares of 0.5 in uv.
//! - `mesh_attribute`: a value stored on a mesh's vertices (interpolated) or faces, read at the
//!   triangle a ray hit (`TexPoint::mesh`).
//! - constants.
//!
//! Colour parameters read `eval`; scalar parameters (roughness, weights, opacity) read `eval_1`,
//! which follows Mitsuba: the mean of a constant colour's channels, a bitmap's luminance, and a
//! checkerboard's colours swapped (a quirk of Mitsuba 3 kept so that scenes look the same).

pub mod image;

use crate::math::{Color, Vec2, luminance};
use glam::Affine2;
use image::TexImage;
use std::sync::Arc;

#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Filter {
    #[default]
    Bilinear,
    Nearest,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Wrap {
    #[default]
    Repeat,
    Mirror,
    Clamp,
}

impl Wrap {
    /// Texel index `i` folded into `0..n`.
    #[inline]
    fn index(self, i: i64, n: u32) -> u32 {
        let n = n as i64;
        (match self {
            Wrap::Repeat => i.rem_euclid(n),
            Wrap::Clamp => i.clamp(0, n - 1),
            // ... 1 0 | 0 1 ... n-1 | n-1 n-2 ...
            Wrap::Mirror => {
                let j = i.rem_euclid(2 * n);
                if j >= n { 2 * n - 1 - j } else { j }
            }
        }) as u32
    }
}

/// An image texture.
#[derive(Clone, Debug)]
pub struct Bitmap {
    /// Shared by every texture that reads the same file with the same decoding.
    pub image: Arc<TexImage>,
    pub filter: Filter,
    pub wrap: Wrap,
    pub to_uv: Affine2,
}

/// A texture of colours (and, through `eval_1`, of scalars).
#[derive(Clone, Debug)]
pub enum Texture {
    Constant(Color),
    Bitmap(Bitmap),
    Checkerboard {
        color0: Color,
        color1: Color,
        to_uv: Affine2,
    },
    /// A mesh attribute by name, times `scale`; zero off a mesh or on a mesh without it (the
    /// loaders refuse both).
    MeshAttribute {
        name: String,
        scale: f32,
    },
}

/// Where a texture is read: the surface coordinates, and on a mesh triangle what mesh
/// attributes need.
#[derive(Clone, Copy, Debug)]
pub struct TexPoint<'a> {
    pub uv: Vec2,
    pub mesh: Option<MeshPoint<'a>>,
}

/// A point on a mesh triangle: the mesh, the triangle's index in it and the barycentrics.
#[derive(Clone, Copy, Debug)]
pub struct MeshPoint<'a> {
    pub mesh: &'a crate::shape::TriangleMesh,
    pub triangle: u32,
    pub b: [f32; 3],
}

impl TexPoint<'_> {
    /// A point off any mesh (or where mesh attributes are not read).
    #[inline]
    pub fn uv(uv: Vec2) -> TexPoint<'static> {
        TexPoint { uv, mesh: None }
    }
}

impl Bitmap {
    /// Texel (x, y) as a colour (a one-channel image gives grey).
    #[inline]
    fn texel(&self, x: u32, y: u32) -> Color {
        let t = self.image.texel(x, y);
        if t.len() >= 3 { Color::new(t[0], t[1], t[2]) } else { Color::splat(t[0]) }
    }

    /// The four texels around `p` (in texel units, centres at integer + 0.5) and the bilinear
    /// weights: (f00, f10, f01, f11), (wx, wy).
    #[inline]
    fn corners(&self, p: Vec2) -> ([Color; 4], Vec2) {
        let (w, h) = (self.image.width, self.image.height);
        let q = p - Vec2::splat(0.5);
        let (fx, fy) = (q.x.floor(), q.y.floor());
        let (x0, y0) = (fx as i64, fy as i64);
        let wrap = |i: i64, n: u32| self.wrap.index(i, n);
        let (xa, xb, ya, yb) = (wrap(x0, w), wrap(x0 + 1, w), wrap(y0, h), wrap(y0 + 1, h));
        (
            [self.texel(xa, ya), self.texel(xb, ya), self.texel(xa, yb), self.texel(xb, yb)],
            Vec2::new(q.x - fx, q.y - fy),
        )
    }

    /// Position in texel units of surface coordinates `uv`.
    #[inline]
    fn texel_position(&self, uv: Vec2) -> Vec2 {
        let p = self.to_uv.transform_point2(uv);
        p * Vec2::new(self.image.width as f32, self.image.height as f32)
    }

    #[inline]
    pub fn eval(&self, uv: Vec2) -> Color {
        let p = self.texel_position(uv);
        // Coordinates far outside any sane range (or NaN) read the first texel.
        if !(p.x.abs() < 1e9 && p.y.abs() < 1e9) {
            return self.texel(0, 0);
        }
        match self.filter {
            Filter::Nearest => {
                let (w, h) = (self.image.width, self.image.height);
                self.texel(self.wrap.index(p.x.floor() as i64, w), self.wrap.index(p.y.floor() as i64, h))
            }
            Filter::Bilinear => {
                let ([f00, f10, f01, f11], t) = self.corners(p);
                let top = f00 * (1.0 - t.x) + f10 * t.x;
                let bottom = f01 * (1.0 - t.x) + f11 * t.x;
                top * (1.0 - t.y) + bottom * t.y
            }
        }
    }

    /// The scalar value at `uv` (luminance of colour texels) and its gradient in (u, v): the
    /// exact derivative of the bilinear interpolant (zero for nearest filtering), for bump maps.
    pub fn eval_1_grad(&self, uv: Vec2) -> (f32, Vec2) {
        let value = scalar_of(self.eval(uv), self.image.channels);
        if self.filter == Filter::Nearest {
            return (value, Vec2::ZERO);
        }
        let p = self.texel_position(uv);
        if !(p.x.abs() < 1e9 && p.y.abs() < 1e9) {
            return (value, Vec2::ZERO);
        }
        let (c, t) = self.corners(p);
        let [f00, f10, f01, f11] = c.map(|c| scalar_of(c, self.image.channels));
        let dx = (1.0 - t.y) * (f10 - f00) + t.y * (f11 - f01);
        let dy = (1.0 - t.x) * (f01 - f00) + t.x * (f11 - f10);
        // Chain rule through the texel scaling and to_uv (d p / d uv = res * M).
        let res = Vec2::new(self.image.width as f32, self.image.height as f32);
        let g = self.to_uv.matrix2.transpose() * (Vec2::new(dx, dy) * res);
        (value, g)
    }
}

/// A texel's scalar reading: one channel as it is, colour as luminance.
#[inline]
fn scalar_of(c: Color, channels: u32) -> f32 {
    if channels >= 3 { luminance(c) } else { c.r() }
}

/// The attribute `name` of the mesh at `p`, zero off a mesh or where the mesh lacks it.
#[inline]
fn attribute_at(name: &str, p: TexPoint<'_>) -> Color {
    let Some(m) = p.mesh else { return Color::ZERO };
    match m.mesh.attributes.iter().find(|a| a.name == name) {
        Some(a) => a.eval(&m.mesh.indices, m.triangle as usize, m.b),
        None => Color::ZERO,
    }
}

/// Which colour of a checkerboard covers `uv`: squares of 0.5, the lower half of each unit
/// square's u and v ranges (0.5 itself included) in `color0`'s pattern.
#[inline]
fn checker_is_color0(to_uv: &Affine2, uv: Vec2) -> bool {
    let p = to_uv.transform_point2(uv);
    let f = p - p.floor();
    (f.x > 0.5) == (f.y > 0.5)
}

impl Texture {
    /// The colour at surface coordinates `uv` (a mesh attribute reads zero: it needs `eval_at`).
    #[inline]
    pub fn eval(&self, uv: Vec2) -> Color {
        self.eval_at(TexPoint::uv(uv))
    }

    /// The colour at `p`.
    #[inline]
    pub fn eval_at(&self, p: TexPoint<'_>) -> Color {
        match self {
            Texture::Constant(c) => *c,
            Texture::Bitmap(b) => b.eval(p.uv),
            Texture::Checkerboard { color0, color1, to_uv } => {
                if checker_is_color0(to_uv, p.uv) {
                    *color0
                } else {
                    *color1
                }
            }
            Texture::MeshAttribute { name, scale } => attribute_at(name, p) * *scale,
        }
    }

    /// The scalar at `uv`, as Mitsuba's `eval_1` reads a texture given for a scalar parameter.
    #[inline]
    pub fn eval_1(&self, uv: Vec2) -> f32 {
        self.eval_1_at(TexPoint::uv(uv))
    }

    /// `eval_1` at `p`: a mesh attribute's first value (Mitsuba reads one-value attributes here).
    #[inline]
    pub fn eval_1_at(&self, p: TexPoint<'_>) -> f32 {
        match self {
            Texture::Constant(c) => c.mean(),
            Texture::Bitmap(b) => scalar_of(b.eval(p.uv), b.image.channels),
            // Mitsuba 3's eval_1 of a checkerboard has the colours the other way round.
            Texture::Checkerboard { color0, color1, to_uv } => {
                if checker_is_color0(to_uv, p.uv) {
                    color1.mean()
                } else {
                    color0.mean()
                }
            }
            Texture::MeshAttribute { name, scale } => attribute_at(name, p).r() * *scale,
        }
    }

    /// The mean colour over the texture's unit square (used to weigh sampling, as Mitsuba's
    /// `mean()`: a bitmap's mean texel, a checkerboard's two colours averaged).
    pub fn mean(&self) -> Color {
        match self {
            Texture::Constant(c) => *c,
            Texture::Bitmap(b) => {
                let img = &b.image;
                let n = (img.width as usize * img.height as usize).max(1);
                let mut sum = glam::DVec3::ZERO;
                for y in 0..img.height {
                    for x in 0..img.width {
                        sum += b.texel(x, y).as_dvec3();
                    }
                }
                Color::from_dvec3(sum / n as f64)
            }
            Texture::Checkerboard { color0, color1, .. } => (*color0 + *color1) * 0.5,
            // Unknown until a surface is named; grey for the uses of a mean (sampling weights).
            Texture::MeshAttribute { scale, .. } => Color::splat(0.5 * *scale),
        }
    }

    /// Width and height of a bitmap's image; `None` for textures without a resolution.
    pub fn resolution(&self) -> Option<(u32, u32)> {
        match self {
            Texture::Bitmap(b) => Some((b.image.width, b.image.height)),
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The 4 x 2 image of the Mitsuba check values in the notes: red channel texels
    /// row 0: 1.0, 0.0319, x, 0.305; row 1 chosen to give the documented means.
    fn image() -> Arc<TexImage> {
        // Rows top to bottom; one channel is enough for the addressing checks.
        let texels = vec![1.0, 0.5, 0.25, 0.125, 0.0, 0.75, 0.375, 0.0625];
        Arc::new(TexImage { width: 4, height: 2, channels: 1, texels })
    }

    fn bitmap(filter: Filter, wrap: Wrap) -> Bitmap {
        Bitmap { image: image(), filter, wrap, to_uv: Affine2::IDENTITY }
    }

    #[test]
    fn texel_centres_top_row_first_and_wrap_modes() {
        let b = bitmap(Filter::Bilinear, Wrap::Repeat);
        // The centre of texel (0, 0) is (0.125, 0.25): the top-left texel exactly.
        assert_eq!(b.eval(Vec2::new(0.125, 0.25)).r(), 1.0);
        assert_eq!(b.eval(Vec2::new(0.125, 0.75)).r(), 0.0);
        // Half-way between texels 0 and 1 of the top row.
        assert!((b.eval(Vec2::new(0.25, 0.25)).r() - 0.75).abs() < 1e-6);
        // u = 0 blends the first and the last column under repeat, and reads the first under
        // clamp and mirror.
        assert!((b.eval(Vec2::new(0.0, 0.25)).r() - 0.5625).abs() < 1e-6);
        for wrap in [Wrap::Clamp, Wrap::Mirror] {
            assert_eq!(bitmap(Filter::Bilinear, wrap).eval(Vec2::new(0.0, 0.25)).r(), 1.0);
        }
        // v = 1 under repeat blends the bottom and top rows; under clamp it is the bottom row.
        assert!((b.eval(Vec2::new(0.125, 1.0)).r() - 0.5).abs() < 1e-6);
        assert_eq!(bitmap(Filter::Bilinear, Wrap::Clamp).eval(Vec2::new(0.125, 1.0)).r(), 0.0);
        // Nearest reads the texel the point falls in; repeat wraps 2 to 0.
        let n = bitmap(Filter::Nearest, Wrap::Repeat);
        assert_eq!(n.eval(Vec2::new(0.3, 0.2)).r(), 0.5);
        assert_eq!(n.eval(Vec2::new(0.125, 1.0)).r(), 1.0);
        assert_eq!(n.eval(Vec2::new(-0.1, 0.2)).r(), 0.125);
        // Mirror indices: ... 1 0 | 0 1 2 3 | 3 2 ...
        let m = bitmap(Filter::Nearest, Wrap::Mirror);
        assert_eq!(m.eval(Vec2::new(-0.1, 0.2)).r(), 1.0);
        assert_eq!(m.eval(Vec2::new(1.1, 0.2)).r(), 0.125);
        assert_eq!(m.eval(Vec2::new(1.3, 0.2)).r(), 0.25);
        // Non-finite coordinates do not panic.
        assert_eq!(b.eval(Vec2::new(f32::NAN, 0.0)).r(), 1.0);
    }

    #[test]
    fn the_gradient_is_the_derivative_of_the_interpolant() {
        let b = Bitmap { to_uv: Affine2::from_scale(Vec2::new(1.7, 0.6)), ..bitmap(Filter::Bilinear, Wrap::Repeat) };
        for uv in [Vec2::new(0.3, 0.3), Vec2::new(0.61, 0.12), Vec2::new(0.9, 0.8)] {
            let (v, g) = b.eval_1_grad(uv);
            let h = 1e-3;
            let du = (b.eval(uv + Vec2::new(h, 0.0)).r() - b.eval(uv - Vec2::new(h, 0.0)).r()) / (2.0 * h);
            let dv = (b.eval(uv + Vec2::new(0.0, h)).r() - b.eval(uv - Vec2::new(0.0, h)).r()) / (2.0 * h);
            assert_eq!(v, b.eval(uv).r());
            assert!(
                (g.x - du).abs() < 1e-2 * (1.0 + du.abs()) && (g.y - dv).abs() < 1e-2 * (1.0 + dv.abs()),
                "{g} vs ({du}, {dv})"
            );
        }
    }

    #[test]
    fn checkerboard_squares_and_scalar_quirk() {
        let t = Texture::Checkerboard { color0: Color::ONE, color1: Color::ZERO, to_uv: Affine2::IDENTITY };
        assert_eq!(t.eval(Vec2::new(0.25, 0.25)), Color::ONE);
        assert_eq!(t.eval(Vec2::new(0.75, 0.25)), Color::ZERO);
        assert_eq!(t.eval(Vec2::new(0.5, 0.25)), Color::ONE);
        assert_eq!(t.eval(Vec2::new(-0.25, 0.25)), Color::ZERO);
        assert_eq!(t.eval(Vec2::new(0.75, 0.75)), Color::ONE);
        // eval_1 swaps the colours, as Mitsuba 3 does.
        assert_eq!(t.eval_1(Vec2::new(0.25, 0.25)), 0.0);
        assert!((Texture::Constant(Color::new(0.2, 0.5, 0.8)).eval_1(Vec2::ZERO) - 0.5).abs() < 1e-6);
    }
}
