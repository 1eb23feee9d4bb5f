//! Random numbers, sample warps and per-pixel samplers.
//!
//! Every random stream is seeded from what it renders, (seed, pixel, sample index) or
//! (seed, photon index), never from a thread or the clock, so any thread count gives the same
//! image (pbrt-v4 `StartPixelSample`).

pub mod chi2;
pub mod distribution;
pub mod sampler;
pub mod warp;

pub use sampler::{Sampler, SamplerKind};

use rand::{Rng, SeedableRng};
use rand_pcg::Pcg32;

/// A fast, well-mixed 64-bit hash step (the splitmix64 / murmur3 finaliser).
#[inline]
pub fn mix64(mut x: u64) -> u64 {
    x ^= x >> 30;
    x = x.wrapping_mul(0xbf58_476d_1ce4_e5b9);
    x ^= x >> 27;
    x = x.wrapping_mul(0x94d0_49bb_1331_11eb);
    x ^ (x >> 31)
}

/// Hashes a list of integers into one 64-bit seed; order matters.
#[inline]
pub fn hash_seed(parts: &[u64]) -> u64 {
    parts.iter().fold(0x9e37_79b9_7f4a_7c15u64, |h, &p| mix64(h ^ mix64(p.wrapping_add(0x632b_e59b_d9b4_e019))))
}

/// The renderer's random number generator: PCG32, small and fast.
#[derive(Clone, Debug)]
pub struct Rng32(Pcg32);

impl Rng32 {
    pub fn new(seed: u64) -> Self {
        Rng32(Pcg32::seed_from_u64(seed))
    }

    #[inline]
    pub fn next_u32(&mut self) -> u32 {
        self.0.next_u32()
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
