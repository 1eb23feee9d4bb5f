//! 4-wide BVH nodes and their traversal. A node holds its four children's boxes side by side,
//! quantized to a byte per coordinate on a grid of the node's own box (one cache line per node,
//! about half the memory of float boxes, which is what incoherent rays wait on), and one SSE
//! slab test checks all four. Children are visited nearest entry first and skipped once a
//! closer hit is known.
//!
//! Robustness: each quantized coordinate is chosen so that the float the traversal decodes,
//! `origin + q * scale` (`scale` a power of two, so the product is exact), lies outside the
//! child's true box; the slab test on that box is pbrt-v4's, with the exit distance widened by
//! 2 gamma(3). So rounding never drops a box the ray grazes.

use crate::geometry::{Aabb, Ray};
use crate::math::Vec3;
use crate::math::float::gamma;
use glam::Vec4;

/// A child reference with this bit set is a leaf: bits 3..31 hold its first primitive, bits
/// 0..3 its primitive count minus one. Otherwise it is the index of a node.
pub(super) const LEAF: u32 = 1 << 31;
/// Binary depth is at most 32 SAH levels plus 28 median levels (`build::MEDIAN_DEPTH`,
/// `build::MAX_PRIMS`); each wide level leaves at most three children on the stack.
const STACK_SIZE: usize = 3 * 60 + 4;
const FAR_SCALE: f32 = 1.0 + 2.0 * gamma(3);
/// Quantized value of an unused lane's min (and 0 its max): an inverted box no ray enters.
const EMPTY_LO: u8 = 255;

#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub(super) struct WideNode {
    origin: [f32; 3],
    /// Grid step per axis, a power of two.
    scale: [f32; 3],
    /// Rows min x, y, z, max x, y, z; a byte per child.
    q: [[u8; 4]; 6],
    pub(super) child: [u32; 4],
}

impl WideNode {
    /// Reference of an unused lane.
    pub(super) const NONE: u32 = u32::MAX;

    /// The node over up to four children's boxes (`lo`, `hi`; the w lanes are ignored).
    pub(super) fn new(boxes: &[(Vec4, Vec4)], child: [u32; 4]) -> WideNode {
        let mut n = WideNode { origin: [0.0; 3], scale: [1.0; 3], q: [[EMPTY_LO; 4], [EMPTY_LO; 4], [EMPTY_LO; 4], [0; 4], [0; 4], [0; 4]], child };
        for a in 0..3 {
            let origin = boxes.iter().fold(f32::INFINITY, |m, b| m.min(b.0[a]));
            let top = boxes.iter().fold(f32::NEG_INFINITY, |m, b| m.max(b.1[a]));
            n.origin[a] = origin;
            let mut scale = pow2_at_least((top - origin) / 255.0);
            // Widen the grid until every box fits and an empty lane stays inverted.
            for _ in 0..300 {
                if origin + 255.0 * scale > origin {
                    let mut q = [(EMPTY_LO, 0u8); 4];
                    let fits = boxes.iter().zip(&mut q).all(|(b, q)| quantize(origin, scale, b.0[a], b.1[a]).map(|v| *q = v).is_some());
                    if fits {
                        for (k, (lo, hi)) in q.into_iter().enumerate() {
                            n.q[a][k] = lo;
                            n.q[a + 3][k] = hi;
                        }
                        break;
                    }
                }
                scale *= 2.0;
            }
            n.scale[a] = scale;
        }
        n
    }

    /// Union of the children's (decoded) boxes.
    pub(super) fn bounds(&self) -> Aabb {
        let mut b = Aabb::EMPTY;
        for k in 0..4 {
            let lo = Vec3::from_array(std::array::from_fn(|a| self.origin[a] + self.q[a][k] as f32 * self.scale[a]));
            let hi = Vec3::from_array(std::array::from_fn(|a| self.origin[a] + self.q[a + 3][k] as f32 * self.scale[a]));
            if lo.cmple(hi).all() {
                b = b.union(Aabb { min: lo, max: hi });
            }
        }
        b
    }
}

/// The smallest power of two at least `x` (and at least the smallest normal float).
fn pow2_at_least(x: f32) -> f32 {
    if !(x > f32::MIN_POSITIVE) {
        return f32::MIN_POSITIVE;
    }
    let bits = x.to_bits();
    let exp = bits & 0x7f80_0000;
    let up = if bits & 0x007f_ffff != 0 { exp + 0x0080_0000 } else { exp };
    if up >= 0x7f80_0000 { f32::MAX } else { f32::from_bits(up) }
}

/// Grid coordinates whose decoded floats enclose [lo, hi], or `None` when they do not fit.
fn quantize(origin: f32, scale: f32, lo: f32, hi: f32) -> Option<(u8, u8)> {
    let dec = |q: i32| origin + q as f32 * scale;
    let mut ql = (((lo - origin) / scale).floor() as i32).clamp(0, 255);
    while ql > 0 && dec(ql) > lo {
        ql -= 1;
    }
    let mut qh = (((hi - origin) / scale).ceil() as i32).clamp(0, 256);
    while qh <= 255 && dec(qh) < hi {
        qh += 1;
    }
    (dec(ql) <= lo && qh <= 255).then_some((ql as u8, qh as u8))
}

/// Four bytes as four floats (four SSE2 instructions; built lane by lane elsewhere).
#[cfg(all(target_arch = "x86_64", target_feature = "sse2"))]
#[inline(always)]
fn lanes(q: [u8; 4]) -> Vec4 {
    use std::arch::x86_64::{_mm_cvtepi32_ps, _mm_cvtsi32_si128, _mm_setzero_si128, _mm_unpacklo_epi8, _mm_unpacklo_epi16};
    // SAFETY: register-only SSE2 intrinsics, and the cfg above guarantees SSE2 is enabled.
    unsafe {
        let z = _mm_setzero_si128();
        let v = _mm_unpacklo_epi16(_mm_unpacklo_epi8(_mm_cvtsi32_si128(i32::from_le_bytes(q)), z), z);
        Vec4::from(_mm_cvtepi32_ps(v))
    }
}

#[cfg(not(all(target_arch = "x86_64", target_feature = "sse2")))]
#[inline(always)]
fn lanes(q: [u8; 4]) -> Vec4 {
    Vec4::new(q[0] as f32, q[1] as f32, q[2] as f32, q[3] as f32)
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
        let t = |row: usize, a: usize| {
            let plane = lanes(n.q[row]) * Vec4::splat(n.scale[a]) + Vec4::splat(n.origin[a]);
            (plane - self.o[a]) * self.inv[a]
        };
        let near = t(self.near[0], 0).max(t(self.near[1], 1).max(t(self.near[2], 2).max(Vec4::ZERO)));
        let far = t(self.far[0], 0).min(t(self.far[1], 1).min(t(self.far[2], 2).min(Vec4::INFINITY))) * FAR_SCALE;
        let mask = near.cmple(far) & near.cmplt(Vec4::splat(t_max));
        (mask.bitmask(), near)
    }
}

/// Visits the leaves whose boxes the ray enters before `*t_max`; `leaf(first, count, t_max)`
/// may lower `*t_max` and returns true to stop (then so does this). With `ORDERED`, children
/// are visited nearest entry first and those entered beyond `*t_max` are skipped when popped.
#[inline(always)]
pub(super) fn traverse<const ORDERED: bool>(
    nodes: &[WideNode],
    ray: &Ray,
    t_max: &mut f32,
    mut leaf: impl FnMut(usize, usize, &mut f32) -> bool,
) -> bool {
    if nodes.is_empty() {
        return false;
    }
    let wr = WideRay::new(ray);
    let mut ids = [0u32; STACK_SIZE];
    let mut ts = [0f32; STACK_SIZE];
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
                        while j > base && ts[j - 1] < t {
                            ids[j] = ids[j - 1];
                            ts[j] = ts[j - 1];
                            j -= 1;
                        }
                        ids[j] = c;
                        ts[j] = t;
                        sp += 1;
                    }
                    sp -= 1;
                    cur = ids[sp];
                } else {
                    let k = mask.trailing_zeros() as usize;
                    mask &= mask - 1;
                    cur = node.child[k];
                    while mask != 0 {
                        let k = mask.trailing_zeros() as usize;
                        mask &= mask - 1;
                        ids[sp] = node.child[k];
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
            if !ORDERED || ts[sp] < *t_max {
                cur = ids[sp];
                break;
            }
        }
    }
}
