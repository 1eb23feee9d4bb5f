//! Two-level acceleration for instancing: each group of primitives has its own BVH, built once
//! in the group's space, and a top-level BVH over the instances, each holding the group's index
//! and its transform both ways. A ray reaching an instance is moved into the group's space and
//! traced through the group's BVH; the hit found there is moved back to world space with its
//! error bound grown by the transform's rounding (pbrt-v4's `TransformedPrimitive`, sec. 6.8.6
//! and 7.1.2), so rays leaving an instanced surface start off it as from any other.
//!
//! An instance costs two 3 x 4 matrices and an index (100 bytes) plus its share of the
//! top-level tree; the group's geometry is stored once however many instances there are.

use super::Bvh;
use super::build::{BuildPrim, build_wide, permute};
use super::wide::{WideNode, traverse};
use crate::geometry::{Aabb, Ray, SurfaceParam, Transform};
use crate::math::Vec3;
use crate::math::float::gamma;
use crate::shape::{PrimHit, Primitives, SurfacePoint, TriangleMesh};
use glam::Affine3;

/// A group placed in the scene.
#[derive(Clone, Copy, Debug)]
pub struct Instance {
    /// From world space to the group's: rays go this way.
    to_object: Affine3,
    /// From the group's space to world: hits come back this way.
    to_world: Affine3,
    pub group: u32,
}

impl Instance {
    /// `None` when the transform cannot be inverted or is not finite.
    pub fn new(group: u32, t: &Transform) -> Option<Self> {
        if !t.is_valid() {
            return None;
        }
        let to_world = Affine3::from_mat4(t.m);
        let to_object = to_world.inverse();
        to_object.is_finite().then_some(Instance { to_object, to_world, group })
    }

    /// The world ray in the group's space, and how far its origin was moved along it. The
    /// direction is not normalised, so distances along the ray are the same in both spaces.
    /// The transformed origin is pushed forward to the edge of its rounding error, so it
    /// cannot fall behind the surface the world ray left (pbrt-v4 `Transform::ApplyInverse`).
    #[inline(always)]
    fn object_ray(&self, ray: &Ray) -> (Ray, f32) {
        let m = &self.to_object;
        let o = m.transform_point3(ray.o);
        let d = m.matrix3 * ray.d;
        let err = gamma(3) * (m.matrix3.abs() * ray.o.abs() + m.translation.abs());
        let l2 = d.length_squared();
        let dt = if l2 > 0.0 { d.abs().dot(err) / l2 } else { 0.0 };
        (Ray::new(o + d * dt, d), dt)
    }

    /// A surface point of the group moved to world space. The error bound adds the rounding
    /// of the transform to the transformed bound of the point (pbrt-v4's transform of an
    /// interval point), and also the rounding that moving a ray spawned there back into the
    /// group's space will add (`object_ray`), carried to world space: so that round trip cannot
    /// put the origin of a ray leaving the surface behind it. (Pushing the origin along the ray,
    /// as `object_ray` does, covers that rounding along the ray only, not across a grazing
    /// ray far from the world's origin.) Normals go by the inverse transpose, tangents by the
    /// matrix itself.
    #[inline]
    fn surface_to_world(&self, sp: &SurfacePoint) -> SurfacePoint {
        let (m, t) = (self.to_world.matrix3, self.to_world.translation);
        let am = m.abs();
        let p = m * sp.p + t;
        let inv = &self.to_object;
        let back = gamma(4) * (inv.matrix3.abs() * p.abs() + inv.translation.abs());
        let p_error = (1.0 + gamma(3)) * (am * sp.p_error)
            + gamma(3) * (am * sp.p.abs() + t.abs())
            + (1.0 + gamma(3)) * (am * back);
        let n = inv.matrix3.transpose();
        let ng = (n * sp.ng).normalize_or_zero();
        let ns = (n * sp.ns).normalize_or_zero();
        let param = SurfaceParam::Known { uv: sp.param.uv(), dpdu: m * sp.param.dpdu(), dpdv: m * sp.param.dpdv() };
        SurfacePoint { p, p_error, ng, ns: if ns == Vec3::ZERO { ng } else { ns }, param }
    }

    /// World bounds of `b` (the group's bounds): the box of its eight transformed corners.
    fn bounds_of(&self, b: Aabb) -> Aabb {
        let corners: [Vec3; 8] = std::array::from_fn(|i| {
            let pick = |bit: usize, axis: usize| if i & bit == 0 { b.min[axis] } else { b.max[axis] };
            self.to_world.transform_point3(Vec3::new(pick(1, 0), pick(2, 1), pick(4, 2)))
        });
        Aabb::from_points(&corners)
    }
}

/// A closest hit on an instance.
#[derive(Clone, Copy, Debug)]
pub struct InstanceHit {
    /// Distance along the world ray.
    pub t: f32,
    /// Index of the instance (in `Instances`' order).
    pub instance: u32,
    /// Index of the primitive in its group's BVH.
    pub prim: u32,
    /// The hit on the group's ray (`ray`), as the shape reported it.
    pub hit: PrimHit,
    /// The ray in the group's space.
    pub ray: Ray,
}

/// Groups and their instances, with the top-level BVH over the instances.
#[derive(Default)]
pub struct Instances {
    nodes: Vec<WideNode>,
    /// Node levels of the top-level tree, and its bounds.
    depth: u32,
    bounds: Aabb,
    /// Instances in leaf order.
    instances: Vec<Instance>,
    /// World bounds of each instance, in leaf order: a leaf of the top-level tree holds several
    /// instances, and a ray that misses one's box skips moving into its space.
    instance_boxes: Vec<Aabb>,
    groups: Vec<Bvh>,
}

impl Instances {
    /// Builds each group's BVH once and the tree over the instances; instances of empty groups
    /// are dropped.
    /// `meshes` are the scene's meshes, which the groups' mesh triangles index.
    pub fn build(groups: Vec<Primitives>, mut instances: Vec<Instance>, meshes: &[TriangleMesh]) -> Self {
        let groups: Vec<Bvh> = groups.into_iter().map(|g| Bvh::build(g, meshes)).collect();
        let group_bounds: Vec<Aabb> = groups.iter().map(Bvh::bounds).collect();
        instances.retain(|i| !group_bounds[i.group as usize].is_empty());
        instances.shrink_to_fit();
        let mut build: Vec<BuildPrim> = instances
            .iter()
            .enumerate()
            .map(|(k, i)| BuildPrim::new(i.bounds_of(group_bounds[i.group as usize]), k))
            .collect();
        let tree = build_wide(&mut build);
        let mut order: Vec<u32> = build.iter().map(BuildPrim::index).collect();
        drop(build);
        permute(&mut instances, &mut order);
        let instance_boxes = instances.iter().map(|i| i.bounds_of(group_bounds[i.group as usize])).collect();
        Instances { depth: tree.depth, bounds: tree.bounds, nodes: tree.nodes(), instances, instance_boxes, groups }
    }

    pub fn is_empty(&self) -> bool {
        self.instances.is_empty()
    }

    pub fn len(&self) -> usize {
        self.instances.len()
    }

    pub fn group_count(&self) -> usize {
        self.groups.len()
    }

    pub fn bounds(&self) -> Aabb {
        self.bounds
    }

    /// The material of every primitive of group `g`.
    pub fn group_materials(&self, g: usize) -> impl Iterator<Item = u32> + '_ {
        let bvh = &self.groups[g];
        (0..bvh.len() as u32).map(move |i| bvh.material_light(i).0)
    }

    /// World bounds of each instance (in `Instances`' order).
    pub fn instance_bounds(&self) -> impl Iterator<Item = (u32, Aabb)> + '_ {
        self.instances.iter().map(|i| (i.group, i.bounds_of(self.groups[i.group as usize].bounds())))
    }

    /// Nodes of the top-level tree and of all groups' trees.
    pub fn node_count(&self) -> usize {
        self.nodes.len() + self.groups.iter().map(Bvh::node_count).sum::<usize>()
    }

    /// Bytes held by the instances, the top-level tree and the groups' trees and primitives.
    pub fn memory_bytes(&self) -> usize {
        self.instances.capacity() * std::mem::size_of::<Instance>()
            + self.instance_boxes.capacity() * std::mem::size_of::<Aabb>()
            + self.nodes.capacity() * std::mem::size_of::<WideNode>()
            + self.groups.iter().map(Bvh::memory_bytes).sum::<usize>()
    }

    /// A hit's surface point in world space and its primitive's material and light; `meshes`
    /// are the scene's meshes.
    #[inline]
    pub fn surface(&self, h: &InstanceHit, meshes: &[TriangleMesh]) -> (SurfacePoint, u32, u32) {
        let inst = &self.instances[h.instance as usize];
        let group = &self.groups[inst.group as usize];
        let sp = group.surface(h.prim, &h.ray, &h.hit, meshes);
        let (material, light) = group.material_light(h.prim);
        (inst.surface_to_world(&sp), material, light)
    }

    /// Closest hit in (0, t_max) on any instance.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<InstanceHit> {
        let mut closest = t_max;
        let mut best = None;
        self.traverse(ray, &mut closest, |k, closest| {
            let inst = &self.instances[k];
            let (r, dt) = inst.object_ray(ray);
            let tm = *closest - dt;
            if !(tm > 0.0) {
                return false;
            }
            if let Some((prim, hit)) = self.groups[inst.group as usize].intersect(&r, tm) {
                *closest = (hit.t + dt).min(*closest);
                best = Some(InstanceHit { t: *closest, instance: k as u32, prim, hit, ray: r });
            }
            false
        });
        best
    }

    /// True when any instance blocks the ray in (0, t_max).
    #[inline]
    pub fn occluded(&self, ray: &Ray, t_max: f32) -> bool {
        let mut closest = t_max;
        self.traverse(ray, &mut closest, |k, closest| {
            let inst = &self.instances[k];
            let (r, dt) = inst.object_ray(ray);
            let tm = *closest - dt;
            tm > 0.0 && self.groups[inst.group as usize].occluded(&r, tm)
        })
    }

    /// Visits the instances whose boxes the ray enters before `closest`, nearest first;
    /// `visit(instance, closest)` may lower `closest` and returns true to stop. Returns whether
    /// it was stopped.
    #[inline(always)]
    fn traverse(&self, ray: &Ray, closest: &mut f32, mut visit: impl FnMut(usize, &mut f32) -> bool) -> bool {
        let inv = ray.d.recip();
        traverse::<true>(&self.nodes, self.depth, ray, closest, |first, count, closest| {
            if count == 1 {
                return visit(first, closest);
            }
            (first..first + count).any(|k| enters(&self.instance_boxes[k], ray.o, inv, *closest) && visit(k, closest))
        })
    }
}

/// True when the ray (origin `o`, reciprocal direction `inv`) enters box `b` before `t_max`,
/// with the wide nodes' robust widening of the exit distance. The near plane of each slab is
/// picked by the sign of `inv` (so a -0 direction picks the right side), and a NaN plane
/// distance (an origin on a plane the ray runs along) leaves that slab unconstrained: `f32::max`
/// and `min` return the other operand.
#[inline(always)]
fn enters(b: &Aabb, o: Vec3, inv: Vec3, t_max: f32) -> bool {
    let neg = inv.cmplt(Vec3::ZERO);
    let t_near = (Vec3::select(neg, b.max, b.min) - o) * inv;
    let t_far = (Vec3::select(neg, b.min, b.max) - o) * inv;
    let near = 0.0f32.max(t_near.x).max(t_near.y).max(t_near.z);
    let far = f32::INFINITY.min(t_far.x).min(t_far.y).min(t_far.z) * (1.0 + 2.0 * gamma(3));
    near <= far && near < t_max
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::NO_LIGHT;
    use crate::shape::{Primitive, RayShear, Shape, Sphere, Triangle};

    #[test]
    fn box_entry_test_keeps_rays_along_a_face_and_refuses_misses() {
        let b = Aabb { min: Vec3::ZERO, max: Vec3::ONE };
        let enter = |o: Vec3, d: Vec3, t_max: f32| enters(&b, o, d.recip(), t_max);
        assert!(enter(Vec3::new(0.5, 0.5, -1.0), Vec3::Z, f32::INFINITY));
        assert!(!enter(Vec3::new(0.5, 0.5, -1.0), Vec3::Z, 0.99), "entered beyond t_max");
        assert!(!enter(Vec3::new(0.5, 0.5, -1.0), -Vec3::Z, f32::INFINITY), "box behind");
        assert!(!enter(Vec3::new(1.5, 0.5, -1.0), Vec3::Z, f32::INFINITY));
        // Along the face x = 0 (0 * inf is NaN there), with +0 and -0 directions in x.
        assert!(enter(Vec3::new(0.0, 0.5, -1.0), Vec3::Z, f32::INFINITY));
        assert!(enter(Vec3::new(0.0, 0.5, -1.0), Vec3::new(-0.0, 0.0, 1.0), f32::INFINITY));
        assert!(enter(Vec3::new(1.0, 0.5, -1.0), Vec3::new(-0.0, 0.0, 1.0), f32::INFINITY));
        // Starting inside.
        assert!(enter(Vec3::splat(0.5), Vec3::new(0.3, -0.4, 0.8).normalize(), 1e-3));
    }

    #[test]
    fn permute_in_place_matches_a_copy() {
        let items: Vec<u32> = (0..50).map(|i| i * 7).collect();
        let order: Vec<u32> = (0..50u32).map(|i| (i * 17 + 3) % 50).collect();
        let expected: Vec<u32> = order.iter().map(|&k| items[k as usize]).collect();
        let (mut got, mut o) = (items.clone(), order.clone());
        permute(&mut got, &mut o);
        assert_eq!(got, expected);
    }

    fn prim(shape: Shape) -> Primitive {
        Primitive { shape, material: 0, light: NO_LIGHT }
    }

    /// An instanced triangle and sphere give the hits of the same shapes placed by hand.
    #[test]
    fn instanced_hits_equal_transformed_shapes() {
        let tri = Triangle::new(Vec3::new(-1.0, -1.0, 0.0), Vec3::new(1.0, -1.0, 0.0), Vec3::new(0.0, 1.0, 0.0));
        let sphere = Sphere::new(Vec3::new(0.0, 0.0, -3.0), 0.5);
        let t = Transform::scale(Vec3::new(2.0, 1.0, 1.5))
            .then(Transform::rotate(Vec3::new(1.0, 2.0, 0.5), 37.0))
            .then(Transform::translate(Vec3::new(0.3, -0.2, -5.0)));
        let inst = Instances::build(
            vec![vec![prim(Shape::Triangle(tri)), prim(Shape::Sphere(sphere))].into()],
            vec![Instance::new(0, &t).unwrap()],
            &[],
        );
        let placed = Triangle::new(t.point(tri.p[0]), t.point(tri.p[1]), t.point(tri.p[2]));
        let mut hits = 0;
        for i in 0..1600 {
            let (x, y) = ((i % 40) as f32 / 20.0 - 1.0, (i / 40) as f32 / 20.0 - 1.0);
            let ray = Ray::new(Vec3::new(x * 3.0, y * 3.0, 5.0), Vec3::new(x * 0.1, y * 0.1, -1.0).normalize());
            let expect = placed.intersect(&ray, &RayShear::new(&ray), f32::INFINITY);
            let got = inst.intersect(&ray, f32::INFINITY);
            if let (Some(e), Some(g)) = (expect, got)
                && matches!(inst.groups[0].prims().get(g.prim as usize, &[]).shape, Shape::Triangle(_))
                && let (sp, _, _) = inst.surface(&g, &[])
            {
                hits += 1;
                assert!((e.t - g.t).abs() < 1e-4 * e.t, "{} vs {}", e.t, g.t);
                assert!((sp.p - ray.at(e.t)).length() < 1e-4);
                let ng = (placed.p[1] - placed.p[0]).cross(placed.p[2] - placed.p[0]).normalize();
                assert!(sp.ng.abs_diff_eq(ng, 1e-5), "{} vs {ng}", sp.ng);
                // dp/du is the transformed edge, as the placed triangle's would be.
                assert!(sp.param.dpdu().abs_diff_eq(placed.p[1] - placed.p[0], 1e-4));
                assert!(sp.p_error.cmpge(Vec3::ZERO).all() && sp.p_error.max_element() < 1e-4);
            }
            // Occlusion agrees with the closest hit.
            assert_eq!(inst.occluded(&ray, f32::INFINITY), got.is_some());
        }
        assert!(hits > 50, "{hits}");
    }

    /// Rays spawned from instanced hits with the transformed error bound never hit the same
    /// surface again, even under a large, shearing transform far from the origin.
    #[test]
    fn spawned_rays_leave_instanced_surfaces() {
        let tri = Triangle::new(Vec3::new(-1.0, -1.0, 0.0), Vec3::new(1.0, -1.0, 0.0), Vec3::new(0.0, 1.0, 0.0));
        let m = glam::Mat4::from_cols_array(&[
            3.0, 0.7, 0.1, 0.0, -0.4, 2.0, 0.3, 0.0, 0.2, 0.5, 4.0, 0.0, 1.0e4, -3.0e3, 2.0e4, 1.0,
        ]);
        let t = Transform::from_mat4(m);
        let inst =
            Instances::build(vec![vec![prim(Shape::Triangle(tri))].into()], vec![Instance::new(0, &t).unwrap()], &[]);
        let target = t.point(Vec3::ZERO);
        let mut tested = 0;
        for i in 0..500 {
            let a = i as f32 * 0.7;
            let o = target + Vec3::new(a.cos(), a.sin(), 1.0 + (i % 7) as f32) * 10.0;
            let ray = Ray::new(o, (target + Vec3::new(0.01 * (i % 13) as f32, 0.0, 0.0) - o).normalize());
            let Some(h) = inst.intersect(&ray, f32::INFINITY) else { continue };
            let (sp, _, _) = inst.surface(&h, &[]);
            for w in [ray.d - 2.0 * ray.d.dot(sp.ng) * sp.ng, ray.d] {
                let r = Ray::spawn(sp.p, sp.p_error, sp.ng, w, 0.0);
                assert!(inst.intersect(&r, f32::INFINITY).is_none(), "re-hit from {} along {w}", sp.p);
                tested += 1;
            }
        }
        assert!(tested > 500, "{tested}");
    }
}
