//! A ray `o + t d`. Directions are unit length wherever the renderer creates them.

use crate::math::Vec3;
use crate::math::float::offset_ray_origin;

/// No participating medium: what every ray travels through until media land (the slot is
/// there so that adding them is an addition, not a change of every ray).
pub const NO_MEDIUM: u32 = u32::MAX;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    pub o: Vec3,
    pub d: Vec3,
    /// The participating medium the ray travels through (an index into the scene's media), or
    /// `NO_MEDIUM`.
    pub medium: u32,
}

impl Ray {
    #[inline]
    pub fn new(o: Vec3, d: Vec3) -> Self {
        Ray { o, d, medium: NO_MEDIUM }
    }

    #[inline]
    pub fn at(&self, t: f32) -> Vec3 {
        self.o + self.d * t
    }

    /// A ray leaving a surface point: the origin is pushed outside the point's error bound on the
    /// side `d` leaves towards (`ng` is the geometric normal), then `bias` further along `d`
    /// (the seed report's ray bias; the scene may set it, 0 disables it).
    #[inline(always)]
    pub fn spawn(p: Vec3, p_error: Vec3, ng: Vec3, d: Vec3, bias: f32) -> Self {
        let o = offset_ray_origin(p, p_error, ng, d) + d * bias;
        Ray { o, d, medium: NO_MEDIUM }
    }
}

/// Where a ray starts off a surface: the point, its error bound and the geometric normal (a hit,
/// a point sampled on a light, or a camera's lens point with no error).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RayOrigin {
    pub p: Vec3,
    pub p_error: Vec3,
    pub ng: Vec3,
}

impl RayOrigin {
    /// A ray leaving the origin in direction `d` (see `Ray::spawn`).
    #[inline(always)]
    pub fn spawn(&self, d: Vec3, bias: f32) -> Ray {
        Ray::spawn(self.p, self.p_error, self.ng, d, bias)
    }
}
