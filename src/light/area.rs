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
    /// Emits from the side (p1 - p0) x (p2 - p0) points to.
    Triangle([Vec3; 3]),
    /// Emits from the side its normal points to.
    Disk(Disk),
    /// Emits from the side its normals point to (outwards unless flipped).
    Cylinder(Cylinder),
}

/// A point sampled on an emitter's surface.
#[derive(Clone, Copy, Debug)]
pub struct SurfaceSample {
    pub p: Vec3,
    /// Conservative error bound of `p` (see `math::float`).
    pub p_error: Vec3,
    /// Unit normal on the emitting side.
    pub n: Vec3,
}

impl Emitter {
    /// The shape to put in the BVH for this surface.
    pub fn shape(&self) -> Shape {
        match *self {
            Emitter::Quad(q) => Shape::Quad(q),
            Emitter::Sphere(s) => Shape::Sphere(s),
            Emitter::Triangle([p0, p1, p2]) => Shape::Triangle(Triangle::new(p0, p1, p2)),
            Emitter::Disk(d) => Shape::Disk(d),
            Emitter::Cylinder(c) => Shape::Cylinder(c),
        }
    }

    pub fn area(&self) -> f32 {
        match self {
            Emitter::Quad(q) => q.area(),
            Emitter::Sphere(s) => 4.0 * PI * s.radius * s.radius,
            Emitter::Triangle([p0, p1, p2]) => 0.5 * (*p1 - *p0).cross(*p2 - *p0).length(),
            Emitter::Disk(d) => d.area(),
            Emitter::Cylinder(c) => c.area(),
        }
    }

    /// A uniformly distributed point on the surface (density 1 / area).
    pub fn sample_area(&self, u: Vec2) -> SurfaceSample {
        match self {
            Emitter::Quad(q) => {
                let (a, b) = (q.e1 * u.x, q.e2 * u.y);
                SurfaceSample { p: q.p0 + a + b, p_error: gamma(6) * (q.p0.abs() + a.abs() + b.abs()), n: q.n }
            }
            Emitter::Sphere(s) => {
                let n = uniform_sphere(u);
                let local = n * s.radius;
                let p = s.center + local;
                SurfaceSample { p, p_error: gamma(5) * local.abs() + gamma(1) * p.abs(), n }
            }
            Emitter::Triangle([p0, p1, p2]) => {
                // Uniform barycentrics by the square-root warp (pbrt-v4 SampleUniformTriangle).
                let su = u.x.sqrt();
                let (b0, b1) = (1.0 - su, u.y * su);
                let b2 = 1.0 - b0 - b1;
                let p = *p0 * b0 + *p1 * b1 + *p2 * b2;
                let p_error = gamma(7) * ((*p0 * b0).abs() + (*p1 * b1).abs() + (*p2 * b2).abs());
                SurfaceSample { p, p_error, n: (*p1 - *p0).cross(*p2 - *p0).normalize_or_zero() }
            }
            Emitter::Disk(d) => {
                let s = d.sample_area(u);
                SurfaceSample { p: s.p, p_error: s.p_error, n: s.n }
            }
            Emitter::Cylinder(c) => {
                let s = c.sample_area(u);
                SurfaceSample { p: s.p, p_error: s.p_error, n: s.n }
            }
        }
    }

    /// A point for shading point `p`: (surface sample, solid-angle pdf). Quads and triangles are
    /// sampled by area; spheres by the cone they subtend (uniform in solid angle).
    #[inline]
    pub fn sample_towards(&self, p: Vec3, u: Vec2) -> Option<(SurfaceSample, f32)> {
        match self {
            Emitter::Quad(_) | Emitter::Triangle(_) | Emitter::Disk(_) | Emitter::Cylinder(_) => {
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
                Some((SurfaceSample { p: x, p_error, n }, 1.0 / (2.0 * PI * (1.0 - cos_max))))
            }
        }
    }

    /// Density of `sample_towards` for the point `q` (normal `n`) seen from `p` along `wi`.
    #[inline]
    pub fn pdf_towards(&self, p: Vec3, q: Vec3, n: Vec3, wi: Vec3) -> f32 {
        match self {
            Emitter::Quad(_) | Emitter::Triangle(_) | Emitter::Disk(_) | Emitter::Cylinder(_) => {
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
