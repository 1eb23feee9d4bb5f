//! Mitsuba's `cylinder`: an open tube (no caps) of circular section from `p0` to `p1`.
//!
//! Kept in world space by its base centre, axis vector and radius, which is all the test
//! needs; the local x axis (where u = 0) and the handedness of the local frame are kept for the
//! parameterisation. Mitsuba takes the local frame from the axis with the branch-free basis of
//! Duff et al. (`Frame::from_z`), then applies `to_world`; a mirroring `to_world` mirrors u,
//! while the normal stays outward.

use super::{PrimHit, SurfacePoint, SurfaceSample};
use crate::geometry::{Aabb, Ray, SurfaceParam, Transform};
use crate::math::float::gamma;
use crate::math::{Frame, Vec2, Vec3};
use std::f32::consts::TAU;

const FLIP_NORMALS: u32 = 1;
/// The local frame is left-handed after a mirroring transform.
const MIRRORED: u32 = 2;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cylinder {
    /// Centre of the base circle (v = 0).
    pub p0: Vec3,
    /// From the base centre to the top centre (v = 1).
    pub axis: Vec3,
    pub radius: f32,
    /// Unit local x axis, perpendicular to the axis: u = 0 there.
    pub x: Vec3,
    flags: u32,
}

impl Cylinder {
    /// Mitsuba's cylinder: centre line from `p0` to `p1` in object space, `radius`, then
    /// `to_world`. Returns the cylinder and, when `to_world` scales the section unevenly or
    /// shears it (which Mitsuba does not support either), a description of that: the radius
    /// is then taken along the local x axis, as Mitsuba does.
    pub fn from_mitsuba(
        p0: Vec3,
        p1: Vec3,
        radius: f32,
        to_world: &Transform,
        flip_normals: bool,
    ) -> Result<(Self, Option<String>), String> {
        let d = p1 - p0;
        let len = d.length();
        if !(len > 0.0 && len.is_finite()) {
            return Err(format!("cylinder p0 {p0} and p1 {p1} must be distinct finite points"));
        }
        if !(radius > 0.0 && radius.is_finite()) {
            return Err(format!("cylinder radius must be positive, found {radius}"));
        }
        let f = Frame::from_z(d / len);
        let base = to_world.point(p0);
        let (wx, wy, axis) = (to_world.vector(f.x * radius), to_world.vector(f.y * radius), to_world.vector(d));
        let (r, ry, l) = (wx.length(), wy.length(), axis.length());
        if !(r > 0.0 && r.is_finite() && l > 0.0 && l.is_finite() && base.is_finite()) {
            return Err("cylinder is degenerate after its to_world transform".into());
        }
        let ez = axis / l;
        let x = (wx - ez * wx.dot(ez)).normalize_or_zero();
        if x == Vec3::ZERO {
            return Err("cylinder is degenerate after its to_world transform".into());
        }
        let tol = 1e-4;
        let uneven = (ry - r).abs() > tol * r
            || wx.dot(wy).abs() > tol * r * ry
            || wx.dot(ez).abs() > tol * r
            || wy.dot(ez).abs() > tol * ry;
        let warning = uneven.then(|| {
            "a cylinder's to_world must not scale its section unevenly or shear it (Mitsuba does not support that either): it stays circular, with the radius along its local x axis".to_string()
        });
        let mirrored = wx.cross(wy).dot(axis) < 0.0;
        let flags = (flip_normals as u32 * FLIP_NORMALS) | (mirrored as u32 * MIRRORED);
        Ok((Cylinder { p0: base, axis, radius: r, x, flags }, warning))
    }

    /// The local y axis: z x x, reversed in a mirrored frame.
    #[inline]
    fn y(&self) -> Vec3 {
        let y = self.axis.normalize().cross(self.x);
        if self.flags & MIRRORED != 0 { -y } else { y }
    }

    #[inline]
    fn normal_sign(&self) -> f32 {
        if self.flags & FLIP_NORMALS != 0 { -1.0 } else { 1.0 }
    }

    /// The box of the two end circles (each reaches r sqrt(1 - e_i^2) along axis i).
    pub fn bounds(&self) -> Aabb {
        let e = self.axis.normalize();
        let ext = (Vec3::ONE - e * e).max(Vec3::ZERO).map(f32::sqrt) * self.radius;
        let p1 = self.p0 + self.axis;
        Aabb { min: self.p0.min(p1) - ext, max: self.p0.max(p1) + ext }
    }

    pub fn area(&self) -> f32 {
        TAU * self.radius * self.axis.length()
    }

    #[inline(always)]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<PrimHit> {
        intersect_cylinder(self.p0, self.axis, self.radius, ray, t_max)
    }

    /// Mitsuba's parameterisation: u = phi / 2 pi around the axis from the local x axis,
    /// v = height / length, dp/du = 2 pi (-y, x, 0) and dp/dv = the axis; the normal points
    /// outward (inward with `flip_normals`).
    pub fn surface(&self, ray: &Ray, h: &PrimHit) -> SurfacePoint {
        let w = ray.at(h.t) - self.p0;
        let l2 = self.axis.length_squared();
        let z = w.dot(self.axis) / l2;
        // The part across the axis, from the unclamped height: clamping first would leave some
        // of the axis in it (a hit computed far from its ray's origin can be that far off).
        let radial = w - self.axis * z;
        let z = z.clamp(0.0, 1.0);
        let along = self.axis * z;
        let rl = radial.length();
        // Re-project onto the surface (pbrt-v4 sec. 6.8.5): what is left is rounding.
        let radial = if rl > 0.0 { radial * (self.radius / rl) } else { self.x * self.radius };
        let p = self.p0 + along + radial;
        // The rounding of p itself, and that of the test's distance from the axis, which it
        // works out from the offset to p0 (up to the tube's length, however thin the tube).
        let p_error = gamma(8) * (self.p0.abs() + along.abs() + radial.abs()) + Vec3::splat(gamma(8) * w.length());
        let n = radial / self.radius;
        let y = self.y();
        let (lx, ly) = (radial.dot(self.x), radial.dot(y));
        let mut phi = ly.atan2(lx);
        if phi < 0.0 {
            phi += TAU;
        }
        let dpdu = (y * lx - self.x * ly) * TAU;
        let param = SurfaceParam::Known { uv: Vec2::new(phi / TAU, z), dpdu, dpdv: self.axis };
        let ng = n * self.normal_sign();
        SurfacePoint { p, p_error, ng, ns: ng, param }
    }

    /// A point uniformly distributed by area (density 1 / area), with Mitsuba's use of the
    /// sample: `u.x` along the axis, `u.y` around it.
    pub fn sample_area(&self, u: Vec2) -> SurfaceSample {
        let (s, c) = (TAU * u.y).sin_cos();
        let n = self.x * c + self.y() * s;
        let (along, radial) = (self.axis * u.x, n * self.radius);
        SurfaceSample {
            p: self.p0 + along + radial,
            p_error: gamma(8) * (self.p0.abs() + along.abs() + radial.abs())
                + Vec3::splat(gamma(8) * (along + radial).length()),
            n: n * self.normal_sign(),
            // (phi / 2 pi, height), as `surface` reports them.
            uv: Vec2::new(u.y, u.x),
        }
    }
}

/// Ray-tube test from the base centre, axis and radius alone (the BVH keeps only these). The
/// quadratic is solved in the plane perpendicular to the axis with the sphere's robust form
/// (the discriminant from the distance of the axis to the ray line, the far root from c / q);
/// the nearer root within the tube's length wins, so the inside of the tube is seen through
/// its open ends.
#[inline(always)]
pub fn intersect_cylinder(p0: Vec3, axis: Vec3, radius: f32, ray: &Ray, t_max: f32) -> Option<PrimHit> {
    let inv_l2 = 1.0 / axis.length_squared();
    let f = ray.o - p0;
    let (fz, dz) = (f.dot(axis) * inv_l2, ray.d.dot(axis) * inv_l2);
    let fp = f - axis * fz;
    let dp = ray.d - axis * dz;
    let a = dp.length_squared();
    if !(a > 0.0) {
        return None;
    }
    let b = -fp.dot(dp);
    let l = fp + dp * (b / a);
    let r2 = radius * radius;
    let disc = a * (r2 - l.length_squared());
    if !(disc >= 0.0) {
        return None;
    }
    let c = fp.length_squared() - r2;
    let q = b + disc.sqrt().copysign(b);
    let (mut t0, mut t1) = if q == 0.0 { (0.0, 0.0) } else { (c / q, q / a) };
    if t0 > t1 {
        std::mem::swap(&mut t0, &mut t1);
    }
    // A root within the rounding error of t of zero is the surface the ray starts on.
    let t_eps = gamma(8) * (fp.abs().max_element() + radius) / a.sqrt();
    for t in [t0, t1] {
        if t > t_eps && t < t_max {
            let z = fz + dz * t;
            if (0.0..=1.0).contains(&z) {
                return Some(PrimHit { t, u: z, v: 0.0 });
            }
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f32::consts::{FRAC_PI_2, PI};

    fn cyl(p0: Vec3, p1: Vec3, r: f32, t: &Transform, flip: bool) -> Cylinder {
        Cylinder::from_mitsuba(p0, p1, r, t, flip).unwrap().0
    }

    fn unit(t: &Transform, flip: bool) -> Cylinder {
        cyl(Vec3::ZERO, Vec3::Z, 1.0, t, flip)
    }

    /// (t, p, uv, n, dp/du, dp/dv) of a hit.
    fn hit(c: &Cylinder, o: Vec3, d: Vec3) -> Option<(f32, Vec3, Vec2, Vec3, Vec3, Vec3)> {
        let r = Ray::new(o, d);
        let h = c.intersect(&r, f32::INFINITY)?;
        let s = c.surface(&r, &h);
        let SurfaceParam::Known { uv, dpdu, dpdv } = s.param else { unreachable!() };
        assert!((r.at(h.t) - s.p).length() < 1e-5);
        Some((h.t, s.p, uv, s.ng, dpdu, dpdv))
    }

    fn close(a: Vec3, b: Vec3) -> bool {
        a.abs_diff_eq(b, 2e-4)
    }

    /// Values Mitsuba 3.9.1 gives (`scene.ray_intersect` on `cylinder`, scalar_rgb).
    #[test]
    fn hits_match_mitsuba() {
        let id = Transform::IDENTITY;
        let (t, p, uv, n, dpdu, dpdv) = hit(&unit(&id, false), Vec3::new(3.0, 0.5, 0.25), -Vec3::X).unwrap();
        assert!((t - 2.133_974_6).abs() < 1e-5);
        assert!(close(p, Vec3::new(0.866026, 0.5, 0.25)));
        assert!(uv.abs_diff_eq(Vec2::new(0.0833334, 0.25), 1e-5), "{uv}");
        assert!(close(n, Vec3::new(0.866025, 0.5, 0.0)));
        assert!(close(dpdu, Vec3::new(-PI, 5.4414, 0.0)), "{dpdu}");
        assert!(close(dpdv, Vec3::Z));
        // From inside the tube: the far wall, normal still outward.
        let (t, _, uv, n, dpdu, _) = hit(&unit(&id, false), Vec3::new(0.0, 0.0, 0.5), Vec3::X).unwrap();
        assert!((t - 1.0).abs() < 1e-5 && uv.abs_diff_eq(Vec2::new(0.0, 0.5), 1e-5) && close(n, Vec3::X));
        assert!(close(dpdu, Vec3::new(0.0, TAU, 0.0)));
        // p0, p1 and radius given.
        let c = cyl(Vec3::new(1.0, 2.0, 3.0), Vec3::new(2.0, 3.0, 3.0), 0.5, &id, false);
        let (t, _, uv, n, dpdu, dpdv) = hit(&c, Vec3::new(1.5, 2.5, 6.0), -Vec3::Z).unwrap();
        assert!((t - 2.5).abs() < 1e-5 && uv.abs_diff_eq(Vec2::new(0.625, 0.5), 1e-5), "{t} {uv}");
        assert!(
            close(n, Vec3::Z)
                && close(dpdu, Vec3::new(2.22144, -2.22144, 0.0))
                && close(dpdv, Vec3::new(1.0, 1.0, 0.0))
        );
        assert!((c.area() - 4.442_882_5).abs() < 1e-5);
        // flip_normals turns the normal only.
        let (_, _, uv, n, dpdu, _) = hit(&unit(&id, true), Vec3::new(3.0, 0.5, 0.25), -Vec3::X).unwrap();
        assert!(uv.abs_diff_eq(Vec2::new(0.0833334, 0.25), 1e-5) && close(n, Vec3::new(-0.866025, -0.5, 0.0)));
        assert!(close(dpdu, Vec3::new(-PI, 5.4414, 0.0)));
        // A mirror mirrors u; the normal stays outward.
        let m = unit(&Transform::scale(Vec3::new(-1.0, 1.0, 1.0)), false);
        let (_, _, uv, n, dpdu, _) = hit(&m, Vec3::new(3.0, 0.5, 0.25), -Vec3::X).unwrap();
        assert!(uv.abs_diff_eq(Vec2::new(0.416667, 0.25), 1e-5) && close(n, Vec3::new(0.866025, 0.5, 0.0)), "{uv}");
        assert!(close(dpdu, Vec3::new(PI, -5.4414, 0.0)));
        // Scaled (2, 2, 3).
        let s = unit(&Transform::scale(Vec3::new(2.0, 2.0, 3.0)), false);
        let (t, _, uv, n, dpdu, dpdv) = hit(&s, Vec3::new(5.0, 0.5, 1.0), -Vec3::X).unwrap();
        assert!((t - 3.063_508).abs() < 1e-5 && uv.abs_diff_eq(Vec2::new(0.0402153, 0.333333), 1e-5));
        assert!(close(n, Vec3::new(0.968246, 0.25, 0.0)) && close(dpdu, Vec3::new(-PI, 12.1673, 0.0)));
        assert!(close(dpdv, Vec3::new(0.0, 0.0, 3.0)));
        // Axis along +y and along -z: the local frame comes from the axis.
        let y = cyl(Vec3::ZERO, Vec3::Y, 1.0, &id, false);
        let (_, _, uv, n, dpdu, dpdv) = hit(&y, Vec3::new(3.0, 0.5, 0.25), -Vec3::X).unwrap();
        assert!(uv.abs_diff_eq(Vec2::new(0.959785, 0.5), 1e-5) && close(n, Vec3::new(0.968246, 0.0, 0.25)), "{uv}");
        assert!(close(dpdu, Vec3::new(FRAC_PI_2, 0.0, -6.08367)) && close(dpdv, Vec3::Y));
        let z = cyl(Vec3::ZERO, -Vec3::Z, 1.0, &id, false);
        let (_, _, uv, _, dpdu, dpdv) = hit(&z, Vec3::new(3.0, 0.5, -0.25), -Vec3::X).unwrap();
        assert!(uv.abs_diff_eq(Vec2::new(0.916667, 0.25), 1e-5), "{uv}");
        assert!(close(dpdu, Vec3::new(PI, -5.4414, 0.0)) && close(dpdv, -Vec3::Z));
    }

    #[test]
    fn open_ends_length_and_parallel_rays() {
        let c = unit(&Transform::IDENTITY, false);
        // Along the axis through the open ends: a miss.
        assert!(hit(&c, Vec3::new(0.0, 0.0, -3.0), Vec3::Z).is_none());
        // Beyond the top or below the base: misses; through the top opening onto the inner wall.
        assert!(hit(&c, Vec3::new(3.0, 0.0, 1.5), -Vec3::X).is_none());
        assert!(hit(&c, Vec3::new(3.0, 0.0, -0.01), -Vec3::X).is_none());
        let d = Vec3::new(-1.0, 0.0, -0.5).normalize();
        let (t, p, _, n, _, _) = hit(&c, Vec3::new(0.5, 0.0, 1.5), d).unwrap();
        assert!(close(p, Vec3::new(-1.0, 0.0, 0.75)) && close(n, -Vec3::X), "{p} {t}");
        // A ray outside, parallel to the axis: no hit.
        assert!(hit(&c, Vec3::new(2.0, 0.0, -1.0), Vec3::Z).is_none());
        let b = c.bounds();
        assert!(close(b.min, Vec3::new(-1.0, -1.0, 0.0)) && close(b.max, Vec3::new(1.0, 1.0, 1.0)));
        // A slanted cylinder's box holds points sampled on it.
        let s = cyl(Vec3::new(1.0, -2.0, 0.5), Vec3::new(3.0, 1.0, -1.0), 0.7, &Transform::IDENTITY, false);
        let b = s.bounds();
        for i in 0..100 {
            let q = s.sample_area(Vec2::new((i % 10) as f32 / 9.0, (i / 10) as f32 / 10.0)).p;
            assert!(q.cmpge(b.min - 1e-5).all() && q.cmple(b.max + 1e-5).all());
        }
    }

    #[test]
    fn samples_lie_on_the_surface_with_mitsubas_normal() {
        let c = cyl(Vec3::new(1.0, -2.0, 0.5), Vec3::new(3.0, 1.0, -1.0), 0.7, &Transform::IDENTITY, true);
        let e = c.axis.normalize();
        for i in 0..64 {
            let u = Vec2::new(0.01 + 0.98 * (i as f32 * 0.618_034).fract(), (i as f32 + 0.5) / 64.0);
            let s = c.sample_area(u);
            let w = s.p - c.p0;
            let radial = w - e * w.dot(e);
            assert!((radial.length() - 0.7).abs() < 1e-5);
            assert!((w.dot(c.axis) / c.axis.length_squared() - u.x).abs() < 1e-5);
            // flip_normals: the normal points in.
            assert!(s.n.abs_diff_eq(-radial / 0.7, 1e-5));
            // The point's (u, v) are the sample's.
            let r = Ray::new(s.p + radial * 2.0, -radial);
            let h = c.intersect(&r, f32::INFINITY).unwrap();
            let uv = c.surface(&r, &h).param.uv();
            assert!((uv.x - u.y).abs() < 1e-4 || (uv.x - u.y).abs() > 0.9999, "{uv} {u}");
            assert!((uv.y - u.x).abs() < 1e-4);
        }
    }
}
