//! Random numbers, sample warps and per-pixel samplers.
//!
//! Every random stream is seeded from what it renders, (seed, pixel, sample index) or
//! (seed, photon index), never from a thread or the clock, so any thread count gives the same
//! image (pbrt-v4 `StartPixelSample`).

pub mod chi2;
pub mod distribution;
pub mod sampler;
mod sobol;
pub mod warp;

pub use sampler::{PixelSampler, Sampler, SamplerKind};

/// A fast, well-mixed 64-bit hash step (the splitmix64 / murmur3 finaliser).
#[inline]
pub const fn mix64(mut x: u64) -> u64 {
    x ^= x >> 30;
    x = x.wrapping_mul(0xbf58_476d_1ce4_e5b9);
    x ^= x >> 27;
    x = x.wrapping_mul(0x94d0_49bb_1331_11eb);
    x ^ (x >> 31)
}

/// Hashes a list of integers into one 64-bit seed; order matters.
#[inline]
pub fn hash_seed(parts: &[u64]) -> u64 {
    SeedPrefix::new(parts).0
}

/// `hash_seed` part way through a list: lists that share their first parts (a pixel's samples,
/// a pass's photons) mix those once. `SeedPrefix::new(&[a, b]).hash(&[c])` is
/// `hash_seed(&[a, b, c])`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SeedPrefix(u64);

impl SeedPrefix {
    #[inline]
    pub fn new(parts: &[u64]) -> Self {
        SeedPrefix(0x9e37_79b9_7f4a_7c15).then(parts)
    }

    /// The prefix followed by `parts`.
    #[inline]
    pub fn then(self, parts: &[u64]) -> Self {
        parts.iter().fold(self, |h, &p| h.then_mixed(part_mix(p)))
    }

    /// The prefix followed by a part already put through `part_mix` (a caller that appends the
    /// same part to many prefixes mixes it once).
    #[inline(always)]
    pub const fn then_mixed(self, mixed: u64) -> Self {
        SeedPrefix(mix64(self.0 ^ mixed))
    }

    /// `hash_seed` of the prefix's parts followed by `parts`.
    #[inline]
    pub fn hash(self, parts: &[u64]) -> u64 {
        self.then(parts).0
    }
}

/// A part of a seed list as `SeedPrefix::then` mixes it before joining it to the prefix.
#[inline(always)]
pub const fn part_mix(p: u64) -> u64 {
    mix64(p.wrapping_add(0x632b_e59b_d9b4_e019))
}

/// PCG32's multiplier (O'Neill 2014), also that of the seeding generator below.
const PCG_MULTIPLIER: u64 = 0x5851_f42d_4c95_7f2d;

/// PCG32's output permutation (XSH RR) of a state.
#[inline(always)]
fn pcg_output(state: u64) -> u32 {
    let xorshifted = (((state >> 18) ^ state) >> 27) as u32;
    xorshifted.rotate_right((state >> 59) as u32)
}

/// The renderer's random number generator: PCG32 (XSH RR, 64-bit state), small and fast.
///
/// Written out rather than taken from `rand_pcg` because a generator is seeded per camera
/// sample and per photon: `Pcg32::seed_from_u64` fills a byte array and reads it back, where
/// here the same four seeding steps stay in registers. The streams are `rand_pcg`'s bit for bit
/// (`matches_rand_pcg`), so every image is as before.
#[derive(Clone, Debug)]
pub struct Rng32 {
    state: u64,
    increment: u64,
}

impl Rng32 {
    /// `rand_pcg::Pcg32::seed_from_u64(seed)`: four outputs of a PCG32 step with `rand_core`'s
    /// increment give the state and the stream, then one step moves away from them.
    #[inline]
    pub fn new(seed: u64) -> Self {
        const SEED_INCREMENT: u64 = 0xa176_54e4_6fbe_17f3;
        let mut s = seed;
        let mut word = || {
            s = s.wrapping_mul(PCG_MULTIPLIER).wrapping_add(SEED_INCREMENT);
            pcg_output(s) as u64
        };
        let state = word() | word() << 32;
        let increment = (word() | word() << 32) | 1;
        let state = state.wrapping_add(increment).wrapping_mul(PCG_MULTIPLIER).wrapping_add(increment);
        Rng32 { state, increment }
    }

    #[inline]
    pub fn next_u32(&mut self) -> u32 {
        let state = self.state;
        self.state = state.wrapping_mul(PCG_MULTIPLIER).wrapping_add(self.increment);
        pcg_output(state)
    }

    /// Uniform in [0, 1): 24 random bits, so 1.0 is never returned.
    #[inline]
    pub fn uniform(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
    }

    #[inline]
    pub fn uniform2(&mut self) -> glam::Vec2 {
        glam::Vec2::new(self.uniform(), self.uniform())
    }
}

/// Element `i` of a pseudo-random permutation of 0..n selected by `seed`, computed without storing
/// the permutation (Kensler 2013, "Correlated multi-jittered sampling"; pbrt-v4 PermutationElement).
pub fn permutation_element(mut i: u32, n: u32, seed: u32) -> u32 {
    if n <= 1 {
        return 0;
    }
    let mut w = n - 1;
    w |= w >> 1;
    w |= w >> 2;
    w |= w >> 4;
    w |= w >> 8;
    w |= w >> 16;
    let p = seed;
    loop {
        i ^= p;
        i = i.wrapping_mul(0xe170893d);
        i ^= p >> 16;
        i ^= (i & w) >> 4;
        i ^= p >> 8;
        i = i.wrapping_mul(0x0929eb3f);
        i ^= p >> 23;
        i ^= (i & w) >> 1;
        i = i.wrapping_mul(1 | p >> 27);
        i = i.wrapping_mul(0x6935fa69);
        i ^= (i & w) >> 11;
        i = i.wrapping_mul(0x74dcb303);
        i ^= (i & w) >> 2;
        i = i.wrapping_mul(0x9e501cc3);
        i ^= (i & w) >> 2;
        i = i.wrapping_mul(0xc860a3df);
        i &= w;
        i ^= i >> 5;
        if i < n {
            break;
        }
    }
    (i.wrapping_add(p)) % n
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn permutation_is_a_bijection() {
        for n in [1u32, 2, 7, 16, 100] {
            for seed in [0u32, 1, 12345, 0xdeadbeef] {
                let mut seen = vec![false; n as usize];
                for i in 0..n {
                    let j = permutation_element(i, n, seed);
                    assert!(!seen[j as usize]);
                    seen[j as usize] = true;
                }
            }
        }
    }

    /// `Rng32` draws `rand_pcg::Pcg32::seed_from_u64`'s numbers, so images stay as they were.
    #[test]
    fn matches_rand_pcg() {
        use rand::{Rng, SeedableRng};
        for seed in [0u64, 1, 7, 0x9e37_79b9_7f4a_7c15, u64::MAX, hash_seed(&[3, 4, 5])] {
            let mut ours = Rng32::new(seed);
            let mut theirs = rand_pcg::Pcg32::seed_from_u64(seed);
            for _ in 0..100 {
                assert_eq!(ours.next_u32(), theirs.next_u32(), "seed {seed}");
            }
        }
    }

    #[test]
    fn a_prefix_continues_the_hash() {
        let parts = [3u64, 1 << 40, 17, u64::MAX];
        for k in 0..=parts.len() {
            assert_eq!(SeedPrefix::new(&parts[..k]).hash(&parts[k..]), hash_seed(&parts));
        }
        assert_eq!(SeedPrefix::new(&[3]).then(&[1 << 40]).hash(&[17, u64::MAX]), hash_seed(&parts));
    }

    #[test]
    fn uniform_is_in_unit_interval_with_right_mean() {
        let mut r = Rng32::new(7);
        let n = 100_000;
        let mut sum = 0.0f64;
        for _ in 0..n {
            let u = r.uniform();
            assert!((0.0..1.0).contains(&u));
            sum += u as f64;
        }
        // Standard error of the mean is sqrt(1/12/n) ~ 0.0009; allow 5 sigma.
        assert!((sum / n as f64 - 0.5).abs() < 0.0046);
    }
}
