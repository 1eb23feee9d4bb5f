//! Top-down binned-SAH build (pbrt-v4 sec. 7.3.2) that writes 4-wide nodes directly: each wide
//! node splits its primitives in two, then keeps splitting the child with the largest surface
//! area until it has four children (the collapse of a binary tree, without storing that tree).
//! Every binary split bins its primitives once; large sets are binned in parallel, the two
//! halves of a node are split in parallel and large subtrees are built as separate rayon tasks,
//! so both cores work from the first level down.
//!
//! Temporaries: the 32-byte `BuildPrim`s, reordered in place into leaf order, and the wide
//! nodes of subtrees built in parallel before they are appended to their parent's array.

use super::wide::{LEAF, WideNode};
use crate::geometry::Aabb;
use glam::Vec4;
use rayon::prelude::*;

const BINS: usize = 16;
pub(super) const MAX_LEAF: usize = 4;
/// Binary depth below which splits are by count, keeping any tree shallow enough for the
/// traversal stack (three entries per wide level).
const MEDIAN_DEPTH: usize = 32;
/// Sets larger than this are binned with rayon.
const PAR_BIN: usize = 1 << 15;
/// Sets up to this size are binned on their longest axis only.
/// (Measured on the knot: 64 saves a tenth of the build's CPU time and no traversal speed.)
const AXIS_ONLY: usize = 64;
/// Sets binned from a sample have at least this many primitives in it.
const SAMPLE: usize = 1 << 16;
/// Subtrees larger than this are built as rayon tasks.
const PAR_TREE: usize = 1 << 14;
/// Leaf offsets are stored in 28 bits (see `wide::LEAF`).
pub(super) const MAX_PRIMS: usize = 1 << 28;
/// Keeps index bits in `BuildPrim::lo.w` a normal float, so arithmetic on that lane is never
/// slowed by denormals.
const INDEX_BIAS: u32 = 0x0080_0000;

/// A primitive's box; `lo.w` carries its index (biased, as float bits), `hi.w` the same value.
#[derive(Clone, Copy)]
#[repr(C)]
pub(super) struct BuildPrim {
    lo: Vec4,
    hi: Vec4,
}

impl BuildPrim {
    pub(super) fn new(bounds: Aabb, index: usize) -> Self {
        let w = f32::from_bits(index as u32 + INDEX_BIAS);
        BuildPrim { lo: bounds.min.extend(w), hi: bounds.max.extend(w) }
    }

    pub(super) fn index(&self) -> u32 {
        self.lo.w.to_bits() - INDEX_BIAS
    }

    /// Twice the centroid (the w lane is meaningless).
    #[inline(always)]
    fn c2(&self) -> Vec4 {
        self.lo + self.hi
    }
}

/// Bounds of a set of primitives and of their doubled centroids.
#[derive(Clone, Copy)]
struct Bounds {
    lo: Vec4,
    hi: Vec4,
    clo: Vec4,
    chi: Vec4,
}

impl Bounds {
    const EMPTY: Bounds =
        Bounds { lo: Vec4::INFINITY, hi: Vec4::NEG_INFINITY, clo: Vec4::INFINITY, chi: Vec4::NEG_INFINITY };

    #[inline(always)]
    fn add(&mut self, p: &BuildPrim) {
        // The running value is the second operand, which SSE min/max return when either is
        // NaN: a primitive with NaN bounds (never hit) cannot poison its node's box.
        self.lo = p.lo.min(self.lo);
        self.hi = p.hi.max(self.hi);
        let c = p.c2();
        self.clo = c.min(self.clo);
        self.chi = c.max(self.chi);
    }

    fn merge(self, o: Bounds) -> Bounds {
        Bounds { lo: self.lo.min(o.lo), hi: self.hi.max(o.hi), clo: self.clo.min(o.clo), chi: self.chi.max(o.chi) }
    }

    fn of(prims: &[BuildPrim]) -> Bounds {
        let fold = |s: &[BuildPrim]| {
            let mut b = Bounds::EMPTY;
            s.iter().for_each(|p| b.add(p));
            b
        };
        if prims.len() > PAR_BIN {
            prims.par_chunks(PAR_BIN / 2).map(fold).reduce(|| Bounds::EMPTY, Bounds::merge)
        } else {
            fold(prims)
        }
    }
}

fn half_area(lo: Vec4, hi: Vec4) -> f32 {
    let e = (hi - lo).max(Vec4::ZERO);
    e.x * e.y + e.y * e.z + e.z * e.x
}

/// How a set is split: primitives whose centroid falls in a bin below `bin` (of `last + 1`
/// bins from `lo` on `axis`, `scale` bins per unit) go left.
#[derive(Clone, Copy)]
enum Split {
    Bin { axis: usize, bin: usize, lo: f32, scale: f32, last: f32 },
    Median { axis: usize },
}

/// A contiguous run of primitives (`start` is relative to the slice its wide node owns), with
/// its bounds, binary depth and its split (`None`: a leaf).
#[derive(Clone, Copy)]
struct Item {
    start: usize,
    len: usize,
    b: Bounds,
    depth: usize,
    split: Option<Split>,
    /// The tree's traversal cost, in primitive intersections (`traversal_cost`).
    trav: f32,
}

#[derive(Clone, Copy)]
struct Bin {
    lo: Vec4,
    hi: Vec4,
    n: usize,
}

const EMPTY_BIN: Bin = Bin { lo: Vec4::INFINITY, hi: Vec4::NEG_INFINITY, n: 0 };
type Bins = [[Bin; BINS]; 3];

/// The bin of a doubled centroid on each axis. Scalar `bin_index` gives the same numbers.
#[inline(always)]
fn bin_of(c: Vec4, lo: Vec4, scale: Vec4, last: Vec4) -> [usize; 3] {
    let f = ((c - lo) * scale).min(last).max(Vec4::ZERO);
    [f.x as i32 as usize, f.y as i32 as usize, f.z as i32 as usize]
}

#[inline(always)]
fn bin_index(c: f32, lo: f32, scale: f32, last: f32) -> usize {
    ((c - lo) * scale).min(last).max(0.0) as i32 as usize
}

#[inline(always)]
fn add_to(bins: &mut Bins, p: &BuildPrim, lo: Vec4, scale: Vec4, last: Vec4, axes: (usize, usize)) {
    let idx = bin_of(p.c2(), lo, scale, last);
    for axis in axes.0..axes.1 {
        let b = &mut bins[axis][idx[axis]];
        b.lo = p.lo.min(b.lo);
        b.hi = p.hi.max(b.hi);
        b.n += 1;
    }
}

fn bin(prims: &[BuildPrim], lo: Vec4, scale: Vec4, last: Vec4, axes: (usize, usize)) -> Bins {
    let mut a = [[EMPTY_BIN; BINS]; 3];
    if prims.len() < 64 {
        prims.iter().for_each(|p| add_to(&mut a, p, lo, scale, last, axes));
        return a;
    }
    // Even and odd primitives go to separate bins, so a run of primitives falling in one bin
    // does not wait on its own stores.
    let mut b = [[EMPTY_BIN; BINS]; 3];
    let mut pairs = prims.chunks_exact(2);
    for pair in &mut pairs {
        add_to(&mut a, &pair[0], lo, scale, last, axes);
        add_to(&mut b, &pair[1], lo, scale, last, axes);
    }
    for p in pairs.remainder() {
        add_to(&mut a, p, lo, scale, last, axes);
    }
    merge_bins(a, b)
}

fn bin_sample(prims: &[BuildPrim], stride: usize, lo: Vec4, scale: Vec4, last: Vec4, axes: (usize, usize)) -> Bins {
    if stride == 1 {
        return bin(prims, lo, scale, last, axes);
    }
    let mut a = [[EMPTY_BIN; BINS]; 3];
    prims.iter().step_by(stride).for_each(|p| add_to(&mut a, p, lo, scale, last, axes));
    a
}

fn merge_bins(mut a: Bins, b: Bins) -> Bins {
    for (x, y) in a.iter_mut().flatten().zip(b.iter().flatten()) {
        x.lo = x.lo.min(y.lo);
        x.hi = x.hi.max(y.hi);
        x.n += y.n;
    }
    a
}

/// The split of `prims` (bounds `b`) with the lowest SAH cost, or `None` when a leaf is cheaper.
fn plan(prims: &[BuildPrim], b: &Bounds, depth: usize, trav: f32) -> Option<Split> {
    let n = prims.len();
    if n <= 1 {
        return None;
    }
    let ext = b.chi - b.clo;
    let longest = if ext.x >= ext.y && ext.x >= ext.z {
        0
    } else if ext.y >= ext.z {
        1
    } else {
        2
    };
    if !(ext[longest] > 0.0) || depth >= MEDIAN_DEPTH {
        // No plane separates the centroids (or the tree is already deep): split by count.
        return (n > MAX_LEAF).then_some(Split::Median { axis: longest });
    }
    // Small sets get fewer bins: the sweep below costs more than binning them.
    let nb = n.clamp(4, BINS);
    let scale = Vec4::select(ext.cmpgt(Vec4::ZERO), Vec4::splat(nb as f32) / ext, Vec4::ZERO);
    let last = Vec4::splat((nb - 1) as f32);
    // Large sets are binned on all three axes; small ones, where the per-set cost dominates,
    // on the longest (as pbrt-v4 does everywhere).
    let axes = if n > AXIS_ONLY { (0, 3) } else { (longest, longest + 1) };
    let bins = if n > PAR_BIN {
        // Large sets are binned from every `stride`-th primitive: the top levels are where
        // the build waits on memory, and a sample of 64k places the plane as well.
        let stride = (n / SAMPLE).max(1);
        prims
            .par_chunks(PAR_BIN / 2)
            .map(|c| bin_sample(c, stride, b.clo, scale, last, axes))
            .reduce(|| [[EMPTY_BIN; BINS]; 3], merge_bins)
    } else {
        bin(prims, b.clo, scale, last, axes)
    };
    let mut best = (f32::INFINITY, 0usize, 0usize);
    for (axis, bins) in bins.iter().enumerate() {
        if !(ext[axis] > 0.0) || axis < axes.0 || axis >= axes.1 {
            continue;
        }
        // Sweep from the right for the area and count of every right-hand side.
        let mut right = [(0.0f32, 0usize); BINS];
        let (mut lo, mut hi, mut cnt) = (Vec4::INFINITY, Vec4::NEG_INFINITY, 0);
        for i in (1..nb).rev() {
            lo = lo.min(bins[i].lo);
            hi = hi.max(bins[i].hi);
            cnt += bins[i].n;
            right[i] = (half_area(lo, hi), cnt);
        }
        let (mut lo, mut hi, mut cnt) = (Vec4::INFINITY, Vec4::NEG_INFINITY, 0);
        for i in 1..nb {
            lo = lo.min(bins[i - 1].lo);
            hi = hi.max(bins[i - 1].hi);
            cnt += bins[i - 1].n;
            if cnt == 0 || right[i].1 == 0 {
                continue;
            }
            let cost = half_area(lo, hi) * cnt as f32 + right[i].0 * right[i].1 as f32;
            if cost < best.0 {
                best = (cost, axis, i);
            }
        }
    }
    // Cost relative to a leaf, with a node's traversal costing `trav` intersections.
    let split_cost = trav + best.0 / half_area(b.lo, b.hi).max(f32::MIN_POSITIVE);
    if n <= MAX_LEAF && split_cost >= n as f32 {
        return None;
    }
    if !best.0.is_finite() {
        return Some(Split::Median { axis: longest });
    }
    let axis = best.1;
    Some(Split::Bin { axis, bin: best.2, lo: b.clo[axis], scale: scale[axis], last: last[axis] })
}

/// Partitions `prims` by `split`; returns the size of the left part and both parts' bounds.
fn partition(prims: &mut [BuildPrim], split: Split) -> (usize, Bounds, Bounds) {
    let n = prims.len();
    let (axis, bin, lo, scale, last) = match split {
        Split::Bin { axis, bin, lo, scale, last } => (axis, bin, lo, scale, last),
        Split::Median { axis } => return median(prims, axis),
    };
    let goes_left = |p: &BuildPrim| bin_index(p.c2()[axis], lo, scale, last) < bin;
    let (mut lb, mut rb) = (Bounds::EMPTY, Bounds::EMPTY);
    // Hoare's scheme: each primitive is read once and moved at most once.
    let (mut i, mut j) = (0, n);
    loop {
        while i < j && goes_left(&prims[i]) {
            lb.add(&prims[i]);
            i += 1;
        }
        while i < j && !goes_left(&prims[j - 1]) {
            rb.add(&prims[j - 1]);
            j -= 1;
        }
        if i >= j {
            break;
        }
        prims.swap(i, j - 1);
        lb.add(&prims[i]);
        rb.add(&prims[j - 1]);
        i += 1;
        j -= 1;
    }
    if i == 0 || i == n {
        // Rounding put everything on one side: fall back to the median.
        let ext = lb.merge(rb);
        let e = ext.chi - ext.clo;
        let longest = if e.x >= e.y && e.x >= e.z {
            0
        } else if e.y >= e.z {
            1
        } else {
            2
        };
        return median(prims, longest);
    }
    (i, lb, rb)
}

fn median(prims: &mut [BuildPrim], axis: usize) -> (usize, Bounds, Bounds) {
    let mid = prims.len() / 2;
    prims.select_nth_unstable_by(mid, |a, b| a.c2()[axis].total_cmp(&b.c2()[axis]));
    let (l, r) = prims.split_at(mid);
    (mid, Bounds::of(l), Bounds::of(r))
}

/// Splits `item` (whose primitives are `prims`) into two planned items.
fn split_item(prims: &mut [BuildPrim], item: &Item) -> (Item, Item) {
    let (mid, lb, rb) = partition(prims, item.split.expect("only planned items are split"));
    let (l, r) = prims.split_at(mid);
    let (depth, trav) = (item.depth + 1, item.trav);
    let plan2 = |s: &[BuildPrim], b: &Bounds| plan(s, b, depth, trav);
    let (pl, pr) = if prims.len() > PAR_BIN {
        rayon::join(|| plan2(l, &lb), || plan2(r, &rb))
    } else {
        (plan2(l, &lb), plan2(r, &rb))
    };
    (
        Item { start: item.start, len: mid, b: lb, depth, split: pl, trav },
        Item { start: item.start + mid, len: item.len - mid, b: rb, depth, split: pr, trav },
    )
}

/// A node's traversal cost relative to one primitive test, for the SAH. One in general: in a
/// mesh, splitting a leaf of a few small triangles culls little and adds a node. In small scenes
/// (rooms of a few dozen quads and spheres, the photon benchmark's Cornell box) the primitives are
/// large and overlap few rays each, and leaves of one or two measured faster (photon tracing
/// 6% faster, the same photons), while a half-cost everywhere made meshes 3-5% slower.
fn traversal_cost(n: usize) -> f32 {
    if n <= SMALL_SCENE { 0.5 } else { 1.0 }
}

/// Up to this many primitives a tree is built with the small scenes' traversal cost.
const SMALL_SCENE: usize = 256;

/// A built tree: node 0 is the root. Its nodes are still in the pieces the threads built
/// (`nodes` joins them), so that the build records can be freed before the nodes are copied
/// together: copying them at each parallel level during the build held the nodes twice beside
/// the records, the peak of loading a big mesh.
pub(super) struct Tree {
    chunk: Chunk,
    /// Number of node levels.
    pub(super) depth: u32,
    /// The exact bounds of all primitives.
    pub(super) bounds: Aabb,
}

impl Tree {
    /// The nodes in one array, each piece after the one that refers to it (depth first).
    pub(super) fn nodes(self) -> Vec<WideNode> {
        let mut out = Vec::with_capacity(self.chunk.total());
        self.chunk.flatten(&mut out);
        out
    }
}

/// Nodes one thread built: their references to each other are indices into `nodes`; the
/// subtrees other threads built hang off child slots and are placed after them.
#[derive(Default)]
struct Chunk {
    nodes: Vec<WideNode>,
    /// (node in `nodes`, child slot, the subtree there).
    subtrees: Vec<(usize, usize, Chunk)>,
}

impl Chunk {
    fn total(&self) -> usize {
        self.nodes.len() + self.subtrees.iter().map(|(_, _, c)| c.total()).sum::<usize>()
    }

    fn flatten(self, out: &mut Vec<WideNode>) {
        let base = out.len() as u32;
        out.extend(self.nodes.into_iter().map(|mut c| {
            c.child.iter_mut().filter(|c| **c & LEAF == 0 && **c != WideNode::NONE).for_each(|c| *c += base);
            c
        }));
        for (node, slot, sub) in self.subtrees {
            out[base as usize + node].child[slot] = out.len() as u32;
            sub.flatten(out);
        }
    }
}

/// The wide tree over `prims`, which are reordered into leaf order (each leaf's offset
/// indexes them).
pub(super) fn build_wide(prims: &mut [BuildPrim]) -> Tree {
    assert!(prims.len() < MAX_PRIMS, "a BVH holds at most {MAX_PRIMS} primitives");
    if prims.is_empty() {
        return Tree { chunk: Chunk::default(), depth: 0, bounds: Aabb::EMPTY };
    }
    let b = Bounds::of(prims);
    let trav = traversal_cost(prims.len());
    let root = Item { start: 0, len: prims.len(), b, depth: 0, split: plan(prims, &b, 0, trav), trav };
    // About one node per eight primitives; untouched capacity costs no memory.
    let mut chunk = Chunk { nodes: Vec::with_capacity(prims.len() / 6 + 1), subtrees: Vec::new() };
    let depth = node(prims, 0, root, &mut chunk, (prims.len() / 16).max(PAR_TREE));
    Tree { chunk, depth, bounds: Aabb { min: b.lo.truncate(), max: b.hi.truncate() } }
}

/// Appends the wide node for `item` (covering all of `prims`, whose first element is at
/// `offset` in the full array) and its subtree to `out`; returns the subtree's node levels.
/// Children larger than `par` are built as separate tasks, each into a chunk of its own.
fn node(prims: &mut [BuildPrim], offset: usize, item: Item, out: &mut Chunk, par: usize) -> u32 {
    let mut items = [item; 4];
    let mut count = 1;
    items[0].start = 0;
    while count < 4 {
        // The two halves of a large node are split at once.
        if count == 2 && items[0].len > PAR_TREE && items[1].split.is_some() && items[0].split.is_some() {
            let (a, b) = (items[0], items[1]);
            let (pa, pb) = prims.split_at_mut(b.start);
            let ((a0, a1), (b0, b1)) = rayon::join(|| split_item(pa, &a), || split_item(pb, &b));
            items = [a0, a1, b0, b1];
            count = 4;
            break;
        }
        let Some(k) = (0..count).filter(|&k| items[k].split.is_some()).max_by(|&a, &b| {
            half_area(items[a].b.lo, items[a].b.hi).total_cmp(&half_area(items[b].b.lo, items[b].b.hi))
        }) else {
            break;
        };
        let it = items[k];
        let (a, b) = split_item(&mut prims[it.start..it.start + it.len], &it);
        items[k] = a;
        items[count] = b;
        count += 1;
    }
    let items = &mut items[..count];
    items.sort_unstable_by_key(|it| it.start);

    let at = out.nodes.len();
    out.nodes.push(WideNode::new(&[], [WideNode::NONE; 4]));
    let mut child = [WideNode::NONE; 4];
    for (k, it) in items.iter().enumerate() {
        if it.split.is_none() {
            child[k] = LEAF | ((offset + it.start) as u32) << 3 | (it.len as u32 - 1);
        }
    }
    let mut depth = 0;
    let interior = items.iter().filter(|it| it.split.is_some()).count();
    let big = items.iter().filter(|it| it.split.is_some() && it.len > par).count();
    // Slices of each child's primitives, in order.
    let mut rest = prims;
    let mut parts = Vec::with_capacity(4);
    for (k, it) in items.iter().enumerate() {
        let (head, tail) = rest.split_at_mut(it.len);
        rest = tail;
        if it.split.is_some() {
            parts.push((k, head, *it));
        }
    }
    if interior >= 2 && big >= 1 {
        let subtrees: Vec<(usize, Chunk, u32)> = parts
            .into_par_iter()
            .map(|(k, s, it)| {
                // About one node per eight primitives; untouched capacity costs no memory.
                let mut c = Chunk { nodes: Vec::with_capacity(it.len / 6 + 1), subtrees: Vec::new() };
                let d = node(s, offset + it.start, Item { start: 0, ..it }, &mut c, par);
                (k, c, d)
            })
            .collect();
        for (k, c, d) in subtrees {
            depth = depth.max(d);
            out.subtrees.push((at, k, c));
        }
    } else {
        for (k, s, it) in parts {
            child[k] = out.nodes.len() as u32;
            depth = depth.max(node(s, offset + it.start, Item { start: 0, ..it }, out, par));
        }
    }
    let boxes: Vec<(Vec4, Vec4)> = items.iter().map(|it| (it.b.lo, it.b.hi)).collect();
    out.nodes[at] = WideNode::new(&boxes, child);
    depth + 1
}

/// Reorders `items` so that item `i` becomes the old `items[order[i]]`, in place (following the
/// permutation's cycles), so nothing is held twice. `order` is consumed.
pub(super) fn permute<T: Copy>(items: &mut [T], order: &mut [u32]) {
    const DONE: u32 = u32::MAX;
    for start in 0..items.len() {
        if order[start] == DONE {
            continue;
        }
        let first = items[start];
        let mut cur = start;
        loop {
            let src = order[cur] as usize;
            order[cur] = DONE;
            if src == start {
                items[cur] = first;
                break;
            }
            items[cur] = items[src];
            cur = src;
        }
    }
}
