//! A photon pass's stored hits, left in the per-chunk buffers the tracing threads filled, in
//! chunk order: joining them into one array copied every hit once more (a million photons store
//! about 90 MB; the copy was a ninth of the pass and doubled its peak memory), and each use reads
//! them in order anyway or through its own index (`HitIds`). The buffers are kept between
//! passes that reuse the set (SPPM traces one per iteration), so a pass allocates nothing anew.

use super::trace::PhotonHit;

/// Stored photon hits in chunks, read as one sequence in chunk order.
#[derive(Clone, Debug, Default)]
pub struct PhotonHits {
    /// Only the first `used` chunks hold this pass's hits; the rest are spare buffers.
    chunks: Vec<Vec<PhotonHit>>,
    used: usize,
}

impl PhotonHits {
    /// One chunk holding `hits`.
    pub fn from_vec(hits: Vec<PhotonHit>) -> Self {
        PhotonHits { chunks: vec![hits], used: 1 }
    }

    /// The chunks in order.
    pub fn chunks(&self) -> &[Vec<PhotonHit>] {
        &self.chunks[..self.used]
    }

    /// `n` empty chunks to be filled, each keeping the buffer it had before.
    pub(super) fn reset(&mut self, n: usize) -> &mut [Vec<PhotonHit>] {
        if self.chunks.len() < n {
            self.chunks.resize_with(n, Vec::new);
        }
        self.used = n;
        let chunks = &mut self.chunks[..n];
        chunks.iter_mut().for_each(Vec::clear);
        chunks
    }

    pub fn len(&self) -> usize {
        self.chunks().iter().map(Vec::len).sum()
    }

    pub fn is_empty(&self) -> bool {
        self.chunks().iter().all(Vec::is_empty)
    }

    /// Bytes the buffers hold (the spare ones included).
    pub fn memory_bytes(&self) -> usize {
        self.chunks.iter().map(Vec::capacity).sum::<usize>() * std::mem::size_of::<PhotonHit>()
    }

    pub fn iter(&self) -> std::iter::Flatten<std::slice::Iter<'_, Vec<PhotonHit>>> {
        self.chunks().iter().flatten()
    }

    pub fn iter_mut(&mut self) -> impl Iterator<Item = &mut PhotonHit> {
        self.chunks[..self.used].iter_mut().flatten()
    }

    /// Keeps the hits `keep` accepts, in order.
    pub fn retain(&mut self, mut keep: impl FnMut(&PhotonHit) -> bool) {
        self.chunks[..self.used].iter_mut().for_each(|c| c.retain(&mut keep));
    }

    /// Keeps the first `n` hits.
    pub fn truncate(&mut self, mut n: usize) {
        for c in &mut self.chunks[..self.used] {
            c.truncate(n);
            n -= c.len();
        }
    }

    /// Moves `other`'s hits after these (their buffers, not copies of them).
    pub fn append(&mut self, other: PhotonHits) {
        let spare = self.chunks.split_off(self.used);
        let PhotonHits { chunks, used } = other;
        self.chunks.extend(chunks.into_iter().take(used));
        self.used = self.chunks.len();
        self.chunks.extend(spare);
    }

    /// The hits copied into one vector.
    pub fn to_vec(&self) -> Vec<PhotonHit> {
        let mut v = Vec::with_capacity(self.len());
        self.chunks().iter().for_each(|c| v.extend_from_slice(c));
        v
    }

    /// Ids of 31 bits for the hits, as `HitIds` packs them; when no split of the bits between
    /// chunk and place fits (over 2^31 hits in all, or chunks far longer than the pass makes),
    /// the hits are first joined into one chunk.
    pub fn ids(&mut self) -> HitIds {
        if let Some(ids) = HitIds::fitting(self.chunks()) {
            return ids;
        }
        let all = self.to_vec();
        *self = PhotonHits::from_vec(all);
        HitIds::fitting(self.chunks()).unwrap_or(HitIds { shift: 31 })
    }
}

impl<'a> IntoIterator for &'a PhotonHits {
    type Item = &'a PhotonHit;
    type IntoIter = std::iter::Flatten<std::slice::Iter<'a, Vec<PhotonHit>>>;

    fn into_iter(self) -> Self::IntoIter {
        self.iter()
    }
}

/// A hit's id in 31 bits: its chunk in the high bits, its place in the chunk in the low
/// `shift`, chosen per pass so the longest chunk fits. Reading a hit by id is two loads, where a
/// running index over the chunks would need a search.
#[derive(Clone, Copy, Debug)]
pub struct HitIds {
    shift: u32,
}

impl HitIds {
    /// The split for `chunks`, if one fits 31 bits.
    fn fitting(chunks: &[Vec<PhotonHit>]) -> Option<HitIds> {
        let longest = chunks.iter().map(Vec::len).max().unwrap_or(0);
        let shift = usize::BITS - longest.leading_zeros();
        let chunk_bits = usize::BITS - chunks.len().saturating_sub(1).leading_zeros();
        (shift + chunk_bits <= 31).then_some(HitIds { shift })
    }

    /// The id of hit `index` of chunk `chunk`.
    #[inline]
    pub fn id(self, chunk: usize, index: usize) -> u32 {
        ((chunk as u32) << self.shift) | index as u32
    }

    /// The hit whose id is `id`.
    #[inline]
    pub fn get(self, hits: &PhotonHits, id: u32) -> &PhotonHit {
        &hits.chunks[(id >> self.shift) as usize][(id & ((1 << self.shift) - 1)) as usize]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::{Color, Vec3};
    use crate::sampling::Rng32;

    fn hit(k: usize) -> PhotonHit {
        PhotonHit { p: Vec3::splat(k as f32), dir: Vec3::Z, flux: Color::ONE.into(), flags: 0, depth: 0, n: Vec3::Z }
    }

    /// Chunks of random sizes, empty ones included, holding hits 0, 1, 2, ... in order.
    fn numbered(rng: &mut Rng32, chunks: usize) -> (PhotonHits, usize) {
        let mut hits = PhotonHits::default();
        let mut next = 0;
        for c in hits.reset(chunks) {
            let len = if rng.uniform() < 0.2 { 0 } else { (rng.uniform() * 900.0) as usize };
            c.extend((next..next + len).map(hit));
            next += len;
        }
        (hits, next)
    }

    #[test]
    fn chunks_read_as_one_sequence() {
        let mut rng = Rng32::new(5);
        let (mut hits, n) = numbered(&mut rng, 40);
        assert_eq!(hits.len(), n);
        assert!(hits.iter().enumerate().all(|(k, h)| h.p.x == k as f32));
        assert!(hits.to_vec().iter().enumerate().all(|(k, h)| h.p.x == k as f32));
        // Every id reads back its own hit.
        let ids = hits.ids();
        for (c, chunk) in hits.chunks().iter().enumerate() {
            for (k, h) in chunk.iter().enumerate() {
                assert_eq!(ids.get(&hits, ids.id(c, k)).p, h.p);
            }
        }
        hits.truncate(n / 3);
        assert_eq!(hits.len(), n / 3);
        assert!(hits.iter().enumerate().all(|(k, h)| h.p.x == k as f32));
        hits.retain(|h| (h.p.x as usize).is_multiple_of(2));
        assert!(hits.iter().enumerate().all(|(k, h)| h.p.x == (2 * k) as f32));
    }

    #[test]
    fn a_reset_keeps_buffers_and_drops_old_hits() {
        let mut rng = Rng32::new(9);
        let (mut hits, _) = numbered(&mut rng, 12);
        let bytes = hits.memory_bytes();
        hits.reset(5)[2].push(hit(7));
        assert_eq!(hits.len(), 1);
        assert_eq!(hits.chunks().len(), 5);
        assert_eq!(hits.memory_bytes(), bytes);
        // Appending moves the other set's chunks in after the used ones.
        let (more, m) = numbered(&mut rng, 3);
        hits.append(more);
        assert_eq!(hits.len(), 1 + m);
        assert!(hits.iter().skip(1).enumerate().all(|(k, h)| h.p.x == k as f32));
    }

    #[test]
    fn ids_split_their_bits_by_the_longest_chunk() {
        let chunks = |lens: &[usize]| lens.iter().map(|&n| vec![hit(0); n]).collect::<Vec<_>>();
        assert_eq!(HitIds::fitting(&chunks(&[4096, 5000, 0])).map(|i| i.shift), Some(13));
        assert_eq!(HitIds::fitting(&chunks(&[1])).map(|i| i.shift), Some(1));
        // 2^20 chunks leave 11 bits: a chunk of 2^11 hits does not fit, one of 2^11 - 1 does.
        let many = vec![Vec::new(); 1 << 20];
        assert!(HitIds::fitting(&many).is_some());
        let mut long = many.clone();
        long[3] = vec![hit(0); 1 << 11];
        assert!(HitIds::fitting(&long).is_none());
        long[3].pop();
        assert_eq!(HitIds::fitting(&long).map(|i| i.shift), Some(11));
    }
}
