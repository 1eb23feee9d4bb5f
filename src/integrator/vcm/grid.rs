//! The light vertices of one VCM iteration in a hashed uniform grid (Teschner et al. 2003's
//! spatial hashing, as SmallVCM's `HashGrid` and SPPM's photon grid use it): cells twice the
//! merge radius wide, so a query sphere overlaps at most 2 x 2 x 2 of them, hashed into as many
//! buckets as there are vertices; a counting sort puts each bucket's vertex indices together in
//! increasing order. A query visits each distinct bucket once (two cells may share one), so
//! every vertex is offered at most once, always in the same order: merges are summed in an
//! order that does not depend on the thread count.
//!
//! Building it is two passes over the vertices and needs no comparison sort (SPPM's grid sorts
//! its entries), since every query has the same radius.

use crate::math::Vec3;

/// Vertex indices bucketed by the hash of their cell.
#[derive(Default)]
pub struct VertexGrid {
    /// Cell width (twice the query radius) and the grid's origin.
    cell: f32,
    origin: Vec3,
    mask: u64,
    /// Bucket b holds `indices[starts[b]..starts[b + 1]]`.
    starts: Vec<u32>,
    indices: Vec<u32>,
}

#[inline]
fn cell_hash(c: [i32; 3]) -> u64 {
    let m = |v: i32| (v as i64 + (1 << 20)) as u64 & 0x1f_ffff;
    crate::sampling::mix64(m(c[0]) | m(c[1]) << 21 | m(c[2]) << 42)
}

impl VertexGrid {
    /// Sorts the points `positions` into the grid for queries of radius `radius`, reusing the
    /// grid's buffers.
    pub fn rebuild(&mut self, positions: &[Vec3], radius: f32, origin: Vec3) {
        let n = positions.len();
        let size = n.next_power_of_two().max(1);
        self.cell = 2.0 * radius;
        self.origin = origin;
        self.mask = size as u64 - 1;
        self.starts.clear();
        self.starts.resize(size + 1, 0);
        let bucket = |p: Vec3| (cell_hash(Self::coords(p, origin, 2.0 * radius)) & (size as u64 - 1)) as usize;
        for &p in positions {
            self.starts[bucket(p) + 1] += 1;
        }
        for b in 0..size {
            self.starts[b + 1] += self.starts[b];
        }
        // Each bucket's next free slot, from its start: indices go in increasing order.
        let mut next: Vec<u32> = self.starts[..size].to_vec();
        self.indices.clear();
        self.indices.resize(n, 0);
        for (i, &p) in positions.iter().enumerate() {
            let b = bucket(p);
            self.indices[next[b] as usize] = i as u32;
            next[b] += 1;
        }
    }

    #[inline]
    fn coords(p: Vec3, origin: Vec3, cell: f32) -> [i32; 3] {
        let c = ((p - origin) / cell).floor();
        [c.x.clamp(-1e6, 1e6) as i32, c.y.clamp(-1e6, 1e6) as i32, c.z.clamp(-1e6, 1e6) as i32]
    }

    /// Calls `f(index)` for every vertex whose cell may hold points within the query radius of
    /// `p` (the caller checks the distance), each once, in a fixed order.
    #[inline]
    pub fn for_each_near(&self, p: Vec3, mut f: impl FnMut(u32)) {
        if self.indices.is_empty() {
            return;
        }
        let r = 0.5 * self.cell;
        let lo = Self::coords(p - Vec3::splat(r), self.origin, self.cell);
        let hi = Self::coords(p + Vec3::splat(r), self.origin, self.cell);
        let mut seen = [usize::MAX; 8];
        let mut n_seen = 0;
        for x in lo[0]..=hi[0] {
            for y in lo[1]..=hi[1] {
                for z in lo[2]..=hi[2] {
                    let b = (cell_hash([x, y, z]) & self.mask) as usize;
                    if seen[..n_seen].contains(&b) {
                        continue;
                    }
                    if n_seen < seen.len() {
                        seen[n_seen] = b;
                        n_seen += 1;
                    }
                    for &i in &self.indices[self.starts[b] as usize..self.starts[b + 1] as usize] {
                        f(i);
                    }
                }
            }
        }
    }

    /// Bytes the grid holds.
    pub fn memory_bytes(&self) -> usize {
        (self.starts.capacity() + self.indices.capacity()) * std::mem::size_of::<u32>()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_point_within_the_radius_is_offered_exactly_once() {
        let mut rng = crate::sampling::Rng32::new(5);
        // Uniform points and a dense cluster (a caustic), some exactly on cell boundaries.
        let mut points: Vec<Vec3> =
            (0..4000).map(|_| Vec3::new(rng.uniform(), rng.uniform(), rng.uniform()) * 4.0 - 2.0).collect();
        points.extend((0..2000).map(|_| Vec3::new(rng.uniform(), rng.uniform(), 0.0) * 0.05));
        points.extend((0..50).map(|k| Vec3::new(k as f32 * 0.3 - 2.0, 0.6, 0.0)));
        let r = 0.15;
        let mut grid = VertexGrid::default();
        grid.rebuild(&points, r, Vec3::splat(-2.0));
        for q in 0..400 {
            let p = if q % 2 == 0 {
                Vec3::new(rng.uniform(), rng.uniform(), rng.uniform()) * 4.0 - 2.0
            } else {
                Vec3::new(rng.uniform(), rng.uniform(), 0.0) * 0.08
            };
            let mut offered = Vec::new();
            grid.for_each_near(p, |i| offered.push(i));
            let mut unique = offered.clone();
            unique.sort();
            unique.dedup();
            assert_eq!(unique.len(), offered.len(), "a point was offered twice");
            let mut found: Vec<u32> = offered.into_iter().filter(|&i| (points[i as usize] - p).length() <= r).collect();
            found.sort();
            let brute: Vec<u32> =
                (0..points.len() as u32).filter(|&i| (points[i as usize] - p).length() <= r).collect();
            assert_eq!(found, brute);
        }
    }
}
