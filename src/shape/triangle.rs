//! Watertight ray-triangle intersection (Woop, Benthin and Wald 2013; pbrt-v4 sec. 6.5.3).
//!
//! The ray is transformed so it runs along +z from the origin; edge functions are then evaluated
//! in 2-D, with a double-precision fallback when one is exactly zero. Rays through an edge or
//! vertex shared by two triangles hit exactly one of them, so meshes show no cracks.

use super::{PrimHit, SurfacePoint, TriangleMesh};
use crate::geometry::{Aabb, Ray, SurfaceParam};
use crate::math::float::gamma;
use crate::math::{Vec2, Vec3};

/// Per-ray constants of the watertight test: the axis permutation and shear. Computed once per
/// traversal, not once per triangle.
#[derive(Clone, Copy, Debug)]
pub struct RayShear {
    pub(crate) kx: usize,
    pub(crate) ky: usize,
    pub(crate) kz: usize,
    pub(crate) sx: f32,
    pub(crate) sy: f32,
    pub(crate) sz: f32,
}

impl RayShear {
    /// What a traversal passes when it meets no triangle: nothing reads it, so the divisions of
    /// `new` are not made (a quarter of a small scene's shadow ray).
    pub const UNUSED: RayShear = RayShear { kx: 0, ky: 1, kz: 2, sx: 0.0, sy: 0.0, sz: 0.0 };

    #[inline]
    pub fn new(ray: &Ray) -> Self {
        let a = ray.d.abs();
        let kz = if a.x > a.y && a.x > a.z {
            0
        } else if a.y > a.z {
            1
        } else {
            2
        };
        let kx = (kz + 1) % 3;
        let ky = (kx + 1) % 3;
        let dz = ray.d[kz];
        RayShear { kx, ky, kz, sx: -ray.d[kx] / dz, sy: -ray.d[ky] / dz, sz: 1.0 / dz }
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Triangle {
    pub p: [Vec3; 3],
    /// Mesh the triangle came from (for smooth normals), `u32::MAX` for none.
    pub mesh: u32,
    /// Triangle index within that mesh.
    pub index: u32,
}

impl Triangle {
    pub fn new(p0: Vec3, p1: Vec3, p2: Vec3) -> Self {
        Triangle { p: [p0, p1, p2], mesh: u32::MAX, index: 0 }
    }

    pub fn bounds(&self) -> Aabb {
        Aabb::from_points(&self.p)
    }

    pub fn area(&self) -> f32 {
        0.5 * (self.p[1] - self.p[0]).cross(self.p[2] - self.p[0]).length()
    }

    #[inline(always)]
    pub fn intersect(&self, ray: &Ray, s: &RayShear, t_max: f32) -> Option<PrimHit> {
        intersect_triangle(&self.p, ray, s, t_max)
    }

    pub fn surface(&self, h: &PrimHit, meshes: &[TriangleMesh]) -> SurfacePoint {
        let (b1, b2) = (h.u, h.v);
        let b0 = 1.0 - b1 - b2;
        let [p0, p1, p2] = self.p;
        let p = b0 * p0 + b1 * p1 + b2 * p2;
        let p_error = gamma(7) * ((b0 * p0).abs() + (b1 * p1).abs() + (b2 * p2).abs());
        let mut ng = (p1 - p0).cross(p2 - p0).normalize_or_zero();
        if ng == Vec3::ZERO {
            ng = Vec3::Z;
        }
        let mut ns = ng;
        let mesh = meshes.get(self.mesh as usize);
        if let Some(n) = mesh.and_then(|m| m.shading_normal(self.index as usize, b0, b1, b2)) {
            ns = n;
            // Vertex normals define the outward side of a smooth mesh.
            if ng.dot(ns) < 0.0 {
                ng = -ng;
            }
        }
        // Without texture coordinates the triangle's own are (0, 0), (1, 0), (0, 1), as in
        // Mitsuba: uv = (b1, b2), dp/du = p1 - p0, dp/dv = p2 - p0.
        let mut uv = Vec2::new(b1, b2);
        let (mut dpdu, mut dpdv) = (p1 - p0, p2 - p0);
        if let Some(t) = mesh.and_then(|m| m.vertex_uvs(self.index as usize)) {
            uv = t[0] * b0 + t[1] * b1 + t[2] * b2;
            // Solve p_i - p_2 = dp/du (u_i - u_2) + dp/dv (v_i - v_2) for i = 0, 1 (pbrt-v4 6.5.3);
            // degenerate texture coordinates keep the barycentric derivatives.
            let (d02, d12) = (t[0] - t[2], t[1] - t[2]);
            let det = d02.x * d12.y - d02.y * d12.x;
            if det.abs() > 1e-12 {
                let inv = 1.0 / det;
                let (dp02, dp12) = (p0 - p2, p1 - p2);
                let (u, v) = ((d12.y * dp02 - d02.y * dp12) * inv, (d02.x * dp12 - d12.x * dp02) * inv);
                if u.is_finite() && v.is_finite() {
                    (dpdu, dpdv) = (u, v);
                }
            }
        }
        SurfacePoint { p, p_error, ng, ns, param: SurfaceParam::Known { uv, dpdu, dpdv } }
    }
}

/// The watertight test on three vertices (shared by `Triangle` and the BVH's compact leaves).
#[inline(always)]
pub fn intersect_triangle(p: &[Vec3; 3], ray: &Ray, s: &RayShear, t_max: f32) -> Option<PrimHit> {
    // Translate to the ray origin, permute so z is the dominant axis, then shear.
    let tr = |p: Vec3| {
        let q = p - ray.o;
        let (x, y, z) = (q[s.kx], q[s.ky], q[s.kz]);
        (x + s.sx * z, y + s.sy * z, z)
    };
    let (x0, y0, z0) = tr(p[0]);
    let (x1, y1, z1) = tr(p[1]);
    let (x2, y2, z2) = tr(p[2]);

    // Plain products, not fused: the edge function of an edge shared by two triangles is then
    // exactly the negation of its neighbour's, so the two always agree on which side a ray
    // passes (and software FMA would be slow on CPUs built without it).
    let mut e0 = x1 * y2 - y1 * x2;
    let mut e1 = x2 * y0 - y2 * x0;
    let mut e2 = x0 * y1 - y0 * x1;
    if e0 == 0.0 || e1 == 0.0 || e2 == 0.0 {
        let (x0, y0, x1, y1, x2, y2) = (x0 as f64, y0 as f64, x1 as f64, y1 as f64, x2 as f64, y2 as f64);
        e0 = (x1 * y2 - y1 * x2) as f32;
        e1 = (x2 * y0 - y2 * x0) as f32;
        e2 = (x0 * y1 - y0 * x1) as f32;
    }
    if (e0 < 0.0 || e1 < 0.0 || e2 < 0.0) && (e0 > 0.0 || e1 > 0.0 || e2 > 0.0) {
        return None;
    }
    let det = e0 + e1 + e2;
    // Zero, or not finite when huge coordinates overflowed the products.
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let (z0, z1, z2) = (z0 * s.sz, z1 * s.sz, z2 * s.sz);
    let t_scaled = e0 * z0 + e1 * z1 + e2 * z2;
    if det < 0.0 && (t_scaled >= 0.0 || t_scaled < t_max * det) {
        return None;
    }
    if det > 0.0 && (t_scaled <= 0.0 || t_scaled > t_max * det) {
        return None;
    }
    let inv_det = 1.0 / det;
    let t = t_scaled * inv_det;

    // Reject t that cannot be told from zero given the rounding error (pbrt-v4 eq. 6.26ff).
    let max_zt = z0.abs().max(z1.abs()).max(z2.abs());
    let delta_z = gamma(3) * max_zt;
    let max_xt = x0.abs().max(x1.abs()).max(x2.abs());
    let max_yt = y0.abs().max(y1.abs()).max(y2.abs());
    let delta_x = gamma(5) * (max_xt + max_zt);
    let delta_y = gamma(5) * (max_yt + max_zt);
    let delta_e = 2.0 * (gamma(2) * max_xt * max_yt + delta_y * max_xt + delta_x * max_yt);
    let max_e = e0.abs().max(e1.abs()).max(e2.abs());
    let delta_t = 3.0 * (gamma(3) * max_e * max_zt + delta_e * max_zt + delta_z * max_e) * inv_det.abs();
    if !(t > delta_t) || !t.is_finite() {
        return None;
    }
    Some(PrimHit { t, u: e1 * inv_det, v: e2 * inv_det })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tri() -> Triangle {
        Triangle::new(Vec3::new(-1.0, -1.0, -2.0), Vec3::new(1.0, -1.0, -2.0), Vec3::new(0.0, 1.0, -2.0))
    }

    fn cast(t: &Triangle, o: Vec3, d: Vec3) -> Option<PrimHit> {
        let r = Ray::new(o, d.normalize());
        t.intersect(&r, &RayShear::new(&r), f32::INFINITY)
    }

    #[test]
    fn triangle_hit_miss_behind_parallel() {
        let t = tri();
        let h = cast(&t, Vec3::ZERO, -Vec3::Z).unwrap();
        assert!((h.t - 2.0).abs() < 1e-6);
        let sp = t.surface(&h, &[]);
        assert!(sp.p.abs_diff_eq(Vec3::new(0.0, 0.0, -2.0), 1e-6));
        assert!(sp.ng.abs_diff_eq(Vec3::Z, 1e-6));
        // From behind the face: still a hit (triangles are two-sided).
        assert!(cast(&t, Vec3::new(0.0, 0.0, -4.0), Vec3::Z).is_some());
        assert!(cast(&t, Vec3::new(3.0, 0.0, 0.0), -Vec3::Z).is_none());
        assert!(cast(&t, Vec3::ZERO, Vec3::Z).is_none());
        assert!(cast(&t, Vec3::new(0.0, 0.0, -2.0), Vec3::X).is_none());
        // Origin on the triangle itself: no self-hit.
        assert!(cast(&t, Vec3::new(0.0, 0.0, -2.0), Vec3::new(0.1, 0.2, 1.0)).is_none());
    }

    #[test]
    fn shared_edge_is_watertight() {
        // Two triangles sharing the edge x = 0; rays exactly through the edge hit at least one.
        let a = Triangle::new(Vec3::new(0.0, -1.0, -1.0), Vec3::new(0.0, 1.0, -1.0), Vec3::new(-1.0, 0.0, -1.0));
        let b = Triangle::new(Vec3::new(0.0, 1.0, -1.0), Vec3::new(0.0, -1.0, -1.0), Vec3::new(1.0, 0.0, -1.0));
        for i in 0..1000 {
            let y = -0.9 + 1.8 * (i as f32 / 999.0);
            let o = Vec3::new(0.3, 0.1, 3.0);
            let d = Vec3::new(0.0, y, -1.0) - o;
            let hits = cast(&a, o, d).is_some() as u32 + cast(&b, o, d).is_some() as u32;
            assert!(hits >= 1, "ray through shared edge at y={y} missed both");
        }
    }
}
