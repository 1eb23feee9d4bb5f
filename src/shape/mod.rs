//! Geometric primitives. `Shape` is a closed set of small `Copy` structs: the BVH stores them
//! inline and intersection `match`es and forwards, with nothing allocated per ray.

pub mod mesh;
mod plane;
mod quad;
mod sphere;
mod triangle;

pub use mesh::TriangleMesh;
pub use plane::Plane;
pub use quad::{Quad, box_faces, intersect_quad, transformed_quad};
pub use sphere::Sphere;
pub use triangle::{RayShear, Triangle, intersect_triangle};

use crate::geometry::{Aabb, Ray, SurfaceParam};
use crate::math::Vec3;

/// What the BVH needs to know about a candidate hit; the full `Hit` is built only for the winner.
#[derive(Clone, Copy, Debug)]
pub struct PrimHit {
    pub t: f32,
    /// Shape-specific surface coordinates (barycentrics b1, b2 for triangles; (u, v) for quads).
    pub u: f32,
    pub v: f32,
}

/// Surface geometry at a hit: point, its error bound, geometric and shading normals, and the
/// surface's parameterisation there.
#[derive(Clone, Copy, Debug)]
pub struct SurfacePoint {
    pub p: Vec3,
    pub p_error: Vec3,
    pub ng: Vec3,
    pub ns: Vec3,
    pub param: SurfaceParam,
}

#[derive(Clone, Copy, Debug)]
pub enum Shape {
    Sphere(Sphere),
    Triangle(Triangle),
    Quad(Quad),
}

/// Only what intersection needs, 40 bytes: the BVH keeps these in leaf order so a leaf of four
/// primitives spans few cache lines; everything else about a primitive is read after the hit.
#[derive(Clone, Copy, Debug)]
pub enum CompactShape {
    Sphere(Sphere),
    Triangle([Vec3; 3]),
    /// Corner and two edges.
    Quad([Vec3; 3]),
}

impl CompactShape {
    #[inline(always)]
    pub fn intersect(&self, ray: &Ray, shear: &RayShear, t_max: f32) -> Option<PrimHit> {
        match self {
            CompactShape::Sphere(s) => s.intersect(ray, t_max),
            CompactShape::Triangle(p) => intersect_triangle(p, ray, shear, t_max),
            CompactShape::Quad([p0, e1, e2]) => intersect_quad(*p0, *e1, *e2, ray, t_max),
        }
    }
}

/// A shape with its material and, when it emits, its light: one element of the BVH. The light
/// index stays valid however the BVH reorders primitives.
#[derive(Clone, Copy, Debug)]
pub struct Primitive {
    pub shape: Shape,
    pub material: u32,
    /// Index of the light this primitive emits (`geometry::NO_LIGHT` for none).
    pub light: u32,
}

impl Shape {
    pub fn compact(&self) -> CompactShape {
        match self {
            Shape::Sphere(s) => CompactShape::Sphere(*s),
            Shape::Triangle(t) => CompactShape::Triangle(t.p),
            Shape::Quad(q) => CompactShape::Quad([q.p0, q.e1, q.e2]),
        }
    }

    #[inline]
    pub fn bounds(&self) -> Aabb {
        match self {
            Shape::Sphere(s) => s.bounds(),
            Shape::Triangle(t) => t.bounds(),
            Shape::Quad(q) => q.bounds(),
        }
    }

    #[inline(always)]
    pub fn intersect(&self, ray: &Ray, shear: &RayShear, t_max: f32) -> Option<PrimHit> {
        match self {
            Shape::Sphere(s) => s.intersect(ray, t_max),
            Shape::Triangle(t) => t.intersect(ray, shear, t_max),
            Shape::Quad(q) => q.intersect(ray, t_max),
        }
    }

    /// Surface data at a hit found by `intersect`. `meshes` supplies vertex normals and uv.
    #[inline]
    pub fn surface(&self, ray: &Ray, h: &PrimHit, meshes: &[TriangleMesh]) -> SurfacePoint {
        match self {
            Shape::Sphere(s) => s.surface(ray, h),
            Shape::Triangle(t) => t.surface(h, meshes),
            Shape::Quad(q) => q.surface(h),
        }
    }

    /// Surface area (used by area lights and photon emission).
    pub fn area(&self) -> f32 {
        match self {
            Shape::Sphere(s) => 4.0 * std::f32::consts::PI * s.radius * s.radius,
            Shape::Triangle(t) => t.area(),
            Shape::Quad(q) => q.area(),
        }
    }
}
