//! Sphere given by centre and radius, and the rotation of its (u, v) parameterisation.

use super::{PrimHit, SurfacePoint};
use crate::geometry::{Aabb, Ray, SurfaceParam, Transform};
use crate::math::Vec3;
use crate::math::float::gamma;
use glam::{Mat3, Quat};

const IDENTITY: [f32; 4] = [0.0, 0.0, 0.0, 1.0];

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sphere {
    pub center: Vec3,
    pub radius: f32,
    /// From world directions to the sphere's own frame, where u runs around +z and v from the
    /// +z pole (Mitsuba's sphere, turned by its `to_world`), as a quaternion (x, y, z, w); the
    /// identity for most spheres. Plain floats keep the BVH's leaf shapes at 40 bytes.
    pub to_local: [f32; 4],
}

impl Sphere {
    pub fn new(center: Vec3, radius: f32) -> Self {
        Sphere { center, radius, to_local: IDENTITY }
    }

    /// The sphere of `radius` about `center` in object space placed by `t` (a similarity, checked
    /// by the caller): its texture coordinates turn with `t`'s rotation. A mirroring transform
    /// keeps the world's orientation (second value false: the caller may warn).
    pub fn transformed(t: &Transform, center: Vec3, radius: f32) -> (Self, bool) {
        let scale = t.axis_scales().x;
        let m = Mat3::from_mat4(t.m) * (1.0 / scale);
        let mut s = Sphere::new(t.point(center), radius * scale);
        let proper = m.determinant() > 0.0;
        if proper {
            let q = Quat::from_mat3(&m).normalize();
            if q.is_finite() && !q.abs_diff_eq(Quat::IDENTITY, 1e-7) {
                s.to_local = q.inverse().to_array();
            }
        }
        (s, proper)
    }

    /// The (u, v) parameterisation at the point with outward unit normal `n` (world space).
    #[inline]
    pub fn param(&self, n: Vec3) -> SurfaceParam {
        if self.to_local == IDENTITY {
            return SurfaceParam::Sphere { n, radius: self.radius };
        }
        let to_local = Quat::from_array(self.to_local);
        let local = SurfaceParam::Sphere { n: to_local * n, radius: self.radius };
        let to_world = to_local.inverse();
        SurfaceParam::Known { uv: local.uv(), dpdu: to_world * local.dpdu(), dpdv: to_world * local.dpdv() }
    }

    pub fn bounds(&self) -> Aabb {
        Aabb { min: self.center - Vec3::splat(self.radius), max: self.center + Vec3::splat(self.radius) }
    }

    /// Nearest root in (0, t_max). The discriminant is computed from the distance of the centre to
    /// the ray line, which stays accurate for small spheres far from the origin (pbrt-v4 / Ray
    /// Tracing Gems ch. 7), and the far root comes from c/q to avoid cancellation.
    #[inline(always)]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<PrimHit> {
        let (t0, t1, t_eps) = self.roots(ray)?;
        let t = if t0 > t_eps {
            t0
        } else if t1 > t_eps {
            t1
        } else {
            return None;
        };
        (t < t_max).then_some(PrimHit { t, u: 0.0, v: 0.0 })
    }

    /// Calls `f` for each crossing of the surface in (0, t_max), nearer first, until it returns
    /// false (then returns false). The roots are those `intersect` chooses from.
    #[inline(always)]
    pub fn for_each_crossing(&self, ray: &Ray, t_max: f32, mut f: impl FnMut(PrimHit) -> bool) -> bool {
        let Some((t0, t1, t_eps)) = self.roots(ray) else { return true };
        for t in [t0, t1] {
            if t > t_eps && t < t_max && !f(PrimHit { t, u: 0.0, v: 0.0 }) {
                return false;
            }
        }
        true
    }

    /// The two roots along `ray` in increasing order, and the distance within which a root is
    /// the surface the ray starts on; `None` when the ray's line misses.
    #[inline(always)]
    fn roots(&self, ray: &Ray) -> Option<(f32, f32, f32)> {
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
        Some((t0, t1, t_eps))
    }

    pub fn surface(&self, ray: &Ray, h: &PrimHit) -> SurfacePoint {
        let local = ray.at(h.t) - self.center;
        let len = local.length();
        // Re-project onto the surface, which keeps the error bound small (pbrt-v4 sec. 6.8.5).
        let local = if len > 0.0 { local * (self.radius / len) } else { Vec3::new(0.0, self.radius, 0.0) };
        let p = self.center + local;
        let p_error = gamma(5) * local.abs() + gamma(1) * p.abs();
        let n = local / self.radius;
        SurfacePoint { p, p_error, ng: n, ns: n, param: self.param(n) }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Vec2;
    use crate::shape::{RayShear, Shape};
    use std::f32::consts::PI;

    /// A ray through a sphere crosses it at both roots, the nearer first and equal to the
    /// closest hit; from inside (or from the surface, outwards through it) only the exit counts;
    /// `t_max` cuts crossings beyond it, and a false return stops the walk.
    #[test]
    fn crossings_are_both_roots() {
        let s = Sphere::new(Vec3::new(1.0, 2.0, 3.0), 2.0);
        let walk = |o: Vec3, d: Vec3, t_max: f32| {
            let mut ts = Vec::new();
            let ray = Ray::new(o, d);
            s.for_each_crossing(&ray, t_max, |h| {
                ts.push(h.t);
                true
            });
            (ts, s.intersect(&ray, t_max).map(|h| h.t))
        };
        let (ts, first) = walk(Vec3::new(1.0, 2.0, -7.0), Vec3::Z, f32::INFINITY);
        assert_eq!(ts.len(), 2);
        assert_eq!(Some(ts[0]), first);
        assert!((ts[0] - 8.0).abs() < 1e-5 && (ts[1] - 12.0).abs() < 1e-5, "{ts:?}");
        let (ts, _) = walk(Vec3::new(1.0, 2.0, -7.0), Vec3::Z, 10.0);
        assert_eq!(ts.len(), 1);
        let (ts, first) = walk(Vec3::new(1.0, 2.5, 3.0), Vec3::Y, f32::INFINITY);
        assert_eq!((ts.len(), Some(ts[0])), (1, first));
        assert!((ts[0] - 1.5).abs() < 1e-5);
        let on_surface = s.surface(&Ray::new(Vec3::new(1.0, 2.0, -7.0), Vec3::Z), &PrimHit { t: 8.0, u: 0.0, v: 0.0 });
        let (ts, _) =
            walk(Ray::spawn(on_surface.p, on_surface.p_error, on_surface.ng, -Vec3::Z, 0.0).o, -Vec3::Z, f32::INFINITY);
        assert!(ts.is_empty(), "{ts:?}");
        let mut calls = 0;
        let done = s.for_each_crossing(&Ray::new(Vec3::new(1.0, 2.0, -7.0), Vec3::Z), f32::INFINITY, |_| {
            calls += 1;
            false
        });
        assert!(!done && calls == 1);
    }

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
