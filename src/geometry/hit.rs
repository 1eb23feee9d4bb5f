//! The full description of a ray-surface intersection, built once per closest hit: where, the
//! surface's parameterisation there, its normals and shading frame, and what it is made of.

use crate::math::{Frame, Vec2, Vec3};

/// No light: the value of `Hit::light` on surfaces that do not emit.
pub const NO_LIGHT: u32 = u32::MAX;

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
    /// Surface coordinates (Mitsuba's conventions per shape; see `shape`).
    pub uv: Vec2,
    /// Partial derivatives of the position with respect to u and v.
    pub dpdu: Vec3,
    pub dpdv: Vec3,
    /// Index into the scene's materials.
    pub material: u32,
    /// Index into the scene's lights of the light this surface emits, or `NO_LIGHT`.
    pub light: u32,
    /// Index of the primitive hit (BVH order), or `u32::MAX - i` for unbounded plane `i`.
    pub prim: u32,
}

impl Hit {
    /// True when the ray direction `d` arrives from the outward side of the surface.
    #[inline]
    pub fn is_front(&self, d: Vec3) -> bool {
        d.dot(self.ng) < 0.0
    }

    /// True when the surface emits light.
    #[inline]
    pub fn is_emitter(&self) -> bool {
        self.light != NO_LIGHT
    }

    /// The shading frame: z is the shading normal and x is dp/du made perpendicular to it (so
    /// anisotropic roughness and tangent-space maps follow the surface's parameterisation), or
    /// any perpendicular direction where dp/du vanishes or is parallel to the normal.
    #[inline]
    pub fn shading_frame(&self) -> Frame {
        Frame::from_z_x(self.ns, self.dpdu)
    }
}
