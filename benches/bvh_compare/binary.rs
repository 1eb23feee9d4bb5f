//! The binary BVH as it was before the 4-wide tree (commit 7d99d8e), kept so the benchmark
//! compares old and new in one run. Binned SAH, 32-byte nodes, near child first.

use caustic::geometry::{Aabb, Ray};
use caustic::math::float::gamma;
use caustic::math::{Vec3, Vec3A};
use caustic::shape::{CompactShape, PrimHit, Primitive, RayShear};

const BINS: usize = 16;
const MAX_LEAF: usize = 4;
/// Subtrees smaller than this are built on the current thread.
const PARALLEL_THRESHOLD: usize = 4096;
const STACK_SIZE: usize = 64;
/// Depth below which splits are by count, keeping any tree shallower than `STACK_SIZE`.
const MEDIAN_DEPTH: usize = 32;

/// A flattened node: leaf when `count > 0` (`offset` = first primitive), interior otherwise
/// (`offset` = index of the second child, `axis` = split axis).
#[derive(Clone, Copy, Debug)]
#[repr(C)]
pub(super) struct Node {
    pub(super) min: Vec3,
    pub(super) offset: u32,
    pub(super) max: Vec3,
    pub(super) count: u16,
    pub(super) axis: u16,
}

pub struct Bvh {
    nodes: Vec<Node>,
    /// Intersection data in leaf order (hot), parallel to `prims`.
    shapes: Vec<CompactShape>,
}

#[derive(Clone, Copy)]
pub(super) struct BuildPrim {
    pub(super) bounds: Aabb,
    pub(super) centroid: Vec3,
    pub(super) index: u32,
}

impl BuildPrim {
    pub(super) fn new(bounds: Aabb, index: usize) -> Self {
        BuildPrim { bounds, centroid: bounds.centroid(), index: index as u32 }
    }
}

/// The flattened tree over `prims`, which are reordered into leaf order (each leaf's `offset`
/// indexes them).
pub(super) fn build_nodes(prims: &mut [BuildPrim]) -> Vec<Node> {
    let mut nodes = Vec::new();
    if !prims.is_empty() {
        let root = build(prims, 0, 0);
        nodes.reserve(2 * prims.len() / MAX_LEAF + 1);
        flatten(&root, &mut nodes);
        nodes.shrink_to_fit();
    }
    nodes
}

enum BuildNode {
    Leaf { bounds: Aabb, first: usize, count: usize },
    Interior { bounds: Aabb, axis: usize, children: Box<[BuildNode; 2]> },
}

impl BuildNode {
    fn bounds(&self) -> Aabb {
        match self {
            BuildNode::Leaf { bounds, .. } | BuildNode::Interior { bounds, .. } => *bounds,
        }
    }
}

/// Builds the subtree over `prims`, whose first element is at `offset` in the full array.
/// Below `MEDIAN_DEPTH` the SAH chooses splits; deeper, splits are at the median so the
/// depth (and the traversal stack) stays bounded even for pathological inputs.
fn build(prims: &mut [BuildPrim], offset: usize, depth: usize) -> BuildNode {
    let bounds = prims.iter().fold(Aabb::EMPTY, |b, p| b.union(p.bounds));
    let n = prims.len();
    let leaf = BuildNode::Leaf { bounds, first: offset, count: n };
    if n <= 1 {
        return leaf;
    }
    let cb = prims.iter().fold(Aabb::EMPTY, |b, p| b.grow(p.centroid));
    let longest = cb.max_axis();
    let median = |prims: &mut [BuildPrim], axis: usize| {
        prims.select_nth_unstable_by(n / 2, |a, b| a.centroid[axis].total_cmp(&b.centroid[axis]));
        n / 2
    };
    if cb.min[longest] >= cb.max[longest] || depth >= MEDIAN_DEPTH {
        // No plane separates the centroids (or the tree is already deep): split by count.
        if n <= MAX_LEAF {
            return leaf;
        }
        let mid = median(prims, longest);
        return interior(prims, offset, depth, bounds, mid, longest);
    }
    // Binned SAH on all three axes; keep the cheapest plane.
    let mut best = (f32::INFINITY, 0usize, 0usize);
    for axis in 0..3 {
        let (lo, hi) = (cb.min[axis], cb.max[axis]);
        if hi <= lo {
            continue;
        }
        let scale = BINS as f32 / (hi - lo);
        let mut counts = [0usize; BINS];
        let mut boxes = [Aabb::EMPTY; BINS];
        for p in prims.iter() {
            let b = (((p.centroid[axis] - lo) * scale) as usize).min(BINS - 1);
            counts[b] += 1;
            boxes[b] = boxes[b].union(p.bounds);
        }
        // Sweep from the right to get the area and count of every right-hand side.
        let mut right_area = [0.0f32; BINS];
        let mut right_count = [0usize; BINS];
        let (mut rb, mut rc) = (Aabb::EMPTY, 0);
        for i in (1..BINS).rev() {
            rb = rb.union(boxes[i]);
            rc += counts[i];
            right_area[i] = rb.half_area();
            right_count[i] = rc;
        }
        let (mut lb, mut lc) = (Aabb::EMPTY, 0);
        for i in 1..BINS {
            lb = lb.union(boxes[i - 1]);
            lc += counts[i - 1];
            if lc == 0 || right_count[i] == 0 {
                continue;
            }
            let cost = lb.half_area() * lc as f32 + right_area[i] * right_count[i] as f32;
            if cost < best.0 {
                best = (cost, axis, i);
            }
        }
    }
    // Cost relative to a leaf, with traversal costing as much as one intersection.
    let split_cost = 1.0 + best.0 / bounds.half_area().max(f32::MIN_POSITIVE);
    if n <= MAX_LEAF && split_cost >= n as f32 {
        return leaf;
    }
    let mut mid = 0;
    if best.0.is_finite() {
        let axis = best.1;
        let (lo, hi) = (cb.min[axis], cb.max[axis]);
        let scale = BINS as f32 / (hi - lo);
        for j in 0..n {
            if ((((prims[j].centroid[axis] - lo) * scale) as usize).min(BINS - 1)) < best.2 {
                prims.swap(mid, j);
                mid += 1;
            }
        }
    }
    let mut axis = best.1;
    if mid == 0 || mid == n {
        mid = median(prims, longest);
        axis = longest;
    }
    interior(prims, offset, depth, bounds, mid, axis)
}

/// Splits `prims` at `mid` and builds both halves (in parallel when large).
fn interior(prims: &mut [BuildPrim], offset: usize, depth: usize, bounds: Aabb, mid: usize, axis: usize) -> BuildNode {
    let n = prims.len();
    let (left, right) = prims.split_at_mut(mid);
    let (l, r) = if n > PARALLEL_THRESHOLD {
        rayon::join(|| build(left, offset, depth + 1), || build(right, offset + mid, depth + 1))
    } else {
        (build(left, offset, depth + 1), build(right, offset + mid, depth + 1))
    };
    BuildNode::Interior { bounds, axis, children: Box::new([l, r]) }
}

fn flatten(node: &BuildNode, nodes: &mut Vec<Node>) {
    let b = node.bounds();
    let at = nodes.len();
    nodes.push(Node { min: b.min, offset: 0, max: b.max, count: 0, axis: 0 });
    match node {
        BuildNode::Leaf { first, count, .. } => {
            nodes[at].offset = *first as u32;
            nodes[at].count = *count as u16;
        }
        BuildNode::Interior { axis, children, .. } => {
            flatten(&children[0], nodes);
            nodes[at].offset = nodes.len() as u32;
            nodes[at].axis = *axis as u16;
            flatten(&children[1], nodes);
        }
    }
}

/// Ray constants for box tests.
pub(super) struct BoxRay {
    o: Vec3A,
    inv_d: Vec3A,
    pub(super) neg: [bool; 3],
}

impl BoxRay {
    #[inline]
    pub(super) fn new(ray: &Ray) -> Self {
        let d = Vec3A::from(ray.d);
        BoxRay { o: Vec3A::from(ray.o), inv_d: d.recip(), neg: [d.x < 0.0, d.y < 0.0, d.z < 0.0] }
    }

    /// Slab test; the far distance is widened by 2 gamma(3) so rounding never drops a box the
    /// ray grazes (pbrt-v4 Bounds3::IntersectP).
    #[inline(always)]
    pub(super) fn hits(&self, n: &Node, t_max: f32) -> bool {
        let t0 = (Vec3A::from(n.min) - self.o) * self.inv_d;
        let t1 = (Vec3A::from(n.max) - self.o) * self.inv_d;
        let near = t0.min(t1).max_element().max(0.0);
        let far = t0.max(t1).min_element() * (1.0 + 2.0 * gamma(3));
        near <= far && near < t_max
    }
}

impl Bvh {
    pub fn build(prims: Vec<Primitive>) -> Self {
        let mut build_prims: Vec<BuildPrim> =
            prims.iter().enumerate().map(|(i, p)| BuildPrim::new(p.shape.bounds(), i)).collect();
        let nodes = build_nodes(&mut build_prims);
        let ordered: Vec<Primitive> = build_prims.iter().map(|b| prims[b.index as usize]).collect();
        let shapes = ordered.iter().map(|p| p.shape.compact()).collect();
        Bvh { nodes, shapes }
    }

    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// Closest hit in (0, t_max): the primitive index (into `prims`) and its hit.
    #[inline(always)]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<(u32, PrimHit)> {
        if self.nodes.is_empty() {
            return None;
        }
        let br = BoxRay::new(ray);
        let shear = RayShear::new(ray);
        let mut closest = t_max;
        let mut best = None;
        let mut stack = [0u32; STACK_SIZE];
        let mut sp = 0;
        let mut idx = 0usize;
        loop {
            let node = &self.nodes[idx];
            if br.hits(node, closest) {
                if node.count > 0 {
                    let first = node.offset as usize;
                    for i in first..first + node.count as usize {
                        if let Some(h) = self.shapes[i].intersect(ray, &shear, closest) {
                            closest = h.t;
                            best = Some((i as u32, h));
                        }
                    }
                } else {
                    // Visit the child on the near side of the split first.
                    let (near, far) = if br.neg[node.axis as usize] {
                        (node.offset as usize, idx + 1)
                    } else {
                        (idx + 1, node.offset as usize)
                    };
                    stack[sp] = far as u32;
                    sp += 1;
                    idx = near;
                    continue;
                }
            }
            if sp == 0 {
                break;
            }
            sp -= 1;
            idx = stack[sp] as usize;
        }
        best
    }

    /// True when anything is hit in (0, t_max). Stops at the first hit found.
    #[inline]
    pub fn occluded(&self, ray: &Ray, t_max: f32) -> bool {
        if self.nodes.is_empty() {
            return false;
        }
        let br = BoxRay::new(ray);
        let shear = RayShear::new(ray);
        let mut stack = [0u32; STACK_SIZE];
        let mut sp = 0;
        let mut idx = 0usize;
        loop {
            let node = &self.nodes[idx];
            if br.hits(node, t_max) {
                if node.count > 0 {
                    let first = node.offset as usize;
                    for p in &self.shapes[first..first + node.count as usize] {
                        if p.intersect(ray, &shear, t_max).is_some() {
                            return true;
                        }
                    }
                } else {
                    let (near, far) = if br.neg[node.axis as usize] {
                        (node.offset as usize, idx + 1)
                    } else {
                        (idx + 1, node.offset as usize)
                    };
                    stack[sp] = far as u32;
                    sp += 1;
                    idx = near;
                    continue;
                }
            }
            if sp == 0 {
                return false;
            }
            sp -= 1;
            idx = stack[sp] as usize;
        }
    }
}
