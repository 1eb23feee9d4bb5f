//! Parallelogram `p0 + u e1 + v e2`, u, v in [0, 1]. Affine transforms keep it a parallelogram,
//! so rectangles and the faces of boxes are quads.

use super::{PrimHit, SurfacePoint};
use crate::geometry::{Aabb, Ray, SurfaceParam, Transform};
use crate::math::float::gamma;
use crate::math::{Vec2, Vec3};

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Quad {
    pub p0: Vec3,
    pub e1: Vec3,
    pub e2: Vec3,
    /// Unit normal, e1 x e2 normalised.
    pub n: Vec3,
}

impl Quad {
    /// `None` when the edges are parallel or zero (a degenerate quad has no area).
    pub fn new(p0: Vec3, e1: Vec3, e2: Vec3) -> Option<Self> {
        let c = e1.cross(e2);
        let l2 = c.length_squared();
        if !(l2 > 0.0) || !l2.is_finite() {
            return None;
        }
        Some(Quad { p0, e1, e2, n: c / l2.sqrt() })
    }

    pub fn bounds(&self) -> Aabb {
        Aabb::from_points(&[self.p0, self.p0 + self.e1, self.p0 + self.e2, self.p0 + self.e1 + self.e2])
    }

    pub fn area(&self) -> f32 {
        self.e1.cross(self.e2).length()
    }

    #[inline(always)]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<PrimHit> {
        intersect_quad(self.p0, self.e1, self.e2, ray, t_max)
    }

    pub fn surface(&self, h: &PrimHit) -> SurfacePoint {
        let a = self.e1 * h.u;
        let b = self.e2 * h.v;
        let p = self.p0 + a + b;
        let p_error = gamma(6) * (self.p0.abs() + a.abs() + b.abs());
        let param = SurfaceParam::Known { uv: Vec2::new(h.u, h.v), dpdu: self.e1, dpdv: self.e2 };
        SurfacePoint { p, p_error, ng: self.n, ns: self.n, param }
    }
}

/// Corner and edges of the six faces of the box [m, mx], each with its normal (e1 x e2)
/// pointing out.
pub fn box_faces(m: Vec3, mx: Vec3) -> [(Vec3, Vec3, Vec3); 6] {
    let e = mx - m;
    let (ex, ey, ez) = (Vec3::new(e.x, 0.0, 0.0), Vec3::new(0.0, e.y, 0.0), Vec3::new(0.0, 0.0, e.z));
    [
        (m, ez, ey),
        (Vec3::new(mx.x, m.y, m.z), ey, ez),
        (m, ex, ez),
        (Vec3::new(m.x, mx.y, m.z), ez, ex),
        (m, ey, ex),
        (Vec3::new(m.x, m.y, mx.z), ex, ey),
    ]
}

/// The quad (corner, e1, e2) moved by `t`; the edges are swapped under a mirroring transform so
/// the normal still points to the side the untransformed normal did. `None` when it has no area.
pub fn transformed_quad(t: &Transform, corner: Vec3, e1: Vec3, e2: Vec3) -> Option<Quad> {
    let (p0, a, b) = (t.point(corner), t.vector(e1), t.vector(e2));
    if t.m.determinant() < 0.0 { Quad::new(p0, b, a) } else { Quad::new(p0, a, b) }
}

/// Ray-parallelogram test from the corner and edges alone (the BVH keeps only these).
#[inline(always)]
pub fn intersect_quad(p0: Vec3, e1: Vec3, e2: Vec3, ray: &Ray, t_max: f32) -> Option<PrimHit> {
    let c = e1.cross(e2);
    let denom = c.dot(ray.d);
    if denom == 0.0 {
        return None;
    }
    let t = c.dot(p0 - ray.o) / denom;
    if !(t > 0.0 && t < t_max) {
        return None;
    }
    let q = ray.at(t) - p0;
    let inv = 1.0 / c.length_squared();
    let u = c.dot(q.cross(e2)) * inv;
    let v = c.dot(e1.cross(q)) * inv;
    if !(0.0..=1.0).contains(&u) || !(0.0..=1.0).contains(&v) {
        return None;
    }
    Some(PrimHit { t, u, v })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quad_hit_miss_edge_behind() {
        let q = Quad::new(Vec3::new(-1.0, -1.0, -3.0), Vec3::new(2.0, 0.0, 0.0), Vec3::new(0.0, 2.0, 0.0)).unwrap();
        let h = q.intersect(&Ray::new(Vec3::ZERO, -Vec3::Z), f32::INFINITY).unwrap();
        assert!((h.t - 3.0).abs() < 1e-6 && (h.u - 0.5).abs() < 1e-6 && (h.v - 0.5).abs() < 1e-6);
        assert!(q.intersect(&Ray::new(Vec3::new(1.5, 0.0, 0.0), -Vec3::Z), f32::INFINITY).is_none());
        assert!(q.intersect(&Ray::new(Vec3::ZERO, Vec3::Z), f32::INFINITY).is_none());
        assert!(q.intersect(&Ray::new(Vec3::ZERO, Vec3::X), f32::INFINITY).is_none());
        assert!(q.n.abs_diff_eq(Vec3::Z, 1e-6));
        assert!(Quad::new(Vec3::ZERO, Vec3::X, Vec3::X * 2.0).is_none());
    }
}
