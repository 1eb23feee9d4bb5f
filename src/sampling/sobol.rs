//! The first two dimensions of Burley's (2020) Owen-scrambled, shuffled Sobol sequence, the only
//! dimensions the sampler reads (every 2-D pair is its own shuffled sequence: `Sampler`).
//!
//! `sobol_burley::sample(i, 0 | 1, seed)` gives the same numbers bit for bit (a test checks it),
//! but walks the 16 index bits through its direction table for each call and shuffles the
//! index once per dimension; here the index is shuffled once per pair and each dimension's
//! generator matrix is applied by two byte-table lookups (the matrices are linear over GF(2)).
//! With the SSE version of the crate a pair cost about 345 instructions in SPPM's camera pass
//! (BENCHMARKS.md, issue 29).

/// Sobol's generator matrices for dimensions 0 and 1 in the bit-reversed form the crate works
/// in: `TABLES[d][b][byte]` is the XOR of the reversed direction numbers selected by `byte`, the
/// `b`-th byte from the top of a reversed index.
static TABLES: [[[u32; 256]; 2]; 2] = tables();

/// Each byte's bits reversed: the build's target has no bit-reversal instruction, and
/// `u32::reverse_bits` in shifts and masks cost three times the four lookups of `reverse`.
static REVERSED_BYTES: [u8; 256] = {
    let mut t = [0u8; 256];
    let mut b = 0;
    while b < 256 {
        t[b] = (b as u8).reverse_bits();
        b += 1;
    }
    t
};

/// `x.reverse_bits()` by bytes.
#[inline(always)]
fn reverse(x: u32) -> u32 {
    let r = |shift: u32| u32::from(REVERSED_BYTES[((x >> shift) & 0xff) as usize]);
    r(0) << 24 | r(8) << 16 | r(16) << 8 | r(24)
}

/// Reversed direction number `k` (k = 0 for the index's lowest bit) of dimension `d`: dimension
/// 0 is the van der Corput sequence (v_k = 2^(31-k)); dimension 1's polynomial is x + 1, so
/// v_k = v_(k-1) ^ (v_(k-1) >> 1) from v_0 = 2^31 (the rows of Pascal's triangle mod 2).
const fn direction_rev(d: usize, k: u32) -> u32 {
    let mut v = 1u32 << 31;
    let mut j = 0;
    while j < k {
        v = if d == 0 { v >> 1 } else { v ^ (v >> 1) };
        j += 1;
    }
    v.reverse_bits()
}

const fn tables() -> [[[u32; 256]; 2]; 2] {
    let mut t = [[[0u32; 256]; 2]; 2];
    let mut d = 0;
    while d < 2 {
        let mut b = 0;
        while b < 2 {
            let mut byte = 0;
            while byte < 256 {
                let mut x = 0u32;
                let mut bit = 0;
                while bit < 8 {
                    // Bit 7 - bit of the byte is index bit 8 b + bit (the reversed index's top
                    // bit is the index's lowest).
                    if byte & (0x80 >> bit) != 0 {
                        x ^= direction_rev(d, 8 * b as u32 + bit);
                    }
                    bit += 1;
                }
                t[d][b][byte] = x;
                byte += 1;
            }
            b += 1;
        }
        d += 1;
    }
    t
}

/// Point `index` (below 2^16) of the shuffled, Owen-scrambled 2-D Sobol sequence `seed`, each
/// coordinate in [0, 1): `(sample(index, 0, seed), sample(index, 1, seed))` of `sobol_burley`.
#[inline]
pub fn sobol_pair(index: u32, seed: u32) -> (f32, f32) {
    let (hi, lo) = shuffled_bytes(index, seed);
    (coordinate(0, hi, lo, seed), coordinate(1, hi, lo, seed))
}

/// The first coordinate of `sobol_pair(index, seed)`, bit for bit, without the second's work
/// (a 1-D sample reads only it).
#[inline]
pub fn sobol_first(index: u32, seed: u32) -> f32 {
    let (hi, lo) = shuffled_bytes(index, seed);
    coordinate(0, hi, lo, seed)
}

/// The top two bytes of the reversed, shuffled index (the index is below 2^16).
#[inline(always)]
fn shuffled_bytes(index: u32, seed: u32) -> (usize, usize) {
    use sobol_burley::parts::{hash, owen_scramble_rev};
    debug_assert!(index < 1 << 16);
    let index_rev = u32::from(REVERSED_BYTES[(index & 0xff) as usize]) << 24
        | u32::from(REVERSED_BYTES[((index >> 8) & 0xff) as usize]) << 16;
    let shuffled = owen_scramble_rev(index_rev, hash(seed ^ 0x79c6_8e4a));
    ((shuffled >> 24) as usize, ((shuffled >> 16) & 0xff) as usize)
}

/// Dimension `d` (0 or 1) of the point whose shuffled index bytes are `hi`, `lo`, scrambled
/// with the crate's per-dimension seed.
#[inline(always)]
fn coordinate(d: usize, hi: usize, lo: usize, seed: u32) -> f32 {
    use sobol_burley::parts::{hash, owen_scramble_rev, u32_to_f32_norm};
    const DIMENSION_SEEDS: [u32; 2] = [0x912f_69ba, 0x174f_18ab];
    let x = TABLES[d][0][hi] ^ TABLES[d][1][lo];
    let s = seed.wrapping_mul(0x9c8f_2d3b);
    u32_to_f32_norm(reverse(owen_scramble_rev(x, hash(s ^ DIMENSION_SEEDS[d]))))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reverse_is_reverse_bits() {
        let mut rng = crate::sampling::Rng32::new(3);
        for x in [0u32, 1, 0x8000_0000, u32::MAX, 0x1234_5678].into_iter().chain((0..10_000).map(|_| rng.next_u32())) {
            assert_eq!(reverse(x), x.reverse_bits(), "{x:#x}");
        }
    }

    #[test]
    fn first_coordinate_alone_equals_the_pairs() {
        let mut rng = crate::sampling::Rng32::new(11);
        for _ in 0..200_000 {
            let (index, seed) = (rng.next_u32() & 0xffff, rng.next_u32());
            assert_eq!(sobol_first(index, seed).to_bits(), sobol_pair(index, seed).0.to_bits(), "{index} {seed}");
        }
    }

    #[test]
    fn equals_sobol_burley_bit_for_bit() {
        for seed in [0u32, 1, 7, 0x1234_5678, 0xdead_beef, u32::MAX] {
            for index in 0..1u32 << 16 {
                let (x, y) = sobol_pair(index, seed);
                assert_eq!(x.to_bits(), sobol_burley::sample(index, 0, seed).to_bits(), "index {index} seed {seed}");
                assert_eq!(y.to_bits(), sobol_burley::sample(index, 1, seed).to_bits(), "index {index} seed {seed}");
            }
        }
    }
}
