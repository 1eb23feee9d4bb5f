//! The photon map: a compact 20-byte photon record and a balanced kd-tree over the photon
//! positions, queried for the k nearest photons within a maximum radius.
//!
//! Source: Jensen 2001, "A practical guide to global illumination using photon mapping"
//! (SIGGRAPH 2001 course 38), sections "Photon storing" (the compact photon, its direction as two
//! quantised angles), "Preparing the photon map for rendering" (the balanced kd-tree, split at the
//! median on the axis of largest extent) and "Locating the nearest photons" (the k nearest within
//! a maximum distance, the radius shrinking as nearer photons are found); the same material is
//! chapter 6 of Jensen's book "Realistic Image Synthesis Using Photon Mapping" (2001).
//!
//! Departures from the notes, each measured (benches/photon_map.rs; on 1M uniform photons, k = 50,
//! queries in tile order, together about 2.2x the gathers per second of kiddo's `ImmutableKdTree`):
//! - The tree is implicit and balanced like Jensen's, but its leaves are buckets of up to
//!   `LEAF_SIZE` photons instead of one photon per node. Leaf `j` of a tree of depth `d` over `n`
//!   photons holds photons `n*j >> d .. n*(j+1) >> d`, so the tree itself is only split planes.
//! - The traversal reads a dense copy of the positions (12 more bytes a photon; reading the
//!   20-byte records instead costs nothing in tile order but 12% with queries in random order).
//! - Far cells are pruned by their full distance to the query, accumulated axis by axis (Arya
//!   and Mount 1993, "Algorithms for fast vector quantization"), not by the split plane alone.
//! - Instead of a max-heap, candidates are appended without a branch and cut down to the nearest
//!   k by a quickselect whenever 2k + 32 have gathered: twice the speed of the heap, whose sifts
//!   branch unpredictably.
//!
//! Splitting at the median *index* (not value) keeps the tree balanced however many photons share
//! a coordinate, so flat walls and exact duplicates need no special case.

use crate::math::{Color, Vec3};
use rayon::prelude::*;
use std::f64::consts::PI;

/// Most photons in one leaf bucket; leaves hold between `LEAF_SIZE / 2` and `LEAF_SIZE`.
const LEAF_SIZE: usize = 32;
const _: () = assert!(LEAF_SIZE >= 2, "with one photon a leaf, leaves could be empty");
/// Traversal stack: at most one entry per tree level, and the tree has < 32 levels (u32 indices).
const STACK_SIZE: usize = 40;
/// Fewest photons split by one parallel task while building.
const PARALLEL_MIN: usize = 1 << 14;

// ---------------------------------------------------------------------------------------------
// The photon record
// ---------------------------------------------------------------------------------------------

/// One stored photon, 20 bytes: the exact position (3 x f32) and 8 packed bytes holding the power
/// (3 x 13-bit floats), the direction of travel (8-bit theta, 9-bit phi) and a flags byte.
///
/// Packed bits, little-endian `u64`: 0..13 red, 13..26 green, 26..39 blue, 39..47 theta, 47..56
/// phi, 56..64 flags.
///
/// Power channels keep a 7-bit mantissa (relative error at most 2^-8 = 0.4%) over
/// 2^-40..2^24 (9.1e-13 to 1.7e7): smaller, negative or NaN values store 0, larger ones clamp. The
/// direction is stored as Jensen's (theta, phi) angles quantised to bin centres, within 0.5
/// degrees of the true direction.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C)]
pub struct Photon {
    position: [f32; 3],
    packed: [u8; 8],
}

const _: () = assert!(size_of::<Photon>() == 20);

const CHANNEL_BITS: u32 = 13;
const CHANNEL_MAX: u32 = (1 << CHANNEL_BITS) - 1;
/// Biased f32 exponent of channel code 0: codes keep the top 15 bits of an f32 (8 exponent bits,
/// 7 mantissa bits, like bfloat16) minus `CHANNEL_EXP_OFFSET << 7`, so 6 exponent bits remain.
const CHANNEL_EXP_OFFSET: u32 = 127 - 40;
const THETA_SHIFT: u32 = 39;
const PHI_SHIFT: u32 = 47;
const FLAGS_SHIFT: u32 = 56;
const THETA_BINS: usize = 256;
const PHI_BINS: usize = 512;

/// The three channels of `power` in the low `3 * CHANNEL_BITS` bits.
#[inline]
fn encode_power(power: Color) -> u64 {
    encode_channel(power.r())
        | encode_channel(power.g()) << CHANNEL_BITS
        | encode_channel(power.b()) << (2 * CHANNEL_BITS)
}

/// Encodes one non-negative power channel into 13 bits, rounding to nearest.
#[inline]
fn encode_channel(v: f32) -> u64 {
    if !(v > 0.0) {
        return 0;
    }
    // Clamping the bits to f32::MAX keeps +inf from rounding into a NaN pattern.
    let top = (v.to_bits().min(f32::MAX.to_bits()) + 0x8000) >> 16;
    let zero = CHANNEL_EXP_OFFSET << 7;
    if top <= zero { 0 } else { u64::from((top - zero).min(CHANNEL_MAX)) }
}

#[inline]
fn decode_channel(code: u32) -> f32 {
    if code == 0 { 0.0 } else { f32::from_bits((code + (CHANNEL_EXP_OFFSET << 7)) << 16) }
}

/// sin and cos of `x` in [-pi, pi] by their Taylor series, so the direction tables below can be
/// built at compile time (the series has converged to f64 precision after 30 terms).
const fn sin_cos(x: f64) -> (f64, f64) {
    let (mut s, mut c) = (0.0, 0.0);
    let (mut ts, mut tc) = (x, 1.0);
    let mut n = 0;
    while n < 30 {
        s += ts;
        c += tc;
        let m = (2 * n + 2) as f64;
        ts *= -x * x / (m * (m + 1.0));
        tc *= -x * x / ((m - 1.0) * m);
        n += 1;
    }
    (s, c)
}

/// (sin, cos) of the centre of each theta bin, theta in [0, pi].
static THETA_TABLE: [[f32; 2]; THETA_BINS] = {
    let mut t = [[0.0; 2]; THETA_BINS];
    let mut i = 0;
    while i < THETA_BINS {
        let (s, c) = sin_cos((i as f64 + 0.5) * PI / THETA_BINS as f64);
        t[i] = [s as f32, c as f32];
        i += 1;
    }
    t
};

/// (cos, sin) of the centre of each phi bin, phi in [-pi, pi].
static PHI_TABLE: [[f32; 2]; PHI_BINS] = {
    let mut t = [[0.0; 2]; PHI_BINS];
    let mut i = 0;
    while i < PHI_BINS {
        let (s, c) = sin_cos((i as f64 + 0.5) * (2.0 * PI / PHI_BINS as f64) - PI);
        t[i] = [c as f32, s as f32];
        i += 1;
    }
    t
};

impl Photon {
    /// A photon at `p` that travelled along `dir` (any length; it is normalised, and a zero or
    /// non-finite `dir` is stored as +z) carrying RGB `power`, with caller-defined `flags`.
    pub fn new(p: Vec3, dir: Vec3, power: Color, flags: u8) -> Self {
        let len = dir.length();
        let d = if len > 0.0 && len.is_finite() { dir / len } else { Vec3::Z };
        let theta = d.z.clamp(-1.0, 1.0).acos();
        let phi = d.y.atan2(d.x);
        let theta_bin = ((theta * (THETA_BINS as f32 / std::f32::consts::PI)) as u64).min(THETA_BINS as u64 - 1);
        // phi = pi lands on bin PHI_BINS, which wraps to bin 0 (the same direction).
        let phi_bin =
            (((phi + std::f32::consts::PI) * (PHI_BINS as f32 / std::f32::consts::TAU)) as u64) & (PHI_BINS as u64 - 1);
        let bits =
            encode_power(power) | theta_bin << THETA_SHIFT | phi_bin << PHI_SHIFT | u64::from(flags) << FLAGS_SHIFT;
        Photon { position: p.to_array(), packed: bits.to_le_bytes() }
    }

    /// The same photon carrying `power` instead (its direction and flags kept bit for bit).
    pub fn with_power(&self, power: Color) -> Photon {
        let mask = (1u64 << (3 * CHANNEL_BITS)) - 1;
        let bits = (self.bits() & !mask) | encode_power(power);
        Photon { position: self.position, packed: bits.to_le_bytes() }
    }

    #[inline]
    fn bits(&self) -> u64 {
        u64::from_le_bytes(self.packed)
    }

    /// The exact position given to [`Photon::new`].
    #[inline]
    pub fn position(&self) -> Vec3 {
        Vec3::from_array(self.position)
    }

    /// Unit direction in which the photon travelled (towards the surface it landed on; the
    /// incident direction in the BSDF's convention is its negation).
    #[inline]
    pub fn direction(&self) -> Vec3 {
        let bits = self.bits();
        let [sin_t, cos_t] = THETA_TABLE[((bits >> THETA_SHIFT) & 0xff) as usize];
        let [cos_p, sin_p] = PHI_TABLE[((bits >> PHI_SHIFT) & 0x1ff) as usize];
        Vec3::new(sin_t * cos_p, sin_t * sin_p, cos_t)
    }

    /// RGB power (flux), within 0.4% per channel of what was stored.
    #[inline]
    pub fn power(&self) -> Color {
        let bits = self.bits();
        let mask = u64::from(CHANNEL_MAX);
        Color::new(
            decode_channel((bits & mask) as u32),
            decode_channel(((bits >> CHANNEL_BITS) & mask) as u32),
            decode_channel(((bits >> (2 * CHANNEL_BITS)) & mask) as u32),
        )
    }

    #[inline]
    pub fn flags(&self) -> u8 {
        self.packed[7]
    }
}

// ---------------------------------------------------------------------------------------------
// The gather buffer
// ---------------------------------------------------------------------------------------------

/// Reusable result buffer of [`PhotonMap::gather`]: (squared distance, photon index) pairs. Keep
/// one per thread (or per chunk of queries) so gathers allocate nothing after the first.
#[derive(Clone, Debug, Default)]
pub struct Gathered {
    /// Candidate buffer; its first `len` entries are the last gather's result.
    buf: Vec<(f32, u32)>,
    len: usize,
    radius2: f32,
}

impl Gathered {
    /// A buffer for gathers of up to `k` photons (it grows on its own if a gather needs more).
    pub fn new(k: usize) -> Self {
        Gathered { buf: Vec::with_capacity(2 * (candidate_limit(k) + LEAF_SIZE)), len: 0, radius2: 0.0 }
    }

    /// The photons of the last gather as (squared distance, photon index), in no particular order.
    #[inline]
    pub fn as_slice(&self) -> &[(f32, u32)] {
        &self.buf[..self.len]
    }

    /// Squared distance of the farthest photon of the last gather (0 when it found none).
    #[inline]
    pub fn radius2(&self) -> f32 {
        self.radius2
    }

    #[inline]
    pub fn len(&self) -> usize {
        self.len
    }

    #[inline]
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }
}

/// Candidates a gather of `k` collects before it cuts them down to the nearest `k` (and shrinks
/// its search radius to the k-th distance): twice `k` keeps the cuts rare and each one cheap.
#[inline]
fn candidate_limit(k: usize) -> usize {
    2 * k + 32
}

/// Reorders `cands` so that its first `k` entries (`1 <= k <= cands.len()`) are the `k` with the
/// smallest distances, and returns the largest of those; the entries after `k` are left in no
/// defined state. A quickselect whose partition copies between `cands` and `scratch` (at least as
/// long) without branching on the comparisons, which are unpredictable. An in-place branch-free
/// partition would be slower: each swap would wait on the store of the one before.
fn select_nearest(cands: &mut [(f32, u32)], scratch: &mut [(f32, u32)], k: usize) -> f32 {
    let target = k - 1;
    let (mut lo, mut hi) = (0, cands.len());
    // Entries before `lo` are final (in `cands`) and no farther than any in lo..hi, entries from
    // `hi` on are discarded, and `target` lies in lo..hi, whose entries live in `scratch` when
    // `in_scratch` is set.
    let mut in_scratch = false;
    while hi - lo > 16 {
        let (src, dst) = if in_scratch { (&*scratch, &mut *cands) } else { (&*cands, &mut *scratch) };
        let (src, dst) = (&src[lo..hi], &mut dst[lo..hi]);
        let (a, b, c) = (src[0].0, src[src.len() / 2].0, src[src.len() - 1].0);
        let pivot = a.max(b).min(a.min(b).max(c));
        let mut split = lo + partition_into(src, dst, |d2| d2 < pivot);
        let mut done = false;
        if split == lo {
            // The pivot is the smallest distance left: split off every entry equal to it instead,
            // which always makes progress however many photons share a distance.
            split = lo + partition_into(src, dst, |d2| d2 <= pivot);
            done = target < split;
        }
        in_scratch = !in_scratch;
        if target < split && !done {
            hi = split;
        } else {
            if in_scratch {
                cands[lo..split].copy_from_slice(&scratch[lo..split]);
            }
            if done {
                return pivot;
            }
            lo = split;
        }
    }
    if in_scratch {
        cands[lo..hi].copy_from_slice(&scratch[lo..hi]);
    }
    // Few left: insertion sort finishes the job.
    let rest = &mut cands[lo..hi];
    for i in 1..rest.len() {
        let e = rest[i];
        let mut j = i;
        while j > 0 && rest[j - 1].0 > e.0 {
            rest[j] = rest[j - 1];
            j -= 1;
        }
        rest[j] = e;
    }
    cands[target].0
}

/// Copies `src` into `dst` (of the same length), the entries whose distance satisfies `left`
/// to the front and the others to the back; returns how many went to the front. Each entry is
/// written to both ends and only the index of its side advances, so nothing branches.
#[inline(always)]
fn partition_into(src: &[(f32, u32)], dst: &mut [(f32, u32)], left: impl Fn(f32) -> bool) -> usize {
    let (mut front, mut back) = (0, dst.len().wrapping_sub(1));
    for &e in src {
        dst[front] = e;
        dst[back] = e;
        let is_left = left(e.0);
        front += usize::from(is_left);
        back = back.wrapping_sub(usize::from(!is_left));
    }
    front
}

// ---------------------------------------------------------------------------------------------
// The kd-tree
// ---------------------------------------------------------------------------------------------

/// Split plane of an interior node: photons left of it have `p[axis] <= value`, right `>= value`.
#[derive(Clone, Copy, Debug, Default)]
#[repr(C)]
struct Split {
    value: f32,
    axis: u32,
}

/// Photons in a balanced kd-tree, built once and then only read (so it is `Sync`).
///
/// Photon indices (in gathers and [`PhotonMap::photon`]) refer to the map's own order, which is
/// not the order of the vector given to [`PhotonMap::build`].
pub struct PhotonMap {
    /// Photons in leaf order.
    photons: Vec<Photon>,
    /// Their positions, the only part the traversal reads.
    points: Vec<[f32; 3]>,
    /// Interior nodes in heap order: root 1, children of `i` are `2i` and `2i + 1`; entry 0 is unused.
    splits: Vec<Split>,
    /// Number of interior levels; leaves are heap nodes `1 << depth .. 2 << depth`.
    depth: u32,
}

impl PhotonMap {
    /// Builds the tree level by level, each level's nodes in parallel; every node splits its
    /// photons at the median of the axis along which their bounding box is largest. Positions
    /// must be finite.
    pub fn build(photons: Vec<Photon>) -> Self {
        Self::build_with_leaf_size(photons, LEAF_SIZE, &std::sync::atomic::AtomicBool::new(false))
            .unwrap_or_else(|| unreachable!("not cancelled"))
    }

    /// `build`, stopping between levels of the tree once `cancel` is set (then `None`).
    pub fn build_cancellable(photons: Vec<Photon>, cancel: &std::sync::atomic::AtomicBool) -> Option<Self> {
        Self::build_with_leaf_size(photons, LEAF_SIZE, cancel)
    }

    /// [`PhotonMap::build`] with leaves of at most `leaf_size >= 2` photons (tests use small
    /// leaves to get deep trees from few photons).
    fn build_with_leaf_size(
        mut photons: Vec<Photon>,
        leaf_size: usize,
        cancel: &std::sync::atomic::AtomicBool,
    ) -> Option<Self> {
        let n = photons.len();
        assert!(n <= u32::MAX as usize, "photon indices are u32");
        assert!(leaf_size >= 2, "with one photon a leaf, leaves could be empty");
        let mut depth = 0u32;
        while n.div_ceil(1 << depth) > leaf_size {
            depth += 1;
        }
        let mut splits = vec![Split::default(); 1 << depth];
        for level in 0..depth {
            if cancel.load(std::sync::atomic::Ordering::Relaxed) {
                return None;
            }
            let nodes = 1usize << level;
            // Split the photon array into this level's node ranges.
            let mut ranges: Vec<&mut [Photon]> = Vec::with_capacity(nodes);
            let mut rest: &mut [Photon] = &mut photons;
            let mut start = 0;
            for j in 0..nodes {
                let end = range_end(n, j + 1, level);
                let (node, tail) = rest.split_at_mut(end - start);
                ranges.push(node);
                rest = tail;
                start = end;
            }
            let level_splits = &mut splits[nodes..2 * nodes];
            let split_node = |(j, (range, split)): (usize, (&mut &mut [Photon], &mut Split))| {
                let mid = range_end(n, 2 * j + 1, level + 1) - range_end(n, j, level);
                *split = split_at_median(range, mid);
            };
            if n >= PARALLEL_MIN {
                // Hand each thread at least PARALLEL_MIN photons' worth of nodes.
                let min_nodes = (PARALLEL_MIN * nodes / n).max(1);
                ranges
                    .par_iter_mut()
                    .zip(level_splits.par_iter_mut())
                    .enumerate()
                    .with_min_len(min_nodes)
                    .for_each(split_node);
            } else {
                ranges.iter_mut().zip(level_splits.iter_mut()).enumerate().for_each(split_node);
            }
        }
        let points = photons.iter().map(|p| p.position).collect();
        Some(PhotonMap { photons, points, splits, depth })
    }

    #[inline]
    pub fn len(&self) -> usize {
        self.photons.len()
    }

    /// Sets the power of each photon (in the map's order) to `power(i)`; positions, directions
    /// and flags, and so the tree, stay as they are.
    pub fn set_powers(&mut self, power: impl Fn(usize) -> Color + Sync) {
        self.photons.par_iter_mut().enumerate().for_each(|(i, p)| *p = p.with_power(power(i)));
    }

    #[inline]
    pub fn is_empty(&self) -> bool {
        self.photons.is_empty()
    }

    /// Photon `i` in the map's order (as returned by [`PhotonMap::gather`]).
    #[inline]
    pub fn photon(&self, i: u32) -> &Photon {
        &self.photons[i as usize]
    }

    /// All photons in the map's order.
    #[inline]
    pub fn photons(&self) -> &[Photon] {
        &self.photons
    }

    /// Heap memory held by the map, in bytes.
    pub fn memory_bytes(&self) -> usize {
        self.photons.capacity() * size_of::<Photon>()
            + self.points.capacity() * size_of::<[f32; 3]>()
            + self.splits.capacity() * size_of::<Split>()
    }

    /// The (at most) `k` photons nearest to `p` with squared distance `<= max_r2`, as
    /// (squared distance, photon index) pairs in no particular order, and the squared distance of
    /// the farthest of them (0 when none was found), which is the radius of the density estimate.
    /// Ties at the k-th distance are broken arbitrarily. Allocates nothing once `out` has served
    /// a gather with the same or a larger `k`.
    ///
    /// Candidates within the current radius are appended to `out`; when `2k + 32` have gathered
    /// they are cut to the nearest `k` and the radius shrinks to the k-th distance.
    pub fn gather<'a>(&self, p: Vec3, k: usize, max_r2: f32, out: &'a mut Gathered) -> (&'a [(f32, u32)], f32) {
        out.len = 0;
        out.radius2 = 0.0;
        if k == 0 || self.photons.is_empty() || !(max_r2 >= 0.0) {
            return (&[], 0.0);
        }
        let k = k.min(self.photons.len());
        let limit = candidate_limit(k);
        let max_leaf = self.photons.len().div_ceil(1 << self.depth);
        // Room for `limit` candidates plus one more leaf (cuts happen between leaves), twice: the
        // second half is the selection's scratch space.
        let room = limit + max_leaf;
        if out.buf.len() < 2 * room {
            out.buf.resize(2 * room, (0.0, 0));
        }
        let (buf, scratch) = out.buf.split_at_mut(room);
        let mut count = 0;

        let q = p.to_array();
        let n = self.photons.len() as u64;
        let first_leaf = 1usize << self.depth;
        let mut bound = max_r2;
        // Far children still to visit, with the squared distance from the query to their cell and
        // its per-axis components (Arya and Mount's incremental distance: `offset` holds them for
        // the current cell), so a cell is skipped when its nearest point, not just its nearest
        // plane, is out of reach.
        let mut stack = [(0u32, 0.0f32, [0.0f32; 3]); STACK_SIZE];
        let mut top = 0;
        let mut node = 1usize;
        let mut offset = [0.0f32; 3];
        'search: loop {
            // Descend to the leaf on the query's side, remembering the far children in reach.
            while node < first_leaf {
                let split = self.splits[node];
                let axis = split.axis as usize;
                let diff = q[axis] - split.value;
                let near = 2 * node + usize::from(diff >= 0.0);
                // Selects rather than an indexed store keep the offsets in registers. The sum is
                // formed like a photon's distance below, so rounding can never make the cell look
                // farther than a photon in it.
                let ox = if axis == 0 { diff } else { offset[0] };
                let oy = if axis == 1 { diff } else { offset[1] };
                let oz = if axis == 2 { diff } else { offset[2] };
                let far_cell2 = ox * ox + oy * oy + oz * oz;
                if far_cell2 <= bound {
                    stack[top] = ((near ^ 1) as u32, far_cell2, [ox, oy, oz]);
                    top += 1;
                }
                node = near;
            }
            let leaf = (node - first_leaf) as u64;
            let start = ((n * leaf) >> self.depth) as usize;
            let end = ((n * (leaf + 1)) >> self.depth) as usize;
            for (i, point) in self.points[start..end].iter().enumerate() {
                let (dx, dy, dz) = (point[0] - q[0], point[1] - q[1], point[2] - q[2]);
                let d2 = dx * dx + dy * dy + dz * dz;
                buf[count] = (d2, (start + i) as u32);
                count += usize::from(d2 <= bound);
            }
            if count >= limit {
                bound = select_nearest(&mut buf[..count], scratch, k);
                count = k;
            }
            // Resume at the deepest far child still within reach.
            loop {
                if top == 0 {
                    break 'search;
                }
                top -= 1;
                let (far, far_cell2, far_offset) = stack[top];
                if far_cell2 <= bound {
                    (node, offset) = (far as usize, far_offset);
                    break;
                }
            }
        }
        out.radius2 = if count > k {
            let kth = select_nearest(&mut buf[..count], scratch, k);
            count = k;
            kth
        } else {
            buf[..count].iter().fold(0.0, |m, e| e.0.max(m))
        };
        out.len = count;
        (&out.buf[..count], out.radius2)
    }
}

/// End of the photon range of node `j` on tree level `level` (the start of node `j + 1`).
#[inline]
fn range_end(n: usize, j: usize, level: u32) -> usize {
    ((n as u64 * j as u64) >> level) as usize
}

/// Reorders `photons` so the first `mid` lie at or below the returned plane and the rest at or
/// above it, on the axis along which their bounding box is largest.
fn split_at_median(photons: &mut [Photon], mid: usize) -> Split {
    let (mut lo, mut hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
    for p in photons.iter() {
        for a in 0..3 {
            lo[a] = lo[a].min(p.position[a]);
            hi[a] = hi[a].max(p.position[a]);
        }
    }
    let extent = [hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]];
    let axis = if extent[0] >= extent[1] && extent[0] >= extent[2] {
        0
    } else if extent[1] >= extent[2] {
        1
    } else {
        2
    };
    photons.select_nth_unstable_by(mid, |a, b| a.position[axis].total_cmp(&b.position[axis]));
    Split { value: photons[mid].position[axis], axis: axis as u32 }
}

#[cfg(test)]
mod tests;
