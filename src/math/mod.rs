//! Vector types (re-exported from glam), colours, orthonormal frames and small helpers.

mod color;
pub mod float;

pub use color::{Color, PackedColor, PackedLanes};
pub use glam::{Vec2, Vec3, Vec3A};

/// Relative luminance of a linear sRGB colour (Rec. 709 weights).
#[inline]
pub fn luminance(c: Color) -> f32 {
    0.2126 * c.r() + 0.7152 * c.g() + 0.0722 * c.b()
}

/// An orthonormal basis whose `z` axis is a given unit normal; used to map local sample
/// directions (z up) into world space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    pub x: Vec3,
    pub y: Vec3,
    pub z: Vec3,
}

impl Frame {
    /// Builds a frame around unit vector `n` without branches on its orientation
    /// (Duff et al. 2017, "Building an orthonormal basis, revisited").
    pub fn from_z(n: Vec3) -> Self {
        let sign = 1.0f32.copysign(n.z);
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        let x = Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
        let y = Vec3::new(b, sign + n.y * n.y * a, -n.y);
        Frame { x, y, z: n }
    }

    /// A frame around unit `n` whose x axis is `t` made perpendicular to `n` (Gram-Schmidt);
    /// falls back to `from_z` when `t` is zero, not finite or parallel to `n`.
    #[inline(always)]
    pub fn from_z_x(n: Vec3, t: Vec3) -> Self {
        let x = t - n * n.dot(t);
        let len2 = x.length_squared();
        if !(len2 > 1e-12 * t.length_squared()) || !len2.is_finite() {
            return Self::from_z(n);
        }
        let x = x / len2.sqrt();
        Frame { x, y: n.cross(x), z: n }
    }

    /// The same frame seen from the other side: z reversed, x kept, y reversed (right-handed).
    #[inline]
    pub fn flipped(&self) -> Self {
        Frame { x: self.x, y: -self.y, z: -self.z }
    }

    #[inline]
    pub fn to_world(&self, v: Vec3) -> Vec3 {
        self.x * v.x + self.y * v.y + self.z * v.z
    }

    #[inline]
    pub fn to_local(&self, v: Vec3) -> Vec3 {
        Vec3::new(v.dot(self.x), v.dot(self.y), v.dot(self.z))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_is_orthonormal_for_any_normal() {
        for n in [
            Vec3::Z,
            -Vec3::Z,
            Vec3::X,
            Vec3::new(0.3, -0.4, 0.866).normalize(),
            Vec3::new(1e-7, 0.0, -1.0).normalize(),
        ] {
            let f = Frame::from_z(n);
            assert!((f.x.length() - 1.0).abs() < 1e-5);
            assert!((f.y.length() - 1.0).abs() < 1e-5);
            assert!(f.x.dot(f.y).abs() < 1e-5);
            assert!(f.x.dot(n).abs() < 1e-5);
            assert!(f.y.dot(n).abs() < 1e-5);
            let v = Vec3::new(0.2, -0.5, 0.7);
            assert!(f.to_local(f.to_world(v)).abs_diff_eq(v, 1e-5));
            // Built from a tangent: x follows it, and the frame is right-handed.
            let t = Vec3::new(1.0, 2.0, -0.5);
            let g = Frame::from_z_x(n, t);
            assert!(g.x.dot(t) > 0.0 && g.x.dot(n).abs() < 1e-5 && (g.x.length() - 1.0).abs() < 1e-5);
            assert!(g.x.cross(g.y).abs_diff_eq(g.z, 1e-5));
            let h = g.flipped();
            assert!(h.x.cross(h.y).abs_diff_eq(h.z, 1e-5) && h.z.abs_diff_eq(-n, 1e-6));
            // A tangent along the normal falls back to an arbitrary frame.
            let k = Frame::from_z_x(n, n * 3.0);
            assert!(k.x.dot(n).abs() < 1e-5 && (k.x.length() - 1.0).abs() < 1e-5);
        }
    }
}
