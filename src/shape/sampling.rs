//! Sampling points on shapes, for the shapes that emit (area lights) and the methods that start
//! paths on them: uniformly by area (quads, triangles, disks, cylinders), or for spheres by the
//! cone of directions they subtend from a shading point. Every sampled point carries the error
//! bound of its position, so rays leaving it start off the surface.

use super::{Shape, SurfaceSample};
use crate::math::float::gamma;
use crate::math::{Frame, Vec2, Vec3};
use crate::sampling::warp::{uniform_cone, uniform_sphere};
use std::f32::consts::PI;

impl Shape {
    /// Surface area (infinite for a plane).
    pub fn area(&self) -> f32 {
        match self {
            Shape::Sphere(s) => 4.0 * PI * s.radius * s.radius,
            Shape::Triangle(t) => t.area(),
            Shape::Quad(q) => q.area(),
            Shape::Disk(d) => d.area(),
            Shape::Cylinder(c) => c.area(),
            Shape::Plane(_) => f32::INFINITY,
            // Never an emitter (the loaders refuse it): no area to sample.
            Shape::SdfVoxel(_) => 0.0,
        }
    }

    /// A uniformly distributed point on the surface (density 1 / area); `None` for a plane,
    /// which has no finite area to spread points over.
    pub fn sample_area(&self, u: Vec2) -> Option<SurfaceSample> {
        Some(match self {
            Shape::Quad(q) => quad_sample(q, u),
            Shape::Sphere(s) => {
                let n = uniform_sphere(u);
                let local = n * s.radius;
                let p = s.center + local;
                let uv = s.param(n).uv();
                SurfaceSample { p, p_error: gamma(5) * local.abs() + gamma(1) * p.abs(), n, uv }
            }
            Shape::Triangle(t) => triangle_sample(t, u),
            Shape::Disk(d) => d.sample_area(u),
            Shape::Cylinder(c) => c.sample_area(u),
            Shape::Plane(_) | Shape::SdfVoxel(_) => return None,
        })
    }

    /// A point for shading point `p`: (surface sample, solid-angle density). Spheres are
    /// sampled by the cone they subtend (uniform in solid angle), every other finite shape by
    /// area; `None` when `p` sees the sampled point from behind or nothing can be sampled.
    ///
    /// Quads and triangles, the common emitters, are sampled inline: through a call, the sample
    /// came back through memory and its first loads waited on the stores just before them.
    #[inline(always)]
    pub fn sample_towards(&self, p: Vec3, u: Vec2) -> Option<(SurfaceSample, f32)> {
        match self {
            Shape::Quad(q) => by_area(quad_sample(q, u), q.area(), p),
            Shape::Triangle(t) => by_area(triangle_sample(t, u), t.area(), p),
            Shape::Sphere(_) | Shape::Disk(_) | Shape::Cylinder(_) | Shape::Plane(_) | Shape::SdfVoxel(_) => {
                self.sample_towards_other(p, u)
            }
        }
    }

    /// `sample_towards` for the shapes it does not sample inline.
    #[inline(never)]
    fn sample_towards_other(&self, p: Vec3, u: Vec2) -> Option<(SurfaceSample, f32)> {
        match self {
            Shape::Quad(_)
            | Shape::Triangle(_)
            | Shape::Disk(_)
            | Shape::Cylinder(_)
            | Shape::Plane(_)
            | Shape::SdfVoxel(_) => by_area(self.sample_area(u)?, self.area(), p),
            Shape::Sphere(sphere) => {
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
            Shape::Quad(_)
            | Shape::Triangle(_)
            | Shape::Disk(_)
            | Shape::Cylinder(_)
            | Shape::Plane(_)
            | Shape::SdfVoxel(_) => {
                let cos = n.dot(-wi);
                if !(cos > 0.0 && self.area() > 0.0) {
                    return 0.0;
                }
                (q - p).length_squared() / (cos * self.area())
            }
            Shape::Sphere(s) => {
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

/// A uniform point on a quad.
#[inline(always)]
fn quad_sample(q: &super::Quad, u: Vec2) -> SurfaceSample {
    let (a, b) = (q.e1 * u.x, q.e2 * u.y);
    let p_error = gamma(6) * (q.p0.abs() + a.abs() + b.abs());
    SurfaceSample { p: q.p0 + a + b, p_error, n: q.n, uv: u }
}

/// A uniform point on a triangle: barycentrics by the square-root warp (pbrt-v4
/// SampleUniformTriangle).
#[inline(always)]
fn triangle_sample(t: &super::Triangle, u: Vec2) -> SurfaceSample {
    let [p0, p1, p2] = t.p;
    let su = u.x.sqrt();
    let (b0, b1) = (1.0 - su, u.y * su);
    let b2 = 1.0 - b0 - b1;
    let p = p0 * b0 + p1 * b1 + p2 * b2;
    let p_error = gamma(7) * ((p0 * b0).abs() + (p1 * b1).abs() + (p2 * b2).abs());
    let n = (p1 - p0).cross(p2 - p0).normalize_or_zero();
    SurfaceSample { p, p_error, n, uv: Vec2::new(b1, b2) }
}

/// A point `s` sampled uniformly on a surface of `area`, with its solid-angle density seen from
/// `p`; `None` when `p` sees it from behind.
#[inline(always)]
fn by_area(s: SurfaceSample, area: f32, p: Vec3) -> Option<(SurfaceSample, f32)> {
    let v = s.p - p;
    let d2 = v.length_squared();
    let cos = s.n.dot(-v) / d2.sqrt();
    if !(cos > 0.0) {
        return None;
    }
    Some((s, d2 / (cos * area)))
}
