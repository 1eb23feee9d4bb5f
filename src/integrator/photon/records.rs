//! The irradiance records final gathering reads: precomputed at a subset of the global photons
//! (Christensen 1999), so that a gather ray's end point looks up one record instead of gathering
//! k photons.

use super::{IRRADIANCE_STRIDE, RECORD_LEVELS, disc_radius2};
use crate::math::{Color, PackedColor};
use crate::photon::trace::{self, Watch};
use crate::photon::{Gathered, Photon, PhotonHits, PhotonMap};
use std::f32::consts::PI;

/// Irradiance records at every `IRRADIANCE_STRIDE`-th global photon: a map of their positions
/// and normals, and for each (in the map's order) the irradiance from its `k` nearest photons
/// (facing the same way and near its tangent plane) of at most `depth - j` bounces for each
/// level j; `None` when cancelled.
pub(super) fn precompute_irradiance(
    hits: &PhotonHits,
    map: &PhotonMap,
    k: usize,
    max_r: f32,
    depth: u32,
    watch: Watch,
) -> Option<(PhotonMap, Vec<[PackedColor; RECORD_LEVELS - 1]>)> {
    use rayon::prelude::*;
    let records: Vec<Photon> =
        hits.iter().step_by(IRRADIANCE_STRIDE).map(|h| Photon::new(h.p, h.n, Color::ZERO, 0)).collect();
    let mut records = PhotonMap::build_cancellable(records, watch.cancel)?;
    // Packed (12 bytes a level): the records are RGB in either mode.
    let levels: Vec<[PackedColor; RECORD_LEVELS]> = records
        .photons()
        .par_chunks(4096)
        .flat_map_iter(|chunk| {
            let mut g = Gathered::new(k);
            if watch.cancelled() {
                return Vec::new();
            }
            watch.advance(chunk.len() as u64);
            chunk
                .iter()
                .map(|rec| {
                    let (p, n) = (rec.position(), rec.direction());
                    let (found, r2) = map.gather(p, k, max_r * max_r, &mut g);
                    let r2 = disc_radius2(found.len(), k, r2, max_r);
                    let mut e = [Color::ZERO; RECORD_LEVELS];
                    if r2 > 0.0 {
                        let thickness = 0.25 * r2.sqrt();
                        for &(_, i) in found {
                            let ph = map.photon(i);
                            // Counted at each level j whose limit depth - j its bounces keep to.
                            let Some(spare) = depth.checked_sub(trace::packed_depth(ph.flags())) else { continue };
                            if ph.direction().dot(n) < 0.0 && (ph.position() - p).dot(n).abs() <= thickness {
                                let power = ph.power();
                                for level in e.iter_mut().take(spare as usize + 1) {
                                    *level += power;
                                }
                            }
                        }
                        for level in &mut e {
                            *level /= PI * r2;
                        }
                    }
                    e.map(PackedColor::from)
                })
                .collect::<Vec<_>>()
        })
        .collect();
    if watch.cancelled() {
        return None;
    }
    // The common level is read with the record itself (one cache line); the others beside it.
    records.set_powers(|i| levels[i][0].get());
    Some((records, levels.iter().map(|l| std::array::from_fn(|j| l[j + 1])).collect()))
}
