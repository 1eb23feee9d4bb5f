//! The light vertices of one VCM iteration in a hashed uniform grid (Teschner et al. 2003's
//! spatial hashing, as SmallVCM's `HashGrid` and SPPM's photon grid use it): cells twice the
//! merge radius wide, so a query sphere overlaps at most 2 x 2 x 2 of them, hashed into as many
//! buckets as there are vertices; a counting sort puts each bucket's vertex indices together in
//! increasing order. A query visits each distinct bucket once (two cells may share one), so
//! every vertex is offered at most once, always in the same order: merges are summed in an
//! order that does not depend on the thread count.
//!
//! Building it is two passes over the vertices and needs no comparison sort (SPPM's grid sorts
//! its entries), since every query has the same radius. Each entry keeps its vertex's position
//! beside its index, so a query tests distances on the bucket's contiguous entries and reads
//! only the vertices within the radius: most of a query's candidates are outside it (a surface
//! crosses 2 x 2 x 2 cells of width 2r, about ten times the disc of radius r), and reading each
//! candidate's vertex (scattered, over a hundred bytes) took half of a caustic box's render.

use crate::math::Vec3;

/// Vertex indices bucketed by the hash of their cell.
#[derive(Default)]
pub struct VertexGrid {
    /// Cell width (twice the query radius) and the grid's origin.
    cell: f32,
    origin: Vec3,
    mask: u64,
    /// Bucket b holds `entries[starts[b]..starts[b + 1]]`: a vertex's position and index.
    starts: Vec<u32>,
    entries: Vec<(Vec3, u32)>,
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
        self.entries.clear();
        self.entries.resize(n, (Vec3::ZERO, 0));
        for (i, &p) in positions.iter().enumerate() {
            let b = bucket(p);
            self.entries[next[b] as usize] = (p, i as u32);
            next[b] += 1;
        }
    }

    #[inline]
    fn coords(p: Vec3, origin: Vec3, cell: f32) -> [i32; 3] {
        let c = ((p - origin) / cell).floor();
        [c.x.clamp(-1e6, 1e6) as i32, c.y.clamp(-1e6, 1e6) as i32, c.z.clamp(-1e6, 1e6) as i32]
    }

    /// The vertex index of each slot, in slot order (bucket by bucket).
    pub fn slots(&self) -> impl Iterator<Item = u32> + '_ {
        self.entries.iter().map(|e| e.1)
    }

    /// Calls `f(slot)` for every vertex within the query radius of `p` (squared distance at
    /// most `r2`, the radius the grid was built for squared), each once, in a fixed order;
    /// `slots` names its vertex. Data kept by slot is read from consecutive addresses.
    #[inline]
    pub fn for_each_within(&self, p: Vec3, r2: f32, mut f: impl FnMut(usize)) {
        if self.entries.is_empty() {
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
                    let (from, to) = (self.starts[b] as usize, self.starts[b + 1] as usize);
                    for (slot, &(q, _)) in self.entries[from..to].iter().enumerate() {
                        if !((q - p).length_squared() > r2) {
                            f(from + slot);
                        }
                    }
                }
            }
        }
    }

    /// Bytes the grid holds.
    pub fn memory_bytes(&self) -> usize {
        self.starts.capacity() * std::mem::size_of::<u32>()
            + self.entries.capacity() * std::mem::size_of::<(Vec3, u32)>()
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
            let slots: Vec<u32> = grid.slots().collect();
            let mut offered = Vec::new();
            grid.for_each_within(p, r * r, |slot| offered.push(slots[slot]));
            let mut found = offered.clone();
            found.sort();
            found.dedup();
            assert_eq!(found.len(), offered.len(), "a point was offered twice");
            let brute: Vec<u32> =
                (0..points.len() as u32).filter(|&i| (points[i as usize] - p).length_squared() <= r * r).collect();
            assert_eq!(found, brute);
        }
    }
}
