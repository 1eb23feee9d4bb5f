//! Bounding volume hierarchy over a scene's primitives: a 4-wide tree over the bounded ones
//! (built by `build`, nodes and traversal in `wide`), and the unbounded ones (planes) after it,
//! tested with every ray. The primitives are reordered into leaf order (planes last) and their
//! intersection data copied beside them, so each leaf is a contiguous run of at most
//! `build::MAX_LEAF` compact shapes and a hit's index names its primitive directly, planes
//! included. Small scenes skip the tree: up to `LINEAR_MAX` bounded primitives are tested in
//! packets, up to `FLAT_MAX` through their boxes in a fixed order (the tree is still built, for
//! the order it gives the primitives).

use super::build::{BuildPrim, build_wide};
use super::packet::Packets;
use super::wide::{SCAN_MAX, WideNode, flat_nodes, scan, traverse};
use crate::geometry::{Aabb, Ray};
use crate::shape::{CompactShape, PrimHit, Primitives, RayShear, SurfacePoint, TriangleMesh, intersect_quad};
use rayon::prelude::*;

/// Up to this many primitives every ray tests them all: no box test beats a handful of shape
/// tests (a four-sphere Whitted scene ran 17% slower through one wide node). Closest-hit and
/// shadow rays test them four at a time (`Packets`: 1.17x the scalar loop's speed on the
/// caustic Cornell box's 7 primitives); for 18 quads culling by boxes won (the diffuse box ran
/// 7% slower in packets; BENCHMARKS.md, issue 29).
const LINEAR_MAX: usize = 8;
/// Up to this many primitives every ray tests all their boxes, four at a time and in a fixed
/// order (`wide::scan`), instead of walking a tree. A room's walls are flat boxes that a ray
/// enters only where it meets the wall, so the boxes cull as well as a tree does, without the
/// tree's unpredictable branches (which child, push, pop): the diffuse Cornell box's 18 quads
/// render 1.13x as fast, with 1% more instructions (BENCHMARKS.md, issue 29). A mesh of
/// 328 triangles ran 2.3x slower this way; 15-35 primitives in open scenes ran as fast.
const FLAT_MAX: usize = 32;
const _: () = assert!(FLAT_MAX <= SCAN_MAX);

pub struct Bvh {
    nodes: Vec<WideNode>,
    /// Node levels (sizes the traversal stack).
    depth: u32,
    bounds: Aabb,
    /// Intersection data in leaf order (hot); the unbounded primitives after the tree's.
    shapes: Vec<CompactShape>,
    /// Primitives the tree holds (the first `bounded` of `shapes`); the rest are unbounded.
    bounded: usize,
    /// The primitives in leaf order, read once per closest hit.
    prims: Primitives,
    /// `for_each_crossing` finds every crossing (no leaf is a cylinder).
    crossings_enumerable: bool,
    /// Some primitive's test reads a ray's `RayShear` (`CompactShape::uses_shear`: triangles).
    triangles: bool,
    /// For at most `LINEAR_MAX` bounded primitives: all of them, four at a time.
    packets: Option<Packets>,
    /// For at most `FLAT_MAX` bounded primitives (and more than `LINEAR_MAX`): their boxes.
    flat: Option<Vec<WideNode>>,
}

impl Bvh {
    /// The tree over `prims`, whose mesh triangles index `meshes` (the scene's meshes, which
    /// every later call that takes them must be given).
    pub fn build(prims: impl Into<Primitives>, meshes: &[TriangleMesh]) -> Self {
        let mut prims = prims.into();
        prims.shrink_to_fit();
        let n = prims.len();
        let unbounded: Vec<u32> =
            (0..n as u32).filter(|&i| !prims.get(i as usize, meshes).shape.is_bounded()).collect();
        let mut build: Vec<BuildPrim> = if unbounded.is_empty() {
            (0..n).into_par_iter().map(|i| BuildPrim::new(prims.bounds(i, meshes), i)).collect()
        } else {
            let bounded = |i: &usize| unbounded.binary_search(&(*i as u32)).is_err();
            (0..n).filter(bounded).map(|i| BuildPrim::new(prims.bounds(i, meshes), i)).collect()
        };
        let tree = build_wide(&mut build);
        let bounded = build.len();
        let mut order: Vec<u32> = build.par_iter().map(BuildPrim::index).collect();
        order.extend(&unbounded);
        // The build records go before the nodes are joined, the primitives reordered and the
        // leaves made: at the peak a mesh triangle holds only its primitive, leaf and node share.
        drop(build);
        let (depth, bounds, nodes) = (tree.depth, tree.bounds, tree.nodes());
        prims.reorder(&order);
        drop(order);
        let shapes: Vec<CompactShape> = (0..n).into_par_iter().map(|i| prims.compact(i, meshes)).collect();
        let crossings_enumerable = shapes.par_iter().all(CompactShape::crossings_enumerable);
        let triangles = shapes.par_iter().any(CompactShape::uses_shear);
        let packets = (bounded <= LINEAR_MAX).then(|| Packets::new(&shapes[..bounded]));
        let flat = (bounded > LINEAR_MAX && bounded <= FLAT_MAX).then(|| {
            let boxes: Vec<Aabb> = (0..bounded).map(|i| prims.bounds(i, meshes)).collect();
            flat_nodes(&boxes)
        });
        Bvh { nodes, depth, bounds, shapes, bounded, prims, crossings_enumerable, triangles, packets, flat }
    }

    /// The unbounded primitives (planes), after the tree's.
    pub fn unbounded(&self) -> impl Iterator<Item = &CompactShape> {
        self.shapes[self.bounded..].iter()
    }

    /// Number of unbounded primitives.
    pub fn unbounded_len(&self) -> usize {
        self.shapes.len() - self.bounded
    }

    /// The primitives, in the order hits name them.
    pub fn prims(&self) -> &Primitives {
        &self.prims
    }

    pub fn len(&self) -> usize {
        self.prims.len()
    }

    pub fn is_empty(&self) -> bool {
        self.prims.is_empty()
    }

    /// Material and light of the primitive a hit names.
    #[inline]
    pub fn material_light(&self, i: u32) -> (u32, u32) {
        self.prims.material_light(i as usize)
    }

    /// Surface data at a hit `intersect` returned (its material and light: `material_light`).
    #[inline]
    pub fn surface(&self, i: u32, ray: &Ray, h: &PrimHit, meshes: &[TriangleMesh]) -> SurfacePoint {
        self.prims.surface(i as usize, &self.shapes[i as usize], ray, h, meshes)
    }

    pub fn bounds(&self) -> Aabb {
        self.bounds
    }

    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// Bytes held by the tree, its leaf shapes and its primitives.
    pub fn memory_bytes(&self) -> usize {
        self.node_bytes()
            + self.shapes.capacity() * std::mem::size_of::<CompactShape>()
            + self.prims.memory_bytes()
            + self.packets.as_ref().map_or(0, Packets::memory_bytes)
            + self.flat.as_ref().map_or(0, |f| f.capacity() * std::mem::size_of::<WideNode>())
    }

    /// Bytes held by the tree's nodes alone.
    pub fn node_bytes(&self) -> usize {
        self.nodes.capacity() * std::mem::size_of::<WideNode>()
    }

    /// The ray's triangle-test constants, made only when the tree holds a triangle.
    #[inline(always)]
    fn shear(&self, ray: &Ray) -> RayShear {
        if self.triangles { RayShear::new(ray) } else { RayShear::UNUSED }
    }

    /// Closest hit in (0, t_max): the primitive's index (into `prims()`) and its hit.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<(u32, PrimHit)> {
        let tree = self.intersect_tree(ray, t_max);
        let closest = tree.map_or(t_max, |(_, h)| h.t);
        self.intersect_unbounded(ray, closest).or(tree)
    }

    /// `intersect` over the primitives in the tree only (what `intersect_unbounded` leaves out).
    #[inline]
    pub fn intersect_tree(&self, ray: &Ray, t_max: f32) -> Option<(u32, PrimHit)> {
        let shear = self.shear(ray);
        let mut closest = t_max;
        if let Some(p) = &self.packets {
            return p.intersect(&self.shapes, ray, &shear, &mut closest).map(|(i, h)| (i as u32, h));
        }
        let mut best = None;
        if let Some(flat) = &self.flat {
            scan(flat, ray, &mut closest, |i, closest| {
                if let Some(h) = self.flat_intersect(i, ray, &shear, *closest) {
                    *closest = h.t;
                    best = Some((i, h));
                }
                false
            });
        } else {
            let leaf = |first: usize, count: usize, closest: &mut f32| {
                for i in first..first + count {
                    if let Some(h) = self.shapes[i].intersect(ray, &shear, *closest) {
                        *closest = h.t;
                        best = Some((i, h));
                    }
                }
                false
            };
            traverse::<true>(&self.nodes, self.depth, ray, &mut closest, leaf);
        }
        best.map(|(i, h)| (i as u32, h))
    }

    /// `intersect` over the unbounded primitives (planes) only, from a loop of their own: one
    /// call site shared with the tree's leaves mispredicted its dispatch on every ray, and
    /// keeping the loop out of the traversal's function keeps that function as small as before
    /// planes joined the BVH (BENCHMARKS.md, architecture step 2).
    #[inline(always)]
    pub fn intersect_unbounded(&self, ray: &Ray, t_max: f32) -> Option<(u32, PrimHit)> {
        // Most scenes have no plane: a call to find that out was 1% of the path tracer's
        // instructions.
        if self.bounded == self.shapes.len() {
            return None;
        }
        self.intersect_planes(ray, t_max)
    }

    #[inline(never)]
    fn intersect_planes(&self, ray: &Ray, t_max: f32) -> Option<(u32, PrimHit)> {
        let mut closest = t_max;
        let mut best = None;
        for (i, s) in self.shapes.iter().enumerate().skip(self.bounded) {
            if let Some(h) = s.intersect_unbounded(ray, closest) {
                closest = h.t;
                best = Some((i as u32, h));
            }
        }
        best
    }

    /// Calls `visit(primitive, hit)` for every surface crossing in (0, t_max), in no particular
    /// order, until it returns false; returns whether it went through all of them. `None` when
    /// the tree holds a shape whose later crossings are not found (`crossings_enumerable`).
    #[inline]
    pub fn for_each_crossing(
        &self,
        ray: &Ray,
        t_max: f32,
        mut visit: impl FnMut(u32, PrimHit) -> bool,
    ) -> Option<bool> {
        if !self.crossings_enumerable {
            return None;
        }
        let shear = self.shear(ray);
        let mut leaf = |first: usize, count: usize, t: &mut f32| {
            (first..first + count).any(|i| !self.shapes[i].for_each_crossing(ray, &shear, *t, |h| visit(i as u32, h)))
        };
        let mut t = t_max;
        let stopped = if self.bounded <= LINEAR_MAX {
            leaf(0, self.bounded, &mut t)
        } else if let Some(flat) = &self.flat {
            scan(flat, ray, &mut t, |i, t| leaf(i, 1, t))
        } else {
            traverse::<false>(&self.nodes, self.depth, ray, &mut t, &mut leaf)
        };
        let stopped = stopped
            || self
                .shapes
                .iter()
                .enumerate()
                .skip(self.bounded)
                .any(|(i, s)| s.intersect_unbounded(ray, t_max).is_some_and(|h| !visit(i as u32, h)));
        Some(!stopped)
    }

    /// Primitive `i`'s test in a flat scan. A room is mostly quads: their test is made in the
    /// scan's loop and the other shapes' out of line, so the loop holds no call for a quad
    /// (a call makes the loop save and reload its vector registers).
    #[inline(always)]
    fn flat_intersect(&self, i: usize, ray: &Ray, shear: &RayShear, t_max: f32) -> Option<PrimHit> {
        match &self.shapes[i] {
            CompactShape::Quad([p0, e1, e2]) => intersect_quad(*p0, *e1, *e2, ray, t_max),
            other => intersect_other(other, ray, shear, t_max),
        }
    }

    /// True when anything is hit in (0, t_max). Stops at the first hit found.
    #[inline]
    pub fn occluded(&self, ray: &Ray, t_max: f32) -> bool {
        let shear = self.shear(ray);
        let leaf = |first: usize, count: usize, t: &mut f32| {
            self.shapes[first..first + count].iter().any(|p| p.intersect(ray, &shear, *t).is_some())
        };
        let mut t = t_max;
        // Planes first: they are few and block many shadow rays.
        if self.shapes[self.bounded..].iter().any(|s| s.intersect_unbounded(ray, t_max).is_some()) {
            return true;
        }
        if let Some(p) = &self.packets {
            return p.occluded(&self.shapes, ray, &shear, t_max);
        }
        if let Some(flat) = &self.flat {
            return scan(flat, ray, &mut t, |i, t| self.flat_intersect(i, ray, &shear, *t).is_some());
        }
        traverse::<false>(&self.nodes, self.depth, ray, &mut t, leaf)
    }
}

/// `CompactShape::intersect` out of line (`Bvh::flat_intersect`).
#[inline(never)]
fn intersect_other(shape: &CompactShape, ray: &Ray, shear: &RayShear, t_max: f32) -> Option<PrimHit> {
    shape.intersect(ray, shear, t_max)
}
