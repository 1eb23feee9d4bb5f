//! Infinite plane through a point with a normal. Unbounded, so the BVH keeps planes beside its
//! tree and tests them with every ray.

use super::{PrimHit, SurfacePoint};
use crate::geometry::{Ray, SurfaceParam};
use crate::math::float::gamma;
use crate::math::{Frame, Vec2, Vec3};

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plane {
    pub point: Vec3,
    /// Unit normal.
    pub normal: Vec3,
    /// The fixed tangent frame uv are measured along (in scene units), made once rather than
    /// per hit.
    tangent: Vec3,
    bitangent: Vec3,
}

/// The hit of `ray` in (0, t_max) with the plane through `point` with unit `normal`.
#[inline]
pub fn intersect_plane(point: Vec3, normal: Vec3, ray: &Ray, t_max: f32) -> Option<PrimHit> {
    let denom = normal.dot(ray.d);
    if denom == 0.0 {
        return None;
    }
    let t = normal.dot(point - ray.o) / denom;
    // A ray nearly parallel to the plane can meet it so far away that the point (or the
    // arithmetic on it) overflows; such distant hits are treated as misses.
    (t > 0.0 && t < t_max && ray.at(t).abs().max_element() < 1e30).then_some(PrimHit { t, u: 0.0, v: 0.0 })
}

impl Plane {
    /// The plane through `point` with unit `normal`.
    pub fn new(point: Vec3, normal: Vec3) -> Self {
        let frame = Frame::from_z(normal);
        Plane { point, normal, tangent: frame.x, bitangent: frame.y }
    }

    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<PrimHit> {
        intersect_plane(self.point, self.normal, ray, t_max)
    }

    /// Out of line: inlined, it made `Primitives::surface` larger and slower for every other
    /// shape's hits too (BENCHMARKS.md, architecture step 2).
    #[inline(never)]
    pub fn surface(&self, ray: &Ray, h: &PrimHit) -> SurfacePoint {
        let p = ray.at(h.t);
        // Project onto the plane: the remaining error is that of one dot product and subtraction.
        let p = p - self.normal * self.normal.dot(p - self.point);
        let p_error = gamma(6) * (p.abs() + self.point.abs());
        // Coordinates in the plane, in scene units, along its tangent frame.
        let d = p - self.point;
        let (dpdu, dpdv) = (self.tangent, self.bitangent);
        let param = SurfaceParam::Known { uv: Vec2::new(d.dot(dpdu), d.dot(dpdv)), dpdu, dpdv };
        SurfacePoint { p, p_error, ng: self.normal, ns: self.normal, param }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plane_hit_parallel_behind() {
        let pl = Plane::new(Vec3::new(0.0, -1.0, 0.0), Vec3::Y);
        let r = Ray::new(Vec3::ZERO, Vec3::new(0.0, -1.0, 0.0));
        assert!((pl.intersect(&r, f32::INFINITY).unwrap().t - 1.0).abs() < 1e-6);
        assert!(pl.intersect(&Ray::new(Vec3::ZERO, Vec3::X), f32::INFINITY).is_none());
        assert!(pl.intersect(&Ray::new(Vec3::ZERO, Vec3::Y), f32::INFINITY).is_none());
        // From below, through the back face.
        let r = Ray::new(Vec3::new(0.0, -2.0, 0.0), Vec3::Y);
        assert!((pl.intersect(&r, f32::INFINITY).unwrap().t - 1.0).abs() < 1e-6);
        assert!(pl.intersect(&r, 0.5).is_none());
    }
}
