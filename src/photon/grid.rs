//! Points in a hashed uniform grid, for queries of about one radius: SPPM's photons and VCM's
//! light vertices (Teschner et al. 2003's spatial hashing, as SmallVCM's `HashGrid` uses it).
//! Cells are hashed into as many buckets as there are points (a power of two), and a counting
//! sort puts each bucket's points together in point order, so a query visits its points in a
//! fixed order whatever the thread count.
//!
//! With cells twice the query radius a query overlaps at most 2 x 2 x 2 cells. Points are kept
//! one coordinate per array beside an id: a query tests four points' distances at once and its
//! caller reads a point's own data (scattered, tens of bytes) only when it is within range;
//! most candidates are not (a surface crosses 2 x 2 x 2 cells of width 2r, about ten times the
//! disc of radius r).

use crate::math::Vec3;
use glam::Vec4;
use rayon::prelude::*;

/// Entries past the points in each coordinate array, so that a bucket's last four-wide load
/// stays within it.
const PAD: usize = 3;

/// Point ids by the hash of their cell (see the module header).
#[derive(Default)]
pub struct HashGrid {
    cell: f32,
    origin: Vec3,
    mask: u64,
    /// Bucket b holds slots `starts[b]..starts[b + 1]` (one more than the buckets; also the
    /// sort's write cursors while it runs).
    starts: Vec<u32>,
    /// Each slot's point, a coordinate per array, and the id it was given.
    xs: Vec<f32>,
    ys: Vec<f32>,
    zs: Vec<f32>,
    ids: Vec<u32>,
    /// Each point's bucket while the grid is sorted.
    buckets: Vec<u32>,
}

/// Points below which a sort is not split between threads.
const PART_MIN: usize = 8192;

/// `v` split into consecutive runs of the given lengths (which sum to at most its length).
fn split_runs<T>(mut v: &mut [T], lengths: impl Iterator<Item = usize>) -> Vec<&mut [T]> {
    let mut runs = Vec::new();
    for len in lengths {
        let (run, rest) = std::mem::take(&mut v).split_at_mut(len);
        runs.push(run);
        v = rest;
    }
    runs
}

/// A point a query found: its slot (its place in the grid's order: data kept in `ids()` order
/// is read from consecutive addresses), its id and its squared distance from the query point.
#[derive(Clone, Copy, Debug)]
pub struct Found {
    pub slot: u32,
    pub id: u32,
    pub d2: f32,
}

#[inline]
fn cell_key(c: [i32; 3]) -> u64 {
    // Distinct cells get distinct keys for coordinates within +-2^20.
    let m = |v: i32| (v as i64 + (1 << 20)) as u64 & 0x1f_ffff;
    m(c[0]) | m(c[1]) << 21 | m(c[2]) << 42
}

/// `v.clamp(-1e6, 1e6).floor() as i32` without a call to the library's `floorf` (the build's
/// target has no rounding instruction): the same integer for every value, NaN included (0).
#[inline(always)]
fn floor_clamped(v: f32) -> i32 {
    let v = v.clamp(-1e6, 1e6);
    let t = v as i32;
    t - i32::from((t as f32) > v)
}

/// Inserts `b` into the sorted first `n` entries of `list`, keeping them sorted.
#[inline(always)]
fn insert_sorted(list: &mut [u32; 8], n: usize, b: u32) {
    let mut k = n;
    while k > 0 && list[k - 1] > b {
        list[k] = list[k - 1];
        k -= 1;
    }
    list[k] = b;
}

impl HashGrid {
    /// Sorts `n` points into the grid again, reusing its buffers (an iteration allocates no new
    /// grid): `points(range)` gives the positions and ids of the points in `range` of `0..n`,
    /// the same on each call. Cells are `cell` wide from `origin`.
    ///
    /// A counting sort, on all threads: each point's bucket is worked out once, by runs of
    /// points; then each thread places the points of one run of buckets, whose slots are a run
    /// of their own, scanning the points in order. The slots are those of a sort on one thread.
    pub fn rebuild<I: Iterator<Item = (Vec3, u32)>>(
        &mut self,
        n: usize,
        points: impl Fn(std::ops::Range<usize>) -> I + Sync,
        cell: f32,
        origin: Vec3,
    ) {
        let size = n.next_power_of_two().max(1);
        let mask = size as u64 - 1;
        let bucket = |p: Vec3| (crate::sampling::mix64(cell_key(Self::coords(p, origin, cell))) & mask) as u32;
        let parts = rayon::current_num_threads().clamp(1, n.div_ceil(PART_MIN).max(1));
        let run = |k: usize| n * k / parts..n * (k + 1) / parts;
        self.buckets.clear();
        self.buckets.resize(n, 0);
        split_runs(&mut self.buckets, (0..parts).map(|k| run(k).len())).into_par_iter().enumerate().for_each(
            |(k, out)| {
                for (b, (p, _)) in out.iter_mut().zip(points(run(k))) {
                    *b = bucket(p);
                }
            },
        );
        self.starts.clear();
        self.starts.resize(size + 1, 0);
        for &b in &self.buckets {
            self.starts[b as usize + 1] += 1;
        }
        for b in 0..size {
            self.starts[b + 1] += self.starts[b];
        }
        for v in [&mut self.xs, &mut self.ys, &mut self.zs] {
            v.clear();
            v.resize(n + PAD, 0.0);
        }
        self.ids.clear();
        self.ids.resize(n, 0);
        // Part k places the buckets from edges[k], whose slots start at about k n / parts.
        let edges: Vec<usize> =
            (0..=parts)
                .map(|k| {
                    if k == parts {
                        size
                    } else {
                        self.starts[..size].partition_point(|&s| (s as usize) < run(k).start)
                    }
                })
                .collect();
        let buckets_of = |k: usize| edges[k + 1] - edges[k];
        let slots_of = |k: usize| (self.starts[edges[k + 1]] - self.starts[edges[k]]) as usize;
        let slot_runs: Vec<usize> = (0..parts).map(slots_of).collect();
        let (xs, ys, zs) = (
            split_runs(&mut self.xs[..n], slot_runs.iter().copied()),
            split_runs(&mut self.ys[..n], slot_runs.iter().copied()),
            split_runs(&mut self.zs[..n], slot_runs.iter().copied()),
        );
        let ids = split_runs(&mut self.ids, slot_runs.iter().copied());
        // Each bucket's start moves up as it is filled, ending at the next bucket's start; the
        // starts are then one bucket behind, and shifting them back restores them.
        let cursors = split_runs(&mut self.starts[..size], (0..parts).map(buckets_of));
        let buckets = &self.buckets;
        let work: Vec<_> = cursors.into_iter().zip(xs).zip(ys).zip(zs).zip(ids).enumerate().collect();
        work.into_par_iter().for_each(|(k, ((((cursors, xs), ys), zs), ids))| {
            let (first, base) = (edges[k], cursors.first().copied().unwrap_or(0) as usize);
            for (&b, (p, id)) in buckets.iter().zip(points(0..n)) {
                let Some(cursor) = (b as usize).checked_sub(first).and_then(|j| cursors.get_mut(j)) else { continue };
                let slot = *cursor as usize - base;
                (xs[slot], ys[slot], zs[slot]) = (p.x, p.y, p.z);
                ids[slot] = id;
                *cursor += 1;
            }
        });
        self.starts.copy_within(0..size, 1);
        self.starts[0] = 0;
        (self.cell, self.origin, self.mask) = (cell, origin, mask);
    }

    /// The points' ids in slot order.
    pub fn ids(&self) -> &[u32] {
        &self.ids
    }

    /// Bytes held.
    pub fn memory_bytes(&self) -> usize {
        (self.xs.capacity()
            + self.ys.capacity()
            + self.zs.capacity()
            + self.ids.capacity()
            + self.starts.capacity()
            + self.buckets.capacity())
            * 4
    }

    #[inline]
    fn coords(p: Vec3, origin: Vec3, cell: f32) -> [i32; 3] {
        let c = (p - origin) / cell;
        [floor_clamped(c.x), floor_clamped(c.y), floor_clamped(c.z)]
    }

    /// Calls `f` for every point within distance `r` of `p` (at most `r`), each once, in a
    /// fixed order. A cell's bucket holds points of other cells too, which the distance test
    /// leaves out; each bucket is read once (in increasing order, each in point order), so a
    /// point in range is met once however many of the query's cells share its bucket. A query
    /// of more than `MAX_BUCKETS` cells (a radius far above the cells' size) reads the cells in
    /// turn instead and counts a point when its own cell is read.
    #[inline]
    pub fn for_each_within(&self, p: Vec3, r: f32, mut f: impl FnMut(Found)) {
        const MAX_BUCKETS: usize = 64;
        if self.ids.is_empty() {
            return;
        }
        let lo = Self::coords(p - Vec3::splat(r), self.origin, self.cell);
        let hi = Self::coords(p + Vec3::splat(r), self.origin, self.cell);
        let r2 = r * r;
        let span = |a: usize| (i64::from(hi[a]) - i64::from(lo[a]) + 1) as usize;
        let bucket = |c: [i32; 3]| (crate::sampling::mix64(cell_key(c)) & self.mask) as usize;
        let cells = span(0) * span(1) * span(2);
        if cells <= 8 {
            // The usual query (cells twice the radius): at most two cells a side, their
            // buckets sorted by insertion into a small array that needs no clearing.
            let mut buckets = [0u32; 8];
            let mut n = 0;
            for x in lo[0]..=hi[0] {
                for y in lo[1]..=hi[1] {
                    for z in lo[2]..=hi[2] {
                        insert_sorted(&mut buckets, n, bucket([x, y, z]) as u32);
                        n += 1;
                    }
                }
            }
            self.scan_buckets(&buckets[..n], p, r2, &mut f);
            return;
        }
        if cells <= MAX_BUCKETS {
            let mut buckets = [0u32; MAX_BUCKETS];
            let mut n = 0;
            for x in lo[0]..=hi[0] {
                for y in lo[1]..=hi[1] {
                    for z in lo[2]..=hi[2] {
                        buckets[n] = bucket([x, y, z]) as u32;
                        n += 1;
                    }
                }
            }
            let buckets = &mut buckets[..n];
            buckets.sort_unstable();
            self.scan_buckets(buckets, p, r2, &mut f);
            return;
        }
        for x in lo[0]..=hi[0] {
            for y in lo[1]..=hi[1] {
                for z in lo[2]..=hi[2] {
                    self.scan(bucket([x, y, z]), p, r2, |q, found| {
                        if Self::coords(q, self.origin, self.cell) == [x, y, z] {
                            f(found);
                        }
                    });
                }
            }
        }
    }

    /// Scans the buckets of a sorted list (repeats once).
    #[inline(always)]
    fn scan_buckets(&self, buckets: &[u32], p: Vec3, r2: f32, f: &mut impl FnMut(Found)) {
        let mut last = u32::MAX;
        for &b in buckets {
            if b != last {
                self.scan(b as usize, p, r2, |_, found| f(found));
                last = b;
            }
        }
    }

    /// Calls `f(position, found)` for the points of bucket `b` within squared distance `r2` of
    /// `p`.
    #[inline(always)]
    fn scan(&self, b: usize, p: Vec3, r2: f32, mut f: impl FnMut(Vec3, Found)) {
        let (start, end) = (self.starts[b] as usize, self.starts[b + 1] as usize);
        // Four points at a time, the last four of a bucket too: the coordinate arrays have
        // `PAD` more entries, and lanes past the bucket's end are masked off (buckets hold a few
        // points, and a scalar tail was half of a query's work). Each lane computes
        // (q - p) . (q - p) with the scalar `length_squared`'s operations in its order, so the
        // distances are the same bit for bit.
        let (px, py, pz, r2s) = (Vec4::splat(p.x), Vec4::splat(p.y), Vec4::splat(p.z), Vec4::splat(r2));
        let load = |c: &[f32], i: usize| Vec4::from(<[f32; 4]>::try_from(&c[i..i + 4]).unwrap_or_default());
        let mut i = start;
        while i < end {
            let (x, y, z) = (load(&self.xs, i), load(&self.ys, i), load(&self.zs, i));
            let (dx, dy, dz) = (x - px, y - py, z - pz);
            let d2 = dx * dx + dy * dy + dz * dz;
            let live = (1u32 << (end - i).min(4)) - 1;
            let mut hits = d2.cmple(r2s).bitmask() & live;
            if hits != 0 {
                let (x, y, z, d2) = (x.to_array(), y.to_array(), z.to_array(), d2.to_array());
                while hits != 0 {
                    let lane = hits.trailing_zeros() as usize & 3;
                    hits &= hits - 1;
                    let slot = i + lane;
                    f(
                        Vec3::new(x[lane], y[lane], z[lane]),
                        Found { slot: slot as u32, id: self.ids[slot], d2: d2[lane] },
                    );
                }
            }
            i += 4;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The sort on several threads puts every point in the slot the sort on one thread does,
    /// with points crowded into a few cells (long buckets on either side of a part's edge) and
    /// spread over many.
    #[test]
    fn threads_sort_points_into_the_same_slots() {
        let mut rng = crate::sampling::Rng32::new(17);
        let mut points: Vec<Vec3> =
            (0..40_000).map(|_| Vec3::new(rng.uniform(), rng.uniform(), rng.uniform()) * 4.0 - 2.0).collect();
        points.extend((0..30_000).map(|_| Vec3::new(rng.uniform(), rng.uniform(), rng.uniform()) * 0.01));
        let numbered = |r: std::ops::Range<usize>| {
            let first = r.start;
            points[r].iter().enumerate().map(move |(i, &p)| (p, (first + i) as u32))
        };
        let sorted = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            let mut grid = HashGrid::default();
            pool.install(|| grid.rebuild(points.len(), numbered, 0.3, Vec3::splat(-2.0)));
            grid
        };
        let one = sorted(1);
        for threads in [2, 3, 8] {
            let many = sorted(threads);
            assert_eq!(many.ids(), one.ids(), "{threads} threads");
            assert_eq!(many.starts, one.starts, "{threads} threads");
            assert!(many.xs == one.xs && many.ys == one.ys && many.zs == one.zs, "{threads} threads");
        }
        // Each slot holds its own point, and each bucket's points are in point order.
        for (slot, &id) in one.ids().iter().enumerate() {
            assert_eq!(Vec3::new(one.xs[slot], one.ys[slot], one.zs[slot]), points[id as usize]);
        }
        for b in one.starts.windows(2) {
            assert!(one.ids[b[0] as usize..b[1] as usize].is_sorted());
        }
    }

    #[test]
    fn floor_clamped_is_the_library_floor() {
        let floor = |v: f32| v.floor().clamp(-1e6, 1e6) as i32;
        let mut rng = crate::sampling::Rng32::new(7);
        let special = [0.0, -0.0, 0.5, -0.5, 1.0, -1.0, 1e6, -1e6, 1e6 + 64.0, -1e6 - 64.0, 3e9, -3e9];
        let more = [f32::INFINITY, f32::NEG_INFINITY, f32::NAN, f32::MIN_POSITIVE, -f32::MIN_POSITIVE];
        let random = (0..100_000).map(|k| (rng.uniform() - 0.5) * 10f32.powi(k % 8));
        for v in special.into_iter().chain(more).chain(random) {
            assert_eq!(floor_clamped(v), floor(v), "{v}");
        }
        // Just below an integer and at it.
        for k in -1000..1000 {
            let v = k as f32;
            assert_eq!(floor_clamped(v), k);
            assert_eq!(floor_clamped(v - v.abs().max(1.0) * f32::EPSILON), k - 1);
        }
    }

    #[test]
    fn every_point_within_the_radius_is_found_exactly_once() {
        let mut rng = crate::sampling::Rng32::new(1);
        // Uniform points and a dense cluster (a caustic), some exactly on cell boundaries.
        let mut points: Vec<Vec3> =
            (0..5000).map(|_| Vec3::new(rng.uniform(), rng.uniform(), rng.uniform()) * 4.0 - 2.0).collect();
        points.extend((0..2000).map(|_| Vec3::new(rng.uniform(), rng.uniform(), 0.0) * 0.05));
        points.extend((0..50).map(|k| Vec3::new(k as f32 * 0.3 - 2.0, 0.6, 0.0)));
        // Cells of twice the radius and of the radius (buckets read once each), and cells far
        // smaller than the radius (cells read in turn).
        for (cell, r) in [(0.6, 0.3), (0.3, 0.3), (0.05, 0.3)] {
            let mut grid = HashGrid::default();
            // Ids other than the index, to tell them from slots.
            let numbered = |r: std::ops::Range<usize>| {
                let first = r.start;
                points[r].iter().enumerate().map(move |(i, &p)| (p, 3 * (first + i) as u32 + 1))
            };
            grid.rebuild(points.len(), numbered, cell, Vec3::splat(-2.0));
            for q in 0..300 {
                let p = if q % 2 == 0 {
                    Vec3::new(rng.uniform(), rng.uniform(), rng.uniform()) * 4.0 - 2.0
                } else {
                    Vec3::new(rng.uniform(), rng.uniform(), 0.0) * 0.08
                };
                let mut found = Vec::new();
                grid.for_each_within(p, r, |f| {
                    let i = (f.id - 1) as usize / 3;
                    assert_eq!(f.d2, (points[i] - p).length_squared());
                    assert_eq!(grid.ids()[f.slot as usize], f.id);
                    found.push(i)
                });
                let mut brute: Vec<usize> =
                    (0..points.len()).filter(|&i| (points[i] - p).length_squared() <= r * r).collect();
                // Each once: sorted, the lists are equal only without repeats.
                found.sort();
                brute.sort();
                assert_eq!(found, brute, "cell {cell}, radius {r}");
            }
        }
    }
}
