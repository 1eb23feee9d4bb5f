//! The photons of one SPPM iteration in a hash grid (`photon::grid`), each marked focused or
//! not: a query visits them in a fixed order whatever the thread count.

use crate::math::Vec3;
use crate::photon::grid::HashGrid;
use crate::photon::trace::PhotonHit;
use crate::photon::{HitIds, PhotonHits};

/// Photons of one iteration in a hash grid, their ids the photons' `HitIds` with `FOCUSED_BIT`
/// set for focused photons: the caller reads a photon only when it is in range (and, for a
/// focused one, within the near disc).
pub(super) struct PhotonGrid {
    grid: HashGrid,
    ids: HitIds,
}

/// The id bit that marks a photon `trace::FOCUSED`; the other 31 bits hold its `HitIds` id.
const FOCUSED_BIT: u32 = 1 << 31;

/// A photon a query found: its id, squared distance from the query point, and whether it is
/// focused (`trace::FOCUSED`), read from the grid without touching the photon itself.
#[derive(Clone, Copy, Debug)]
pub(super) struct Found {
    pub(super) id: u32,
    pub(super) d2: f32,
    pub(super) focused: bool,
}

impl PhotonGrid {
    pub(super) fn build(hits: &mut PhotonHits, cell: f32, origin: Vec3) -> Self {
        let mut grid = PhotonGrid { grid: HashGrid::default(), ids: hits.ids() };
        grid.rebuild(hits, cell, origin);
        grid
    }

    /// Sorts `hits` into the grid again, reusing its buffers (an SPPM iteration allocates no
    /// new grid).
    pub(super) fn rebuild(&mut self, hits: &mut PhotonHits, cell: f32, origin: Vec3) {
        let ids = hits.ids();
        let hits = &*hits;
        let points = |r: std::ops::Range<usize>| {
            let all = hits.chunks().iter().enumerate().flat_map(move |(c, chunk)| {
                chunk.iter().enumerate().map(move |(k, h)| {
                    let focused = if h.flags & crate::photon::trace::FOCUSED != 0 { FOCUSED_BIT } else { 0 };
                    (h.p, ids.id(c, k) | focused)
                })
            });
            all.skip(r.start).take(r.len())
        };
        self.grid.rebuild(hits.len(), points, cell, origin);
        self.ids = ids;
    }

    /// The photon a query found.
    #[inline]
    pub(super) fn photon<'a>(&self, hits: &'a PhotonHits, found: Found) -> &'a PhotonHit {
        self.ids.get(hits, found.id)
    }

    /// Bytes held.
    pub(super) fn memory_bytes(&self) -> usize {
        self.grid.memory_bytes()
    }

    /// Calls `f` for every photon within distance `r` of `p` (at most `r`), each once, in a
    /// fixed order (`HashGrid::for_each_within`).
    #[inline]
    pub(super) fn for_each_within(&self, p: Vec3, r: f32, mut f: impl FnMut(Found)) {
        self.grid.for_each_within(p, r, |found| {
            f(Found { id: found.id & !FOCUSED_BIT, d2: found.d2, focused: found.id & FOCUSED_BIT != 0 })
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Color;

    #[test]
    fn photons_are_found_with_their_index_and_focus() {
        let mut rng = crate::sampling::Rng32::new(1);
        let all: Vec<PhotonHit> = (0..3000)
            .map(|k| PhotonHit {
                p: Vec3::new(rng.uniform(), rng.uniform(), rng.uniform()) * 4.0 - 2.0,
                dir: -Vec3::Y,
                flux: Color::ONE.into(),
                flags: if k % 3 == 0 { crate::photon::trace::FOCUSED } else { 0 },
                depth: 0,
                n: Vec3::Y,
            })
            .collect();
        // In chunks of several sizes, so that ids are not the photons' places in `all`.
        let mut hits = PhotonHits::from_vec(all[..1000].to_vec());
        hits.append(PhotonHits::from_vec(all[1000..1001].to_vec()));
        hits.append(PhotonHits::from_vec(all[1001..].to_vec()));
        let place = |h: &PhotonHit| all.iter().position(|a| a.p == h.p).unwrap() as u32;
        let grid = PhotonGrid::build(&mut hits, 0.6, Vec3::splat(-2.0));
        for _ in 0..100 {
            let q = Vec3::new(rng.uniform(), rng.uniform(), rng.uniform()) * 4.0 - 2.0;
            let mut found = Vec::new();
            grid.for_each_within(q, 0.3, |f| {
                let h = grid.photon(&hits, f);
                assert_eq!(f.d2, (h.p - q).length_squared());
                assert_eq!(f.focused, place(h) % 3 == 0);
                found.push(place(h))
            });
            found.sort();
            let brute: Vec<u32> =
                (0..all.len() as u32).filter(|&i| (all[i as usize].p - q).length_squared() <= 0.09).collect();
            assert_eq!(found, brute);
        }
    }
}
