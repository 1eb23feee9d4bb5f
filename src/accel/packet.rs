//! Four primitives of one kind side by side, each coordinate a row of four lanes, tested against
//! a ray at once with SSE (glam's `Vec4`): what a small scene's BVH tests every ray against in
//! place of a tree (`Packets`).
//!
//! Each lane repeats its scalar test's arithmetic operation for operation and in the same order
//! (`intersect_quad`, `intersect_triangle`, `Sphere::intersect`): IEEE arithmetic is the same in a
//! lane as in a scalar register, so a packet finds exactly the hits, distances and surface
//! coordinates the scalar tests find. A triangle lane that the scalar test would send down its
//! slower path (an edge function of exactly zero, recomputed in double precision) is handed to the
//! scalar test itself. `tests` checks the equality on random and degenerate cases.

use crate::geometry::Ray;
use crate::math::float::gamma;
use crate::shape::{CompactShape, PrimHit, RayShear};
use glam::{BVec4A, Vec3, Vec4};

/// Rows x, y, z of four points or vectors.
#[derive(Clone, Copy, Debug)]
struct Rows([Vec4; 3]);

impl Rows {
    fn gather(v: [Vec3; 4]) -> Rows {
        Rows(std::array::from_fn(|a| Vec4::new(v[0][a], v[1][a], v[2][a], v[3][a])))
    }

    #[inline(always)]
    fn splat(v: Vec3) -> Rows {
        Rows([Vec4::splat(v.x), Vec4::splat(v.y), Vec4::splat(v.z)])
    }

    #[inline(always)]
    fn x(&self) -> Vec4 {
        self.0[0]
    }

    #[inline(always)]
    fn y(&self) -> Vec4 {
        self.0[1]
    }

    #[inline(always)]
    fn z(&self) -> Vec4 {
        self.0[2]
    }

    /// As glam's `Vec3::dot`: (x x' + y y') + z z'.
    #[inline(always)]
    fn dot(&self, o: &Rows) -> Vec4 {
        self.x() * o.x() + self.y() * o.y() + self.z() * o.z()
    }

    /// As glam's `Vec3::cross`.
    #[inline(always)]
    fn cross(&self, o: &Rows) -> Rows {
        Rows([
            self.y() * o.z() - o.y() * self.z(),
            self.z() * o.x() - o.z() * self.x(),
            self.x() * o.y() - o.x() * self.y(),
        ])
    }

    #[inline(always)]
    fn sub(&self, o: &Rows) -> Rows {
        Rows([self.x() - o.x(), self.y() - o.y(), self.z() - o.z()])
    }
}

/// The ray, splatted across lanes once for every packet it meets.
pub(super) struct PacketRay {
    o: Rows,
    d: Rows,
    /// `d.length_squared()`, and its square root (spheres).
    a: Vec4,
    sqrt_a: Vec4,
}

impl PacketRay {
    #[inline(always)]
    pub(super) fn new(ray: &Ray) -> Self {
        let a = ray.d.length_squared();
        PacketRay { o: Rows::splat(ray.o), d: Rows::splat(ray.d), a: Vec4::splat(a), sqrt_a: Vec4::splat(a.sqrt()) }
    }
}

/// Four quads (corner, edges, and the normal e1 x e2 and 1 / |e1 x e2|^2 the scalar test
/// computes per ray, worked out once with the same operations).
#[derive(Clone, Copy, Debug)]
struct QuadPacket {
    p0: Rows,
    e1: Rows,
    e2: Rows,
    c: Rows,
    inv: Vec4,
}

impl QuadPacket {
    fn new(q: [[Vec3; 3]; 4]) -> Self {
        let c = q.map(|[_, e1, e2]| e1.cross(e2));
        QuadPacket {
            p0: Rows::gather(q.map(|q| q[0])),
            e1: Rows::gather(q.map(|q| q[1])),
            e2: Rows::gather(q.map(|q| q[2])),
            c: Rows::gather(c),
            inv: Vec4::from_array(c.map(|c| 1.0 / c.length_squared())),
        }
    }

    /// Lanes hit in (0, t_max), with their distances and (u, v).
    #[inline(always)]
    fn hits(&self, r: &PacketRay, t_max: f32) -> (BVec4A, Vec4, Vec4, Vec4) {
        let denom = self.c.dot(&r.d);
        let t = self.c.dot(&self.p0.sub(&r.o)) / denom;
        let mut mask = denom.cmpne(Vec4::ZERO) & t.cmpgt(Vec4::ZERO) & t.cmplt(Vec4::splat(t_max));
        if !mask.any() {
            return (mask, t, t, t);
        }
        let at = Rows([r.o.x() + r.d.x() * t, r.o.y() + r.d.y() * t, r.o.z() + r.d.z() * t]);
        let q = at.sub(&self.p0);
        let u = self.c.dot(&q.cross(&self.e2)) * self.inv;
        let v = self.c.dot(&self.e1.cross(&q)) * self.inv;
        let (zero, one) = (Vec4::ZERO, Vec4::ONE);
        mask &= u.cmpge(zero) & u.cmple(one) & v.cmpge(zero) & v.cmple(one);
        (mask, t, u, v)
    }
}

/// Four triangles' vertices.
#[derive(Clone, Copy, Debug)]
struct TrianglePacket {
    p: [Rows; 3],
}

impl TrianglePacket {
    fn new(t: [[Vec3; 3]; 4]) -> Self {
        TrianglePacket { p: std::array::from_fn(|k| Rows::gather(t.map(|t| t[k]))) }
    }

    /// Lanes hit in (0, t_max) with their distances and barycentrics (b1, b2), and the lanes the
    /// scalar test must decide (an edge function of exactly zero).
    #[inline(always)]
    fn hits(&self, r: &PacketRay, s: &RayShear, t_max: f32) -> (BVec4A, BVec4A, Vec4, Vec4, Vec4) {
        let (sx, sy, sz) = (Vec4::splat(s.sx), Vec4::splat(s.sy), Vec4::splat(s.sz));
        // Translate to the ray origin, permute so z is the dominant axis, then shear.
        let tr = |p: &Rows| {
            let q = p.sub(&r.o);
            let (x, y, z) = (q.0[s.kx], q.0[s.ky], q.0[s.kz]);
            (x + sx * z, y + sy * z, z)
        };
        let (x0, y0, z0) = tr(&self.p[0]);
        let (x1, y1, z1) = tr(&self.p[1]);
        let (x2, y2, z2) = tr(&self.p[2]);
        let e0 = x1 * y2 - y1 * x2;
        let e1 = x2 * y0 - y2 * x0;
        let e2 = x0 * y1 - y0 * x1;
        let zero = Vec4::ZERO;
        let scalar = e0.cmpeq(zero) | e1.cmpeq(zero) | e2.cmpeq(zero);
        let neg = e0.cmplt(zero) | e1.cmplt(zero) | e2.cmplt(zero);
        let pos = e0.cmpgt(zero) | e1.cmpgt(zero) | e2.cmpgt(zero);
        let det = e0 + e1 + e2;
        let mut mask = !(neg & pos) & det.cmpne(zero) & det.is_finite_mask() & !scalar;
        if !mask.any() {
            return (mask, scalar, det, det, det);
        }
        let (z0, z1, z2) = (z0 * sz, z1 * sz, z2 * sz);
        let t_scaled = e0 * z0 + e1 * z1 + e2 * z2;
        let bound = Vec4::splat(t_max) * det;
        let below = det.cmplt(zero) & (t_scaled.cmpge(zero) | t_scaled.cmplt(bound));
        let above = det.cmpgt(zero) & (t_scaled.cmple(zero) | t_scaled.cmpgt(bound));
        mask &= !(below | above);
        let inv_det = Vec4::ONE / det;
        let t = t_scaled * inv_det;
        // Reject t that cannot be told from zero given the rounding error (pbrt-v4 eq. 6.26ff).
        let max_zt = z0.abs().max(z1.abs()).max(z2.abs());
        let delta_z = Vec4::splat(gamma(3)) * max_zt;
        let max_xt = x0.abs().max(x1.abs()).max(x2.abs());
        let max_yt = y0.abs().max(y1.abs()).max(y2.abs());
        let delta_x = Vec4::splat(gamma(5)) * (max_xt + max_zt);
        let delta_y = Vec4::splat(gamma(5)) * (max_yt + max_zt);
        let delta_e =
            Vec4::splat(2.0) * (Vec4::splat(gamma(2)) * max_xt * max_yt + delta_y * max_xt + delta_x * max_yt);
        let max_e = e0.abs().max(e1.abs()).max(e2.abs());
        let delta_t = Vec4::splat(3.0)
            * (Vec4::splat(gamma(3)) * max_e * max_zt + delta_e * max_zt + delta_z * max_e)
            * inv_det.abs();
        mask &= t.cmpgt(delta_t) & t.is_finite_mask();
        (mask, scalar, t, e1 * inv_det, e2 * inv_det)
    }
}

/// Four spheres.
#[derive(Clone, Copy, Debug)]
struct SpherePacket {
    center: Rows,
    radius: Vec4,
}

impl SpherePacket {
    /// Lanes hit in (0, t_max) and their distances: the nearer root beyond the distance within
    /// which a root is the surface the ray starts on, else the farther.
    #[inline(always)]
    fn hits(&self, r: &PacketRay, t_max: f32) -> (BVec4A, Vec4) {
        let f = r.o.sub(&self.center);
        let b = -f.dot(&r.d);
        let ba = b / r.a;
        let l = Rows([f.x() + r.d.x() * ba, f.y() + r.d.y() * ba, f.z() + r.d.z() * ba]);
        let r2 = self.radius * self.radius;
        let disc = r.a * (r2 - l.dot(&l));
        let zero = Vec4::ZERO;
        let mut mask = !disc.cmplt(zero);
        if !mask.any() {
            return (mask, disc);
        }
        let c = f.dot(&f) - r2;
        let q = b + disc.sqrt().copysign(b);
        let q_zero = q.cmpeq(zero);
        let t0 = Vec4::select(q_zero, zero, c / q);
        let t1 = Vec4::select(q_zero, zero, q / r.a);
        let swap = t0.cmpgt(t1);
        let (t0, t1) = (Vec4::select(swap, t1, t0), Vec4::select(swap, t0, t1));
        let f_max = f.x().abs().max(f.y().abs().max(f.z().abs()));
        let t_eps = Vec4::splat(gamma(8)) * (f_max + self.radius) / r.sqrt_a;
        let near = t0.cmpgt(t_eps);
        let t = Vec4::select(near, t0, t1);
        mask &= (near | t1.cmpgt(t_eps)) & t.cmplt(Vec4::splat(t_max));
        (mask, t)
    }
}

#[derive(Clone, Copy, Debug)]
enum Kind {
    Quads(QuadPacket),
    Triangles(TrianglePacket),
    Spheres(SpherePacket),
}

/// Four primitives of one kind and the indices of those in use (`lanes` of them).
#[derive(Clone, Copy, Debug)]
struct Packet {
    kind: Kind,
    prim: [u32; 4],
    lanes: u32,
}

/// A set of primitives as packets by kind, with the shapes no packet holds tested one by one.
#[derive(Clone, Debug, Default)]
pub(super) struct Packets {
    packets: Vec<Packet>,
    /// Primitives tested alone (disks, cylinders, voxels).
    others: Vec<u32>,
}

impl Packets {
    /// Packets of `shapes` (indices are into it).
    pub(super) fn new(shapes: &[CompactShape]) -> Packets {
        let (mut quads, mut triangles, mut spheres, mut others) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        for (i, s) in shapes.iter().enumerate() {
            let i = i as u32;
            match s {
                CompactShape::Quad(q) => quads.push((i, *q)),
                CompactShape::Triangle(t) => triangles.push((i, *t)),
                CompactShape::Sphere(s) => spheres.push((i, (s.center, s.radius))),
                CompactShape::Disk(_)
                | CompactShape::Cylinder { .. }
                | CompactShape::Plane(_)
                | CompactShape::SdfVoxel(_) => others.push(i),
            }
        }
        let mut packets = Vec::new();
        // Unused lanes repeat the last primitive and are masked off by `lanes`.
        fn fill<T: Copy>(group: &[(u32, T)], k: usize) -> (u32, T) {
            group[k.min(group.len() - 1)]
        }
        for g in quads.chunks(4) {
            let kind = Kind::Quads(QuadPacket::new(std::array::from_fn(|k| fill(g, k).1)));
            packets.push(Packet { kind, prim: std::array::from_fn(|k| fill(g, k).0), lanes: g.len() as u32 });
        }
        for g in triangles.chunks(4) {
            let kind = Kind::Triangles(TrianglePacket::new(std::array::from_fn(|k| fill(g, k).1)));
            packets.push(Packet { kind, prim: std::array::from_fn(|k| fill(g, k).0), lanes: g.len() as u32 });
        }
        for g in spheres.chunks(4) {
            let s: [(Vec3, f32); 4] = std::array::from_fn(|k| fill(g, k).1);
            let kind = Kind::Spheres(SpherePacket {
                center: Rows::gather(s.map(|s| s.0)),
                radius: Vec4::from_array(s.map(|s| s.1)),
            });
            packets.push(Packet { kind, prim: std::array::from_fn(|k| fill(g, k).0), lanes: g.len() as u32 });
        }
        Packets { packets, others }
    }

    /// Bytes held.
    pub(super) fn memory_bytes(&self) -> usize {
        self.packets.capacity() * std::mem::size_of::<Packet>() + self.others.capacity() * 4
    }

    /// The closest hit in (0, *closest) among the set (`shapes` as given to `new`), lowering
    /// `*closest` to it: its primitive and hit. Of equally distant hits, the first packet's and
    /// lowest lane's wins.
    #[inline(always)]
    pub(super) fn intersect(
        &self,
        shapes: &[CompactShape],
        ray: &Ray,
        shear: &RayShear,
        closest: &mut f32,
    ) -> Option<(usize, PrimHit)> {
        let r = PacketRay::new(ray);
        let mut best = None;
        for p in &self.packets {
            if p.lanes == 1 {
                // One primitive left over: its scalar test, whose operations a lane repeats,
                // is a quarter of the packet's work (the same hit, and tested in the same turn).
                let i = p.prim[0] as usize;
                if let Some(h) = shapes[i].intersect(ray, shear, *closest) {
                    *closest = h.t;
                    best = Some((i, h));
                }
                continue;
            }
            let live = (1u32 << p.lanes) - 1;
            let (mask, t, u, v, scalar) = match &p.kind {
                Kind::Quads(q) => {
                    let (m, t, u, v) = q.hits(&r, *closest);
                    (m.bitmask(), t, u, v, 0)
                }
                Kind::Triangles(tp) => {
                    let (m, s, t, u, v) = tp.hits(&r, shear, *closest);
                    (m.bitmask(), t, u, v, s.bitmask() & live)
                }
                Kind::Spheres(sp) => {
                    let (m, t) = sp.hits(&r, *closest);
                    (m.bitmask(), t, Vec4::ZERO, Vec4::ZERO, 0)
                }
            };
            // Lanes hit or left to the scalar test, in lane order (a lane in neither has no hit).
            let mut todo = (mask | scalar) & live;
            if todo == 0 {
                continue;
            }
            let (t, u, v) = (t.to_array(), u.to_array(), v.to_array());
            while todo != 0 {
                let k = todo.trailing_zeros() as usize;
                todo &= todo - 1;
                let hit = if scalar & (1 << k) != 0 {
                    shapes[p.prim[k] as usize].intersect(ray, shear, *closest)
                } else if t[k] < *closest {
                    Some(PrimHit { t: t[k], u: u[k], v: v[k] })
                } else {
                    None
                };
                if let Some(h) = hit {
                    *closest = h.t;
                    best = Some((p.prim[k] as usize, h));
                }
            }
        }
        for &i in &self.others {
            if let Some(h) = shapes[i as usize].intersect(ray, shear, *closest) {
                *closest = h.t;
                best = Some((i as usize, h));
            }
        }
        best
    }

    /// True when some primitive of the set is hit in (0, t_max).
    #[inline(always)]
    pub(super) fn occluded(&self, shapes: &[CompactShape], ray: &Ray, shear: &RayShear, t_max: f32) -> bool {
        let r = PacketRay::new(ray);
        for p in &self.packets {
            if p.lanes == 1 {
                // As in `intersect`: a lone primitive by its scalar test.
                if shapes[p.prim[0] as usize].intersect(ray, shear, t_max).is_some() {
                    return true;
                }
                continue;
            }
            let live = (1u32 << p.lanes) - 1;
            let (mask, scalar) = match &p.kind {
                Kind::Quads(q) => (q.hits(&r, t_max).0.bitmask(), 0),
                Kind::Triangles(tp) => {
                    let (m, s, ..) = tp.hits(&r, shear, t_max);
                    (m.bitmask(), s.bitmask())
                }
                Kind::Spheres(sp) => (sp.hits(&r, t_max).0.bitmask(), 0),
            };
            if mask & live != 0 {
                return true;
            }
            let mut scalar = scalar & live;
            while scalar != 0 {
                let k = scalar.trailing_zeros() as usize;
                scalar &= scalar - 1;
                if shapes[p.prim[k] as usize].intersect(ray, shear, t_max).is_some() {
                    return true;
                }
            }
        }
        self.others.iter().any(|&i| shapes[i as usize].intersect(ray, shear, t_max).is_some())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng32;
    use crate::shape::Sphere;

    /// The closest hit of the scalar tests, primitive by primitive in index order.
    fn scalar_closest(shapes: &[CompactShape], ray: &Ray, t_max: f32) -> Option<(usize, PrimHit)> {
        let shear = RayShear::new(ray);
        let mut closest = t_max;
        let mut best = None;
        for (i, s) in shapes.iter().enumerate() {
            if let Some(h) = s.intersect(ray, &shear, closest) {
                closest = h.t;
                best = Some((i, h));
            }
        }
        best
    }

    fn point(rng: &mut Rng32, scale: f32) -> Vec3 {
        Vec3::new(rng.uniform() - 0.5, rng.uniform() - 0.5, rng.uniform() - 0.5) * scale
    }

    /// Random quads, triangles (some sharing edges and vertices), spheres and a disk.
    fn shapes(rng: &mut Rng32, n: usize) -> Vec<CompactShape> {
        let mut out = Vec::new();
        while out.len() < n {
            let c = point(rng, 4.0);
            match out.len() % 4 {
                0 => out.push(CompactShape::Quad([c, point(rng, 2.0), point(rng, 2.0)])),
                1 => {
                    // Two triangles sharing the edge (a, b), often axis-aligned so rays graze it.
                    let (a, b) = (c.round(), (c + point(rng, 2.0)).round());
                    out.push(CompactShape::Triangle([a, b, c + point(rng, 2.0)]));
                    out.push(CompactShape::Triangle([b, a, c + point(rng, 2.0)]));
                }
                2 => out.push(CompactShape::Sphere(Sphere::new(c, 0.1 + rng.uniform()))),
                _ => out.push(CompactShape::Disk([c, point(rng, 1.0), point(rng, 1.0)])),
            }
        }
        out
    }

    /// Rays from random points, from points on the shapes' corners and edges (exact zeros of the
    /// edge functions), and along the axes.
    fn rays(rng: &mut Rng32, shapes: &[CompactShape]) -> Vec<Ray> {
        let mut out = Vec::new();
        for _ in 0..400 {
            let o = point(rng, 12.0);
            let target = match shapes[(rng.uniform() * shapes.len() as f32) as usize % shapes.len()] {
                CompactShape::Triangle([a, b, _]) => a + (b - a) * (rng.uniform() * 4.0).floor() * 0.25,
                CompactShape::Quad([p0, e1, _]) => p0 + e1 * 0.5,
                CompactShape::Sphere(s) => s.center + Vec3::X * s.radius,
                _ => point(rng, 4.0),
            };
            let d = target - o;
            if d.length_squared() > 0.0 {
                out.push(Ray::new(o, d.normalize()));
            }
            let axis = [Vec3::X, Vec3::Y, Vec3::Z, -Vec3::X, -Vec3::Y, -Vec3::Z][out.len() % 6];
            out.push(Ray::new(target.round() - axis * 10.0, axis));
        }
        out
    }

    /// Packets find the closest hit the scalar tests find: the same distance bit for bit, the
    /// same primitive and surface coordinates unless two primitives tie, and the same answer to
    /// shadow rays.
    #[test]
    fn packets_find_the_scalar_hits() {
        let mut rng = Rng32::new(7);
        let (mut hits, mut ties) = (0, 0);
        for n in [1, 3, 4, 5, 8, 13] {
            for _ in 0..20 {
                let shapes = shapes(&mut rng, n);
                let packets = Packets::new(&shapes);
                for ray in rays(&mut rng, &shapes) {
                    for t_max in [f32::INFINITY, 6.0] {
                        let want = scalar_closest(&shapes, &ray, t_max);
                        let mut closest = t_max;
                        let got = packets.intersect(&shapes, &ray, &RayShear::new(&ray), &mut closest);
                        match (want, got) {
                            (None, None) => {}
                            (Some((i, a)), Some((j, b))) => {
                                if i == j {
                                    assert_eq!(a.t.to_bits(), b.t.to_bits(), "{ray:?}: {:?}", shapes[i]);
                                    assert_eq!((a.u.to_bits(), a.v.to_bits()), (b.u.to_bits(), b.v.to_bits()));
                                } else {
                                    // A tie within rounding (a ray through an edge two triangles
                                    // share): a triangle is tested against the closest distance
                                    // so far in its own scaled units, so which of the two wins
                                    // depends on the order they are met in.
                                    let ulps = (a.t.to_bits() as i64 - b.t.to_bits() as i64).abs();
                                    assert!(
                                        ulps <= 4,
                                        "{ray:?}: {:?} at {} vs {:?} at {}",
                                        shapes[i],
                                        a.t,
                                        shapes[j],
                                        b.t
                                    );
                                    ties += 1;
                                }
                                assert_eq!(closest, b.t);
                                hits += 1;
                            }
                            _ => panic!("{ray:?} t_max {t_max}: scalar {want:?}, packets {got:?}"),
                        }
                        let shear = RayShear::new(&ray);
                        assert_eq!(packets.occluded(&shapes, &ray, &shear, t_max), want.is_some(), "{ray:?}");
                    }
                }
            }
        }
        // Rays here are aimed at shared edges on purpose; ties stay a small part of them.
        assert!(hits > 5000 && ties < hits / 20, "{hits} hits compared, {ties} ties");
    }
}
