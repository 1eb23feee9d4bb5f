//! Mitsuba's `disk`: the unit disk at z = 0 of a local frame, facing +z, placed by an affine
//! transform. Stored by its centre and the images `a`, `b` of the local x and y axes, so any
//! transform (an ellipse after a non-uniform scale) is exact and the test is that of a quad with
//! a round inside test.

use super::{PrimHit, SurfacePoint, SurfaceSample};
use crate::geometry::{Aabb, Ray, SurfaceParam, Transform};
use crate::math::float::gamma;
use crate::math::{Vec2, Vec3};
use crate::sampling::warp::concentric_disk;
use std::f32::consts::{PI, TAU};

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Disk {
    pub center: Vec3,
    /// dp/dx and dp/dy of the local unit disk.
    pub a: Vec3,
    pub b: Vec3,
    /// Unit normal: a x b normalised (the plane the test uses), on the side of the local +z
    /// transformed as a normal (so a mirroring transform turns it over, as in Mitsuba), and
    /// negated by `flip_normals`.
    pub n: Vec3,
}

impl Disk {
    /// The unit disk moved by `t`; `None` when it has no area or is not finite.
    pub fn from_transform(t: &Transform, flip_normals: bool) -> Option<Self> {
        let (center, a, b) = (t.point(Vec3::ZERO), t.vector(Vec3::X), t.vector(Vec3::Y));
        let m = a.cross(b);
        let side = t.normal(Vec3::Z);
        let area2 = m.length_squared();
        if !(area2 > 0.0 && area2.is_finite() && center.is_finite() && side.is_finite()) {
            return None;
        }
        let n = m / area2.sqrt();
        let n = if (m.dot(side) < 0.0) != flip_normals { -n } else { n };
        Some(Disk { center, a, b, n })
    }

    /// The disk of `radius` around `center` facing `normal`, its local x axis that of
    /// `Frame::from_z(normal)` (where v = 0), then moved by `to_world`.
    pub fn facing(center: Vec3, normal: Vec3, radius: f32, to_world: &Transform) -> Option<Self> {
        let f = crate::math::Frame::from_z(normal.try_normalize()?);
        let m = glam::Mat4::from_cols(
            (f.x * radius).extend(0.0),
            (f.y * radius).extend(0.0),
            f.z.extend(0.0),
            center.extend(1.0),
        );
        Self::from_transform(&Transform::from_mat4(m).then(*to_world), false)
    }

    /// The ellipse's box: along each axis it reaches sqrt(a_i^2 + b_i^2) from the centre.
    pub fn bounds(&self) -> Aabb {
        let r = (self.a * self.a + self.b * self.b).map(f32::sqrt);
        Aabb { min: self.center - r, max: self.center + r }
    }

    pub fn area(&self) -> f32 {
        PI * self.a.cross(self.b).length()
    }

    #[inline(always)]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<PrimHit> {
        intersect_disk(self.center, self.a, self.b, ray, t_max)
    }

    /// `h.u`, `h.v` are the local x, y of the hit. Mitsuba's parameterisation: u = r,
    /// v = phi / 2 pi, dp/du = (cos phi, sin phi, 0), dp/dv = 2 pi (-y, x, 0), transformed.
    pub fn surface(&self, h: &PrimHit) -> SurfacePoint {
        let (x, y) = (h.u, h.v);
        let (ax, by) = (self.a * x, self.b * y);
        // Onto the plane the test uses (through the centre, normal a x b): however thin or
        // skewed the ellipse, what is left is the rounding of this projection (as for `Plane`).
        let p = self.center + ax + by;
        let p = p - self.n * self.n.dot(p - self.center);
        let p_error = gamma(6) * (self.center.abs() + p.abs());
        let r = (x * x + y * y).sqrt();
        let mut phi = y.atan2(x);
        if phi < 0.0 {
            phi += TAU;
        }
        let dpdu = if r > 0.0 { (ax + by) / r } else { self.a };
        let dpdv = (self.b * x - self.a * y) * TAU;
        let param = SurfaceParam::Known { uv: Vec2::new(r, phi / TAU), dpdu, dpdv };
        SurfacePoint { p, p_error, ng: self.n, ns: self.n, param }
    }

    /// A point uniformly distributed by area (density 1 / area): the concentric map of the
    /// unit square onto the unit disk, as Mitsuba samples it, then the affine map (whose
    /// Jacobian is constant).
    pub fn sample_area(&self, u: Vec2) -> SurfaceSample {
        let d = concentric_disk(u);
        let p = self.center + self.a * d.x + self.b * d.y;
        let p = p - self.n * self.n.dot(p - self.center);
        // (r, phi / 2 pi) of the local point, as `surface` reports it.
        let mut phi = d.y.atan2(d.x);
        if phi < 0.0 {
            phi += TAU;
        }
        let uv = Vec2::new(d.length(), phi / TAU);
        SurfaceSample { p, p_error: gamma(6) * (self.center.abs() + p.abs()), n: self.n, uv }
    }
}

/// Ray-disk test from the centre and axes alone (the BVH keeps only these): the plane's hit,
/// its local coordinates by the same solve as a quad's, and x^2 + y^2 <= 1.
#[inline(always)]
pub fn intersect_disk(c: Vec3, a: Vec3, b: Vec3, ray: &Ray, t_max: f32) -> Option<PrimHit> {
    let m = a.cross(b);
    let denom = m.dot(ray.d);
    if denom == 0.0 {
        return None;
    }
    let t = m.dot(c - ray.o) / denom;
    if !(t > 0.0 && t < t_max) {
        return None;
    }
    let q = ray.at(t) - c;
    let inv = 1.0 / m.length_squared();
    let x = m.dot(q.cross(b)) * inv;
    let y = m.dot(a.cross(q)) * inv;
    if !(x * x + y * y <= 1.0) {
        return None;
    }
    Some(PrimHit { t, u: x, v: y })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f32::consts::FRAC_1_SQRT_2;

    fn hit(d: &Disk, o: Vec3, dir: Vec3) -> Option<SurfacePoint> {
        let r = Ray::new(o, dir);
        d.intersect(&r, f32::INFINITY).map(|h| {
            assert!((r.at(h.t) - d.surface(&h).p).length() < 1e-5);
            d.surface(&h)
        })
    }

    /// Values Mitsuba 3.9.1 gives (`scene.ray_intersect` on `disk`, scalar_rgb).
    #[test]
    fn hits_match_mitsuba() {
        let d = Disk::from_transform(&Transform::IDENTITY, false).unwrap();
        let s = hit(&d, Vec3::new(0.3, -0.3, 2.0), -Vec3::Z).unwrap();
        assert!(s.p.abs_diff_eq(Vec3::new(0.3, -0.3, 0.0), 1e-6));
        let SurfaceParam::Known { uv, dpdu, dpdv } = s.param else { panic!() };
        assert!(uv.abs_diff_eq(Vec2::new(0.424264, 0.875), 1e-5), "{uv}");
        assert!(dpdu.abs_diff_eq(Vec3::new(FRAC_1_SQRT_2, -FRAC_1_SQRT_2, 0.0), 1e-5), "{dpdu}");
        assert!(dpdv.abs_diff_eq(Vec3::new(1.88496, 1.88496, 0.0), 1e-4), "{dpdv}");
        assert_eq!(s.ng, Vec3::Z);
        // flip_normals turns only the normal over.
        let f = Disk::from_transform(&Transform::IDENTITY, true).unwrap();
        let s = hit(&f, Vec3::new(0.3, -0.3, 2.0), -Vec3::Z).unwrap();
        assert_eq!(s.ng, -Vec3::Z);
        // A mirror in z turns the normal over; a mirror in x keeps it and mirrors v.
        let mz = Disk::from_transform(&Transform::scale(Vec3::new(1.0, 1.0, -1.0)), false).unwrap();
        assert_eq!(hit(&mz, Vec3::new(0.3, -0.3, 2.0), -Vec3::Z).unwrap().ng, -Vec3::Z);
        let mx = Disk::from_transform(&Transform::scale(Vec3::new(-1.0, 1.0, 1.0)), false).unwrap();
        let s = hit(&mx, Vec3::new(0.3, -0.3, 2.0), -Vec3::Z).unwrap();
        assert_eq!(s.ng, Vec3::Z);
        assert!((s.param.uv().y - 0.625).abs() < 1e-5);
        // Scaled by (2, 1, 1) and turned 30 degrees about x: an ellipse.
        let t = Transform::scale(Vec3::new(2.0, 1.0, 1.0)).then(Transform::rotate(Vec3::X, 30.0));
        let e = Disk::from_transform(&t, false).unwrap();
        let s = hit(&e, Vec3::new(0.6, -0.3, 3.0), -Vec3::Z).unwrap();
        let SurfaceParam::Known { uv, dpdu, dpdv } = s.param else { panic!() };
        assert!(s.p.abs_diff_eq(Vec3::new(0.6, -0.3, -0.173205), 1e-5), "{}", s.p);
        assert!(uv.abs_diff_eq(Vec2::new(0.458258, 0.863593), 1e-5), "{uv}");
        assert!(s.ng.abs_diff_eq(Vec3::new(0.0, -0.5, 0.866025), 1e-5));
        assert!(dpdu.abs_diff_eq(Vec3::new(1.30931, -0.654654, -0.377964), 1e-4), "{dpdu}");
        assert!(dpdv.abs_diff_eq(Vec3::new(4.35312, 1.63242, 0.942478), 1e-4), "{dpdv}");
        assert!((e.area() - 2.0 * PI).abs() < 1e-5);
    }

    #[test]
    fn misses_outside_the_rim_behind_and_parallel() {
        let d = Disk::facing(Vec3::new(0.0, 1.0, 0.0), Vec3::Y, 2.0, &Transform::IDENTITY).unwrap();
        assert!(hit(&d, Vec3::new(1.9, 5.0, 0.0), -Vec3::Y).is_some());
        assert!(hit(&d, Vec3::new(1.5, 5.0, 1.5), -Vec3::Y).is_none());
        assert!(hit(&d, Vec3::new(0.0, 5.0, 0.0), Vec3::Y).is_none());
        assert!(hit(&d, Vec3::new(0.0, 1.0, -5.0), Vec3::Z).is_none());
        // From below: still a hit (one-sidedness is the material's business), normal kept.
        let s = hit(&d, Vec3::new(0.5, -3.0, 0.5), Vec3::Y).unwrap();
        assert_eq!(s.ng, Vec3::Y);
        let b = d.bounds();
        assert!(
            b.min.abs_diff_eq(Vec3::new(-2.0, 1.0, -2.0), 1e-5) && b.max.abs_diff_eq(Vec3::new(2.0, 1.0, 2.0), 1e-5)
        );
    }

    #[test]
    fn samples_cover_the_disk_uniformly() {
        let d = Disk::from_transform(&Transform::scale(Vec3::new(3.0, 1.0, 1.0)), false).unwrap();
        // The share of samples with local radius below 1/2 is the share of the area: 1/4.
        let n = 64;
        let mut inner = 0;
        for i in 0..n {
            for j in 0..n {
                let s = d.sample_area(Vec2::new((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32));
                let (x, y) = (s.p.x / 3.0, s.p.y);
                assert!(x * x + y * y <= 1.0 + 1e-5 && s.p.z == 0.0);
                inner += (x * x + y * y < 0.25) as u32;
            }
        }
        assert!((inner as f32 / (n * n) as f32 - 0.25).abs() < 0.01, "{inner}");
    }
}
