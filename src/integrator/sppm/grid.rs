//! The photons of one SPPM iteration in a hash grid: entries in bucket order, so a pixel's query
//! visits its photons in a fixed order whatever the thread count.

use crate::math::Vec3;
use crate::photon::trace::PhotonHit;
use glam::Vec4;

/// Photons of one iteration sorted into a hash grid: entries in bucket order, and within a
/// bucket in photon order.
pub(super) struct PhotonGrid {
    pub(super) cell: f32,
    origin: Vec3,
    mask: u64,
    /// bucket -> range in `entries` (one more than the buckets; also the sort's write cursors
    /// while it runs).
    pub(super) starts: Vec<u32>,
    /// The entries' photon positions, one coordinate per array (a query tests four entries'
    /// distances at once), and their photon indices with `FOCUSED_BIT` set for focused photons:
    /// the caller reads a photon only when it is in range (and, for a focused one, within the
    /// near disc).
    xs: Vec<f32>,
    ys: Vec<f32>,
    zs: Vec<f32>,
    ids: Vec<u32>,
}

/// The entry bit that marks a photon `trace::FOCUSED`; the other 31 bits hold its index (an
/// iteration's photons are far fewer than 2^31: 2^31 hits would be 96 GiB).
const FOCUSED_BIT: u32 = 1 << 31;

/// A photon a query found: its index, squared distance from the query point, and whether it
/// is focused (`trace::FOCUSED`), read from the grid without touching the photon itself.
#[derive(Clone, Copy, Debug)]
pub(super) struct Found {
    pub(super) index: u32,
    pub(super) d2: f32,
    pub(super) focused: bool,
}

impl Found {
    #[inline(always)]
    fn of(entry: u32, d2: f32) -> Self {
        Found { index: entry & !FOCUSED_BIT, d2, focused: entry & FOCUSED_BIT != 0 }
    }
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

impl PhotonGrid {
    pub(super) fn build(hits: &[PhotonHit], cell: f32, origin: Vec3) -> Self {
        let mut grid = PhotonGrid {
            cell,
            origin,
            mask: 0,
            starts: Vec::new(),
            xs: Vec::new(),
            ys: Vec::new(),
            zs: Vec::new(),
            ids: Vec::new(),
        };
        grid.rebuild(hits, cell, origin);
        grid
    }

    /// Sorts `hits` into the grid again, reusing its buffers (an SPPM iteration allocates no
    /// new grid): a counting sort by bucket, in photon order within each bucket.
    pub(super) fn rebuild(&mut self, hits: &[PhotonHit], cell: f32, origin: Vec3) {
        let size = hits.len().next_power_of_two().max(1);
        let mask = size as u64 - 1;
        let bucket = |k: u64| (crate::sampling::mix64(k) & mask) as usize;
        // Buckets are worked out twice (to count, then to place) rather than kept: a buffer of
        // them was a tenth of SPPM's memory.
        let key = |h: &PhotonHit| cell_key(Self::coords(h.p, origin, cell));
        self.starts.clear();
        self.starts.resize(size + 1, 0);
        for h in hits {
            self.starts[bucket(key(h)) + 1] += 1;
        }
        for b in 0..size {
            self.starts[b + 1] += self.starts[b];
        }
        for v in [&mut self.xs, &mut self.ys, &mut self.zs] {
            v.clear();
            v.resize(hits.len(), 0.0);
        }
        self.ids.clear();
        self.ids.resize(hits.len(), 0);
        // Each bucket's start moves up as it is filled, ending at the next bucket's start; the
        // starts are then one bucket behind, and shifting them back restores them.
        debug_assert!(hits.len() < FOCUSED_BIT as usize);
        for (i, h) in hits.iter().enumerate() {
            let b = bucket(key(h));
            let focused = if h.flags & crate::photon::trace::FOCUSED != 0 { FOCUSED_BIT } else { 0 };
            let k = self.starts[b] as usize;
            (self.xs[k], self.ys[k], self.zs[k]) = (h.p.x, h.p.y, h.p.z);
            self.ids[k] = i as u32 | focused;
            self.starts[b] += 1;
        }
        self.starts.copy_within(0..size, 1);
        self.starts[0] = 0;
        (self.cell, self.origin, self.mask) = (cell, origin, mask);
    }

    /// Bytes held.
    pub(super) fn memory_bytes(&self) -> usize {
        (self.xs.capacity() + self.ys.capacity() + self.zs.capacity() + self.ids.capacity() + self.starts.capacity())
            * 4
    }

    #[inline]
    fn coords(p: Vec3, origin: Vec3, cell: f32) -> [i32; 3] {
        let c = (p - origin) / cell;
        [floor_clamped(c.x), floor_clamped(c.y), floor_clamped(c.z)]
    }

    /// Calls `f` for every photon within distance `r` of `p` (at most `r`), each once, in a
    /// fixed order. A cell's bucket holds photons of other cells too, which the
    /// distance test leaves out; each bucket is read once (in increasing order, each in photon
    /// order), so a photon in range is met once however many of the query's cells share its
    /// bucket. A query of more than `MAX_BUCKETS` cells (a radius far above the cells' size)
    /// reads the cells in turn instead and counts a photon when its own cell is read.
    #[inline]
    pub(super) fn for_each_within(&self, p: Vec3, r: f32, mut f: impl FnMut(Found)) {
        const MAX_BUCKETS: usize = 64;
        let lo = Self::coords(p - Vec3::splat(r), self.origin, self.cell);
        let hi = Self::coords(p + Vec3::splat(r), self.origin, self.cell);
        let r2 = r * r;
        let span = |a: usize| (i64::from(hi[a]) - i64::from(lo[a]) + 1) as usize;
        let bucket = |c: [i32; 3]| (crate::sampling::mix64(cell_key(c)) & self.mask) as usize;
        let cells = span(0) * span(1) * span(2);
        if cells <= 8 {
            // The usual query (cells twice the mean radius): at most two cells a side, their
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

    /// Calls `f(position, found)` for the photons of bucket `b` within squared distance `r2` of
    /// `p`.
    #[inline(always)]
    fn scan(&self, b: usize, p: Vec3, r2: f32, mut f: impl FnMut(Vec3, Found)) {
        let (start, end) = (self.starts[b] as usize, self.starts[b + 1] as usize);
        let (xs, ys, zs, ids) =
            (&self.xs[start..end], &self.ys[start..end], &self.zs[start..end], &self.ids[start..end]);
        // Four entries at a time: each lane computes (q - p) . (q - p) with the scalar
        // `length_squared`'s operations in its order, so the distances are the same bit for bit.
        let (px, py, pz, r2s) = (Vec4::splat(p.x), Vec4::splat(p.y), Vec4::splat(p.z), Vec4::splat(r2));
        let load = |c: &[f32]| Vec4::from(<[f32; 4]>::try_from(c).unwrap_or_default());
        let quads = xs.len() / 4;
        let chunks = xs.chunks_exact(4).zip(ys.chunks_exact(4)).zip(zs.chunks_exact(4).zip(ids.chunks_exact(4)));
        for ((cx, cy), (cz, ci)) in chunks {
            let (dx, dy, dz) = (load(cx) - px, load(cy) - py, load(cz) - pz);
            let d2 = dx * dx + dy * dy + dz * dz;
            let mut hits = d2.cmple(r2s).bitmask();
            if hits == 0 {
                continue;
            }
            let d2 = d2.to_array();
            while hits != 0 {
                let lane = hits.trailing_zeros() as usize & 3;
                hits &= hits - 1;
                f(Vec3::new(cx[lane], cy[lane], cz[lane]), Found::of(ci[lane], d2[lane]));
            }
        }
        for i in 4 * quads..xs.len() {
            let q = Vec3::new(xs[i], ys[i], zs[i]);
            let d2 = (q - p).length_squared();
            if d2 <= r2 {
                f(q, Found::of(ids[i], d2));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Color;

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
    fn grid_finds_each_nearby_photon_once() {
        let mut rng = crate::sampling::Rng32::new(1);
        let hits: Vec<PhotonHit> = (0..5000)
            .map(|_| PhotonHit {
                p: Vec3::new(rng.uniform(), rng.uniform(), rng.uniform()) * 4.0 - 2.0,
                dir: -Vec3::Y,
                flux: Color::ONE.into(),
                flags: 0,
                depth: 0,
                n: Vec3::Y,
            })
            .collect();
        // Cells of twice the radius and of the radius (buckets read once each), and cells far
        // smaller than the radius (cells read in turn).
        for (cell, r) in [(0.6, 0.3), (0.3, 0.3), (0.05, 0.3)] {
            let grid = PhotonGrid::build(&hits, cell, Vec3::splat(-2.0));
            for _ in 0..200 {
                let q = Vec3::new(rng.uniform(), rng.uniform(), rng.uniform()) * 4.0 - 2.0;
                let mut found = Vec::new();
                grid.for_each_within(q, r, |f| {
                    assert_eq!(f.d2, (hits[f.index as usize].p - q).length_squared());
                    found.push(f.index)
                });
                let mut brute: Vec<u32> =
                    (0..hits.len() as u32).filter(|&i| (hits[i as usize].p - q).length_squared() <= r * r).collect();
                // Each once: sorted, the lists are equal only without repeats.
                found.sort();
                brute.sort();
                assert_eq!(found, brute, "cell {cell}, radius {r}");
            }
        }
    }
}
