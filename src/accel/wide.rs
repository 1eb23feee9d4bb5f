//! 4-wide BVH nodes and their traversal. A node holds its four children's boxes side by side
//! (a row of four floats per plane, two cache lines per node) and one SSE slab test checks all
//! four, with pbrt-v4's robust exit distance. Children are visited nearest entry first and
//! skipped once a closer hit is known.
//!
//! Boxes are stored as floats: byte-quantized boxes (one cache line per node, as in CWBVH) were
//! measured slower here for camera and incoherent rays alike (BENCHMARKS.md), the decoding
//! costing more than the memory traffic it saved.

use crate::geometry::{Aabb, Ray};
use crate::math::float::gamma;
use glam::Vec4;

/// A child reference with this bit set is a leaf: bits 3..31 hold its first primitive, bits
/// 0..3 its primitive count minus one. Otherwise it is the index of a node.
pub(super) const LEAF: u32 = 1 << 31;
/// A tree of `depth` node levels needs at most `3 * depth + 1` stack entries (each level
/// leaves at most three siblings behind, the deepest pushes four). Trees up to 21 levels use
/// the small stack, up to 10 the medium one and up to 5 the tiny one (the stack is zeroed per
/// ray, and per instance a ray enters: a room of a few dozen primitives or an instanced mesh
/// should not pay for 64 entries); binary depth, and so `depth`, is at most
/// 32 SAH levels plus 28 median levels (`build::MEDIAN_DEPTH`, `build::MAX_PRIMS`).
const TINY_STACK: usize = 16;
const MEDIUM_STACK: usize = 32;
const SMALL_STACK: usize = 64;
const LARGE_STACK: usize = 256;
/// pbrt-v4's widening of a box's exit distance, so rounding never drops a box the ray grazes.
const FAR_SCALE: f32 = 1.0 + 2.0 * gamma(3);

/// Rows min x, y, z, max x, y, z, a lane per child; unused lanes hold an inverted box that no
/// ray enters (the near plane is picked by the sign of the direction, see `WideRay`).
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub(super) struct WideNode {
    b: [[f32; 4]; 6],
    pub(super) child: [u32; 4],
}

impl WideNode {
    /// Reference of an unused lane.
    pub(super) const NONE: u32 = u32::MAX;

    /// The node over up to four children's boxes (`lo`, `hi`; the w lanes are ignored).
    pub(super) fn new(boxes: &[(Vec4, Vec4)], child: [u32; 4]) -> WideNode {
        let mut b = [[f32::INFINITY; 4]; 6];
        b[3..].fill([f32::NEG_INFINITY; 4]);
        for (k, (lo, hi)) in boxes.iter().enumerate() {
            for a in 0..3 {
                b[a][k] = lo[a];
                b[a + 3][k] = hi[a];
            }
        }
        WideNode { b, child }
    }
}

/// Ray constants for the four-box slab test: per axis, which row is the near plane (by the
/// sign of the reciprocal, so -0 directions pick the right side too).
struct WideRay {
    o: [Vec4; 3],
    inv: [Vec4; 3],
    near: [usize; 3],
    far: [usize; 3],
}

impl WideRay {
    #[inline(always)]
    fn new(ray: &Ray) -> Self {
        let inv = ray.d.recip();
        let neg = [inv.x.is_sign_negative(), inv.y.is_sign_negative(), inv.z.is_sign_negative()];
        WideRay {
            o: [Vec4::splat(ray.o.x), Vec4::splat(ray.o.y), Vec4::splat(ray.o.z)],
            inv: [Vec4::splat(inv.x), Vec4::splat(inv.y), Vec4::splat(inv.z)],
            near: std::array::from_fn(|a| if neg[a] { a + 3 } else { a }),
            far: std::array::from_fn(|a| if neg[a] { a } else { a + 3 }),
        }
    }

    /// Which of the four boxes the ray enters before `t_max` (bit k for child k), and the
    /// entry distances. A NaN plane distance (origin on a plane the ray runs along) leaves
    /// that slab unconstrained: `min`/`max` return their second operand when either is NaN,
    /// and the second operand is always the running value.
    #[inline(always)]
    fn hit(&self, n: &WideNode, t_max: f32) -> (u32, Vec4) {
        let t = |row: usize, a: usize| (Vec4::from_array(n.b[row]) - self.o[a]) * self.inv[a];
        let near = t(self.near[0], 0).max(t(self.near[1], 1).max(t(self.near[2], 2).max(Vec4::ZERO)));
        let far = t(self.far[0], 0).min(t(self.far[1], 1).min(t(self.far[2], 2).min(Vec4::INFINITY))) * FAR_SCALE;
        let mask = near.cmple(far) & near.cmplt(Vec4::splat(t_max));
        (mask.bitmask(), near)
    }
}

/// Visits the leaves whose boxes the ray enters before `*t_max`; `leaf(first, count, t_max)`
/// may lower `*t_max` and returns true to stop (then so does this). With `ORDERED`, children
/// are visited nearest entry first and those entered beyond `*t_max` are skipped when popped.
/// `depth` is the tree's number of node levels.
#[inline(always)]
pub(super) fn traverse<const ORDERED: bool>(
    nodes: &[WideNode],
    depth: u32,
    ray: &Ray,
    t_max: &mut f32,
    leaf: impl FnMut(usize, usize, &mut f32) -> bool,
) -> bool {
    if nodes.is_empty() {
        return false;
    }
    if 3 * (depth as usize) < TINY_STACK {
        walk::<ORDERED, TINY_STACK>(nodes, ray, t_max, leaf)
    } else if 3 * (depth as usize) < MEDIUM_STACK {
        walk::<ORDERED, MEDIUM_STACK>(nodes, ray, t_max, leaf)
    } else if 3 * (depth as usize) < SMALL_STACK {
        walk::<ORDERED, SMALL_STACK>(nodes, ray, t_max, leaf)
    } else {
        walk::<ORDERED, LARGE_STACK>(nodes, ray, t_max, leaf)
    }
}

/// `traverse` with a stack of `N` entries (a power of two: indices are masked, never checked).
#[inline(always)]
fn walk<const ORDERED: bool, const N: usize>(
    nodes: &[WideNode],
    ray: &Ray,
    t_max: &mut f32,
    mut leaf: impl FnMut(usize, usize, &mut f32) -> bool,
) -> bool {
    let wr = WideRay::new(ray);
    let mut ids = [0u32; N];
    let mut ts = [0f32; N];
    let mut sp = 0usize;
    let mut cur = 0u32;
    loop {
        if cur & LEAF != 0 {
            if leaf(((cur & !LEAF) >> 3) as usize, (cur & 7) as usize + 1, t_max) {
                return true;
            }
        } else {
            let node = &nodes[cur as usize];
            let (mut mask, near) = wr.hit(node, *t_max);
            if mask != 0 {
                let near = near.to_array();
                if ORDERED && mask & (mask - 1) != 0 {
                    // Insert the hit children so the stack's top is the nearest.
                    let base = sp;
                    while mask != 0 {
                        let k = mask.trailing_zeros() as usize;
                        mask &= mask - 1;
                        let (c, t) = (node.child[k], near[k]);
                        let mut j = sp;
                        while j > base && ts[(j - 1) & (N - 1)] < t {
                            ids[j & (N - 1)] = ids[(j - 1) & (N - 1)];
                            ts[j & (N - 1)] = ts[(j - 1) & (N - 1)];
                            j -= 1;
                        }
                        ids[j & (N - 1)] = c;
                        ts[j & (N - 1)] = t;
                        sp += 1;
                    }
                    sp -= 1;
                    cur = ids[sp & (N - 1)];
                } else {
                    let k = mask.trailing_zeros() as usize;
                    mask &= mask - 1;
                    cur = node.child[k];
                    while mask != 0 {
                        let k = mask.trailing_zeros() as usize;
                        mask &= mask - 1;
                        ids[sp & (N - 1)] = node.child[k];
                        sp += 1;
                    }
                }
                continue;
            }
        }
        loop {
            if sp == 0 {
                return false;
            }
            sp -= 1;
            if !ORDERED || ts[sp & (N - 1)] < *t_max {
                cur = ids[sp & (N - 1)];
                break;
            }
        }
    }
}

/// Most primitives `flat_nodes` and `scan` take: the boxes' hits make one 32-bit mask.
pub(super) const SCAN_MAX: usize = 32;

/// The boxes of a small scene's primitives (at most `SCAN_MAX`), four to a node in primitive
/// order (child k of node c is primitive 4c + k), for `scan`.
/// (Largest boxes first, to lower t_max early, measured no faster on the Cornell box.)
pub(super) fn flat_nodes(boxes: &[Aabb]) -> Vec<WideNode> {
    assert!(boxes.len() <= SCAN_MAX, "a flat scan takes at most {SCAN_MAX} boxes");
    boxes
        .chunks(4)
        .enumerate()
        .map(|(c, chunk)| {
            let rows: Vec<(Vec4, Vec4)> = chunk.iter().map(|b| (b.min.extend(0.0), b.max.extend(0.0))).collect();
            let child = std::array::from_fn(|k| if k < chunk.len() { (4 * c + k) as u32 } else { WideNode::NONE });
            WideNode::new(&rows, child)
        })
        .collect()
}

/// Calls `prim(i, t_max)` for every primitive whose box (in `flat_nodes`) the ray enters before
/// `*t_max`, in primitive order; `prim` may lower `*t_max` and returns true to stop (then so
/// does this). No hierarchy, no stack: for a few dozen primitives whose boxes are tight (the
/// walls of a room), testing every box four at a time visits fewer boxes than a tree does.
///
/// All boxes are tested first, and then the primitives whose boxes were entered, each only if
/// its box is entered before the `*t_max` of that moment. Calling `prim` between box tests
/// made every call spill and reload the ray's box-test constants (all vector registers are
/// the caller's to save), most of the scan's instructions.
#[inline(always)]
pub(super) fn scan(
    nodes: &[WideNode],
    ray: &Ray,
    t_max: &mut f32,
    mut prim: impl FnMut(usize, &mut f32) -> bool,
) -> bool {
    let wr = WideRay::new(ray);
    let mut near = [0f32; SCAN_MAX];
    let mut entered = 0u32;
    for (c, (node, near)) in nodes.iter().zip(near.chunks_exact_mut(4)).enumerate() {
        let (mask, t) = wr.hit(node, *t_max);
        near.copy_from_slice(&t.to_array());
        entered |= mask << (4 * c);
    }
    while entered != 0 {
        let i = entered.trailing_zeros() as usize;
        entered &= entered - 1;
        if near[i] < *t_max && prim(i, t_max) {
            return true;
        }
    }
    false
}
