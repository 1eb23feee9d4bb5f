//! Bounding volume hierarchy over all bounded primitives: a 4-wide tree (built by `build`,
//! nodes and traversal in `wide`). The intersection data of the primitives is copied into leaf
//! order so each leaf is a contiguous run of at most `build::MAX_LEAF` compact shapes; the
//! primitives themselves stay in the order given.

use super::build::{BuildPrim, build_wide};
use super::wide::{WideNode, traverse};
use crate::geometry::{Aabb, Ray};
use crate::shape::{CompactShape, PrimHit, Primitive, RayShear};
use rayon::prelude::*;

/// Up to this many primitives every ray tests them all in leaf order: no box test beats a
/// handful of shape tests (a four-sphere Whitted scene ran 17% slower through one wide node).
const LINEAR_MAX: usize = 8;

pub struct Bvh {
    nodes: Vec<WideNode>,
    /// Node levels (sizes the traversal stack).
    depth: u32,
    bounds: Aabb,
    /// Intersection data in leaf order (hot).
    shapes: Vec<CompactShape>,
    /// Index in `prims` of each leaf shape.
    order: Vec<u32>,
    /// The primitives in the order given, read once per closest hit.
    pub prims: Vec<Primitive>,
}

impl Bvh {
    pub fn build(prims: Vec<Primitive>) -> Self {
        let mut build: Vec<BuildPrim> =
            prims.par_iter().enumerate().map(|(i, p)| BuildPrim::new(p.shape.bounds(), i)).collect();
        let tree = build_wide(&mut build);
        let order: Vec<u32> = build.par_iter().map(BuildPrim::index).collect();
        drop(build);
        let shapes = order.par_iter().map(|&i| prims[i as usize].shape.compact()).collect();
        Bvh { nodes: tree.nodes, depth: tree.depth, bounds: tree.bounds, shapes, order, prims }
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
            + self.order.capacity() * std::mem::size_of::<u32>()
            + self.prims.capacity() * std::mem::size_of::<Primitive>()
    }

    /// Bytes held by the tree's nodes alone.
    pub fn node_bytes(&self) -> usize {
        self.nodes.capacity() * std::mem::size_of::<WideNode>()
    }

    /// Closest hit in (0, t_max): the primitive index (into `prims`) and its hit.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<(u32, PrimHit)> {
        let shear = RayShear::new(ray);
        let mut closest = t_max;
        let mut best = None;
        let mut leaf = |first: usize, count: usize, closest: &mut f32| {
            for i in first..first + count {
                if let Some(h) = self.shapes[i].intersect(ray, &shear, *closest) {
                    *closest = h.t;
                    best = Some((i, h));
                }
            }
            false
        };
        if self.shapes.len() <= LINEAR_MAX {
            leaf(0, self.shapes.len(), &mut closest);
        } else {
            traverse::<true>(&self.nodes, self.depth, ray, &mut closest, leaf);
        }
        best.map(|(i, h)| (self.order[i], h))
    }

    /// True when anything is hit in (0, t_max). Stops at the first hit found.
    #[inline]
    pub fn occluded(&self, ray: &Ray, t_max: f32) -> bool {
        let shear = RayShear::new(ray);
        let leaf = |first: usize, count: usize, t: &mut f32| {
            self.shapes[first..first + count].iter().any(|p| p.intersect(ray, &shear, *t).is_some())
        };
        let mut t = t_max;
        if self.shapes.len() <= LINEAR_MAX {
            return leaf(0, self.shapes.len(), &mut t);
        }
        traverse::<false>(&self.nodes, self.depth, ray, &mut t, leaf)
    }
}
