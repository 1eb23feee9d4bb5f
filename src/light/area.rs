//! The surfaces of area lights: a copy of the emitting primitive's shape, sampled by area (quads
//! and triangles) or by the solid angle it subtends (spheres), with the error bounds of the
//! sampled points so rays leaving them start off the surface.

use crate::math::float::gamma;
use crate::math::{Frame, Vec2, Vec3};
use crate::sampling::warp::{uniform_cone, uniform_sphere};
use crate::shape::{Cylinder, Disk, Quad, Shape, Sphere, Triangle};
use std::f32::consts::PI;

/// The surface of an area light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Emitter {
    /// Emits from its front side (the side e1 x e2 points to).
    Quad(Quad),
    /// Emits outwards.
    Sphere(Sphere),
    /// Emits from the side (p1 - p0) x (p2 - p0) points to; `uv` are the vertices' texture
    /// coordinates (`TRIANGLE_UV` when the mesh has none: uv = the barycentrics (b1, b2)).
    Triangle { p: [Vec3; 3], uv: [Vec2; 3] },
    /// Emits from the side its normal points to.
    Disk(Disk),
    /// Emits from the side its normals point to (outwards unless flipped).
    Cylinder(Cylinder),
}

/// Texture coordinates of a triangle without them, as Mitsuba gives: uv = (b1, b2).
pub const TRIANGLE_UV: [Vec2; 3] = [Vec2::ZERO, Vec2::X, Vec2::Y];

/// A point sampled on an emitter's surface.
#[derive(Clone, Copy, Debug)]
pub struct SurfaceSample {
    pub p: Vec3,
    /// Conservative error bound of `p` (see `math::float`).
    pub p_error: Vec3,
    /// Unit normal on the emitting side.
    pub n: Vec3,
    /// The shape's own surface coordinates of `p`, as a ray hitting `p` reports them (`Hit::uv`;
    /// for a triangle its barycentrics (b1, b2)); `texture_uv` turns them into texture
    /// coordinates.
    pub uv: Vec2,
}

impl Emitter {
    /// The shape to put in the BVH for this surface.
    pub fn shape(&self) -> Shape {
        match *self {
            Emitter::Quad(q) => Shape::Quad(q),
            Emitter::Sphere(s) => Shape::Sphere(s),
            Emitter::Triangle { p: [p0, p1, p2], .. } => Shape::Triangle(Triangle::new(p0, p1, p2)),
            Emitter::Disk(d) => Shape::Disk(d),
            Emitter::Cylinder(c) => Shape::Cylinder(c),
        }
    }

    pub fn area(&self) -> f32 {
        match self {
            Emitter::Quad(q) => q.area(),
            Emitter::Sphere(s) => 4.0 * PI * s.radius * s.radius,
            Emitter::Triangle { p: [p0, p1, p2], .. } => 0.5 * (*p1 - *p0).cross(*p2 - *p0).length(),
            Emitter::Disk(d) => d.area(),
            Emitter::Cylinder(c) => c.area(),
        }
    }

    /// Texture coordinates of the surface point whose own coordinates are `uv` (`Hit::uv` of a
    /// hit on this emitter's shape, or `SurfaceSample::uv`): the vertices' coordinates
    /// interpolated on a triangle, `uv` itself on every other shape.
    #[inline]
    pub fn texture_uv(&self, uv: Vec2) -> Vec2 {
        match self {
            Emitter::Triangle { uv: t, .. } => t[0] * (1.0 - uv.x - uv.y) + t[1] * uv.x + t[2] * uv.y,
            _ => uv,
        }
    }

    /// A uniformly distributed point on the surface (density 1 / area).
    pub fn sample_area(&self, u: Vec2) -> SurfaceSample {
        match self {
            Emitter::Quad(q) => {
                let (a, b) = (q.e1 * u.x, q.e2 * u.y);
                let p_error = gamma(6) * (q.p0.abs() + a.abs() + b.abs());
                SurfaceSample { p: q.p0 + a + b, p_error, n: q.n, uv: u }
            }
            Emitter::Sphere(s) => {
                let n = uniform_sphere(u);
                let local = n * s.radius;
                let p = s.center + local;
                let uv = s.param(n).uv();
                SurfaceSample { p, p_error: gamma(5) * local.abs() + gamma(1) * p.abs(), n, uv }
            }
            Emitter::Triangle { p: [p0, p1, p2], .. } => {
                // Uniform barycentrics by the square-root warp (pbrt-v4 SampleUniformTriangle).
                let su = u.x.sqrt();
                let (b0, b1) = (1.0 - su, u.y * su);
                let b2 = 1.0 - b0 - b1;
                let p = *p0 * b0 + *p1 * b1 + *p2 * b2;
                let p_error = gamma(7) * ((*p0 * b0).abs() + (*p1 * b1).abs() + (*p2 * b2).abs());
                let n = (*p1 - *p0).cross(*p2 - *p0).normalize_or_zero();
                SurfaceSample { p, p_error, n, uv: Vec2::new(b1, b2) }
            }
            Emitter::Disk(d) => {
                let s = d.sample_area(u);
                SurfaceSample { p: s.p, p_error: s.p_error, n: s.n, uv: s.uv }
            }
            Emitter::Cylinder(c) => {
                let s = c.sample_area(u);
                SurfaceSample { p: s.p, p_error: s.p_error, n: s.n, uv: s.uv }
            }
        }
    }

    /// A point for shading point `p`: (surface sample, solid-angle pdf). Quads and triangles are
    /// sampled by area; spheres by the cone they subtend (uniform in solid angle).
    #[inline]
    pub fn sample_towards(&self, p: Vec3, u: Vec2) -> Option<(SurfaceSample, f32)> {
        match self {
            Emitter::Quad(_) | Emitter::Triangle { .. } | Emitter::Disk(_) | Emitter::Cylinder(_) => {
                let s = self.sample_area(u);
                let v = s.p - p;
                let d2 = v.length_squared();
                let cos = s.n.dot(-v) / d2.sqrt();
                if !(cos > 0.0) {
                    return None;
                }
                Some((s, d2 / (cos * self.area())))
            }
            Emitter::Sphere(sphere) => {
                let to_c = sphere.center - p;
                let dc2 = to_c.length_squared();
                let r2 = sphere.radius * sphere.radius;
                if dc2 <= r2 * 1.0001 {
                    return None;
                }
                let dc = dc2.sqrt();
                let sin2_max = r2 / dc2;
                let cos_max = (1.0 - sin2_max).max(0.0).sqrt();
                let frame = Frame::from_z(to_c / dc);
                let dir = frame.to_world(uniform_cone(u, cos_max));
                // Where the direction meets the sphere (nearest root; grazing rounds to tangent).
                let b = dir.dot(to_c);
                let disc = (b * b - (dc2 - r2)).max(0.0);
                let t = b - disc.sqrt();
                let x = p + dir * t;
                let n = (x - sphere.center).normalize();
                let p_error = gamma(5) * (x - sphere.center).abs() + gamma(1) * x.abs();
                let uv = sphere.param(n).uv();
                Some((SurfaceSample { p: x, p_error, n, uv }, 1.0 / (2.0 * PI * (1.0 - cos_max))))
            }
        }
    }

    /// Density of `sample_towards` for the point `q` (normal `n`) seen from `p` along `wi`.
    #[inline]
    pub fn pdf_towards(&self, p: Vec3, q: Vec3, n: Vec3, wi: Vec3) -> f32 {
        match self {
            Emitter::Quad(_) | Emitter::Triangle { .. } | Emitter::Disk(_) | Emitter::Cylinder(_) => {
                let cos = n.dot(-wi);
                if cos <= 0.0 {
                    return 0.0;
                }
                (q - p).length_squared() / (cos * self.area())
            }
            Emitter::Sphere(s) => {
                let dc2 = (s.center - p).length_squared();
                let r2 = s.radius * s.radius;
                if dc2 <= r2 * 1.0001 {
                    return 0.0;
                }
                let cos_max = (1.0 - r2 / dc2).max(0.0).sqrt();
                1.0 / (2.0 * PI * (1.0 - cos_max))
            }
        }
    }
}
