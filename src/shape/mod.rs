//! Geometric primitives. `Shape` is a closed set of small `Copy` structs: the BVH stores them
//! inline and intersection `match`es and forwards, with nothing allocated per ray.

mod cylinder;
mod disk;
pub mod mesh;
mod plane;
mod primitives;
mod quad;
mod sampling;
pub mod sdf;
mod sphere;
mod triangle;

pub use cylinder::{Cylinder, intersect_cylinder};
pub use disk::{Disk, intersect_disk};
pub use mesh::TriangleMesh;
pub use plane::{Plane, intersect_plane};
pub use primitives::Primitives;
pub use quad::{Quad, box_faces, intersect_quad, transformed_quad};
pub use sphere::Sphere;
pub use triangle::{RayShear, Triangle, intersect_triangle};

use crate::geometry::{Aabb, Ray, SurfaceParam};
use crate::math::{Vec2, Vec3};

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

/// A point sampled on a shape's surface (for emitting shapes: `Shape::sample_area`,
/// `Shape::sample_towards`).
#[derive(Clone, Copy, Debug)]
pub struct SurfaceSample {
    pub p: Vec3,
    /// Conservative error bound of `p` (see `math::float`).
    pub p_error: Vec3,
    /// Unit normal there, on the side the shape's normals point to (the side it emits from).
    pub n: Vec3,
    /// The surface coordinates a hit at `p` reports (`SurfacePoint::param`'s uv; a triangle's
    /// barycentrics (b1, b2)).
    pub uv: Vec2,
}

/// Texture coordinates of a triangle's vertices when it has none of its own, as Mitsuba gives
/// them: the point with barycentrics (b0, b1, b2) reads uv = (b1, b2).
pub const TRIANGLE_UV: [Vec2; 3] = [Vec2::ZERO, Vec2::X, Vec2::Y];

/// A geometric primitive: the one list of shape kinds. Finite shapes are built into the BVH;
/// planes, which have no bounds, are kept beside its tree and tested with every ray.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Shape {
    Sphere(Sphere),
    Triangle(Triangle),
    Quad(Quad),
    Disk(Disk),
    Cylinder(Cylinder),
    Plane(Plane),
    /// One voxel of a signed distance grid, in the grid's index space (see `sdf`).
    SdfVoxel(sdf::SdfVoxel),
}

/// Only what intersection needs, 40 bytes: the BVH keeps these in leaf order so a leaf of four
/// primitives spans few cache lines; everything else about a primitive is read after the hit.
#[derive(Clone, Copy, Debug)]
pub enum CompactShape {
    Sphere(Sphere),
    Triangle([Vec3; 3]),
    /// Corner and two edges.
    Quad([Vec3; 3]),
    /// Centre and the two axes.
    Disk([Vec3; 3]),
    Cylinder {
        p0: Vec3,
        axis: Vec3,
        radius: f32,
    },
    /// A point on the plane and its unit normal.
    Plane([Vec3; 2]),
    SdfVoxel(sdf::SdfVoxel),
}

impl CompactShape {
    /// Calls `f` for every crossing of the surface in (0, t_max) until it returns false (then
    /// returns false). Only a cylinder's first crossing is found (see `crossings_enumerable`).
    #[inline(always)]
    pub fn for_each_crossing(&self, ray: &Ray, shear: &RayShear, t_max: f32, f: impl FnMut(PrimHit) -> bool) -> bool {
        match self {
            CompactShape::Sphere(s) => s.for_each_crossing(ray, t_max, f),
            // One crossing at most (a cylinder's later one is not found: see above).
            // One crossing at most of a voxel's surface is found too: the first root.
            CompactShape::Triangle(_)
            | CompactShape::Quad(_)
            | CompactShape::Disk(_)
            | CompactShape::Cylinder { .. }
            | CompactShape::Plane(_)
            | CompactShape::SdfVoxel(_) => self.intersect(ray, shear, t_max).is_none_or(f),
        }
    }

    /// True for shapes whose test reads the ray's `RayShear` (a traversal meeting none skips
    /// making it).
    pub fn uses_shear(&self) -> bool {
        match self {
            CompactShape::Triangle(_) => true,
            CompactShape::Sphere(_)
            | CompactShape::Quad(_)
            | CompactShape::Disk(_)
            | CompactShape::Cylinder { .. }
            | CompactShape::Plane(_)
            | CompactShape::SdfVoxel(_) => false,
        }
    }

    /// False for shapes a ray can cross more than once that `for_each_crossing` does not walk.
    pub fn crossings_enumerable(&self) -> bool {
        match self {
            CompactShape::Cylinder { .. } | CompactShape::SdfVoxel(_) => false,
            CompactShape::Sphere(_)
            | CompactShape::Triangle(_)
            | CompactShape::Quad(_)
            | CompactShape::Disk(_)
            | CompactShape::Plane(_) => true,
        }
    }

    #[inline(always)]
    pub fn intersect(&self, ray: &Ray, shear: &RayShear, t_max: f32) -> Option<PrimHit> {
        match self {
            CompactShape::Sphere(s) => s.intersect(ray, t_max),
            CompactShape::Triangle(p) => intersect_triangle(p, ray, shear, t_max),
            CompactShape::Quad([p0, e1, e2]) => intersect_quad(*p0, *e1, *e2, ray, t_max),
            CompactShape::Disk([c, a, b]) => intersect_disk(*c, *a, *b, ray, t_max),
            CompactShape::Cylinder { p0, axis, radius } => intersect_cylinder(*p0, *axis, *radius, ray, t_max),
            CompactShape::Plane([point, normal]) => intersect_plane(*point, *normal, ray, t_max),
            CompactShape::SdfVoxel(v) => v.intersect(ray, t_max),
        }
    }

    /// `intersect` for the shapes a BVH keeps outside its tree (planes: `Shape::is_bounded`),
    /// from a call site of their own: the general one's dispatch, switching between a leaf's
    /// shapes and a plane on every ray, mispredicted (ten times the indirect mispredicts on the
    /// Whitted benchmark).
    #[inline(always)]
    pub fn intersect_unbounded(&self, ray: &Ray, t_max: f32) -> Option<PrimHit> {
        if let CompactShape::Plane([point, normal]) = self {
            intersect_plane(*point, *normal, ray, t_max)
        } else {
            self.intersect_other_unbounded(ray, t_max)
        }
    }

    /// (No unbounded shape but the plane exists: out of line, so the plane's test stays small
    /// enough to inline.)
    #[cold]
    #[inline(never)]
    fn intersect_other_unbounded(&self, ray: &Ray, t_max: f32) -> Option<PrimHit> {
        self.intersect(ray, &RayShear::new(ray), t_max)
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
            Shape::Disk(d) => CompactShape::Disk([d.center, d.a, d.b]),
            Shape::Cylinder(c) => CompactShape::Cylinder { p0: c.p0, axis: c.axis, radius: c.radius },
            Shape::Plane(p) => CompactShape::Plane([p.point, p.normal]),
            Shape::SdfVoxel(v) => CompactShape::SdfVoxel(*v),
        }
    }

    #[inline]
    pub fn bounds(&self) -> Aabb {
        match self {
            Shape::Sphere(s) => s.bounds(),
            Shape::Triangle(t) => t.bounds(),
            Shape::Quad(q) => q.bounds(),
            Shape::Disk(d) => d.bounds(),
            Shape::Cylinder(c) => c.bounds(),
            Shape::Plane(_) => Aabb::INFINITE,
            Shape::SdfVoxel(v) => v.bounds(),
        }
    }

    #[inline(always)]
    pub fn intersect(&self, ray: &Ray, shear: &RayShear, t_max: f32) -> Option<PrimHit> {
        match self {
            Shape::Sphere(s) => s.intersect(ray, t_max),
            Shape::Triangle(t) => t.intersect(ray, shear, t_max),
            Shape::Quad(q) => q.intersect(ray, t_max),
            Shape::Disk(d) => d.intersect(ray, t_max),
            Shape::Cylinder(c) => c.intersect(ray, t_max),
            Shape::Plane(p) => p.intersect(ray, t_max),
            Shape::SdfVoxel(v) => v.intersect(ray, t_max),
        }
    }

    /// Surface data at a hit found by `intersect`. `meshes` supplies vertex normals and uv.
    #[inline(always)]
    pub fn surface(&self, ray: &Ray, h: &PrimHit, meshes: &[TriangleMesh]) -> SurfacePoint {
        match self {
            Shape::Sphere(s) => s.surface(ray, h),
            Shape::Triangle(t) => t.surface(h, meshes),
            Shape::Quad(q) => q.surface(h),
            Shape::Disk(d) => d.surface(h),
            Shape::Cylinder(c) => c.surface(ray, h),
            Shape::Plane(p) => p.surface(ray, h),
            Shape::SdfVoxel(v) => v.surface(ray, h),
        }
    }

    /// True for shapes with finite bounds (every shape but the plane), which the BVH's tree
    /// holds.
    #[inline]
    pub fn is_bounded(&self) -> bool {
        match self {
            Shape::Plane(_) => false,
            Shape::Sphere(_)
            | Shape::Triangle(_)
            | Shape::Quad(_)
            | Shape::Disk(_)
            | Shape::Cylinder(_)
            | Shape::SdfVoxel(_) => true,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Disks and cylinders fit in the space quads and triangles took: no primitive got bigger.
    #[test]
    fn shapes_stay_small() {
        assert!(std::mem::size_of::<Shape>() <= 52, "{}", std::mem::size_of::<Shape>());
        assert!(std::mem::size_of::<CompactShape>() <= 40, "{}", std::mem::size_of::<CompactShape>());
        assert!(std::mem::size_of::<Primitive>() <= 60, "{}", std::mem::size_of::<Primitive>());
    }
}
