//! The full description of a ray-surface intersection, built once per closest hit.

use crate::math::Vec3;

#[derive(Clone, Copy, Debug)]
pub struct Hit {
    /// Ray parameter of the hit.
    pub t: f32,
    /// Hit point.
    pub p: Vec3,
    /// Conservative absolute error bound of `p`, per axis (see `math::float`).
    pub p_error: Vec3,
    /// Geometric normal, unit length, on the shape's outward side (not flipped towards the ray).
    pub ng: Vec3,
    /// Shading normal (interpolated for smooth meshes), in the same hemisphere as `ng`.
    pub ns: Vec3,
    /// Index into the scene's materials.
    pub material: u32,
    /// Index of the primitive hit (BVH order), or `u32::MAX - i` for unbounded plane `i`.
    pub prim: u32,
}

impl Hit {
    /// True when the ray direction `d` arrives from the outward side of the surface.
    #[inline]
    pub fn is_front(&self, d: Vec3) -> bool {
        d.dot(self.ng) < 0.0
    }
}
