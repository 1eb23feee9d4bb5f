//! Sphere given by centre and radius.

use super::{PrimHit, SurfacePoint};
use crate::geometry::{Aabb, Ray, SurfaceParam};
use crate::math::Vec3;
use crate::math::float::gamma;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sphere {
    pub center: Vec3,
    pub radius: f32,
}

impl Sphere {
    pub fn new(center: Vec3, radius: f32) -> Self {
        Sphere { center, radius }
    }

    pub fn bounds(&self) -> Aabb {
        Aabb { min: self.center - Vec3::splat(self.radius), max: self.center + Vec3::splat(self.radius) }
    }

    /// Nearest root in (0, t_max). The discriminant is computed from the distance of the centre to
    /// the ray line, which stays accurate for small spheres far from the origin (pbrt-v4 / Ray
    /// Tracing Gems ch. 7), and the far root comes from c/q to avoid cancellation.
    #[inline(always)]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<PrimHit> {
        let f = ray.o - self.center;
        let a = ray.d.length_squared();
        let b = -f.dot(ray.d);
        let l = f + ray.d * (b / a);
        let r2 = self.radius * self.radius;
        let disc = a * (r2 - l.length_squared());
        if disc < 0.0 {
            return None;
        }
        let c = f.length_squared() - r2;
        let sq = disc.sqrt();
        let q = b + sq.copysign(b);
        let (mut t0, mut t1) = if q == 0.0 { (0.0, 0.0) } else { (c / q, q / a) };
        if t0 > t1 {
            std::mem::swap(&mut t0, &mut t1);
        }
        // A root within the rounding error of t of zero is the surface the ray starts on.
        let t_eps = gamma(8) * (f.abs().max_element() + self.radius) / a.sqrt();
        let t = if t0 > t_eps {
            t0
        } else if t1 > t_eps {
            t1
        } else {
            return None;
        };
        (t < t_max).then_some(PrimHit { t, u: 0.0, v: 0.0 })
    }

    pub fn surface(&self, ray: &Ray, h: &PrimHit) -> SurfacePoint {
        let local = ray.at(h.t) - self.center;
        let len = local.length();
        // Re-project onto the surface, which keeps the error bound small (pbrt-v4 sec. 6.8.5).
        let local = if len > 0.0 { local * (self.radius / len) } else { Vec3::new(0.0, self.radius, 0.0) };
        let p = self.center + local;
        let p_error = gamma(5) * local.abs() + gamma(1) * p.abs();
        let n = local / self.radius;
        SurfacePoint { p, p_error, ng: n, ns: n, param: SurfaceParam::Sphere { n, radius: self.radius } }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Vec2;
    use crate::shape::{RayShear, Shape};
    use std::f32::consts::PI;

    fn hit(s: &Sphere, o: Vec3, d: Vec3) -> Option<f32> {
        let r = Ray::new(o, d.normalize());
        Shape::Sphere(*s).intersect(&r, &RayShear::new(&r), f32::INFINITY).map(|h| h.t)
    }

    #[test]
    fn sphere_hit_miss_inside_tangent_behind() {
        let s = Sphere::new(Vec3::new(0.0, 0.0, -5.0), 1.0);
        assert!((hit(&s, Vec3::ZERO, -Vec3::Z).unwrap() - 4.0).abs() < 1e-5);
        assert!(hit(&s, Vec3::ZERO, Vec3::Y).is_none());
        // Origin inside: the far side.
        assert!((hit(&s, Vec3::new(0.0, 0.0, -5.0), Vec3::X).unwrap() - 1.0).abs() < 1e-5);
        // Sphere behind the origin.
        assert!(hit(&s, Vec3::ZERO, Vec3::Z).is_none());
        // Tangent ray grazing y = 1 hits at the touching point (or misses by rounding), never elsewhere.
        if let Some(t) = hit(&s, Vec3::new(0.0, 1.0, 0.0), -Vec3::Z) {
            assert!((t - 5.0).abs() < 1e-2);
        }
        // Just outside the tangent: a miss.
        assert!(hit(&s, Vec3::new(0.0, 1.0001, 0.0), -Vec3::Z).is_none());
    }

    #[test]
    fn uv_follows_mitsuba() {
        // Values Mitsuba 3 gives on the unit sphere at (0.866, 0, 0.5) (docs in the notes of
        // issue 10): uv = (0, 1/3), dp/du = (0, 2 pi, 0) (sin theta), dp/dv points towards -z.
        let s = Sphere::new(Vec3::ZERO, 1.0);
        let n = Vec3::new(0.866_025_4, 0.0, 0.5);
        let param = SurfaceParam::Sphere { n, radius: s.radius };
        let (uv, dpdu, dpdv) = (param.uv(), param.dpdu(), param.dpdv());
        assert!(uv.abs_diff_eq(Vec2::new(0.0, 1.0 / 3.0), 1e-5), "{uv}");
        assert!(dpdu.abs_diff_eq(Vec3::new(0.0, 5.441_398, 0.0), 1e-4), "{dpdu}");
        assert!(dpdv.abs_diff_eq(Vec3::new(PI * 0.5, 0.0, -PI * 0.866_025_4), 1e-4), "{dpdv}");
        // u grows from +x towards +y and wraps to [0, 1).
        assert!((SurfaceParam::Sphere { n: Vec3::Y, radius: 1.0 }.uv().x - 0.25).abs() < 1e-6);
        assert!((SurfaceParam::Sphere { n: -Vec3::Y, radius: 1.0 }.uv().x - 0.75).abs() < 1e-6);
        // The tangents are perpendicular to the normal.
        assert!(dpdu.dot(n).abs() < 1e-5 && dpdv.dot(n).abs() < 1e-5);
    }

    #[test]
    fn far_small_sphere_is_accurate() {
        let s = Sphere::new(Vec3::new(0.0, 0.0, -1.0e4), 0.01);
        let t = hit(&s, Vec3::ZERO, -Vec3::Z).unwrap();
        assert!((t - (1.0e4 - 0.01)).abs() < 2e-3, "{t}");
    }
}
