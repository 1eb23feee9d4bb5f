//! The full description of a ray-surface intersection, built once per closest hit: where, the
//! surface's parameterisation there, its normals and shading frame, and what it is made of.

use crate::math::{Frame, Vec2, Vec3};

/// No light: the value of `Hit::light` on surfaces that do not emit.
pub const NO_LIGHT: u32 = u32::MAX;

/// A hit's parameterisation: surface coordinates (u, v) and the derivatives dp/du, dp/dv, or
/// what they are computed from when that costs more than the rest of the hit. A sphere's uv
/// needs an arc tangent and an arc cosine and its dp/dv a square root, which most shading never
/// asks for (textures and bump maps do), so they are worked out on request.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SurfaceParam {
    Known {
        uv: Vec2,
        dpdu: Vec3,
        dpdv: Vec3,
    },
    /// On a sphere of this radius with this unit outward normal: u = phi / 2 pi (phi from +x
    /// towards +y, in [0, 2 pi)), v = theta / pi from the +z pole (Mitsuba's `sphere`).
    Sphere {
        n: Vec3,
        radius: f32,
    },
}

impl SurfaceParam {
    #[inline]
    pub fn uv(&self) -> Vec2 {
        match *self {
            SurfaceParam::Known { uv, .. } => uv,
            SurfaceParam::Sphere { n, .. } => {
                let mut phi = n.y.atan2(n.x);
                if phi < 0.0 {
                    phi += std::f32::consts::TAU;
                }
                let theta = n.z.clamp(-1.0, 1.0).acos();
                Vec2::new(phi / std::f32::consts::TAU, theta / std::f32::consts::PI)
            }
        }
    }

    #[inline]
    pub fn dpdu(&self) -> Vec3 {
        match *self {
            SurfaceParam::Known { dpdu, .. } => dpdu,
            SurfaceParam::Sphere { n, radius } => Vec3::new(-n.y, n.x, 0.0) * (std::f32::consts::TAU * radius),
        }
    }

    /// For a sphere without trigonometry: cos phi = x / rho, sin phi = y / rho, rho = sin theta.
    #[inline]
    pub fn dpdv(&self) -> Vec3 {
        match *self {
            SurfaceParam::Known { dpdv, .. } => dpdv,
            SurfaceParam::Sphere { n, radius } => {
                let rho = (n.x * n.x + n.y * n.y).sqrt();
                let scale = std::f32::consts::PI * radius;
                // At the poles phi is undefined; any direction in the tangent plane will do.
                if rho > 0.0 {
                    Vec3::new(n.x * n.z / rho, n.y * n.z / rho, -rho) * scale
                } else {
                    Vec3::new(n.z, 0.0, 0.0) * scale
                }
            }
        }
    }
}

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
    /// Surface coordinates (Mitsuba's conventions per shape; see `shape`) and the partial
    /// derivatives of the position with respect to them: read with `uv()`, `dpdu()`, `dpdv()`.
    pub param: SurfaceParam,
    /// Index into the scene's materials.
    pub material: u32,
    /// Index into the scene's lights of the light this surface emits, or `NO_LIGHT`.
    pub light: u32,
    /// Index of the primitive hit (BVH order, planes included; in its group's BVH for an
    /// instanced one).
    pub prim: u32,
}

impl Hit {
    /// Where rays leaving the hit start from.
    #[inline(always)]
    pub fn origin(&self) -> crate::geometry::RayOrigin {
        crate::geometry::RayOrigin { p: self.p, p_error: self.p_error, ng: self.ng }
    }

    /// A ray leaving the hit point in direction `d`, off the surface (outside the point's error
    /// bound, on the side `d` leaves towards) and `bias` further along `d` (the seed report's
    /// ray bias: `IntegratorDesc::ray_bias`).
    #[inline(always)]
    pub fn spawn(&self, d: Vec3, bias: f32) -> crate::geometry::Ray {
        crate::geometry::Ray::spawn(self.p, self.p_error, self.ng, d, bias)
    }

    /// True when the ray direction `d` arrives from the outward side of the surface.
    #[inline]
    pub fn is_front(&self, d: Vec3) -> bool {
        d.dot(self.ng) < 0.0
    }

    /// The surface coordinates at the hit.
    #[inline]
    pub fn uv(&self) -> Vec2 {
        self.param.uv()
    }

    /// dp/du at the hit.
    #[inline]
    pub fn dpdu(&self) -> Vec3 {
        self.param.dpdu()
    }

    /// dp/dv at the hit.
    #[inline]
    pub fn dpdv(&self) -> Vec3 {
        self.param.dpdv()
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
        Frame::from_z_x(self.ns, self.dpdu())
    }
}
